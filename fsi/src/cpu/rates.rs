//! The rate evaluation of one stage: boundary-marker extrapolation, then one fused pass over
//! each soil particle's neighbours giving the density rate, acceleration, velocity gradient,
//! XSPH correction, shifting gradient and free-surface measure; then the Jaumann stress rate.
//! The pair arithmetic itself is [`super::pair`]'s.

use rayon::prelude::*;

use crate::Real;
use crate::kernel::Kernel;
use crate::math::{Sym3, Vec3};
use crate::rheology::{Material, Moduli, PointState, jaumann_rate};

use super::neighbors::NeighborList;
use super::pair::{Packed, PairConsts, momentum, neighbour_sums};

/// Per-particle rates of one stage.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Rate<T> {
    pub drho: T,
    pub acc: Vec3<T>,
    pub dsigma: Sym3<T>,
    /// Rate of deformation D (1/s).
    pub d: Sym3<T>,
    /// XSPH velocity correction (m/s), not yet scaled by ε.
    pub xsph: Vec3<T>,
    /// Σ V_b ∇W_ab, the concentration gradient (1/m).
    pub grad_c: Vec3<T>,
    /// Free-surface indicator: the smallest eigenvalue of `Σ V_b (x_b − x_a) ⊗ ∇W_ab`
    /// (Marrone et al. 2010), 1 inside the soil, about 0.5 in a flat top layer, lower at edges
    /// and for isolated particles.
    pub fs: T,
    /// Some wall or body marker lies within the support (set with `fs`).
    pub contact: bool,
    /// Moduli the stress rate used.
    pub moduli: Moduli<T>,
}

/// The soil state a stage reads.
pub(crate) struct SoilView<'a, T> {
    pub pos: &'a [Vec3<T>],
    pub vel: &'a [Vec3<T>],
    pub rho: &'a [T],
    pub sigma: &'a [Sym3<T>],
    pub state: &'a [PointState<T>],
    pub material: &'a [u16],
    pub mass: &'a [T],
}

/// Builds the soil records and per-particle moduli.
pub(crate) fn pack_soil<T: Real>(
    materials: &[Material<T>],
    s: &SoilView<'_, T>,
    packed: &mut [Packed<T>],
    moduli: &mut [Moduli<T>],
) {
    packed.par_iter_mut().zip(moduli.par_iter_mut()).enumerate().for_each(|(i, (p, m))| {
        let mat = &materials[s.material[i] as usize];
        *m = mat.moduli(&s.sigma[i], &s.state[i]);
        let r = s.rho[i];
        *p = Packed {
            x: s.pos[i],
            v: s.vel[i],
            s: s.sigma[i] * (T::one() / (r * r)),
            vol: s.mass[i] / r,
            mass: s.mass[i],
            rho: r,
            cs: (m.p_wave() / mat.density).sqrt(),
        };
    });
}

/// How the soil slides along the markers of each owner (see [`crate::config::WallContact`]):
/// the Coulomb coefficient μ of each owner (0 = fixed walls, k + 1 = body k), `INFINITY` for
/// rough (no slip), the owner and the wall's unit normal (into the soil; zero where there is
/// none, which makes the marker rough) of each marker, original order, reached from a sorted
/// marker through `orig`.
#[derive(Clone, Copy)]
pub(crate) struct ContactView<'a, T> {
    /// Original index of each sorted marker.
    pub orig: &'a [u32],
    /// Owner of each marker, original order.
    pub owner: &'a [u32],
    /// Wall normal of each marker, original order.
    pub normal: &'a [Vec3<T>],
    /// μ per owner.
    pub mu: &'a [T],
}

impl<T: Real> ContactView<'_, T> {
    /// μ and the normal of sorted marker `m`; μ is `INFINITY` (rough) where the normal is zero.
    #[inline(always)]
    fn of(&self, m: usize) -> (T, Vec3<T>) {
        let o = self.orig[m] as usize;
        let n = self.normal[o];
        if n.norm2() > T::zero() { (self.mu[self.owner[o] as usize], n) } else { (T::infinity(), n) }
    }
}

/// Applies a wall contact of coefficient `mu` (finite) to an extrapolated marker, with `n` the
/// wall's unit normal into the soil, `vb` the wall's velocity, `vbar` the soil's (kernel
/// average) and `sigma` the extrapolated stress. Kinematics: free slip (the normal relative
/// velocity is mirrored, so the wall stays impermeable; the tangential one is carried through,
/// so the wall adds no shear rate). Traction `σ n`: its normal part is kept and its tangential
/// part replaced by the friction traction `ŝ min(μ max(−t·n, 0), Z |u|)`, with `u` the soil's
/// tangential velocity relative to the wall, `ŝ` its direction and `Z = ρ c` the soil's
/// impedance: regularised Coulomb friction that slides at `μ` times the normal pressure and
/// sticks to within a creep of `τ / (ρ c)` below it (`Z` is also the largest coefficient an
/// explicit step at the CFL limit keeps stable). Smooth is `μ = 0`. Returns `(v, σ)`.
#[inline(always)]
fn apply_contact<T: Real>(
    mu: T,
    n: Vec3<T>,
    impedance: T,
    vb: Vec3<T>,
    vbar: Vec3<T>,
    sigma: Sym3<T>,
) -> (Vec3<T>, Sym3<T>) {
    let t = sigma.mul_vec(n);
    let tn = t.dot(n);
    let tt = t - n * tn;
    let rel = vb - vbar;
    let rel_n = n * rel.dot(n);
    let v = vbar + rel_n * T::of(2.0);
    let slip = rel_n - rel;
    let s = slip.norm();
    let friction = if s > T::zero() && mu > T::zero() {
        slip * ((mu * (-tn).max(T::zero())).min(impedance * s) / s)
    } else {
        Vec3::zero()
    };
    (v, sigma - Sym3::sym_outer(tt, n) + Sym3::sym_outer(friction, n))
}

/// Boundary-marker extrapolation (Adami et al. 2012) for the markers `touched[k]` that have
/// soil within reach (row `k` of `nl_ms`, result in `out[k]`). Each takes
/// `v_w = 2 v_body − Σ v W / Σ W` (no slip), `σ_w = Σ σ W / Σ W − Δp I` with
/// `Δp = (g − a_body) · Σ ρ (x_w − x_b) W / Σ W` (the hydrostatic step from the soil to the
/// marker), and `ρ_w = Σ ρ W / Σ W`. A marker with no soil around it keeps the body's velocity
/// and zero stress. Markers of an owner with a smooth or frictional contact then go through
/// [`apply_contact`]; rough ones (and every marker without `contact`) are left as above.
///
/// `select(a)` gives the stress of neighbour `a` and the density its hydrostatic step uses,
/// or `None` to leave it out (a wet scene extrapolates each phase from its own particles).
#[allow(clippy::too_many_arguments)]
pub(crate) fn extrapolate_markers<T: Real, K: Kernel<T>, S: Fn(usize) -> Option<(Sym3<T>, T)> + Sync>(
    c: &PairConsts<T>,
    marker_pos: &[Vec3<T>],
    marker_vel: &[Vec3<T>],
    marker_acc: &[Vec3<T>],
    marker_volume: T,
    reference_rho: T,
    reference_cs: T,
    touched: &[u32],
    nl_ms: &NeighborList,
    soil: &[Packed<T>],
    select: S,
    contact: Option<ContactView<'_, T>>,
    out: &mut [Packed<T>],
) {
    out.par_iter_mut().enumerate().for_each(|(k, o)| {
        let m = touched[k] as usize;
        let xw = marker_pos[m];
        let (mu, normal) = contact.map_or((T::infinity(), Vec3::zero()), |c| c.of(m));
        let (mut sw, mut sv, mut ss, mut srr, mut srho, mut scs) =
            (T::zero(), Vec3::zero(), Sym3::zero(), Vec3::zero(), T::zero(), T::zero());
        for &a in nl_ms.of(k) {
            let pa = &soil[a as usize];
            let r = xw - pa.x;
            let r2 = r.norm2();
            if r2 >= c.support2 {
                continue;
            }
            let Some((sigma_a, rho_step)) = select(a as usize) else { continue };
            let w = K::w(r2.sqrt(), c.inv_h, c.alpha);
            sw += w;
            sv += pa.v * w;
            ss += sigma_a * w;
            srr += r * (rho_step * w);
            srho += pa.rho * w;
            scs += pa.cs * w;
        }
        let tiny = T::min_positive_value().sqrt();
        *o = if sw > tiny {
            let inv = T::one() / sw;
            let rho = srho * inv;
            let dp = (c.gravity - marker_acc[m]).dot(srr) * inv;
            let sigma = ss * inv - Sym3::iso(dp);
            let (v, sigma) = if mu.is_finite() {
                apply_contact(mu, normal, rho * scs * inv, marker_vel[m], sv * inv, sigma)
            } else {
                (marker_vel[m] * T::of(2.0) - sv * inv, sigma)
            };
            Packed {
                x: xw,
                v,
                s: sigma * (T::one() / (rho * rho)),
                vol: marker_volume,
                mass: rho * marker_volume,
                rho,
                cs: scs * inv,
            }
        } else {
            Packed {
                x: xw,
                v: marker_vel[m],
                s: Sym3::zero(),
                vol: marker_volume,
                mass: reference_rho * marker_volume,
                rho: reference_rho,
                cs: reference_cs,
            }
        };
    });
}

/// Soil rates for all particles. `XSPH` and `PPST` select the optional sums at compile time;
/// `FS` adds the free-surface moment matrix (needed at the first stage of a step only).
#[allow(clippy::too_many_arguments)]
pub(crate) fn soil_rates<
    T: Real,
    K: Kernel<T>,
    const VISC: bool,
    const XSPH: bool,
    const PPST: bool,
    const FS: bool,
>(
    c: &PairConsts<T>,
    soil: &[Packed<T>],
    markers: &[Packed<T>],
    nl_ss: &NeighborList,
    nl_sm: &NeighborList,
    sigma: &[Sym3<T>],
    moduli: &[Moduli<T>],
    out: &mut [Rate<T>],
) {
    out.par_iter_mut().enumerate().for_each(|(a, out)| {
        let pa = &soil[a];
        out.moduli = moduli[a];
        let (ss, sm) = (nl_ss.of(a), nl_sm.of(a));
        let sums = if T::PAIR_BLOCKS {
            super::lanes::neighbour_sums::<T, K, VISC, XSPH, PPST, FS>(c, pa, ss, sm, soil, markers)
        } else {
            neighbour_sums::<T, K, VISC, XSPH, PPST, FS>(c, pa, ss, sm, soil, markers)
        };
        let d = sums.l.sym();
        let spin = sums.l.skew();
        out.drho = sums.drho * pa.rho;
        out.acc = sums.acc + c.gravity;
        out.d = d;
        out.dsigma = jaumann_rate(&sigma[a], &d, spin, out.moduli);
        out.xsph = sums.xs;
        out.grad_c = sums.gc;
        if FS {
            out.fs = sums.fs.min_eigenvalue();
            out.contact = sums.contact;
        }
    });
}

/// Force (N) on each touched marker (row `k` of `nl_ms`, record `markers[k]`) from the soil:
/// minus the same pair terms the soil particles receive. Only the particles of `soil` (the
/// awake ones) count: frozen soil listed in `nl_ms` neither pushes nor is pushed.
///
/// With `moments` as long as `out` (else empty: not recorded), row `k` also gets the diagonal
/// of the pairs' moment `Σ_a (x_a − x_k) ∘ f_ak` (N m), `f_ak` the force of particle `a` on
/// the marker: with it the moment of the walls' forces about the soil particles they act on,
/// `Σ_a x_a ∘ F_a = −Σ_k (x_k ∘ f_k + moment_k)`, needs only per-marker sums.
pub(crate) fn marker_forces<T: Real, K: Kernel<T>, const VISC: bool>(
    c: &PairConsts<T>,
    soil: &[Packed<T>],
    markers: &[Packed<T>],
    nl_ms: &NeighborList,
    out: &mut [Vec3<T>],
    moments: &mut [Vec3<T>],
) {
    if moments.len() != out.len() {
        out.par_iter_mut().enumerate().for_each(|(k, out)| {
            let pw = &markers[k];
            let mut f = Vec3::zero();
            for &a in nl_ms.of(k) {
                let Some(pa) = soil.get(a as usize) else { continue };
                f -= marker_pair::<T, K, VISC>(c, pa, pw);
            }
            *out = f;
        });
        return;
    }
    out.par_iter_mut().zip(moments.par_iter_mut()).enumerate().for_each(|(k, (out, moment))| {
        let pw = &markers[k];
        let (mut f, mut q) = (Vec3::zero(), Vec3::zero());
        for &a in nl_ms.of(k) {
            let Some(pa) = soil.get(a as usize) else { continue };
            let fa = marker_pair::<T, K, VISC>(c, pa, pw);
            let r = pa.x - pw.x;
            f -= fa;
            q -= Vec3::new(r.x * fa.x, r.y * fa.y, r.z * fa.z);
        }
        *out = f;
        *moment = q;
    });
}

/// The force (N) a marker `pw` exerts on particle `pa` through the momentum pair term, zero
/// outside the support: what [`marker_forces`] subtracts for each neighbour.
#[inline(always)]
pub(crate) fn marker_pair<T: Real, K: Kernel<T>, const VISC: bool>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    pw: &Packed<T>,
) -> Vec3<T> {
    let r = pa.x - pw.x;
    let r2 = r.norm2();
    if r2 >= c.support2 {
        return Vec3::zero();
    }
    let gw = r * K::grad_factor(r2.sqrt(), c.inv_h, c.alpha);
    let vab = pa.v - pw.v;
    momentum::<T, VISC>(c, pa, (pw.s, pw.rho, pw.cs), r, r2, gw, vab) * (pa.mass * pw.mass)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::WendlandC2;

    /// A deterministic pseudo-random number in [-1, 1).
    fn rnd(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// A marker's pair moment is the sum over its particles of (their position − its
    /// position) ∘ (each one's force on it): checked against the forces of each pair alone
    /// (one-particle lists), and the forces are those of the loop without moments.
    #[test]
    fn a_markers_moment_takes_each_force_at_its_particle() {
        let h = 0.012;
        let c = PairConsts::<f64>::for_test::<WendlandC2>(h);
        let mut state = 11_u64;
        let mut record = |scale: f64| {
            let mut v3 = |s: f64| Vec3::new(rnd(&mut state) * s, rnd(&mut state) * s, rnd(&mut state) * s);
            let (x, v) = (v3(scale), v3(0.3));
            let s = Sym3::new(-1.0, -1.2, -0.8, 0.1, -0.05, 0.2) * (1e4 / (1700.0 * 1700.0));
            Packed { x, v, s, vol: 1e-6, mass: 1.7e-3, rho: 1700.0, cs: 50.0 }
        };
        let soil: Vec<Packed<f64>> = (0..40).map(|_| record(2.0 * h)).collect();
        let markers: Vec<Packed<f64>> = (0..5).map(|_| record(0.5 * h)).collect();
        let all: Vec<Vec<u32>> = vec![(0..soil.len() as u32).collect(); markers.len()];
        let nl = NeighborList::from_rows(&all);
        let (mut f, mut q, mut plain) = (vec![Vec3::zero(); 5], vec![Vec3::zero(); 5], vec![Vec3::zero(); 5]);
        marker_forces::<f64, WendlandC2, true>(&c, &soil, &markers, &nl, &mut f, &mut q);
        marker_forces::<f64, WendlandC2, true>(&c, &soil, &markers, &nl, &mut plain, &mut []);
        assert_eq!(f, plain);
        for (k, m) in markers.iter().enumerate() {
            let mut expect = Vec3::zero();
            let mut touching = 0;
            for (a, p) in soil.iter().enumerate() {
                let mut rows = vec![Vec::new(); markers.len()];
                rows[k].push(a as u32);
                let mut fa = vec![Vec3::zero(); markers.len()];
                marker_forces::<f64, WendlandC2, true>(
                    &c,
                    &soil,
                    &markers,
                    &NeighborList::from_rows(&rows),
                    &mut fa,
                    &mut [],
                );
                let r = p.x - m.x;
                expect += Vec3::new(r.x * fa[k].x, r.y * fa[k].y, r.z * fa[k].z);
                touching += usize::from(fa[k].norm2() > 0.0);
            }
            assert!(touching > 5, "marker {k} touches {touching} particles");
            let scale = expect.norm2().sqrt();
            assert!(scale > 0.0);
            assert!((q[k] - expect).norm2().sqrt() <= 1e-12 * scale, "marker {k}: {:?} against {:?}", q[k], expect);
        }
    }
}
