//! `regolith study stability` and `regolith study accuracy`.

use std::path::Path;

use anyhow::anyhow;

use super::Failure;
use crate::study::StudyError;
use crate::study::stability::{CaseResult, StabilityOptions, stability};

pub(super) fn stability_cmd(opts: &StabilityOptions) -> Result<(), Failure> {
    let results = stability(opts).map_err(study_failure)?;
    let (text, failed) = stability_verdict(&results, &opts.out);
    println!("{text}");
    match failed {
        None => Ok(()),
        Some(f) => Err(Failure::Run(anyhow!("{f}"))),
    }
}

/// A study error as the CLI reports it.
pub(super) fn study_failure(e: StudyError) -> Failure {
    match e {
        StudyError::Input(e) => Failure::Input(e),
        e => Failure::Run(anyhow::Error::new(e)),
    }
}

/// The suite's verdict line, and the failure when a case fails its bounds.
pub(super) fn stability_verdict(results: &[CaseResult], out: &Path) -> (String, Option<String>) {
    let failed: Vec<&str> = results.iter().filter(|r| !r.pass).map(|r| r.case.as_str()).collect();
    let wall: f64 = results.iter().map(|r| r.wall_s).sum();
    let known: Vec<&str> =
        results.iter().filter(|r| r.pass && r.known_failure.is_some()).map(|r| r.case.as_str()).collect();
    let known_text = if known.is_empty() {
        String::new()
    } else {
        format!(", {} fail as known ({})", known.len(), known.join(", "))
    };
    let text = format!(
        "{} of {} cases pass{known_text}, in {wall:.1} s; table in {}",
        results.len() - failed.len() - known.len(),
        results.len(),
        out.join("stability.md").display()
    );
    let failure = (!failed.is_empty()).then(|| format!("cases failing their bounds: {}", failed.join(", ")));
    (text, failure)
}

pub(super) fn accuracy_cmd(opts: &crate::accuracy::AccuracyOptions) -> Result<(), Failure> {
    let a = crate::accuracy::accuracy(opts).map_err(study_failure)?;
    let (text, failed) = accuracy_text(&a, &opts.out);
    println!("{text}");
    match failed {
        None => Ok(()),
        Some(f) => Err(Failure::Run(anyhow!("{f}"))),
    }
}

/// Per case its order and cheapest setting within 5 %, as printed; and the failure when
/// points failed.
pub(super) fn accuracy_text(a: &crate::accuracy::Accuracy, out: &Path) -> (String, Option<String>) {
    let mut text = String::new();
    let mut failed = Vec::new();
    for c in &a.cases {
        let n_failed = c.rows.iter().filter(|r| r.failure.is_some()).count();
        if n_failed > 0 {
            failed.push(format!("{} ({n_failed} of {})", c.case, c.rows.len()));
        }
        let best = c.cheapest.iter().find(|(t, _)| *t == 0.05).and_then(|(_, i)| *i);
        text.push_str(&format!(
            "{}: order {:.2} ({}); within 5 %: {}\n",
            c.case,
            c.order.order,
            c.order.method,
            best.map_or("not reached".to_string(), |i| {
                let r = &c.rows[i];
                if r.knob == "d0" {
                    format!("d0 = {} ({:.1} s)", r.setting, r.wall_s)
                } else {
                    format!("{} = {} at d0 = {} ({:.1} s)", r.knob, r.setting, r.d0, r.wall_s)
                }
            })
        ));
    }
    text.push_str(&format!("table in {}", out.join("accuracy.md").display()));
    let failure = (!failed.is_empty()).then(|| format!("points failed in: {} (see accuracy.md)", failed.join(", ")));
    (text, failure)
}
