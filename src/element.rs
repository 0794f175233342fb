//! Single material-point driver (`regolith element`): isotropic compression, drained and
//! undrained triaxial, and oedometer tests, run through the same constitutive functions the SPH
//! solver uses.
//!
//! The point is axisymmetric about z: `σ = diag(σr, σr, σa)`. Axial strain is imposed in equal
//! increments; a stress condition (constant cell pressure, a target mean pressure) is met
//! every step by solving for the free strain component with a bracketed root finder, so the
//! path is exact to round-off at every recorded point, not only on average. The test is
//! quasi-static: μ(I) sees an inertial number of zero.
//!
//! Reported strains and pressures are compression positive (Pa).

use std::cell::RefCell;

use regolith_fsi::Real;
use regolith_fsi::math::{Sym3, Vec3};
use regolith_fsi::rheology::{Material, PointState, Rheology, RheologyError, brent, cone_from_mohr_coulomb};
use serde::Serialize;

/// Which laboratory test to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementTest {
    /// Mean stress from p0 to a target (and optionally back down).
    Isotropic,
    /// Cell pressure held at p0, axial compression, free volume change.
    DrainedTriaxial,
    /// Axial compression at constant volume.
    UndrainedTriaxial,
    /// Laterally confined compression.
    Oedometer,
}

impl ElementTest {
    /// Parses the CLI name.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "isotropic" => Self::Isotropic,
            "drained-triaxial" => Self::DrainedTriaxial,
            "undrained-triaxial" => Self::UndrainedTriaxial,
            "oedometer" => Self::Oedometer,
            _ => return None,
        })
    }
    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Isotropic => "isotropic",
            Self::DrainedTriaxial => "drained-triaxial",
            Self::UndrainedTriaxial => "undrained-triaxial",
            Self::Oedometer => "oedometer",
        }
    }
}

/// How the test is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Control {
    /// Total axial strain: natural (logarithmic) strain, compression positive, in (0, 5].
    AxialStrain(f64),
    /// Mean pressure to reach (Pa), then optionally unload to a lower one.
    Pressure {
        /// Target mean pressure (Pa).
        end: f64,
        /// Optional unloading target (Pa), below `end`.
        unload: Option<f64>,
    },
}

/// A complete element test specification.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementSpec {
    /// The test.
    pub test: ElementTest,
    /// Initial isotropic pressure p0 (Pa), also the cell pressure of a drained triaxial test.
    pub p0: f64,
    /// Overconsolidation ratio overriding the material's (MCC only).
    pub ocr: Option<f64>,
    /// Loading control.
    pub control: Control,
    /// Number of increments.
    pub steps: usize,
}

/// Why an element test could not run.
#[derive(Debug, thiserror::Error)]
pub enum ElementError {
    /// The specification is inconsistent (names the CLI flag).
    #[error("{flag}: {message}")]
    Spec {
        /// The flag to fix.
        flag: &'static str,
        /// What is allowed.
        message: String,
    },
    /// The constitutive update failed.
    #[error("step {step}: {source}")]
    Rheology {
        /// Step index.
        step: usize,
        /// The model's error.
        source: RheologyError,
    },
    /// A stress condition could not be met (e.g. the material cannot carry the target).
    #[error("step {step}: could not satisfy the {what} (the material cannot follow this path)")]
    Control {
        /// Step index.
        step: usize,
        /// Which condition.
        what: &'static str,
    },
}

/// Closed-form results the test should reach, when the theory gives one.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Expected {
    /// MCC critical state mean pressure (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_state_p: Option<f64>,
    /// MCC critical state deviator `q = M p` (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_state_q: Option<f64>,
    /// Drucker–Prager / Mohr–Coulomb failure deviator in drained compression (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure_q: Option<f64>,
    /// MCC yield pressure on the isotropic axis, `p_c0` (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub isotropic_yield_p: Option<f64>,
}

/// Final values of a test.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FinalState {
    /// Mean pressure (Pa).
    pub p: f64,
    /// Deviator (Pa).
    pub q: f64,
    /// Preconsolidation pressure (Pa), MCC only.
    pub pc: Option<f64>,
    /// Specific volume (MCC) or volume relative to the start (other models).
    pub v: f64,
    /// Axial strain, compression positive.
    pub eps_axial: f64,
    /// Volumetric strain, compression positive.
    pub eps_vol: f64,
    /// Axial stress, compression positive (Pa).
    pub sigma_axial: f64,
    /// Radial stress, compression positive (Pa).
    pub sigma_radial: f64,
}

/// The recorded path of a test; `element.json` is this structure.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ElementPath {
    /// Test name.
    pub test: &'static str,
    /// Model name.
    pub model: &'static str,
    /// Precision the test ran in.
    pub precision: &'static str,
    /// Initial pressure (Pa).
    pub p0: f64,
    /// Overconsolidation ratio used (MCC).
    pub ocr: Option<f64>,
    /// MCC critical-state slope, or the Drucker–Prager compression slope.
    pub m: Option<f64>,
    /// Mean pressure per step (Pa).
    pub p: Vec<f64>,
    /// Deviator per step (Pa).
    pub q: Vec<f64>,
    /// Preconsolidation pressure per step (Pa); `null` for models without one.
    pub pc: Option<Vec<f64>>,
    /// Specific volume per step (MCC) or relative volume (other models).
    pub v: Vec<f64>,
    /// Axial strain per step, compression positive.
    pub eps_axial: Vec<f64>,
    /// Volumetric strain per step, compression positive.
    pub eps_vol: Vec<f64>,
    /// Axial stress per step, compression positive (Pa).
    pub sigma_axial: Vec<f64>,
    /// Radial stress per step, compression positive (Pa).
    pub sigma_radial: Vec<f64>,
    /// Final values.
    #[serde(rename = "final")]
    pub final_state: FinalState,
    /// Closed-form targets, where theory gives them.
    pub expected: Expected,
}

fn spec_err(flag: &'static str, message: impl Into<String>) -> ElementError {
    ElementError::Spec { flag, message: message.into() }
}

impl ElementSpec {
    /// Checks the flags against each other and the test.
    pub fn validate(&self) -> Result<(), ElementError> {
        if !(self.p0.is_finite() && self.p0 > 0.0) {
            return Err(spec_err("--p0", format!("must be > 0 Pa (got {})", self.p0)));
        }
        if self.steps == 0 || self.steps > 10_000_000 {
            return Err(spec_err("--steps", format!("must be in 1..=10000000 (got {})", self.steps)));
        }
        if let Some(ocr) = self.ocr
            && !(ocr.is_finite() && ocr >= 1.0)
        {
            return Err(spec_err("--ocr", format!("must be ≥ 1 (got {ocr})")));
        }
        match (self.test, self.control) {
            (ElementTest::Isotropic, Control::AxialStrain(_)) => Err(spec_err(
                "--axial-strain",
                "does not apply to an isotropic test; give --p-end (and optionally --p-unload)",
            )),
            (ElementTest::DrainedTriaxial | ElementTest::UndrainedTriaxial, Control::Pressure { .. }) => {
                Err(spec_err("--p-end", "does not apply to a triaxial test; give --axial-strain"))
            }
            (_, Control::AxialStrain(e)) => {
                if e.is_finite() && e > 0.0 && e <= 5.0 {
                    Ok(())
                } else {
                    Err(spec_err(
                        "--axial-strain",
                        format!("must be in (0, 5] (natural strain, compression positive; got {e})"),
                    ))
                }
            }
            (_, Control::Pressure { end, unload }) => {
                if !(end.is_finite() && end > 0.0) {
                    return Err(spec_err("--p-end", format!("must be > 0 Pa (got {end})")));
                }
                if let Some(u) = unload
                    && !(u.is_finite() && u > 0.0 && u < end)
                {
                    return Err(spec_err("--p-unload", format!("must be in (0, --p-end = {end}) Pa (got {u})")));
                }
                Ok(())
            }
        }
    }
}

struct Point<T> {
    sigma: Sym3<T>,
    state: PointState<T>,
    eps: [f64; 2], // radial, axial (extension positive)
}

/// Runs an element test on a material in precision `T`.
pub fn run_element<T: Real>(material: &Material<T>, spec: &ElementSpec) -> Result<ElementPath, ElementError> {
    spec.validate()?;
    if material.is_water() {
        return Err(spec_err("--material", "is water: element tests take a soil (elastic, drucker-prager or mcc)"));
    }
    let mut material = *material;
    let is_mcc = matches!(material.rheology, Rheology::Mcc(_));
    if let Some(ocr) = spec.ocr {
        if !is_mcc {
            return Err(spec_err(
                "--ocr",
                format!("applies to model \"mcc\" only (the material is \"{}\")", material.rheology.name()),
            ));
        }
        material.ocr = T::of(ocr);
    }
    let p0 = T::of(spec.p0);
    let mut pt = Point { sigma: Sym3::iso(-p0), state: material.initial_state(p0), eps: [0.0; 2] };
    if is_mcc && pt.state.v <= T::one() {
        return Err(spec_err(
            "--p0",
            format!("gives an initial specific volume v = {} ≤ 1; raise mcc_v_lambda or lower p0/OCR", pt.state.v),
        ));
    }
    let mut rec = Recorder::default();
    rec.push(&pt, is_mcc);

    match (spec.test, spec.control) {
        (ElementTest::Isotropic | ElementTest::Oedometer, Control::Pressure { end, unload }) => {
            let mut legs = vec![(spec.p0, end)];
            if let Some(u) = unload {
                legs.push((end, u));
            }
            let total: f64 = legs.iter().map(|(a, b)| (b / a).ln().abs()).sum();
            let mut step = 0;
            for (i, &(a, b)) in legs.iter().enumerate() {
                let n = if legs.len() == 1 {
                    spec.steps
                } else if i == 0 {
                    ((spec.steps as f64 * (b / a).ln().abs() / total).round() as usize).clamp(1, spec.steps.max(2) - 1)
                } else {
                    (spec.steps - step).max(1)
                };
                for k in 1..=n {
                    let target = a * ((b / a).ln() * k as f64 / n as f64).exp();
                    step += 1;
                    pressure_step(&material, &mut pt, spec.test, T::of(target), step)?;
                    rec.push(&pt, is_mcc);
                }
            }
        }
        (test, Control::AxialStrain(total)) => {
            let de_a = -total / spec.steps as f64;
            for step in 1..=spec.steps {
                match test {
                    ElementTest::UndrainedTriaxial => {
                        apply(&material, &mut pt, -0.5 * de_a, de_a, step)?;
                    }
                    ElementTest::Oedometer => {
                        apply(&material, &mut pt, 0.0, de_a, step)?;
                    }
                    ElementTest::DrainedTriaxial => drained_step(&material, &mut pt, de_a, p0, step)?,
                    ElementTest::Isotropic => unreachable!("rejected by validate"),
                }
                rec.push(&pt, is_mcc);
            }
        }
        _ => unreachable!("rejected by validate"),
    }

    let expected = expected(&material, spec);
    let n = rec.p.len() - 1;
    let final_state = FinalState {
        p: rec.p[n],
        q: rec.q[n],
        pc: if is_mcc { Some(rec.pc[n]) } else { None },
        v: rec.v[n],
        eps_axial: rec.eps_axial[n],
        eps_vol: rec.eps_vol[n],
        sigma_axial: rec.sigma_axial[n],
        sigma_radial: rec.sigma_radial[n],
    };
    let (ocr, m) = match &material.rheology {
        Rheology::Mcc(mcc) => (Some(material.ocr.as_f64()), Some(mcc.m.as_f64())),
        Rheology::DruckerPrager(_) => {
            let (mu, _) = cone_from_mohr_coulomb(material.friction_angle_deg.as_f64(), 0.0);
            (None, Some(mu * 3f64.sqrt()))
        }
        Rheology::Elastic | Rheology::Water(_) => (None, None),
    };
    Ok(ElementPath {
        test: spec.test.name(),
        model: material.rheology.name(),
        precision: T::NAME,
        p0: spec.p0,
        ocr,
        m,
        p: rec.p,
        q: rec.q,
        pc: if is_mcc { Some(rec.pc) } else { None },
        v: rec.v,
        eps_axial: rec.eps_axial,
        eps_vol: rec.eps_vol,
        sigma_axial: rec.sigma_axial,
        sigma_radial: rec.sigma_radial,
        final_state,
        expected,
    })
}

fn expected<T: Real>(material: &Material<T>, spec: &ElementSpec) -> Expected {
    let mut e = Expected::default();
    match (&material.rheology, spec.test) {
        (Rheology::Mcc(mcc), test) => {
            let m = mcc.m.as_f64();
            let (l, k) = (mcc.lambda.as_f64(), mcc.kappa.as_f64());
            let ocr = material.ocr.as_f64();
            match test {
                ElementTest::DrainedTriaxial => {
                    let p = 3.0 * spec.p0 / (3.0 - m);
                    e.critical_state_p = Some(p);
                    e.critical_state_q = Some(m * p);
                }
                ElementTest::UndrainedTriaxial => {
                    let p = spec.p0 * (ocr / 2.0).powf((l - k) / l);
                    e.critical_state_p = Some(p);
                    e.critical_state_q = Some(m * p);
                }
                ElementTest::Isotropic => e.isotropic_yield_p = Some(ocr * spec.p0),
                ElementTest::Oedometer => {}
            }
        }
        (Rheology::DruckerPrager(_), ElementTest::DrainedTriaxial) => {
            let s = material.friction_angle_deg.as_f64().to_radians().sin();
            let c = material.cohesion.as_f64();
            let kp = (1.0 + s) / (1.0 - s);
            e.failure_q = Some(spec.p0 * (kp - 1.0) + 2.0 * c * kp.sqrt());
        }
        _ => {}
    }
    e
}

/// Applies one strain increment (extension positive) and commits it.
fn apply<T: Real>(m: &Material<T>, pt: &mut Point<T>, de_r: f64, de_a: f64, step: usize) -> Result<(), ElementError> {
    let (sigma, state) = trial(m, pt, de_r, de_a).map_err(|source| ElementError::Rheology { step, source })?;
    pt.sigma = sigma;
    pt.state = state;
    pt.eps[0] += de_r;
    pt.eps[1] += de_a;
    Ok(())
}

fn trial<T: Real>(
    m: &Material<T>,
    pt: &Point<T>,
    de_r: f64,
    de_a: f64,
) -> Result<(Sym3<T>, PointState<T>), RheologyError> {
    let mut state = pt.state;
    let d = Sym3::diag(T::of(de_r), T::of(de_r), T::of(de_a));
    let s = m.update(&pt.sigma, &mut state, &d, Vec3::zero(), T::one())?;
    Ok((s, state))
}

/// Solves `r(u) = 0` for the free strain component `u`, where `r` increases with `u` when
/// `increasing`, starting from the elastic estimate `guess`.
fn solve_free<T: Real>(
    r: impl Fn(T) -> Result<T, RheologyError>,
    guess: T,
    increasing: bool,
    step: usize,
    what: &'static str,
) -> Result<T, ElementError> {
    let err: RefCell<Option<RheologyError>> = RefCell::new(None);
    let f = |u: T| match r(u) {
        Ok(v) => v,
        Err(e) => {
            *err.borrow_mut() = Some(e);
            T::nan()
        }
    };
    let a = guess;
    let fa = f(a);
    if let Some(e) = err.borrow_mut().take() {
        return Err(ElementError::Rheology { step, source: e });
    }
    if fa == T::zero() {
        return Ok(a);
    }
    // Move against the residual's sign, doubling the step until the sign flips.
    let dir = if (fa > T::zero()) == increasing { -T::one() } else { T::one() };
    let mut delta = guess.abs().max(T::of(1e-12)) * T::of(0.5);
    let (mut lo, mut flo) = (a, fa);
    for _ in 0..200 {
        let b = lo + dir * delta;
        let fb = f(b);
        if let Some(e) = err.borrow_mut().take() {
            return Err(ElementError::Rheology { step, source: e });
        }
        if !fb.is_finite() {
            break;
        }
        if (fb > T::zero()) != (flo > T::zero()) || fb == T::zero() {
            let (x0, x1, f0, f1) = if b < lo { (b, lo, fb, flo) } else { (lo, b, flo, fb) };
            let root = brent(&f, x0, x1, f0, f1, T::min_positive_value(), 400);
            if let Some(e) = err.borrow_mut().take() {
                return Err(ElementError::Rheology { step, source: e });
            }
            return root.ok_or(ElementError::Control { step, what });
        }
        lo = b;
        flo = fb;
        delta *= T::of(2.0);
    }
    Err(ElementError::Control { step, what })
}

fn pressure_step<T: Real>(
    m: &Material<T>,
    pt: &mut Point<T>,
    test: ElementTest,
    target: T,
    step: usize,
) -> Result<(), ElementError> {
    let mods = m.moduli(&pt.sigma, &pt.state);
    let dp = target - pt.sigma.pressure();
    match test {
        ElementTest::Isotropic => {
            // p decreases as the isotropic extension e grows.
            let guess = -dp / (T::of(3.0) * mods.bulk);
            let r = |e: T| trial(m, pt, e.as_f64(), e.as_f64()).map(|(s, _)| s.pressure() - target);
            let e = solve_free(r, guess, false, step, "target mean pressure")?;
            apply(m, pt, e.as_f64(), e.as_f64(), step)
        }
        ElementTest::Oedometer => {
            let guess = -dp / mods.p_wave() * T::of(3.0) / (T::one() + T::of(2.0) * m.k0());
            let r = |e: T| trial(m, pt, 0.0, e.as_f64()).map(|(s, _)| s.pressure() - target);
            let e = solve_free(r, guess, false, step, "target mean pressure")?;
            apply(m, pt, 0.0, e.as_f64(), step)
        }
        _ => unreachable!("pressure control is for isotropic and oedometer tests"),
    }
}

fn drained_step<T: Real>(
    m: &Material<T>,
    pt: &mut Point<T>,
    de_a: f64,
    cell: T,
    step: usize,
) -> Result<(), ElementError> {
    let mods = m.moduli(&pt.sigma, &pt.state);
    let lame = mods.bulk - T::of(2.0 / 3.0) * mods.shear;
    let target = -cell; // radial stress, tension positive
    let dsr = target - pt.sigma.xx;
    let guess = (dsr - lame * T::of(de_a)) / (T::of(2.0) * (lame + mods.shear));
    let r = |e: T| trial(m, pt, e.as_f64(), de_a).map(|(s, _)| s.xx - target);
    let e = solve_free(r, guess, true, step, "constant cell pressure")?;
    apply(m, pt, e.as_f64(), de_a, step)
}

#[derive(Default)]
struct Recorder {
    p: Vec<f64>,
    q: Vec<f64>,
    pc: Vec<f64>,
    v: Vec<f64>,
    eps_axial: Vec<f64>,
    eps_vol: Vec<f64>,
    sigma_axial: Vec<f64>,
    sigma_radial: Vec<f64>,
}

impl Recorder {
    fn push<T: Real>(&mut self, pt: &Point<T>, is_mcc: bool) {
        self.p.push(pt.sigma.pressure().as_f64());
        self.q.push(pt.sigma.von_mises().as_f64());
        self.pc.push(if is_mcc { pt.state.pc.as_f64() } else { 0.0 });
        self.v.push(pt.state.v.as_f64());
        self.eps_axial.push(-pt.eps[1]);
        self.eps_vol.push(-(2.0 * pt.eps[0] + pt.eps[1]));
        self.sigma_axial.push(-pt.sigma.zz.as_f64());
        self.sigma_radial.push(-pt.sigma.xx.as_f64());
    }
}
