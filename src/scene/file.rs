//! The scene file as written: serde structures with `deny_unknown_fields`. Everything is
//! optional at parse time so that a missing key gets a message saying what is allowed.

use regolith_fsi::rheology::MaterialParams;
use serde::Deserialize;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    pub simulation: Option<SimulationFile>,
    pub sph: Option<SphFile>,
    #[serde(default)]
    pub materials: Vec<MaterialParams>,
    pub container: Option<ContainerFile>,
    pub terrain: Option<TerrainFile>,
    #[serde(default)]
    pub soil_blocks: Vec<SoilBlockFile>,
    #[serde(default)]
    pub water_blocks: Vec<SoilBlockFile>,
    #[serde(default)]
    pub bodies: Vec<BodyFile>,
    pub rig: Option<RigFile>,
    pub output: Option<OutputFile>,
    #[serde(default)]
    pub vehicles: Vec<super::vehicle::VehicleFile>,
    /// What a correct run shows (`[[expect]]`), read by `regolith study stability`; a run
    /// ignores it.
    #[serde(default, rename = "expect")]
    pub _expect: Option<serde::de::IgnoredAny>,
    /// Problem sizes of a study case (`[study.ci]`), read by `regolith study`; a run ignores it.
    #[serde(rename = "study")]
    pub _study: Option<serde::de::IgnoredAny>,
    /// What an accuracy case measures and its ladders (`[accuracy]`), read by
    /// `regolith study accuracy`; a run ignores it.
    #[serde(rename = "accuracy")]
    pub _accuracy: Option<serde::de::IgnoredAny>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct OutputFile {
    pub dir: Option<String>,
    pub every: Option<f64>,
    pub mcap: Option<bool>,
    pub particles: Option<bool>,
    pub decimate: Option<i64>,
    pub roi_min: Option<[f64; 3]>,
    pub roi_max: Option<[f64; 3]>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SimulationFile {
    pub end_time: Option<f64>,
    pub dt: Option<toml::Value>,
    pub cfl: Option<f64>,
    pub max_dt: Option<f64>,
    pub integrator: Option<IntegratorName>,
    pub gravity: Option<[f64; 3]>,
    pub backend: Option<BackendName>,
    pub precision: Option<PrecisionName>,
    pub exchange_interval: Option<f64>,
    pub allow_unstable_dt: Option<bool>,
    pub runaway_speed: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum IntegratorName {
    Rk2,
    Euler,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum BackendName {
    Auto,
    Cpu,
    Wgpu,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum PrecisionName {
    F32,
    F64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SphFile {
    pub spacing: Option<f64>,
    pub h_factor: Option<f64>,
    pub kernel: Option<KernelName>,
    pub artificial_viscosity: Option<f64>,
    pub shifting: Option<ShiftingName>,
    pub xsph_epsilon: Option<f64>,
    pub shifting_coefficient: Option<f64>,
    pub free_surface: Option<bool>,
    pub free_surface_threshold: Option<f64>,
    pub free_surface_stress: Option<FreeSurfaceStressName>,
    pub bce_layers: Option<i64>,
    pub neighbor_skin: Option<f64>,
    pub drag: Option<DragName>,
    pub body_markers: Option<BodyMarkersName>,
    pub active: Option<ActiveFile>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ActiveFile {
    pub enabled: Option<bool>,
    pub margin: Option<f64>,
    pub depth_factor: Option<f64>,
    pub travel: Option<f64>,
    pub sleep_speed: Option<f64>,
    pub free_flow_time: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum FreeSurfaceStressName {
    Keep,
    Zero,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum BodyMarkersName {
    Surface,
    Inset,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum DragName {
    Svf,
    Particle,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum KernelName {
    Wendland,
    Cubic,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub(crate) enum ShiftingName {
    #[serde(rename = "none")]
    None,
    #[serde(rename = "xsph")]
    Xsph,
    #[serde(rename = "ppst")]
    Ppst,
    #[serde(rename = "ppst+xsph")]
    PpstXsph,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ContainerFile {
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub soil_contact: Option<toml::Value>,
    pub walls: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TerrainFile {
    pub material: Option<String>,
    pub depth: Option<f64>,
    pub heightmap: Option<String>,
    pub heightmap_range: Option<[f64; 2]>,
    pub patch: Option<PatchFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PatchFile {
    pub length: Option<f64>,
    pub trigger: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SoilBlockFile {
    pub material: Option<String>,
    pub shape: Option<BlockShapeName>,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub base_center: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub height: Option<f64>,
    pub velocity: Option<[f64; 3]>,
    pub initial_pressure: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum BlockShapeName {
    Box,
    Cylinder,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BodyFile {
    pub name: Option<String>,
    pub shape: Option<ShapeFile>,
    pub mass: Option<f64>,
    pub density: Option<f64>,
    pub position: Option<[f64; 3]>,
    pub orientation: Option<[f64; 3]>,
    pub motion: Option<MotionFile>,
    pub fsi: Option<bool>,
    pub bce_layers: Option<i64>,
    pub friction: Option<f64>,
    pub active_margin: Option<f64>,
    pub soil_contact: Option<toml::Value>,
    pub permeable: Option<bool>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum AxisName {
    X,
    Y,
    Z,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub(crate) enum ScaleFile {
    Uniform(f64),
    PerAxis([f64; 3]),
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub(crate) enum ShapeFile {
    Box {
        size: [f64; 3],
    },
    Sphere {
        radius: f64,
    },
    Cylinder {
        radius: f64,
        length: f64,
        axis: Option<AxisName>,
    },
    Cone {
        radius: f64,
        height: f64,
    },
    Mesh {
        file: String,
        scale: Option<ScaleFile>,
    },
    Wheel {
        radius: f64,
        width: f64,
        grousers: Option<u32>,
        grouser_height: Option<f64>,
        grouser_thickness: Option<f64>,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub(crate) enum MotionFile {
    Free { velocity: Option<[f64; 3]> },
    Fixed,
    Prescribed { linear_velocity: Option<[f64; 3]>, angular_velocity: Option<[f64; 3]> },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum RigKind {
    Plate,
    Cone,
    Wheel,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RigFile {
    #[serde(rename = "type")]
    pub kind: Option<RigKind>,
    pub body: Option<String>,
    pub speed: Option<f64>,
    pub depth: Option<f64>,
    pub load: Option<f64>,
    pub sizes: Option<Vec<f64>>,
    pub angular_velocity: Option<f64>,
    pub slips: Option<Vec<f64>>,
    pub tow_force: Option<f64>,
    pub slopes: Option<Vec<f64>>,
    pub slip_radius: Option<f64>,
}
