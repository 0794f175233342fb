//! Least-squares fits with their standard errors: a straight line, a line through the origin,
//! a common slope over several groups, and the Mohr–Coulomb envelope of Mohr circles (with
//! cohesion, or through the origin).
//!
//! Standard errors are the usual ones of ordinary least squares, from the residual variance
//! with the degrees of freedom left after the fit; with no degree of freedom left (two points
//! on a line) they are `None`, not zero.

use serde::Serialize;

/// A fitted straight line `y = intercept + slope x`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Line {
    /// Intercept at x = 0.
    pub intercept: f64,
    /// Slope.
    pub slope: f64,
    /// Standard error of the intercept.
    pub se_intercept: Option<f64>,
    /// Standard error of the slope.
    pub se_slope: Option<f64>,
    /// Covariance of intercept and slope.
    #[serde(skip)]
    pub cov: Option<f64>,
    /// Root-mean-square residual.
    pub rms_residual: f64,
    /// Points fitted.
    pub points: usize,
}

/// Why a fit could not be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FitError {
    /// Fewer points than the fit needs.
    #[error("{got} points where the fit needs at least {need}")]
    TooFewPoints {
        /// Points given.
        got: usize,
        /// Points needed.
        need: usize,
    },
    /// The x and y of a fit have different lengths.
    #[error("{x} x values against {y} y values; a fit needs one y per x")]
    LengthMismatch {
        /// x values given.
        x: usize,
        /// y values given.
        y: usize,
    },
    /// All x values are equal: no slope is defined.
    #[error("all x values are equal, so no slope can be fitted")]
    Degenerate,
    /// The envelope is not a Mohr–Coulomb line of this material class.
    #[error("{0}")]
    NotMohrCoulomb(String),
}

fn same_length(x: &[f64], y: &[f64]) -> Result<(), FitError> {
    if x.len() == y.len() { Ok(()) } else { Err(FitError::LengthMismatch { x: x.len(), y: y.len() }) }
}

fn mean(v: impl Iterator<Item = f64> + Clone) -> f64 {
    let n = v.clone().count() as f64;
    v.sum::<f64>() / n
}

/// Ordinary least squares of `y` on `x`.
pub fn line(x: &[f64], y: &[f64]) -> Result<Line, FitError> {
    same_length(x, y)?;
    let n = x.len();
    if n < 2 {
        return Err(FitError::TooFewPoints { got: n, need: 2 });
    }
    let (xm, ym) = (mean(x.iter().copied()), mean(y.iter().copied()));
    let sxx: f64 = x.iter().map(|a| (a - xm).powi(2)).sum();
    if sxx <= 0.0 {
        return Err(FitError::Degenerate);
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum();
    let slope = sxy / sxx;
    let intercept = ym - slope * xm;
    let ssr: f64 = x.iter().zip(y).map(|(a, b)| (b - intercept - slope * a).powi(2)).sum();
    let s2 = (n > 2).then(|| ssr / (n - 2) as f64);
    Ok(Line {
        intercept,
        slope,
        se_intercept: s2.map(|s2| (s2 * (1.0 / n as f64 + xm * xm / sxx)).sqrt()),
        se_slope: s2.map(|s2| (s2 / sxx).sqrt()),
        cov: s2.map(|s2| -xm * s2 / sxx),
        rms_residual: (ssr / n as f64).sqrt(),
        points: n,
    })
}

/// A slope through the origin, `y = slope x`, with its standard error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Proportional {
    /// Slope.
    pub slope: f64,
    /// Standard error of the slope.
    pub se_slope: Option<f64>,
    /// Points fitted.
    pub points: usize,
}

/// Least squares of `y = b x`.
pub fn proportional(x: &[f64], y: &[f64]) -> Result<Proportional, FitError> {
    same_length(x, y)?;
    let n = x.len();
    if n < 1 {
        return Err(FitError::TooFewPoints { got: n, need: 1 });
    }
    let sxx: f64 = x.iter().map(|a| a * a).sum();
    if sxx <= 0.0 {
        return Err(FitError::Degenerate);
    }
    let slope = x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>() / sxx;
    let ssr: f64 = x.iter().zip(y).map(|(a, b)| (b - slope * a).powi(2)).sum();
    let se_slope = (n > 1).then(|| (ssr / (n - 1) as f64 / sxx).sqrt());
    Ok(Proportional { slope, se_slope, points: n })
}

/// One slope shared by several groups of points, each with its own intercept (the swelling
/// lines of several unloading branches). Returns the slope, its standard error and the
/// intercept of each group.
pub fn common_slope(groups: &[(Vec<f64>, Vec<f64>)]) -> Result<(f64, Option<f64>, Vec<f64>), FitError> {
    for (x, y) in groups {
        same_length(x, y)?;
    }
    let n: usize = groups.iter().map(|g| g.0.len()).sum();
    let k = groups.len();
    if groups.iter().any(|g| g.0.len() < 2) || n < 2 {
        return Err(FitError::TooFewPoints { got: groups.iter().map(|g| g.0.len()).min().unwrap_or(0), need: 2 });
    }
    let means: Vec<(f64, f64)> =
        groups.iter().map(|(x, y)| (mean(x.iter().copied()), mean(y.iter().copied()))).collect();
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for ((x, y), (xm, ym)) in groups.iter().zip(&means) {
        sxx += x.iter().map(|a| (a - xm).powi(2)).sum::<f64>();
        sxy += x.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum::<f64>();
    }
    if sxx <= 0.0 {
        return Err(FitError::Degenerate);
    }
    let slope = sxy / sxx;
    let intercepts: Vec<f64> = means.iter().map(|(xm, ym)| ym - slope * xm).collect();
    let ssr: f64 = groups
        .iter()
        .zip(&intercepts)
        .map(|((x, y), a)| x.iter().zip(y).map(|(u, v)| (v - a - slope * u).powi(2)).sum::<f64>())
        .sum();
    let se = (n > k + 1).then(|| (ssr / (n - k - 1) as f64 / sxx).sqrt());
    Ok((slope, se, intercepts))
}

/// The Mohr–Coulomb envelope `τ = c + σ tan φ` tangent to Mohr circles, with standard errors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MohrCoulomb {
    /// Cohesion c (Pa).
    pub c: f64,
    /// Friction angle φ (degrees).
    pub phi: f64,
    /// Standard error of c (Pa).
    pub se_c: Option<f64>,
    /// Standard error of φ (degrees).
    pub se_phi: Option<f64>,
    /// Circles fitted.
    pub circles: usize,
}

/// Fits the tangent envelope to circles given by their minor and major principal stresses at
/// failure (compression positive, Pa).
///
/// A line is tangent to every circle exactly when the circles' radii `t = (σ1 − σ3)/2` lie
/// on `t = c cos φ + s sin φ` against their centres `s = (σ1 + σ3)/2`: the fit is the least
/// squares line of t on s, then `sin φ = slope`, `c = intercept / cos φ`, with standard errors
/// carried through by the delta method (with the intercept–slope covariance).
pub fn mohr_coulomb(sigma3: &[f64], sigma1: &[f64]) -> Result<MohrCoulomb, FitError> {
    same_length(sigma3, sigma1)?;
    let s: Vec<f64> = sigma3.iter().zip(sigma1).map(|(a, b)| 0.5 * (a + b)).collect();
    let t: Vec<f64> = sigma3.iter().zip(sigma1).map(|(a, b)| 0.5 * (b - a)).collect();
    let l = line(&s, &t)?;
    if !(l.slope > 0.0 && l.slope < 1.0) {
        return Err(FitError::NotMohrCoulomb(format!(
            "the circles' radii grow with slope {:.4} against their centres; a frictional envelope needs a slope in (0, 1)",
            l.slope
        )));
    }
    let (sin, cos) = (l.slope, (1.0 - l.slope * l.slope).sqrt());
    let c = l.intercept / cos;
    let se_phi = l.se_slope.map(|se| (se / cos).to_degrees());
    // c = a / sqrt(1 − b²): ∂c/∂a = 1/cos φ, ∂c/∂b = a b / cos³ φ.
    let se_c = match (l.se_intercept, l.se_slope, l.cov) {
        (Some(sa), Some(sb), Some(cov)) => {
            let (da, db) = (1.0 / cos, l.intercept * sin / cos.powi(3));
            Some((da * da * sa * sa + db * db * sb * sb + 2.0 * da * db * cov).max(0.0).sqrt())
        }
        _ => None,
    };
    Ok(MohrCoulomb { c, phi: sin.asin().to_degrees(), se_c, se_phi, circles: s.len() })
}

/// The cohesionless envelope `τ = σ tan φ` (c = 0) tangent to Mohr circles given by σ3 and σ1
/// (compression positive): the least-squares slope of the radii on the centres through the
/// origin is sin φ. The critical state of a Cam Clay soil (q = M p) is such an envelope.
/// Returns φ and its standard error (degrees; `None` with one circle).
pub fn mohr_coulomb_cohesionless(sigma3: &[f64], sigma1: &[f64]) -> Result<(f64, Option<f64>), FitError> {
    same_length(sigma3, sigma1)?;
    let s: Vec<f64> = sigma3.iter().zip(sigma1).map(|(a, b)| 0.5 * (a + b)).collect();
    let t: Vec<f64> = sigma3.iter().zip(sigma1).map(|(a, b)| 0.5 * (b - a)).collect();
    let p = proportional(&s, &t)?;
    if !(p.slope > 0.0 && p.slope < 1.0) {
        return Err(FitError::NotMohrCoulomb(format!(
            "the circles' radii grow with slope {:.4} against their centres; a frictional envelope needs a slope in (0, 1)",
            p.slope
        )));
    }
    let cos = (1.0 - p.slope * p.slope).sqrt();
    Ok((p.slope.asin().to_degrees(), p.se_slope.map(|se| (se / cos).to_degrees())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn a_line_through_exact_points_is_recovered_with_zero_error() {
        let x = [1.0, 2.0, 4.0, 7.0];
        let y: Vec<f64> = x.iter().map(|a| 3.0 - 0.5 * a).collect();
        let l = line(&x, &y).expect("fit");
        assert!((l.slope + 0.5).abs() < 1e-14 && (l.intercept - 3.0).abs() < 1e-14);
        assert!(l.se_slope.expect("se") < 1e-14);
        let two = line(&x[..2], &y[..2]).expect("fit");
        assert_eq!(two.se_slope, None, "no degree of freedom left: no standard error");
        assert_eq!(line(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), Err(FitError::Degenerate));
    }

    #[test]
    fn a_common_slope_ignores_the_offsets_between_groups() {
        let g = |a: f64, xs: &[f64]| (xs.to_vec(), xs.iter().map(|x| a - 0.02 * x).collect::<Vec<_>>());
        let (b, se, a) = common_slope(&[g(2.0, &[1.0, 2.0, 3.0]), g(1.7, &[2.5, 4.0])]).expect("fit");
        assert!((b + 0.02).abs() < 1e-15 && se.expect("se") < 1e-15);
        assert!((a[0] - 2.0).abs() < 1e-14 && (a[1] - 1.7).abs() < 1e-14);
    }

    /// Circles from a known line: the envelope is recovered exactly.
    #[test]
    fn mohr_coulomb_recovers_a_known_envelope_exactly() {
        for (c, phi) in [(0.0, 30.0), (5000.0, 25.0), (1200.0, 41.0)] {
            let (s3, s1) = circles(c, phi, &[5e3, 10e3, 20e3, 40e3, 80e3]);
            let f = mohr_coulomb(&s3, &s1).expect("fit");
            assert!((f.phi - phi).abs() < 1e-10, "φ {} against {phi}", f.phi);
            assert!((f.c - c).abs() < 1e-8 * (1.0 + c), "c {} against {c}", f.c);
        }
    }

    /// σ1 at failure for each σ3 on the envelope (c, φ): σ1 = σ3 Nφ + 2 c √Nφ.
    fn circles(c: f64, phi: f64, s3: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = (45.0 + 0.5 * phi).to_radians().tan().powi(2);
        (s3.to_vec(), s3.iter().map(|s| s * n + 2.0 * c * n.sqrt()).collect())
    }

    /// Noisy failure stresses: the reported standard errors match the spread of the fitted c
    /// and φ over many noisy samples within 20 %.
    #[test]
    fn mohr_coulomb_standard_errors_match_a_monte_carlo_spread() {
        let (c, phi) = (3000.0, 32.0);
        let s3 = [5e3, 10e3, 15e3, 20e3, 30e3, 40e3, 50e3, 60e3, 80e3, 100e3];
        let (_, s1) = circles(c, phi, &s3);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let noise = 1500.0;
        let trials = 4000;
        let (mut cs, mut phis, mut se_c, mut se_phi) = (Vec::new(), Vec::new(), 0.0, 0.0);
        for _ in 0..trials {
            // Gaussian noise on σ1 (Box–Muller).
            let noisy: Vec<f64> = s1
                .iter()
                .map(|s| {
                    let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                    s + noise * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
                })
                .collect();
            let f = mohr_coulomb(&s3, &noisy).expect("fit");
            cs.push(f.c);
            phis.push(f.phi);
            se_c += f.se_c.expect("se") / trials as f64;
            se_phi += f.se_phi.expect("se") / trials as f64;
        }
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let (sd_c, sd_phi) = (sd(&cs), sd(&phis));
        assert!((se_c / sd_c - 1.0).abs() < 0.2, "se(c) {se_c} against a spread of {sd_c}");
        assert!((se_phi / sd_phi - 1.0).abs() < 0.2, "se(φ) {se_phi} against a spread of {sd_phi}");
    }

    #[test]
    fn the_cohesionless_envelope_recovers_a_critical_state_angle() {
        let (s3, s1) = circles(0.0, 30.0, &[10e3, 20e3, 35e3]);
        let (phi, se) = mohr_coulomb_cohesionless(&s3, &s1).expect("fit");
        assert!((phi - 30.0).abs() < 1e-10 && se.expect("se") < 1e-10);
        assert!(mohr_coulomb_cohesionless(&[1.0], &[1.0]).is_err(), "equal stresses: no friction");
    }

    #[test]
    fn mismatched_lengths_are_errors_not_panics() {
        let e = FitError::LengthMismatch { x: 3, y: 2 };
        assert_eq!(line(&[1.0, 2.0, 3.0], &[1.0, 2.0]), Err(e.clone()));
        assert_eq!(proportional(&[1.0, 2.0, 3.0], &[1.0, 2.0]), Err(e.clone()));
        assert_eq!(mohr_coulomb(&[1.0, 2.0, 3.0], &[4.0, 5.0]), Err(e.clone()));
        assert_eq!(common_slope(&[(vec![1.0, 2.0, 3.0], vec![1.0, 2.0])]), Err(e));
    }

    #[test]
    fn an_envelope_steeper_than_any_friction_angle_is_an_error() {
        // Radii growing faster than the centres (σ3 falling as σ1 rises), and radii shrinking.
        assert!(matches!(mohr_coulomb(&[3.0, 2.0, 1.0], &[4.0, 8.0, 12.0]), Err(FitError::NotMohrCoulomb(_))));
        assert!(matches!(mohr_coulomb(&[1.0, 2.0, 3.0], &[5.0, 5.0, 5.0]), Err(FitError::NotMohrCoulomb(_))));
    }
}
