//! `regolith calibrate cone`: the cone index profile of the SPH soil. A cone penetrometer rig
//! scene is run (one point of the sweep runner: recorded, resumable) and its cone index —
//! force over the cone's base area — is averaged over depth layers of the base, once the cone
//! is fully in the soil, with the spread in each layer; the cone index gradient G of
//! `CI = CI₀ + G z` (Wismer and Luth describe a uniform cohesionless soil by its gradient; the
//! intercept holds what the cone's own height adds, since z is the depth of its base) is
//! fitted through the layer means with standard errors.

use std::path::PathBuf;

use serde::Serialize;

use super::CommandError;
use crate::input::InputError;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use crate::scene::{RigSpec, load_scene};
use crate::sweep::{Plan, Record, forget, read_all, run_local};

/// What `regolith calibrate cone` reads.
#[derive(Clone, Debug)]
pub struct ConeInputs {
    /// A scene with a cone rig (`[rig] type = "cone"`).
    pub scene: PathBuf,
    /// Overrides (`--set KEY=VALUE`).
    pub sets: Vec<(String, toml::Value)>,
    /// Thickness of the depth layers (m).
    pub layer: f64,
    /// Output folder.
    pub out: PathBuf,
    /// Keep the run if it is already recorded in `out`.
    pub resume: bool,
}

/// One depth layer of the profile.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ConeLayer {
    /// Top and bottom of the layer: depth of the cone's base (m).
    pub from: f64,
    /// Bottom (m).
    pub to: f64,
    /// Mean cone index over the layer (Pa).
    pub cone_index: f64,
    /// Its standard deviation over the layer's samples (Pa).
    pub std_dev: f64,
    /// Samples (one per exchange).
    pub samples: usize,
}

/// `cone.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ConeCalibration {
    /// "cone_penetrometer".
    pub test: &'static str,
    /// The scene.
    pub scene: String,
    /// The profile, from the surface down.
    pub layers: Vec<ConeLayer>,
    /// Cone index gradient G of `CI = CI₀ + G z`, through the layer means (Pa/m).
    pub gradient: Option<f64>,
    /// Its standard error (Pa/m), from the layer means' scatter about the line (three or
    /// more layers).
    pub standard_error_gradient: Option<f64>,
    /// The line's intercept CI₀ at base depth 0 (Pa).
    pub intercept: Option<f64>,
    /// Its standard error (Pa).
    pub standard_error_intercept: Option<f64>,
    /// The run's wall-clock time (s).
    pub wall_s: f64,
    /// The command that reproduces the run.
    pub command: String,
    /// Plots written.
    pub plots: Vec<String>,
}

/// Runs the cone scene (unless recorded and `resume`), and writes `cone.json` and
/// `cone_index.png` / `.svg`.
pub fn calibrate_cone(inp: &ConeInputs) -> Result<ConeCalibration, CommandError> {
    if !(inp.layer.is_finite() && inp.layer > 0.0) {
        return Err(InputError::flag("--layer", format!("must be > 0 m (got {})", inp.layer)).into());
    }
    let scene = load_scene(&inp.scene, &inp.sets)?;
    let Some(RigSpec::Cone { depth, .. }) = &scene.rig else {
        return Err(InputError::key(&inp.scene, "rig.type", "calibrate cone needs a cone rig (type = \"cone\")").into());
    };
    if inp.layer > *depth {
        return Err(InputError::flag(
            "--layer",
            format!("{} m is thicker than the push (rig.depth = {depth} m): no layer would fill", inp.layer),
        )
        .into());
    }
    let plan = Plan::from_overrides(&inp.scene, vec![inp.sets.clone()])?;
    if !inp.resume {
        forget(&inp.out)?;
    }
    run_local(&plan, &inp.out, None, 1, true, false)?;
    let p = &plan.points[0];
    let rec = read_all(&inp.out)?.into_iter().find(|r| r.id == p.id);
    let rec = match rec {
        Some(r) if r.ok() => r,
        Some(r) => return Err(CommandError::Run(format!("the cone run failed: {}", r.error.unwrap_or_default()))),
        None => return Err(CommandError::Run("the cone run left no record".into())),
    };
    let curve = curve_of(&rec).ok_or_else(|| CommandError::Run("the cone run's summary holds no cone curve".into()))?;
    let layers = profile(&curve, inp.layer);
    let line = line(&layers);
    let plots = write_figure(&figure(&curve, &layers, line), &inp.out, "cone_index")
        .map_err(|e| CommandError::Output(e.to_string()))?
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let report = ConeCalibration {
        test: "cone_penetrometer",
        scene: inp.scene.display().to_string(),
        layers,
        gradient: line.map(|l| l.slope),
        standard_error_gradient: line.and_then(|l| l.se_slope),
        intercept: line.map(|l| l.intercept),
        standard_error_intercept: line.and_then(|l| l.se_intercept),
        wall_s: rec.wall_s,
        command: crate::scene::overrides::command_line(&inp.scene, &p.overrides),
        plots,
    };
    let json = inp.out.join("cone.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| CommandError::Output(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// (base depth, cone index) of the run's summary (`rig.curve`).
fn curve_of(r: &Record) -> Option<Vec<(f64, f64)>> {
    r.summary
        .as_ref()?
        .get("rig")?
        .get("curve")?
        .as_array()?
        .iter()
        .map(|c| Some((c.get("base_depth")?.as_f64()?, c.get("cone_index")?.as_f64()?)))
        .collect()
}

/// Mean and spread of the cone index per layer of base depth, from the surface (base depth 0:
/// the cone just fully in) down to the last full layer.
pub fn profile(curve: &[(f64, f64)], layer: f64) -> Vec<ConeLayer> {
    let deepest = curve.iter().map(|c| c.0).fold(0.0, f64::max);
    let full = (deepest / layer + 1e-9).floor() as usize;
    (0..full)
        .filter_map(|k| {
            let (from, to) = (k as f64 * layer, (k + 1) as f64 * layer);
            let v: Vec<f64> = curve.iter().filter(|c| c.0 >= from && c.0 < to).map(|c| c.1).collect();
            if v.is_empty() {
                return None;
            }
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let sd = if v.len() > 1 {
                (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
            } else {
                0.0
            };
            Some(ConeLayer { from, to, cone_index: m, std_dev: sd, samples: v.len() })
        })
        .collect()
}

/// A least-squares line with standard errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// Slope.
    pub slope: f64,
    /// Intercept.
    pub intercept: f64,
    /// Slope's standard error (three or more points).
    pub se_slope: Option<f64>,
    /// Intercept's standard error (three or more points).
    pub se_intercept: Option<f64>,
}

/// `CI = CI₀ + G z` through the layer means at their mid-depths (`None` with fewer than two
/// layers).
pub fn line(layers: &[ConeLayer]) -> Option<Line> {
    if layers.len() < 2 {
        return None;
    }
    let m = layers.len() as f64;
    let z: Vec<f64> = layers.iter().map(|l| 0.5 * (l.from + l.to)).collect();
    let (mz, mc) = (z.iter().sum::<f64>() / m, layers.iter().map(|l| l.cone_index).sum::<f64>() / m);
    let szz: f64 = z.iter().map(|x| (x - mz).powi(2)).sum();
    let slope = z.iter().zip(layers).map(|(x, l)| (x - mz) * (l.cone_index - mc)).sum::<f64>() / szz;
    let intercept = mc - slope * mz;
    let (se_slope, se_intercept) = if layers.len() > 2 {
        let s2 =
            z.iter().zip(layers).map(|(x, l)| (l.cone_index - intercept - slope * x).powi(2)).sum::<f64>() / (m - 2.0);
        (Some((s2 / szz).sqrt()), Some((s2 * (1.0 / m + mz * mz / szz)).sqrt()))
    } else {
        (None, None)
    };
    Some(Line { slope, intercept, se_slope, se_intercept })
}

/// Cone index against base depth, the layer means and the gradient line.
fn figure(curve: &[(f64, f64)], layers: &[ConeLayer], line: Option<Line>) -> Figure {
    let mut p = Panel {
        title: "cone index profile".into(),
        x_label: "base depth (mm)".into(),
        y_label: "cone index (kPa)".into(),
        ..Default::default()
    };
    p.series.push(Series::line("cone index", curve.iter().map(|(z, ci)| (z * 1e3, ci / 1e3)).collect()));
    p.series.push(Series::points(
        "layer means",
        layers.iter().map(|l| (0.5e3 * (l.from + l.to), l.cone_index / 1e3)).collect(),
    ));
    if let (Some(l), Some(last)) = (line, layers.last()) {
        p.series.push(Series::line(
            format!("CI = CI0 + G z, G = {:.3e} Pa/m", l.slope),
            vec![(0.0, l.intercept / 1e3), (last.to * 1e3, (l.intercept + l.slope * last.to) / 1e3)],
        ));
    }
    Figure { panels: vec![p] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_profile_gives_its_gradient_exactly() {
        // CI = 5e3 + 2e6 z sampled every 0.1 mm (at the middles of the 0.1 mm steps) down to
        // 30 mm: each layer's mean is the value at its mid-depth, on the line.
        let curve: Vec<(f64, f64)> = (0..=300).map(|i| (i as f64 + 0.5) * 1e-4).map(|z| (z, 5e3 + 2e6 * z)).collect();
        let layers = profile(&curve, 0.01);
        assert_eq!(layers.len(), 3);
        assert_eq!(layers[0].samples, 100);
        let l = line(&layers).expect("line");
        assert!((l.slope - 2e6).abs() / 2e6 < 1e-9 && (l.intercept - 5e3).abs() < 1e-6, "{l:?}");
        assert!(l.se_slope.is_some_and(|s| s < 1e-6 * 2e6) && l.se_intercept.is_some(), "{l:?}");
        assert!(line(&layers[..1]).is_none());
        assert!(line(&layers[..2]).is_some_and(|l| l.se_slope.is_none()), "two points leave no error");
    }
}
