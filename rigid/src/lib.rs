//! # regolith-rigid
//!
//! A thin owner of the rapier3d world of a Regolith simulation (Z up, gravity from the scene,
//! SI units, `f64` in the interface, rapier's `f32` inside): rigid bodies built from shapes
//! with a mass or a density, fixed bodies, prescribed (kinematic) motion by velocity or by
//! waypoints, revolute and prismatic joints with velocity motors, an external force and torque
//! applied at the centre of mass each step (and reset every step, since rapier keeps forces
//! until `reset_forces`), and body states with positions, velocities and accelerations.
#![warn(missing_docs)]

pub mod bench;
mod mesh;
mod mesh_io;
mod shape;
mod world;

pub mod dae;
pub use mesh::{MeshError, TriangleMesh};
pub use mesh_io::load_mesh;
pub use regolith_body::BodyState;
pub use shape::{Axis, Grousers, Pose, ShapeDesc, quat_mul, quat_rotate};
pub use world::{
    BodyDesc, BodyId, JointDesc, JointId, JointKind, MOTOR_GAIN, MassSpec, Motion, RigidWorld, VelocityMotor,
    rapier_body_state,
};

/// Errors of the rigid world.
#[derive(Debug, thiserror::Error)]
pub enum RigidError {
    /// A body or joint description is invalid.
    #[error("{0}")]
    Invalid(String),
}
