//! Regolith soil as a plugin over a rapier world the caller owns.
//!
//! [`RapierSoil`] attaches SPH soil to chosen bodies of a caller's `RigidBodySet` (a plain
//! rapier simulation, rapier's `PhysicsWorld`, or bevy_rapier's sets): each attached body gets
//! BCE markers from its collider shapes. Call [`RapierSoil::advance`] with the step you are
//! about to take, before your rapier step: it reads the attached bodies' states, advances the
//! soil over the step (its own substeps, markers moving with the bodies' motion extrapolated
//! from the step's start, as in [`crate::FsiSystem`]), and sets each dynamic attached body's
//! user force and torque to the soil's mean wrench over the step plus the extra load you gave
//! with [`RapierSoil::set_extra_force`].
//!
//! The plugin owns the user force and torque of the bodies it is attached to: it resets them
//! on every call (rapier keeps user forces until reset, so this is what keeps a wrench from
//! being applied twice). Put your own loads on those bodies through `set_extra_force`, joints
//! or impulses. Accelerations for the markers are finite differences of the velocities seen at
//! consecutive calls. Step rapier once per call, with the same `dt`, for that to be the
//! acceleration of the last step.

use rapier3d::dynamics::{RigidBody, RigidBodyHandle, RigidBodySet};
use rapier3d::geometry::{ColliderSet, Shape};
use rapier3d::math::{Real as RapierReal, Vector};
use regolith_body::{BodyState, Wrench};
use regolith_fsi::{BodyMarkers, MarkerInit, Real, SolverError, SphSolver};
use regolith_rigid::{Axis, Pose, ShapeDesc, rapier_body_state};

use crate::CouplingError;
use crate::system::{ExchangeReport, SoilInit, SolverMaker, cpu_solver, grow_domain, soil_interval};

/// A body the soil is attached to.
#[derive(Clone, Debug)]
struct Attached {
    handle: RigidBodyHandle,
    local: Vec<[f64; 3]>,
    first: usize,
    wrench: Wrench,
    extra: [f64; 3],
    last_vel: Option<([f64; 3], [f64; 3], f64)>,
    acc: ([f64; 3], [f64; 3]),
}

/// SPH soil coupled to bodies of a rapier world the caller owns.
pub struct RapierSoil<T: Real> {
    /// The soil solver.
    pub fluid: Box<dyn SphSolver<T>>,
    bodies: Vec<Attached>,
    time: f64,
}

/// What to attach: a rigid body and the shape its markers are made from (body frame).
#[derive(Clone, Debug)]
pub struct Attachment {
    /// The caller's body.
    pub handle: RigidBodyHandle,
    /// Its shape for the markers, from [`shape_of_body`] or written by hand.
    pub shape: ShapeDesc,
    /// BCE layers (3 is the usual).
    pub layers: usize,
}

impl<T: Real> RapierSoil<T> {
    /// Soil on the CPU backend attached to `attach` (their markers placed from the bodies'
    /// current poses). The neighbour grid is grown to cover each body where it starts.
    pub fn new(soil: SoilInit<'_, T>, bodies: &RigidBodySet, attach: &[Attachment]) -> Result<Self, CouplingError> {
        Self::with_solver(soil, bodies, attach, &cpu_solver::<T>)
    }

    /// As [`RapierSoil::new`], with the soil solver built by `make` (e.g. the wgpu backend).
    pub fn with_solver(
        soil: SoilInit<'_, T>,
        bodies: &RigidBodySet,
        attach: &[Attachment],
        make: SolverMaker<'_, T>,
    ) -> Result<Self, CouplingError> {
        let SoilInit { config, materials, particles, wall_markers, mut domain } = soil;
        let mut markers = wall_markers.to_vec();
        let mut out = Vec::with_capacity(attach.len());
        for (k, a) in attach.iter().enumerate() {
            let rb = bodies
                .get(a.handle)
                .ok_or_else(|| CouplingError::Invalid(format!("attachment {k}: no such rigid body in the set")))?;
            let local = crate::shape_markers(&a.shape, config.spacing, a.layers, 0.0)?;
            let s = state_of(rb, ([0.0; 3], [0.0; 3]));
            domain = grow_domain(domain, s.origin, a.shape.bounding_radius() + 2.0 * config.h());
            let first = markers.len();
            markers.extend(local.iter().map(|l| MarkerInit { pos: s.to_world(*l), owner: k as u32 + 1 }));
            out.push(Attached {
                handle: a.handle,
                local,
                first,
                wrench: Wrench::default(),
                extra: [0.0; 3],
                last_vel: None,
                acc: ([0.0; 3], [0.0; 3]),
            });
        }
        let mut fluid = make(config, materials, particles, &markers, domain).map_err(CouplingError::Solver)?;
        let states: Vec<BodyState> = out
            .iter()
            .map(|b| bodies.get(b.handle).map_or_else(BodyState::default, |rb| state_of(rb, b.acc)))
            .collect();
        let sets: Vec<BodyMarkers<'_>> = out.iter().map(|b| BodyMarkers { first: b.first, local: &b.local }).collect();
        fluid.place_bodies(&sets, &states);
        Ok(Self { fluid, bodies: out, time: 0.0 })
    }

    /// Simulated soil time (s): the sum of the steps advanced.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Mean soil wrench on attached body `k` (in the order attached) over the last step.
    pub fn wrench(&self, k: usize) -> Option<Wrench> {
        self.bodies.get(k).map(|b| b.wrench)
    }

    /// A constant force (N, world frame, at the centre of mass) applied to attached body `k`
    /// with the soil's wrench, since the plugin owns that body's user force.
    pub fn set_extra_force(&mut self, k: usize, force: [f64; 3]) -> Result<(), CouplingError> {
        let n = self.bodies.len();
        let b = self
            .bodies
            .get_mut(k)
            .ok_or_else(|| CouplingError::Invalid(format!("attached body {k} does not exist ({n} attached)")))?;
        b.extra = force;
        Ok(())
    }

    fn states(&self, bodies: &RigidBodySet) -> Vec<BodyState> {
        self.bodies
            .iter()
            .map(|b| bodies.get(b.handle).map_or_else(BodyState::default, |rb| state_of(rb, b.acc)))
            .collect()
    }

    /// Advances the soil over the rapier step `dt` (s) you are about to take, and sets the
    /// attached dynamic bodies' user force and torque to the soil's mean wrench over it (plus
    /// their extra force). Call it before each rapier step.
    pub fn advance(&mut self, bodies: &mut RigidBodySet, dt: f64) -> Result<ExchangeReport, SolverError> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(SolverError::Setup(format!("the step must be positive and finite (got {dt} s)")));
        }
        // Accelerations: the velocity change over the last step (rapier keeps none).
        for b in &mut self.bodies {
            let Some(rb) = bodies.get(b.handle) else { continue };
            let (v, w) = (a3(rb.linvel()), a3(rb.angvel()));
            if let Some((v0, w0, h)) = b.last_vel {
                b.acc = ([0, 1, 2].map(|k| (v[k] - v0[k]) / h), [0, 1, 2].map(|k| (w[k] - w0[k]) / h));
            }
            b.last_vel = Some((v, w, dt));
        }
        let start = self.states(bodies);
        let sets: Vec<BodyMarkers<'_>> =
            self.bodies.iter().map(|b| BodyMarkers { first: b.first, local: &b.local }).collect();
        let (mut report, mean, tau) = soil_interval(self.fluid.as_mut(), &sets, &start, dt)?;
        for (b, w) in self.bodies.iter_mut().zip(mean) {
            b.wrench = w;
            let Some(rb) = bodies.get_mut(b.handle) else { continue };
            if rb.is_dynamic() {
                rb.reset_forces(true);
                rb.reset_torques(true);
                rb.add_force(v3([0, 1, 2].map(|k| w.force[k] + b.extra[k])), true);
                rb.add_torque(v3(w.torque), true);
            }
        }
        self.time += tau;
        report.time = self.time;
        Ok(report)
    }
}

/// The state of a rapier body as the soil sees it, with the given accelerations.
fn state_of(rb: &RigidBody, acc: ([f64; 3], [f64; 3])) -> BodyState {
    rapier_body_state(rb, acc.0, acc.1)
}

fn v3(a: [f64; 3]) -> Vector {
    Vector::new(a[0] as RapierReal, a[1] as RapierReal, a[2] as RapierReal)
}
fn a3(v: Vector) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// The shape of a rapier body for its markers, in the body frame: its colliders (balls,
/// cuboids, cylinders, cones, triangle meshes, convex polyhedra and compounds of these), each
/// at its position relative to the body.
pub fn shape_of_body(
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    handle: RigidBodyHandle,
) -> Result<ShapeDesc, CouplingError> {
    let rb = bodies.get(handle).ok_or_else(|| CouplingError::Invalid("no such rigid body in the set".into()))?;
    let mut parts = Vec::new();
    for ch in rb.colliders() {
        let Some(c) = colliders.get(*ch) else { continue };
        let at = c.position_wrt_parent().map_or_else(Pose::default, pose_of);
        parts.push((at, shape_desc(c.shape())?));
    }
    match parts.len() {
        0 => Err(CouplingError::Invalid("the body has no collider to make soil markers from".into())),
        1 if parts[0].0 == Pose::default() => Ok(parts.remove(0).1),
        _ => Ok(ShapeDesc::Compound(parts)),
    }
}

fn pose_of(p: &rapier3d::math::Pose) -> Pose {
    let r = p.rotation;
    Pose { translation: a3(p.translation), rotation: [f64::from(r.x), f64::from(r.y), f64::from(r.z), f64::from(r.w)] }
}

fn shape_desc(s: &dyn Shape) -> Result<ShapeDesc, CouplingError> {
    let f = f64::from;
    // Rapier's cylinders and cones run along +y.
    let y_up = |d: ShapeDesc| ShapeDesc::Compound(vec![(Pose::from_rpy_deg([0.0; 3], [90.0, 0.0, 0.0]), d)]);
    if let Some(b) = s.as_ball() {
        return Ok(ShapeDesc::Sphere { radius: f(b.radius) });
    }
    if let Some(c) = s.as_cuboid() {
        let h = a3(c.half_extents);
        return Ok(ShapeDesc::Box { size: h.map(|x| 2.0 * x) });
    }
    if let Some(c) = s.as_cylinder() {
        return Ok(ShapeDesc::Cylinder { radius: f(c.radius), length: 2.0 * f(c.half_height), axis: Axis::Y });
    }
    if let Some(c) = s.as_cone() {
        // Our cone has its apex down −z; rapier's points up +y: turn −z onto +y.
        return Ok(y_up(ShapeDesc::Cone { radius: f(c.radius), height: 2.0 * f(c.half_height) }));
    }
    if let Some(m) = s.as_trimesh() {
        return Ok(ShapeDesc::Mesh {
            vertices: m.vertices().iter().map(|v| a3(*v)).collect(),
            indices: m.indices().to_vec(),
        });
    }
    if let Some(p) = s.as_convex_polyhedron() {
        let (vertices, indices) = p.to_trimesh();
        return Ok(ShapeDesc::Mesh { vertices: vertices.iter().map(|v| a3(*v)).collect(), indices });
    }
    if let Some(c) = s.as_compound() {
        let parts =
            c.shapes().iter().map(|(p, sh)| Ok((pose_of(p), shape_desc(sh.as_ref())?))).collect::<Result<_, _>>()?;
        return Ok(ShapeDesc::Compound(parts));
    }
    Err(CouplingError::Invalid(format!(
        "collider shape {:?} cannot carry soil markers (balls, cuboids, cylinders, cones, triangle meshes, convex polyhedra and compounds can)",
        s.shape_type()
    )))
}

#[cfg(test)]
mod tests {
    use rapier3d::math::{Pose as RPose, Rotation};
    use rapier3d::prelude::*;

    use super::*;

    /// Each collider kind becomes a shape that contains exactly the points rapier's shape does
    /// (away from the surface, where f32 rounding could decide), at its offset in the body.
    #[test]
    fn collider_shapes_become_the_same_shapes() {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let offset =
            RPose::from_parts(Vector::new(0.01, -0.02, 0.03), Rotation::from_scaled_axis(Vector::new(0.3, -0.2, 0.5)));
        let kinds = [
            ColliderBuilder::ball(0.05),
            ColliderBuilder::cuboid(0.04, 0.02, 0.03),
            ColliderBuilder::cylinder(0.03, 0.02),
            ColliderBuilder::cone(0.04, 0.03),
        ];
        for (i, kind) in kinds.into_iter().enumerate() {
            let h = bodies.insert(RigidBodyBuilder::dynamic());
            let c = colliders.insert_with_parent(kind.position(offset).build(), h, &mut bodies);
            let shape = shape_of_body(&bodies, &colliders, h).expect("supported");
            let mut pts = Vec::new();
            let mut x = 0.123_f64;
            for _ in 0..3000 {
                let mut p = [0.0; 3];
                for v in &mut p {
                    x = (x * 9301.0 + 0.49297).fract();
                    *v = 0.12 * (x - 0.5);
                }
                pts.push(p);
            }
            let inside = shape.contains_points(&pts, 0.0);
            let col = &colliders[c];
            let (mut checked, mut hits) = (0, 0);
            for (p, ours) in pts.iter().zip(&inside) {
                let q = Vector::new(p[0] as f32, p[1] as f32, p[2] as f32);
                let local = offset.inverse_transform_point(q);
                if col.shape().distance_to_local_point(local, true) < 1e-4 && !col.shape().contains_local_point(local) {
                    continue;
                }
                let proj = col.shape().project_local_point(local, false);
                if (proj.point - local).length() < 1e-4 {
                    continue;
                }
                checked += 1;
                hits += usize::from(proj.is_inside);
                assert_eq!(*ours, proj.is_inside, "shape {i}: point {p:?}");
            }
            assert!(checked > 2500 && hits > 30, "shape {i}: {checked} points checked, {hits} inside");
        }
    }

    #[test]
    fn unsupported_and_missing_bodies_are_errors() {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let h = bodies.insert(RigidBodyBuilder::dynamic());
        assert!(shape_of_body(&bodies, &colliders, h).is_err(), "no collider");
        colliders.insert_with_parent(ColliderBuilder::capsule_z(0.02, 0.01).build(), h, &mut bodies);
        let e = shape_of_body(&bodies, &colliders, h).expect_err("capsules are not supported");
        assert!(e.to_string().contains("cannot carry soil markers"), "{e}");
    }
}
