//! A sweep's tidy table `results.csv`, made from its records, and the joining of shard files
//! (the records themselves are the runner's: [`crate::runner`]).

use std::collections::BTreeMap;
use std::path::Path;

use crate::input::InputError;
use crate::runner::{Record, read_all};

/// Joins a sweep directory's records (shards included) into `results.jsonl` and
/// `results.csv`; returns how many points they hold.
pub fn merge(out: &Path) -> Result<usize, InputError> {
    let records = read_all(out)?;
    if records.is_empty() {
        return Err(InputError::file(out, "holds no results.jsonl or results.shard-*.jsonl records to merge"));
    }
    let jsonl = out.join("results.jsonl");
    let tmp = out.join("results.jsonl.tmp");
    let mut text = String::new();
    for r in &records {
        text.push_str(&serde_json::to_string(r).map_err(|e| InputError::file(&jsonl, e.to_string()))?);
        text.push('\n');
    }
    std::fs::write(&tmp, text).map_err(|e| InputError::file(&tmp, format!("cannot write: {e}")))?;
    std::fs::rename(&tmp, &jsonl).map_err(|e| InputError::file(&jsonl, format!("cannot write: {e}")))?;
    write_csv(out, &records)?;
    Ok(records.len())
}

/// Writes `results.csv`: one row per point — point, id, status, the overridden keys (as
/// `set:KEY`), wall_s, every scalar of its summary (nested keys dotted, entries of arrays of up
/// to [`MAX_ARRAY_COLUMNS`] items indexed; longer arrays such as curves, and the summary's
/// `outputs`, `notes` and `error`, are left to results.jsonl), and the point's error.
pub fn write_csv(out: &Path, records: &[Record]) -> Result<(), InputError> {
    let mut keys: Vec<String> = Vec::new();
    let mut columns: Vec<String> = Vec::new();
    let rows: Vec<BTreeMap<String, String>> = records
        .iter()
        .map(|r| {
            let mut row = BTreeMap::new();
            for (k, v) in &r.overrides {
                if !keys.contains(k) {
                    keys.push(k.clone());
                }
                row.insert(format!("set:{k}"), scalar(v));
            }
            if let Some(serde_json::Value::Object(s)) = &r.summary {
                let mut flat = Vec::new();
                for (k, v) in s.iter().filter(|(k, _)| !SKIPPED.contains(&k.as_str())) {
                    flatten(k, v, &mut flat);
                }
                for (k, v) in flat {
                    if !columns.contains(&k) {
                        columns.push(k.clone());
                    }
                    row.insert(k, v);
                }
            }
            row
        })
        .collect();
    keys.sort();
    let mut header = vec!["point".to_string(), "id".into(), "status".into()];
    header.extend(keys.iter().map(|k| format!("set:{k}")));
    header.push("wall_s".into());
    header.push("peak_mem_bytes".into());
    header.extend(columns.iter().cloned());
    header.push("error".into());
    let mut text = header.iter().map(|h| quote(h)).collect::<Vec<_>>().join(",");
    text.push('\n');
    for (r, row) in records.iter().zip(&rows) {
        let mut cells = vec![r.point.to_string(), r.id.clone(), r.status.clone()];
        cells.extend(keys.iter().map(|k| row.get(&format!("set:{k}")).cloned().unwrap_or_default()));
        cells.push(format!("{}", r.wall_s));
        cells.push(r.peak_mem_bytes.map(|b| b.to_string()).unwrap_or_default());
        cells.extend(columns.iter().map(|c| row.get(c).cloned().unwrap_or_default()));
        cells.push(r.error.clone().unwrap_or_default());
        text.push_str(&cells.iter().map(|c| quote(c)).collect::<Vec<_>>().join(","));
        text.push('\n');
    }
    let path = out.join("results.csv");
    std::fs::write(&path, text).map_err(|e| InputError::file(&path, format!("cannot write: {e}")))
}

/// Summary keys `results.csv` leaves out (file lists, free text, the error it has already).
const SKIPPED: [&str; 3] = ["outputs", "notes", "error"];

/// Arrays longer than this are not spread over `results.csv` columns.
pub const MAX_ARRAY_COLUMNS: usize = 16;

fn flatten(prefix: &str, v: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                flatten(&key, x, out);
            }
        }
        serde_json::Value::Array(a) if a.len() <= MAX_ARRAY_COLUMNS => {
            for (i, x) in a.iter().enumerate() {
                flatten(&format!("{prefix}[{i}]"), x, out);
            }
        }
        serde_json::Value::Array(_) => {}
        x => out.push((prefix.to_string(), scalar(x))),
    }
}

fn scalar(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => String::new(),
        x => x.to_string(),
    }
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::Shard;

    #[test]
    fn shards_partition_the_points() {
        let s =
            [Shard::parse("1/3").expect("1/3"), Shard::parse("2/3").expect("2/3"), Shard::parse("3/3").expect("3/3")];
        for p in 0..10 {
            assert_eq!(s.iter().filter(|s| s.holds(p)).count(), 1);
        }
        assert!(Shard::parse("0/3").is_err() && Shard::parse("4/3").is_err() && Shard::parse("x").is_err());
        let env = |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some("5".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            "SLURM_ARRAY_TASK_MIN" => Some("2".to_string()),
            _ => None,
        };
        assert_eq!(Shard::from_slurm(env).expect("slurm"), Some(Shard { index: 4, count: 4 }));
        assert_eq!(Shard::from_slurm(|_| None).expect("none"), None);
    }

    #[test]
    fn csv_flattens_scalars_and_short_arrays() {
        let mut flat = Vec::new();
        let v = serde_json::json!({"a": 1.5, "b": {"c": "x,y"}, "d": [1, 2], "e": vec![0; 40]});
        flatten("", &v, &mut flat);
        assert_eq!(
            flat,
            vec![
                ("a".into(), "1.5".into()),
                ("b.c".into(), "x,y".into()),
                ("d[0]".into(), "1".into()),
                ("d[1]".into(), "2".into())
            ]
        );
        assert_eq!(quote("x,y"), "\"x,y\"");
    }
}
