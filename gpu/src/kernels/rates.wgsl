// The rates of one stage, one fused pass over each soil particle's soil and marker neighbours:
// density rate, acceleration, velocity gradient (hence D and the Jaumann stress rate), XSPH
// correction, concentration gradient and, at the first stage (FS), the free-surface measure
// (smallest eigenvalue of sum V_b (x_b - x_a) (x) grad W), the surface flags and the pair count.
// Neighbours come from for_each_in_reach (the CPU's visiting order, see neighbour_loop.rs), so
// the sums round the same way. CPU twin: `rates::soil_rates`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> packed: array<Packed>;
@group(0) @binding(2) var<storage, read> start: array<u32>;
@group(0) @binding(3) var<storage, read> m_packed: array<Packed>;
@group(0) @binding(4) var<storage, read> m_start: array<u32>;
@group(0) @binding(5) var<storage, read> moduli: array<vec2<f32>>;
@group(0) @binding(6) var<storage, read_write> parts: array<Particle>;
@group(0) @binding(7) var<storage, read_write> rates: array<Rate>;
@group(0) @binding(8) var<storage, read_write> info: Info;

@compute @workgroup_size(64)
fn soil_rates(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active || (parts[i].flags & FLAG_FROZEN) != 0u) { return; }
    let pa = packed[i];
    let xa = packed_x(pa);
    var s = Acc(0.0, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), sym_zero(), vec3<f32>(0.0), vec3<f32>(0.0));
    var pairs = 0u;
    var near_markers = 0u;
    let c = cell_coords(xa);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            if (j == i) { continue; }
            let pb = packed[j];
            let d = xa - packed_x(pb);
            if (dot(d, d) >= prm.radius2) { continue; }
            pairs++;
            visit(&s, pa, pb, true);
        }
        for_each_in_reach(j, m_start, rc) {
            let pb = m_packed[j];
            let d = xa - packed_x(pb);
            if (dot(d, d) >= prm.radius2) { continue; }
            near_markers++;
            visit(&s, pa, pb, false);
        }
    }
    // L_ij = sum V_b (v_b - v_a)_i d_j W; D = sym(L), spin = skew(L).
    let l0 = s.l0;
    let l1 = s.l1;
    let l2 = s.l2;
    let d = Sym(l0.x, l1.y, l2.z, 0.5 * (l0.y + l1.x), 0.5 * (l0.z + l2.x), 0.5 * (l1.z + l2.y));
    let spin = vec3<f32>(0.5 * (l0.y - l1.x), 0.5 * (l0.z - l2.x), 0.5 * (l1.z - l2.y));
    let m = moduli[i];
    let ds = jaumann(load_sigma(parts[i]), d, spin, m);
    let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
    let acc = s.acc + g;
    var fs = rates[i].fs;
    if (FS) {
        fs = sym_min_eigenvalue(s.fs);
        // A particle with wall or body markers in its support is in contact, not free;
        // detachment counts the markers as neighbours (fs sums over both).
        let free = near_markers == 0u;
        var flags = 0u;
        if (free && fs < prm.fs_threshold) { flags |= FLAG_FREE; }
        if (fs < prm.detach_threshold) { flags |= FLAG_DETACHED; }
        parts[i].flags = flags;
        atomicAdd(&info.pairs, pairs + near_markers);
    }
    rates[i] = Rate(pa.rho * s.drho, acc.x, acc.y, acc.z,
        ds.xx, ds.yy, ds.zz, ds.xy, ds.xz, ds.yz,
        d.xx, d.yy, d.zz, d.xy, d.xz, d.yz,
        s.xs.x, s.xs.y, s.xs.z, s.gc.x, s.gc.y, s.gc.z,
        fs, m.x, m.y, 0.0);
}
