//! The CPU reference backend in f64: the yardstick for the GPU path.

pub mod cells;
pub mod engine;
pub mod jump;
pub mod threads;

pub use engine::{ContactStats, CpuEngine, CpuState, Energies, Partner};
pub use threads::Threads;
