//! Uniform cell grid over a fixed domain, rebuilt every step by counting sort.
//!
//! Cells are numbered z-fastest, `(ix * ny + iy) * nz + iz`, so the cells of a column `(ix, iy)`
//! around `iz` are one contiguous range of the sorted particles. The solver uses cells of edge
//! h, half the kernel support: a query scans 5 × 5 contiguous column ranges of 5 cells, a
//! candidate volume of (5h)³ instead of (6h)³ with cells of edge 2h (about 40 % fewer distance
//! checks; measured +7 % on the 100k bench).

use rayon::prelude::*;

use crate::Real;
use crate::math::Vec3;

/// The grid's geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Lower corner of the domain (m).
    pub origin: [f64; 3],
    /// Cell edge (m), at least the kernel support.
    pub cell: f64,
    /// Cells along x, y, z.
    pub dims: [usize; 3],
}

impl GridSpec {
    /// A grid covering `[min, max]` with cells of at least `cell` (m).
    pub fn covering(min: [f64; 3], max: [f64; 3], cell: f64) -> Self {
        let dims = [0, 1, 2].map(|a| (((max[a] - min[a]) / cell).ceil() as usize).max(1));
        Self { origin: min, cell, dims }
    }
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
    /// Upper corner (m).
    pub fn max(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + self.dims[a] as f64 * self.cell)
    }
}

/// Cell lookups in precision `T`.
#[derive(Clone, Copy, Debug)]
pub struct CellIndexer<T> {
    origin: Vec3<T>,
    cell: T,
    inv_cell: T,
    dims: [usize; 3],
}

impl<T: Real> CellIndexer<T> {
    /// From a grid spec.
    pub fn new(spec: &GridSpec) -> Self {
        Self {
            origin: Vec3::of(spec.origin),
            cell: T::of(spec.cell),
            inv_cell: T::one() / T::of(spec.cell),
            dims: spec.dims,
        }
    }
    /// Cell edge (m).
    pub fn cell(&self) -> T {
        self.cell
    }
    /// Integer cell coordinates of a point, or `None` outside the grid (or non-finite).
    #[inline(always)]
    pub fn coords(&self, p: Vec3<T>) -> Option<[usize; 3]> {
        let f = [
            (p.x - self.origin.x) * self.inv_cell,
            (p.y - self.origin.y) * self.inv_cell,
            (p.z - self.origin.z) * self.inv_cell,
        ];
        let mut c = [0usize; 3];
        for a in 0..3 {
            // NaN lands outside.
            if f[a].is_nan() || f[a] < T::zero() {
                return None;
            }
            let i = f[a].floor().as_f64() as usize;
            if i >= self.dims[a] {
                return None;
            }
            c[a] = i;
        }
        Some(c)
    }
    /// Linear index of cell coordinates.
    #[inline(always)]
    pub fn linear(&self, c: [usize; 3]) -> usize {
        (c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]
    }
    /// Grid dimensions.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
}

/// The result of a counting sort: particles grouped by cell, over the window of the grid
/// their cells span (so that sorting a few particles in a large grid costs what the few
/// cost, not what the grid does).
#[derive(Clone, Debug, Default)]
pub struct CellSort {
    /// Lower corner of the window (cell coordinates).
    lo: [usize; 3],
    /// Window size (cells); zero when no point is inside the grid.
    dims: [usize; 3],
    /// `start[c]..start[c + 1]` are the sorted indices of window cell `c`; the last entry is
    /// the number of points inside the grid (those outside come last).
    start: Vec<u32>,
    /// `order[k]` is the old index of the point now at position `k`.
    pub order: Vec<u32>,
    /// Scratch: the cell of each point before sorting (grid-linear, then window-linear).
    cell_of: Vec<u32>,
    next: Vec<u32>,
}

impl CellSort {
    /// Bytes the sort's arrays reserve.
    pub(super) fn heap_bytes(&self) -> usize {
        [&self.start, &self.order, &self.cell_of, &self.next].iter().map(|v| v.capacity()).sum::<usize>()
            * size_of::<u32>()
    }

    /// Sorts points by cell (stable within a cell). Points outside the grid go to the end.
    pub fn sort<T: Real>(&mut self, idx: &CellIndexer<T>, pos: &[Vec3<T>]) {
        const OUT: u32 = u32::MAX;
        self.cell_of.resize(pos.len(), 0);
        let (lo, hi) = self
            .cell_of
            .par_iter_mut()
            .zip(pos.par_iter())
            .map(|(c, p)| match idx.coords(*p) {
                Some(c3) => {
                    *c = idx.linear(c3) as u32;
                    (c3, c3)
                }
                None => {
                    *c = OUT;
                    ([usize::MAX; 3], [0; 3])
                }
            })
            .reduce(
                || ([usize::MAX; 3], [0; 3]),
                |a, b| ([0, 1, 2].map(|k| a.0[k].min(b.0[k])), [0, 1, 2].map(|k| a.1[k].max(b.1[k]))),
            );
        let any = lo[0] != usize::MAX;
        self.lo = if any { lo } else { [0; 3] };
        self.dims = if any { [0, 1, 2].map(|k| hi[k] - lo[k] + 1) } else { [0; 3] };
        let cells = self.dims[0] * self.dims[1] * self.dims[2];
        let outside = cells as u32;
        let (g, w, o) = (idx.dims(), self.dims, self.lo);
        self.cell_of.par_iter_mut().for_each(|c| {
            *c = if *c == OUT {
                outside
            } else {
                let c0 = *c as usize;
                let (x, y, z) = (c0 / (g[1] * g[2]), c0 / g[2] % g[1], c0 % g[2]);
                (((x - o[0]) * w[1] + (y - o[1])) * w[2] + (z - o[2])) as u32
            }
        });
        self.start.clear();
        self.start.resize(cells + 2, 0);
        for &c in &self.cell_of {
            self.start[c as usize + 1] += 1;
        }
        for c in 0..=cells {
            self.start[c + 1] += self.start[c];
        }
        self.order.resize(pos.len(), 0);
        self.next.clear();
        self.next.extend_from_slice(&self.start[..=cells]);
        for (i, &c) in self.cell_of.iter().enumerate() {
            let slot = &mut self.next[c as usize];
            self.order[*slot as usize] = i as u32;
            *slot += 1;
        }
        self.start.truncate(cells + 1);
    }

    /// The sorted index range of the cells `(ix, iy, z0..=z1)` (grid coordinates): one
    /// contiguous run, empty where the column misses the window.
    #[inline(always)]
    pub fn column(&self, ix: usize, iy: usize, z0: usize, z1: usize) -> (usize, usize) {
        let (lo, d) = (self.lo, self.dims);
        if ix < lo[0] || ix >= lo[0] + d[0] || iy < lo[1] || iy >= lo[1] + d[1] {
            return (0, 0);
        }
        let za = z0.max(lo[2]);
        let zb = z1.min(lo[2] + d[2] - 1);
        if za > zb {
            return (0, 0);
        }
        let base = ((ix - lo[0]) * d[1] + (iy - lo[1])) * d[2];
        (self.start[base + za - lo[2]] as usize, self.start[base + zb - lo[2] + 1] as usize)
    }

    /// Number of points inside the grid.
    pub fn inside(&self) -> usize {
        self.start.last().copied().unwrap_or(0) as usize
    }
}

/// Reorders `v` so that `v_new[k] = v_old[order[k]]`, using `tmp` as scratch.
#[cfg(test)]
pub fn permute<X: Copy + Send + Sync + Default>(v: &mut Vec<X>, order: &[u32], tmp: &mut Vec<X>) {
    tmp.clear();
    tmp.resize(v.len(), X::default());
    tmp.par_iter_mut().zip(order.par_iter()).for_each(|(t, &o)| *t = v[o as usize]);
    std::mem::swap(v, tmp);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counting_sort_groups_by_cell_and_puts_outsiders_last() {
        let spec = GridSpec::covering([0.0; 3], [1.0, 1.0, 1.0], 0.25);
        assert_eq!(spec.dims, [4, 4, 4]);
        let idx = CellIndexer::<f64>::new(&spec);
        let pts = vec![
            Vec3::new(0.9, 0.9, 0.9),
            Vec3::new(0.1, 0.1, 0.1),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.1, 0.1, 0.2),
            Vec3::new(f64::NAN, 0.0, 0.0),
            Vec3::new(0.1, 0.1, 0.3),
        ];
        let mut s = CellSort::default();
        s.sort(&idx, &pts);
        assert_eq!(s.inside(), 4);
        assert_eq!(&s.order[..4], &[1, 3, 5, 0]);
        // z-fastest: cells (0,0,0) and (0,0,1) are adjacent in the order.
        assert_eq!(idx.linear([0, 0, 1]), idx.linear([0, 0, 0]) + 1);
        assert_eq!(s.column(0, 0, 0, 0), (0, 2));
        assert_eq!(s.column(0, 0, 0, 3), (0, 3));
        // Outside the window of occupied cells, columns are empty.
        assert_eq!(s.column(1, 0, 0, 3), (3, 3));
        assert_eq!(s.column(0, 2, 0, 3), (3, 3));
        assert_eq!(s.column(3, 3, 3, 3), (3, 4));
        let mut empty = CellSort::default();
        empty.sort(&idx, &[Vec3::new(5.0, 0.0, 0.0)]);
        assert_eq!((empty.inside(), empty.column(0, 0, 0, 3)), (0, (0, 0)));
        let mut v: Vec<u32> = (0..6).collect();
        let mut tmp = Vec::new();
        permute(&mut v, &s.order, &mut tmp);
        assert_eq!(&v[..4], &[1, 3, 5, 0]);
    }
}
