//! The soil surface height on a coarse grid, from the initial particles: where vehicles are
//! lowered to and what wheel sinkage is measured from.

/// The soil surface height on a grid of cells of one spacing: the top of the highest
/// particle's cell in each column.
#[derive(Clone, Debug)]
pub struct SurfaceGrid {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    top: Vec<f64>,
}

impl SurfaceGrid {
    /// From particle centres with spacing `d0`.
    pub fn new(points: impl Iterator<Item = [f64; 3]> + Clone, d0: f64) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points.clone() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !lo[0].is_finite() {
            return Self { origin: [0.0; 2], cell: d0, nx: 0, ny: 0, top: Vec::new() };
        }
        let mut g = Self::covering(lo, hi, d0);
        g.add(points);
        g
    }

    /// An empty grid (no soil anywhere yet) for particle centres in `[lo, hi]` (x, y).
    pub fn covering(lo: [f64; 2], hi: [f64; 2], d0: f64) -> Self {
        let origin = [lo[0] - 0.5 * d0, lo[1] - 0.5 * d0];
        let nx = ((hi[0] - origin[0]) / d0).floor() as usize + 1;
        let ny = ((hi[1] - origin[1]) / d0).floor() as usize + 1;
        Self { origin, cell: d0, nx, ny, top: vec![f64::NEG_INFINITY; nx * ny] }
    }

    /// Raises the surface to the tops of these particles' cells (points off the grid count
    /// in its edge cells).
    pub fn add(&mut self, points: impl Iterator<Item = [f64; 3]>) {
        if self.nx == 0 {
            return;
        }
        let (o, d0, nx, ny) = (self.origin, self.cell, self.nx, self.ny);
        for p in points {
            let i = ((p[0] - o[0]) / d0).floor().clamp(0.0, (nx - 1) as f64) as usize;
            let j = ((p[1] - o[1]) / d0).floor().clamp(0.0, (ny - 1) as f64) as usize;
            self.top[j * nx + i] = self.top[j * nx + i].max(p[2] + 0.5 * d0);
        }
    }

    /// Highest surface within `r` of `(x, y)` (`None` off the soil).
    pub fn height(&self, x: f64, y: f64, r: f64) -> Option<f64> {
        if self.nx == 0 {
            return None;
        }
        let idx = |v: f64, o: f64, n: usize| ((v - o) / self.cell).floor().clamp(0.0, (n - 1) as f64) as usize;
        let (i0, i1) = (idx(x - r, self.origin[0], self.nx), idx(x + r, self.origin[0], self.nx));
        let (j0, j1) = (idx(y - r, self.origin[1], self.ny), idx(y + r, self.origin[1], self.ny));
        // Off the grid on any side is off the soil (not the edge column, clamped).
        let far = [self.origin[0] + self.nx as f64 * self.cell, self.origin[1] + self.ny as f64 * self.cell];
        if x + r < self.origin[0] || y + r < self.origin[1] || x - r > far[0] || y - r > far[1] {
            return None;
        }
        let mut best = f64::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                best = best.max(self.top[j * self.nx + i]);
            }
        }
        best.is_finite().then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_the_grid_on_any_side_is_off_the_soil() {
        // A 4 x 4 patch of columns at 0.1 m spacing, x and y in [0.05, 0.35], top at z = 0.25.
        let pts: Vec<[f64; 3]> =
            (0..4).flat_map(|i| (0..4).map(move |j| [0.05 + 0.1 * i as f64, 0.05 + 0.1 * j as f64, 0.2])).collect();
        let g = SurfaceGrid::new(pts.iter().copied(), 0.1);
        assert_eq!(g.height(0.2, 0.2, 0.0), Some(0.25));
        for (x, y) in [(-0.5, 0.2), (0.2, -0.5), (0.9, 0.2), (0.2, 0.9)] {
            assert_eq!(g.height(x, y, 0.05), None, "({x}, {y})");
        }
        // Within r of the edge still sees the edge column.
        assert_eq!(g.height(0.45, 0.2, 0.1), Some(0.25));
    }
}
