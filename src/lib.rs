//! # Regolith
//!
//! Deformable soil simulated with SPH (the continuum representation model) and coupled to rigid
//! bodies. This facade re-exports the member crates.
#![warn(missing_docs)]

pub use regolith_fsi as fsi;
