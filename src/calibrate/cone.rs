//! `regolith calibrate cone`: the cone index profile of the SPH soil. A cone penetrometer rig
//! scene is run (one point of the sweep runner: recorded, resumable) and its cone index —
//! force over the cone's base area — is averaged over depth layers of the base, once the cone
//! is fully in the soil, with the spread in each layer; the cone index gradient G of
//! `CI = G z` (Wismer and Luth's description of a uniform cohesionless soil) is fitted
//! through the layer means with its standard error.

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
    /// Cone index gradient G of `CI = G z`, through the layer means (Pa/m).
    pub gradient: Option<f64>,
    /// Its standard error (Pa/m), from the layer means' scatter about the line.
    pub standard_error_gradient: Option<f64>,
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
    let (gradient, standard_error_gradient) = gradient(&layers);
    let plots = write_figure(&figure(&curve, &layers, gradient), &inp.out, "cone_index")
        .map_err(|e| CommandError::Output(e.to_string()))?
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let report = ConeCalibration {
        test: "cone_penetrometer",
        scene: inp.scene.display().to_string(),
        layers,
        gradient,
        standard_error_gradient,
        wall_s: rec.wall_s,
        command: super::run_command(&inp.scene, &p.overrides),
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

/// G of `CI = G z` through the layer means at their mid-depths, and its standard error
/// (`None` with fewer than two layers).
pub fn gradient(layers: &[ConeLayer]) -> (Option<f64>, Option<f64>) {
    if layers.is_empty() {
        return (None, None);
    }
    let z: Vec<f64> = layers.iter().map(|l| 0.5 * (l.from + l.to)).collect();
    let szz: f64 = z.iter().map(|x| x * x).sum();
    let g = z.iter().zip(layers).map(|(x, l)| x * l.cone_index).sum::<f64>() / szz;
    let se = (layers.len() > 1).then(|| {
        let s2 =
            z.iter().zip(layers).map(|(x, l)| (l.cone_index - g * x).powi(2)).sum::<f64>() / (layers.len() - 1) as f64;
        (s2 / szz).sqrt()
    });
    (Some(g), se)
}

/// Cone index against base depth, the layer means and the gradient line.
fn figure(curve: &[(f64, f64)], layers: &[ConeLayer], g: Option<f64>) -> Figure {
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
    if let (Some(g), Some(last)) = (g, layers.last()) {
        p.series.push(Series::line(
            format!("CI = G z, G = {:.3e} Pa/m", g),
            vec![(0.0, 0.0), (last.to * 1e3, g * last.to / 1e3)],
        ));
    }
    Figure { panels: vec![p] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_profile_gives_its_gradient_exactly() {
        // CI = 2e6 z sampled every 0.1 mm (at the middles of the 0.1 mm steps) down to 30 mm:
        // each layer's mean is the value at its mid-depth, on the line.
        let curve: Vec<(f64, f64)> = (0..=300).map(|i| (i as f64 + 0.5) * 1e-4).map(|z| (z, 2e6 * z)).collect();
        let layers = profile(&curve, 0.01);
        assert_eq!(layers.len(), 3);
        assert_eq!(layers[0].samples, 100);
        let (g, se) = gradient(&layers);
        assert!((g.expect("g") - 2e6).abs() / 2e6 < 1e-9, "{g:?}");
        assert!(se.expect("se") < 1e-6 * 2e6, "{se:?}");
        assert!(gradient(&[]).0.is_none());
    }
}
