//! Studies and calibrations whose runs are independent (the stability suite's cases, a
//! triaxial envelope's tests) run on threads of this process, or one Ray task each through the
//! Python package's runner (`regolith.batch`). For the latter a batch is named by its command
//! line: [`open`] parses it as the CLI does, and the Python side asks for the pending runs,
//! runs each in a Ray task ([`Batch::run`], the same code the threads run) and appends its
//! record, then lets [`Batch::finish`] write the tables from the records.

use std::path::{Path, PathBuf};

use clap::Parser;

use super::ray::{check_ray_flags, run_module};
use super::{
    BatchRunArgs, Cli, Command, Failure, FailureArg, FilterArg, MatchArg, PlateArgs, Precision, StabilityArgs,
    TriaxialArgs,
};
use crate::calibrate::lowpass::FilterKind;
use crate::calibrate::plate::{PlateInputs, PlatePlan};
use crate::calibrate::triaxial::{
    EnvelopeSource, FailureRule, TriaxialInputs, TriaxialPlan, TriaxialSettings, default_rule, envelope_of_recorded,
};
use crate::input::InputError;
use crate::study::stability::{StabilityOptions, StabilityPlan};
use crate::sweep::{Plan, PlanPoint, Record, Task, forget, pending, read_all};

impl TriaxialArgs {
    /// The calibration's inputs (the material is read for its default failure rule).
    pub fn inputs(&self) -> Result<TriaxialInputs, Failure> {
        let mut s = TriaxialSettings::for_width(self.width);
        if let Some(h) = self.height {
            s.height = h;
        }
        if let Some(d) = self.spacing {
            s.spacing = d;
        }
        if !self.confining.is_empty() {
            s.confining = self.confining.clone();
        }
        s.strain_rate = self.strain_rate;
        s.max_strain = self.max_strain;
        s.failure = match self.failure {
            Some(FailureArg::Peak) => FailureRule::Peak,
            Some(FailureArg::Plateau) => FailureRule::Plateau,
            None => default_rule(&self.material)?,
        };
        s.filter = match self.filter {
            FilterArg::Gaussian => FilterKind::Gaussian,
            FilterArg::Butterworth => FilterKind::Butterworth,
        };
        match (s.filter, self.filter_order) {
            (FilterKind::Butterworth, Some(n)) => s.filter_order = n,
            (FilterKind::Gaussian, Some(_)) => {
                return Err(InputError::flag(
                    "--filter-order",
                    "applies to --filter butterworth only (a Gaussian has no order)",
                )
                .into());
            }
            (_, None) => {}
        }
        s.filter_wavelength = self.filter_wavelength;
        s.servo_crossings = self.servo_crossings;
        s.precision = match self.precision {
            Precision::F32 => crate::scene::Precision::F32,
            Precision::F64 => crate::scene::Precision::F64,
        };
        Ok(TriaxialInputs {
            material: self.material.clone(),
            settings: s,
            out: self.out.clone(),
            jobs: self.runner.jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            resume: self.runner.resume,
            target_phi: self.target_phi,
            tolerance_phi: self.tolerance,
            target_c: self.target_c,
            matching: match self.matching {
                Some(_) if self.target_phi.is_none() && self.target_c.is_none() => {
                    return Err(InputError::flag("--match", "applies to --target-phi or --target-c only").into());
                }
                Some(MatchArg::Plates) => EnvelopeSource::Plates,
                Some(MatchArg::Particles) | None => EnvelopeSource::Particles,
            },
            tolerance_c: self.tolerance_c,
        })
    }
}

impl PlateArgs {
    /// The calibration's inputs.
    pub fn inputs(&self) -> Result<PlateInputs, Failure> {
        let sets = self
            .sets
            .iter()
            .map(|s| crate::scene::parse_set(s).map_err(|m| InputError::flag("--set", m)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PlateInputs {
            scene: self.scene.clone(),
            sizes: self.sizes.clone(),
            sets,
            out: self.out.clone(),
            jobs: self.runner.jobs.unwrap_or(1),
            resume: self.runner.resume,
        })
    }
}

impl StabilityArgs {
    /// The study's options.
    pub fn options(&self) -> StabilityOptions {
        StabilityOptions {
            cases_dir: self.cases_dir.clone(),
            cases: self.cases.clone(),
            size: match self.size {
                super::SizeArg::Ci => "ci".into(),
                super::SizeArg::Full => "full".into(),
            },
            out: self.out.clone(),
            quiet: false,
            jobs: self.runner.jobs.unwrap_or(1),
            resume: self.runner.resume,
        }
    }
}

/// Refuses the Ray flags on the threads runner.
pub(super) fn threads_only(r: &BatchRunArgs) -> Result<(), Failure> {
    for (flag, given) in
        [("--address", r.address.is_some()), ("--num-cpus", r.num_cpus.is_some()), ("--num-gpus", r.num_gpus.is_some())]
    {
        if given {
            return Err(InputError::flag(flag, "applies to --runner ray only").into());
        }
    }
    if r.jobs == Some(0) {
        return Err(InputError::flag("--jobs", "0 runs at once runs nothing; allowed: 1 or more").into());
    }
    Ok(())
}

/// A triaxial calibration loop (`--target-phi`, `--target-c`) is no batch: its rounds run
/// one after another.
pub(super) fn no_loop_on_ray(a: &TriaxialArgs) -> Result<(), Failure> {
    match (a.target_phi, a.target_c) {
        (None, None) => Ok(()),
        (phi, _) => Err(InputError::flag(
            if phi.is_some() { "--target-phi" } else { "--target-c" },
            "its rounds run one after another; use --runner threads (each round's tests still run in parallel)",
        )
        .into()),
    }
}

/// Hands the command (this process's own arguments) to the Python package's Ray runner
/// (`regolith.batch`) and passes its exit code on.
pub(super) fn ray(r: &BatchRunArgs, what: &str) -> Result<(), Failure> {
    check_ray_flags(r.jobs, r.num_cpus, r.num_gpus)?;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (python, status) = run_module("batch", &args)?;
    match status.code() {
        Some(0) => Ok(()),
        Some(c @ (1 | 2)) => Err(Failure::Reported(c as u8)),
        Some(130) => Err(Failure::Interrupted(format!(
            "{what} interrupted; rerun it with --resume to run only what is not yet recorded"
        ))),
        _ => Err(Failure::Run(anyhow::anyhow!("the Ray runner ({python}, regolith.batch) failed: {status}"))),
    }
}

/// A batch named by its command line.
#[derive(Debug)]
pub enum Batch {
    /// `study stability ...`.
    Stability(StabilityPlan),
    /// `calibrate triaxial ...` (without `--target-phi` or `--target-c`: their rounds depend
    /// on each other).
    Triaxial(TriaxialInputs, TriaxialPlan),
    /// `calibrate plate ...`.
    Plate(PlatePlan),
    /// `study accuracy ...`: every case's points, each recorded in its case's folder.
    Accuracy(crate::accuracy::AccuracyOptions, Vec<(String, Plan)>),
}

/// A point of the accuracy study, numbered across its cases.
struct AccuracyPoint<'a> {
    index: usize,
    case: &'a str,
    point: PlanPoint<'a>,
}

impl Task for AccuracyPoint<'_> {
    fn index(&self) -> usize {
        self.index
    }
    fn id(&self) -> &str {
        self.point.id()
    }
    fn label(&self) -> String {
        format!("case {} point {}", self.case, self.point.index())
    }
    fn run(&self, out: &Path, alone: bool) -> Record {
        self.point.run(&out.join(self.case), alone)
    }
}

/// A failure as one line.
pub fn failure_line(f: &Failure) -> String {
    match f {
        Failure::Input(e) => e.to_string(),
        Failure::Run(e) => format!("{e:#}"),
        Failure::Interrupted(m) => m.clone(),
        Failure::Reported(c) => format!("exit code {c}"),
    }
}

/// Parses `args` (the command line after `regolith`) into a batch. Only the batch commands
/// are accepted; the runner flags are left to the caller.
pub fn open(args: &[String]) -> Result<Batch, Failure> {
    let cli =
        Cli::try_parse_from(std::iter::once("regolith".to_string()).chain(args.iter().cloned())).map_err(|e| {
            let text = e.render().to_string();
            let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("invalid arguments").trim().to_string();
            Failure::Input(InputError::flag("arguments", first))
        })?;
    match cli.command {
        Command::Study { study: super::StudyCommand::Stability(a) } => {
            Ok(Batch::Stability(StabilityPlan::new(&a.options()).map_err(super::study::study_failure)?))
        }
        Command::Calibrate { calibrate: super::CalibrateCommand::Triaxial(a) } => {
            no_loop_on_ray(&a)?;
            let inp = a.inputs()?;
            inp.settings.check().map_err(|(flag, msg)| InputError::flag(flag, msg))?;
            let material = crate::calibrate::target::material_table(&inp.material)?;
            let plan = TriaxialPlan::new(&material, &inp.settings, &inp.out).map_err(super::calibrate::failure)?;
            Ok(Batch::Triaxial(inp, plan))
        }
        Command::Study { study: super::StudyCommand::Accuracy { cases, budget, cases_dir, out, runner } } => {
            let opts = super::accuracy_options(cases, budget, cases_dir, out, runner.jobs.unwrap_or(1));
            let plans = crate::accuracy::read_cases(&opts)
                .map_err(super::study::study_failure)?
                .iter()
                .map(|c| Ok((c.name.clone(), crate::accuracy::plan_of(c)?)))
                .collect::<Result<Vec<_>, InputError>>()?;
            Ok(Batch::Accuracy(opts, plans))
        }
        Command::Calibrate { calibrate: super::CalibrateCommand::Plate(a) } => {
            Ok(Batch::Plate(PlatePlan::new(&a.inputs()?).map_err(super::calibrate::failure)?))
        }
        _ => Err(InputError::flag(
            "arguments",
            "not a batch command; allowed: `study stability ...`, `study accuracy ...`, `calibrate triaxial ...`, `calibrate plate ...`",
        )
        .into()),
    }
}

impl Batch {
    /// What the progress lines call it.
    pub fn what(&self) -> &'static str {
        match self {
            Self::Stability(_) => "stability",
            Self::Triaxial(..) => "triaxial",
            Self::Plate(_) => "plate",
            Self::Accuracy(..) => "accuracy",
        }
    }

    /// Its folder (records and outputs).
    pub fn out(&self) -> &Path {
        match self {
            Self::Stability(p) => &p.out,
            Self::Triaxial(_, p) => &p.dir,
            Self::Plate(p) => &p.inputs.out,
            Self::Accuracy(o, _) => &o.out,
        }
    }

    /// Calls `f` with the batch's runs.
    fn with_tasks<R>(&self, f: impl FnOnce(&[&dyn Task]) -> R) -> R {
        match self {
            Self::Stability(p) => f(&p.cases.iter().map(|t| t as &dyn Task).collect::<Vec<_>>()),
            Self::Triaxial(_, p) => f(&p.tests.iter().map(|t| t as &dyn Task).collect::<Vec<_>>()),
            Self::Plate(p) => {
                let points = p.plan.tasks();
                f(&points.iter().map(|t| t as &dyn Task).collect::<Vec<_>>())
            }
            Self::Accuracy(_, plans) => {
                let points: Vec<AccuracyPoint> = plans
                    .iter()
                    .flat_map(|(case, plan)| plan.tasks().into_iter().map(move |point| (case.as_str(), point)))
                    .enumerate()
                    .map(|(index, (case, point))| AccuracyPoint { index, case, point })
                    .collect();
                f(&points.iter().map(|t| t as &dyn Task).collect::<Vec<_>>())
            }
        }
    }

    /// Every run as `(index, id, label, folder its record goes to)`.
    pub fn runs(&self) -> Vec<(usize, String, String, PathBuf)> {
        let folders: Vec<PathBuf> = match self {
            Self::Accuracy(o, plans) => {
                plans.iter().flat_map(|(case, plan)| plan.points.iter().map(move |_| o.out.join(case))).collect()
            }
            _ => Vec::new(),
        };
        self.with_tasks(|ts| {
            ts.iter()
                .map(|t| {
                    let folder = folders.get(t.index()).cloned().unwrap_or_else(|| self.out().to_path_buf());
                    (t.index(), t.id().to_string(), t.label(), folder)
                })
                .collect()
        })
    }

    /// The records so far (the accuracy study: of every case's folder).
    fn done(&self) -> Result<Vec<Record>, InputError> {
        match self {
            Self::Accuracy(o, plans) => {
                let mut all = Vec::new();
                for (case, _) in plans {
                    all.extend(read_all(&o.out.join(case))?);
                }
                Ok(all)
            }
            _ => read_all(self.out()),
        }
    }

    /// The runs to do: all (the records are forgotten first) unless `resume`, then those not
    /// recorded (and the failed ones when `retry_failed`).
    pub fn pending(&self, resume: bool, retry_failed: bool) -> Result<Vec<usize>, Failure> {
        std::fs::create_dir_all(self.out()).map_err(|e| InputError::file(self.out(), format!("cannot create: {e}")))?;
        // The accuracy study always resumes, as its command does.
        if !resume && !matches!(self, Self::Accuracy(..)) {
            forget(self.out())?;
        }
        let done = self.done()?;
        Ok(self.with_tasks(|ts| pending(ts, None, &done, retry_failed).iter().map(|t| t.index()).collect()))
    }

    /// Runs run `index` (its record; the caller appends it to the results file).
    pub fn run(&self, index: usize) -> Result<Record, Failure> {
        let out = self.out();
        self.with_tasks(|ts| match ts.get(index) {
            Some(t) => Ok(t.run(out, false)),
            None => {
                Err(InputError::flag("index", format!("{index} is not a run of this batch (it has {})", ts.len()))
                    .into())
            }
        })
    }

    /// Writes the tables from the records; returns the text the CLI prints, or the failure
    /// (a case failing its bounds, a run not carried out).
    pub fn finish(&self) -> Result<String, Failure> {
        match self {
            Self::Stability(p) => {
                let results = p.finish().map_err(super::study::study_failure)?;
                let (text, failed) = super::study::stability_verdict(&results, &p.out);
                match failed {
                    None => Ok(text),
                    Some(f) => Err(Failure::Run(anyhow::anyhow!("{text}\n{f}"))),
                }
            }
            Self::Triaxial(inp, _) => {
                let r = envelope_of_recorded(inp).map_err(super::calibrate::failure)?;
                Ok(format!("{}outputs in {}", super::calibrate::triaxial_text(&r), inp.out.display()))
            }
            Self::Plate(p) => {
                let r = p.finish().map_err(super::calibrate::failure)?;
                Ok(format!("{}outputs in {}", super::calibrate::plate_text(&r), p.inputs.out.display()))
            }
            Self::Accuracy(o, _) => {
                // Every point is recorded: the study runs nothing and writes its tables.
                let quiet = crate::accuracy::AccuracyOptions { quiet: true, ..o.clone() };
                let a = crate::accuracy::accuracy(&quiet).map_err(super::study::study_failure)?;
                let (text, failed) = super::study::accuracy_text(&a, &o.out);
                match failed {
                    None => Ok(text),
                    Some(f) => Err(Failure::Run(anyhow::anyhow!("{text}\n{f}"))),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::RunnerArg;

    #[test]
    fn only_batch_commands_open_and_the_target_loop_is_refused() {
        let args = |s: &str| s.split_whitespace().map(String::from).collect::<Vec<_>>();
        let e = open(&args("run examples/scenes/plate.toml")).map(|_| ()).map_err(|f| failure_line(&f));
        assert!(e.is_err_and(|m| m.contains("not a batch command")));
        let e = open(&args("calibrate triaxial --material m.toml --target-phi 30"))
            .map(|_| ())
            .map_err(|f| failure_line(&f));
        assert!(e.is_err_and(|m| m.contains("--target-phi")));
        let e = open(&args("study stability --size huge")).map(|_| ()).map_err(|f| failure_line(&f));
        assert!(e.is_err_and(|m| m.contains("huge")));
    }

    #[test]
    fn a_plate_calibration_opens_as_one_run_per_size() {
        let dir = std::env::temp_dir().join(format!("regolith-batch-plate-{}", std::process::id()));
        let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/scenes/plate_sinkage.toml");
        let args: Vec<String> =
            ["calibrate", "plate", "--scene", scene, "--sizes", "0.04,0.06", "--out", dir.to_str().unwrap_or(".")]
                .iter()
                .map(|s| s.to_string())
                .collect();
        let b = open(&args).map_err(|f| failure_line(&f)).expect("opens");
        assert_eq!(b.what(), "plate");
        let runs = b.runs();
        assert_eq!(runs.iter().map(|r| r.0).collect::<Vec<_>>(), vec![0, 1]);
        assert_ne!(runs[0].1, runs[1].1, "each size is its own configuration");
        assert_eq!(b.pending(false, false).map_err(|f| failure_line(&f)).expect("pending"), vec![0, 1]);
        assert!(b.run(5).is_err_and(|f| failure_line(&f).contains("5 is not a run")));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_runner_flags_of_the_other_runner_are_refused() {
        let r = BatchRunArgs {
            runner: RunnerArg::Threads,
            jobs: None,
            resume: false,
            address: Some("auto".into()),
            num_cpus: None,
            num_gpus: None,
        };
        assert!(threads_only(&r).is_err_and(|f| failure_line(&f).contains("--address")));
    }
}
