//! A batch's records: one JSON line per finished run (`results.jsonl`, or one file per
//! shard), appended as runs finish and read back, the last one of each id kept.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::input::InputError;

/// What became of one run (a sweep's point, a stability case, a triaxial test, ...).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Position in its batch (0-based; a sweep's point list).
    pub point: usize,
    /// The run's configuration hash (a sweep point's `id`, a stability case's, ...).
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
