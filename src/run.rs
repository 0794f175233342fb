//! Running scenes: build the simulation from a [`Scene`], step it to the end time (or run its
//! rig), and write `summary.json`, `particles_final.csv`, `series.csv` and plots.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use regolith_fsi::rheology::{Material, Rheology};
use regolith_fsi::{Real, SphSolver};
use regolith_terrain::{RegionSpec, SoilRegion, TerrainBuild, build_terrain};
use serde::Serialize;

use crate::scene::{Precision, Scene};
use crate::series::Series;
use crate::sim::{Body, Simulation};

/// Version of the `summary.json` layout.
pub const SUMMARY_SCHEMA_VERSION: u32 = 1;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene cannot be built (should have been caught by validation).
    #[error("building the scene: {0}")]
    Build(String),
    /// The solver stopped.
    #[error("solver: {0}")]
    Solver(#[from] regolith_fsi::SolverError),
    /// Writing an output failed.
    #[error("writing {path}: {message}")]
    Output {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// Ctrl-C (SIGINT) stopped the run; the outputs up to that point were written.
    #[error("interrupted (outputs up to t = {time:.4} s were written)")]
    Interrupted {
        /// Simulated time reached (s).
        time: f64,
    },
}

static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Asks running simulations to stop at the next exchange (what Ctrl-C does in the CLI).
pub fn request_stop() {
    INTERRUPTED.store(true, std::sync::atomic::Ordering::SeqCst);
}

fn stop_requested() -> bool {
    INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst)
}

/// A built terrain simulation.
pub struct SoilModel<T: Real> {
    /// The SPH solver (the scene's backend).
    pub solver: Box<dyn SphSolver<T>>,
    /// What the terrain generator produced (container, domain, notes).
    pub terrain: TerrainBuild,
}

/// A scene's materials in precision `T` and its terrain (soil particles, wall markers,
/// domain), as generated from its soil regions.
pub fn scene_terrain<T: Real>(scene: &Scene) -> Result<(Vec<Material<T>>, TerrainBuild), RunError> {
    let build = |e: String| RunError::Build(e);
    let mats64: Vec<Material<f64>> =
        scene.materials.iter().map(|m| m.params.build()).collect::<Result<_, _>>().map_err(|e| build(e.to_string()))?;
    let mats: Vec<Material<T>> =
        scene.materials.iter().map(|m| m.params.build()).collect::<Result<_, _>>().map_err(|e| build(e.to_string()))?;
    let container = scene.container.ok_or_else(|| build("a scene needs a [container]".into()))?;
    let regions: Vec<RegionSpec> =
        scene.soil.iter().map(|s| RegionSpec { region: s.region.clone(), material: s.material as u16 }).collect();
    let terrain = build_terrain(
        &container,
        scene.solver.spacing,
        scene.solver.bce_layers,
        scene.solver.gravity,
        &regions,
        &mats64,
    )
    .map_err(|e| build(e.to_string()))?;
    Ok((mats, terrain))
}

/// Builds the soil solver of a terrain scene (bodies ignored) in precision `T`.
pub fn build_soil<T: Real>(scene: &Scene) -> Result<SoilModel<T>, RunError> {
    let (mats, terrain) = scene_terrain::<T>(scene)?;
    let wgpu = scene.backend == crate::scene::Backend::Wgpu;
    let solver =
        crate::gpu::make_solver(wgpu, scene.solver, mats, &terrain.particles, &terrain.markers, terrain.domain)?;
    Ok(SoilModel { solver, terrain })
}

/// Drives the stepping loop of a run: counts what it did (for the summary), records frames,
/// shows the progress bar and stops on Ctrl-C.
#[derive(Debug)]
pub struct Stepper {
    start: Instant,
    /// Soil steps taken.
    pub steps: u64,
    /// Soil particles × steps.
    pub particle_steps: f64,
    /// Sum of neighbour pairs over steps (for the mean).
    pub pairs: f64,
    /// Largest particle speed seen (m/s).
    pub max_speed_run: f64,
    /// Largest particle speed at the last step (m/s).
    pub last_speed: f64,
    /// Smallest soil step (s).
    pub dt_min: f64,
    /// Largest soil step (s).
    pub dt_max: f64,
    end_time: f64,
    bar: Option<indicatif::ProgressBar>,
    /// The recording, if the run writes one.
    pub recorder: Option<crate::record::Recorder>,
}

impl Stepper {
    /// A fresh counter for runs that end at `end_time` (s). The progress bar shows unless
    /// `quiet` or stdout is not a terminal.
    pub fn new(quiet: bool, end_time: f64) -> Self {
        use std::io::IsTerminal as _;
        let bar = (!quiet && std::io::stdout().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:30} {msg} ETA {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        Self {
            start: Instant::now(),
            steps: 0,
            particle_steps: 0.0,
            pairs: 0.0,
            max_speed_run: 0.0,
            last_speed: 0.0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            end_time,
            bar,
            recorder: None,
        }
    }

    /// Starts a run of a simulation (`label`: a rig run's slip or plate size): records its
    /// shapes and first frame.
    pub fn begin<T: Real>(&mut self, sim: &Simulation<T>, label: Option<f64>) -> Result<(), RunError> {
        if let Some(b) = &self.bar {
            b.reset_eta();
        }
        match self.recorder.as_mut() {
            Some(r) => r.begin_run(sim, label),
            None => Ok(()),
        }
    }

    /// Advances a simulation by one exchange interval (at most to the end time).
    pub fn step<T: Real>(&mut self, sim: &mut Simulation<T>) -> Result<(), RunError> {
        if stop_requested() {
            return Err(RunError::Interrupted { time: sim.time() });
        }
        let remaining = self.end_time - sim.time();
        let r = sim.step_max(Some(remaining))?;
        let n = sim.system.fluid.active() as f64;
        self.steps += u64::from(r.fluid_steps);
        self.particle_steps += n * f64::from(r.fluid_steps);
        self.pairs += r.pairs as f64 * f64::from(r.fluid_steps);
        self.last_speed = r.max_speed;
        self.dt_min = self.dt_min.min(r.dt_min);
        self.dt_max = self.dt_max.max(r.dt_max);
        self.max_speed_run = self.max_speed_run.max(r.max_speed);
        if let Some(rec) = self.recorder.as_mut() {
            rec.after_step(sim)?;
        }
        if let Some(b) = &self.bar {
            let el = self.start.elapsed().as_secs_f64().max(1e-9);
            let t = sim.time();
            b.set_position((1000.0 * t / self.end_time).round() as u64);
            b.set_message(format!(
                "t = {t:.4}/{} s  RTF {:.2e}  {:.2e} particle-steps/s",
                self.end_time,
                t / el,
                self.particle_steps / el
            ));
        }
        Ok(())
    }

    /// Records a rig's quantities with the frame the last step took, if it took one.
    pub fn rig<T: Real>(&mut self, sim: &Simulation<T>, kind: &str, fields: &[(&str, f64)]) -> Result<(), RunError> {
        match self.recorder.as_mut() {
            Some(r) => r.rig(sim, kind, fields),
            None => Ok(()),
        }
    }

    /// Records every vehicle's pose, speed and wheel states on `/vehicles/<name>` with the
    /// frame the last step took, if it took one.
    pub fn vehicles<T: Real>(&mut self, sim: &Simulation<T>) -> Result<(), RunError> {
        let Some(r) = self.recorder.as_mut() else { return Ok(()) };
        for (vi, v) in sim.scene.vehicles.iter().enumerate() {
            let names = crate::series::vehicle_columns(v);
            let values = crate::series::vehicle_values(sim, vi);
            let fields: Vec<(&str, f64)> = names.iter().map(String::as_str).zip(values).collect();
            r.values(sim, &format!("/vehicles/{}", v.name), "regolith.Vehicle", &fields)?;
        }
        Ok(())
    }

    /// Clears the progress bar.
    pub fn finish_bar(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }

    /// Wall-clock time since the counter started (s).
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// A body's final state in the summary.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BodySummary {
    /// Name.
    pub name: String,
    /// Centre of mass at the end (m).
    pub position: [f64; 3],
    /// Centre-of-mass velocity at the end (m/s).
    pub velocity: [f64; 3],
    /// Mean soil force over the last exchange interval (N).
    pub fsi_force: [f64; 3],
    /// Mean soil torque about the centre of mass over the last exchange interval (N m).
    pub fsi_torque: [f64; 3],
}

/// Runout of an axisymmetric column collapse.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Runout {
    /// Column axis (x, y), m.
    pub axis: [f64; 2],
    /// Initial radius R0 (m), the column's nominal radius.
    pub initial_radius: f64,
    /// Initial height h0 (m).
    pub initial_height: f64,
    /// Aspect ratio a = h0 / R0.
    pub aspect_ratio: f64,
    /// Final radius R∞ of the deposit (m): R0 plus the growth of the radius that holds 99 % of
    /// the particles (plus half a spacing).
    pub final_radius: f64,
    /// (R∞ − R0) / R0.
    pub normalized: f64,
    /// Lube et al. (2004): 1.24 a for a ≲ 1.7, 1.6 a^(1/2) above.
    pub lube_2004: f64,
    /// Final deposit height at the axis (m).
    pub final_height: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Summary {
    /// Layout version.
    pub schema_version: u32,
    /// Scene file.
    pub scene: String,
    /// Backend that ran.
    pub backend: String,
    /// Device adapter (`cpu` for the CPU backend).
    pub adapter: String,
    /// Precision.
    pub precision: String,
    /// Soil particles at the start.
    pub particles: usize,
    /// Wall and body markers.
    pub markers: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time reached (s).
    pub sim_time: f64,
    /// Wall-clock time of the stepping loop (s).
    pub wall_time_s: f64,
    /// Soil particles × steps per wall-clock second.
    pub particle_steps_per_s: f64,
    /// Mean neighbour pairs per rate evaluation.
    pub neighbour_pairs: f64,
    /// Smallest and largest step (s).
    pub dt_min: f64,
    /// Largest step (s).
    pub dt_max: f64,
    /// Largest particle speed at the end (m/s).
    pub max_speed: f64,
    /// Largest particle speed during the run (m/s).
    pub max_speed_run: f64,
    /// Soil mass at the start (kg).
    pub mass_initial: f64,
    /// Soil mass still in the domain at the end (kg).
    pub mass_final: f64,
    /// Particles that left the domain.
    pub escaped_particles: usize,
    /// True when the run stopped on a non-finite value.
    pub nan_detected: bool,
    /// The error that stopped the run, if any.
    pub error: Option<String>,
    /// Column-collapse runout, for scenes whose soil is one cylinder.
    pub runout: Option<Runout>,
    /// Bodies at the end.
    pub bodies: Vec<BodySummary>,
    /// The rig's report, if the scene has a rig.
    pub rig: Option<serde_json::Value>,
    /// Bekker pressure–sinkage fit of a plate rig.
    pub bekker: Option<crate::rig::bekker::BekkerFit>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Adjustments made while building (e.g. container snapping).
    pub notes: Vec<String>,
}

/// Options of [`run_scene`].
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// No progress lines.
    pub quiet: bool,
}

/// Runs a scene and writes its outputs. On a solver failure the summary and final particles
/// are still written (with `nan_detected` / `error` set) before the error is returned.
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary, RunError> {
    match scene.precision {
        Precision::F32 => run_t::<f32>(scene, opts),
        Precision::F64 => run_t::<f64>(scene, opts),
    }
}

fn run_t<T: Real>(scene: &Scene, opts: &RunOptions) -> Result<Summary, RunError> {
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| RunError::Output { path: opts.out.clone(), message: e.to_string() })?;
    let mut stepper = Stepper::new(opts.quiet, scene.end_time);
    if scene.output.mcap {
        stepper.recorder = Some(crate::record::Recorder::create(&opts.out.join("recording.mcap"), &scene.output)?);
    }
    let mut outputs = Vec::new();
    let mut failure = None;
    let mut interrupted = None;
    // A solver error or Ctrl-C ends the run with its outputs written; other errors end it at once.
    let mut stopped = |e: RunError| match e {
        RunError::Solver(e) => {
            failure = Some(e);
            Ok(())
        }
        RunError::Interrupted { time } => {
            interrupted = Some(time);
            Ok(())
        }
        e => Err(e),
    };
    let (sim, series, rig, bekker, mut figures, initial) = if let Some(spec) = &scene.rig {
        match crate::rig::run_rig::<T>(scene, spec, &mut stepper) {
            Ok(out) => (out.last, Some(out.series), Some(out.report), out.bekker, out.figures, None),
            Err(e) => {
                stopped(e)?;
                (None, None, None, None, Vec::new(), None)
            }
        }
    } else {
        let mut sim = Simulation::<T>::new(scene)?;
        let initial: Vec<[f64; 3]> = sim.system.fluid.positions().iter().map(|p| p.as_f64()).collect();
        // Every run writes series.csv: the bodies and vehicles, then the soil's largest speed
        // and kinetic energy (how a terrain scene settles).
        let soil_columns = ["soil.max_speed", "soil.kinetic_energy"];
        let mut series = Series::new(&sim, false, &soil_columns);
        series.push(&sim, None, &[0.0, sim.soil_kinetic_energy()]);
        stepper.begin(&sim, None)?;
        stepper.vehicles(&sim)?;
        while sim.time() < scene.end_time * (1.0 - 1e-12) {
            match stepper.step(&mut sim) {
                Ok(()) => {
                    series.push(&sim, None, &[stepper.last_speed, sim.soil_kinetic_energy()]);
                    stepper.vehicles(&sim)?;
                }
                Err(e) => {
                    stopped(e)?;
                    break;
                }
            }
        }
        let series = Some(series);
        (Some(sim), series, None, None, Vec::new(), Some(initial))
    };
    stepper.finish_bar();
    if let Some(mut r) = stepper.recorder.take() {
        r.finish()?;
        outputs.push(r.path().to_path_buf());
    }
    let wall = stepper.elapsed();
    let fluid = sim.as_ref().map(|s| s.system.fluid.as_ref());
    let mut summary = Summary {
        schema_version: SUMMARY_SCHEMA_VERSION,
        scene: scene.path.display().to_string(),
        backend: fluid.map_or_else(|| "cpu".into(), |f| f.backend().into()),
        adapter: fluid.map_or_else(|| "cpu".into(), |f| f.adapter()),
        precision: T::NAME.into(),
        particles: fluid.map_or(0, |f| f.len()),
        markers: fluid.map_or(0, |f| f.marker_positions().len()),
        steps: stepper.steps,
        sim_time: sim.as_ref().map_or(0.0, |s| s.time()),
        wall_time_s: wall,
        particle_steps_per_s: if wall > 0.0 { stepper.particle_steps / wall } else { 0.0 },
        neighbour_pairs: if stepper.steps > 0 { stepper.pairs / stepper.steps as f64 } else { 0.0 },
        dt_min: if stepper.dt_min.is_finite() { stepper.dt_min } else { 0.0 },
        dt_max: stepper.dt_max,
        max_speed: stepper.last_speed,
        max_speed_run: stepper.max_speed_run,
        mass_initial: fluid.map_or(0.0, |f| f.total_mass()),
        mass_final: fluid.map_or(0.0, |f| f.active_mass()),
        escaped_particles: fluid.map_or(0, |f| f.len() - f.active()),
        nan_detected: matches!(
            failure,
            Some(regolith_fsi::SolverError::NonFinite { .. })
                | Some(regolith_fsi::SolverError::Rheology {
                    source: regolith_fsi::rheology::RheologyError::NonFinite { .. },
                    ..
                })
        ),
        error: failure.as_ref().map(|e| e.to_string()),
        runout: match (fluid, &initial) {
            (Some(f), Some(i)) => column_runout(scene, i, f),
            _ => None,
        },
        bodies: sim
            .as_ref()
            .map(|s| {
                (0..s.scene.bodies.len())
                    .map(|i| {
                        let st = s.body_state(Body(i));
                        let w = s.fsi_wrench(Body(i));
                        BodySummary {
                            name: s.scene.bodies[i].desc.name.clone(),
                            position: st.com,
                            velocity: st.linvel,
                            fsi_force: w.force,
                            fsi_torque: w.torque,
                        }
                    })
                    .collect()
            })
            .unwrap_or_default(),
        rig,
        bekker,
        outputs: Vec::new(),
        notes: sim.as_ref().map(|s| s.terrain.notes.clone()).unwrap_or_default(),
    };
    if let Some(f) = fluid {
        let p = opts.out.join("particles_final.csv");
        write_particles_csv(&p, f)?;
        outputs.push(p);
    }
    if let Some(s) = &series {
        let p = opts.out.join("series.csv");
        s.write(&p)?;
        outputs.push(p);
    }
    if let (Some(ser), None) = (&series, &scene.rig) {
        for v in &scene.vehicles {
            figures.push((format!("vehicle_{}", v.name), vehicle_figure(ser, v)));
        }
    }
    if let (Some(s), Some(i)) = (&sim, &initial) {
        figures.push((
            "deposit_profile".into(),
            deposit_profile(scene, i, s.system.fluid.as_ref(), summary.runout.as_ref()),
        ));
    }
    for (stem, fig) in &figures {
        let files = crate::plot::write_figure(fig, &opts.out, stem)
            .map_err(|e| RunError::Output { path: e.path.clone(), message: e.message })?;
        outputs.extend(files);
    }
    let summary_path = opts.out.join("summary.json");
    outputs.push(summary_path.clone());
    summary.outputs = outputs.iter().map(|p| p.display().to_string()).collect();
    write_json(&summary_path, &summary)?;
    match (failure, interrupted) {
        (Some(e), _) => Err(RunError::Solver(e)),
        (None, Some(time)) => Err(RunError::Interrupted { time }),
        (None, None) => Ok(summary),
    }
}

/// Writes any serialisable value as pretty JSON.
pub fn write_json<S: Serialize>(path: &Path, value: &S) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| RunError::Output { path: path.to_path_buf(), message: e.to_string() })?;
    std::fs::write(path, text).map_err(|e| RunError::Output { path: path.to_path_buf(), message: e.to_string() })
}

/// One particle's output values.
#[derive(Clone, Copy, Debug)]
pub struct ParticleRow {
    /// Position (m).
    pub pos: [f64; 3],
    /// Velocity (m/s).
    pub vel: [f64; 3],
    /// Pressure p = −tr σ / 3 (Pa, compression positive).
    pub p: f64,
    /// Von Mises deviatoric stress q (Pa).
    pub q: f64,
    /// MCC preconsolidation pressure (Pa), 0 for other models.
    pub pc: f64,
    /// Material id.
    pub material: u16,
}

/// The output values of active particle `i`.
pub fn particle_row<T: Real>(s: &dyn SphSolver<T>, i: usize) -> ParticleRow {
    let sig = s.stresses()[i];
    let material = s.material_ids()[i];
    let pc = match s.materials()[material as usize].rheology {
        Rheology::Mcc(_) => s.states()[i].pc.as_f64(),
        _ => 0.0,
    };
    ParticleRow {
        pos: s.positions()[i].as_f64(),
        vel: s.velocities()[i].as_f64(),
        p: sig.pressure().as_f64(),
        q: sig.von_mises().as_f64(),
        pc,
        material,
    }
}

/// `x,y,z,vx,vy,vz,p,q,pc,material` for every active particle.
pub fn write_particles_csv<T: Real>(path: &Path, s: &dyn SphSolver<T>) -> Result<(), RunError> {
    let io = |e: std::io::Error| RunError::Output { path: path.to_path_buf(), message: e.to_string() };
    let f = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(f);
    writeln!(w, "x,y,z,vx,vy,vz,p,q,pc,material").map_err(io)?;
    for i in 0..s.active() {
        let r = particle_row(s, i);
        let [x, y, z] = r.pos;
        let [vx, vy, vz] = r.vel;
        writeln!(w, "{x},{y},{z},{vx},{vy},{vz},{},{},{},{}", r.p, r.q, r.pc, r.material).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// A vehicle's path, speed, and each wheel's slip and sinkage against time, from the series.
fn vehicle_figure(s: &Series, v: &crate::scene::VehicleSpec) -> crate::plot::Figure {
    use crate::plot::{Panel, Series as Line};
    let col = |name: String| s.column(&name).map(|c| s.rows.iter().map(|r| r[c]).collect::<Vec<f64>>());
    let t = col("time".into()).unwrap_or_default();
    let pair = |a: &[f64], b: &[f64], scale: f64| -> Vec<(f64, f64)> {
        a.iter().zip(b).filter(|(_, y)| y.is_finite()).map(|(x, y)| (*x, y * scale)).collect()
    };
    let x = col(format!("{}.x", v.name)).unwrap_or_default();
    let y = col(format!("{}.y", v.name)).unwrap_or_default();
    let speed = col(format!("{}.speed", v.name)).unwrap_or_default();
    let mut slip =
        Panel { title: "wheel slip".into(), x_label: "time (s)".into(), y_label: "slip".into(), ..Default::default() };
    let mut sink = Panel {
        title: "wheel sinkage".into(),
        x_label: "time (s)".into(),
        y_label: "sinkage (mm)".into(),
        ..Default::default()
    };
    for w in &v.wheels {
        let name = &v.model.links[w.link].name;
        if let (Some(c), Some(om)) = (col(format!("{}/{name}.slip", v.name)), col(format!("{}/{name}.omega", v.name))) {
            // Slip is undefined while a wheel barely turns: plot it where the wheel spins at
            // 0.3 rad/s or more.
            let pts = t
                .iter()
                .zip(&c)
                .zip(&om)
                .filter(|((_, s), w)| s.is_finite() && w.abs() >= 0.3)
                .map(|((t, s), _)| (*t, *s))
                .collect();
            slip.series.push(Line::line(name.clone(), pts));
        }
        if let Some(c) = col(format!("{}/{name}.sinkage", v.name)) {
            sink.series.push(Line::line(name.clone(), pair(&t, &c, 1e3)));
        }
    }
    crate::plot::Figure {
        panels: vec![
            Panel {
                title: format!("{} path", v.name),
                x_label: "x (m)".into(),
                y_label: "y (m)".into(),
                series: vec![Line::line("root link", pair(&x, &y, 1.0))],
                ..Default::default()
            },
            Panel {
                title: "speed".into(),
                x_label: "time (s)".into(),
                y_label: "horizontal speed (m/s)".into(),
                series: vec![Line::line("speed", pair(&t, &speed, 1.0))],
                ..Default::default()
            },
            slip,
            sink,
        ],
    }
}

/// The deposit's surface profile, initial and final: the highest particle top in bins of the
/// radial distance from the column axis (column collapse) or of x (other terrain).
fn deposit_profile<T: Real>(
    scene: &Scene,
    initial: &[[f64; 3]],
    s: &dyn SphSolver<T>,
    runout: Option<&Runout>,
) -> crate::plot::Figure {
    let d0 = scene.solver.spacing;
    let coord = |p: [f64; 3]| match runout {
        Some(r) => ((p[0] - r.axis[0]).powi(2) + (p[1] - r.axis[1]).powi(2)).sqrt(),
        None => p[0],
    };
    let profile = |pts: &mut dyn Iterator<Item = [f64; 3]>| {
        let mut bins: std::collections::BTreeMap<i64, f64> = std::collections::BTreeMap::new();
        for p in pts {
            let k = (coord(p) / d0).floor() as i64;
            let top = p[2] + 0.5 * d0;
            let e = bins.entry(k).or_insert(f64::NEG_INFINITY);
            *e = e.max(top);
        }
        bins.into_iter().map(|(k, z)| ((k as f64 + 0.5) * d0, z)).collect::<Vec<_>>()
    };
    let fin = profile(&mut (0..s.active()).map(|i| s.positions()[i].as_f64()));
    let ini = profile(&mut initial.iter().copied());
    let x_label = if runout.is_some() { "distance from the column axis r (m)" } else { "x (m)" };
    let floor = initial.iter().map(|p| p[2] - 0.5 * d0).fold(f64::INFINITY, f64::min);
    let top = ini.iter().chain(&fin).map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    crate::plot::Figure {
        panels: vec![crate::plot::Panel {
            title: "deposit surface".into(),
            x_label: x_label.into(),
            y_label: "surface height z (m)".into(),
            series: vec![crate::plot::Series::line("initial", ini), crate::plot::Series::line("final", fin)],
            y_range: (floor.is_finite() && top > floor).then_some((floor, top + 0.1 * (top - floor))),
            ..Default::default()
        }],
    }
}

/// The radius within which 99 % of the particles lie, about an axis, plus half a spacing
/// (the extent of the outermost particles' cells). The same estimator is applied to the
/// initial column and the deposit, so lattice effects cancel in (R∞ − R0)/R0.
fn deposit_radius(points: impl Iterator<Item = [f64; 3]>, axis: [f64; 2], d0: f64) -> f64 {
    let mut r: Vec<f64> = points.map(|p| ((p[0] - axis[0]).powi(2) + (p[1] - axis[1]).powi(2)).sqrt()).collect();
    if r.is_empty() {
        return 0.0;
    }
    r.sort_by(f64::total_cmp);
    let k = ((r.len() as f64 * 0.99).ceil() as usize).clamp(1, r.len()) - 1;
    r[k] + 0.5 * d0
}

fn column_runout<T: Real>(scene: &Scene, initial: &[[f64; 3]], s: &dyn SphSolver<T>) -> Option<Runout> {
    if scene.soil.len() != 1 {
        return None;
    }
    let SoilRegion::Cylinder { base_center, height, radius } = scene.soil[0].region else { return None };
    let axis = [base_center[0], base_center[1]];
    let d0 = scene.solver.spacing;
    // The lattice disc has the area of the nominal circle; the percentile estimator reads its
    // edge a little outside. Measuring both states with it and adding the difference to the
    // nominal radius cancels that bias.
    let r0_est = deposit_radius(initial.iter().copied(), axis, d0);
    let rf_est = deposit_radius(s.positions()[..s.active()].iter().map(|p| p.as_f64()), axis, d0);
    let r0 = radius;
    let rf = r0 + (rf_est - r0_est);
    let a = height / r0;
    let lube = if a <= 1.7 { 1.24 * a } else { 1.6 * a.sqrt() };
    let near_axis = s.positions()[..s.active()]
        .iter()
        .map(|p| p.as_f64())
        .filter(|p| ((p[0] - axis[0]).powi(2) + (p[1] - axis[1]).powi(2)).sqrt() < 1.5 * d0)
        .map(|p| p[2] - base_center[2] + 0.5 * d0)
        .fold(0.0, f64::max);
    Some(Runout {
        axis,
        initial_radius: r0,
        initial_height: height,
        aspect_ratio: a,
        final_radius: rf,
        normalized: (rf - r0) / r0,
        lube_2004: lube,
        final_height: near_axis,
    })
}
