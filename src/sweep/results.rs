//! A sweep's results: one JSON line per finished point (`results.jsonl`, or one file per
//! shard), and the tidy table `results.csv` made from them.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::input::InputError;

/// What became of one point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Position in the sweep's point list (0-based).
    pub point: usize,
    /// The point's configuration hash (see [`super::Point::id`]).
    pub id: String,
    /// `"ok"` or `"failed"`.
    pub status: String,
    /// The overrides this point applied, by key (the sweep's `--set` ones included).
    pub overrides: BTreeMap<String, serde_json::Value>,
    /// Wall-clock time of the point (s), loading and writing included.
    pub wall_s: f64,
    /// Peak resident memory of the process while the point ran (bytes, Linux): recorded when
    /// the point ran alone (one job), since points running side by side share one process's
    /// memory; `None` otherwise and where the system does not say.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_mem_bytes: Option<u64>,
    /// The one-line error of a failed point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Its output directory, relative to the sweep's.
    pub out: String,
    /// Its `summary.json` (also when it failed after the run started).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub summary: Option<serde_json::Value>,
}

impl Record {
    /// True for a point that ran to the end.
    pub fn ok(&self) -> bool {
        self.status == "ok"
    }
}

/// One slice of a sweep's points: shard `index` of `count` (1-based) holds the points whose
/// position `p` has `p % count == index − 1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 1-based.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Parses `i/n` (1 ≤ i ≤ n).
    pub fn parse(s: &str) -> Result<Self, InputError> {
        let bad = || InputError::flag("--shard", format!("`{s}` is not i/n with 1 <= i <= n"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) =
            (i.trim().parse::<usize>().map_err(|_| bad())?, n.trim().parse::<usize>().map_err(|_| bad())?);
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// The shard of a SLURM array task: `SLURM_ARRAY_TASK_ID` counted from
    /// `SLURM_ARRAY_TASK_MIN` (0 when unset) among `SLURM_ARRAY_TASK_COUNT` tasks; `None` outside
    /// an array job.
    pub fn from_slurm(env: impl Fn(&str) -> Option<String>) -> Result<Option<Self>, InputError> {
        let (Some(id), Some(count)) = (env("SLURM_ARRAY_TASK_ID"), env("SLURM_ARRAY_TASK_COUNT")) else {
            return Ok(None);
        };
        let num = |name: &str, v: &str| {
            v.trim().parse::<usize>().map_err(|_| InputError::flag(name, format!("`{v}` is not a whole number")))
        };
        let min = env("SLURM_ARRAY_TASK_MIN").map(|m| num("SLURM_ARRAY_TASK_MIN", &m)).transpose()?.unwrap_or(0);
        let (id, count) = (num("SLURM_ARRAY_TASK_ID", &id)?, num("SLURM_ARRAY_TASK_COUNT", &count)?);
        if id < min || id - min >= count {
            return Err(InputError::flag(
                "SLURM_ARRAY_TASK_ID",
                format!("{id} is outside the array ({count} tasks from {min}); use a contiguous --array"),
            ));
        }
        Ok(Some(Self { index: id - min + 1, count }))
    }

    /// True when point `p` belongs to this shard.
    pub fn holds(self, p: usize) -> bool {
        p % self.count == self.index - 1
    }
}

/// The results file a run of `shard` appends to.
pub fn results_file(out: &Path, shard: Option<Shard>) -> PathBuf {
    match shard {
        None => out.join("results.jsonl"),
        Some(s) => out.join(format!("results.shard-{}-of-{}.jsonl", s.index, s.count)),
    }
}

/// Appends one record to a results file (one line, flushed).
pub fn append(file: &Path, r: &Record) -> Result<(), InputError> {
    let line = serde_json::to_string(r).map_err(|e| InputError::file(file, e.to_string()))?;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(file)
        .map_err(|e| InputError::file(file, format!("cannot append: {e}")))?;
    writeln!(f, "{line}").and_then(|_| f.flush()).map_err(|e| InputError::file(file, format!("cannot append: {e}")))
}

/// Every record of a sweep directory, from `results.jsonl` and the shard files, the last one
/// of each point id kept, ordered by point. A torn last line (a run killed while writing) is
/// skipped; any other unreadable line is an error naming the file and line.
pub fn read_all(out: &Path) -> Result<Vec<Record>, InputError> {
    let mut files: Vec<PathBuf> = match std::fs::read_dir(out) {
        Ok(d) => d
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n == "results.jsonl" || (n.starts_with("results.shard-") && n.ends_with(".jsonl")))
            })
            .collect(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(InputError::file(out, format!("cannot list: {e}"))),
    };
    files.sort();
    let mut by_id: BTreeMap<String, Record> = BTreeMap::new();
    for f in files {
        let text = std::fs::read_to_string(&f).map_err(|e| InputError::file(&f, format!("cannot read: {e}")))?;
        let lines: Vec<&str> = text.lines().collect();
        for (n, line) in lines.iter().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            match serde_json::from_str::<Record>(line) {
                Ok(r) => {
                    by_id.insert(r.id.clone(), r);
                }
                Err(_) if n + 1 == lines.len() && !text.ends_with('\n') => {}
                Err(e) => {
                    return Err(InputError {
                        file: Some(f.clone()),
                        line: Some(n + 1),
                        key: None,
                        message: format!("not a sweep record: {e}"),
                    });
                }
            }
        }
    }
    let mut v: Vec<Record> = by_id.into_values().collect();
    v.sort_by(|a, b| a.point.cmp(&b.point).then_with(|| a.id.cmp(&b.id)));
    Ok(v)
}

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
