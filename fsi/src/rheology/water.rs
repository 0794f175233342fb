//! Pore water and free water: a weakly compressible liquid.
//!
//! The pressure follows the linear equation of state `p = c² (ρ − ρ0)` of the water's *own*
//! (intrinsic) density ρ, which inside soil is the particle's partial density divided by the
//! porosity (see `crate::cpu` for how the porosity is found). Water carries no tension: where
//! the state would give `p < 0` (a free surface pulled apart, a film draining off a filter) it
//! cavitates at `p = 0`, which is also what keeps a weakly compressible free surface from
//! clumping. The sound speed is a numerical choice, as in every weakly compressible SPH: large
//! enough that the water is nearly incompressible against the soil skeleton
//! (`ρ0 c² / n ≫` the skeleton's constrained modulus) and against the flow (`c ≥ 10 |v|max`),
//! small enough that the time step `∝ h / c` stays affordable.

use crate::Real;

/// Standard gravity (m/s²): hydraulic conductivities are quoted at it, so a conductivity k
/// (m/s) means a drag coefficient `ρ_w g_n / k` whatever the scene's gravity (a consolidation
/// test without gravity still drains).
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Porosity is kept at or above this value where the soil's smoothed solid fraction says less
/// (a water particle squeezed between soil particles closer than their lattice spacing): the
/// intrinsic density `ρ̄ / n` would otherwise blow up.
pub const MIN_POROSITY: f64 = 0.05;

/// A liquid's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Water<T> {
    /// Numerical sound speed c (m/s).
    pub sound_speed: T,
    /// Dynamic viscosity μ (Pa s).
    pub viscosity: T,
}

impl<T: Real> Water<T> {
    /// Pressure (Pa, compression positive) at intrinsic density `rho` for rest density
    /// `rest`: `max(c² (ρ − ρ0), 0)`.
    #[inline(always)]
    pub fn pressure(&self, rho: T, rest: T) -> T {
        (self.sound_speed * self.sound_speed * (rho - rest)).max(T::zero())
    }

    /// The intrinsic density at pressure `p` (the inverse of [`Water::pressure`] for p ≥ 0).
    pub fn density_at(&self, p: T, rest: T) -> T {
        rest + p / (self.sound_speed * self.sound_speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pressure_is_linear_in_density_and_never_tensile() {
        let w = Water { sound_speed: 50.0_f64, viscosity: 1e-3 };
        assert_eq!(w.pressure(1000.0, 1000.0), 0.0);
        assert!((w.pressure(1001.0, 1000.0) - 2500.0).abs() < 1e-9);
        assert_eq!(w.pressure(990.0, 1000.0), 0.0);
        assert!((w.density_at(w.pressure(1003.0, 1000.0), 1000.0) - 1003.0).abs() < 1e-12);
    }
}
