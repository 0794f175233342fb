//! The test rigs: plate sinkage (bevameter), cone penetrometer and single-wheel rig. Each runs
//! one or more simulations of its scene, records `series.csv`, and reports its curves in
//! `summary.json` (under `rig`, and the Bekker fit under `bekker`).
//!
//! Every rig places its body vertically so that it starts in contact with the soil: its lowest
//! point one spacing above the top soil particle below it (the body's markers and the soil
//! particles then sit on one lattice spacing, the contact distance). Sinkage and depth are
//! measured from there.

pub mod bekker;

mod cone;
mod plate;
mod wheel;

use regolith_fsi::Real;
use regolith_rigid::{Pose, ShapeDesc};

use crate::build::{BuildError, scene_terrain};
use crate::driver::{Driver, RunError};
use crate::output::{Figure, Series};
use crate::scene::{RigSpec, Scene};
use crate::sim::Simulation;
use bekker::BekkerFit;

/// Top of the soil (m) under a disc of radius `r` around `(x, y)`: the highest particle's
/// centre, from the scene's initial terrain.
pub fn soil_top(scene: &Scene, x: f64, y: f64, r: f64) -> Result<f64, BuildError> {
    let (_, t) = scene_terrain::<f64>(scene)?;
    t.particles
        .iter()
        .filter(|p| (p.pos[0] - x).powi(2) + (p.pos[1] - y).powi(2) <= r * r)
        .map(|p| p.pos[2])
        .reduce(f64::max)
        .ok_or(BuildError::NoSoilUnder { x, y })
}

/// Distance from a shape's origin down to its lowest point (m), upright.
fn bottom_offset(shape: &ShapeDesc) -> f64 {
    -shape.lowest_z(&Pose::default())
}

fn footprint(shape: &ShapeDesc) -> f64 {
    match shape {
        ShapeDesc::Box { size } => 0.5 * size[0].min(size[1]),
        ShapeDesc::Cylinder { radius, .. } | ShapeDesc::Cone { radius, .. } => *radius,
        ShapeDesc::Wheel { width, .. } => 0.5 * width,
        s => s.bounding_radius(),
    }
}

/// Places body `i` so that its lowest markers are one spacing above the top soil particle
/// (its lowest point one spacing above it with markers on the surface, half a spacing with
/// `body_markers = "inset"`: on the soil's surface); returns that height.
pub fn place_on_soil(scene: &mut Scene, i: usize) -> Result<f64, BuildError> {
    let d0 = scene.solver.spacing;
    let b = &scene.bodies[i].desc;
    let [x, y, _] = b.pose.translation;
    let top = soil_top(scene, x, y, footprint(&b.shape).max(d0))?;
    // The top particle's cell ends half a spacing above its centre: the soil's surface.
    let bottom = top + (0.5 * d0 + scene.body_markers.contact_offset(d0));
    let z = bottom + bottom_offset(&b.shape);
    scene.bodies[i].desc.pose.translation[2] = z;
    Ok(bottom)
}

/// What a rig run produced.
pub struct RigOutput<T: Real> {
    /// The series of all its runs.
    pub series: Series,
    /// Its report (`summary.json` → `rig`).
    pub report: serde_json::Value,
    /// The Bekker fit of a plate rig.
    pub bekker: Option<BekkerFit>,
    /// Plots to draw.
    pub figures: Vec<(String, Figure)>,
    /// The last simulation (for the final particles).
    pub last: Option<Simulation<T>>,
    /// Why the rig stopped early: a solver failure or a stop request. The series, report and
    /// `last` hold everything up to that exchange (the interrupted run included).
    pub stopped: Option<RunError>,
}

/// Splits an error of [`Driver::step`] into one that ends the rig with its outputs kept
/// ([`RunError::keeps_outputs`]: `Ok`) and one that ends it at once (`Err`).
fn halt(e: RunError) -> Result<RunError, RunError> {
    if e.keeps_outputs() { Ok(e) } else { Err(e) }
}

/// Runs a rig with the run loop `driver` (which carries the observers).
pub fn run_rig<T: Real>(scene: &Scene, rig: &RigSpec, driver: &mut Driver<'_, T>) -> Result<RigOutput<T>, RunError> {
    match rig {
        RigSpec::Plate { body, control, depth, sizes } => {
            plate::plate::<T>(scene, *body, *control, *depth, sizes, driver)
        }
        RigSpec::Cone { body, speed, depth } => cone::cone::<T>(scene, *body, *speed, *depth, driver),
        RigSpec::Wheel { body, load, angular_velocity, drive, slip_radius } => {
            wheel::wheel::<T>(scene, *body, *load, *angular_velocity, drive, *slip_radius, driver)
        }
    }
}
