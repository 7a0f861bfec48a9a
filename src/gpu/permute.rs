//! A rebuild's re-sort of the particle state, in place, through one scratch buffer
//! (`shaders/permute.wgsl`): the state's fields move in groups of up to [`ROW_WORDS`] words
//! a particle (each a [`Field`]; a wider field alone), so the scratch holds one group's row
//! a particle instead of a second copy of the whole state. `n` groups take `n + 1`
//! dispatches (each stores the previous group and loads the next). The scratch may be
//! lent: a buffer idle while the re-sort runs (the new lists', written only after it).

use crate::error::PowderError;
use crate::gpu::context::GpuContext;
use crate::gpu::kernel::{storage_buffer, uniform_buffer, Kernel, Program};
use crate::gpu::pages::Pages;
use crate::gpu::shaders;
use crate::gpu::window::{Paged, WindowBindings};

/// Words of a scratch row: the fields moved in one dispatch (a particle's field is never
/// split, so a wider one takes a row of its own).
pub const ROW_WORDS: u32 = 8;

/// Where a field lies in its buffer (`Field` in `shaders/permute.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FieldPlace {
    /// u32 words per particle and block.
    pub words: u32,
    /// Blocks (fields of the state moved together; 1 otherwise).
    pub blocks: u32,
    /// First word of block 0.
    pub base: u32,
    /// Words from one block to the next.
    pub stride: u32,
}

/// One dispatch's parameters (`Move` in `shaders/permute.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MoveParams {
    /// The field stored from the scratch (words 0: none).
    pub store: FieldPlace,
    /// The field loaded into the scratch (words 0: none).
    pub load: FieldPlace,
    /// Scratch words per particle.
    pub row: u32,
    /// Words of a window's block of the stored field's buffer (0: one window).
    pub store_window: u32,
    /// Words of a window's block of the loaded field's buffer.
    pub load_window: u32,
    /// Words of a window's block of the scratch.
    pub scratch_window: u32,
    /// The scratch's first word in a window's block.
    pub scratch_base: u32,
}

/// One field of the particle state to re-sort.
#[derive(Clone, Debug)]
pub struct Field {
    /// Name, for traffic reports (`permute <name>`).
    pub name: String,
    buffer: wgpu::Buffer,
    /// The buffer's pages where the state is in pages (`gpu::pages`; empty: one buffer).
    pages: Vec<wgpu::Buffer>,
    place: FieldPlace,
    /// Words of a window's block of the buffer (0 with one window).
    window: u32,
}

impl Field {
    /// `bytes` per particle (a multiple of 4), particle k at byte k·bytes.
    pub fn per_particle(name: &str, buffer: &wgpu::Buffer, bytes: u64) -> Self {
        Self {
            name: name.to_string(),
            buffer: buffer.clone(),
            pages: Vec::new(),
            place: FieldPlace {
                words: (bytes / 4) as u32,
                blocks: 1,
                base: 0,
                stride: 0,
            },
            window: 0,
        }
    }

    /// The field in a buffer blocked by window (`gpu::window`), `words` a window's block:
    /// `base` and `stride` are then within a block, and the particle's index its index in
    /// its window.
    pub fn windowed(mut self, words: u32) -> Self {
        self.window = words;
        self
    }

    /// `blocks` consecutive regions of one buffer, each `words` u32 per particle, the first
    /// at word `base`, `stride` words apart: moved together (`blocks · words` at most
    /// [`ROW_WORDS`] unless a single region is wider).
    pub fn regions(
        name: &str,
        buffer: &wgpu::Buffer,
        words: u32,
        (base, stride, blocks): (u32, u32, u32),
    ) -> Self {
        Self {
            name: name.to_string(),
            buffer: buffer.clone(),
            pages: Vec::new(),
            place: FieldPlace {
                words,
                blocks,
                base,
                stride,
            },
            window: 0,
        }
    }

    /// The field in a buffer cut into `pages` as the state is ([`WindowBindings::state_pages`]).
    pub fn in_pages(mut self, pages: &[wgpu::Buffer]) -> Self {
        self.pages = pages.to_vec();
        self
    }

    /// The field's buffer as bound page by page under `name` (`other`: the other page's
    /// binding), cut as `state_pages` where it has pages.
    fn paged<'a>(&'a self, name: &'a str, other: Option<&'a str>, state_pages: Pages) -> Paged<'a> {
        match self.pages.is_empty() {
            true => Paged {
                name,
                pages: std::slice::from_ref(&self.buffer),
                layout: Pages {
                    windows: 1,
                    count: 1,
                },
                other,
            },
            false => Paged {
                name,
                pages: &self.pages,
                layout: state_pages,
                other,
            },
        }
    }

    /// Words one particle has in this field.
    fn row_words(&self) -> u32 {
        self.place.words * self.place.blocks
    }
}

/// One dispatch of the re-sort.
struct Move {
    /// One a window.
    groups: Vec<wgpu::BindGroup>,
    /// `permute <field loaded>` (or the last field stored).
    name: String,
    /// What it touches, as (name, bytes) (`gpu::traffic`).
    touched: Vec<(String, u64)>,
}

/// The re-sort of one run's state: the kernel, the scratch and a bind group per dispatch.
pub struct Permutation {
    kernel: Kernel,
    /// Scratch words a particle: the widest field's.
    row: u32,
    /// The scratch where it is the re-sort's own (none where it is lent).
    own: Option<wgpu::Buffer>,
    moves: Vec<Move>,
}

/// Part of a buffer the re-sort may use as its scratch: in each window's `block` bytes,
/// `bytes` from byte `base`.
pub struct Lent<'a> {
    /// The buffer.
    pub buffer: &'a wgpu::Buffer,
    /// Bytes of a window's block of it.
    pub block: u64,
    /// Where the lent part starts in a block, bytes.
    pub base: u64,
    /// Bytes of the lent part of a block.
    pub bytes: u64,
}

impl Permutation {
    /// The re-sort of `fields` for `n` particles by the grid sort's `sorted_index` (the
    /// k-th particle of the new order was `sorted_index[k]`), with `grid` its parameters.
    /// Dispatched once a window of `windowing` (the fields' buffers and the scratch bound
    /// a window and its neighbours at a time where there are several). The scratch is
    /// `lent` where a window's block of it holds a row a particle, else its own.
    pub fn new(
        ctx: &GpuContext,
        (grid, sorted_index): (&wgpu::Buffer, &wgpu::Buffer),
        n: u32,
        fields: &[Field],
        (windowing, lent): (&WindowBindings, Option<Lent>),
    ) -> Result<Self, PowderError> {
        let variant = shaders::stage("permute").expect("permute is a stage");
        let program = Program::new(ctx, &variant)?;
        let kernel = program.kernel("permute")?.clone();
        let row = fields
            .iter()
            .map(Field::row_words)
            .max()
            .unwrap_or(1)
            .max(1);
        let mut p = Self {
            kernel,
            row,
            own: None,
            moves: Vec::new(),
        };
        p.bind(ctx, (grid, sorted_index), n, fields, (windowing, lent))?;
        Ok(p)
    }

    /// Binds the re-sort anew (the fields, the scratch lent or its own): after the lent
    /// buffer was replaced.
    pub fn bind(
        &mut self,
        ctx: &GpuContext,
        (grid, sorted_index): (&wgpu::Buffer, &wgpu::Buffer),
        n: u32,
        fields: &[Field],
        (windowing, lent): (&WindowBindings, Option<Lent>),
    ) -> Result<(), PowderError> {
        let windows = &windowing.windows;
        let row = self.row;
        // a row a particle, blocked by window like the state where there are several
        let block = 4 * row as u64 * windows.len;
        let lent = lent.filter(|l| l.bytes >= block);
        self.own = None;
        if lent.is_none() {
            let (scratch_bytes, bound_bytes) = match windows.count {
                1 => (4 * row as u64 * n as u64, 4 * row as u64 * n as u64),
                count => (count * block, windows.covered() * block),
            };
            if bound_bytes > ctx.max_storage_binding() {
                return Err(PowderError::Run(format!(
                    "the re-sort's scratch needs {bound_bytes} bytes for {n} particles bound at a time, over the adapter's storage binding limit of {} bytes",
                    ctx.max_storage_binding()
                )));
            }
            self.own = Some(storage_buffer(
                &ctx.device,
                "permute.scratch",
                scratch_bytes,
            ));
        }
        let (scratch, scratch_block, scratch_base) = match (lent, &self.own) {
            (Some(l), _) => (l.buffer, l.block, l.base),
            (None, Some(own)) => (own, block, 0),
            (None, None) => unreachable!("the scratch is lent or the re-sort's own"),
        };
        let none = FieldPlace::default();
        let mut moves = Vec::with_capacity(fields.len() + 1);
        for i in 0..=fields.len() {
            let store = i.checked_sub(1).map(|p| &fields[p]);
            let load = fields.get(i);
            let Some(any) = load.or(store) else {
                break;
            };
            let params = MoveParams {
                store: store.map_or(none, |f| f.place),
                load: load.map_or(none, |f| f.place),
                row,
                store_window: store.map_or(0, |f| f.window),
                load_window: load.map_or(0, |f| f.window),
                scratch_window: (scratch_block / 4) as u32,
                scratch_base: (scratch_base / 4) as u32,
            };
            let uniform = uniform_buffer(&ctx.device, "permute.move", bytemuck::bytes_of(&params));
            let (stored, loaded) = (store.unwrap_or(any), load.unwrap_or(any));
            let blocks = [
                ("scratch", scratch_block),
                ("stored", 4 * stored.window as u64),
                ("loaded", 4 * loaded.window as u64),
            ];
            let groups = windowing.groups(
                &ctx.device,
                &self.kernel,
                (
                    &[
                        ("grid", grid),
                        ("mv", &uniform),
                        ("sorted_index", sorted_index),
                        ("scratch", scratch),
                        ("stored", &stored.buffer),
                        ("loaded", &loaded.buffer),
                    ],
                    &blocks,
                ),
                &[],
                &[
                    stored.paged("stored", None, windowing.state_pages),
                    loaded.paged("loaded", Some("loaded_x"), windowing.state_pages),
                ],
            )?;
            let touched = |f: &Field| 4 * f.row_words() as u64 * n as u64;
            let scratch_touched = store.map_or(0, touched) + load.map_or(0, touched);
            let mut bound = vec![
                ("sorted_index".to_string(), 4 * n as u64),
                ("scratch".to_string(), scratch_touched),
            ];
            bound.extend(store.map(|f| (format!("stored {}", f.name), touched(f))));
            bound.extend(load.map(|f| (format!("loaded {}", f.name), touched(f))));
            let touched = bound;
            let name = match load {
                Some(f) => format!("permute {}", f.name),
                None => format!("permute (store {})", any.name),
            };
            moves.push(Move {
                groups,
                name,
                touched,
            });
        }
        self.moves = moves;
        Ok(())
    }

    /// The bytes of the re-sort's own scratch buffer (0 where it is lent).
    pub fn scratch_bytes(&self) -> u64 {
        self.own.as_ref().map_or(0, wgpu::Buffer::size)
    }

    /// Dispatches of one re-sort.
    pub fn dispatches(&self) -> usize {
        self.moves.len()
    }

    /// Records the re-sort's dispatches, each with workgroup counts from `args` at
    /// `offset` (one invocation per particle in workgroups of `WG_SIZE`; zeros: none).
    /// Returns the dispatches recorded.
    pub fn encode_indirect(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        args: &wgpu::Buffer,
        offset: u64,
    ) -> usize {
        for m in &self.moves {
            for group in &m.groups {
                self.kernel.dispatch_indirect(pass, group, args, offset);
            }
        }
        self.moves.iter().map(|m| m.groups.len()).sum()
    }

    /// Records the re-sort's dispatches for `n` particles a window (`Kernel::dispatch`).
    pub fn encode(&self, pass: &mut wgpu::ComputePass<'_>, n: u32, max_per_dim: u32) {
        for m in &self.moves {
            for group in &m.groups {
                self.kernel.dispatch(pass, group, n, max_per_dim);
            }
        }
    }

    /// (pass name, what it touches as (name, bytes)) per dispatch, for `gpu::traffic`:
    /// the scratch row is written and read once, each field's words once.
    pub fn traffic(&self) -> Vec<(String, Vec<(String, u64)>)> {
        self.moves
            .iter()
            .map(|m| (m.name.clone(), m.touched.clone()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_permute_params_match_the_shader_layout() {
        let source = shaders::stage("permute").expect("a stage").source;
        let (module, _) = shaders::validate(&source).expect("permute.wgsl validates");
        let size = |name: &str| {
            module
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .map(|(_, t)| t.inner.size(module.to_ctx()))
                .expect("struct present")
        };
        assert_eq!(size("Field") as usize, std::mem::size_of::<FieldPlace>());
        assert_eq!(size("Move") as usize, std::mem::size_of::<MoveParams>());
    }
}
