//! Command-line commands. Each returns a [`Failure`]: an input error (exit code 2, one line
//! naming the file or flag and what is allowed) or a run failure (exit code 1).

pub mod batch;
mod bench;
mod calibrate;
mod check;
mod element;
mod inspect;
mod ray;
mod run;
mod study;
mod sweep;

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

use crate::calibrate::repose::{ANGLE_TOLERANCE, ReposeSettings};
use crate::calibrate::triaxial::{PHI_TOLERANCE, SERVO_CROSSINGS};
use crate::input::InputError;

/// Why a command failed.
#[derive(Debug)]
pub enum Failure {
    /// A wrong user input: printed as one line, exit code 2.
    Input(InputError),
    /// The run itself failed: exit code 1.
    Run(anyhow::Error),
    /// Ctrl-C stopped the run after writing its outputs: exit code 130.
    Interrupted(String),
    /// A child process (the Ray sweep runner) already printed its error: exit with its code.
    Reported(u8),
}

impl From<InputError> for Failure {
    fn from(e: InputError) -> Self {
        Self::Input(e)
    }
}

impl From<anyhow::Error> for Failure {
    fn from(e: anyhow::Error) -> Self {
        Self::Run(e)
    }
}

/// Regolith: deformable soil (SPH CRM) coupled to rigid bodies.
#[derive(Debug, Parser)]
#[command(name = "regolith", version, about, long_about = None)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// Floating-point precision of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Precision {
    /// Single precision (what GPUs run).
    F32,
    /// Double precision (the reference).
    F64,
}

/// Compute backends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// A GPU when there is one, else the CPU.
    Auto,
    /// The CPU (rayon).
    Cpu,
    /// WGSL compute through wgpu.
    Wgpu,
}

/// Which bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchSceneArg {
    /// The granular block collapse.
    Block,
    /// The 0.2 × 0.4 × 0.4 m sand column collapse at d0 = 7.8 mm (67 626 particles).
    Column,
    /// A grousered wheel at 30 % slip crossing a long bed.
    WheelLong,
    /// The example rover driving along a long bed, on a moving patch against the whole bed.
    RoverPatch,
}

/// Active region of the wheel-long bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ActiveArg {
    /// Active region on.
    On,
    /// Whole domain.
    Off,
    /// Off, then on, and their ratio.
    Both,
}

/// Bench rheology.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchModelArg {
    /// Drucker–Prager.
    Dp,
    /// Modified Cam Clay.
    Mcc,
    /// Both, one after the other.
    Both,
}

/// Element tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TestArg {
    /// Isotropic compression (needs --p-end).
    Isotropic,
    /// Drained triaxial compression at cell pressure p0 (needs --axial-strain).
    DrainedTriaxial,
    /// Undrained (constant volume) triaxial compression (needs --axial-strain).
    UndrainedTriaxial,
    /// Oedometer, laterally confined (--axial-strain or --p-end).
    Oedometer,
}

/// Problem sizes of a study.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SizeArg {
    /// What CI runs (minutes on 2 cores).
    Ci,
    /// The documented size (the case files as written).
    Full,
}

/// Studies.
#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Run the hard cases and check each against its `[[expect]]` bounds; writes
    /// stability.md, stability.csv and stability.json (exit code 1 when a case fails).
    Stability(StabilityArgs),
    /// What accuracy costs in time: each case's d0 ladder and knobs, errors against closed
    /// forms, experiments or the ladder's Richardson limit; writes accuracy.csv, accuracy.json,
    /// accuracy.md and plots. Resumes: finished points are not run again.
    Accuracy {
        /// Cases to run (file stems, comma-separated; default: every case with a section for
        /// the budget).
        #[arg(long, value_name = "NAME,...", value_delimiter = ',')]
        cases: Vec<String>,
        /// Budget: which ladders and knobs (quick runs in CI in minutes).
        #[arg(long, value_enum, default_value_t = BudgetArg::Standard)]
        budget: BudgetArg,
        /// Folder of case files.
        #[arg(long, value_name = "DIR", default_value = "examples/study")]
        cases_dir: PathBuf,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/accuracy")]
        out: PathBuf,
        /// How the points are scheduled (default --jobs 1; the study always resumes).
        #[command(flatten)]
        runner: BatchRunArgs,
    },
    /// Steady seepage through a sand layer on a filter stone over a ladder of spacings, for
    /// each soil–water drag distribution: the Darcy flux against k Δh / L and against the
    /// measured gradient, with the observed order; writes darcy.md and darcy.json.
    Darcy {
        /// Spacings d0 (m), coarse to fine, comma-separated.
        #[arg(long, value_name = "M,...", value_delimiter = ',', default_value = "0.02,0.01")]
        spacings: Vec<f64>,
        /// Drag distributions, comma-separated.
        #[arg(long, value_enum, value_name = "DRAG,...", value_delimiter = ',', default_value = "svf,particle")]
        drag: Vec<DragArg>,
        /// Backend: cpu (f64, the reference) or wgpu (f32).
        #[arg(long, value_enum, default_value = "cpu")]
        backend: StudyBackendArg,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/darcy")]
        out: PathBuf,
    },
}

/// The backend a study's runs take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StudyBackendArg {
    /// Rayon on the CPU, f64.
    Cpu,
    /// WGSL compute through wgpu, f32.
    Wgpu,
}

/// Soil–water drag distribution (`[sph] drag`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DragArg {
    /// Smooth volume fractions.
    Svf,
    /// Per particle (bang-bang).
    Particle,
}

/// The accuracy study's options from its flags.
pub(crate) fn accuracy_options(
    cases: Vec<String>,
    budget: BudgetArg,
    cases_dir: PathBuf,
    out: PathBuf,
    jobs: usize,
) -> crate::accuracy::AccuracyOptions {
    let budget = match budget {
        BudgetArg::Quick => "quick",
        BudgetArg::Standard => "standard",
        BudgetArg::Full => "full",
    };
    crate::accuracy::AccuracyOptions { cases_dir, cases, budget: budget.into(), jobs, out, quiet: false }
}

/// Budgets of the accuracy study.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BudgetArg {
    /// Minutes on 2 cores (CI).
    Quick,
    /// The shipped study (docs/accuracy).
    Standard,
    /// Finer ladders, more knobs.
    Full,
}

/// Calibrations.
#[derive(Debug, Subcommand)]
pub enum CalibrateCommand {
    /// Fit the tangent Mohr–Coulomb envelope (c, φ with standard errors) to triaxial failure
    /// stresses; writes envelope.json and mohr.png/svg.
    Envelope {
        /// CSV with `sigma3` (confining) and `sigma1` (vertical at failure) in Pa, compression
        /// positive, one row per test.
        #[arg(long, value_name = "FILE.csv")]
        tests: PathBuf,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/calibrate-envelope")]
        out: PathBuf,
    },
    /// Fit Modified Cam Clay parameters to lab data: λ, κ, v_λ (at 1 kPa) and the OCR from an
    /// isotropic compression test, M from critical states; writes mcc.json, isotropic.png/svg
    /// and, with --base, a ready material.toml.
    Mcc {
        /// Isotropic compression CSV: a header with `p` (Pa) and `v` (specific volume) or `e`
        /// (void ratio), rows in test order (loading, unloading and reloading).
        #[arg(long, value_name = "FILE.csv")]
        isotropic: PathBuf,
        /// Critical states CSV: `p` and `q` (Pa), one row per triaxial test.
        #[arg(long, value_name = "FILE.csv")]
        critical: Option<PathBuf>,
        /// Material file whose other keys (density, elasticity) the written material keeps.
        #[arg(long, value_name = "FILE")]
        base: Option<PathBuf>,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/calibrate-mcc")]
        out: PathBuf,
    },
    /// The static angle of repose of the SPH soil: a column on a base disc inside a hollow
    /// cylinder that is lifted; what falls off the base sinks; the pile is analysed in slices ×
    /// cells (AGX's method). Writes repose.json, particles.csv, series.csv, scene.toml and the
    /// profile and top_view plots.
    Repose {
        /// Material file (TOML).
        #[arg(long, value_name = "FILE")]
        material: PathBuf,
        /// Radius of the base disc and of the cylinder (m).
        #[arg(long, value_name = "M", default_value_t = 0.1)]
        radius: f64,
        /// Height of the soil column (m) [default: 2 × radius].
        #[arg(long, value_name = "M")]
        height: Option<f64>,
        /// Particle spacing d0 (m) [default: radius / 15].
        #[arg(long, value_name = "M")]
        spacing: Option<f64>,
        /// Lifting speed of the cylinder (m/s).
        #[arg(long, value_name = "M/S", default_value_t = 0.1)]
        lift_speed: f64,
        /// Longest relaxation after the cylinder has cleared the pile (s); it ends sooner once
        /// the pile is at rest (rms speed below 10⁻³ √(g R)).
        #[arg(long, value_name = "S", default_value_t = 3.0)]
        relax_time: f64,
        /// Slices of the analysis.
        #[arg(long, value_name = "N", default_value_t = 20)]
        slices: usize,
        /// Cells per slice.
        #[arg(long, value_name = "N", default_value_t = 15)]
        cells: usize,
        /// Cell radius (m) [default: the spacing].
        #[arg(long, value_name = "M")]
        cell_radius: Option<f64>,
        /// Floating-point precision of the run.
        #[arg(long, value_enum, default_value = "f32")]
        precision: Precision,
        /// Adjust the material's friction angle until the pile stands at this angle (degrees);
        /// writes material.toml when the loop converges.
        #[arg(long, value_name = "DEG")]
        target_angle: Option<f64>,
        /// The loop accepts a pile within this many degrees of the target, or within the
        /// slices' standard error if that is larger.
        #[arg(long, value_name = "DEG", default_value_t = ANGLE_TOLERANCE)]
        tolerance: f64,
        /// Override a key of the test's scene, e.g. `--set sph.artificial_viscosity=0`
        /// (repeatable; the scene is written into the output folder).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = crate::scene::parse_set)]
        sets: Vec<(String, toml::Value)>,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/calibrate-repose")]
        out: PathBuf,
    },
    /// The virtual triaxial test of the SPH soil: a box sample between six servo-controlled
    /// smooth plates, consolidated to each confining stress and sheared by the top and
    /// bottom plates; failure on the low-pass-filtered vertical stress; the Mohr–Coulomb
    /// envelope (c, φ with standard errors). Writes triaxial.json, per test series.csv and
    /// stress_strain plots, and the Mohr-circle plot.
    Triaxial(TriaxialArgs),
    /// Bekker's k_c, k_φ and n of the SPH soil, with standard errors: a plate rig scene run at
    /// each plate size (in parallel, resumable), the law fitted to all curves; writes
    /// bekker.json and the curves with the fit (bekker.png / .svg).
    Plate(PlateArgs),
    /// The cone index profile of the SPH soil: a cone rig scene run once (recorded,
    /// resumable), the cone index averaged over depth layers with its spread, and the gradient
    /// G of CI = G z; writes cone.json and cone_index.png / .svg.
    Cone {
        /// A scene with a cone rig (`[rig] type = "cone"`).
        #[arg(long, value_name = "FILE")]
        scene: PathBuf,
        /// Override a scene key, e.g. `--set sph.spacing=0.005` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Thickness of the depth layers (m).
        #[arg(long, value_name = "M", default_value_t = 0.01)]
        layer: f64,
        /// Keep the run if it is already recorded in the output folder.
        #[arg(long)]
        resume: bool,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "out/calibrate-cone")]
        out: PathBuf,
    },
}

/// The envelope a triaxial calibration loop matches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MatchArg {
    /// The particles' own stresses.
    Particles,
    /// The soil's load from the plates' forces (the report's main envelope).
    Plates,
}

/// The low-pass filter of a triaxial test's failure pick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FilterArg {
    /// A Gaussian kernel (positive: it never overshoots).
    Gaussian,
    /// AGX's Butterworth, forward and backward.
    Butterworth,
}

/// How a triaxial test's failure point is picked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FailureArg {
    /// The first local maximum of the filtered vertical stress.
    Peak,
    /// The critical state: the mean over the last fifth of the test.
    Plateau,
}

/// Sweep subcommands.
#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Join a sweep directory's shard files (results.shard-I-of-N.jsonl) into results.jsonl
    /// and results.csv.
    Merge {
        /// The sweep's output directory.
        dir: PathBuf,
    },
    /// Observed order and extrapolated limit (Richardson) of a summary value over a
    /// resolution ladder: points that differ only in `--over` form one ladder each. Writes
    /// convergence.json in DIR.
    Converge {
        /// The sweep's output directory.
        dir: PathBuf,
        /// The resolution key the sweep varied.
        #[arg(long, value_name = "KEY", default_value = "sph.spacing")]
        over: String,
        /// The summary value to analyse, named as its results.csv column
        /// (e.g. `rig.steady_state[0].drawbar_pull`, `runout.runout_m`).
        #[arg(long, value_name = "COLUMN")]
        metric: String,
    },
}

/// How a sweep's points are run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RunnerArg {
    /// One Ray task per point (a local Ray instance, or the cluster at --address); needs
    /// Python with the regolith package and ray.
    Ray,
    /// --jobs points at a time on threads of this process.
    Threads,
}

/// `regolith calibrate triaxial ...`.
#[derive(Debug, Clone, clap::Args)]
pub struct TriaxialArgs {
    /// Material file (TOML).
    #[arg(long, value_name = "FILE")]
    pub material: PathBuf,
    /// Confining stresses, one test each (Pa) [default: 5e3,10e3,...,50e3].
    #[arg(long, value_name = "PA,...", value_delimiter = ',')]
    pub confining: Vec<f64>,
    /// Sample width along x and y (m).
    #[arg(long, value_name = "M", default_value_t = 0.1)]
    pub width: f64,
    /// Sample height (m) [default: 2 × width].
    #[arg(long, value_name = "M")]
    pub height: Option<f64>,
    /// Particle spacing d0 (m) [default: width / 10].
    #[arg(long, value_name = "M")]
    pub spacing: Option<f64>,
    /// Axial strain rate of the shear phase (1/s).
    #[arg(long, value_name = "1/S", default_value_t = 0.2)]
    pub strain_rate: f64,
    /// Axial strain at which the shear phase ends.
    #[arg(long, value_name = "STRAIN", default_value_t = 0.1)]
    pub max_strain: f64,
    /// Failure: the first peak of the filtered vertical stress (AGX), or the critical-state
    /// plateau (the mean over the last fifth) [default: plateau for MCC, else peak].
    #[arg(long, value_enum)]
    pub failure: Option<FailureArg>,
    /// Low-pass filter of the failure pick: a Gaussian kernel (no overshoot where the sample
    /// yields) or AGX's Butterworth (which overshoots a sharp yield by about 1.6 % of the
    /// elastic slope × the wavelength, read as cohesion).
    #[arg(long, value_enum, default_value = "gaussian")]
    pub filter: FilterArg,
    /// Order of the Butterworth filter [default: 4; only with --filter butterworth].
    #[arg(long, value_name = "N")]
    pub filter_order: Option<usize>,
    /// Shortest wavelength the filter keeps (axial strain).
    #[arg(long, value_name = "STRAIN", default_value_t = 0.01)]
    pub filter_wavelength: f64,
    /// Time constant of the plates' servo, in P-wave crossings of the sample's longest side
    /// (smaller: stiffer; the lateral stress lags a yielding sample less).
    #[arg(long, value_name = "N", default_value_t = SERVO_CROSSINGS)]
    pub servo_crossings: f64,
    /// Floating-point precision of the runs.
    #[arg(long, value_enum, default_value = "f32")]
    pub precision: Precision,
    /// Adjust the material's friction angle until the sample's envelope has this φ
    /// (degrees); writes material.toml when the loop converges.
    #[arg(long, value_name = "DEG")]
    pub target_phi: Option<f64>,
    /// The loop accepts a φ within this many degrees of the target, or within its
    /// standard error if that is larger.
    #[arg(long, value_name = "DEG", default_value_t = PHI_TOLERANCE)]
    pub tolerance: f64,
    /// Adjust the material's cohesion until the sample's envelope has this c (Pa); with
    /// --target-phi, both are adjusted together. Drucker–Prager materials only.
    #[arg(long, value_name = "PA")]
    pub target_c: Option<f64>,
    /// The loop accepts a c within this many pascals of the target, or within its standard
    /// error if that is larger [default: 5 % of the target, at least 50 Pa].
    #[arg(long, value_name = "PA")]
    pub tolerance_c: Option<f64>,
    /// The envelope the loop matches to the targets: the particles' own stresses (the soil's
    /// strength) or the soil's load from the plates' forces (the report's main envelope)
    /// [default: particles; only with --target-phi or --target-c].
    #[arg(long = "match", value_enum, value_name = "ENVELOPE")]
    pub matching: Option<MatchArg>,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "out/calibrate-triaxial")]
    pub out: PathBuf,
    /// How the tests are scheduled (default --jobs: one per core).
    #[command(flatten)]
    pub runner: BatchRunArgs,
}

/// `regolith calibrate plate ...`.
#[derive(Debug, Clone, clap::Args)]
pub struct PlateArgs {
    /// A scene with a plate rig (`[rig] type = "plate"`).
    #[arg(long, value_name = "FILE")]
    pub scene: PathBuf,
    /// Plate sizes, one run each (radius of a circular plate, smaller side of a rectangular
    /// one, m) [default: the rig's `sizes`].
    #[arg(long, value_name = "M,...", value_delimiter = ',')]
    pub sizes: Vec<f64>,
    /// Override a scene key in every run, e.g. `--set sph.spacing=0.01` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "out/calibrate-plate")]
    pub out: PathBuf,
    /// How the runs are scheduled.
    #[command(flatten)]
    pub runner: BatchRunArgs,
}

/// `regolith study stability ...`.
#[derive(Debug, Clone, clap::Args)]
pub struct StabilityArgs {
    /// Cases to run (file stems, comma-separated; default: all).
    #[arg(long, value_name = "NAME,...", value_delimiter = ',')]
    pub cases: Vec<String>,
    /// Problem size.
    #[arg(long, value_enum, default_value_t = SizeArg::Ci)]
    pub size: SizeArg,
    /// Folder of case files.
    #[arg(long, value_name = "DIR", default_value = "examples/hard")]
    pub cases_dir: PathBuf,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "out/stability")]
    pub out: PathBuf,
    /// How the cases are scheduled.
    #[command(flatten)]
    pub runner: BatchRunArgs,
}

/// How the runs of a study or a calibration are scheduled: threads of this process, or one Ray
/// task each (the Python package's runner, on a local instance or a cluster). Either way each
/// run's record goes to the output folder's `results.jsonl` as it finishes.
#[derive(Debug, Clone, clap::Args)]
pub struct BatchRunArgs {
    /// Threads of this process, or one Ray task per run.
    #[arg(long, value_enum, default_value_t = RunnerArg::Threads)]
    pub runner: RunnerArg,
    /// Runs at once (threads).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Keep the runs already recorded in the output folder (same inputs, same version) and
    /// run only the others; without it every run starts again.
    #[arg(long)]
    pub resume: bool,
    /// Ray cluster to join (`auto`, `ray://host:10001`); default: start a local instance.
    #[arg(long, value_name = "ADDRESS")]
    pub address: Option<String>,
    /// CPUs per run (Ray).
    #[arg(long, value_name = "N")]
    pub num_cpus: Option<f64>,
    /// GPUs per run (Ray).
    #[arg(long, value_name = "N")]
    pub num_gpus: Option<f64>,
}

/// How a sweep combines its varied keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DesignArg {
    /// Every combination of the listed values.
    Grid,
    /// A Latin hypercube of --samples points.
    Lhs,
}

/// `regolith sweep SCENE ...`.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// Scene file (TOML).
    pub scene: Option<PathBuf>,
    /// A varied key and its values: `KEY=a,b,c` (TOML values) or `KEY=lo:hi` (a range, for
    /// --design lhs). Repeatable; a grid crosses them, the first varying slowest.
    #[arg(long, value_name = "KEY=VALUES")]
    pub vary: Vec<String>,
    /// Override a scene key at every point, e.g. `--set output.mcap=false` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Grid or Latin hypercube.
    #[arg(long, value_enum, default_value_t = DesignArg::Grid)]
    pub design: DesignArg,
    /// Points of a Latin hypercube.
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Seed of the Latin hypercube.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Ray tasks or threads of this process.
    #[arg(long, value_enum, default_value_t = RunnerArg::Ray)]
    pub runner: RunnerArg,
    /// Ray cluster to join (`auto`, `ray://host:10001`); default: start a local instance.
    #[arg(long, value_name = "ADDRESS")]
    pub address: Option<String>,
    /// CPUs per point (Ray).
    #[arg(long, value_name = "N")]
    pub num_cpus: Option<f64>,
    /// GPUs per point (Ray).
    #[arg(long, value_name = "N")]
    pub num_gpus: Option<f64>,
    /// Points run at once (threads).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Run only shard i of n (points p with p % n = i − 1); default inside a SLURM array job:
    /// the task's (SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Run again the points recorded as failed.
    #[arg(long)]
    pub retry_failed: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    pub out: PathBuf,
    /// No progress lines.
    #[arg(long)]
    pub quiet: bool,
}

/// `regolith bench`: which bench and how it is timed.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// Which bench: the soil block, the sand column, or a wheel at 30 % slip on a long bed.
    #[arg(long, value_enum, default_value_t = BenchSceneArg::Block)]
    pub scene: BenchSceneArg,
    /// wheel-long only: run with the active region on, off, or both (the ratio in one run).
    #[arg(long, value_enum)]
    pub active: Option<ActiveArg>,
    /// wheel-long and rover-patch only: bed length (m; default 10 and 20).
    #[arg(long, value_name = "M")]
    pub length: Option<f64>,
    /// wheel-long: also time the wheel on a moving patch of this length (m), without the
    /// active region and (unless `--active off`) with it, against the whole bed;
    /// rover-patch: the patch's length (default 3 m).
    #[arg(long, value_name = "M")]
    pub patch: Option<f64>,
    /// Verlet skins of the neighbour lists to time, multiples of h, comma-separated (e.g.
    /// `0,0.3`: rebuilt every step against reused lists, in one run); default: the scene
    /// default.
    #[arg(long, value_name = "S,…", value_delimiter = ',')]
    pub skin: Vec<f64>,
    /// block only: soil particles (about; default 100 000).
    #[arg(long, value_name = "N")]
    pub particles: Option<usize>,
    /// block only: rheology, dp, mcc or both (default both).
    #[arg(long, value_enum)]
    pub model: Option<BenchModelArg>,
    /// Backend.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Precision.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    pub precision: Precision,
    /// Timed steps (exchanges of 1 ms for wheel-long and rover-patch); default 40, rover-patch
    /// 200.
    #[arg(long, value_name = "N")]
    pub steps: Option<u64>,
    /// Untimed warm-up steps (exchanges for wheel-long and rover-patch); default 5,
    /// rover-patch 150 (the rover settles and its wheels spin up).
    #[arg(long, value_name = "N")]
    pub warmup: Option<u64>,
    /// Also write the results as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Time carving a 100 000-triangle closed mesh out of a 1 M-point lattice (what a mesh
    /// body costs at scene start) instead of the soil block.
    #[arg(long)]
    pub carve: bool,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one scene at many points (`--vary KEY=VALUES`, a grid or a Latin hypercube) on Ray
    /// or threads, resumable, in shards for SLURM arrays: results.jsonl, results.csv and each
    /// point's outputs under `points/<id>/`. `regolith sweep merge DIR` joins shards.
    #[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
    Sweep {
        /// `merge`.
        #[command(subcommand)]
        sub: Option<SweepCommand>,
        /// The sweep.
        #[command(flatten)]
        args: SweepArgs,
    },
    /// Soil parameters from measurements: `mcc` (Modified Cam Clay from lab data), `envelope`
    /// (c and φ from triaxial failure stresses).
    Calibrate {
        /// Which calibration.
        #[command(subcommand)]
        calibrate: CalibrateCommand,
    },
    /// Studies over shipped scenes: `stability` (the hard-case suite), `accuracy` (error
    /// against cost over d0 ladders and knobs).
    Study {
        /// Which study.
        #[command(subcommand)]
        study: StudyCommand,
    },
    /// Drive one material point through a laboratory test (calibration and verification).
    #[command(allow_negative_numbers = true)]
    Element {
        /// Material file (TOML).
        #[arg(long, value_name = "FILE")]
        material: PathBuf,
        /// The test.
        #[arg(long, value_enum)]
        test: TestArg,
        /// Initial isotropic pressure, also the cell pressure (Pa).
        #[arg(long, value_name = "PA")]
        p0: f64,
        /// Overconsolidation ratio, overriding the material's (MCC).
        #[arg(long, value_name = "X")]
        ocr: Option<f64>,
        /// Total axial strain: natural (logarithmic), compression positive, in (0, 5] (triaxial, oedometer).
        #[arg(long, value_name = "E", conflicts_with = "p_end")]
        axial_strain: Option<f64>,
        /// Final mean pressure (isotropic, oedometer), Pa.
        #[arg(long, value_name = "PA")]
        p_end: Option<f64>,
        /// Unload to this mean pressure after --p-end (Pa).
        #[arg(long, value_name = "PA", requires = "p_end")]
        p_unload: Option<f64>,
        /// Number of increments.
        #[arg(long, value_name = "N", default_value_t = 2000)]
        steps: usize,
        /// Precision.
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
        /// Output directory (element.json, element.png, element.svg).
        #[arg(long, value_name = "DIR", default_value = "out/element")]
        out: PathBuf,
    },
    /// Run a scene: write summary.json, particles_final.csv, series.csv, recording.mcap and
    /// plots to the output directory.
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: the scene's output.dir, else `out/<scene name>`).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Backend, overriding the scene's.
        #[arg(long, value_enum)]
        backend: Option<BackendArg>,
        /// Precision, overriding the scene's.
        #[arg(long, value_enum)]
        precision: Option<Precision>,
        /// Override a scene key, e.g. `--set simulation.end_time=0.5` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = crate::scene::parse_set)]
        sets: Vec<(String, toml::Value)>,
        /// Slip ratios for a single-wheel rig, e.g. `--slips 0,0.2,0.4` (overrides rig.slips).
        #[arg(long, value_name = "S,S,...", value_delimiter = ',')]
        slips: Option<Vec<f64>>,
        /// No scene description and no progress bar (the one-line summary still prints).
        #[arg(long)]
        quiet: bool,
    },
    /// Print the topics, message counts and time range of a recording (.mcap).
    Inspect {
        /// Recording file.
        recording: PathBuf,
    },
    /// Time a fixed granular block collapse (particle-steps/s, neighbour interactions/s), or a
    /// wheel crossing a long bed with and without an active region (`--scene wheel-long`).
    Bench(BenchArgs),
    /// Parse and validate a scene file and print what would run.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene key, e.g. `--set simulation.end_time=0.5` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = crate::scene::parse_set)]
        sets: Vec<(String, toml::Value)>,
    },
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Element { material, test, p0, ocr, axial_strain, p_end, p_unload, steps, precision, out } => {
            element::run(element::Args {
                material,
                test,
                p0,
                ocr,
                axial_strain,
                p_end,
                p_unload,
                steps,
                precision,
                out,
            })
        }
        Command::Check { scene, sets } => check::run(&scene, &sets),
        Command::Bench(a) => bench_cmd(a),
        Command::Run { scene, out, backend, precision, sets, slips, quiet } => {
            let mut sets = sets;
            if let Some(s) = slips {
                sets.push((
                    "rig.slips".to_string(),
                    toml::Value::Array(s.into_iter().map(toml::Value::Float).collect()),
                ));
            }
            run::run(&scene, out.as_deref(), backend, precision, &sets, quiet)
        }
        Command::Inspect { recording } => inspect::run(&recording),
        Command::Sweep { sub: Some(SweepCommand::Merge { dir }), .. } => sweep::merge(&dir),
        Command::Sweep { sub: Some(SweepCommand::Converge { dir, over, metric }), .. } => {
            sweep::converge(&dir, &over, &metric)
        }
        Command::Sweep { sub: None, args } => sweep::run(args),
        Command::Calibrate { calibrate } => calibrate_cmd(calibrate),
        Command::Study { study } => study_cmd(study),
    }
}

/// `regolith bench`: the flags each bench takes are checked here, each wrong one a one-line
/// error naming it.
fn bench_cmd(args: BenchArgs) -> Result<(), Failure> {
    match args {
        BenchArgs { carve: true, skin, .. } if !skin.is_empty() => {
            Err(InputError::flag("--skin", "does not apply to --carve".to_string()).into())
        }
        BenchArgs { carve: true, json, .. } => bench::carve(json.as_deref()),
        BenchArgs { scene: BenchSceneArg::WheelLong | BenchSceneArg::RoverPatch, precision, .. }
            if precision != Precision::F32 =>
        {
            Err(InputError::flag("--precision", "wheel-long and rover-patch run in f32 only".to_string()).into())
        }
        BenchArgs { scene: BenchSceneArg::RoverPatch, backend, .. } if backend != BackendArg::Cpu => {
            Err(InputError::flag("--backend", "rover-patch times the CPU backend only: use --backend cpu".to_string())
                .into())
        }
        BenchArgs { scene: BenchSceneArg::WheelLong, particles, model, .. }
            if particles.is_some() || model.is_some() =>
        {
            Err(InputError::flag(
                if particles.is_some() { "--particles" } else { "--model" },
                "applies to --scene block only".to_string(),
            )
            .into())
        }
        BenchArgs {
            scene: BenchSceneArg::WheelLong,
            active,
            backend,
            length,
            patch,
            steps,
            warmup,
            json,
            skin,
            carve: false,
            ..
        } => bench::wheel_long(
            bench::WheelLong {
                active: active.unwrap_or(ActiveArg::Both),
                backend,
                length: length.unwrap_or(10.0),
                patch,
            },
            &skin,
            steps.unwrap_or(40),
            warmup.unwrap_or(5),
            json.as_deref(),
        ),
        BenchArgs { scene: BenchSceneArg::RoverPatch, particles, model, active, skin, .. }
            if particles.is_some() || model.is_some() || active.is_some() || !skin.is_empty() =>
        {
            Err(InputError::flag(
                if particles.is_some() {
                    "--particles"
                } else if model.is_some() {
                    "--model"
                } else if active.is_some() {
                    "--active"
                } else {
                    "--skin"
                },
                "does not apply to --scene rover-patch (its flags: --length, --patch, --steps, --warmup, --json)"
                    .to_string(),
            )
            .into())
        }
        BenchArgs { scene: BenchSceneArg::RoverPatch, length, patch, steps, warmup, json, carve: false, .. } => {
            bench::rover_patch(
                length.unwrap_or(20.0),
                patch.unwrap_or(3.0),
                steps.unwrap_or(200),
                warmup.unwrap_or(150),
                json.as_deref(),
            )
        }
        BenchArgs { active, length, patch, .. } if active.is_some() || length.is_some() || patch.is_some() => {
            Err(InputError::flag(
                if active.is_some() {
                    "--active"
                } else if length.is_some() {
                    "--length"
                } else {
                    "--patch"
                },
                if active.is_some() {
                    "applies to --scene wheel-long only"
                } else {
                    "applies to --scene wheel-long or rover-patch only"
                }
                .to_string(),
            )
            .into())
        }
        BenchArgs { scene: BenchSceneArg::Column, particles, model, .. } if particles.is_some() || model.is_some() => {
            Err(InputError::flag(
                if particles.is_some() { "--particles" } else { "--model" },
                "applies to --scene block only (the column is fixed: 67 626 particles, Drucker-Prager)".to_string(),
            )
            .into())
        }
        BenchArgs {
            scene: bench_kind,
            particles,
            model,
            backend,
            precision,
            steps,
            warmup,
            json,
            skin,
            carve: false,
            ..
        } => bench::run(
            bench::Kind { column: bench_kind == BenchSceneArg::Column, particles, model },
            backend,
            precision,
            &skin,
            steps.unwrap_or(40),
            warmup.unwrap_or(5),
            json.as_deref(),
        ),
    }
}

/// `regolith calibrate …`.
fn calibrate_cmd(calibrate: CalibrateCommand) -> Result<(), Failure> {
    match calibrate {
        CalibrateCommand::Envelope { tests, out } => calibrate::envelope(tests, out),
        CalibrateCommand::Mcc { isotropic, critical, base, out } => calibrate::mcc(isotropic, critical, base, out),
        CalibrateCommand::Repose {
            material,
            radius,
            height,
            spacing,
            lift_speed,
            relax_time,
            slices,
            cells,
            cell_radius,
            precision,
            target_angle,
            tolerance,
            sets,
            out,
        } => {
            let mut s = ReposeSettings::for_radius(radius);
            s.sets = sets;
            if let Some(h) = height {
                s.height = h;
            }
            if let Some(d) = spacing {
                s.spacing = d;
                s.cell_radius = d;
            }
            if let Some(c) = cell_radius {
                s.cell_radius = c;
            }
            s.lift_speed = lift_speed;
            s.relax_time = relax_time;
            s.slices = slices;
            s.cells = cells;
            s.precision = match precision {
                Precision::F32 => crate::scene::Precision::F32,
                Precision::F64 => crate::scene::Precision::F64,
            };
            calibrate::repose(material, s, target_angle, tolerance, out)
        }
        CalibrateCommand::Cone { scene, sets, layer, resume, out } => {
            let sets = sets
                .iter()
                .map(|s| crate::scene::parse_set(s).map_err(|m| InputError::flag("--set", m)))
                .collect::<Result<Vec<_>, _>>()?;
            calibrate::cone(crate::calibrate::cone::ConeInputs { scene, sets, layer, out, resume })
        }
        CalibrateCommand::Plate(a) => {
            if a.runner.runner == RunnerArg::Ray {
                return batch::ray(&a.runner, "calibrate plate");
            }
            batch::threads_only(&a.runner)?;
            calibrate::plate(a.inputs()?)
        }
        CalibrateCommand::Triaxial(a) => {
            if a.runner.runner == RunnerArg::Ray {
                batch::no_loop_on_ray(&a)?;
                return batch::ray(&a.runner, "calibrate triaxial");
            }
            batch::threads_only(&a.runner)?;
            calibrate::triaxial(a.inputs()?)
        }
    }
}

/// `regolith study …`.
fn study_cmd(study: StudyCommand) -> Result<(), Failure> {
    match study {
        StudyCommand::Darcy { spacings, drag, backend, out } => {
            // Without an adapter the first point says so in one line (`darcy_point_on`).
            let backend = match backend {
                StudyBackendArg::Cpu => crate::scene::Backend::Cpu,
                StudyBackendArg::Wgpu => crate::scene::Backend::Wgpu,
            };
            let drags = drag
                .into_iter()
                .map(|d| match d {
                    DragArg::Svf => regolith_fsi::config::Drag::Svf,
                    DragArg::Particle => regolith_fsi::config::Drag::Particle,
                })
                .collect();
            let points = crate::study::darcy::darcy_study(&crate::study::darcy::DarcyOptions {
                spacings,
                drags,
                backend,
                out: out.clone(),
            })
            .map_err(study::study_failure)?;
            println!("{}", crate::study::darcy::table(&points));
            println!("table in {}", out.join("darcy.md").display());
            Ok(())
        }
        StudyCommand::Stability(a) => {
            if a.runner.runner == RunnerArg::Ray {
                return batch::ray(&a.runner, "study stability");
            }
            batch::threads_only(&a.runner)?;
            study::stability_cmd(&a.options())
        }
        StudyCommand::Accuracy { cases, budget, cases_dir, out, runner } => {
            if runner.resume {
                return Err(InputError::flag(
                    "--resume",
                    "the accuracy study always resumes (a finished point is never run again); drop the flag",
                )
                .into());
            }
            if runner.runner == RunnerArg::Ray {
                return batch::ray(&runner, "study accuracy");
            }
            batch::threads_only(&runner)?;
            study::accuracy_cmd(&accuracy_options(cases, budget, cases_dir, out, runner.jobs.unwrap_or(1)))
        }
    }
}
