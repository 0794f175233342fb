//! # Regolith
//!
//! Deformable soil simulated with SPH (the continuum representation model) and coupled to rigid
//! bodies. This facade re-exports the member crates and holds what ties them together: scene
//! and material files, the material-point driver, plots and the command-line tool's commands.
#![warn(missing_docs)]

pub mod bench;
pub mod cli;
pub mod element;
pub mod gpu;
pub mod input;
pub mod material;
pub mod plot;
pub mod record;
pub mod rig;
pub mod run;
pub mod scene;
pub mod series;
pub mod sim;

pub mod element_plot;

pub use regolith_fsi as fsi;
pub use regolith_terrain as terrain;

pub use regolith_fsi::config::DEFAULT_FREE_SURFACE_THRESHOLD;
