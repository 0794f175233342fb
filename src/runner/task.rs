//! The runner every batch of independent runs shares: a sweep's points, the stability suite's
//! cases, a triaxial calibration's tests. Each unit of work is a [`Task`] with a position and a
//! configuration hash; [`run_tasks`] runs the ones not yet recorded on threads of this
//! process, appends one [`Record`] per finished task to the batch's `results.jsonl` (so an
//! interrupted batch resumes where it stopped), records a failure without stopping the others,
//! and prints progress (done, running, failed, ETA). The Python package's Ray runner schedules
//! the same tasks, one Ray task each, through the same records.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use super::records::{Record, Shard, append, read_all, results_file};
use crate::input::InputError;

/// One unit of work of a batch.
pub trait Task: Sync {
    /// Position in the batch (0-based): shards split on it and records are ordered by it.
    fn index(&self) -> usize;
    /// Configuration hash: a task whose id is recorded as finished is not run again.
    fn id(&self) -> &str;
    /// What a progress line calls it (`point 3`, `case jet_at_wall`).
    fn label(&self) -> String;
    /// Runs it, writing its outputs under the batch folder `out`. Never fails: a failure is
    /// the record's `error`. `alone`: nothing else runs in this process meanwhile, so its peak
    /// memory can be measured.
    fn run(&self, out: &Path, alone: bool) -> Record;
}

impl<T: Task + ?Sized> Task for &T {
    fn index(&self) -> usize {
        (**self).index()
    }
    fn id(&self) -> &str {
        (**self).id()
    }
    fn label(&self) -> String {
        (**self).label()
    }
    fn run(&self, out: &Path, alone: bool) -> Record {
        (**self).run(out, alone)
    }
}

/// FNV-1a (64 bit, hex) of `parts`, each followed by a zero byte: the same parts give the same
/// id on every machine.
pub fn fnv_id(parts: &[&[u8]]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for b in part.iter().chain(std::iter::once(&0u8)) {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}

/// The tasks of `shard` (all without one) that `done` does not hold: those without a record,
/// and the failed ones when `retry_failed`.
pub fn pending<'a, T: Task>(tasks: &'a [T], shard: Option<Shard>, done: &[Record], retry_failed: bool) -> Vec<&'a T> {
    let finished: BTreeMap<&str, bool> = done.iter().map(|r| (r.id.as_str(), r.ok())).collect();
    tasks
        .iter()
        .filter(|t| shard.is_none_or(|s| s.holds(t.index())))
        .filter(|t| match finished.get(t.id()) {
            Some(true) => false,
            Some(false) => retry_failed,
            None => true,
        })
        .collect()
}

/// What a runner did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// Tasks of this shard in the batch.
    pub points: usize,
    /// Already recorded, so not run.
    pub skipped: usize,
    /// Run now and finished.
    pub ok: usize,
    /// Run now and failed.
    pub failed: usize,
}

/// Runs the pending tasks of a batch (see [`pending`]) on `jobs` threads of this process,
/// appending each record to `out`'s results file as it finishes. `what` names the batch in
/// the progress lines (stderr, unless `quiet`).
pub fn run_tasks<T: Task>(
    what: &str,
    tasks: &[T],
    out: &Path,
    shard: Option<Shard>,
    jobs: usize,
    retry_failed: bool,
    quiet: bool,
) -> Result<Outcome, InputError> {
    std::fs::create_dir_all(out).map_err(|e| InputError::file(out, format!("cannot create: {e}")))?;
    let done = read_all(out)?;
    let todo = pending(tasks, shard, &done, retry_failed);
    let points = tasks.iter().filter(|t| shard.is_none_or(|s| s.holds(t.index()))).count();
    let jobs = jobs.max(1);
    let mut outcome = Outcome { points, skipped: points - todo.len(), ..Outcome::default() };
    if !quiet {
        eprintln!(
            "{what}: {points} points{}, {} already recorded, {} to run on {jobs} thread(s)",
            shard.map(|s| format!(" in shard {}/{}", s.index, s.count)).unwrap_or_default(),
            outcome.skipped,
            todo.len(),
        );
    }
    let file = results_file(out, shard);
    let next = AtomicUsize::new(0);
    let state = Mutex::new((Progress::new(todo.len(), jobs), Ok::<(), InputError>(())));
    std::thread::scope(|s| {
        for _ in 0..jobs.min(todo.len().max(1)) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(t) = todo.get(i) else { break };
                    if let Ok(mut g) = state.lock() {
                        g.0.running += 1;
                    }
                    let rec = t.run(out, jobs == 1);
                    let Ok(mut g) = state.lock() else { break };
                    if let Err(e) = append(&file, &rec) {
                        g.1 = Err(e);
                    }
                    g.0.finish(&rec);
                    if !quiet {
                        eprintln!("{what}: {}", g.0.line(&t.label(), &rec));
                    }
                }
            });
        }
    });
    let (progress, written) = state.into_inner().map_err(|_| InputError::file(&file, "a runner thread panicked"))?;
    written?;
    outcome.ok = progress.ok;
    outcome.failed = progress.failed;
    Ok(outcome)
}

/// Removes a batch's records (`results.jsonl` and shard files), so that every task runs again.
pub fn forget(out: &Path) -> Result<(), InputError> {
    let entries = match std::fs::read_dir(out) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(InputError::file(out, format!("cannot list: {e}"))),
    };
    for p in entries.filter_map(|e| e.ok().map(|e| e.path())) {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if name == "results.jsonl" || (name.starts_with("results.shard-") && name.ends_with(".jsonl")) {
            std::fs::remove_file(&p).map_err(|e| InputError::file(&p, format!("cannot remove: {e}")))?;
        }
    }
    Ok(())
}

/// Tasks done, running and failed, and the time left at the pace so far.
struct Progress {
    total: usize,
    jobs: usize,
    ok: usize,
    failed: usize,
    running: usize,
    started: Instant,
}

impl Progress {
    fn new(total: usize, jobs: usize) -> Self {
        Self { total, jobs, ok: 0, failed: 0, running: 0, started: Instant::now() }
    }

    fn finish(&mut self, r: &Record) {
        self.running = self.running.saturating_sub(1);
        if r.ok() { self.ok += 1 } else { self.failed += 1 }
    }

    fn line(&self, label: &str, r: &Record) -> String {
        let done = self.ok + self.failed;
        let left = self.total - done;
        let eta = self.started.elapsed().as_secs_f64() / done.max(1) as f64 * left as f64 / self.jobs as f64;
        let what = match &r.error {
            None => "ok".to_string(),
            Some(e) => format!("FAILED: {e}"),
        };
        format!(
            "{label} ({}) {what} in {:.1} s; {done}/{} done, {} running, {} failed, ETA {}",
            r.id,
            r.wall_s,
            self.total,
            self.running,
            self.failed,
            eta_text(if left == 0 { 0.0 } else { eta })
        )
    }
}

/// `1h 02m`, `3m 20s` or `12 s`.
pub fn eta_text(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    if s >= 3600 {
        format!("{}h {:02}m", s / 3600, (s % 3600) / 60)
    } else if s >= 60 {
        format!("{}m {:02}s", s / 60, s % 60)
    } else {
        format!("{s} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Counting<'a> {
        index: usize,
        id: String,
        runs: &'a AtomicUsize,
        fail: bool,
    }

    impl Task for Counting<'_> {
        fn index(&self) -> usize {
            self.index
        }
        fn id(&self) -> &str {
            &self.id
        }
        fn label(&self) -> String {
            format!("task {}", self.index)
        }
        fn run(&self, _out: &Path, _alone: bool) -> Record {
            self.runs.fetch_add(1, Ordering::Relaxed);
            Record {
                point: self.index,
                id: self.id.clone(),
                status: if self.fail { "failed" } else { "ok" }.into(),
                overrides: BTreeMap::new(),
                wall_s: 0.0,
                peak_mem_bytes: None,
                error: self.fail.then(|| "bad".to_string()),
                out: String::new(),
                summary: None,
            }
        }
    }

    #[test]
    fn a_batch_resumes_records_failures_and_forgets() {
        let dir = std::env::temp_dir().join(format!("regolith-task-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let runs = AtomicUsize::new(0);
        let tasks: Vec<Counting> =
            (0..4).map(|i| Counting { index: i, id: fnv_id(&[b"t", &[i as u8]]), runs: &runs, fail: i == 2 }).collect();
        let o = run_tasks("test", &tasks, &dir, None, 2, false, true).expect("run");
        assert_eq!((o.points, o.skipped, o.ok, o.failed), (4, 0, 3, 1));
        assert_eq!(runs.load(Ordering::Relaxed), 4);
        // Finished tasks are not run again; the failed one is only with retry_failed.
        let o = run_tasks("test", &tasks, &dir, None, 1, false, true).expect("rerun");
        assert_eq!((o.skipped, o.ok + o.failed), (4, 0));
        let o = run_tasks("test", &tasks, &dir, None, 1, true, true).expect("retry");
        assert_eq!((o.skipped, o.failed), (3, 1));
        assert_eq!(runs.load(Ordering::Relaxed), 5);
        assert_eq!(read_all(&dir).expect("records").len(), 4);
        forget(&dir).expect("forget");
        assert!(read_all(&dir).expect("records").is_empty());
        let o = run_tasks("test", &tasks, &dir, Some(Shard { index: 2, count: 2 }), 1, false, true).expect("shard");
        assert_eq!((o.points, o.ok), (2, 2), "shard 2/2 holds tasks 1 and 3");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn ids_depend_on_every_part_and_its_boundaries() {
        assert_eq!(fnv_id(&[b"ab", b"c"]), fnv_id(&[b"ab", b"c"]));
        assert_ne!(fnv_id(&[b"ab", b"c"]), fnv_id(&[b"a", b"bc"]));
        assert_eq!(eta_text(3725.0), "1h 02m");
        assert_eq!(eta_text(200.0), "3m 20s");
    }
}
