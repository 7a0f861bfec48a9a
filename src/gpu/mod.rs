//! The GPU engine (wgpu + WGSL compute), built brick by brick next to the f64 CPU
//! reference in [`crate::cpu`].
//!
//! # Architecture
//!
//! * **Device** ([`context`]): one [`GpuContext`] per run — the best adapter present
//!   (discrete > integrated > virtual GPU, else the software adapter: Mesa lavapipe on
//!   Vulkan or llvmpipe on GL), chosen or overridden with `POWDER_ADAPTER`, opened with
//!   the adapter's own limits and no optional features (a pass profile's context adds
//!   the timestamps of [`timestamps`]). `powder info` prints it.
//! * **Portability**: kernels are core WGSL — f32 arithmetic, u32/i32 atomics, no f64,
//!   no float atomics, no subgroups — so the same code runs on Vulkan, Metal, DX12 and
//!   GL, on any GPU and on the CPU rasterisers used in CI. Storage bindings may be
//!   capped (128 MiB on lavapipe): where the arrays do not fit one binding the particles
//!   are cut into windows ([`window`]) whose dispatches bind a window and its neighbours
//!   only, and the lists' entries beyond the largest buffer go into pages of windows
//!   ([`pages`]); what still does not fit is refused at construction with an error naming
//!   the array, and dispatches larger than `max_compute_workgroups_per_dimension` are split
//!   over y/z.
//! * **Positions** ([`layout`]): an integer cell (`vec4<i32>`, w = material) plus an f32
//!   offset inside the cell (`vec4<f32>`, w = radius). Separations are formed as
//!   `(cell_i - cell_j) h + (off_i - off_j)`, so the overlaps that drive the contact
//!   forces keep f32's relative precision anywhere in the domain, while f32 absolute
//!   positions would lose them ~1e4 diameters from the origin. The cell width `h`
//!   (>= the largest interaction distance + the Verlet skin) is also the neighbour
//!   grid's, fixed for a run, with the origin at the domain's min corner.
//! * **Shaders** ([`shaders`], top-level `shaders/`): one WGSL file per stage, each
//!   module composed as `common.wgsl` + feature snippets + the stage file, and every
//!   variant validated with naga in a unit test (no GPU needed). Model variants of the
//!   force kernels are further entries, switched by composed snippets or WGSL
//!   `override` constants. [`kernel`] turns a variant into pipelines (one per entry
//!   point, automatic layouts, bindings found by name through naga's reflection).
//! * **Neighbour grid** ([`grid`]): a deterministic counting sort of particles by
//!   clamped cell key — keys, atomic counts, a multi-level exclusive scan, an atomic
//!   scatter, then a per-cell sort by original index that removes the atomics' racy
//!   order — giving `sorted_index`, `cell_start` and `cell_count`, bit-identical to a
//!   stable CPU counting sort and from run to run.
//! * **Stepping** ([`engine`]): drift, a rebuild where some particle moved more than half
//!   the Verlet skin (sort, re-sort in place, new lists from the 27 neighbouring cells,
//!   each contact's history carried over by its partner's id), the contact forces, the
//!   kick — dispatches recorded into one command encoder per batch of steps, because a
//!   submission and wait costs many dispatches' time. Results are read back only for
//!   output; the CPU engine stays the reference the GPU one is tested against.

pub mod composition;
pub mod context;
pub mod engine;
pub mod grid;
pub mod kernel;
pub mod layout;
pub mod mirror;
pub mod pages;
pub mod permute;
pub mod quiet;
pub mod records;
pub mod shaders;
pub mod state;
pub mod timestamps;
pub mod traffic;
pub mod window;

pub use context::{AdapterPreference, AdapterSummary, GpuContext, LimitsSummary};
pub use engine::{GpuEngine, GpuOptions, GpuSavedState, GpuState, RebuildChain};
pub use grid::{ExclusiveScan, GridSort, SortResult};
pub use layout::{decode, encode, CellCoord, CellOffset, GridParams, PackedPosition};
pub use quiet::QuietBatches;
pub use shaders::{all_variants, validate, ShaderVariant};
pub use traffic::{PassTraffic, TrafficEstimate};
