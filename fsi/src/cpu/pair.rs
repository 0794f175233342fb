//! One soil pair's arithmetic, written once: [`pair_terms`] is what neighbour `b` adds to
//! particle `a`'s sums (density rate, acceleration, velocity gradient, free-surface moment,
//! XSPH correction, concentration gradient). The pair-at-a-time loop here
//! ([`neighbour_sums`], used for `f64` and by the wet loop) and the blocks of `lanes.rs`
//! (`f32`) both evaluate it, the first on `Packed` records, the second on one
//! lane of a gathered block, so a change to a pair term is made in one place.
//!
//! Pair terms are written so that the (a, b) and (b, a) evaluations are exact negatives of
//! each other (same operands in the same order), which is what makes the soil's internal
//! forces cancel to round-off and the marker forces equal and opposite to what the soil feels.

use crate::Real;
use crate::kernel::Kernel;
use crate::math::{Mat3, Sym3, Vec3};

/// What a neighbour contributes, packed into one record per particle so that a pair loop reads
/// one contiguous 64-byte (f32) record per neighbour.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Packed<T> {
    pub x: Vec3<T>,
    pub v: Vec3<T>,
    /// σ / ρ² (Pa m⁶/kg²).
    pub s: Sym3<T>,
    /// m / ρ (m³).
    pub vol: T,
    pub mass: T,
    pub rho: T,
    /// Elastic wave speed (m/s).
    pub cs: T,
}

/// Constants of the pair loops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairConsts<T> {
    pub h: T,
    pub inv_h: T,
    pub alpha: T,
    pub support2: T,
    pub visc_alpha: T,
    pub eta2: T,
    pub gravity: Vec3<T>,
}

#[cfg(test)]
impl<T: Real> PairConsts<T> {
    /// The constants the pair-loop tests use: support 2h, α = 0.5, η² = 0.01 h², no gravity.
    pub(crate) fn for_test<K: Kernel<T>>(h: T) -> Self {
        Self {
            h,
            inv_h: T::one() / h,
            alpha: K::alpha(h),
            support2: T::of(4.0) * h * h,
            visc_alpha: T::of(0.5),
            eta2: T::of(0.01) * h * h,
            gravity: Vec3::zero(),
        }
    }
}

/// Neighbour `b` of particle `a` as the pair arithmetic reads it: the separation `x_a − x_b`,
/// the relative velocity `v_a − v_b`, and `b`'s σ/ρ², volume, mass, density and wave speed.
#[derive(Clone, Copy)]
pub(crate) struct Neighbour<T> {
    pub r: Vec3<T>,
    pub v: Vec3<T>,
    pub s: Sym3<T>,
    pub vol: T,
    pub mass: T,
    pub rho: T,
    pub cs: T,
}

impl<T: Real> Neighbour<T> {
    /// Record `pb` seen from `pa`.
    #[inline(always)]
    pub(crate) fn of(pa: &Packed<T>, pb: &Packed<T>) -> Self {
        Self { r: pa.x - pb.x, v: pa.v - pb.v, s: pb.s, vol: pb.vol, mass: pb.mass, rho: pb.rho, cs: pb.cs }
    }
}

/// The momentum pair term `(S_a + S_b) ∇W − Π ∇W` with `S = σ/ρ²` and Monaghan's artificial
/// viscosity on approaching pairs, per unit mass of `b`: `gw` is ∇W at `r = x_a − x_b`, `vab`
/// is `v_a − v_b`. Exactly antisymmetric under swapping a and b.
#[inline(always)]
pub(crate) fn momentum<T: Real, const VISC: bool>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    (s_b, rho_b, cs_b): (Sym3<T>, T, T),
    r: Vec3<T>,
    r2: T,
    gw: Vec3<T>,
    vab: Vec3<T>,
) -> Vec3<T> {
    let mut ga = (pa.s + s_b).mul_vec(gw);
    if VISC {
        // Π = −α c̄ μ / ρ̄ with μ = h v·r / (r² + η²) on approaching pairs (v·r < 0), 0 else;
        // c̄ and ρ̄ are pair means, so Π = −α (c_a + c_b) h min(v·r, 0) / ((r² + η²)(ρ_a + ρ_b)):
        // one division, and no branch (half the pairs approach, at random).
        let vr = vab.dot(r).min(T::zero());
        let pi = -c.visc_alpha * (pa.cs + cs_b) * (c.h * vr) / ((r2 + c.eta2) * (pa.rho + rho_b));
        ga -= gw * pi;
    }
    ga
}

/// What one pair adds to `a`'s [`PairSums`]. Terms a stage does not ask for (by the const
/// parameters of [`pair_terms`]) are zero.
#[derive(Clone, Copy)]
pub(crate) struct PairTerms<T> {
    /// `b` lies inside the support (outside it every term is an exact zero).
    pub inside: bool,
    pub drho: T,
    pub acc: Vec3<T>,
    /// `V_b (v_b − v_a) ⊗ ∇W`.
    pub l: Mat3<T>,
    /// `V_b (x_b − x_a) ⊗ ∇W`.
    pub fs: Sym3<T>,
    pub xs: Vec3<T>,
    pub gc: Vec3<T>,
}

/// The single definition of what neighbour `b` (a soil particle with `SOIL`, else a marker)
/// adds to particle `a`'s sums. Branch-free: a neighbour outside the support gives exact zeros
/// (the kernel and its gradient vanish there), so the lane blocks evaluate it unconditionally
/// and the pair loop skips such a neighbour first. `XSPH`, `PPST` and `FS` select the optional
/// terms at compile time.
#[inline(always)]
pub(crate) fn pair_terms<
    T: Real,
    K: Kernel<T>,
    const VISC: bool,
    const XSPH: bool,
    const PPST: bool,
    const FS: bool,
    const SOIL: bool,
>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    b: &Neighbour<T>,
) -> PairTerms<T> {
    let (r, v) = (b.r, b.v);
    let r2 = r.norm2();
    let rr = r2.sqrt();
    let f = K::grad_factor(rr, c.inv_h, c.alpha);
    let gw = r * f;
    let drho = b.vol * v.dot(gw);
    let acc = momentum::<T, VISC>(c, pa, (b.s, b.rho, b.cs), r, r2, gw, v) * b.mass;
    // L_ij = Σ V_b (v_b − v_a)_i ∂_j W
    let mv = v * (-b.vol);
    let l = Mat3::new([
        [mv.x * gw.x, mv.x * gw.y, mv.x * gw.z],
        [mv.y * gw.x, mv.y * gw.y, mv.y * gw.z],
        [mv.z * gw.x, mv.z * gw.y, mv.z * gw.z],
    ]);
    let fs = if FS {
        // (x_b − x_a) ⊗ ∇W = −F r ⊗ r: symmetric for a radial kernel.
        let k = -b.vol * f;
        Sym3::new(k * r.x * r.x, k * r.y * r.y, k * r.z * r.z, k * r.x * r.y, k * r.x * r.z, k * r.y * r.z)
    } else {
        Sym3::zero()
    };
    let xs = if XSPH && SOIL {
        let w = K::w(rr, c.inv_h, c.alpha);
        v * -(T::of(2.0) * b.mass / (pa.rho + b.rho) * w)
    } else {
        Vec3::zero()
    };
    let gc = if PPST { gw * b.vol } else { Vec3::zero() };
    PairTerms { inside: r2 < c.support2, drho, acc, l, fs, xs, gc }
}

/// What one soil particle's neighbours add up to (the rate pass, `rates.rs`, turns them into
/// rates).
#[derive(Clone, Copy, Default)]
pub(crate) struct PairSums<T> {
    pub drho: T,
    pub acc: Vec3<T>,
    /// Velocity gradient L.
    pub l: Mat3<T>,
    pub xs: Vec3<T>,
    pub gc: Vec3<T>,
    pub fs: Sym3<T>,
    pub contact: bool,
}

impl<T: Real> PairSums<T> {
    /// Adds neighbour `pb` (a soil particle with `SOIL`, else a marker) of `pa`; nothing when
    /// it is outside the support.
    #[inline(always)]
    pub(crate) fn add<
        K: Kernel<T>,
        const VISC: bool,
        const XSPH: bool,
        const PPST: bool,
        const FS: bool,
        const SOIL: bool,
    >(
        &mut self,
        c: &PairConsts<T>,
        pa: &Packed<T>,
        pb: &Packed<T>,
    ) {
        let b = Neighbour::of(pa, pb);
        if b.r.norm2() >= c.support2 {
            return;
        }
        let t = pair_terms::<T, K, VISC, XSPH, PPST, FS, SOIL>(c, pa, &b);
        self.drho += t.drho;
        self.acc += t.acc;
        self.l += t.l;
        if FS {
            self.contact |= !SOIL;
            self.fs += t.fs;
        }
        if XSPH && SOIL {
            self.xs += t.xs;
        }
        if PPST {
            self.gc += t.gc;
        }
    }
}

/// Sums over one soil particle's neighbours (`ss`: soil, `sm`: markers), one pair at a time
/// (for `f64`; `f32` takes the blocks of `lanes.rs`). Sums in locals, each neighbour
/// kind in its own inlined loop: the compiler keeps the accumulators in registers instead of
/// calling a closure per pair.
#[inline(always)]
pub(crate) fn neighbour_sums<
    T: Real,
    K: Kernel<T>,
    const VISC: bool,
    const XSPH: bool,
    const PPST: bool,
    const FS: bool,
>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    ss: &[u32],
    sm: &[u32],
    soil: &[Packed<T>],
    markers: &[Packed<T>],
) -> PairSums<T> {
    let mut sums = PairSums::default();
    for &b in ss {
        sums.add::<K, VISC, XSPH, PPST, FS, true>(c, pa, &soil[b as usize]);
    }
    for &w in sm {
        sums.add::<K, VISC, XSPH, PPST, FS, false>(c, pa, &markers[w as usize]);
    }
    sums
}
