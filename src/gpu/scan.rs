//! The multi-level exclusive prefix sum on the GPU ([`ExclusiveScan`]): the grid sort's
//! cell starts and the new lists' first entries (`scan_blocks`, `scan_add` in
//! `shaders/grid.wgsl`).

use crate::gpu::context::GpuContext;
use crate::gpu::grid::grid_variant;
use crate::gpu::kernel::{self, split_workgroups, Kernel, Part, Program};
use crate::gpu::layout::ScanParams;
use crate::PowderError;

/// Elements per workgroup of `scan_blocks` (`SCAN_BLOCK` in `shaders/grid.wgsl`).
pub const SCAN_BLOCK: u32 = 1024;

/// Exclusive prefix sum of `n` u32s from one buffer into another, in levels of
/// [`SCAN_BLOCK`]-element blocks: each level scans its blocks and writes block sums,
/// the sums are scanned by the next level, and the scanned sums are added back. Sums
/// wrap modulo 2^32.
pub struct ExclusiveScan {
    n: u32,
    levels: Vec<ScanLevel>,
    scan_blocks: Kernel,
    scan_add: Kernel,
    max_per_dim: u32,
    _buffers: Vec<wgpu::Buffer>,
}

struct ScanLevel {
    n: u32,
    n_blocks: u32,
    blocks: wgpu::BindGroup,
    /// Adds the next level's scanned sums into this level's output (absent at the top).
    add: Option<wgpu::BindGroup>,
    /// (global name, bytes) of what `blocks` and `add` bind (`gpu::traffic`).
    blocks_bound: Vec<(String, u64)>,
    add_bound: Vec<(String, u64)>,
}

impl ExclusiveScan {
    /// Scans `input[0..n]` into `output[0..n]` (both storage buffers of >= 4 n bytes,
    /// not the same buffer). `program` is the `grid` shader program.
    pub fn new(
        ctx: &GpuContext,
        program: &Program,
        input: &wgpu::Buffer,
        output: &wgpu::Buffer,
        n: u32,
    ) -> Result<Self, PowderError> {
        Self::with_offsets(ctx, program, (input, 0), (output, 0), n)
    }

    /// Scans `n` elements of `input` from element `input.1` into `output` from element
    /// `output.1`; the two may be one buffer when the ranges do not overlap.
    pub fn with_offsets(
        ctx: &GpuContext,
        program: &Program,
        (input, in_offset): (&wgpu::Buffer, u32),
        (output, out_offset): (&wgpu::Buffer, u32),
        n: u32,
    ) -> Result<Self, PowderError> {
        Self::with_parts(
            ctx,
            program,
            (Part::whole(input), in_offset),
            (Part::whole(output), out_offset),
            n,
        )
    }

    /// As [`Self::with_offsets`], the input and output bound in part (the offsets then
    /// count from the parts' starts).
    pub fn with_parts(
        ctx: &GpuContext,
        program: &Program,
        (input, in_offset): (Part, u32),
        (output, out_offset): (Part, u32),
        n: u32,
    ) -> Result<Self, PowderError> {
        ctx.check_binding("exclusive scan", n as u64, 4, "elements")?;
        let device = &ctx.device;
        let scan_blocks = program.kernel("scan_blocks")?.clone();
        let scan_add = program.kernel("scan_add")?.clone();
        let mut levels: Vec<ScanLevel> = Vec::new();
        let mut buffers = Vec::new();
        let own = |p: Part| (p.buffer.clone(), p.offset, p.size);
        let (mut level_in, mut level_out, mut level_n) = (own(input), own(output), n);
        fn part((buffer, offset, size): &(wgpu::Buffer, u64, Option<u64>)) -> Part<'_> {
            Part {
                buffer,
                offset: *offset,
                size: *size,
            }
        }
        let mut offsets = (in_offset, out_offset);
        loop {
            let n_blocks = level_n.div_ceil(SCAN_BLOCK).max(1);
            let params = kernel::uniform_buffer(
                device,
                "scan params",
                bytemuck::bytes_of(&ScanParams {
                    n: level_n,
                    n_blocks,
                    in_offset: offsets.0,
                    out_offset: offsets.1,
                }),
            );
            let sums = kernel::storage_buffer(device, "scan block sums", n_blocks as u64 * 4);
            let named: &[(&str, &wgpu::Buffer)] = &[
                ("scan_params", &params),
                ("scan_in", &level_in.0),
                ("scan_out", &level_out.0),
                ("scan_sums", &sums),
            ];
            let blocks = scan_blocks.bind_parts(
                device,
                &[
                    ("scan_params", Part::whole(&params)),
                    ("scan_in", part(&level_in)),
                    ("scan_out", part(&level_out)),
                    ("scan_sums", Part::whole(&sums)),
                ],
                &[],
            )?;
            let mut level = ScanLevel {
                n: level_n,
                n_blocks,
                blocks,
                add: None,
                blocks_bound: scan_blocks.bound_bytes(named, &[]),
                add_bound: Vec::new(),
            };
            if n_blocks == 1 {
                levels.push(level);
                buffers.extend([params, sums]);
                break;
            }
            let scanned_sums =
                kernel::storage_buffer(device, "scanned block sums", n_blocks as u64 * 4);
            let named: &[(&str, &wgpu::Buffer)] = &[
                ("scan_params", &params),
                ("scan_out", &level_out.0),
                ("scan_carry", &scanned_sums),
            ];
            level.add = Some(scan_add.bind_parts(
                device,
                &[
                    ("scan_params", Part::whole(&params)),
                    ("scan_out", part(&level_out)),
                    ("scan_carry", Part::whole(&scanned_sums)),
                ],
                &[],
            )?);
            level.add_bound = scan_add.bound_bytes(named, &[]);
            levels.push(level);
            buffers.extend([params, sums.clone(), scanned_sums.clone()]);
            level_in = (sums, 0, None);
            level_out = (scanned_sums, 0, None);
            level_n = n_blocks;
            offsets = (0, 0);
        }
        Ok(Self {
            n,
            levels,
            scan_blocks,
            scan_add,
            max_per_dim: ctx.limits().max_compute_workgroups_per_dimension,
            _buffers: buffers,
        })
    }

    /// Elements scanned.
    pub fn len(&self) -> u32 {
        self.n
    }

    /// Whether there is nothing to scan.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Whether `group` is one of the scan's bind groups.
    pub(crate) fn binds(&self, group: &wgpu::BindGroup) -> bool {
        self.levels
            .iter()
            .any(|l| &l.blocks == group || l.add.as_ref() == Some(group))
    }

    /// Number of levels (1 up to [`SCAN_BLOCK`] elements, 2 up to `SCAN_BLOCK^2`, ...).
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Records the scan's dispatches into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (kernel, bind_group, workgroups) in self.plan() {
            kernel.dispatch_workgroups(pass, bind_group, workgroups, self.max_per_dim);
        }
    }

    /// The `[x, y, z]` workgroup counts of the scan's dispatches, in recording order (for
    /// [`Self::record_indirect`]).
    pub fn indirect_args(&self) -> Vec<[u32; 3]> {
        self.plan()
            .into_iter()
            .map(|(_, _, g)| split_workgroups(g, self.max_per_dim))
            .collect()
    }

    /// Records the scan's dispatches into `pass`, dispatch `i` reading its workgroup
    /// counts from `args` at byte `offset + 12·i` ([`Self::indirect_args`], or zeros to
    /// skip the scan). Returns the dispatches recorded.
    pub fn record_indirect(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        args: &wgpu::Buffer,
        offset: u64,
    ) -> usize {
        let plan = self.plan();
        for (i, (kernel, bind_group, _)) in plan.iter().enumerate() {
            kernel.dispatch_indirect(pass, bind_group, args, offset + 12 * i as u64);
        }
        plan.len()
    }

    /// (kernel, global name and bytes of what it binds) of the scan's dispatches in
    /// recording order (`gpu::traffic`).
    pub fn traffic(&self) -> Vec<(String, Vec<(String, u64)>)> {
        let mut out: Vec<(String, Vec<(String, u64)>)> = self
            .levels
            .iter()
            .map(|level| (self.scan_blocks.name.clone(), level.blocks_bound.clone()))
            .collect();
        for level in self.levels.iter().rev() {
            if level.add.is_some() {
                out.push((self.scan_add.name.clone(), level.add_bound.clone()));
            }
        }
        out
    }

    /// The scan's dispatches in recording order: (kernel, bind group, workgroups).
    pub(crate) fn plan(&self) -> Vec<(&Kernel, &wgpu::BindGroup, u32)> {
        let mut plan: Vec<(&Kernel, &wgpu::BindGroup, u32)> = self
            .levels
            .iter()
            .map(|level| (&self.scan_blocks, &level.blocks, level.n_blocks))
            .collect();
        for level in self.levels.iter().rev() {
            if let Some(add) = &level.add {
                plan.push((&self.scan_add, add, self.scan_add.workgroups_for(level.n)));
            }
        }
        plan
    }
}

/// Exclusive scan of `values` on the GPU (upload, scan, read back): for tests.
pub fn scan_blocking(ctx: &GpuContext, values: &[u32]) -> Result<Vec<u32>, PowderError> {
    use wgpu::util::DeviceExt;
    let n = u32::try_from(values.len())
        .map_err(|_| PowderError::Run(format!("cannot scan {} elements", values.len())))?;
    let program = Program::new(ctx, &grid_variant()?)?;
    let input = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scan input"),
            contents: if values.is_empty() {
                &[0; 4]
            } else {
                bytemuck::cast_slice(values)
            },
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let output = kernel::storage_buffer(&ctx.device, "scan output", n as u64 * 4);
    let scan = ExclusiveScan::new(ctx, &program, &input, &output, n)?;
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("scan"),
        });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("scan"),
            timestamp_writes: None,
        });
        scan.record(&mut pass);
    }
    let bytes = kernel::submit_and_read(ctx, encoder, &[(&output, n as u64 * 4)])?;
    Ok(kernel::u32s(&bytes[0]))
}
