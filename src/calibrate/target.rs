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
use crate::input::{InputError, read_text};
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

/// One evaluation of the joint loop.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointIterate {
    /// Parameter values tried, in the order of [`JointRun::parameters`].
    pub parameters: [f64; 2],
    /// What the test measured, one per target.
    pub measured: [f64; 2],
    /// Their uncertainties (standard errors).
    pub uncertainty: [f64; 2],
}

/// The joint loop's settings: two parameters, one target each, the i-th measurement steered
/// mainly by the i-th parameter (a test's c and φ both move with the material's c and φ).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointSettings {
    /// Parameter names (material keys), for the record and the errors.
    pub parameters: [&'static str; 2],
    /// The values the test should measure.
    pub target: [f64; 2],
    /// Smallest tolerance of each, whatever the measurement's uncertainty.
    pub tolerance_floor: [f64; 2],
    /// Allowed range of each parameter (inclusive).
    pub range: [(f64, f64); 2],
    /// Most evaluations.
    pub max_evaluations: usize,
}

/// The joint loop's record.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointRun {
    /// Parameter names.
    pub parameters: [&'static str; 2],
    /// Every evaluation, in order.
    pub iterates: Vec<JointIterate>,
    /// The accepted parameters, if every target was met at once.
    pub converged: Option<[f64; 2]>,
    /// Why not, otherwise.
    pub failure: Option<String>,
}

/// Runs the joint loop from `start`: Broyden's method on the misses, each coordinate scaled by
/// its tolerance. The first Jacobian is the identity: the measurement moves one for one with
/// the typed value (an SPH sample's c and φ are the material's plus an offset of the
/// discretisation, which the loop removes); each evaluation then corrects it with Broyden's
/// rank-one update, which learns the coupling between the parameters (a larger φ raises the
/// measured c too). It stops when every measurement is within its uncertainty (or floor) of
/// its target. A step that would leave a parameter's range tries that range's end once, then
/// stops naming the parameter; a Jacobian that cannot be inverted stops as flat.
pub fn calibrate_jointly<E>(
    s: &JointSettings,
    start: [f64; 2],
    mut eval: impl FnMut([f64; 2]) -> Result<([f64; 2], [f64; 2]), E>,
) -> Result<JointRun, E> {
    let mut run = JointRun { parameters: s.parameters, iterates: Vec::new(), converged: None, failure: None };
    // Scaled coordinates: parameter / floor, measurement / floor.
    let sc = |v: [f64; 2]| -> [f64; 2] { [v[0] / s.tolerance_floor[0], v[1] / s.tolerance_floor[1]] };
    let mut jac = [[1.0, 0.0], [0.0, 1.0]];
    let mut x = start;
    let mut prev: Option<([f64; 2], [f64; 2])> = None;
    let mut edge_tried = [false; 2];
    loop {
        let (m, u) = eval(x)?;
        run.iterates.push(JointIterate { parameters: x, measured: m, uncertainty: u });
        let within = (0..2).all(|i| (m[i] - s.target[i]).abs() <= u[i].max(s.tolerance_floor[i]));
        if within {
            run.converged = Some(x);
            return Ok(run);
        }
        if run.iterates.len() >= s.max_evaluations {
            run.failure = Some(TargetError::Exhausted(run.iterates.len()).to_string());
            return Ok(run);
        }
        let (xs, ms) = (sc(x), sc(m));
        if let Some((px, pm)) = prev {
            let dx = [xs[0] - px[0], xs[1] - px[1]];
            let dm = [ms[0] - pm[0], ms[1] - pm[1]];
            let dd = dx[0] * dx[0] + dx[1] * dx[1];
            if dd > 0.0 {
                for (row, dmi) in jac.iter_mut().zip(dm) {
                    let r = dmi - (row[0] * dx[0] + row[1] * dx[1]);
                    row[0] += r * dx[0] / dd;
                    row[1] += r * dx[1] / dd;
                }
            }
        }
        prev = Some((xs, ms));
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        let scale = jac.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        if det.is_nan() || det.abs() <= 1e-9 * scale * scale {
            let p = &run.iterates[run.iterates.len() - 2];
            run.failure = Some(format!(
                "the measurements did not change independently between {:?} and {:?}: the loop cannot steer",
                p.parameters, x
            ));
            return Ok(run);
        }
        let r = [(s.target[0] - m[0]) / s.tolerance_floor[0], (s.target[1] - m[1]) / s.tolerance_floor[1]];
        let step = [(jac[1][1] * r[0] - jac[0][1] * r[1]) / det, (jac[0][0] * r[1] - jac[1][0] * r[0]) / det];
        let mut next = [(xs[0] + step[0]) * s.tolerance_floor[0], (xs[1] + step[1]) * s.tolerance_floor[1]];
        for (i, v) in next.iter_mut().enumerate() {
            let (lo, hi) = s.range[i];
            if !v.is_finite() || *v < lo || *v > hi {
                let edge = if *v > hi { hi } else { lo };
                if !edge_tried[i] && v.is_finite() && (x[i] - edge).abs() > 1e-12 * edge.abs().max(1.0) {
                    edge_tried[i] = true;
                    *v = edge;
                } else {
                    run.failure = Some(format!(
                        "{}: {}",
                        s.parameters[i],
                        TargetError::OutOfRange { target: s.target[i], lo, hi, at: x[i], measured: m[i] }
                    ));
                    return Ok(run);
                }
            }
        }
        x = next;
    }
}

/// Writes `base` with the keys `set` changed to `out`, under a header saying which command
/// wrote it and why (`why`, one line), and checks it by loading it back. Returns the path
/// written.
pub fn write_calibrated(base: &Path, set: &[(&str, f64)], why: &str, out: &Path) -> Result<String, CommandError> {
    let mut t = material_table(base)?;
    for (k, v) in set {
        t.insert((*k).into(), (*v).into());
    }
    let body = toml::to_string(&t).map_err(|e| CommandError::Output(e.to_string()))?;
    let text = format!("# Written by {why} from {}; other keys as there.\n{body}", base.display());
    std::fs::write(out, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", out.display())))?;
    load_material_file(out)?;
    Ok(out.display().to_string())
}

/// Reads a material file as a table, after checking it through the material loader.
pub fn material_table(path: &Path) -> Result<toml::Table, InputError> {
    load_material_file(path)?;
    let text = read_text(path)?;
    toml::from_str(&text).map_err(|e| InputError::file(path, e.to_string()))
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

    fn joint(target: [f64; 2]) -> JointSettings {
        JointSettings {
            parameters: ["friction_angle", "cohesion"],
            target,
            tolerance_floor: [0.5, 100.0],
            range: [(1.0, 60.0), (0.0, 1e6)],
            max_evaluations: 8,
        }
    }

    /// A sample whose φ reads 2° low and whose c reads 20 % low plus 40 Pa per degree of φ
    /// (coupled, as an envelope fitted over a few circles is): linear, so Broyden's method
    /// lands in a few steps.
    fn coupled(p: [f64; 2]) -> [f64; 2] {
        [p[0] - 2.0 + 0.0002 * p[1], 0.8 * p[1] + 40.0 * (p[0] - 30.0)]
    }

    #[test]
    fn the_joint_loop_meets_both_targets_of_a_coupled_response() {
        let r =
            calibrate_jointly::<()>(&joint([35.0, 2000.0]), [35.0, 2000.0], |p| Ok((coupled(p), [0.3, 80.0]))).unwrap();
        let c = r.converged.unwrap_or_else(|| panic!("{r:?}"));
        let m = coupled(c);
        assert!((m[0] - 35.0).abs() <= 0.5 && (m[1] - 2000.0).abs() <= 100.0, "{r:?}");
        assert!(r.iterates.len() <= 5, "{} evaluations: {r:?}", r.iterates.len());
    }

    #[test]
    fn the_joint_loop_names_the_parameter_it_cannot_reach_and_stops_when_flat() {
        // A cohesion the sample can only reach with a negative one.
        let r = calibrate_jointly::<()>(&joint([30.0, 10.0]), [30.0, 1000.0], |p| {
            Ok(([p[0], 0.5 * p[1] + 300.0], [0.3, 10.0]))
        })
        .unwrap();
        assert!(r.converged.is_none());
        assert_eq!(r.iterates.last().unwrap().parameters[1], 0.0, "tries the range end: {r:?}");
        let f = r.failure.unwrap();
        assert!(f.starts_with("cohesion: the target 10 needs a parameter outside [0, 1000000]"), "{f}");
        // The measured c does not follow the typed one: no step can be taken.
        let r = calibrate_jointly::<()>(&joint([30.0, 2000.0]), [30.0, 1000.0], |p| Ok(([p[0], 500.0], [0.3, 10.0])))
            .unwrap();
        assert!(r.failure.is_some_and(|f| f.contains("cannot steer")));
    }
}
