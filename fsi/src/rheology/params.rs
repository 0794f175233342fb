//! Material parameters as users write them (SI units, angles in degrees), and the consistency
//! rules that turn them into a [`Material`].
//!
//! The field names are the keys of material files and of a scene's `[[materials]]` entries, so
//! a [`ParamError`] names the key the user has to fix.

use serde::Deserialize;

use super::{DruckerPrager, Material, MccSafeguards, ModifiedCamClay, Moduli, Rheology, Water};
use super::{kappa_from_cr, lambda_from_cc, m_from_friction_angle};
use crate::Real;

/// Which constitutive model a material uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Hypoelastic, no yield.
    Elastic,
    /// Drucker–Prager / μ(I).
    DruckerPrager,
    /// Modified Cam Clay.
    Mcc,
    /// Water: a weakly compressible liquid, alone or in the pores of a soil.
    Water,
}

impl ModelKind {
    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Elastic => "elastic",
            Self::DruckerPrager => "drucker-prager",
            Self::Mcc => "mcc",
            Self::Water => "water",
        }
    }
}

/// A material as written in a TOML file: every key optional at parse time, checked by
/// [`MaterialParams::build`].
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialParams {
    /// Name (required inside scenes, optional in a material file).
    pub name: Option<String>,
    /// Scenes only: read the material from this file (relative to the scene) instead.
    pub file: Option<String>,
    /// `"elastic"`, `"drucker-prager"`, `"mcc"` or `"water"`.
    pub model: Option<ModelKind>,
    /// Bulk density (kg/m³).
    pub density: Option<f64>,
    /// Young's modulus E (Pa): the elastic stiffness, and for MCC the clamp's reference.
    pub youngs_modulus: Option<f64>,
    /// Poisson ratio ν, 0 < ν < 0.5.
    pub poisson_ratio: Option<f64>,
    /// Friction angle φ (degrees): the Drucker–Prager cone, or M for MCC when `mcc_m` is absent.
    pub friction_angle: Option<f64>,
    /// Cohesion c (Pa), Drucker–Prager only.
    pub cohesion: Option<f64>,
    /// μ(I): limiting friction angle (degrees) at high inertial number, ≥ `friction_angle`.
    pub mu_i_friction_angle: Option<f64>,
    /// μ(I): reference inertial number I0.
    pub mu_i_i0: Option<f64>,
    /// μ(I): grain diameter (m).
    pub grain_diameter: Option<f64>,
    /// Grain (solid) density (kg/m³): for μ(I), and for the porosity `1 − density /
    /// grain_density` of a soil that water flows through.
    pub grain_density: Option<f64>,
    /// Hydraulic conductivity k (m/s, at standard gravity) of a soil that water flows through
    /// (needs `grain_density`).
    pub permeability: Option<f64>,
    /// Water: numerical sound speed (m/s).
    pub sound_speed: Option<f64>,
    /// Water: dynamic viscosity (Pa s).
    pub viscosity: Option<f64>,
    /// MCC critical-state slope M.
    pub mcc_m: Option<f64>,
    /// MCC swelling slope κ (v–ln p).
    pub mcc_kappa: Option<f64>,
    /// MCC normal compression slope λ (v–ln p).
    pub mcc_lambda: Option<f64>,
    /// MCC recompression index Cr (e–log10 p), instead of `mcc_kappa`.
    pub mcc_cr: Option<f64>,
    /// MCC compression index Cc (e–log10 p), instead of `mcc_lambda`.
    pub mcc_cc: Option<f64>,
    /// MCC specific volume on the normal compression line at 1000 Pa.
    pub mcc_v_lambda: Option<f64>,
    /// MCC overconsolidation ratio `p_c0 / p0` (≥ 1, default 1).
    pub ocr: Option<f64>,
    /// MCC safeguard: clamp K and G to [0.1, 1] × the reference moduli (default true).
    pub mcc_clamp_moduli: Option<bool>,
    /// MCC safeguard: floor on p_c in Pa (default 100; 0 turns it off).
    pub mcc_pc_floor: Option<f64>,
}

/// A rule a material breaks: the offending key and what is allowed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("key `{key}`: {message}")]
pub struct ParamError {
    /// The key to fix, as written in files.
    pub key: &'static str,
    /// What is wrong and what is allowed.
    pub message: String,
}

fn err(key: &'static str, message: impl Into<String>) -> ParamError {
    ParamError { key, message: message.into() }
}

fn require(key: &'static str, v: Option<f64>, model: ModelKind) -> Result<f64, ParamError> {
    let x = v.ok_or_else(|| err(key, format!("is required for model \"{}\"", model.name())))?;
    if x.is_finite() { Ok(x) } else { Err(err(key, format!("must be a finite number (got {x})"))) }
}

fn positive(key: &'static str, x: f64, unit: &str) -> Result<f64, ParamError> {
    if x > 0.0 && x.is_finite() { Ok(x) } else { Err(err(key, format!("must be > 0{unit} (got {x})"))) }
}

fn forbid(key: &'static str, present: bool, model: ModelKind, hint: &str) -> Result<(), ParamError> {
    if present { Err(err(key, format!("does not apply to model \"{}\"{hint}", model.name()))) } else { Ok(()) }
}

impl MaterialParams {
    /// Checks every consistency rule and builds the material. Rules: density, E > 0;
    /// 0 < ν < 0.5; 0 ≤ φ < 90°; c ≥ 0; a Drucker–Prager material has some strength; MCC needs
    /// κ > 0, λ > κ (and says so when they look swapped), M > 0 (or φ), v_λ > 1, OCR ≥ 1;
    /// μ(I) keys come together; keys that do not apply to the model are errors, never ignored.
    pub fn build<T: Real>(&self) -> Result<Material<T>, ParamError> {
        let model = self
            .model
            .ok_or_else(|| err("model", "is required: one of \"elastic\", \"drucker-prager\", \"mcc\", \"water\""))?;
        if self.file.is_some() {
            return Err(err("file", "a material read from a file cannot itself name a file"));
        }
        let density = positive("density", require("density", self.density, model)?, " kg/m³")?;
        if model == ModelKind::Water {
            return self.build_water(density);
        }
        for (k, v) in [("sound_speed", self.sound_speed), ("viscosity", self.viscosity)] {
            forbid(k, v.is_some(), model, " (it is a water key; set model = \"water\")")?;
        }
        let (permeability, grain_density) = self.pore_keys(density)?;
        let young = positive("youngs_modulus", require("youngs_modulus", self.youngs_modulus, model)?, " Pa")?;
        let nu = require("poisson_ratio", self.poisson_ratio, model)?;
        if !(nu > 0.0 && nu < 0.5) {
            return Err(err("poisson_ratio", format!("must satisfy 0 < ν < 0.5 (got {nu})")));
        }
        if let Some(phi) = self.friction_angle
            && !(phi.is_finite() && (0.0..90.0).contains(&phi))
        {
            return Err(err("friction_angle", format!("must be in [0, 90) degrees (got {phi})")));
        }
        // μ(I) also needs grain_density, which a wet soil may give on its own (`pore_keys`).
        let mu_i_keys = [
            ("mu_i_friction_angle", self.mu_i_friction_angle),
            ("mu_i_i0", self.mu_i_i0),
            ("grain_diameter", self.grain_diameter),
        ];
        let mcc_keys = self.mcc_keys();
        let elastic = Moduli::from_young_poisson(T::of(young), T::of(nu));
        let mut material = Material {
            density: T::of(density),
            elastic,
            poisson: T::of(nu),
            friction_angle_deg: T::zero(),
            cohesion: T::zero(),
            ocr: T::one(),
            rheology: Rheology::Elastic,
            permeability: T::of(permeability.unwrap_or(0.0)),
            grain_density: T::of(grain_density.unwrap_or(0.0)),
        };
        match model {
            ModelKind::Water => return self.build_water(density),
            ModelKind::Elastic => {
                forbid("friction_angle", self.friction_angle.is_some(), model, "")?;
                forbid("cohesion", self.cohesion.is_some(), model, "")?;
                for (k, v) in mu_i_keys {
                    forbid(k, v.is_some(), model, "")?;
                }
                for (k, present) in mcc_keys {
                    forbid(k, present, model, "")?;
                }
            }
            ModelKind::DruckerPrager => {
                let (phi, c, dp) = self.build_dp(model, mu_i_keys, mcc_keys)?;
                material.friction_angle_deg = T::of(phi);
                material.cohesion = T::of(c);
                material.rheology = Rheology::DruckerPrager(dp);
            }
            ModelKind::Mcc => {
                let (m, ocr, mcc) = self.build_mcc(model, mu_i_keys, nu, elastic)?;
                // sin φ from M (triaxial compression), used for K0 at rest.
                let sin_phi = 3.0 * m / (6.0 + m);
                material.friction_angle_deg = T::of(sin_phi.asin().to_degrees());
                material.ocr = T::of(ocr);
                material.rheology = Rheology::Mcc(mcc);
            }
        }
        if grain_density.is_some() && permeability.is_none() && self.mu_i_i0.is_none() {
            return Err(err(
                "grain_density",
                "applies with permeability (a soil water flows through) or with the μ(I) keys; give one or drop it",
            ));
        }
        Ok(material)
    }

    /// A Drucker–Prager material's φ (degrees), c (Pa) and yield surface, with μ(I) when its
    /// keys are given (all of them, grain density included).
    fn build_dp<T: Real>(
        &self,
        model: ModelKind,
        mu_i_keys: [(&'static str, Option<f64>); 3],
        mcc_keys: [(&'static str, bool); 9],
    ) -> Result<(f64, f64, DruckerPrager<T>), ParamError> {
        for (k, present) in mcc_keys {
            forbid(k, present, model, " (it is a Modified Cam Clay key; set model = \"mcc\")")?;
        }
        let phi = require("friction_angle", self.friction_angle, model)?;
        let c = self.cohesion.unwrap_or(0.0);
        if !(c.is_finite() && c >= 0.0) {
            return Err(err("cohesion", format!("must be ≥ 0 Pa (got {c})")));
        }
        if phi == 0.0 && c == 0.0 {
            return Err(err(
                "friction_angle",
                "and cohesion are both zero: the soil would have no strength; give φ > 0 or c > 0",
            ));
        }
        let mut dp = DruckerPrager::from_mohr_coulomb(T::of(phi), T::of(c));
        let given = mu_i_keys.iter().filter(|(_, v)| v.is_some()).count();
        if given > 0 {
            let missing = mu_i_keys.iter().copied().chain([("grain_density", self.grain_density)]);
            if let Some((k, _)) = missing.into_iter().find(|(_, v)| v.is_none()) {
                return Err(err(
                    k,
                    "is required when any μ(I) key is given (mu_i_friction_angle, mu_i_i0, grain_diameter, grain_density)",
                ));
            }
            let phi2 = self.mu_i_friction_angle.unwrap_or(phi);
            if !(phi2.is_finite() && phi2 >= phi && phi2 < 90.0) {
                return Err(err(
                    "mu_i_friction_angle",
                    format!("must be in [friction_angle = {phi}, 90) degrees (got {phi2})"),
                ));
            }
            let i0 = positive("mu_i_i0", self.mu_i_i0.unwrap_or(0.0), "")?;
            let d = positive("grain_diameter", self.grain_diameter.unwrap_or(0.0), " m")?;
            let rho_s = positive("grain_density", self.grain_density.unwrap_or(0.0), " kg/m³")?;
            dp = dp.with_mu_i(T::of(phi2), T::of(i0), T::of(d), T::of(rho_s));
        }
        Ok((phi, c, dp))
    }

    /// A Modified Cam Clay material's M, OCR and model: M or φ, κ or Cr, λ or Cc, v_λ and the
    /// safeguards.
    fn build_mcc<T: Real>(
        &self,
        model: ModelKind,
        mu_i_keys: [(&'static str, Option<f64>); 3],
        nu: f64,
        elastic: Moduli<T>,
    ) -> Result<(f64, f64, ModifiedCamClay<T>), ParamError> {
        forbid("cohesion", self.cohesion.is_some(), model, " (Modified Cam Clay is cohesionless here)")?;
        for (k, v) in mu_i_keys {
            forbid(k, v.is_some(), model, "")?;
        }
        let m = match (self.mcc_m, self.friction_angle) {
            (Some(_), Some(_)) => {
                return Err(err("mcc_m", "and friction_angle are both given: give one (M = 6 sinφ / (3 − sinφ))"));
            }
            (Some(m), None) => m,
            (None, Some(phi)) => {
                if phi <= 0.0 {
                    return Err(err("friction_angle", format!("must be > 0 degrees for model \"mcc\" (got {phi})")));
                }
                m_from_friction_angle(phi)
            }
            (None, None) => return Err(err("mcc_m", "is required for model \"mcc\" (or give friction_angle)")),
        };
        if !(m.is_finite() && m > 0.0 && m < 3.0) {
            return Err(err("mcc_m", format!("must satisfy 0 < M < 3 (got {m})")));
        }
        let (kappa, lambda) = self.mcc_slopes()?;
        let v_lambda = require("mcc_v_lambda", self.mcc_v_lambda, model)?;
        if v_lambda <= 1.0 {
            return Err(err("mcc_v_lambda", format!("must be > 1: it is a specific volume 1 + e (got {v_lambda})")));
        }
        let ocr = self.ocr.unwrap_or(1.0);
        if !(ocr.is_finite() && ocr >= 1.0) {
            return Err(err(
                "ocr",
                format!("must be ≥ 1 (got {ocr}); OCR < 1 puts the start outside the yield surface"),
            ));
        }
        let floor = self.mcc_pc_floor.unwrap_or(100.0);
        if !(floor.is_finite() && floor >= 0.0) {
            return Err(err("mcc_pc_floor", format!("must be ≥ 0 Pa (got {floor}); 0 turns the floor off")));
        }
        let clamp = self.mcc_clamp_moduli.unwrap_or(true);
        let safeguards = MccSafeguards {
            moduli_clamp: if clamp { Some((T::of(0.1), T::one())) } else { None },
            pc_floor: T::of(floor),
        };
        Ok((
            m,
            ocr,
            ModifiedCamClay {
                m: T::of(m),
                kappa: T::of(kappa),
                lambda: T::of(lambda),
                v_lambda: T::of(v_lambda),
                poisson: T::of(nu),
                reference: elastic,
                safeguards,
            },
        ))
    }

    /// κ (from `mcc_kappa` or `mcc_cr`) and λ (from `mcc_lambda` or `mcc_cc`): one of each pair,
    /// both > 0 and λ > κ.
    fn mcc_slopes(&self) -> Result<(f64, f64), ParamError> {
        let kappa = match (self.mcc_kappa, self.mcc_cr) {
            (Some(_), Some(_)) => {
                return Err(err("mcc_kappa", "and mcc_cr are both given: give one (κ = Cr / ln 10)"));
            }
            (Some(k), None) => k,
            (None, Some(cr)) => kappa_from_cr(cr),
            (None, None) => return Err(err("mcc_kappa", "is required for model \"mcc\" (or give mcc_cr)")),
        };
        let lambda = match (self.mcc_lambda, self.mcc_cc) {
            (Some(_), Some(_)) => {
                return Err(err("mcc_lambda", "and mcc_cc are both given: give one (λ = Cc / ln 10)"));
            }
            (Some(l), None) => l,
            (None, Some(cc)) => lambda_from_cc(cc),
            (None, None) => return Err(err("mcc_lambda", "is required for model \"mcc\" (or give mcc_cc)")),
        };
        let kappa_key = if self.mcc_kappa.is_some() { "mcc_kappa" } else { "mcc_cr" };
        let lambda_key = if self.mcc_lambda.is_some() { "mcc_lambda" } else { "mcc_cc" };
        if !(kappa.is_finite() && kappa > 0.0) {
            return Err(err(kappa_key, format!("must be > 0 (got {kappa})")));
        }
        if !(lambda.is_finite() && lambda > 0.0) {
            return Err(err(lambda_key, format!("must be > 0 (got {lambda})")));
        }
        if lambda < kappa {
            return Err(err(
                lambda_key,
                format!(
                    "λ = {lambda} is smaller than κ = {kappa}: they look swapped. κ ({kappa_key}) is the swelling slope, \
                     λ ({lambda_key}) the steeper normal compression slope; MCC needs λ > κ"
                ),
            ));
        }
        if lambda == kappa {
            return Err(err(
                lambda_key,
                format!("must be greater than κ (both are {kappa}): the hardening law divides by λ − κ"),
            ));
        }
        Ok((kappa, lambda))
    }

    /// The Modified Cam Clay keys and whether each is given.
    fn mcc_keys(&self) -> [(&'static str, bool); 9] {
        [
            ("mcc_m", self.mcc_m.is_some()),
            ("mcc_kappa", self.mcc_kappa.is_some()),
            ("mcc_lambda", self.mcc_lambda.is_some()),
            ("mcc_cr", self.mcc_cr.is_some()),
            ("mcc_cc", self.mcc_cc.is_some()),
            ("mcc_v_lambda", self.mcc_v_lambda.is_some()),
            ("ocr", self.ocr.is_some()),
            ("mcc_clamp_moduli", self.mcc_clamp_moduli.is_some()),
            ("mcc_pc_floor", self.mcc_pc_floor.is_some()),
        ]
    }

    /// `permeability` and `grain_density` of a soil: a conductivity needs the grain density, and
    /// the grain density must exceed the bulk density (a porosity in (0, 1)).
    fn pore_keys(&self, density: f64) -> Result<(Option<f64>, Option<f64>), ParamError> {
        let k = self.permeability.map(|k| positive("permeability", k, " m/s")).transpose()?;
        let rho_g = self.grain_density.map(|g| positive("grain_density", g, " kg/m³")).transpose()?;
        if k.is_some() && rho_g.is_none() {
            return Err(err(
                "grain_density",
                "is required with permeability: the porosity is 1 − density / grain_density (quartz sand: 2650 kg/m³)",
            ));
        }
        if let (Some(_), Some(g)) = (k, rho_g)
            && g <= density
        {
            return Err(err(
                "grain_density",
                format!(
                    "must exceed the bulk density {density} kg/m³ (porosity 1 − density / grain_density > 0; got {g})"
                ),
            ));
        }
        Ok((k, rho_g))
    }

    /// A liquid: density, sound speed and viscosity; every soil key is refused.
    fn build_water<T: Real>(&self, density: f64) -> Result<Material<T>, ParamError> {
        let model = ModelKind::Water;
        let c = positive("sound_speed", require("sound_speed", self.sound_speed, model)?, " m/s")?;
        let mu = require("viscosity", self.viscosity, model)?;
        if mu < 0.0 {
            return Err(err("viscosity", format!("must be ≥ 0 Pa s (water at 20 °C: 1.0e-3; got {mu})")));
        }
        let soil_keys = [
            ("youngs_modulus", self.youngs_modulus.is_some()),
            ("poisson_ratio", self.poisson_ratio.is_some()),
            ("friction_angle", self.friction_angle.is_some()),
            ("cohesion", self.cohesion.is_some()),
            ("mu_i_friction_angle", self.mu_i_friction_angle.is_some()),
            ("mu_i_i0", self.mu_i_i0.is_some()),
            ("grain_diameter", self.grain_diameter.is_some()),
            ("grain_density", self.grain_density.is_some()),
            ("permeability", self.permeability.is_some()),
        ];
        for (k, present) in soil_keys.into_iter().chain(self.mcc_keys()) {
            forbid(k, present, model, " (it is a soil key; give it to the soil the water flows through)")?;
        }
        Ok(Material {
            density: T::of(density),
            elastic: Moduli { bulk: T::of(density * c * c), shear: T::zero() },
            poisson: T::of(0.5),
            friction_angle_deg: T::zero(),
            cohesion: T::zero(),
            ocr: T::one(),
            rheology: Rheology::Water(Water { sound_speed: T::of(c), viscosity: T::of(mu) }),
            permeability: T::zero(),
            grain_density: T::zero(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mcc() -> MaterialParams {
        MaterialParams {
            model: Some(ModelKind::Mcc),
            density: Some(1700.0),
            youngs_modulus: Some(2.0e7),
            poisson_ratio: Some(0.3),
            mcc_m: Some(1.2),
            mcc_kappa: Some(0.02),
            mcc_lambda: Some(0.1),
            mcc_v_lambda: Some(2.2),
            ocr: Some(2.0),
            ..Default::default()
        }
    }

    #[test]
    fn mcc_builds_with_defaults_for_safeguards() {
        let m = mcc().build::<f64>().unwrap();
        match m.rheology {
            Rheology::Mcc(p) => {
                assert_eq!(p.safeguards, MccSafeguards::default());
                assert_eq!(p.m, 1.2);
            }
            _ => panic!("not mcc"),
        }
        assert!((m.friction_angle_deg - 30.0).abs() < 1e-9);
    }

    #[test]
    fn indices_convert() {
        let p = MaterialParams { mcc_kappa: None, mcc_lambda: None, mcc_cr: Some(0.046), mcc_cc: Some(0.23), ..mcc() };
        let Rheology::Mcc(m) = p.build::<f64>().unwrap().rheology else { panic!() };
        assert!((m.lambda - 0.23 / std::f64::consts::LN_10).abs() < 1e-15);
        assert!((m.kappa - 0.046 / std::f64::consts::LN_10).abs() < 1e-15);
    }
}
