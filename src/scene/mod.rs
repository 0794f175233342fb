//! Scene files: what to simulate, as TOML. `load_scene` parses (with `--set` overrides),
//! validates every key against its allowed range and resolves the scene into solver settings,
//! materials and soil regions. Errors are one line naming the file, the key and what is allowed.
//!
//! ```toml
//! [simulation]
//! end_time = 1.0            # s
//! dt = "auto"               # or a fixed step in s, at most 0.5 h / c (refused above)
//! integrator = "rk2"        # the only one a scene takes ("euler" is refused: unstable)
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
//! # drag = "svf"            # wet scenes only: "svf" (smooth volume fractions) | "particle"
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

mod body;
mod contact;
mod file;
mod output;
pub mod overrides;
mod plan;
mod rig;
mod settings;
mod soil;
mod types;
pub mod vehicle;

use body::resolve_body;
use output::resolve_output;
use rig::resolve_rig;
use settings::{Settings, resolve_settings};
use soil::resolve_soil;
pub use types::{
    ActiveSpec, Backend, BodyMarkers, BodySpec, DEFAULT_ACTIVE_DEPTH_FACTOR, DEFAULT_RUNAWAY_SPEED,
    DEFAULT_SLEEP_SPEED, OutputSpec, PatchSpec, PlateControl, Precision, RigSpec, Scene, SceneMaterial, SoilSpec,
    WheelDrive,
};

pub use contact::ContainerContact;
pub use vehicle::{Profile, VehicleSpec, WheelSpec};

use std::path::{Path, PathBuf};

use regolith_fsi::config::{
    Drag, FreeSurfaceStress, Integrator, KernelKind, Shifting, SolverConfig, TimeStep, WallContact,
};
use regolith_fsi::rheology::MaterialParams;
use regolith_terrain::{Aabb, Heightmap, SoilRegion, Surface};

pub use overrides::parse_set;
pub use plan::describe;

use crate::input::{InputError, parse_toml, read_text};
use crate::material::{build_material, load_material_file};
use file::{
    AxisName, BackendName, BlockShapeName, BodyFile, DragName, FreeSurfaceStressName, IntegratorName, KernelName,
    MotionFile, OutputFile, PatchFile, PrecisionName, RigFile, RigKind, ScaleFile, SceneFile, ShapeFile, ShiftingName,
};
use regolith_rigid::{Axis, BodyDesc, Grousers, MassSpec, Motion, Pose, ShapeDesc};

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

    let Settings { end_time, backend, precision, precision_set, solver, exchange_interval, active, body_markers } =
        resolve_settings(file.simulation.as_ref(), file.sph.as_ref(), &e)?;
    let (spacing, bce_layers) = (solver.spacing, solver.bce_layers);
    let (materials, container, soil) = resolve_soil(path, source, dir, &file, spacing, &e)?;
    let wall_contact = match file.container.as_ref().and_then(|c| c.soil_contact.as_ref()) {
        None => ContainerContact::ROUGH,
        Some(v) => contact::parse_container_contact(v).map_err(|m| e("container.soil_contact", m))?,
    };
    let container_walls = file.container.as_ref().and_then(|c| c.walls).unwrap_or(true);
    if !container_walls && !wall_contact.is_rough() {
        return Err(e(
            "container.soil_contact",
            "is set but container.walls = false (there is no wall to slide on); remove one of them".into(),
        ));
    }
    let allow_unstable = file.simulation.as_ref().and_then(|s| s.allow_unstable_dt).unwrap_or(false);
    settings::check_fixed_step(&solver, &materials, allow_unstable, &e)?;
    let runaway_speed = file.simulation.as_ref().and_then(|s| s.runaway_speed).unwrap_or(DEFAULT_RUNAWAY_SPEED);
    if !(runaway_speed.is_finite() && runaway_speed > 0.0) {
        return Err(e("simulation.runaway_speed", format!("must be > 0 m/s (got {runaway_speed})")));
    }
    let mut bodies = Vec::new();
    for (i, b) in file.bodies.iter().enumerate() {
        let spec = resolve_body(path, source, dir, i, b, bce_layers, &bodies)?;
        bodies.push(spec);
    }
    let mut vehicles = Vec::new();
    for (i, v) in file.vehicles.iter().enumerate() {
        if vehicles.iter().any(|x: &VehicleSpec| Some(&x.name) == v.name.as_ref()) {
            return Err(e(&format!("vehicles[{i}].name"), "is used twice; vehicle names must be unique".into()));
        }
        vehicles.push(vehicle::resolve_vehicle(path, i, v, bce_layers, &mut bodies, &e)?);
    }
    check_lattice_size(&container, &bodies, spacing, &e)?;
    let wet = materials.iter().any(|m| m.params.model == Some(regolith_fsi::rheology::ModelKind::Water));
    if let Some(i) = bodies.iter().position(|b| b.permeable)
        && !wet
    {
        return Err(e(&format!("bodies[{i}].permeable"), "needs water in the scene ([[water_blocks]])".into()));
    }
    if !wet && file.sph.as_ref().is_some_and(|s| s.drag.is_some()) {
        return Err(e(
            "sph.drag",
            "applies to scenes with water ([[water_blocks]]); remove it from a dry scene".into(),
        ));
    }
    if wet && active.is_some() {
        return Err(e("sph.active", "is not available with water yet: remove [sph.active] from a wet scene".into()));
    }
    let patch = soil::resolve_patch(
        file.terrain.as_ref().and_then(|t| t.patch.as_ref()),
        &container,
        (&solver, wet, container_walls),
        &bodies,
        &e,
    )?;
    let rig = match &file.rig {
        None => None,
        Some(r) => Some(resolve_rig(path, source, r, &bodies, &file.bodies, solver.gravity)?),
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
        container_walls,
        wall_contact,
        soil,
        bodies,
        rig,
        exchange_interval,
        body_markers,
        runaway_speed,
        output,
        vehicles,
        active,
        patch,
    })
}

/// Most lattice points a container (or an FSI body's bounding cube) may span at its spacing:
/// particle and marker indices are 32-bit, and a billion particles need hundreds of GB.
pub const MAX_LATTICE_POINTS: f64 = 1e9;

/// Refuses a spacing so fine that the container or a body would span more than
/// [`MAX_LATTICE_POINTS`] lattice points (it would exhaust memory before the first step).
fn check_lattice_size(
    container: &Option<Aabb>,
    bodies: &[BodySpec],
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(), InputError> {
    let d3 = spacing.powi(3);
    let too_many = |what: String, volume: f64| {
        let n = volume / d3;
        if n > MAX_LATTICE_POINTS || !n.is_finite() {
            return Err(e(
                "sph.spacing",
                format!(
                    "{spacing:e} m is too fine: {what} would span {n:.3e} lattice points (at most {MAX_LATTICE_POINTS:e})"
                ),
            ));
        }
        Ok(())
    };
    if let Some(c) = container {
        too_many("the container".into(), (0..3).map(|a| c.max[a] - c.min[a]).product())?;
    }
    for b in bodies.iter().filter(|b| b.fsi) {
        too_many(format!("body \"{}\"", b.desc.name), (2.0 * b.desc.shape.bounding_radius()).powi(3))?;
    }
    Ok(())
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
