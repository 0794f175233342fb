// Modified Cam Clay return mapping: backward Euler with hardening inside the solve, stresses
// scaled by S = max(p, q/M) so f32 cannot overflow, the plastic volumetric strain x found by
// bracketed Brent solves. Line for line the CPU twin `ModifiedCamClay::correct`; WGSL has no
// closures, so the three scalar functions the solves need are one function with a selector.

struct MccCtx {
    big_p: f32, big_q: f32, c: f32, half_c: f32,
    x_end: f32, beta: f32, ln_c: f32, m: f32,
    m2: f32, g_s: f32,
}

const F_LOG: u32 = 0u;      // ln(2P'/c) - beta x: zero at x*, where 2P' = c-hat
const F_CAP: u32 = 1u;      // ln(P'/c) - beta x: zero at x0, where P' = c-hat
const F_RESIDUAL: u32 = 2u; // the flow-rule residual R(x)

fn mcc_p_at(k: MccCtx, x: f32) -> f32 {
    if (k.x_end == 0.0) { return k.big_p; }
    return k.half_c + (k.big_p - k.half_c) * (1.0 - x / k.x_end);
}

fn mcc_q_at(k: MccCtx, x: f32) -> f32 {
    let pp = mcc_p_at(k, x);
    return k.m * sqrt(max(pp * (k.c * exp(k.beta * x) - pp), 0.0));
}

fn mcc_fn(which: u32, k: MccCtx, x: f32) -> f32 {
    if (which == F_LOG) { return log(2.0 * mcc_p_at(k, x)) - k.ln_c - k.beta * x; }
    if (which == F_CAP) { return log(mcc_p_at(k, x)) - k.ln_c - k.beta * x; }
    let pp = mcc_p_at(k, x);
    let g = 2.0 * pp - k.c * exp(k.beta * x);
    let qq = mcc_q_at(k, x);
    return k.m2 * g * (qq - k.big_q) + 6.0 * k.g_s * x * qq;
}

// Brent's method on [a0, b0] with f(a0), f(b0) of opposite signs; y = 1 on success.
fn brent(which: u32, k: MccCtx, a0: f32, b0: f32, fa0: f32, fb0: f32, tol: f32) -> vec2<f32> {
    var a = a0;
    var b = b0;
    var fa = fa0;
    var fb = fb0;
    if (fa == 0.0) { return vec2<f32>(a, 1.0); }
    if (fb == 0.0) { return vec2<f32>(b, 1.0); }
    if ((fa > 0.0) == (fb > 0.0) || !finite(fa) || !finite(fb)) { return vec2<f32>(0.0, 0.0); }
    var c = a;
    var fc = fa;
    var d = b - a;
    var e = d;
    for (var it = 0u; it < 300u; it++) {
        if ((fb > 0.0) == (fc > 0.0)) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if (abs(fc) < abs(fb)) {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * F32_EPS * abs(b) + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if (abs(xm) <= tol1 || fb == 0.0) { return vec2<f32>(b, 1.0); }
        if (abs(e) >= tol1 && abs(fa) > abs(fb)) {
            let s = fb / fa;
            var p: f32;
            var q: f32;
            if (a == c) {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0) { q = -q; }
            p = abs(p);
            let min1 = 3.0 * xm * q - abs(tol1 * q);
            let min2 = abs(e * q);
            if (2.0 * p < min(min1, min2)) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        if (abs(d) > tol1) {
            b += d;
        } else {
            b += select(-tol1, tol1, xm > 0.0);
        }
        fb = mcc_fn(which, k, b);
        if (!finite(fb)) { return vec2<f32>(0.0, 0.0); }
    }
    return vec2<f32>(0.0, 0.0);
}

fn mcc_correct(mat: Material, trial: Sym, pc_io: ptr<function, f32>, sv: f32, moduli: vec2<f32>, err: ptr<function, u32>) -> Sym {
    let pc = *pc_io;
    if (!sym_finite(trial) || !finite(pc) || !finite(sv)) { *err = ERR_MCC_NONFINITE_TRIAL; return trial; }
    let p_tr = sym_pressure(trial);
    if (p_tr <= 0.0) { return sym_zero(); }
    if (pc <= 0.0) { *err = ERR_MCC_PC; return trial; }
    let s_tr = sym_dev(trial);
    let q_tr = von_mises_of_deviator(s_tr);
    let m2 = mat.m * mat.m;
    let scale = max(p_tr, q_tr / mat.m);
    var k: MccCtx;
    k.big_p = p_tr / scale;
    k.big_q = q_tr / scale;
    k.c = pc / scale;
    k.m = mat.m;
    k.m2 = m2;
    let f_tr = k.big_q * k.big_q + m2 * k.big_p * (k.big_p - k.c);
    let tol_f = 64.0 * F32_EPS * (k.big_q * k.big_q + m2 * k.big_p * (k.big_p + k.c));
    if (f_tr <= tol_f) { return trial; }
    if (!(moduli.x > 0.0 && moduli.y > 0.0)) { *err = ERR_MCC_MODULI; return trial; }
    let k_s = moduli.x / scale;
    k.g_s = moduli.y / scale;
    k.beta = sv / (mat.lambda - mat.kappa);
    k.ln_c = log(k.c);
    k.half_c = k.c / 2.0;
    k.x_end = (k.big_p - k.half_c) / k_s;
    let tiny = F32_MIN_POS;
    var x = 0.0;
    if (k.x_end != 0.0) {
        let g0 = log(2.0 * k.big_p) - k.ln_c;
        let g_end = -k.beta * k.x_end;
        var lo = k.x_end;
        var hi = 0.0;
        var g_lo = g_end;
        var g_hi = g0;
        if (k.x_end > 0.0) {
            lo = 0.0;
            hi = k.x_end;
            g_lo = g0;
            g_hi = g_end;
        }
        let rs = brent(F_LOG, k, lo, hi, g_lo, g_hi, tiny);
        if (rs.y == 0.0) { *err = ERR_MCC_NO_CONVERGENCE; return trial; }
        let x_star = rs.x;
        if (x_star == 0.0) {
            x = 0.0;
        } else if (k.x_end > 0.0) {
            let h0 = log(k.big_p) - k.ln_c;
            var x0 = 0.0;
            if (h0 > 0.0) {
                let r0s = brent(F_CAP, k, 0.0, x_star, h0, -0.6931472, tiny);
                if (r0s.y == 0.0) { *err = ERR_MCC_NO_CONVERGENCE; return trial; }
                x0 = r0s.x;
            }
            var r0: f32;
            if (x0 == 0.0) {
                r0 = min(mcc_fn(F_RESIDUAL, k, x0), -tiny);
            } else {
                r0 = -m2 * mcc_p_at(k, x0) * k.big_q;
            }
            if (k.big_q == 0.0 || r0 >= 0.0) {
                x = x0;
            } else {
                let r_star = 6.0 * k.g_s * x_star * mcc_q_at(k, x_star);
                let rx = brent(F_RESIDUAL, k, x0, x_star, r0, r_star, tiny);
                if (rx.y == 0.0) { *err = ERR_MCC_NO_CONVERGENCE; return trial; }
                x = rx.x;
            }
        } else {
            let r_star = 6.0 * k.g_s * x_star * mcc_q_at(k, x_star);
            let r0 = max(mcc_fn(F_RESIDUAL, k, 0.0), tiny);
            let rx = brent(F_RESIDUAL, k, x_star, 0.0, r_star, r0, tiny);
            if (rx.y == 0.0) { *err = ERR_MCC_NO_CONVERGENCE; return trial; }
            x = rx.x;
        }
    }
    var p_new = p_tr;
    if (x != 0.0) { p_new = mcc_p_at(k, x) * scale; }
    var ratio = 0.0;
    if (k.big_q > 0.0) { ratio = mcc_q_at(k, x) / k.big_q; }
    let out = sym_sub(sym_scale(s_tr, ratio), sym_iso(p_new));
    let pc_new = max(pc * exp(k.beta * x), mat.pc_floor);
    if (!sym_finite(out) || !finite(pc_new)) { *err = ERR_MCC_NONFINITE_RESULT; return trial; }
    *pc_io = pc_new;
    return out;
}
