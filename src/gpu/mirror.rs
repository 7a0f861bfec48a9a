//! Read-only texture mirrors of the per-particle state the force pass reads for every
//! pair: the cell, the cell offset with the radius, the predicted velocity with the mass
//! (and the predicted angular velocity when the scene rotates), copied from the state's
//! fields right before each force pass — on a software adapter only
//! (`GpuOptions::software_paths`, `shaders/state_mirrors.wgsl`; a GPU reads the buffers,
//! `shaders/state_buffers.wgsl`). Why: on Mesa lavapipe a storage-buffer load with a
//! per-invocation index is a loop over the SIMD lanes, a texture load one gather
//! (`docs/design_log.md`, *Measurements moved out of the code*).
//!
//! A rebuild's `gather` writes the re-sorted cells and offsets into their mirrors itself,
//! so the neighbour search reads its candidates through gathers too. Texels are row-major,
//! [`MIRROR_WIDTH`] particles a row (a power of two: `mirror_texel` in
//! `shaders/state_mirrors.wgsl` finds a texel with a mask and a shift).

use crate::error::PowderError;

/// Particles per texture row (`MIRROR_WIDTH` in `shaders/state_mirrors.wgsl`; a test ties
/// them).
pub const MIRROR_WIDTH: u32 = 4096;

/// Bytes of one texel (a vec4 of 32-bit components).
const TEXEL_BYTES: u32 = 16;

/// One mirrored buffer: its texture and view.
struct Mirror {
    name: &'static str,
    /// The WGSL name under which a kernel writes the texture itself (the rebuild's
    /// `gather`), if any.
    write_name: Option<&'static str>,
    source: wgpu::Buffer,
    /// Byte offset of the mirrored field in `source`.
    offset: u64,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

/// The mirrors of one run, all `n` particles wide.
pub struct Mirrors {
    n: u32,
    mirrors: Vec<Mirror>,
}

impl Mirrors {
    /// Textures for `sources` (WGSL global name, the name a kernel writes it under if
    /// any, buffer holding `n` vec4s from a byte offset (a multiple of 16), texel format), or an error naming the limit when `n`
    /// particles need more rows than the adapter allows. No sources: no mirrors (the GPU
    /// path, `shaders/state_buffers.wgsl`), and nothing to copy.
    pub fn new(
        device: &wgpu::Device,
        n: u32,
        sources: &[(
            &'static str,
            Option<&'static str>,
            &wgpu::Buffer,
            u64,
            wgpu::TextureFormat,
        )],
    ) -> Result<Self, PowderError> {
        let rows = n.div_ceil(MIRROR_WIDTH).max(1);
        let max_rows = device.limits().max_texture_dimension_2d;
        if rows > max_rows && !sources.is_empty() {
            return Err(PowderError::Run(format!(
                "{n} particles need {rows} rows of {MIRROR_WIDTH} texels in the force pass's \
                 state mirrors; the adapter allows {max_rows} (at most {} particles)",
                max_rows as u64 * MIRROR_WIDTH as u64
            )));
        }
        let mirrors = sources
            .iter()
            .map(|&(name, write_name, source, offset, format)| {
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(name),
                    size: wgpu::Extent3d {
                        width: MIRROR_WIDTH.min(n.max(1)),
                        height: rows,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                let view = texture.create_view(&Default::default());
                Mirror {
                    name,
                    write_name,
                    source: source.clone(),
                    offset,
                    texture,
                    view,
                }
            })
            .collect();
        Ok(Self { n, mirrors })
    }

    /// Whether there are none (the GPU path).
    pub fn is_empty(&self) -> bool {
        self.mirrors.is_empty()
    }

    /// (WGSL global name, texture view) of every mirror, for binding: under its read name
    /// and, where a kernel writes it, its write name too (the same texture).
    pub fn views(&self) -> Vec<(&'static str, &wgpu::TextureView)> {
        let mut v = Vec::new();
        for m in &self.mirrors {
            v.push((m.name, &m.view));
            if let Some(w) = m.write_name {
                v.push((w, &m.view));
            }
        }
        v
    }

    /// (name, bytes) of every mirror texture (for the memory report).
    pub fn sizes(&self) -> Vec<(String, u64)> {
        self.mirrors
            .iter()
            .map(|m| (format!("mirror.{}", m.name), texture_bytes(&m.texture)))
            .collect()
    }

    /// [`Self::views`] with each texture's bytes (for `Kernel::bound_bytes`).
    pub fn view_bytes(&self) -> Vec<(&'static str, &wgpu::TextureView, u64)> {
        let mut v = Vec::new();
        for m in &self.mirrors {
            let bytes = texture_bytes(&m.texture);
            v.push((m.name, &m.view, bytes));
            if let Some(w) = m.write_name {
                v.push((w, &m.view, bytes));
            }
        }
        v
    }

    /// What [`Self::encode`] moves (`gpu::traffic`): each source's `n` texels read
    /// (`<name>.read`) and written into its texture (`<name>.write`), bytes.
    pub fn copy_traffic(&self) -> Vec<(String, u64)> {
        let bytes = self.n as u64 * TEXEL_BYTES as u64;
        self.mirrors
            .iter()
            .flat_map(|m| {
                [
                    (format!("{}.read", m.name), bytes),
                    (format!("{}.write", m.name), bytes),
                ]
            })
            .collect()
    }

    /// Records the copies of the sources into their mirrors: the whole rows, then the
    /// last, partial one.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let full_rows = self.n / MIRROR_WIDTH;
        let rest = self.n % MIRROR_WIDTH;
        for m in &self.mirrors {
            let mut copy = |row: u32, width: u32, height: u32| {
                encoder.copy_buffer_to_texture(
                    wgpu::TexelCopyBufferInfo {
                        buffer: &m.source,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: m.offset + row as u64 * (MIRROR_WIDTH * TEXEL_BYTES) as u64,
                            bytes_per_row: Some(MIRROR_WIDTH * TEXEL_BYTES),
                            rows_per_image: None,
                        },
                    },
                    wgpu::TexelCopyTextureInfo {
                        texture: &m.texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y: row, z: 0 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                );
            };
            if full_rows > 0 {
                copy(0, MIRROR_WIDTH, full_rows);
            }
            if rest > 0 {
                copy(full_rows, rest, 1);
            }
        }
    }
}

/// Bytes of a mirror texture (whole rows of [`MIRROR_WIDTH`] texels).
fn texture_bytes(texture: &wgpu::Texture) -> u64 {
    let s = texture.size();
    s.width as u64 * s.height as u64 * TEXEL_BYTES as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::{self, wgsl_u32_const};

    #[test]
    fn gpu_mirror_width_matches_wgsl() {
        let kind = &crate::gpu::composition::Composition::all()[0];
        let (module, _) = shaders::validate(
            &kind
                .variant(crate::gpu::composition::Keeps::default(), true, false)
                .source,
        )
        .unwrap();
        assert_eq!(wgsl_u32_const(&module, "MIRROR_WIDTH"), MIRROR_WIDTH);
        assert!(MIRROR_WIDTH.is_power_of_two());
        // a row's bytes meet the buffer-to-texture copy alignment
        assert_eq!(
            (MIRROR_WIDTH * TEXEL_BYTES) % wgpu::COPY_BYTES_PER_ROW_ALIGNMENT,
            0
        );
    }
}
