//! A study case's `[[expect]]` checks and `[study.<size>]` overrides, read from the scene
//! file's own TOML (a run ignores both sections).
//!
//! ```toml
//! [[expect]]
//! metric = "max_soil_speed"   # one of `Metric::ALL`
//! max = 3.0                   # and/or min
//! why = "the rim moves at 0.3 m/s; soil thrown by a grouser is a few times that"
//!
//! [[expect]]
//! metric = "body_depth"
//! body = "ball"               # the body metrics name one
//! min = 0.01
//!
//! [[expect]]
//! metric = "uehara_ratio"     # report = true: tabulated against its band, not a verdict
//! body = "ball"
//! min = 0.33
//! max = 3.0
//! report = true
//!
//! [study.ci]                  # what the `ci` size changes (`--set` keys and values)
//! "simulation.end_time" = 0.3
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use crate::input::{InputError, parse_toml};

/// What a check measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Metric {
    /// Largest soil particle speed over the run (m/s).
    MaxSoilSpeed,
    /// Largest soil particle speed at the end (m/s).
    FinalSoilSpeed,
    /// Fraction of the particles that left the domain.
    EscapedFraction,
    /// Particles beyond the container's side walls or below its floor (by more than half a
    /// spacing, below the top of the walls): soil that went through a wall.
    Leaked,
    /// Largest number, over the run, of soil particle centres more than half a spacing inside
    /// an FSI body.
    InsideBodies,
    /// Largest soil kinetic energy in the second half of a run over that of the first half.
    KeGrowth,
    /// Root-mean-square soil speed `sqrt(2 KE / M)` at the end (m/s).
    RmsSpeedFinal,
    /// Largest displacement of a particle still in the domain from where it started (m).
    MaxDisplacement,
    /// Final height of the body's shape origin (m).
    BodyZ,
    /// Final speed of the body's centre of mass (m/s).
    BodySpeed,
    /// Mean speed of the body over the last quarter of the run (m/s): the net displacement
    /// of its origin over that time, divided by the time. A body at rest, or rocking in place
    /// (stick-slip), shows a mean far below its instantaneous peaks; a body still sinking or
    /// sliding does not.
    BodyMeanSpeed,
    /// How deep the body's lowest point ends below the initial soil surface under it (m):
    /// sinkage, crater depth.
    BodyDepth,
    /// [`Metric::BodyDepth`] of a sphere over Uehara et al. (2003)'s penetration depth of a
    /// ball dropped into dry sand.
    UeharaRatio,
    /// The run must stop with a one-line report naming the particle (a fault injected on
    /// purpose); the measured figure is 1 when it did.
    ReportedFailure,
    /// The scene must be refused before running, with a message holding `contains`.
    Refused,
}

impl Metric {
    /// Every metric, with its name in files.
    pub const ALL: [(Metric, &'static str); 15] = [
        (Metric::MaxSoilSpeed, "max_soil_speed"),
        (Metric::FinalSoilSpeed, "final_soil_speed"),
        (Metric::EscapedFraction, "escaped_fraction"),
        (Metric::Leaked, "leaked"),
        (Metric::InsideBodies, "inside_bodies"),
        (Metric::KeGrowth, "ke_growth"),
        (Metric::RmsSpeedFinal, "rms_speed_final"),
        (Metric::MaxDisplacement, "max_displacement"),
        (Metric::BodyZ, "body_z"),
        (Metric::BodySpeed, "body_speed"),
        (Metric::BodyMeanSpeed, "body_mean_speed"),
        (Metric::BodyDepth, "body_depth"),
        (Metric::UeharaRatio, "uehara_ratio"),
        (Metric::ReportedFailure, "reported_failure"),
        (Metric::Refused, "refused"),
    ];

    /// Its name in files and tables.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(m, _)| *m == self).map_or("?", |(_, n)| n)
    }

    /// Its unit (empty: none).
    pub fn unit(self) -> &'static str {
        match self {
            Self::MaxSoilSpeed | Self::FinalSoilSpeed | Self::RmsSpeedFinal | Self::BodySpeed | Self::BodyMeanSpeed => {
                "m/s"
            }
            Self::MaxDisplacement | Self::BodyZ | Self::BodyDepth => "m",
            Self::Leaked | Self::InsideBodies => "particles",
            _ => "",
        }
    }

    /// Whether the check names a body.
    pub fn needs_body(self) -> bool {
        matches!(self, Self::BodyZ | Self::BodySpeed | Self::BodyMeanSpeed | Self::BodyDepth | Self::UeharaRatio)
    }
}

/// One check of a case.
#[derive(Clone, Debug, PartialEq)]
pub struct Expectation {
    /// What is measured.
    pub metric: Metric,
    /// The name of the body it is about, for body metrics.
    pub body: Option<String>,
    /// Lower bound.
    pub min: Option<f64>,
    /// Upper bound.
    pub max: Option<f64>,
    /// For [`Metric::Refused`]: text the refusal must hold.
    pub contains: Option<String>,
    /// Why the bound is what a correct run shows.
    pub why: String,
    /// Measured and tabulated against its band, but not part of the verdict (`report = true`:
    /// a comparison with a law the model is not expected to meet closely, stated with its miss).
    pub report_only: bool,
}

impl Expectation {
    /// Whether `value` is within the bounds.
    pub fn holds(&self, value: f64) -> bool {
        value.is_finite() && self.min.is_none_or(|m| value >= m) && self.max.is_none_or(|m| value <= m)
    }

    /// The bounds as text (`≤ 3`, `[0.01, 0.2]`, `≥ 1`).
    pub fn bound_text(&self) -> String {
        match (self.min, self.max) {
            (Some(a), Some(b)) => format!("[{a}, {b}]"),
            (Some(a), None) => format!("≥ {a}"),
            (None, Some(b)) => format!("≤ {b}"),
            (None, None) => match &self.contains {
                Some(c) => format!("refused: \"{c}\""),
                None => "holds".into(),
            },
        }
    }
}

/// The study sections of a case file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CaseSpec {
    /// Its checks, in file order.
    pub expect: Vec<Expectation>,
    /// Per size (`ci`, `full`): the `--set` overrides that make the case that size.
    pub sizes: BTreeMap<String, Vec<(String, toml::Value)>>,
    /// `[study] known_failure = "why"`: a defect the case exposes and that is not fixed yet.
    /// The case is then expected to fail (reported as a known failure); passing is an error,
    /// so the mark cannot outlive the fix.
    pub known_failure: Option<String>,
}

/// The sizes a case may define.
pub const SIZES: [&str; 2] = ["ci", "full"];

#[derive(Deserialize)]
struct CaseFile {
    #[serde(default)]
    expect: Vec<ExpectFile>,
    study: Option<toml::Table>,
    #[serde(default)]
    bodies: Vec<BodyName>,
}

#[derive(Deserialize)]
struct BodyName {
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExpectFile {
    metric: Option<String>,
    body: Option<String>,
    min: Option<f64>,
    max: Option<f64>,
    contains: Option<String>,
    why: Option<String>,
    report: Option<bool>,
}

/// Reads the `[[expect]]` checks and `[study.*]` sizes of a case file's text. Every case must
/// say at least one check, and every check why its bound holds.
pub fn read_case(path: &Path, source: &str) -> Result<CaseSpec, InputError> {
    let file: CaseFile = parse_toml(path, source)?;
    let e = |key: String, msg: String| InputError::key(path, key, msg).located(source);
    if file.expect.is_empty() {
        return Err(e("expect".into(), "a study case needs at least one [[expect]] check".into()));
    }
    let names: Vec<&str> = file.bodies.iter().filter_map(|b| b.name.as_deref()).collect();
    let mut expect = Vec::new();
    for (i, x) in file.expect.into_iter().enumerate() {
        let key = |k: &str| format!("expect[{i}].{k}");
        let allowed = Metric::ALL.iter().map(|(_, n)| *n).collect::<Vec<_>>().join(", ");
        let name = x.metric.ok_or_else(|| e(key("metric"), format!("is required: one of {allowed}")))?;
        let metric = Metric::ALL
            .iter()
            .find(|(_, n)| *n == name)
            .map(|(m, _)| *m)
            .ok_or_else(|| e(key("metric"), format!("\"{name}\" is not a metric; allowed: {allowed}")))?;
        let why = x
            .why
            .filter(|w| !w.trim().is_empty())
            .ok_or_else(|| e(key("why"), "is required: say why the bound is what a correct run shows".into()))?;
        match (&x.body, metric.needs_body()) {
            (None, true) => return Err(e(key("body"), format!("is required for {name}: a body's name"))),
            (Some(_), false) => return Err(e(key("body"), format!("applies to body metrics only, not {name}"))),
            (Some(b), true) if !names.contains(&b.as_str()) => {
                return Err(e(
                    key("body"),
                    format!("\"{b}\" is not a body of this scene; bodies: {}", names.join(", ")),
                ));
            }
            _ => {}
        }
        for (k, v) in [("min", x.min), ("max", x.max)] {
            if v.is_some_and(|v| !v.is_finite()) {
                return Err(e(key(k), "must be finite".into()));
            }
        }
        if let (Some(a), Some(b)) = (x.min, x.max)
            && a > b
        {
            return Err(e(key("min"), format!("{a} is above max = {b}")));
        }
        match metric {
            Metric::Refused => {
                if x.contains.is_none() || x.min.is_some() || x.max.is_some() {
                    return Err(e(
                        key("contains"),
                        "refused takes `contains` (text of the refusal), no min/max".into(),
                    ));
                }
            }
            Metric::ReportedFailure => {
                if x.min.is_some() || x.max.is_some() || x.contains.is_some() {
                    return Err(e(key("metric"), "reported_failure takes no min, max or contains".into()));
                }
            }
            _ => {
                if x.contains.is_some() {
                    return Err(e(key("contains"), "applies to metric = \"refused\" only".into()));
                }
                if x.min.is_none() && x.max.is_none() {
                    return Err(e(key("max"), format!("{name} needs a bound: min, max or both")));
                }
            }
        }
        let report_only = x.report.unwrap_or(false);
        if report_only && matches!(metric, Metric::Refused | Metric::ReportedFailure) {
            return Err(e(key("report"), format!("{name} is a verdict; it cannot be report-only")));
        }
        expect.push(Expectation {
            metric,
            body: x.body,
            min: x.min,
            max: x.max,
            contains: x.contains,
            why,
            report_only,
        });
    }
    let mut sizes = BTreeMap::new();
    let mut known_failure = None;
    for (key, value) in file.study.unwrap_or_default() {
        match (key.as_str(), value) {
            ("known_failure", toml::Value::String(why)) if !why.trim().is_empty() => known_failure = Some(why),
            ("known_failure", _) => {
                return Err(e(
                    "study.known_failure".into(),
                    "must be a non-empty text: the defect and where it is tracked".into(),
                ));
            }
            (size, toml::Value::Table(t)) if SIZES.contains(&size) => {
                sizes.insert(key.clone(), t.into_iter().collect());
            }
            _ => {
                return Err(e(
                    format!("study.{key}"),
                    format!("is not a size table or known_failure; allowed: {}, known_failure", SIZES.join(", ")),
                ));
            }
        }
    }
    Ok(CaseSpec { expect, sizes, known_failure })
}
