//! Particles and wall markers for a terrain scene, on one lattice.
//!
//! Soil particles and container-wall markers share a cubic lattice of spacing d0 anchored at
//! the container's lower corner, so the particle distribution is uniform across the wall. The
//! first marker layer lies on each wall plane, the others behind it; the first soil layer is
//! one spacing in. Each lattice point stands for a d0³ cell, so the soil's effective boundary
//! is d0/2 from the wall plane (Chrono's convention for markers on the surface).
//!
//! Initial stress is geostatic, along the gravity vector it is given: in each lattice column
//! the vertical stress at a particle is the weight of the soil above it (its own half cell
//! included), `σzz = −Σ ρ |g_z| d0`, and `σxx = σyy = K0 σzz` with the particle's material K0.
//! A tilted gravity (a slope modelled by tilting g over a level bed) adds the shear that holds
//! the layer against gravity's tangential part, `σxz = −Σ ρ g_x d0` and `σyz = −Σ ρ g_y d0`
//! (the infinite-slope state: `∂σ_iz/∂z + ρ g_i = 0`), so a tilted bed starts in
//! equilibrium too. MCC points get `p_c0 = OCR · p0` and their specific volume from the
//! compression lines.
//!
//! Water regions (a water material) may overlap soil: a lattice point holding both is
//! saturated, its water particle's partial density `n ρ_w` (n = 1 − ρ / ρ_g of the soil there,
//! 1 in free water). The pore pressure is hydrostatic from the water above the point, the total
//! stress carries the weight of soil and water above, and the soil starts at the effective
//! stress, the total plus the pore pressure (so a saturated bed is buoyed: γ' = γ_sat − γ_w).

use std::collections::{BTreeMap, HashMap};

use regolith_fsi::rheology::{Material, Rheology};
use regolith_fsi::{MarkerInit, ParticleInit};

use crate::{Aabb, SoilRegion, TerrainError};

/// A region, the index of its material and the velocity its particles start with.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionSpec {
    /// Where.
    pub region: SoilRegion,
    /// Material index.
    pub material: u16,
    /// Initial velocity of its particles (m/s).
    pub velocity: [f64; 3],
    /// Isotropic compression its particles start with (Pa) in place of the geostatic state;
    /// `None`: geostatic. MCC points get `p_c0 = OCR · p` and their specific volume at `p`.
    pub initial_pressure: Option<f64>,
}

/// Everything the solver is built from.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainBuild {
    /// Soil particles.
    pub particles: Vec<ParticleInit>,
    /// Wall markers (owner 0).
    pub markers: Vec<MarkerInit>,
    /// The container actually used: its size is a whole number of spacings.
    pub container: Aabb,
    /// The domain the neighbour grid covers; soil leaving it is escaped.
    pub domain: ([f64; 3], [f64; 3]),
    /// Adjustments worth telling the user about.
    pub notes: Vec<String>,
}

/// Lattice geometry of a container.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Origin (the container's lower corner), m.
    pub origin: [f64; 3],
    /// Spacing d0, m.
    pub d0: f64,
    /// Intervals along each axis (the container spans `n · d0`).
    pub n: [i64; 3],
}

impl Lattice {
    /// The lattice of a container, snapped to whole spacings.
    pub fn of(container: &Aabb, d0: f64) -> Self {
        let s = container.size();
        Self { origin: container.min, d0, n: [0, 1, 2].map(|a| ((s[a] / d0).round() as i64).max(4)) }
    }
    /// Position of lattice point `(i, j, k)`.
    pub fn point(&self, c: [i64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + c[a] as f64 * self.d0)
    }
    /// The snapped container.
    pub fn container(&self) -> Aabb {
        Aabb { min: self.origin, max: self.point(self.n) }
    }
}

/// Lattice indices whose coordinate `c` satisfies `lo < c ≤ hi` (cell-centre ownership).
fn index_range(origin: f64, d0: f64, lo: f64, hi: f64) -> (i64, i64) {
    let eps = 1e-9;
    let first = ((lo - origin) / d0 + eps).floor() as i64 + 1;
    let last = ((hi - origin) / d0 + eps).floor() as i64;
    (first, last)
}

/// The soil region and the water region holding a lattice point, if any.
type Occupants = (Option<usize>, Option<usize>);

/// Occupied lattice points and the region (index into the regions) holding each.
type Cells = HashMap<[i64; 3], usize>;

/// Builds soil particles and wall markers.
pub fn build_terrain(
    container: &Aabb,
    spacing: f64,
    bce_layers: usize,
    gravity: [f64; 3],
    regions: &[RegionSpec],
    materials: &[Material<f64>],
) -> Result<TerrainBuild, TerrainError> {
    build_terrain_in(container, spacing, bce_layers, gravity, regions, materials, None)
}

/// Builds the soil particles and wall markers of a slice of the container along x: with
/// `window = Some([a, b])` only the lattice columns `a < i < b` hold soil and the walls are
/// the shell of that slice (its end walls on the planes `i = a` and `i = b`), which is what a
/// moving patch simulates of a longer bed. Each column's state is exactly what
/// [`build_terrain`] gives it (columns are independent: the geostatic stress integrates down
/// a column), so slices laid side by side make up the whole bed. `None`: the whole container
/// (as [`build_terrain`]). A slice may hold no soil; the whole container must.
pub fn build_terrain_in(
    container: &Aabb,
    spacing: f64,
    bce_layers: usize,
    gravity: [f64; 3],
    regions: &[RegionSpec],
    materials: &[Material<f64>],
    window: Option<[i64; 2]>,
) -> Result<TerrainBuild, TerrainError> {
    let lat = Lattice::of(container, spacing);
    let snapped = lat.container();
    let mut notes = Vec::new();
    let moved = (0..3).map(|a| (snapped.max[a] - container.max[a]).abs()).fold(0.0, f64::max);
    if moved > 1e-9 * spacing {
        notes.push(format!(
            "container max snapped from {:?} to {:?} m so that its size is a whole number of spacings",
            container.max, snapped.max
        ));
    }
    let nx = lat.n[0];
    let d0 = spacing;
    // The end-wall planes of the slice (the container's own without a window).
    let [xa, xb] = window.unwrap_or([0, nx]);
    if xa >= xb || xa < 0 || xb > nx {
        return Err(TerrainError::Setup(format!(
            "slice of lattice columns ({xa}, {xb}) is not inside the container's 0..={nx}"
        )));
    }
    if let Some(spec) = regions.iter().find(|r| r.material as usize >= materials.len()) {
        return Err(TerrainError::Setup(format!("material index {} out of range", spec.material)));
    }
    let (cells, water_cells) = occupied(&lat, regions, materials, [xa, xb])?;
    if window.is_none() && cells.is_empty() && water_cells.is_empty() {
        return Err(TerrainError::Setup(
            "the soil regions contain no lattice point: make them larger than the spacing".into(),
        ));
    }
    let particles = geostatic(cells, water_cells, &lat, regions, materials, gravity);
    let l = bce_layers as i64;
    let markers = wall_markers(&lat, [xa, xb], l);
    let h_room = snapped.size()[2];
    let pad = (l as f64 + 3.0) * d0;
    let domain = (
        [snapped.min[0] - pad, snapped.min[1] - pad, snapped.min[2] - pad],
        [snapped.max[0] + pad, snapped.max[1] + pad, snapped.max[2] + h_room + pad],
    );
    Ok(TerrainBuild { particles, markers, container: snapped, domain, notes })
}

/// The occupied interior lattice points of the slice `xa < i < xb` and the region holding
/// each, one map per phase (water shares space with soil); regions of one phase may not
/// overlap.
fn occupied(
    lat: &Lattice,
    regions: &[RegionSpec],
    materials: &[Material<f64>],
    [xa, xb]: [i64; 2],
) -> Result<(Cells, Cells), TerrainError> {
    let [_, ny, nz] = lat.n;
    let d0 = lat.d0;
    let snapped = lat.container();
    let is_water = |r: usize| materials[regions[r].material as usize].is_water();
    let mut cells = Cells::new();
    let mut water_cells = Cells::new();
    let mut overlap = None;
    let mut insert = |c: [i64; 3], r: usize| {
        if c[0] > xa && c[0] < xb && c[1] >= 1 && c[1] < ny && c[2] >= 1 && c[2] < nz {
            let map = if is_water(r) { &mut water_cells } else { &mut cells };
            let held = *map.entry(c).or_insert(r);
            if held != r && overlap.is_none() {
                overlap = Some((held, r, c));
            }
        }
    };
    for (r, spec) in regions.iter().enumerate() {
        match &spec.region {
            SoilRegion::Bed { surface, .. } => {
                let size = snapped.size();
                for i in xa + 1..xb {
                    for j in 1..ny {
                        let p = lat.point([i, j, 0]);
                        let depth =
                            surface.depth_at((p[0] - snapped.min[0]) / size[0], (p[1] - snapped.min[1]) / size[1]);
                        let top = (depth / d0).round() as i64;
                        for k in 1..=top {
                            insert([i, j, k], r);
                        }
                    }
                }
            }
            SoilRegion::Block(b) => {
                let (i0, i1) = index_range(lat.origin[0], d0, b.min[0], b.max[0]);
                let (j0, j1) = index_range(lat.origin[1], d0, b.min[1], b.max[1]);
                let (k0, k1) = index_range(lat.origin[2], d0, b.min[2], b.max[2]);
                for i in i0.max(xa + 1)..=i1.min(xb - 1) {
                    for j in j0..=j1 {
                        for k in k0..=k1 {
                            insert([i, j, k], r);
                        }
                    }
                }
            }
            SoilRegion::Cylinder { base_center: c, radius, height } => {
                let (i0, i1) = index_range(lat.origin[0], d0, c[0] - radius - d0, c[0] + radius + d0);
                let (j0, j1) = index_range(lat.origin[1], d0, c[1] - radius - d0, c[1] + radius + d0);
                let (k0, k1) = index_range(lat.origin[2], d0, c[2], c[2] + height);
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        let p = lat.point([i, j, 0]);
                        if (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) <= radius * radius * (1.0 + 1e-12) {
                            for k in k0..=k1 {
                                insert([i, j, k], r);
                            }
                        }
                    }
                }
            }
        }
    }
    if let Some((first, second, c)) = overlap {
        return Err(TerrainError::Overlap { first, second, at: lat.point(c) });
    }
    Ok((cells, water_cells))
}

/// The soil and water particles of the occupied points, with the geostatic stress integrated
/// column by column from the top: each lattice point holds soil, water or both (a saturated
/// cell).
fn geostatic(
    cells: Cells,
    water_cells: Cells,
    lat: &Lattice,
    regions: &[RegionSpec],
    materials: &[Material<f64>],
    gravity: [f64; 3],
) -> Vec<ParticleInit> {
    let d0 = lat.d0;
    let mut columns: BTreeMap<(i64, i64), BTreeMap<i64, Occupants>> = BTreeMap::new();
    for (c, r) in &cells {
        columns.entry((c[0], c[1])).or_default().entry(c[2]).or_default().0 = Some(*r);
    }
    for (c, r) in &water_cells {
        columns.entry((c[0], c[1])).or_default().entry(c[2]).or_default().1 = Some(*r);
    }
    let mut particles = Vec::with_capacity(cells.len() + water_cells.len());
    for ((i, j), col) in columns {
        // Mass per area of the mixture above the current point (kg/m²), whose weight the
        // total stress carries, and the depth of water above it (m), whose weight its pore
        // pressure carries (hydrostatic below a water table).
        let (mut above, mut water_above) = (0.0, 0.0);
        for (k, (soil, water)) in col.into_iter().rev() {
            let soil_mat = soil.map(|r| &materials[regions[r].material as usize]);
            let water_mat = water.map(|r| &materials[regions[r].material as usize]);
            // The water's partial density: its rest density times the soil's porosity.
            let porosity =
                soil_mat.map_or(1.0, |m| if m.grain_density > 0.0 { 1.0 - m.density / m.grain_density } else { 1.0 });
            let water_rho = water_mat.map_or(0.0, |w| w.density * porosity);
            let half = (soil_mat.map_or(0.0, |m| m.density) + water_rho) * 0.5 * d0;
            let column = above + half;
            above += 2.0 * half;
            let u = water_mat.map_or(0.0, |w| w.density * (water_above + 0.5 * d0) * -gravity[2]).max(0.0);
            if water.is_some() {
                water_above += d0;
            }
            if let (Some(r), Some(mat)) = (soil, soil_mat) {
                let (sigma, p0) = match regions[r].initial_pressure {
                    Some(p) => ([-p, -p, -p, 0.0, 0.0, 0.0], p),
                    None => {
                        // Effective stress: the total minus the pore pressure.
                        let sv = column * gravity[2] + u;
                        let (sxz, syz) = (-column * gravity[0], -column * gravity[1]);
                        let sh = mat.k0() * sv;
                        ([sh, sh, sv, 0.0, sxz, syz], -(sv + 2.0 * sh) / 3.0)
                    }
                };
                let st = mat.initial_state(p0);
                particles.push(ParticleInit {
                    pos: lat.point([i, j, k]),
                    vel: regions[r].velocity,
                    rho: mat.density,
                    mass: mat.density * d0 * d0 * d0,
                    sigma,
                    pc: if matches!(mat.rheology, Rheology::Mcc(_)) { st.pc } else { 0.0 },
                    specific_volume: st.v,
                    material: regions[r].material,
                });
            }
            if let Some(r) = water {
                particles.push(ParticleInit {
                    pos: lat.point([i, j, k]),
                    vel: regions[r].velocity,
                    rho: water_rho,
                    mass: water_rho * d0 * d0 * d0,
                    sigma: [-u, -u, -u, 0.0, 0.0, 0.0],
                    pc: 0.0,
                    specific_volume: 1.0,
                    material: regions[r].material,
                });
            }
        }
    }
    particles
}

/// The container's wall markers for the slice between the end-wall planes `i = xa` and
/// `i = xb`: `l` layers behind the floor, the side walls and the end walls (no lid).
fn wall_markers(lat: &Lattice, [xa, xb]: [i64; 2], l: i64) -> Vec<MarkerInit> {
    let [_, ny, nz] = lat.n;
    let mut markers = Vec::new();
    for i in xa - (l - 1)..=(xb + l - 1) {
        for j in -(l - 1)..=(ny + l - 1) {
            for k in -(l - 1)..=nz {
                if i <= xa || i >= xb || j <= 0 || j >= ny || k <= 0 {
                    markers.push(MarkerInit { pos: lat.point([i, j, k]), owner: 0 });
                }
            }
        }
    }
    markers
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Surface;
    use regolith_fsi::rheology::MaterialParams;

    fn dp() -> Material<f64> {
        MaterialParams {
            model: Some(regolith_fsi::rheology::ModelKind::DruckerPrager),
            density: Some(1600.0),
            youngs_modulus: Some(1e7),
            poisson_ratio: Some(0.3),
            friction_angle: Some(30.0),
            ..Default::default()
        }
        .build()
        .expect("valid")
    }

    /// A 0.2 × 0.1 × 0.2 m container with a flat bed of dp() soil 0.1 m deep.
    fn flat_bed() -> (Aabb, [RegionSpec; 1]) {
        let c = Aabb { min: [0.0; 3], max: [0.2, 0.1, 0.2] };
        let bed = RegionSpec {
            region: SoilRegion::Bed { container: c, surface: Surface::Flat(0.1) },
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: None,
        };
        (c, [bed])
    }

    #[test]
    fn bed_has_the_right_count_and_geostatic_stress() {
        let (c, regions) = flat_bed();
        let b = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &regions, &[dp()]).expect("builds");
        // 19 × 9 interior columns, 10 layers.
        assert_eq!(b.particles.len(), 19 * 9 * 10);
        let bottom = b.particles.iter().find(|p| (p.pos[2] - 0.01).abs() < 1e-12).expect("bottom");
        // 9.5 cells of soil above the bottom particle's centre.
        assert!((bottom.sigma[2] + 1600.0 * 9.81 * 0.095).abs() < 1e-9);
        assert!((bottom.sigma[0] / bottom.sigma[2] - 0.5).abs() < 1e-12);
        // Wall shell: floor and four walls, 3 layers, up to the container top.
        assert!(b.markers.iter().all(|m| m.pos[2] <= 0.2 + 1e-12 && m.pos[2] >= -0.02 - 1e-12));
        assert!(b.notes.is_empty());
    }

    #[test]
    fn a_tilted_gravity_gives_the_infinite_slope_state() {
        // g tilted by 10° about y (a 10° slope rising towards +x) and 4° about x.
        let (c, regions) = flat_bed();
        let (a, b) = (10f64.to_radians(), 4f64.to_radians());
        let g = [-9.81 * a.sin(), 9.81 * b.sin(), -9.81 * a.cos() * b.cos()];
        let built = build_terrain(&c, 0.01, 3, g, &regions, &[dp()]).expect("builds");
        for p in &built.particles {
            // Mass per area above the particle's centre (its own half cell included).
            let w = 1600.0 * (0.1 - p.pos[2] + 0.005);
            let want = [0.5 * w * g[2], 0.5 * w * g[2], w * g[2], 0.0, -w * g[0], -w * g[1]];
            for (k, (got, want)) in p.sigma.iter().zip(want).enumerate() {
                assert!((got - want).abs() < 1e-9 * w * 9.81, "σ[{k}] at z = {}: {got} vs {want}", p.pos[2]);
            }
            // Tangential over normal traction on a horizontal plane is tan of the tilt.
            assert!((p.sigma[4] / p.sigma[2] + a.tan() / b.cos()).abs() < 1e-12);
        }
    }

    #[test]
    fn slices_laid_side_by_side_make_up_the_whole_bed() {
        // A bed with a block on it, so that columns differ in height and stress.
        let (c, [bed]) = flat_bed();
        let block = RegionSpec {
            region: SoilRegion::Block(Aabb { min: [0.04, 0.0, 0.1], max: [0.12, 0.1, 0.15] }),
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: None,
        };
        let regions = [bed, block];
        let g = [0.0, 0.0, -9.81];
        let whole = build_terrain(&c, 0.01, 3, g, &regions, &[dp()]).expect("builds");
        let nx = Lattice::of(&c, 0.01).n[0];
        let key = |p: &ParticleInit| p.pos.map(|x| (x * 1e6).round() as i64);
        let mut parts = Vec::new();
        // Columns a < i < b of each: 1..=6, 7, 8..nx (a slice's end walls are its
        // neighbours' first and last columns).
        for w in [[0, 7], [6, 8], [7, nx]] {
            let slice = build_terrain_in(&c, 0.01, 3, g, &regions, &[dp()], Some(w)).expect("slice");
            let x = |i: i64| i as f64 * 0.01;
            assert!(slice.particles.iter().all(|p| p.pos[0] > x(w[0]) && p.pos[0] < x(w[1])), "{w:?}");
            // The slice's shell: its end walls on x(a) and x(b), three layers deep.
            let (lo, hi) =
                slice.markers.iter().fold((f64::MAX, f64::MIN), |(l, h), m| (l.min(m.pos[0]), h.max(m.pos[0])));
            assert!((lo - x(w[0] - 2)).abs() < 1e-12 && (hi - x(w[1] + 2)).abs() < 1e-12, "{w:?}: {lo} {hi}");
            assert_eq!(slice.domain, whole.domain);
            parts.extend(slice.particles);
        }
        let mut a = whole.particles.clone();
        a.sort_by_key(key);
        parts.sort_by_key(key);
        assert!(a == parts, "the slices hold {} particles, the whole bed {}", parts.len(), a.len());
        // A window outside the container is refused.
        assert!(build_terrain_in(&c, 0.01, 3, g, &regions, &[dp()], Some([5, nx + 1])).is_err());
        assert!(build_terrain_in(&c, 0.01, 3, g, &regions, &[dp()], Some([5, 5])).is_err());
    }

    #[test]
    fn cylinder_and_block_fill_their_volume() {
        let c = Aabb { min: [0.0; 3], max: [0.6, 0.6, 0.3] };
        let regions = [RegionSpec {
            region: SoilRegion::Cylinder { base_center: [0.3, 0.3, 0.0], radius: 0.1, height: 0.1 },
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: None,
        }];
        let b = build_terrain(&c, 0.005, 3, [0.0, 0.0, -9.81], &regions, &[dp()]).expect("builds");
        let expect = std::f64::consts::PI * 0.01 * 0.1 / 0.005f64.powi(3);
        assert!((b.particles.len() as f64 - expect).abs() / expect < 0.01, "{} vs {expect}", b.particles.len());
        let top = b.particles.iter().map(|p| p.pos[2]).fold(0.0, f64::max);
        assert!((top - 0.1).abs() < 1e-9);
    }

    #[test]
    fn overlapping_regions_are_refused_and_touching_ones_are_not() {
        let c = Aabb { min: [0.0; 3], max: [0.1, 0.1, 0.3] };
        let bed = RegionSpec {
            region: SoilRegion::Bed { container: c, surface: Surface::Flat(0.1) },
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: None,
        };
        let block = |z0: f64| RegionSpec {
            region: SoilRegion::Block(Aabb { min: [0.0, 0.0, z0], max: [0.05, 0.05, 0.2] }),
            material: 0,
            velocity: [2.0, 0.0, -1.0],
            initial_pressure: None,
        };
        let err =
            build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &[bed.clone(), block(0.09)], &[dp()]).expect_err("overlap");
        assert!(
            matches!(err, TerrainError::Overlap { first: 0, second: 1, at } if (at[2] - 0.1).abs() < 1e-9),
            "{err}"
        );
        // Touching at z = 0.1: the block's particles carry its velocity, the bed's are at rest.
        let b = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &[bed, block(0.1)], &[dp()]).expect("builds");
        let moving = b.particles.iter().filter(|p| p.vel == [2.0, 0.0, -1.0]).count();
        let resting = b.particles.iter().filter(|p| p.vel == [0.0; 3]).count();
        assert_eq!(moving, 5 * 5 * 10, "block 5 x 5 x 10 cm: points with lo < x ≤ hi");
        assert_eq!(resting, 9 * 9 * 10, "bed");
        assert!(b.particles.iter().filter(|p| p.vel != [0.0; 3]).all(|p| p.pos[2] > 0.1 + 1e-9));
    }

    #[test]
    fn layered_materials_carry_the_weight_of_each_layer() {
        let light = dp();
        let mut heavy = dp();
        heavy.density = 2400.0;
        let c = Aabb { min: [0.0; 3], max: [0.1, 0.1, 0.3] };
        // Heavy bed 0.1 m deep, light block 0.1 m on top of it.
        let regions = [
            RegionSpec {
                region: SoilRegion::Block(Aabb { min: [0.0, 0.0, 0.1], max: [0.1, 0.1, 0.2] }),
                material: 1,
                velocity: [0.0; 3],
                initial_pressure: None,
            },
            RegionSpec {
                region: SoilRegion::Bed { container: c, surface: Surface::Flat(0.1) },
                material: 0,
                velocity: [0.0; 3],
                initial_pressure: None,
            },
        ];
        let b = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &regions, &[heavy, light]).expect("builds");
        let at = |z: f64| {
            b.particles
                .iter()
                .find(|p| {
                    (p.pos[2] - z).abs() < 1e-9 && (p.pos[0] - 0.05).abs() < 1e-9 && (p.pos[1] - 0.05).abs() < 1e-9
                })
                .copied()
                .expect("particle")
        };
        // Top of the light block: half a cell of light soil.
        assert!((at(0.2).sigma[2] + 1600.0 * 9.81 * 0.005).abs() < 1e-9);
        assert_eq!(at(0.2).material, 1);
        // Bottom particle: 10 cells of light soil and 9.5 of heavy soil above its centre.
        let expect = 1600.0 * 9.81 * 0.1 + 2400.0 * 9.81 * 0.095;
        assert!((at(0.01).sigma[2] + expect).abs() < 1e-9, "{}", at(0.01).sigma[2]);
        assert_eq!(at(0.01).material, 0);
        assert!((at(0.01).mass - 2400.0 * 1e-6).abs() < 1e-15);
    }

    #[test]
    fn container_is_snapped_to_whole_spacings_with_a_note() {
        let c = Aabb { min: [0.0; 3], max: [0.205, 0.1, 0.1] };
        let regions = [RegionSpec {
            region: SoilRegion::Block(Aabb { min: [0.0; 3], max: [0.1, 0.1, 0.05] }),
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: None,
        }];
        let b = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &regions, &[dp()]).expect("builds");
        assert_eq!(b.notes.len(), 1);
        assert!((b.container.max[0] - 0.2).abs() < 1e-12 || (b.container.max[0] - 0.21).abs() < 1e-12);
    }

    #[test]
    fn a_pressurised_block_starts_isotropic_with_its_ocr() {
        let clay = MaterialParams {
            model: Some(regolith_fsi::rheology::ModelKind::Mcc),
            density: Some(1800.0),
            youngs_modulus: Some(5e6),
            poisson_ratio: Some(0.3),
            mcc_m: Some(1.2),
            mcc_lambda: Some(0.1),
            mcc_kappa: Some(0.02),
            mcc_v_lambda: Some(2.2),
            ocr: Some(3.0),
            ..Default::default()
        }
        .build()
        .expect("valid");
        let c = Aabb { min: [0.0; 3], max: [0.1, 0.1, 0.1] };
        let block = |p| RegionSpec {
            region: SoilRegion::Block(Aabb { min: [0.0; 3], max: [0.05, 0.05, 0.05] }),
            material: 0,
            velocity: [0.0; 3],
            initial_pressure: p,
        };
        // Gravity is ignored for a pressurised block: every particle holds −p I.
        let b = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &[block(Some(2e4))], std::slice::from_ref(&clay))
            .expect("builds");
        let expect = clay.initial_state(2e4);
        assert!(expect.pc > 5.9e4 && expect.pc < 6.1e4, "p_c0 = OCR p = 6e4 Pa: {}", expect.pc);
        for q in &b.particles {
            assert_eq!(q.sigma, [-2e4, -2e4, -2e4, 0.0, 0.0, 0.0]);
            assert_eq!((q.pc, q.specific_volume), (expect.pc, expect.v));
        }
        // Without it: geostatic, p_c0 from the (small) overburden.
        let g = build_terrain(&c, 0.01, 3, [0.0, 0.0, -9.81], &[block(None)], &[clay]).expect("builds");
        assert!(g.particles.iter().all(|q| q.sigma[2] < 0.0 && q.sigma[2] > -1e3 && q.pc < 1e4));
    }
}
