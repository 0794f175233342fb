//! Sweeps: one scene run at many points (`--vary key=values`), each point's summary recorded,
//! resumable, sliceable into shards for SLURM arrays. The points, their configuration hashes,
//! how one point runs and how results are written live here; the runners — in-process threads
//! ([`run_local`]) or Ray tasks (the Python package's `regolith.sweep`) — only schedule them.
//!
//! Layout of a sweep directory: `results.jsonl` (or `results.shard-I-of-N.jsonl`, one line
//! per finished point, see [`Record`]), `results.csv` (the tidy table), and
//! `points/<id>/` with each point's own `summary.json`, `series.csv` and plots, and after
//! `regolith sweep converge` a `convergence.json` (observed order and limit per ladder).

mod converge;
mod design;
mod memory;
mod results;

pub use crate::runner::{
    Outcome, Record, Shard, Task, append, eta_text, fnv_id, forget, pending, read_all, results_file, run_tasks,
    toml_to_json,
};
pub use converge::{Ladder, converge, lookup};
pub use design::{Design, Values, Vary, parse_vary, points};
pub use memory::{peak_rss_bytes, reset_peak_rss};
pub use results::{MAX_ARRAY_COLUMNS, merge, write_csv};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::input::{InputError, read_text};
use crate::run::{RunOptions, run_scene};
use crate::scene::{load_scene_source, overrides};

/// One point of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Position in the sweep (0-based).
    pub index: usize,
    /// Configuration hash: FNV-1a (64 bit, hex) of the scene file's text and the point's
    /// overrides (key and TOML value, in order). The same scene text and overrides give the
    /// same id on every machine; files the scene refers to (materials, URDF) are not hashed.
    pub id: String,
    /// The overrides, applied in order after the sweep's `--set` ones (which they include).
    pub overrides: Vec<(String, toml::Value)>,
}

/// A sweep's points for one scene.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The scene file.
    pub scene: PathBuf,
    /// Its text, as hashed and run.
    pub source: String,
    /// The points, in order.
    pub points: Vec<Point>,
}

impl Plan {
    /// The points of `design` over `vary`, each after the common overrides `sets`. A scalar
    /// given for a key that holds an array in the scene (`--vary rig.slips=0,0.2`) stands for
    /// the one-element array (`rig.slips = [0.2]`). The scene file must read as TOML; each
    /// point's scene is validated when it runs, and a point with a bad value is recorded as
    /// failed with the one-line error while the others go on.
    pub fn new(
        scene: &Path,
        sets: &[(String, toml::Value)],
        vary: &[Vary],
        design: Design,
    ) -> Result<Self, InputError> {
        let source = read_text(scene)?;
        let table: toml::Table = crate::input::parse_toml(scene, &source)?;
        for v in vary {
            if sets.iter().any(|(k, _)| *k == v.key) {
                return Err(InputError::flag("--vary", format!("{} is both --set and --vary", v.key)));
            }
        }
        let points = points(vary, design)?
            .into_iter()
            .enumerate()
            .map(|(index, varied)| {
                let mut o: Vec<(String, toml::Value)> = sets.to_vec();
                for (k, v) in varied {
                    let v = match (overrides::get(&table, &k), v) {
                        (Some(toml::Value::Array(_)), v @ toml::Value::Array(_)) => v,
                        (Some(toml::Value::Array(_)), v) => toml::Value::Array(vec![v]),
                        (_, v) => v,
                    };
                    o.push((k, v));
                }
                Point { index, id: config_hash(&source, &o), overrides: o }
            })
            .collect();
        Ok(Self { scene: scene.to_path_buf(), source, points })
    }

    /// A plan of explicit points: each list of overrides is one point, in order (the accuracy
    /// study's ladders and one-knob changes). The scene file must read as TOML.
    pub fn from_overrides(scene: &Path, lists: Vec<Vec<(String, toml::Value)>>) -> Result<Self, InputError> {
        let source = read_text(scene)?;
        let _: toml::Table = crate::input::parse_toml(scene, &source)?;
        let points = lists
            .into_iter()
            .enumerate()
            .map(|(index, o)| Point { index, id: config_hash(&source, &o), overrides: o })
            .collect();
        Ok(Self { scene: scene.to_path_buf(), source, points })
    }

    /// Runs point `p`, writing its outputs under `out/points/<id>/`. Never fails: a bad value
    /// or a failed run is the record's `error`. No peak memory is recorded (other points may
    /// share the process); see [`Plan::run_point_alone`].
    pub fn run_point(&self, p: &Point, out: &Path) -> Record {
        self.run_point_measured(p, out, false)
    }

    /// [`Plan::run_point`] for a point that has the process to itself: the process's peak
    /// resident memory is reset before it runs and recorded after (`peak_mem_bytes`).
    pub fn run_point_alone(&self, p: &Point, out: &Path) -> Record {
        self.run_point_measured(p, out, true)
    }

    fn run_point_measured(&self, p: &Point, out: &Path, alone: bool) -> Record {
        let measure = alone && reset_peak_rss();
        let t0 = Instant::now();
        let dir = Path::new("points").join(&p.id);
        let mut rec = Record {
            point: p.index,
            id: p.id.clone(),
            status: "failed".into(),
            overrides: p.overrides.iter().map(|(k, v)| (k.clone(), toml_to_json(v))).collect::<BTreeMap<_, _>>(),
            wall_s: 0.0,
            peak_mem_bytes: None,
            error: None,
            out: dir.display().to_string(),
            summary: None,
        };
        match load_scene_source(&self.scene, &self.source, &p.overrides) {
            Err(e) => rec.error = Some(e.to_string()),
            Ok(mut scene) => {
                let dir = out.join(&dir);
                if let Err(m) = crate::build::backend::resolve_backend(&mut scene) {
                    rec.error = Some(format!("simulation.backend: {m}"));
                    rec.wall_s = t0.elapsed().as_secs_f64();
                    return rec;
                }
                match run_scene(&scene, &RunOptions::quiet(&dir)) {
                    Ok(s) => {
                        rec.status = "ok".into();
                        rec.summary = serde_json::to_value(&s).ok();
                    }
                    Err(e) => {
                        rec.error = Some(crate::error::report(&e));
                        // A run that failed after it started wrote its summary.
                        rec.summary = std::fs::read_to_string(dir.join("summary.json"))
                            .ok()
                            .and_then(|t| serde_json::from_str(&t).ok());
                    }
                }
            }
        }
        rec.wall_s = t0.elapsed().as_secs_f64();
        if measure {
            rec.peak_mem_bytes = peak_rss_bytes();
        }
        rec
    }

    /// The points of `shard` (all without one) that `done` does not hold: those without a
    /// record, and the failed ones when `retry_failed`.
    pub fn pending(&self, shard: Option<Shard>, done: &[Record], retry_failed: bool) -> Vec<Point> {
        let tasks = self.tasks();
        pending(&tasks, shard, done, retry_failed).into_iter().map(|t| t.point.clone()).collect()
    }

    /// The points as tasks of the shared runner.
    pub fn tasks(&self) -> Vec<PlanPoint<'_>> {
        self.points.iter().map(|point| PlanPoint { plan: self, point }).collect()
    }
}

/// A point of a plan, as the runner schedules it.
pub struct PlanPoint<'a> {
    plan: &'a Plan,
    point: &'a Point,
}

impl Task for PlanPoint<'_> {
    fn index(&self) -> usize {
        self.point.index
    }
    fn id(&self) -> &str {
        &self.point.id
    }
    fn label(&self) -> String {
        format!("point {}", self.point.index)
    }
    fn run(&self, out: &Path, alone: bool) -> Record {
        self.plan.run_point_measured(self.point, out, alone)
    }
}

/// FNV-1a, 64 bit, of the scene text and the overrides.
fn config_hash(source: &str, overrides: &[(String, toml::Value)]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(source.as_bytes());
    for (k, v) in overrides {
        eat(b"\0");
        eat(k.as_bytes());
        eat(b"=");
        eat(v.to_string().as_bytes());
    }
    format!("{h:016x}")
}

/// Runs a sweep's pending points on `jobs` threads of this process, appending each record as
/// it finishes, then writes `results.csv` (unsharded runs; shards are joined by [`merge`]).
/// Progress lines go to stderr unless `quiet`.
pub fn run_local(
    plan: &Plan,
    out: &Path,
    shard: Option<Shard>,
    jobs: usize,
    retry_failed: bool,
    quiet: bool,
) -> Result<Outcome, InputError> {
    let outcome = run_tasks("sweep", &plan.tasks(), out, shard, jobs, retry_failed, quiet)?;
    if shard.is_none() {
        write_csv(out, &read_all(out)?)?;
    }
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_depends_on_text_and_overrides_only() {
        let o = vec![("a.b".to_string(), toml::Value::Float(0.5))];
        assert_eq!(config_hash("x = 1", &o), config_hash("x = 1", &o.clone()));
        assert_ne!(config_hash("x = 1", &o), config_hash("x = 2", &o));
        assert_ne!(config_hash("x = 1", &o), config_hash("x = 1", &[("a.b".into(), toml::Value::Float(0.25))]));
        assert_eq!(config_hash("", &[]), "cbf29ce484222325", "FNV-1a offset basis");
    }
}
