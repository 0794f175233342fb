//! The calibration loop: adjust one material parameter until a virtual test measures a target.
//!
//! Each evaluation is a whole SPH test (minutes), and the measurement is noisy (a standard
//! error comes with it), so the loop is a safeguarded secant: the first step scales the
//! parameter in proportion to the miss, later steps follow the secant through the last two
//! points, and once the target is bracketed the step is kept inside the bracket (bisection
//! when the secant leaves it). It stops when the measurement is within its own uncertainty (or
//! a floor) of the target, and says so; out of the parameter's allowed range or out of
//! iterations it stops with what it measured, never with a silently clamped value.

use std::path::Path;

use serde::Serialize;

use super::CommandError;
use super::repose::material_table;
use crate::material::load_material_file;

/// One evaluation of the loop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Iterate {
    /// Parameter value tried.
    pub parameter: f64,
    /// What the test measured.
    pub measured: f64,
    /// Its uncertainty (standard error), same unit.
    pub uncertainty: f64,
}

/// The loop's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TargetSettings {
    /// The value the test should measure.
    pub target: f64,
    /// Smallest tolerance, whatever the measurement's own uncertainty (same unit).
    pub tolerance_floor: f64,
    /// Allowed parameter range (inclusive).
    pub range: (f64, f64),
    /// Most evaluations.
    pub max_evaluations: usize,
}

/// Why the loop stopped without meeting the target.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TargetError {
    /// The next value would leave the allowed range.
    #[error(
        "the target {target} needs a parameter outside [{lo}, {hi}] (at {at} the test measured {measured}); it cannot be reached with this model"
    )]
    OutOfRange {
        /// Target.
        target: f64,
        /// Range.
        lo: f64,
        /// Range.
        hi: f64,
        /// The last value tried.
        at: f64,
        /// What it measured.
        measured: f64,
    },
    /// The measurement does not change with the parameter.
    #[error("the measurement did not change between parameters {a} and {b} ({m}): the loop cannot steer")]
    Flat {
        /// First value.
        a: f64,
        /// Second value.
        b: f64,
        /// Measured at both.
        m: f64,
    },
    /// Out of evaluations.
    #[error("not within tolerance after {0} evaluations")]
    Exhausted(usize),
}

/// The loop's record.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetRun {
    /// Every evaluation, in order.
    pub iterates: Vec<Iterate>,
    /// The accepted parameter, if the target was met.
    pub converged: Option<f64>,
    /// Why not, otherwise.
    pub failure: Option<String>,
}

impl TargetSettings {
    fn tolerance(&self, it: &Iterate) -> f64 {
        it.uncertainty.max(self.tolerance_floor)
    }
}

/// Runs the loop from `start`: `eval(parameter)` runs the test and returns (measured,
/// uncertainty), or an error that ends the loop. The measurement is assumed to grow with the
/// parameter or fall with it, not both.
pub fn calibrate_to_target<E>(
    s: &TargetSettings,
    start: f64,
    mut eval: impl FnMut(f64) -> Result<(f64, f64), E>,
) -> Result<TargetRun, E> {
    let mut run = TargetRun { iterates: Vec::new(), converged: None, failure: None };
    let (lo, hi) = s.range;
    let mut x = start;
    // Bracket: (parameter, miss) with the miss of each sign, once seen.
    let mut below: Option<(f64, f64)> = None;
    let mut above: Option<(f64, f64)> = None;
    loop {
        let (m, u) = eval(x)?;
        let it = Iterate { parameter: x, measured: m, uncertainty: u };
        run.iterates.push(it);
        let miss = m - s.target;
        if miss.abs() <= s.tolerance(&it) {
            run.converged = Some(x);
            return Ok(run);
        }
        if run.iterates.len() >= s.max_evaluations {
            run.failure = Some(TargetError::Exhausted(run.iterates.len()).to_string());
            return Ok(run);
        }
        if miss < 0.0 {
            below = Some((x, miss));
        } else {
            above = Some((x, miss));
        }
        let n = run.iterates.len();
        let next = if n == 1 {
            // Proportional first step: the measurement scales with the parameter.
            if m.abs() > 0.0 { x * s.target / m } else { x * 1.5 }
        } else {
            let p = run.iterates[n - 2];
            if (m - p.measured).abs() < f64::EPSILON * m.abs().max(1.0) {
                run.failure = Some(TargetError::Flat { a: p.parameter, b: x, m }.to_string());
                return Ok(run);
            }
            x + (s.target - m) * (x - p.parameter) / (m - p.measured)
        };
        let next = match (below, above) {
            (Some((a, _)), Some((b, _))) => {
                let (l, h) = (a.min(b), a.max(b));
                if next > l && next < h { next } else { 0.5 * (a + b) }
            }
            _ => next,
        };
        if !(next >= lo && next <= hi && next.is_finite()) {
            // One try at the range's end in the right direction before giving up.
            let edge = if next > hi { hi } else { lo };
            if (x - edge).abs() > 1e-12 * edge.abs().max(1.0) && next.is_finite() {
                x = edge;
                continue;
            }
            run.failure = Some(TargetError::OutOfRange { target: s.target, lo, hi, at: x, measured: m }.to_string());
            return Ok(run);
        }
        x = next;
    }
}

/// Writes `base` with its friction angle set to `phi` to `out`, under a header saying which
/// command wrote it and why (`why`, one line), and checks it by loading it back. Returns the
/// path written.
pub fn write_calibrated(base: &Path, phi: f64, why: &str, out: &Path) -> Result<String, CommandError> {
    let mut t = material_table(base)?;
    t.insert("friction_angle".into(), phi.into());
    let body = toml::to_string(&t).map_err(|e| CommandError::Output(e.to_string()))?;
    let text = format!("# Written by {why} from {}; other keys as there.\n{body}", base.display());
    std::fs::write(out, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", out.display())))?;
    load_material_file(out)?;
    Ok(out.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(target: f64) -> TargetSettings {
        TargetSettings { target, tolerance_floor: 0.25, range: (1.0, 60.0), max_evaluations: 8 }
    }

    #[test]
    fn a_smooth_response_converges_in_a_few_evaluations() {
        // A pile angle of about half φ, bending (like the SPH piles of docs/calibration.md).
        let f = |phi: f64| 0.45 * phi + 0.004 * phi * phi - 1.0;
        let r = calibrate_to_target::<()>(&settings(20.0), 30.0, |p| Ok((f(p), 0.3))).unwrap();
        let c = r.converged.expect("converged");
        assert!((f(c) - 20.0).abs() <= 0.3, "{r:?}");
        assert!(r.iterates.len() <= 5, "{r:?}");
    }

    #[test]
    fn a_noisy_response_stays_inside_its_bracket() {
        let mut k = 0;
        let noise = [0.4, -0.5, 0.3, -0.2, 0.1, 0.0, 0.2, -0.1];
        let r = calibrate_to_target::<()>(&settings(20.0), 30.0, |p| {
            k += 1;
            Ok((0.5 * p + noise[k - 1], 0.5))
        })
        .unwrap();
        assert!(r.converged.is_some(), "{r:?}");
        assert!((r.converged.unwrap() - 40.0).abs() < 2.5, "{r:?}");
    }

    #[test]
    fn an_unreachable_target_says_so_after_trying_the_range_end() {
        let r = calibrate_to_target::<()>(&settings(45.0), 30.0, |p| Ok((0.5 * p, 0.3))).unwrap();
        assert!(r.converged.is_none());
        assert_eq!(r.iterates.last().unwrap().parameter, 60.0, "{r:?}");
        assert!(r.failure.unwrap().contains("outside [1, 60]"));
    }

    #[test]
    fn a_flat_response_and_errors_stop_the_loop() {
        let r = calibrate_to_target::<()>(&settings(20.0), 30.0, |_| Ok((10.0, 0.1))).unwrap();
        assert!(r.failure.unwrap().contains("did not change"));
        let e = calibrate_to_target(&settings(20.0), 30.0, |_| Err::<(f64, f64), _>("run failed")).unwrap_err();
        assert_eq!(e, "run failed");
    }
}
