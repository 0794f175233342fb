//! Smoothing kernels with support radius 2h, as zero-sized types chosen at compile time.
//!
//! A kernel gives `W(r)` and the gradient factor `F(r)` with `∇_a W_ab = F(r) (x_a − x_b)`,
//! so a pair loop computes one scalar and multiplies the separation vector.

use crate::Real;

/// A radially symmetric 3D smoothing kernel with compact support 2h.
pub trait Kernel<T: Real>: Copy + Send + Sync + 'static {
    /// Name, for reports.
    const NAME: &'static str;
    /// Normalisation constant for smoothing length `h` (1/m³).
    fn alpha(h: T) -> T;
    /// `W(r)` for the given `alpha = Self::alpha(h)` and `1/h`.
    fn w(r: T, inv_h: T, alpha: T) -> T;
    /// Gradient factor `F(r) = W'(r)/r` (1/m⁵), so that `∇W = F r_vec`. Zero outside support.
    fn grad_factor(r: T, inv_h: T, alpha: T) -> T;
}

/// Wendland C2: `W = α (1 − q/2)⁴ (2q + 1)`, `α = 21 / (16 π h³)`, `q = r/h ∈ [0, 2]`.
#[derive(Clone, Copy, Debug, Default)]
pub struct WendlandC2;

impl<T: Real> Kernel<T> for WendlandC2 {
    const NAME: &'static str = "wendland";
    #[inline(always)]
    fn alpha(h: T) -> T {
        T::of(21.0) / (T::of(16.0) * T::PI() * h * h * h)
    }
    #[inline(always)]
    fn w(r: T, inv_h: T, alpha: T) -> T {
        // Branch-free: t = 0 at and beyond the support (pair loops visit listed pairs outside
        // it, and an unpredictable branch costs more than the arithmetic).
        let q = r * inv_h;
        let t = (T::one() - T::of(0.5) * q).max(T::zero());
        let t2 = t * t;
        alpha * t2 * t2 * (T::of(2.0) * q + T::one())
    }
    #[inline(always)]
    fn grad_factor(r: T, inv_h: T, alpha: T) -> T {
        // dW/dr = −5 α q (1 − q/2)³ / h, divided by r = q h.
        let q = r * inv_h;
        let t = (T::one() - T::of(0.5) * q).max(T::zero());
        -T::of(5.0) * alpha * t * t * t * inv_h * inv_h
    }
}

/// Cubic B-spline (Monaghan): `W = σ (1 − 1.5q² + 0.75q³)` for `q < 1`, `σ (2 − q)³/4` for
/// `1 ≤ q < 2`, `σ = 1/(π h³)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct CubicSpline;

impl<T: Real> Kernel<T> for CubicSpline {
    const NAME: &'static str = "cubic";
    #[inline(always)]
    fn alpha(h: T) -> T {
        T::one() / (T::PI() * h * h * h)
    }
    #[inline(always)]
    fn w(r: T, inv_h: T, alpha: T) -> T {
        let q = r * inv_h;
        if q >= T::of(2.0) {
            T::zero()
        } else if q >= T::one() {
            let t = T::of(2.0) - q;
            alpha * T::of(0.25) * t * t * t
        } else {
            alpha * (T::one() - T::of(1.5) * q * q + T::of(0.75) * q * q * q)
        }
    }
    #[inline(always)]
    fn grad_factor(r: T, inv_h: T, alpha: T) -> T {
        let q = r * inv_h;
        let ih2 = inv_h * inv_h;
        if q >= T::of(2.0) {
            T::zero()
        } else if q >= T::one() {
            let t = T::of(2.0) - q;
            -T::of(0.75) * alpha * t * t * ih2 / q
        } else {
            alpha * (T::of(-3.0) + T::of(2.25) * q) * ih2
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn normalisation<K: Kernel<f64>>() -> f64 {
        // ∫ W 4π r² dr over [0, 2h] by Simpson's rule.
        let h = 0.7;
        let a = K::alpha(h);
        let n = 20_000;
        let dr = 2.0 * h / n as f64;
        let f = |r: f64| 4.0 * std::f64::consts::PI * r * r * K::w(r, 1.0 / h, a);
        let mut s = f(0.0) + f(2.0 * h);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * dr);
        }
        s * dr / 3.0
    }

    #[test]
    fn kernels_integrate_to_one() {
        assert_relative_eq!(normalisation::<WendlandC2>(), 1.0, max_relative = 1e-10);
        assert_relative_eq!(normalisation::<CubicSpline>(), 1.0, max_relative = 1e-10);
    }

    fn gradient_matches_derivative<K: Kernel<f64>>() {
        let h = 0.3;
        let (ih, a) = (1.0 / h, K::alpha(h));
        for i in 1..60 {
            let r = 2.0 * h * i as f64 / 60.0;
            let eps = 1e-7 * h;
            let dw = (K::w(r + eps, ih, a) - K::w(r - eps, ih, a)) / (2.0 * eps);
            assert_relative_eq!(K::grad_factor(r, ih, a) * r, dw, max_relative = 1e-5, epsilon = 1e-9 * a / h);
        }
    }

    #[test]
    fn gradient_is_the_radial_derivative() {
        gradient_matches_derivative::<WendlandC2>();
        gradient_matches_derivative::<CubicSpline>();
    }

    fn compact_and_antisymmetric<K: Kernel<f32>>() {
        let h = 0.012_f32;
        let (ih, a) = (1.0 / h, K::alpha(h));
        assert_eq!(K::w(2.0 * h, ih, a), 0.0);
        assert_eq!(K::w(3.0 * h, ih, a), 0.0);
        assert_eq!(K::grad_factor(2.0 * h, ih, a), 0.0);
        assert!(K::w(1.999 * h, ih, a) >= 0.0 && K::w(0.0, ih, a) > 0.0);
        // ∇_a W_ab = F r_ab and ∇_b W_ba = F r_ba = −∇_a W_ab exactly, since F depends on |r| only.
        let rab = [0.004_f32, -0.003, 0.007];
        let r = (rab[0] * rab[0] + rab[1] * rab[1] + rab[2] * rab[2]).sqrt();
        let f = K::grad_factor(r, ih, a);
        for c in rab {
            assert_eq!(f * c, -(f * -c));
        }
        // Monotone decreasing: the gradient factor is never positive inside the support.
        for i in 0..200 {
            let r = 2.0 * h * i as f32 / 200.0;
            assert!(K::grad_factor(r, ih, a) <= 0.0);
        }
    }

    #[test]
    fn kernels_have_compact_support_and_antisymmetric_gradients() {
        compact_and_antisymmetric::<WendlandC2>();
        compact_and_antisymmetric::<CubicSpline>();
    }

    fn lattice_sums<K: Kernel<f64>>() -> (f64, f64) {
        // On a cubic lattice of spacing d0 with h = 1.2 d0: Σ V W ≈ 1 and Σ V (−r·∇W) ≈ 3.
        let d0 = 0.01;
        let h = 1.2 * d0;
        let (ih, a) = (1.0 / h, K::alpha(h));
        let v = d0 * d0 * d0;
        let (mut s0, mut div) = (0.0, 0.0);
        for i in -4..=4 {
            for j in -4..=4 {
                for k in -4..=4 {
                    let r = d0 * ((i * i + j * j + k * k) as f64).sqrt();
                    s0 += v * K::w(r, ih, a);
                    div += v * (-K::grad_factor(r, ih, a) * r * r);
                }
            }
        }
        (s0, div)
    }

    #[test]
    fn lattice_sums_approximate_unity_and_three() {
        for (s0, div) in [lattice_sums::<WendlandC2>(), lattice_sums::<CubicSpline>()] {
            assert!((s0 - 1.0).abs() < 0.03, "Σ V W = {s0}");
            assert!((div - 3.0).abs() < 0.1, "Σ V (−r·∇W) = {div}");
        }
    }
}
