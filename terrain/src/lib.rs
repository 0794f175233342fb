//! # regolith-terrain
//!
//! Builds soil domains for the SPH solver: box patches in containers, heightmap patches, soil
//! blocks and columns, geostatic initial stress (σv = −ρ g depth, σh = K0 σv) and the MCC
//! initial state (p_c0 = OCR p0, specific volume from the compression lines), with several
//! materials per scene.
#![warn(missing_docs)]

mod generate;
mod heightmap;
mod shapes;

pub use generate::{Lattice, RegionSpec, TerrainBuild, build_terrain, build_terrain_in};
pub use heightmap::Heightmap;
pub use shapes::{Aabb, SoilRegion, Surface};

use std::path::PathBuf;

/// Errors building terrain.
#[derive(Debug, thiserror::Error)]
pub enum TerrainError {
    /// A heightmap file is unreadable or invalid.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Heightmap {
        /// The file.
        path: PathBuf,
        /// 1-based line (CSV), when known.
        line: Option<usize>,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// The regions or materials are inconsistent.
    #[error("{0}")]
    Setup(String),
    /// Two regions claim the same lattice point: which one the particle would belong to
    /// would be a silent choice.
    #[error("soil regions {first} and {second} overlap (both hold the lattice point at {at:?} m)")]
    Overlap {
        /// The earlier region (index into the regions).
        first: usize,
        /// The later one.
        second: usize,
        /// A point both hold (m).
        at: [f64; 3],
    },
}
