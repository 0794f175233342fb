//! `regolith calibrate`.

use std::path::PathBuf;

use super::Failure;
use crate::calibrate::cone::{ConeInputs, calibrate_cone};
use crate::calibrate::plate::{PlateCalibration, PlateInputs, calibrate_plate};
use crate::calibrate::repose::{ReposeInputs, ReposeSettings, calibrate_repose};
use crate::calibrate::triaxial::{TriaxialInputs, TriaxialReport, calibrate_triaxial};
use crate::calibrate::{CommandError, McCInputs, calibrate_envelope, calibrate_mcc};
use crate::input::InputError;

pub(super) fn failure(e: CommandError) -> Failure {
    match e {
        CommandError::Input(e) => Failure::Input(e),
        CommandError::Data { file, source } => Failure::Input(InputError::file(&file, source.to_string())),
        CommandError::Output(m) | CommandError::Run(m) => Failure::Run(anyhow::anyhow!(m)),
    }
}

fn se(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |s| format!("{s:.2e}"))
}

pub(super) fn envelope(tests: PathBuf, out: PathBuf) -> Result<(), Failure> {
    let r = calibrate_envelope(&tests, &out).map_err(failure)?.envelope;
    println!(
        "Mohr–Coulomb envelope of {} tests: c = {:.4e} ± {} Pa, φ = {:.3}° ± {}°",
        r.consolidation_stress.len(),
        r.c,
        se(r.standard_error_c),
        r.phi,
        se(r.standard_error_phi)
    );
    println!("outputs in {}", out.display());
    Ok(())
}

pub(super) fn mcc(
    isotropic: PathBuf,
    critical: Option<PathBuf>,
    base: Option<PathBuf>,
    out: PathBuf,
) -> Result<(), Failure> {
    let r = calibrate_mcc(&McCInputs { isotropic, critical, base, out: out.clone() }).map_err(failure)?;
    let f = &r.isotropic;
    println!(
        "isotropic ({} NCL rows, {} recompression, {} excursion(s)): λ = {:.5} ± {}, κ = {:.5} ± {} (from {}), v_λ = {:.5} ± {} at {} Pa",
        f.ncl_rows,
        f.recompression_rows,
        f.excursions,
        f.lambda,
        se(f.se_lambda),
        f.kappa,
        se(f.se_kappa),
        f.kappa_from,
        f.v_lambda,
        se(f.se_v_lambda),
        f.p_ref
    );
    println!("  sample: p0 = {:.4e} Pa, p_c0 = {:.4e} Pa, OCR = {:.3}", f.p0, f.pc0, f.ocr);
    if let Some(c) = &r.critical_state {
        println!("critical state ({} tests): M = {:.4} ± {}, φ_cs = {:.2}°", c.tests, c.m, se(c.se_m), c.phi_cs);
    }
    match &r.material_file {
        Some(m) => println!("material: {m}"),
        None => println!("material.toml not written: give --base MATERIAL for density and elasticity"),
    }
    println!("outputs in {}", out.display());
    Ok(())
}

pub(super) fn repose(
    material: PathBuf,
    settings: ReposeSettings,
    target_angle: Option<f64>,
    tolerance: f64,
    out: PathBuf,
) -> Result<(), Failure> {
    let r = calibrate_repose(&ReposeInputs { material, settings, out: out.clone(), target_angle, tolerance })
        .map_err(failure)?;
    let a = &r.analysis;
    println!(
        "static angle of repose: {:.2}° ± {:.2}° (min {:.2}°, max {:.2}°) over {} of {} slices",
        a.mean_deg,
        a.std_deg,
        a.min_deg,
        a.max_deg,
        r.IndividualAnglesOfRepose.len(),
        a.slices.len()
    );
    let u = &r.run;
    println!(
        "  {} particles: {} on the base, {} sunk, {} falling off, {} through the base, {} lifted; pile {} (rms speed {:.2e} m/s, largest {:.2e} m/s); {:.2} s simulated in {:.1} s",
        u.particles,
        u.on_base,
        u.sunk,
        u.falling,
        u.through_base,
        u.lifted,
        if u.settled { "at rest" } else { "still moving at the end" },
        u.final_rms_speed,
        u.final_max_speed,
        u.end_time,
        u.wall_time_s
    );
    if let Some(c) = &r.calibration {
        match (c.converged, &r.calibrated_material) {
            (Some(phi), Some(m)) => {
                println!("calibrated: friction_angle = {phi:.3}° after {} tests; material: {m}", c.iterates.len())
            }
            _ => {
                return Err(Failure::Run(anyhow::anyhow!(
                    "calibration did not converge: {} (tests in {}, repose.json lists them)",
                    c.failure.as_deref().unwrap_or("unknown"),
                    out.display()
                )));
            }
        }
    }
    println!("outputs in {}", out.display());
    Ok(())
}

pub(super) fn triaxial(inp: TriaxialInputs) -> Result<(), Failure> {
    let r = calibrate_triaxial(&inp).map_err(failure)?;
    print!("{}", triaxial_text(&r));
    let outcome = match (&r.calibration, &r.joint_calibration) {
        (Some(c), _) => Some((
            c.converged.map(|v| format!("{} = {v:.4}", r.calibration_parameter.unwrap_or("parameter"))),
            c.iterates.len(),
            c.failure.clone(),
        )),
        (None, Some(j)) => Some((
            j.converged.map(|v| {
                j.parameters.iter().zip(v).map(|(k, x)| format!("{k} = {x:.4}")).collect::<Vec<_>>().join(", ")
            }),
            j.iterates.len(),
            j.failure.clone(),
        )),
        (None, None) => None,
    };
    if let Some((set, rounds, why)) = outcome {
        match (set, &r.calibrated_material) {
            (Some(set), Some(m)) => println!("calibrated: {set} after {rounds} rounds; material: {m}"),
            _ => {
                return Err(Failure::Run(anyhow::anyhow!(
                    "calibration did not converge: {} (rounds in {}, triaxial.json lists them)",
                    why.as_deref().unwrap_or("unknown"),
                    inp.out.display()
                )));
            }
        }
    }
    println!("outputs in {}", inp.out.display());
    Ok(())
}

pub(super) fn cone(inp: ConeInputs) -> Result<(), Failure> {
    let r = calibrate_cone(&inp).map_err(failure)?;
    println!(
        "cone index CI = CI0 + G z: G = {} ± {} Pa/m, CI0 = {} ± {} Pa over {} layers of {} m",
        r.gradient.map_or_else(|| "n/a".to_string(), |g| format!("{g:.4e}")),
        se(r.standard_error_gradient),
        r.intercept.map_or_else(|| "n/a".to_string(), |g| format!("{g:.4e}")),
        se(r.standard_error_intercept),
        r.layers.len(),
        inp.layer
    );
    for l in &r.layers {
        println!(
            "  base depth {:.4}–{:.4} m: cone index {:.4e} ± {:.2e} Pa ({} samples)",
            l.from, l.to, l.cone_index, l.std_dev, l.samples
        );
    }
    println!("outputs in {}", inp.out.display());
    Ok(())
}

pub(super) fn plate(inp: PlateInputs) -> Result<(), Failure> {
    let r = calibrate_plate(&inp).map_err(failure)?;
    print!("{}", plate_text(&r));
    println!("outputs in {}", inp.out.display());
    Ok(())
}

/// The Bekker fit and every plate, as printed.
pub(super) fn plate_text(r: &PlateCalibration) -> String {
    let b = &r.bekker;
    let opt = |v: Option<f64>| v.map_or_else(|| "n/a".to_string(), |x| format!("{x:.4e}"));
    let mut t = format!(
        "Bekker fit of {} plates: k_c = {} ± {} N/m^(n+1), k_φ = {} ± {} N/m^(n+2), n = {:.4} ± {} (R² {:.4}, {} points)\n",
        r.runs.len(),
        opt(b.kc),
        se(b.standard_error_kc),
        opt(b.kphi),
        se(b.standard_error_kphi),
        b.n,
        se(b.standard_error_n),
        b.r2,
        b.points
    );
    for p in &r.runs {
        let k = b.k_per_plate.iter().find(|(x, _)| (x - p.b).abs() < 1e-12).map(|(_, k)| *k);
        t.push_str(&format!(
            "  b = {} m: k = {}, to {:.4} m sinkage at {:.4e} Pa; {:.1} s\n",
            p.b,
            opt(k),
            p.max_sinkage,
            p.max_pressure,
            p.wall_s
        ));
    }
    t
}

/// The envelope and every test, as printed.
pub(super) fn triaxial_text(r: &TriaxialReport) -> String {
    let mut t = format!(
        "triaxial envelope of {} tests (the soil's load, from the plates' forces on its particles): c = {:.4e} ± {} Pa, φ = {:.3}° ± {}°{}\n",
        r.tests.len(),
        r.c,
        se(r.standard_error_c),
        r.phi,
        se(r.standard_error_phi),
        match (r.material_phi, r.material_c) {
            (Some(p), c) => format!(" (material: φ = {p}°, c = {} Pa)", c.unwrap_or(0.0)),
            _ => String::new(),
        }
    );
    t.push_str(&format!(
        "  through the origin (c = 0, a critical state): φ = {:.3}° ± {}°\n",
        r.phi_cohesionless,
        se(r.standard_error_phi_cohesionless)
    ));
    let envelope = |e: &crate::calibrate::Envelope| {
        format!("c = {:.4e} ± {} Pa, φ = {:.3}° ± {}°", e.c, se(e.standard_error_c), e.phi, se(e.standard_error_phi))
    };
    t.push_str(&format!(
        "  on the particles' own (volume-mean) stresses, same rule: {}; through the origin φ = {:.3}° ± {}°\n",
        envelope(&r.bulk),
        r.bulk_phi_cohesionless,
        se(r.bulk_standard_error_phi_cohesionless)
    ));
    t.push_str(&format!(
        "  on the faces' normal force over area alone (AGX's reading, which also counts the load the plates' markers pass between soil layers): {}\n",
        envelope(&r.faces)
    ));
    for x in &r.tests {
        t.push_str(&format!(
            "  σ0 = {:.4e} Pa: {} particles, consolidated in {:.3} s, failure ({:?}) at axial strain {:.4}: σ1 = {:.4e} Pa, σ3 = {:.4e} Pa; inertial number {:.1e}; {} escaped; {:.1} s\n",
            x.confining,
            x.particles,
            x.consolidation_time,
            x.failure.kind,
            x.strain_at_failure,
            x.vertical_at_failure,
            x.lateral_at_failure,
            x.inertial_number,
            x.escaped,
            x.wall_time_s
        ));
    }
    t
}
