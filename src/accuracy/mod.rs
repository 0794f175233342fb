//! `regolith study accuracy`: what accuracy costs in time. Each case of `examples/study/` is a
//! scene with an `[accuracy]` section (see [`case`]): a value of its summary, a reference (a
//! closed form, an experiment, or the limit of its own resolution ladder), and per budget a
//! d0 ladder and knobs turned one at a time from a baseline. Every point runs through the
//! sweep runner ([`crate::sweep::run_local`]: resumable, a finished point is never run again,
//! `--jobs` points at once, progress with an ETA) into `OUT/<case>/`; the study then writes
//! `accuracy.csv`, `accuracy.json`, `accuracy.md` and the plots of each case to `OUT`.

pub mod analysis;
pub mod case;
mod report;

pub use analysis::{CaseResult, Order, Row, TOLERANCES};
pub use case::{BUDGETS, Case, ReferenceKind};
pub use report::CSV_COLUMNS;

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::input::{InputError, read_text};
use crate::output::DRAWS_PLOTS;
use crate::study::StudyError;
use crate::study::stability::case_files;
use crate::sweep::{Plan, Record, read_all, run_local};

/// What to run.
#[derive(Clone, Debug)]
pub struct AccuracyOptions {
    /// The folder of case files.
    pub cases_dir: PathBuf,
    /// Case names (file stems); empty: every case with a section for the budget.
    pub cases: Vec<String>,
    /// `quick`, `standard` or `full`.
    pub budget: String,
    /// Points run at once.
    pub jobs: usize,
    /// Output folder.
    pub out: PathBuf,
    /// No progress lines.
    pub quiet: bool,
}

/// The study's outcome.
#[derive(Clone, Debug)]
pub struct Accuracy {
    /// Per case.
    pub cases: Vec<CaseResult>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// CPU model and core count of this machine, as the tables record it.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores")
}

/// The cases chosen for a budget, read and checked (every point's scene loads) before anything
/// runs.
pub fn read_cases(opts: &AccuracyOptions) -> Result<Vec<Case>, StudyError> {
    if !BUDGETS.contains(&opts.budget.as_str()) {
        return Err(InputError::flag(
            "--budget",
            format!("\"{}\" is not a budget; allowed: quick, standard, full", opts.budget),
        )
        .into());
    }
    if opts.jobs == 0 {
        return Err(InputError::flag("--jobs", "0 points at once runs nothing; allowed: 1 or more").into());
    }
    let all = case_files(&opts.cases_dir)?;
    for c in &opts.cases {
        if !all.iter().any(|(n, _)| n == c) {
            let names: Vec<&str> = all.iter().map(|(n, _)| n.as_str()).collect();
            return Err(InputError::flag(
                "--cases",
                format!("no case \"{c}\" in {}; cases: {}", opts.cases_dir.display(), names.join(", ")),
            )
            .into());
        }
    }
    let mut cases = Vec::new();
    for (name, path) in all {
        let text = read_text(&path)?;
        if opts.cases.is_empty() {
            // Every file with a section for this budget; scenes that are not accuracy cases
            // (or not at this budget) are passed over.
            if !case::has_budget(&path, &text, &opts.budget)? {
                continue;
            }
        } else if !opts.cases.contains(&name) {
            continue;
        }
        cases.push(case::read_case(&name, &path, &text, &opts.budget)?);
    }
    if cases.is_empty() {
        return Err(InputError::flag(
            "--budget",
            format!("no case of {} has an [accuracy.{}] section", opts.cases_dir.display(), opts.budget),
        )
        .into());
    }
    Ok(cases)
}

/// Runs the study (the points not yet recorded) and writes its tables and plots.
pub fn accuracy(opts: &AccuracyOptions) -> Result<Accuracy, StudyError> {
    let cases = read_cases(opts)?;
    let out = &opts.out;
    std::fs::create_dir_all(out).map_err(|e| StudyError::output(out, e))?;
    let machine = machine();
    let mut results = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        if !opts.quiet {
            eprintln!(
                "accuracy: case {} of {}: {} ({} points: {} ladder levels, {} knob settings)",
                k + 1,
                cases.len(),
                c.name,
                c.points.len(),
                c.ladder.len(),
                c.points.len() - c.ladder.len()
            );
        }
        let plan = plan_of(c)?;
        let dir = out.join(&c.name);
        // Failed points are tried again; finished ones never are.
        run_local(&plan, &dir, None, opts.jobs, true, opts.quiet)?;
        let by_id: BTreeMap<String, Record> = read_all(&dir)?.into_iter().map(|r| (r.id.clone(), r)).collect();
        let records: Vec<Option<Record>> = plan.points.iter().map(|p| by_id.get(&p.id).cloned()).collect();
        results.push(analysis::analyse(c, &records, &machine));
    }
    let mut files = Vec::new();
    let command = study_command(opts);
    let csv_path = out.join("accuracy.csv");
    crate::study::write_text(&csv_path, &report::csv(&results))?;
    files.push(csv_path);
    let json_path = out.join("accuracy.json");
    let json = serde_json::json!({
        "budget": opts.budget,
        "machine": machine,
        "command": command,
        "columns": CSV_COLUMNS,
        "cases": results,
    });
    let text = serde_json::to_string_pretty(&json).map_err(|e| StudyError::output(&json_path, e))?;
    crate::study::write_text(&json_path, &text)?;
    files.push(json_path);
    if DRAWS_PLOTS {
        for c in &results {
            files.extend(report::write_plots(c, out)?);
        }
    }
    let md_path = out.join("accuracy.md");
    crate::study::write_text(&md_path, &report::markdown(&results, &opts.budget, &machine, &command))?;
    files.push(md_path);
    Ok(Accuracy { cases: results, files })
}

/// A case's points as a sweep plan (its ladder levels, then its knob settings).
pub fn plan_of(c: &Case) -> Result<Plan, InputError> {
    Plan::from_overrides(&c.path, c.points.iter().map(|p| p.overrides.clone()).collect())
}

/// The command line that reproduces this study.
fn study_command(opts: &AccuracyOptions) -> String {
    let mut c = format!("regolith study accuracy --budget {} --cases-dir {}", opts.budget, opts.cases_dir.display());
    if !opts.cases.is_empty() {
        c.push_str(&format!(" --cases {}", opts.cases.join(",")));
    }
    c.push_str(&format!(" --jobs {} --out {}", opts.jobs, opts.out.display()));
    c
}
