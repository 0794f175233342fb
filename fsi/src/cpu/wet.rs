//! Wet soil: a water phase sharing space with the soil skeleton, coupled by drag and by the
//! pore pressure (mixture theory, both phases as SPH particles on the same support).
//!
//! Per unit volume of mixture, with porosity n, pore pressure p, effective stress σ' and
//! hydraulic conductivity k (at standard gravity g_n, `γ_w = ρ_w g_n`):
//!
//! ```text
//! water:  n ρ_w a_w = −n ∇p + n ρ_w g − f
//! soil:   ρ_s a_s   = ∇·σ' − (1 − n) ∇p + ρ_s g + f,      f = (n² γ_w / k) (v_w − v_s)
//! ```
//!
//! so that at steady state `n (v_w − v_s) = −(k / γ_w)(∇p − ρ_w g)` (Darcy) and the soil's
//! constitutive model acts on the effective stress (Terzaghi). Discretisation:
//!
//! - **Porosity by smoothed volume fractions.** `1 − n_a = Σ_s V^g_s W_as / max(Σ_s V_s W_as,
//!   χ L)`: the grain volume `V^g = m / ρ_g` of the soil particles smoothed by the kernel and
//!   divided by the kernel's sum L over the starting lattice (so that the undisturbed soil
//!   reads its nominal porosity), and by the soil's own volume sum where the soil fills the
//!   support (χ: [`WetSetup::full_support`]), so that inside the soil the porosity is the
//!   Shepard mean of the soil's own and does not dip as the water crosses the soil's lattice;
//!   boundary markers count as soil with the mean solid fraction of the soil next to them, so
//!   a wall does not read as a pore. A water particle's density ρ̄ is its partial density
//!   n ρ_w (continuity over water neighbours), its intrinsic density is ρ̄ / n and its
//!   pressure follows from that.
//! - **Water–water pairs** take the usual momentum pair term with the stress −p I, i.e.
//!   `−∇p / ρ̄`, laminar (Morris) viscosity and δ-SPH density diffusion of the intrinsic
//!   density with its hydrostatic part removed.
//! - **Soil–water pairs** carry only the interaction. The pore-pressure pair force
//!   `F_w = −(p_w − p̂_s) V_w V^g_s ∇_w W` (p̂_s the pore pressure interpolated at the soil
//!   particle) sums on the water to `+(1 − n) ∇p` per unit volume, which turns its `−∇p` into
//!   `−n ∇p`, and on the soil to `−(1 − n) ∇p`; the difference form keeps both exact for a
//!   uniform pressure whatever the particle disorder. The drag pair force
//!   `F_w = −(n_w² γ_w / k_s) V_w V_s W (v_w − v_s − ½ (L_w + L_s)(x_w − x_s))` sums to the
//!   drag above (the smooth volume fraction, "SVF", distribution); the slip is taken at the
//!   pair's midpoint with the two phases' velocity gradients L, so that soil and water moving
//!   together in a non-uniform flow do not drag on each other (see [`coupling`]). Both are
//!   one expression evaluated with the same operands from either side, so they are equal and
//!   opposite per pair to round-off.
//! - **Walls** keep two extrapolated records per marker (Adami et al. 2012), one from the soil
//!   and one from the water, and each phase meets the record of its own phase; the soil's
//!   pore-pressure term also sees the markers' extrapolated pore pressure, and the water's
//!   porosity and drag see the markers as soil moving with the soil beside them (the soil the
//!   wall cuts off the water's support, not the wall: at the wall's velocity, water beside a
//!   wall that the soil slides along was dragged as through soil at rest). Markers of a
//!   permeable owner (a filter stone) are invisible to the water.
//!
//! The explicit drag is stable for `dt < 2 / λ` with `λ = Σ C V W / m` per particle (about
//! `n g_n / k` for water); the time step is held below `1 / λ`.

use rayon::prelude::*;

use crate::Real;
use crate::config::Drag;
use crate::kernel::Kernel;
use crate::math::{Mat3, Sym3, Vec3};
use crate::rheology::{MIN_POROSITY, Material, Moduli, Rheology, STANDARD_GRAVITY, Water, jaumann_rate};

use super::neighbors::NeighborList;
use super::pair::{Packed, PairConsts, PairSums};
use super::rates::Rate;

/// The water of a wet scene (one water material): what every backend's coupling passes need.
#[derive(Clone, Copy, Debug)]
pub struct WetSetup<T> {
    /// The liquid.
    pub water: Water<T>,
    /// Rest density ρ_w (kg/m³).
    pub rest: T,
    /// Unit weight at standard gravity `ρ_w g_n` (N/m³), which turns conductivities into
    /// drag coefficients.
    pub gamma: T,
    /// `1 / Σ d0³ W` over the cubic lattice the particles start on. The kernel sum of a
    /// lattice is not exactly 1 (Wendland C2 at h = 1.2 d0 sums to 1.017), and the
    /// porosity and the drag are kernel sums of volumes: scaled by this, the undisturbed
    /// lattice reads its nominal porosity and the full drag.
    pub inv_lattice_sum: T,
    /// The lattice sum itself: the pore-pressure coupling takes the grain volumes unscaled,
    /// so that its gradient sum carries the same lattice moment as the water's own pressure
    /// term and the two cancel to `n ∇p` (scaled, they would leave `(M − (1 − n)) ∇p`, an
    /// error of the moment amplified by 1 / n).
    pub lattice_sum: T,
    /// The least kernel sum a full support of the starting lattice gives anywhere in a
    /// lattice cell, over its sum at a lattice site (0.973 for Wendland C2 at h = 1.2 d0,
    /// lowest at the cell's centre). A water particle whose soil volume sum reads at least
    /// this much of the site's sits inside the soil: its porosity is then taken from the
    /// soil's own solid fraction (a Shepard mean) rather than from the kernel sum, whose
    /// dips between lattice sites would otherwise read as pore space. See `cpu::wet::porosity`.
    pub full_support: T,
    /// How the drag is spread over the pairs.
    pub drag: Drag,
}

impl<T: Real> WetSetup<T> {
    /// The water of `materials`: `None` for a dry scene; an error when there are two water
    /// materials or a soil without `permeability` shares the scene with water. `lattice_sum`
    /// is the kernel's sum over the particles' starting lattice at a lattice site,
    /// `full_support` the least fraction of it a point inside a cell sees.
    pub fn of(
        materials: &[Material<T>],
        (lattice_sum, full_support): (f64, f64),
        drag: Drag,
    ) -> Result<Option<Self>, String> {
        let mut found = None;
        for m in materials {
            if let Rheology::Water(w) = m.rheology {
                if found.is_some() {
                    return Err("a scene holds at most one water material".into());
                }
                found = Some(Self {
                    water: w,
                    rest: m.density,
                    gamma: m.density * T::of(STANDARD_GRAVITY),
                    inv_lattice_sum: T::of(1.0 / lattice_sum),
                    lattice_sum: T::of(lattice_sum),
                    full_support: T::of(full_support),
                    drag,
                });
            }
        }
        if found.is_some()
            && let Some(i) = materials.iter().position(|m| !m.is_water() && m.permeability <= T::zero())
        {
            return Err(format!(
                "material {i} shares the scene with water but has no permeability (and grain_density)"
            ));
        }
        Ok(found)
    }
}

/// What a particle brings to the phase coupling that does not change during a step.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Phase<T> {
    pub water: bool,
    /// Soil: grain volume `m / ρ_g` (m³); water: 0.
    pub vg: T,
    /// Soil: `1 / k` (s/m); water: 0.
    pub inv_k: T,
}

/// What the porosity pass finds for a particle at a stage.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Pore<T> {
    /// Water: porosity n; soil: 0.
    pub n: T,
    /// Pore pressure p (Pa, compression positive): the water's own; at a soil particle, the
    /// water's interpolated there ([`soil_pressures`]).
    pub p: T,
    /// Water: `n² γ_w` (N/m³); soil: 0.
    pub cw: T,
    /// Water: what each of its drag pairs' `V_s W` is divided by, inverted: `1 / L` for
    /// [`Drag::Svf`] (L the lattice sum), `1 / Σ V_s W` over the soil and solid markers in its
    /// support for [`Drag::Particle`] (0 with none); soil: 0.
    pub inv_sum: T,
    /// Soil: the fraction of its pores water fills (kernel sum of water volume over that of
    /// soil volume, at most 1); water: 0.
    pub sat: T,
    /// The velocity gradient of the particle's own phase, `Σ V_b (v_b − v_a) ⊗ ∇W` over its
    /// same-phase neighbours (1/s): the drag's relative velocity is taken at each pair's
    /// midpoint with it (see [`coupling`]).
    pub gv: Mat3<T>,
}

/// The pore pressure at each soil particle, interpolated from the water around it (Shepard:
/// `Σ V_w p_w W / Σ V_w W`; 0 where there is none), after [`porosity`] gave the water theirs.
pub(crate) fn soil_pressures<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    nl_ss: &NeighborList,
    packed: &[Packed<T>],
    phase: &[Phase<T>],
    pore: &mut [Pore<T>],
) {
    let found: Vec<T> = (0..pore.len())
        .into_par_iter()
        .map(|a| {
            if phase[a].water {
                return pore[a].p;
            }
            let pa = &packed[a];
            let (mut sw, mut sp) = (T::zero(), T::zero());
            for &b in nl_ss.of(a) {
                let b = b as usize;
                if !phase[b].water {
                    continue;
                }
                let r2 = (pa.x - packed[b].x).norm2();
                if r2 < c.support2 {
                    let w = packed[b].vol * K::w(r2.sqrt(), c.inv_h, c.alpha);
                    sw += w;
                    sp += pore[b].p * w;
                }
            }
            if sw > T::min_positive_value().sqrt() { sp / sw } else { T::zero() }
        })
        .collect();
    pore.par_iter_mut().zip(found.into_par_iter()).for_each(|(po, p)| po.p = p);
}

/// A touched marker's share of the coupling: its solid volume (`V_m` times the mean solid
/// fraction of the soil around it), the mean `1 / k` of that soil, the extrapolated pore
/// pressure, and the velocity the water is dragged towards there: the mean velocity of that
/// soil (the marker stands in for the soil the wall cuts off the water's support; an
/// impermeable wall itself drags no water). The wall's own velocity where no soil is near
/// (no drag there).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MarkerPore<T> {
    pub vg: T,
    pub inv_k: T,
    pub p: T,
    pub vel: Vec3<T>,
}

/// The phase of each of the first `phase.len()` particles (grain volumes scaled by the
/// lattice sum, see [`WetSetup::inv_lattice_sum`]).
pub(crate) fn phases<T: Real>(
    setup: &WetSetup<T>,
    materials: &[Material<T>],
    material: &[u16],
    mass: &[T],
    phase: &mut [Phase<T>],
) {
    phase.par_iter_mut().enumerate().for_each(|(i, ph)| {
        let m = &materials[material[i] as usize];
        *ph = if m.is_water() {
            Phase { water: true, vg: T::zero(), inv_k: T::zero() }
        } else {
            Phase {
                water: false,
                vg: mass[i] / m.grain_density * setup.inv_lattice_sum,
                inv_k: T::one() / m.permeability,
            }
        };
    });
}

/// The soil-side share of each touched marker (`vg`, `inv_k`, `vel`), from the soil listed
/// in its row of `nl_ms`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn marker_solids<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    marker_pos: &[Vec3<T>],
    marker_vel: &[Vec3<T>],
    marker_volume: T,
    touched: &[u32],
    nl_ms: &NeighborList,
    soil: &[Packed<T>],
    phase: &[Phase<T>],
    out: &mut [MarkerPore<T>],
) {
    out.par_iter_mut().enumerate().for_each(|(k, o)| {
        let m = touched[k] as usize;
        let (mut sw, mut sf, mut sk, mut sv) = (T::zero(), T::zero(), T::zero(), Vec3::zero());
        for &a in nl_ms.of(k) {
            let (pa, ph) = (&soil[a as usize], &phase[a as usize]);
            if ph.water {
                continue;
            }
            let r2 = (marker_pos[m] - pa.x).norm2();
            if r2 >= c.support2 {
                continue;
            }
            let w = K::w(r2.sqrt(), c.inv_h, c.alpha);
            sw += w;
            sf += ph.vg / pa.vol * w;
            sk += ph.inv_k * w;
            sv += pa.v * w;
        }
        let tiny = T::min_positive_value().sqrt();
        *o = if sw > tiny {
            MarkerPore { vg: marker_volume * sf / sw, inv_k: sk / sw, p: T::zero(), vel: sv * (T::one() / sw) }
        } else {
            MarkerPore { vel: marker_vel[m], ..MarkerPore::default() }
        };
    });
}

/// The porosity pass: for each water particle its porosity (smoothed solid fraction, markers
/// included but for `permeable` ones), pore pressure and partial stress (written into its record, `s = −n p I / ρ̄²`);
/// for each soil particle its saturation.
#[allow(clippy::too_many_arguments)]
pub(crate) fn porosity<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    setup: &WetSetup<T>,
    nl_ss: &NeighborList,
    nl_sm: &NeighborList,
    phase: &[Phase<T>],
    marker_solid: &[MarkerPore<T>],
    (permeable, marker_volume): (&[bool], T),
    markers_x: impl Fn(usize) -> Vec3<T> + Sync,
    packed: &mut [Packed<T>],
    pore: &mut [Pore<T>],
) {
    let records: &[Packed<T>] = packed;
    let found: Vec<(Pore<T>, Option<Sym3<T>>)> = (0..pore.len())
        .into_par_iter()
        .map(|a| {
            let pa = &records[a];
            let water = phase[a].water;
            let (mut solid, mut vw, mut vs, mut gv) = (T::zero(), T::zero(), T::zero(), Mat3::zero());
            for &b in nl_ss.of(a) {
                let pb = &records[b as usize];
                let r = pa.x - pb.x;
                let r2 = r.norm2();
                if r2 >= c.support2 {
                    continue;
                }
                let rr = r2.sqrt();
                let w = K::w(rr, c.inv_h, c.alpha);
                if phase[b as usize].water == water {
                    gv += gradient_term::<T, K>(c, pa, pb, r, rr);
                }
                if phase[b as usize].water {
                    vw += pb.vol * w;
                } else {
                    solid += phase[b as usize].vg * w;
                    vs += pb.vol * w;
                }
            }
            if water {
                for &m in nl_sm.of(a) {
                    if permeable[m as usize] {
                        continue;
                    }
                    let r2 = (pa.x - markers_x(m as usize)).norm2();
                    if r2 < c.support2 {
                        let w = K::w(r2.sqrt(), c.inv_h, c.alpha);
                        let ms = &marker_solid[m as usize];
                        solid += ms.vg * w;
                        // Markers drag the water where they hold soil (see `wet_rates`).
                        if ms.inv_k > T::zero() {
                            vs += marker_volume * w;
                        }
                    }
                }
                // `solid` is Σ V^g W / L and `vs / L` how much of the support the soil fills
                // (about 1 inside). Where it fills it, their ratio is the Shepard mean of the
                // soil's own solid fraction, which does not change as the water moves across
                // the soil's lattice; where it fills less than any full lattice would (a
                // surface, a layer's face), the smoothed volume fraction over χ.
                let presence = (vs * setup.inv_lattice_sum).max(setup.full_support);
                let n = (T::one() - solid / presence).max(T::of(MIN_POROSITY));
                let p = setup.water.pressure(pa.rho / n, setup.rest);
                let s = Sym3::iso(-p / (pa.rho * pa.rho));
                let inv_sum = match setup.drag {
                    Drag::Svf => setup.inv_lattice_sum,
                    Drag::Particle if vs > T::min_positive_value().sqrt() => T::one() / vs,
                    Drag::Particle => T::zero(),
                };
                (Pore { n, p, cw: n * n * setup.gamma, inv_sum, sat: T::zero(), gv }, Some(s))
            } else {
                // The particle's own volume is in the soil sum (W(0)), so it is never empty.
                vs += pa.vol * K::w(T::zero(), c.inv_h, c.alpha);
                let sat = (vw / vs).min(T::one());
                (Pore { sat, gv, ..Pore::default() }, None)
            }
        })
        .collect();
    packed.par_iter_mut().zip(pore.par_iter_mut()).zip(found.into_par_iter()).for_each(|((pk, po), (f, s))| {
        *po = f;
        if let Some(s) = s {
            pk.s = s;
        }
    });
}

/// Neighbour `pb`'s term of `a`'s velocity gradient `Σ V_b (v_b − v_a) ⊗ ∇W` (1/s), with
/// `r = x_a − x_b` and `rr = |r|` inside the support.
#[inline(always)]
fn gradient_term<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    pb: &Packed<T>,
    r: Vec3<T>,
    rr: T,
) -> Mat3<T> {
    Mat3::outer(pb.v - pa.v, r * (pb.vol * K::grad_factor(rr, c.inv_h, c.alpha)))
}

/// The water-side share of each touched marker: the pore pressure extrapolated from the water
/// in its row of `nl_ms`, with the hydrostatic step `ρ_w (g − a) · (x_m − x_b)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn marker_pressures<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    setup: &WetSetup<T>,
    marker_pos: &[Vec3<T>],
    marker_acc: &[Vec3<T>],
    touched: &[u32],
    nl_ms: &NeighborList,
    soil: &[Packed<T>],
    phase: &[Phase<T>],
    pore: &[Pore<T>],
    out: &mut [MarkerPore<T>],
) {
    out.par_iter_mut().enumerate().for_each(|(k, o)| {
        let m = touched[k] as usize;
        let xw = marker_pos[m];
        let (mut sw, mut sp, mut sr) = (T::zero(), T::zero(), Vec3::zero());
        for &a in nl_ms.of(k) {
            if !phase[a as usize].water {
                continue;
            }
            let r = xw - soil[a as usize].x;
            let r2 = r.norm2();
            if r2 >= c.support2 {
                continue;
            }
            let w = K::w(r2.sqrt(), c.inv_h, c.alpha);
            sw += w;
            sp += pore[a as usize].p * w;
            sr += r * w;
        }
        let tiny = T::min_positive_value().sqrt();
        o.p = if sw > tiny {
            ((sp + setup.rest * (c.gravity - marker_acc[m]).dot(sr)) / sw).max(T::zero())
        } else {
            T::zero()
        };
    });
}

/// The phase-coupling force on particle `a` from particle `b` of the other phase (N): pore
/// pressure and drag, one expression from either side (water operands first), so the two
/// evaluations of a pair are exact negatives. The operands are the pressure difference, the
/// water's `n² γ_w`, the soil's grain volume and `1 / k`, and the water's drag normaliser
/// [`Pore::inv_sum`] that scales the drag's kernel weight; `sum` is
/// [`WetSetup::lattice_sum`]. Also returns the drag coefficient `C V_a V_b W` (kg/s) for the
/// time-step bound.
///
/// The drag's relative velocity is taken at the pair's midpoint: `v_a − v_b − ½ (L_a + L_b)
/// (x_a − x_b)`, with `gsum = L_a + L_b` the two particles' own-phase velocity gradients
/// (zero for a marker). Taken plainly, `v_a − v_b` compares the two velocity fields at points
/// up to 2h apart: a soil and water moving together in any non-uniform flow (a collapse,
/// shear) then drag on each other as if they slipped: an artificial viscosity of about
/// `C ⟨r²⟩ / 6`, `⟨r²⟩ = 0.8 h²` for Wendland C2 (120 Pa s at k = 1e-3 m/s and h = 2.4 cm,
/// ten times the soil's artificial viscosity). With the midpoint correction the pair's
/// relative velocity vanishes to second order in r for a common smooth field, while a true
/// slip (Darcy flow) is kept; the expression is still the exact negative of its partner's.
#[inline(always)]
fn coupling<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    pa: &Packed<T>,
    pb: &Packed<T>,
    a_water: bool,
    (dp, cw, vg, inv_k, inv_sum): (T, T, T, T, T),
    gsum: &Mat3<T>,
    sum: T,
) -> (Vec3<T>, T) {
    let r = pa.x - pb.x;
    let r2 = r.norm2();
    if r2 >= c.support2 {
        return (Vec3::zero(), T::zero());
    }
    let rr = r2.sqrt();
    let gw = r * K::grad_factor(rr, c.inv_h, c.alpha);
    let w = K::w(rr, c.inv_h, c.alpha);
    let (vw, vs) = if a_water { (pa.vol, pb.vol) } else { (pb.vol, pa.vol) };
    let drag = cw * inv_k * (vw * vs) * (w * inv_sum);
    let slip = (pa.v - pb.v) - gsum.mul_vec(r) * T::of(0.5);
    (-(gw * (dp * vw * (vg * sum))) - slip * drag, drag)
}

/// Soil and water rates of the awake particles of a wet scene: same-phase pairs as in the dry
/// loop ([`super::rates::soil_rates`]), cross-phase pairs through the coupling only, each
/// phase meeting its own record of the markers (`m_soil`, `m_water`). Water passes through
/// `permeable` markers (a filter stone holds the soil, not the water); the soil still feels
/// the pore pressure extrapolated to them.
#[allow(clippy::too_many_arguments)]
pub(crate) fn wet_rates<T: Real, K: Kernel<T>, const VISC: bool, const XSPH: bool, const PPST: bool, const FS: bool>(
    c: &PairConsts<T>,
    setup: &WetSetup<T>,
    soil: &[Packed<T>],
    m_soil: &[Packed<T>],
    m_water: &[Packed<T>],
    (m_pore, permeable): (&[MarkerPore<T>], &[bool]),
    phase: &[Phase<T>],
    pore: &[Pore<T>],
    (nl_ss, nl_sm): (&NeighborList, &NeighborList),
    sigma: &[Sym3<T>],
    moduli: &[Moduli<T>],
    out: &mut [Rate<T>],
    drag_rate: &mut [T],
) {
    let mu = setup.water.viscosity;
    out.par_iter_mut().zip(drag_rate.par_iter_mut()).enumerate().for_each(|(a, (out, lambda))| {
        let pa = &soil[a];
        let (pha, poa) = (phase[a], pore[a]);
        let mut sums = PairSums::default();
        let (mut f, mut drag, mut diffusion) = (Vec3::zero(), T::zero(), T::zero());
        for &b in nl_ss.of(a) {
            let b = b as usize;
            let pb = &soil[b];
            if phase[b].water == pha.water {
                sums.add::<K, VISC, XSPH, PPST, FS, true>(c, pa, pb);
                if pha.water {
                    if mu > T::zero() {
                        f += laminar::<T, K>(c, mu, pa, pb);
                    }
                    diffusion += density_diffusion::<T, K>(c, setup, pa, pb, pa.rho / poa.n, pb.rho / pore[b].n);
                }
            } else {
                let k = if pha.water {
                    (poa.p - pore[b].p, poa.cw, phase[b].vg, phase[b].inv_k, poa.inv_sum)
                } else {
                    (pore[b].p - poa.p, pore[b].cw, pha.vg, pha.inv_k, pore[b].inv_sum)
                };
                let gsum = poa.gv + pore[b].gv;
                let (fi, d) = coupling::<T, K>(c, pa, pb, pha.water, k, &gsum, setup.lattice_sum);
                f += fi;
                drag += d;
            }
        }
        let records = if pha.water { m_water } else { m_soil };
        for &w in nl_sm.of(a) {
            let w = w as usize;
            if pha.water && permeable[w] {
                continue;
            }
            sums.add::<K, VISC, XSPH, PPST, FS, false>(c, pa, &records[w]);
            let mp = &m_pore[w];
            // The marker as the other phase: soil moving with the soil beside it for the water,
            // the extrapolated pore pressure for the soil.
            let wall = Packed { v: mp.vel, ..records[w] };
            let k = if pha.water {
                (poa.p - mp.p, poa.cw, mp.vg, mp.inv_k, poa.inv_sum)
            } else {
                (mp.p - poa.p, T::zero(), pha.vg, T::zero(), T::zero())
            };
            let (fi, d) = coupling::<T, K>(c, pa, &wall, pha.water, k, &Mat3::zero(), setup.lattice_sum);
            f += fi;
            drag += d;
        }
        let inv_m = T::one() / pa.mass;
        out.moduli = moduli[a];
        let d = sums.l.sym();
        out.drho = sums.drho * pa.rho;
        if pha.water {
            out.drho += T::of(DELTA_SPH) * c.h * setup.water.sound_speed * poa.n * diffusion;
        }
        out.acc = sums.acc + f * inv_m + c.gravity;
        out.d = d;
        out.dsigma = if pha.water { Sym3::zero() } else { jaumann_rate(&sigma[a], &d, sums.l.skew(), out.moduli) };
        out.xsph = sums.xs;
        out.grad_c = sums.gc;
        if FS {
            out.fs = sums.fs.min_eigenvalue();
            out.contact = sums.contact;
        }
        *lambda = drag * inv_m;
    });
}

/// The δ-SPH coefficient δ of the water's density diffusion (Molteni & Colagrossi 2009; 0.1 is
/// the usual value).
pub const DELTA_SPH: f64 = 0.1;

/// The water's density diffusion between `a` and `b` (before the factor `δ h c n_a`): the
/// Laplacian `2 Σ V_b (ψ_b − ψ_a − ψ^H_ab) (r·∇W) / (r² + η²)` of the intrinsic density ψ,
/// less its hydrostatic part `ψ^H_ab = ρ_w g·(x_b − x_a) / c²` (Antuono et al. 2012), so that
/// a column at rest is not diffused out of hydrostatic balance. It damps the odd–even pressure
/// mode the sum-form pressure term cannot see.
#[inline(always)]
fn density_diffusion<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    setup: &WetSetup<T>,
    pa: &Packed<T>,
    pb: &Packed<T>,
    psi_a: T,
    psi_b: T,
) -> T {
    let r = pa.x - pb.x;
    let r2 = r.norm2();
    if r2 >= c.support2 {
        return T::zero();
    }
    let cw = setup.water.sound_speed;
    let hydro = setup.rest * c.gravity.dot(r) / (cw * cw);
    let rgw = r2 * K::grad_factor(r2.sqrt(), c.inv_h, c.alpha);
    T::of(2.0) * pb.vol * (psi_a - psi_b - hydro) * rgw / (r2 + c.eta2)
}

/// Morris et al. (1997) laminar viscous force on `a` from `b` (N):
/// `m_a m_b (μ_a + μ_b) (r·∇W) / (ρ_a ρ_b (r² + η²)) v_ab`, antisymmetric in a and b.
#[inline(always)]
fn laminar<T: Real, K: Kernel<T>>(c: &PairConsts<T>, mu: T, pa: &Packed<T>, pb: &Packed<T>) -> Vec3<T> {
    let r = pa.x - pb.x;
    let r2 = r.norm2();
    if r2 >= c.support2 {
        return Vec3::zero();
    }
    // r·∇W = r² F(r) ≤ 0.
    let rgw = r2 * K::grad_factor(r2.sqrt(), c.inv_h, c.alpha);
    let k = (pa.vol * pb.vol) * (mu + mu) * rgw / (r2 + c.eta2);
    (pa.v - pb.v) * k
}

/// Force (N) on each touched marker from the wet mixture: minus the same-phase pair terms each
/// awake particle receives from the marker's record of its phase, and minus the coupling
/// forces (see [`wet_rates`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn wet_marker_forces<T: Real, K: Kernel<T>>(
    c: &PairConsts<T>,
    (visc, sum): (bool, T),
    soil: &[Packed<T>],
    (m_soil, m_water): (&[Packed<T>], &[Packed<T>]),
    (m_pore, permeable): (&[MarkerPore<T>], &[bool]),
    phase: &[Phase<T>],
    pore: &[Pore<T>],
    nl_ms: &NeighborList,
    out: &mut [Vec3<T>],
) {
    out.par_iter_mut().enumerate().for_each(|(k, out)| {
        let mp = &m_pore[k];
        let mut f = Vec3::zero();
        for &a in nl_ms.of(k) {
            let Some(pa) = soil.get(a as usize) else { continue };
            let (pha, poa) = (phase[a as usize], pore[a as usize]);
            if pha.water && permeable[k] {
                continue;
            }
            let pw = if pha.water { &m_water[k] } else { &m_soil[k] };
            f -= if visc {
                super::rates::marker_pair::<T, K, true>(c, pa, pw)
            } else {
                super::rates::marker_pair::<T, K, false>(c, pa, pw)
            };
            let wall = Packed { v: mp.vel, ..*pw };
            let kk = if pha.water {
                (poa.p - mp.p, poa.cw, mp.vg, mp.inv_k, poa.inv_sum)
            } else {
                (mp.p - poa.p, T::zero(), pha.vg, T::zero(), T::zero())
            };
            f -= coupling::<T, K>(c, pa, &wall, pha.water, kk, &Mat3::zero(), sum).0;
        }
        *out = f;
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::WendlandC2;

    /// The pair constants of a Wendland C2 kernel of smoothing length `h`, no viscosity nor
    /// gravity.
    fn consts(h: f64) -> PairConsts<f64> {
        PairConsts {
            h,
            inv_h: 1.0 / h,
            alpha: <WendlandC2 as Kernel<f64>>::alpha(h),
            support2: 4.0 * h * h,
            visc_alpha: 0.0,
            eta2: 0.01 * h * h,
            gravity: Vec3::zero(),
        }
    }

    /// Soil and water on the same cubic lattice (d0 = 1 cm, h = 1.2 d0, Wendland C2) moving
    /// together in the shear flow `u = (a z², 0, 0)`: the drag on the water particle at the
    /// origin, summed over its soil pairs. Taken plainly (`v_w − v_s`), it is the artificial
    /// viscosity `C V_w (⟨r²⟩ / 6) ∇²u` with `⟨r²⟩ = ∫ W r² dV = 0.8 h²` (closed form for
    /// Wendland C2; measured −1.0 % on the lattice, bound 3 %); with the midpoint slip it must
    /// vanish (measured 1.5 % of the plain value, bound 5 %: what is left is the lattice moment
    /// of the SPH gradient, 1 − Σ V r ⊗ ∇W). A true slip (water faster than the soil by a uniform δ) keeps
    /// its whole drag `C V_w (Σ V_s W / L) δ` with the correction, to round-off.
    #[test]
    fn the_midpoint_slip_removes_the_drag_of_a_shared_shear_flow_and_keeps_a_true_slip() {
        type K = WendlandC2;
        let d0 = 0.01_f64;
        let h = 1.2 * d0;
        let c = consts(h);
        let a = 50.0; // 1/(m s): u_x = a z², ∇²u_x = 2a.
        let u = |x: Vec3<f64>| Vec3::new(a * x.z * x.z, 0.0, 0.0);
        let vol = d0 * d0 * d0;
        let at = |x: Vec3<f64>, v: Vec3<f64>| Packed { x, v, s: Sym3::zero(), vol, mass: vol, rho: 1.0, cs: 1.0 };
        // Lattice sites within 2h of the origin, and within 2h of each of those (for gradients).
        let sites: Vec<Vec3<f64>> = (-6..=6)
            .flat_map(|i| (-6..=6).flat_map(move |j| (-6..=6).map(move |k| (i, j, k))))
            .map(|(i, j, k)| Vec3::new(i as f64 * d0, j as f64 * d0, k as f64 * d0))
            .collect();
        let gradient = |x: Vec3<f64>, v: &dyn Fn(Vec3<f64>) -> Vec3<f64>| {
            let pa = at(x, v(x));
            let mut g = Mat3::zero();
            for &y in &sites {
                let r = x - y;
                let r2 = r.norm2();
                if r2 > 0.0 && r2 < c.support2 {
                    g += gradient_term::<f64, K>(&c, &pa, &at(y, v(y)), r, r2.sqrt());
                }
            }
            g
        };
        let lattice_sum: f64 =
            sites.iter().map(|y| vol * <K as Kernel<f64>>::w(y.norm2().sqrt(), c.inv_h, c.alpha)).sum();
        let (gamma, k, n) = (9810.0, 1e-3, 0.4);
        let cw = n * n * gamma;
        let drag_on_water =
            |vw: &dyn Fn(Vec3<f64>) -> Vec3<f64>, vs: &dyn Fn(Vec3<f64>) -> Vec3<f64>, midpoint: bool| {
                let water = at(Vec3::zero(), vw(Vec3::zero()));
                let gw = gradient(Vec3::zero(), vw);
                let mut f = Vec3::zero();
                for &y in &sites {
                    if y.norm2() >= c.support2 {
                        continue;
                    }
                    let soil = at(y, vs(y));
                    let gsum = if midpoint { gw + gradient(y, vs) } else { Mat3::zero() };
                    let ops = (0.0, cw, vol, 1.0 / k, 1.0 / lattice_sum);
                    f += coupling::<f64, K>(&c, &water, &soil, true, ops, &gsum, lattice_sum).0;
                }
                f
            };
        // The plain drag against its closed form C V_w (0.8 h² / 6) ∇²u (on the water: along +x,
        // the soil around it moving faster on average).
        let plain = drag_on_water(&u, &u, false);
        let closed = cw / k * vol * (0.8 * h * h / 6.0) * (2.0 * a);
        assert!(
            (plain.x / closed - 1.0).abs() < 0.03,
            "plain drag {} N against C V (⟨r²⟩/6) ∇²u = {closed} N",
            plain.x
        );
        let corrected = drag_on_water(&u, &u, true);
        eprintln!("plain {plain:?} N, closed form {closed} N, midpoint {corrected:?} N");
        assert!(
            corrected.norm2().sqrt() < 0.05 * plain.x.abs(),
            "midpoint drag {corrected:?} N against the plain {} N",
            plain.x
        );
        // A true slip δ on top of the shared flow keeps its whole drag.
        let delta = Vec3::new(0.0, 0.0, 2e-3);
        let faster = |x: Vec3<f64>| u(x) + delta;
        let slip = drag_on_water(&faster, &u, true) - corrected;
        let expected = -(delta * (cw / k * vol));
        assert!(
            (slip - expected).norm2().sqrt() < 1e-9 * expected.norm2().sqrt(),
            "drag of a uniform slip {slip:?} N against {expected:?} N"
        );
    }

    /// A water particle anywhere inside a uniform soil lattice reads the soil's porosity
    /// (n0 = 0.396), to round-off: at a site, a fifth of a spacing off, a quarter of the
    /// diagonal, the cell's centre. The plain smoothed volume fraction reads the lattice's
    /// dip there as pore space (n up by (1 − n0)(1 − χ) = 0.016 at the centre, checked so the
    /// test can tell the two apart). Above a soil surface the support is not full: the water
    /// reads the smoothed fraction over χ, between n0 and 1.
    #[test]
    fn water_inside_uniform_soil_reads_its_porosity_wherever_it_sits() {
        type K = WendlandC2;
        let cfg = crate::config::SolverConfig::default();
        let (d0, h) = (cfg.spacing, cfg.h());
        let (lattice_sum, chi) = super::super::lattice_sums(&cfg);
        let c = consts(h);
        let setup = WetSetup {
            water: Water { sound_speed: 50.0, viscosity: 1e-3 },
            rest: 1000.0,
            gamma: 1000.0 * STANDARD_GRAVITY,
            inv_lattice_sum: 1.0 / lattice_sum,
            lattice_sum,
            full_support: chi,
            drag: Drag::Svf,
        };
        let n0 = 1.0 - 1600.0 / 2650.0;
        let vol = d0 * d0 * d0;
        let read = |at: [f64; 3], top: i32| {
            // Index 0: the water particle; then the soil sites up to layer `top`.
            let mut packed = vec![Packed {
                x: Vec3::new(at[0] * d0, at[1] * d0, at[2] * d0),
                v: Vec3::zero(),
                s: Sym3::zero(),
                vol,
                mass: n0 * 1000.0 * vol,
                rho: n0 * 1000.0,
                cs: 1.0,
            }];
            let mut phase = vec![Phase { water: true, vg: 0.0, inv_k: 0.0 }];
            for (i, j, k) in (-5..=5).flat_map(|i| (-5..=5).flat_map(move |j| (-5..=top).map(move |k| (i, j, k)))) {
                let x = Vec3::new(i as f64 * d0, j as f64 * d0, k as f64 * d0);
                packed.push(Packed {
                    x,
                    v: Vec3::zero(),
                    s: Sym3::zero(),
                    vol,
                    mass: 1600.0 * vol,
                    rho: 1600.0,
                    cs: 1.0,
                });
                phase.push(Phase { water: false, vg: (1.0 - n0) * vol / lattice_sum, inv_k: 1e3 });
            }
            let m = packed.len();
            let mut rows = vec![Vec::new(); m];
            rows[0] = (1..m as u32).collect();
            let nl_ss = NeighborList::from_rows(&rows);
            let nl_sm = NeighborList::from_rows(&vec![Vec::new(); m]);
            let plain: f64 = 1.0
                - packed[1..]
                    .iter()
                    .zip(&phase[1..])
                    .map(|(p, ph)| {
                        let r2 = (p.x - packed[0].x).norm2();
                        if r2 < c.support2 { ph.vg * <K as Kernel<f64>>::w(r2.sqrt(), c.inv_h, c.alpha) } else { 0.0 }
                    })
                    .sum::<f64>();
            let mut pore = vec![Pore::default(); m];
            porosity::<f64, K>(
                &c,
                &setup,
                &nl_ss,
                &nl_sm,
                &phase,
                &[],
                (&[], vol),
                |_| Vec3::zero(),
                &mut packed,
                &mut pore,
            );
            (pore[0].n, plain)
        };
        for at in [[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.25, 0.25, 0.25], [0.5, 0.5, 0.5]] {
            let (n, plain) = read(at, 5);
            eprintln!("at {at:?} d0: n = {n:.6}, plain smoothed fraction {plain:.6}");
            assert!((n - n0).abs() < 1e-12, "n = {n} at {at:?} against {n0}");
            if at == [0.5, 0.5, 0.5] {
                assert!((plain - n0 - (1.0 - n0) * (1.0 - chi)).abs() < 1e-3, "plain {plain}");
            }
        }
        // One spacing above the top soil layer: a cut support.
        let (n, plain) = read([0.0, 0.0, 1.0], 0);
        eprintln!("above the surface: n = {n:.6}, plain {plain:.6}");
        assert!(n > n0 + 0.1 && n < 1.0, "{n}");
        assert!((1.0 - n - (1.0 - plain) / chi).abs() < 1e-12, "{n} against {plain} / χ");
    }
}
