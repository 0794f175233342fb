//! Drucker–Prager at a material point: drained triaxial failure equals Mohr–Coulomb for the
//! compression-matched cone (f64 and f32).

use regolith::element::{Control, ElementSpec, ElementTest, run_element};
use regolith::fsi::Real;
use regolith::fsi::rheology::{MaterialParams, ModelKind};

fn check<T: Real>() {
    for (phi, c, s3) in [
        (30.0, 0.0, 100.0e3),
        (35.0, 5.0e3, 50.0e3),
        (20.0, 20.0e3, 10.0e3),
        (42.0, 1.0e3, 200.0e3),
        (0.0, 30.0e3, 80.0e3),
    ] {
        let mat = MaterialParams {
            model: Some(ModelKind::DruckerPrager),
            density: Some(1600.0),
            youngs_modulus: Some(3.0e7),
            poisson_ratio: Some(0.3),
            friction_angle: Some(phi),
            cohesion: Some(c),
            ..Default::default()
        }
        .build::<T>()
        .expect("valid");
        let spec = ElementSpec {
            test: ElementTest::DrainedTriaxial,
            p0: s3,
            ocr: None,
            control: Control::AxialStrain(0.08),
            steps: 2000,
        };
        let path = run_element(&mat, &spec).expect("runs");
        let sp = f64::to_radians(phi).sin();
        let kp = (1.0 + sp) / (1.0 - sp);
        let qf = s3 * (kp - 1.0) + 2.0 * c * kp.sqrt();
        let q = path.final_state.q;
        assert!(
            (q - qf).abs() / qf < 0.01,
            "φ = {phi}, c = {c}, σ3 = {s3}: q = {q} vs Mohr–Coulomb {qf} ({})",
            T::NAME
        );
        assert_eq!(path.expected.failure_q, Some(qf));
        // Plateau: no hardening after failure.
        let n = path.q.len();
        assert!((path.q[n / 2] - q).abs() / qf < 0.01);
        // Elastic start: the first increment follows E (q = E ε_a in drained axial loading).
        let e0 = path.eps_axial[1];
        assert!((path.q[1] / e0 - 3.0e7).abs() / 3.0e7 < 1e-3, "initial slope {} ({})", path.q[1] / e0, T::NAME);
    }
}

#[test]
fn drained_failure_matches_mohr_coulomb_f64() {
    check::<f64>();
}

#[test]
fn drained_failure_matches_mohr_coulomb_f32() {
    check::<f32>();
}

#[test]
fn undrained_von_mises_clay_fails_at_2c() {
    let mat = MaterialParams {
        model: Some(ModelKind::DruckerPrager),
        density: Some(1800.0),
        youngs_modulus: Some(1.0e7),
        poisson_ratio: Some(0.3),
        friction_angle: Some(0.0),
        cohesion: Some(12.0e3),
        ..Default::default()
    }
    .build::<f64>()
    .expect("valid");
    let spec = ElementSpec {
        test: ElementTest::UndrainedTriaxial,
        p0: 50.0e3,
        ocr: None,
        control: Control::AxialStrain(0.05),
        steps: 500,
    };
    let path = run_element(&mat, &spec).expect("runs");
    assert!((path.final_state.q - 24.0e3).abs() / 24.0e3 < 1e-6);
}
