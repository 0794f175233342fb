//! `regolith calibrate plate`: Bekker's pressure–sinkage parameters of the SPH soil. A plate
//! rig scene is run once per plate size (each size one point of the sweep runner: run in
//! parallel, resumable), and the law `p = (k_c / b + k_φ) zⁿ` is fitted to all the curves
//! together ([`crate::rig::bekker::fit`]: one exponent, one k per plate, then k against 1/b),
//! with standard errors.

use std::path::PathBuf;

use serde::Serialize;

use super::CommandError;
use crate::input::InputError;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use crate::rig::bekker::{BekkerFit, PlateCurve, fit};
use crate::scene::{RigSpec, load_scene};
use crate::sweep::{Plan, Record, forget, read_all, run_local};

/// What `regolith calibrate plate` reads.
#[derive(Clone, Debug)]
pub struct PlateInputs {
    /// A scene with a plate rig (`[rig] type = "plate"`).
    pub scene: PathBuf,
    /// Plate sizes (radius of a circular plate, the smaller side of a rectangular one, m);
    /// empty: the rig's `sizes`.
    pub sizes: Vec<f64>,
    /// Overrides applied to every run (`--set KEY=VALUE`).
    pub sets: Vec<(String, toml::Value)>,
    /// Output folder.
    pub out: PathBuf,
    /// Runs at once (threads).
    pub jobs: usize,
    /// Keep the runs already recorded in `out`.
    pub resume: bool,
}

/// One plate's run.
#[derive(Clone, Debug, Serialize)]
pub struct PlateRun {
    /// Plate size b (m).
    pub b: f64,
    /// The run's configuration hash and folder (under `points/`).
    pub id: String,
    /// Largest sinkage reached (m).
    pub max_sinkage: f64,
    /// Largest pressure (Pa).
    pub max_pressure: f64,
    /// Wall-clock time (s).
    pub wall_s: f64,
    /// The command that reproduces it.
    pub command: String,
}

/// `bekker.json`.
#[derive(Clone, Debug, Serialize)]
pub struct PlateCalibration {
    /// "plate_sinkage".
    pub test: &'static str,
    /// The scene.
    pub scene: String,
    /// The fit.
    pub bekker: BekkerFit,
    /// Every plate's run.
    pub runs: Vec<PlateRun>,
    /// Plots written.
    pub plots: Vec<String>,
}

/// The plate runs of a calibration, as points of the sweep runner.
#[derive(Clone, Debug)]
pub struct PlatePlan {
    /// The inputs.
    pub inputs: PlateInputs,
    /// The plate sizes, one run each.
    pub sizes: Vec<f64>,
    /// One point per size: the scene with `rig.sizes = [b]` after the common overrides.
    pub plan: Plan,
}

impl PlatePlan {
    /// Checks the inputs (the scene has a plate rig, two or more sizes > 0, every run's scene
    /// loads).
    pub fn new(inp: &PlateInputs) -> Result<Self, CommandError> {
        if inp.jobs == 0 {
            return Err(InputError::flag("--jobs", "0 runs at once runs nothing; allowed: 1 or more").into());
        }
        let scene = load_scene(&inp.scene, &inp.sets)?;
        let Some(RigSpec::Plate { sizes, .. }) = &scene.rig else {
            return Err(InputError::key(
                &inp.scene,
                "rig.type",
                "calibrate plate needs a plate rig (type = \"plate\")",
            )
            .into());
        };
        let sizes = if inp.sizes.is_empty() { sizes.clone() } else { inp.sizes.clone() };
        if sizes.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(InputError::flag("--sizes", format!("plate sizes must be > 0 m (got {sizes:?})")).into());
        }
        let mut distinct = sizes.clone();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        if distinct.len() < 2 {
            return Err(InputError::flag(
                "--sizes",
                format!(
                    "needs two or more different plate sizes (k_c and k_φ come from how k changes with 1/b); got {sizes:?}"
                ),
            )
            .into());
        }
        let lists: Vec<Vec<(String, toml::Value)>> = sizes
            .iter()
            .map(|&s| {
                let mut o = inp.sets.clone();
                o.push(("rig.sizes".into(), toml::Value::Array(vec![toml::Value::Float(s)])));
                o
            })
            .collect();
        let plan = Plan::from_overrides(&inp.scene, lists)?;
        // Each run's scene must load (a size the rig cannot take is an input error now).
        for p in &plan.points {
            load_scene(&inp.scene, &p.overrides)?;
        }
        Ok(Self { inputs: inp.clone(), sizes, plan })
    }

    /// Fits Bekker's law to the recorded runs and writes `bekker.json` and `bekker.png` /
    /// `.svg` (the curves with the fit, and k against 1/b). A run without a finished record
    /// is an error naming its size.
    pub fn finish(&self) -> Result<PlateCalibration, CommandError> {
        let inp = &self.inputs;
        let records = read_all(&inp.out)?;
        let mut curves = Vec::new();
        let mut runs = Vec::new();
        let mut missing = Vec::new();
        for (p, &b) in self.plan.points.iter().zip(&self.sizes) {
            match records.iter().find(|r| r.id == p.id) {
                Some(r) if r.ok() => match curve_of(r) {
                    Some(points) => {
                        runs.push(PlateRun {
                            b,
                            id: p.id.clone(),
                            max_sinkage: points.iter().map(|q| q.0).fold(0.0, f64::max),
                            max_pressure: points.iter().map(|q| q.1).fold(0.0, f64::max),
                            wall_s: r.wall_s,
                            command: crate::scene::overrides::command_line(&inp.scene, &p.overrides),
                        });
                        curves.push(PlateCurve { b, points });
                    }
                    None => missing.push(format!("b = {b} m: its summary holds no plate curve")),
                },
                Some(r) => missing.push(format!("b = {b} m: {}", r.error.as_deref().unwrap_or("failed"))),
                None => missing.push(format!("b = {b} m: not run")),
            }
        }
        if !missing.is_empty() {
            return Err(CommandError::Run(format!("plate runs not carried out: {}", missing.join("; "))));
        }
        let bekker = fit(&curves).ok_or_else(|| {
            CommandError::Run(
                "no plate curve has three points with sinkage above a fifth of its largest: push deeper (rig.depth)"
                    .into(),
            )
        })?;
        let plots = write_figure(&figure(&curves, &bekker), &inp.out, "bekker")
            .map_err(|e| CommandError::Output(e.to_string()))?
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        let report =
            PlateCalibration { test: "plate_sinkage", scene: inp.scene.display().to_string(), bekker, runs, plots };
        let json = inp.out.join("bekker.json");
        let text = serde_json::to_string_pretty(&report).map_err(|e| CommandError::Output(e.to_string()))?;
        std::fs::write(&json, text)
            .map_err(|e| CommandError::Output(format!("cannot write {}: {e}", json.display())))?;
        Ok(report)
    }
}

/// Checks the inputs, runs the plates not yet recorded (all of them unless `resume`) on
/// `jobs` threads, fits Bekker's law and writes its report (see [`PlatePlan::finish`]).
pub fn calibrate_plate(inp: &PlateInputs) -> Result<PlateCalibration, CommandError> {
    let p = PlatePlan::new(inp)?;
    if !inp.resume {
        forget(&inp.out)?;
    }
    run_local(&p.plan, &inp.out, None, inp.jobs, true, false)?;
    p.finish()
}

/// The (sinkage, pressure) curve of a plate run's summary (`rig.runs[0].curve`).
fn curve_of(r: &Record) -> Option<Vec<(f64, f64)>> {
    let run = r.summary.as_ref()?.get("rig")?.get("runs")?.get(0)?;
    run.get("curve")?.as_array()?.iter().map(|p| Some((p.get(0)?.as_f64()?, p.get(1)?.as_f64()?))).collect()
}

/// The curves with the fitted law, and k against 1/b with its line.
fn figure(curves: &[PlateCurve], f: &BekkerFit) -> Figure {
    let mut sinkage = Panel {
        title: format!("pressure–sinkage, n = {:.3}", f.n),
        x_label: "sinkage z (mm)".into(),
        y_label: "pressure p (kPa)".into(),
        ..Default::default()
    };
    for c in curves {
        sinkage.series.push(Series::line(
            format!("b = {} mm", c.b * 1e3),
            c.points.iter().map(|(z, p)| (z * 1e3, p / 1e3)).collect(),
        ));
        if let Some(k) = f.k_per_plate.iter().find(|(b, _)| (b - c.b).abs() < 1e-12).map(|(_, k)| *k) {
            let zmax = c.points.iter().map(|q| q.0).fold(0.0, f64::max);
            sinkage.series.push(Series::line(
                format!("fit, b = {} mm", c.b * 1e3),
                (1..=50).map(|i| zmax * f64::from(i) / 50.0).map(|z| (z * 1e3, k * z.powf(f.n) / 1e3)).collect(),
            ));
        }
    }
    let mut line = Panel {
        title: "k = k_c / b + k_φ".into(),
        x_label: "1 / b (1/m)".into(),
        y_label: "k (N/m^(n+2))".into(),
        ..Default::default()
    };
    line.series.push(Series::points("plates", f.k_per_plate.iter().map(|(b, k)| (1.0 / b, *k)).collect()));
    if let (Some(kc), Some(kphi)) = (f.kc, f.kphi) {
        let xs: Vec<f64> = f.k_per_plate.iter().map(|(b, _)| 1.0 / b).collect();
        let (lo, hi) = (xs.iter().copied().fold(f64::INFINITY, f64::min), xs.iter().copied().fold(0.0, f64::max));
        line.series.push(Series::line(
            format!("k_c = {kc:.3e}, k_φ = {kphi:.3e}"),
            vec![(lo.min(0.0), kphi + kc * lo.min(0.0)), (hi * 1.1, kphi + kc * hi * 1.1)],
        ));
    }
    Figure { panels: vec![sinkage, line] }
}
