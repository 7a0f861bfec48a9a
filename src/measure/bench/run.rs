//! One size of one case timed on each backend: warm-up, then the timed steps.

use std::time::Instant;

use super::{coordination, BenchOptions, BenchRow, Case};
use crate::cpu::{CpuEngine, Threads};
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine};
use crate::scene::Scene;

pub(super) fn run_cpu(
    scene: &Scene,
    case: Case,
    threads: &Threads,
    opts: &BenchOptions,
) -> Result<BenchRow, PowderError> {
    let n = scene.particles.len();
    let t0 = Instant::now();
    let mut engine = CpuEngine::with_threads(scene, threads.clone())?;
    let setup = t0.elapsed().as_secs_f64();
    engine.run_steps(opts.warmup)?;
    let before = engine.rebuilds();
    let t1 = Instant::now();
    engine.run_steps(opts.steps)?;
    let wall = t1.elapsed().as_secs_f64();
    let rebuilds = engine.rebuilds() - before;
    let z = coordination(scene, engine.positions(), engine.radii())?;
    Ok(BenchRow {
        case: case.name(),
        backend: "cpu",
        threads: Some(threads.count()),
        speedup: None,
        particles: n,
        status: "ran",
        note: None,
        dt: Some(engine.dt()),
        steps: opts.steps,
        setup_seconds: Some(setup),
        wall_seconds: Some(wall),
        seconds_per_step: Some(wall / opts.steps as f64),
        particle_steps_per_second: Some(n as f64 * opts.steps as f64 / wall.max(1e-12)),
        gpu_bytes: None,
        gpu_buffers: None,
        gpu_bytes_per_particle: None,
        list_entries: None,
        windows: None,
        rebuilds: Some(rebuilds),
        quiet_batches: None,
        rebuild_halts: None,
        dispatches_per_step: None,
        runs: Vec::new(),
        contacts_per_particle: Some(z),
        passes: None,
        traffic: None,
    })
}

pub(super) fn run_gpu(
    scene: &Scene,
    case: Case,
    ctx: GpuContext,
    opts: &BenchOptions,
) -> Result<BenchRow, PowderError> {
    let n = scene.particles.len();
    let t0 = Instant::now();
    let mut engine = GpuEngine::with_options(
        scene,
        ctx,
        crate::gpu::GpuOptions {
            ledger: opts.ledger,
            quiet: opts.quiet,
            rebuild_chain: opts.rebuild_chain,
            software_paths: opts.software_paths,
            window_particles: opts.window_particles,
            ..Default::default()
        },
    )?;
    let setup = t0.elapsed().as_secs_f64();
    engine.run_steps(opts.warmup)?;
    let before = engine.rebuilds()?;
    let quiet_before = engine.quiet_batches();
    let halts_before = engine.rebuild_halts();
    let t1 = Instant::now();
    // run_steps waits for the device after every batch, so the clock sees the work done
    engine.run_steps(opts.steps)?;
    let wall = t1.elapsed().as_secs_f64();
    let rebuilds = engine.rebuilds()? - before;
    let quiet = engine.quiet_batches();
    let halts = engine.rebuild_halts() - halts_before;
    let quiet = (quiet.0 - quiet_before.0, quiet.1 - quiet_before.1);
    let state = engine.state()?;
    let z = coordination(scene, &state.positions, engine.radii())?;
    let bytes = engine.buffer_bytes();
    let buffers = engine.buffers();
    let traffic = crate::gpu::TrafficEstimate::new(engine.traffic(), n, rebuilds, opts.steps);
    let (dt, entries) = (engine.dt(), engine.list_entries());
    let windows = engine.windows();
    // after the timed steps, as many again with a timestamp after every pass (an adapter
    // without timestamps keeps the timed row and says why it has no profile)
    let (passes, no_profile) = match opts.profile {
        true => match engine.profile(opts.steps) {
            Ok(p) => (Some(p), None),
            Err(e) => (None, Some(format!("no pass profile: {e}"))),
        },
        false => (None, None),
    };
    let pages = engine.entry_pages();
    let mut paged = match pages.paged() {
        true => format!(", the list entries in {} pages", pages.count),
        false => String::new(),
    };
    let state_pages = engine.state_pages();
    if state_pages.paged() {
        paged += &format!(", the particle state in {} pages", state_pages.count);
    }
    let windowed = (windows.count > 1).then(|| {
        format!(
            "{} windows of {} particles{paged}",
            windows.count, windows.len
        )
    });
    let note = match (windowed, no_profile) {
        (Some(w), Some(p)) => Some(format!("{w}; {p}")),
        (w, p) => w.or(p),
    };
    Ok(BenchRow {
        passes,
        case: case.name(),
        backend: "gpu",
        threads: None,
        speedup: None,
        particles: n,
        status: "ran",
        note,
        dt: Some(dt),
        steps: opts.steps,
        setup_seconds: Some(setup),
        wall_seconds: Some(wall),
        seconds_per_step: Some(wall / opts.steps as f64),
        particle_steps_per_second: Some(n as f64 * opts.steps as f64 / wall.max(1e-12)),
        gpu_bytes: Some(bytes),
        gpu_buffers: Some(buffers),
        gpu_bytes_per_particle: Some(bytes as f64 / n as f64),
        list_entries: Some(entries),
        windows: Some((windows.len, windows.count)),
        rebuilds: Some(rebuilds),
        quiet_batches: Some(quiet),
        rebuild_halts: Some(halts),
        dispatches_per_step: Some(engine.dispatches_per_step()),
        runs: Vec::new(),
        contacts_per_particle: Some(z),
        traffic: Some(traffic),
    })
}
