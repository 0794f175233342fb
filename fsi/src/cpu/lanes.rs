//! The fused pair sums of one soil particle, [`LANES`] neighbours at a time: the `f32` path
//! of the rate pass (`rates.rs`).
//!
//! The scalar loop ([`PairSums::add`]) keeps about thirty accumulators live, more than the
//! sixteen vector registers of x86-64 hold, and runs one latency-bound chain per pair. Here
//! a block of up to [`LANES`] neighbours is first gathered into structure-of-arrays form
//! (the separation, the relative velocity and the neighbour's fields, one array each), then
//! one branch-free loop over the lanes evaluates [`super::pair::pair_terms`] (the same
//! definition the scalar loop calls) for every lane, which the compiler turns
//! into packed SIMD (four f32 or two f64 lanes per SSE instruction on the generic x86-64
//! target), with lane-wise accumulators summed once at the end.
//!
//! Used for `f32` only ([`crate::Real::PAIR_BLOCKS`]): with two f64 lanes per register the
//! gather costs what the packed arithmetic saves.
//!
//! Same terms as the scalar loop, so the same answers up to the order of the sums: listed
//! pairs outside the support are not skipped but add exact zeros (the kernel and its
//! gradient are zero there), and a short last block is padded with a neighbour placed two
//! supports away.

use crate::Real;
use crate::kernel::Kernel;
use crate::math::{Mat3, Sym3, Vec3};

use super::pair::{Neighbour, Packed, PairConsts, PairSums, pair_terms};

/// Neighbours per block.
pub(crate) const LANES: usize = 16;

/// One block of neighbours in structure-of-arrays form: separation `x_a − x_b`, relative
/// velocity `v_a − v_b`, and the neighbour's σ/ρ², volume, mass, density and wave speed.
struct Block<T> {
    r: [[T; LANES]; 3],
    v: [[T; LANES]; 3],
    s: [[T; LANES]; 6],
    vol: [T; LANES],
    mass: [T; LANES],
    rho: [T; LANES],
    cs: [T; LANES],
}

impl<T: Real> Block<T> {
    /// A block of padding lanes (see [`Block::pad`]).
    fn padding(c: &PairConsts<T>, pa: &Packed<T>) -> Self {
        let z = [T::zero(); LANES];
        let mut b = Block { r: [z; 3], v: [z; 3], s: [z; 6], vol: z, mass: z, rho: z, cs: z };
        for l in 0..LANES {
            b.pad(l, c, pa);
        }
        b
    }

    /// Makes lane `l` a massless, motionless, stress-free neighbour at distance 4h from `pa`,
    /// outside the support: every term it adds is an exact zero.
    #[inline(always)]
    fn pad(&mut self, l: usize, c: &PairConsts<T>, pa: &Packed<T>) {
        self.r[0][l] = T::of(4.0) * c.h;
        self.r[1][l] = T::zero();
        self.r[2][l] = T::zero();
        for v in &mut self.v {
            v[l] = T::zero();
        }
        for s in &mut self.s {
            s[l] = T::zero();
        }
        self.vol[l] = T::zero();
        self.mass[l] = T::zero();
        self.rho[l] = pa.rho;
        self.cs[l] = T::zero();
    }

    /// Gathers `ids` (at most [`LANES`]) from `recs` relative to `pa`; lanes past the end
    /// are set to padding (as [`Block::padding`]).
    #[inline(always)]
    fn gather(&mut self, c: &PairConsts<T>, pa: &Packed<T>, ids: &[u32], recs: &[Packed<T>]) {
        for (l, &id) in ids.iter().enumerate() {
            let pb = &recs[id as usize];
            let r = pa.x - pb.x;
            let v = pa.v - pb.v;
            self.r[0][l] = r.x;
            self.r[1][l] = r.y;
            self.r[2][l] = r.z;
            self.v[0][l] = v.x;
            self.v[1][l] = v.y;
            self.v[2][l] = v.z;
            self.s[0][l] = pb.s.xx;
            self.s[1][l] = pb.s.yy;
            self.s[2][l] = pb.s.zz;
            self.s[3][l] = pb.s.xy;
            self.s[4][l] = pb.s.xz;
            self.s[5][l] = pb.s.yz;
            self.vol[l] = pb.vol;
            self.mass[l] = pb.mass;
            self.rho[l] = pb.rho;
            self.cs[l] = pb.cs;
        }
        for l in ids.len()..LANES {
            self.pad(l, c, pa);
        }
    }
}

/// Lane-wise accumulators of [`PairSums`].
struct Acc<T> {
    drho: [T; LANES],
    acc: [[T; LANES]; 3],
    /// Velocity gradient, row-major.
    l: [[T; LANES]; 9],
    xs: [[T; LANES]; 3],
    gc: [[T; LANES]; 3],
    /// xx, yy, zz, xy, xz, yz.
    fs: [[T; LANES]; 6],
    /// Per lane: some listed marker was inside the support.
    near: [bool; LANES],
}

impl<T: Real> Acc<T> {
    fn new() -> Self {
        let z = [T::zero(); LANES];
        Acc { drho: z, acc: [z; 3], l: [z; 9], xs: [z; 3], gc: [z; 3], fs: [z; 6], near: [false; LANES] }
    }

    /// Adds one block's pairs. `SOIL`: the neighbours are soil particles (else markers).
    ///
    /// Not inlined on purpose: inlined into the caller's loops, the lane loop is left scalar
    /// (the compiler does not vectorize it there; measured: 30 % slower than the scalar pair
    /// loop), while compiled on its own it becomes packed SIMD.
    #[inline(never)]
    fn add<K: Kernel<T>, const VISC: bool, const XSPH: bool, const PPST: bool, const FS: bool, const SOIL: bool>(
        &mut self,
        c: &PairConsts<T>,
        pa: &Packed<T>,
        b: &Block<T>,
    ) {
        for l in 0..LANES {
            let nb = Neighbour {
                r: Vec3::new(b.r[0][l], b.r[1][l], b.r[2][l]),
                v: Vec3::new(b.v[0][l], b.v[1][l], b.v[2][l]),
                s: Sym3::new(b.s[0][l], b.s[1][l], b.s[2][l], b.s[3][l], b.s[4][l], b.s[5][l]),
                vol: b.vol[l],
                mass: b.mass[l],
                rho: b.rho[l],
                cs: b.cs[l],
            };
            let t = pair_terms::<T, K, VISC, XSPH, PPST, FS, SOIL>(c, pa, &nb);
            self.drho[l] += t.drho;
            self.acc[0][l] += t.acc.x;
            self.acc[1][l] += t.acc.y;
            self.acc[2][l] += t.acc.z;
            for (i, row) in t.l.m.iter().enumerate() {
                for (j, x) in row.iter().enumerate() {
                    self.l[3 * i + j][l] += *x;
                }
            }
            if FS {
                if !SOIL {
                    self.near[l] |= t.inside;
                }
                let f = t.fs;
                for (k, x) in [f.xx, f.yy, f.zz, f.xy, f.xz, f.yz].into_iter().enumerate() {
                    self.fs[k][l] += x;
                }
            }
            if XSPH && SOIL {
                self.xs[0][l] += t.xs.x;
                self.xs[1][l] += t.xs.y;
                self.xs[2][l] += t.xs.z;
            }
            if PPST {
                self.gc[0][l] += t.gc.x;
                self.gc[1][l] += t.gc.y;
                self.gc[2][l] += t.gc.z;
            }
        }
    }

    /// The lanes' sums; `contact` is set where some marker lay inside the support.
    fn reduce(&self) -> PairSums<T> {
        let mut sums = PairSums::default();
        let sum = |a: &[T; LANES]| a.iter().fold(T::zero(), |s, &x| s + x);
        sums.drho += sum(&self.drho);
        sums.acc += Vec3::new(sum(&self.acc[0]), sum(&self.acc[1]), sum(&self.acc[2]));
        let l = |i: usize| sum(&self.l[i]);
        sums.l += Mat3::new([[l(0), l(1), l(2)], [l(3), l(4), l(5)], [l(6), l(7), l(8)]]);
        sums.xs += Vec3::new(sum(&self.xs[0]), sum(&self.xs[1]), sum(&self.xs[2]));
        sums.gc += Vec3::new(sum(&self.gc[0]), sum(&self.gc[1]), sum(&self.gc[2]));
        let f = |i: usize| sum(&self.fs[i]);
        sums.fs += Sym3::new(f(0), f(1), f(2), f(3), f(4), f(5));
        sums.contact = self.near.iter().any(|&n| n);
        sums
    }
}

/// The sums over one soil particle's neighbours (`ss`: soil, `sm`: markers), as
/// [`PairSums::add`] over each, [`LANES`] at a time.
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
    let mut acc = Acc::new();
    let mut b = Block::padding(c, pa);
    for ids in ss.chunks(LANES) {
        b.gather(c, pa, ids, soil);
        acc.add::<K, VISC, XSPH, PPST, FS, true>(c, pa, &b);
    }
    for ids in sm.chunks(LANES) {
        b.gather(c, pa, ids, markers);
        acc.add::<K, VISC, XSPH, PPST, FS, false>(c, pa, &b);
    }
    acc.reduce()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::{CubicSpline, WendlandC2};

    /// A deterministic pseudo-random number in [-1, 1).
    fn rnd(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    /// Records scattered within 2.4h of the origin (some outside the support 2h).
    fn records(n: usize, h: f32, state: &mut u64) -> Vec<Packed<f32>> {
        (0..n)
            .map(|_| {
                let mut v3 = |scale: f32| Vec3::new(rnd(state) * scale, rnd(state) * scale, rnd(state) * scale);
                let x = v3(1.4 * h);
                let v = v3(0.3);
                let s = Sym3::new(rnd(state), rnd(state), rnd(state), rnd(state), rnd(state), rnd(state)) * 1e-2;
                let rho = 1700.0 + 100.0 * rnd(state);
                let vol = 1e-6 * (1.0 + 0.1 * rnd(state));
                Packed { x, v, s, vol, mass: vol * rho, rho, cs: 50.0 + 10.0 * rnd(state) }
            })
            .collect()
    }

    fn close(a: f32, b: f32, scale: f32) -> bool {
        (a - b).abs() <= 1e-5 * scale
    }

    /// Blocks of neighbours (padded tails, listed pairs outside the support, with and without
    /// markers) sum what the pair-at-a-time loop sums, to f32 round-off; `contact` exactly.
    fn blocks_match_scalar<K: Kernel<f32>>() {
        let h = 0.012_f32;
        let c = PairConsts::for_test::<K>(h);
        let mut state = 7_u64;
        let mut contact_seen = [false; 2];
        for (n_soil, n_markers) in [(0, 0), (1, 0), (15, 3), (16, 16), (17, 1), (77, 20), (40, 0)] {
            let soil = records(n_soil.max(1), h, &mut state);
            let markers = records(n_markers.max(1), h, &mut state);
            let pa = records(1, h, &mut state)[0];
            let pa = Packed { x: Vec3::zero(), ..pa };
            let ss: Vec<u32> = (0..n_soil as u32).collect();
            // A lone marker is placed outside the support: listed, but no contact.
            let markers =
                if n_markers == 1 { vec![Packed { x: Vec3::new(2.2 * h, 0.0, 0.0), ..markers[0] }] } else { markers };
            let sm: Vec<u32> = (0..n_markers as u32).collect();
            let a = neighbour_sums::<f32, K, true, true, true, true>(&c, &pa, &ss, &sm, &soil, &markers);
            let b = super::super::pair::neighbour_sums::<f32, K, true, true, true, true>(
                &c, &pa, &ss, &sm, &soil, &markers,
            );
            assert_eq!(a.contact, b.contact, "{n_soil} soil, {n_markers} markers");
            contact_seen[usize::from(a.contact)] = true;
            // Scales: the sum of the magnitudes of the terms (one pair's worth at least).
            let scalar_scale = |x: f32| x.abs().max(1e-30);
            let acc_scale = a.acc.norm().max(b.acc.norm()) + 1.0;
            let checks = [
                (a.drho, b.drho, scalar_scale(b.drho) + 1.0),
                (a.acc.x, b.acc.x, acc_scale),
                (a.acc.y, b.acc.y, acc_scale),
                (a.acc.z, b.acc.z, acc_scale),
                (a.xs.x, b.xs.x, 1.0),
                (a.gc.z, b.gc.z, scalar_scale(b.gc.z) + 1.0),
                (a.fs.xx, b.fs.xx, 1.0),
                (a.fs.yz, b.fs.yz, 1.0),
                (a.l.m[0][1], b.l.m[0][1], 1.0),
                (a.l.m[2][2], b.l.m[2][2], 1.0),
            ];
            for (i, (x, y, scale)) in checks.into_iter().enumerate() {
                assert!(close(x, y, scale), "{n_soil} soil, {n_markers} markers, check {i}: {x} vs {y}");
            }
            if n_soil + n_markers > 0 {
                assert!(b.fs.xx != 0.0 && a.acc.norm() > 0.0, "the case tests nothing");
            }
        }
        assert_eq!(contact_seen, [true, true]);
    }

    #[test]
    fn blocks_of_neighbours_sum_what_pairs_sum() {
        blocks_match_scalar::<WendlandC2>();
        blocks_match_scalar::<CubicSpline>();
    }
}
