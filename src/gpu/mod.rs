//! The GPU engine (wgpu + WGSL compute): the CPU engine's scenes in f32, tested against
//! the f64 reference in [`crate::cpu`]. Core WGSL only, so it runs on every backend and
//! adapter wgpu supports, the software rasterisers included.
//!
//! [`GpuEngine`] steps a run: drift, a rebuild of the neighbour lists where some particle
//! moved more than half the Verlet skin, the contact forces, the kick — many steps recorded
//! into one command encoder, results read back only for output. What each submodule does:
//! `docs/architecture.md`, *The crate map*; the design: *The GPU engine* there.

pub mod adapter;
pub mod composition;
pub mod context;
pub mod control;
pub mod engine;
pub mod grid;
pub mod kernel;
pub mod layout;
pub mod mirror;
pub mod pages;
pub mod permute;
pub mod quiet;
pub mod records;
pub mod scan;
mod section;
pub mod shaders;
pub mod state;
pub mod timestamps;
pub mod traffic;
pub mod window;

pub use adapter::{AdapterPreference, AdapterSummary, LimitsSummary};
pub use context::GpuContext;
pub use engine::{GpuEngine, GpuOptions, GpuSavedState, GpuState, RebuildChain};
pub use grid::{GridSort, SortResult};
pub use layout::{decode, encode, CellCoord, CellOffset, GridParams, PackedPosition};
pub use quiet::QuietBatches;
pub use scan::ExclusiveScan;
pub use shaders::{all_variants, validate, ShaderVariant};
pub use traffic::{PassTraffic, TrafficEstimate};
