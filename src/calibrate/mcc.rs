//! Modified Cam Clay parameters from laboratory data (`regolith calibrate mcc`).
//!
//! **Isotropic compression** (`p`, and `v` or `e` per row, in test order) gives λ, κ, v_λ and
//! the sample's overconsolidation:
//! - the rows are split into branches by the running maximum of p: a row that raises it is
//!   loading; the rows below it are an unloading/reloading excursion, which in MCC stays on one
//!   swelling line (each excursion also takes the row it turned at);
//! - κ is the common slope of the excursions in v–ln p (each with its own intercept); without
//!   one it comes from the recompression part of the first loading;
//! - the first loading is split where it joins the normal compression line (NCL): the split is
//!   the one with the smallest squared residuals of a swelling line (slope κ) before it and a
//!   free line after it; the NCL is fitted over the rows after the split and every later row
//!   that raises the maximum: `v = v_λ − λ ln(p / 1 kPa)` (Chrono's reference pressure);
//! - the isotropic yield pressure p_c0 is where the first swelling line meets the NCL, and the
//!   OCR is p_c0 over the first row's pressure (1 when the first loading starts on the NCL).
//!
//! **Critical states** (`p`, `q` per row, one row per triaxial test) give M as the slope of
//! q on p through the origin, and φ_cs = asin(3M / (6 + M)) for triaxial compression.

use std::path::Path;

use serde::Serialize;

use super::fit::{FitError, Line, common_slope, line, proportional};
use crate::input::{InputError, read_text};
use regolith_fsi::rheology::P_REF;

/// Reads a CSV of lab data: a header row naming the columns, `#` comments and blank lines
/// skipped, numbers separated by commas. Returns the columns asked for, in that order; `alt`
/// names a column accepted in place of the last one (with its name returned).
fn read_columns(path: &Path, want: &[&str], alt: Option<&str>) -> Result<(Vec<Vec<f64>>, String), InputError> {
    let text = read_text(path)?;
    let mut rows = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (hline, header) = rows.next().ok_or_else(|| InputError::file(path, "is empty: a header row is required"))?;
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_ascii_lowercase()).collect();
    let allowed = || {
        let mut a: Vec<&str> = want.to_vec();
        if let Some(x) = alt {
            a.push(x);
        }
        a.join(", ")
    };
    let missing = |w: &str| InputError {
        file: Some(path.to_path_buf()),
        line: Some(hline + 1),
        key: Some(format!("column {w}")),
        message: format!("is missing from the header `{}`; columns needed: {}", header.trim(), allowed()),
    };
    let find = |w: &str| names.iter().position(|n| n == w);
    let mut idx = Vec::new();
    let mut last_name = want[want.len() - 1].to_string();
    for (k, w) in want.iter().enumerate() {
        let i = match (find(w), alt) {
            (Some(i), _) => i,
            (None, Some(a)) if k + 1 == want.len() => {
                last_name = a.to_string();
                find(a).ok_or_else(|| missing(w))?
            }
            _ => return Err(missing(w)),
        };
        idx.push(i);
    }
    let mut cols = vec![Vec::new(); want.len()];
    for (ln, l) in rows {
        let cells: Vec<&str> = l.split(',').map(str::trim).collect();
        for (k, &i) in idx.iter().enumerate() {
            let name = if k + 1 == want.len() { last_name.as_str() } else { want[k] };
            let cell = cells.get(i).copied().unwrap_or("");
            let x: f64 = cell.parse().ok().filter(|x: &f64| x.is_finite()).ok_or_else(|| InputError {
                file: Some(path.to_path_buf()),
                line: Some(ln + 1),
                key: Some(format!("column {name}")),
                message: format!("`{cell}` is not a finite number"),
            })?;
            cols[k].push(x);
        }
    }
    Ok((cols, last_name))
}

/// Isotropic compression data: mean effective pressure (Pa) and specific volume per row.
#[derive(Clone, Debug, PartialEq)]
pub struct IsotropicData {
    /// Mean pressure (Pa), > 0.
    pub p: Vec<f64>,
    /// Specific volume v = 1 + e, > 1.
    pub v: Vec<f64>,
}

/// Reads `p` (Pa) and `v` (specific volume) or `e` (void ratio) columns.
pub fn read_isotropic(path: &Path) -> Result<IsotropicData, InputError> {
    let (cols, last) = read_columns(path, &["p", "v"], Some("e"))?;
    let p = cols[0].clone();
    let v: Vec<f64> = if last == "e" { cols[1].iter().map(|e| 1.0 + e).collect() } else { cols[1].clone() };
    let bad = |key: &str, msg: String| InputError::key(path, format!("column {key}"), msg);
    if p.len() < 4 {
        return Err(InputError::file(path, format!("has {} data rows; an isotropic test needs at least 4", p.len())));
    }
    if let Some((i, x)) = p.iter().enumerate().find(|(_, x)| **x <= 0.0) {
        return Err(bad("p", format!("row {} has p = {x}; pressures are > 0 Pa (compression positive)", i + 1)));
    }
    if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| **x <= 1.0) {
        return Err(bad(&last, format!("row {} gives v = {x}; the specific volume 1 + e is > 1", i + 1)));
    }
    Ok(IsotropicData { p, v })
}

/// Reads critical-state points: `p` and `q` columns (Pa), one row per test.
pub fn read_critical_states(path: &Path) -> Result<(Vec<f64>, Vec<f64>), InputError> {
    let (cols, _) = read_columns(path, &["p", "q"], None)?;
    if cols[0].is_empty() {
        return Err(InputError::file(path, "has no data rows; one row per triaxial test is needed"));
    }
    if let Some((i, x)) = cols[0].iter().enumerate().find(|(_, x)| **x <= 0.0) {
        return Err(InputError::key(path, "column p", format!("row {} has p = {x}; pressures are > 0 Pa", i + 1)));
    }
    Ok((cols[0].clone(), cols[1].clone()))
}

/// Reads triaxial failure stresses: `sigma3` (confining) and `sigma1` (vertical at failure)
/// columns in Pa, compression positive, one row per test.
pub fn read_failure_stresses(path: &Path) -> Result<(Vec<f64>, Vec<f64>), InputError> {
    let (cols, _) = read_columns(path, &["sigma3", "sigma1"], None)?;
    if cols[0].len() < 2 {
        return Err(InputError::file(
            path,
            format!("has {} data rows; an envelope needs at least 2 tests", cols[0].len()),
        ));
    }
    for (i, (a, b)) in cols[0].iter().zip(&cols[1]).enumerate() {
        if !(*a >= 0.0 && b > a) {
            return Err(InputError::key(
                path,
                "column sigma1",
                format!(
                    "row {} has sigma3 = {a}, sigma1 = {b}; failure needs 0 ≤ sigma3 < sigma1 (Pa, compression positive)",
                    i + 1
                ),
            ));
        }
    }
    Ok((cols[0].clone(), cols[1].clone()))
}

/// The isotropic fit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IsotropicFit {
    /// NCL slope λ in v–ln p.
    pub lambda: f64,
    /// Its standard error.
    pub se_lambda: Option<f64>,
    /// Swelling slope κ in v–ln p.
    pub kappa: f64,
    /// Its standard error.
    pub se_kappa: Option<f64>,
    /// Where κ came from: `"unloading"` (the excursions) or `"recompression"` (the first
    /// loading before the NCL).
    pub kappa_from: &'static str,
    /// Specific volume on the NCL at the reference pressure.
    pub v_lambda: f64,
    /// Its standard error.
    pub se_v_lambda: Option<f64>,
    /// Reference pressure of v_λ (Pa).
    pub p_ref: f64,
    /// Pressure of the first row (Pa).
    pub p0: f64,
    /// Isotropic yield (preconsolidation) pressure of the sample (Pa).
    pub pc0: f64,
    /// Overconsolidation ratio p_c0 / p0.
    pub ocr: f64,
    /// Rows on the NCL.
    pub ncl_rows: usize,
    /// Rows of the first loading before the NCL.
    pub recompression_rows: usize,
    /// Unloading/reloading excursions and their rows.
    pub excursions: usize,
    /// Rows in the excursions (each with its turning row).
    pub swelling_rows: usize,
    /// RMS residual of the NCL in v.
    pub ncl_rms: f64,
}

/// Why data could not be fitted.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// The data do not allow the fit; says what is missing.
    #[error("{0}")]
    Data(String),
    /// A fit failed.
    #[error("{what}: {source}")]
    Fit {
        /// Which fit.
        what: &'static str,
        /// The reason.
        source: FitError,
    },
}

fn fit_err(what: &'static str) -> impl Fn(FitError) -> CalibrateError {
    move |source| CalibrateError::Fit { what, source }
}

/// Fits λ, κ, v_λ and the OCR to isotropic compression data (see the module docs).
pub fn fit_isotropic(d: &IsotropicData) -> Result<IsotropicFit, CalibrateError> {
    let n = d.p.len();
    let x: Vec<f64> = d.p.iter().map(|p| (p / P_REF).ln()).collect();
    // Rows that raise the running maximum of p.
    let mut raises = vec![false; n];
    let mut max = f64::NEG_INFINITY;
    for (i, &p) in d.p.iter().enumerate() {
        if p > max {
            raises[i] = true;
            max = p;
        }
    }
    // Excursions below the maximum, each with the row it turned at.
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for i in 1..n {
        if !raises[i] {
            if raises[i - 1] {
                groups.push(vec![i - 1]);
            }
            if let Some(g) = groups.last_mut() {
                g.push(i);
            }
        }
    }
    let first_run = raises.iter().take_while(|r| **r).count();
    let take = |idx: &[usize]| -> (Vec<f64>, Vec<f64>) {
        (idx.iter().map(|&i| x[i]).collect(), idx.iter().map(|&i| d.v[i]).collect())
    };
    let swelling: Vec<(Vec<f64>, Vec<f64>)> = groups.iter().filter(|g| g.len() >= 2).map(|g| take(g)).collect();
    let kappa_unload = if swelling.is_empty() {
        None
    } else {
        let (b, se, _) = common_slope(&swelling).map_err(fit_err("swelling lines"))?;
        Some((-b, se))
    };
    // Split of the first loading: rows [0, k) on a swelling line, [k, first_run) on the NCL.
    let sse_line = |xs: &[f64], ys: &[f64], slope: Option<f64>| -> Option<(f64, f64, f64)> {
        match slope {
            Some(b) => {
                if xs.is_empty() {
                    return None;
                }
                let a = ys.iter().zip(xs).map(|(y, x)| y - b * x).sum::<f64>() / xs.len() as f64;
                Some((xs.iter().zip(ys).map(|(x, y)| (y - a - b * x).powi(2)).sum(), a, b))
            }
            None => {
                let l = line(xs, ys).ok()?;
                Some((l.rms_residual.powi(2) * xs.len() as f64, l.intercept, l.slope))
            }
        }
    };
    if first_run < 3 {
        return Err(CalibrateError::Data(format!(
            "the first loading has {first_run} rows raising the pressure; at least 3 are needed on the normal compression line"
        )));
    }
    let fixed = kappa_unload.map(|(k, _)| -k);
    let min_left = if fixed.is_some() { 1 } else { 2 };
    let (fx, fy) = take(&(0..first_run).collect::<Vec<_>>());
    // Splits whose residuals differ by round-off only are ties (exact data fit several).
    let ym = fy.iter().sum::<f64>() / fy.len() as f64;
    let tie = 1e-12 * fy.iter().map(|y| (y - ym).powi(2)).sum::<f64>();
    // (squared residuals, split, the swelling line's intercept and slope before it)
    type Split = (f64, usize, Option<(f64, f64)>);
    let mut best: Option<Split> = None;
    for k in std::iter::once(0).chain(min_left..=first_run - 3) {
        let right = sse_line(&fx[k..], &fy[k..], None).map_or(f64::INFINITY, |r| r.0);
        let (left, lab) = if k == 0 {
            (0.0, None)
        } else {
            match sse_line(&fx[..k], &fy[..k], fixed) {
                Some((s, a, b)) => (s, Some((a, b))),
                None => continue,
            }
        };
        // Ties go to the split with the most NCL rows (first found).
        if best.is_none_or(|(s, _, _)| left + right < s - tie) {
            best = Some((left + right, k, lab));
        }
    }
    let (_, split, left_line) =
        best.ok_or_else(|| CalibrateError::Data("no split of the first loading fits".into()))?;
    let ncl_idx: Vec<usize> = (split..n).filter(|&i| raises[i]).collect();
    let (nx, ny) = take(&ncl_idx);
    let ncl: Line = line(&nx, &ny).map_err(fit_err("normal compression line"))?;
    let lambda = -ncl.slope;
    let (kappa, se_kappa, kappa_from) = match (kappa_unload, left_line) {
        (Some((k, se)), _) => (k, se, "unloading"),
        (None, Some(_)) if split >= 3 => {
            let l = line(&fx[..split], &fy[..split]).map_err(fit_err("recompression line"))?;
            (-l.slope, l.se_slope, "recompression")
        }
        (None, Some((_, b))) => (-b, None, "recompression"),
        (None, None) => {
            return Err(CalibrateError::Data(
                "no unloading branch and no recompression part before the normal compression line: κ cannot be fitted; add an unload (rows with p below the largest p so far)".into(),
            ));
        }
    };
    if !(kappa > 0.0 && lambda > kappa) {
        return Err(CalibrateError::Data(format!(
            "the fitted slopes are λ = {lambda:.5}, κ = {kappa:.5}; MCC needs λ > κ > 0 (is v falling as p rises?)"
        )));
    }
    let p0 = d.p[0];
    let pc0 = match left_line {
        // v = a − κ x meets v = v_λ − λ x at x = (v_λ − a) / (λ − κ).
        Some((a, _)) => P_REF * ((ncl.intercept - a) / (lambda - kappa)).exp(),
        None => p0,
    };
    Ok(IsotropicFit {
        lambda,
        se_lambda: ncl.se_slope,
        kappa,
        se_kappa,
        kappa_from,
        v_lambda: ncl.intercept,
        se_v_lambda: ncl.se_intercept,
        p_ref: P_REF,
        p0,
        pc0,
        ocr: (pc0 / p0).max(1.0),
        ncl_rows: ncl_idx.len(),
        recompression_rows: split,
        excursions: swelling.len(),
        swelling_rows: swelling.iter().map(|g| g.0.len()).sum(),
        ncl_rms: ncl.rms_residual,
    })
}

/// The critical-state fit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CriticalStateFit {
    /// Critical-state slope M = q / p.
    pub m: f64,
    /// Its standard error.
    pub se_m: Option<f64>,
    /// The triaxial-compression friction angle asin(3M / (6 + M)) (degrees).
    pub phi_cs: f64,
    /// Tests fitted.
    pub tests: usize,
}

/// Fits M through the origin of q against p.
pub fn fit_critical_state(p: &[f64], q: &[f64]) -> Result<CriticalStateFit, CalibrateError> {
    let f = proportional(p, q).map_err(fit_err("critical state line"))?;
    let m = f.slope;
    if !(m > 0.0 && m < 3.0) {
        return Err(CalibrateError::Data(format!(
            "the critical-state slope is M = {m:.4}; triaxial compression allows 0 < M < 3"
        )));
    }
    Ok(CriticalStateFit { m, se_m: f.se_slope, phi_cs: (3.0 * m / (6.0 + m)).asin().to_degrees(), tests: f.points })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact piecewise data: recompression at κ to p_c0, the NCL to the top, an unload at κ.
    fn synthetic(p0: f64, pc0: f64, top: f64, low: f64, lambda: f64, kappa: f64, v_l: f64) -> IsotropicData {
        let ncl = |p: f64| v_l - lambda * (p / P_REF).ln();
        let mut p = Vec::new();
        let mut v = Vec::new();
        let geom = |a: f64, b: f64, k: usize| (0..=k).map(move |i| a * (b / a).powf(i as f64 / k as f64));
        if pc0 > p0 {
            for q in geom(p0, pc0, 5).take(5) {
                p.push(q);
                v.push(ncl(pc0) + kappa * (pc0 / q).ln());
            }
        }
        for q in geom(pc0, top, 10) {
            p.push(q);
            v.push(ncl(q));
        }
        for q in geom(top, low, 6).skip(1) {
            p.push(q);
            v.push(ncl(top) + kappa * (top / q).ln());
        }
        IsotropicData { p, v }
    }

    #[test]
    fn exact_piecewise_data_give_back_their_parameters() {
        let d = synthetic(20e3, 60e3, 800e3, 100e3, 0.12, 0.02, 2.4);
        let f = fit_isotropic(&d).expect("fit");
        assert!((f.lambda - 0.12).abs() < 1e-12 && (f.kappa - 0.02).abs() < 1e-12, "{f:?}");
        assert!((f.v_lambda - 2.4).abs() < 1e-12);
        assert!((f.ocr - 3.0).abs() < 1e-9, "OCR {}", f.ocr);
        assert_eq!((f.kappa_from, f.recompression_rows, f.excursions), ("unloading", 5, 1));
        // Without the unload, κ comes from the recompression part.
        let n = d.p.len() - 6;
        assert!((d.p[n - 1] - 800e3).abs() < 1e-6, "the unload is cut off");
        let f2 = fit_isotropic(&IsotropicData { p: d.p[..n].to_vec(), v: d.v[..n].to_vec() }).expect("fit");
        assert_eq!(f2.kappa_from, "recompression");
        assert!((f2.kappa - 0.02).abs() < 1e-12 && (f2.ocr - 3.0).abs() < 1e-9);
    }

    #[test]
    fn a_normally_consolidated_sample_has_ocr_one() {
        let d = synthetic(50e3, 50e3, 800e3, 100e3, 0.1, 0.01, 2.2);
        let f = fit_isotropic(&d).expect("fit");
        assert_eq!(f.recompression_rows, 0);
        assert!((f.ocr - 1.0).abs() < 1e-12 && (f.lambda - 0.1).abs() < 1e-12);
    }

    #[test]
    fn data_without_a_swelling_slope_or_a_rising_v_are_errors() {
        let p: Vec<f64> = (1..=8).map(|i| 1e4 * f64::from(i)).collect();
        let ncl: Vec<f64> = p.iter().map(|q| 2.0 - 0.1 * (q / P_REF).ln()).collect();
        let e = fit_isotropic(&IsotropicData { p: p.clone(), v: ncl }).expect_err("no κ");
        assert!(e.to_string().contains("κ cannot be fitted"), "{e}");
        let rising: Vec<f64> = p.iter().map(|q| 1.5 + 0.1 * (q / P_REF).ln()).collect();
        let mut p2 = p.clone();
        p2.push(5e4);
        let mut r2 = rising.clone();
        r2.push(1.5 + 0.1 * 50.0f64.ln());
        assert!(fit_isotropic(&IsotropicData { p: p2, v: r2 }).is_err());
    }

    #[test]
    fn critical_states_give_m_and_the_compression_angle() {
        let p = [50e3, 100e3, 200e3];
        let q: Vec<f64> = p.iter().map(|x| 1.2 * x).collect();
        let f = fit_critical_state(&p, &q).expect("fit");
        assert!((f.m - 1.2).abs() < 1e-14);
        assert!((f.phi_cs - 30.0).abs() < 1e-9, "asin(3.6 / 7.2) = 30°, got {}", f.phi_cs);
    }
}
