//! Drucker–Prager with a μ(I) friction law, cohesion and tension cut-off.
//!
//! Yield: `τ ≤ μ(I) p + k` with `τ = sqrt(J2) = q/√3`. The cone is matched to Mohr–Coulomb in
//! triaxial compression, so a drained triaxial test fails at the Mohr–Coulomb deviator
//! `q_f = σ3 (K_p − 1) + 2c √K_p`. Plastic flow is deviatoric (zero dilatancy, as in
//! Chrono's CRM): the return is radial in the deviatoric plane with `p` unchanged, which is
//! exact for constant elastic moduli.
//!
//! μ(I) (GDR MiDi): `μ(I) = μs + (μ2 − μs) / (I0/I + 1)`, `I = γ̇ d / sqrt(p/ρs)`,
//! `γ̇ = sqrt(2 D':D')`. With `μ2 = μs` it is plain Drucker–Prager.

use crate::Real;
use crate::math::Sym3;

use super::RheologyError;

/// Drucker–Prager / μ(I) parameters in the `τ = sqrt(J2)` form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DruckerPrager<T> {
    /// Static friction coefficient μs of the compression-matched cone (τ/p).
    pub mu_s: T,
    /// Limiting friction coefficient μ2 ≥ μs at high inertial number (τ/p).
    pub mu_2: T,
    /// Reference inertial number I0 (> 0 when μ2 > μs).
    pub i0: T,
    /// Grain diameter d (m), for the inertial number.
    pub grain_diameter: T,
    /// Grain (solid) density ρs (kg/m³), for the inertial number.
    pub grain_density: T,
    /// Cohesion term k of the cone (Pa), `τ_max = μ p + k`.
    pub k: T,
}

impl<T: Real> DruckerPrager<T> {
    /// Plain Drucker–Prager matched to Mohr–Coulomb in triaxial compression for a friction
    /// angle `phi_deg` (degrees) and cohesion `c` (Pa):
    /// `μ = 2√3 sinφ / (3 − sinφ)`, `k = 2√3 c cosφ / (3 − sinφ)`.
    pub fn from_mohr_coulomb(phi_deg: T, c: T) -> Self {
        let (mu, k) = cone_from_mohr_coulomb(phi_deg, c);
        Self { mu_s: mu, mu_2: mu, i0: T::one(), grain_diameter: T::zero(), grain_density: T::one(), k }
    }

    /// Adds a μ(I) law whose limiting friction comes from the angle `phi2_deg` ≥ φ, with
    /// reference inertial number `i0`, grain diameter `d` (m) and grain density `rho_s` (kg/m³).
    pub fn with_mu_i(mut self, phi2_deg: T, i0: T, d: T, rho_s: T) -> Self {
        self.mu_2 = cone_from_mohr_coulomb(phi2_deg, T::zero()).0;
        self.i0 = i0;
        self.grain_diameter = d;
        self.grain_density = rho_s;
        self
    }

    /// True when the friction depends on the inertial number.
    pub fn has_mu_i(&self) -> bool {
        self.mu_2 > self.mu_s
    }

    /// Friction coefficient at pressure `p` (Pa) and rate of deformation `d` (1/s).
    #[inline(always)]
    pub fn friction(&self, p: T, d: &Sym3<T>) -> T {
        if !self.has_mu_i() || p <= T::zero() {
            return self.mu_s;
        }
        let dev = d.deviator();
        let gamma_dot = (T::of(2.0) * dev.ddot(dev)).sqrt();
        let inertial = gamma_dot * self.grain_diameter / (p / self.grain_density).sqrt();
        if inertial <= T::zero() {
            return self.mu_s;
        }
        self.mu_s + (self.mu_2 - self.mu_s) / (self.i0 / inertial + T::one())
    }

    /// Plastic correction of a trial stress (tension positive, Pa) at rate of deformation `d`.
    ///
    /// Cohesionless soil (`k = 0`) carries no tension: a trial with `p ≤ 0` returns zero stress.
    /// A cohesive cone returns to its apex `p = −k/μ` beyond it. A frictionless cohesive
    /// material (μ = 0, von Mises) has no apex.
    #[inline]
    pub fn correct(&self, trial: Sym3<T>, d: &Sym3<T>) -> Result<Sym3<T>, RheologyError> {
        if !trial.is_finite() {
            return Err(RheologyError::NonFinite { model: "drucker-prager", stage: "trial stress" });
        }
        let p = trial.pressure();
        if self.k <= T::zero() && p <= T::zero() {
            return Ok(Sym3::zero());
        }
        if self.mu_s > T::zero() && p * self.mu_s + self.k <= T::zero() {
            let p_apex = -self.k / self.mu_s;
            return Ok(Sym3::iso(-p_apex));
        }
        let s = trial.deviator();
        let tau = (T::of(0.5) * s.ddot(s)).sqrt();
        let tau_max = self.friction(p, d) * p + self.k;
        if tau <= tau_max {
            return Ok(trial);
        }
        let scale = tau_max / tau;
        Ok(s * scale - Sym3::iso(p))
    }
}

/// `(μ, k)` of the Drucker–Prager cone through the Mohr–Coulomb compression meridian, in the
/// `τ = sqrt(J2)` form.
pub fn cone_from_mohr_coulomb<T: Real>(phi_deg: T, c: T) -> (T, T) {
    let phi = phi_deg.to_radians();
    let (s, co) = (phi.sin(), phi.cos());
    let f = T::of(2.0) * T::of(3.0).sqrt() / (T::of(3.0) - s);
    (f * s, f * c * co)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn cone_equals_mohr_coulomb_in_compression() {
        for &(phi, c, s3) in &[(30.0_f64, 0.0, 1.0e4), (35.0, 2.0e3, 5.0e4), (20.0, 1.0e4, 1.0e3)] {
            let dp = DruckerPrager::from_mohr_coulomb(phi, c);
            let sp = phi.to_radians().sin();
            let kp = (1.0 + sp) / (1.0 - sp);
            let qf = s3 * (kp - 1.0) + 2.0 * c * kp.sqrt();
            // On the cone, τ = μ p + k with p = σ3 + q/3, τ = q/√3.
            let p = s3 + qf / 3.0;
            assert_relative_eq!(qf / 3f64.sqrt(), dp.mu_s * p + dp.k, max_relative = 1e-12);
        }
    }

    #[test]
    fn cohesionless_soil_carries_no_tension() {
        let dp = DruckerPrager::<f64>::from_mohr_coulomb(30.0, 0.0);
        let out = dp.correct(Sym3::new(100.0, 50.0, -20.0, 10.0, 0.0, 5.0), &Sym3::zero()).unwrap();
        assert_eq!(out, Sym3::zero());
    }

    #[test]
    fn cohesive_cone_returns_to_apex_in_tension() {
        let dp = DruckerPrager::<f64>::from_mohr_coulomb(30.0, 1.0e3);
        let out = dp.correct(Sym3::new(1.0e5, 1.0e5, 1.0e5, 0.0, 0.0, 0.0), &Sym3::zero()).unwrap();
        assert_relative_eq!(out.pressure(), -dp.k / dp.mu_s, max_relative = 1e-12);
        assert_relative_eq!(out.von_mises(), 0.0, epsilon = 1e-9);
    }

    #[test]
    fn radial_return_keeps_pressure_and_lands_on_the_cone() {
        let dp = DruckerPrager::<f64>::from_mohr_coulomb(30.0, 500.0);
        let trial = Sym3::new(-1.0e4, -3.0e4, -8.0e4, 2.0e4, -1.0e4, 5.0e3);
        let out = dp.correct(trial, &Sym3::zero()).unwrap();
        assert_relative_eq!(out.pressure(), trial.pressure(), max_relative = 1e-12);
        let tau = out.von_mises() / 3f64.sqrt();
        assert_relative_eq!(tau, dp.mu_s * out.pressure() + dp.k, max_relative = 1e-12);
    }

    #[test]
    fn mu_i_raises_friction_with_shear_rate_and_saturates() {
        let dp = DruckerPrager::<f64>::from_mohr_coulomb(25.0, 0.0).with_mu_i(35.0, 0.3, 1e-3, 2600.0);
        let shear = |g: f64| Sym3::new(0.0, 0.0, 0.0, 0.5 * g, 0.0, 0.0);
        let p = 1.0e3;
        let mu0 = dp.friction(p, &shear(0.0));
        let mu1 = dp.friction(p, &shear(10.0));
        let mu_inf = dp.friction(p, &shear(1.0e9));
        assert_relative_eq!(mu0, dp.mu_s);
        assert!(mu1 > dp.mu_s && mu1 < dp.mu_2);
        assert_relative_eq!(mu_inf, dp.mu_2, max_relative = 1e-4);
        // I = γ̇ d / sqrt(p/ρs) = 10 * 1e-3 / sqrt(1e3/2600)
        let i = 10.0 * 1e-3 / (p / 2600.0_f64).sqrt();
        assert_relative_eq!(mu1, dp.mu_s + (dp.mu_2 - dp.mu_s) / (0.3 / i + 1.0), max_relative = 1e-12);
    }
}
