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
