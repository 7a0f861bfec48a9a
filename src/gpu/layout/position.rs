//! **Positions: integer cell + f32 offset.** f32 absolute positions ~1e4 diameters from
//! the origin are spaced as coarsely as the overlaps that decide the forces, so a particle
//! is an integer cell ([`CellCoord`], w = material) and an f32 offset inside it
//! ([`CellOffset`], in `[0, h)`, w = radius). Separations are formed as
//! `(cell_i - cell_j) * h + (off_i - off_j)`: the integer difference is exact, so an
//! overlap keeps f32's relative precision (`h * 2^-24`) anywhere in a domain of up to
//! `2^31` cells per axis. The cell width `h` (from the domain's min corner, fixed for a
//! run) is the neighbour grid's ([`crate::gpu::grid`]); encode with the f32 value the
//! kernels see ([`gpu_cell_width`]).

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// Integer cell of a particle: xyz = cell coordinates, w = material index (in the engine's
/// state with `gpu::state::NOT_APPEARED` added until the particle appears). WGSL: `vec4<i32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CellCoord(pub [i32; 4]);

/// Position inside the cell: xyz in `[0, h)`, w = radius. WGSL: `vec4<f32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CellOffset(pub [f32; 4]);

/// The f32-representable cell width nearest `h`: what the kernels will see.
pub fn gpu_cell_width(h: f64) -> f64 {
    h as f32 as f64
}

/// Splits an absolute position into its cell (relative to `origin`, width `h`) and the
/// f32 offset inside it, each component in `[0, h)`. The w components are 0; set them
/// to the material index and the radius (or use [`PackedPosition::new`]).
///
/// The offset is rounded to the nearest f32; when that rounds up to `h` itself the
/// particle moves to the next cell with offset 0, so `0 <= offset < h` always holds.
/// Cells beyond the i32 range saturate (positions there are not representable).
pub fn encode(p: DVec3, origin: DVec3, h: f64) -> ([i32; 4], [f32; 4]) {
    encode3(p, origin, DVec3::splat(h))
}

/// [`encode`] with a cell width per axis.
pub fn encode3(p: DVec3, origin: DVec3, hs: DVec3) -> ([i32; 4], [f32; 4]) {
    let mut cell = [0i32; 4];
    let mut offset = [0f32; 4];
    for axis in 0..3 {
        let h = hs[axis];
        let h32 = h as f32;
        let rel = p[axis] - origin[axis];
        let mut c = (rel / h).floor();
        // Offset taken in f64 from the cell's corner; exact up to f64 rounding of rel.
        let mut o = rel - c * h;
        // (rel / h).floor() can be off by one next to a cell face.
        if o < 0.0 {
            c -= 1.0;
            o += h;
        } else if o >= h {
            c += 1.0;
            o -= h;
        }
        let mut o32 = o as f32;
        if o32 >= h32 || (o32 as f64) >= h {
            c += 1.0;
            o32 = 0.0;
        }
        cell[axis] = c as i32;
        offset[axis] = o32.max(0.0);
    }
    (cell, offset)
}

/// Absolute position of a cell and offset (w components ignored).
pub fn decode(cell: [i32; 4], offset: [f32; 4], origin: DVec3, h: f64) -> DVec3 {
    decode3(cell, offset, origin, DVec3::splat(h))
}

/// [`decode`] with a cell width per axis.
pub fn decode3(cell: [i32; 4], offset: [f32; 4], origin: DVec3, h: DVec3) -> DVec3 {
    DVec3::new(
        origin.x + (cell[0] as f64) * h.x + offset[0] as f64,
        origin.y + (cell[1] as f64) * h.y + offset[1] as f64,
        origin.z + (cell[2] as f64) * h.z + offset[2] as f64,
    )
}

/// A particle's position with its material (cell.w) and radius (offset.w).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PackedPosition {
    /// Integer cell; w = material index (see [`CellCoord`]).
    pub cell: CellCoord,
    /// Offset inside the cell, m; w = radius, m.
    pub offset: CellOffset,
}

impl PackedPosition {
    /// Encodes position `p` (m) on the grid at `origin` with cell width `h` (see [`encode`]),
    /// with `material` in cell.w and `radius` (m, rounded to f32) in offset.w.
    pub fn new(p: DVec3, origin: DVec3, h: f64, material: u32, radius: f64) -> Self {
        let (mut cell, mut offset) = encode(p, origin, h);
        cell[3] = material as i32;
        offset[3] = radius as f32;
        Self {
            cell: CellCoord(cell),
            offset: CellOffset(offset),
        }
    }

    /// The absolute position, m, on the grid at `origin` with cell width `h` (see [`decode`]).
    pub fn position(&self, origin: DVec3, h: f64) -> DVec3 {
        decode(self.cell.0, self.offset.0, origin, h)
    }

    /// The material index (cell.w without `NOT_APPEARED`).
    pub fn material(&self) -> u32 {
        (self.cell.0[3] & !crate::gpu::state::NOT_APPEARED) as u32
    }

    /// The radius, m (offset.w).
    pub fn radius(&self) -> f32 {
        self.offset.0[3]
    }
}

/// The vector from particle j to particle i as the kernels form it, in f32:
/// `(cell_i - cell_j) * h + (off_i - off_j)`.
pub fn separation_f32(
    cell_i: [i32; 4],
    off_i: [f32; 4],
    cell_j: [i32; 4],
    off_j: [f32; 4],
    h: f32,
) -> [f32; 3] {
    let mut d = [0f32; 3];
    for axis in 0..3 {
        let dc = cell_i[axis].wrapping_sub(cell_j[axis]) as f32;
        d[axis] = dc * h + (off_i[axis] - off_j[axis]);
    }
    d
}
