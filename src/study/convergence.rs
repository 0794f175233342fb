//! Self-convergence of a result over a resolution ladder: the observed order `p` and the
//! extrapolated limit `f₀` of `f(h) = f₀ + C hᵖ` (Richardson), with an uncertainty.
//!
//! With three levels at a constant ratio `r` the order follows in closed form,
//! `p = ln((f₁ − f₂)/(f₂ − f₃)) / ln r` (levels coarse to fine). With more levels, or ratios that
//! vary, `p` is the least-squares fit: for a trial `p` the model is linear in `f₀` and `C`,
//! so the residual is a function of `p` alone and is minimised by golden-section search over
//! `p ∈ [P_MIN, P_MAX]`. The uncertainty of `p` is the spread of the three-level estimates of
//! consecutive triplets (their range), and that of the limit is Roache's grid convergence
//! index on the two finest levels, `GCI = 1.25 |f₂ − f₁| / (rᵖ − 1)`.

/// Smallest order searched.
pub const P_MIN: f64 = 0.05;
/// Largest order searched.
pub const P_MAX: f64 = 8.0;

/// Why a ladder gives no estimate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConvergenceError {
    /// Fewer than three levels.
    #[error("{got} resolution levels where a convergence estimate needs at least 3")]
    TooFewLevels {
        /// Levels given.
        got: usize,
    },
    /// `h` and `f` differ in length.
    #[error("{h} resolutions but {f} results")]
    LengthMismatch {
        /// Resolutions.
        h: usize,
        /// Results.
        f: usize,
    },
    /// A resolution that is not positive and finite, or repeated, or a result that is not finite.
    #[error("level {index}: {what}")]
    BadLevel {
        /// Index in the ladder as given.
        index: usize,
        /// What is wrong.
        what: String,
    },
    /// The differences between levels do not shrink monotonically: no asymptotic range.
    #[error("the results do not converge monotonically over the ladder ({0})")]
    NotMonotone(String),
}

/// The estimate of one ladder.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Convergence {
    /// Observed order (least squares over all levels).
    pub order: f64,
    /// Smallest and largest three-level order of consecutive triplets (equal for three levels).
    pub order_range: (f64, f64),
    /// Extrapolated limit `f₀`.
    pub limit: f64,
    /// The fitted coefficient `C` of `hᵖ`.
    pub coefficient: f64,
    /// Roache's grid convergence index on the two finest levels, as an absolute band on `f`.
    pub gci: f64,
    /// Root-mean-square residual of the fit.
    pub rms_residual: f64,
}

/// The least-squares `(f₀, C, residual²)` of `f = f₀ + C hᵖ` for a fixed `p`.
fn linear_fit(h: &[f64], f: &[f64], p: f64) -> (f64, f64, f64) {
    let n = h.len() as f64;
    let x: Vec<f64> = h.iter().map(|h| h.powf(p)).collect();
    let (mx, my) = (x.iter().sum::<f64>() / n, f.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(f).map(|(x, y)| (x - mx) * (y - my)).sum();
    let c = sxy / sxx;
    let f0 = my - c * mx;
    let r2 = x.iter().zip(f).map(|(x, y)| (y - f0 - c * x).powi(2)).sum();
    (f0, c, r2)
}

/// Three-level order of `(h, f)` triplet levels coarse to fine, for any two ratios: solves
/// `(f₁ − f₂)/(f₂ − f₃) = (h₁ᵖ − h₂ᵖ)/(h₂ᵖ − h₃ᵖ)` for `p` by bisection (closed form when the
/// ratios are equal).
fn triplet_order(h: [f64; 3], f: [f64; 3]) -> Option<f64> {
    let q = (f[0] - f[1]) / (f[1] - f[2]);
    if !(q.is_finite() && q > 0.0) {
        return None;
    }
    let g = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p)) - q;
    let (mut lo, mut hi) = (P_MIN, P_MAX);
    if g(lo) * g(hi) > 0.0 {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(lo) * g(mid) <= 0.0 { hi = mid } else { lo = mid }
    }
    Some(0.5 * (lo + hi))
}

/// Estimates the order and limit of results `f` at resolutions `h` (a length: d0, say; any
/// order of levels).
pub fn richardson(h: &[f64], f: &[f64]) -> Result<Convergence, ConvergenceError> {
    if h.len() != f.len() {
        return Err(ConvergenceError::LengthMismatch { h: h.len(), f: f.len() });
    }
    if h.len() < 3 {
        return Err(ConvergenceError::TooFewLevels { got: h.len() });
    }
    for (i, (h, f)) in h.iter().zip(f).enumerate() {
        if !(h.is_finite() && *h > 0.0) {
            return Err(ConvergenceError::BadLevel { index: i, what: format!("resolution {h} is not > 0") });
        }
        if !f.is_finite() {
            return Err(ConvergenceError::BadLevel { index: i, what: format!("result {f} is not finite") });
        }
    }
    // Coarse to fine.
    let mut levels: Vec<(f64, f64)> = h.iter().copied().zip(f.iter().copied()).collect();
    levels.sort_by(|a, b| b.0.total_cmp(&a.0));
    if let Some(w) = levels.windows(2).position(|w| w[0].0 <= w[1].0 * (1.0 + 1e-12)) {
        return Err(ConvergenceError::BadLevel {
            index: w + 1,
            what: format!("resolution {} is repeated", levels[w].0),
        });
    }
    let (hs, fs): (Vec<f64>, Vec<f64>) = levels.iter().copied().unzip();
    let diffs: Vec<f64> = fs.windows(2).map(|w| w[1] - w[0]).collect();
    let monotone = diffs.windows(2).all(|d| d[0] * d[1] > 0.0 && d[1].abs() < d[0].abs());
    if !monotone {
        let shown: Vec<String> = diffs.iter().map(|d| format!("{d:.4e}")).collect();
        return Err(ConvergenceError::NotMonotone(format!("differences coarse to fine: {}", shown.join(", "))));
    }
    let triplets: Vec<f64> = (0..hs.len() - 2)
        .filter_map(|i| triplet_order([hs[i], hs[i + 1], hs[i + 2]], [fs[i], fs[i + 1], fs[i + 2]]))
        .collect();
    if triplets.is_empty() {
        return Err(ConvergenceError::NotMonotone(format!("no triplet has an order in [{P_MIN}, {P_MAX}]")));
    }
    let order_range = triplets.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
    // Golden-section search of the residual over p.
    let cost = |p: f64| linear_fit(&hs, &fs, p).2;
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (P_MIN, P_MAX);
    let (mut x1, mut x2) = (b - phi * (b - a), a + phi * (b - a));
    let (mut c1, mut c2) = (cost(x1), cost(x2));
    for _ in 0..200 {
        if c1 <= c2 {
            b = x2;
            (x2, c2) = (x1, c1);
            x1 = b - phi * (b - a);
            c1 = cost(x1);
        } else {
            a = x1;
            (x1, c1) = (x2, c2);
            x2 = a + phi * (b - a);
            c2 = cost(x2);
        }
    }
    let order = 0.5 * (a + b);
    let (limit, coefficient, r2) = linear_fit(&hs, &fs, order);
    let n = hs.len();
    let r = hs[n - 2] / hs[n - 1];
    let gci = 1.25 * (fs[n - 1] - fs[n - 2]).abs() / (r.powf(order) - 1.0);
    Ok(Convergence { order, order_range, limit, coefficient, gci, rms_residual: (r2 / n as f64).sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_manufactured_sequence_gives_back_its_order_and_limit() {
        // f = 2 + 0.5 h^1.7 on a ratio-2 ladder, and on a ratio-√2 one given out of order.
        for hs in [vec![0.04, 0.02, 0.01, 0.005], vec![0.01, 0.04, 0.02 * 2f64.sqrt(), 0.02, 0.01 * 2f64.sqrt()]] {
            let fs: Vec<f64> = hs.iter().map(|h: &f64| 2.0 + 0.5 * h.powf(1.7)).collect();
            let c = richardson(&hs, &fs).expect("converges");
            assert!((c.order - 1.7).abs() < 0.01 * 1.7, "order {}", c.order);
            assert!((c.limit - 2.0).abs() < 0.01 * 2.0, "limit {}", c.limit);
            assert!(
                (c.order_range.0 - 1.7).abs() < 1e-6 && (c.order_range.1 - 1.7).abs() < 1e-6,
                "{:?}",
                c.order_range
            );
            // The finest level lies within the GCI band of the limit (for exact data the band is
            // 1.25 times the finest level's error).
            let finest = hs.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| fs[i]).expect("levels");
            let err = (finest - c.limit).abs();
            assert!(err < c.gci && c.gci < 1.3 * err, "error {err} vs GCI {}", c.gci);
        }
        // Three levels: the closed form.
        let c = richardson(&[0.4, 0.2, 0.1], &[1.0 - 0.16, 1.0 - 0.04, 1.0 - 0.01]).expect("order 2");
        assert!((c.order - 2.0).abs() < 1e-6 && (c.limit - 1.0).abs() < 1e-9, "{c:?}");
    }

    #[test]
    fn a_perturbed_sequence_reports_the_spread_of_its_order() {
        // ±0.5 % of the error term on each level: the order moves and its range says by how much.
        let hs: [f64; 4] = [0.04, 0.02, 0.01, 0.005];
        let wiggle = [1.005, 0.995, 1.005, 0.995];
        let fs: Vec<f64> = hs.iter().zip(wiggle).map(|(h, w)| 2.0 + 0.5 * w * h.powf(1.0)).collect();
        let c = richardson(&hs, &fs).expect("converges");
        assert!(c.order_range.0 < c.order && c.order < c.order_range.1, "{c:?}");
        assert!((c.order - 1.0).abs() < 0.05, "{c:?}");
        assert!((c.limit - 2.0).abs() < 0.01, "{c:?}");
    }

    #[test]
    fn ladders_without_an_asymptotic_range_are_refused() {
        let e = richardson(&[0.04, 0.02, 0.01], &[1.0, 1.2, 0.9]).expect_err("oscillates");
        assert!(matches!(e, ConvergenceError::NotMonotone(_)), "{e}");
        let e = richardson(&[0.04, 0.02, 0.01], &[1.0, 1.1, 1.3]).expect_err("diverges");
        assert!(matches!(e, ConvergenceError::NotMonotone(_)), "{e}");
        assert_eq!(richardson(&[0.04, 0.02], &[1.0, 1.1]), Err(ConvergenceError::TooFewLevels { got: 2 }));
        assert_eq!(richardson(&[0.04, 0.02, 0.01], &[1.0, 1.1]), Err(ConvergenceError::LengthMismatch { h: 3, f: 2 }));
        assert!(matches!(richardson(&[0.04, 0.02, 0.02], &[1.0, 1.1, 1.15]), Err(ConvergenceError::BadLevel { .. })));
        assert!(matches!(richardson(&[0.04, -0.02, 0.01], &[1.0, 1.1, 1.15]), Err(ConvergenceError::BadLevel { .. })));
    }
}
