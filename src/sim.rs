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
    /// Per vehicle: the rapier joint of each model joint (`None` when not built).
    vehicle_joints: Vec<Vec<Option<JointId>>>,
    /// Initial soil surface, for sinkage.
    surface0: SurfaceGrid,
}

/// The soil surface height on a grid of cells of one spacing: the top of the highest
/// particle's cell in each column.
#[derive(Clone, Debug)]
pub struct SurfaceGrid {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    top: Vec<f64>,
}

impl SurfaceGrid {
    /// From particle centres with spacing `d0`.
    pub fn new(points: impl Iterator<Item = [f64; 3]> + Clone, d0: f64) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points.clone() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !lo[0].is_finite() {
            return Self { origin: [0.0; 2], cell: d0, nx: 0, ny: 0, top: Vec::new() };
        }
        let origin = [lo[0] - 0.5 * d0, lo[1] - 0.5 * d0];
        let nx = ((hi[0] - origin[0]) / d0).floor() as usize + 1;
        let ny = ((hi[1] - origin[1]) / d0).floor() as usize + 1;
        let mut top = vec![f64::NEG_INFINITY; nx * ny];
        for p in points {
            let i = (((p[0] - origin[0]) / d0) as usize).min(nx - 1);
            let j = (((p[1] - origin[1]) / d0) as usize).min(ny - 1);
            top[j * nx + i] = top[j * nx + i].max(p[2] + 0.5 * d0);
        }
        Self { origin, cell: d0, nx, ny, top }
    }

    /// Highest surface within `r` of `(x, y)` (`None` off the soil).
    pub fn height(&self, x: f64, y: f64, r: f64) -> Option<f64> {
        if self.nx == 0 {
            return None;
        }
        let idx = |v: f64, o: f64, n: usize| ((v - o) / self.cell).floor().clamp(0.0, (n - 1) as f64) as usize;
        let (i0, i1) = (idx(x - r, self.origin[0], self.nx), idx(x + r, self.origin[0], self.nx));
        let (j0, j1) = (idx(y - r, self.origin[1], self.ny), idx(y + r, self.origin[1], self.ny));
        if x + r < self.origin[0] || y + r < self.origin[1] {
            return None;
        }
        let mut best = f64::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                best = best.max(self.top[j * self.nx + i]);
            }
        }
        best.is_finite().then_some(best)
    }
}

/// A wheel's state: slip, sinkage and speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelState {
    /// `1 − v / (ω R)`: v the wheel centre's speed along the vehicle's heading, ω the wheel's
    /// forward spin relative to the chassis (NaN when the wheel does not turn).
    pub slip: f64,
    /// Depth of the rim's lowest point below the initial soil surface there (m).
    pub sinkage: f64,
    /// Forward spin relative to the chassis (rad/s).
    pub omega: f64,
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
        let d0 = scene.solver.spacing;
        let surface0 = SurfaceGrid::new(terrain.particles.iter().map(|p| p.pos), d0);
        let mut scene = scene.clone();
        place_vehicles(&mut scene, &surface0)?;
        let scene = &scene;
        // Soil cannot start inside a body: carve each FSI body (grown by half a spacing, the
        // distance at which its markers and the soil would overlap) out of the soil.
        let mut terrain = terrain;
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
        let mut vehicle_joints = Vec::new();
        for v in &scene.vehicles {
            vehicle_joints.push(build_vehicle_joints(&mut rigid, v, &scene.bodies, &ids)?);
        }
        let soil = SoilInit {
            config: scene.solver,
            materials: mats,
            particles: &terrain.particles,
            wall_markers: &terrain.markers,
            domain: (lo, hi),
        };
        let wgpu = scene.backend == crate::scene::Backend::Wgpu;
        let make = |c, m, p: &[_], mk: &[_], d| crate::gpu::make_solver::<T>(wgpu, c, m, p, mk, d);
        let system = FsiSystem::with_solver(soil, rigid, fsi_bodies, scene.exchange_interval, &make)
            .map_err(|e| build(e.to_string()))?;
        let mut sim = Self { system, scene: scene.clone(), terrain, ids, fsi, vehicle_joints, surface0 };
        sim.apply_drives();
        Ok(sim)
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

    /// Advances one exchange interval (or to `max` seconds ahead if sooner). Vehicle drive
    /// profiles are applied at the start of the interval.
    pub fn step_max(&mut self, max: Option<f64>) -> Result<ExchangeReport, RunError> {
        self.apply_drives();
        let r = self.system.advance(max)?;
        // A device backend refreshes its host copy of the particles once per exchange, for
        // the series, rigs and recording that read them (a no-op on the CPU).
        self.system.fluid.sync()?;
        Ok(r)
    }

    /// Sets every vehicle's wheel motor targets and steering angles for the current time.
    fn apply_drives(&mut self) {
        let t = self.time();
        for (v, joints) in self.scene.vehicles.iter().zip(&self.vehicle_joints) {
            for (ji, prof) in &v.drive {
                let sign = v.wheels.iter().find(|w| w.joint == *ji).map_or(1.0, |w| w.forward_sign);
                if let Some(j) = joints[*ji] {
                    self.system.rigid.set_motor_target(j, sign * prof.at(t));
                }
            }
            for (ji, prof) in &v.steering {
                if let Some(j) = joints[*ji] {
                    let (k, c) = steering_gains(v.max_torque);
                    self.system.rigid.set_motor_position(j, prof.at(t), k, c, v.max_torque);
                }
            }
        }
    }

    /// Drives a vehicle's wheels from now on at constant speeds (rad/s, forward positive): the
    /// left-side wheels at `left`, the right-side ones at `right` (equal for straight driving,
    /// different for skid steering), with motor torques up to `max_torque` (N m). Replaces the
    /// scene's drive profiles of those wheels.
    pub fn set_vehicle_drive(&mut self, vehicle: &str, left: f64, right: f64, max_torque: f64) -> Result<(), RunError> {
        let vi = self
            .scene
            .vehicles
            .iter()
            .position(|v| v.name == vehicle)
            .ok_or_else(|| RunError::Build(format!("no vehicle \"{vehicle}\"")))?;
        if !(max_torque > 0.0 && max_torque.is_finite() && left.is_finite() && right.is_finite()) {
            return Err(RunError::Build(format!(
                "vehicle \"{vehicle}\": wheel speeds must be finite and max_torque > 0"
            )));
        }
        let v = &mut self.scene.vehicles[vi];
        v.max_torque = max_torque;
        v.drive = v
            .wheels
            .iter()
            .map(|w| (w.joint, crate::scene::Profile(vec![(0.0, if w.side > 0.0 { left } else { right })])))
            .collect();
        for w in &self.scene.vehicles[vi].wheels {
            if let Some(j) = self.vehicle_joints[vi][w.joint] {
                self.system.rigid.set_motor_max_effort(j, max_torque);
            }
        }
        self.apply_drives();
        Ok(())
    }

    /// The rapier joint of a vehicle's joint, by vehicle and joint name.
    pub fn vehicle_joint(&self, vehicle: &str, joint: &str) -> Option<JointId> {
        let vi = self.scene.vehicles.iter().position(|v| v.name == vehicle)?;
        let ji = self.scene.vehicles[vi].model.joints.iter().position(|j| j.name == joint)?;
        self.vehicle_joints[vi][ji]
    }

    /// Slip, sinkage and spin of every wheel of vehicle `v` (index into the scene's vehicles),
    /// in the order of its `wheels`.
    pub fn wheel_states(&self, v: usize) -> Vec<WheelState> {
        let spec = &self.scene.vehicles[v];
        let chassis = self.body_state(Body(spec.body(spec.model.root)));
        let left = regolith_rigid::quat_rotate(chassis.rotation, [0.0, 1.0, 0.0]);
        // Heading: the root's x projected on the horizontal plane.
        let fwd = regolith_rigid::quat_rotate(chassis.rotation, [1.0, 0.0, 0.0]);
        let h = (fwd[0] * fwd[0] + fwd[1] * fwd[1]).sqrt().max(1e-12);
        let heading = [fwd[0] / h, fwd[1] / h, 0.0];
        spec.wheels
            .iter()
            .map(|w| {
                let st = self.body_state(Body(spec.body(w.link)));
                let j = &spec.model.joints[w.joint];
                let axle = regolith_rigid::quat_rotate(st.rotation, j.axis);
                let rel = [0, 1, 2].map(|k| st.angvel[k] - chassis.angvel[k]);
                let sign = if dot(axle, left) >= 0.0 { 1.0 } else { -1.0 };
                let omega = sign * dot(rel, axle);
                let v = dot(st.velocity_at(st.origin), heading);
                let slip = if (omega * w.radius).abs() > 1e-9 { 1.0 - v / (omega * w.radius) } else { f64::NAN };
                let surface = self
                    .surface0
                    .height(st.origin[0], st.origin[1], 0.5 * self.scene.solver.spacing)
                    .unwrap_or(f64::NAN);
                WheelState { slip, sinkage: surface - (st.origin[2] - w.radius), omega }
            })
            .collect()
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

    /// The geometry drawn in each frame of [`Self::frames`] (a URDF link's visual geometry
    /// when it has one, else its collision shape).
    pub fn frame_shapes(&self) -> Vec<(String, ShapeDesc)> {
        self.scene
            .bodies
            .iter()
            .map(|b| (b.desc.name.clone(), b.visual.clone().unwrap_or_else(|| b.desc.shape.clone())))
            .collect()
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

    /// Kinetic energy of the soil still in the domain (J).
    pub fn soil_kinetic_energy(&self) -> f64 {
        let f = &self.system.fluid;
        (0..f.active())
            .map(|i| {
                let v = f.velocities()[i].as_f64();
                0.5 * f.masses()[i].as_f64() * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            })
            .sum()
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

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Spring and damper of a steering actuator with torque limit `max_torque`: full torque at
/// 0.05 rad of error, damping a tenth of the stiffness per rad/s.
fn steering_gains(max_torque: f64) -> (f64, f64) {
    let k = max_torque / 0.05;
    (k, 0.1 * k)
}

/// Lowers every vehicle without a given height so that its lowest collision point sits one
/// spacing above the top soil particle's centre below it (the contact distance of markers and
/// soil), as the rigs place their bodies.
fn place_vehicles(scene: &mut Scene, surface: &SurfaceGrid) -> Result<(), RunError> {
    let d0 = scene.solver.spacing;
    for v in scene.vehicles.clone() {
        if !v.place_on_soil {
            continue;
        }
        let mut lift = f64::NEG_INFINITY;
        for li in 0..v.model.links.len() {
            let b = &scene.bodies[v.body(li)];
            let low = b.desc.shape.lowest_z(&b.desc.pose);
            if !low.is_finite() {
                continue;
            }
            let t = b.desc.pose.translation;
            if let Some(top) = surface.height(t[0], t[1], b.desc.shape.bounding_radius()) {
                lift = lift.max(top + 0.5 * d0 - low);
            }
        }
        if !lift.is_finite() {
            return Err(RunError::Build(format!(
                "{}: vehicle \"{}\" is not over the soil: place it over the terrain or give position = [x, y, z]",
                v.key, v.name
            )));
        }
        for li in 0..v.model.links.len() {
            scene.bodies[v.body(li)].desc.pose.translation[2] += lift;
        }
    }
    Ok(())
}

/// Builds a vehicle's joints between its link bodies (`bodies[i]` added to `rigid` as
/// `ids[i]`, at their current poses), with wheel velocity motors (target 0 until driven) and
/// joint limits. Returns the rapier joint of each model joint.
pub fn build_vehicle_joints(
    rigid: &mut RigidWorld,
    v: &crate::scene::VehicleSpec,
    bodies: &[crate::scene::BodySpec],
    ids: &[BodyId],
) -> Result<Vec<Option<JointId>>, RunError> {
    use regolith_vehicles::JointType;
    let mut out = Vec::with_capacity(v.model.joints.len());
    for (ji, j) in v.model.joints.iter().enumerate() {
        let child = &bodies[v.body(j.child)].desc.pose;
        let kind = match j.kind {
            JointType::Fixed => regolith_rigid::JointKind::Fixed,
            JointType::Continuous | JointType::Revolute { .. } => regolith_rigid::JointKind::Revolute,
            JointType::Prismatic { .. } => regolith_rigid::JointKind::Prismatic,
        };
        let driven = v.drive.iter().any(|(d, _)| *d == ji);
        let desc = JointDesc {
            name: format!("{}/{}", v.name, j.name),
            body1: ids[v.body(j.parent)],
            body2: ids[v.body(j.child)],
            kind,
            anchor: child.translation,
            axis: child.rotate(j.axis),
            motor: driven.then_some(regolith_rigid::VelocityMotor { target: 0.0, max_effort: v.max_torque }),
        };
        let id = rigid.add_joint(&desc).map_err(|e| RunError::Build(format!("{}: {e}", v.key)))?;
        match j.kind {
            JointType::Revolute { lower, upper } | JointType::Prismatic { lower, upper }
                if lower.is_finite() && upper.is_finite() =>
            {
                rigid.set_joint_limits(id, lower, upper);
            }
            _ => {}
        }
        out.push(Some(id));
    }
    Ok(out)
}
