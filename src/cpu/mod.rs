//! The CPU reference backend in f64: the yardstick for the GPU path.

pub mod cells;
pub mod engine;

pub use engine::{ContactStats, CpuEngine, CpuState, Energies, Partner};
