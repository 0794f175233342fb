//! Modified Cam Clay at a material point against its closed forms (f64 and f32).
//!
//! Parameter sets are chosen to span soft to stiff, low to high M; the closed forms hold for
//! any consistent set. Safeguards are off unless a test is about them, because the clamp
//! deliberately changes the elastic law.

use regolith::element::{Control, ElementPath, ElementSpec, ElementTest, run_element};
use regolith::fsi::Real;
use regolith::fsi::rheology::{Material, MaterialParams, ModelKind, Rheology};

#[derive(Clone, Copy)]
struct Set {
    m: f64,
    kappa: f64,
    lambda: f64,
    v_lambda: f64,
    nu: f64,
}

const SETS: [Set; 4] = [
    Set { m: 1.2, kappa: 0.05, lambda: 0.2, v_lambda: 2.8, nu: 0.25 },
    Set { m: 0.9, kappa: 0.01, lambda: 0.08, v_lambda: 2.2, nu: 0.3 },
    Set { m: 1.4, kappa: 0.03, lambda: 0.3, v_lambda: 3.2, nu: 0.2 },
    Set { m: 1.0, kappa: 0.02, lambda: 0.12, v_lambda: 2.4, nu: 0.35 },
];

fn material<T: Real>(s: Set, clamp: bool, young: f64) -> Material<T> {
    MaterialParams {
        model: Some(ModelKind::Mcc),
        density: Some(1800.0),
        youngs_modulus: Some(young),
        poisson_ratio: Some(s.nu),
        mcc_m: Some(s.m),
        mcc_kappa: Some(s.kappa),
        mcc_lambda: Some(s.lambda),
        mcc_v_lambda: Some(s.v_lambda),
        mcc_clamp_moduli: Some(clamp),
        mcc_pc_floor: Some(0.0),
        ..Default::default()
    }
    .build::<T>()
    .expect("valid test material")
}

fn run<T: Real>(
    mat: &Material<T>,
    test: ElementTest,
    p0: f64,
    ocr: f64,
    control: Control,
    steps: usize,
) -> ElementPath {
    run_element(mat, &ElementSpec { test, p0, ocr: Some(ocr), control, steps }).expect("element test runs")
}

/// Least-squares slope of v against ln p over the selected indices.
fn slope(path: &ElementPath, idx: impl Iterator<Item = usize>) -> f64 {
    let pts: Vec<(f64, f64)> = idx.map(|i| (path.p[i].ln(), path.v[i])).collect();
    let n = pts.len() as f64;
    assert!(n >= 10.0, "too few points for a slope");
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn isotropic_yields_at_pc0_then_follows_lambda_and_kappa<T: Real>() {
    for s in SETS {
        let mat = material::<T>(s, false, 1e9);
        let (p0, ocr) = (40.0e3, 3.0);
        let pc0 = p0 * ocr;
        let path =
            run(&mat, ElementTest::Isotropic, p0, ocr, Control::Pressure { end: 800.0e3, unload: Some(100.0e3) }, 3000);
        let pc = path.pc.as_ref().expect("mcc records pc");
        let tol = if T::NAME == "f32" { 1e-5 } else { 1e-10 };
        // Elastic (pc unchanged) until the first step whose pressure reaches pc0.
        let k = pc.iter().position(|&x| x > pc0 * (1.0 + tol)).expect("the test yields");
        assert!(pc[..k].iter().all(|&x| rel(x, pc0) <= tol), "pc changed before yield");
        assert!(
            path.p[k - 1] <= pc0 * (1.0 + tol) && path.p[k] >= pc0 * (1.0 - tol),
            "yield between p = {} and {} but pc0 = {pc0}",
            path.p[k - 1],
            path.p[k]
        );
        // Virgin loading: slope −λ. Unloading: slope −κ.
        let peak = path.p.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i).unwrap_or(0);
        let virgin = slope(&path, (k + 1..=peak).filter(|&i| path.p[i] > 1.05 * pc0));
        let unload = slope(&path, peak + 1..path.p.len());
        assert!(rel(-virgin, s.lambda) < 0.005, "virgin slope {virgin} vs λ = {} ({})", s.lambda, T::NAME);
        assert!(rel(-unload, s.kappa) < 0.005, "unload slope {unload} vs κ = {} ({})", s.kappa, T::NAME);
        // Reloading before yield also follows κ.
        let reload = slope(&path, 0..k);
        assert!(rel(-reload, s.kappa) < 0.005, "reload slope {reload} vs κ = {} ({})", s.kappa, T::NAME);
    }
}

#[test]
fn isotropic_f64() {
    isotropic_yields_at_pc0_then_follows_lambda_and_kappa::<f64>();
}

#[test]
fn isotropic_f32() {
    isotropic_yields_at_pc0_then_follows_lambda_and_kappa::<f32>();
}

fn drained_reaches_critical_state<T: Real>() {
    for s in SETS {
        let mat = material::<T>(s, false, 1e9);
        for ocr in [1.0, 1.5] {
            let p0 = 100.0e3;
            let path = run(&mat, ElementTest::DrainedTriaxial, p0, ocr, Control::AxialStrain(3.0), 3000);
            let p_cs = 3.0 * p0 / (3.0 - s.m);
            let f = &path.final_state;
            assert!(rel(f.p, p_cs) < 0.01, "drained p = {} vs {p_cs} (M = {}, OCR = {ocr}, {})", f.p, s.m, T::NAME);
            assert!(rel(f.q, s.m * p_cs) < 0.01, "drained q = {} vs {} ({})", f.q, s.m * p_cs, T::NAME);
            // Cell pressure held: σr = p0 at every step.
            assert!(path.sigma_radial.iter().all(|&r| rel(r, p0) < 1e-4), "cell pressure drifted ({})", T::NAME);
            // Normally and lightly overconsolidated soil compacts and hardens on the way.
            assert!(f.eps_vol > 0.0 && f.pc.unwrap_or(0.0) > ocr * p0);
        }
    }
}

#[test]
fn drained_triaxial_f64() {
    drained_reaches_critical_state::<f64>();
}

#[test]
fn drained_triaxial_f32() {
    drained_reaches_critical_state::<f32>();
}

fn undrained_reaches_critical_state<T: Real>() {
    for s in SETS {
        let mat = material::<T>(s, false, 1e9);
        for ocr in [1.0, 1.5, 3.0, 8.0] {
            let p0 = 100.0e3;
            let path = run(&mat, ElementTest::UndrainedTriaxial, p0, ocr, Control::AxialStrain(1.0), 2000);
            let p_cs = p0 * (ocr / 2.0).powf((s.lambda - s.kappa) / s.lambda);
            let f = &path.final_state;
            assert!(rel(f.p, p_cs) < 0.01, "undrained p = {} vs {p_cs} (OCR {ocr}, {})", f.p, T::NAME);
            assert!(rel(f.q, s.m * p_cs) < 0.01, "undrained q = {} vs {} (OCR {ocr}, {})", f.q, s.m * p_cs, T::NAME);
            assert!(f.eps_vol.abs() < 1e-6, "volume changed in an undrained test");
        }
    }
}

#[test]
fn undrained_triaxial_f64() {
    undrained_reaches_critical_state::<f64>();
}

#[test]
fn undrained_triaxial_f32() {
    undrained_reaches_critical_state::<f32>();
}

fn heavily_overconsolidated_peaks_then_softens<T: Real>() {
    for s in SETS {
        let mat = material::<T>(s, false, 1e9);
        for ocr in [4.0, 8.0] {
            let p0 = 50.0e3;
            let path = run(&mat, ElementTest::DrainedTriaxial, p0, ocr, Control::AxialStrain(3.0), 3000);
            assert!(path.p.iter().chain(&path.q).chain(&path.v).all(|x| x.is_finite()), "NaN in the path");
            let (i_peak, q_peak) =
                path.q.iter().copied().enumerate().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap_or((0, 0.0));
            let ratio_peak = q_peak / path.p[i_peak];
            assert!(ratio_peak > s.m * 1.02, "peak q/p = {ratio_peak} not above M = {} (OCR {ocr})", s.m);
            let f = &path.final_state;
            assert!(f.q < 0.99 * q_peak, "no softening after the peak (OCR {ocr})");
            assert!(rel(f.q / f.p, s.m) < 0.01, "final q/p = {} does not approach M = {}", f.q / f.p, s.m);
            // Softening after the peak is monotone down to the critical state.
            assert!(path.q[i_peak..].windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-5)), "q not monotone after the peak");
            // The dry side dilates while it softens (the net strain may stay compressive: the
            // elastic approach to the peak compresses the sample first).
            assert!(f.eps_vol < path.eps_vol[i_peak] - 1e-3, "no dilation after the peak (OCR {ocr})");
        }
    }
}

#[test]
fn heavily_overconsolidated_f64() {
    heavily_overconsolidated_peaks_then_softens::<f64>();
}

#[test]
fn heavily_overconsolidated_f32() {
    heavily_overconsolidated_peaks_then_softens::<f32>();
}

/// The safeguards are real options: with the default clamp active the elastic slope departs
/// from κ (the stiffness is capped), and switched off it matches.
#[test]
fn moduli_clamp_is_on_by_default_and_switchable() {
    let s = SETS[3];
    // E small enough that K_ref = E/(3(1-2ν)) caps v p / κ above about 60 kPa.
    let young = 1.0e7;
    let on = MaterialParams {
        model: Some(ModelKind::Mcc),
        density: Some(1800.0),
        youngs_modulus: Some(young),
        poisson_ratio: Some(s.nu),
        mcc_m: Some(s.m),
        mcc_kappa: Some(s.kappa),
        mcc_lambda: Some(s.lambda),
        mcc_v_lambda: Some(s.v_lambda),
        ..Default::default()
    }
    .build::<f64>()
    .expect("valid");
    let Rheology::Mcc(p) = on.rheology else { panic!("mcc") };
    assert!(p.safeguards.moduli_clamp.is_some() && p.safeguards.pc_floor == 100.0);
    let off = material::<f64>(s, false, young);
    let ctl = Control::Pressure { end: 800.0e3, unload: Some(200.0e3) };
    let a = run(&on, ElementTest::Isotropic, 40.0e3, 2.0, ctl, 2000);
    let b = run(&off, ElementTest::Isotropic, 40.0e3, 2.0, ctl, 2000);
    let peak = |p: &ElementPath| p.p.iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1)).map(|(i, _)| i).unwrap_or(0);
    let ua = slope(&a, peak(&a) + 1..a.p.len());
    let ub = slope(&b, peak(&b) + 1..b.p.len());
    assert!(rel(-ub, s.kappa) < 0.005, "unclamped unload slope {ub}");
    assert!(rel(-ua, s.kappa) > 0.05, "clamped unload slope {ua} should depart from κ");
}

/// `calibrate mcc` on isotropic data generated by the element driver gives back the
/// material's λ, κ, v_λ and OCR within 1 % (every parameter set; load past p_c0, unload).
/// The element integrates the elastic law explicitly, so its swelling line deviates from the
/// exact log law by the relative size of a pressure increment: 4000 increments keep that
/// below 0.1 % (400 gave κ 0.6 % low).
#[test]
fn calibrate_mcc_recovers_the_parameters_the_element_data_came_from() {
    use regolith::calibrate::mcc::{IsotropicData, fit_isotropic};
    for (k, s) in SETS.iter().enumerate() {
        let mat = material::<f64>(*s, false, 1e8);
        let ocr = 1.0 + 0.5 * k as f64;
        let (p0, top) = (20e3, 600e3);
        let path = run(&mat, ElementTest::Isotropic, p0, ocr, Control::Pressure { end: top, unload: Some(60e3) }, 4000);
        let f = fit_isotropic(&IsotropicData { p: path.p.clone(), v: path.v.clone() }).expect("fit");
        for (name, got, want) in
            [("λ", f.lambda, s.lambda), ("κ", f.kappa, s.kappa), ("v_λ", f.v_lambda, s.v_lambda), ("OCR", f.ocr, ocr)]
        {
            assert!(rel(got, want) < 0.01, "set {k}: {name} = {got} against {want}");
        }
        assert_eq!((f.kappa_from, f.excursions), ("unloading", 1));
        assert_eq!(f.recompression_rows > 0, ocr > 1.0, "set {k}: recompression rows {}", f.recompression_rows);
    }
}
