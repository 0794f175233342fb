// Shared by every Regolith kernel: the record layouts (mirrors of the `#[repr(C)]` structs in
// layout.rs), the solver constants, small tensor helpers, the smoothing kernels and the cell
// grid. Each kernel's source is this file, the generated effect constants, and its own file.

struct Params {
    origin_x: f32, origin_y: f32, origin_z: f32, inv_cell: f32,
    dim_x: u32, dim_y: u32, dim_z: u32, n_cells: u32,
    n: u32, nm: u32, reach: u32, radius2: f32,
    h: f32, inv_h: f32, alpha: f32, support2: f32,
    visc_alpha: f32, eta2: f32, m_volume: f32, ref_rho: f32,
    g_x: f32, g_y: f32, g_z: f32, ref_cs: f32,
    xsph_eps: f32, shift: f32, max_shift: f32, fs_threshold: f32,
    detach_threshold: f32, cfl: f32, dt_max: f32, dt_fixed: f32,
    w_rest: f32, w_c: f32, w_mu: f32, w_gamma: f32,
    inv_lsum: f32, lsum: f32, full_support: f32, drag_particle: u32,
}

struct Particle {
    px: f32, py: f32, pz: f32,
    vx: f32, vy: f32, vz: f32,
    rho: f32,
    sxx: f32, syy: f32, szz: f32, sxy: f32, sxz: f32, syz: f32,
    pc: f32, sv: f32, mass: f32,
    material: u32, id: u32, flags: u32, pad: u32,
}

struct Packed {
    x: f32, y: f32, z: f32,
    vx: f32, vy: f32, vz: f32,
    sxx: f32, syy: f32, szz: f32, sxy: f32, sxz: f32, syz: f32,
    vol: f32, mass: f32, rho: f32, cs: f32,
}

struct Rate {
    drho: f32, ax: f32, ay: f32, az: f32,
    dsxx: f32, dsyy: f32, dszz: f32, dsxy: f32, dsxz: f32, dsyz: f32,
    dxx: f32, dyy: f32, dzz: f32, dxy: f32, dxz: f32, dyz: f32,
    xsx: f32, xsy: f32, xsz: f32,
    gcx: f32, gcy: f32, gcz: f32,
    fs: f32, bulk: f32, shear: f32, pad: f32,
}

struct Marker {
    px: f32, py: f32, pz: f32,
    vx: f32, vy: f32, vz: f32,
    ax: f32, ay: f32, az: f32,
    owner: u32,
    nx: f32, ny: f32, nz: f32,
}

// Step bookkeeping on the device. `active` and `dt` persist; the rest is reset every step.
struct Info {
    n_active: u32, dt: f32, max_dt: f32, rarefied: atomic<u32>,
    cmax: atomic<u32>, vmax: atomic<u32>, amax: atomic<u32>, pairs: atomic<u32>,
    err_key: atomic<u32>, vmax_end: atomic<u32>, amax_end: atomic<u32>,
    drag: atomic<u32>, uncovered: atomic<u32>,
}

// Flag bits of `Particle.flags`.
const FLAG_FREE: u32 = 1u;
const FLAG_DETACHED: u32 = 2u;
// Extended particle of an active region: a neighbour only, its state frozen (see
// `regolith_fsi::active`).
const FLAG_FROZEN: u32 = 4u;

// A dispatch wider than the 65535 workgroups one dimension allows comes in rows of
// ROW_GROUPS workgroups (`kernels::dispatch`): the flat index of a thread of a 64-wide kernel.
const ROW_GROUPS: u32 = 65535u;
fn flat(g: vec3<u32>) -> u32 { return g.x + g.y * (ROW_GROUPS * 64u); }

const F32_EPS: f32 = 1.1920929e-7;
const F32_MIN_POS: f32 = 1.1754944e-38;
const PI: f32 = 3.14159265358979;

// A symmetric 3x3 tensor (xx, yy, zz, xy, xz, yz).
struct Sym { xx: f32, yy: f32, zz: f32, xy: f32, xz: f32, yz: f32 }

fn sym(xx: f32, yy: f32, zz: f32, xy: f32, xz: f32, yz: f32) -> Sym { return Sym(xx, yy, zz, xy, xz, yz); }
fn sym_zero() -> Sym { return Sym(0.0, 0.0, 0.0, 0.0, 0.0, 0.0); }
fn sym_iso(a: f32) -> Sym { return Sym(a, a, a, 0.0, 0.0, 0.0); }
fn sym_add(a: Sym, b: Sym) -> Sym { return Sym(a.xx + b.xx, a.yy + b.yy, a.zz + b.zz, a.xy + b.xy, a.xz + b.xz, a.yz + b.yz); }
fn sym_sub(a: Sym, b: Sym) -> Sym { return Sym(a.xx - b.xx, a.yy - b.yy, a.zz - b.zz, a.xy - b.xy, a.xz - b.xz, a.yz - b.yz); }
fn sym_scale(a: Sym, s: f32) -> Sym { return Sym(a.xx * s, a.yy * s, a.zz * s, a.xy * s, a.xz * s, a.yz * s); }
fn sym_trace(a: Sym) -> f32 { return a.xx + a.yy + a.zz; }
fn sym_pressure(a: Sym) -> f32 { return -sym_trace(a) / 3.0; }
fn sym_dev(a: Sym) -> Sym {
    let m = sym_trace(a) / 3.0;
    return Sym(a.xx - m, a.yy - m, a.zz - m, a.xy, a.xz, a.yz);
}
fn sym_ddot(a: Sym, b: Sym) -> f32 {
    return a.xx * b.xx + a.yy * b.yy + a.zz * b.zz + 2.0 * (a.xy * b.xy + a.xz * b.xz + a.yz * b.yz);
}
fn sym_mul_vec(a: Sym, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.xx * v.x + a.xy * v.y + a.xz * v.z, a.xy * v.x + a.yy * v.y + a.yz * v.z, a.xz * v.x + a.yz * v.y + a.zz * v.z);
}

// Finite without relying on NaN comparisons (which shader compilers may fold away).
fn finite(x: f32) -> bool { return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u; }
fn finite3(v: vec3<f32>) -> bool { return finite(v.x) && finite(v.y) && finite(v.z); }
fn sym_finite(a: Sym) -> bool {
    return finite(a.xx) && finite(a.yy) && finite(a.zz) && finite(a.xy) && finite(a.xz) && finite(a.yz);
}

// sqrt(3/2 s:s) of a deviator, on the tensor scaled by its largest entry (no overflow).
fn von_mises_of_deviator(s: Sym) -> f32 {
    let a = max(max(max(abs(s.xx), abs(s.yy)), max(abs(s.zz), abs(s.xy))), max(abs(s.xz), abs(s.yz)));
    if (a == 0.0 || !finite(a)) { return a; }
    let n = sym_scale(s, 1.0 / a);
    return a * sqrt(1.5 * sym_ddot(n, n));
}

// Smallest eigenvalue, trigonometric closed form (as Sym3::min_eigenvalue).
fn sym_min_eigenvalue(a: Sym) -> f32 {
    let p1 = a.xy * a.xy + a.xz * a.xz + a.yz * a.yz;
    let q = sym_trace(a) / 3.0;
    let sa = abs(a.xx) + abs(a.yy) + abs(a.zz);
    if (p1 <= F32_EPS * sa * sa) { return min(min(a.xx, a.yy), a.zz); }
    let p2 = (a.xx - q) * (a.xx - q) + (a.yy - q) * (a.yy - q) + (a.zz - q) * (a.zz - q) + 2.0 * p1;
    let p = sqrt(p2 / 6.0);
    let b = sym_scale(sym_sub(a, sym_iso(q)), 1.0 / p);
    let det = b.xx * (b.yy * b.zz - b.yz * b.yz) - b.xy * (b.xy * b.zz - b.yz * b.xz) + b.xz * (b.xy * b.yz - b.yy * b.xz);
    let r = min(max(det / 2.0, -1.0), 1.0);
    let phi = acos(r) / 3.0;
    return q + 2.0 * p * cos(phi + 2.0 * PI / 3.0);
}

fn load_sigma(p: Particle) -> Sym { return Sym(p.sxx, p.syy, p.szz, p.sxy, p.sxz, p.syz); }
fn packed_s(p: Packed) -> Sym { return Sym(p.sxx, p.syy, p.szz, p.sxy, p.sxz, p.syz); }
fn packed_x(p: Packed) -> vec3<f32> { return vec3<f32>(p.x, p.y, p.z); }
fn packed_v(p: Packed) -> vec3<f32> { return vec3<f32>(p.vx, p.vy, p.vz); }

// Smoothing kernels (support 2h). KERNEL_CUBIC is a generated constant.
fn kernel_w(r: f32, inv_h: f32, alpha: f32) -> f32 {
    let q = r * inv_h;
    if (q >= 2.0) { return 0.0; }
    if (KERNEL_CUBIC) {
        if (q >= 1.0) {
            let t = 2.0 - q;
            return alpha * 0.25 * t * t * t;
        }
        return alpha * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
    }
    let t = 1.0 - 0.5 * q;
    let t2 = t * t;
    return alpha * t2 * t2 * (2.0 * q + 1.0);
}

fn kernel_grad_factor(r: f32, inv_h: f32, alpha: f32) -> f32 {
    let q = r * inv_h;
    if (q >= 2.0) { return 0.0; }
    if (KERNEL_CUBIC) {
        let ih2 = inv_h * inv_h;
        if (q >= 1.0) {
            let t = 2.0 - q;
            return -0.75 * alpha * t * t * ih2 / q;
        }
        return alpha * (-3.0 + 2.25 * q) * ih2;
    }
    let t = 1.0 - 0.5 * q;
    return -5.0 * alpha * t * t * t * inv_h * inv_h;
}

// Cell coordinates of a point, or x = -1 outside the grid (NaN included).
fn cell_coords(p: vec3<f32>) -> vec3<i32> {
    let f = vec3<f32>((p.x - prm.origin_x) * prm.inv_cell, (p.y - prm.origin_y) * prm.inv_cell, (p.z - prm.origin_z) * prm.inv_cell);
    let dims = vec3<u32>(prm.dim_x, prm.dim_y, prm.dim_z);
    var c = vec3<i32>(0);
    for (var a = 0u; a < 3u; a++) {
        let x = f[a];
        if (!finite(x) || !(x >= 0.0)) { return vec3<i32>(-1); }
        let fl = floor(x);
        if (fl >= f32(dims[a])) { return vec3<i32>(-1); }
        c[a] = i32(fl);
    }
    return c;
}

fn cell_linear(ix: u32, iy: u32, iz: u32) -> u32 {
    return (ix * prm.dim_y + iy) * prm.dim_z + iz;
}

// The range of cells a neighbour query at cell c scans: x and y bounds, and the z bounds of
// each contiguous column.
struct Reach { x0: u32, x1: u32, y0: u32, y1: u32, z0: u32, z1: u32 }

fn reach_of(c: vec3<i32>) -> Reach {
    let r = i32(prm.reach);
    return Reach(
        u32(max(c.x - r, 0)), u32(min(c.x + r, i32(prm.dim_x) - 1)),
        u32(max(c.y - r, 0)), u32(min(c.y + r, i32(prm.dim_y) - 1)),
        u32(max(c.z - r, 0)), u32(min(c.z + r, i32(prm.dim_z) - 1)));
}

// Monaghan's artificial viscosity and the symmetric stress term of a pair (a, b):
// (S_a + S_b) grad W - Pi grad W, exactly antisymmetric under swapping a and b.
fn pair_term(pa: Packed, pb: Packed, r: vec3<f32>, r2: f32, gw: vec3<f32>, vab: vec3<f32>) -> vec3<f32> {
    var ga = sym_mul_vec(sym_add(packed_s(pa), packed_s(pb)), gw);
    if (VISC) {
        // Approaching pairs only (v.r < 0), without a branch; one division (the CPU twin's
        // form: Pi = -alpha (c_a + c_b) h min(v.r, 0) / ((r2 + eta2)(rho_a + rho_b))).
        let vr = min(dot(vab, r), 0.0);
        let pi = -prm.visc_alpha * (pa.cs + pb.cs) * (prm.h * vr) / ((r2 + prm.eta2) * (pa.rho + pb.rho));
        ga = ga - gw * pi;
    }
    return ga;
}

// The symmetric product a (x) b + b (x) a.
fn sym_outer(a: vec3<f32>, b: vec3<f32>) -> Sym {
    return Sym(a.x * b.x + a.x * b.x, a.y * b.y + a.y * b.y, a.z * b.z + a.z * b.z,
        a.x * b.y + b.x * a.y, a.x * b.z + b.x * a.z, a.y * b.z + b.y * a.z);
}

// A marker's extrapolated velocity and stress. Rough (mu not finite, or no wall normal): the
// mirrored velocity 2 v_b - v_bar and the stress as extrapolated. Otherwise the wall contact of
// coefficient mu: free-slip kinematics (the normal relative velocity mirrored, the tangential
// one carried through) and the traction's tangential part replaced by regularised Coulomb
// friction, s_hat min(mu max(-t.n, 0), Z |u|), Z = rho c the soil's impedance. CPU twin:
// `rates::apply_contact` through `ContactView::of`.
struct WallState { v: vec3<f32>, s: Sym }

fn wall_state(mk: Marker, mu: f32, impedance: f32, vbar: vec3<f32>, sigma: Sym) -> WallState {
    let vb = vec3<f32>(mk.vx, mk.vy, mk.vz);
    let n = vec3<f32>(mk.nx, mk.ny, mk.nz);
    if (!(dot(n, n) > 0.0) || !finite(mu)) { return WallState(vb * 2.0 - vbar, sigma); }
    let t = sym_mul_vec(sigma, n);
    let tn = dot(t, n);
    let tt = t - n * tn;
    let rel = vb - vbar;
    let rel_n = n * dot(rel, n);
    let v = vbar + rel_n * 2.0;
    let slip = rel_n - rel;
    let s = length(slip);
    var friction = vec3<f32>(0.0);
    if (s > 0.0 && mu > 0.0) { friction = slip * (min(mu * max(-tn, 0.0), impedance * s) / s); }
    return WallState(v, sym_add(sym_sub(sigma, sym_outer(tt, n)), sym_outer(friction, n)));
}

// max over non-negative floats with a u32 atomic: their bit patterns order like the values.
fn max_bits(x: f32) -> u32 { return bitcast<u32>(max(x, 0.0)); }

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

// The pair sums of a soil particle's rates with neighbour pb (is_soil: a particle, not a
// marker). CPU twin: `PairSums::add`.
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
