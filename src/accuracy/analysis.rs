//! From the points' records to the study's rows: the error of each point against its
//! reference, the observed order over the ladder, the Pareto front of error against wall time,
//! and the cheapest point within each tolerance.

use serde::Serialize;

use super::case::{Case, PointSpec, Reference, ReferenceKind};
use crate::study::convergence::{Convergence, richardson};
use crate::sweep::{Record, lookup};

/// The tolerances the report answers for (relative errors).
pub const TOLERANCES: [f64; 3] = [0.10, 0.05, 0.02];

/// One point of the study: a row of `accuracy.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Case (file stem).
    pub case: String,
    /// `d0` for a ladder level, else the knob's key.
    pub knob: String,
    /// The setting.
    pub setting: String,
    /// The measured value (NaN for a failed point).
    pub measured: f64,
    /// The reference value.
    pub reference: f64,
    /// `closed-form`, `experiment` or `self-convergence`.
    pub reference_kind: String,
    /// measured − reference.
    pub error: f64,
    /// error / |reference|.
    pub rel_error: f64,
    /// Wall-clock time of the point (s), loading and writing included.
    pub wall_s: f64,
    /// Soil particle-steps integrated.
    pub particle_steps: f64,
    /// Soil steps.
    pub steps: u64,
    /// Peak resident memory (bytes) when the point ran alone; `None` otherwise.
    pub peak_mem_bytes: Option<u64>,
    /// CPU model, cores, backend and adapter.
    pub machine: String,
    /// The command that runs this point by hand.
    pub command: String,
    /// Resolution (m).
    pub d0: f64,
    /// Simulated time (s).
    pub sim_time: f64,
    /// The one-line error of a failed point.
    pub failure: Option<String>,
}

impl Row {
    /// Wall seconds per simulated second.
    pub fn cost_per_sim_s(&self) -> f64 {
        if self.sim_time > 0.0 { self.wall_s / self.sim_time } else { f64::NAN }
    }

    /// A finished point with a finite error.
    pub fn usable(&self) -> bool {
        self.failure.is_none() && self.rel_error.is_finite()
    }
}

/// The observed order of a case's ladder.
#[derive(Clone, Debug, Serialize)]
pub struct Order {
    /// How it was found: `error-slope` (least-squares slope of ln|error| on ln d0, against an
    /// external reference) or `richardson` (self-convergence).
    pub method: String,
    /// The order (NaN when none could be found).
    pub order: f64,
    /// Smallest and largest order of consecutive levels (pairs for `error-slope`, triplets for
    /// `richardson`).
    pub range: (f64, f64),
    /// Why there is none, when there is none.
    pub note: Option<String>,
}

/// A case's analysed result.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// Case (file stem).
    pub case: String,
    /// What is measured.
    pub quantity: String,
    /// The reference kind.
    pub reference_kind: String,
    /// The reference's source.
    pub source: String,
    /// The ladder's key.
    pub resolution: String,
    /// The level the knobs were turned at.
    pub baseline: f64,
    /// The observed order over the ladder.
    pub order: Order,
    /// The Richardson fit of a self-convergence case.
    pub richardson: Option<Convergence>,
    /// The rows, ladder first.
    pub rows: Vec<Row>,
    /// Indices of the rows on the Pareto front of |error| against wall time, cheapest first.
    pub pareto: Vec<usize>,
    /// Per tolerance (10, 5, 2 %): the cheapest row within it, if any.
    pub cheapest: Vec<(f64, Option<usize>)>,
}

/// The command that runs one point by hand.
pub fn command(case: &Case, p: &PointSpec) -> String {
    crate::scene::overrides::command_line(&case.path, &p.overrides)
}

fn number(summary: Option<&serde_json::Value>, path: &str) -> Option<f64> {
    lookup(summary?, path)?.as_f64()
}

/// The rows of a case from its points' records (`records[i]` for `case.points[i]`; `None`
/// when the point has not run).
pub fn analyse(case: &Case, records: &[Option<Record>], machine: &str) -> CaseResult {
    let mut rows: Vec<Row> = case
        .points
        .iter()
        .zip(records)
        .map(|(p, r)| {
            let summary = r.as_ref().and_then(|r| r.summary.as_ref());
            let measured = match r {
                Some(r) if r.ok() => number(summary, &case.measure).unwrap_or(f64::NAN),
                _ => f64::NAN,
            };
            let reference = match &case.reference {
                Reference::Value(v) => *v,
                Reference::Summary(k) => number(summary, k).unwrap_or(f64::NAN),
                Reference::Limit => f64::NAN,
            };
            let failure = match r {
                None => Some("not run".to_string()),
                Some(r) if !r.ok() => Some(r.error.clone().unwrap_or_else(|| "failed".into())),
                Some(_) if !measured.is_finite() => {
                    Some(format!("the summary holds no finite {} (is this the right scene?)", case.measure))
                }
                Some(_) => None,
            };
            let backend = summary.and_then(|s| s.get("backend")).and_then(|v| v.as_str()).unwrap_or("?");
            let adapter = summary.and_then(|s| s.get("adapter")).and_then(|v| v.as_str()).unwrap_or("?");
            Row {
                case: case.name.clone(),
                knob: p.knob.clone(),
                setting: match &p.setting {
                    toml::Value::String(s) => s.clone(),
                    v => v.to_string(),
                },
                measured,
                reference,
                reference_kind: case.kind.name().into(),
                error: measured - reference,
                rel_error: (measured - reference) / reference.abs(),
                wall_s: r.as_ref().map_or(f64::NAN, |r| r.wall_s),
                particle_steps: number(summary, "particle_steps").unwrap_or(0.0),
                steps: summary.and_then(|s| s.get("steps")).and_then(|v| v.as_u64()).unwrap_or(0),
                peak_mem_bytes: r.as_ref().and_then(|r| r.peak_mem_bytes),
                machine: format!("{machine}, backend {backend} ({adapter})"),
                command: command(case, p),
                d0: p.d0,
                sim_time: number(summary, "sim_time").unwrap_or(f64::NAN),
                failure,
            }
        })
        .collect();
    let ladder: Vec<&Row> = rows.iter().filter(|r| r.knob == "d0").collect();
    let (order, fit) = match case.kind {
        ReferenceKind::SelfConvergence => {
            let (h, f): (Vec<f64>, Vec<f64>) =
                ladder.iter().filter(|r| r.failure.is_none()).map(|r| (r.d0, r.measured)).unzip();
            match richardson(&h, &f) {
                Ok(c) => {
                    (Order { method: "richardson".into(), order: c.order, range: c.order_range, note: None }, Some(c))
                }
                Err(e) => (
                    Order {
                        method: "richardson".into(),
                        order: f64::NAN,
                        range: (f64::NAN, f64::NAN),
                        note: Some(format!("{e}; the finest level stands in as the reference")),
                    },
                    None,
                ),
            }
        }
        _ => (error_slope(&ladder), None),
    };
    if case.kind == ReferenceKind::SelfConvergence {
        // The reference is the limit, or the finest finished level when there is none.
        let reference = match &fit {
            Some(c) => c.limit,
            None => ladder.iter().rev().find(|r| r.failure.is_none()).map_or(f64::NAN, |r| r.measured),
        };
        for r in &mut rows {
            r.reference = reference;
            r.error = r.measured - reference;
            r.rel_error = r.error / reference.abs();
        }
    }
    let pareto = pareto_front(&rows);
    let cheapest = TOLERANCES
        .iter()
        .map(|&t| {
            let best = rows
                .iter()
                .enumerate()
                .filter(|(_, r)| r.usable() && r.rel_error.abs() <= t)
                .min_by(|a, b| a.1.wall_s.total_cmp(&b.1.wall_s))
                .map(|(i, _)| i);
            (t, best)
        })
        .collect();
    CaseResult {
        case: case.name.clone(),
        quantity: case.quantity.clone(),
        reference_kind: case.kind.name().into(),
        source: case.source_note.clone(),
        resolution: case.resolution.clone(),
        baseline: case.baseline,
        order,
        richardson: fit,
        rows,
        pareto,
        cheapest,
    }
}

/// The least-squares slope of ln|error| on ln d0 over the ladder's finished levels, and the
/// range of the slopes between consecutive levels.
fn error_slope(ladder: &[&Row]) -> Order {
    let pts: Vec<(f64, f64)> =
        ladder.iter().filter(|r| r.usable() && r.error != 0.0).map(|r| (r.d0.ln(), r.error.abs().ln())).collect();
    if pts.len() < 2 {
        return Order {
            method: "error-slope".into(),
            order: f64::NAN,
            range: (f64::NAN, f64::NAN),
            note: Some(format!("{} level(s) with a finite, non-zero error; the slope needs 2", pts.len())),
        };
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let pairs: Vec<f64> = pts.windows(2).map(|w| (w[0].1 - w[1].1) / (w[0].0 - w[1].0)).collect();
    let range = pairs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let sign_flips = ladder.windows(2).filter(|w| w[0].error.signum() != w[1].error.signum()).count();
    Order {
        method: "error-slope".into(),
        order: sxy / sxx,
        range,
        note: (sign_flips > 0).then(|| {
            format!("the error changes sign {sign_flips} time(s) over the ladder: |error| is not a power of d0 there")
        }),
    }
}

/// Rows no other row beats in both wall time and |relative error|, cheapest first.
pub fn pareto_front(rows: &[Row]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].usable() && rows[i].wall_s.is_finite()).collect();
    idx.sort_by(|&a, &b| {
        rows[a].wall_s.total_cmp(&rows[b].wall_s).then(rows[a].rel_error.abs().total_cmp(&rows[b].rel_error.abs()))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        let e = rows[i].rel_error.abs();
        if e < best {
            front.push(i);
            best = e;
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(d0: f64, err: f64, wall: f64) -> Row {
        Row {
            case: "c".into(),
            knob: "d0".into(),
            setting: d0.to_string(),
            measured: 1.0 + err,
            reference: 1.0,
            reference_kind: "closed-form".into(),
            error: err,
            rel_error: err,
            wall_s: wall,
            particle_steps: 0.0,
            steps: 0,
            peak_mem_bytes: None,
            machine: String::new(),
            command: String::new(),
            d0,
            sim_time: 1.0,
            failure: None,
        }
    }

    #[test]
    fn the_error_slope_recovers_a_power_law() {
        let rows: Vec<Row> = [0.04, 0.02, 0.01, 0.005].iter().map(|&d| row(d, 3.0 * d.powf(1.5), 1.0 / d)).collect();
        let o = error_slope(&rows.iter().collect::<Vec<_>>());
        assert!((o.order - 1.5).abs() < 1e-12, "{o:?}");
        assert!((o.range.0 - 1.5).abs() < 1e-12 && (o.range.1 - 1.5).abs() < 1e-12);
        assert!(o.note.is_none());
    }

    #[test]
    fn the_pareto_front_keeps_what_nothing_beats() {
        let rows = vec![row(0.04, 0.2, 1.0), row(0.02, 0.1, 4.0), row(0.01, 0.15, 16.0), row(0.005, 0.01, 64.0)];
        // The third costs more than the second and is less accurate: dominated.
        assert_eq!(pareto_front(&rows), vec![0, 1, 3]);
        let mut failed = row(0.03, 0.0, 0.5);
        failed.failure = Some("x".into());
        let mut with_failed = rows.clone();
        with_failed.push(failed);
        assert_eq!(pareto_front(&with_failed), vec![0, 1, 3], "a failed point is never on the front");
    }
}
