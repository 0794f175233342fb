//! # regolith-coupling
//!
//! `FsiSystem { fluid, rigid, interface }`: SPH soil (`regolith-fsi`) coupled to rapier bodies
//! (`regolith-rigid`) through BCE markers generated from each body's shape, split as in
//! Chrono's `ChFsiSystem` / `ChFsiInterface`: what crosses the interface is body states (pose,
//! velocities, accelerations; world frame) in, and a force and torque at each body's centre of
//! mass (world frame) out. The exchange schedule and its lag are documented in [`FsiSystem`]'s
//! module, [`system`].
#![warn(missing_docs)]

mod markers;
pub mod plugin;
pub mod system;

pub use markers::{check_watertight, shape_markers};
pub use plugin::{Attachment, RapierSoil, shape_of_body};
pub use regolith_body::{BodyState, Wrench};
pub use system::{
    ExchangeReport, FsiBody, FsiBodyId, FsiInterface, FsiSystem, SoilInit, SolverMaker, cpu_solver, extrapolate,
    grow_domain, soil_interval,
};

/// Errors of the coupling layer.
#[derive(Debug, thiserror::Error)]
pub enum CouplingError {
    /// A description is invalid.
    #[error("{0}")]
    Invalid(String),
    /// A mesh cannot be used for markers.
    #[error("{0}")]
    Mesh(String),
    /// The soil solver rejected its inputs (the solver's error is the source).
    #[error("soil solver")]
    Solver(#[source] regolith_fsi::SolverError),
}
