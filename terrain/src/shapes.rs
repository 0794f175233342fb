//! Geometric descriptions of where soil is: the bed of a container (flat or heightmap) and free
//! blocks or columns.

use crate::Heightmap;

/// An axis-aligned box (m, world frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl Aabb {
    /// Extent along each axis (m).
    pub fn size(&self) -> [f64; 3] {
        [self.max[0] - self.min[0], self.max[1] - self.min[1], self.max[2] - self.min[2]]
    }
    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i])
    }
}

/// The top surface of a terrain bed, measured up from the container floor.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// A flat bed of the given depth (m).
    Flat(f64),
    /// Heights (m above the floor) sampled over the container's x–y extent.
    Heightmap(Heightmap),
}

impl Surface {
    /// Soil depth (m) at normalised position `(u, v) ∈ [0, 1]²` across the container.
    pub fn depth_at(&self, u: f64, v: f64) -> f64 {
        match self {
            Self::Flat(d) => *d,
            Self::Heightmap(h) => h.sample(u, v),
        }
    }
    /// Deepest point (m).
    pub fn max_depth(&self) -> f64 {
        match self {
            Self::Flat(d) => *d,
            Self::Heightmap(h) => h.max_height(),
        }
    }
}

/// A region filled with soil of one material.
#[derive(Clone, Debug, PartialEq)]
pub enum SoilRegion {
    /// The bed of a container up to its surface.
    Bed {
        /// The container.
        container: Aabb,
        /// The soil surface.
        surface: Surface,
    },
    /// An axis-aligned block.
    Block(Aabb),
    /// A vertical cylinder (column).
    Cylinder {
        /// Centre of the bottom face (m).
        base_center: [f64; 3],
        /// Radius (m).
        radius: f64,
        /// Height (m).
        height: f64,
    },
}
