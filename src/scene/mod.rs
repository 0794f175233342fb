//! Scene files: what to simulate, as TOML. `load_scene` parses (with `--set` overrides),
//! validates every key against its allowed range and resolves the scene into solver settings,
//! materials and soil regions. Errors are one line naming the file, the key and what is allowed.
//!
//! ```toml
//! [simulation]
//! end_time = 1.0            # s
//! dt = "auto"               # or a fixed step in s
//! integrator = "rk2"        # or "euler"
//! gravity = [0.0, 0.0, -9.81]
//! backend = "cpu"           # "auto" | "cpu" | "wgpu"
//! precision = "f64"         # or "f32"
//!
//! [sph]
//! spacing = 0.02            # m
//! h_factor = 1.2
//! kernel = "wendland"       # or "cubic"
//! artificial_viscosity = 0.1
//! shifting = "xsph"         # "none" | "xsph" | "ppst" | "ppst+xsph"
//!
//! [[materials]]
//! name = "sand"
//! model = "drucker-prager"
//! density = 1600.0
//! youngs_modulus = 2e7
//! poisson_ratio = 0.3
//! friction_angle = 32.0
//!
//! [container]
//! min = [0.0, 0.0, 0.0]
//! max = [1.0, 0.5, 0.6]
//!
//! [terrain]
//! material = "sand"
//! depth = 0.3
//! ```

mod file;
mod overrides;
mod plan;
pub mod vehicle;

pub use vehicle::{Profile, VehicleSpec, WheelSpec};

use std::path::{Path, PathBuf};

use regolith_fsi::config::{FreeSurfaceStress, Integrator, KernelKind, Shifting, SolverConfig, TimeStep};
use regolith_fsi::rheology::{MaterialParams, Rheology};
use regolith_terrain::{Aabb, Heightmap, SoilRegion, Surface};

pub use overrides::parse_set;
pub use plan::describe;

use crate::input::{InputError, parse_toml, read_text};
use crate::material::{build_material, load_material_file};
use file::{
    AxisName, BackendName, BlockShapeName, BodyFile, FreeSurfaceStressName, IntegratorName, KernelName, MotionFile,
    OutputFile, PrecisionName, RigFile, RigKind, ScaleFile, SceneFile, ShapeFile, ShiftingName,
};
use regolith_rigid::{Axis, BodyDesc, Grousers, MassSpec, Motion, Pose, ShapeDesc};

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

/// Soil of one material in one region.
#[derive(Clone, Debug, PartialEq)]
pub struct SoilSpec {
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Where.
    pub region: SoilRegion,
    /// The key it came from (`terrain`, `soil_blocks[2]`), for messages.
    pub key: String,
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
    },
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
    /// Fixed walls on the bottom and four sides (open top).
    pub container: Option<Aabb>,
    /// Soil regions.
    pub soil: Vec<SoilSpec>,
    /// Rigid bodies.
    pub bodies: Vec<BodySpec>,
    /// Test rig, if any.
    pub rig: Option<RigSpec>,
    /// Soil–body exchange interval (s).
    pub exchange_interval: f64,
    /// What the run records.
    pub output: OutputSpec,
    /// URDF vehicles (their links are in `bodies`).
    pub vehicles: Vec<VehicleSpec>,
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

fn key_err(path: &Path, source: &str, key: impl Into<String>, message: impl Into<String>) -> InputError {
    InputError::key(path, key, message).located(source)
}

/// Reads, overrides (`--set key=value`, applied in order) and validates a scene file.
pub fn load_scene(path: &Path, sets: &[(String, toml::Value)]) -> Result<Scene, InputError> {
    let source = read_text(path)?;
    load_scene_source(path, &source, sets)
}

/// Like [`load_scene`] for scene text already in memory; `path` names it in messages and
/// anchors relative file references.
pub fn load_scene_source(path: &Path, source: &str, sets: &[(String, toml::Value)]) -> Result<Scene, InputError> {
    // Parse the file as written first, so that errors carry the file's own line numbers.
    let mut file: SceneFile = parse_toml(path, source)?;
    if !sets.is_empty() {
        let mut table: toml::Table = parse_toml(path, source)?;
        for (key, value) in sets {
            overrides::apply(&mut table, key, value.clone())
                .map_err(|m| InputError::flag("--set", format!("{key}: {m}")))?;
        }
        let text = toml::to_string(&table).map_err(|e| InputError::flag("--set", e.to_string()))?;
        file = parse_toml::<SceneFile>(path, &text).map_err(|mut e| {
            e.line = None;
            e.message = format!("{} (after --set overrides)", e.message);
            e
        })?;
    }
    resolve(path, source, file).map_err(|mut err| {
        // A value that came from --set is reported as such, not at the file's line.
        if let Some(k) = &err.key
            && sets.iter().any(|(s, _)| s == k)
        {
            err.line = None;
            err.message = format!("{} (value from --set)", err.message);
        }
        err
    })
}

fn resolve(path: &Path, source: &str, file: SceneFile) -> Result<Scene, InputError> {
    let e = |key: &str, msg: String| key_err(path, source, key, msg);
    let dir = path.parent().unwrap_or(Path::new("."));

    let sim = file
        .simulation
        .ok_or_else(|| e("simulation", "section [simulation] is required (at least end_time)".into()))?;
    let end_time =
        sim.end_time.ok_or_else(|| e("simulation.end_time", "is required: simulated time in s, > 0".into()))?;
    if !(end_time.is_finite() && end_time > 0.0) {
        return Err(e("simulation.end_time", format!("must be > 0 s (got {end_time})")));
    }
    // Defaults are the library's: what a scene does not set, SolverConfig::default() decides.
    let d = SolverConfig::default();
    let TimeStep::Adaptive { cfl: default_cfl, max: default_max_dt } = d.time_step else {
        unreachable!("the default time step is adaptive")
    };
    let cfl = sim.cfl.unwrap_or(default_cfl);
    if !(cfl.is_finite() && cfl > 0.0 && cfl <= 1.0) {
        return Err(e("simulation.cfl", format!("must be in (0, 1] (got {cfl})")));
    }
    let max_dt = sim.max_dt.unwrap_or(default_max_dt);
    if !(max_dt.is_finite() && max_dt > 0.0) {
        return Err(e("simulation.max_dt", format!("must be > 0 s (got {max_dt})")));
    }
    let time_step = match &sim.dt {
        None => TimeStep::Adaptive { cfl, max: max_dt },
        Some(toml::Value::String(s)) if s == "auto" => TimeStep::Adaptive { cfl, max: max_dt },
        Some(v) => {
            let dt = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
            match dt {
                Some(dt) if dt.is_finite() && dt > 0.0 && dt <= end_time => {
                    if sim.cfl.is_some() || sim.max_dt.is_some() {
                        return Err(e(
                            "simulation.cfl",
                            "and max_dt apply to dt = \"auto\" only; remove them or set dt = \"auto\"".into(),
                        ));
                    }
                    TimeStep::Fixed(dt)
                }
                _ => {
                    return Err(e(
                        "simulation.dt",
                        format!("must be \"auto\" or a step in s in (0, end_time = {end_time}] (got {v})"),
                    ));
                }
            }
        }
    };
    let integrator = match sim.integrator {
        None => d.integrator,
        Some(IntegratorName::Rk2) => Integrator::Rk2,
        Some(IntegratorName::Euler) => Integrator::Euler,
    };
    let gravity = sim.gravity.unwrap_or(d.gravity);
    if gravity.iter().any(|g| !g.is_finite()) {
        return Err(e("simulation.gravity", format!("must be three finite numbers in m/s² (got {gravity:?})")));
    }
    let backend = match sim.backend.unwrap_or(BackendName::Cpu) {
        BackendName::Auto => Backend::Auto,
        BackendName::Cpu => Backend::Cpu,
        BackendName::Wgpu => Backend::Wgpu,
    };
    let precision_set = sim.precision.is_some();
    if backend == Backend::Wgpu && matches!(sim.precision, Some(PrecisionName::F64)) {
        return Err(e("simulation.precision", "the wgpu backend runs in f32: use \"f32\" or backend \"cpu\"".into()));
    }
    let precision =
        match sim.precision.unwrap_or(if backend == Backend::Wgpu { PrecisionName::F32 } else { PrecisionName::F64 }) {
            PrecisionName::F32 => Precision::F32,
            PrecisionName::F64 => Precision::F64,
        };

    let sph = file.sph.ok_or_else(|| e("sph", "section [sph] is required (at least spacing)".into()))?;
    let spacing =
        sph.spacing.ok_or_else(|| e("sph.spacing", "is required: initial particle spacing in m, > 0".into()))?;
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(e("sph.spacing", format!("must be > 0 m (got {spacing})")));
    }
    let h_factor = sph.h_factor.unwrap_or(d.h_factor);
    if !(h_factor.is_finite() && (1.0..=2.0).contains(&h_factor)) {
        return Err(e("sph.h_factor", format!("must be in [1.0, 2.0] (h/d0; got {h_factor})")));
    }
    let alpha = sph.artificial_viscosity.unwrap_or(d.artificial_viscosity);
    if !(alpha.is_finite() && (0.0..=5.0).contains(&alpha)) {
        return Err(e("sph.artificial_viscosity", format!("must be in [0, 5] (got {alpha})")));
    }
    let shifting = match sph.shifting {
        None => d.shifting,
        Some(ShiftingName::None) => Shifting::None,
        Some(ShiftingName::Xsph) => Shifting::Xsph,
        Some(ShiftingName::Ppst) => Shifting::Ppst,
        Some(ShiftingName::PpstXsph) => Shifting::PpstXsph,
    };
    let xsph_epsilon = sph.xsph_epsilon.unwrap_or(d.xsph_epsilon);
    if !(xsph_epsilon.is_finite() && (0.0..=1.0).contains(&xsph_epsilon)) {
        return Err(e("sph.xsph_epsilon", format!("must be in [0, 1] (got {xsph_epsilon})")));
    }
    if sph.xsph_epsilon.is_some() && !shifting.xsph() {
        return Err(e("sph.xsph_epsilon", "applies only when shifting includes \"xsph\"".into()));
    }
    let shifting_coefficient = sph.shifting_coefficient.unwrap_or(d.shifting_coefficient);
    if !(shifting_coefficient.is_finite() && (0.0..=1.0).contains(&shifting_coefficient)) {
        return Err(e("sph.shifting_coefficient", format!("must be in [0, 1] (got {shifting_coefficient})")));
    }
    if sph.shifting_coefficient.is_some() && !shifting.ppst() {
        return Err(e("sph.shifting_coefficient", "applies only when shifting includes \"ppst\"".into()));
    }
    let free_surface = sph.free_surface.unwrap_or(d.free_surface_threshold.is_some());
    let threshold = sph
        .free_surface_threshold
        .or(d.free_surface_threshold)
        .unwrap_or(regolith_fsi::config::DEFAULT_FREE_SURFACE_THRESHOLD);
    if !(threshold.is_finite() && threshold > 0.0 && threshold < 1.0) {
        return Err(e(
            "sph.free_surface_threshold",
            format!(
                "must be in (0, 1): the smallest eigenvalue of Σ V (x_b − x_a) ⊗ ∇W is 1 inside the soil (got {threshold})"
            ),
        ));
    }
    if !free_surface && sph.free_surface_threshold.is_some() {
        return Err(e("sph.free_surface_threshold", "is set but free_surface = false".into()));
    }
    if !free_surface && sph.free_surface_stress.is_some() {
        return Err(e("sph.free_surface_stress", "is set but free_surface = false".into()));
    }
    let free_surface_stress = match sph.free_surface_stress {
        None => d.free_surface_stress,
        Some(FreeSurfaceStressName::Keep) => FreeSurfaceStress::Keep,
        Some(FreeSurfaceStressName::Zero) => FreeSurfaceStress::Zero,
    };
    let bce_layers = sph.bce_layers.unwrap_or(d.bce_layers as i64);
    if !(1..=8).contains(&bce_layers) {
        return Err(e("sph.bce_layers", format!("must be an integer in 1..=8 (got {bce_layers})")));
    }
    let kernel = match sph.kernel {
        None => d.kernel,
        Some(KernelName::Wendland) => KernelKind::Wendland,
        Some(KernelName::Cubic) => KernelKind::Cubic,
    };
    let solver = SolverConfig {
        spacing,
        h_factor,
        kernel,
        integrator,
        time_step,
        artificial_viscosity: alpha,
        shifting,
        xsph_epsilon,
        shifting_coefficient,
        free_surface_threshold: free_surface.then_some(threshold),
        free_surface_stress,
        gravity,
        bce_layers: bce_layers as usize,
    };

    // Materials: inline, or from a file named relative to the scene.
    let mut materials = Vec::new();
    for (i, m) in file.materials.iter().enumerate() {
        let prefix = format!("materials[{i}].");
        let name = m.name.clone().ok_or_else(|| {
            e(&format!("materials[{i}].name"), "is required: the name terrain and soil blocks refer to".into())
        })?;
        if name.trim().is_empty() {
            return Err(e(&format!("materials[{i}].name"), "must not be empty".into()));
        }
        if materials.iter().any(|x: &SceneMaterial| x.name == name) {
            return Err(e(
                &format!("materials[{i}].name"),
                format!("\"{name}\" is defined twice; material names must be unique"),
            ));
        }
        let params = if let Some(f) = &m.file {
            let only_name = MaterialParams { name: m.name.clone(), file: m.file.clone(), ..Default::default() };
            if *m != only_name {
                return Err(e(
                    &format!("materials[{i}].file"),
                    "a material read from a file takes only `name` and `file` here; put the other keys in the file"
                        .into(),
                ));
            }
            let p = dir.join(f);
            let mut params = load_material_file(&p)?;
            params.name = Some(name.clone());
            params
        } else {
            build_material::<f64>(m, path, &prefix, source)?;
            m.clone()
        };
        materials.push(SceneMaterial { name, params });
    }
    let find_material = |key: &str, name: &Option<String>| -> Result<usize, InputError> {
        let n = name.as_ref().ok_or_else(|| e(key, "is required: the name of a [[materials]] entry".into()))?;
        materials.iter().position(|m| &m.name == n).ok_or_else(|| {
            let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            e(
                key,
                format!(
                    "\"{n}\" is not a defined material (defined: {})",
                    if known.is_empty() { "none".into() } else { known.join(", ") }
                ),
            )
        })
    };

    let container = match &file.container {
        None => None,
        Some(c) => {
            let min = c.min.ok_or_else(|| e("container.min", "is required: lower corner [x, y, z] in m".into()))?;
            let max = c.max.ok_or_else(|| e("container.max", "is required: upper corner [x, y, z] in m".into()))?;
            if min.iter().chain(&max).any(|v| !v.is_finite()) {
                return Err(e("container.max", "corners must be finite".into()));
            }
            for k in 0..3 {
                if max[k] - min[k] < 4.0 * spacing {
                    return Err(e(
                        "container.max",
                        format!(
                            "must exceed container.min by at least 4 × sph.spacing = {} m along each axis (axis {} spans {} m)",
                            4.0 * spacing,
                            ["x", "y", "z"][k],
                            max[k] - min[k]
                        ),
                    ));
                }
            }
            Some(Aabb { min, max })
        }
    };

    let mut soil = Vec::new();
    if let Some(t) = &file.terrain {
        let material = find_material("terrain.material", &t.material)?;
        let c =
            container.ok_or_else(|| e("terrain", "needs a [container]: the bed fills the container floor".into()))?;
        let height = c.size()[2];
        let surface = match (t.depth, &t.heightmap) {
            (Some(_), Some(_)) => {
                return Err(e("terrain.depth", "and terrain.heightmap are both given: give one".into()));
            }
            (None, None) => {
                return Err(e("terrain.depth", "is required (or terrain.heightmap): bed depth in m".into()));
            }
            (Some(d), None) => {
                if t.heightmap_range.is_some() {
                    return Err(e("terrain.heightmap_range", "applies only with terrain.heightmap".into()));
                }
                if !(d.is_finite() && d >= 2.0 * spacing && d <= height) {
                    return Err(e(
                        "terrain.depth",
                        format!(
                            "must be in [2 × sph.spacing = {}, container height = {height}] m (got {d})",
                            2.0 * spacing
                        ),
                    ));
                }
                Surface::Flat(d)
            }
            (None, Some(hm)) => {
                let range = t.heightmap_range.map(|r| (r[0], r[1]));
                let map = Heightmap::load(&dir.join(hm), range)
                    .map_err(|err| InputError::key(path, "terrain.heightmap", err.to_string()).located(source))?;
                if map.max_height() > height {
                    return Err(e(
                        "terrain.heightmap",
                        format!("heights reach {} m, above the container height {height} m", map.max_height()),
                    ));
                }
                Surface::Heightmap(map)
            }
        };
        soil.push(SoilSpec { material, region: SoilRegion::Bed { container: c, surface }, key: "terrain".into() });
    }
    for (i, b) in file.soil_blocks.iter().enumerate() {
        let k = |s: &str| format!("soil_blocks[{i}].{s}");
        let material = find_material(&k("material"), &b.material)?;
        let shape = b.shape.ok_or_else(|| e(&k("shape"), "is required: \"box\" or \"cylinder\"".into()))?;
        let region = match shape {
            BlockShapeName::Box => {
                for (name, present) in [
                    ("base_center", b.base_center.is_some()),
                    ("radius", b.radius.is_some()),
                    ("height", b.height.is_some()),
                ] {
                    if present {
                        return Err(e(
                            &k(name),
                            "applies to shape = \"cylinder\" only; a box takes min and max".into(),
                        ));
                    }
                }
                let min =
                    b.min.ok_or_else(|| e(&k("min"), "is required for a box: lower corner [x, y, z] in m".into()))?;
                let max =
                    b.max.ok_or_else(|| e(&k("max"), "is required for a box: upper corner [x, y, z] in m".into()))?;
                if (0..3)
                    .any(|a| !min[a].is_finite() || !max[a].is_finite() || max[a] - min[a] < spacing * (1.0 - 1e-9))
                {
                    return Err(e(
                        &k("max"),
                        format!("must exceed min by at least sph.spacing = {spacing} m along each axis"),
                    ));
                }
                SoilRegion::Block(Aabb { min, max })
            }
            BlockShapeName::Cylinder => {
                for (name, present) in [("min", b.min.is_some()), ("max", b.max.is_some())] {
                    if present {
                        return Err(e(
                            &k(name),
                            "applies to shape = \"box\" only; a cylinder takes base_center, radius and height".into(),
                        ));
                    }
                }
                let base_center = b.base_center.ok_or_else(|| {
                    e(&k("base_center"), "is required for a cylinder: [x, y, z] of the bottom face centre in m".into())
                })?;
                let radius = b.radius.ok_or_else(|| e(&k("radius"), "is required for a cylinder (m)".into()))?;
                let height = b.height.ok_or_else(|| e(&k("height"), "is required for a cylinder (m)".into()))?;
                if !(radius.is_finite() && radius >= spacing * (1.0 - 1e-9)) {
                    return Err(e(&k("radius"), format!("must be ≥ sph.spacing = {spacing} m (got {radius})")));
                }
                if !(height.is_finite() && height >= spacing * (1.0 - 1e-9)) {
                    return Err(e(&k("height"), format!("must be ≥ sph.spacing = {spacing} m (got {height})")));
                }
                SoilRegion::Cylinder { base_center, radius, height }
            }
        };
        if let Some(c) = container {
            let (lo, hi) = region_bounds(&region);
            let eps = 1e-9 * spacing;
            if (0..3).any(|a| lo[a] < c.min[a] - eps || hi[a] > c.max[a] + eps) {
                return Err(e(
                    &k("shape"),
                    format!("the block [{lo:?} .. {hi:?}] must lie inside the container [{:?} .. {:?}]", c.min, c.max),
                ));
            }
        } else {
            return Err(e(&k("shape"), "soil blocks need a [container] to stand in (walls and floor)".into()));
        }
        soil.push(SoilSpec { material, region, key: format!("soil_blocks[{i}]") });
    }
    if soil.is_empty() {
        return Err(InputError::file(path, "the scene has no soil: add [terrain] or [[soil_blocks]]"));
    }
    for (i, m) in materials.iter().enumerate() {
        if !soil.iter().any(|s| s.material == i) {
            return Err(e(
                &format!("materials[{i}].name"),
                format!("material \"{}\" is defined but not used by any soil", m.name),
            ));
        }
    }
    let exchange_interval = sim.exchange_interval.unwrap_or(1e-3);
    if !(exchange_interval.is_finite() && exchange_interval > 0.0 && exchange_interval <= end_time) {
        return Err(e(
            "simulation.exchange_interval",
            format!("must be in (0, end_time = {end_time}] s (got {exchange_interval})"),
        ));
    }
    let mut bodies = Vec::new();
    for (i, b) in file.bodies.iter().enumerate() {
        let spec = resolve_body(path, source, dir, i, b, bce_layers as usize, &bodies)?;
        bodies.push(spec);
    }
    let mut vehicles = Vec::new();
    for (i, v) in file.vehicles.iter().enumerate() {
        if vehicles.iter().any(|x: &VehicleSpec| Some(&x.name) == v.name.as_ref()) {
            return Err(e(&format!("vehicles[{i}].name"), "is used twice; vehicle names must be unique".into()));
        }
        vehicles.push(vehicle::resolve_vehicle(path, i, v, bce_layers as usize, &mut bodies, &e)?);
    }
    let rig = match &file.rig {
        None => None,
        Some(r) => Some(resolve_rig(path, source, r, &bodies, &file.bodies)?),
    };
    let output = resolve_output(file.output.unwrap_or_default(), end_time, exchange_interval, &e)?;
    Ok(Scene {
        path: path.to_path_buf(),
        end_time,
        backend,
        precision,
        precision_set,
        solver,
        materials,
        container,
        soil,
        bodies,
        rig,
        exchange_interval,
        output,
        vehicles,
    })
}

fn resolve_output(
    o: OutputFile,
    end_time: f64,
    exchange: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<OutputSpec, InputError> {
    let dir = match o.dir {
        Some(d) if d.trim().is_empty() => return Err(e("output.dir", "must not be empty".into())),
        d => d.map(PathBuf::from),
    };
    // 100 frames by default, never closer than one exchange interval.
    let every = o.every.unwrap_or((end_time / 100.0).max(exchange));
    if !(every.is_finite() && every > 0.0) {
        return Err(e("output.every", format!("must be > 0 s (got {every})")));
    }
    if every < exchange * (1.0 - 1e-9) {
        return Err(e(
            "output.every",
            format!(
                "must be at least simulation.exchange_interval = {exchange} s: frames are taken between exchanges (got {every})"
            ),
        ));
    }
    let decimate = o.decimate.unwrap_or(1);
    if decimate < 1 {
        return Err(e(
            "output.decimate",
            format!("must be an integer ≥ 1: record every n-th particle (got {decimate})"),
        ));
    }
    let roi = match (o.roi_min, o.roi_max) {
        (None, None) => None,
        (Some(lo), Some(hi)) => {
            if lo.iter().chain(&hi).any(|v| !v.is_finite()) || (0..3).any(|k| lo[k] >= hi[k]) {
                return Err(e(
                    "output.roi_max",
                    format!("must be finite and above roi_min on every axis (got {lo:?} .. {hi:?})"),
                ));
            }
            Some((lo, hi))
        }
        (Some(_), None) => {
            return Err(e("output.roi_max", "is required with roi_min (the region of interest is a box)".into()));
        }
        (None, Some(_)) => {
            return Err(e("output.roi_min", "is required with roi_max (the region of interest is a box)".into()));
        }
    };
    let mcap = o.mcap.unwrap_or(true);
    if !mcap && (o.particles.is_some() || o.decimate.is_some() || roi.is_some()) {
        return Err(e(
            "output.mcap",
            "is false but particles, decimate or roi are set; they configure the recording".into(),
        ));
    }
    Ok(OutputSpec { dir, every, mcap, particles: o.particles.unwrap_or(true), decimate: decimate as usize, roi })
}

fn resolve_body(
    path: &Path,
    source: &str,
    dir: &Path,
    i: usize,
    b: &BodyFile,
    default_layers: usize,
    earlier: &[BodySpec],
) -> Result<BodySpec, InputError> {
    let key = format!("bodies[{i}]");
    let e = |k: &str, msg: String| key_err(path, source, format!("{key}.{k}"), msg);
    let name = b.name.clone().ok_or_else(|| e("name", "is required: the body's name in outputs".into()))?;
    if name.trim().is_empty() || name.contains(',') || name.contains('/') {
        return Err(e("name", format!("\"{name}\" is not allowed: a non-empty name without ',' or '/'")));
    }
    if earlier.iter().any(|x| x.desc.name == name) {
        return Err(e("name", format!("\"{name}\" is used twice; body names must be unique")));
    }
    let pos = |k: &str, v: f64| -> Result<f64, InputError> {
        if v.is_finite() && v > 0.0 { Ok(v) } else { Err(e(&format!("shape.{k}"), format!("must be > 0 m (got {v})"))) }
    };
    let shape_file = b.shape.clone().ok_or_else(|| {
        e(
            "shape",
            "is required: { type = \"box\" | \"sphere\" | \"cylinder\" | \"cone\" | \"mesh\" | \"wheel\", ... }".into(),
        )
    })?;
    let fsi = b.fsi.unwrap_or(true);
    let shape = match shape_file {
        ShapeFile::Box { size } => {
            for s in size {
                pos("size", s)?;
            }
            ShapeDesc::Box { size }
        }
        ShapeFile::Sphere { radius } => ShapeDesc::Sphere { radius: pos("radius", radius)? },
        ShapeFile::Cylinder { radius, length, axis } => ShapeDesc::Cylinder {
            radius: pos("radius", radius)?,
            length: pos("length", length)?,
            axis: match axis.unwrap_or(AxisName::Z) {
                AxisName::X => Axis::X,
                AxisName::Y => Axis::Y,
                AxisName::Z => Axis::Z,
            },
        },
        ShapeFile::Cone { radius, height } => {
            ShapeDesc::Cone { radius: pos("radius", radius)?, height: pos("height", height)? }
        }
        ShapeFile::Mesh { file, scale } => {
            let scale = match scale {
                None => [1.0; 3],
                Some(ScaleFile::Uniform(s)) => [s; 3],
                Some(ScaleFile::PerAxis(s)) => s,
            };
            if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(e("shape.scale", format!("must be positive (got {scale:?})")));
            }
            let mesh =
                regolith_rigid::load_mesh(&dir.join(&file), scale).map_err(|m| e("shape.file", m.to_string()))?;
            if fsi {
                regolith_coupling::check_watertight(&mesh.vertices, &mesh.indices)
                    .map_err(|m| e("shape.file", format!("{}: {m}", dir.join(&file).display())))?;
            }
            ShapeDesc::Mesh { vertices: mesh.vertices, indices: mesh.indices }
        }
        ShapeFile::Wheel { radius, width, grousers, grouser_height, grouser_thickness } => {
            let radius = pos("radius", radius)?;
            let width = pos("width", width)?;
            let grousers = match grousers.unwrap_or(0) {
                0 => {
                    if grouser_height.is_some() || grouser_thickness.is_some() {
                        return Err(e(
                            "shape.grousers",
                            "is 0 but grouser_height or grouser_thickness is given".into(),
                        ));
                    }
                    None
                }
                n => Some(Grousers {
                    count: n,
                    height: pos(
                        "grouser_height",
                        grouser_height
                            .ok_or_else(|| e("shape.grouser_height", "is required when grousers > 0 (m)".into()))?,
                    )?,
                    thickness: pos(
                        "grouser_thickness",
                        grouser_thickness
                            .ok_or_else(|| e("shape.grouser_thickness", "is required when grousers > 0 (m)".into()))?,
                    )?,
                }),
            };
            ShapeDesc::Wheel { radius, width, grousers }
        }
    };
    let mass = match (b.mass, b.density) {
        (Some(_), Some(_)) => return Err(e("mass", "and density are both given: give one".into())),
        (None, None) => return Err(e("mass", "is required (kg), or give density (kg/m³)".into())),
        (Some(m), None) if m.is_finite() && m > 0.0 => MassSpec::Mass(m),
        (None, Some(d)) if d.is_finite() && d > 0.0 => MassSpec::Density(d),
        (Some(m), None) => return Err(e("mass", format!("must be > 0 kg (got {m})"))),
        (None, Some(d)) => return Err(e("density", format!("must be > 0 kg/m³ (got {d})"))),
    };
    let position =
        b.position.ok_or_else(|| e("position", "is required: [x, y, z] of the body's centre in m".into()))?;
    if position.iter().any(|x| !x.is_finite()) {
        return Err(e("position", "must be finite".into()));
    }
    let orientation = b.orientation.unwrap_or([0.0; 3]);
    if orientation.iter().any(|x| !x.is_finite()) {
        return Err(e("orientation", "must be finite roll, pitch, yaw in degrees".into()));
    }
    let motion = match b.motion.clone().unwrap_or(MotionFile::Free) {
        MotionFile::Free => Motion::Free,
        MotionFile::Fixed => Motion::Fixed,
        MotionFile::Prescribed { linear_velocity, angular_velocity } => {
            let l = linear_velocity.unwrap_or([0.0; 3]);
            let a = angular_velocity.unwrap_or([0.0; 3]);
            if l.iter().chain(&a).any(|x| !x.is_finite()) {
                return Err(e("motion", "velocities must be finite".into()));
            }
            Motion::Prescribed { linvel: l, angvel: a.map(f64::to_radians) }
        }
    };
    let layers = b.bce_layers.unwrap_or(default_layers as i64);
    if !(1..=8).contains(&layers) {
        return Err(e("bce_layers", format!("must be an integer in 1..=8 (got {layers})")));
    }
    if !fsi && b.bce_layers.is_some() {
        return Err(e("bce_layers", "is set but fsi = false (the body has no markers)".into()));
    }
    let friction = b.friction.unwrap_or(0.5);
    if !(friction.is_finite() && friction >= 0.0) {
        return Err(e("friction", format!("must be ≥ 0 (got {friction})")));
    }
    Ok(BodySpec {
        desc: BodyDesc {
            name,
            shape,
            mass,
            pose: Pose::from_rpy_deg(position, orientation),
            motion,
            friction,
            collides: true,
        },
        fsi,
        bce_layers: layers as usize,
        key,
        visual: None,
    })
}

fn resolve_rig(
    path: &Path,
    source: &str,
    r: &RigFile,
    bodies: &[BodySpec],
    files: &[BodyFile],
) -> Result<RigSpec, InputError> {
    let e = |k: &str, msg: String| key_err(path, source, format!("rig.{k}"), msg);
    let kind = r.kind.ok_or_else(|| e("type", "is required: \"plate\", \"cone\" or \"wheel\"".into()))?;
    let kind_name = match kind {
        RigKind::Plate => "plate",
        RigKind::Cone => "cone",
        RigKind::Wheel => "wheel",
    };
    let name = r
        .body
        .as_ref()
        .ok_or_else(|| e("body", "is required: the name of the [[bodies]] entry the rig drives".into()))?;
    let body = bodies
        .iter()
        .position(|b| &b.desc.name == name)
        .ok_or_else(|| e("body", format!("\"{name}\" is not a body of the scene")))?;
    if !bodies[body].fsi {
        return Err(e("body", format!("\"{name}\" has fsi = false: a rig measures the soil's force on it")));
    }
    if files[body].motion.is_some() {
        return Err(key_err(
            path,
            source,
            format!("{}.motion", bodies[body].key),
            format!("is set, but the {kind_name} rig drives body \"{name}\"; remove it"),
        ));
    }
    let forbid = |k: &str, present: bool| -> Result<(), InputError> {
        if present { Err(e(k, format!("does not apply to a {kind_name} rig"))) } else { Ok(()) }
    };
    let positive = |k: &str, v: Option<f64>, unit: &str| -> Result<f64, InputError> {
        let v = v.ok_or_else(|| e(k, format!("is required for a {kind_name} rig ({unit})")))?;
        if v.is_finite() && v > 0.0 { Ok(v) } else { Err(e(k, format!("must be > 0 {unit} (got {v})"))) }
    };
    let shape = &bodies[body].desc.shape;
    Ok(match kind {
        RigKind::Plate => {
            forbid("angular_velocity", r.angular_velocity.is_some())?;
            forbid("slips", r.slips.is_some())?;
            forbid("tow_force", r.tow_force.is_some())?;
            match shape {
                ShapeDesc::Cylinder { axis: Axis::Z, .. } | ShapeDesc::Box { .. } => {}
                _ => {
                    return Err(e(
                        "body",
                        format!(
                            "\"{name}\" must be a plate: a cylinder with axis = \"z\" (circular) or a box (rectangular)"
                        ),
                    ));
                }
            }
            let control = match (r.speed, r.load) {
                (Some(_), Some(_)) => {
                    return Err(e("speed", "and load are both given: a plate is speed- or load-controlled".into()));
                }
                (None, None) => return Err(e("speed", "is required (m/s, downward), or give load (N)".into())),
                (Some(_), None) => PlateControl::Speed(positive("speed", r.speed, "m/s")?),
                (None, Some(_)) => PlateControl::Load(positive("load", r.load, "N")?),
            };
            let depth = positive("depth", r.depth, "m")?;
            let sizes = r.sizes.clone().unwrap_or_default();
            if let Some(s) = sizes.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
                return Err(e("sizes", format!("must all be > 0 m (got {s})")));
            }
            RigSpec::Plate { body, control, depth, sizes }
        }
        RigKind::Cone => {
            for (k, p) in [
                ("load", r.load.is_some()),
                ("sizes", r.sizes.is_some()),
                ("angular_velocity", r.angular_velocity.is_some()),
                ("slips", r.slips.is_some()),
                ("tow_force", r.tow_force.is_some()),
            ] {
                forbid(k, p)?;
            }
            if !matches!(shape, ShapeDesc::Cone { .. }) {
                return Err(e("body", format!("\"{name}\" must have shape type = \"cone\"")));
            }
            RigSpec::Cone { body, speed: positive("speed", r.speed, "m/s")?, depth: positive("depth", r.depth, "m")? }
        }
        RigKind::Wheel => {
            for (k, p) in [("speed", r.speed.is_some()), ("depth", r.depth.is_some()), ("sizes", r.sizes.is_some())] {
                forbid(k, p)?;
            }
            match shape {
                ShapeDesc::Wheel { .. } | ShapeDesc::Cylinder { axis: Axis::Y, .. } => {}
                _ => {
                    return Err(e(
                        "body",
                        format!("\"{name}\" must be a wheel: shape type = \"wheel\" (or a cylinder with axis = \"y\")"),
                    ));
                }
            }
            let drive = match (&r.slips, r.tow_force) {
                (Some(_), Some(_)) => {
                    return Err(e("slips", "and tow_force are both given: prescribe slips or tow the carriage".into()));
                }
                (None, None) => {
                    return Err(e(
                        "slips",
                        "is required (a list of slip ratios in [0, 1]), or give tow_force (N)".into(),
                    ));
                }
                (Some(s), None) => {
                    if s.is_empty() {
                        return Err(e("slips", "must list at least one slip ratio".into()));
                    }
                    if let Some(x) = s.iter().find(|x| !(x.is_finite() && (0.0..=1.0).contains(*x))) {
                        return Err(e("slips", format!("must be in [0, 1] (got {x})")));
                    }
                    WheelDrive::Slips(s.clone())
                }
                (None, Some(t)) => {
                    if !(t.is_finite() && t >= 0.0) {
                        return Err(e("tow_force", format!("must be ≥ 0 N (got {t})")));
                    }
                    WheelDrive::Tow(t)
                }
            };
            RigSpec::Wheel {
                body,
                load: positive("load", r.load, "N")?,
                angular_velocity: positive("angular_velocity", r.angular_velocity, "rad/s")?,
                drive,
            }
        }
    })
}

/// Bounding box of a soil region (m).
pub fn region_bounds(r: &SoilRegion) -> ([f64; 3], [f64; 3]) {
    match r {
        SoilRegion::Bed { container, surface } => {
            (container.min, [container.max[0], container.max[1], container.min[2] + surface.max_depth()])
        }
        SoilRegion::Block(b) => (b.min, b.max),
        SoilRegion::Cylinder { base_center: c, radius, height } => {
            ([c[0] - radius, c[1] - radius, c[2]], [c[0] + radius, c[1] + radius, c[2] + height])
        }
    }
}

/// The rheology of each material of a scene, in `f64` (for reporting).
pub fn rheologies(scene: &Scene) -> Vec<Rheology<f64>> {
    scene.materials.iter().filter_map(|m| m.params.build::<f64>().ok()).map(|m| m.rheology).collect()
}
