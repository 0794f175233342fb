// Force on each marker from the soil (minus the pair terms the soil receives), written in the
// markers' original order for the coupling layer. CPU twin: `rates::marker_forces`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> m_packed: array<Packed>;
@group(0) @binding(2) var<storage, read> m_start: array<u32>;
@group(0) @binding(3) var<storage, read> m_order: array<u32>;
@group(0) @binding(4) var<storage, read> packed: array<Packed>;
@group(0) @binding(5) var<storage, read> start: array<u32>;
@group(0) @binding(6) var<storage, read_write> m_force: array<f32>;
@group(0) @binding(7) var<storage, read> parts: array<Particle>;

@compute @workgroup_size(64)
fn marker_forces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= m_start[prm.n_cells]) { return; }
    let pw = m_packed[k];
    let xw = packed_x(pw);
    var f = vec3<f32>(0.0);
    let c = cell_coords(xw);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            // Extended (frozen) soil is a neighbour of the soil, not a load on markers.
            if ((parts[j].flags & FLAG_FROZEN) != 0u) { continue; }
            let pa = packed[j];
            let r = packed_x(pa) - xw;
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let gw = r * kernel_grad_factor(sqrt(r2), prm.inv_h, prm.alpha);
            let vab = packed_v(pa) - packed_v(pw);
            f -= pair_term(pa, pw, r, r2, gw, vab) * (pa.mass * pw.mass);
        }
    }
    let o = m_order[k];
    m_force[3u * o] = f.x;
    m_force[3u * o + 1u] = f.y;
    m_force[3u * o + 2u] = f.z;
}
