//! `summary.json`: what a run did, in one file.

use regolith_fsi::{Real, SphSolver};
use regolith_terrain::SoilRegion;
use serde::Serialize;

use crate::rig::bekker::BekkerFit;
use crate::scene::Scene;

/// Version of the `summary.json` layout.
pub const SUMMARY_SCHEMA_VERSION: u32 = 1;

/// A body's final state in the summary.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BodySummary {
    /// Name.
    pub name: String,
    /// Centre of mass at the end (m).
    pub position: [f64; 3],
    /// Centre-of-mass velocity at the end (m/s).
    pub velocity: [f64; 3],
    /// Mean soil force over the last exchange interval (N).
    pub fsi_force: [f64; 3],
    /// Mean soil torque about the centre of mass over the last exchange interval (N m).
    pub fsi_torque: [f64; 3],
}

/// Runout of an axisymmetric column collapse.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Runout {
    /// Column axis (x, y), m.
    pub axis: [f64; 2],
    /// Initial radius R0 (m), the column's nominal radius.
    pub initial_radius: f64,
    /// Initial height h0 (m).
    pub initial_height: f64,
    /// Aspect ratio a = h0 / R0.
    pub aspect_ratio: f64,
    /// Final radius R∞ of the deposit (m): R0 plus the growth of the radius that holds 99 % of
    /// the particles (plus half a spacing).
    pub final_radius: f64,
    /// (R∞ − R0) / R0.
    pub normalized: f64,
    /// Lube et al. (2004): 1.24 a for a ≲ 1.7, 1.6 a^(1/2) above.
    pub lube_2004: f64,
    /// Final deposit height at the axis (m).
    pub final_height: f64,
}

/// A plane-strain collapse: a block of soil against one end wall of the container, released
/// towards the other (Bui et al. 2008's aluminium-bar test). Lengths are along x from that
/// wall.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Slump {
    /// x of the wall the block leaned on (m).
    pub wall_x: f64,
    /// +1 when the soil runs out towards +x, −1 towards −x.
    pub direction: f64,
    /// Initial length L0 of the block along x (m).
    pub initial_length: f64,
    /// Initial height H0 (m).
    pub initial_height: f64,
    /// Final length L∞ from the wall to the toe (m): L0 plus the growth of the distance that
    /// holds 99 % of the particles (the estimator of [`Runout`], applied to both states).
    pub final_length: f64,
    /// (L∞ − L0) / L0.
    pub normalized: f64,
    /// Final height of the deposit at the wall (m).
    pub final_height: f64,
    /// Distance from the wall at which the deposit's thickness has fallen to a tenth of H0
    /// (m). The thickness of columns H0 / 5 long (or d0, if larger) is their particles'
    /// lattice volume (d0³ each) over the column's floor area (its length × the lattice's
    /// width, the initial particles' volume over L0 H0), so it varies in steps far finer than
    /// d0 and the same columns serve every level of a d0 ladder. The crossing is interpolated
    /// between the farthest column at or above the level and the next one out (so a deposit
    /// that slid off the wall, thin there and thick farther out, still reads its front).
    /// Unlike the 99 % reach it does not hang on the sparse grains of a thin tail, and a
    /// digitised experimental profile gives it too.
    pub reach_tenth: f64,
    /// (reach_tenth − L0) / L0.
    pub reach_tenth_normalized: f64,
    /// Angle of the failure surface with the horizontal (degrees): the slope of the boundary
    /// between soil that moved more than `moved_threshold` and soil that did not, fitted by
    /// least squares over the initial lattice rows between 10 % and 90 % of H0 (each row's
    /// boundary placed at its fraction of unmoved particles times L0). `None` when fewer than
    /// three rows hold both.
    pub failure_angle_deg: Option<f64>,
    /// Displacement above which a particle counts as moved (m): 1.5 % of H0 (1.5 mm in Bui et
    /// al.'s 0.1 m body, the bars' size, which is how the experiment's undisturbed region was
    /// read).
    pub moved_threshold: f64,
    /// Rows the angle was fitted over.
    pub failure_rows: usize,
}

/// The stresses of a flat bed at mid-depth against the geostatic state: the closed form
/// σv = ρ g depth and σh = K0 σv. Read from the particles of the lattice layer nearest
/// mid-depth, three spacings or more from the side walls (the walls' own stress layer is left
/// out); depth is measured from the top particle plus half a spacing.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Geostatic {
    /// Depth of the measured layer below the soil surface (m).
    pub depth: f64,
    /// Particles averaged.
    pub particles: usize,
    /// Mean vertical stress −σzz there (Pa, compression positive).
    pub sigma_v: f64,
    /// The closed form ρ |g| depth (Pa), with the material's reference density.
    pub sigma_v_expected: f64,
    /// σv over its closed form.
    pub sigma_v_ratio: f64,
    /// Mean horizontal over vertical stress, (σxx + σyy) / (2 σzz).
    pub k_ratio: f64,
    /// The material's at-rest coefficient K0 (Jáky's 1 − sin φ for frictional models).
    pub k0: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Summary {
    /// Layout version.
    pub schema_version: u32,
    /// Scene file.
    pub scene: String,
    /// Backend that ran.
    pub backend: String,
    /// Device adapter (`cpu` for the CPU backend).
    pub adapter: String,
    /// Precision.
    pub precision: String,
    /// Soil particles at the start.
    pub particles: usize,
    /// Wall and body markers.
    pub markers: usize,
    /// Steps taken.
    pub steps: u64,
    /// Soil particles integrated, summed over the steps (the awake ones when an active region
    /// is kept).
    pub particle_steps: f64,
    /// Simulated time reached (s).
    pub sim_time: f64,
    /// Wall-clock time of the stepping loop (s).
    pub wall_time_s: f64,
    /// Soil particles × steps per wall-clock second.
    pub particle_steps_per_s: f64,
    /// Mean listed neighbour pairs per rate evaluation (within 2h + the Verlet skin, so more
    /// than the pairs inside the support when `sph.neighbor_skin > 0`).
    pub neighbour_pairs: f64,
    /// Smallest and largest step (s).
    pub dt_min: f64,
    /// Largest step (s).
    pub dt_max: f64,
    /// Largest particle speed at the end (m/s).
    pub max_speed: f64,
    /// Largest particle speed during the run (m/s).
    pub max_speed_run: f64,
    /// Soil mass at the start (kg): the total held at the end, escaped particles included, which
    /// is the start's unless a moving patch lifted and laid soil or the first step set the
    /// water's masses (wet scenes).
    pub mass_initial: f64,
    /// Soil mass still in the domain at the end (kg).
    pub mass_final: f64,
    /// Particles that left the domain.
    pub escaped_particles: usize,
    /// Most soil particles held at the density floor in one step
    /// (`regolith_fsi::config::RAREFIED_DENSITY`: spread to half their bulk density, a
    /// splash's grains in flight).
    pub rarefied_max: usize,
    /// The active region, when the scene keeps one (`[sph.active]`).
    pub active_domain: Option<ActiveSummary>,
    /// The moving patch, when the scene has one (`[terrain] patch`).
    pub patch: Option<PatchSummary>,
    /// True when the run stopped on a non-finite value.
    pub nan_detected: bool,
    /// The error that stopped the run, if any.
    pub error: Option<String>,
    /// Column-collapse runout, for scenes whose soil is one cylinder.
    pub runout: Option<Runout>,
    /// Plane-strain collapse, for scenes whose soil is one block against an end wall.
    pub slump: Option<Slump>,
    /// Mid-depth stresses of a bed at rest, for scenes whose soil is one flat bed and that
    /// hold no body.
    pub geostatic: Option<Geostatic>,
    /// Bodies at the end.
    pub bodies: Vec<BodySummary>,
    /// The rig's report, if the scene has a rig.
    pub rig: Option<serde_json::Value>,
    /// Bekker pressure–sinkage fit of a plate rig.
    pub bekker: Option<BekkerFit>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Adjustments made while building (e.g. container snapping).
    pub notes: Vec<String>,
}

/// How many particles an active region integrated.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ActiveSummary {
    /// Fewest integrated in a step.
    pub awake_min: usize,
    /// Most integrated in a step.
    pub awake_max: usize,
    /// Integrated in the last step.
    pub awake_final: usize,
    /// Mean over steps (particle-steps / steps).
    pub awake_mean: f64,
    /// Soil particles inside the domain at the end (awake, extended and asleep).
    pub inside_final: usize,
    /// Classifications made.
    pub classifications: u64,
}

/// Where a moving patch went and how much soil it moved.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PatchSummary {
    /// Length held (m).
    pub length: f64,
    /// Soil kept ahead of the foremost FSI body (m).
    pub trigger: f64,
    /// x of its back and front end walls at the end (m).
    pub span_final: [f64; 2],
    /// Times it advanced.
    pub advances: u64,
    /// Particles lifted behind it, in all.
    pub lifted: u64,
    /// Particles laid ahead of it, in all.
    pub laid: u64,
}

/// The distance within which 99 % of `distances` lie, plus half a spacing (the extent of the
/// outermost particles' cells). The same estimator is applied to the initial and the final
/// soil, so lattice effects cancel in their difference.
fn reach_99(distances: impl Iterator<Item = f64>, d0: f64) -> f64 {
    let mut d: Vec<f64> = distances.collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_by(f64::total_cmp);
    let k = ((d.len() as f64 * 0.99).ceil() as usize).clamp(1, d.len()) - 1;
    d[k] + 0.5 * d0
}

/// The radius within which 99 % of the particles lie about an axis ([`reach_99`]).
fn deposit_radius(points: impl Iterator<Item = [f64; 3]>, axis: [f64; 2], d0: f64) -> f64 {
    reach_99(points.map(|p| ((p[0] - axis[0]).powi(2) + (p[1] - axis[1]).powi(2)).sqrt()), d0)
}

/// The soil particles still in the domain (water left out) by original id: what a
/// displacement field is measured on.
pub(super) fn soil_by_id<T: Real>(s: &dyn SphSolver<T>) -> Vec<(u32, [f64; 3])> {
    let (mats, ids) = (s.materials(), s.material_ids());
    (0..s.active())
        .filter(|&i| !mats[ids[i] as usize].is_water())
        .map(|i| (s.ids()[i], s.positions()[i].as_f64()))
        .collect()
}

/// The plane-strain collapse of a scene whose soil is one block with a container end wall
/// (x) within half a spacing of one of its x faces; `None` otherwise, and for a block that
/// touches both.
pub(super) fn slump(scene: &Scene, initial: &[(u32, [f64; 3])], last: &[(u32, [f64; 3])]) -> Option<Slump> {
    let mut soil = scene.soil.iter().filter(|s| !scene.materials[s.material].is_water());
    let (Some(only), None) = (soil.next(), soil.next()) else { return None };
    let SoilRegion::Block(b) = only.region else { return None };
    let c = scene.container.as_ref()?;
    if !scene.container_walls {
        return None;
    }
    let d0 = scene.solver.spacing;
    let (at_min, at_max) = ((b.min[0] - c.min[0]).abs() < 0.5 * d0, (c.max[0] - b.max[0]).abs() < 0.5 * d0);
    let (wall_x, dir) = match (at_min, at_max) {
        (true, false) => (c.min[0], 1.0),
        (false, true) => (c.max[0], -1.0),
        _ => return None,
    };
    let (l0, h0, base) = (b.max[0] - b.min[0], b.max[2] - b.min[2], b.min[2]);
    let l0_est = reach_99(initial.iter().map(|(_, p)| dir * (p[0] - wall_x)), d0);
    let lf_est = reach_99(last.iter().map(|(_, p)| dir * (p[0] - wall_x)), d0);
    let lf = l0 + (lf_est - l0_est);
    let final_height = last
        .iter()
        .filter(|(_, p)| dir * (p[0] - wall_x) < 1.5 * d0)
        .map(|(_, p)| p[2] - base + 0.5 * d0)
        .fold(0.0, f64::max);
    // The lattice's own width: the generator fits whole spacings into the block, so the
    // block's nominal width can hold one layer fewer than it seems to (the initial column then
    // reads H0 from its particles, whatever the fit).
    let width = initial.len() as f64 * d0.powi(3) / (l0 * h0);
    // Columns a fifth of H0 long whatever d0 (2 cm in Bui's body): a column one spacing long
    // holds few particles at the coarse levels, and its count's scatter moved the crossing by
    // up to 6 cm at d0 = 1 cm.
    let bin = (0.2 * h0).max(d0);
    let reach_tenth = tenth_height_reach(last.iter().map(|(_, p)| dir * (p[0] - wall_x)), h0, d0, width, bin);
    // Displacements by id; each initial lattice row's share of unmoved particles.
    let threshold = 0.015 * h0;
    let end: std::collections::HashMap<u32, [f64; 3]> = last.iter().copied().collect();
    let zmin = initial.iter().map(|(_, p)| p[2]).fold(f64::INFINITY, f64::min);
    let mut rows: std::collections::BTreeMap<i64, (usize, usize, f64)> = Default::default();
    for (id, p) in initial {
        let moved = end
            .get(id)
            .is_none_or(|q| ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt() > threshold);
        let r = rows.entry(((p[2] - zmin) / d0).round() as i64).or_insert((0, 0, 0.0));
        r.0 += 1;
        r.1 += usize::from(!moved);
        r.2 = p[2] - base;
    }
    let pts: Vec<(f64, f64)> = rows
        .values()
        .filter(|(n, still, z)| *still > 0 && still < n && *z > 0.1 * h0 && *z < 0.9 * h0)
        .map(|(n, still, z)| (*z, *still as f64 / *n as f64 * l0))
        .collect();
    let failure_angle_deg = (pts.len() >= 3).then(|| {
        let m = pts.len() as f64;
        let (mz, mx) = (pts.iter().map(|p| p.0).sum::<f64>() / m, pts.iter().map(|p| p.1).sum::<f64>() / m);
        let szz: f64 = pts.iter().map(|p| (p.0 - mz).powi(2)).sum();
        let szx: f64 = pts.iter().map(|p| (p.0 - mz) * (p.1 - mx)).sum();
        // x_b = a + (dx/dz) z; the surface rises at atan(1 / |dx/dz|) from the horizontal.
        (szz / szx.abs()).atan().to_degrees()
    });
    Some(Slump {
        wall_x,
        direction: dir,
        initial_length: l0,
        initial_height: h0,
        final_length: lf,
        normalized: (lf - l0) / l0,
        final_height,
        reach_tenth,
        reach_tenth_normalized: (reach_tenth - l0) / l0,
        failure_angle_deg,
        moved_threshold: threshold,
        failure_rows: pts.len(),
    })
}

/// See [`Slump::reach_tenth`]: `points` are distances from the wall; each particle stands for
/// a lattice cell d0³ spread over a column `bin` long and `width` wide.
fn tenth_height_reach(points: impl Iterator<Item = f64>, h0: f64, d0: f64, width: f64, bin: f64) -> f64 {
    let mut thick: Vec<f64> = Vec::new();
    for x in points {
        // Soil behind the wall's plane, or not finite after a failed run, has no column.
        if !(x >= 0.0 && x.is_finite()) {
            continue;
        }
        let k = (x / bin) as usize;
        if thick.len() <= k {
            thick.resize(k + 1, 0.0);
        }
        thick[k] += d0.powi(3) / (width * bin);
    }
    // Past the farthest particle the deposit has no height.
    thick.push(0.0);
    let level = 0.1 * h0;
    let centre = |k: usize| (k as f64 + 0.5) * bin;
    // The farthest column at or above the level (a deposit that slid off the wall may be thin
    // there and thick farther out), and the crossing towards the next one.
    match thick.iter().rposition(|t| *t >= level) {
        Some(k) => {
            let next = thick.get(k + 1).copied().unwrap_or(0.0);
            centre(k) + (thick[k] - level) / (thick[k] - next).max(f64::MIN_POSITIVE) * bin
        }
        None => 0.0,
    }
}

/// The runout of a scene whose soil is one cylinder (water blocks aside: a saturated column
/// is measured on its soil), from the soil's positions at the start and at the end.
pub(super) fn column_runout(scene: &Scene, initial: &[[f64; 3]], last: &[[f64; 3]]) -> Option<Runout> {
    let mut soil = scene.soil.iter().filter(|s| !scene.materials[s.material].is_water());
    let (Some(only), None) = (soil.next(), soil.next()) else { return None };
    let SoilRegion::Cylinder { base_center, height, radius } = only.region else { return None };
    let axis = [base_center[0], base_center[1]];
    let d0 = scene.solver.spacing;
    // The lattice disc has the area of the nominal circle; the percentile estimator reads its
    // edge a little outside. Measuring both states with it and adding the difference to the
    // nominal radius cancels that bias.
    let r0_est = deposit_radius(initial.iter().copied(), axis, d0);
    let rf_est = deposit_radius(last.iter().copied(), axis, d0);
    let r0 = radius;
    let rf = r0 + (rf_est - r0_est);
    let a = height / r0;
    let lube = if a <= 1.7 { 1.24 * a } else { 1.6 * a.sqrt() };
    let near_axis = last
        .iter()
        .filter(|p| ((p[0] - axis[0]).powi(2) + (p[1] - axis[1]).powi(2)).sqrt() < 1.5 * d0)
        .map(|p| p[2] - base_center[2] + 0.5 * d0)
        .fold(0.0, f64::max);
    Some(Runout {
        axis,
        initial_radius: r0,
        initial_height: height,
        aspect_ratio: a,
        final_radius: rf,
        normalized: (rf - r0) / r0,
        lube_2004: lube,
        final_height: near_axis,
    })
}

/// The mid-depth state of a flat bed at rest (see [`Geostatic`]); `None` for other scenes, and
/// when the layer holds no central particle (a box narrower than six spacings).
pub(super) fn geostatic_state<T: Real>(scene: &Scene, s: &dyn SphSolver<T>) -> Option<Geostatic> {
    if scene.soil.len() != 1 || !scene.bodies.is_empty() || scene.rig.is_some() {
        return None;
    }
    let SoilRegion::Bed { container, surface: regolith_terrain::Surface::Flat(_) } = &scene.soil[0].region else {
        return None;
    };
    let g = scene.solver.gravity;
    if g[0] != 0.0 || g[1] != 0.0 || g[2] >= 0.0 {
        return None;
    }
    let d0 = scene.solver.spacing;
    let n = s.active();
    let pos = &s.positions()[..n];
    let zmax = pos.iter().map(|p| p.as_f64()[2]).fold(f64::MIN, f64::max);
    let zmin = pos.iter().map(|p| p.as_f64()[2]).fold(f64::MAX, f64::min);
    let top = zmax + 0.5 * d0;
    // The lattice layer (zmin + k d0) nearest mid-depth of the particle centres.
    let mid_z = zmin + ((0.5 * (zmax - zmin)) / d0).round() * d0;
    let (lo, hi) = (container.min, container.max);
    let (mut sv, mut sh, mut z_sum, mut count) = (0.0, 0.0, 0.0, 0usize);
    for (i, p) in pos.iter().enumerate() {
        let p = p.as_f64();
        let central =
            p[0] > lo[0] + 3.0 * d0 && p[0] < hi[0] - 3.0 * d0 && p[1] > lo[1] + 3.0 * d0 && p[1] < hi[1] - 3.0 * d0;
        if central && (p[2] - mid_z).abs() < 0.25 * d0 {
            let sig = s.stresses()[i].as_f64();
            sv -= sig[2];
            sh -= 0.5 * (sig[0] + sig[1]);
            z_sum += p[2];
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let c = count as f64;
    let material = &s.materials()[scene.soil[0].material];
    let depth = top - z_sum / c;
    let expected = material.density.as_f64() * (-g[2]) * depth;
    Some(Geostatic {
        depth,
        particles: count,
        sigma_v: sv / c,
        sigma_v_expected: expected,
        sigma_v_ratio: sv / c / expected,
        k_ratio: sh / sv,
        k0: material.k0().as_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block 0.2 m long and 0.1 m high against the wall at x = 0, on a 5 mm lattice.
    fn block_scene(d0: f64) -> Scene {
        let text = format!(
            "[simulation]\nend_time = 0.1\n\n[sph]\nspacing = {d0}\n\n[[materials]]\nname = \"bars\"\n\
             model = \"drucker-prager\"\ndensity = 2650\nyoungs_modulus = 8.4e5\npoisson_ratio = 0.3\n\
             friction_angle = 19.8\n\n[container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.6, 0.02, 0.15]\n\n\
             [[soil_blocks]]\nmaterial = \"bars\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.02, 0.1]\n"
        );
        crate::scene::load_scene_source(std::path::Path::new("slump.toml"), &text, &[]).expect("scene")
    }

    fn lattice(d0: f64) -> Vec<(u32, [f64; 3])> {
        let mut pts = Vec::new();
        for i in 0..40 {
            for j in 0..4 {
                for k in 0..20 {
                    let p = [(i as f64 + 0.5) * d0, (j as f64 + 0.5) * d0, (k as f64 + 0.5) * d0];
                    pts.push((pts.len() as u32, p));
                }
            }
        }
        pts
    }

    #[test]
    fn a_slump_reads_the_failure_angle_and_the_reach_it_was_given() {
        let d0 = 0.005;
        let scene = block_scene(d0);
        let initial = lattice(d0);
        // Soil beyond a 35° line from the toe (0.2, 0) slides 2 cm out and 1 cm down; the rest
        // stays.
        let tan = 35f64.to_radians().tan();
        let last: Vec<(u32, [f64; 3])> = initial
            .iter()
            .map(|&(id, p)| if p[0] > 0.2 - p[2] / tan { (id, [p[0] + 0.02, p[1], p[2] - 0.01]) } else { (id, p) })
            .collect();
        let s = slump(&scene, &initial, &last).expect("a block against the wall");
        assert_eq!((s.wall_x, s.direction, s.initial_length, s.initial_height), (0.0, 1.0, 0.2, 0.1));
        let angle = s.failure_angle_deg.expect("rows on both sides");
        // Rows are 5 mm apart and each row's boundary is quantised to a particle: 1° is two
        // particles' worth of slope over the 8 cm fitted.
        assert!((angle - 35.0).abs() < 1.0, "failure angle {angle}");
        assert!(s.failure_rows >= 14, "{} rows", s.failure_rows);
        // Everything at the toe moved 2 cm out: the 99 % reach grows by 2 cm.
        assert!((s.final_length - 0.22).abs() < 1e-9, "final length {}", s.final_length);
        assert!((s.final_height - 0.1).abs() < 1e-9, "the wall's soil stayed: {}", s.final_height);
        // The moved soil ends at 0.2175 m, still thick there (the toe's rows moved together):
        // over columns H0 / 5 = 2 cm long the crossing lies between the centre of the last
        // filled column (0.21 m) and that of the empty one beyond (0.23 m).
        assert!(s.reach_tenth > 0.21 && s.reach_tenth < 0.23, "reach {}", s.reach_tenth);
        // Nothing moved: no boundary, no angle.
        let still = slump(&scene, &initial, &initial).expect("slump");
        assert_eq!((still.failure_angle_deg, still.failure_rows, still.normalized), (None, 0, 0.0));
    }

    #[test]
    fn the_tenth_height_reach_interpolates_a_linear_profile() {
        // A wedge whose thickness falls from 0.1 m at the wall to 0 at 0.5 m, 20 particles
        // wide (each particle d0 / 20 = 0.25 mm of thickness): a tenth of 0.1 m is reached at
        // 0.45 m.
        let (h0, d0) = (0.1, 0.005);
        let mut pts = Vec::new();
        for i in 0..100 {
            let x = (i as f64 + 0.5) * d0;
            let n = (0.1 * (1.0 - x / 0.5) / (d0 / 20.0)).round() as usize;
            pts.extend(std::iter::repeat_n(x, n));
        }
        let r = tenth_height_reach(pts.iter().copied(), h0, d0, 20.0 * d0, d0);
        // Thickness quantised to 0.25 mm on a slope of 0.2: the 1 cm line is met within
        // half a spacing of 0.45 m.
        assert!((r - 0.45).abs() < 0.5 * d0, "reach {r}");
        // Columns four spacings long average a linear profile to its value at their centre:
        // the same crossing.
        let r = tenth_height_reach(pts.iter().copied(), h0, d0, 20.0 * d0, 4.0 * d0);
        assert!((r - 0.45).abs() < 0.5 * d0, "reach over 2 cm columns {r}");
        // A column of 3 particles across a width of 4 d0 is 0.75 d0 thick: finer than a layer.
        let r = tenth_height_reach([0.001, 0.002, 0.003, 0.006, 0.007].into_iter(), 0.05, d0, 4.0 * d0, d0);
        // Columns 0.75 d0 and 0.5 d0 thick (3.75 and 2.5 mm) against a level of 5 mm: none
        // reaches it.
        assert_eq!(r, 0.0);
        let r = tenth_height_reach([0.001, 0.002, 0.003, 0.006, 0.007].into_iter(), 0.03, d0, 4.0 * d0, d0);
        // Level 3 mm: the first column (3.75 mm) is above, the second (2.5 mm) below; the
        // crossing lies 0.6 of the way between their centres.
        assert!((r - (0.5 + 0.6) * d0).abs() < 1e-12, "reach {r}");
        assert_eq!(tenth_height_reach(std::iter::empty(), h0, d0, d0, d0), 0.0);
        // Slid off the wall: empty near it, one column 2 cm thick at 0.3 m. The front is that
        // column's, not zero.
        let r = tenth_height_reach(std::iter::repeat_n(0.301, 4), 0.1, d0, d0, d0);
        assert!((r - (0.3025 + 0.5 * d0)).abs() < 1e-12, "reach {r}");
    }
}
