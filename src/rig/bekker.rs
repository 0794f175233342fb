//! Bekker's pressure–sinkage law `p = (k_c / b + k_φ) zⁿ` fitted to plate tests.
//!
//! With one plate the fit gives the combined modulus `k = k_c/b + k_φ` and `n`; with plates of
//! two or more widths `b` it gives `k_c` and `k_φ` as well: a common exponent n is fitted to all
//! curves in log–log space (one intercept per plate), then `k` against `1/b` is a line of
//! slope `k_c` and intercept `k_φ`.

use serde::Serialize;

/// One plate's pressure–sinkage curve: `(z, p)` pairs in m and Pa.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateCurve {
    /// Plate width b (m): the radius of a circular plate, the smaller side of a rectangle.
    pub b: f64,
    /// Points (sinkage m, pressure Pa).
    pub points: Vec<(f64, f64)>,
}

/// A fit of Bekker's law.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BekkerFit {
    /// Cohesive modulus k_c (N/m^(n+1)); `None` with a single plate width.
    pub kc: Option<f64>,
    /// Frictional modulus k_φ (N/m^(n+2)); `None` with a single plate width.
    pub kphi: Option<f64>,
    /// Sinkage exponent n.
    pub n: f64,
    /// Standard error of n: the common slope of the log–log regression with one intercept per
    /// plate (`s² / Σ(x − x̄ᵢ)²`, `s²` the residual variance on N − G − 1 degrees of freedom
    /// for N points of G plates); `None` without a spare degree of freedom.
    pub standard_error_n: Option<f64>,
    /// Standard error of k_c: the larger of the log–log fit's uncertainty (each plate's
    /// intercept and the common n, carried through k = exp(intercept) and the line of k
    /// against 1/b by the delta method) and, with three or more widths, the scatter of the k's
    /// about that line (how far the soil is from Bekker's k_c / b + k_φ).
    pub standard_error_kc: Option<f64>,
    /// Standard error of k_φ, likewise.
    pub standard_error_kphi: Option<f64>,
    /// Combined modulus `k = k_c/b + k_φ` of each plate, with its width b (m).
    pub k_per_plate: Vec<(f64, f64)>,
    /// Coefficient of determination of the log–log fit.
    pub r2: f64,
    /// Points used (sinkage above 20 % of each curve's largest, positive pressure).
    pub points: usize,
}

/// Fits the law; `None` when no curve has enough points (at least 3 with z > 0, p > 0).
pub fn fit(curves: &[PlateCurve]) -> Option<BekkerFit> {
    let mut groups = Vec::new();
    for c in curves {
        let zmax = c.points.iter().map(|p| p.0).fold(0.0, f64::max);
        let pts: Vec<(f64, f64)> = c
            .points
            .iter()
            .filter(|(z, p)| *z > 0.2 * zmax && *z > 0.0 && *p > 0.0)
            .map(|(z, p)| (z.ln(), p.ln()))
            .collect();
        if pts.len() >= 3 {
            groups.push((c.b, pts));
        }
    }
    if groups.is_empty() {
        return None;
    }
    // Common slope n, one intercept per plate.
    let (mut sxy, mut sxx) = (0.0, 0.0);
    let means: Vec<(f64, f64)> = groups
        .iter()
        .map(|(_, g)| {
            let m = g.len() as f64;
            (g.iter().map(|p| p.0).sum::<f64>() / m, g.iter().map(|p| p.1).sum::<f64>() / m)
        })
        .collect();
    for ((_, g), (mx, my)) in groups.iter().zip(&means) {
        for (x, y) in g {
            sxy += (x - mx) * (y - my);
            sxx += (x - mx) * (x - mx);
        }
    }
    if sxx <= 0.0 {
        return None;
    }
    let n = sxy / sxx;
    let k_per_plate: Vec<(f64, f64)> =
        groups.iter().zip(&means).map(|((b, _), (mx, my))| (*b, (my - n * mx).exp())).collect();
    let (mut ss_res, mut ss_tot) = (0.0, 0.0);
    let all: Vec<(f64, f64)> = groups.iter().flat_map(|(_, g)| g.iter().copied()).collect();
    let ybar = all.iter().map(|p| p.1).sum::<f64>() / all.len() as f64;
    for ((_, g), (mx, my)) in groups.iter().zip(&means) {
        let a = my - n * mx;
        for (x, y) in g {
            ss_res += (y - a - n * x).powi(2);
            ss_tot += (y - ybar).powi(2);
        }
    }
    let r2 = if ss_tot > 0.0 { 1.0 - ss_res / ss_tot } else { 1.0 };
    let dof = all.len() as f64 - groups.len() as f64 - 1.0;
    let s2 = (dof > 0.0).then(|| ss_res / dof);
    let standard_error_n = s2.map(|s2| (s2 / sxx).sqrt());
    // Covariance of the intercepts aᵢ = ȳᵢ − n x̄ᵢ of the pooled regression:
    // s² (δᵢⱼ / Nᵢ + x̄ᵢ x̄ⱼ / Sxx) (they share the slope's error).
    let cov_a = |i: usize, j: usize, s2: f64| {
        let own = if i == j { 1.0 / groups[i].1.len() as f64 } else { 0.0 };
        s2 * (own + means[i].0 * means[j].0 / sxx)
    };
    let (mut kc, mut kphi, mut se_kc, mut se_kphi) = (None, None, None, None);
    if k_per_plate.len() >= 2 {
        // k = kc (1/b) + kphi by least squares: kc = Σ wᵢ kᵢ, kphi = Σ vᵢ kᵢ.
        let m = k_per_plate.len() as f64;
        let xs: Vec<f64> = k_per_plate.iter().map(|(b, _)| 1.0 / b).collect();
        let ks: Vec<f64> = k_per_plate.iter().map(|(_, k)| *k).collect();
        let mx = xs.iter().sum::<f64>() / m;
        let sxx_b: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        if sxx_b > 0.0 {
            let w: Vec<f64> = xs.iter().map(|x| (x - mx) / sxx_b).collect();
            let v: Vec<f64> = w.iter().map(|wi| 1.0 / m - mx * wi).collect();
            kc = Some(w.iter().zip(&ks).map(|(a, b)| a * b).sum());
            kphi = Some(v.iter().zip(&ks).map(|(a, b)| a * b).sum());
            // Delta method: kᵢ = exp(aᵢ), so Cov(kᵢ, kⱼ) = kᵢ kⱼ Cov(aᵢ, aⱼ).
            if let Some(s2) = s2 {
                let var = |c: &[f64]| {
                    let mut t = 0.0;
                    for i in 0..ks.len() {
                        for j in 0..ks.len() {
                            t += c[i] * c[j] * ks[i] * ks[j] * cov_a(i, j, s2);
                        }
                    }
                    t.max(0.0).sqrt()
                };
                (se_kc, se_kphi) = (Some(var(&w)), Some(var(&v)));
            }
            // With three or more widths the scatter of the k's about their line measures how
            // far they are from Bekker's k_c / b + k_φ; the larger of the two errors is kept.
            if m > 2.0 {
                let (a, b) = (kphi.unwrap_or(0.0), kc.unwrap_or(0.0));
                let s2_line = xs.iter().zip(&ks).map(|(x, k)| (k - a - b * x).powi(2)).sum::<f64>() / (m - 2.0);
                let line_kc = (s2_line / sxx_b).sqrt();
                let line_kphi = (s2_line * (1.0 / m + mx * mx / sxx_b)).sqrt();
                se_kc = Some(se_kc.map_or(line_kc, |e| e.max(line_kc)));
                se_kphi = Some(se_kphi.map_or(line_kphi, |e| e.max(line_kphi)));
            }
        }
    }
    Some(BekkerFit {
        kc,
        kphi,
        n,
        standard_error_n,
        standard_error_kc: se_kc,
        standard_error_kphi: se_kphi,
        k_per_plate,
        r2,
        points: all.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_known_parameters() {
        let (kc, kphi, n) = (2.0e4, 8.0e5, 1.1);
        let curves: Vec<PlateCurve> = [0.05, 0.1]
            .iter()
            .map(|&b| PlateCurve {
                b,
                points: (1..40).map(|i| i as f64 * 1e-3).map(|z| (z, (kc / b + kphi) * z.powf(n))).collect(),
            })
            .collect();
        let f = fit(&curves).expect("fit");
        assert!((f.n - n).abs() < 1e-9);
        assert!((f.kc.expect("kc") - kc).abs() / kc < 1e-6);
        assert!((f.kphi.expect("kphi") - kphi).abs() / kphi < 1e-6);
        assert!(f.r2 > 0.999_999);
        let one = fit(&curves[..1]).expect("fit");
        assert!(one.kc.is_none() && (one.k_per_plate[0].1 - (kc / 0.05 + kphi)).abs() < 1e-3);
        assert!(f.standard_error_n.is_some_and(|s| s < 1e-9), "exact data: {:?}", f.standard_error_n);
        assert!(f.standard_error_kc.is_some_and(|s| s < 1e-6 * kc), "exact data: {:?}", f.standard_error_kc);
    }

    /// The standard errors against a Monte-Carlo estimate: 400 noisy repeats of three plates'
    /// curves (5 % multiplicative noise on p); the reported errors (root mean square) within
    /// 20 % of the spread of the fitted values.
    #[test]
    fn standard_errors_match_a_monte_carlo_spread() {
        let (kc, kphi, n) = (3.0e4, 6.0e5, 0.9);
        let widths = [0.04, 0.06, 0.1];
        // A small deterministic generator (xorshift) and Box–Muller normals.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut normal = move || {
            let (u, v) = (uniform().max(1e-300), uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let (mut ns, mut kcs, mut kphis, mut se_n, mut se_kc, mut se_kphi) =
            (Vec::new(), Vec::new(), Vec::new(), 0.0, 0.0, 0.0);
        let trials = 400;
        for _ in 0..trials {
            let curves: Vec<PlateCurve> = widths
                .iter()
                .map(|&b| PlateCurve {
                    b,
                    points: (1..30)
                        .map(|i| i as f64 * 1e-3)
                        .map(|z| (z, (kc / b + kphi) * z.powf(n) * (0.05 * normal()).exp()))
                        .collect(),
                })
                .collect();
            let f = fit(&curves).expect("fit");
            ns.push(f.n);
            kcs.push(f.kc.expect("kc"));
            kphis.push(f.kphi.expect("kphi"));
            se_kphi += f.standard_error_kphi.expect("se kphi").powi(2) / trials as f64;
            se_n += f.standard_error_n.expect("se n") / trials as f64;
            se_kc += f.standard_error_kc.expect("se kc").powi(2) / trials as f64;
        }
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let (mc_n, mc_kc) = (sd(&ns), sd(&kcs));
        assert!((se_n / mc_n - 1.0).abs() < 0.2, "n: reported {se_n:.3e}, Monte Carlo {mc_n:.3e}");
        let (rms_kc, rms_kphi, mc_kphi) = (se_kc.sqrt(), se_kphi.sqrt(), sd(&kphis));
        eprintln!("n {se_n:.3e} vs {mc_n:.3e}; kc {rms_kc:.3e} vs {mc_kc:.3e}; kphi {rms_kphi:.3e} vs {mc_kphi:.3e}");
        assert!((rms_kc / mc_kc - 1.0).abs() < 0.2, "k_c: reported {rms_kc:.3e}, Monte Carlo {mc_kc:.3e}");
        assert!((rms_kphi / mc_kphi - 1.0).abs() < 0.2, "k_φ: reported {rms_kphi:.3e}, Monte Carlo {mc_kphi:.3e}");
    }
}
