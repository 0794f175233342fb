//! Neighbour lists in compressed-row form, built from a cell grid.
//!
//! Built with the search radius 2h + skin and reused by both stages of the midpoint
//! integrator and, with a Verlet skin, by later steps until the moves since the build could
//! bring an unlisted pair inside 2h (`CpuSph::lists_still_hold`); a listed pair outside the
//! support just gets `W = 0`.

use rayon::prelude::*;

use crate::Real;
use crate::math::Vec3;

use super::grid::{CellIndexer, CellSort};

/// For each query point, the indices of target points within the radius.
#[derive(Clone, Debug, Default)]
pub struct NeighborList {
    /// `offsets[i]..offsets[i + 1]` index `indices` for query `i`.
    pub offsets: Vec<u32>,
    /// Target indices.
    pub indices: Vec<u32>,
    chunk_counts: Vec<Vec<u32>>,
    chunk_lists: Vec<Vec<u32>>,
    /// Transpose scratch, one entry per target, zero (and `u32::MAX`) between calls.
    count: Vec<u32>,
    row_of: Vec<u32>,
}

const CHUNK: usize = 512;

/// Cells a search of `radius` scans on each side of a query's cell (edge `cell`).
pub fn reach(radius: f64, cell: f64) -> usize {
    (radius / cell - 1e-9).ceil().max(1.0) as usize
}

/// Targets sorted by one cell sort, listed from `offset` on.
#[derive(Clone, Copy, Debug)]
pub struct TargetGroup<'a, T> {
    /// The targets' cell sort.
    pub sort: &'a CellSort,
    /// Target positions, in the sort's order.
    pub targets: &'a [Vec3<T>],
    /// Index of the group's first target in the list.
    pub offset: u32,
}

impl NeighborList {
    /// Neighbours of `i`.
    #[inline(always)]
    pub fn of(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Total number of pairs.
    pub fn pairs(&self) -> usize {
        self.indices.len()
    }

    /// Builds the list of targets (sorted by `sort` over `idx`, positions `targets`) within
    /// `radius` of each query point. With `same_set`, a query does not list itself.
    #[cfg(test)]
    pub fn build<T: Real>(
        &mut self,
        queries: &[Vec3<T>],
        idx: &CellIndexer<T>,
        sort: &CellSort,
        targets: &[Vec3<T>],
        radius: T,
        same_set: bool,
    ) {
        self.build_groups(queries, idx, &[TargetGroup { sort, targets, offset: 0 }], radius, same_set);
    }

    /// As [`NeighborList::build`] over several target groups, each sorted by its own cell sort;
    /// group `g`'s target `j` is listed as `offset_g + j`, groups in order. With `same_set`, query
    /// `i` does not list target `i` of a group with offset 0.
    pub fn build_groups<T: Real>(
        &mut self,
        queries: &[Vec3<T>],
        idx: &CellIndexer<T>,
        groups: &[TargetGroup<'_, T>],
        radius: T,
        same_set: bool,
    ) {
        let r2 = radius * radius;
        // Cells to scan on each side: the radius over the cell edge, rounded up.
        let reach = reach(radius.as_f64(), idx.cell().as_f64());
        let n = queries.len();
        let chunks = n.div_ceil(CHUNK);
        self.chunk_counts.resize_with(chunks, Vec::new);
        self.chunk_lists.resize_with(chunks, Vec::new);
        let dims = idx.dims();
        self.chunk_counts.par_iter_mut().zip(self.chunk_lists.par_iter_mut()).enumerate().for_each(
            |(ch, (counts, list))| {
                counts.clear();
                list.clear();
                let lo = ch * CHUNK;
                let hi = (lo + CHUNK).min(n);
                for (i, &p) in queries.iter().enumerate().take(hi).skip(lo) {
                    let before = list.len();
                    if let Some(c) = idx.coords(p) {
                        let x0 = c[0].saturating_sub(reach);
                        let x1 = (c[0] + reach).min(dims[0] - 1);
                        let y0 = c[1].saturating_sub(reach);
                        let y1 = (c[1] + reach).min(dims[1] - 1);
                        let z0 = c[2].saturating_sub(reach);
                        let z1 = (c[2] + reach).min(dims[2] - 1);
                        for g in groups {
                            let skip = if same_set && g.offset == 0 { i } else { usize::MAX };
                            for ix in x0..=x1 {
                                for iy in y0..=y1 {
                                    let (a, b) = g.sort.column(ix, iy, z0, z1);
                                    for (off, t) in g.targets[a..b].iter().enumerate() {
                                        let j = a + off;
                                        if j == skip {
                                            continue;
                                        }
                                        if (p - *t).norm2() < r2 {
                                            list.push(g.offset + j as u32);
                                        }
                                    }
                                }
                            }
                        }
                    }
                    counts.push((list.len() - before) as u32);
                }
            },
        );
        self.offsets.clear();
        self.offsets.reserve(n + 1);
        self.offsets.push(0);
        let mut total = 0u32;
        for counts in &self.chunk_counts[..chunks] {
            for &c in counts {
                total += c;
                self.offsets.push(total);
            }
        }
        self.indices.resize(total as usize, 0);
        // Copy each chunk's list into its slot.
        let mut rest: &mut [u32] = &mut self.indices;
        let mut slices = Vec::with_capacity(chunks);
        for list in &self.chunk_lists[..chunks] {
            let (head, tail) = rest.split_at_mut(list.len());
            slices.push(head);
            rest = tail;
        }
        slices
            .into_par_iter()
            .zip(self.chunk_lists[..chunks].par_iter())
            .for_each(|(dst, src)| dst.copy_from_slice(src));
    }
}

impl NeighborList {
    /// Makes `self` the transpose of `other` (queries ↔ targets) over `targets` target points,
    /// listing only targets that appear in `other`: `touched` receives them in ascending order,
    /// and row `k` of `self` holds the queries of `other` that list `touched[k]`, ascending.
    /// `other`'s target indices are then renumbered to rows of `touched`, so both lists index
    /// the same compact per-target arrays.
    pub fn transpose_compact(&mut self, other: &mut NeighborList, targets: usize, touched: &mut Vec<u32>) {
        // Per-target scratch kept between calls and reset only where touched: the cost
        // follows the pairs, not the number of targets.
        let (count, row_of) = (&mut self.count, &mut self.row_of);
        count.resize(targets, 0);
        row_of.resize(targets, u32::MAX);
        touched.clear();
        for &j in &other.indices {
            let c = &mut count[j as usize];
            if *c == 0 {
                touched.push(j);
            }
            *c += 1;
        }
        touched.sort_unstable();
        self.offsets.clear();
        self.offsets.push(0);
        let mut total = 0;
        for (row, &j) in touched.iter().enumerate() {
            row_of[j as usize] = row as u32;
            total += count[j as usize];
            self.offsets.push(total);
        }
        self.indices.resize(total as usize, 0);
        let mut next: Vec<u32> = self.offsets[..touched.len()].to_vec();
        for q in 0..other.offsets.len().saturating_sub(1) {
            for &j in other.of(q) {
                let row = row_of[j as usize] as usize;
                self.indices[next[row] as usize] = q as u32;
                next[row] += 1;
            }
        }
        let row_of = &*row_of;
        other.indices.par_iter_mut().for_each(|j| *j = row_of[*j as usize]);
        for &j in touched.iter() {
            self.count[j as usize] = 0;
            self.row_of[j as usize] = u32::MAX;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::grid::GridSpec;
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let spec = GridSpec::covering([0.0; 3], [1.0, 0.7, 0.5], 0.1);
        let idx = CellIndexer::<f64>::new(&spec);
        let mut pts: Vec<Vec3<f64>> = (0..3000)
            .map(|_| Vec3::new(rng.random::<f64>(), rng.random::<f64>() * 0.7, rng.random::<f64>() * 0.5))
            .collect();
        let mut sort = CellSort::default();
        sort.sort(&idx, &pts);
        let mut tmp = Vec::new();
        super::super::grid::permute(&mut pts, &sort.order, &mut tmp);
        let mut nl = NeighborList::default();
        nl.build(&pts, &idx, &sort, &pts, 0.1, true);
        for i in (0..pts.len()).step_by(37) {
            let mut brute: Vec<u32> =
                (0..pts.len()).filter(|&j| j != i && (pts[i] - pts[j]).norm2() < 0.01).map(|j| j as u32).collect();
            let mut got = nl.of(i).to_vec();
            brute.sort_unstable();
            got.sort_unstable();
            assert_eq!(got, brute, "particle {i}");
        }
        // Symmetric: j in list(i) iff i in list(j).
        for i in 0..pts.len() {
            for &j in nl.of(i) {
                assert!(nl.of(j as usize).contains(&(i as u32)));
            }
        }
        // The transpose of a symmetric list is itself (over touched points), and the
        // renumbered original points at the same targets.
        let original = nl.clone();
        let mut t = NeighborList::default();
        let mut touched = Vec::new();
        t.transpose_compact(&mut nl, pts.len(), &mut touched);
        for (k, &j) in touched.iter().enumerate() {
            let mut a = t.of(k).to_vec();
            let mut b = original.of(j as usize).to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
        }
        for i in 0..pts.len() {
            let renamed: Vec<u32> = nl.of(i).iter().map(|&r| touched[r as usize]).collect();
            assert_eq!(renamed, original.of(i));
        }
    }
}
