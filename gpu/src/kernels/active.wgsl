// Active regions (see `regolith_fsi::active`): `cover` checks, after a step, that every awake
// particle is still in a cell awake particles may be in (those they held at the last
// classification and one more on every side); when one is not, or has left the grid,
// `info.uncovered` is set and the device classifies again before the next step
// (classify.wgsl, dilate.wgsl, partition.wgsl; CPU twin `regolith_fsi::cpu::ActiveRegion`).
// CPU twin: `CpuSph::awake_still_covered`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> parts: array<Particle>;
@group(0) @binding(2) var<storage, read> cells: array<u32>;
@group(0) @binding(3) var<storage, read_write> info: Info;

@compute @workgroup_size(64)
fn cover(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let p = parts[i];
    if ((p.flags & FLAG_FROZEN) != 0u) { return; }
    let c = cell_coords(vec3<f32>(p.px, p.py, p.pz));
    if (c.x < 0) {
        atomicMax(&info.uncovered, 1u);
        return;
    }
    if (cells[cell_linear(u32(c.x), u32(c.y), u32(c.z))] == 0u) { atomicMax(&info.uncovered, 1u); }
}
