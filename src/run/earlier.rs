//! What an output folder already holds from an earlier run: a fresh run does not remove
//! another run's outputs, nor a resume the results of a later step, unless asked to
//! ([`RunOptions::overwrite`], `powder run --overwrite`).

use super::*;
use crate::output::folder::{CHECKPOINT, SERIES, SUMMARY};
use crate::output::vtk;
use std::path::{Path, PathBuf};

/// Refuses a run of `scene` into `d` that would remove or trim what an earlier run wrote
/// there, unless `opts.overwrite`: a fresh run where the folder holds a checkpoint, a
/// summary, a series or this scene's snapshots; a resume from step `resumed_from` where it
/// holds a run that finished later, a checkpoint of a later step, or rows or snapshots
/// beyond this run's `end` (a killed run resumed from its own checkpoint to its end loses
/// only the rows it writes again). Call it before anything in the folder changes.
pub(super) fn check(
    d: &Path,
    scene: &Scene,
    opts: &RunOptions,
    resumed_from: Option<u64>,
    end: u64,
) -> Result<(), PowderError> {
    if opts.overwrite {
        return Ok(());
    }
    let (found, what) = match resumed_from {
        None => (
            fresh_run_would_remove(d, scene),
            "an earlier run's outputs".to_string(),
        ),
        Some(step) => (
            later_results(d, scene, opts, step, end),
            format!("results beyond the checkpoint's step {step}"),
        ),
    };
    if found.is_empty() {
        return Ok(());
    }
    // (only a checkpoint this scene can resume: after a run that blew up, rerun with a
    // smaller dt, the earlier checkpoint is another run's)
    let own = d.join(CHECKPOINT);
    let continue_it = match resumed_from {
        None if own.is_file() && crate::checkpoint::is_of(&own, scene) => format!(
            "continue that run (--resume {}), ",
            d.join(CHECKPOINT).display()
        ),
        _ => String::new(),
    };
    Err(PowderError::Run(format!(
        "`{}` holds {what} ({}), which this run would remove: {continue_it}write elsewhere (--out), or replace {} (--overwrite)",
        d.display(),
        found.join(", "),
        if found.len() > 1 { "them" } else { "it" },
    )))
}

/// The scenes whose snapshot series a fresh run of `scene` into `d` replaces: its own, and
/// that of the run whose summary or checkpoint is there (another scene's run into the same
/// folder).
pub(super) fn replaced_scenes(d: &Path, scene: &Scene) -> Vec<String> {
    let summary = std::fs::read(d.join(SUMMARY))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v.get("scene")?.as_str().map(str::to_string));
    let checkpoint = crate::checkpoint::scene_of(&d.join(CHECKPOINT)).ok();
    let mut names = vec![scene.name.clone()];
    // (only a name a scene can have: one that names files in the folder, not a path)
    for n in [summary, checkpoint].into_iter().flatten() {
        if crate::scene::can_name_files(&n) && !names.contains(&n) {
            names.push(n);
        }
    }
    names
}

/// What a fresh run of `scene` into `d` would remove or replace: the checkpoint, summary
/// and series, and the snapshot series of this scene and of the run replaced.
fn fresh_run_would_remove(d: &Path, scene: &Scene) -> Vec<String> {
    let mut found: Vec<String> = [CHECKPOINT, SUMMARY, SERIES]
        .into_iter()
        .filter(|f| d.join(f).exists())
        .map(|f| format!("`{f}`"))
        .collect();
    let names = replaced_scenes(d, scene);
    for s in names.iter().flat_map(|n| vtk::Series::both_unopened(d, n)) {
        let collection = s.collection_path();
        if collection.exists() {
            found.push(format!("`{}`", collection.display()));
        }
        let n = s.snapshot_count();
        if n > 0 {
            found.push(format!("{n} snapshot files in `{}`", s.folder().display()));
        }
    }
    found
}

/// The summary of a run in `d` that finished beyond `step` and a checkpoint there of a
/// later step than `step` (not the one `opts` resumes), each with its step: a resume from
/// `step` that cuts the folder's rows removes them first, or a kill would leave a folder
/// whose files claim results it no longer holds.
pub(super) fn later_files(d: &Path, opts: &RunOptions, step: u64) -> [Option<(PathBuf, u64)>; 2] {
    let summary = d.join(SUMMARY);
    let finished = std::fs::read(&summary)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v.get("steps").and_then(serde_json::Value::as_u64))
        .filter(|&s| s > step);
    let own = d.join(CHECKPOINT);
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    // (the folder's own checkpoint, resumed, is at `step`: not read a second time)
    let resumed = opts.resume.as_deref();
    let later = match own.is_file() && !resumed.is_some_and(|r| same(r, &own)) {
        true => crate::checkpoint::steps_of(&own).ok().filter(|&s| s > step),
        false => None,
    };
    [finished.map(|s| (summary, s)), later.map(|s| (own, s))]
}

/// What a resume from step `step` to step `end` into `d` would trim: a run there that
/// finished beyond `step` (its `summary.json`), a checkpoint of a later step, or a killed
/// run's rows or snapshots beyond `end` (those up to `end` it writes again).
fn later_results(d: &Path, scene: &Scene, opts: &RunOptions, step: u64, end: u64) -> Vec<String> {
    let mut found = Vec::new();
    let [summary, checkpoint] = later_files(d, opts, step);
    if let Some((_, s)) = summary {
        found.push(format!("a run that finished at step {s} (`{SUMMARY}`)"));
    }
    if let Some((_, s)) = checkpoint {
        found.push(format!("a checkpoint at step {s} (`{CHECKPOINT}`)"));
    }
    // (a run that finished later is named above: its rows need no second mention)
    // (one step to run on to: the latest of the files, which may end at different steps)
    if found.is_empty() {
        let mut beyond = Vec::new();
        let last = crate::output::series_csv::last_row_step(&d.join(SERIES));
        if let Some(s) = last.filter(|&s| s > end) {
            beyond.push((format!("`{SERIES}`'s rows"), s));
        }
        for series in vtk::Series::both_unopened(d, &scene.name) {
            if let Some(s) = series.last_step().filter(|&s| s > end) {
                beyond.push((format!("snapshots in `{}`", series.folder().display()), s));
            }
        }
        if let Some(latest) = beyond.iter().map(|&(_, s)| s).max() {
            let files: Vec<String> = (beyond.iter())
                .map(|(what, s)| format!("{what} to step {s}"))
                .collect();
            found.push(format!(
                "{} past this run's end at step {end}: run on to step {latest} (the resume writes its own rows and snapshots after the checkpoint's step, at its own cadence, in place of the killed run's)",
                files.join(", ")
            ));
        }
    }
    found
}
