// Gathers records into their new (cell) order: soil particles (`permute_particles`, then the
// active count becomes the number inside the grid) and markers (`gather_markers`, the sorted
// copy the neighbour loops read; the original order stays with the coupling layer).

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> order: array<u32>;
@group(0) @binding(2) var<storage, read> start: array<u32>;
@group(0) @binding(3) var<storage, read> src_particles: array<Particle>;
@group(0) @binding(4) var<storage, read_write> dst_particles: array<Particle>;
@group(0) @binding(5) var<storage, read_write> info: Info;
@group(0) @binding(6) var<storage, read> src_markers: array<Marker>;
@group(0) @binding(7) var<storage, read_write> dst_markers: array<Marker>;

@compute @workgroup_size(64)
fn permute_particles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= prm.n) { return; }
    // `start[n_cells + 1]` is the number of points sorted: the previous active count.
    if (k < start[prm.n_cells + 1u]) {
        dst_particles[k] = src_particles[order[k]];
    } else {
        dst_particles[k] = src_particles[k];
    }
}

@compute @workgroup_size(1)
fn set_active() {
    info.n_active = start[prm.n_cells];
}

@compute @workgroup_size(64)
fn gather_markers(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= start[prm.n_cells]) { return; }
    dst_markers[k] = src_markers[order[k]];
}
