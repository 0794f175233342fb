//! Calibration from measurements (`regolith calibrate`): fits with standard errors, and the
//! MCC parameters of a soil from its isotropic compression and critical-state data.
//!
//! - [`fit`]: least-squares lines, slopes and the Mohr–Coulomb envelope of Mohr circles;
//! - [`mcc`]: λ, κ, v_λ, OCR and M from laboratory rows;
//! - [`calibrate_mcc`]: the whole command: read, fit, write `mcc.json`, the plot and a ready
//!   material file.

pub mod fit;
pub mod mcc;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::input::{InputError, read_text};
use crate::material::load_material_file;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use mcc::{CalibrateError, CriticalStateFit, IsotropicData, IsotropicFit};

/// What `regolith calibrate mcc` reads.
#[derive(Clone, Debug)]
pub struct McCInputs {
    /// Isotropic compression CSV (`p` in Pa, and `v` or `e`).
    pub isotropic: PathBuf,
    /// Critical states CSV (`p`, `q` in Pa), optional.
    pub critical: Option<PathBuf>,
    /// A material file whose other keys (density, elasticity, safeguards) the written material
    /// keeps; without it no material file is written.
    pub base: Option<PathBuf>,
    /// Output directory.
    pub out: PathBuf,
}

/// `mcc.json`.
#[derive(Clone, Debug, Serialize)]
pub struct McCReport {
    /// The isotropic data file.
    pub isotropic_file: String,
    /// The isotropic fit.
    pub isotropic: IsotropicFit,
    /// The critical-state data file.
    pub critical_file: Option<String>,
    /// The critical-state fit.
    pub critical_state: Option<CriticalStateFit>,
    /// The material file written (None without `--base`).
    pub material_file: Option<String>,
    /// Plots written.
    pub plots: Vec<String>,
}

/// Why `calibrate mcc` failed.
#[derive(Debug, thiserror::Error)]
pub enum McCError {
    /// A wrong input file or flag.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The data cannot be fitted (names the file).
    #[error("{file}: {source}")]
    Data {
        /// The data file.
        file: PathBuf,
        /// Why.
        source: CalibrateError,
    },
    /// An output could not be written.
    #[error("{0}")]
    Output(String),
}

/// Reads the data, fits, and writes `mcc.json`, `isotropic.png/svg` and (with a base material)
/// `material.toml`, which is read back through the material loader before it is reported.
pub fn calibrate_mcc(inp: &McCInputs) -> Result<McCReport, McCError> {
    let data = mcc::read_isotropic(&inp.isotropic)?;
    let iso = mcc::fit_isotropic(&data).map_err(|source| McCError::Data { file: inp.isotropic.clone(), source })?;
    let cs = match &inp.critical {
        Some(path) => {
            let (p, q) = mcc::read_critical_states(path)?;
            Some(mcc::fit_critical_state(&p, &q).map_err(|source| McCError::Data { file: path.clone(), source })?)
        }
        None => None,
    };
    let base = inp.base.as_ref().map(|b| load_material_file(b).map(|_| b)).transpose()?;
    std::fs::create_dir_all(&inp.out)
        .map_err(|e| McCError::Output(format!("cannot create {}: {e}", inp.out.display())))?;
    let material_file = match base {
        Some(b) => Some(write_material(b, &iso, cs.as_ref(), &inp.out.join("material.toml"))?),
        None => None,
    };
    let plots = write_figure(&isotropic_figure(&data, &iso), &inp.out, "isotropic")
        .map_err(|e| McCError::Output(e.to_string()))?;
    let report = McCReport {
        isotropic_file: inp.isotropic.display().to_string(),
        isotropic: iso,
        critical_file: inp.critical.as_ref().map(|p| p.display().to_string()),
        critical_state: cs,
        material_file: material_file.map(|p| p.display().to_string()),
        plots: plots.iter().map(|p| p.display().to_string()).collect(),
    };
    let json = inp.out.join("mcc.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| McCError::Output(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| McCError::Output(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// The base material with the fitted keys set (and the keys they replace removed), checked by
/// loading it back.
fn write_material(
    base: &Path,
    iso: &IsotropicFit,
    cs: Option<&CriticalStateFit>,
    out: &Path,
) -> Result<PathBuf, McCError> {
    let source = read_text(base)?;
    let mut t: toml::Table =
        source.parse().map_err(|e: toml::de::Error| InputError::file(base, e.message().to_string()))?;
    t.insert("model".into(), "mcc".into());
    for k in ["mcc_cr", "mcc_cc", "cohesion", "mu_i_friction_angle", "mu_i_i0", "grain_diameter", "grain_density"] {
        t.remove(k);
    }
    t.insert("mcc_lambda".into(), iso.lambda.into());
    t.insert("mcc_kappa".into(), iso.kappa.into());
    t.insert("mcc_v_lambda".into(), iso.v_lambda.into());
    t.insert("ocr".into(), iso.ocr.into());
    if let Some(cs) = cs {
        t.remove("friction_angle");
        t.insert("mcc_m".into(), cs.m.into());
    } else if !t.contains_key("mcc_m") && !t.contains_key("friction_angle") {
        return Err(InputError::key(
            base,
            "mcc_m",
            "is needed for the written material: give --critical with critical-state rows, or mcc_m (or friction_angle) in the base material",
        )
        .into());
    }
    let body = toml::to_string(&t).map_err(|e| McCError::Output(e.to_string()))?;
    let text = format!(
        "# Written by `regolith calibrate mcc` from {} (λ, κ, v_λ at {} Pa, OCR{}); other keys from {}.\n{body}",
        iso_source(iso),
        iso.p_ref,
        if cs.is_some() { ", M" } else { "" },
        base.display()
    );
    std::fs::write(out, text).map_err(|e| McCError::Output(format!("cannot write {}: {e}", out.display())))?;
    load_material_file(out)?;
    Ok(out.to_path_buf())
}

fn iso_source(iso: &IsotropicFit) -> String {
    format!("{} NCL rows, κ from {}", iso.ncl_rows, iso.kappa_from)
}

/// v against p (log axis): the rows, the fitted NCL and the swelling line through p_c0.
pub fn isotropic_figure(d: &IsotropicData, f: &IsotropicFit) -> Figure {
    let (lo, hi) = d.p.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &p| (a.min(p), b.max(p)));
    let samples = |a: f64, b: f64| (0..=40).map(move |i| a * (b / a).powf(f64::from(i) / 40.0));
    let ncl: Vec<(f64, f64)> =
        samples(lo.min(f.pc0), hi).map(|p| (p, f.v_lambda - f.lambda * (p / f.p_ref).ln())).collect();
    let v_c = f.v_lambda - f.lambda * (f.pc0 / f.p_ref).ln();
    let swell: Vec<(f64, f64)> =
        samples(lo, f.pc0.max(lo * 1.0001)).map(|p| (p, v_c + f.kappa * (f.pc0 / p).ln())).collect();
    Figure {
        panels: vec![Panel {
            title: format!("isotropic compression, OCR {:.2}", f.ocr),
            x_label: "mean pressure p (Pa)".into(),
            y_label: "specific volume v".into(),
            x_log: true,
            series: vec![
                Series::points("data", d.p.iter().copied().zip(d.v.iter().copied()).collect()),
                Series::line(format!("NCL: λ = {:.4}, v_λ = {:.4}", f.lambda, f.v_lambda), ncl),
                Series::line(format!("swelling to p_c0: κ = {:.4}", f.kappa), swell),
            ],
            x_range: None,
            y_range: None,
        }],
    }
}
