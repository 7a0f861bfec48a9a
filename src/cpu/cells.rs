//! Linked-cell neighbour search (O(N)): particles binned into cubic cells at least as wide
//! as the largest interaction distance, pairs taken from the 27 surrounding cells.

use glam::DVec3;

/// A uniform grid over a box; positions outside the box are clamped into the edge cells,
/// which keeps every pair closer than one cell width in the same or adjacent cells.
#[derive(Clone, Debug)]
pub struct CellGrid {
    origin: DVec3,
    inv_width: f64,
    dims: [usize; 3],
    /// First particle of each cell (usize::MAX = empty).
    head: Vec<usize>,
    /// Next particle in the same cell.
    next: Vec<usize>,
    /// Periodic axes: neighbour cells wrap around (needs at least 3 cells on the axis).
    periodic: [bool; 3],
}

const EMPTY: usize = usize::MAX;

impl CellGrid {
    /// A grid over [min, max] with cells at least `cutoff` wide, and no more cells than
    /// a few per particle (sparse scenes would otherwise pay for empty cells).
    pub fn new(min: DVec3, max: DVec3, cutoff: f64, particles: usize) -> Self {
        Self::with_widest(min, max, cutoff, particles, f64::INFINITY)
    }

    /// As [`Self::new`] with cells no wider than `widest` (where that is above `cutoff`).
    fn with_widest(min: DVec3, max: DVec3, cutoff: f64, particles: usize, widest: f64) -> Self {
        let extent = (max - min).max(DVec3::splat(cutoff));
        let target_cells = (4 * particles).max(64) as f64;
        let by_count = (extent.x * extent.y * extent.z / target_cells).cbrt();
        let width = cutoff.max(by_count.min(widest));
        let dim = |e: f64| ((e / width).floor() as usize).clamp(1, 1 << 20);
        let dims = [dim(extent.x), dim(extent.y), dim(extent.z)];
        Self {
            origin: min,
            inv_width: 1.0 / width,
            dims,
            head: vec![EMPTY; dims[0] * dims[1] * dims[2]],
            next: Vec::new(),
            periodic: [false; 3],
        }
    }

    /// As [`Self::new`] with periodic axes; `None` when a periodic axis has fewer than 3
    /// cells (the box is shorter than 3 cut-offs there: a pair would meet two images).
    pub fn periodic(
        min: DVec3,
        max: DVec3,
        cutoff: f64,
        particles: usize,
        periodic: [bool; 3],
    ) -> Option<Self> {
        // (cells widened for a sparse scene are narrowed to three along each periodic axis)
        let widest = (0..3)
            .filter(|&a| periodic[a])
            .map(|a| (max[a] - min[a]) / 3.0 * (1.0 - 1e-12))
            .fold(f64::INFINITY, f64::min);
        let mut g = Self::with_widest(min, max, cutoff, particles, widest);
        if (0..3).any(|a| periodic[a] && g.dims[a] < 3) {
            return None;
        }
        g.periodic = periodic;
        Some(g)
    }

    /// The cells' width (at least the cut-off; wider where cells are capped by count).
    pub fn width(&self) -> f64 {
        1.0 / self.inv_width
    }

    fn coord(&self, p: DVec3) -> [usize; 3] {
        let c = (p - self.origin) * self.inv_width;
        let clamp = |x: f64, n: usize| {
            if x.is_nan() || x < 0.0 {
                0
            } else {
                (x as usize).min(n - 1)
            }
        };
        [
            clamp(c.x, self.dims[0]),
            clamp(c.y, self.dims[1]),
            clamp(c.z, self.dims[2]),
        ]
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// The cell a position is binned into.
    pub fn cell_of(&self, p: DVec3) -> usize {
        self.index(self.coord(p))
    }

    /// Bins all particles (in reverse, so each cell lists its particles in ascending order).
    pub fn rebuild(&mut self, positions: &[DVec3]) {
        let cells: Vec<usize> = positions.iter().map(|&p| self.cell_of(p)).collect();
        self.link(&cells);
    }

    /// Bins particle i into `cells[i]` (each from [`Self::cell_of`], computed by the caller,
    /// e.g. in parallel): the linking itself, in reverse, so each cell lists its particles
    /// in ascending order.
    pub fn link(&mut self, cells: &[usize]) {
        self.head.fill(EMPTY);
        self.next.clear();
        self.next.resize(cells.len(), EMPTY);
        for (i, &cell) in cells.iter().enumerate().rev() {
            self.next[i] = self.head[cell];
            self.head[cell] = i;
        }
    }

    /// Calls `f(j)` for every particle binned in the 27 cells around `p`'s cell (wrapped
    /// on periodic axes), in a fixed order (neighbour cells in a fixed order, then cell
    /// order). Every particle closer to `p` than one cell width is among them (each once).
    #[inline]
    pub fn for_each_near(&self, p: DVec3, mut f: impl FnMut(usize)) {
        // the neighbour cell along axis a, wrapped on periodic axes, or None off the grid
        let along = |a: usize, c: usize, d: i64| -> Option<usize> {
            let n = self.dims[a] as i64;
            let x = c as i64 + d;
            if self.periodic[a] {
                Some(x.rem_euclid(n) as usize)
            } else {
                (0..n).contains(&x).then_some(x as usize)
            }
        };
        let c = self.coord(p);
        for dz in -1i64..=1 {
            let Some(z) = along(2, c[2], dz) else {
                continue;
            };
            for dy in -1i64..=1 {
                let Some(y) = along(1, c[1], dy) else {
                    continue;
                };
                for dx in -1i64..=1 {
                    let Some(x) = along(0, c[0], dx) else {
                        continue;
                    };
                    let mut j = self.head[self.index([x, y, z])];
                    while j != EMPTY {
                        f(j);
                        j = self.next[j];
                    }
                }
            }
        }
    }

    /// Calls `f(i, j)` once for every candidate pair i < j, in a fixed order
    /// (i ascending, then neighbour cells in a fixed order, then cell order).
    pub fn for_each_pair(&self, positions: &[DVec3], mut f: impl FnMut(usize, usize)) {
        for (i, &p) in positions.iter().enumerate() {
            self.for_each_near(p, |j| {
                if j > i {
                    f(i, j);
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn finds_exactly_the_pairs_within_cutoff() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let pts: Vec<DVec3> = (0..400)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * 1.2 - 0.1)
            .collect();
        let cutoff = 0.08;
        let mut grid = CellGrid::new(DVec3::ZERO, DVec3::ONE, cutoff, pts.len());
        grid.rebuild(&pts);
        let mut found = Vec::new();
        grid.for_each_pair(&pts, |i, j| {
            if pts[i].distance(pts[j]) < cutoff {
                found.push((i, j))
            }
        });
        let mut brute = Vec::new();
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                if pts[i].distance(pts[j]) < cutoff {
                    brute.push((i, j));
                }
            }
        }
        found.sort();
        assert_eq!(found, brute);
        assert!(!brute.is_empty());
    }

    /// A sparse scene's cells, widened by the particle count, still give a periodic axis
    /// three cells where three cut-offs fit (two particles in a 1 × 1 × 4 m box were
    /// refused as "shorter than 3 interaction cut-offs" of 6 cm).
    #[test]
    fn sparse_periodic_grids_keep_three_cells() {
        let (min, max) = (DVec3::ZERO, DVec3::new(1.0, 1.0, 4.0));
        let periodic = [true, true, false];
        let g = CellGrid::periodic(min, max, 0.06, 2, periodic).expect("three cells fit");
        assert!(g.dims[0] >= 3 && g.dims[1] >= 3, "{:?}", g.dims);
        assert!(CellGrid::periodic(min, max, 0.34, 2, periodic).is_none());
    }
}
