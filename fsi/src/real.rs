//! The scalar type the solver is generic over.
//!
//! Every numerical routine in `regolith-fsi` is written once for `T: Real` and instantiated for
//! `f64` (the reference precision) and `f32` (what GPUs run, and what halves memory traffic on
//! the CPU). Tests run both.

use std::fmt::{Debug, Display};
use std::iter::Sum;
use std::ops::{AddAssign, DivAssign, MulAssign, SubAssign};

use num_traits::{Float, FloatConst};

/// A floating-point scalar: `f32` or `f64`.
pub trait Real:
    Float
    + FloatConst
    + Default
    + Debug
    + Display
    + Send
    + Sync
    + Sum
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + 'static
{
    /// Converts an `f64` constant (rounding to nearest for `f32`).
    fn of(x: f64) -> Self;
    /// Widens to `f64` (exact for both implementors).
    fn as_f64(self) -> f64;
    /// Name used in reports: `"f32"` or `"f64"`.
    const NAME: &'static str;
    /// The soil pair loop gathers neighbours into blocks for packed SIMD arithmetic
    /// (`cpu::lanes`): pays with four f32 lanes per SSE register, not with two f64 ones
    /// (measured in BENCHMARKS.md), which run the scalar loop.
    const PAIR_BLOCKS: bool;
}

impl Real for f64 {
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn as_f64(self) -> f64 {
        self
    }
    const NAME: &'static str = "f64";
    const PAIR_BLOCKS: bool = false;
}

impl Real for f32 {
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn as_f64(self) -> f64 {
        f64::from(self)
    }
    const NAME: &'static str = "f32";
    const PAIR_BLOCKS: bool = true;
}
