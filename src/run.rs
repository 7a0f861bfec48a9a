//! Running a scene headless: step to the end, report progress at the scene's cadence,
//! and summarise (energies, coordination, overlaps).

use crate::checkpoint;
use crate::cpu::{ContactStats, CpuEngine, Energies};
use crate::error::PowderError;
use crate::output::atomic::write_atomic;
use crate::output::vtk;
use crate::scene::Scene;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

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
    /// Particle volume over the domain box, and over the box enclosing the particles.
    pub solid_fraction_domain: f64,
    pub solid_fraction_bounding_box: f64,
    /// Force on each wall at the end, N.
    pub wall_forces: Vec<[f64; 3]>,
    /// The step the run resumed from, if it did.
    pub resumed_from: Option<u64>,
    /// Stopped early by an interrupt (Ctrl-C) after writing a last checkpoint.
    pub interrupted: bool,
    pub out_dir: Option<String>,
}

fn snapshot(engine: &CpuEngine) -> Snapshot {
    Snapshot {
        step: engine.steps,
        time: engine.time,
        energies: engine.energies(),
        contacts: engine.contact_stats(),
    }
}

/// Where and how `powder run` writes its outputs.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (VTK snapshots + `.pvd`, `series.csv`, `checkpoint.bin`,
    /// `summary.json`); `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Continue from this checkpoint (of the same scene and powder version).
    pub resume: Option<PathBuf>,
    /// Stop after this many steps in total (default: the scene's duration).
    pub max_steps: Option<u64>,
    /// Draw a progress bar with ETA and steps/s on stderr.
    pub progress_bar: bool,
    /// Print a progress line (energies, coordination, overlap) to stderr at every output.
    pub verbose: bool,
    /// Set (e.g. by Ctrl-C) to stop after the current chunk with a last checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Header of `series.csv`.
pub fn csv_header(n_walls: usize) -> String {
    let mut h = String::from(
        "step,time,kinetic,elastic,gravitational,dissipated,total,contacts,wall_contacts,non_contact,coordination,max_overlap,max_overlap_ratio,mean_overlap_ratio",
    );
    for w in 0..n_walls {
        h.push_str(&format!(",wall{w}_fx,wall{w}_fy,wall{w}_fz"));
    }
    h
}

fn csv_row(s: &Snapshot, wall_forces: &[glam::DVec3]) -> String {
    let e = &s.energies;
    let c = &s.contacts;
    let mut row = format!(
        "{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{:e},{:e},{:e},{:e}",
        s.step,
        s.time,
        e.kinetic,
        e.elastic,
        e.gravitational,
        e.dissipated,
        e.total(),
        c.contacts,
        c.wall_contacts,
        c.non_contact,
        c.coordination,
        c.max_overlap,
        c.max_overlap_ratio,
        c.mean_overlap_ratio
    );
    for f in wall_forces {
        row.push_str(&format!(",{:e},{:e},{:e}", f.x, f.y, f.z));
    }
    row
}

impl Snapshot {
    /// One human-readable progress line.
    pub fn line(&self) -> String {
        format!(
            "step {:>9}  t = {:.4e} s  E_kin {:.4e}  E_el {:.4e}  E_diss {:.4e}  E_tot {:.6e} J  Z = {:.3}  max δ/a12 = {:.3e}",
            self.step,
            self.time,
            self.energies.kinetic,
            self.energies.elastic,
            self.energies.dissipated,
            self.energies.total(),
            self.contacts.coordination,
            self.contacts.max_overlap_ratio
        )
    }
}

/// Largest overlap over the reduced radius a12 the run monitor accepts: beyond it the
/// contact model is outside anything the papers calibrate (overlaps of half a radius).
pub const MAX_OVERLAP_RATIO: f64 = 0.5;
/// Largest growth of the total energy (kinetic + stored + gravitational + dissipated),
/// relative to the run's energy scale, that the monitor accepts: none of the models
/// injects energy, so growth means the integration has gone wrong.
pub const MAX_ENERGY_GROWTH: f64 = 0.05;

/// The run monitor: what must stop a run, with the step, the particles and a hint.
fn monitor(engine: &mut CpuEngine, initial_total: f64, scale: f64) -> Result<(), PowderError> {
    let hint = format!(
        "the time step ({:.4e} s; {}) may be too large for this scene",
        engine.dt(),
        engine.time_step().reason
    );
    if let Some(i) = engine.non_finite() {
        return Err(PowderError::Run(format!(
            "step {}: particle {i} has a non-finite position or velocity; {hint}",
            engine.steps
        )));
    }
    if let Some((ratio, i, partner)) = engine.take_peak_overlap() {
        if ratio > MAX_OVERLAP_RATIO {
            let with = match partner {
                crate::cpu::Partner::Particle(j) => format!("particle {j}"),
                crate::cpu::Partner::Wall(w) => format!("wall {w}"),
            };
            return Err(PowderError::Run(format!(
                "step {}: particle {i} overlaps {with} by {ratio:.3} of the reduced radius (limit {MAX_OVERLAP_RATIO}); the impact is too violent for the contact stiffness or {hint}",
                engine.steps
            )));
        }
    }
    let escaped = engine.escaped(5);
    if !escaped.is_empty() {
        return Err(PowderError::Run(format!(
            "step {}: particles {escaped:?} left the domain box; enlarge [domain] or add walls (or {hint})",
            engine.steps
        )));
    }
    let total = engine.energies().total();
    if scale > 0.0 && total - initial_total > MAX_ENERGY_GROWTH * scale {
        return Err(PowderError::Run(format!(
            "step {}: the total energy grew by {:.3e} J ({:.1}% of the run's energy scale {:.3e} J), which no contact model can inject; {hint}",
            engine.steps,
            total - initial_total,
            100.0 * (total - initial_total) / scale,
            scale
        )));
    }
    Ok(())
}

/// Solid fraction of the particles in the domain box and in the box that encloses them.
fn solid_fractions(scene: &Scene, engine: &CpuEngine) -> (f64, f64) {
    let vol: f64 = engine
        .radii()
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        .sum();
    let d = scene.domain;
    let domain = (0..3).map(|a| d.max[a] - d.min[a]).product::<f64>();
    let mut lo = glam::DVec3::splat(f64::INFINITY);
    let mut hi = glam::DVec3::splat(f64::NEG_INFINITY);
    for (p, r) in engine.positions().iter().zip(engine.radii()) {
        lo = lo.min(*p - *r);
        hi = hi.max(*p + *r);
    }
    let b = hi - lo;
    (vol / domain, vol / (b.x * b.y * b.z))
}

/// The CSV rows of an earlier run up to `step` (on resume), header excluded.
fn earlier_rows(path: &Path, step: u64) -> Vec<String> {
    std::fs::read_to_string(path)
        .map(|text| {
            text.lines()
                .skip(1)
                .filter(|l| {
                    l.split(',')
                        .next()
                        .and_then(|s| s.parse::<u64>().ok())
                        .is_some_and(|s| s <= step)
                })
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default()
}

/// The snapshots of an earlier run up to `step` (on resume), with their times.
fn earlier_snapshots(dir: &Path, name: &str, step: u64, dt: f64) -> Vec<(f64, String)> {
    let prefix = format!("{name}_");
    let mut found: Vec<(u64, String)> = std::fs::read_dir(dir.join("snapshots"))
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter_map(|e| {
                    let f = e.file_name().to_string_lossy().into_owned();
                    let s = f
                        .strip_prefix(&prefix)?
                        .strip_suffix(".vtp")?
                        .parse::<u64>()
                        .ok()?;
                    (s <= step).then(|| (s, format!("snapshots/{f}")))
                })
                .collect()
        })
        .unwrap_or_default();
    found.sort();
    found.into_iter().map(|(s, f)| (s as f64 * dt, f)).collect()
}

/// Runs `scene` on the CPU reference backend to its duration (or `opts.max_steps`),
/// writing outputs to `opts.out_dir` and calling `progress` at every output.
pub fn run_cpu_with(
    scene: &Scene,
    opts: &RunOptions,
    mut progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    let mut engine = CpuEngine::new(scene)?;
    let mut resumed_from = None;
    if let Some(ckpt) = &opts.resume {
        engine.restore(checkpoint::load(ckpt, scene)?)?;
        resumed_from = Some(engine.steps);
    }
    let total = ((scene.duration / engine.dt()).ceil() as u64).max(1);
    let total = opts.max_steps.map_or(total, |m| m.min(total));
    let out = opts.out_dir.as_deref();
    let csv_path = out.map(|d| d.join("series.csv"));
    let ckpt_path = out.map(|d| d.join("checkpoint.bin"));
    let mut series = match out {
        Some(d) => Some(vtk::Series::new(d, &scene.name)?),
        None => None,
    };
    let mut rows = match (&csv_path, resumed_from) {
        (Some(p), Some(step)) => earlier_rows(p, step),
        _ => Vec::new(),
    };
    if let (Some(s), Some(d), Some(step)) = (series.as_mut(), out, resumed_from) {
        s.keep_until(earlier_snapshots(d, &scene.name, step, engine.dt()));
    }
    let header = csv_header(scene.walls.len());
    let write_outputs = |engine: &CpuEngine,
                         snap: &Snapshot,
                         rows: &mut Vec<String>,
                         series: &mut Option<vtk::Series>|
     -> Result<(), PowderError> {
        rows.retain(|r| !r.starts_with(&format!("{},", snap.step)));
        rows.push(csv_row(snap, &engine.wall_forces()));
        if let Some(s) = series.as_mut() {
            s.write(
                snap.step,
                snap.time,
                &vtk::Particles {
                    positions: engine.positions(),
                    velocities: engine.velocities(),
                    radii: engine.radii(),
                    angular_velocities: engine.angular_velocities(),
                },
            )?;
        }
        Ok(())
    };
    let save = |engine: &CpuEngine, rows: &[String]| -> Result<(), PowderError> {
        if let (Some(c), Some(p)) = (&ckpt_path, &csv_path) {
            let mut text = header.clone();
            text.push('\n');
            for r in rows {
                text.push_str(r);
                text.push('\n');
            }
            write_atomic(p, text.as_bytes())?;
            checkpoint::save(c, scene, engine)?;
        }
        Ok(())
    };

    let bar = opts.progress_bar.then(|| {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:30}] {pos}/{len} steps  {per_sec}  ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_position(engine.steps);
        bar
    });
    let say = |snap: &Snapshot| match &bar {
        Some(b) => b.println(snap.line()),
        None => eprintln!("{}", snap.line()),
    };

    let initial = snapshot(&engine);
    progress(&initial);
    if opts.verbose {
        say(&initial);
    }
    if resumed_from.is_none() {
        write_outputs(&engine, &initial, &mut rows, &mut series)?;
    }
    let started = std::time::Instant::now();
    let start_steps = engine.steps;
    let mut scale = initial.energies.kinetic.abs() + initial.energies.elastic.abs();
    let mut interrupted = false;
    // Chunks end at outputs, checkpoints and at most 1000 steps apart (for Ctrl-C).
    while engine.steps < total {
        let to_output = scene.output_every - engine.steps % scene.output_every;
        let to_ckpt = scene.checkpoint_every - engine.steps % scene.checkpoint_every;
        let chunk = to_output.min(to_ckpt).min(1000).min(total - engine.steps);
        // The state before the chunk: if the monitor stops the run, the checkpoint holds
        // the last state that passed it.
        let before = engine.state();
        let stepped = engine.run_steps(chunk).and_then(|()| {
            let now = engine.energies();
            let scale = scale
                .max(now.kinetic.abs())
                .max(now.elastic.abs())
                .max((now.gravitational - initial.energies.gravitational).abs());
            monitor(&mut engine, initial.energies.total(), scale)
        });
        if let Err(e) = stepped {
            if let Some(b) = &bar {
                b.finish_and_clear();
            }
            let failed_at = engine.steps;
            engine.restore(before)?;
            save(&engine, &rows)?;
            let note = match &ckpt_path {
                Some(c) => format!(
                    "; the state at step {} (before the failure, at most 1000 steps earlier than step {failed_at}) is in {}",
                    engine.steps,
                    c.display()
                ),
                None => String::new(),
            };
            return Err(PowderError::Run(format!("{e}{note}")));
        }
        if let Some(b) = &bar {
            b.set_position(engine.steps);
        }
        if engine.steps % scene.output_every == 0 || engine.steps == total {
            let snap = snapshot(&engine);
            scale = scale
                .max(snap.energies.kinetic.abs())
                .max(snap.energies.elastic.abs())
                .max((snap.energies.gravitational - initial.energies.gravitational).abs());
            progress(&snap);
            if opts.verbose {
                say(&snap);
            }
            write_outputs(&engine, &snap, &mut rows, &mut series)?;
        }
        if engine.steps % scene.checkpoint_every == 0 {
            save(&engine, &rows)?;
        }
        if opts
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
        {
            interrupted = true;
            break;
        }
    }
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let last = snapshot(&engine);
    if interrupted && engine.steps % scene.output_every != 0 {
        write_outputs(&engine, &last, &mut rows, &mut series)?;
    }
    save(&engine, &rows)?;
    let wall = started.elapsed().as_secs_f64();
    let drift = (last.energies.total() - initial.energies.total()).abs();
    let (solid_fraction_domain, solid_fraction_bounding_box) = solid_fractions(scene, &engine);
    let summary = RunSummary {
        scene: scene.name.clone(),
        backend: "cpu",
        particles: engine.len(),
        dt: engine.dt(),
        dt_rule: engine.time_step().reason.clone(),
        steps: engine.steps,
        time: engine.time,
        wall_seconds: wall,
        particle_steps_per_second: engine.len() as f64 * (engine.steps - start_steps) as f64
            / wall.max(1e-9),
        initial,
        last,
        energy_balance_error: if scale > 0.0 { drift / scale } else { 0.0 },
        outside_domain: engine.outside_domain(),
        solid_fraction_domain,
        solid_fraction_bounding_box,
        wall_forces: engine.wall_forces().iter().map(|f| f.to_array()).collect(),
        resumed_from,
        interrupted,
        out_dir: out.map(|d| d.display().to_string()),
    };
    if let Some(d) = out {
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| PowderError::Run(format!("cannot encode the summary: {e}")))?;
        write_atomic(&d.join("summary.json"), text.as_bytes())?;
    }
    Ok(summary)
}

/// Runs `scene` on the CPU reference backend to its duration (or `max_steps`), calling
/// `progress` every `scene.output_every` steps; writes no files.
pub fn run_cpu(
    scene: &Scene,
    max_steps: Option<u64>,
    progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    run_cpu_with(
        scene,
        &RunOptions {
            max_steps,
            ..Default::default()
        },
        progress,
    )
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
    /// Neighbour-list rebuilds (Verlet skin), the initial build included.
    pub rebuilds: u64,
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
        rebuilds: engine.rebuilds()?,
    })
}
