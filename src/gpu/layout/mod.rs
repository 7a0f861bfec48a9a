//! Memory layout shared by the host and the kernels: the particle position
//! representation (`position`), each contact law's and sub-model's pair-table row
//! (`pair_rows`) and the uniform blocks, as `#[repr(C)]` bytemuck structs whose WGSL twins
//! are generated from them (`wgsl`; the tests check the two layouts against naga's).

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

mod pair_rows;
mod position;
mod solver_consts;
#[cfg(test)]
mod tests;
mod wgsl;

pub use pair_rows::*;
pub use position::*;
pub use solver_consts::*;
pub use wgsl::{
    declarations, shared_consts, shared_structs, Pad, SharedStruct, WgslField, WgslLiteral,
    WgslMember, WgslStruct, WgslType,
};
pub(crate) use wgsl::{wgsl_consts, wgsl_struct};

wgsl_struct! {
/// Grid parameters of a run (the uniform `grid`). The grid's origin, the domain's min
/// corner, is implicit: cells are integer coordinates relative to it.
#[wgsl("GridParams")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridParams {
    /// Cells per axis.
    pub dims: [u32; 3],
    /// Particles in the run.
    pub n_particles: u32,
    /// Cell width per axis (equal unless periodic axes fix it to the period over the
    /// cell count).
    pub cell_width: [f32; 3],
    /// `dims[0] * dims[1] * dims[2]`.
    pub n_cells: u32,
    /// The windows ([`crate::gpu::window::Windows::params`]): shift (k >> shift is
    /// particle k's window), len (particles a window holds), rec_shift (where a record
    /// index's window bits start), the `state` buffer's fields.
    pub window: [u32; 4],
}
}

wgsl_struct! {
/// One level of the exclusive scan (`shaders/grid.wgsl`).
#[wgsl("ScanParams")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ScanParams {
    /// Elements at this level.
    pub n: u32,
    /// Workgroups doing real work: `ceil(n / SCAN_BLOCK)`.
    pub n_blocks: u32,
    /// Where the elements start in the input (elements).
    pub in_offset: u32,
    /// Where they go in the output (elements).
    pub out_offset: u32,
}
}

wgsl_struct! {
/// Per-run step parameters (the uniform `step`).
#[wgsl("StepParams")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StepParams {
    /// Time step, s.
    pub dt: f32,
    /// Entries the neighbour lists have room for (each per-entry array).
    pub list_capacity: u32,
    /// Materials in the pair-model table (n_materials × n_materials rows).
    pub n_materials: u32,
    /// Walls in the wall buffer.
    pub n_walls: u32,
    /// Gravity, m/s², at offset 16 rather than 0 (why: `docs/design_log.md`,
    /// *Measurements moved out of the code*).
    pub gravity: [f32; 3],
    /// Largest distance beyond touching at which any pair interacts (non-contact range or
    /// JKR neck), m, plus the f32 slack of the neighbour search's separations (a few ulp
    /// of the cell width); pairs farther apart than r_i + r_j + reach exert no force.
    pub reach: f32,
    /// The domain box's extent in cells (the run monitor's escape check).
    pub extent_cells: [f32; 3],
    /// 1 when some wall is servo-controlled: the force kernel then writes each wall
    /// entry's push (`store_wall_push`).
    pub servo_walls: u32,
    /// 1 on periodic axes: cells wrap around (the axis holds a whole number ≥ 3 of cells,
    /// so dims·cell_width is the period) and separations take the nearest image.
    pub periodic: [u32; 3],
    /// Always 0: the kernels read it to hide values from the shader compiler, so Kahan
    /// compensations are not folded away (see `opaque` in `shaders/step/shared.wgsl`).
    pub zero: u32,
    /// The Verlet skin, m: a rebuild comes once a particle (or a moving wall, along its
    /// normal) has moved more than half of it.
    pub skin: f32,
    /// 1 when the force jumps of a variant that places them are placed (0 for the initial
    /// forces, whose contacts crossed nothing).
    pub jumps: u32,
    /// Pads `period_lo` to its 16-byte alignment.
    pub _pad: Pad<2>,
    /// Per periodic axis, the scene's period less the device's, L − dims·h, m (h is
    /// rounded to f32): a wrap and a separation across the seam add it (0 elsewhere).
    pub period_lo: [f32; 3],
    /// Pads the struct to WGSL's 16-byte size multiple.
    pub _pad_end: u32,
}
}

wgsl_struct! {
/// A planar wall: a point as cell + offset and the unit normal (`walls` in
/// `shaders/step/shared.wgsl`).
#[wgsl("Wall")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WallGpu {
    /// A point of the plane: integer cell (xyz), w unused.
    pub cell: [i32; 4],
    /// A point of the plane: offset inside the cell (xyz), m; w: the plane's rounding
    /// residual n·(encoded − true point), m, which the kernels' overlap subtracts (a wall the
    /// device moves books each move's rounding into it).
    pub offset: [f32; 4],
    /// Unit normal pointing into the domain (xyz); w unused.
    pub normal: [f32; 4],
    /// Velocity over the current step (xyz).
    pub velocity: [f32; 4],
    /// x: [`WALL_FIXED`], [`WALL_PRESCRIBED`] or [`WALL_SERVO`]; y, z, w: the servo's
    /// force (N), gain (m/s per N) and largest speed (m/s).
    pub motion: [f32; 4],
    /// The unit normal's f32 rounding residual (xyz, true − stored); w unused. The kernels'
    /// wall overlap adds it, so a tilted plane does not turn about its stored point.
    pub normal_lo: [f32; 4],
}
}

wgsl_consts! {
    /// Wall motion kinds of [`WallGpu::motion`].
    pub WALL_MOTIONS: f32 = {
        /// The wall is at rest.
        WALL_FIXED = 0.0,
        /// The wall moves with a prescribed velocity schedule.
        WALL_PRESCRIBED = 1.0,
        /// The wall is servo-controlled to hold a target force.
        WALL_SERVO = 2.0,
    }
}

impl WallGpu {
    /// A fixed wall through `point` (m) with normal `normal` (normalised here), encoded on the
    /// grid at `origin` with cell widths `h`.
    pub fn new(point: DVec3, normal: DVec3, origin: DVec3, h: DVec3) -> Self {
        let (cell, mut offset) = encode3(point, origin, h);
        let n = normal.normalize();
        let n32 = DVec3::new(n.x as f32 as f64, n.y as f32 as f64, n.z as f32 as f64);
        offset[3] = n32.dot(decode3(cell, offset, origin, h) - point) as f32;
        Self {
            cell,
            offset,
            normal: [n.x as f32, n.y as f32, n.z as f32, 0.0],
            velocity: [0.0; 4],
            motion: [WALL_FIXED, 0.0, 0.0, 0.0],
            normal_lo: [
                (n.x - n32.x) as f32,
                (n.y - n32.y) as f32,
                (n.z - n32.z) as f32,
                0.0,
            ],
        }
    }

    /// A scene wall at time 0.
    pub fn from_scene(w: &crate::scene::Wall, origin: DVec3, h: DVec3) -> Self {
        let mut g = Self::new(
            DVec3::from_array(w.point),
            DVec3::from_array(w.normal),
            origin,
            h,
        );
        g.motion = Self::motion_code(w.motion.at(0.0));
        g
    }

    /// `motion` for a wall in `phase`: (kind, servo force, gain, largest speed).
    pub fn motion_code(phase: crate::scene::WallPhase) -> [f32; 4] {
        use crate::scene::WallPhase;
        match phase {
            WallPhase::Rest => [WALL_FIXED, 0.0, 0.0, 0.0],
            WallPhase::Velocity(_) => [WALL_PRESCRIBED, 0.0, 0.0, 0.0],
            WallPhase::Servo {
                force,
                gain,
                max_speed,
            } => [WALL_SERVO, force as f32, gain as f32, max_speed as f32],
        }
    }
}
