//! A uniform hash grid of points for O(N) neighbour checks (overlaps at load time,
//! random placement).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

pub(super) fn sq(x: f64) -> f64 {
    x * x
}

pub(super) fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    sq(a[0] - b[0]) + sq(a[1] - b[1]) + sq(a[2] - b[2])
}

/// FxHash-style hasher for integer cell keys.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
}

type Cell = (i64, i64, i64);

pub(crate) struct Grid {
    cell: f64,
    map: HashMap<Cell, Vec<usize>, BuildHasherDefault<CellHasher>>,
}

impl Grid {
    pub(crate) fn new(cell: f64) -> Self {
        Self {
            cell: if cell > 0.0 { cell } else { 1.0 },
            map: HashMap::default(),
        }
    }

    fn cell_of(&self, p: [f64; 3]) -> Cell {
        let c = |x: f64| (x / self.cell).floor() as i64;
        (c(p[0]), c(p[1]), c(p[2]))
    }

    pub(crate) fn insert(&mut self, i: usize, p: [f64; 3]) {
        let c = self.cell_of(p);
        self.map.entry(c).or_default().push(i);
    }

    /// Indices of all points in cells that may hold a point within `reach` of `p`.
    pub(crate) fn neighbours(&self, p: [f64; 3], reach: f64) -> impl Iterator<Item = usize> + '_ {
        let lo = self.cell_of([p[0] - reach, p[1] - reach, p[2] - reach]);
        let hi = self.cell_of([p[0] + reach, p[1] + reach, p[2] + reach]);
        (lo.0..=hi.0).flat_map(move |x| {
            (lo.1..=hi.1).flat_map(move |y| {
                (lo.2..=hi.2).flat_map(move |z| {
                    self.map
                        .get(&(x, y, z))
                        .map(|v| v.as_slice())
                        .unwrap_or(&[])
                        .iter()
                        .copied()
                })
            })
        })
    }

    /// [`Self::neighbours`] of `p` and of its images a period away on the axes with a
    /// period (`periods[a]`: `Some(L)` on a periodic axis), each index once.
    pub(crate) fn near_images(
        &self,
        p: [f64; 3],
        reach: f64,
        periods: [Option<f64>; 3],
    ) -> Vec<usize> {
        let shifts = |a: usize| match periods[a] {
            Some(l) => vec![-l, 0.0, l],
            None => vec![0.0],
        };
        let (sx, sy, sz) = (shifts(0), shifts(1), shifts(2));
        let mut near = Vec::new();
        for &ox in &sx {
            for &oy in &sy {
                for &oz in &sz {
                    near.extend(self.neighbours([p[0] + ox, p[1] + oy, p[2] + oz], reach));
                }
            }
        }
        near.sort_unstable();
        near.dedup();
        near
    }
}
