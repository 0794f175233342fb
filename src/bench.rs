//! `regolith bench`: a fixed granular block collapse, timed; or the sand column collapse
//! other codes publish figures for (`--scene column`).
//!
//! A block of soil `n × n × 2n` particles (n chosen from the requested count) stands in the
//! corner of a container three blocks wide and collapses under gravity: the neighbour grid
//! changes every step, part of the soil yields, part rests. Rheology Drucker–Prager or MCC,
//! RK2, h/d0 = 1.2, Wendland kernel, XSPH, artificial viscosity — the defaults users run.
//! Warm-up steps are not timed.

use std::path::Path;
use std::time::Instant;

use regolith_fsi::Real;
use serde::Serialize;

use crate::build::build_soil;
use crate::driver::RunError;
use crate::input::InputError;
use crate::scene::{Precision, Scene, load_scene_source};

/// Which rheology the bench block uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchModel {
    /// Drucker–Prager, φ = 30°.
    DruckerPrager,
    /// Modified Cam Clay, M = 1.2, OCR = 1.5.
    Mcc,
}

impl BenchModel {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::DruckerPrager => "drucker-prager",
            Self::Mcc => "mcc",
        }
    }
}

/// One bench result.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BenchResult {
    /// Which scene: `block` or `column`.
    pub scene: &'static str,
    /// Rheology.
    pub model: &'static str,
    /// Backend.
    pub backend: String,
    /// Precision.
    pub precision: &'static str,
    /// Soil particles.
    pub particles: usize,
    /// Wall markers.
    pub markers: usize,
    /// Timed steps.
    pub steps: u64,
    /// Wall time of the timed steps (s).
    pub seconds: f64,
    /// Soil particles × steps / s.
    pub particle_steps_per_s: f64,
    /// Mean time step of the timed steps (s).
    pub dt_mean: f64,
    /// Simulated seconds per wall second over the timed steps.
    pub sim_s_per_wall_s: f64,
    /// Neighbour interactions (soil–soil and soil–marker pairs, each rate evaluation) per s.
    pub interactions_per_s: f64,
    /// Mean neighbours per soil particle.
    pub neighbours_per_particle: f64,
    /// Rayon threads.
    pub threads: usize,
    /// Device adapter (`cpu` for the CPU backend).
    pub adapter: String,
    /// Verlet skin of the neighbour lists (multiple of h); with a skin the pair counts above
    /// are listed pairs (within 2h + skin), not pairs within the support.
    pub neighbor_skin: f64,
    /// Neighbour-list builds during the timed steps (CPU backend; the wgpu backend rebuilds
    /// every step).
    pub list_builds: u64,
    /// Of those, steps made again because their midpoint stage left the skin (0 on wgpu).
    pub stage_retries: u64,
    /// Bytes the solver's arrays reserve at the end, per soil particle, markers and lists
    /// included (CPU backend; `None` on wgpu, whose buffers live on the device).
    pub bytes_per_particle: Option<f64>,
}

/// The smallest bench block: 4 × 4 × 8 particles.
pub const MIN_BENCH_PARTICLES: usize = 128;

/// The bench scene for about `particles` soil particles (at least [`MIN_BENCH_PARTICLES`]).
pub fn bench_scene(particles: usize, model: BenchModel, precision: Precision) -> Result<Scene, InputError> {
    let d0 = 0.01;
    if particles < MIN_BENCH_PARTICLES {
        return Err(InputError::flag(
            "--particles",
            format!("{particles} is below the smallest block, {MIN_BENCH_PARTICLES} particles (4 x 4 x 8)"),
        ));
    }
    let n = ((particles as f64 / 2.0).cbrt().round() as usize).max(4);
    let side = n as f64 * d0;
    let material = match model {
        BenchModel::DruckerPrager => "model = \"drucker-prager\"\nfriction_angle = 30.0\n",
        BenchModel::Mcc => {
            "model = \"mcc\"\nmcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.2\nocr = 1.5\n"
        }
    };
    let text = format!(
        "[simulation]\nend_time = 1.0\ndt = \"auto\"\nintegrator = \"rk2\"\nprecision = \"{prec}\"\n\n\
         [sph]\nspacing = {d0}\nh_factor = 1.2\nkernel = \"wendland\"\nartificial_viscosity = 0.5\nshifting = \"xsph\"\n\n\
         [[materials]]\nname = \"soil\"\ndensity = 1700\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\n{material}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{w}, {w}, {hgt}]\n\n\
         [[soil_blocks]]\nmaterial = \"soil\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{side}, {side}, {top}]\n",
        prec = precision.name(),
        w = 3.0 * side + 2.0 * d0,
        hgt = 2.0 * side + 2.0 * d0,
        top = 2.0 * side,
    );
    load_scene_source(Path::new("<bench>"), &text, &[])
}

/// `regolith bench --scene column`: the sand column collapse of issue 13's comparison with
/// Taichi's MLS-MPM example. A column 0.2 m long (x), 0.4 m wide (y, the container's width)
/// and 0.4 m tall, d0 = 7.8 mm (26 × 51 × 51 lattice points: 67 626 particles),
/// Drucker–Prager sand (φ = 30°, E = 1 MPa, ν = 0.3, ρ = 1600 kg/m³), stands at one end of a
/// 1.0 m long container and collapses along x. Same solver settings as the block bench.
pub fn column_scene(precision: Precision) -> Result<Scene, InputError> {
    let text = format!(
        "[simulation]\nend_time = 10.0\ndt = \"auto\"\nintegrator = \"rk2\"\nprecision = \"{prec}\"\n\n\
         [sph]\nspacing = 0.0078\nh_factor = 1.2\nkernel = \"wendland\"\nartificial_viscosity = 0.5\nshifting = \"xsph\"\n\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.4056, 0.6]\n\n\
         [[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2028, 0.4056, 0.4017]\n",
        prec = precision.name(),
    );
    load_scene_source(Path::new("<bench column>"), &text, &[])
}

/// Runs the bench on `scene` (named `scene_name` in the result): `warmup` untimed steps, then
/// `steps` timed ones.
pub fn run_bench(
    scene_name: &'static str,
    scene: &Scene,
    model: BenchModel,
    warmup: u64,
    steps: u64,
) -> Result<BenchResult, RunError> {
    match scene.precision {
        Precision::F32 => bench_t::<f32>(scene_name, scene, model, warmup, steps),
        Precision::F64 => bench_t::<f64>(scene_name, scene, model, warmup, steps),
    }
}

fn bench_t<T: Real>(
    scene_name: &'static str,
    scene: &Scene,
    model: BenchModel,
    warmup: u64,
    steps: u64,
) -> Result<BenchResult, RunError> {
    let mut m = build_soil::<T>(scene)?;
    for _ in 0..warmup {
        m.solver.step(None)?;
    }
    let evals = if scene.solver.integrator == regolith_fsi::config::Integrator::Rk2 { 2.0 } else { 1.0 };
    let builds0 = m.solver.as_cpu().map_or(0, |c| c.list_builds());
    let retries0 = m.solver.as_cpu().map_or(0, |c| c.stage_retries());
    let start = Instant::now();
    let (mut pairs, mut simulated) = (0.0, 0.0);
    for _ in 0..steps {
        let r = m.solver.step(None)?;
        pairs += r.pairs as f64;
        simulated += r.dt;
    }
    let secs = start.elapsed().as_secs_f64();
    let n = m.solver.active();
    Ok(BenchResult {
        scene: scene_name,
        model: model.name(),
        backend: m.solver.backend().into(),
        precision: T::NAME,
        particles: n,
        markers: m.solver.marker_positions().len(),
        steps,
        seconds: secs,
        particle_steps_per_s: n as f64 * steps as f64 / secs,
        dt_mean: simulated / steps as f64,
        sim_s_per_wall_s: simulated / secs,
        interactions_per_s: pairs * evals / secs,
        neighbours_per_particle: pairs / (steps as f64 * n as f64),
        threads: rayon::current_num_threads(),
        adapter: m.solver.adapter(),
        neighbor_skin: scene.solver.neighbor_skin,
        list_builds: m.solver.as_cpu().map_or(steps, |c| c.list_builds() - builds0),
        stage_retries: m.solver.as_cpu().map_or(0, |c| c.stage_retries() - retries0),
        bytes_per_particle: m.solver.as_cpu().map(|c| c.memory().total() as f64 / n.max(1) as f64),
    })
}

/// `regolith bench --scene wheel-long`: a grousered wheel at 30 % slip on a long bed.
///
/// A VIPER-sized wheel (R = 0.225 m plus 24 grousers of 0.03 m, width 0.2 m) turns at
/// ω = 0.8 rad/s and moves forward at ω r (1 − 0.3) with r = 0.255 m, its axle held 0.235 m
/// above the floor of a bed 0.2 m deep (2 cm of sinkage at the grouser tips), d0 = 2 cm,
/// Drucker–Prager sand (φ = 30°, E = 1 MPa). The bed is `length` × 0.6 m; the wheel starts
/// 1 m from its start. With the active region on, only the soil around the wheel is integrated;
/// with `patch = Some(l)` the soil is a moving patch of `l` m keeping 1 m ahead of the wheel.
pub fn wheel_long_scene(length: f64, active: bool, patch: Option<f64>) -> Result<Scene, InputError> {
    if !(length.is_finite() && (3.0..=100.0).contains(&length)) {
        return Err(InputError::flag("--length", format!("must be in [3, 100] m (got {length})")));
    }
    if let Some(l) = patch
        && !(l.is_finite() && l >= 2.5 && l < length)
    {
        return Err(InputError::flag(
            "--patch",
            format!(
                "must be at least 2.5 m (the wheel, 1 m ahead of it and the support behind) and shorter than --length {length} m (got {l})"
            ),
        ));
    }
    let omega: f64 = 0.8;
    let v = omega * 0.255 * (1.0 - 0.3);
    let text = format!(
        "[simulation]\nend_time = 1000.0\nprecision = \"f32\"\nexchange_interval = 0.001\n\n\
         [sph]\nspacing = 0.02\n{active}\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{length}, 0.6, 0.6]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n{patch}\n\
         [[bodies]]\nname = \"wheel\"\nshape = {{ type = \"wheel\", radius = 0.225, width = 0.2, grousers = 24, grouser_height = 0.03, grouser_thickness = 0.01 }}\n\
         mass = 17.5\nposition = [1.0, 0.3, 0.435]\nmotion = {{ type = \"prescribed\", linear_velocity = [{v}, 0.0, 0.0], angular_velocity = [0.0, {w}, 0.0] }}\n",
        active = if active { "\n[sph.active]\nenabled = true\n" } else { "" },
        patch = patch.map_or(String::new(), |l| format!("patch = {{ length = {l}, trigger = 1.0 }}\n")),
        w = omega.to_degrees(),
    );
    load_scene_source(Path::new("<bench wheel-long>"), &text, &[])
}

/// The timed part of a run made of exchanges (wheel-long, rover-patch).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Timed {
    /// Soil steps timed.
    pub steps: u64,
    /// Exchanges timed.
    pub exchanges: u64,
    /// Mean soil step (s).
    pub dt_mean: f64,
    /// Simulated time timed (s).
    pub simulated_s: f64,
    /// Wall time (s).
    pub seconds: f64,
    /// Simulated seconds per wall second.
    pub sim_s_per_wall_s: f64,
    /// Integrated particles × steps / s.
    pub particle_steps_per_s: f64,
}

impl Timed {
    /// From the counts: `particle_steps` is the sum over steps of the particles integrated.
    fn of(exchanges: u64, steps: u64, simulated: f64, seconds: f64, particle_steps: f64) -> Self {
        Self {
            steps,
            exchanges,
            dt_mean: simulated / steps.max(1) as f64,
            simulated_s: simulated,
            seconds,
            sim_s_per_wall_s: simulated / seconds,
            particle_steps_per_s: particle_steps / seconds,
        }
    }
}

/// One wheel-long bench run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct WheelBenchResult {
    /// Active region on.
    pub active: bool,
    /// Backend (`cpu` or `wgpu`).
    pub backend: String,
    /// Device adapter (`cpu` for the CPU backend).
    pub adapter: String,
    /// Moving patch length (m), if one.
    pub patch: Option<f64>,
    /// Soil particles in the bed.
    pub particles: usize,
    /// Wall and wheel markers.
    pub markers: usize,
    /// Mean particles integrated per step.
    pub awake_mean: f64,
    /// Exchanges, steps and time of the timed part.
    #[serde(flatten)]
    pub timed: Timed,
    /// Mean soil force on the wheel over the timed exchanges (N, world x and z).
    pub force_xz: [f64; 2],
    /// Classifications of the active region during the timed exchanges.
    pub classifications: u64,
    /// Rayon threads.
    pub threads: usize,
    /// Verlet skin of the neighbour lists (multiple of h).
    pub neighbor_skin: f64,
    /// Neighbour-list builds during the timed exchanges.
    pub list_builds: u64,
    /// Of those, steps made again because their midpoint stage left the skin.
    pub stage_retries: u64,
}

/// Runs the wheel-long bench: `warmup` untimed exchanges (1 ms each), then `exchanges` timed.
pub fn run_wheel_long(scene: &Scene, warmup: u64, exchanges: u64) -> Result<WheelBenchResult, RunError> {
    let mut sim = crate::sim::Simulation::<f32>::new(scene)?;
    let wheel = sim.body("wheel").ok_or_else(|| {
        RunError::Solver(regolith_fsi::SolverError::Setup("the wheel-long scene has no body \"wheel\"".into()))
    })?;
    for _ in 0..warmup {
        sim.step()?;
    }
    let (mut steps, mut awake_steps, mut fx, mut fz) = (0u64, 0.0, 0.0, 0.0);
    let t0 = sim.time();
    let c0 = sim.system.fluid.classifications();
    let builds0 = sim.system.fluid.as_cpu().map_or(0, |c| c.list_builds());
    let retries0 = sim.system.fluid.as_cpu().map_or(0, |c| c.stage_retries());
    let start = Instant::now();
    for _ in 0..exchanges {
        let r = sim.step()?;
        steps += u64::from(r.fluid_steps);
        awake_steps += sim.system.fluid.awake() as f64 * f64::from(r.fluid_steps);
        let w = sim.fsi_wrench(wheel);
        fx += w.force[0];
        fz += w.force[2];
    }
    let seconds = start.elapsed().as_secs_f64();
    let simulated = sim.time() - t0;
    let f = &sim.system.fluid;
    Ok(WheelBenchResult {
        active: scene.active.is_some(),
        backend: f.backend().into(),
        adapter: f.adapter(),
        patch: scene.patch.map(|p| p.length),
        particles: f.len(),
        markers: f.marker_positions().len(),
        awake_mean: awake_steps / steps.max(1) as f64,
        timed: Timed::of(exchanges, steps, simulated, seconds, awake_steps),
        force_xz: [fx / exchanges as f64, fz / exchanges as f64],
        classifications: f.classifications() - c0,
        threads: rayon::current_num_threads(),
        neighbor_skin: scene.solver.neighbor_skin,
        list_builds: f.as_cpu().map_or(steps, |c| c.list_builds() - builds0),
        stage_retries: f.as_cpu().map_or(0, |c| c.stage_retries() - retries0),
    })
}

/// The example rover's scene, from the repository root.
const ROVER_SCENE: &str = "examples/scenes/rover.toml";

/// The example rover's scene file: under the current directory (a run from the repository
/// root), else under the source tree this binary was built from.
pub fn rover_scene_file() -> Result<std::path::PathBuf, InputError> {
    let here = std::env::current_dir().map(|d| d.join(ROVER_SCENE)).ok();
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join(ROVER_SCENE);
    here.into_iter().chain([built]).find(|p| p.is_file()).ok_or_else(|| {
        InputError::flag(
            "--scene",
            format!("rover-patch needs the example scene {ROVER_SCENE}: run from the repository root"),
        )
    })
}

/// `regolith bench --scene rover-patch`: the example rover scene (`file`, examples/scenes/
/// rover.toml: the four-wheeled URDF rover, 8.5 kg, wheels R = 0.07 m with 10 grousers of
/// 8 mm, on its loose MCC soil, d0 = 2 cm, a bed 0.7 m wide and 0.1 m deep) with the bed made
/// `length` m long and the rover driving straight ahead: its wheels spin up to 3 rad/s over the
/// first 0.1 s. With `patch` the soil is a moving patch of `patch_length` m that keeps
/// `trigger` = 1 m ahead of the front wheels. The rover starts with its front wheels just
/// behind that point, so the patch advances as soon as it moves; both runs start it there.
pub fn rover_patch_scene(file: &Path, length: f64, patch_length: f64, patch: bool) -> Result<Scene, InputError> {
    if !(length.is_finite() && (3.0..=100.0).contains(&length)) {
        return Err(InputError::flag("--length", format!("must be in [3, 100] m (got {length})")));
    }
    if !(patch_length.is_finite() && patch_length >= 2.0 && patch_length < length) {
        return Err(InputError::flag(
            "--patch",
            format!(
                "must be at least 2 m (the rover, 1 m ahead of it and the support behind) and shorter than --length {length} m (got {patch_length})"
            ),
        ));
    }
    let trigger = 1.0;
    // The wheels' centres are 0.15 m ahead of and behind the chassis origin (rover.urdf);
    // their grousers reach 0.078 m from the axle.
    let x0 = patch_length - trigger - 0.15 - 0.078 - 0.02;
    let drive = "[[0.0, 0.0], [0.1, 3.0]]";
    let mut sets: Vec<(String, String)> = vec![
        ("simulation.end_time".into(), "10000.0".into()),
        ("container.max".into(), format!("[{length}, 0.7, 0.3]")),
        ("vehicles[0].position".into(), format!("[{x0}, 0.35]")),
        ("vehicles[0].drive".into(), format!("{{ left = {drive}, right = {drive}, max_torque = 6.0 }}")),
    ];
    if patch {
        sets.push(("terrain.patch".into(), format!("{{ length = {patch_length}, trigger = {trigger} }}")));
    }
    let sets: Vec<(String, toml::Value)> =
        sets.into_iter().map(|(k, v)| (k, crate::scene::overrides::parse_value(&v))).collect();
    // The example drives on a patch of its own: the whole-bed run leaves it out.
    let source = crate::input::read_text(file)?;
    let mut table: toml::Table = crate::input::parse_toml(file, &source)?;
    if let Some(t) = table.get_mut("terrain").and_then(toml::Value::as_table_mut) {
        t.remove("patch");
    }
    let text = toml::to_string(&table).map_err(|e| InputError::flag("--scene", format!("{}: {e}", file.display())))?;
    load_scene_source(file, &text, &sets)
}

/// One rover-patch bench run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RoverBenchResult {
    /// Bed length (m).
    pub length: f64,
    /// Moving patch length (m), if one.
    pub patch: Option<f64>,
    /// Soil particles at the start and the end of the timed exchanges.
    pub particles: [usize; 2],
    /// Wall and wheel markers.
    pub markers: usize,
    /// Bytes of the solver's particle, marker and list arrays at the start and the end of the
    /// timed exchanges.
    pub solver_bytes: [usize; 2],
    /// Exchanges, steps and time of the timed part.
    #[serde(flatten)]
    pub timed: Timed,
    /// The chassis' x at the start and the end of the timed exchanges (m).
    pub chassis_x: [f64; 2],
    /// Times the patch advanced during the timed exchanges.
    pub advances: u64,
    /// Rayon threads.
    pub threads: usize,
}

/// Runs the rover-patch bench: `warmup` untimed exchanges (1 ms each), then `exchanges` timed.
pub fn run_rover(scene: &Scene, warmup: u64, exchanges: u64) -> Result<RoverBenchResult, RunError> {
    let mut sim = crate::sim::Simulation::<f32>::new(scene)?;
    let chassis = sim.body("rover/base_link").ok_or_else(|| {
        RunError::Solver(regolith_fsi::SolverError::Setup("the rover-patch scene has no link rover/base_link".into()))
    })?;
    for _ in 0..warmup {
        sim.step()?;
    }
    let advances = |s: &crate::sim::Simulation<f32>| s.patch().map_or(0, |p| p.counts().0);
    let bytes = |s: &crate::sim::Simulation<f32>| s.system.fluid.as_cpu().map_or(0, |c| c.memory().total());
    let (n0, b0, a0, x0) = (sim.system.fluid.len(), bytes(&sim), advances(&sim), sim.body_state(chassis).origin[0]);
    let (mut steps, mut particle_steps) = (0u64, 0.0);
    let t0 = sim.time();
    let start = Instant::now();
    for _ in 0..exchanges {
        let r = sim.step()?;
        steps += u64::from(r.fluid_steps);
        particle_steps += sim.system.fluid.len() as f64 * f64::from(r.fluid_steps);
    }
    let seconds = start.elapsed().as_secs_f64();
    let simulated = sim.time() - t0;
    Ok(RoverBenchResult {
        length: scene.container.as_ref().map_or(0.0, |c| c.max[0] - c.min[0]),
        patch: scene.patch.map(|p| p.length),
        particles: [n0, sim.system.fluid.len()],
        markers: sim.system.fluid.marker_positions().len(),
        solver_bytes: [b0, bytes(&sim)],
        timed: Timed::of(exchanges, steps, simulated, seconds, particle_steps),
        chassis_x: [x0, sim.body_state(chassis).origin[0]],
        advances: advances(&sim) - a0,
        threads: rayon::current_num_threads(),
    })
}
