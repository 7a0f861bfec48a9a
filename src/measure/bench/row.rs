//! One (case, backend, size) of `powder bench`: what it measured and how the row reads.

use serde::Serialize;

use super::{backend_name, Case};
use crate::measure::collide::Backend;

/// One (case, backend, size) of the benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// `hysteretic` or `jkr`.
    pub case: &'static str,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// CPU: the threads the engine ran on.
    pub threads: Option<usize>,
    /// CPU: the rate over the rate of the first thread count measured (`--threads 1,2`:
    /// the speed-up from 1 to 2 threads).
    pub speedup: Option<f64>,
    /// N.
    pub particles: usize,
    /// `ran`, `skipped` (by the time or memory budget, or after a larger size stopped) or
    /// `failed` (the engine refused or stopped, e.g. over the adapter's storage binding
    /// limit); the reason is in `note`.
    pub status: &'static str,
    /// Why a size was skipped or failed.
    pub note: Option<String>,
    /// Time step, s.
    pub dt: Option<f64>,
    /// Timed steps (after `warmup` untimed ones).
    pub steps: u64,
    /// Building the engine (upload, pipelines, first neighbour lists), s.
    pub setup_seconds: Option<f64>,
    /// Wall time of the timed steps, s.
    pub wall_seconds: Option<f64>,
    /// `wall_seconds / steps`, s.
    pub seconds_per_step: Option<f64>,
    /// `particles · steps / wall_seconds`.
    pub particle_steps_per_second: Option<f64>,
    /// Device buffers of the GPU engine (`GpuEngine::buffer_bytes`), bytes.
    pub gpu_bytes: Option<u64>,
    /// `gpu_bytes / particles`.
    pub gpu_bytes_per_particle: Option<f64>,
    /// GPU: the device buffers by name, bytes (`GpuEngine::buffers`: where the bytes go).
    pub gpu_buffers: Option<Vec<(String, u64)>>,
    /// Entries the GPU engine's neighbour lists had room for at the end (grown to 1.25×
    /// what a rebuild needs).
    pub list_entries: Option<u64>,
    /// GPU: the windows the particles were blocked into (particles a window, windows;
    /// `gpu::window`).
    pub windows: Option<(u64, u64)>,
    /// Neighbour-list rebuilds during the timed steps (both backends keep a Verlet list
    /// with a skin).
    pub rebuilds: Option<u64>,
    /// GPU: quiet batches kept and rolled back during the timed steps (`gpu::quiet`).
    pub quiet_batches: Option<(u64, u64)>,
    /// GPU: batches halted for a rebuild due in a step recorded without one during the
    /// timed steps (`RebuildChain::OnDemand`).
    pub rebuild_halts: Option<u64>,
    /// GPU: compute dispatches a step records, without and with a rebuild's passes
    /// (`GpuEngine::dispatches_per_step`).
    pub dispatches_per_step: Option<[usize; 2]>,
    /// The particle-steps per second of every run (`--repeats`); the row is the fastest.
    pub runs: Vec<f64>,
    /// Particle–particle contacts per particle at the end (shows the packing is dense).
    pub contacts_per_particle: Option<f64>,
    /// GPU with `--profile`: the device time of each pass over as many steps again as
    /// were timed (`GpuEngine::profile`).
    pub passes: Option<crate::gpu::timestamps::PassProfile>,
    /// GPU: the bytes each pass binds and the estimate of bytes moved per particle-step
    /// with the rebuilds of the timed steps (`gpu::traffic`; an upper bound).
    pub traffic: Option<crate::gpu::TrafficEstimate>,
}

impl BenchRow {
    pub(super) fn skipped(
        case: Case,
        backend: Backend,
        n: usize,
        steps: u64,
        note: String,
    ) -> Self {
        Self {
            case: case.name(),
            backend: backend_name(backend),
            threads: None,
            speedup: None,
            particles: n,
            status: "skipped",
            note: Some(note),
            dt: None,
            steps,
            setup_seconds: None,
            wall_seconds: None,
            seconds_per_step: None,
            particle_steps_per_second: None,
            gpu_bytes: None,
            gpu_buffers: None,
            gpu_bytes_per_particle: None,
            list_entries: None,
            windows: None,
            rebuilds: None,
            quiet_batches: None,
            rebuild_halts: None,
            dispatches_per_step: None,
            runs: Vec::new(),
            contacts_per_particle: None,
            passes: None,
            traffic: None,
        }
    }
}
