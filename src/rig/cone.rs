//! Cone penetrometer: a cone pushed at constant speed; force and cone index against depth.

use regolith_fsi::Real;
use regolith_rigid::{Motion, ShapeDesc};

use super::{RigOutput, place_on_soil};
use crate::build::BuildError;
use crate::driver::{Driver, RunError};
use crate::output::Series;
use crate::scene::Scene;
use crate::sim::Simulation;

pub(super) fn cone<T: Real>(
    scene: &Scene,
    body: usize,
    speed: f64,
    depth: f64,
    driver: &mut Driver<'_, T>,
) -> Result<RigOutput<T>, RunError> {
    let mut sc = scene.clone();
    let ShapeDesc::Cone { radius, height } = sc.bodies[body].desc.shape else {
        return Err(BuildError::RigShape { rig: "cone", allowed: "a cone" }.into());
    };
    sc.bodies[body].desc.motion = Motion::Prescribed { linvel: [0.0, 0.0, -speed], angvel: [0.0; 3] };
    let tip0 = place_on_soil(&mut sc, body)?;
    // The soil surface: the tip starts the contact offset above it.
    let surface = tip0 - sc.body_markers.contact_offset(sc.solver.spacing);
    let area = std::f64::consts::PI * radius * radius;
    let mut sim = Simulation::<T>::new(&sc)?;
    let mut series = Series::new(&sim, false, &["tip_depth", "base_depth", "cone_force", "cone_index"]);
    let row0 = [surface - tip0, surface - tip0 - height, 0.0, 0.0];
    series.push(&sim, None, &row0);
    let names = ["tip_depth", "base_depth", "cone_force", "cone_index"];
    driver.begin(&sim, None)?;
    driver.publish(
        &sim,
        "/rig/cone",
        "regolith.Rig.cone",
        &[(names[0], row0[0]), (names[1], row0[1]), (names[2], 0.0), (names[3], 0.0)],
    )?;
    let mut curve = Vec::new();
    let mut stopped = None;
    while sim.time() < sc.end_time * (1.0 - 1e-12) {
        if let Err(e) = driver.step(&mut sim) {
            stopped = Some(super::halt(e)?);
            break;
        }
        let st = sim.body_state(sim.body_at(body));
        let tip = st.origin[2] - 0.5 * height;
        let (tip_depth, base_depth) = (surface - tip, surface - (tip + height));
        let f = sim.fsi_wrench(sim.body_at(body)).force[2];
        series.push(&sim, None, &[tip_depth, base_depth, f, f / area]);
        let vals = [tip_depth, base_depth, f, f / area];
        driver.publish(
            &sim,
            "/rig/cone",
            "regolith.Rig.cone",
            &[(names[0], vals[0]), (names[1], vals[1]), (names[2], vals[2]), (names[3], vals[3])],
        )?;
        curve.push((base_depth, f, f / area));
        if base_depth >= depth {
            break;
        }
    }
    let angle = 2.0 * (radius / height).atan().to_degrees();
    let report = serde_json::json!({
        "type": "cone",
        "apex_angle_deg": angle,
        "base_area_m2": area,
        "speed": speed,
        "max_force_n": curve.iter().map(|c| c.1).fold(0.0, f64::max),
        "final_base_depth_m": curve.last().map(|c| c.0),
        "final_cone_index_pa": curve.last().map(|c| c.2),
        "curve": curve.iter().map(|c| serde_json::json!({"base_depth": c.0, "force": c.1, "cone_index": c.2})).collect::<Vec<_>>(),
    });
    let force = crate::output::plot::Panel {
        title: format!("cone penetrometer ({angle:.0}°, {:.0} mm²)", area * 1e6),
        x_label: "base depth (mm)".into(),
        y_label: "force (N)".into(),
        series: vec![crate::output::plot::Series::line("force", curve.iter().map(|c| (c.0 * 1e3, c.1)).collect())],
        ..Default::default()
    };
    let ci = crate::output::plot::Panel {
        title: "cone index".into(),
        x_label: "base depth (mm)".into(),
        y_label: "cone index (kPa)".into(),
        series: vec![crate::output::plot::Series::line(
            "cone index",
            curve.iter().map(|c| (c.0 * 1e3, c.2 / 1e3)).collect(),
        )],
        ..Default::default()
    };
    Ok(RigOutput {
        series,
        report,
        bekker: None,
        figures: vec![("cone_penetrometer".into(), crate::output::plot::Figure { panels: vec![force, ci] })],
        last: Some(sim),
        stopped,
    })
}
