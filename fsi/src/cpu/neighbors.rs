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
///
/// The entries stay in the per-chunk vectors the parallel build filled (queries
/// `k·CHUNK..(k+1)·CHUNK` in chunk `k`): concatenating them into one array would hold every
/// list twice, the chunks being kept between builds so that a rebuild does not allocate.
#[derive(Clone, Debug, Default)]
pub struct NeighborList {
    /// `offsets[i]..offsets[i + 1]` are query `i`'s entries, counted over the whole list.
    offsets: Vec<u32>,
    /// The entries of each chunk of queries, in query order; chunk `k` starts at entry
    /// `offsets[k·CHUNK]`.
    chunks: Vec<Vec<u32>>,
    /// Transpose scratch, one entry per target, zero (and `u32::MAX`) between calls.
    count: Vec<u32>,
    row_of: Vec<u32>,
}

const CHUNK: usize = 512;

/// Sizes `chunks` for `rows` queries, dropping chunks left over from a larger build; with
/// `offsets` (the whole list's, filled) each chunk is also resized to hold its entries.
fn size_chunks(chunks: &mut Vec<Vec<u32>>, rows: usize, offsets: Option<&[u32]>) {
    let n = rows.div_ceil(CHUNK);
    chunks.truncate(n);
    chunks.resize_with(n, Vec::new);
    if let Some(offsets) = offsets {
        for (k, c) in chunks.iter_mut().enumerate() {
            let len = offsets[((k + 1) * CHUNK).min(rows)] - offsets[k * CHUNK];
            c.clear();
            c.resize(len as usize, 0);
        }
    }
}

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
    /// Bytes the list's arrays reserve: the offsets, the entries' chunks and the transpose
    /// scratch.
    pub(super) fn heap_bytes(&self) -> usize {
        [&self.offsets, &self.count, &self.row_of].into_iter().chain(&self.chunks).map(|v| v.capacity()).sum::<usize>()
            * size_of::<u32>()
    }

    /// Neighbours of `i`.
    #[inline(always)]
    pub fn of(&self, i: usize) -> &[u32] {
        let c = i / CHUNK;
        let base = self.offsets[c * CHUNK];
        &self.chunks[c][(self.offsets[i] - base) as usize..(self.offsets[i + 1] - base) as usize]
    }

    /// Total number of pairs.
    pub fn pairs(&self) -> usize {
        self.offsets.last().map_or(0, |&n| n as usize)
    }

    /// A list from its rows (query `i` lists `rows[i]`).
    #[cfg(test)]
    pub fn from_rows(rows: &[Vec<u32>]) -> Self {
        let mut nl = Self { offsets: vec![0], ..Self::default() };
        for (k, row) in rows.iter().enumerate() {
            if k % CHUNK == 0 {
                nl.chunks.push(Vec::new());
            }
            nl.chunks[k / CHUNK].extend_from_slice(row);
            nl.offsets.push(nl.offsets[k] + row.len() as u32);
        }
        nl
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
        size_chunks(&mut self.chunks, n, None);
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        let dims = idx.dims();
        // Each chunk lists its queries' targets and writes each query's end within the chunk.
        self.offsets[1..].par_chunks_mut(CHUNK).zip(self.chunks.par_iter_mut()).enumerate().for_each(
            |(ch, (ends, list))| {
                list.clear();
                let lo = ch * CHUNK;
                for (k, end) in ends.iter_mut().enumerate() {
                    let i = lo + k;
                    let p = queries[i];
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
                    *end = list.len() as u32;
                }
                // A vector that grew by doubling may hold up to twice its entries; give back
                // what the next build is unlikely to need (it keeps 1/8 to grow into).
                let len = list.len();
                if list.capacity() > len + len / 2 {
                    list.shrink_to(len + len / 8);
                }
            },
        );
        // Chunk-local ends to whole-list offsets.
        let mut base = 0;
        for ends in self.offsets[1..].chunks_mut(CHUNK) {
            for e in ends.iter_mut() {
                *e += base;
            }
            base = ends.last().copied().unwrap_or(base);
        }
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
        for &j in other.chunks.iter().flatten() {
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
        let rows = touched.len();
        size_chunks(&mut self.chunks, rows, Some(&self.offsets));
        let mut next: Vec<u32> = self.offsets[..rows].to_vec();
        for q in 0..other.offsets.len().saturating_sub(1) {
            for &j in other.of(q) {
                let row = row_of[j as usize] as usize;
                let c = row / CHUNK;
                self.chunks[c][(next[row] - self.offsets[c * CHUNK]) as usize] = q as u32;
                next[row] += 1;
            }
        }
        let row_of = &*row_of;
        other.chunks.par_iter_mut().for_each(|c| c.iter_mut().for_each(|j| *j = row_of[*j as usize]));
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
