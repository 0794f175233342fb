use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use crate::Real;

use super::{Mat3, Vec3};

/// A symmetric 3×3 tensor stored as its six independent components.
///
/// Used for Cauchy stress (tension positive, Pa), the rate of deformation `D` (1/s) and strain
/// increments (dimensionless, extension positive).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sym3<T> {
    /// xx component.
    pub xx: T,
    /// yy component.
    pub yy: T,
    /// zz component.
    pub zz: T,
    /// xy = yx component.
    pub xy: T,
    /// xz = zx component.
    pub xz: T,
    /// yz = zy component.
    pub yz: T,
}

impl<T: Real> Sym3<T> {
    /// The symmetric product `a ⊗ b + b ⊗ a`.
    #[inline(always)]
    pub fn sym_outer(a: Vec3<T>, b: Vec3<T>) -> Self {
        Self::new(
            a.x * b.x + a.x * b.x,
            a.y * b.y + a.y * b.y,
            a.z * b.z + a.z * b.z,
            a.x * b.y + b.x * a.y,
            a.x * b.z + b.x * a.z,
            a.y * b.z + b.y * a.z,
        )
    }

    /// Builds a tensor from its six components.
    #[inline(always)]
    pub fn new(xx: T, yy: T, zz: T, xy: T, xz: T, yz: T) -> Self {
        Self { xx, yy, zz, xy, xz, yz }
    }
    /// The zero tensor.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new(T::zero(), T::zero(), T::zero(), T::zero(), T::zero(), T::zero())
    }
    /// `a · I`.
    #[inline(always)]
    pub fn iso(a: T) -> Self {
        Self::new(a, a, a, T::zero(), T::zero(), T::zero())
    }
    /// A diagonal tensor.
    #[inline(always)]
    pub fn diag(xx: T, yy: T, zz: T) -> Self {
        Self::new(xx, yy, zz, T::zero(), T::zero(), T::zero())
    }
    /// Converts from `f64` components in the order xx, yy, zz, xy, xz, yz.
    #[inline(always)]
    pub fn of(c: [f64; 6]) -> Self {
        Self::new(T::of(c[0]), T::of(c[1]), T::of(c[2]), T::of(c[3]), T::of(c[4]), T::of(c[5]))
    }
    /// Widens to `f64` components in the order xx, yy, zz, xy, xz, yz.
    #[inline(always)]
    pub fn as_f64(self) -> [f64; 6] {
        [self.xx.as_f64(), self.yy.as_f64(), self.zz.as_f64(), self.xy.as_f64(), self.xz.as_f64(), self.yz.as_f64()]
    }
    /// Trace.
    #[inline(always)]
    pub fn trace(self) -> T {
        self.xx + self.yy + self.zz
    }
    /// Deviatoric part `A - tr(A)/3 I`.
    #[inline(always)]
    pub fn deviator(self) -> Self {
        let m = self.trace() / T::of(3.0);
        Self::new(self.xx - m, self.yy - m, self.zz - m, self.xy, self.xz, self.yz)
    }
    /// Double contraction `A : B`.
    #[inline(always)]
    pub fn ddot(self, o: Self) -> T {
        self.xx * o.xx
            + self.yy * o.yy
            + self.zz * o.zz
            + T::of(2.0) * (self.xy * o.xy + self.xz * o.xz + self.yz * o.yz)
    }
    /// Mean pressure `p = -tr(σ)/3` (compression positive, for a stress tensor).
    #[inline(always)]
    pub fn pressure(self) -> T {
        -self.trace() / T::of(3.0)
    }
    /// Von Mises equivalent deviatoric stress `q = sqrt(3/2 s:s)`, overflow-safe (see
    /// [`Sym3::von_mises_of_deviator`]).
    #[inline(always)]
    pub fn von_mises(self) -> T {
        self.deviator().von_mises_of_deviator()
    }
    /// `sqrt(3/2 s:s)` of a tensor that is already deviatoric, computed on the tensor scaled by
    /// its largest component so that the squares cannot overflow (`f32` stresses near 1e20 Pa
    /// have `s:s` beyond `f32::MAX`).
    #[inline]
    pub fn von_mises_of_deviator(self) -> T {
        let a = self
            .xx
            .abs()
            .max(self.yy.abs())
            .max(self.zz.abs())
            .max(self.xy.abs())
            .max(self.xz.abs())
            .max(self.yz.abs());
        if a == T::zero() || !a.is_finite() {
            return a;
        }
        let n = self * (T::one() / a);
        a * (T::of(1.5) * n.ddot(n)).sqrt()
    }
    /// Smallest eigenvalue (closed form for a symmetric 3×3, trigonometric method).
    #[inline]
    pub fn min_eigenvalue(self) -> T {
        let p1 = self.xy * self.xy + self.xz * self.xz + self.yz * self.yz;
        let three = T::of(3.0);
        let q = self.trace() / three;
        if p1 <= T::epsilon() * (self.xx.abs() + self.yy.abs() + self.zz.abs()).powi(2) {
            return self.xx.min(self.yy).min(self.zz);
        }
        let p2 = (self.xx - q).powi(2) + (self.yy - q).powi(2) + (self.zz - q).powi(2) + T::of(2.0) * p1;
        let p = (p2 / T::of(6.0)).sqrt();
        let b = (self - Sym3::iso(q)) * (T::one() / p);
        let det = b.xx * (b.yy * b.zz - b.yz * b.yz) - b.xy * (b.xy * b.zz - b.yz * b.xz)
            + b.xz * (b.xy * b.yz - b.yy * b.xz);
        let r = (det / T::of(2.0)).max(-T::one()).min(T::one());
        let phi = r.acos() / three;
        // Eigenvalues q + 2p cos(φ + 2πk/3); the smallest is k = 1.
        q + T::of(2.0) * p * (phi + T::of(2.0 * std::f64::consts::PI / 3.0)).cos()
    }
    /// Matrix-vector product.
    #[inline(always)]
    pub fn mul_vec(self, v: Vec3<T>) -> Vec3<T> {
        Vec3::new(
            self.xx * v.x + self.xy * v.y + self.xz * v.z,
            self.xy * v.x + self.yy * v.y + self.yz * v.z,
            self.xz * v.x + self.yz * v.y + self.zz * v.z,
        )
    }
    /// As a full matrix.
    #[inline(always)]
    pub fn to_mat(self) -> Mat3<T> {
        Mat3::new([[self.xx, self.xy, self.xz], [self.xy, self.yy, self.yz], [self.xz, self.yz, self.zz]])
    }
    /// True when every component is finite.
    #[inline(always)]
    pub fn is_finite(self) -> bool {
        self.xx.is_finite()
            && self.yy.is_finite()
            && self.zz.is_finite()
            && self.xy.is_finite()
            && self.xz.is_finite()
            && self.yz.is_finite()
    }
}

impl<T: Real> Add for Sym3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.xx + o.xx, self.yy + o.yy, self.zz + o.zz, self.xy + o.xy, self.xz + o.xz, self.yz + o.yz)
    }
}
impl<T: Real> Sub for Sym3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.xx - o.xx, self.yy - o.yy, self.zz - o.zz, self.xy - o.xy, self.xz - o.xz, self.yz - o.yz)
    }
}
impl<T: Real> Neg for Sym3<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.xx, -self.yy, -self.zz, -self.xy, -self.xz, -self.yz)
    }
}
impl<T: Real> Mul<T> for Sym3<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        Self::new(self.xx * s, self.yy * s, self.zz * s, self.xy * s, self.xz * s, self.yz * s)
    }
}
impl<T: Real> AddAssign for Sym3<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<T: Real> SubAssign for Sym3<T> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_eigenvalue_matches_known_spectra() {
        // diag with a rotation: eigenvalues 0.5, 0.8, 1.3
        let c = std::f64::consts::FRAC_1_SQRT_2;
        // R = rotation about z by 45°, A = R diag(0.5, 0.8, 1.3) Rᵀ
        let a = Sym3::new(0.5 * c * c + 0.8 * c * c, 0.5 * c * c + 0.8 * c * c, 1.3, (0.5 - 0.8) * c * c, 0.0, 0.0);
        assert!((a.min_eigenvalue() - 0.5).abs() < 1e-12);
        assert!((Sym3::diag(2.0_f64, -1.0, 3.0).min_eigenvalue() + 1.0).abs() < 1e-12);
        assert!((Sym3::iso(0.7_f32).min_eigenvalue() - 0.7).abs() < 1e-6);
        let b = Sym3::new(1.0_f64, 2.0, 3.0, 0.4, -0.2, 0.7);
        // Check against the characteristic polynomial: det(B − λ I) = 0.
        let l = b.min_eigenvalue();
        let m = b - Sym3::iso(l);
        let det = m.xx * (m.yy * m.zz - m.yz * m.yz) - m.xy * (m.xy * m.zz - m.yz * m.xz)
            + m.xz * (m.xy * m.yz - m.yy * m.xz);
        assert!(det.abs() < 1e-10, "det = {det}");
        assert!(l < 1.0);
    }
}
