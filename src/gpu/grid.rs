//! Deterministic counting sort of particles by grid cell on the GPU ([`GridSort`]).
//!
//! A particle's key is its cell ([`crate::gpu::layout`]) clamped into the grid and
//! linearised x fastest, `key = x + dx (y + dy z)`. The output is `sorted_index[k]`, the
//! original index of the k-th particle in order of (key, index) — a stable counting sort's
//! order, the same on every run and adapter: each cell's slice is sorted by index after the
//! atomics' racy scatter — and `cell_start[c]`, `cell_count[c]`, cell c's slice of it. The
//! passes (`shaders/grid.wgsl`) are dispatches of one compute pass in the caller's encoder;
//! the cell counts become starts through [`crate::gpu::scan::ExclusiveScan`].

use crate::gpu::context::GpuContext;
use crate::gpu::kernel::{self, split_workgroups, Kernel, Part, Program};
use crate::gpu::layout::GridParams;
use crate::gpu::scan::ExclusiveScan;
use crate::gpu::shaders;
use crate::PowderError;

/// Largest cell sorted by one invocation (`SMALL_CELL` in `shaders/grid.wgsl`).
pub const SMALL_CELL: u32 = 32;
/// Workgroups of `sort_large_cells` (a grid-stride loop over the queued cells).
pub const LARGE_CELL_GROUPS: u32 = 64;

/// Bytes per particle of the cell buffer passed to [`GridSort::encode`].
pub const CELL_BYTES: u64 = 16;

pub(super) fn grid_variant() -> Result<shaders::ShaderVariant, PowderError> {
    shaders::variant("grid")
        .ok_or_else(|| PowderError::Run("shader variant `grid` is missing".into()))
}

/// What [`GridSort::sort_blocking`] reads back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SortResult {
    /// `sorted_index[k]` = original index of the k-th particle in (cell key, index) order.
    pub sorted_index: Vec<u32>,
    /// First slot of each cell in `sorted_index`.
    pub cell_start: Vec<u32>,
    /// Particles in each cell.
    pub cell_count: Vec<u32>,
}

/// Pipelines and buffers of the cell sort for `n_particles` particles on a grid of
/// `dims` cells; reusable for every step of a run.
pub struct GridSort {
    device: wgpu::Device,
    n_particles: u32,
    dims: [u32; 3],
    n_cells: u32,
    cell_width: [f32; 3],
    max_per_dim: u32,
    large_groups: u32,
    /// Particles one `cell_keys` dispatch covers (all, or a window's).
    key_invocations: u32,
    /// The window uniform of a dispatch over all particles (`win`, `gpu::window`).
    whole_window: wgpu::Buffer,
    cell_keys: Kernel,
    clear_counts: Kernel,
    count: Kernel,
    scatter: Kernel,
    sort_within_cells: Kernel,
    sort_large_cells: Kernel,
    params: wgpu::Buffer,
    keys: wgpu::Buffer,
    cell_count: wgpu::Buffer,
    cell_start: wgpu::Buffer,
    sorted_index: wgpu::Buffer,
    large_cells: wgpu::Buffer,
    bg_clear: wgpu::BindGroup,
    bg_count: wgpu::BindGroup,
    bg_scatter: wgpu::BindGroup,
    bg_sort_small: wgpu::BindGroup,
    bg_sort_large: wgpu::BindGroup,
    scan: ExclusiveScan,
}

impl GridSort {
    /// Builds the pipelines and allocates the buffers. Fails with a message naming the
    /// sizes when a buffer would exceed the adapter's storage binding limit.
    pub fn new(
        ctx: &GpuContext,
        n_particles: u32,
        dims: [u32; 3],
        cell_width: f32,
    ) -> Result<Self, PowderError> {
        Self::with_cell_widths(ctx, n_particles, dims, [cell_width; 3])
    }

    /// As [`Self::new`] with a cell width per axis.
    pub fn with_cell_widths(
        ctx: &GpuContext,
        n_particles: u32,
        dims: [u32; 3],
        cell_width: [f32; 3],
    ) -> Result<Self, PowderError> {
        if dims.contains(&0) || dims.iter().any(|&d| d > i32::MAX as u32) {
            return Err(PowderError::Run(format!(
                "grid dims {dims:?}: each axis needs 1 to {} cells",
                i32::MAX
            )));
        }
        let n_cells64 = dims.iter().map(|&d| d as u64).product::<u64>();
        let n_cells = u32::try_from(n_cells64).map_err(|_| {
            PowderError::Run(format!(
                "grid of {}x{}x{} = {n_cells64} cells exceeds 2^32 - 1 cells",
                dims[0], dims[1], dims[2]
            ))
        })?;
        if !cell_width.iter().all(|h| h.is_finite() && *h > 0.0) {
            return Err(PowderError::Run(format!(
                "cell widths must be finite and > 0, got {cell_width:?}"
            )));
        }
        let grid_name = format!("grid sort of {}x{}x{} cells", dims[0], dims[1], dims[2]);
        // (the keys and the sorted index, 4 bytes a particle; the cells may be bound a
        // window at a time, `keys_bind_group_part`)
        ctx.check_binding("grid sort", n_particles as u64, 4, "particles")?;
        ctx.check_binding(&grid_name, n_cells as u64, 4, "cells")?;

        let device = &ctx.device;
        let program = Program::new(ctx, &grid_variant()?)?;
        let k = |name: &str| program.kernel(name).cloned();
        let params = kernel::uniform_buffer(
            device,
            "grid params",
            bytemuck::bytes_of(&GridParams {
                dims,
                n_particles,
                cell_width,
                n_cells,
                // one window; `cells` a plain array (`set_windows` for a blocked state)
                window: crate::gpu::window::Windows::one(n_particles as u64).params(1),
            }),
        );
        let n4 = n_particles as u64 * 4;
        let c4 = n_cells as u64 * 4;
        let keys = kernel::storage_buffer(device, "cell keys", n4);
        let cell_count = kernel::storage_buffer(device, "cell count", c4);
        let cell_start = kernel::storage_buffer(device, "cell start", c4);
        let sorted_index = kernel::storage_buffer(device, "sorted index", n4);
        // Queue of large cells: a count, then at most n / (SMALL_CELL + 1) cell keys (at
        // least one slot: a struct ending in a runtime array binds >= 8 bytes).
        let large_capacity = n_particles / (SMALL_CELL + 1);
        let large_cells =
            kernel::storage_buffer(device, "large cells", 4 + large_capacity.max(1) as u64 * 4);
        let named: &[(&str, &wgpu::Buffer)] = &[
            ("grid", &params),
            ("keys", &keys),
            ("cell_count", &cell_count),
            ("cell_count_atomic", &cell_count),
            ("cell_start", &cell_start),
            ("sorted_index", &sorted_index),
            ("large_cells", &large_cells),
            ("large_cells_atomic", &large_cells),
        ];
        let clear_counts = k("clear_counts")?;
        let count = k("count")?;
        let scatter = k("scatter")?;
        let sort_within_cells = k("sort_within_cells")?;
        let sort_large_cells = k("sort_large_cells")?;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let bg_clear = clear_counts.bind(device, named)?;
        let bg_count = count.bind(device, named)?;
        let bg_scatter = scatter.bind(device, named)?;
        let bg_sort_small = sort_within_cells.bind(device, named)?;
        let bg_sort_large = sort_large_cells.bind(device, named)?;
        let scan = ExclusiveScan::new(ctx, &program, &cell_count, &cell_start, n_cells)?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(PowderError::Run(format!(
                "cannot set up the {grid_name} for {n_particles} particles: {e}"
            )));
        }
        Ok(Self {
            device: device.clone(),
            n_particles,
            dims,
            n_cells,
            cell_width,
            max_per_dim: ctx.limits().max_compute_workgroups_per_dimension,
            large_groups: large_capacity.min(LARGE_CELL_GROUPS),
            key_invocations: n_particles,
            whole_window: kernel::uniform_buffer(
                device,
                "grid window",
                bytemuck::bytes_of(&crate::gpu::window::WindowParams::default()),
            ),
            cell_keys: k("cell_keys")?,
            clear_counts,
            count,
            scatter,
            sort_within_cells,
            sort_large_cells,
            params,
            keys,
            cell_count,
            cell_start,
            sorted_index,
            large_cells,
            bg_clear,
            bg_count,
            bg_scatter,
            bg_sort_small,
            bg_sort_large,
            scan,
        })
    }

    /// Particles the sort was built for.
    pub fn n_particles(&self) -> u32 {
        self.n_particles
    }

    /// Cells per axis.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// Total cells, `dims[0] * dims[1] * dims[2]`.
    pub fn n_cells(&self) -> u32 {
        self.n_cells
    }

    /// Cell width per axis, m (f32, as the kernels see it).
    pub fn cell_width(&self) -> [f32; 3] {
        self.cell_width
    }

    /// `array<u32>`, n_particles: original index of each sorted slot.
    pub fn sorted_index(&self) -> &wgpu::Buffer {
        &self.sorted_index
    }

    /// `array<u32>`, n_cells: first sorted slot of each cell.
    pub fn cell_start(&self) -> &wgpu::Buffer {
        &self.cell_start
    }

    /// `array<u32>`, n_cells: particles in each cell.
    pub fn cell_count(&self) -> &wgpu::Buffer {
        &self.cell_count
    }

    /// `array<u32>`, n_particles: clamped cell key of each particle, original order.
    pub fn keys(&self) -> &wgpu::Buffer {
        &self.keys
    }

    /// The uniform `GridParams` buffer.
    pub fn params(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// Tells the kernels the run's windows (`GridParams::window`), `cells` then being the
    /// blocked particle state with `state_fields` fields a particle.
    pub fn set_windows(
        &mut self,
        queue: &wgpu::Queue,
        windows: &crate::gpu::window::Windows,
        state_fields: u32,
    ) {
        // `cell_keys` then runs once a window
        self.key_invocations = self.n_particles.min(windows.len as u32);
        let at = std::mem::offset_of!(GridParams, window) as u64;
        queue.write_buffer(
            &self.params,
            at,
            bytemuck::cast_slice(&windows.params(state_fields)),
        );
    }

    /// The bind group of `cell_keys` for this cell buffer (for [`Self::encode_indirect`]:
    /// a stepping loop makes it once, not per step).
    pub fn keys_bind_group(&self, cells: &wgpu::Buffer) -> wgpu::BindGroup {
        self.keys_bind_group_part(Part::whole(cells), &self.whole_window)
            .expect("cell_keys binds grid, cells, keys and its window")
    }

    /// The bind group of `cell_keys` for one window: `cells` the part of the blocked
    /// particle state its window's dispatch binds, `window` its uniform.
    pub fn keys_bind_group_part(
        &self,
        cells: Part,
        window: &wgpu::Buffer,
    ) -> Result<wgpu::BindGroup, PowderError> {
        self.cell_keys.bind_parts(
            &self.device,
            &[
                ("grid", Part::whole(&self.params)),
                ("cells", cells),
                ("keys", Part::whole(&self.keys)),
                ("win", Part::whole(window)),
            ],
            &[],
        )
    }

    /// Records the whole sort into `encoder` as one compute pass. `cells` holds one
    /// `vec4<i32>` per particle (storage usage).
    ///
    /// # Panics
    /// If `cells` is smaller than 16 bytes per particle or lacks `STORAGE` usage.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, cells: &wgpu::Buffer) {
        let need = self.n_particles as u64 * CELL_BYTES;
        assert!(
            cells.size() >= need && cells.usage().contains(wgpu::BufferUsages::STORAGE),
            "GridSort::encode: the cell buffer must be a storage buffer of >= {need} bytes \
             (16 per particle, {} particles); got {} bytes, usage {:?}",
            self.n_particles,
            cells.size(),
            cells.usage()
        );
        let bg_keys = self.keys_bind_group(cells);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("grid sort"),
            timestamp_writes: None,
        });
        for (kernel, bind_group, groups) in self.plan() {
            let bind_group = bind_group.unwrap_or(&bg_keys);
            kernel.dispatch_workgroups(&mut pass, bind_group, groups, self.max_per_dim);
        }
    }

    /// The sort's dispatches in recording order: (kernel, bind group, workgroups before
    /// splitting); `None` stands for the `cell_keys` bind group, made per `cells` buffer.
    fn plan(&self) -> Vec<(&Kernel, Option<&wgpu::BindGroup>, u32)> {
        let (n, c) = (self.n_particles, self.n_cells);
        let mut plan = vec![
            // One invocation at least: it also empties the large-cell queue.
            (
                &self.clear_counts,
                Some(&self.bg_clear),
                self.clear_counts.workgroups_for(c),
            ),
            (
                &self.cell_keys,
                None,
                self.cell_keys.workgroups_for(self.key_invocations),
            ),
            (
                &self.count,
                Some(&self.bg_count),
                self.count.workgroups_for(n),
            ),
        ];
        plan.extend(
            self.scan
                .plan()
                .into_iter()
                .map(|(k, b, g)| (k, Some(b), g)),
        );
        plan.push((
            &self.scatter,
            Some(&self.bg_scatter),
            self.scatter.workgroups_for(n),
        ));
        plan.push((
            &self.sort_within_cells,
            Some(&self.bg_sort_small),
            self.sort_within_cells.workgroups_for(c),
        ));
        plan.push((
            &self.sort_large_cells,
            Some(&self.bg_sort_large),
            self.large_groups,
        ));
        plan.retain(|&(_, _, g)| g > 0);
        plan
    }

    /// (kernel, global name and bytes of what it binds) of the sort's dispatches in
    /// recording order, `cells` being the cell buffer sorted (`gpu::traffic`).
    pub fn traffic(&self, cells: &wgpu::Buffer) -> Vec<(String, Vec<(String, u64)>)> {
        let named: &[(&str, &wgpu::Buffer)] = &[
            ("grid", &self.params),
            ("cells", cells),
            ("keys", &self.keys),
            ("cell_count", &self.cell_count),
            ("cell_count_atomic", &self.cell_count),
            ("cell_start", &self.cell_start),
            ("sorted_index", &self.sorted_index),
            ("large_cells", &self.large_cells),
            ("large_cells_atomic", &self.large_cells),
        ];
        // the scan's dispatches come in the plan in the order of its own traffic
        let mut scan = self.scan.traffic().into_iter();
        let out = self
            .plan()
            .into_iter()
            .map(|(kernel, bind_group, _)| {
                let bound = if bind_group.is_some_and(|b| self.scan.binds(b)) {
                    scan.next().map(|(_, b)| b).unwrap_or_default()
                } else {
                    kernel.bound_bytes(named, &[])
                };
                (kernel.name.clone(), bound)
            })
            .collect();
        debug_assert!(scan.next().is_none(), "every scan dispatch is in the plan");
        out
    }

    /// The `[x, y, z]` workgroup counts of the sort's dispatches, in the order
    /// [`Self::encode_indirect`] reads them: the arguments of a full sort.
    pub fn indirect_args(&self) -> Vec<[u32; 3]> {
        self.plan()
            .into_iter()
            .map(|(_, _, g)| split_workgroups(g, self.max_per_dim))
            .collect()
    }

    /// Records the sort as [`Self::encode`] does, but every dispatch indirect: dispatch
    /// `i` reads its `[x, y, z]` from `args` at byte `offset + 12·i` (a buffer with
    /// `INDIRECT` usage holding [`Self::indirect_args`] to sort, or zeros to skip the
    /// sort and keep the previous result). `keys`: [`Self::keys_bind_group`] of the cells,
    /// or one [`Self::keys_bind_group_part`] a window. Returns the dispatches recorded.
    pub fn encode_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        keys: &[wgpu::BindGroup],
        args: &wgpu::Buffer,
        offset: u64,
    ) -> usize {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("grid sort (indirect)"),
            timestamp_writes: None,
        });
        let mut n = 0;
        for (i, (kernel, bind_group, _)) in self.plan().into_iter().enumerate() {
            pass.set_pipeline(&kernel.pipeline);
            // (`cell_keys`: once per window, each with the same workgroup counts)
            let groups = bind_group.map_or(keys, std::slice::from_ref);
            for group in groups {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups_indirect(args, offset + 12 * i as u64);
                n += 1;
            }
        }
        n
    }

    /// Uploads `cells`, sorts, and reads the result back (one submission): for tests
    /// and tools, not for the stepping loop.
    pub fn sort_blocking(
        &self,
        ctx: &GpuContext,
        cells: &[[i32; 4]],
    ) -> Result<SortResult, PowderError> {
        use wgpu::util::DeviceExt;
        if cells.len() != self.n_particles as usize {
            return Err(PowderError::Run(format!(
                "GridSort for {} particles was given {} cells",
                self.n_particles,
                cells.len()
            )));
        }
        let zero = [[0i32; 4]];
        let contents: &[[i32; 4]] = if cells.is_empty() { &zero } else { cells };
        let cell_buf = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("particle cells"),
                contents: bytemuck::cast_slice(contents),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("grid sort"),
            });
        self.encode(&mut encoder, &cell_buf);
        let n4 = self.n_particles as u64 * 4;
        let c4 = self.n_cells as u64 * 4;
        let out = kernel::submit_and_read(
            ctx,
            encoder,
            &[
                (&self.sorted_index, n4),
                (&self.cell_start, c4),
                (&self.cell_count, c4),
            ],
        )?;
        Ok(SortResult {
            sorted_index: kernel::u32s(&out[0]),
            cell_start: kernel::u32s(&out[1]),
            cell_count: kernel::u32s(&out[2]),
        })
    }
}

/// The CPU reference of the sort: clamped linear cell keys, then a stable counting sort
/// by key (ties keep index order). Used by the tests and as documentation of the result.
pub fn sort_reference(cells: &[[i32; 4]], dims: [u32; 3]) -> SortResult {
    let n_cells = dims.iter().map(|&d| d as usize).product::<usize>();
    let key = |c: &[i32; 4]| -> usize {
        let cl = |v: i32, d: u32| v.clamp(0, d as i32 - 1) as usize;
        let (x, y, z) = (cl(c[0], dims[0]), cl(c[1], dims[1]), cl(c[2], dims[2]));
        x + dims[0] as usize * (y + dims[1] as usize * z)
    };
    let keys: Vec<usize> = cells.iter().map(key).collect();
    let mut cell_count = vec![0u32; n_cells];
    for &k in &keys {
        cell_count[k] += 1;
    }
    let mut cell_start = vec![0u32; n_cells];
    let mut acc = 0u32;
    for (s, &c) in cell_start.iter_mut().zip(&cell_count) {
        *s = acc;
        acc += c;
    }
    let mut next = cell_start.clone();
    let mut sorted_index = vec![0u32; cells.len()];
    for (i, &k) in keys.iter().enumerate() {
        sorted_index[next[k] as usize] = i as u32;
        next[k] += 1;
    }
    SortResult {
        sorted_index,
        cell_start,
        cell_count,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::scan::SCAN_BLOCK;
    use crate::gpu::shaders::wgsl_u32_const;

    #[test]
    fn gpu_grid_constants_match_wgsl() {
        let (module, _) = shaders::validate(&grid_variant().unwrap().source).unwrap();
        assert_eq!(wgsl_u32_const(&module, "SCAN_BLOCK"), SCAN_BLOCK);
        assert_eq!(
            wgsl_u32_const(&module, "SCAN_BLOCK"),
            wgsl_u32_const(&module, "WG_SIZE") * wgsl_u32_const(&module, "SCAN_ITEMS")
        );
        assert_eq!(wgsl_u32_const(&module, "SMALL_CELL"), SMALL_CELL);
    }

    #[test]
    fn gpu_grid_reference_is_a_stable_counting_sort() {
        let cells = [
            [5, 0, 0, 0],
            [-3, 0, 0, 0],
            [1, 1, 0, 0],
            [0, 0, 0, 0],
            [9, 9, 9, 0],
        ];
        let r = sort_reference(&cells, [2, 2, 1]);
        // keys: 1, 0, 3, 0, 3
        assert_eq!(r.sorted_index, vec![1, 3, 0, 2, 4]);
        assert_eq!(r.cell_start, vec![0, 2, 3, 3]);
        assert_eq!(r.cell_count, vec![2, 1, 0, 2]);
    }
}
