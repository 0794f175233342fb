//! The virtual triaxial test (`regolith calibrate triaxial`) on small SPH samples: the
//! measured envelope against the Mohr–Coulomb parameters the material was given (the
//! Drucker–Prager cone is matched to Mohr–Coulomb in triaxial compression, so an SPH sample
//! that deforms as the material point does fails on that envelope), and Modified Cam Clay's
//! critical state against φ_cs = asin(3M / (6 + M)) (the envelope through the origin).
//!
//! The tolerances are the issue's: φ within ±1.5°, c within its standard error of 0 for a
//! cohesionless soil and within 15 % for a cohesive one, on the envelope of the soil's load
//! from the plates' forces; the faces' force over area alone (AGX's reading) and the
//! particles' own stresses are checked too. The samples are 6 × 6 × 12 spacings
//! (432 particles), at three confining stresses (two for the clay).

use std::path::PathBuf;

use regolith::calibrate::lowpass::FailureKind;
use regolith::calibrate::triaxial::{
    FailureRule, TriaxialInputs, TriaxialReport, TriaxialSettings, calibrate_triaxial,
};

fn run(
    name: &str,
    material: &str,
    confining: &[f64],
    failure: FailureRule,
    max_strain: f64,
    strain_rate: f64,
) -> TriaxialReport {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("triaxial").join(name);
    std::fs::create_dir_all(&dir).expect("tmp");
    let file = dir.join("material.toml");
    std::fs::write(&file, material).expect("write");
    let mut s = TriaxialSettings::for_width(0.06);
    s.spacing = 0.01;
    s.confining = confining.to_vec();
    s.failure = failure;
    s.max_strain = max_strain;
    s.strain_rate = strain_rate;
    let r = calibrate_triaxial(&TriaxialInputs {
        material: file,
        settings: s,
        out: dir.join("out"),
        jobs: 2,
        resume: false,
        target_phi: None,
        tolerance_phi: 0.5,
        target_c: None,
        tolerance_c: None,
        matching: regolith::calibrate::triaxial::EnvelopeSource::Particles,
    })
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    for t in &r.tests {
        eprintln!(
            "{name}: σ0 = {:.0} Pa: σ1 = {:.0}, σ3 = {:.0} Pa at strain {:.4} ({:?}), {} escaped, {:.1} s",
            t.confining,
            t.vertical_at_failure,
            t.lateral_at_failure,
            t.strain_at_failure,
            t.failure.kind,
            t.escaped,
            t.wall_time_s
        );
        assert_eq!(t.escaped, 0, "{name}: soil left the sample at {} Pa", t.confining);
        // Consolidation held every face at the confining stress.
        for f in t.consolidated_stresses {
            assert!(
                (f / t.confining - 1.0).abs() <= 0.01,
                "{name}: face at {f} Pa after consolidating to {}",
                t.confining
            );
        }
    }
    eprintln!(
        "{name}: c = {:.1} ± {:?} Pa, φ = {:.2} ± {:?}°, through the origin {:.2}°",
        r.c, r.standard_error_c, r.phi, r.standard_error_phi, r.phi_cohesionless
    );
    eprintln!(
        "{name}: particles: c = {:.1} ± {:?} Pa, φ = {:.2} ± {:?}°, through the origin {:.2}°",
        r.bulk.c, r.bulk.standard_error_c, r.bulk.phi, r.bulk.standard_error_phi, r.bulk_phi_cohesionless
    );
    eprintln!(
        "{name}: faces alone: c = {:.1} ± {:?} Pa, φ = {:.2} ± {:?}°",
        r.faces.c, r.faces.standard_error_c, r.faces.phi, r.faces.standard_error_phi
    );
    assert!(dir.join("out").join("triaxial.json").is_file());
    r
}

const DP: &str = "model = \"drucker-prager\"\ndensity = 1600.0\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\n";

#[test]
fn a_cohesionless_drucker_prager_sample_fails_on_its_mohr_coulomb_envelope() {
    let r = run("dp30", &format!("{DP}friction_angle = 30.0\n"), &[10e3, 20e3, 30e3], FailureRule::Peak, 0.06, 0.2);
    // The envelope of the soil's load from the plates' forces (measured: −32 ± 66 Pa,
    // 29.06°, through the origin 29.0°): the criterion, c within one standard error
    // of 0 and φ within 1.5°.
    assert!((r.phi - 30.0).abs() <= 1.5, "φ = {} against 30", r.phi);
    assert!((r.phi_cohesionless - 30.0).abs() <= 1.5, "φ (c = 0) = {} against 30", r.phi_cohesionless);
    let se = r.standard_error_c.expect("three tests give a standard error");
    assert!(r.c.abs() <= se, "c = {} Pa against 0 ± {se} Pa", r.c);
    assert!(r.tests.iter().all(|t| t.failure.kind == FailureKind::Peak));
    // The faces' normal force over area alone (AGX's reading) read 524 ± 207 Pa and 29.44°:
    // the side plates' markers carry part of the axial load (docs/calibration.md). Its bound
    // is a tenth of the lowest confining stress (1 kPa, which would add 3.5 kPa, 12 %, to the
    // lowest test's σ1 of 30 kPa).
    assert!(r.faces.c.abs() <= 0.1 * 10e3, "faces' c = {} Pa against 0", r.faces.c);
    assert!((r.faces.phi - 30.0).abs() <= 1.5, "faces' φ = {} against 30", r.faces.phi);
    // The soil's own stresses (the particles' volume mean, same filter and rule) hold the
    // issue's criterion: c within one standard error of 0 (measured 4 ± 75 Pa, φ 29.75°).
    let b = &r.bulk;
    let se_b = b.standard_error_c.expect("three tests give a standard error");
    assert!(b.c.abs() <= se_b, "particles' c = {} Pa against 0 ± {se_b} Pa", b.c);
    assert!((b.phi - 30.0).abs() <= 1.5, "particles' φ = {} against 30", b.phi);
}

#[test]
fn a_cohesive_drucker_prager_sample_fails_on_its_mohr_coulomb_envelope() {
    let r = run(
        "dp25_c5k",
        &format!("{DP}friction_angle = 25.0\ncohesion = 5000.0\n"),
        &[10e3, 20e3, 30e3],
        FailureRule::Peak,
        0.06,
        0.2,
    );
    // Measured: 4376 ± 45 Pa (−12.5 %) and 24.06° on the soil's load from the plates' forces;
    // 5193 Pa (+3.9 %) and 24.36° on the faces alone; 5003 ± 45 Pa and 24.77° on the particles.
    assert!((r.phi - 25.0).abs() <= 1.5, "φ = {} against 25", r.phi);
    assert!((r.c / 5000.0 - 1.0).abs() <= 0.15, "c = {} Pa against 5000", r.c);
    assert!((r.faces.phi - 25.0).abs() <= 1.5, "faces' φ = {} against 25", r.faces.phi);
    assert!((r.faces.c / 5000.0 - 1.0).abs() <= 0.15, "faces' c = {} Pa against 5000", r.faces.c);
    assert!((r.bulk.phi - 25.0).abs() <= 1.5, "particles' φ = {} against 25", r.bulk.phi);
    assert!((r.bulk.c / 5000.0 - 1.0).abs() <= 0.15, "particles' c = {} Pa against 5000", r.bulk.c);
}

#[test]
fn a_cam_clay_sample_reaches_its_critical_state_friction_angle() {
    // M = 1.2: φ_cs = asin(3 · 1.2 / 7.2) = 30°. Started at σ0 with OCR 1, the sample is
    // normally consolidated and hardens towards the critical state (the plateau is the mean
    // over the last fifth of the test). E sets the moduli
    // clamp (Chrono's safeguard) and with it the time step; the critical state does not
    // depend on it. Two confining stresses: the angle needs no standard error here.
    let clay = "model = \"mcc\"\ndensity = 1800.0\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\nmcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.12\nmcc_v_lambda = 2.4\nocr = 1.0\n";
    // 30 % strain (the plates' limit): at 15 % the sample is still hardening, and its
    // particles read 27.74° (the faces alone 29.11°); at 30 % the particles read 29.91°, the
    // soil's load from the plates' forces 30.10° (with c) and the faces alone 29.10°.
    let r = run("mcc_m12", clay, &[10e3, 20e3], FailureRule::Plateau, 0.3, 0.5);
    // The critical state line passes through the origin: the envelope without cohesion.
    assert!((r.phi_cohesionless - 30.0).abs() <= 1.5, "φ_cs = {} against 30", r.phi_cohesionless);
    assert!((r.bulk_phi_cohesionless - 30.0).abs() <= 1.5, "particles' φ_cs = {} against 30", r.bulk_phi_cohesionless);
    assert!((r.faces.phi - 30.0).abs() <= 1.5, "faces' φ = {} against 30", r.faces.phi);
    assert!(r.tests.iter().all(|t| t.failure.kind == FailureKind::Plateau));
}
