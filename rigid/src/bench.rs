//! The carving benchmark: `ShapeDesc::contains_points` on a closed, non-convex mesh against a
//! lattice, the query that carves a mesh body out of the soil when a scene starts. Run by
//! `regolith bench --carve` and `cargo run --release -p regolith-rigid --example carve_bench`.

use std::time::Instant;

use crate::ShapeDesc;

/// What one carving run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CarveBench {
    /// Triangles of the torus mesh.
    pub triangles: usize,
    /// Lattice points tested.
    pub points: usize,
    /// Lattice spacing (m).
    pub spacing: f64,
    /// Margin the body was grown by (m).
    pub margin: f64,
    /// Points inside the grown body.
    pub removed: usize,
    /// Wall time of `contains_points`, the mesh's BVH build included (s).
    pub seconds: f64,
}

/// A torus (R = 0.3 m, r = 0.1 m) of about `triangles` triangles against a lattice of about
/// `points` cell centres filling its box grown by r/10, the body grown by `margin_spacings`
/// lattice spacings (0.5 is what a scene grows a body by).
pub fn carve_torus(triangles: usize, points: usize, margin_spacings: f64) -> CarveBench {
    let (major, minor) = (0.3, 0.1);
    let tri = triangles as f64;
    // Near-square quads: `around / across ≈ major / minor`, 2 · around · across triangles.
    let across = (tri / (2.0 * major / minor)).sqrt().round().max(3.0);
    let around = (tri / (2.0 * across)).round().max(3.0);
    let torus = ShapeDesc::torus_mesh(major, minor, around as u32, across as u32);
    let ShapeDesc::Mesh { vertices, indices } = &torus else { return CarveBench::default() };
    let triangles = indices.len();
    // The lattice: cell centres filling the mesh's box grown by a tenth of the tube radius.
    let pad = 0.1 * minor;
    let lo = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MAX, f64::min) - pad);
    let hi = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MIN, f64::max) + pad);
    let size = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let d0 = (size[0] * size[1] * size[2] / points.max(1) as f64).cbrt();
    let n = size.map(|s| ((s / d0).round() as usize).max(1));
    let mut lattice = Vec::with_capacity(n[0] * n[1] * n[2]);
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let c = [i, j, k].map(|x| x as f64 + 0.5);
                lattice.push([lo[0] + c[0] * d0, lo[1] + c[1] * d0, lo[2] + c[2] * d0]);
            }
        }
    }
    let margin = margin_spacings * d0;
    let t = Instant::now();
    let inside = torus.contains_points(&lattice, margin);
    let seconds = t.elapsed().as_secs_f64();
    CarveBench {
        triangles,
        points: lattice.len(),
        spacing: d0,
        margin,
        removed: inside.iter().filter(|x| **x).count(),
        seconds,
    }
}
