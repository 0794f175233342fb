//! Self-convergence of a sweep: the points that differ only in one resolution key (`sph.spacing`,
//! say) form a ladder; each ladder's metric gets an observed order and an extrapolated limit
//! ([`crate::study::convergence::richardson`]). `regolith sweep converge DIR` writes
//! `convergence.json` and prints one line per ladder.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::input::InputError;
use crate::runner::{Record, read_all};
use crate::study::convergence::{Convergence, richardson};

/// One ladder: the points sharing every override but `over`.
#[derive(Clone, Debug, Serialize)]
pub struct Ladder {
    /// The overrides the ladder's points share (`over` left out).
    pub fixed: BTreeMap<String, serde_json::Value>,
    /// `(resolution, metric)` of each finished point, coarse to fine.
    pub levels: Vec<(f64, f64)>,
    /// Points of the ladder that failed or whose summary lacks the metric.
    pub missing: Vec<usize>,
    /// The estimate.
    pub convergence: Option<Convergence>,
    /// Why there is none (too few levels, not monotone).
    pub error: Option<String>,
}

/// The value at `path` in a summary: keys separated by `.`, array entries as `[i]` — the
/// column names of `results.csv` (`rig.steady_state[0].drawbar_pull`).
pub fn lookup<'v>(v: &'v serde_json::Value, path: &str) -> Option<&'v serde_json::Value> {
    let mut cur = v;
    for part in path.split('.') {
        let (key, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if !key.is_empty() {
            cur = cur.get(key)?;
        }
        while let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']')?;
            cur = cur.get(r[..end].parse::<usize>().ok()?)?;
            rest = &r[end + 1..];
        }
        if !rest.is_empty() {
            return None;
        }
    }
    Some(cur)
}

/// The ladders of the sweep in `out` over the resolution key `over`, for the summary value
/// `metric`. Errors name the flag: a sweep without records, a key it does not vary, a metric no
/// finished point has.
pub fn converge(out: &Path, over: &str, metric: &str) -> Result<Vec<Ladder>, InputError> {
    let records = read_all(out)?;
    if records.is_empty() {
        return Err(InputError::file(out, "holds no results.jsonl (nothing to analyse)"));
    }
    ladders(&records, over, metric)
}

fn ladders(records: &[Record], over: &str, metric: &str) -> Result<Vec<Ladder>, InputError> {
    let varied: Vec<&String> = records.first().map(|r| r.overrides.keys().collect()).unwrap_or_default();
    let mut groups: BTreeMap<String, Ladder> = BTreeMap::new();
    let mut found_metric = false;
    for r in records {
        let h = r.overrides.get(over).and_then(serde_json::Value::as_f64).ok_or_else(|| {
            let keys: Vec<&str> = varied.iter().map(|k| k.as_str()).collect();
            InputError::flag(
                "--over",
                format!("`{over}` is not a number every point sets (the sweep's keys: {})", keys.join(", ")),
            )
        })?;
        let mut fixed = r.overrides.clone();
        fixed.remove(over);
        let key = serde_json::to_string(&fixed).unwrap_or_default();
        let ladder = groups.entry(key).or_insert_with(|| Ladder {
            fixed,
            levels: Vec::new(),
            missing: Vec::new(),
            convergence: None,
            error: None,
        });
        let value = r.summary.as_ref().and_then(|s| lookup(s, metric)).and_then(serde_json::Value::as_f64);
        match value {
            Some(f) if r.ok() && f.is_finite() => {
                found_metric = true;
                ladder.levels.push((h, f));
            }
            _ => ladder.missing.push(r.point),
        }
    }
    if !found_metric {
        return Err(InputError::flag(
            "--metric",
            format!(
                "no finished point has a number at `{metric}` (use a column name of results.csv, e.g. rig.steady_state[0].drawbar_pull)"
            ),
        ));
    }
    let mut out: Vec<Ladder> = groups.into_values().collect();
    for l in &mut out {
        l.levels.sort_by(|a, b| b.0.total_cmp(&a.0));
        let (h, f): (Vec<f64>, Vec<f64>) = l.levels.iter().copied().unzip();
        match richardson(&h, &f) {
            Ok(c) => l.convergence = Some(c),
            Err(e) => l.error = Some(e.to_string()),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(point: usize, h: f64, slip: f64, value: Option<f64>) -> Record {
        let mut overrides = BTreeMap::new();
        overrides.insert("sph.spacing".to_string(), serde_json::json!(h));
        overrides.insert("rig.slips".to_string(), serde_json::json!([slip]));
        overrides.insert("simulation.end_time".to_string(), serde_json::json!(0.5));
        Record {
            point,
            id: format!("{point:016x}"),
            status: if value.is_some() { "ok" } else { "failed" }.into(),
            overrides,
            wall_s: 1.0,
            peak_mem_bytes: None,
            error: None,
            out: String::new(),
            summary: value.map(|v| serde_json::json!({"rig": {"steady_state": [{"drawbar_pull": v}]}})),
        }
    }

    #[test]
    fn points_differing_only_in_the_resolution_form_one_ladder_each() {
        // DBP = 3 + 10 s + 40 h^1.5 for two slips over four spacings; one point failed.
        let mut recs = Vec::new();
        for (i, (s, h)) in [0.2, 0.4].iter().flat_map(|s| [0.04, 0.02, 0.01, 0.005].map(|h| (*s, h))).enumerate() {
            let v = 3.0 + 10.0 * s + 40.0 * f64::powf(h, 1.5);
            recs.push(record(i, h, s, Some(v)));
        }
        recs.push(record(8, 0.0025, 0.4, None));
        let ls = ladders(&recs, "sph.spacing", "rig.steady_state[0].drawbar_pull").expect("ladders");
        assert_eq!(ls.len(), 2);
        for (l, s) in ls.iter().zip([0.2, 0.4]) {
            assert_eq!(l.fixed["rig.slips"], serde_json::json!([s]));
            assert!(!l.fixed.contains_key("sph.spacing"));
            assert_eq!(l.levels.len(), 4);
            let c = l.convergence.as_ref().expect("estimate");
            assert!((c.order - 1.5).abs() < 0.015, "{c:?}");
            assert!((c.limit - (3.0 + 10.0 * s)).abs() < 0.01 * (3.0 + 10.0 * s), "{c:?}");
        }
        assert_eq!(ls[1].missing, vec![8]);
        let e = ladders(&recs, "sph.h_factor", "rig.steady_state[0].drawbar_pull").expect_err("not varied");
        assert!(e.to_string().contains("`sph.h_factor` is not a number every point sets"), "{e}");
        let e = ladders(&recs, "sph.spacing", "rig.steady_state[0].torque").expect_err("no metric");
        assert!(e.to_string().starts_with("--metric: no finished point has a number at"), "{e}");
    }

    #[test]
    fn lookup_reads_csv_column_names() {
        let v = serde_json::json!({"a": {"b": [1.0, {"c": [5.0, 6.0]}]}, "x": 2});
        assert_eq!(lookup(&v, "a.b[0]"), Some(&serde_json::json!(1.0)));
        assert_eq!(lookup(&v, "a.b[1].c[1]"), Some(&serde_json::json!(6.0)));
        assert_eq!(lookup(&v, "x"), Some(&serde_json::json!(2)));
        assert_eq!(lookup(&v, "a.b[2]"), None);
        assert_eq!(lookup(&v, "a.b[x]"), None);
        assert_eq!(lookup(&v, "a.q"), None);
    }
}
