//! Where the indirect dispatches' arguments lie in `args`: a rebuild's (the grid sort's, a
//! per-particle pass's, the list scans') and every step's, which `decide` sets or zeroes.

use super::allocator::Allocator;
use crate::gpu::context::GpuContext;
use crate::gpu::grid::GridSort;
use crate::gpu::kernel::split_workgroups;
use crate::gpu::scan::ExclusiveScan;

/// Offsets (bytes) into `args` and the values every step's arguments take.
pub(super) struct Dispatches {
    /// A rebuild's per-particle passes.
    pub(super) rebuild: u64,
    /// The two list scans of a window (every window's have the first one's).
    pub(super) scans: [u64; 2],
    /// Every step's: per particle, then one workgroup.
    pub(super) step: u64,
    /// The values of every step's (written before each batch; a halt zeroes them).
    pub(super) step_full: [[u32; 3]; 2],
}

impl Dispatches {
    /// Lays the arguments out for `grid`'s sort, the first window's `scans` and a window of
    /// `per_window` particles in workgroups of `per_group`; returns them with `full_args`
    /// (a rebuild's arguments, which `decide` copies) and `args` (what the passes read).
    pub(super) fn new(
        ctx: &GpuContext,
        alloc: &mut Allocator,
        (grid, scans): (&GridSort, &[ExclusiveScan]),
        (per_window, per_group): (u32, u32),
    ) -> (Self, wgpu::Buffer, wgpu::Buffer) {
        let max_per_dim = ctx.limits().max_compute_workgroups_per_dimension;
        let sort_args = grid.indirect_args();
        let particle_args = split_workgroups(per_window.div_ceil(per_group), max_per_dim);
        let rebuild = 12 * sort_args.len() as u64;
        let scan_at = [
            rebuild + 12,
            rebuild + 12 + 12 * scans[0].indirect_args().len() as u64,
        ];
        let full: Vec<u32> = sort_args
            .into_iter()
            .chain([particle_args])
            .chain(scans[0].indirect_args())
            .chain(scans[1].indirect_args())
            .flatten()
            .collect();
        let full_args = alloc.buffer("full_args", 4 * full.len() as u64);
        ctx.queue
            .write_buffer(&full_args, 0, bytemuck::cast_slice(&full));
        // then every step's: one invocation per particle, one workgroup
        let step = 4 * full.len() as u64;
        let args = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("args"),
            size: step + 24,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        alloc.list.push(("args".into(), args.size()));
        let dispatches = Self {
            rebuild,
            scans: scan_at,
            step,
            step_full: [particle_args, [1, 1, 1]],
        };
        (dispatches, full_args, args)
    }
}
