//! What a validated scene is made of: the types [`super::load_scene`] returns.

use super::*;

/// Which compute backend runs the soil.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// A GPU through wgpu when one exists, else the CPU.
    Auto,
    /// Rayon on the CPU (the reference).
    Cpu,
    /// WGSL compute through wgpu.
    Wgpu,
}

impl Backend {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Cpu => "cpu",
            Self::Wgpu => "wgpu",
        }
    }
}

/// Floating-point precision of the soil solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// Single.
    F32,
    /// Double.
    F64,
}

/// Where a body's outermost BCE marker layer lies (`[sph] body_markers`). Soil resting on
/// markers sits one spacing from them, i.e. meets the body half a spacing outside the
/// outermost layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BodyMarkers {
    /// On the body's surface (the default): the body acts half a spacing larger than its
    /// geometry on every face (a plate of radius R as R + d0/2).
    #[default]
    Surface,
    /// Half a spacing inside the surface: the soil meets the body's geometry.
    Inset,
}

impl BodyMarkers {
    /// Where the outermost layer lies, in words (`regolith check`).
    pub fn describe(self) -> &'static str {
        match self {
            Self::Surface => "the first on the surface",
            Self::Inset => "the first d0/2 inside the surface",
        }
    }

    /// Depth of the outermost layer below the surface at spacing `d0` (m).
    pub fn inset(self, d0: f64) -> f64 {
        match self {
            Self::Surface => 0.0,
            Self::Inset => 0.5 * d0,
        }
    }

    /// How far outside its geometry a body meets the soil (m): soil rests one spacing from
    /// the outermost markers, i.e. half a spacing beyond them, less the inset. Rigs and
    /// vehicles start bodies this far above the soil's surface, and soil closer than this to
    /// a body at the start is carved out.
    pub fn contact_offset(self, d0: f64) -> f64 {
        0.5 * d0 - self.inset(d0)
    }
}

impl Precision {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::F64 => "f64",
        }
    }
}

/// A named, validated material of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMaterial {
    /// Name used by terrain and soil blocks.
    pub name: String,
    /// Checked parameters (from the scene or from the file it names).
    pub params: MaterialParams,
}

impl SceneMaterial {
    /// Whether this is the scene's pore water (`model = "water"`) rather than a soil.
    pub fn is_water(&self) -> bool {
        self.params.model == Some(regolith_fsi::rheology::ModelKind::Water)
    }
}

/// Soil of one material in one region.
#[derive(Clone, Debug, PartialEq)]
pub struct SoilSpec {
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Where.
    pub region: SoilRegion,
    /// The key it came from (`terrain`, `soil_blocks[2]`), for messages.
    pub key: String,
    /// Initial velocity of its particles (m/s; `soil_blocks[i].velocity`, the bed starts at rest).
    pub velocity: [f64; 3],
    /// Isotropic compression the particles start with in place of the geostatic state (Pa;
    /// `soil_blocks[i].initial_pressure`): a sample consolidated before the run, whose MCC
    /// preconsolidation is `ocr` times it. The walls or bodies around it must hold it.
    pub initial_pressure: Option<f64>,
}

/// A body of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct BodySpec {
    /// The rigid body.
    pub desc: BodyDesc,
    /// Whether it interacts with the soil (gets BCE markers).
    pub fsi: bool,
    /// Marker layers.
    pub bce_layers: usize,
    /// The key it came from (`bodies[1]`).
    pub key: String,
    /// What to draw in place of the collision shape (a URDF link's visual geometry).
    pub visual: Option<ShapeDesc>,
    /// A free body's velocity at the start (m/s; `motion = { type = "free", velocity = … }`).
    pub initial_velocity: Option<[f64; 3]>,
    /// Half-width (m) the body's active-domain box adds around its bounding box
    /// (`active_margin`); `None` takes `[sph.active]`'s.
    pub active_margin: Option<f64>,
    /// How soil slides along the body (`soil_contact`; rough by default).
    pub contact: WallContact,
    /// Water passes through the body's markers, the soil does not (`permeable`: a filter
    /// stone).
    pub permeable: bool,
}

/// How a plate is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlateControl {
    /// Pushed down at a constant speed (m/s).
    Speed(f64),
    /// Loaded with a constant downward force (N) on top of its weight.
    Load(f64),
}

/// How a wheel's carriage moves.
#[derive(Clone, Debug, PartialEq)]
pub enum WheelDrive {
    /// Carriage speed prescribed for each slip ratio `s`: `v = ω R (1 − s)`, one run per slip.
    Slips(Vec<f64>),
    /// Free carriage pulled back by a constant towing force (N); slip is an output.
    Tow(f64),
    /// Free carriage driven up each slope (degrees, one run per slope): gravity is tilted
    /// about y so that the slope rises along +x, the load is carried along gravity, and the
    /// steady slip is an output.
    Slopes(Vec<f64>),
}

/// A test rig.
#[derive(Clone, Debug, PartialEq)]
pub enum RigSpec {
    /// Plate sinkage (bevameter).
    Plate {
        /// Index into [`Scene::bodies`].
        body: usize,
        /// Speed or load control.
        control: PlateControl,
        /// Sinkage at which the push stops (m).
        depth: f64,
        /// Plate sizes to run (radius of a circular plate, smaller side of a rectangular
        /// one, m); empty runs the body as given.
        sizes: Vec<f64>,
    },
    /// Cone penetrometer.
    Cone {
        /// Index into [`Scene::bodies`].
        body: usize,
        /// Push speed (m/s).
        speed: f64,
        /// Depth of the cone base at which the push stops (m).
        depth: f64,
    },
    /// Single-wheel test rig.
    Wheel {
        /// Index into [`Scene::bodies`].
        body: usize,
        /// Vertical load on the soil, wheel weight included (N).
        load: f64,
        /// Wheel angular velocity (rad/s).
        angular_velocity: f64,
        /// Slip list or towing force.
        drive: WheelDrive,
        /// Radius in the slip `s = 1 − v / (ω r)` (m): the rim's unless given (experiments on
        /// grousered wheels often use the rim plus the grouser height).
        slip_radius: Option<f64>,
    },
}

/// Default `[simulation] runaway_speed` (m/s): five times the fastest soil of the stability
/// suite (a 20 m/s jet at a wall); soil moving at 100 m/s in a terramechanics scene means the
/// solution has already diverged.
pub const DEFAULT_RUNAWAY_SPEED: f64 = 100.0;

/// `[sph.active]`: how the active region is kept.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveSpec {
    /// Travel allowance, sleep speed, free-flow time.
    pub settings: regolith_fsi::active::ActiveSettings,
    /// Margin (m) around every FSI body's bounding box; `None`: 2h plus `depth_factor` times
    /// the body's largest extent.
    pub margin: Option<f64>,
    /// The soil-disturbance depth as a multiple of a body's largest extent.
    pub depth_factor: f64,
}

/// Default `[sph.active] depth_factor`: the disturbed soil reaches one body size past it. At
/// 0.5 the single-wheel example's drawbar pull came out 5 % low against the full bed (the frozen
/// soil at the box front acts as a wall); at 1.0 it is within 0.3 % (BENCHMARKS.md).
pub const DEFAULT_ACTIVE_DEPTH_FACTOR: f64 = 1.0;
/// Default `[sph.active] sleep_speed` (m/s).
pub const DEFAULT_SLEEP_SPEED: f64 = 0.01;

impl ActiveSpec {
    /// The margin around a body whose markers span `extent` (m, largest side), unless the
    /// body sets its own.
    pub fn margin_for(&self, own: Option<f64>, extent: f64, h: f64) -> f64 {
        own.or(self.margin).unwrap_or(2.0 * h + self.depth_factor * extent)
    }
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The file it came from.
    pub path: PathBuf,
    /// Simulated time to run (s).
    pub end_time: f64,
    /// Backend.
    pub backend: Backend,
    /// Precision.
    pub precision: Precision,
    /// True when the precision was chosen (in the file or on the command line) rather than
    /// defaulted: `auto` and `wgpu` may then not switch it to f32.
    pub precision_set: bool,
    /// Solver settings.
    pub solver: SolverConfig,
    /// Materials, by index.
    pub materials: Vec<SceneMaterial>,
    /// Fixed walls on the bottom and four sides (open top); with `container_walls` false only
    /// the region the soil may occupy.
    pub container: Option<Aabb>,
    /// Whether the container has walls (`[container] walls`, default true). Without them soil
    /// that leaves the container's domain (a few spacings beyond it) escapes: a sink. Bodies
    /// then carry the soil.
    pub container_walls: bool,
    /// How soil slides along the container's floor and walls (`[container] soil_contact`; rough
    /// by default).
    pub wall_contact: ContainerContact,
    /// Soil regions.
    pub soil: Vec<SoilSpec>,
    /// Rigid bodies.
    pub bodies: Vec<BodySpec>,
    /// Test rig, if any.
    pub rig: Option<RigSpec>,
    /// Soil–body exchange interval (s).
    pub exchange_interval: f64,
    /// Where the bodies' outermost BCE layer lies (`[sph] body_markers`).
    pub body_markers: BodyMarkers,
    /// A particle faster than this (m/s) stops the run as a runaway (`[simulation]
    /// runaway_speed`, default [`DEFAULT_RUNAWAY_SPEED`]).
    pub runaway_speed: f64,
    /// What the run records.
    pub output: OutputSpec,
    /// URDF vehicles (their links are in `bodies`).
    pub vehicles: Vec<VehicleSpec>,
    /// The active region (`[sph.active]` with `enabled = true`); `None` integrates the whole
    /// domain.
    pub active: Option<ActiveSpec>,
    /// A moving patch (`[terrain] patch`); `None` simulates the whole bed.
    pub patch: Option<PatchSpec>,
}

/// `[terrain] patch = { length, trigger }`: the soil simulates `length` metres of the bed
/// along x, starting at the container's low-x end, and moves forward with the scene's FSI
/// bodies: whenever less than `trigger` metres of soil lie ahead of the foremost body, rows
/// are lifted at the back and laid ahead in their generated (geostatic) state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchSpec {
    /// Length of the simulated patch along x (m).
    pub length: f64,
    /// Soil kept ahead of the foremost FSI body (m).
    pub trigger: f64,
}

/// The `[output]` section: where the run writes and what `recording.mcap` holds.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSpec {
    /// Output directory (relative to the working directory); `--out` overrides it.
    pub dir: Option<PathBuf>,
    /// Recording interval in simulated seconds: a frame at t = 0, every, 2·every, … (each taken
    /// at the first exchange at or after its time).
    pub every: f64,
    /// Whether `recording.mcap` is written at all.
    pub mcap: bool,
    /// Whether frames carry the soil point cloud.
    pub particles: bool,
    /// Keep the particles whose id is a multiple of this (a fixed subset, so it does not flicker).
    pub decimate: usize,
    /// Only particles inside this box (min, max) are recorded.
    pub roi: Option<([f64; 3], [f64; 3])>,
}
