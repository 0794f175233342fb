//! The Rust API for scripting a simulation: build or load a scene, step it, change a body's
//! velocity or a motor's target between steps, read the soil's force on a body.
//!
//! ```no_run
//! use regolith::sim::Simulation;
//! let mut sim = Simulation::<f64>::load("examples/scenes/cone_penetrometer.toml".as_ref()).unwrap();
//! let cone = sim.body("cone").unwrap();
//! sim.set_body_velocity(cone, [0.0, 0.0, -0.03], [0.0; 3]);
//! while sim.time() < 0.5 {
//!     sim.step().unwrap();
//! }
//! println!("soil force on the cone: {:?} N", sim.fsi_wrench(cone).force);
//! ```

use std::path::Path;

use regolith_coupling::{ExchangeReport, FsiSystem, SoilInit, Wrench, shape_markers};
use regolith_fsi::Real;
use regolith_rigid::{BodyId, BodyState, JointDesc, JointId, Motion, Pose, RigidWorld, ShapeDesc};
use regolith_terrain::TerrainBuild;

use crate::run::RunError;
use crate::scene::{Scene, load_scene};

/// A body of a [`Simulation`], by index into the scene's bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Body(pub usize);

/// A scene being simulated: soil, bodies and their coupling.
pub struct Simulation<T: Real> {
    /// The coupled system (soil solver, rapier world, interface).
    pub system: FsiSystem<T>,
    /// The scene it was built from.
    pub scene: Scene,
    /// What the terrain generator produced.
    pub terrain: TerrainBuild,
    ids: Vec<BodyId>,
    fsi: Vec<Option<usize>>,
}

impl<T: Real> Simulation<T> {
    /// Loads and validates a scene file and builds it.
    pub fn load(path: &Path) -> Result<Self, RunError> {
        let scene = load_scene(path, &[]).map_err(|e| RunError::Build(e.to_string()))?;
        Self::new(&scene)
    }

    /// Builds a validated scene.
    pub fn new(scene: &Scene) -> Result<Self, RunError> {
        let build = |e: String| RunError::Build(e);
        let (mats, terrain) = crate::run::scene_terrain::<T>(scene)?;
        // Soil cannot start inside a body: carve each FSI body (grown by half a spacing, the
        // distance at which its markers and the soil would overlap) out of the soil.
        let mut terrain = terrain;
        let d0 = scene.solver.spacing;
        for b in scene.bodies.iter().filter(|b| b.fsi) {
            let pose = b.desc.pose;
            let inv = [-pose.rotation[0], -pose.rotation[1], -pose.rotation[2], pose.rotation[3]];
            let local: Vec<[f64; 3]> = terrain
                .particles
                .iter()
                .map(|p| regolith_rigid::quat_rotate(inv, [0, 1, 2].map(|k| p.pos[k] - pose.translation[k])))
                .collect();
            let inside = b.desc.shape.contains_points(&local, 0.5 * d0);
            let removed = inside.iter().filter(|x| **x).count();
            if removed > 0 {
                let mut it = inside.iter();
                terrain.particles.retain(|_| !it.next().copied().unwrap_or(false));
                terrain
                    .notes
                    .push(format!("removed {removed} soil particles that started inside body \"{}\"", b.desc.name));
            }
        }
        if terrain.particles.is_empty() {
            return Err(build("the bodies fill all the soil".into()));
        }
        let mut rigid = RigidWorld::new(scene.solver.gravity);
        // The container's floor and walls, for body–wall contact (outside the soil's walls).
        let c = terrain.container;
        let t = 0.25 * (c.size()[0].min(c.size()[1])).max(scene.solver.spacing);
        let [x0, y0, z0] = c.min;
        let [x1, y1, z1] = c.max;
        let walls = [
            ("container floor", [x0 - t, y0 - t, z0 - t], [x1 + t, y1 + t, z0]),
            ("container wall -x", [x0 - t, y0 - t, z0], [x0, y1 + t, z1]),
            ("container wall +x", [x1, y0 - t, z0], [x1 + t, y1 + t, z1]),
            ("container wall -y", [x0, y0 - t, z0], [x1, y0, z1]),
            ("container wall +y", [x0, y1, z0], [x1, y1 + t, z1]),
        ];
        for (name, lo, hi) in walls {
            rigid.add_fixed_box(name, lo, hi, 0.5).map_err(|e| build(e.to_string()))?;
        }
        let (mut lo, mut hi) = terrain.domain;
        let mut ids = Vec::new();
        let mut fsi_bodies = Vec::new();
        let mut fsi = Vec::new();
        for b in &scene.bodies {
            let id = rigid.add_body(&b.desc).map_err(|e| build(format!("{}: {e}", b.key)))?;
            ids.push(id);
            if b.fsi {
                let local = shape_markers(&b.desc.shape, scene.solver.spacing, b.bce_layers)
                    .map_err(|e| build(format!("{}: {e}", b.key)))?;
                fsi.push(Some(fsi_bodies.len()));
                fsi_bodies.push((id, local));
                // The neighbour grid must cover the body where it starts and, if prescribed,
                // where it ends.
                let r = b.desc.shape.bounding_radius() + 2.0 * scene.solver.h();
                let p = b.desc.pose.translation;
                let mut ends = vec![p];
                if let Motion::Prescribed { linvel, .. } = b.desc.motion {
                    ends.push([0, 1, 2].map(|k| p[k] + linvel[k] * scene.end_time));
                }
                for e in ends {
                    for k in 0..3 {
                        lo[k] = lo[k].min(e[k] - r);
                        hi[k] = hi[k].max(e[k] + r);
                    }
                }
            } else {
                fsi.push(None);
            }
        }
        let soil = SoilInit {
            config: scene.solver,
            materials: mats,
            particles: &terrain.particles,
            wall_markers: &terrain.markers,
            domain: (lo, hi),
        };
        let system =
            FsiSystem::new(soil, rigid, fsi_bodies, scene.exchange_interval).map_err(|e| build(e.to_string()))?;
        Ok(Self { system, scene: scene.clone(), terrain, ids, fsi })
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.system.time()
    }

    /// A body by name.
    pub fn body(&self, name: &str) -> Option<Body> {
        self.scene.bodies.iter().position(|b| b.desc.name == name).map(Body)
    }

    /// Its rapier-side id.
    pub fn rigid_id(&self, b: Body) -> BodyId {
        self.ids[b.0]
    }

    /// State (world frame, centre-of-mass velocities).
    pub fn body_state(&self, b: Body) -> BodyState {
        self.system.rigid.state(self.ids[b.0])
    }

    /// Mean soil force and torque (about the centre of mass) on a body over the last exchange
    /// interval; zero for bodies without markers.
    pub fn fsi_wrench(&self, b: Body) -> Wrench {
        self.fsi[b.0].map(|k| self.system.wrench(k)).unwrap_or_default()
    }

    /// Sets a prescribed body's velocity (m/s, rad/s) from the next step on.
    pub fn set_body_velocity(&mut self, b: Body, linvel: [f64; 3], angvel: [f64; 3]) {
        self.system.rigid.set_prescribed_velocity(self.ids[b.0], linvel, angvel);
    }

    /// Adds a joint (world-frame anchor and axis).
    pub fn add_joint(&mut self, j: &JointDesc) -> Result<JointId, RunError> {
        self.system.rigid.add_joint(j).map_err(|e| RunError::Build(e.to_string()))
    }

    /// Changes a joint motor's target velocity.
    pub fn set_motor_target(&mut self, j: JointId, target: f64) {
        self.system.rigid.set_motor_target(j, target);
    }

    /// Advances one exchange interval (or to `max` seconds ahead if sooner).
    pub fn step_max(&mut self, max: Option<f64>) -> Result<ExchangeReport, RunError> {
        Ok(self.system.advance(max)?)
    }

    /// Advances one exchange interval.
    pub fn step(&mut self) -> Result<ExchangeReport, RunError> {
        self.step_max(None)
    }

    /// Every named frame to record: each scene body's shape frame (its origin and orientation),
    /// in world coordinates.
    pub fn frames(&self) -> Vec<(String, Pose)> {
        self.scene
            .bodies
            .iter()
            .zip(&self.ids)
            .map(|(b, id)| {
                let st = self.system.rigid.state(*id);
                (b.desc.name.clone(), Pose { translation: st.origin, rotation: st.rotation })
            })
            .collect()
    }

    /// The geometry drawn in each frame of [`Self::frames`].
    pub fn frame_shapes(&self) -> Vec<(String, ShapeDesc)> {
        self.scene.bodies.iter().map(|b| (b.desc.name.clone(), b.desc.shape.clone())).collect()
    }

    /// The soil wrench on every FSI body, by name.
    pub fn fsi_wrenches(&self) -> Vec<(String, Wrench)> {
        self.scene
            .bodies
            .iter()
            .zip(&self.fsi)
            .filter_map(|(b, k)| k.map(|k| (b.desc.name.clone(), self.system.wrench(k))))
            .collect()
    }

    /// Effective soil surface height (m) over a disc of radius `r` around `(x, y)`: the top of
    /// the highest particle's cell there.
    pub fn surface_height(&self, x: f64, y: f64, r: f64) -> Option<f64> {
        let f = &self.system.fluid;
        let d0 = self.scene.solver.spacing;
        (0..f.active())
            .map(|i| f.positions()[i].as_f64())
            .filter(|p| (p[0] - x).powi(2) + (p[1] - y).powi(2) <= r * r)
            .map(|p| p[2] + 0.5 * d0)
            .reduce(f64::max)
    }
}
