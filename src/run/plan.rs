//! What a run checks and settles before anything in its output folder changes: the scene
//! and engine fit, the Tabor parameters, the checkpoint resumed, the first energies, the
//! step the run ends at, and the warnings a run gives before it starts.

use super::simulation::{Observation, Simulation};
use super::tabor::{tabor_pairs, TaborPair};
use super::{fits, servo, RunOptions};
use crate::checkpoint::RunMarks;
use crate::error::PowderError;
use crate::scene::Scene;

/// A run settled before it starts.
pub(super) struct RunPlan {
    /// The JKR pairs' Tabor parameters.
    pub tabor: Vec<TaborPair>,
    /// The step of the checkpoint resumed from.
    pub resumed_from: Option<u64>,
    /// What the checkpoint resumed from kept of its run (its rows, its monitor).
    pub marks: RunMarks,
    /// The engine's state at the start, observed.
    pub first: Observation,
    /// The step the run ends at.
    pub total: u64,
}

/// Checks `scene` and `engine` for a run with `opts` (resuming `engine` from its
/// checkpoint where asked) and settles where it ends; refuses before anything is written.
pub(super) fn plan<S: Simulation>(
    scene: &Scene,
    engine: &mut S,
    opts: &RunOptions,
) -> Result<RunPlan, PowderError> {
    // before anything is written: a scene built in code may not have met the reader, an
    // engine may have been built from another scene (whose build checked its placement)
    scene.validate_settings()?;
    if opts.out_dir.is_some() {
        scene.check_file_name()?;
    }
    fits::engine_fits(scene, engine)?;
    if !scene.duration.is_finite() && opts.max_steps.is_none() {
        return Err(PowderError::Run(format!(
            "scene `{}` has an infinite duration: a run needs a finite simulation.duration or a step limit (`RunOptions::max_steps`, `--steps`)",
            scene.name
        )));
    }
    let d_min = match opts.tabor_dmin {
        Some(d) => crate::error::require_positive("tabor-dmin", d, "D_min of the Tabor parameter")?,
        None => crate::model::analytic::TABOR_MIN_SEPARATION,
    };
    let tabor = tabor_pairs(scene, d_min);
    if let Some(t) = tabor.iter().find(|t| !t.tabor.is_finite()) {
        return Err(PowderError::Run(format!(
            "the Tabor parameter of materials `{}`-`{}` comes out as {} at D_min = {:e} m: D_min and the materials combine beyond what f64 holds; check D_min's units (`--tabor-dmin`, in m)",
            t.materials[0], t.materials[1], t.tabor, d_min
        )));
    }
    if opts.verbose {
        for w in tabor.iter().flat_map(TaborPair::warnings) {
            eprintln!("warning: {w}");
        }
    }
    let mut resumed_from = None;
    let mut marks = RunMarks::default();
    if let Some(ckpt) = &opts.resume {
        marks = engine.read_checkpoint(ckpt, scene)?;
        resumed_from = Some(engine.steps());
    }
    // a start whose energies are beyond f64's range is refused before anything in the
    // output folder changes
    let first = engine.observe()?;
    if let Some((name, value)) = first.energies.non_finite() {
        return Err(PowderError::Run(format!(
            "the {name} energy at step {} is {value}, beyond f64's range: a velocity, angular velocity or wall speed of the scene is far too large",
            engine.steps()
        )));
    }
    let total = ((scene.duration / engine.dt()).ceil() as u64).max(1);
    if let Some(m) = opts.max_steps.filter(|&m| m > total && opts.verbose) {
        eprintln!(
            "notice: the scene's duration {:e} s ends the run at step {total}, before --steps {m}",
            scene.duration
        );
    }
    let total = opts.max_steps.map_or(total, |m| m.min(total));
    if let Some(from) = resumed_from.filter(|&from| total < from) {
        return Err(PowderError::Run(format!(
            "the checkpoint is at step {from}, past this run's end at step {total} ({}): nothing to run; ask for a later end",
            match opts.max_steps {
                Some(m) if m < from => format!("--steps {m}"),
                _ => format!("the scene's duration {:e} s", scene.duration),
            }
        )));
    }
    if resumed_from == Some(total) && opts.verbose {
        // (not an error: a script that resumes until done may resume once more)
        eprintln!(
            "notice: the checkpoint is at this run's end, step {total}: nothing left to run; the outputs stay as that run wrote them"
        );
    }
    if opts.verbose {
        // (step k begins at k·dt)
        if let Some(w) = scene.late_insertions(total.saturating_sub(1) as f64 * engine.dt()) {
            eprintln!("warning: {w}");
        }
        if let Some(w) = scene.pour_onto_earlier() {
            eprintln!("warning: {w}");
        }
        if let Some(w) = scene.touching_at_start() {
            eprintln!("warning: {w}");
        }
        for w in servo::unstable_gains(scene, engine.dt()) {
            eprintln!("warning: {w}");
        }
        for w in super::overdamped::overdamped_friction(scene) {
            eprintln!("warning: {w}");
        }
    }
    Ok(RunPlan {
        tabor,
        resumed_from,
        marks,
        first,
        total,
    })
}
