use std::ops::{Add, AddAssign, Mul};

use crate::Real;

use super::{Sym3, Vec3};

/// A general 3×3 matrix, row-major (`m[row][col]`). Used for the velocity gradient
/// `L_ij = ∂v_i/∂x_j` (1/s) and rotations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mat3<T> {
    /// Rows.
    pub m: [[T; 3]; 3],
}

impl<T: Real> Mat3<T> {
    /// Builds a matrix from rows.
    #[inline(always)]
    pub fn new(m: [[T; 3]; 3]) -> Self {
        Self { m }
    }
    /// The zero matrix.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new([[T::zero(); 3]; 3])
    }
    /// The identity.
    #[inline(always)]
    pub fn identity() -> Self {
        let (o, z) = (T::one(), T::zero());
        Self::new([[o, z, z], [z, o, z], [z, z, o]])
    }
    /// Outer product `a ⊗ b` (`a_i b_j`).
    #[inline(always)]
    pub fn outer(a: Vec3<T>, b: Vec3<T>) -> Self {
        Self::new([
            [a.x * b.x, a.x * b.y, a.x * b.z],
            [a.y * b.x, a.y * b.y, a.y * b.z],
            [a.z * b.x, a.z * b.y, a.z * b.z],
        ])
    }
    /// Symmetric part `(A + Aᵀ)/2`.
    #[inline(always)]
    pub fn sym(&self) -> Sym3<T> {
        let h = T::of(0.5);
        let m = &self.m;
        Sym3::new(m[0][0], m[1][1], m[2][2], h * (m[0][1] + m[1][0]), h * (m[0][2] + m[2][0]), h * (m[1][2] + m[2][1]))
    }
    /// Skew part `(A - Aᵀ)/2` returned as its three independent entries `(W_xy, W_xz, W_yz)`.
    #[inline(always)]
    pub fn skew(&self) -> Vec3<T> {
        let h = T::of(0.5);
        let m = &self.m;
        Vec3::new(h * (m[0][1] - m[1][0]), h * (m[0][2] - m[2][0]), h * (m[1][2] - m[2][1]))
    }
    /// Transpose.
    #[inline(always)]
    pub fn transpose(&self) -> Self {
        let m = &self.m;
        Self::new([[m[0][0], m[1][0], m[2][0]], [m[0][1], m[1][1], m[2][1]], [m[0][2], m[1][2], m[2][2]]])
    }
    /// Matrix product.
    #[inline(always)]
    pub fn matmul(&self, o: &Self) -> Self {
        let mut r = Self::zero();
        for i in 0..3 {
            for j in 0..3 {
                r.m[i][j] = self.m[i][0] * o.m[0][j] + self.m[i][1] * o.m[1][j] + self.m[i][2] * o.m[2][j];
            }
        }
        r
    }
    /// Matrix-vector product.
    #[inline(always)]
    pub fn mul_vec(&self, v: Vec3<T>) -> Vec3<T> {
        let m = &self.m;
        Vec3::new(
            m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
        )
    }
    /// Trace.
    #[inline(always)]
    pub fn trace(&self) -> T {
        self.m[0][0] + self.m[1][1] + self.m[2][2]
    }
    /// True when every entry is finite.
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        self.m.iter().all(|r| r.iter().all(|x| x.is_finite()))
    }
}

impl<T: Real> Add for Mat3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let mut r = self;
        r += o;
        r
    }
}
impl<T: Real> AddAssign for Mat3<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        for i in 0..3 {
            for j in 0..3 {
                self.m[i][j] += o.m[i][j];
            }
        }
    }
}
impl<T: Real> Mul<T> for Mat3<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        let mut r = self;
        for row in r.m.iter_mut() {
            for x in row.iter_mut() {
                *x *= s;
            }
        }
        r
    }
}
