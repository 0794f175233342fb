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
    let (kc, kphi) = if k_per_plate.len() >= 2 {
        // k = kc (1/b) + kphi by least squares.
        let m = k_per_plate.len() as f64;
        let xs: Vec<f64> = k_per_plate.iter().map(|(b, _)| 1.0 / b).collect();
        let ys: Vec<f64> = k_per_plate.iter().map(|(_, k)| *k).collect();
        let (mx, my) = (xs.iter().sum::<f64>() / m, ys.iter().sum::<f64>() / m);
        let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        if sxx > 0.0 {
            let kc = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>() / sxx;
            (Some(kc), Some(my - kc * mx))
        } else {
            (None, None)
        }
    } else {
        (None, None)
    };
    Some(BekkerFit { kc, kphi, n, k_per_plate, r2, points: all.len() })
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
    }
}
