//! Running terrain scenes: build the solver from a [`Scene`], step it to the end time, and
//! write `summary.json` and `particles_final.csv`.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use regolith_fsi::Real;
use regolith_fsi::cpu::CpuSph;
use regolith_fsi::rheology::Rheology;
use regolith_terrain::{RegionSpec, SoilRegion, TerrainBuild, build_terrain};
use serde::Serialize;

use crate::scene::{Precision, Scene};

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

/// Builds the soil solver of a scene in precision `T`.
pub fn build_soil<T: Real>(scene: &Scene) -> Result<SoilModel<T>, RunError> {
    let mats64: Vec<_> = scene
        .materials
        .iter()
        .map(|m| m.params.build::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| RunError::Build(e.to_string()))?;
    let mats: Vec<_> = scene
        .materials
        .iter()
        .map(|m| m.params.build::<T>())
        .collect::<Result<_, _>>()
        .map_err(|e| RunError::Build(e.to_string()))?;
    let container = scene.container.ok_or_else(|| RunError::Build("a terrain scene needs a [container]".into()))?;
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
    .map_err(|e| RunError::Build(e.to_string()))?;
    let solver = CpuSph::new(scene.solver, mats, &terrain.particles, &terrain.markers, terrain.domain)?;
    Ok(SoilModel { solver, terrain })
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
    let mut model = build_soil::<T>(scene)?;
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| RunError::Output { path: opts.out.clone(), message: e.to_string() })?;
    let initial: Vec<[f64; 3]> = model.solver.positions().iter().map(|p| p.as_f64()).collect();
    let mass_initial = model.solver.total_mass();
    let n = model.solver.len();
    let start = Instant::now();
    let mut last_print = Instant::now();
    let (mut dt_min, mut dt_max, mut pairs, mut vmax_run) = (f64::INFINITY, 0.0_f64, 0.0, 0.0_f64);
    let mut failure = None;
    let mut last_speed = 0.0;
    while model.solver.time() < scene.end_time * (1.0 - 1e-12) {
        let remaining = scene.end_time - model.solver.time();
        match model.solver.step(Some(remaining)) {
            Ok(r) => {
                dt_min = dt_min.min(r.dt);
                dt_max = dt_max.max(r.dt);
                pairs += r.pairs as f64;
                last_speed = r.max_speed;
                vmax_run = vmax_run.max(r.max_speed);
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        if !opts.quiet && last_print.elapsed().as_secs_f64() > 2.0 {
            last_print = Instant::now();
            let el = start.elapsed().as_secs_f64();
            let t = model.solver.time();
            eprintln!(
                "  t = {t:.4} / {} s, {} steps, {:.2e} particle-steps/s, eta {:.0} s",
                scene.end_time,
                model.solver.steps(),
                n as f64 * model.solver.steps() as f64 / el,
                el * (scene.end_time - t) / t.max(1e-30)
            );
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let steps = model.solver.steps();
    let runout = column_runout(scene, &initial, &model.solver);
    let summary = Summary {
        schema_version: SUMMARY_SCHEMA_VERSION,
        scene: scene.path.display().to_string(),
        backend: "cpu".into(),
        adapter: "cpu".into(),
        precision: T::NAME.into(),
        particles: n,
        markers: model.solver.marker_positions().len(),
        steps,
        sim_time: model.solver.time(),
        wall_time_s: wall,
        particle_steps_per_s: if wall > 0.0 { n as f64 * steps as f64 / wall } else { 0.0 },
        neighbour_pairs: if steps > 0 { pairs / steps as f64 } else { 0.0 },
        dt_min: if dt_min.is_finite() { dt_min } else { 0.0 },
        dt_max,
        max_speed: last_speed,
        max_speed_run: vmax_run,
        mass_initial,
        mass_final: model.solver.active_mass(),
        escaped_particles: model.solver.len() - model.solver.active(),
        nan_detected: matches!(
            failure,
            Some(regolith_fsi::SolverError::NonFinite { .. })
                | Some(regolith_fsi::SolverError::Rheology {
                    source: regolith_fsi::rheology::RheologyError::NonFinite { .. },
                    ..
                })
        ),
        error: failure.as_ref().map(|e| e.to_string()),
        runout,
        notes: model.terrain.notes.clone(),
    };
    write_json(&opts.out.join("summary.json"), &summary)?;
    write_particles_csv(&opts.out.join("particles_final.csv"), &model.solver)?;
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
