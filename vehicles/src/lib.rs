//! # regolith-vehicles
//!
//! URDF vehicles on Regolith terrain: [`UrdfModel`] reads a URDF (links with inertials,
//! collision and visual geometry — boxes, cylinders, spheres, capsules, STL/OBJ/DAE meshes with
//! scale — and fixed, continuous, revolute and prismatic joints), resolving mesh URIs
//! (`package://` through a [`PackagePath`], `file://`, relative to the URDF). Missing files,
//! unknown packages, malformed files and links without an inertial are errors naming the link
//! and the URI; joints it cannot honour (planar, floating, spherical, `mimic`) are listed in
//! [`UrdfModel::unsupported`] for the caller to report once.
//!
//! The wheel links (children of continuous joints with a cylinder or mesh collision) are what
//! touches the soil by default; [`wheel_shape`] turns a cylinder wheel into a Regolith wheel
//! with optional grousers, so its BCE markers carry the grousers too. Building the links into
//! the rapier world, placing the vehicle on the terrain and driving it (wheel velocity motors,
//! skid steering, steering joints) is done by the `regolith` facade from a scene's
//! `[[vehicles]]` section or through its scripting API.

pub mod lump;
pub mod urdf;
pub mod xacro;

pub use lump::{MassProperties, combine_mass};
pub use urdf::{FrameModel, JointModel, JointType, LinkModel, PackagePath, UrdfError, UrdfModel, combine, resolve_uri};
pub use xacro::Substitution;

use regolith_rigid::{Grousers, Pose, ShapeDesc};

/// A wheel link's soil-contact shape in the link frame and its rolling radius: a cylinder
/// collision becomes a [`ShapeDesc::Wheel`] (axle along the cylinder axis) with `grousers`; a
/// mesh stays a mesh, its radius (the rim radius for a cylinder, grousers not included) the largest distance of a vertex from the mesh's axle line
/// through the link origin along `axle` (link frame). Other shapes: `None`.
pub fn wheel_shape(link: &LinkModel, axle: [f64; 3], grousers: Option<Grousers>) -> Option<(ShapeDesc, f64)> {
    let (at, shape) =
        link.collision.iter().find(|(_, s)| matches!(s, ShapeDesc::Cylinder { .. } | ShapeDesc::Mesh { .. }))?;
    match shape {
        ShapeDesc::Cylinder { radius, length, .. } => {
            // The Regolith wheel's axle is its y axis; the URDF cylinder's is its z axis.
            let y_to_z = Pose::from_rpy_deg([0.0; 3], [90.0, 0.0, 0.0]);
            let wheel = ShapeDesc::Wheel { radius: *radius, width: *length, grousers };
            Some((ShapeDesc::Compound(vec![(at.compose(&y_to_z), wheel)]), *radius))
        }
        ShapeDesc::Mesh { vertices, .. } => {
            let r = vertices
                .iter()
                .map(|v| at.apply(*v))
                .map(|p| {
                    let d = p[0] * axle[0] + p[1] * axle[1] + p[2] * axle[2];
                    let q = [p[0] - d * axle[0], p[1] - d * axle[1], p[2] - d * axle[2]];
                    (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
                })
                .fold(0.0, f64::max);
            Some((ShapeDesc::Compound(vec![(*at, shape.clone())]), r))
        }
        _ => None,
    }
}
