//! Running scenes: build the simulation from a [`Scene`], step it to the end time (or run its
//! rig), and write `summary.json`, `particles_final.csv`, `series.csv` and plots.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use regolith_fsi::Real;
use regolith_fsi::cpu::CpuSph;
use regolith_fsi::rheology::{Material, Rheology};
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
}

/// A built terrain simulation.
pub struct SoilModel<T: Real> {
    /// The SPH solver.
    pub solver: CpuSph<T>,
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
    let solver = CpuSph::new(scene.solver, mats, &terrain.particles, &terrain.markers, terrain.domain)?;
    Ok(SoilModel { solver, terrain })
}

/// Counts what the stepping loop did, for the summary and the progress line.
#[derive(Debug)]
pub struct Stepper {
    start: Instant,
    last_print: Instant,
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
    quiet: bool,
    end_time: f64,
}

impl Stepper {
    /// A fresh counter for a run that ends at `end_time` (s).
    pub fn new(quiet: bool, end_time: f64) -> Self {
        Self {
            start: Instant::now(),
            last_print: Instant::now(),
            steps: 0,
            particle_steps: 0.0,
            pairs: 0.0,
            max_speed_run: 0.0,
            last_speed: 0.0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            quiet,
            end_time,
        }
    }

    /// Advances a simulation by one exchange interval (at most to the end time).
    pub fn step<T: Real>(&mut self, sim: &mut Simulation<T>) -> Result<(), RunError> {
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
        if !self.quiet && self.last_print.elapsed().as_secs_f64() > 2.0 {
            self.last_print = Instant::now();
            let el = self.start.elapsed().as_secs_f64();
            let t = sim.time();
            eprintln!(
                "  t = {t:.4} / {} s, {} steps, {:.2e} particle-steps/s, real-time factor {:.2e}",
                self.end_time,
                self.steps,
                self.particle_steps / el,
                t / el
            );
        }
        Ok(())
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
    let mut outputs = Vec::new();
    let mut failure = None;
    let (sim, series, rig, bekker, figures, initial) = if let Some(spec) = &scene.rig {
        match crate::rig::run_rig::<T>(scene, spec, &mut stepper) {
            Ok(out) => (out.last, Some(out.series), Some(out.report), out.bekker, out.figures, None),
            Err(RunError::Solver(e)) => {
                failure = Some(e);
                (None, None, None, None, Vec::new(), None)
            }
            Err(e) => return Err(e),
        }
    } else {
        let mut sim = Simulation::<T>::new(scene)?;
        let initial: Vec<[f64; 3]> = sim.system.fluid.positions().iter().map(|p| p.as_f64()).collect();
        let mut series = (!scene.bodies.is_empty()).then(|| Series::new(&sim, false, &[]));
        if let Some(s) = series.as_mut() {
            s.push(&sim, None, &[]);
        }
        while sim.time() < scene.end_time * (1.0 - 1e-12) {
            match stepper.step(&mut sim) {
                Ok(()) => {
                    if let Some(s) = series.as_mut() {
                        s.push(&sim, None, &[]);
                    }
                }
                Err(RunError::Solver(e)) => {
                    failure = Some(e);
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        (Some(sim), series, None, None, Vec::new(), Some(initial))
    };
    let wall = stepper.elapsed();
    let fluid = sim.as_ref().map(|s| &s.system.fluid);
    let mut summary = Summary {
        schema_version: SUMMARY_SCHEMA_VERSION,
        scene: scene.path.display().to_string(),
        backend: "cpu".into(),
        adapter: "cpu".into(),
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
    for (stem, fig) in &figures {
        let files = crate::plot::write_figure(fig, &opts.out, stem)
            .map_err(|e| RunError::Output { path: e.path.clone(), message: e.message })?;
        outputs.extend(files);
    }
    let summary_path = opts.out.join("summary.json");
    outputs.push(summary_path.clone());
    summary.outputs = outputs.iter().map(|p| p.display().to_string()).collect();
    write_json(&summary_path, &summary)?;
    match failure {
        Some(e) => Err(RunError::Solver(e)),
        None => Ok(summary),
    }
}

/// Writes any serialisable value as pretty JSON.
pub fn write_json<S: Serialize>(path: &Path, value: &S) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| RunError::Output { path: path.to_path_buf(), message: e.to_string() })?;
    std::fs::write(path, text).map_err(|e| RunError::Output { path: path.to_path_buf(), message: e.to_string() })
}

/// `x,y,z,vx,vy,vz,p,q,pc,material` for every active particle.
pub fn write_particles_csv<T: Real>(path: &Path, s: &CpuSph<T>) -> Result<(), RunError> {
    let io = |e: std::io::Error| RunError::Output { path: path.to_path_buf(), message: e.to_string() };
    let f = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(f);
    writeln!(w, "x,y,z,vx,vy,vz,p,q,pc,material").map_err(io)?;
    for i in 0..s.active() {
        let p = s.positions()[i].as_f64();
        let v = s.velocities()[i].as_f64();
        let sig = s.stresses()[i];
        let mat = s.material_ids()[i];
        let pc = match s.materials()[mat as usize].rheology {
            Rheology::Mcc(_) => s.states()[i].pc.as_f64(),
            _ => 0.0,
        };
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{}",
            p[0],
            p[1],
            p[2],
            v[0],
            v[1],
            v[2],
            sig.pressure().as_f64(),
            sig.von_mises().as_f64(),
            pc,
            mat
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)
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

fn column_runout<T: Real>(scene: &Scene, initial: &[[f64; 3]], s: &CpuSph<T>) -> Option<Runout> {
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
