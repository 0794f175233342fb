//! Parameter conversions used to calibrate the models from common lab quantities.

use crate::Real;

/// Critical-state slope M from a friction angle (degrees), triaxial compression:
/// `M = 6 sinφ / (3 − sinφ)`.
pub fn m_from_friction_angle<T: Real>(phi_deg: T) -> T {
    let s = phi_deg.to_radians().sin();
    T::of(6.0) * s / (T::of(3.0) - s)
}

/// Normal compression slope from the compression index of e–log10 p data: `λ = Cc / ln 10`.
pub fn lambda_from_cc<T: Real>(cc: T) -> T {
    cc / T::LN_10()
}

/// Swelling slope from the recompression index of e–log10 p data: `κ = Cr / ln 10`.
pub fn kappa_from_cr<T: Real>(cr: T) -> T {
    cr / T::LN_10()
}

/// Initial preconsolidation pressure `p_c0 = OCR · p0` (Pa).
pub fn pc0_from_ocr<T: Real>(ocr: T, p0: T) -> T {
    ocr * p0
}

/// Jáky's at-rest coefficient `K0 = 1 − sin φ` (φ in degrees).
pub fn k0_jaky<T: Real>(phi_deg: T) -> T {
    T::one() - phi_deg.to_radians().sin()
}

/// At-rest coefficient of a laterally confined elastic solid, `K0 = ν / (1 − ν)`.
pub fn k0_elastic<T: Real>(poisson: T) -> T {
    poisson / (T::one() - poisson)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn m_matches_the_itasca_form() {
        for phi in [20.0_f64, 30.0, 37.5] {
            let s = phi.to_radians().sin();
            let n = (1.0 + s) / (1.0 - s);
            assert_relative_eq!(m_from_friction_angle(phi), 3.0 * (n - 1.0) / (n + 2.0), max_relative = 1e-14);
        }
        assert_relative_eq!(m_from_friction_angle(30.0_f64), 1.2, max_relative = 1e-14);
    }

    #[test]
    fn log10_indices_convert_to_natural_slopes() {
        assert_relative_eq!(lambda_from_cc(0.23_f64), 0.23 / std::f64::consts::LN_10);
        assert_relative_eq!(kappa_from_cr(0.046_f64), 0.046 / std::f64::consts::LN_10);
        assert_relative_eq!(pc0_from_ocr(2.0_f64, 5.0e4), 1.0e5);
        assert_relative_eq!(k0_jaky(30.0_f64), 0.5, max_relative = 1e-14);
        assert_relative_eq!(k0_elastic(0.25_f64), 1.0 / 3.0, max_relative = 1e-14);
    }
}
