//! Soil constitutive models as pure, backend-independent functions.
//!
//! Each model is a function of (stress, state variables, rate of deformation or strain
//! increment, time step) generic over `f32`/`f64`. The SPH solver, the material-point driver
//! (`regolith element`) and the GPU kernels' CPU twins all call these same functions, so what
//! the verification tests check is what the solver runs.
//!
//! Conventions: Cauchy stress, tension positive, Pa; `p = −tr(σ)/3` (compression positive);
//! `q = sqrt(3/2 s:s)`; strain increments extension positive.

mod calibration;
mod drucker_prager;
mod elastic;
mod mcc;
mod params;
mod root;
mod water;

pub use calibration::{k0_elastic, k0_jaky, kappa_from_cr, lambda_from_cc, m_from_friction_angle, pc0_from_ocr};
pub use drucker_prager::{DruckerPrager, cone_from_mohr_coulomb};
pub use elastic::{Moduli, elastic_increment, jaumann_rate, spin_terms};
pub use mcc::{MccSafeguards, ModifiedCamClay, P_REF};
pub use params::{MaterialParams, ModelKind, ParamError};
pub use root::brent;
pub use water::{MIN_POROSITY, STANDARD_GRAVITY, Water};

use crate::Real;
use crate::math::{Sym3, Vec3};

/// Why a constitutive update failed. The solver stops with this error rather than replacing a
/// bad value.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RheologyError {
    /// A NaN or infinity entered or left the model.
    #[error("{model}: non-finite value in the {stage}")]
    NonFinite {
        /// Model name.
        model: &'static str,
        /// Where it was detected.
        stage: &'static str,
    },
    /// The return mapping did not converge (should not happen: the solve is bracketed).
    #[error("{model}: return mapping did not converge ({stage})")]
    NoConvergence {
        /// Model name.
        model: &'static str,
        /// Which solve.
        stage: &'static str,
    },
    /// The state variables are outside the model's domain.
    #[error("{model}: invalid state: {what}")]
    InvalidState {
        /// Model name.
        model: &'static str,
        /// What is wrong.
        what: &'static str,
    },
}

/// Per-point state variables. `pc` and `v` are used by Modified Cam Clay only; other models
/// carry them untouched.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointState<T> {
    /// Preconsolidation pressure `p_c` (Pa).
    pub pc: T,
    /// Specific volume `v = 1 + e`.
    pub v: T,
}

impl<T: Real> PointState<T> {
    /// Advances the specific volume by a volumetric strain increment `tr(Δε)` (extension
    /// positive): `v ← v exp(tr Δε)`, the exact integral of `dv = v tr(D) dt`.
    #[inline(always)]
    pub fn advance_volume(&mut self, tr_d_eps: T) {
        self.v *= tr_d_eps.exp();
    }
}

/// The constitutive model of a material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rheology<T> {
    /// Hypoelastic, no yield.
    Elastic,
    /// Drucker–Prager / μ(I).
    DruckerPrager(DruckerPrager<T>),
    /// Modified Cam Clay.
    Mcc(ModifiedCamClay<T>),
    /// Water (not a soil: a liquid phase that may share space with the soil).
    Water(Water<T>),
}

impl<T> Rheology<T> {
    /// Short name, as in material files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Elastic => "elastic",
            Self::DruckerPrager(_) => "drucker-prager",
            Self::Mcc(_) => "mcc",
            Self::Water(_) => "water",
        }
    }
}

/// A soil material: density, reference elasticity and a constitutive model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material<T> {
    /// Bulk density ρ0 (kg/m³).
    pub density: T,
    /// Reference moduli from E and ν (Pa).
    pub elastic: Moduli<T>,
    /// Poisson ratio ν.
    pub poisson: T,
    /// Friction angle φ (degrees), used for K0 and reporting; 0 for elastic materials.
    pub friction_angle_deg: T,
    /// Cohesion c (Pa).
    pub cohesion: T,
    /// Overconsolidation ratio p_c0/p0 used to initialise MCC points (1 for other models).
    pub ocr: T,
    /// The model.
    pub rheology: Rheology<T>,
    /// Hydraulic conductivity k (m/s, at standard gravity) of a soil that water can flow
    /// through; 0 when not given (the soil then cannot share space with water).
    pub permeability: T,
    /// Grain (solid) density ρ_g (kg/m³) of a soil, from which its porosity is
    /// `n = 1 − ρ / ρ_g`; 0 when not given.
    pub grain_density: T,
}

impl<T: Real> Material<T> {
    /// Elastic moduli at the given stress and state (pressure-dependent for MCC).
    #[inline(always)]
    pub fn moduli(&self, sigma: &Sym3<T>, state: &PointState<T>) -> Moduli<T> {
        match &self.rheology {
            Rheology::Mcc(mcc) => mcc.moduli(sigma.pressure(), state.v),
            _ => self.elastic,
        }
    }

    /// Plastic correction of a trial stress. `d` is the rate of deformation (1/s), used by
    /// μ(I); `moduli` are those the trial was computed with.
    #[inline]
    pub fn correct(
        &self,
        trial: Sym3<T>,
        state: &mut PointState<T>,
        moduli: Moduli<T>,
        d: &Sym3<T>,
    ) -> Result<Sym3<T>, RheologyError> {
        match &self.rheology {
            Rheology::Elastic => {
                if trial.is_finite() {
                    Ok(trial)
                } else {
                    Err(RheologyError::NonFinite { model: "elastic", stage: "trial stress" })
                }
            }
            Rheology::DruckerPrager(dp) => dp.correct(trial, d),
            Rheology::Mcc(mcc) => mcc.correct(trial, state, moduli),
            // The solver sets a liquid's stress from its equation of state each stage.
            Rheology::Water(_) => Ok(trial),
        }
    }

    /// One full material-point increment: elastic predictor with the Jaumann rate, plastic
    /// correction, specific-volume update. `d_eps` is the strain increment `D dt`, `spin` the
    /// spin increment `Ω dt` as `(Ω_xy, Ω_xz, Ω_yz)`, `dt` the time step (s, > 0; only μ(I)
    /// uses it).
    pub fn update(
        &self,
        sigma: &Sym3<T>,
        state: &mut PointState<T>,
        d_eps: &Sym3<T>,
        spin: Vec3<T>,
        dt: T,
    ) -> Result<Sym3<T>, RheologyError> {
        let moduli = self.moduli(sigma, state);
        let trial = *sigma + elastic_increment(d_eps, moduli) + spin_terms(sigma, spin);
        let rate = *d_eps * (T::one() / dt);
        let out = self.correct(trial, state, moduli, &rate)?;
        state.advance_volume(d_eps.trace());
        Ok(out)
    }

    /// The state of a point at isotropic pressure `p0` (Pa): for MCC `p_c0 = OCR p0` (with the
    /// floor) and `v` from the normal compression and swelling lines; otherwise `v = 1`
    /// (volume relative to the initial one).
    pub fn initial_state(&self, p0: T) -> PointState<T> {
        match &self.rheology {
            Rheology::Mcc(mcc) => {
                let p0 = p0.max(T::of(1e-3));
                let pc = pc0_from_ocr(self.ocr, p0).max(mcc.safeguards.pc_floor);
                PointState { pc, v: mcc.initial_specific_volume(pc, p0) }
            }
            _ => PointState { pc: T::zero(), v: T::one() },
        }
    }

    /// At-rest earth pressure coefficient: `1 − sin φ` (Jáky) for frictional models,
    /// `ν/(1 − ν)` for elastic ones.
    pub fn k0(&self) -> T {
        match &self.rheology {
            Rheology::Elastic => k0_elastic(self.poisson),
            Rheology::Water(_) => T::one(),
            _ => k0_jaky(self.friction_angle_deg),
        }
    }

    /// Whether this is a liquid (the water phase) rather than a soil.
    pub fn is_water(&self) -> bool {
        matches!(self.rheology, Rheology::Water(_))
    }

    /// Largest elastic wave speed `sqrt((K + 4G/3)/ρ0)` (m/s) over the moduli this material
    /// can take (the reference moduli; MCC moduli are bounded by them when clamped).
    pub fn wave_speed(&self) -> T {
        (self.elastic.p_wave() / self.density).sqrt()
    }
}
