//! Vehicles in the rigid world: lowered onto the soil, their URDF joints built with wheel
//! motors and limits.

use regolith_rigid::{BodyId, JointDesc, JointId, RigidWorld};

use super::{BuildError, SurfaceGrid};
use crate::scene::{BodySpec, Scene, VehicleSpec};

/// Lowers every vehicle without a given height so that its lowest markers sit one spacing
/// above the top soil particle's centre below it (the contact distance of markers and soil),
/// as the rigs place their bodies: its lowest collision point that high with markers on the
/// surface, half a spacing lower with `body_markers = "inset"`.
pub fn place_vehicles(scene: &mut Scene, surface: &SurfaceGrid) -> Result<(), BuildError> {
    let offset = scene.body_markers.contact_offset(scene.solver.spacing);
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
                lift = lift.max(top + offset - low);
            }
        }
        if !lift.is_finite() {
            return Err(BuildError::VehicleOffSoil { key: v.key.clone(), name: v.name.clone() });
        }
        for li in 0..v.model.links.len() {
            scene.bodies[v.body(li)].desc.pose.translation[2] += lift;
        }
    }
    check_inside_walls(scene)
}

/// Every vehicle link below the walls' tops lies between the container's side walls: one that
/// starts through a wall is pushed out by it with the whole robot (rapier resolves the overlap
/// at once), which no user means.
fn check_inside_walls(scene: &Scene) -> Result<(), BuildError> {
    let Some(c) = scene.container.as_ref().filter(|_| scene.container_walls) else { return Ok(()) };
    for v in &scene.vehicles {
        for (li, link) in v.model.links.iter().enumerate() {
            let b = &scene.bodies[v.body(li)];
            // Above the walls' tops it clears them.
            if link.collision.is_empty() || b.desc.shape.lowest_z(&b.desc.pose) >= c.max[2] {
                continue;
            }
            let extent = b.desc.shape.horizontal_extent(&b.desc.pose);
            for (k, axis) in [(0, "x"), (1, "y")] {
                let [low, high] = extent[k];
                let beyond = if low < c.min[k] {
                    Some((low, c.min[k]))
                } else if high > c.max[k] {
                    Some((high, c.max[k]))
                } else {
                    None
                };
                if let Some((reach, wall)) = beyond {
                    return Err(BuildError::VehicleOutsideContainer {
                        key: v.key.clone(),
                        message: format!(
                            "vehicle \"{}\" does not fit in the container: link `{}` reaches {axis} = {reach:.3} m, beyond the wall at {wall:.3} m",
                            v.name, link.name
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

/// Builds a vehicle's joints between its link bodies (`bodies[i]` added to `rigid` as
/// `ids[i]`, at their current poses), with wheel velocity motors (target 0 until driven) and
/// joint limits. Returns the rapier joint of each model joint.
pub fn build_vehicle_joints(
    rigid: &mut RigidWorld,
    v: &VehicleSpec,
    bodies: &[BodySpec],
    ids: &[BodyId],
) -> Result<Vec<Option<JointId>>, BuildError> {
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
        let id = rigid.add_joint(&desc).map_err(BuildError::rigid(&v.key))?;
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
    if !v.self_collide {
        let links: Vec<BodyId> = (0..v.model.links.len()).map(|l| ids[v.body(l)]).collect();
        rigid.ignore_collisions_among(&links).map_err(BuildError::rigid(&v.key))?;
    }
    if let Some(d) = &v.differential
        && let (Some(l), Some(r)) = (out[d.left], out[d.right])
    {
        rigid.add_differential(l, r, d.sign).map_err(BuildError::rigid(&v.key))?;
    }
    Ok(out)
}
