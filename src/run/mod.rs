//! Running a scene from end to end, as `regolith run` does: build it, run its rig (or step
//! the terrain to the end time) through the [`crate::driver`] loop with the recording, series
//! and progress bar observing, and write `summary.json`, `particles_final.csv`, `series.csv`
//! and the plots.

mod summary;

pub use summary::{BodySummary, Geostatic, Runout, SUMMARY_SCHEMA_VERSION, Slump, Summary};

pub use crate::driver::{RunError, StopToken};

use std::path::PathBuf;

use regolith_fsi::Real;

use crate::driver::{Driver, Observer, Progress, RunStats};
use crate::output::DRAWS_PLOTS;
#[cfg(feature = "mcap")]
use crate::output::Recorder;
use crate::output::{TerrainSeries, figures, write_figure, write_json, write_particles_csv};
use crate::scene::{Precision, Scene};
use crate::sim::Simulation;

/// Options of [`run_scene`].
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// No progress lines.
    pub quiet: bool,
    /// Raised, it stops this run at its next exchange (what the CLI's Ctrl-C does).
    pub stop: StopToken,
}

impl RunOptions {
    /// Writes to `out`, with progress lines and a fresh stop token.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self { out: out.into(), quiet: false, stop: StopToken::new() }
    }
    /// Writes to `out`, without progress lines, with a fresh stop token.
    pub fn quiet(out: impl Into<PathBuf>) -> Self {
        Self { quiet: true, ..Self::new(out) }
    }
}

/// An observer that watches nothing.
struct Nobody;
impl<T: Real> Observer<T> for Nobody {}

/// Runs a scene and writes its outputs. When the solver fails at a particle, or a particle
/// runs away, the summary (with `nan_detected` / `error` set), the final particles, the series,
/// the rig's curves and the recording are still written up to that exchange, and
/// [`RunError::Failed`] or [`RunError::Runaway`] names the particle; when `opts.stop` is
/// raised (Ctrl-C) they are written and [`RunError::Interrupted`] is returned.
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary, RunError> {
    run_scene_observed(scene, opts, &mut Nobody)
}

/// [`run_scene`] with one more observer (a study's probe), told of every run and exchange
/// after the recording and the progress bar.
pub fn run_scene_observed<O: Observer<f32> + Observer<f64>>(
    scene: &Scene,
    opts: &RunOptions,
    extra: &mut O,
) -> Result<Summary, RunError> {
    match scene.precision {
        Precision::F32 => run_t::<f32>(scene, opts, extra),
        Precision::F64 => run_t::<f64>(scene, opts, extra),
    }
}

/// What the stepping produced, whichever way the scene ran.
struct Ran<T: Real> {
    sim: Option<Simulation<T>>,
    series: Option<crate::output::Series>,
    rig: Option<serde_json::Value>,
    bekker: Option<crate::rig::bekker::BekkerFit>,
    figures: Vec<(String, crate::output::Figure)>,
    /// The soil by particle id at the start (scenes without a rig: collapses and beds).
    initial: Option<Vec<(u32, [f64; 3])>>,
}

impl<T: Real> Default for Ran<T> {
    fn default() -> Self {
        Self { sim: None, series: None, rig: None, bekker: None, figures: Vec::new(), initial: None }
    }
}

fn run_t<T: Real>(scene: &Scene, opts: &RunOptions, extra: &mut dyn Observer<T>) -> Result<Summary, RunError> {
    std::fs::create_dir_all(&opts.out).map_err(|e| RunError::output(&opts.out, e))?;
    // Scene validation refuses `output.mcap = true` in a build without the `mcap` feature.
    #[cfg(feature = "mcap")]
    let mut recorder =
        if scene.output.mcap { Some(Recorder::create(&opts.out.join("recording.mcap"), &scene.output)?) } else { None };
    let mut progress = Progress::new(opts.quiet);
    let mut terrain_series = TerrainSeries::default();
    let mut failure = None;
    let mut interrupted = None;
    // A solver error, a runaway or a stop ends the run with its outputs written; other errors
    // end it at once.
    let mut stopped = |e: RunError| match e {
        RunError::Interrupted { time } => {
            interrupted = Some(time);
            Ok(())
        }
        e if e.keeps_outputs() => {
            failure = Some(e);
            Ok(())
        }
        e => Err(e),
    };
    let mut driver = Driver::<T>::new(scene.end_time, opts.stop.clone());
    #[cfg(feature = "mcap")]
    if let Some(r) = recorder.as_mut() {
        driver.observe(r);
    }
    driver.observe(&mut progress);
    driver.observe(extra);
    let ran = if let Some(spec) = &scene.rig {
        let out = crate::rig::run_rig::<T>(scene, spec, &mut driver)?;
        if let Some(e) = out.stopped {
            stopped(e)?;
        }
        Ran {
            sim: out.last,
            series: Some(out.series),
            rig: Some(out.report),
            bekker: out.bekker,
            figures: out.figures,
            initial: None,
        }
    } else {
        let mut sim = Simulation::<T>::new(scene)?;
        let initial = summary::soil_by_id(sim.system.fluid.as_ref());
        driver.observe(&mut terrain_series);
        driver.begin(&sim, None)?;
        while !driver.done(&sim) {
            if let Err(e) = driver.step(&mut sim) {
                stopped(e)?;
                break;
            }
        }
        Ran { sim: Some(sim), initial: Some(initial), ..Ran::default() }
    };
    driver.finish()?;
    let stats = driver.stats.clone();
    drop(driver);
    let Ran { sim, series, rig, bekker, figures, initial } = ran;
    let series = series.or_else(|| initial.is_some().then_some(terrain_series.0));
    let mut outputs = Vec::new();
    #[cfg(feature = "mcap")]
    if let Some(r) = &recorder {
        outputs.push(r.path().to_path_buf());
    }
    let fluid = sim.as_ref().map(|s| s.system.fluid.as_ref());
    // The soil at the start and at the end, by id and as plain positions (what the runout and
    // the deposit profile read), for the scenes that sampled the start.
    let last_soil = fluid.filter(|_| initial.is_some()).map(|f| summary::soil_by_id(f));
    let positions = |v: &[(u32, [f64; 3])]| v.iter().map(|p| p.1).collect::<Vec<_>>();
    let ends = match (&initial, &last_soil) {
        (Some(i), Some(l)) => Some((positions(i), positions(l))),
        _ => None,
    };
    let soil = SoilEnds { initial: initial.as_deref(), last: last_soil.as_deref(), ends: ends.as_ref() };
    let mut summary = summarise(scene, sim.as_ref(), &stats, &soil, failure.as_ref(), rig, bekker);
    if let Some(f) = fluid {
        let p = opts.out.join("particles_final.csv");
        write_particles_csv(&p, f)?;
        outputs.push(p);
    }
    write_outputs(scene, opts, &mut summary, series.as_ref(), figures, ends.as_ref(), outputs)?;
    match (failure, interrupted) {
        (Some(e), _) => Err(e),
        (None, Some(time)) => Err(RunError::Interrupted { time }),
        (None, None) => Ok(summary),
    }
}

/// The soil's particle positions at the start and at the end of a run.
type Ends = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// The soil by particle id at the start and at the end, and as plain positions, of a run
/// that sampled the start (scenes without a rig).
struct SoilEnds<'a> {
    initial: Option<&'a [(u32, [f64; 3])]>,
    last: Option<&'a [(u32, [f64; 3])]>,
    ends: Option<&'a Ends>,
}

/// `summary.json`'s content, but for the list of outputs (`write_outputs` fills it).
fn summarise<T: Real>(
    scene: &Scene,
    sim: Option<&Simulation<T>>,
    stats: &RunStats,
    soil: &SoilEnds<'_>,
    failure: Option<&RunError>,
    rig: Option<serde_json::Value>,
    bekker: Option<crate::rig::bekker::BekkerFit>,
) -> Summary {
    let wall = stats.elapsed();
    let fluid = sim.map(|s| s.system.fluid.as_ref());
    Summary {
        schema_version: SUMMARY_SCHEMA_VERSION,
        scene: scene.path.display().to_string(),
        backend: fluid.map_or_else(|| "cpu".into(), |f| f.backend().into()),
        adapter: fluid.map_or_else(|| "cpu".into(), |f| f.adapter()),
        precision: T::NAME.into(),
        particles: fluid.map_or(0, |f| f.len()),
        markers: fluid.map_or(0, |f| f.marker_positions().len()),
        steps: stats.steps,
        particle_steps: stats.particle_steps,
        sim_time: sim.map_or(0.0, |s| s.time()),
        wall_time_s: wall,
        particle_steps_per_s: if wall > 0.0 { stats.particle_steps / wall } else { 0.0 },
        neighbour_pairs: if stats.steps > 0 { stats.pairs / stats.steps as f64 } else { 0.0 },
        dt_min: if stats.dt_min.is_finite() { stats.dt_min } else { 0.0 },
        dt_max: stats.dt_max,
        max_speed: stats.last_speed,
        max_speed_run: stats.max_speed_run,
        mass_initial: fluid.map_or(0.0, |f| f.total_mass()),
        mass_final: fluid.map_or(0.0, |f| f.active_mass()),
        escaped_particles: fluid.map_or(0, |f| f.len() - f.active()),
        rarefied_max: stats.rarefied_max,
        active_domain: match fluid {
            Some(f) if scene.active.is_some() => Some(summary::ActiveSummary {
                awake_min: if stats.steps > 0 { stats.awake_min } else { f.awake() },
                awake_max: stats.awake_max,
                awake_final: f.awake(),
                awake_mean: if stats.steps > 0 { stats.particle_steps / stats.steps as f64 } else { 0.0 },
                inside_final: f.active(),
                classifications: f.classifications(),
            }),
            _ => None,
        },
        patch: sim.and_then(|s| s.patch()).map(|p| {
            let (advances, lifted, laid) = p.counts();
            summary::PatchSummary {
                length: p.spec().length,
                trigger: p.spec().trigger,
                span_final: p.span(),
                advances,
                lifted,
                laid,
            }
        }),
        nan_detected: matches!(
            failure,
            Some(RunError::Failed { cause: regolith_fsi::SolverError::NonFinite { .. }, .. })
                | Some(RunError::Failed {
                    cause: regolith_fsi::SolverError::Rheology {
                        source: regolith_fsi::rheology::RheologyError::NonFinite { .. },
                        ..
                    },
                    ..
                })
        ),
        error: failure.as_ref().map(|e| e.to_string()),
        runout: soil.ends.and_then(|(i, l)| summary::column_runout(scene, i, l)),
        slump: match (soil.initial, soil.last) {
            (Some(i), Some(l)) => summary::slump(scene, i, l),
            _ => None,
        },
        geostatic: match (fluid, soil.initial) {
            (Some(f), Some(_)) => summary::geostatic_state(scene, f),
            _ => None,
        },
        bodies: sim.map(body_summaries).unwrap_or_default(),
        rig,
        bekker,
        outputs: Vec::new(),
        notes: sim.map(|s| s.terrain.notes.clone()).unwrap_or_default(),
    }
}

/// Writes `series.csv`, the figures (the rig's, each vehicle's, the deposit profile) and
/// `summary.json`, whose list of outputs ends with them after `outputs`.
fn write_outputs(
    scene: &Scene,
    opts: &RunOptions,
    summary: &mut Summary,
    series: Option<&crate::output::Series>,
    mut figures: Vec<(String, crate::output::Figure)>,
    ends: Option<&Ends>,
    mut outputs: Vec<PathBuf>,
) -> Result<(), RunError> {
    if let Some(s) = series {
        let p = opts.out.join("series.csv");
        s.write(&p)?;
        outputs.push(p);
    }
    if let (Some(ser), None) = (series, &scene.rig) {
        for v in &scene.vehicles {
            figures.push((format!("vehicle_{}", v.name), figures::vehicle_figure(ser, v)));
        }
    }
    if let Some((i, l)) = ends {
        let axis = summary.runout.as_ref().map(|r| r.axis);
        figures.push(("deposit_profile".into(), figures::deposit_profile(scene, i, l, axis)));
    }
    if !DRAWS_PLOTS && !figures.is_empty() {
        summary.notes.push("no plots drawn: this build of regolith has no `plots` feature".into());
    }
    for (stem, fig) in &figures {
        let files = write_figure(fig, &opts.out, stem).map_err(|e| RunError::output(&e.path.clone(), e))?;
        outputs.extend(files);
    }
    let summary_path = opts.out.join("summary.json");
    outputs.push(summary_path.clone());
    summary.outputs = outputs.iter().map(|p| p.display().to_string()).collect();
    write_json(&summary_path, &summary)?;
    Ok(())
}

fn body_summaries<T: Real>(s: &Simulation<T>) -> Vec<BodySummary> {
    (0..s.scene.bodies.len())
        .map(|i| {
            let st = s.body_state(s.body_at(i));
            let w = s.fsi_wrench(s.body_at(i));
            BodySummary {
                name: s.scene.bodies[i].desc.name.clone(),
                position: st.com,
                velocity: st.linvel,
                fsi_force: w.force,
                fsi_torque: w.torque,
            }
        })
        .collect()
}
