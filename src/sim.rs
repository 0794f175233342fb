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

use regolith_coupling::{ExchangeReport, FsiBodyId, FsiSystem, Wrench};
use regolith_fsi::{ByPrecision, PerPrecision, Real, SolverError};
use regolith_rigid::{BodyId, BodyState, JointDesc, JointId, Pose, ShapeDesc};
use regolith_terrain::TerrainBuild;

use crate::build::{BuildError, Patch, SurfaceGrid, assemble};
use crate::scene::{Scene, load_scene};

/// A body of a [`Simulation`]: got from [`Simulation::body`] or [`Simulation::bodies`], so it
/// always names one of the scene's bodies. It remembers which simulation it came from: using
/// it on another one is a programming error and panics with a message saying so (rather than
/// reading some other body, or past the end).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Body {
    sim: u64,
    index: usize,
}

impl Body {
    /// Position in the scene's `[[bodies]]` (vehicle links follow them).
    pub fn index(self) -> usize {
        self.index
    }
}

/// Source of each simulation's identity, for its [`Body`] handles.
static NEXT_SIMULATION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A scene being simulated: soil, bodies and their coupling.
pub struct Simulation<T: Real> {
    /// The coupled system (soil solver, rapier world, interface).
    pub system: FsiSystem<T>,
    /// The scene it was built from.
    pub scene: Scene,
    /// What the terrain generator produced.
    pub terrain: TerrainBuild,
    ids: Vec<BodyId>,
    fsi: Vec<Option<FsiBodyId>>,
    /// Per vehicle: the rapier joint of each model joint (`None` when not built).
    vehicle_joints: Vec<Vec<Option<JointId>>>,
    /// Initial soil surface, for sinkage.
    surface0: SurfaceGrid,
    /// The moving patch (`[terrain] patch`), if any.
    patch: Option<Patch>,
    /// Identity carried by this simulation's [`Body`] handles.
    uid: u64,
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
    pub fn load(path: &Path) -> Result<Self, BuildError> {
        let scene = load_scene(path, &[])?;
        Self::new(&scene)
    }

    /// Builds a validated scene (see [`crate::build::assemble`]).
    ///
    /// Compiled once per precision, in this crate ([`Real::by_precision`]).
    pub fn new(scene: &Scene) -> Result<Self, BuildError> {
        T::from_precision::<Built>(|| new_f32(scene), || new_f64(scene))
    }

    fn new_generic(scene: &Scene) -> Result<Self, BuildError> {
        let a = assemble::<T>(scene)?;
        let mut sim = Self {
            system: a.system,
            scene: a.scene,
            terrain: a.terrain,
            ids: a.ids,
            fsi: a.fsi,
            vehicle_joints: a.vehicle_joints,
            surface0: a.surface0,
            patch: a.patch,
            uid: NEXT_SIMULATION.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        };
        sim.apply_drives();
        Ok(sim)
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.system.time()
    }

    /// A body by name.
    pub fn body(&self, name: &str) -> Option<Body> {
        self.scene.bodies.iter().position(|b| b.desc.name == name).map(|i| self.body_at(i))
    }

    /// Every body, in scene order.
    pub fn bodies(&self) -> impl Iterator<Item = Body> + use<T> {
        let sim = self.uid;
        (0..self.scene.bodies.len()).map(move |index| Body { sim, index })
    }

    /// The body at a position of the scene's body list (bodies, then vehicle links), for the
    /// crate's rigs and outputs, which hold scene indices.
    pub(crate) fn body_at(&self, index: usize) -> Body {
        debug_assert!(index < self.scene.bodies.len());
        Body { sim: self.uid, index }
    }

    /// A handle's index, checked to belong to this simulation.
    fn slot(&self, b: Body) -> usize {
        assert!(
            b.sim == self.uid,
            "Body handle of another Simulation used (body index {}): get handles from this simulation's body() or bodies()",
            b.index
        );
        b.index
    }

    /// Its rapier-side id.
    pub fn rigid_id(&self, b: Body) -> BodyId {
        self.ids[self.slot(b)]
    }

    /// State (world frame, centre-of-mass velocities).
    pub fn body_state(&self, b: Body) -> BodyState {
        self.system.rigid.state(self.ids[self.slot(b)])
    }

    /// Mean soil force and torque (about the centre of mass) on a body over the last exchange
    /// interval; zero for bodies without markers.
    pub fn fsi_wrench(&self, b: Body) -> Wrench {
        self.fsi[self.slot(b)].map(|k| self.system.wrench(k)).unwrap_or_default()
    }

    /// Sets a prescribed body's velocity (m/s, rad/s) from the next step on.
    pub fn set_body_velocity(&mut self, b: Body, linvel: [f64; 3], angvel: [f64; 3]) {
        self.system.rigid.set_prescribed_velocity(self.ids[self.slot(b)], linvel, angvel);
    }

    /// Adds a joint (world-frame anchor and axis).
    pub fn add_joint(&mut self, j: &JointDesc) -> Result<JointId, BuildError> {
        self.system
            .rigid
            .add_joint(j)
            .map_err(|source| BuildError::Rigid { key: format!("joint \"{}\"", j.name), source })
    }

    /// Changes a joint motor's target velocity.
    pub fn set_motor_target(&mut self, j: JointId, target: f64) {
        self.system.rigid.set_motor_target(j, target);
    }

    /// Advances one exchange interval (or to `max` seconds ahead if sooner). Vehicle drive
    /// profiles are applied at the start of the interval.
    ///
    /// Compiled once per precision, in this crate ([`Real::by_precision`]).
    pub fn step_max(&mut self, max: Option<f64>) -> Result<ExchangeReport, SolverError> {
        match T::by_precision::<SimMut<'_>>(self) {
            ByPrecision::F32(sim) => step_f32(sim, max),
            ByPrecision::F64(sim) => step_f64(sim, max),
        }
    }

    fn step_generic(&mut self, max: Option<f64>) -> Result<ExchangeReport, SolverError> {
        self.apply_drives();
        let r = self.system.advance(max)?;
        // A device backend refreshes its host copy of the particles once per exchange, for
        // the series, rigs and recording that read them (a no-op on the CPU).
        self.system.fluid.sync()?;
        self.follow_patch()?;
        Ok(r)
    }

    /// The moving patch, if the scene has one (where it is, how often it advanced).
    pub fn patch(&self) -> Option<&Patch> {
        self.patch.as_ref()
    }

    /// Moves the patch forward if the FSI bodies have come within its trigger distance of its
    /// front (see [`crate::build::Patch`]).
    fn follow_patch(&mut self) -> Result<(), SolverError> {
        let Some(patch) = &mut self.patch else { return Ok(()) };
        // The FSI markers' span along x, from the bodies' states (a device backend places its
        // markers on the device, so its host copy of them is not current).
        let (mut back, mut front) = (f64::INFINITY, f64::NEG_INFINITY);
        for b in &self.system.interface.bodies {
            let s = self.system.rigid.state(b.body);
            for l in &b.local {
                let x = s.to_world(*l)[0];
                back = back.min(x);
                front = front.max(x);
            }
        }
        if !front.is_finite() {
            return Ok(());
        }
        let Some(relay) = patch.follow(front, back).map_err(SolverError::Setup)? else { return Ok(()) };
        self.surface0.add(relay.fresh.iter().map(|p| p.pos));
        let lifted = self.system.fluid.relay(relay.cut, relay.shift, &relay.fresh)?;
        patch.lifted(lifted);
        Ok(())
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
    pub fn set_vehicle_drive(
        &mut self,
        vehicle: &str,
        left: f64,
        right: f64,
        max_torque: f64,
    ) -> Result<(), BuildError> {
        let vi = self
            .scene
            .vehicles
            .iter()
            .position(|v| v.name == vehicle)
            .ok_or_else(|| BuildError::UnknownVehicle(vehicle.to_string()))?;
        if !(max_torque > 0.0 && max_torque.is_finite() && left.is_finite() && right.is_finite()) {
            return Err(BuildError::InvalidDrive {
                vehicle: vehicle.to_string(),
                message: "wheel speeds must be finite and max_torque > 0".into(),
            });
        }
        let invalid = |message| BuildError::InvalidDrive { vehicle: vehicle.to_string(), message };
        let v = &mut self.scene.vehicles[vi];
        v.max_torque = max_torque;
        v.drive = v
            .wheels
            .iter()
            .map(|w| {
                Ok((
                    w.joint,
                    crate::scene::Profile::constant(if w.side > 0.0 { left } else { right }).map_err(invalid)?,
                ))
            })
            .collect::<Result<_, BuildError>>()?;
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
        let chassis = self.body_state(self.body_at(spec.body(spec.model.root)));
        let left = regolith_rigid::quat_rotate(chassis.rotation, [0.0, 1.0, 0.0]);
        // Heading: the root's x projected on the horizontal plane.
        let fwd = regolith_rigid::quat_rotate(chassis.rotation, [1.0, 0.0, 0.0]);
        let h = (fwd[0] * fwd[0] + fwd[1] * fwd[1]).sqrt().max(1e-12);
        let heading = [fwd[0] / h, fwd[1] / h, 0.0];
        spec.wheels
            .iter()
            .map(|w| {
                let st = self.body_state(self.body_at(spec.body(w.link)));
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
    pub fn step(&mut self) -> Result<ExchangeReport, SolverError> {
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

    /// The URDF links lumped by fixed joints into each vehicle's links (sensor frames, mounts,
    /// footprints): `(carrier body, "<vehicle>/<link>", pose in the carrier's frame)`, for `/tf`.
    pub fn lumped_frames(&self) -> Vec<(String, String, Pose)> {
        self.scene
            .vehicles
            .iter()
            .flat_map(|v| {
                v.model.frames.iter().map(move |f| {
                    let carrier = format!("{}/{}", v.name, v.model.links[f.link].name);
                    (carrier, format!("{}/{}", v.name, f.name), f.pose)
                })
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

    /// One line about soil particle `id` (its original index): material, position, velocity,
    /// stress (p, q and the components), p_c and specific volume, as the solver holds them now.
    pub fn particle_report(&self, id: u32) -> String {
        let f = &self.system.fluid;
        let Some(i) = f.ids().iter().position(|x| *x == id) else {
            return format!("particle {id} (not in this simulation)");
        };
        let material = f.material_ids()[i] as usize;
        let name = self.scene.materials.get(material).map_or("?", |m| m.name.as_str());
        let p = f.positions()[i].as_f64();
        let v = f.velocities()[i].as_f64();
        let st = f.stresses()[i];
        let c = |x: T| x.as_f64();
        let state = f.states()[i];
        format!(
            "particle {id} (material \"{name}\") at [{:.4}, {:.4}, {:.4}] m, velocity [{:.3e}, {:.3e}, {:.3e}] m/s, stress p = {:.4e} Pa, q = {:.4e} Pa (xx {:.3e}, yy {:.3e}, zz {:.3e}, xy {:.3e}, xz {:.3e}, yz {:.3e}), p_c = {:.4e} Pa, v = {:.4}",
            p[0],
            p[1],
            p[2],
            v[0],
            v[1],
            v[2],
            c(st.pressure()),
            c(st.von_mises()),
            c(st.xx),
            c(st.yy),
            c(st.zz),
            c(st.xy),
            c(st.xz),
            c(st.yz),
            c(state.pc),
            c(state.v)
        )
    }

    /// The initial soil surface height (m) at `(x, y)`: the top of the highest particle's cell
    /// within `r` of it when the scene was built.
    pub fn initial_surface_height(&self, x: f64, y: f64, r: f64) -> Option<f64> {
        self.surface0.height(x, y, r)
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

/// `Result<Simulation<T>, BuildError>` as a [`PerPrecision`] family, for [`Simulation::new`].
struct Built;

impl PerPrecision for Built {
    type Of<T: Real> = Result<Simulation<T>, BuildError>;
}

/// `&mut Simulation<T>` as a [`PerPrecision`] family, for [`Simulation::step_max`].
struct SimMut<'a>(std::marker::PhantomData<&'a ()>);

impl<'a> PerPrecision for SimMut<'a> {
    type Of<T: Real> = &'a mut Simulation<T>;
}

/// The `f32` build, compiled here once (never inlined into a caller's crate, which would
/// compile the generic build there again).
#[inline(never)]
fn new_f32(scene: &Scene) -> Result<Simulation<f32>, BuildError> {
    Simulation::new_generic(scene)
}

/// The `f64` build, compiled here once.
#[inline(never)]
fn new_f64(scene: &Scene) -> Result<Simulation<f64>, BuildError> {
    Simulation::new_generic(scene)
}

/// The `f32` exchange step, compiled here once.
#[inline(never)]
fn step_f32(sim: &mut Simulation<f32>, max: Option<f64>) -> Result<ExchangeReport, SolverError> {
    sim.step_generic(max)
}

/// The `f64` exchange step, compiled here once.
#[inline(never)]
fn step_f64(sim: &mut Simulation<f64>, max: Option<f64>) -> Result<ExchangeReport, SolverError> {
    sim.step_generic(max)
}
