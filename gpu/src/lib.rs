//! # regolith-wgpu
//!
//! The wgpu backend of Regolith's SPH soil: every stage of the CPU step (cell binning and
//! sort, neighbour loops, rates, Jaumann update, the Drucker–Prager and Modified Cam Clay return
//! mappings, RK2/Euler, shifting, free surface, wall and body markers with rough, smooth or
//! frictional contact, and the wet loop of a scene with water) as a WGSL compute kernel, with
//! all particle state resident on the device. f32 only.
//!
//! The library never creates a device: [`GpuSph::new`] takes the caller's `wgpu::Device` and
//! `wgpu::Queue` (the `regolith` facade opens them). Kernels are specialised to the scene's
//! [`Effects`] by generated constants and module selection, so an effect that is off costs
//! nothing per particle and a model no material uses is not compiled
//! ([`SphSolver::variants`](regolith_fsi::SphSolver::variants)).
//!
//! Each kernel's CPU twin is the `regolith-fsi` CPU backend; `tests/wgpu_parity.rs` of the
//! workspace checks them against each other.
#![warn(missing_docs)]

mod active;
mod error_code;
mod kernels;
mod layout;
mod neighbour_loop;
mod resources;
mod shader;
mod solver;

pub use shader::Effects;
pub use solver::GpuSph;

/// What can go wrong setting up the wgpu backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// A kernel failed to compile or validate.
    #[error("kernel {kernel}: {message}")]
    Shader {
        /// Kernel label.
        kernel: String,
        /// The compiler's message.
        message: String,
    },
    /// The problem does not fit the device's limits.
    #[error("{what} needs {needed} but the adapter allows {allowed} ({limit})")]
    Limit {
        /// What was too big.
        what: String,
        /// Needed amount.
        needed: u64,
        /// Allowed amount.
        allowed: u64,
        /// Which limit.
        limit: &'static str,
    },
    /// The solver's inputs are inconsistent.
    #[error("{0}")]
    Setup(String),
    /// A device operation failed (mapping, lost device).
    #[error("device: {0}")]
    Device(String),
    /// A bug: a pipeline list came back short.
    #[error("internal: {0}")]
    Internal(&'static str),
}
