//! Plots of a terrain run: the deposit's surface profile and each vehicle's path, speed,
//! wheel slip and sinkage.

use super::plot::{Figure, Panel, Series as Line};
use super::series::Series;
use crate::scene::{Scene, VehicleSpec};

/// A vehicle's path, speed, and each wheel's slip and sinkage against time, from the series.
pub fn vehicle_figure(s: &Series, v: &VehicleSpec) -> Figure {
    let col = |name: String| s.column(&name).map(|c| s.rows.iter().map(|r| r[c]).collect::<Vec<f64>>());
    let t = col("time".into()).unwrap_or_default();
    let pair = |a: &[f64], b: &[f64], scale: f64| -> Vec<(f64, f64)> {
        a.iter().zip(b).filter(|(_, y)| y.is_finite()).map(|(x, y)| (*x, y * scale)).collect()
    };
    let x = col(format!("{}.x", v.name)).unwrap_or_default();
    let y = col(format!("{}.y", v.name)).unwrap_or_default();
    let speed = col(format!("{}.speed", v.name)).unwrap_or_default();
    let mut slip =
        Panel { title: "wheel slip".into(), x_label: "time (s)".into(), y_label: "slip".into(), ..Default::default() };
    let mut sink = Panel {
        title: "wheel sinkage".into(),
        x_label: "time (s)".into(),
        y_label: "sinkage (mm)".into(),
        ..Default::default()
    };
    for w in &v.wheels {
        let name = &v.model.links[w.link].name;
        if let (Some(c), Some(om)) = (col(format!("{}/{name}.slip", v.name)), col(format!("{}/{name}.omega", v.name))) {
            // Slip is undefined while a wheel barely turns: plot it where the wheel spins at
            // 0.3 rad/s or more.
            let pts = t
                .iter()
                .zip(&c)
                .zip(&om)
                .filter(|((_, s), w)| s.is_finite() && w.abs() >= 0.3)
                .map(|((t, s), _)| (*t, *s))
                .collect();
            slip.series.push(Line::line(name.clone(), pts));
        }
        if let Some(c) = col(format!("{}/{name}.sinkage", v.name)) {
            sink.series.push(Line::line(name.clone(), pair(&t, &c, 1e3)));
        }
    }
    Figure {
        panels: vec![
            Panel {
                title: format!("{} path", v.name),
                x_label: "x (m)".into(),
                y_label: "y (m)".into(),
                series: vec![Line::line("root link", pair(&x, &y, 1.0))],
                ..Default::default()
            },
            Panel {
                title: "speed".into(),
                x_label: "time (s)".into(),
                y_label: "horizontal speed (m/s)".into(),
                series: vec![Line::line("speed", pair(&t, &speed, 1.0))],
                ..Default::default()
            },
            slip,
            sink,
        ],
    }
}

/// The deposit's surface profile, initial and final, from the soil's positions (water left
/// out): the highest particle top in bins of the radial distance from `axis` (a column
/// collapse's) or of x (other terrain).
pub fn deposit_profile(scene: &Scene, initial: &[[f64; 3]], last: &[[f64; 3]], axis: Option<[f64; 2]>) -> Figure {
    let d0 = scene.solver.spacing;
    let coord = |p: [f64; 3]| match axis {
        Some(a) => ((p[0] - a[0]).powi(2) + (p[1] - a[1]).powi(2)).sqrt(),
        None => p[0],
    };
    let profile = |pts: &mut dyn Iterator<Item = [f64; 3]>| {
        let mut bins: std::collections::BTreeMap<i64, f64> = std::collections::BTreeMap::new();
        for p in pts {
            let k = (coord(p) / d0).floor() as i64;
            let top = p[2] + 0.5 * d0;
            let e = bins.entry(k).or_insert(f64::NEG_INFINITY);
            *e = e.max(top);
        }
        bins.into_iter().map(|(k, z)| ((k as f64 + 0.5) * d0, z)).collect::<Vec<_>>()
    };
    let fin = profile(&mut last.iter().copied());
    let ini = profile(&mut initial.iter().copied());
    let x_label = if axis.is_some() { "distance from the column axis r (m)" } else { "x (m)" };
    let floor = initial.iter().map(|p| p[2] - 0.5 * d0).fold(f64::INFINITY, f64::min);
    let top = ini.iter().chain(&fin).map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    Figure {
        panels: vec![Panel {
            title: "deposit surface".into(),
            x_label: x_label.into(),
            y_label: "surface height z (m)".into(),
            series: vec![Line::line("initial", ini), Line::line("final", fin)],
            y_range: (floor.is_finite() && top > floor).then_some((floor, top + 0.1 * (top - floor))),
            ..Default::default()
        }],
    }
}
