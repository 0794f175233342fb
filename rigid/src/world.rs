//! The rapier world of a simulation.

use rapier3d::prelude::*;

use crate::RigidError;
use regolith_body::BodyState;

use crate::shape::{Axis, Pose, ShapeDesc};

/// How a body's mass is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MassSpec {
    /// Total mass (kg).
    Mass(f64),
    /// Uniform density (kg/m³).
    Density(f64),
    /// Given mass properties (a URDF `<inertial>`): the colliders carry no mass.
    Inertial {
        /// Mass (kg).
        mass: f64,
        /// Centre of mass in the body frame (m).
        com: [f64; 3],
        /// Inertia tensor about the centre of mass, body-frame axes:
        /// `[ixx, iyy, izz, ixy, ixz, iyz]` (kg m²).
        inertia: [f64; 6],
    },
}

impl MassSpec {
    /// Mass (kg) of a body of this spec and shape.
    pub fn mass_of(&self, shape: &ShapeDesc) -> f64 {
        match *self {
            Self::Mass(m) | Self::Inertial { mass: m, .. } => m,
            Self::Density(d) => d * shape.volume(),
        }
    }
}

/// How a body moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Dynamic: gravity, contacts, joints and applied wrenches move it.
    Free,
    /// Never moves.
    Fixed,
    /// Kinematic with a prescribed world velocity (changeable between steps).
    Prescribed {
        /// Linear velocity of the centre of mass (m/s).
        linvel: [f64; 3],
        /// Angular velocity (rad/s).
        angvel: [f64; 3],
    },
    /// Kinematic following a piecewise-linear path of body-origin positions `(t, [x, y, z])`,
    /// held at the last waypoint afterwards.
    Waypoints(Vec<(f64, [f64; 3])>),
}

/// Everything needed to add a body.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyDesc {
    /// Name (unique).
    pub name: String,
    /// Shape in the body frame.
    pub shape: ShapeDesc,
    /// Mass or density.
    pub mass: MassSpec,
    /// Initial pose of the body frame (world).
    pub pose: Pose,
    /// Motion.
    pub motion: Motion,
    /// Coulomb friction with other bodies and walls.
    pub friction: f64,
    /// Whether it collides with other bodies and walls (rig frames and carriages do not).
    pub collides: bool,
}

/// A velocity motor on a joint's free axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityMotor {
    /// Target velocity (rad/s or m/s).
    pub target: f64,
    /// Largest torque (N m) or force (N) the motor may apply.
    pub max_effort: f64,
}

/// Joint kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about one axis.
    Revolute,
    /// Translation along one axis.
    Prismatic,
    /// No relative motion (the axis is ignored).
    Fixed,
}

/// A joint between two bodies, given in the world frame at creation.
#[derive(Clone, Debug, PartialEq)]
pub struct JointDesc {
    /// Name.
    pub name: String,
    /// First body.
    pub body1: BodyId,
    /// Second body.
    pub body2: BodyId,
    /// Kind.
    pub kind: JointKind,
    /// Anchor point (world, m).
    pub anchor: [f64; 3],
    /// Free axis (world).
    pub axis: [f64; 3],
    /// Optional velocity motor.
    pub motor: Option<VelocityMotor>,
}

/// A body of a [`RigidWorld`]: made only by [`RigidWorld::add_body`] (and the world's other
/// adders), so it always names a body that exists.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(usize);

impl BodyId {
    /// Position in the world's insertion order (for tables and reports).
    pub fn index(self) -> usize {
        self.0
    }
}

/// A joint of a [`RigidWorld`]: made only by [`RigidWorld::add_joint`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JointId(usize);

impl JointId {
    /// Position in the world's insertion order.
    pub fn index(self) -> usize {
        self.0
    }
}

pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The state of a rapier body (world frame, f64) with the given accelerations of its centre
/// of mass: rapier keeps none, so its owner supplies them (finite differences of velocities).
pub fn rapier_body_state(body: &RigidBody, linacc: [f64; 3], angacc: [f64; 3]) -> BodyState {
    let p = body.position();
    let r = p.rotation;
    BodyState {
        origin: a3(p.translation),
        com: a3(body.center_of_mass()),
        rotation: [f64::from(r.x), f64::from(r.y), f64::from(r.z), f64::from(r.w)],
        linvel: a3(body.linvel()),
        angvel: a3(body.angvel()),
        linacc,
        angacc,
    }
}

fn v3(a: [f64; 3]) -> Vector {
    Vector::new(a[0] as Real, a[1] as Real, a[2] as Real)
}
fn a3(v: Vector) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}
/// An angle brought into (−π, π].
fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = a.rem_euclid(TAU);
    if w > PI { w - TAU } else { w }
}
fn quat(q: [f64; 4]) -> Rotation {
    Rotation::from_xyzw(q[0] as Real, q[1] as Real, q[2] as Real, q[3] as Real).normalize()
}
fn pose(p: &Pose) -> rapier3d::math::Pose {
    rapier3d::math::Pose::from_parts(v3(p.translation), quat(p.rotation))
}

struct BodyRecord {
    name: String,
    handle: RigidBodyHandle,
    motion: Motion,
    force: [f64; 3],
    torque: [f64; 3],
    extra: [f64; 3],
    linacc: [f64; 3],
    angacc: [f64; 3],
    mass: f64,
}

struct JointRecord {
    name: String,
    handle: ImpulseJointHandle,
    kind: JointKind,
}

/// A rapier world with Z up, SI units and an `f64` interface.
///
/// Forces applied with [`RigidWorld::set_wrench`] act at the centre of mass and are re-applied
/// every step (rapier keeps user forces until `reset_forces`, so each step resets them first
/// and adds the current wrench: a wrench is never applied twice, and never forgotten).
pub struct RigidWorld {
    world: PhysicsWorld,
    bodies: Vec<BodyRecord>,
    joints: Vec<JointRecord>,
    differentials: Vec<Differential>,
    /// Collision groups handed out by [`RigidWorld::ignore_collisions_among`].
    groups_used: u32,
    time: f64,
}

/// Two revolute joints held to `θ_left + sign θ_right = 0` (see [`RigidWorld::add_differential`]).
#[derive(Clone, Copy, Debug)]
struct Differential {
    left: JointId,
    right: JointId,
    sign: f64,
}

/// Natural frequency (Hz) of the spring that stands for a differential bar: its period (20 ms)
/// is long against a rigid step (at most a 1 ms exchange, usually an SPH step of ~0.1 ms), so
/// the explicit spring is stable (ω dt ≤ 0.31), and short against a rocker's swing over
/// terrain.
const DIFFERENTIAL_HZ: f64 = 50.0;

impl RigidWorld {
    /// An empty world with the given gravity (m/s², world frame).
    pub fn new(gravity: [f64; 3]) -> Self {
        let world = PhysicsWorld { gravity: v3(gravity), ..Default::default() };
        Self { world, bodies: Vec::new(), joints: Vec::new(), differentials: Vec::new(), groups_used: 0, time: 0.0 }
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.bodies.len()
    }

    /// True when there are no bodies.
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    /// Body name.
    pub fn name(&self, b: BodyId) -> &str {
        &self.bodies[b.0].name
    }

    /// Finds a body by name.
    pub fn find(&self, name: &str) -> Option<BodyId> {
        self.bodies.iter().position(|b| b.name == name).map(BodyId)
    }

    /// The underlying rapier world (for advanced use; changes made there bypass this API).
    pub fn rapier(&self) -> &PhysicsWorld {
        &self.world
    }

    /// Adds a body.
    pub fn add_body(&mut self, desc: &BodyDesc) -> Result<BodyId, RigidError> {
        if self.find(&desc.name).is_some() {
            return Err(RigidError::Invalid(format!("body name \"{}\" is used twice", desc.name)));
        }
        let builder = match &desc.motion {
            Motion::Free => RigidBodyBuilder::dynamic(),
            Motion::Fixed => RigidBodyBuilder::fixed(),
            Motion::Prescribed { linvel, angvel } => {
                RigidBodyBuilder::kinematic_velocity_based().linvel(v3(*linvel)).angvel(v3(*angvel))
            }
            Motion::Waypoints(w) => {
                if w.is_empty() || w.windows(2).any(|p| p[1].0 <= p[0].0) {
                    return Err(RigidError::Invalid(format!(
                        "body \"{}\": waypoints need increasing times",
                        desc.name
                    )));
                }
                RigidBodyBuilder::kinematic_position_based()
            }
        };
        let body = builder.pose(pose(&desc.pose)).can_sleep(false).ccd_enabled(false).build();
        let handle = self.world.bodies.insert(body);
        let density = match desc.mass {
            MassSpec::Inertial { mass, com, inertia } => {
                let [ixx, iyy, izz, ixy, ixz, iyz] = inertia;
                let positive = mass > 0.0 && mass.is_finite() && [ixx, iyy, izz].iter().all(|i| *i > 0.0);
                // The principal moments of a physical body obey the triangle inequality.
                let triangle = ixx + iyy >= izz && iyy + izz >= ixx && ixx + izz >= iyy;
                if !positive || !triangle || inertia.iter().chain(&com).any(|v| !v.is_finite()) {
                    return Err(RigidError::Invalid(format!(
                        "body \"{}\": inertial needs mass > 0 and a physical inertia (ixx, iyy, izz > 0, triangle inequality); got mass {mass}, inertia {inertia:?}",
                        desc.name
                    )));
                }
                let m = Matrix::from_cols_array(&[
                    ixx as Real,
                    ixy as Real,
                    ixz as Real,
                    ixy as Real,
                    iyy as Real,
                    iyz as Real,
                    ixz as Real,
                    iyz as Real,
                    izz as Real,
                ]);
                let props = MassProperties::with_inertia_matrix(v3(com), mass as Real, m);
                self.world.bodies[handle].set_additional_mass_properties(props, true);
                0.0
            }
            MassSpec::Density(d) | MassSpec::Mass(d) => {
                let total_volume = desc.shape.volume();
                if !(total_volume > 0.0 && total_volume.is_finite()) {
                    return Err(RigidError::Invalid(format!("body \"{}\": shape has no volume", desc.name)));
                }
                let density = if matches!(desc.mass, MassSpec::Density(_)) { d } else { d / total_volume };
                if !(density > 0.0 && density.is_finite()) {
                    return Err(RigidError::Invalid(format!(
                        "body \"{}\": mass and density must be positive",
                        desc.name
                    )));
                }
                density
            }
        };
        for (p, collider) in colliders(&desc.shape, &Pose::default())? {
            let mut c = collider.position(pose(&p)).density(density as Real).friction(desc.friction as Real);
            if !desc.collides {
                c = c.collision_groups(InteractionGroups::none());
            }
            let c = c.build();
            self.world.colliders.insert_with_parent(c, handle, &mut self.world.bodies);
        }
        let mass = f64::from(self.world.bodies[handle].mass());
        self.bodies.push(BodyRecord {
            name: desc.name.clone(),
            handle,
            motion: desc.motion.clone(),
            force: [0.0; 3],
            torque: [0.0; 3],
            extra: [0.0; 3],
            linacc: [0.0; 3],
            angacc: [0.0; 3],
            mass,
        });
        Ok(BodyId(self.bodies.len() - 1))
    }

    /// Adds a fixed, axis-aligned box (walls, floors) that bodies collide with.
    pub fn add_fixed_box(
        &mut self,
        name: &str,
        min: [f64; 3],
        max: [f64; 3],
        friction: f64,
    ) -> Result<BodyId, RigidError> {
        let size = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
        let center = [0.5 * (min[0] + max[0]), 0.5 * (min[1] + max[1]), 0.5 * (min[2] + max[2])];
        self.add_body(&BodyDesc {
            name: name.to_string(),
            shape: ShapeDesc::Box { size },
            mass: MassSpec::Density(1000.0),
            pose: Pose::translation(center),
            motion: Motion::Fixed,
            friction,
            collides: true,
        })
    }

    /// Adds a joint.
    pub fn add_joint(&mut self, j: &JointDesc) -> Result<JointId, RigidError> {
        let (h1, h2) = (self.bodies[j.body1.0].handle, self.bodies[j.body2.0].handle);
        let n = (j.axis[0] * j.axis[0] + j.axis[1] * j.axis[1] + j.axis[2] * j.axis[2]).sqrt();
        if n.is_nan() || n <= 0.0 {
            return Err(RigidError::Invalid(format!("joint \"{}\": zero axis", j.name)));
        }
        let axis = [j.axis[0] / n, j.axis[1] / n, j.axis[2] / n];
        let p1 = *self.world.bodies[h1].position();
        let p2 = *self.world.bodies[h2].position();
        let anchor = v3(j.anchor);
        let a = v3(axis);
        let (mask, motor_axis) = match j.kind {
            JointKind::Revolute => (JointAxesMask::LOCKED_REVOLUTE_AXES, JointAxis::AngX),
            JointKind::Prismatic => (JointAxesMask::LOCKED_PRISMATIC_AXES, JointAxis::LinX),
            JointKind::Fixed => (JointAxesMask::LOCKED_FIXED_AXES, JointAxis::AngX),
        };
        if j.kind == JointKind::Fixed && j.motor.is_some() {
            return Err(RigidError::Invalid(format!("joint \"{}\": a fixed joint has no motor", j.name)));
        }
        // One world frame at the anchor with its x along the axis, seen from both bodies: the
        // locked axes then hold the bodies' relative pose as it is now, whatever their
        // orientations (a fixed or prismatic joint between rotated links keeps its twist).
        let frame = rapier3d::math::Pose::from_parts(anchor, Rotation::from_rotation_arc(Vector::X, a));
        let mut b = GenericJointBuilder::new(mask)
            .local_frame1(p1.inverse() * frame)
            .local_frame2(p2.inverse() * frame)
            .contacts_enabled(false);
        if let Some(m) = j.motor {
            b = b
                .motor_velocity(motor_axis, m.target as Real, MOTOR_GAIN)
                .motor_max_force(motor_axis, m.max_effort as Real);
        }
        let handle = self.world.impulse_joints.insert(h1, h2, b.build(), true);
        self.joints.push(JointRecord { name: j.name.clone(), handle, kind: j.kind });
        Ok(JointId(self.joints.len() - 1))
    }

    /// Joint name.
    pub fn joint_name(&self, j: JointId) -> &str {
        &self.joints[j.0].name
    }

    /// The free axis of a joint and its rapier data (`None` for a fixed joint).
    fn free_axis(&mut self, j: JointId) -> Option<(JointAxis, &mut GenericJoint)> {
        let rec = &self.joints[j.0];
        let axis = match rec.kind {
            JointKind::Revolute => JointAxis::AngX,
            JointKind::Prismatic => JointAxis::LinX,
            JointKind::Fixed => return None,
        };
        self.world.impulse_joints.get_mut(rec.handle, true).map(|joint| (axis, &mut joint.data))
    }

    /// Changes a joint motor's target velocity (rad/s or m/s). No effect on a fixed joint.
    pub fn set_motor_target(&mut self, j: JointId, target: f64) {
        if let Some((axis, data)) = self.free_axis(j) {
            data.set_motor_velocity(axis, target as Real, MOTOR_GAIN);
        }
    }

    /// Sets the largest torque (N m) or force (N) a joint's motor may apply.
    pub fn set_motor_max_effort(&mut self, j: JointId, max_effort: f64) {
        if let Some((axis, data)) = self.free_axis(j) {
            data.set_motor_max_force(axis, max_effort as Real);
        }
    }

    /// Drives a joint to a position (rad or m) with a spring of `stiffness` (N m/rad or N/m)
    /// and `damping`, its effort limited to `max_effort`: a steering actuator. No effect on a
    /// fixed joint.
    pub fn set_motor_position(&mut self, j: JointId, target: f64, stiffness: f64, damping: f64, max_effort: f64) {
        if let Some((axis, data)) = self.free_axis(j) {
            data.set_motor_model(axis, MotorModel::ForceBased);
            data.set_motor_position(axis, target as Real, stiffness as Real, damping as Real);
            data.set_motor_max_force(axis, max_effort as Real);
        }
    }

    /// Makes `bodies` ignore collisions among themselves while still colliding with every other
    /// body and wall: the links of one robot, which Gazebo, PyBullet and Isaac keep apart by
    /// default (a URDF's link shapes often overlap at its joints, and a rocker-bogie's corner
    /// blocks overlap its rockers). Each call takes one of 32 collision groups; a body that
    /// collides with nothing stays so. Errors when the groups are used up.
    pub fn ignore_collisions_among(&mut self, bodies: &[BodyId]) -> Result<(), RigidError> {
        if self.groups_used >= 32 {
            return Err(RigidError::Invalid(
                "more than 32 sets of bodies that ignore collisions among themselves (one per robot)".into(),
            ));
        }
        let bit = Group::from_bits_truncate(1u32 << self.groups_used);
        self.groups_used += 1;
        let groups = InteractionGroups::new(bit, Group::ALL.difference(bit), InteractionTestMode::And);
        for b in bodies {
            let handle = self.bodies[b.0].handle;
            for c in self.world.bodies[handle].colliders().to_vec() {
                let collider = &mut self.world.colliders[c];
                if collider.collision_groups() != InteractionGroups::none() {
                    collider.set_collision_groups(groups);
                }
            }
        }
        Ok(())
    }

    /// Couples two revolute joints the way a rocker-bogie rover's differential bar couples its
    /// rockers: `θ_left + sign θ_right = 0` (`sign` +1 when their axes point the same way, −1
    /// when opposite), the angles measured from the pose the joints were made in. The bar is a
    /// stiff (50 Hz), critically damped spring on that sum, applied at each
    /// step as equal torques on the two rockers about their axes and the opposite on the link
    /// they hang from: the pair keeps its opposite swing freely and resists only a common one.
    /// Errors if either joint is not revolute, they are the same, or they do not share a parent.
    pub fn add_differential(&mut self, left: JointId, right: JointId, sign: f64) -> Result<(), RigidError> {
        let revolute = |j: JointId| self.joints[j.0].kind == JointKind::Revolute;
        let parent = |j: JointId| self.world.impulse_joints.get(self.joints[j.0].handle).map(|x| x.body1());
        if left == right || !revolute(left) || !revolute(right) || parent(left) != parent(right) || sign.abs() != 1.0 {
            return Err(RigidError::Invalid(format!(
                "differential between \"{}\" and \"{}\": needs two distinct revolute joints on one parent body and a sign of ±1",
                self.joints[left.0].name, self.joints[right.0].name
            )));
        }
        self.differentials.push(Differential { left, right, sign });
        Ok(())
    }

    /// The bars' torques on their bodies for this step (explicit: from the joints' angles and
    /// rates now).
    fn differential_torques(&self) -> Vec<(RigidBodyHandle, Vector)> {
        let w = (2.0 * std::f64::consts::PI * DIFFERENTIAL_HZ) as Real;
        let mut out = Vec::new();
        for d in &self.differentials {
            let (Some((al, wl)), Some((ar, wr))) = (self.joint_position(d.left), self.joint_position(d.right)) else {
                continue;
            };
            let (Some((jl, fl, _)), Some((jr, fr, _))) = (self.joint_frames(d.left), self.joint_frames(d.right)) else {
                continue;
            };
            let (axl, axr) = (fl.rotation * Vector::X, fr.rotation * Vector::X);
            let s = d.sign as Real;
            // The sum's inverse inertia: g = θl + s θr moves with either rocker (and all that
            // hangs from it, turning about its pivot) and twice with the body.
            let inv_sum = 1.0 / self.subtree_inertia(jl.body2(), jl.body1(), fl.translation, axl)
                + 1.0 / self.subtree_inertia(jr.body2(), jr.body1(), fr.translation, axr)
                + 4.0 * self.inverse_inertia_about(jl.body1(), axl);
            if !(inv_sum > 0.0 && inv_sum.is_finite()) {
                continue;
            }
            let (g, g_rate) = (wrap_angle(al + d.sign * ar) as Real, (wl + d.sign * wr) as Real);
            let tau = -(w * w * g + 2.0 * w * g_rate) / inv_sum;
            out.push((jl.body2(), axl * tau));
            out.push((jr.body2(), axr * (s * tau)));
            out.push((jl.body1(), -(axl * tau + axr * (s * tau))));
        }
        out
    }

    /// `a · I⁻¹ a` of a body about its centre of mass (1 / its moment about `a` when `a` is a
    /// principal axis; 0 for a fixed body).
    fn inverse_inertia_about(&self, h: RigidBodyHandle, a: Vector) -> Real {
        let m = &self.world.bodies[h].mass_properties().effective_world_inv_inertia;
        a.x * (m.m11 * a.x + m.m12 * a.y + m.m13 * a.z)
            + a.y * (m.m12 * a.x + m.m22 * a.y + m.m23 * a.z)
            + a.z * (m.m13 * a.x + m.m23 * a.y + m.m33 * a.z)
    }

    /// The moment of inertia about the line through `pivot` along `a` of `root` and every body
    /// joined to it except through `parent` (a rocker with its bogie, corners and wheels), as
    /// if rigid: each body's own moment (taken as 1 / `a · I⁻¹ a`) plus `m r²`.
    fn subtree_inertia(&self, root: RigidBodyHandle, parent: RigidBodyHandle, pivot: Vector, a: Vector) -> Real {
        let (mut seen, mut todo, mut total) = (vec![parent, root], vec![root], 0.0);
        while let Some(h) = todo.pop() {
            let b = &self.world.bodies[h];
            let own = self.inverse_inertia_about(h, a);
            let r = (b.center_of_mass() - pivot).cross(a);
            total += if own > 0.0 { 1.0 / own } else { 0.0 } + b.mass() * r.dot(r);
            for (h1, h2, _, _) in self.world.impulse_joints.attached_joints(h) {
                let other = if h1 == h { h2 } else { h1 };
                if !seen.contains(&other) {
                    seen.push(other);
                    todo.push(other);
                }
            }
        }
        total
    }

    /// A joint and its two frames in the world (on its first and second body).
    fn joint_frames(&self, j: JointId) -> Option<(&ImpulseJoint, rapier3d::math::Pose, rapier3d::math::Pose)> {
        let joint = self.world.impulse_joints.get(self.joints[j.0].handle)?;
        let f1 = *self.world.bodies[joint.body1()].position() * joint.data.local_frame1;
        let f2 = *self.world.bodies[joint.body2()].position() * joint.data.local_frame2;
        Some((joint, f1, f2))
    }

    /// A revolute joint's angle (rad, in (−π, π]) and rate (rad/s) about its axis, or a
    /// prismatic joint's offset (m) and rate (m/s) along it, both from the pose the joint was
    /// made in; `None` for a fixed joint.
    pub fn joint_position(&self, j: JointId) -> Option<(f64, f64)> {
        let (joint, f1, f2) = self.joint_frames(j)?;
        let (b1, b2) = (&self.world.bodies[joint.body1()], &self.world.bodies[joint.body2()]);
        let axis = f1.rotation * Vector::X;
        match self.joints[j.0].kind {
            JointKind::Revolute => {
                // The twist about the joint's x: the locked axes leave the relative rotation
                // (cos θ/2, sin θ/2 along x).
                let rel = f1.rotation.inverse() * f2.rotation;
                let angle = 2.0 * f64::from(rel.x).atan2(f64::from(rel.w));
                let rate = (b2.angvel() - b1.angvel()).dot(axis);
                Some((wrap_angle(angle), f64::from(rate)))
            }
            JointKind::Prismatic => {
                let offset = (f2.translation - f1.translation).dot(axis);
                let (o1, o2) = (f1.translation, f2.translation);
                let rate = (b2.velocity_at_point(o2) - b1.velocity_at_point(o1)).dot(axis);
                Some((f64::from(offset), f64::from(rate)))
            }
            JointKind::Fixed => None,
        }
    }

    /// Limits a revolute or prismatic joint's position to `[lower, upper]` (rad or m).
    pub fn set_joint_limits(&mut self, j: JointId, lower: f64, upper: f64) {
        if let Some((axis, data)) = self.free_axis(j) {
            data.set_limits(axis, [lower as Real, upper as Real]);
        }
    }

    /// Sets the wrench applied at a body's centre of mass from now on (world frame, N and N m).
    pub fn set_wrench(&mut self, b: BodyId, force: [f64; 3], torque: [f64; 3]) {
        let rec = &mut self.bodies[b.0];
        rec.force = force;
        rec.torque = torque;
    }

    /// Sets a constant force at a body's centre of mass applied in addition to the wrench
    /// (a test load, a towing force), world frame (N).
    pub fn set_extra_force(&mut self, b: BodyId, force: [f64; 3]) {
        self.bodies[b.0].extra = force;
    }

    /// Locks a body's rotations: it only translates (a rig's sled or carriage on its rails).
    /// Its rotational inertia is then infinite to the solver, so a motor or joint acting on it
    /// pushes against a frame instead of a light part it would spin up. A chain of light rig
    /// parts before a heavy wheel otherwise lets the iterative joint solver pass on only a
    /// fraction of a velocity motor's torque (see NOTES.md, "A driven wheel that did not drive").
    pub fn lock_rotations(&mut self, b: BodyId) {
        let handle = self.bodies[b.0].handle;
        self.world.bodies[handle].lock_rotations(true, true);
    }

    /// Sets a free body's velocity (m/s, rad/s), e.g. an impactor's speed at the start
    /// (ignored for other motions: a prescribed body's is set by
    /// [`Self::set_prescribed_velocity`]).
    pub fn set_velocity(&mut self, b: BodyId, linvel: [f64; 3], angvel: [f64; 3]) {
        let rec = &self.bodies[b.0];
        if let Motion::Free = rec.motion {
            let body = &mut self.world.bodies[rec.handle];
            body.set_linvel(v3(linvel), true);
            body.set_angvel(v3(angvel), true);
        }
    }

    /// Changes a prescribed body's velocity (ignored for other motions).
    pub fn set_prescribed_velocity(&mut self, b: BodyId, linvel: [f64; 3], angvel: [f64; 3]) {
        let rec = &mut self.bodies[b.0];
        if let Motion::Prescribed { .. } = rec.motion {
            rec.motion = Motion::Prescribed { linvel, angvel };
        }
    }

    /// The body's motion.
    pub fn motion(&self, b: BodyId) -> &Motion {
        &self.bodies[b.0].motion
    }

    /// Mass (kg).
    pub fn mass(&self, b: BodyId) -> f64 {
        self.bodies[b.0].mass
    }

    /// Principal angular inertia about the centre of mass (kg m², principal axes).
    pub fn principal_inertia(&self, b: BodyId) -> [f64; 3] {
        let props = self.world.bodies[self.bodies[b.0].handle].mass_properties().local_mprops;
        a3(props.principal_inertia())
    }

    /// State of a body.
    pub fn state(&self, b: BodyId) -> BodyState {
        let rec = &self.bodies[b.0];
        rapier_body_state(&self.world.bodies[rec.handle], rec.linacc, rec.angacc)
    }

    /// Advances by one rapier step of `dt` (s): prescribed motions and wrenches are applied,
    /// then the solver runs, then accelerations are updated.
    pub fn step(&mut self, dt: f64) {
        self.world.integration_parameters.dt = dt as Real;
        let t1 = self.time + dt;
        let mut before = Vec::with_capacity(self.bodies.len());
        for rec in &self.bodies {
            let body = &mut self.world.bodies[rec.handle];
            before.push((a3(body.linvel()), a3(body.angvel())));
            match &rec.motion {
                Motion::Free => {
                    body.reset_forces(true);
                    body.reset_torques(true);
                    body.add_force(v3(add(rec.force, rec.extra)), true);
                    body.add_torque(v3(rec.torque), true);
                }
                Motion::Fixed => {}
                Motion::Prescribed { linvel, angvel } => {
                    body.set_linvel(v3(*linvel), true);
                    body.set_angvel(v3(*angvel), true);
                }
                Motion::Waypoints(w) => {
                    let target = waypoint(w, t1);
                    let mut next = *body.position();
                    next.translation = v3(target);
                    body.set_next_kinematic_position(next);
                }
            }
        }
        for (h, torque) in self.differential_torques() {
            self.world.bodies[h].add_torque(torque, true);
        }
        self.world.step();
        for (rec, (v0, w0)) in self.bodies.iter_mut().zip(before) {
            let body = &self.world.bodies[rec.handle];
            let (v1, w1) = (a3(body.linvel()), a3(body.angvel()));
            rec.linacc = [0, 1, 2].map(|k| (v1[k] - v0[k]) / dt);
            rec.angacc = [0, 1, 2].map(|k| (w1[k] - w0[k]) / dt);
        }
        self.time = t1;
    }
}

/// Damping gain of velocity motors (1/s, acceleration-based): stiff enough that a motor holds
/// its target unless the effort limit is reached.
pub const MOTOR_GAIN: Real = 1.0e4;

fn waypoint(w: &[(f64, [f64; 3])], t: f64) -> [f64; 3] {
    if t <= w[0].0 {
        return w[0].1;
    }
    for p in w.windows(2) {
        if t <= p[1].0 {
            let s = (t - p[0].0) / (p[1].0 - p[0].0);
            return [0, 1, 2].map(|k| p[0].1[k] + s * (p[1].1[k] - p[0].1[k]));
        }
    }
    w[w.len() - 1].1
}

/// Rapier colliders (with their poses in the body frame) of a shape.
fn colliders(shape: &ShapeDesc, at: &Pose) -> Result<Vec<(Pose, ColliderBuilder)>, RigidError> {
    let along_y_to = |axis: Axis| -> Pose {
        // Rapier's cylinders and cones run along +y; rotate them onto the wanted axis.
        match axis {
            Axis::Y => Pose::default(),
            Axis::X => Pose::from_rpy_deg([0.0; 3], [0.0, 0.0, -90.0]),
            Axis::Z => Pose::from_rpy_deg([0.0; 3], [90.0, 0.0, 0.0]),
        }
    };
    let positive = |x: f64, what: &str| {
        if x > 0.0 && x.is_finite() {
            Ok(())
        } else {
            Err(RigidError::Invalid(format!("{what} must be > 0 (got {x})")))
        }
    };
    Ok(match shape {
        ShapeDesc::Box { size } => {
            for s in size {
                positive(*s, "box size")?;
            }
            vec![(
                *at,
                ColliderBuilder::cuboid((0.5 * size[0]) as Real, (0.5 * size[1]) as Real, (0.5 * size[2]) as Real),
            )]
        }
        ShapeDesc::Sphere { radius } => {
            positive(*radius, "sphere radius")?;
            vec![(*at, ColliderBuilder::ball(*radius as Real))]
        }
        ShapeDesc::Cylinder { radius, length, axis } => {
            positive(*radius, "cylinder radius")?;
            positive(*length, "cylinder length")?;
            vec![(at.compose(&along_y_to(*axis)), ColliderBuilder::cylinder((0.5 * length) as Real, *radius as Real))]
        }
        ShapeDesc::Cone { radius, height } => {
            positive(*radius, "cone radius")?;
            positive(*height, "cone height")?;
            // Apex down: +y onto −z.
            let down = Pose::from_rpy_deg([0.0; 3], [-90.0, 0.0, 0.0]);
            vec![(at.compose(&down), ColliderBuilder::cone((0.5 * height) as Real, *radius as Real))]
        }
        ShapeDesc::Mesh { vertices, indices } => {
            let pts: Vec<Vector> = vertices.iter().map(|v| v3(*v)).collect();
            let c = ColliderBuilder::convex_hull(&pts)
                .ok_or_else(|| RigidError::Invalid("mesh has no convex hull (degenerate vertices)".into()))?;
            let _ = indices;
            vec![(*at, c)]
        }
        ShapeDesc::Wheel { radius, width, grousers } => {
            positive(*radius, "wheel radius")?;
            positive(*width, "wheel width")?;
            let mut v = vec![(
                at.compose(&along_y_to(Axis::Y)),
                ColliderBuilder::cylinder((0.5 * width) as Real, *radius as Real),
            )];
            if let Some(g) = grousers {
                positive(g.height, "grouser height")?;
                positive(g.thickness, "grouser thickness")?;
                for p in g.plate_poses(*radius) {
                    v.push((
                        at.compose(&p),
                        ColliderBuilder::cuboid(
                            (0.5 * g.thickness) as Real,
                            (0.5 * width) as Real,
                            (0.5 * g.height) as Real,
                        ),
                    ));
                }
            }
            v
        }
        ShapeDesc::Compound(parts) => {
            let mut v = Vec::new();
            for (p, s) in parts {
                v.extend(colliders(s, &at.compose(p))?);
            }
            v
        }
    })
}
