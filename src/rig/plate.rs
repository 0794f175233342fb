//! Plate sinkage (bevameter): a circular or rectangular plate pushed at a speed or under a
//! load; the pressure–sinkage curve of each plate size and their Bekker fit.

use regolith_fsi::Real;
use regolith_rigid::{Motion, ShapeDesc};
use serde::Serialize;

use super::bekker::{self, PlateCurve};
use super::{RigOutput, bottom_offset, place_on_soil};
use crate::build::BuildError;
use crate::driver::{Driver, RunError};
use crate::output::Series;
use crate::scene::{PlateControl, Scene};
use crate::sim::Simulation;

/// One plate's curve in the report.
#[derive(Clone, Debug, Serialize)]
struct PlateRun {
    /// Plate width b (m).
    b: f64,
    /// Plate area (m²).
    area: f64,
    /// Largest sinkage reached (m).
    max_sinkage: f64,
    /// Largest pressure (Pa).
    max_pressure: f64,
    /// The plate's width B (m): the diameter of a circular plate, the short side of a
    /// rectangular one.
    width: f64,
    /// Mean pressure over the sinkages within ±10 % of 0.1 B (Pa), where bearing capacity is
    /// read for a plate punching into soil; `None` when the run did not reach 0.11 B.
    pressure_at_tenth_width: Option<f64>,
    /// (sinkage m, pressure Pa), every exchange.
    curve: Vec<(f64, f64)>,
}

pub(super) fn plate<T: Real>(
    scene: &Scene,
    body: usize,
    control: PlateControl,
    depth: f64,
    sizes: &[f64],
    driver: &mut Driver<'_, T>,
) -> Result<RigOutput<T>, RunError> {
    let base = scene.bodies[body].desc.shape.clone();
    let sizes: Vec<Option<f64>> = if sizes.is_empty() { vec![None] } else { sizes.iter().map(|s| Some(*s)).collect() };
    let multi = sizes.len() > 1;
    let mut series: Option<Series> = None;
    let mut runs = Vec::new();
    let mut last: Option<Simulation<T>> = None;
    let mut stopped = None;
    for size in sizes {
        let mut sc = scene.clone();
        let shape = match (&base, size) {
            (ShapeDesc::Cylinder { length, axis, radius }, s) => {
                ShapeDesc::Cylinder { radius: s.unwrap_or(*radius), length: *length, axis: *axis }
            }
            (ShapeDesc::Box { size: sz }, Some(s)) => {
                let k = s / sz[0].min(sz[1]);
                ShapeDesc::Box { size: [sz[0] * k, sz[1] * k, sz[2]] }
            }
            (other, _) => other.clone(),
        };
        let (b, area) = match &shape {
            ShapeDesc::Cylinder { radius, .. } => (*radius, std::f64::consts::PI * radius * radius),
            ShapeDesc::Box { size } => (size[0].min(size[1]), size[0] * size[1]),
            _ => return Err(BuildError::RigShape { rig: "plate", allowed: "a cylinder or a box" }.into()),
        };
        sc.bodies[body].desc.shape = shape;
        sc.bodies[body].desc.motion = match control {
            PlateControl::Speed(v) => Motion::Prescribed { linvel: [0.0, 0.0, -v], angvel: [0.0; 3] },
            PlateControl::Load(_) => Motion::Free,
        };
        let bottom0 = place_on_soil(&mut sc, body)?;
        let mut sim = Simulation::<T>::new(&sc)?;
        let id = sim.rigid_id(sim.body_at(body));
        if let PlateControl::Load(f) = control {
            sim.system.rigid.set_extra_force(id, [0.0, 0.0, -f]);
        }
        let offset = bottom_offset(&sc.bodies[body].desc.shape);
        let s = series.get_or_insert_with(|| Series::new(&sim, multi, &["sinkage", "pressure"]));
        s.push(&sim, multi.then_some(b), &[0.0, 0.0]);
        driver.begin(&sim, multi.then_some(b))?;
        driver.publish(&sim, "/rig/plate", "regolith.Rig.plate", &[("sinkage", 0.0), ("pressure", 0.0)])?;
        let mut curve = Vec::new();
        let (mut zmax, mut pmax) = (0.0_f64, 0.0_f64);
        while sim.time() < sc.end_time * (1.0 - 1e-12) {
            if let Err(e) = driver.step(&mut sim) {
                stopped = Some(super::halt(e)?);
                break;
            }
            let st = sim.body_state(sim.body_at(body));
            let sinkage = bottom0 - (st.origin[2] - offset);
            let p = sim.fsi_wrench(sim.body_at(body)).force[2] / area;
            s.push(&sim, multi.then_some(b), &[sinkage, p]);
            driver.publish(&sim, "/rig/plate", "regolith.Rig.plate", &[("sinkage", sinkage), ("pressure", p)])?;
            curve.push((sinkage, p));
            zmax = zmax.max(sinkage);
            pmax = pmax.max(p);
            if sinkage >= depth {
                break;
            }
        }
        let width = match &sc.bodies[body].desc.shape {
            ShapeDesc::Cylinder { radius, .. } => 2.0 * radius,
            _ => b,
        };
        let pressure_at_tenth_width = mean_pressure_near(&curve, 0.1 * width, 0.1);
        runs.push(PlateRun { b, area, max_sinkage: zmax, max_pressure: pmax, width, pressure_at_tenth_width, curve });
        last = Some(sim);
        if stopped.is_some() {
            break;
        }
    }
    let fit = bekker::fit(&runs.iter().map(|r| PlateCurve { b: r.b, points: r.curve.clone() }).collect::<Vec<_>>());
    let mut panel = crate::output::plot::Panel {
        title: "plate sinkage".into(),
        x_label: "sinkage z (mm)".into(),
        y_label: "pressure p (kPa)".into(),
        ..Default::default()
    };
    for r in &runs {
        panel.series.push(crate::output::plot::Series::line(
            format!("b = {} mm", r.b * 1e3),
            r.curve.iter().map(|(z, p)| (z * 1e3, p / 1e3)).collect(),
        ));
        if let Some(f) = &fit
            && let Some(k) = f.k_per_plate.iter().find(|(b, _)| (b - r.b).abs() < 1e-12).map(|(_, k)| *k)
        {
            panel.series.push(crate::output::plot::Series::line(
                format!("Bekker fit, b = {} mm", r.b * 1e3),
                (1..=50).map(|i| r.max_sinkage * i as f64 / 50.0).map(|z| (z * 1e3, k * z.powf(f.n) / 1e3)).collect(),
            ));
        }
    }
    let report = serde_json::json!({
        "type": "plate",
        "control": match control { PlateControl::Speed(v) => serde_json::json!({"speed": v}), PlateControl::Load(f) => serde_json::json!({"load": f}) },
        "runs": runs,
    });
    Ok(RigOutput {
        series: series.unwrap_or_default(),
        report,
        bekker: fit,
        figures: vec![("plate_sinkage".into(), crate::output::plot::Figure { panels: vec![panel] })],
        last,
        stopped,
    })
}

/// The mean pressure of the curve's points with sinkage within `rel` of `z` (`None` when the
/// curve does not reach `z (1 + rel)`, or holds no point there).
fn mean_pressure_near(curve: &[(f64, f64)], z: f64, rel: f64) -> Option<f64> {
    if curve.iter().all(|(s, _)| *s < z * (1.0 + rel)) {
        return None;
    }
    let near: Vec<f64> = curve.iter().filter(|(s, _)| (s - z).abs() <= rel * z).map(|(_, p)| *p).collect();
    (!near.is_empty()).then(|| near.iter().sum::<f64>() / near.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pressure_at_a_tenth_of_the_width_is_read_where_the_curve_reaches_it() {
        // Sinkages (i + ½)·0.1 mm, pressures i kPa.
        let curve: Vec<(f64, f64)> = (0..=120).map(|i| ((i as f64 + 0.5) * 1e-4, 1000.0 * i as f64)).collect();
        // Within 9–11 mm: i = 90..=109, mean 99.5 kPa.
        let p = mean_pressure_near(&curve, 0.01, 0.1).expect("reached");
        assert!((p - 99_500.0).abs() < 1e-6, "{p}");
        assert_eq!(mean_pressure_near(&curve[..105], 0.01, 0.1), None, "stops at 10.45 mm, short of 11");
    }
}
