//! Compute kernels built from a [`ShaderVariant`]: one pipeline per entry point, with its
//! bindings found by name from naga's reflection, plus dispatch and read-back helpers.
//!
//! Each pipeline uses wgpu's automatic layout (bind group 0 holds exactly the globals its
//! entry point uses), so one WGSL module can declare every buffer of a stage — with
//! atomic and plain views of the same buffer under different names — and each kernel
//! binds only what it touches: [`Kernel::bind`] takes `(global name, buffer)` pairs,
//! ignores names the kernel does not use and reports the ones it misses.

use crate::gpu::context::GpuContext;
use crate::gpu::shaders::{self, ShaderVariant};
use crate::PowderError;
use std::collections::BTreeMap;
use std::sync::mpsc;

/// One compute entry point, ready to bind and dispatch.
#[derive(Clone, Debug)]
pub struct Kernel {
    /// Entry-point name in the WGSL module.
    pub name: String,
    /// The compiled compute pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Bind group 0's layout, derived by wgpu from the globals the entry point uses.
    pub layout: wgpu::BindGroupLayout,
    /// (global variable name, binding) of every group-0 global the entry point uses.
    pub bindings: Vec<(String, u32)>,
    /// Names of the functions the entry point calls, directly or through others (for the
    /// traffic estimate: which state fields' accessors it uses).
    pub calls: std::collections::BTreeSet<String>,
    /// Storage buffers the entry point binds (wgpu limits them per shader stage).
    pub storage_buffers: u32,
    /// `@workgroup_size` of the entry point (x, y, z).
    pub workgroup_size: [u32; 3],
}

/// The kernels of one shader variant, by entry-point name.
#[derive(Clone, Debug)]
pub struct Program {
    /// Name of the shader variant the kernels come from.
    pub name: String,
    /// One kernel per compute entry point, by name.
    pub kernels: BTreeMap<String, Kernel>,
}

impl Program {
    /// Validates the variant with naga, then builds one pipeline per compute entry point.
    /// wgpu validation errors come back as `PowderError::Run` instead of panicking.
    pub fn new(ctx: &GpuContext, variant: &ShaderVariant) -> Result<Self, PowderError> {
        Self::with_entry_points(ctx, variant, None)
    }

    /// As [`Self::new`], building pipelines only for the entry points in `only` (all when
    /// `None`): a kernel a scene does not run is not compiled.
    pub fn with_entry_points(
        ctx: &GpuContext,
        variant: &ShaderVariant,
        only: Option<&[&str]>,
    ) -> Result<Self, PowderError> {
        Self::specialized(ctx, variant, only, &[])
    }

    /// As [`Self::with_entry_points`], with values for the module's pipeline-overridable
    /// constants (WGSL `override`; those not given keep their defaults): the shader
    /// compiler folds them, so a scene's pipelines drop the code it cannot reach.
    pub fn specialized(
        ctx: &GpuContext,
        variant: &ShaderVariant,
        only: Option<&[&str]>,
        constants: &[(&str, f64)],
    ) -> Result<Self, PowderError> {
        let (module, info) = shaders::validate(&variant.source).map_err(|e| {
            PowderError::Run(format!(
                "shader variant `{}` is invalid:\n{e}",
                variant.name
            ))
        })?;
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&variant.name),
                source: wgpu::ShaderSource::Wgsl(variant.source.as_str().into()),
            });
        let mut kernels = BTreeMap::new();
        for (index, ep) in module.entry_points.iter().enumerate() {
            if ep.stage != naga::ShaderStage::Compute
                || only.is_some_and(|names| !names.contains(&ep.name.as_str()))
            {
                continue;
            }
            let uses = info.get_entry_point(index);
            let mut bindings = Vec::new();
            let mut storage = 0u32;
            for (handle, var) in module.global_variables.iter() {
                if let Some(rb) = &var.binding {
                    if !uses[handle].is_empty() {
                        if rb.group != 0 {
                            return Err(PowderError::Run(format!(
                                "kernel {}::{}: global `{}` is in bind group {}; kernels \
                                 use group 0 only",
                                variant.name,
                                ep.name,
                                var.name.as_deref().unwrap_or("?"),
                                rb.group
                            )));
                        }
                        bindings.push((var.name.clone().unwrap_or_default(), rb.binding));
                        if matches!(var.space, naga::AddressSpace::Storage { .. }) {
                            storage += 1;
                        }
                    }
                }
            }
            let max_storage = ctx.device.limits().max_storage_buffers_per_shader_stage;
            if storage > max_storage {
                return Err(PowderError::Run(format!(
                    "kernel {}::{} binds {storage} storage buffers; {} allows {max_storage}",
                    variant.name, ep.name, ctx.summary.name
                )));
            }
            let pipeline = ctx
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&format!("{}::{}", variant.name, ep.name)),
                    layout: None,
                    module: &shader,
                    entry_point: Some(&ep.name),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        ..Default::default()
                    },
                    cache: None,
                });
            let layout = pipeline.get_bind_group_layout(0);
            kernels.insert(
                ep.name.clone(),
                Kernel {
                    name: ep.name.clone(),
                    pipeline,
                    layout,
                    bindings,
                    calls: called_functions(&module, &ep.function),
                    storage_buffers: storage,
                    workgroup_size: ep.workgroup_size,
                },
            );
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(PowderError::Run(format!(
                "cannot build the `{}` kernels on {}: {e}",
                variant.name, ctx.summary.name
            )));
        }
        Ok(Self {
            name: variant.name.clone(),
            kernels,
        })
    }

    /// The kernel called `name` (an entry point of this program).
    pub fn kernel(&self, name: &str) -> Result<&Kernel, PowderError> {
        self.kernels.get(name).ok_or_else(|| {
            PowderError::Run(format!(
                "shader variant `{}` has no compute entry point `{name}`",
                self.name
            ))
        })
    }
}

/// A buffer, or the range of one a binding covers (a window's, `gpu::window`).
#[derive(Clone, Copy, Debug)]
pub struct Part<'a> {
    /// The buffer.
    pub buffer: &'a wgpu::Buffer,
    /// First byte bound.
    pub offset: u64,
    /// Bytes bound (`None`: to the end).
    pub size: Option<u64>,
}

impl<'a> Part<'a> {
    /// The whole buffer.
    pub fn whole(buffer: &'a wgpu::Buffer) -> Self {
        Self {
            buffer,
            offset: 0,
            size: None,
        }
    }

    /// Bytes bound.
    pub fn bytes(&self) -> u64 {
        self.size.unwrap_or(self.buffer.size() - self.offset)
    }

    fn resource(&self) -> wgpu::BindingResource<'a> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: self.buffer,
            offset: self.offset,
            size: self.size.and_then(std::num::NonZeroU64::new),
        })
    }
}

impl Kernel {
    /// Workgroups of a 1-D dispatch of `invocations` invocations (as [`Kernel::dispatch`]
    /// rounds).
    pub fn workgroups_for(&self, invocations: u32) -> u32 {
        invocations.div_ceil(self.workgroup_size.iter().product::<u32>().max(1))
    }

    /// Bind group 0 for this kernel from `(global name, buffer)` pairs (whole buffers).
    /// Names the kernel does not use are ignored; a missing one is an error.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        buffers: &[(&str, &wgpu::Buffer)],
    ) -> Result<wgpu::BindGroup, PowderError> {
        self.bind_with_textures(device, buffers, &[])
    }

    /// Whether the kernel binds the global `name`.
    pub fn uses(&self, name: &str) -> bool {
        self.bindings.iter().any(|(n, _)| n == name)
    }

    /// As [`Self::bind`], with `(global name, texture view)` pairs for texture globals.
    pub fn bind_with_textures(
        &self,
        device: &wgpu::Device,
        buffers: &[(&str, &wgpu::Buffer)],
        textures: &[(&str, &wgpu::TextureView)],
    ) -> Result<wgpu::BindGroup, PowderError> {
        let parts: Vec<(&str, Part)> = buffers.iter().map(|&(n, b)| (n, Part::whole(b))).collect();
        self.bind_parts(device, &parts, textures)
    }

    /// As [`Self::bind_with_textures`], each buffer bound whole or in part.
    pub fn bind_parts(
        &self,
        device: &wgpu::Device,
        buffers: &[(&str, Part)],
        textures: &[(&str, &wgpu::TextureView)],
    ) -> Result<wgpu::BindGroup, PowderError> {
        let mut entries = Vec::with_capacity(self.bindings.len());
        for (name, binding) in &self.bindings {
            let buffer = buffers.iter().find(|(n, _)| n == name).map(|(_, b)| *b);
            let texture = textures.iter().find(|(n, _)| n == name).map(|(_, t)| *t);
            let resource = match (buffer, texture) {
                (Some(b), _) => b.resource(),
                (None, Some(t)) => wgpu::BindingResource::TextureView(t),
                (None, None) => {
                    return Err(PowderError::Run(format!(
                        "kernel `{}` needs a buffer or texture for `{name}` (binding {binding})",
                        self.name
                    )))
                }
            };
            entries.push(wgpu::BindGroupEntry {
                binding: *binding,
                resource,
            });
        }
        // (a binding over the adapter's limits is an error here, not a panic)
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.name),
            layout: &self.layout,
            entries: &entries,
        });
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(PowderError::Run(format!(
                "cannot bind the buffers of kernel `{}`: {e}",
                self.name
            ))),
            None => Ok(group),
        }
    }

    /// (global name, bytes) of every distinct buffer or texture this kernel binds from
    /// the same pairs [`Self::bind_with_textures`] takes, textures with their bytes: what a
    /// dispatch may touch (`gpu::traffic`).
    pub fn bound_bytes(
        &self,
        buffers: &[(&str, &wgpu::Buffer)],
        textures: &[(&str, &wgpu::TextureView, u64)],
    ) -> Vec<(String, u64)> {
        #[derive(PartialEq)]
        enum Resource<'a> {
            Buffer(&'a wgpu::Buffer),
            Texture(&'a wgpu::TextureView),
        }
        let resources: Vec<(&str, Resource, u64)> = buffers
            .iter()
            .map(|&(n, b)| (n, Resource::Buffer(b), b.size()))
            .chain(
                textures
                    .iter()
                    .map(|&(n, t, bytes)| (n, Resource::Texture(t), bytes)),
            )
            .collect();
        crate::gpu::traffic::distinct_bound(&self.bindings, &resources)
    }

    /// Records a 1-D dispatch of `invocations` invocations (rounded up to whole
    /// workgroups), split over y (and z) when the workgroup count exceeds
    /// `max_per_dim`; kernels recover the linear index with `global_index` from
    /// `common.wgsl`. Nothing is recorded for zero invocations.
    pub fn dispatch(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind_group: &wgpu::BindGroup,
        invocations: u32,
        max_per_dim: u32,
    ) {
        let groups = self.workgroups_for(invocations);
        self.dispatch_workgroups(pass, bind_group, groups, max_per_dim);
    }

    /// Records a dispatch whose `[x, y, z]` workgroup counts the device reads from `args`
    /// at byte `offset` (a buffer with `INDIRECT` usage; zeros launch nothing).
    pub fn dispatch_indirect(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind_group: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups_indirect(args, offset);
    }

    /// Records a dispatch of `workgroups` workgroups, split as in [`Kernel::dispatch`].
    pub fn dispatch_workgroups(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind_group: &wgpu::BindGroup,
        workgroups: u32,
        max_per_dim: u32,
    ) {
        if workgroups == 0 {
            return;
        }
        let [x, y, z] = split_workgroups(workgroups, max_per_dim);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(x, y, z);
    }
}

/// Splits `count` workgroups into `[x, y, z]` with each at most `max_per_dim` and
/// `x * y * z >= count`, keeping the excess below one row.
pub fn split_workgroups(count: u32, max_per_dim: u32) -> [u32; 3] {
    let max = max_per_dim.max(1);
    if count <= max {
        return [count, 1, 1];
    }
    let rows = count.div_ceil(max);
    if rows <= max {
        let x = count.div_ceil(rows);
        return [x, rows, 1];
    }
    let planes = rows.div_ceil(max);
    let y = rows.div_ceil(planes);
    [max, y, planes]
}

/// Creates a buffer usable as storage, copy source and copy destination.
pub fn storage_buffer(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        // Zero-sized bindings are invalid; keep at least one word.
        size: bytes.max(4).next_multiple_of(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Creates a uniform buffer holding `data`.
pub fn uniform_buffer(device: &wgpu::Device, label: &str, data: &[u8]) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: data,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

/// Appends copies of `sources` (buffer, bytes from its start) into fresh staging buffers
/// to `encoder`, submits it, waits, and returns the bytes: one submission for all.
pub fn submit_and_read(
    ctx: &GpuContext,
    encoder: wgpu::CommandEncoder,
    sources: &[(&wgpu::Buffer, u64)],
) -> Result<Vec<Vec<u8>>, PowderError> {
    let parts: Vec<(&wgpu::Buffer, u64, u64)> = sources.iter().map(|&(b, n)| (b, 0, n)).collect();
    submit_and_read_parts(ctx, encoder, &parts)
}

/// As [`submit_and_read`], each source a part of a buffer: (buffer, byte offset, bytes;
/// the offset a multiple of 4).
pub fn submit_and_read_parts(
    ctx: &GpuContext,
    encoder: wgpu::CommandEncoder,
    sources: &[(&wgpu::Buffer, u64, u64)],
) -> Result<Vec<Vec<u8>>, PowderError> {
    let mut out = Vec::with_capacity(sources.len());
    read_parts_with(ctx, encoder, sources, |bytes| out.push(bytes.to_vec()))?;
    Ok(out)
}

/// Copies `sources` into fresh staging buffers (appended to `encoder`), submits, waits and
/// hands each part's mapped bytes to `each`, in order, unmapping each after.
fn read_parts_with(
    ctx: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    sources: &[(&wgpu::Buffer, u64, u64)],
    mut each: impl FnMut(&[u8]),
) -> Result<(), PowderError> {
    let staging: Vec<(wgpu::Buffer, u64)> = sources
        .iter()
        .map(|&(src, at, bytes)| {
            let size = bytes.max(4).next_multiple_of(4);
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("read-back"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            if bytes > 0 {
                encoder.copy_buffer_to_buffer(src, at, &buf, 0, size.min(src.size() - at));
            }
            (buf, bytes)
        })
        .collect();
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = mpsc::channel();
    for (i, (buf, _)) in staging.iter().enumerate() {
        let tx = tx.clone();
        buf.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send((i, r));
        });
    }
    drop(tx);
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| PowderError::Run(format!("GPU wait failed: {e}")))?;
    for (i, r) in rx.iter() {
        r.map_err(|e| PowderError::Run(format!("cannot map read-back buffer {i}: {e}")))?;
    }
    for (buf, bytes) in &staging {
        let view = buf
            .get_mapped_range(..)
            .map_err(|e| PowderError::Run(format!("cannot read mapped buffer: {e}")))?;
        each(&view[..*bytes as usize]);
        drop(view);
        buf.unmap();
    }
    Ok(())
}

/// Whole buffers (buffer, bytes from its start) as parts from offset 0.
pub fn whole(sources: Vec<(&wgpu::Buffer, u64)>) -> Vec<(&wgpu::Buffer, u64, u64)> {
    sources.into_iter().map(|(b, n)| (b, 0, n)).collect()
}

/// Reads `groups` of buffer parts (buffer, byte offset, bytes) back, each group's bytes
/// joined into one vector, one part at a time (a submission and wait each; `encoder`,
/// submitted with the first copy, may hold earlier commands): each part goes from its
/// staging buffer straight into the joined bytes, so at the peak the host holds the bytes
/// read so far and one part's staging copy (3× the bytes before: staging, parts, joined).
pub fn read_joined(
    ctx: &GpuContext,
    encoder: wgpu::CommandEncoder,
    groups: &[Vec<(&wgpu::Buffer, u64, u64)>],
) -> Result<Vec<Vec<u8>>, PowderError> {
    let mut encoder = Some(encoder);
    let mut out = Vec::with_capacity(groups.len());
    for group in groups {
        let bytes: u64 = group.iter().map(|p| p.2).sum();
        let mut joined = Vec::with_capacity(bytes as usize);
        for &part in group {
            let encoder = encoder
                .take()
                .unwrap_or_else(|| ctx.device.create_command_encoder(&Default::default()));
            read_parts_with(ctx, encoder, &[part], |bytes| {
                joined.extend_from_slice(bytes)
            })?;
        }
        out.push(joined);
    }
    if let Some(encoder) = encoder {
        ctx.queue.submit([encoder.finish()]);
    }
    Ok(out)
}

/// Reinterprets read-back bytes as u32s.
pub fn u32s(bytes: &[u8]) -> Vec<u32> {
    bytemuck::pod_collect_to_vec(bytes)
}

/// The names of every function `function` calls, directly or through the functions it
/// calls.
pub fn called_functions(
    module: &naga::Module,
    function: &naga::Function,
) -> std::collections::BTreeSet<String> {
    fn walk(block: &naga::Block, out: &mut Vec<naga::Handle<naga::Function>>) {
        for statement in block.iter() {
            match statement {
                naga::Statement::Call { function, .. } => out.push(*function),
                naga::Statement::Block(b) => walk(b, out),
                naga::Statement::If { accept, reject, .. } => {
                    walk(accept, out);
                    walk(reject, out);
                }
                naga::Statement::Switch { cases, .. } => {
                    for c in cases {
                        walk(&c.body, out);
                    }
                }
                naga::Statement::Loop {
                    body, continuing, ..
                } => {
                    walk(body, out);
                    walk(continuing, out);
                }
                _ => {}
            }
        }
    }
    let mut seen = std::collections::BTreeSet::new();
    let mut names = std::collections::BTreeSet::new();
    let mut todo = Vec::new();
    walk(&function.body, &mut todo);
    while let Some(h) = todo.pop() {
        if seen.insert(h) {
            let f = &module.functions[h];
            names.extend(f.name.clone());
            walk(&f.body, &mut todo);
        }
    }
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_kernel_split_workgroups() {
        for &(count, max) in &[
            (0u32, 65535u32),
            (1, 65535),
            (65535, 65535),
            (65536, 65535),
            (65537, 65535),
            (1 << 24, 65535),
            (u32::MAX, 65535),
            (50, 7),
            (49, 7),
            (343, 7),
        ] {
            let [x, y, z] = split_workgroups(count, max);
            assert!(
                x <= max && y <= max && z <= max,
                "{count}/{max}: {x} {y} {z}"
            );
            let total = x as u64 * y as u64 * z as u64;
            assert!(total >= count as u64, "{count}/{max}: {x} {y} {z}");
            assert!(
                count == 0 || total - (count as u64) < (x as u64) * (y as u64),
                "{count}: {x} {y} {z}"
            );
        }
    }
}
