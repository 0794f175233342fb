//! `regolith study stability`.

use std::path::PathBuf;

use anyhow::anyhow;

use super::Failure;
use crate::study::StudyError;
use crate::study::stability::{StabilityOptions, stability};

pub(super) fn stability_cmd(cases_dir: PathBuf, cases: Vec<String>, size: String, out: PathBuf) -> Result<(), Failure> {
    let opts = StabilityOptions { cases_dir, cases, size, out: out.clone(), quiet: false };
    let results = stability(&opts).map_err(|e| match e {
        StudyError::Input(e) => Failure::Input(e),
        e => Failure::Run(anyhow::Error::new(e)),
    })?;
    let failed: Vec<&str> = results.iter().filter(|r| !r.pass).map(|r| r.case.as_str()).collect();
    let wall: f64 = results.iter().map(|r| r.wall_s).sum();
    let known: Vec<&str> =
        results.iter().filter(|r| r.pass && r.known_failure.is_some()).map(|r| r.case.as_str()).collect();
    let known_text = if known.is_empty() {
        String::new()
    } else {
        format!(", {} fail as known ({})", known.len(), known.join(", "))
    };
    println!(
        "{} of {} cases pass{known_text}, in {wall:.1} s; table in {}",
        results.len() - failed.len() - known.len(),
        results.len(),
        out.join("stability.md").display()
    );
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Failure::Run(anyhow!("cases failing their bounds: {}", failed.join(", "))))
    }
}
