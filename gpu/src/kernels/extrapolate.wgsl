// Boundary-marker extrapolation (Adami et al. 2012) for every marker inside the grid, from the
// soil within reach: v_w = 2 v_body - sum(v W)/sum(W), sigma_w = sum(sigma W)/sum(W) - dp I with
// dp = (g - a_body) . sum(rho (x_w - x_b) W)/sum(W), rho_w = sum(rho W)/sum(W). A marker with
// no soil around it keeps the body's velocity and zero stress. A marker of an owner with a
// smooth or frictional contact (`owner_mu` finite) and a wall normal goes through `wall_state`.
// CPU twin: `rates::extrapolate_markers`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> markers: array<Marker>;
@group(0) @binding(2) var<storage, read> m_start: array<u32>;
@group(0) @binding(3) var<storage, read> packed: array<Packed>;
@group(0) @binding(4) var<storage, read> parts: array<Particle>;
@group(0) @binding(5) var<storage, read> start: array<u32>;
@group(0) @binding(6) var<storage, read_write> m_packed: array<Packed>;
@group(0) @binding(7) var<storage, read> owner_mu: array<f32>;

@compute @workgroup_size(64)
fn extrapolate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= m_start[prm.n_cells]) { return; }
    let mk = markers[k];
    let xw = vec3<f32>(mk.px, mk.py, mk.pz);
    var sw = 0.0;
    var sv = vec3<f32>(0.0);
    var ss = sym_zero();
    var srr = vec3<f32>(0.0);
    var srho = 0.0;
    var scs = 0.0;
    let c = cell_coords(xw);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            let pa = packed[j];
            let r = xw - packed_x(pa);
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let w = kernel_w(sqrt(r2), prm.inv_h, prm.alpha);
            sw += w;
            sv += packed_v(pa) * w;
            ss = sym_add(ss, sym_scale(load_sigma(parts[j]), w));
            srr += r * (pa.rho * w);
            srho += pa.rho * w;
            scs += pa.cs * w;
        }
    }
    let vb = vec3<f32>(mk.vx, mk.vy, mk.vz);
    if (sw > sqrt(F32_MIN_POS)) {
        let inv = 1.0 / sw;
        let rho = srho * inv;
        let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
        let dp = dot(g - vec3<f32>(mk.ax, mk.ay, mk.az), srr) * inv;
        let w = wall_state(mk, owner_mu[mk.owner], rho * scs * inv, sv * inv, sym_sub(sym_scale(ss, inv), sym_iso(dp)));
        let s = sym_scale(w.s, 1.0 / (rho * rho));
        let v = w.v;
        m_packed[k] = Packed(xw.x, xw.y, xw.z, v.x, v.y, v.z, s.xx, s.yy, s.zz, s.xy, s.xz, s.yz,
            prm.m_volume, rho * prm.m_volume, rho, scs * inv);
    } else {
        m_packed[k] = Packed(xw.x, xw.y, xw.z, vb.x, vb.y, vb.z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            prm.m_volume, prm.ref_rho * prm.m_volume, prm.ref_rho, prm.ref_cs);
    }
}
