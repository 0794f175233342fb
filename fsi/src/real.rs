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
    /// Says which of the two precisions `Self` is, handing `x` back typed with it: the way
    /// to call code compiled once per precision from code generic over `T: Real`.
    ///
    /// A generic function is compiled again in every crate that calls it with a concrete `T`
    /// (release builds do not share instantiations between crates), so a generic solver step
    /// was compiled into the library, its unit tests, the integration tests and the Python
    /// bindings alike. A generic entry point that matches on `by_precision` and calls a plain
    /// `fn(&mut CpuSph<f32>)` or `fn(&mut CpuSph<f64>)` keeps the step's machine code in this
    /// crate, compiled once (`cpu::CpuSph::step`; NOTES.md, session 27).
    fn by_precision<W: PerPrecision>(x: W::Of<Self>) -> ByPrecision<W::Of<f32>, W::Of<f64>>;
    /// The way back: makes a value of the family at precision `Self` with whichever of the
    /// two makers is `Self`'s (a constructor compiled once per precision, say).
    fn from_precision<W: PerPrecision>(
        f32: impl FnOnce() -> W::Of<f32>,
        f64: impl FnOnce() -> W::Of<f64>,
    ) -> W::Of<Self>;
}

/// A family of types built on a precision (`&mut CpuSph<T>`, say), for [`Real::by_precision`].
pub trait PerPrecision {
    /// The family's type at precision `T`.
    type Of<T: Real>;
}

/// A value of a [`PerPrecision`] family at either precision.
pub enum ByPrecision<A, B> {
    /// The `f32` member.
    F32(A),
    /// The `f64` member.
    F64(B),
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
    #[inline(always)]
    fn by_precision<W: PerPrecision>(x: W::Of<f64>) -> ByPrecision<W::Of<f32>, W::Of<f64>> {
        ByPrecision::F64(x)
    }
    #[inline(always)]
    fn from_precision<W: PerPrecision>(_: impl FnOnce() -> W::Of<f32>, f64: impl FnOnce() -> W::Of<f64>) -> W::Of<f64> {
        f64()
    }
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
    #[inline(always)]
    fn by_precision<W: PerPrecision>(x: W::Of<f32>) -> ByPrecision<W::Of<f32>, W::Of<f64>> {
        ByPrecision::F32(x)
    }
    #[inline(always)]
    fn from_precision<W: PerPrecision>(f32: impl FnOnce() -> W::Of<f32>, _: impl FnOnce() -> W::Of<f64>) -> W::Of<f32> {
        f32()
    }
}
