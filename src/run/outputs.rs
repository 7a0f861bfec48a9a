//! A run's output folder: taken and checked before anything in it changes, trimmed to a
//! resumed checkpoint's step (or cleared of an earlier run), then written at the scene's
//! cadence (series rows, particle and contact snapshots), checkpointed, and summarised.

use std::path::{Path, PathBuf};

use crate::checkpoint::RunMarks;
use crate::error::PowderError;
use crate::output::atomic::{remove_stale_temps, write_atomic};
use crate::output::folder::{check_writable, FolderLock, CHECKPOINT, SERIES, SUMMARY};
use crate::output::series_csv::{self, SeriesCsv, SeriesMark};
use crate::output::{contacts, vtk};
use crate::run::monitor::MonitorReference;
use crate::run::simulation::{Observation, Simulation};
use crate::run::snapshot::{csv_header, csv_row, Snapshot};
use crate::run::{RunOptions, RunSummary};
use crate::scene::Scene;

/// The writers of a run's output folder (none where the run writes nothing).
pub(super) struct RunOutputs {
    /// `series.csv`.
    csv: Option<SeriesCsv>,
    /// The particle snapshots (`snapshots/`).
    particles: Option<vtk::Series>,
    /// The contact network (`contacts/`).
    contacts: Option<vtk::Series>,
    /// The particles' radii (the snapshots').
    radii: Vec<f64>,
    /// The walls' normals (the contact network's wall ends).
    wall_normals: Vec<glam::DVec3>,
    /// The latest state saved for a resume (its step and checkpoint): the one this run
    /// last wrote, or the one it resumed from.
    latest: Option<(u64, PathBuf)>,
    /// The folder, held for this run (last: released after the writers close).
    dir: Option<(PathBuf, FolderLock)>,
}

impl RunOutputs {
    /// Takes `opts.out_dir` for a run of `scene` to step `end` whose engine has `radii` and
    /// step `dt`:
    /// every output it replaces checked writable, and, resuming from step `resumed_from`
    /// with the checkpoint's `marks`, the series' rows up to that step kept (refused where
    /// they are not the ones that run wrote) and later snapshots removed; a fresh run
    /// removes the earlier run's checkpoint, summary and snapshots (where
    /// `opts.overwrite` allows: otherwise `earlier::check` refuses it first).
    pub(super) fn open(
        scene: &Scene,
        opts: &RunOptions,
        (resumed_from, marks): (Option<u64>, &RunMarks),
        radii: Vec<f64>,
        (dt, end): (f64, u64),
    ) -> Result<Self, PowderError> {
        let wall_normals = scene
            .walls
            .iter()
            .map(|w| glam::DVec3::from_array(w.normal).normalize())
            .collect();
        let Some(d) = opts.out_dir.as_deref() else {
            return Ok(RunOutputs {
                latest: None,
                dir: None,
                csv: None,
                particles: None,
                contacts: None,
                radii,
                wall_normals,
            });
        };
        let lock = Self::take(d, scene)?;
        super::earlier::check(d, scene, opts, resumed_from, end)?;
        let csv_path = d.join(SERIES);
        // the series' rows up to the checkpoint's step on resume, read (and its columns
        // checked) before anything in the directory changes
        let header = csv_header(&scene.walls);
        let mut kept = match resumed_from {
            Some(step) => series_csv::rows_until(&csv_path, step, &header)?,
            None => Vec::new(),
        };
        // only the rows written before the checkpoint: Ctrl-C's row off the output cadence
        // follows it (the straight run has none there); `late` is that row
        let mut late = None;
        let found = kept.len();
        // rows beyond the marked ones that are not that late row: another run's series
        let mut foreign = false;
        if let (Some(m), Some(step)) = (marks.series, resumed_from) {
            let marked = usize::try_from(m.rows).unwrap_or(usize::MAX);
            if kept.len() > marked {
                let beyond = kept.split_off(marked);
                foreign = beyond.iter().any(|r| !series_csv::row_is_at(r, step));
                late = beyond.into_iter().find(|r| series_csv::row_is_at(r, step));
            }
        }
        // rows kept on resume must be those the checkpoint's run wrote (no series at all: it
        // starts at the checkpoint's step)
        if let (Some(ckpt), Some(step)) = (&opts.resume, resumed_from) {
            let ours = marks.series;
            let differ = !kept.is_empty() && ours.is_some_and(|m| m != SeriesMark::of(&kept));
            if foreign || differ {
                return Err(PowderError::Run(format!(
                    "the series `{}` is not the one the run of checkpoint `{}` wrote (its {found} rows up to step {step} differ from that run's {}): resume into the folder that run wrote (--out), or into an empty one, where the series starts at the checkpoint's step",
                    csv_path.display(),
                    ckpt.display(),
                    ours.map_or(0, |m| m.rows)
                )));
            }
        }
        // (the scenes whose snapshots a resume cuts: a branch under another name cuts the
        // killed run's too; read before its summary and checkpoint may go)
        let cut_scenes = match resumed_from {
            Some(_) => super::earlier::replaced_scenes(d, scene),
            None => Vec::new(),
        };
        // a later run's summary and checkpoint go before its rows and snapshots are cut (a
        // kill in between left a folder whose files claimed results it no longer held;
        // `earlier::check` has refused this without --overwrite)
        if let Some(step) = resumed_from {
            for (file, _) in super::earlier::later_files(d, opts, step)
                .into_iter()
                .flatten()
            {
                std::fs::remove_file(&file).map_err(|e| {
                    PowderError::io(format!("cannot remove `{}`", file.display()), e)
                })?;
                if opts.verbose {
                    eprintln!("removed the later run's {}", file.display());
                }
            }
        }
        // a branch whose cadence falls on the checkpoint's step keeps that row (its straight
        // run has it, and a resumed run does not write its first step); otherwise the row and
        // the snapshots of that step go
        let drop_late = match late {
            Some(row) if resumed_from.is_some_and(|s| s.is_multiple_of(scene.output_every)) => {
                kept.push(row);
                false
            }
            Some(_) => true,
            None => false,
        };
        let mut particles = match opts.no_snapshots {
            false => Some(vtk::Series::new(d, &scene.name)?),
            true => None,
        };
        let mut network = match scene.writes_contacts() && !opts.no_snapshots {
            true => Some(vtk::Series::contacts(d, &scene.name)?),
            false => None,
        };
        // what writes killed before their rename left (the files they replace are intact)
        let stale = remove_stale_temps(d)
            + remove_stale_temps(&d.join("snapshots"))
            + remove_stale_temps(&d.join("contacts"));
        if stale > 0 && opts.verbose {
            eprintln!(
                "removed {stale} temporary files that interrupted writes left in {}",
                d.display()
            );
        }
        match resumed_from {
            Some(step) => {
                // the snapshots go with the rows: none at the checkpoint's step where its row
                // goes; both series, whether this run writes them or not (--no-snapshots)
                let last = if drop_late {
                    step.saturating_sub(1)
                } else {
                    step
                };
                let [p, c] = vtk::Series::both_unopened(d, &scene.name);
                for (opened, mut unopened) in [(particles.as_mut(), p), (network.as_mut(), c)] {
                    match opened {
                        Some(s) => s.keep_until(last, dt)?,
                        None => unopened.keep_until(last, dt)?,
                    }
                }
                let others = cut_scenes.iter().filter(|n| **n != scene.name);
                for mut s in others.flat_map(|n| vtk::Series::both_unopened(d, n)) {
                    s.keep_until(last, dt)?;
                }
            }
            None => Self::clear_earlier_run(d, scene, opts.verbose)?,
        }
        Ok(RunOutputs {
            csv: Some(SeriesCsv::start(&csv_path, &header, &kept)?),
            latest: resumed_from.zip(opts.resume.clone()),
            dir: Some((d.to_path_buf(), lock)),
            particles,
            contacts: network,
            radii,
            wall_normals,
        })
    }

    /// Holds the folder `d` for this run, with every output it writes checked writable
    /// before anything there changes.
    fn take(d: &Path, scene: &Scene) -> Result<FolderLock, PowderError> {
        let lock = FolderLock::take(d)?;
        // (`series.csv` is appended to and, at the start, replaced whole; the series of the
        // run replaced or cut are another scene's where another scene's run wrote the folder)
        let csv = d.join(SERIES);
        let series: Vec<vtk::Series> = (super::earlier::replaced_scenes(d, scene).iter())
            .flat_map(|n| vtk::Series::both_unopened(d, n))
            .collect();
        let mut replaced = vec![d.join(CHECKPOINT), d.join(SUMMARY), csv.clone()];
        replaced.extend(series.iter().map(vtk::Series::collection_path));
        check_writable(d, &replaced, &[csv])?;
        for s in &series {
            let sub = s.folder();
            if sub.is_dir() {
                check_writable(&sub, &s.snapshot_paths(), &[])?;
            }
        }
        Ok(lock)
    }

    /// A fresh run replaces the series (a resume keeps its rows up to the checkpoint's
    /// step: a killed run may have written more), and the checkpoint of the run it
    /// replaces goes with it (resumed, it would continue a series that is no longer
    /// there), with its summary and its snapshots (left beside the new run's, a killed run
    /// would look finished, its folder holding two runs).
    fn clear_earlier_run(d: &Path, scene: &Scene, verbose: bool) -> Result<(), PowderError> {
        // (read before the summary and checkpoint that name the earlier run's scene go)
        let names = super::earlier::replaced_scenes(d, scene);
        for c in [d.join(CHECKPOINT), d.join(SUMMARY)] {
            match std::fs::remove_file(&c) {
                Ok(()) if verbose => eprintln!("removed the earlier run's {}", c.display()),
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => {
                    return Err(PowderError::io(
                        format!("cannot remove `{}`", c.display()),
                        e,
                    ))
                }
            }
        }
        // (both series, whether this run writes them or not: they are the earlier run's;
        // that run's scene's too, where another scene's run wrote the folder)
        for mut s in names.iter().flat_map(|n| vtk::Series::both_unopened(d, n)) {
            let (removed, collection) = s.clear()?;
            if (removed > 0 || collection) && verbose {
                eprintln!(
                    "removed the earlier run's {removed} snapshot files in {}{}",
                    s.folder().display(),
                    match collection {
                        true => format!(" and {}", s.collection_path().display()),
                        false => String::new(),
                    }
                );
            }
        }
        Ok(())
    }

    /// The checkpoint's path, where the run writes one.
    pub(super) fn checkpoint_path(&self) -> Option<PathBuf> {
        self.dir.as_ref().map(|(d, _)| d.join(CHECKPOINT))
    }

    /// Whether the contact network is written with the snapshots.
    pub(super) fn writes_contacts(&self) -> bool {
        self.contacts.is_some()
    }

    /// The output folder, where the run writes one.
    pub(super) fn dir(&self) -> Option<&Path> {
        self.dir.as_ref().map(|(d, _)| d.as_path())
    }

    /// Writes the outputs of one step: its series row, particle snapshot and contact
    /// network.
    pub(super) fn write<S: Simulation>(
        &mut self,
        scene: &Scene,
        engine: &S,
        obs: &Observation,
        snap: &Snapshot,
    ) -> Result<(), PowderError> {
        if let Some(c) = self.csv.as_mut() {
            c.append(snap.step, &csv_row(snap, obs, &scene.walls))?;
        }
        if let Some(s) = self.particles.as_mut() {
            let appeared: Vec<bool> = match scene.pours() {
                true => (0..self.radii.len())
                    .map(|i| engine.has_appeared(i))
                    .collect(),
                false => Vec::new(),
            };
            s.write(
                snap.step,
                snap.time,
                &vtk::Particles {
                    positions: &obs.positions,
                    velocities: &obs.velocities,
                    radii: &self.radii,
                    angular_velocities: &obs.angular_velocities,
                    appeared: &appeared,
                },
            )?;
        }
        if let Some(n) = self.contacts.as_mut() {
            let ends = contacts::Ends {
                positions: &obs.positions,
                radii: &self.radii,
                wall_normals: &self.wall_normals,
                periodic: scene.domain.periodic,
                domain: (
                    glam::DVec3::from_array(scene.domain.min),
                    glam::DVec3::from_array(scene.domain.max),
                ),
            };
            let doc = contacts::vtp(&engine.contact_network()?, &ends);
            n.write_vtp(snap.step, snap.time, &doc)?;
        }
        Ok(())
    }

    /// Syncs the series' rows to disk.
    pub(super) fn sync_series(&mut self) -> Result<(), PowderError> {
        match self.csv.as_mut() {
            Some(c) => c.sync(),
            None => Ok(()),
        }
    }

    /// The rows synced, then the checkpoint they lead up to, with what the monitor
    /// measures against.
    pub(super) fn checkpoint<S: Simulation>(
        &mut self,
        scene: &Scene,
        engine: &S,
        monitor: MonitorReference,
    ) -> Result<(), PowderError> {
        self.checkpoint_marked(scene, engine, monitor, None)
    }

    /// The series' mark now (rows written so far), where the run writes one.
    pub(super) fn series_mark(&self) -> Option<SeriesMark> {
        self.csv.as_ref().map(SeriesCsv::mark)
    }

    /// [`Self::checkpoint`] with the series as `series` marked it, where given: an engine
    /// restored to an earlier step after a failed write checkpoints the rows as of then.
    pub(super) fn checkpoint_marked<S: Simulation>(
        &mut self,
        scene: &Scene,
        engine: &S,
        monitor: MonitorReference,
        series: Option<SeriesMark>,
    ) -> Result<(), PowderError> {
        let path = self.checkpoint_path();
        if let (Some(c), Some(rows)) = (path, self.csv.as_mut()) {
            rows.sync()?;
            let marks = RunMarks {
                series: Some(series.unwrap_or_else(|| rows.mark())),
                monitor: Some(monitor),
            };
            engine.write_checkpoint(&c, scene, &marks)?;
            self.latest = Some((engine.steps(), c));
        }
        Ok(())
    }

    /// Where a run stopped by an error can go on from: the latest state saved, or that
    /// none was (nothing where the run writes no folder).
    pub(super) fn latest_saved(&self) -> Option<String> {
        self.dir.as_ref()?;
        Some(match &self.latest {
            Some((step, c)) => format!(
                "the latest state saved is step {step}'s, in {}: resume it with --resume once the cause is fixed",
                c.display()
            ),
            None => "no state of this run was saved: it has to be run again".to_string(),
        })
    }

    /// [`Self::checkpoint`], whose failure (a full disk) says which step it was and the
    /// latest state saved before it (the earlier checkpoint stays whole).
    pub(super) fn checkpoint_or_say<S: Simulation>(
        &mut self,
        scene: &Scene,
        engine: &S,
        monitor: MonitorReference,
    ) -> Result<(), PowderError> {
        self.checkpoint(scene, engine, monitor).map_err(|e| {
            let latest = self.latest_saved().unwrap_or_default();
            PowderError::Run(format!(
                "the checkpoint at step {} could not be written ({e}); {latest}",
                engine.steps()
            ))
        })
    }

    /// Whether the folder holds a `summary.json`.
    pub(super) fn has_summary(&self) -> bool {
        self.dir().is_some_and(|d| d.join(SUMMARY).is_file())
    }

    /// Writes `summary.json`, where the run writes a folder.
    pub(super) fn write_summary(&self, summary: &RunSummary) -> Result<(), PowderError> {
        if let Some(d) = self.dir() {
            let text = serde_json::to_string_pretty(summary)
                .map_err(|e| PowderError::Run(format!("cannot encode the summary: {e}")))?;
            write_atomic(&d.join(SUMMARY), text.as_bytes())?;
        }
        Ok(())
    }
}
