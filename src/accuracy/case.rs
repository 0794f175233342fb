//! An accuracy case: a scene with an `[accuracy]` section saying what to measure, against
//! what reference, and which points each budget runs.
//!
//! ```toml
//! [accuracy]
//! quantity = "normalised runout (R∞ − R0)/R0"
//! measure = "runout.normalized"        # a summary.json value (dotted path, [i] for arrays)
//! reference_from = "runout.lube_2004"  # or `reference = 0.62`; none for self-convergence
//! reference_kind = "experiment"        # closed-form | experiment | self-convergence
//! source = "Lube et al. (2004), J. Fluid Mech. 508, 175–199: ΔR/R0 = 1.24 a for a ≤ 1.7"
//! resolution = "sph.spacing"           # the ladder's key (the default)
//!
//! [accuracy.quick]
//! ladder = [0.02, 0.014142, 0.01, 0.007071]   # ≥ 4 levels, ratio √2 or 2
//! baseline = 0.01                             # where the knobs are turned (a ladder level)
//! set = { "simulation.end_time" = 0.3 }       # overrides every point of this budget takes
//! knobs = { "sph.h_factor" = [1.0, 1.5] }     # one key at a time, from the baseline
//! ```
//!
//! A run ignores the section, so every case is also a scene `regolith run` takes.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::input::{InputError, parse_toml};
use crate::scene::load_scene_source;

/// The budgets, cheapest first.
pub const BUDGETS: [&str; 3] = ["quick", "standard", "full"];

/// What the reference of a case is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// An exact solution of the continuum problem.
    ClosedForm,
    /// A measurement.
    Experiment,
    /// The Richardson limit of the case's own resolution ladder.
    SelfConvergence,
}

impl ReferenceKind {
    /// The name in case files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::ClosedForm => "closed-form",
            Self::Experiment => "experiment",
            Self::SelfConvergence => "self-convergence",
        }
    }
}

/// Where a reference value comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// A number stated in the case file.
    Value(f64),
    /// A value of each point's own summary (a closed form evaluated on the run's geometry).
    Summary(String),
    /// The Richardson limit of the ladder.
    Limit,
}

/// One point to run.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSpec {
    /// `d0` for a ladder level (the resolution key), else the knob's key.
    pub knob: String,
    /// The setting, as written.
    pub setting: toml::Value,
    /// The overrides, in order: the budget's `set`, the resolution, the knob.
    pub overrides: Vec<(String, toml::Value)>,
    /// Its resolution (m).
    pub d0: f64,
}

/// A case at one budget.
#[derive(Clone, Debug)]
pub struct Case {
    /// File stem.
    pub name: String,
    /// The scene file.
    pub path: PathBuf,
    /// Its text.
    pub source: String,
    /// What is measured, in words.
    pub quantity: String,
    /// The summary value measured.
    pub measure: String,
    /// The reference.
    pub reference: Reference,
    /// Its kind.
    pub kind: ReferenceKind,
    /// Where the reference comes from (publication, closed form).
    pub source_note: String,
    /// The ladder's key.
    pub resolution: String,
    /// The ladder, coarse to fine.
    pub ladder: Vec<f64>,
    /// The level the knobs are turned at.
    pub baseline: f64,
    /// Ladder levels first (coarse to fine), then one point per knob setting.
    pub points: Vec<PointSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AccuracyFile {
    quantity: String,
    measure: String,
    reference: Option<f64>,
    reference_from: Option<String>,
    reference_kind: String,
    source: String,
    resolution: Option<String>,
    quick: Option<BudgetFile>,
    standard: Option<BudgetFile>,
    full: Option<BudgetFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BudgetFile {
    ladder: Vec<f64>,
    baseline: Option<f64>,
    #[serde(default)]
    set: toml::Table,
    #[serde(default)]
    knobs: toml::Table,
}

#[derive(Debug, Deserialize)]
struct CaseFile {
    accuracy: Option<toml::Value>,
}

/// Whether the file at `path` (text `source`) is an accuracy case with a section for `budget`.
pub fn has_budget(path: &Path, source: &str, budget: &str) -> Result<bool, InputError> {
    let file: CaseFile = parse_toml(path, source)?;
    Ok(file.accuracy.as_ref().and_then(|a| a.get(budget)).is_some())
}

/// Reads the case `name` at `path` for `budget`, and checks every point's scene (a wrong key
/// or value is an error naming the file and key before anything runs).
pub fn read_case(name: &str, path: &Path, source: &str, budget: &str) -> Result<Case, InputError> {
    let key_err = |k: &str, m: String| InputError::key(path, k, m).located(source);
    let file: CaseFile = parse_toml(path, source)?;
    let Some(raw) = file.accuracy else {
        return Err(InputError::file(path, "has no [accuracy] section (what to measure and against what)"));
    };
    let a: AccuracyFile = raw
        .try_into()
        .map_err(|e: toml::de::Error| InputError::key(path, "accuracy", e.message().to_string()).located(source))?;
    let kind = match a.reference_kind.as_str() {
        "closed-form" => ReferenceKind::ClosedForm,
        "experiment" => ReferenceKind::Experiment,
        "self-convergence" => ReferenceKind::SelfConvergence,
        other => {
            return Err(key_err(
                "accuracy.reference_kind",
                format!("\"{other}\" is not a kind; allowed: closed-form, experiment, self-convergence"),
            ));
        }
    };
    let reference = match (kind, a.reference, a.reference_from) {
        (ReferenceKind::SelfConvergence, None, None) => Reference::Limit,
        (ReferenceKind::SelfConvergence, _, _) => {
            return Err(key_err(
                "accuracy.reference",
                "a self-convergence case takes its reference from its ladder; remove reference and reference_from"
                    .into(),
            ));
        }
        (_, Some(v), None) if v.is_finite() => Reference::Value(v),
        (_, None, Some(k)) if !k.trim().is_empty() => Reference::Summary(k),
        _ => {
            return Err(key_err(
                "accuracy.reference",
                format!(
                    "a {} case needs exactly one of reference (a finite number) and reference_from (a summary value)",
                    kind.name()
                ),
            ));
        }
    };
    if a.measure.trim().is_empty() {
        return Err(key_err("accuracy.measure", "is empty; give a summary.json value, e.g. runout.normalized".into()));
    }
    let resolution = a.resolution.unwrap_or_else(|| "sph.spacing".into());
    let b = match budget {
        "quick" => a.quick,
        "standard" => a.standard,
        "full" => a.full,
        other => {
            return Err(InputError::flag(
                "--budget",
                format!("\"{other}\" is not a budget; allowed: quick, standard, full"),
            ));
        }
    };
    let bkey = format!("accuracy.{budget}");
    let Some(b) = b else {
        return Err(InputError::file(
            path,
            format!("has no [{bkey}] section: this case does not run at the {budget} budget"),
        ));
    };
    let ladder = check_ladder(&b.ladder).map_err(|m| key_err(&format!("{bkey}.ladder"), m))?;
    let baseline = match b.baseline {
        Some(v) => ladder.iter().copied().find(|l| (l - v).abs() <= 1e-9 * v.abs()).ok_or_else(|| {
            key_err(&format!("{bkey}.baseline"), format!("{v} is not a level of the ladder {:?}", ladder))
        })?,
        None => ladder[ladder.len() / 2],
    };
    let mut common: Vec<(String, toml::Value)> = Vec::new();
    for (k, v) in &b.set {
        if *k == resolution {
            return Err(key_err(&format!("{bkey}.set"), format!("sets the ladder's key {k}; the ladder gives it")));
        }
        common.push((k.clone(), v.clone()));
    }
    let mut points: Vec<PointSpec> = ladder
        .iter()
        .map(|&d| {
            let mut o = common.clone();
            o.push((resolution.clone(), toml::Value::Float(d)));
            PointSpec { knob: "d0".into(), setting: toml::Value::Float(d), overrides: o, d0: d }
        })
        .collect();
    for (k, values) in &b.knobs {
        let kkey = format!("{bkey}.knobs");
        if *k == resolution || b.set.contains_key(k) {
            return Err(key_err(&kkey, format!("{k} is the ladder's key or in set; a knob must be another key")));
        }
        let toml::Value::Array(values) = values else {
            return Err(key_err(&kkey, format!("{k} must be a list of settings, e.g. [1.0, 1.5]")));
        };
        if values.is_empty() {
            return Err(key_err(&kkey, format!("{k} has no setting")));
        }
        for v in values {
            let mut o = common.clone();
            o.push((resolution.clone(), toml::Value::Float(baseline)));
            o.push((k.clone(), v.clone()));
            points.push(PointSpec { knob: k.clone(), setting: v.clone(), overrides: o, d0: baseline });
        }
    }
    // Every point's scene must load: a wrong key or value is reported now, with its file.
    for p in &points {
        load_scene_source(path, source, &p.overrides)?;
    }
    Ok(Case {
        name: name.to_string(),
        path: path.to_path_buf(),
        source: source.to_string(),
        quantity: a.quantity,
        measure: a.measure,
        reference,
        kind,
        source_note: a.source,
        resolution,
        ladder,
        baseline,
        points,
    })
}

/// At least four distinct positive levels at a ratio of √2 or 2 (within 1 %), sorted coarse
/// to fine.
fn check_ladder(ladder: &[f64]) -> Result<Vec<f64>, String> {
    if ladder.len() < 4 {
        return Err(format!("has {} levels; a ladder needs at least 4", ladder.len()));
    }
    if let Some(v) = ladder.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(format!("{v} is not a positive length"));
    }
    let mut l = ladder.to_vec();
    l.sort_by(|a, b| b.total_cmp(a));
    for w in l.windows(2) {
        let r = w[0] / w[1];
        let ok = [std::f64::consts::SQRT_2, 2.0].iter().any(|t| (r / t - 1.0).abs() <= 0.01);
        if !ok {
            return Err(format!("levels {} and {} are at ratio {r:.4}; allowed: √2 or 2 (within 1 %)", w[0], w[1]));
        }
    }
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladders_need_four_levels_at_root_two_or_two() {
        assert_eq!(check_ladder(&[0.01, 0.02, 0.005, 0.0025]).expect("ratio 2"), vec![0.02, 0.01, 0.005, 0.0025]);
        assert!(check_ladder(&[0.02, 0.014142, 0.01, 0.007071]).is_ok());
        assert!(check_ladder(&[0.02, 0.01, 0.005]).expect_err("3 levels").contains("at least 4"));
        assert!(check_ladder(&[0.02, 0.015, 0.01, 0.005]).expect_err("ratio 1.33").contains("ratio"));
        assert!(check_ladder(&[0.02, 0.01, 0.01, 0.005]).is_err(), "a repeated level");
        assert!(check_ladder(&[0.02, 0.01, -0.005, 0.0025]).is_err());
    }
}
