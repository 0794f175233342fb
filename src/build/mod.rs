//! Scene → the objects that simulate it: materials in the run's precision, the terrain
//! (soil particles, wall markers, domain), the rapier world with the container, bodies and
//! vehicle joints, each FSI body's BCE markers, and the soil solver on the chosen backend.
//!
//! This is the second stage of a run (after [`crate::scene`] has validated the files); it knows
//! nothing of stepping or outputs. [`assemble`] gives the parts a simulation is made of.

pub mod backend;
mod bodies;
mod patch;
mod surface;
mod vehicles;

pub use bodies::carve_bodies;
pub use patch::{Patch, Relay};
pub use surface::SurfaceGrid;
pub use vehicles::{build_vehicle_joints, place_vehicles};

use regolith_coupling::{CouplingError, FsiBodyId, FsiSystem, SoilInit, grow_domain, shape_markers};
use regolith_fsi::active::{ActiveDomain, BodyBox};
use regolith_fsi::rheology::{Material, ParamError};
use regolith_fsi::{Real, SolverError, SphSolver};
use regolith_rigid::{BodyId, JointId, Motion, RigidError, RigidWorld};
use regolith_terrain::{Aabb, RegionSpec, TerrainBuild, TerrainError, build_terrain};

use crate::input::InputError;
use crate::scene::{Backend, Scene};

/// Why a scene could not be built. Displays as one line; the wrapped error, if any, is the
/// [`std::error::Error::source`].
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene file itself is wrong (when a scene is loaded and built in one call).
    #[error(transparent)]
    Input(#[from] InputError),
    /// A material's parameters are inconsistent.
    #[error(transparent)]
    Material(#[from] ParamError),
    /// The terrain generator refused the regions.
    #[error(transparent)]
    Terrain(#[from] TerrainError),
    /// A body, joint or wall was refused by the rigid world (`key`: the scene key it came from).
    #[error("{key}")]
    Rigid {
        /// Scene key (`bodies[1]`, `vehicles[0]`, `rig`).
        key: String,
        /// What rapier's side said.
        #[source]
        source: RigidError,
    },
    /// A body's BCE markers could not be generated.
    #[error("{key}")]
    Markers {
        /// Scene key.
        key: String,
        /// What the marker generator said.
        #[source]
        source: CouplingError,
    },
    /// The coupled system refused its inputs.
    #[error(transparent)]
    Coupling(#[from] CouplingError),
    /// The soil solver refused its inputs.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// Terrain scenes need a container.
    #[error("a scene needs a [container]")]
    NoContainer,
    /// Every soil particle started inside a body.
    #[error("the bodies fill all the soil")]
    NoSoilLeft,
    /// Two soil regions hold the same lattice point.
    #[error(
        "{second} overlaps {first} (both hold the lattice point at [{:.4}, {:.4}, {:.4}] m); soil regions must not overlap: move the block or lower the terrain",
        at[0],
        at[1],
        at[2]
    )]
    SoilOverlap {
        /// The earlier region's key (`terrain`, `soil_blocks[0]`).
        first: String,
        /// The later one's.
        second: String,
        /// A point both hold (m).
        at: [f64; 3],
    },
    /// A vehicle to be lowered onto the soil is not over it.
    #[error("{key}: vehicle \"{name}\" is not over the soil: place it over the terrain or give position = [x, y, z]")]
    VehicleOffSoil {
        /// Scene key.
        key: String,
        /// Vehicle name.
        name: String,
    },
    /// A vehicle's link reaches through a side wall of the container.
    #[error("{key}: {message}; move it or widen [container]")]
    VehicleOutsideContainer {
        /// Scene key.
        key: String,
        /// Which vehicle and link, how far it reaches and where the wall is.
        message: String,
    },
    /// A rig body is not over the soil.
    #[error("no soil under ({x}, {y}): place the rig body over the soil")]
    NoSoilUnder {
        /// x (m).
        x: f64,
        /// y (m).
        y: f64,
    },
    /// A rig's body has a shape the rig cannot use.
    #[error("{rig} rig body must be {allowed}")]
    RigShape {
        /// Rig type.
        rig: &'static str,
        /// Shapes allowed.
        allowed: &'static str,
    },
    /// A scripting call named a vehicle the scene does not have.
    #[error("no vehicle \"{0}\"")]
    UnknownVehicle(String),
    /// A scripting call gave a drive that cannot be applied.
    #[error("vehicle \"{vehicle}\": {message}")]
    InvalidDrive {
        /// Vehicle name.
        vehicle: String,
        /// What is allowed.
        message: String,
    },
}

impl BuildError {
    fn rigid(key: &str) -> impl FnOnce(RigidError) -> Self + '_ {
        move |source| Self::Rigid { key: key.to_string(), source }
    }
}

/// A built terrain simulation (soil only, bodies ignored).
pub struct SoilModel<T: Real> {
    /// The SPH solver (the scene's backend).
    pub solver: Box<dyn SphSolver<T>>,
    /// What the terrain generator produced (container, domain, notes).
    pub terrain: TerrainBuild,
}

/// A scene's materials in precision `T` and its terrain (soil particles, wall markers,
/// domain), as generated from its soil regions.
/// With `[terrain] patch`, the soil and walls of the patch where it starts.
pub fn scene_terrain<T: Real>(scene: &Scene) -> Result<(Vec<Material<T>>, TerrainBuild), BuildError> {
    let mats: Vec<Material<T>> = scene.materials.iter().map(|m| m.params.build()).collect::<Result<_, _>>()?;
    let (mats64, regions, container) = terrain_inputs(scene)?;
    let terrain = match scene_patch(scene)? {
        Some(p) => p.generate(p.window()),
        None => build_terrain(
            &container,
            scene.solver.spacing,
            scene.solver.bce_layers,
            scene.solver.gravity,
            &regions,
            &mats64,
        ),
    }
    .map_err(|e| match e {
        TerrainError::Overlap { first, second, at } => {
            BuildError::SoilOverlap { first: scene.soil[first].key.clone(), second: scene.soil[second].key.clone(), at }
        }
        e => e.into(),
    })?;
    let mut terrain = terrain;
    if !scene.container_walls {
        terrain.markers.clear();
    }
    Ok((mats, terrain))
}

/// What the terrain generator takes from a scene: its materials in f64, its soil regions and
/// its container.
type TerrainInputs = (Vec<Material<f64>>, Vec<RegionSpec>, Aabb);

/// A scene's [`TerrainInputs`].
fn terrain_inputs(scene: &Scene) -> Result<TerrainInputs, BuildError> {
    let mats64: Vec<Material<f64>> = scene.materials.iter().map(|m| m.params.build()).collect::<Result<_, _>>()?;
    let container = scene.container.ok_or(BuildError::NoContainer)?;
    let regions: Vec<RegionSpec> = scene
        .soil
        .iter()
        .map(|s| RegionSpec {
            region: s.region.clone(),
            material: s.material as u16,
            velocity: s.velocity,
            initial_pressure: s.initial_pressure,
        })
        .collect();
    Ok((mats64, regions, container))
}

/// The scene's moving patch where it starts (`None` without `[terrain] patch`).
pub fn scene_patch(scene: &Scene) -> Result<Option<Patch>, BuildError> {
    let Some(spec) = scene.patch else { return Ok(None) };
    let (mats64, regions, container) = terrain_inputs(scene)?;
    Ok(Some(Patch::new(scene, spec, regions, mats64, &container)))
}

/// Builds the soil solver of a terrain scene (bodies ignored) in precision `T`.
pub fn build_soil<T: Real>(scene: &Scene) -> Result<SoilModel<T>, BuildError> {
    let (mats, terrain) = scene_terrain::<T>(scene)?;
    let wgpu = scene.backend == Backend::Wgpu;
    let mut solver =
        backend::make_solver(wgpu, 1.0, scene.solver, mats, &terrain.particles, &terrain.markers, terrain.domain)?;
    set_contacts(solver.as_mut(), scene, &[scene.wall_contact.owner()], &terrain)?;
    Ok(SoilModel { solver, terrain })
}

/// Hands the walls' and bodies' soil contacts to the solver (owner 0 the walls, k + 1 the k-th
/// FSI body).
fn set_contacts<T: Real>(
    solver: &mut dyn SphSolver<T>,
    scene: &Scene,
    contacts: &[regolith_fsi::config::WallContact],
    terrain: &TerrainBuild,
) -> Result<(), BuildError> {
    let all_rough = contacts.iter().all(|c| *c == regolith_fsi::config::WallContact::Rough);
    if all_rough {
        return Ok(());
    }
    let normals = wall_normals(terrain, scene.solver.spacing, &scene.wall_contact);
    solver.set_wall_contact(contacts, &normals).map_err(BuildError::Solver)
}

/// The unit normal into the container at each wall marker (the terrain's markers, which come
/// first in the solver's marker order): the sum of the inward normals of the faces whose plane
/// the marker lies on or behind (markers sit on the lattice, the first layer on each wall
/// plane), normalised, so that edges and corners get the diagonal. Faces that `contact` keeps
/// rough add nothing, so a marker behind rough faces only has no normal and stays rough, and an
/// edge between a rough floor and a smooth wall slides along the wall.
pub fn wall_normals(terrain: &TerrainBuild, d0: f64, contact: &crate::scene::ContainerContact) -> Vec<[f64; 3]> {
    use regolith_fsi::config::WallContact;
    let c = &terrain.container;
    let (floor, walls) = (contact.floor != WallContact::Rough, contact.walls != WallContact::Rough);
    terrain
        .markers
        .iter()
        .map(|m| {
            let mut n = [0.0_f64; 3];
            for (a, na) in n.iter_mut().enumerate() {
                let (low, high) = if a == 2 { (floor, walls) } else { (walls, walls) };
                if low && m.pos[a] <= c.min[a] + 0.5 * d0 {
                    *na += 1.0;
                }
                if high && m.pos[a] >= c.max[a] - 0.5 * d0 {
                    *na -= 1.0;
                }
            }
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if l > 0.0 { n.map(|x| x / l) } else { n }
        })
        .collect()
}

/// Everything a simulation of a scene is made of: what `sim::Simulation` holds.
pub struct Assembly<T: Real> {
    /// The coupled system.
    pub system: FsiSystem<T>,
    /// The scene as built (vehicles lowered onto the soil).
    pub scene: Scene,
    /// What the terrain generator produced, less the soil carved out of bodies.
    pub terrain: TerrainBuild,
    /// Rapier-side id of each scene body.
    pub ids: Vec<BodyId>,
    /// The FSI body of each scene body (`None`: no markers).
    pub fsi: Vec<Option<FsiBodyId>>,
    /// Per vehicle: the rapier joint of each model joint.
    pub vehicle_joints: Vec<Vec<Option<JointId>>>,
    /// The initial soil surface (for sinkage).
    pub surface0: SurfaceGrid,
    /// The moving patch (`[terrain] patch`), where it starts.
    pub patch: Option<Patch>,
}

/// The active region of a scene (`[sph.active]`): one box per FSI body, its markers' bounding
/// box grown by the body's margin. `None` when the scene keeps none or has no FSI body (the
/// whole domain is then awake).
pub fn active_domain(scene: &Scene, fsi_bodies: &[(BodyId, Vec<[f64; 3]>)]) -> Option<ActiveDomain> {
    let a = scene.active?;
    if fsi_bodies.is_empty() {
        return None;
    }
    let specs = scene.bodies.iter().filter(|b| b.fsi);
    let h = scene.solver.h();
    let boxes = fsi_bodies
        .iter()
        .zip(specs)
        .map(|((_, local), spec)| {
            let tight = BodyBox::around(local);
            let extent = 2.0 * tight.half.iter().copied().fold(0.0, f64::max);
            tight.grown(a.margin_for(spec.active_margin, extent, h))
        })
        .collect();
    Some(ActiveDomain { settings: a.settings, boxes })
}

/// Builds a validated scene: terrain, carving, the rigid world (container walls, bodies,
/// vehicle joints), the FSI bodies' markers and the soil solver on the scene's backend.
pub fn assemble<T: Real>(scene: &Scene) -> Result<Assembly<T>, BuildError> {
    let (mats, terrain) = scene_terrain::<T>(scene)?;
    let d0 = scene.solver.spacing;
    let patch = scene_patch(scene)?;
    let surface0 = if patch.is_some() {
        // The surface of the whole bed, filled in as the patch lays it.
        let c = &terrain.container;
        let mut g = SurfaceGrid::covering([c.min[0] + d0, c.min[1] + d0], [c.max[0] - d0, c.max[1] - d0], d0);
        g.add(terrain.particles.iter().map(|p| p.pos));
        g
    } else {
        SurfaceGrid::new(terrain.particles.iter().map(|p| p.pos), d0)
    };
    let mut scene = scene.clone();
    place_vehicles(&mut scene, &surface0)?;
    let mut terrain = terrain;
    carve_bodies(&scene, &mut terrain);
    if terrain.particles.is_empty() {
        return Err(BuildError::NoSoilLeft);
    }
    let mut rigid = RigidWorld::new(scene.solver.gravity);
    if scene.container_walls {
        bodies::add_container(&mut rigid, &terrain, d0)?;
    }
    let mut domain = terrain.domain;
    let mut ids = Vec::new();
    let mut fsi_bodies = Vec::new();
    for b in &scene.bodies {
        let id = rigid.add_body(&b.desc).map_err(BuildError::rigid(&b.key))?;
        if let Some(v) = b.initial_velocity {
            rigid.set_velocity(id, v, [0.0; 3]);
        }
        ids.push(id);
        if !b.fsi {
            continue;
        }
        let local = shape_markers(&b.desc.shape, d0, b.bce_layers, scene.body_markers.inset(d0))
            .map_err(|source| BuildError::Markers { key: b.key.clone(), source })?;
        fsi_bodies.push((id, local));
        // The neighbour grid must cover the body where it starts and, if prescribed, where it
        // ends.
        let r = b.desc.shape.bounding_radius() + 2.0 * scene.solver.h();
        let p = b.desc.pose.translation;
        domain = grow_domain(domain, p, r);
        if let Motion::Prescribed { linvel, .. } = b.desc.motion {
            domain = grow_domain(domain, [0, 1, 2].map(|k| p[k] + linvel[k] * scene.end_time), r);
        }
    }
    let mut vehicle_joints = Vec::new();
    for v in &scene.vehicles {
        vehicle_joints.push(build_vehicle_joints(&mut rigid, v, &scene.bodies, &ids)?);
    }
    let soil = SoilInit {
        config: scene.solver,
        materials: mats,
        particles: &terrain.particles,
        wall_markers: &terrain.markers,
        domain,
    };
    let wgpu = scene.backend == Backend::Wgpu;
    let active = active_domain(&scene, &fsi_bodies);
    // A moving patch lays more soil than it lifts at times (the bow wave, soil thrown ahead:
    // +27 % over a 20 m drive in tests/patch.rs): device buffers get room for twice the start.
    let room = if patch.is_some() { 2.0 } else { 1.0 };
    let make = |c, m, p: &[_], mk: &[_], d| backend::make_solver::<T>(wgpu, room, c, m, p, mk, d);
    let mut system = FsiSystem::with_solver(soil, rigid, fsi_bodies, scene.exchange_interval, &make)?;
    let contacts: Vec<_> = std::iter::once(scene.wall_contact.owner())
        .chain(scene.bodies.iter().filter(|b| b.fsi).map(|b| b.contact))
        .collect();
    set_contacts(system.fluid.as_mut(), &scene, &contacts, &terrain)?;
    let permeable: Vec<bool> =
        std::iter::once(false).chain(scene.bodies.iter().filter(|b| b.fsi).map(|b| b.permeable)).collect();
    if permeable.iter().any(|p| *p) {
        system.fluid.set_permeable(&permeable)?;
    }
    if let Some(a) = active {
        system.fluid.set_active_domain(Some(a))?;
    }
    let fsi = ids.iter().map(|id| system.fsi_body(*id)).collect();
    Ok(Assembly { system, scene, terrain, ids, fsi, vehicle_joints, surface0, patch })
}
