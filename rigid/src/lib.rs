//! # regolith-rigid
//!
//! Will own the rapier3d world of a Regolith simulation (Z up, gravity from the scene): rigid
//! bodies built from shapes with mass or density, fixed bodies, prescribed (kinematic) motion,
//! revolute and prismatic joints with velocity motors, external force and torque applied at the
//! centre of mass every step (and reset every step, since rapier keeps forces until
//! `reset_forces`), and reading body poses, velocities and accelerations.
//!
//! Nothing here yet: the crate is filled by the rigid-coupling work.
