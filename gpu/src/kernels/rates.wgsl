// The rates of one stage, one fused pass over each soil particle's soil and marker neighbours:
// density rate, acceleration, velocity gradient (hence D and the Jaumann stress rate), XSPH
// correction, concentration gradient and, at the first stage (FS), the free-surface measure
// (smallest eigenvalue of sum V_b (x_b - x_a) (x) grad W), the surface flags and the pair count.
// Neighbours are visited in the CPU's order (columns x then y, each a contiguous z range of
// cell-sorted records), so the sums round the same way. CPU twin: `rates::soil_rates`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> packed: array<Packed>;
@group(0) @binding(2) var<storage, read> start: array<u32>;
@group(0) @binding(3) var<storage, read> m_packed: array<Packed>;
@group(0) @binding(4) var<storage, read> m_start: array<u32>;
@group(0) @binding(5) var<storage, read> moduli: array<vec2<f32>>;
@group(0) @binding(6) var<storage, read_write> parts: array<Particle>;
@group(0) @binding(7) var<storage, read_write> rates: array<Rate>;
@group(0) @binding(8) var<storage, read_write> info: Info;

// Jaumann rate 2G D' + K tr(D) I + (Omega sigma - sigma Omega), spin as (W_xy, W_xz, W_yz).
fn jaumann(s: Sym, d: Sym, w: vec3<f32>, m: vec2<f32>) -> Sym {
    let dev = sym_dev(d);
    let el = sym_add(sym_scale(dev, 2.0 * m.y), sym_iso(m.x * sym_trace(d)));
    let a = w.x;
    let b = w.y;
    let c = w.z;
    let mxx = a * s.xy + b * s.xz;
    let mxy = a * s.yy + b * s.yz;
    let mxz = a * s.yz + b * s.zz;
    let myx = -a * s.xx + c * s.xz;
    let myy = -a * s.xy + c * s.yz;
    let myz = -a * s.xz + c * s.zz;
    let mzx = -b * s.xx - c * s.xy;
    let mzy = -b * s.xy - c * s.yy;
    let mzz = -b * s.xz - c * s.yz;
    return sym_add(el, Sym(2.0 * mxx, 2.0 * myy, 2.0 * mzz, mxy + myx, mxz + mzx, myz + mzy));
}

struct Acc {
    drho: f32,
    acc: vec3<f32>,
    l0: vec3<f32>, l1: vec3<f32>, l2: vec3<f32>,
    fs: Sym,
    xs: vec3<f32>,
    gc: vec3<f32>,
}

fn visit(s: ptr<function, Acc>, pa: Packed, pb: Packed, is_soil: bool) {
    let r = packed_x(pa) - packed_x(pb);
    let r2 = dot(r, r);
    if (r2 >= prm.support2) { return; }
    let rr = sqrt(r2);
    let f = kernel_grad_factor(rr, prm.inv_h, prm.alpha);
    let gw = r * f;
    let vab = packed_v(pa) - packed_v(pb);
    (*s).drho += pb.vol * dot(vab, gw);
    (*s).acc += pair_term(pa, pb, r, r2, gw, vab) * pb.mass;
    let mv = vab * (-pb.vol);
    (*s).l0 += mv.x * gw;
    (*s).l1 += mv.y * gw;
    (*s).l2 += mv.z * gw;
    if (FS) {
        let k = -pb.vol * f;
        (*s).fs = sym_add((*s).fs, Sym(k * r.x * r.x, k * r.y * r.y, k * r.z * r.z, k * r.x * r.y, k * r.x * r.z, k * r.y * r.z));
    }
    if (XSPH && is_soil) {
        let w = kernel_w(rr, prm.inv_h, prm.alpha);
        (*s).xs -= vab * (2.0 * pb.mass / (pa.rho + pb.rho) * w);
    }
    if (PPST) {
        (*s).gc += gw * pb.vol;
    }
}

@compute @workgroup_size(64)
fn soil_rates(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= info.n_active) { return; }
    let pa = packed[i];
    let xa = packed_x(pa);
    var s = Acc(0.0, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), sym_zero(), vec3<f32>(0.0), vec3<f32>(0.0));
    var pairs = 0u;
    var near_markers = 0u;
    let c = cell_coords(xa);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for (var ix = rc.x0; ix <= rc.x1; ix++) {
            for (var iy = rc.y0; iy <= rc.y1; iy++) {
                let a = start[cell_linear(ix, iy, rc.z0)];
                let b = start[cell_linear(ix, iy, rc.z1) + 1u];
                for (var j = a; j < b; j++) {
                    if (j == i) { continue; }
                    let pb = packed[j];
                    let d = xa - packed_x(pb);
                    if (dot(d, d) >= prm.radius2) { continue; }
                    pairs++;
                    visit(&s, pa, pb, true);
                }
            }
        }
        for (var ix = rc.x0; ix <= rc.x1; ix++) {
            for (var iy = rc.y0; iy <= rc.y1; iy++) {
                let a = m_start[cell_linear(ix, iy, rc.z0)];
                let b = m_start[cell_linear(ix, iy, rc.z1) + 1u];
                for (var j = a; j < b; j++) {
                    let pb = m_packed[j];
                    let d = xa - packed_x(pb);
                    if (dot(d, d) >= prm.radius2) { continue; }
                    near_markers++;
                    visit(&s, pa, pb, false);
                }
            }
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
