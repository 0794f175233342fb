//! The figure of an element test: the stress path in q–p with yield surfaces and the critical
//! state line, and the compression path in v–ln p with the normal compression and critical
//! state lines (MCC).

use regolith_fsi::Real;
use regolith_fsi::rheology::{Material, P_REF, Rheology};

use super::plot::{Figure, Panel, Series};
use crate::element::ElementPath;

fn ellipse(m: f64, pc: f64) -> Vec<(f64, f64)> {
    (0..=200)
        .map(|i| {
            let p = pc * i as f64 / 200.0;
            (p / 1e3, m * (p * (pc - p)).max(0.0).sqrt() / 1e3)
        })
        .collect()
}

/// Builds the two-panel figure of an element test.
pub fn element_figure<T: Real>(path: &ElementPath, material: &Material<T>) -> Figure {
    let kpa = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x / 1e3).collect() };
    let (p, q) = (kpa(&path.p), kpa(&path.q));
    let p_max = path.p.iter().copied().fold(0.0, f64::max);
    let mut pq = Panel {
        title: format!("{} ({}) — stress path", path.test, path.model),
        x_label: "mean pressure p (kPa)".into(),
        y_label: "deviator q (kPa)".into(),
        ..Default::default()
    };
    pq.series.push(Series::line("path", p.iter().copied().zip(q.iter().copied()).collect()));
    let mut vp = Panel {
        title: "compression — v vs ln p".into(),
        x_label: "mean pressure p (kPa, log)".into(),
        y_label: if matches!(material.rheology, Rheology::Mcc(_)) {
            "specific volume v".into()
        } else {
            "relative volume V/V0".into()
        },
        x_log: true,
        ..Default::default()
    };
    vp.series.push(Series::line("path", p.iter().copied().zip(path.v.iter().copied()).collect()));
    match &material.rheology {
        Rheology::Mcc(mcc) => {
            let m = mcc.m.as_f64();
            let pcs = path.pc.as_deref().unwrap_or(&[]);
            let pc0 = pcs.first().copied().unwrap_or(p_max);
            let pc1 = pcs.last().copied().unwrap_or(p_max);
            let top = p_max.max(pc0).max(pc1) * 1.05;
            pq.series.push(Series::line("CSL q = M p", vec![(0.0, 0.0), (top / 1e3, m * top / 1e3)]));
            pq.series.push(Series::line("initial yield surface", ellipse(m, pc0)));
            pq.series.push(Series::line("final yield surface", ellipse(m, pc1)));
            pq.x_range = Some((0.0, top / 1e3));
            let q_max = path.q.iter().copied().fold(m * pc0.max(pc1) / 2.0, f64::max);
            pq.y_range = Some((0.0, q_max * 1.1 / 1e3));
            let (l, k, vl) = (mcc.lambda.as_f64(), mcc.kappa.as_f64(), mcc.v_lambda.as_f64());
            let p_lo = path.p.iter().copied().filter(|x| *x > 0.0).fold(f64::INFINITY, f64::min);
            let (a, b) = (p_lo / 1.2, p_max * 1.2);
            let line = |shift: f64| -> Vec<(f64, f64)> {
                (0..=50)
                    .map(|i| {
                        let pp = a * (b / a).powf(i as f64 / 50.0);
                        (pp / 1e3, vl - l * (pp / P_REF).ln() - shift)
                    })
                    .collect()
            };
            vp.series.push(Series::line("NCL", line(0.0)));
            vp.series.push(Series::line("CSL", line((l - k) * 2f64.ln())));
        }
        Rheology::DruckerPrager(dp) => {
            let top = p_max * 1.1;
            let slope = dp.mu_s.as_f64() * 3f64.sqrt();
            let d = dp.k.as_f64() * 3f64.sqrt();
            pq.series.push(Series::line(
                "failure cone (compression)",
                vec![(0.0, d / 1e3), (top / 1e3, (d + slope * top) / 1e3)],
            ));
            pq.x_range = Some((0.0, top / 1e3));
        }
        Rheology::Elastic | Rheology::Water(_) => {}
    }
    Figure { panels: vec![pq, vp] }
}
