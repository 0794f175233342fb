//! Calibration from measurements (`regolith calibrate`): fits with standard errors, and the
//! MCC parameters of a soil from its isotropic compression and critical-state data.
//!
//! - [`fit`]: least-squares lines, slopes and the Mohr–Coulomb envelope of Mohr circles;
//! - [`mcc`]: λ, κ, v_λ, OCR and M from laboratory rows;
//! - [`calibrate_mcc`]: the whole command: read, fit, write `mcc.json`, the plot and a ready
//!   material file;
//! - [`calibrate_envelope`]: c and φ from triaxial failure stresses (`envelope.json` with the
//!   field names AGX users know, and the Mohr-circle plot);
//! - [`repose`]: the static angle of repose of the SPH soil (lifted hollow cylinder), and
//!   the friction angle that gives a target angle;
//! - [`triaxial`]: the virtual triaxial test of the SPH soil (six servo-controlled plates),
//!   c and φ with standard errors, and the friction angle that gives a target φ;
//! - [`lowpass`]: the zero-phase Butterworth filter and the failure pick of a triaxial test;
//! - [`target`]: the calibration loop (a safeguarded secant over one material parameter).

pub mod cone;
pub mod fit;
pub mod lowpass;
pub mod mcc;
pub mod plate;
pub mod repose;
pub mod target;
pub mod triaxial;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::input::{InputError, read_text};
use crate::material::load_material_file;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use fit::{FitError, MohrCoulomb};
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

/// Why a `regolith calibrate` command failed.
#[derive(Debug, thiserror::Error)]
pub enum CommandError {
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
    /// A simulation the command runs failed (names the scene or material).
    #[error("{0}")]
    Run(String),
}

/// A flag's value must be a finite number > 0; the error names the flag.
pub(crate) fn positive(flag: &'static str, v: f64) -> Result<(), (&'static str, String)> {
    if v.is_finite() && v > 0.0 { Ok(()) } else { Err((flag, format!("must be a finite number > 0 (got {v})"))) }
}

/// Reads the data, fits, and writes `mcc.json`, `isotropic.png/svg` and (with a base material)
/// `material.toml`, which is read back through the material loader before it is reported.
pub fn calibrate_mcc(inp: &McCInputs) -> Result<McCReport, CommandError> {
    let data = mcc::read_isotropic(&inp.isotropic)?;
    let iso = mcc::fit_isotropic(&data).map_err(|source| CommandError::Data { file: inp.isotropic.clone(), source })?;
    let cs = match &inp.critical {
        Some(path) => {
            let (p, q) = mcc::read_critical_states(path)?;
            Some(mcc::fit_critical_state(&p, &q).map_err(|source| CommandError::Data { file: path.clone(), source })?)
        }
        None => None,
    };
    let base = inp.base.as_ref().map(|b| load_material_file(b).map(|_| b)).transpose()?;
    std::fs::create_dir_all(&inp.out)
        .map_err(|e| CommandError::Output(format!("cannot create {}: {e}", inp.out.display())))?;
    let material_file = match base {
        Some(b) => Some(write_material(b, &iso, cs.as_ref(), &inp.out.join("material.toml"))?),
        None => None,
    };
    let plots = write_figure(&isotropic_figure(&data, &iso), &inp.out, "isotropic")
        .map_err(|e| CommandError::Output(e.to_string()))?;
    let report = McCReport {
        isotropic_file: inp.isotropic.display().to_string(),
        isotropic: iso,
        critical_file: inp.critical.as_ref().map(|p| p.display().to_string()),
        critical_state: cs,
        material_file: material_file.map(|p| p.display().to_string()),
        plots: plots.iter().map(|p| p.display().to_string()).collect(),
    };
    let json = inp.out.join("mcc.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| CommandError::Output(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// The base material with the fitted keys set (and the keys they replace removed), checked by
/// loading it back.
fn write_material(
    base: &Path,
    iso: &IsotropicFit,
    cs: Option<&CriticalStateFit>,
    out: &Path,
) -> Result<PathBuf, CommandError> {
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
    let body = toml::to_string(&t).map_err(|e| CommandError::Output(e.to_string()))?;
    let text = format!(
        "# Written by `regolith calibrate mcc` from {} (λ, κ, v_λ at {} Pa, OCR{}); other keys from {}.\n{body}",
        iso_source(iso),
        iso.p_ref,
        if cs.is_some() { ", M" } else { "" },
        base.display()
    );
    std::fs::write(out, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", out.display())))?;
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
            y_log: false,
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

/// A Mohr–Coulomb envelope with the failure stresses it was fitted to, under AGX's field
/// names.
#[derive(Clone, Debug, Serialize)]
pub struct Envelope {
    /// Cohesion c (Pa).
    pub c: f64,
    /// Friction angle φ (degrees).
    pub phi: f64,
    /// Standard error of c (Pa); `null` with fewer than three tests.
    #[serde(rename = "standardError_c")]
    pub standard_error_c: Option<f64>,
    /// Standard error of φ (degrees); `null` with fewer than three tests.
    #[serde(rename = "standardError_phi")]
    pub standard_error_phi: Option<f64>,
    /// Confining (minor principal) stress of each test (Pa).
    #[serde(rename = "consolidationStress")]
    pub consolidation_stress: Vec<f64>,
    /// Vertical (major principal) stress at failure of each test (Pa).
    #[serde(rename = "verticalStress")]
    pub vertical_stress: Vec<f64>,
}

impl Envelope {
    /// The envelope fitted to σ3 and σ1 at failure (Pa, compression positive), and the fit.
    pub fn fit(s3: &[f64], s1: &[f64]) -> Result<(Self, MohrCoulomb), FitError> {
        let f = fit::mohr_coulomb(s3, s1)?;
        let e = Self {
            c: f.c,
            phi: f.phi,
            standard_error_c: f.se_c,
            standard_error_phi: f.se_phi,
            consolidation_stress: s3.to_vec(),
            vertical_stress: s1.to_vec(),
        };
        Ok((e, f))
    }
}

/// `envelope.json`: the Mohr–Coulomb fit of triaxial failure stresses, with the field names of
/// AGX's triaxial calibration output.
#[derive(Clone, Debug, Serialize)]
pub struct EnvelopeReport {
    /// The data file.
    pub file: String,
    /// The envelope and the stresses it was fitted to.
    #[serde(flatten)]
    pub envelope: Envelope,
    /// Plots written.
    pub plots: Vec<String>,
}

/// Reads `sigma3,sigma1` rows (Pa, compression positive: confining and vertical stress at
/// failure), fits the tangent Mohr–Coulomb envelope, writes `envelope.json` and
/// `mohr.png`/`.svg` into `out`.
pub fn calibrate_envelope(file: &Path, out: &Path) -> Result<EnvelopeReport, CommandError> {
    let (s3, s1) = mcc::read_failure_stresses(file)?;
    let (envelope, f) = Envelope::fit(&s3, &s1).map_err(|source| CommandError::Data {
        file: file.to_path_buf(),
        source: CalibrateError::Fit { what: "Mohr–Coulomb envelope", source },
    })?;
    std::fs::create_dir_all(out).map_err(|e| CommandError::Output(format!("cannot create {}: {e}", out.display())))?;
    let figure = mohr_figure(&envelope.consolidation_stress, &envelope.vertical_stress, &f);
    let plots = write_figure(&figure, out, "mohr").map_err(|e| CommandError::Output(e.to_string()))?;
    let report = EnvelopeReport {
        file: file.display().to_string(),
        envelope,
        plots: plots.iter().map(|p| p.display().to_string()).collect(),
    };
    let json = out.join("envelope.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| CommandError::Output(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// The Mohr circles (upper halves) and the fitted envelope τ = c + σ tan φ.
pub fn mohr_figure(s3: &[f64], s1: &[f64], f: &MohrCoulomb) -> Figure {
    let mut series: Vec<Series> = s3
        .iter()
        .zip(s1)
        .enumerate()
        .map(|(i, (a, b))| {
            let (centre, radius) = (0.5 * (a + b), 0.5 * (b - a));
            let pts = (0..=60)
                .map(|k| {
                    let t = std::f64::consts::PI * f64::from(k) / 60.0;
                    (centre + radius * t.cos(), radius * t.sin())
                })
                .collect();
            Series::line(format!("test {}: σ3 = {:.3e} Pa", i + 1, a), pts)
        })
        .collect();
    // Axes to about the same scale (the plot area is about 0.8 as high as it is wide), so
    // that circles look round and the tangent points can be seen; the envelope ends inside.
    let x_max = 1.05 * s1.iter().copied().fold(0.0, f64::max);
    let y_max = 0.8 * x_max;
    let tan = f.phi.to_radians().tan();
    let x_end = ((y_max - f.c) / tan).clamp(0.0, x_max);
    series.push(Series::line(
        format!("envelope: c = {:.4e} Pa, φ = {:.2}°", f.c, f.phi),
        vec![(0.0, f.c), (x_end, f.c + x_end * tan)],
    ));
    Figure {
        panels: vec![Panel {
            title: "Mohr circles at failure".into(),
            x_label: "normal stress σ (Pa)".into(),
            y_label: "shear stress τ (Pa)".into(),
            x_log: false,
            y_log: false,
            series,
            x_range: Some((0.0, x_max)),
            y_range: Some((0.0, y_max)),
        }],
    }
}
