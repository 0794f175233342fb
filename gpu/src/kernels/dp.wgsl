// Drucker-Prager / mu(I) plastic correction, radial return in the deviatoric plane at constant
// p; zero stress in tension for cohesionless soil, apex return for a cohesive cone. CPU twin:
// `DruckerPrager::correct`. Returns the stress; sets *err to an error code on failure.

fn dp_friction(mat: Material, p: f32, d: Sym) -> f32 {
    if (!(mat.mu_2 > mat.mu_s) || p <= 0.0) { return mat.mu_s; }
    let dev = sym_dev(d);
    let gamma_dot = sqrt(2.0 * sym_ddot(dev, dev));
    let inertial = gamma_dot * mat.grain_d / sqrt(p / mat.grain_rho);
    if (inertial <= 0.0) { return mat.mu_s; }
    return mat.mu_s + (mat.mu_2 - mat.mu_s) / (mat.i0 / inertial + 1.0);
}

fn dp_correct(mat: Material, trial: Sym, d: Sym, err: ptr<function, u32>) -> Sym {
    if (!sym_finite(trial)) { *err = ERR_DP_NONFINITE; return trial; }
    let p = sym_pressure(trial);
    if (mat.k <= 0.0 && p <= 0.0) { return sym_zero(); }
    if (mat.mu_s > 0.0 && p * mat.mu_s + mat.k <= 0.0) {
        let p_apex = -mat.k / mat.mu_s;
        return sym_iso(-p_apex);
    }
    let s = sym_dev(trial);
    let tau = sqrt(0.5 * sym_ddot(s, s));
    let tau_max = dp_friction(mat, p, d) * p + mat.k;
    if (tau <= tau_max) { return trial; }
    return sym_sub(sym_scale(s, tau_max / tau), sym_iso(p));
}
