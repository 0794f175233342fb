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

/// The radius within which 99 % of the particles lie, about an axis, plus half a spacing
/// (the extent of the outermost particles' cells). The same estimator is applied to the
/// initial column and the deposit, so lattice effects cancel in (R∞ − R0)/R0.
fn deposit_radius(points: impl Iterator<Item = [f64; 3]>, axis: [f64; 2], d0: f64) -> f64 {
    let mut r: Vec<f64> = points.map(|p| ((p[0] - axis[0]).powi(2) + (p[1] - axis[1]).powi(2)).sqrt()).collect();
    if r.is_empty() {
        return 0.0;
    }
    r.sort_by(f64::total_cmp);
    let k = ((r.len() as f64 * 0.99).ceil() as usize).clamp(1, r.len()) - 1;
    r[k] + 0.5 * d0
}

/// The positions of the soil particles still in the domain (water left out): what a runout
/// or a deposit profile measures.
pub(super) fn soil_points<T: Real>(s: &dyn SphSolver<T>) -> Vec<[f64; 3]> {
    let (mats, ids) = (s.materials(), s.material_ids());
    (0..s.active()).filter(|&i| !mats[ids[i] as usize].is_water()).map(|i| s.positions()[i].as_f64()).collect()
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
