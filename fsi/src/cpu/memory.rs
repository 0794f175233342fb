//! What the CPU solver's arrays hold, by kind: the figure `regolith check` reports per
//! particle and the benches compare.
//!
//! Every count is a capacity (bytes reserved, not bytes used), so it is what the process
//! holds for the solver. The few fixed-size fields (configuration, materials, boxes) are
//! left out: they do not grow with the problem.

use crate::Real;

use super::CpuSph;

/// Bytes the solver's arrays reserve, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MemoryUse {
    /// Per-particle state of soil and water: positions, velocities, densities, stresses,
    /// constitutive state, the midpoint stage's copies, packed pair records and rates.
    pub particles: usize,
    /// Wall and body markers: kinematics, forces, their cell-sorted copies and records.
    pub markers: usize,
    /// Neighbour lists (soil–soil, soil–marker and marker–soil), with the scratch their
    /// builds keep between calls.
    pub lists: usize,
    /// Entries the three lists hold (4 bytes each; the rest of `lists` is offsets, scratch
    /// and the capacity the lists keep for their next build).
    pub list_entries: usize,
    /// Cell sorts and reorder scratch.
    pub sorting: usize,
}

impl MemoryUse {
    /// Everything.
    pub fn total(&self) -> usize {
        self.particles + self.markers + self.lists + self.sorting
    }
}

/// Bytes a vector reserves.
fn cap<V>(v: &Vec<V>) -> usize {
    v.capacity() * size_of::<V>()
}

impl<T: Real> CpuSph<T> {
    /// Bytes the solver's arrays reserve, by kind (their capacities: what the process holds).
    pub fn memory(&self) -> MemoryUse {
        macro_rules! sum {
            ($($v:expr),* $(,)?) => { 0 $(+ cap(&$v))* };
        }
        let particles = sum!(
            self.pos,
            self.vel,
            self.rho,
            self.sigma,
            self.state,
            self.material,
            self.mass,
            self.id,
            self.free_surface,
            self.detached,
            self.s_pos,
            self.s_vel,
            self.s_rho,
            self.s_sigma,
            self.s_state,
            self.packed,
            self.moduli,
            self.rates,
            self.x_ref,
            self.phase,
            self.pore,
            self.drag_rate,
        );
        let markers = sum!(
            self.m_pos,
            self.m_vel,
            self.m_acc,
            self.m_owner,
            self.m_normal,
            self.m_force,
            self.m_moment,
            self.ms_pos,
            self.ms_vel,
            self.ms_acc,
            self.touched,
            self.m_packed,
            self.ms_force,
            self.ms_moment,
            self.ms_orig,
            self.wall_ids,
            self.body_ids,
            self.bm_ref,
            self.bm_inside,
            self.m_packed_w,
            self.m_pore,
            self.m_permeable,
        );
        let nl = [&self.nl_ss, &self.nl_sm, &self.nl_ms];
        let lists = nl.iter().map(|l| l.heap_bytes()).sum();
        let list_entries = nl.iter().map(|l| l.pairs()).sum();
        let s = &self.scratch;
        let sorting = [&self.soil_sort, &self.wall_sort, &self.body_sort, &self.ext_sort]
            .iter()
            .map(|c| c.heap_bytes())
            .sum::<usize>()
            + sum!(s.v3, s.t, s.sym, s.st, s.u16, s.u32, s.b)
            + self.region.heap_bytes();
        MemoryUse { particles, markers, lists, list_entries, sorting }
    }
}
