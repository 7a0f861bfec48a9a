//! Running a scene headless on either backend: step to the end, report progress at the
//! scene's cadence, write outputs and checkpoints, watch the run (the monitor), and
//! summarise (energies, coordination, overlaps). One loop drives both backends through
//! [`Simulation`]. A GPU run without the energy ledger ([`RunOptions::gpu`], `powder run
//! --no-ledger`) leaves what only the ledger knows absent: empty CSV cells, keys left out
//! of the JSON, "n/a" in the progress line.

mod earlier;
mod fits;
pub(crate) use fits::engine_fits;
mod monitor;
pub mod observed;
mod outputs;
pub(crate) mod overdamped;
mod overlap_partner;
mod plan;
mod recovery;
mod servo;
pub mod simulation;
mod snapshot;
mod summary;
mod tabor;

use crate::cpu::{ContactStats, CpuEngine, Threads};
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine, GpuOptions};
use crate::run::observed::ObservedEnergies;
use crate::run::simulation::{Observation, Simulation};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use monitor::{energy_scale, first_failure, monitor};
pub use monitor::{MonitorReference, MAX_ENERGY_GROWTH, MAX_OVERLAP_RATIO};
use outputs::RunOutputs;
use plan::RunPlan;
use recovery::RecoveryCopy;
use servo::ServoWatch;
pub use servo::{ServoHold, SERVO_RMS_MAX};
use snapshot::snapshot;
pub use snapshot::{csv_header, Snapshot};
pub use summary::RunSummary;
use summary::{outside_domain, solid_fractions};
pub use tabor::{tabor_pairs, TaborPair};

/// Where and how `powder run` writes its outputs.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (VTK snapshots + `.pvd`, `series.csv`, `checkpoint.bin`,
    /// `summary.json`); `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Continue from this checkpoint (of the same powder version, and a scene whose run
    /// agrees with its own up to its time: `checkpoint::run_digest`).
    pub resume: Option<PathBuf>,
    /// Stop after at most this many steps in total (the scene's duration ends the run
    /// sooner where it comes first; default: the duration).
    pub max_steps: Option<u64>,
    /// Draw a progress bar with ETA and steps/s on stderr.
    pub progress_bar: bool,
    /// Print a progress line (energies, coordination, overlap) to stderr at every output.
    pub verbose: bool,
    /// Set (e.g. by Ctrl-C) to stop after the current chunk with a last checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// The GPU engine's options (the energy ledger, on by default); the CPU backend keeps
    /// its ledger always (it is cheap there) and ignores them.
    pub gpu: GpuOptions,
    /// D_min of the Tabor parameter in the scene's length unit; `None`: the paper's
    /// 1.65 Å ([`crate::model::analytic::TABOR_MIN_SEPARATION`]).
    pub tabor_dmin: Option<f64>,
    /// The CPU engine's threads (every core by default; the results do not depend on it).
    pub threads: Threads,
    /// Why the backend was chosen, for the summary (`powder run --backend auto`).
    pub backend_reason: Option<String>,
    /// Write no VTK snapshots (nor the contact network): the series, checkpoints and
    /// summary only.
    pub no_snapshots: bool,
    /// Replace an earlier run's outputs in `out_dir` (a fresh run), or trim results beyond
    /// the checkpoint's step (a resume); without it such a run is refused before anything
    /// changes.
    pub overwrite: bool,
    /// Steps between the copies of the state that a failing chunk is stepped again from
    /// (to name its failing step and checkpoint its start); `None`: as often as keeps the
    /// copies under 5 % of the stepping time (every chunk where a copy is cheap; on a GPU
    /// at 10^7 particles, where one reads the whole device state back, far fewer).
    pub copy_every: Option<u64>,
}

/// Runs `scene` on the CPU reference backend to its duration (or `opts.max_steps`),
/// writing outputs to `opts.out_dir` and calling `progress` at every output.
pub fn run_cpu_with(
    scene: &Scene,
    opts: &RunOptions,
    progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    let engine = CpuEngine::with_threads(scene, opts.threads.clone())?;
    let rule = dt_choice(scene, engine.time_step(), engine.dt());
    run_with(scene, engine, &rule, opts, progress)
}

/// What chose the step `dt` of `scene`, and the stability limit `ts` it is checked against
/// (the summary's `dt_rule`).
fn dt_choice(scene: &Scene, ts: &crate::model::TimeStep, dt: f64) -> String {
    use crate::model::DEFAULT_DT_FRACTION;
    let chosen = match scene.dt {
        crate::scene::DtSetting::Fixed(_) => "simulation.dt".to_string(),
        _ if dt.to_bits() == (ts.contact_time / DEFAULT_DT_FRACTION).to_bits() => format!(
            "the automatic step tc/{DEFAULT_DT_FRACTION} with tc = {:.4e} s",
            ts.contact_time
        ),
        _ if dt.to_bits() == ts.max.to_bits() => {
            "the automatic step, at the stability limit (below tc/50)".to_string()
        }
        _ => format!(
            "the automatic step, {:.2} of the stability limit",
            dt / ts.max
        ),
    };
    format!("{chosen}; the stability limit: {}", ts.reason)
}

/// Runs `scene` on the GPU engine (with the energy ledger unless `opts.gpu` turns it off)
/// with the same outputs, checkpoints and monitor as the CPU backend.
pub fn run_gpu_with(
    scene: &Scene,
    ctx: GpuContext,
    opts: &RunOptions,
    progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    let options = GpuOptions {
        contacts: opts.gpu.contacts || (opts.out_dir.is_some() && scene.writes_contacts()),
        ..opts.gpu
    };
    let engine = GpuEngine::with_options(scene, ctx, options)?;
    let rule = dt_choice(scene, engine.time_step(), engine.dt());
    run_with(scene, engine, &rule, opts, progress)
}

/// The run loop of both backends: `dt_rule` says where dt came from (for hints).
pub fn run_with<S: Simulation>(
    scene: &Scene,
    mut engine: S,
    dt_rule: &str,
    opts: &RunOptions,
    mut progress: impl FnMut(&Snapshot),
) -> Result<RunSummary, PowderError> {
    let RunPlan {
        tabor,
        resumed_from,
        marks,
        first,
        total,
    } = plan::plan(scene, &mut engine, opts)?;
    let mut outputs = RunOutputs::open(
        scene,
        opts,
        (resumed_from, &marks),
        engine.radii().to_vec(),
        (engine.dt(), total),
    )?;

    let bar = opts.progress_bar.then(|| {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:30}] {pos}/{len} steps  {per_sec}  ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_position(engine.steps());
        bar
    });
    let say = |snap: &Snapshot| match &bar {
        Some(b) => b.println(snap.line()),
        None => eprintln!("{}", snap.line()),
    };

    let obs = first;
    let initial = snapshot(&engine, &obs);
    progress(&initial);
    if opts.verbose {
        say(&initial);
    }
    if resumed_from.is_none() {
        outputs.write(scene, &engine, &obs, &initial)?;
    }
    let started = std::time::Instant::now();
    let start_steps = engine.steps();
    let start_time = engine.time();
    let mut servo = ServoWatch::new(scene);
    // the energy check's reference: the run's start (a resume's from its checkpoint)
    let (start, mut scale) = match marks.monitor {
        Some(m) => (m.initial, m.scale),
        None => (
            initial.energies,
            initial.energies.kinetic.abs() + initial.energies.elastic.unwrap_or(0.0).abs(),
        ),
    };
    let reference = |scale| MonitorReference {
        initial: start,
        scale,
    };
    let mut interrupted = false;
    // (the time inside the engine's steps; the rest of the wall time reads the state back,
    // checks it and writes)
    let mut stepping = std::time::Duration::ZERO;
    // Without the ledger the monitor needs little on the host (the engine watches its
    // overlaps, escapes and non-finite values — the GPU its accelerations —; there is no
    // energy check, so the energy scale stays as it began), so a chunk that writes nothing
    // observes nothing: on the GPU reading the state back and decoding it costs about as
    // much as the steps at 10^7 (servo walls are judged every chunk).
    let servo_walls = scene.walls.iter().any(|w| w.motion.servo());
    let light = !engine.has_ledger() && !servo_walls;
    let mut last_obs = obs;
    let mut last_obs_step = engine.steps();
    let mut copy = RecoveryCopy::new(opts.copy_every);
    // Chunks end at outputs, checkpoints and at most 1000 steps apart (for Ctrl-C and the
    // monitor).
    while engine.steps() < total {
        let steps = engine.steps();
        let to_output = scene.output_every - steps % scene.output_every;
        let to_ckpt = scene.checkpoint_every - steps % scene.checkpoint_every;
        let chunk = to_output.min(to_ckpt).min(1000).min(total - steps);
        // The state before the chunk, or one before it to step again from: if the monitor
        // stops the run, the checkpoint holds the last state that passed it.
        copy.refresh(&engine)?;
        let scale_before = scale;
        let stepping_from = std::time::Instant::now();
        let ran = engine.run_steps(chunk);
        let took = stepping_from.elapsed();
        stepping += took;
        copy.stepped(took);
        let writes = {
            let now = engine.steps();
            now.is_multiple_of(scene.output_every) || now == total
        };
        let stepped = ran.and_then(|()| {
            // (between outputs the monitor's checks need no wall forces, unless servo
            // walls are judged)
            let obs = match (writes || servo_walls, light) {
                (true, _) => Some((engine.observe()?, true)),
                (false, false) => Some((engine.observe_for_checks()?, false)),
                (false, true) => None,
            };
            let scale = match (&obs, light) {
                (Some((o, _)), false) => energy_scale(scale, &o.energies, &start),
                _ => scale,
            };
            let checked = obs.as_ref().map(|(o, _)| o);
            monitor(&mut engine, dt_rule, scene, (checked, &start), scale)?;
            Ok((obs, scale))
        });
        let obs = match stepped {
            Ok((obs, grown)) => {
                // (after every chunk: the walls' work can fall back between outputs)
                scale = grown;
                obs
            }
            Err(e) => {
                if let Some(b) = &bar {
                    b.finish_and_clear();
                }
                // the chunk again a step at a time from its start, to name the step that
                // failed (the chunk's end may be up to 1000 steps later, its values wild)
                copy.restore_to(&mut engine, steps)?;
                let before = engine.save()?;
                let e = first_failure(
                    &mut engine,
                    chunk,
                    (dt_rule, scene),
                    &start,
                    scale_before,
                    light,
                )
                .unwrap_or(e);
                engine.restore(before)?;
                let saved = outputs.checkpoint(scene, &engine, reference(scale));
                return Err(saved_before(e, saved, &outputs, &engine, "the failure"));
            }
        };
        if let Some(b) = &bar {
            b.set_position(engine.steps());
        }
        let steps = engine.steps();
        if let Some((obs, _)) = obs.as_ref().filter(|_| writes) {
            let snap = snapshot(&engine, obs);
            progress(&snap);
            if opts.verbose {
                say(&snap);
            }
            // a write that fails (a full disk) leaves the state healthy: it is checkpointed
            // as the chunk began, with the rows as of then, so only the chunk is run again
            let rows = outputs.series_mark();
            if let Err(e) = outputs.write(scene, &engine, obs, &snap) {
                if let Some(b) = &bar {
                    b.finish_and_clear();
                }
                copy.restore_to(&mut engine, steps - chunk)?;
                let saved =
                    outputs.checkpoint_marked(scene, &engine, reference(scale_before), rows);
                return Err(saved_before(
                    e,
                    saved,
                    &outputs,
                    &engine,
                    "the failed write",
                ));
            }
        }
        // (only a full observation is the run's last: its row may be written at the end)
        if let Some((obs, true)) = obs {
            servo.record(
                engine.time(),
                obs.wall_forces.as_deref(),
                &obs.wall_velocities,
            );
            last_obs = obs;
            last_obs_step = steps;
        }
        if steps.is_multiple_of(scene.checkpoint_every) {
            outputs.checkpoint_or_say(scene, &engine, reference(scale))?;
        }
        // (a Ctrl-C in the last chunk finds the run complete: not interrupted)
        if steps < total
            && opts
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
    // (a run stopped off its outputs without the ledger observed last before)
    if last_obs_step != engine.steps() {
        last_obs = engine.observe()?;
    }
    let last = snapshot(&engine, &last_obs);
    outputs.checkpoint_or_say(scene, &engine, reference(scale))?;
    // Ctrl-C off the output cadence: a last row and snapshot after the checkpoint, which a
    // resume drops (the straight run has none there)
    if interrupted && !engine.steps().is_multiple_of(scene.output_every) {
        outputs.write(scene, &engine, &last_obs, &last)?;
        outputs.sync_series()?;
    }
    let wall = started.elapsed().as_secs_f64();
    let drift = last
        .energies
        .total()
        .zip(start.total())
        .map(|(end, start)| (end - start).abs());
    let (solid_fraction_domain, solid_fraction_bounding_box) =
        solid_fractions(scene, &last_obs.positions, engine.radii());
    let (servo, unjudged) = servo.holds(scene, start_time, engine.time());
    if opts.verbose {
        for w in servo.iter().filter_map(|h| h.warning(engine.dt())) {
            eprintln!("warning: {w}");
        }
    }
    // (a servo wall left unjudged is said, in the summary's notes too)
    let mut notes = engine.notes()?;
    notes.extend(unjudged);
    let summary = RunSummary {
        scene: scene.name.clone(),
        backend: engine.backend(),
        adapter: engine.adapter(),
        threads: engine.threads(),
        backend_reason: opts.backend_reason.clone(),
        particles: engine.len(),
        ledger: engine.has_ledger(),
        dt: engine.dt(),
        dt_rule: dt_rule.to_string(),
        steps: engine.steps(),
        time: engine.time(),
        wall_seconds: wall,
        stepping_seconds: stepping.as_secs_f64(),
        particle_steps_per_second: engine.len() as f64 * (engine.steps() - start_steps) as f64
            / wall.max(1e-9),
        initial,
        last,
        energy_balance_error: drift.map(|d| if scale > 0.0 { d / scale } else { 0.0 }),
        outside_domain: outside_domain(scene, &last_obs.positions),
        solid_fraction_domain,
        solid_fraction_bounding_box,
        wall_forces: last_obs
            .wall_forces
            .as_ref()
            .map(|f| f.iter().map(|f| f.to_array()).collect()),
        resumed_from,
        interrupted,
        out_dir: outputs.dir().map(|d| d.display().to_string()),
        contact_network: outputs.writes_contacts(),
        rebuilds: engine.rebuilds()?,
        quiet_batches: engine.quiet_batches().map(|(kept, back)| [kept, back]),
        notes,
        tabor,
        servo,
    };
    // (a resume with nothing to run keeps the summary of the run that reached its step: the
    // run's start and wall time would go)
    let ran_none = resumed_from.is_some() && engine.steps() == start_steps;
    if !(ran_none && outputs.has_summary()) {
        outputs.write_summary(&summary)?;
    }
    Ok(summary)
}

/// The error `e` that stopped a run (it names its step), with where the state before it
/// went: the checkpoint `saved` wrote (the engine restored to the step before `cause`), or
/// why it could not be written either.
fn saved_before<S: Simulation>(
    e: PowderError,
    saved: Result<(), PowderError>,
    outputs: &RunOutputs,
    engine: &S,
    cause: &str,
) -> PowderError {
    let step = engine.steps();
    let note = match (saved, outputs.checkpoint_path()) {
        (Ok(()), Some(c)) => format!(
            "; the state at step {step} (before {cause}) is in {}: resume it with --resume once the cause is fixed",
            c.display()
        ),
        (Ok(()), None) => String::new(),
        (Err(e2), _) => format!(
            "; the state at step {step} (before {cause}) could not be checkpointed either ({e2}); {}",
            outputs.latest_saved().unwrap_or_default()
        ),
    };
    PowderError::Run(format!("{e}{note}"))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The energy scale counts the work of moving walls, not only the kinetic, stored and
    /// gravitational energy: a servo wall gathering a packing does work many times the
    /// packing's kinetic energy, and the ledger's second-order error (half a per cent of
    /// that work at dt = tc/10) must not read as an energy blow-up.
    #[test]
    fn the_energy_scale_counts_the_walls_work() {
        let initial = ObservedEnergies {
            wall_work: Some(0.1),
            elastic: Some(0.0),
            dissipated: Some(0.0),
            ..Default::default()
        };
        let now = ObservedEnergies {
            kinetic: 0.04,
            elastic: Some(2e-4),
            dissipated: Some(0.36),
            wall_work: Some(0.49),
            gravitational: -0.01,
            inserted: 0.0,
        };
        assert_eq!(energy_scale(0.0, &now, &initial), 0.39);
        assert_eq!(energy_scale(0.5, &now, &initial), 0.5);
        let quiet = ObservedEnergies {
            wall_work: Some(0.1),
            kinetic: 0.04,
            ..initial
        };
        assert_eq!(energy_scale(0.0, &quiet, &initial), 0.04);
        // work the walls took back counts as much as work they gave
        let pulled = ObservedEnergies {
            wall_work: Some(-0.2),
            ..quiet
        };
        assert_eq!(energy_scale(0.0, &pulled, &initial), 0.1 + 0.2);
        // without the ledger the walls' work is unknown
        let blind = ObservedEnergies {
            wall_work: None,
            ..now
        };
        assert_eq!(energy_scale(0.0, &blind, &initial), 0.04);
    }

    /// λT of paper 002 eq. 1 by hand: (4R*γ²/(E*²D³))^(1/3), E* = E/(2(1 − ν²)).
    fn by_hand(youngs: f64, gamma: f64, r_eff: f64) -> f64 {
        let e_star = youngs / (2.0 * (1.0 - 0.3 * 0.3));
        (4.0 * r_eff * gamma * gamma / (e_star * e_star * 1.65e-10f64.powi(3))).cbrt()
    }

    #[test]
    fn tabor_pairs_cover_the_jkr_pairs_that_can_meet() {
        // "soft": JKR, two sizes; "lone": JKR, one particle (no lone-lone pair);
        // "plain": hysteretic; soft-lone: a stiffer JKR interaction; soft-plain: Hertz (no
        // adhesion, no λT); a wall of "lone"
        let text = r#"
            [domain]
            min = [0.0, 0.0, 0.0]
            max = [1e-3, 1e-3, 1e-3]
            [simulation]
            duration = 1e-6
            [[material]]
            name = "soft"
            density = 2000.0
            model = "jkr"
            youngs = 1e8
            poisson = 0.3
            surface_energy = 0.01
            [[material]]
            name = "lone"
            density = 2000.0
            model = "jkr"
            youngs = 1e9
            poisson = 0.3
            surface_energy = 0.02
            [[material]]
            name = "plain"
            density = 2000.0
            model = "hysteretic"
            k1 = 100.0
            kp = 500.0
            kc = 0.0
            phi_f = 0.05
            [[interaction]]
            materials = ["lone", "soft"]
            model = "jkr"
            youngs = 1e11
            poisson = 0.3
            surface_energy = 0.01
            [[interaction]]
            materials = ["soft", "plain"]
            model = "hertz"
            youngs = 1e9
            poisson = 0.3
            [[interaction]]
            materials = ["lone", "plain"]
            model = "hertz"
            youngs = 1e9
            poisson = 0.3
            [[wall]]
            point = [0.0, 0.0, 0.0]
            normal = [0.0, 0.0, 1.0]
            material = "lone"
            [[particles]]
            kind = "list"
            material = "soft"
            positions = [[2e-4, 2e-4, 2e-4], [5e-4, 5e-4, 5e-4]]
            radii = [2e-5, 1e-5]
            [[particles]]
            kind = "list"
            material = "lone"
            positions = [[8e-4, 8e-4, 8e-4]]
            radius = 4e-5
            [[particles]]
            kind = "list"
            material = "plain"
            positions = [[2e-4, 8e-4, 2e-4]]
            radius = 3e-5
        "#;
        let scene = Scene::from_toml_str(text, "mixed").unwrap();
        let pairs = tabor_pairs(&scene, 1.65e-10);
        let got: Vec<(String, bool, f64, f64)> = pairs
            .iter()
            .map(|p| (p.label(), p.wall, p.r_eff, p.tabor))
            .collect();
        let r_soft_lone = 1e-5 * 4e-5 / 5e-5;
        let expect = [
            ("`soft`-`soft`", false, 0.5e-5, by_hand(1e8, 0.01, 0.5e-5)),
            (
                "`soft`-`lone`",
                false,
                r_soft_lone,
                by_hand(1e11, 0.01, r_soft_lone),
            ),
            // the wall (of "lone") against soft particles: the lone-soft interaction
            ("wall `lone`-`soft`", true, 1e-5, by_hand(1e11, 0.01, 1e-5)),
            ("wall `lone`-`lone`", true, 4e-5, by_hand(1e9, 0.02, 4e-5)),
        ];
        assert_eq!(got.len(), expect.len(), "{got:?}");
        for (g, e) in got.iter().zip(expect) {
            assert_eq!(g.0, e.0);
            assert_eq!(g.1, e.1);
            assert!((g.2 - e.2).abs() < 1e-12 * e.2, "{g:?}");
            assert!((g.3 - e.3).abs() < 1e-12 * e.3, "{g:?}");
        }
        // E = 100 GPa at γ = 0.01 and R* = 8 µm: λT ≈ 0.618, warned; the soft pair is not
        assert!(!pairs[1].jkr_range && (pairs[1].tabor - 0.618).abs() < 1e-3);
        let w = pairs[1].warnings().concat();
        assert!(w.contains("the material pair `soft`-`lone`"), "{w}");
        assert!(pairs[0].jkr_range && pairs[0].warnings().is_empty());
        let w = pairs[2].warnings().concat();
        assert!(w.contains("the wall-particle pair `lone`-`soft`"), "{w}");
    }

    /// A resume from an older checkpoint with --overwrite removes the later run's
    /// checkpoint and summary before it cuts that run's rows: killed right after the cut,
    /// the folder held a checkpoint and summary of results it no longer had, and no resume
    /// was accepted there.
    #[test]
    fn a_resume_that_cuts_a_later_run_removes_its_checkpoint_and_summary_first() {
        let scene = Scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/cohesive_cluster.toml"
        )))
        .unwrap();
        let scene = Scene {
            output_every: 500,
            checkpoint_every: 1000,
            ..scene
        };
        let (older, later) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let run = |dir: &std::path::Path, steps: u64| {
            let opts = RunOptions {
                out_dir: Some(dir.to_path_buf()),
                max_steps: Some(steps),
                no_snapshots: true,
                ..Default::default()
            };
            run_cpu_with(&scene, &opts, |_| {}).unwrap();
        };
        run(older.path(), 1000);
        run(later.path(), 3000);
        let old = older.path().join("checkpoint.bin");
        let (_, marks) = crate::checkpoint::load(&old, &scene).unwrap();
        let opts = RunOptions {
            out_dir: Some(later.path().to_path_buf()),
            resume: Some(old),
            overwrite: true,
            no_snapshots: true,
            ..Default::default()
        };
        let radii = scene.particles.iter().map(|p| p.radius).collect();
        // (opened, then dropped: a kill before the first chunk)
        let dt = CpuEngine::new(&scene).unwrap().dt();
        drop(RunOutputs::open(&scene, &opts, (Some(1000), &marks), radii, (dt, 3000)).unwrap());
        let d = later.path();
        assert!(!d.join("checkpoint.bin").exists() && !d.join("summary.json").exists());
        let last = crate::output::series_csv::last_row_step(&d.join("series.csv"));
        assert_eq!(last, Some(1000));
        // the folder resumes from the older checkpoint again, as straight as before
        let again = RunOptions {
            overwrite: false,
            ..opts
        };
        run_cpu_with(&scene, &again, |_| {}).unwrap();
    }
}
