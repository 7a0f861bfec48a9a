//! `powder bench`: throughput (particle-steps per second, wall time per step) and GPU memory
//! per particle against the particle count, on both backends.
//!
//! Two cases, both the dense packing of [`packing`] (`measure::packing`):
//!
//! * [`Case::Hysteretic`] — the frictionless hysteretic adhesive elasto-plastic model with
//!   the paper's parameters and viscous damping (the cohesive cluster's material);
//! * [`Case::Jkr`] — JKR micro-spheres with Tsuji damping, friction and rolling resistance
//!   (the JKR deposition example's material), so the GPU runs its largest step variant.
//!
//! Each size is warmed up, then a fixed number of steps is timed. A size is skipped — with a
//! note saying why — when it would not fit in memory ([`crate::memory`]), when the adapter
//! refuses it (e.g. the contact history beyond its storage binding limit), or when the rate
//! measured at the previous size predicts more than the per-case time budget; larger sizes
//! of that case and backend are then skipped too. Timings are measured, never asserted.

mod row;
mod run;
mod table;

use crate::cpu::Threads;
use crate::error::{ParamError, PowderError};
use crate::gpu::GpuContext;
use crate::measure::collide::Backend;
use serde::Serialize;

pub use super::packing::{coordination, packing, Case, LATTICE_OVERLAP};
pub use super::provenance::{utc_date, utc_now, Adapter, Machine, Provenance};
pub use row::BenchRow;
use run::{run_cpu, run_gpu};
pub use table::{table_header, table_line};

/// The name of a backend in tables and JSON.
pub fn backend_name(b: Backend) -> &'static str {
    match b {
        Backend::Cpu => "cpu",
        Backend::Gpu => "gpu",
    }
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Particle counts (run in ascending order).
    pub sizes: Vec<usize>,
    /// The packings to run.
    pub cases: Vec<Case>,
    /// The backends to run each on.
    pub backends: Vec<Backend>,
    /// Timed steps per size.
    pub steps: u64,
    /// Untimed steps before the timed ones (pipelines, caches, first neighbour lists).
    pub warmup: u64,
    /// Budget per case and backend: a size whose predicted run time (from the previous
    /// size's rate) exceeds it is skipped, and so are the larger ones, s.
    pub max_seconds: f64,
    /// Multiplies the packing's random velocities (1 = the benchmark; larger values force
    /// more neighbour-list rebuilds, to measure what a rebuild costs).
    pub velocity_scale: f64,
    /// Seed of the packings' jitter and velocities.
    pub seed: u64,
    /// Keep the GPU energy ledger and contact statistics (`GpuOptions::ledger`) during the
    /// timed steps; off by default, so the rate is the step's own cost.
    pub ledger: bool,
    /// After the timed steps, as many more with a GPU timestamp after every pass
    /// (`GpuEngine::profile`).
    pub profile: bool,
    /// Quiet batches of the GPU engine (`GpuOptions::quiet`).
    pub quiet: crate::gpu::QuietBatches,
    /// How the GPU's steps hold a rebuild (`GpuOptions::rebuild_chain`).
    pub rebuild_chain: crate::gpu::RebuildChain,
    /// The software adapter's paths (`GpuOptions::software_paths`; `None`: by the adapter).
    pub software_paths: Option<bool>,
    /// Particles a GPU window holds (`GpuOptions::window_particles`; `None`: chosen).
    pub window_particles: Option<u64>,
    /// Runs per (case, backend, size), each with a fresh engine; the row keeps the fastest
    /// and lists every run's rate (shared machines vary from run to run).
    pub repeats: u32,
    /// The CPU engine's thread counts, each measured as its own series (0: every core);
    /// rows after the first count show their speed-up over it.
    pub threads: Vec<usize>,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            sizes: vec![1_000, 10_000, 100_000, 1_000_000],
            cases: vec![Case::Hysteretic, Case::Jkr],
            backends: vec![Backend::Cpu, Backend::Gpu],
            steps: 128,
            warmup: 32,
            max_seconds: 120.0,
            velocity_scale: 1.0,
            seed: 1,
            ledger: false,
            profile: false,
            quiet: crate::gpu::QuietBatches::Auto,
            rebuild_chain: crate::gpu::RebuildChain::OnDemand,
            software_paths: None,
            window_particles: None,
            repeats: 1,
            threads: vec![0],
        }
    }
}

impl BenchOptions {
    /// Checks the options, naming the offending one.
    pub fn validate(&self) -> Result<(), PowderError> {
        if self.sizes.is_empty() {
            return Err(ParamError::new("sizes", "give at least one particle count").into());
        }
        if let Some(&n) = self.sizes.iter().find(|&&n| n == 0) {
            return Err(
                ParamError::new("sizes", format!("particle counts must be >= 1, got {n}")).into(),
            );
        }
        if self
            .sizes
            .iter()
            .any(|&n| n as u64 > crate::scene::MAX_BLOCK_PARTICLES)
        {
            return Err(ParamError::new(
                "sizes",
                format!(
                    "particle counts must be <= {}",
                    crate::scene::MAX_BLOCK_PARTICLES
                ),
            )
            .into());
        }
        if self.cases.is_empty() || self.backends.is_empty() {
            return Err(ParamError::new("case", "nothing to measure").into());
        }
        if self.steps == 0 {
            return Err(ParamError::new("steps", "time at least one step").into());
        }
        if self.repeats == 0 {
            return Err(ParamError::new("repeats", "run each size at least once").into());
        }
        if self.threads.is_empty() {
            return Err(ParamError::new("threads", "give at least one thread count").into());
        }
        if let Some(t) = self
            .threads
            .iter()
            .find(|&&t| t > crate::cpu::threads::MAX_THREADS)
        {
            return Err(ParamError::new(
                "threads",
                format!(
                    "{t} threads is more than the {} allowed (0 means every core)",
                    crate::cpu::threads::MAX_THREADS
                ),
            )
            .into());
        }
        if let Some(w) = self.window_particles {
            crate::gpu::window::valid_len(w).map_err(|e| ParamError::new("window-particles", e))?;
        }
        crate::error::require_positive("max-seconds", self.max_seconds, "the time budget")?;
        crate::error::require_non_negative(
            "velocity-scale",
            self.velocity_scale,
            "the velocity scale",
        )?;
        Ok(())
    }
}

/// The whole benchmark, as `--json` writes it.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Version, commit, date and machine (flattened into the top level of the JSON).
    #[serde(flatten)]
    pub provenance: Provenance,
    /// The GPU adapter (null when the GPU backend was not measured or has no adapter).
    pub adapter: Option<Adapter>,
    /// Timed steps per size (the other options as in [`BenchOptions`]).
    pub steps: u64,
    /// Untimed steps before the timed ones.
    pub warmup: u64,
    /// Time budget per case and backend, s.
    pub max_seconds: f64,
    /// Multiplier of the packings' random velocities.
    pub velocity_scale: f64,
    /// Seed of the packings.
    pub seed: u64,
    /// Whether the GPU kept its energy ledger during the timed steps (its rows are in the
    /// bytes per particle).
    pub ledger: bool,
    /// One row per (case, backend, size), in that order.
    pub rows: Vec<BenchRow>,
}

/// Runs the benchmark, calling `progress` after every row. A GPU backend without an
/// adapter is an error when it is the only backend asked for; with the CPU also asked
/// for, its rows are skipped with the reason.
pub fn bench(
    opts: &BenchOptions,
    mut progress: impl FnMut(&BenchRow),
) -> Result<BenchReport, PowderError> {
    opts.validate()?;
    let mut sizes = opts.sizes.clone();
    sizes.sort_unstable();
    sizes.dedup();
    let provenance = Provenance::now();
    let mut adapter = None;
    let mut gpu_error = None;
    if opts.backends.contains(&Backend::Gpu) {
        match GpuContext::new() {
            Ok(ctx) => adapter = Some(Adapter::of(&ctx)),
            Err(e) if opts.backends.len() == 1 => return Err(e),
            Err(e) => gpu_error = Some(e.to_string()),
        }
    }
    let software = adapter.as_ref().is_some_and(|a| a.device_type == "Cpu");
    let mut rows = Vec::new();
    // the series: each backend, the CPU once per thread count
    let mut series: Vec<(Backend, Option<Threads>)> = Vec::new();
    for &backend in &opts.backends {
        match backend {
            Backend::Cpu => {
                for &t in &opts.threads {
                    series.push((backend, Some(Threads::new(t)?)));
                }
            }
            Backend::Gpu => series.push((backend, None)),
        }
    }
    for &case in &opts.cases {
        for (backend, threads) in &series {
            let backend = *backend;
            // (particles, s per particle-step, setup s per particle, bytes per particle)
            let mut last: Option<(usize, f64, f64, f64)> = None;
            let mut stopped: Option<String> = None;
            for &n in &sizes {
                let skip = |note: String| BenchRow {
                    threads: threads.as_ref().map(Threads::count),
                    ..BenchRow::skipped(case, backend, n, opts.steps, note)
                };
                let row = if let Some(why) = &stopped {
                    skip(format!("not run: {why}"))
                } else if let (Backend::Gpu, Some(e)) = (backend, &gpu_error) {
                    skip(format!("no GPU adapter: {e}"))
                } else if let Some(why) = predicted_over_budget(last, n, opts) {
                    stopped = Some(format!("N = {n} was skipped by the time budget"));
                    skip(why)
                } else if let Err(why) = fits(backend, n, last, software) {
                    stopped = Some(format!("N = {n} did not fit in memory"));
                    skip(why)
                } else {
                    let scene = packing(case, n, opts.velocity_scale, opts.seed)?;
                    let result = best_of(opts.repeats, || match threads {
                        Some(threads) => run_cpu(&scene, case, threads, opts),
                        None => {
                            let ctx = match opts.profile {
                                true => GpuContext::with_timestamps()?,
                                false => GpuContext::new()?,
                            };
                            run_gpu(&scene, case, ctx, opts)
                        }
                    });
                    match result {
                        Ok(row) => row,
                        Err(e) => {
                            stopped = Some(format!("N = {n} failed"));
                            // (the packing's only knob for its speeds is bench's own)
                            let knob = if opts.velocity_scale > 1.0 {
                                format!(" [the packing's velocities are scaled by --velocity-scale {}: lower it]", opts.velocity_scale)
                            } else {
                                String::new()
                            };
                            BenchRow {
                                status: "failed",
                                ..skip(format!("failed: {e}{knob}"))
                            }
                        }
                    }
                };
                let mut row = row;
                row.speedup = speedup(&rows, &row);
                if let (Some(wall), Some(setup)) = (row.wall_seconds, row.setup_seconds) {
                    let work = (n as f64 * opts.steps as f64).max(1.0);
                    last = Some((
                        n,
                        wall / work,
                        setup / n as f64,
                        row.gpu_bytes_per_particle.unwrap_or(0.0),
                    ));
                }
                progress(&row);
                rows.push(row);
            }
        }
    }
    Ok(BenchReport {
        provenance,
        adapter,
        steps: opts.steps,
        warmup: opts.warmup,
        max_seconds: opts.max_seconds,
        velocity_scale: opts.velocity_scale,
        seed: opts.seed,
        ledger: opts.ledger,
        rows,
    })
}

/// A CPU row's rate over the rate of the first thread count's row of the same case and
/// size (None for that row itself, and where either did not run).
fn speedup(rows: &[BenchRow], row: &BenchRow) -> Option<f64> {
    if row.backend != "cpu" {
        return None;
    }
    let first = rows
        .iter()
        .find(|r| r.backend == "cpu" && r.case == row.case && r.particles == row.particles)?;
    if first.threads == row.threads {
        return None;
    }
    Some(row.particle_steps_per_second? / first.particle_steps_per_second?)
}

/// The fastest of `repeats` runs, with every run's rate in `runs` (the first error stops).
fn best_of(
    repeats: u32,
    mut run: impl FnMut() -> Result<BenchRow, PowderError>,
) -> Result<BenchRow, PowderError> {
    let rate = |r: &BenchRow| r.particle_steps_per_second.unwrap_or(0.0);
    let mut best: Option<BenchRow> = None;
    let mut runs = Vec::new();
    for _ in 0..repeats.max(1) {
        let row = run()?;
        runs.push(rate(&row));
        if best.as_ref().is_none_or(|b| rate(&row) > rate(b)) {
            best = Some(row);
        }
    }
    let mut best = best.expect("at least one run");
    best.runs = runs;
    Ok(best)
}

/// Why size `n` would exceed the time budget, predicted from the last measured size
/// (stepping time scaled linearly in N; set-up likewise).
fn predicted_over_budget(
    last: Option<(usize, f64, f64, f64)>,
    n: usize,
    opts: &BenchOptions,
) -> Option<String> {
    let (n_prev, per_particle_step, setup_per_particle, _) = last?;
    let predicted = opts.repeats.max(1) as f64
        * n as f64
        * ((opts.warmup + opts.steps) as f64 * per_particle_step + setup_per_particle);
    (predicted > opts.max_seconds).then(|| {
        format!(
            "skipped: predicted {} s from the rate at N = {n_prev}, over the budget of {} s per case (--max-seconds)",
            crate::error::num(predicted),
            crate::error::num(opts.max_seconds)
        )
    })
}

/// Whether `n` particles fit in the host memory (the CPU engine; the GPU engine's buffers
/// when the adapter is a software one, whose device memory is host memory).
fn fits(
    backend: Backend,
    n: usize,
    last: Option<(usize, f64, f64, f64)>,
    software: bool,
) -> Result<(), String> {
    // the scene itself (ParticleInit) and the set-up's copies
    let scene_bytes = 256;
    let (per_particle, what) = match backend {
        Backend::Cpu => (
            crate::memory::CPU_BYTES_PER_PARTICLE + scene_bytes,
            "the CPU engine",
        ),
        Backend::Gpu if software => {
            let device = last.map_or(4096.0, |l| l.3.max(1.0) * 1.25);
            (
                device as u64 + scene_bytes,
                "the GPU engine's buffers (a software adapter: in host memory)",
            )
        }
        Backend::Gpu => (scene_bytes, "the scene"),
    };
    crate::memory::check_particles(n as u64, per_particle, what)
        .map_err(|e| format!("skipped: {e}"))
}

/// Parses `--sizes`: comma-separated counts, each an integer or a float like `1e5`.
pub fn parse_sizes(text: &str) -> Result<Vec<usize>, PowderError> {
    let bad = |item: &str, why: &str| {
        PowderError::from(ParamError::new(
            "sizes",
            format!("`{item}` {why}; expected comma-separated particle counts, e.g. 1e3,1e4,1e5"),
        ))
    };
    let mut sizes = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let value: f64 = item.parse().map_err(|_| bad(item, "is not a number"))?;
        if !(value >= 1.0 && value.is_finite() && value.fract() == 0.0) {
            return Err(bad(item, "is not a whole number >= 1"));
        }
        sizes.push(value as usize);
    }
    if sizes.is_empty() {
        return Err(bad(text, "holds no count"));
    }
    Ok(sizes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_bad_ones_are_named() {
        assert_eq!(parse_sizes("1e3, 20000,5").unwrap(), vec![1000, 20000, 5]);
        for bad in ["", "0", "1.5", "abc", "-3"] {
            let e = parse_sizes(bad).unwrap_err().to_string();
            assert!(e.contains("sizes"), "{bad}: {e}");
        }
    }

    #[test]
    fn budget_prediction_skips_what_would_take_too_long() {
        let opts = BenchOptions {
            max_seconds: 10.0,
            steps: 100,
            warmup: 0,
            ..Default::default()
        };
        // 1e-6 s per particle-step: 1e4 particles x 100 steps = 1 s, 1e6 = 100 s
        let last = Some((1000, 1e-6, 0.0, 0.0));
        assert!(predicted_over_budget(last, 10_000, &opts).is_none());
        let why = predicted_over_budget(last, 1_000_000, &opts).unwrap();
        assert!(why.contains("--max-seconds"), "{why}");
        assert!(predicted_over_budget(None, 1_000_000, &opts).is_none());
    }
}
