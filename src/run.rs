//! Running a scene headless: step to the end, report progress at the scene's cadence,
//! and summarise (energies, coordination, overlaps).

use crate::cpu::{ContactStats, CpuEngine, Energies};
use crate::error::PowderError;
use crate::scene::Scene;
use serde::Serialize;

/// The state of a run at one output instant.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Snapshot {
    pub step: u64,
    pub time: f64,
    pub energies: Energies,
    pub contacts: ContactStats,
}

/// What `powder run` reports at the end.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    pub scene: String,
    pub backend: &'static str,
    pub particles: usize,
    pub dt: f64,
    pub dt_rule: String,
    pub steps: u64,
    pub time: f64,
    pub wall_seconds: f64,
    pub particle_steps_per_second: f64,
    pub initial: Snapshot,
    pub last: Snapshot,
    /// |E_total(end) − E_total(start)| relative to the largest of the kinetic, stored and
    /// gravitational energy changes seen (0 when nothing moved).
    pub energy_balance_error: f64,
    pub outside_domain: usize,
}

fn snapshot(engine: &CpuEngine) -> Snapshot {
    Snapshot {
        step: engine.steps,
        time: engine.time,
        energies: engine.energies(),
        contacts: engine.contact_stats(),
    }
}

/// Runs `scene` on the CPU reference backend to its duration (or `max_steps`), calling
/// `progress` every `scene.output_every` steps.
pub fn run_cpu(
    scene: &Scene,
    max_steps: Option<u64>,
    mut progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    let mut engine = CpuEngine::new(scene)?;
    let total = ((scene.duration / engine.dt()).ceil() as u64).max(1);
    let total = max_steps.map_or(total, |m| m.min(total));
    let initial = snapshot(&engine);
    progress(&initial);
    let started = std::time::Instant::now();
    let mut scale = initial.energies.kinetic.abs() + initial.energies.elastic.abs();
    while engine.steps < total {
        let chunk = scene.output_every.min(total - engine.steps);
        engine.run_steps(chunk)?;
        let snap = snapshot(&engine);
        let de = snap.energies;
        scale = scale
            .max(de.kinetic.abs())
            .max(de.elastic.abs())
            .max((de.gravitational - initial.energies.gravitational).abs());
        progress(&snap);
    }
    let wall = started.elapsed().as_secs_f64();
    let last = snapshot(&engine);
    let drift = (last.energies.total() - initial.energies.total()).abs();
    Ok(RunSummary {
        scene: scene.name.clone(),
        backend: "cpu",
        particles: engine.len(),
        dt: engine.dt(),
        dt_rule: engine.time_step().reason.clone(),
        steps: engine.steps,
        time: engine.time,
        wall_seconds: wall,
        particle_steps_per_second: engine.len() as f64 * engine.steps as f64 / wall.max(1e-9),
        initial,
        last,
        energy_balance_error: if scale > 0.0 { drift / scale } else { 0.0 },
        outside_domain: engine.outside_domain(),
    })
}

/// What `powder run --backend gpu` reports: the GPU engine keeps no energy ledger or
/// contact statistics yet, so the summary has the kinetic energy and the throughput.
#[derive(Clone, Debug, Serialize)]
pub struct GpuRunSummary {
    pub scene: String,
    pub backend: &'static str,
    pub adapter: String,
    pub particles: usize,
    pub dt: f64,
    pub steps: u64,
    pub time: f64,
    pub wall_seconds: f64,
    pub particle_steps_per_second: f64,
    pub kinetic_initial: f64,
    pub kinetic_final: f64,
}

/// Runs `scene` on the GPU engine, calling `progress(step, time, kinetic)` every
/// `scene.output_every` steps (each call reads the state back).
pub fn run_gpu(
    scene: &Scene,
    ctx: crate::gpu::GpuContext,
    max_steps: Option<u64>,
    mut progress: impl FnMut(u64, f64, f64),
) -> Result<GpuRunSummary, PowderError> {
    let mut engine = crate::gpu::GpuEngine::new(scene, ctx)?;
    let total = ((scene.duration / engine.dt()).ceil() as u64).max(1);
    let total = max_steps.map_or(total, |m| m.min(total));
    let kinetic_initial = engine.kinetic_energy(&engine.state()?);
    progress(0, 0.0, kinetic_initial);
    let started = std::time::Instant::now();
    let mut kinetic_final = kinetic_initial;
    while engine.steps < total {
        let chunk = scene.output_every.min(total - engine.steps);
        engine.run_steps(chunk)?;
        kinetic_final = engine.kinetic_energy(&engine.state()?);
        progress(engine.steps, engine.time, kinetic_final);
    }
    let wall = started.elapsed().as_secs_f64();
    Ok(GpuRunSummary {
        scene: scene.name.clone(),
        backend: "gpu",
        adapter: engine.adapter().to_string(),
        particles: engine.len(),
        dt: engine.dt(),
        steps: engine.steps,
        time: engine.time,
        wall_seconds: wall,
        particle_steps_per_second: engine.len() as f64 * engine.steps as f64 / wall.max(1e-9),
        kinetic_initial,
        kinetic_final,
    })
}
