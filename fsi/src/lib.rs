//! # regolith-fsi
//!
//! The SPH continuum representation model (CRM) of deformable soil: particle storage, smoothing
//! kernels, the neighbour grid, the constitutive models ([`rheology`]), integrators, free
//! surface and BCE-marker boundaries, on a CPU (rayon) backend and a wgpu backend.
//!
//! Units are SI, the world frame is Z up, stress is Cauchy with tension positive. Everything
//! numerical is generic over [`Real`] (`f32` or `f64`).
#![warn(missing_docs)]

pub mod active;
pub mod config;
pub mod cpu;
pub mod kernel;
pub mod math;
mod particles;
mod real;
pub mod rheology;
mod solver;

pub use particles::{MarkerInit, ParticleInit, SolverError, StepReport};
pub use real::{ByPrecision, PerPrecision, Real};
pub use regolith_body::{BodyState, Wrench};
pub use solver::{BodyMarkers, SphSolver, place_on_host};
