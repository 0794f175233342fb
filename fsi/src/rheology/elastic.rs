//! Hypoelastic response: isotropic moduli and the Jaumann (co-rotational) stress rate.

use crate::Real;
use crate::math::{Sym3, Vec3};

/// Bulk and shear moduli (Pa) of an isotropic elastic response.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moduli<T> {
    /// Bulk modulus K (Pa).
    pub bulk: T,
    /// Shear modulus G (Pa).
    pub shear: T,
}

impl<T: Real> Moduli<T> {
    /// K = E / (3 (1 − 2ν)) and G = E / (2 (1 + ν)).
    pub fn from_young_poisson(young: T, poisson: T) -> Self {
        let one = T::one();
        let two = T::of(2.0);
        Self { bulk: young / (T::of(3.0) * (one - two * poisson)), shear: young / (two * (one + poisson)) }
    }

    /// G from K at a fixed Poisson ratio: G = 3K (1 − 2ν) / (2 (1 + ν)).
    pub fn from_bulk_poisson(bulk: T, poisson: T) -> Self {
        let one = T::one();
        let two = T::of(2.0);
        Self { bulk, shear: T::of(3.0) * bulk * (one - two * poisson) / (two * (one + poisson)) }
    }

    /// P-wave modulus K + 4G/3, which sets the elastic wave speed `sqrt((K + 4G/3)/ρ)`.
    pub fn p_wave(&self) -> T {
        self.bulk + T::of(4.0 / 3.0) * self.shear
    }
}

/// Elastic stress increment `C : Δε = 2G Δε' + K tr(Δε) I` for a strain increment Δε
/// (extension positive), without the rotation terms.
#[inline(always)]
pub fn elastic_increment<T: Real>(d_eps: &Sym3<T>, moduli: Moduli<T>) -> Sym3<T> {
    let dev = d_eps.deviator();
    dev * (T::of(2.0) * moduli.shear) + Sym3::iso(moduli.bulk * d_eps.trace())
}

/// The rotation terms `Ω σ − σ Ω` of the Jaumann rate, with the spin `Ω = (L − Lᵀ)/2` given by
/// its upper entries `(Ω_xy, Ω_xz, Ω_yz)` (see [`crate::math::Mat3::skew`]).
#[inline(always)]
pub fn spin_terms<T: Real>(sigma: &Sym3<T>, spin: Vec3<T>) -> Sym3<T> {
    let (a, b, c) = (spin.x, spin.y, spin.z);
    let s = sigma;
    // M = Ω σ; the result Ωσ − σΩ = M + Mᵀ because σ is symmetric and Ω skew.
    let mxx = a * s.xy + b * s.xz;
    let mxy = a * s.yy + b * s.yz;
    let mxz = a * s.yz + b * s.zz;
    let myx = -a * s.xx + c * s.xz;
    let myy = -a * s.xy + c * s.yz;
    let myz = -a * s.xz + c * s.zz;
    let mzx = -b * s.xx - c * s.xy;
    let mzy = -b * s.xy - c * s.yy;
    let mzz = -b * s.xz - c * s.yz;
    let two = T::of(2.0);
    Sym3::new(two * mxx, two * myy, two * mzz, mxy + myx, mxz + mzx, myz + mzy)
}

/// Jaumann stress rate `dσ/dt = 2G D' + K tr(D) I + Ωσ − σΩ` for the rate of deformation `D`
/// (1/s) and spin `Ω` (1/s). Returns Pa/s.
#[inline(always)]
pub fn jaumann_rate<T: Real>(sigma: &Sym3<T>, d: &Sym3<T>, spin: Vec3<T>, moduli: Moduli<T>) -> Sym3<T> {
    elastic_increment(d, moduli) + spin_terms(sigma, spin)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat3;
    use approx::assert_relative_eq;

    #[test]
    fn moduli_from_young_poisson_round_trip() {
        let m = Moduli::from_young_poisson(2.0e7_f64, 0.3);
        // E = 9KG / (3K + G), ν = (3K − 2G) / (2 (3K + G))
        let e = 9.0 * m.bulk * m.shear / (3.0 * m.bulk + m.shear);
        let nu = (3.0 * m.bulk - 2.0 * m.shear) / (2.0 * (3.0 * m.bulk + m.shear));
        assert_relative_eq!(e, 2.0e7, max_relative = 1e-14);
        assert_relative_eq!(nu, 0.3, max_relative = 1e-14);
        let g = Moduli::from_bulk_poisson(m.bulk, 0.3).shear;
        assert_relative_eq!(g, m.shear, max_relative = 1e-14);
    }

    #[test]
    fn spin_terms_match_full_matrix_product() {
        let sigma = Sym3::new(-3.0_f64, -1.5, -2.0, 0.4, -0.7, 0.9);
        let l = Mat3::new([[0.1, 0.7, -0.3], [-0.2, 0.05, 0.4], [0.6, -0.8, -0.15]]);
        let w = l.skew();
        let omega = Mat3::new([[0.0, w.x, w.y], [-w.x, 0.0, w.z], [-w.y, -w.z, 0.0]]);
        let full = {
            let a = omega.matmul(&sigma.to_mat());
            let b = sigma.to_mat().matmul(&omega);
            let mut r = Mat3::zero();
            for i in 0..3 {
                for j in 0..3 {
                    r.m[i][j] = a.m[i][j] - b.m[i][j];
                }
            }
            r
        };
        let got = spin_terms(&sigma, w).to_mat();
        for i in 0..3 {
            for j in 0..3 {
                assert_relative_eq!(got.m[i][j], full.m[i][j], epsilon = 1e-14);
            }
        }
    }

    #[test]
    fn rigid_rotation_rotates_stress_without_changing_invariants() {
        // Spin about z at ω rad/s; integrate the Jaumann rate with small steps and compare with
        // R σ0 Rᵀ. D = 0, so only the spin terms act.
        let omega = 2.0_f64;
        let spin = Vec3::new(-omega, 0.0, 0.0); // L = [[0,-ω,0],[ω,0,0],[0,0,0]] -> Ω_xy = -ω
        let s0 = Sym3::new(-5.0, -1.0, -2.0, 0.0, 0.0, 0.0);
        let t_end = 0.3;
        let n = 20_000;
        let dt = t_end / n as f64;
        let mut s = s0;
        let m = Moduli { bulk: 1.0, shear: 1.0 };
        for _ in 0..n {
            // midpoint for second-order accuracy
            let k1 = jaumann_rate(&s, &Sym3::zero(), spin, m);
            let mid = s + k1 * (0.5 * dt);
            s += jaumann_rate(&mid, &Sym3::zero(), spin, m) * dt;
        }
        let th = omega * t_end;
        let (c, si) = (th.cos(), th.sin());
        let xx = -5.0 * c * c - si * si;
        let yy = -5.0 * si * si - c * c;
        let xy = (-5.0 + 1.0) * c * si;
        assert_relative_eq!(s.xx, xx, epsilon = 1e-8);
        assert_relative_eq!(s.yy, yy, epsilon = 1e-8);
        assert_relative_eq!(s.xy, xy, epsilon = 1e-8);
        assert_relative_eq!(s.von_mises(), s0.von_mises(), epsilon = 1e-8);
        assert_relative_eq!(s.pressure(), s0.pressure(), epsilon = 1e-12);
    }
}
