//! `powder run` outputs: VTK + pvd, CSV series, summary, checkpoints that resume bitwise,
//! refusal of foreign checkpoints, Ctrl-C.

mod common;
use common::gpu;

use powder::checkpoint::npz;
use powder::error::PowderError;
use powder::run::{run_cpu_with, run_gpu_with, RunOptions, RunSummary, Snapshot};
use powder::scene::Scene;
use std::path::Path;

fn cluster() -> Scene {
    common::cluster_with_outputs()
}

fn options(out: &Path, steps: u64, resume: Option<&Path>) -> RunOptions {
    RunOptions {
        out_dir: Some(out.to_path_buf()),
        resume: resume.map(Path::to_path_buf),
        max_steps: Some(steps),
        ..Default::default()
    }
}

fn run(scene: &Scene, out: &Path, steps: u64, resume: Option<&Path>) -> powder::run::RunSummary {
    run_cpu_with(scene, &options(out, steps, resume), |_| {}).unwrap()
}

/// The GPU backend writes the same outputs, and its checkpoints resume bitwise on the same
/// adapter: resumed at step 5500, while the first contacts form (their history and the
/// energy ledger are part of the state), the run ends with the straight run's bytes.
#[test]
fn gpu_outputs_and_bitwise_resume() {
    let scene = cluster();
    let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let Some(ctx) = gpu() else { return };
    let a = run_gpu_with(&scene, ctx, &options(straight.path(), 6500, None), |_| {}).unwrap();
    assert_eq!(a.backend, "gpu");
    assert!(a.adapter.is_some());
    assert!(a.ledger);
    let contacts = a.last.contacts.expect("the ledger counts contacts");
    assert!(contacts.contacts > 0 && a.last.energies.dissipated > Some(0.0));
    let balance = a.energy_balance_error.expect("the ledger's balance");
    assert!(balance < 1e-3, "{balance}");
    let Some(ctx) = gpu() else { return };
    run_gpu_with(&scene, ctx, &options(split.path(), 5500, None), |_| {}).unwrap();
    let ckpt = split.path().join("checkpoint.bin");
    let Some(ctx) = gpu() else { return };
    let b = run_gpu_with(
        &scene,
        ctx,
        &options(split.path(), 6500, Some(&ckpt)),
        |_| {},
    )
    .unwrap();
    assert_eq!(b.resumed_from, Some(5500));
    let bytes = |d: &Path| std::fs::read(d.join("checkpoint.bin")).unwrap();
    assert!(
        bytes(straight.path()) == bytes(split.path()),
        "resumed GPU run differs"
    );
    let csv = |d: &Path| std::fs::read_to_string(d.join("series.csv")).unwrap();
    assert_eq!(csv(straight.path()), csv(split.path()));
    assert_eq!(csv(straight.path()).lines().count(), 1 + 14);
    assert!(split
        .path()
        .join("snapshots/cohesive_cluster_0000006500.vtp")
        .exists());
    // a GPU checkpoint does not resume on the CPU backend, and the reverse
    let err = run_cpu_with(&scene, &options(split.path(), 7000, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("gpu backend"), "{err}");
    let cpu_dir = tempfile::tempdir().unwrap();
    run(&scene, cpu_dir.path(), 100, None);
    let Some(ctx) = gpu() else { return };
    let cpu_ckpt = cpu_dir.path().join("checkpoint.bin");
    let err = run_gpu_with(
        &scene,
        ctx,
        &options(split.path(), 7000, Some(&cpu_ckpt)),
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("cpu backend"), "{err}");
}

/// A GPU checkpoint taken in the middle of a Krijt contact carries the contact radius (part
/// of the per-contact history): the resumed run ends with the straight run's bytes.
#[test]
fn gpu_krijt_checkpoint_mid_contact_resumes_bitwise() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/lj_krijt_pair.toml");
    let mut scene = Scene::load(Path::new(path)).unwrap();
    scene.output_every = 50;
    scene.checkpoint_every = 100;
    let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let Some(ctx) = gpu() else { return };
    // contact from t ≈ 20 (step ≈ 19) for about 230 (≈ 216 steps of dt = 1.07)
    let a = run_gpu_with(&scene, ctx, &options(straight.path(), 200, None), |_| {}).unwrap();
    assert!(
        a.last.contacts.is_some_and(|c| c.contacts > 0),
        "in contact at step 200"
    );
    let Some(ctx) = gpu() else { return };
    run_gpu_with(&scene, ctx, &options(split.path(), 100, None), |_| {}).unwrap();
    let ckpt = split.path().join("checkpoint.bin");
    let Some(ctx) = gpu() else { return };
    let b = run_gpu_with(
        &scene,
        ctx,
        &options(split.path(), 200, Some(&ckpt)),
        |_| {},
    )
    .unwrap();
    assert_eq!(b.resumed_from, Some(100));
    let bytes = |d: &Path| std::fs::read(d.join("checkpoint.bin")).unwrap();
    assert!(
        bytes(straight.path()) == bytes(split.path()),
        "resumed GPU Krijt run differs"
    );
}

#[test]
fn outputs_are_written_and_a_resumed_run_is_bitwise_identical() {
    let scene = cluster();
    let straight = tempfile::tempdir().unwrap();
    let split = tempfile::tempdir().unwrap();
    let whole = run(&scene, straight.path(), 3000, None);
    let first = run(&scene, split.path(), 1500, None);
    assert_eq!(first.steps, 1500);
    // (the wall time splits into the steps and the work around them)
    assert!(
        whole.stepping_seconds > 0.0 && whole.stepping_seconds <= whole.wall_seconds,
        "{} of {} s",
        whole.stepping_seconds,
        whole.wall_seconds
    );
    let ckpt = split.path().join("checkpoint.bin");
    let resumed = run(&scene, split.path(), 3000, Some(&ckpt));
    assert_eq!(resumed.resumed_from, Some(1500));
    assert_eq!(resumed.steps, 3000);
    // the energy balance measured from the run's start, as the straight run's
    let balance = whole.energy_balance_error.expect("the ledger's balance");
    assert!(balance > 0.0);
    assert_eq!(resumed.energy_balance_error, Some(balance));
    // identical state ⇒ identical checkpoint bytes
    let a = std::fs::read(straight.path().join("checkpoint.bin")).unwrap();
    let b = std::fs::read(split.path().join("checkpoint.bin")).unwrap();
    assert!(a == b, "resumed run differs from the straight run");
    // the series and the collection continue seamlessly
    let csv_a = std::fs::read_to_string(straight.path().join("series.csv")).unwrap();
    let csv_b = std::fs::read_to_string(split.path().join("series.csv")).unwrap();
    assert_eq!(csv_a, csv_b);
    assert_eq!(
        csv_a.lines().count(),
        1 + 7,
        "header + steps 0..=3000 every 500"
    );
    for collection in ["cohesive_cluster.pvd", "cohesive_cluster_contacts.pvd"] {
        let pvd = std::fs::read_to_string(split.path().join(collection)).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 7, "{collection}");
    }
    let vtp = std::fs::read_to_string(
        split
            .path()
            .join("snapshots/cohesive_cluster_0000003000.vtp"),
    )
    .unwrap();
    assert!(vtp.contains(r#"NumberOfPoints="200""#));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(split.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["steps"], 3000);
    assert!(summary["solid_fraction_bounding_box"].as_f64().unwrap() > 0.0);
    // a fresh run into the same folder, asked to replace it, removes that run's summary
    // and snapshots at its start (a file of another series stays)
    let other = split.path().join("snapshots/other_0000000500.vtp");
    std::fs::write(&other, "another series").unwrap();
    let summary = split.path().join("summary.json");
    let mut checked = 0;
    let replace = RunOptions {
        overwrite: true,
        ..options(split.path(), 1000, None)
    };
    run_cpu_with(&scene, &replace, |_| {
        assert!(
            !summary.exists(),
            "the earlier run's summary is still there"
        );
        checked += 1;
    })
    .unwrap();
    assert!(checked > 0);
    for folder in ["snapshots", "contacts"] {
        let mut files: Vec<String> = std::fs::read_dir(split.path().join(folder))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f.starts_with("cohesive_cluster"))
            .collect();
        files.sort();
        let steps: Vec<&str> = files
            .iter()
            .map(|f| &f[f.len() - 14..f.len() - 4])
            .collect();
        assert_eq!(
            steps,
            ["0000000000", "0000000500", "0000001000"],
            "{folder}"
        );
    }
    assert!(other.exists());
    for collection in ["cohesive_cluster.pvd", "cohesive_cluster_contacts.pvd"] {
        let pvd = std::fs::read_to_string(split.path().join(collection)).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 3, "{collection}");
    }
}

/// A checkpoint resumes under a scene that changes only what follows it — the wall
/// phases from its time on, the duration, the outputs, the name — and the run ends bitwise
/// as that scene's straight run (one prepared sample, tested several ways); a scene that
/// changes a wall phase before the checkpoint's time is refused.
#[test]
fn a_checkpoint_branches_into_wall_phases_that_follow_it() {
    use powder::scene::{WallMotion, WallPhase};
    let with_floor = |phases: Vec<(f64, WallPhase)>| {
        let mut s = cluster();
        s.walls[0].motion = WallMotion { phases };
        s
    };
    let dt = powder::cpu::CpuEngine::new(&cluster()).unwrap().dt();
    let (t_switch, ckpt_step) = (2000.5 * dt, 1500);
    let lift = WallPhase::Velocity([0.0, 0.0, 0.02]);
    let drop = WallPhase::Velocity([0.0, 0.0, -0.02]);
    let prepared = with_floor(vec![(t_switch, lift)]);
    let mut branch = with_floor(vec![(t_switch, drop)]);
    branch.duration *= 2.0;
    branch.output_every = 250;
    let straight = tempfile::tempdir().unwrap();
    let split = tempfile::tempdir().unwrap();
    run(&branch, straight.path(), 3000, None);
    run(&prepared, split.path(), ckpt_step, None);
    let ckpt = split.path().join("prepared.bin");
    std::fs::copy(split.path().join("checkpoint.bin"), &ckpt).unwrap();
    let mut renamed = branch.clone();
    renamed.name = "another_name".into();
    let resumed = run_cpu_with(&renamed, &options(split.path(), 3000, Some(&ckpt)), |_| {});
    assert_eq!(resumed.unwrap().resumed_from, Some(ckpt_step));
    let state = |dir: &Path| {
        let bytes = std::fs::read(dir.join("checkpoint.bin")).unwrap();
        let archive = npz::Archive::read(&bytes).unwrap();
        let names: Vec<String> = archive.names().map(str::to_string).collect();
        names
            .iter()
            .filter(|n| n.as_str() != "powder.json")
            .map(|n| archive.raw(n).unwrap().to_vec())
            .collect::<Vec<_>>()
    };
    assert!(
        state(straight.path()) == state(split.path()),
        "the branch differs from its straight run"
    );
    // (the floor went down in both: the branch's phase, not the prepared one's)
    let last = |dir: &Path| {
        let csv = std::fs::read_to_string(dir.join("series.csv")).unwrap();
        csv.lines().last().unwrap().to_string()
    };
    assert_eq!(last(straight.path()), last(split.path()));
    // a wall that starts moving only after the checkpoint adds columns to the series: not
    // into the directory whose series lacks them (left as it was), but into another
    let mut moving_later = branch.clone();
    moving_later.walls[1].motion = WallMotion {
        phases: vec![(t_switch, WallPhase::Velocity([0.0, 0.01, 0.0]))],
    };
    // (asked to replace the branch's later results: the columns refuse it all the same)
    let series = std::fs::read(split.path().join("series.csv")).unwrap();
    let replace = RunOptions {
        overwrite: true,
        ..options(split.path(), 3000, Some(&ckpt))
    };
    let err = run_cpu_with(&moving_later, &replace, |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("other columns"), "{err}");
    assert_eq!(
        std::fs::read(split.path().join("series.csv")).unwrap(),
        series
    );
    let elsewhere = tempfile::tempdir().unwrap();
    run_cpu_with(
        &moving_later,
        &options(elsewhere.path(), 3000, Some(&ckpt)),
        |_| {},
    )
    .unwrap();
    // a phase before the checkpoint's time is part of the run so far: refused
    let early = with_floor(vec![(1000.5 * dt, drop)]);
    let err = run_cpu_with(&early, &options(split.path(), 3000, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("wall phases from the checkpoint's time on"),
        "{err}"
    );
}

/// The checkpoint `bytes` with its header changed by `edit` (the members otherwise as they
/// are).
fn with_header(bytes: &[u8], edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    let archive = npz::Archive::read(bytes).unwrap();
    let members: Vec<(String, npz::Member)> = archive
        .names()
        .map(|name| {
            let raw = archive.raw(name).unwrap().to_vec();
            let raw = match name {
                "powder.json" => {
                    let mut header: serde_json::Value = serde_json::from_slice(&raw).unwrap();
                    edit(&mut header);
                    serde_json::to_vec_pretty(&header).unwrap()
                }
                _ => raw,
            };
            (name.to_string(), npz::Member::Raw(raw))
        })
        .collect();
    npz::write(&members)
}

/// The format after this powder's.
const NEXT_FORMAT: u32 = powder::checkpoint::FORMAT + 1;

/// The checkpoint `bytes` with its header saying the next format.
fn as_next_format(bytes: &[u8]) -> Vec<u8> {
    with_header(bytes, |h| h["format"] = NEXT_FORMAT.into())
}

/// A fresh run into a folder holding an earlier run's outputs, or files of the names a run
/// writes, is refused before anything there changes; so is a resume from an earlier
/// checkpoint into a folder whose run finished later. `overwrite` replaces them. (A fresh
/// run used to remove them unasked, and one that then failed left a finished run's folder
/// with a single row.)
#[test]
fn an_earlier_runs_outputs_are_kept_unless_overwritten() {
    let scene = cluster();
    let (done, early, mine) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    run(&scene, done.path(), 1500, None);
    let files = |d: &Path| {
        let mut v: Vec<(String, Vec<u8>)> = ["series.csv", "summary.json", "checkpoint.bin"]
            .iter()
            .map(|f| (f.to_string(), std::fs::read(d.join(f)).unwrap()))
            .collect();
        let mut shots: Vec<_> = std::fs::read_dir(d.join("snapshots"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        shots.sort();
        v.push(("snapshots".into(), shots.join(",").into_bytes()));
        v
    };
    let before = files(done.path());
    let err = run_cpu_with(&scene, &options(done.path(), 1000, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("an earlier run's outputs")
            && err.contains("`checkpoint.bin`")
            && err.contains("snapshot files")
            && err.contains("--resume")
            && err.contains("--overwrite"),
        "{err}"
    );
    assert!(
        files(done.path()) == before,
        "the refused run changed the folder"
    );
    // another scene (a rerun after a change) is not told to resume a checkpoint it cannot
    let mut changed = scene.clone();
    changed.gravity[2] *= 0.5;
    let err = run_cpu_with(&changed, &options(done.path(), 1000, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("--overwrite") && !err.contains("--resume"),
        "{err}"
    );
    // a resume from an earlier checkpoint of the same run would trim the later results
    run(&scene, early.path(), 500, None);
    let ckpt = mine.path().join("at_500.bin");
    std::fs::copy(early.path().join("checkpoint.bin"), &ckpt).unwrap();
    let err = run_cpu_with(&scene, &options(done.path(), 1000, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("beyond the checkpoint's step 500")
            && err.contains("finished at step 1500")
            && err.contains("checkpoint at step 1500"),
        "{err}"
    );
    assert!(
        files(done.path()) == before,
        "the refused resume changed the folder"
    );
    // a resume that would end before its checkpoint has nothing to run
    let err = run_cpu_with(&scene, &options(early.path(), 200, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("checkpoint is at step 500") && err.contains("--steps 200"),
        "{err}"
    );
    // files of a run's names that no run wrote
    std::fs::write(mine.path().join("series.csv"), "my,own\n1,2\n").unwrap();
    let err = run_cpu_with(&scene, &options(mine.path(), 100, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("`series.csv`"), "{err}");
    assert_eq!(
        std::fs::read_to_string(mine.path().join("series.csv")).unwrap(),
        "my,own\n1,2\n"
    );
    // asked to, both replace
    let overwrite = |steps, resume: Option<&Path>| RunOptions {
        overwrite: true,
        ..options(done.path(), steps, resume)
    };
    let s = run_cpu_with(&scene, &overwrite(1000, Some(&ckpt)), |_| {}).unwrap();
    assert_eq!(s.steps, 1000);
    let s = run_cpu_with(&scene, &overwrite(500, None), |_| {}).unwrap();
    assert_eq!(s.steps, 500);
    let rows = std::fs::read_to_string(done.path().join("series.csv")).unwrap();
    assert!(rows.lines().last().unwrap().starts_with("500,"), "{rows}");
}

/// A killed run resumed to an earlier end than the rows it wrote past its checkpoint is
/// refused (those rows and snapshots would go); resumed to its end, it writes them again,
/// byte for byte.
#[test]
fn a_killed_run_resumed_short_of_its_rows_is_refused() {
    let scene = cluster();
    let (done, early, killed) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    run(&scene, done.path(), 1500, None);
    run(&scene, early.path(), 500, None);
    // a run killed after step 1500's row and snapshot, its last checkpoint at step 500
    let copy = |from: &Path, to: &Path| {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            if e.file_type().unwrap().is_file() {
                std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
            }
        }
    };
    copy(done.path(), killed.path());
    copy(
        &done.path().join("snapshots"),
        &killed.path().join("snapshots"),
    );
    std::fs::remove_file(killed.path().join("summary.json")).unwrap();
    std::fs::copy(
        early.path().join("checkpoint.bin"),
        killed.path().join("checkpoint.bin"),
    )
    .unwrap();
    // (its series cut after step 1000's row: the files end at different steps)
    let csv = killed.path().join("series.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let cut = text.trim_end().rfind('\n').unwrap() + 1;
    assert!(text[cut..].starts_with("1500,"), "{text}");
    std::fs::write(&csv, &text[..cut]).unwrap();
    let ckpt = killed.path().join("checkpoint.bin");
    let series = || std::fs::read(killed.path().join("series.csv")).unwrap();
    let shots = || {
        std::fs::read_dir(killed.path().join("snapshots"))
            .unwrap()
            .count()
    };
    let (rows, snapshots) = (series(), shots());
    let err = run_cpu_with(&scene, &options(killed.path(), 700, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    // one step to run on to, the latest of the files'
    assert!(
        err.contains("`series.csv`'s rows to step 1000, snapshots in")
            && err.contains("to step 1500 past this run's end at step 700: run on to step 1500")
            && err.matches("run on to").count() == 1
            && err.contains("--overwrite"),
        "{err}"
    );
    assert!(
        series() == rows && shots() == snapshots,
        "the refused resume changed the folder"
    );
    // to its end it writes the same rows again
    run(&scene, killed.path(), 1500, Some(&ckpt));
    assert!(series() == std::fs::read(done.path().join("series.csv")).unwrap());
    assert_eq!(shots(), snapshots);
}

/// The files a run leaves that a resume must reproduce: the series, the checkpoint and the
/// snapshot files' names.
fn run_files(d: &Path) -> (Vec<u8>, Vec<u8>, Vec<String>) {
    let mut shots: Vec<String> = std::fs::read_dir(d.join("snapshots"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    shots.sort();
    (
        std::fs::read(d.join("series.csv")).unwrap(),
        std::fs::read(d.join("checkpoint.bin")).unwrap(),
        shots,
    )
}

/// A run that ended off the output cadence (step 1250 of 500), resumed to a later end,
/// keeps its last row and snapshot (written on that run's cadence: a resume cannot tell
/// them from a branch's), and otherwise leaves what the straight run does.
#[test]
fn a_run_ended_off_the_cadence_and_extended_keeps_its_last_row() {
    let scene = cluster();
    let (straight, extended) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&scene, straight.path(), 2000, None);
    run(&scene, extended.path(), 1250, None);
    let ckpt = extended.path().join("checkpoint.bin");
    let rows = std::fs::read_to_string(extended.path().join("series.csv")).unwrap();
    assert!(rows.lines().last().unwrap().starts_with("1250,"), "{rows}");
    run(&scene, extended.path(), 2000, Some(&ckpt));
    let (rows, _, mut shots) = run_files(extended.path());
    let (straight_rows, _, straight_shots) = run_files(straight.path());
    let rows = String::from_utf8(rows).unwrap();
    let without: String = (rows.lines())
        .filter(|l| !l.starts_with("1250,"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(rows.contains("\n1250,") && without.as_bytes() == straight_rows);
    shots.retain(|f| !f.ends_with("_0000001250.vtp"));
    assert_eq!(shots, straight_shots);
    // resumed to the same end (nothing to run), its last row stays, and its summary (the
    // run's start and wall time were replaced by those of no steps)
    let summary = std::fs::read(straight.path().join("summary.json")).unwrap();
    let again = run(
        &scene,
        straight.path(),
        2000,
        Some(&straight.path().join("checkpoint.bin")),
    );
    assert_eq!(again.steps, 2000);
    let rows = std::fs::read_to_string(straight.path().join("series.csv")).unwrap();
    assert!(rows.lines().last().unwrap().starts_with("2000,"), "{rows}");
    assert_eq!(
        std::fs::read(straight.path().join("summary.json")).unwrap(),
        summary
    );
}

/// A branch resumed with another `output_every` keeps the rows and snapshots its first run
/// wrote on that run's cadence, the checkpoint's own step included (1500: on the cadence of
/// 500, off that of 750), and goes on at the new cadence.
#[test]
fn a_branch_with_another_output_cadence_keeps_the_rows_before_it() {
    let scene = cluster();
    let d = tempfile::tempdir().unwrap();
    run(&scene, d.path(), 1500, None);
    let mut branch = scene.clone();
    branch.output_every = 750;
    run(
        &branch,
        d.path(),
        3000,
        Some(&d.path().join("checkpoint.bin")),
    );
    let (rows, _, shots) = run_files(d.path());
    let steps: Vec<&str> = (std::str::from_utf8(&rows).unwrap().lines())
        .filter(|l| !l.starts_with('#') && !l.starts_with("step"))
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(steps, ["0", "500", "1000", "1500", "2250", "3000"]);
    for step in ["0000001500", "0000002250", "0000003000"] {
        assert!(shots.iter().any(|f| f.contains(step)), "{step}: {shots:?}");
    }
}

/// A snapshot that cannot be written (here `snapshots/` turned into a file at step 1000's
/// output, before the first periodic checkpoint is written) stops the run with the state
/// as the chunk began (step 500) checkpointed: resumed once the folder is back, the run
/// ends with the straight run's files.
#[test]
fn a_failed_write_checkpoints_the_state_before_it() {
    let scene = cluster();
    let (straight, failed) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&scene, straight.path(), 2000, None);
    let (shots, aside) = (failed.path().join("snapshots"), failed.path().join("aside"));
    let sabotage = |s: &powder::run::Snapshot| {
        if s.step == 1000 {
            std::fs::rename(&shots, &aside).unwrap();
            std::fs::write(&shots, "not a folder").unwrap();
        }
    };
    let err = run_cpu_with(&scene, &options(failed.path(), 2000, None), sabotage)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("the state at step 500 (before the failed write")
            && err.contains("checkpoint.bin")
            && err.contains("--resume"),
        "{err}"
    );
    std::fs::remove_file(&shots).unwrap();
    std::fs::rename(&aside, &shots).unwrap();
    let ckpt = failed.path().join("checkpoint.bin");
    run(&scene, failed.path(), 2000, Some(&ckpt));
    assert!(run_files(failed.path()) == run_files(straight.path()));
    // where no checkpoint can be written either (a folder in its way), the error says that
    // no state was saved: after a failed write, and at the periodic checkpoint
    for write_fails in [true, false] {
        let d = tempfile::tempdir().unwrap();
        let (shots, ckpt) = (d.path().join("snapshots"), d.path().join("checkpoint.bin"));
        let sabotage = |s: &powder::run::Snapshot| {
            if s.step == 1000 {
                std::fs::create_dir_all(ckpt.join("in the way")).unwrap();
                if write_fails {
                    std::fs::remove_dir_all(&shots).unwrap();
                    std::fs::write(&shots, "not a folder").unwrap();
                }
            }
        };
        let err = run_cpu_with(&scene, &options(d.path(), 2000, None), sabotage)
            .unwrap_err()
            .to_string();
        let said = match write_fails {
            true => "(before the failed write) could not be checkpointed either",
            false => "the checkpoint at step 1000 could not be written",
        };
        assert!(
            err.contains(said) && err.contains("no state of this run was saved"),
            "{err}"
        );
    }
}

/// Another scene's fresh run into a folder replaces the earlier run's snapshots too (by
/// the scene its summary names), so the folder never mixes two scenes' outputs.
#[test]
fn another_scenes_run_replaces_the_earlier_runs_snapshots() {
    let scene = cluster();
    let mut other = scene.clone();
    other.name = "other".into();
    let dir = tempfile::tempdir().unwrap();
    run(&scene, dir.path(), 600, None);
    let err = run_cpu_with(&other, &options(dir.path(), 600, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("cohesive_cluster.pvd") && err.contains("--overwrite"),
        "{err}"
    );
    let opts = RunOptions {
        overwrite: true,
        ..options(dir.path(), 600, None)
    };
    run_cpu_with(&other, &opts, |_| {}).unwrap();
    let left: Vec<String> = walk(dir.path())
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .filter(|p| p.contains("cohesive_cluster"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    assert!(dir.path().join("other.pvd").exists());
}

/// Ctrl-C during the last chunk finds the run complete: it is not reported interrupted
/// (a resume would have nothing to run).
#[test]
fn an_interrupt_in_the_last_chunk_leaves_a_complete_run() {
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        interrupt: Some(std::sync::Arc::new(std::sync::atomic::AtomicBool::new(
            true,
        ))),
        ..options(dir.path(), 300, None)
    };
    let s = run_cpu_with(&cluster(), &opts, |_| {}).unwrap();
    assert!(!s.interrupted && s.steps == 300, "{} steps", s.steps);
}

/// A resume keeps only the rows its checkpoint's run wrote: into a folder of another run
/// it is refused (nothing there changes); into an empty one the series starts at the
/// checkpoint's step.
#[test]
fn a_resume_into_another_runs_folder_is_refused() {
    let scene = cluster();
    let mut other = scene.clone();
    other.gravity[2] *= 0.5;
    let (mine, theirs, empty) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    run(&scene, mine.path(), 1500, None);
    run(&other, theirs.path(), 1500, None);
    let ckpt = mine.path().join("checkpoint.bin");
    let before = std::fs::read(theirs.path().join("series.csv")).unwrap();
    let err = run_cpu_with(&scene, &options(theirs.path(), 3000, Some(&ckpt)), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("is not the one the run of checkpoint") && err.contains("--out"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(theirs.path().join("series.csv")).unwrap(),
        before
    );
    // a checkpoint whose run wrote no rows before it (a branch with a long cadence, into an
    // empty folder) is refused too where the folder has rows
    let mut sparse = scene.clone();
    sparse.output_every = 1_000_000;
    let branch = tempfile::tempdir().unwrap();
    run(&sparse, branch.path(), 2500, Some(&ckpt));
    let before = std::fs::read(mine.path().join("series.csv")).unwrap();
    let zero_rows = branch.path().join("checkpoint.bin");
    let err = run_cpu_with(
        &sparse,
        &options(mine.path(), 3000, Some(&zero_rows)),
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("is not the one the run of checkpoint"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(mine.path().join("series.csv")).unwrap(),
        before
    );
    // its own folder and an empty one resume
    run(&scene, empty.path(), 3000, Some(&ckpt));
    let rows = std::fs::read_to_string(empty.path().join("series.csv")).unwrap();
    assert!(rows.lines().nth(1).unwrap().starts_with("2000,"), "{rows}");
    run(&scene, mine.path(), 3000, Some(&ckpt));
}

#[test]
fn foreign_or_broken_checkpoints_are_refused() {
    let scene = cluster();
    let dir = tempfile::tempdir().unwrap();
    run(&scene, dir.path(), 200, None);
    let ckpt = dir.path().join("checkpoint.bin");
    let mut other = scene.clone();
    other.gravity[2] = -9.8;
    let opts = RunOptions {
        resume: Some(ckpt.clone()),
        ..Default::default()
    };
    let err = run_cpu_with(&other, &opts, |_| {}).unwrap_err().to_string();
    assert!(
        err.contains("belongs to scene") && err.contains("very scene"),
        "{err}"
    );
    // the refusal names what differs, and only that
    assert!(err.contains("they differ in simulation.gravity:"), "{err}");
    let mut other = scene.clone();
    other.materials[0].density *= 1.01;
    other.particles.pop();
    let err = run_cpu_with(&other, &opts, |_| {}).unwrap_err().to_string();
    assert!(
        err.contains("they differ in material 0, particles:"),
        "{err}"
    );
    let bytes = std::fs::read(&ckpt).unwrap();
    let refusal = |file: &[u8]| {
        let broken = dir.path().join("broken.bin");
        std::fs::write(&broken, file).unwrap();
        let opts = RunOptions {
            resume: Some(broken),
            ..Default::default()
        };
        run_cpu_with(&scene, &opts, |_| {}).unwrap_err().to_string()
    };
    // cut within the opening bytes and the header, then after it
    for cut in [4, 12] {
        let err = refusal(&bytes[..cut]);
        assert!(
            err.contains("not a powder checkpoint"),
            "cut at {cut}: {err}"
        );
    }
    for cut in [bytes.len() / 2, bytes.len() - 1] {
        let err = refusal(&bytes[..cut]);
        assert!(err.contains("damaged or truncated"), "cut at {cut}: {err}");
    }
    // another format is named: the archive written again with another header
    let err = refusal(&as_next_format(&bytes));
    assert!(err.contains(&format!("(format {NEXT_FORMAT})")), "{err}");
    // a header whose step is not the state's
    let err = refusal(&with_header(&bytes, |h| {
        h["steps"] = (h["steps"].as_u64().unwrap() + 1).into()
    }));
    assert!(
        err.contains("damaged or truncated") && err.contains("its header says step"),
        "{err}"
    );
    // the bincode checkpoints of formats up to 16 are named as such
    let err = refusal(b"POWDERCK\x11\x00\x00\x00 and the rest");
    assert!(err.contains("format 16 or earlier"), "{err}");
    // one flipped bit in the state (in the arrays; near the end, in the zip directory)
    for at in [bytes.len() / 3, bytes.len() / 2, bytes.len() - 2] {
        let mut flipped = bytes.clone();
        flipped[at] ^= 0x10;
        let err = refusal(&flipped);
        assert!(
            err.contains("damaged or truncated"),
            "bit flipped at {at}: {err}"
        );
    }
    let broken = dir.path().join("broken.bin");
    std::fs::write(&broken, b"not a checkpoint").unwrap();
    let opts = RunOptions {
        resume: Some(broken),
        ..Default::default()
    };
    let err = run_cpu_with(&scene, &opts, |_| {}).unwrap_err().to_string();
    assert!(err.contains("not a powder checkpoint"), "{err}");
    let opts = RunOptions {
        out_dir: Some("/dev/null/cannot".into()),
        ..Default::default()
    };
    let err = run_cpu_with(&scene, &opts, |_| {}).unwrap_err().to_string();
    assert!(err.contains("/dev/null/cannot"), "{err}");
}

/// A `powder run` whose stderr is read on a thread as it comes, its stop signals at their
/// defaults (a test runner started in the background of a script ignores SIGINT, and so
/// would the run it starts: the lease script's did on the H200). Killed if dropped
/// unfinished (a failed assertion leaves no run behind).
#[cfg(unix)]
struct SignalledRun {
    child: std::process::Child,
    lines: std::sync::mpsc::Receiver<String>,
    seen: String,
}

#[cfg(unix)]
impl SignalledRun {
    fn start(args: &[&str]) -> Self {
        use std::io::BufRead;
        use std::os::unix::process::CommandExt;
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_powder"));
        cmd.args(args)
            .stderr(std::process::Stdio::piped())
            .stdout(std::process::Stdio::null());
        // SAFETY: only async-signal-safe calls between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                    libc::signal(sig, libc::SIG_DFL);
                }
                Ok(())
            });
        }
        let mut child = cmd.spawn().unwrap();
        let stderr = child.stderr.take().unwrap();
        let (tx, lines) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr)
                .lines()
                .map_while(Result::ok)
            {
                let _ = tx.send(line);
            }
        });
        Self {
            child,
            lines,
            seen: String::new(),
        }
    }

    /// Waits (at most a minute) for a stderr line that starts with `text`.
    fn wait_for(&mut self, text: &str) {
        let end = std::time::Instant::now() + std::time::Duration::from_secs(60);
        while let Some(left) = end.checked_duration_since(std::time::Instant::now()) {
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    let found = line.starts_with(text);
                    self.seen.push_str(&line);
                    self.seen.push('\n');
                    if found {
                        return;
                    }
                }
                Err(_) => break,
            }
        }
        panic!("no line starting {text:?} within a minute: {}", self.seen);
    }

    fn signal(&self, sig: libc::c_int) {
        // SAFETY: kill with the child's pid, which it keeps until it is waited for.
        let sent = unsafe { libc::kill(self.child.id() as libc::pid_t, sig) };
        assert_eq!(sent, 0, "kill({sig}) failed");
    }

    /// Waits (at most a minute) for the process; its status and all it wrote to stderr.
    fn finish(mut self) -> (std::process::ExitStatus, String) {
        let end = std::time::Instant::now() + std::time::Duration::from_secs(60);
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if std::time::Instant::now() > end {
                panic!("the run did not end within a minute: {}", self.seen);
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        while let Ok(line) = self.lines.recv_timeout(std::time::Duration::from_secs(10)) {
            self.seen.push_str(&line);
            self.seen.push('\n');
        }
        (status, std::mem::take(&mut self.seen))
    }
}

#[cfg(unix)]
impl Drop for SignalledRun {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Ctrl-C, and the SIGTERM and SIGHUP that schedulers, `timeout` and a closed terminal
/// send, each write a checkpoint and exit with 128 + the signal's number; no thread but the
/// one that takes them can be interrupted by them (Linux: read from /proc).
#[cfg(unix)]
#[test]
fn a_stop_signal_writes_a_checkpoint_and_exits_with_its_status() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/jkr_deposition.toml");
    let runs: Vec<_> = [
        ("INT", libc::SIGINT, 130),
        ("TERM", libc::SIGTERM, 143),
        ("HUP", libc::SIGHUP, 129),
    ]
    .into_iter()
    .map(|(signal, number, status)| {
        let dir = tempfile::tempdir().unwrap();
        let run = SignalledRun::start(&["run", scene, "--out", dir.path().to_str().unwrap()]);
        (signal, number, status, dir, run)
    })
    .collect();
    for (signal, number, status, dir, mut run) in runs {
        // (the first progress line: the run has begun)
        run.wait_for("step ");
        let open: Vec<_> = threads_of(run.child.id())
            .into_iter()
            .filter(|(_, name, blocked)| {
                name != "stop-signals" && blocked & STOP_SIGNALS != STOP_SIGNALS
            })
            .collect();
        assert!(
            open.is_empty(),
            "SIG{signal}: threads that take stop signals: {open:?}"
        );
        run.signal(number);
        let (code, stderr) = run.finish();
        assert_eq!(code.code(), Some(status), "SIG{signal}: {stderr}");
        assert!(
            stderr.contains("interrupted at step"),
            "SIG{signal}: {stderr}"
        );
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(summary["interrupted"], true);
        assert!(dir.path().join("checkpoint.bin").exists());
    }
}

/// SIGHUP, SIGINT and SIGTERM as bits of a /proc signal mask.
#[cfg(unix)]
const STOP_SIGNALS: u64 = 1 << 0 | 1 << 1 | 1 << 14;

/// Each thread of a process: its id, name and blocked-signal mask (Linux; none elsewhere).
#[cfg(unix)]
fn threads_of(pid: u32) -> Vec<(u32, String, u64)> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .flatten()
        .filter_map(|task| {
            let tid = task.file_name().to_str()?.parse().ok()?;
            let name = std::fs::read_to_string(task.path().join("comm")).ok()?;
            let status = std::fs::read_to_string(task.path().join("status")).ok()?;
            let mask = status.lines().find_map(|l| l.strip_prefix("SigBlk:"))?;
            let mask = u64::from_str_radix(mask.trim(), 16).ok()?;
            Some((tid, name.trim().to_string(), mask))
        })
        .collect()
}

/// A stop signal during set-up (here as soon as the process takes the signals, long before
/// a 96 100-sphere packing is built) ends the process at once, by the signal, as it would
/// without powder's handling: nothing has run that a checkpoint would keep.
#[cfg(target_os = "linux")]
#[test]
fn a_stop_signal_during_set_up_ends_the_process_at_once() {
    use std::os::unix::process::ExitStatusExt;
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/packing.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = SignalledRun::start(&[
        "run",
        scene,
        "--set",
        "domain.max=[0.1455,0.1455,0.08]",
        "--set",
        "particles[0].max=[0.1449,0.1449,0.0585]",
        "--out",
        out.to_str().unwrap(),
    ]);
    let start = std::time::Instant::now();
    let taken = |run: &SignalledRun| {
        let threads = threads_of(run.child.id());
        let main = threads.iter().find(|(tid, ..)| *tid == run.child.id());
        main.is_some_and(|(_, _, m)| m & STOP_SIGNALS == STOP_SIGNALS)
    };
    while !taken(&run) {
        assert!(
            start.elapsed().as_secs() < 20,
            "the run never blocked the stop signals"
        );
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    run.signal(libc::SIGTERM);
    let (status, stderr) = run.finish();
    assert_eq!(status.signal(), Some(libc::SIGTERM), "{status:?}: {stderr}");
    assert!(!out.join("checkpoint.bin").exists(), "{stderr}");
}

/// A stopped `--no-output` run says that it wrote no checkpoint (it used to name one in
/// "(no output directory)").
#[cfg(unix)]
#[test]
fn a_stopped_run_without_outputs_says_it_wrote_no_checkpoint() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/jkr_deposition.toml");
    let mut run = SignalledRun::start(&["run", scene, "--no-output"]);
    run.wait_for("step ");
    run.signal(libc::SIGINT);
    let (status, stderr) = run.finish();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("no checkpoint (--no-output") && !stderr.contains("checkpoint.bin"),
        "{stderr}"
    );
}

/// Ctrl-C off the output cadence (here after the first chunk of 1000 steps, with rows
/// every 1500) writes a last row and snapshot after its checkpoint; the run resumed from
/// that checkpoint drops them and ends with the straight run's bytes, on both backends.
#[test]
fn a_run_interrupted_off_its_cadence_resumes_to_the_straight_runs_outputs() {
    let mut scene = cluster();
    scene.output_every = 1500;
    scene.checkpoint_every = 3000;
    type Run = fn(&Scene, &RunOptions) -> Option<RunSummary>;
    let backends: [(&str, Run); 2] = [
        ("cpu", |scene, opts| {
            Some(run_cpu_with(scene, opts, |_| {}).unwrap())
        }),
        ("gpu", |scene, opts| {
            Some(run_gpu_with(scene, gpu()?, opts, |_| {}).unwrap())
        }),
    ];
    for (backend, run) in backends {
        let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let Some(whole) = run(&scene, &options(straight.path(), 4000, None)) else {
            continue;
        };
        assert_eq!(whole.steps, 4000);
        let opts = RunOptions {
            interrupt: Some(std::sync::Arc::new(std::sync::atomic::AtomicBool::new(
                true,
            ))),
            ..options(split.path(), 4000, None)
        };
        let a = run(&scene, &opts).unwrap();
        assert!(
            a.interrupted && a.steps == 1000,
            "{backend}: {} steps",
            a.steps
        );
        // the interrupted run's last row and snapshot, at step 1000
        let rows = std::fs::read_to_string(split.path().join("series.csv")).unwrap();
        assert!(rows.lines().last().unwrap().starts_with("1000,"), "{rows}");
        let at_1000 = split
            .path()
            .join("snapshots/cohesive_cluster_0000001000.vtp");
        assert!(at_1000.exists());
        let ckpt = split.path().join("checkpoint.bin");
        let b = run(&scene, &options(split.path(), 4000, Some(&ckpt))).unwrap();
        assert_eq!((b.resumed_from, b.steps), (Some(1000), 4000));
        assert!(
            !at_1000.exists(),
            "{backend}: the interrupt's snapshot is left"
        );
        assert!(!split
            .path()
            .join("contacts/cohesive_cluster_0000001000.vtp")
            .exists());
        assert_same_outputs(straight.path(), split.path(), backend);
    }
    // resumed without snapshots, the interrupt's snapshot goes all the same
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        interrupt: Some(std::sync::Arc::new(std::sync::atomic::AtomicBool::new(
            true,
        ))),
        ..options(dir.path(), 4000, None)
    };
    run_cpu_with(&scene, &opts, |_| {}).unwrap();
    let at_1000 = dir.path().join("snapshots/cohesive_cluster_0000001000.vtp");
    assert!(at_1000.exists());
    let opts = RunOptions {
        no_snapshots: true,
        ..options(dir.path(), 2000, Some(&dir.path().join("checkpoint.bin")))
    };
    run_cpu_with(&scene, &opts, |_| {}).unwrap();
    assert!(!at_1000.exists());
    let pvd = std::fs::read_to_string(dir.path().join("cohesive_cluster.pvd")).unwrap();
    assert!(
        !pvd.contains("0000001000") && pvd.contains("0000000000"),
        "{pvd}"
    );
}

/// `powder run` of the cohesive cluster with rows every 100 steps and checkpoints every
/// `checkpoint_every` on `backend`, into `out`, for `steps` steps (from `resume`).
fn cluster_command(
    backend: &str,
    out: &Path,
    (steps, checkpoint_every): (u64, u64),
    resume: Option<&Path>,
) -> std::process::Command {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/cohesive_cluster.toml"
    );
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_powder"));
    cmd.args(["run", scene, "--backend", backend, "--steps"])
        .arg(steps.to_string())
        .args(["--set", "simulation.output_every=100", "--set"])
        .arg(format!("simulation.checkpoint_every={checkpoint_every}"))
        .arg("--out")
        .arg(out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    if let Some(r) = resume {
        cmd.arg("--resume").arg(r);
    }
    cmd
}

/// `series.csv`, `checkpoint.bin`, the collections and every particle and contact
/// snapshot of `run` are byte for byte those of `straight`.
fn assert_same_outputs(straight: &Path, run: &Path, what: &str) {
    assert_same_files(straight, run, what, &["snapshots", "contacts"]);
}

/// `series.csv`, `checkpoint.bin` and every file in `folders` (and their collections) of
/// `run` are byte for byte those of `straight`.
fn assert_same_files(straight: &Path, run: &Path, what: &str, folders: &[&str]) {
    let text = |d: &Path| std::fs::read_to_string(d.join("series.csv")).unwrap();
    assert_eq!(text(run), text(straight), "{what}: the series differs");
    let bytes = |d: &Path, f: &str| std::fs::read(d.join(f)).unwrap();
    let mut files = vec!["checkpoint.bin".to_string()];
    for folder in folders {
        files.push(match *folder {
            "snapshots" => "cohesive_cluster.pvd".into(),
            _ => format!("cohesive_cluster_{folder}.pvd"),
        });
        for e in std::fs::read_dir(straight.join(folder)).unwrap() {
            let name = e.unwrap().file_name().into_string().unwrap();
            files.push(format!("{folder}/{name}"));
        }
    }
    assert!(files.len() > 4 * folders.len(), "{files:?}");
    for f in &files {
        assert!(
            bytes(straight, f) == bytes(run, f),
            "{what}: {f} differs from the straight run's"
        );
    }
}

/// A child process killed (and waited for) when dropped, so a failing test leaves no run
/// behind.
struct Running(std::process::Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The whole lines of `text` (a line cut by a kill has no end).
fn whole_lines(text: &str) -> Vec<&str> {
    text.split_inclusive('\n')
        .filter_map(|l| l.strip_suffix('\n'))
        .collect()
}

/// A run killed with SIGKILL keeps every row it wrote (the same as a straight run's), and
/// resumed from its checkpoint it ends with the straight run's series and checkpoint, byte
/// for byte.
fn killed_run_keeps_its_rows_and_resumes_bitwise(backend: &str) {
    let straight = tempfile::tempdir().unwrap();
    let killed = tempfile::tempdir().unwrap();
    let steps = (10_000, 1000);
    let done = cluster_command(backend, straight.path(), steps, None)
        .status()
        .unwrap();
    assert!(done.success());
    let expected = std::fs::read_to_string(straight.path().join("series.csv")).unwrap();
    let mut child = Running(
        cluster_command(backend, killed.path(), (1_000_000, 1000), None)
            .spawn()
            .unwrap(),
    );
    let csv = killed.path().join("series.csv");
    // killed past step 2500 while the rows run ahead of the last checkpoint (rows every
    // 100 steps from step 0, checkpoints every 1000: the header and rows up to step 1000·k
    // are 2 + 10·k lines; a series written only with the checkpoints shows nothing else)
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(300);
    let ahead = |lines: usize| lines >= 27 && !(lines - 2).is_multiple_of(10);
    while !ahead(std::fs::read_to_string(&csv).map_or(0, |t| t.lines().count())) {
        assert!(
            std::time::Instant::now() < deadline,
            "no row past the last checkpoint after 300 s"
        );
        assert!(child.0.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(
        child.0.try_wait().unwrap().is_none(),
        "the run ended before the kill"
    );
    drop(child);
    let left = std::fs::read_to_string(&csv).unwrap();
    let rows = whole_lines(&left);
    assert!(rows.len() >= 27, "{left}");
    assert!(
        rows.len() <= 1 + 101,
        "killed after step 10 000, past the straight run"
    );
    assert_eq!(
        rows,
        whole_lines(&expected)[..rows.len()],
        "the killed run's rows are the straight run's"
    );
    let ckpt = killed.path().join("checkpoint.bin");
    let resumed = cluster_command(backend, killed.path(), steps, Some(&ckpt))
        .status()
        .unwrap();
    assert!(resumed.success());
    assert_same_outputs(straight.path(), killed.path(), "the killed and resumed run");
}

#[test]
fn killed_cpu_run_keeps_its_rows_and_resumes_bitwise() {
    killed_run_keeps_its_rows_and_resumes_bitwise("cpu");
}

#[test]
fn killed_gpu_run_keeps_its_rows_and_resumes_bitwise() {
    if gpu().is_some() {
        killed_run_keeps_its_rows_and_resumes_bitwise("gpu");
    }
}

/// `scene` run on `backend` ("cpu", or "gpu" where an adapter exists: else `None`).
fn run_on(
    backend: &str,
    scene: &Scene,
    opts: &RunOptions,
    progress: impl FnMut(&Snapshot),
) -> Option<Result<RunSummary, PowderError>> {
    match backend {
        "cpu" => Some(run_cpu_with(scene, opts, progress)),
        _ => gpu().map(|ctx| run_gpu_with(scene, ctx, opts, progress)),
    }
}

/// An output directory that breaks mid-run (its snapshots folder replaced by a file at step
/// 1500) stops the run with an error naming the file it could not write; the rows and the
/// checkpoint of step 1000 are intact, and resumed from it the run ends with the straight
/// run's checkpoint and series, byte for byte.
fn broken_output_directory_keeps_the_last_checkpoint(backend: &str) {
    let scene = cluster();
    let (straight, dir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let Some(done) = run_on(
        backend,
        &scene,
        &options(straight.path(), 3000, None),
        |_| {},
    ) else {
        return;
    };
    done.unwrap();
    let snaps = dir.path().join("snapshots");
    let sabotage = |s: &Snapshot| {
        if s.step == 1500 {
            std::fs::remove_dir_all(&snaps).unwrap();
            std::fs::write(&snaps, b"in the way").unwrap();
        }
    };
    // (the only copy of the state the start's: the chunk's start is stepped to again)
    let opts = RunOptions {
        copy_every: Some(u64::MAX),
        ..options(dir.path(), 3000, None)
    };
    let err = run_on(backend, &scene, &opts, sabotage)
        .unwrap()
        .unwrap_err()
        .to_string();
    assert!(err.contains("cohesive_cluster_0000001500.vtp"), "{err}");
    let csv = |d: &Path| std::fs::read_to_string(d.join("series.csv")).unwrap();
    let expected = csv(straight.path());
    let rows: Vec<&str> = expected.lines().take(1 + 4).collect();
    assert_eq!(
        csv(dir.path()).lines().collect::<Vec<_>>(),
        rows,
        "header + steps 0..=1500"
    );
    std::fs::remove_file(&snaps).unwrap();
    let ckpt = dir.path().join("checkpoint.bin");
    let opts = options(dir.path(), 3000, Some(&ckpt));
    let resumed = run_on(backend, &scene, &opts, |_| {}).unwrap().unwrap();
    assert_eq!(resumed.resumed_from, Some(1000));
    // (the sabotage took the particle snapshots before step 1500 with it)
    assert_same_files(
        straight.path(),
        dir.path(),
        "the run resumed after the break",
        &["contacts"],
    );
}

#[test]
fn broken_output_directory_keeps_the_last_cpu_checkpoint() {
    broken_output_directory_keeps_the_last_checkpoint("cpu");
}

#[test]
fn broken_output_directory_keeps_the_last_gpu_checkpoint() {
    broken_output_directory_keeps_the_last_checkpoint("gpu");
}

/// The number of lines of `path` (0 when it cannot be read).
fn lines_of(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| t.lines().count())
}

/// Killed again and again, each time within a few milliseconds of a new row — inside the
/// snapshot, collection or checkpoint writes that follow it (a checkpoint every 100 steps
/// here) — and resumed each time, a run ends with the straight run's series and checkpoint,
/// byte for byte; no checkpoint left behind is refused, and no temporary file is left.
fn killed_again_and_again_ends_as_a_straight_run(backend: &str) {
    let (straight, dir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let every = (3000, 100);
    let done = cluster_command(backend, straight.path(), every, None).status();
    assert!(done.unwrap().success());
    let (csv, ckpt) = (
        dir.path().join("series.csv"),
        dir.path().join("checkpoint.bin"),
    );
    let temps = |d: &Path| -> Vec<String> {
        ["", "snapshots"]
            .iter()
            .filter_map(|sub| std::fs::read_dir(d.join(sub)).ok())
            .flatten()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f.ends_with(".tmp"))
            .collect()
    };
    // one as a killed write of a process long gone leaves it
    std::fs::write(
        dir.path()
            .join(format!(".checkpoint.bin.{}.0.tmp", u32::MAX - 1)),
        b"x",
    )
    .unwrap();
    let (mut kills, mut interrupted_writes) = (0, 0);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(600);
    for round in 0..100 {
        let resume = ckpt.exists().then_some(ckpt.as_path());
        let target = lines_of(&csv) + 2 + round % 3;
        // (killed before its first checkpoint, a run is started afresh over its rows)
        let mut cmd = cluster_command(backend, dir.path(), every, resume);
        if resume.is_none() && round > 0 {
            cmd.arg("--overwrite");
        }
        let mut child = Running(cmd.spawn().unwrap());
        let ended = loop {
            assert!(std::time::Instant::now() < deadline, "round {round}: stuck");
            if let Some(status) = child.0.try_wait().unwrap() {
                break Some(status);
            }
            if lines_of(&csv) >= target {
                break None;
            }
            std::thread::sleep(std::time::Duration::from_micros(200));
        };
        if let Some(status) = ended {
            assert!(status.success(), "round {round}: the run (resumed) failed");
            break;
        }
        std::thread::sleep(std::time::Duration::from_micros(700 * (round as u64 % 5)));
        drop(child);
        kills += 1;
        interrupted_writes += temps(dir.path()).len();
    }
    eprintln!("{backend}: {kills} kills, {interrupted_writes} writes left unfinished");
    assert!(kills >= 5, "only {kills} kills");
    assert_same_outputs(straight.path(), dir.path(), &format!("{kills} kills"));
    let left = temps(dir.path());
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn killed_cpu_run_again_and_again_ends_as_a_straight_run() {
    killed_again_and_again_ends_as_a_straight_run("cpu");
}

#[test]
fn killed_gpu_run_again_and_again_ends_as_a_straight_run() {
    if gpu().is_some() {
        killed_again_and_again_ends_as_a_straight_run("gpu");
    }
}

/// A disk that fills mid-run (a 512 KiB tmpfs, mounted in a mount namespace of its own
/// with `unshare`) stops the run with the system's message and a non-zero exit, and leaves
/// its outputs and last good checkpoint intact: copied off the full disk and resumed, the
/// run ends with the straight run's outputs, byte for byte.
fn a_full_disk_stops_the_run_and_keeps_the_last_checkpoint(backend: &str) {
    let (straight, full, keep) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    let every = (3000, 500);
    let done = cluster_command(backend, straight.path(), every, None).status();
    assert!(done.unwrap().success());
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/cohesive_cluster.toml"
    );
    // the tmpfs lives as long as the shell: what the test reads is copied off it first
    let script = r#"
        mount -t tmpfs -o size=512k none "$FULL" || exit 97
        touch "$KEEP/mounted"
        "$POWDER" run "$SCENE" --backend "$BACKEND" --steps 100000 --set simulation.output_every=100 \
            --set simulation.checkpoint_every=500 --out "$FULL/out" 2> "$KEEP/stderr"
        echo $? > "$KEEP/status"
        cp -r "$FULL/out/." "$KEEP/"
    "#;
    // `mounted` appears once the tmpfs is there (unshare itself may be refused)
    let ran = ["-m", "-rm"].iter().find_map(|flags| {
        let status = std::process::Command::new("unshare")
            .args([flags, "sh", "-c", script])
            .env("FULL", full.path())
            .env("KEEP", keep.path())
            .env("POWDER", env!("CARGO_BIN_EXE_powder"))
            .env("SCENE", scene)
            .env("BACKEND", backend)
            .status()
            .ok()?;
        keep.path().join("mounted").exists().then_some(status)
    });
    let Some(status) = ran else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs `unshare -m` and tmpfs mounts for the full-disk test"
        );
        eprintln!("skipping the full-disk test: no private tmpfs mount here");
        return;
    };
    assert!(
        status.success(),
        "the outputs could not be copied off the full disk"
    );
    let read = |f: &str| std::fs::read_to_string(keep.path().join(f)).unwrap();
    assert_ne!(read("status").trim(), "0", "the run did not fail");
    let stderr = read("stderr");
    assert!(
        stderr.contains("No space left on device")
            && stderr.contains(full.path().to_str().unwrap())
            && stderr.contains("--resume"),
        "{stderr}"
    );
    let ckpt = keep.path().join("checkpoint.bin");
    let resumed = cluster_command(backend, keep.path(), every, Some(&ckpt))
        .status()
        .unwrap();
    assert!(resumed.success());
    assert_same_outputs(
        straight.path(),
        keep.path(),
        "the run resumed off the full disk",
    );
}

/// A Python that imports NumPy: `$PYTHON`, `python3` on PATH, then Debian's
/// `/usr/bin/python3` (where `.ci/run` installs python3-numpy; a pyenv `python3` first on PATH
/// may lack it). Under CI one must be found: there the test must run.
fn python_with_numpy() -> Option<std::ffi::OsString> {
    let candidates = std::env::var_os("PYTHON")
        .into_iter()
        .chain(["python3", "/usr/bin/python3"].map(std::ffi::OsString::from));
    let found = candidates.into_iter().find(|python| {
        std::process::Command::new(python)
            .args(["-c", "import numpy"])
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    });
    assert!(
        found.is_some() || std::env::var_os("CI").is_none(),
        "CI needs a python3 with NumPy (python3-numpy for /usr/bin/python3, or PYTHON=...) \
         for the checkpoint reader's test"
    );
    found
}

/// A checkpoint is a NumPy archive: `tools/read_checkpoint.py` reads the engine's state from
/// it to the bit (positions, the contacts' structured rows), and refuses another format by
/// name.
#[test]
fn a_checkpoint_reads_in_python_to_the_bit() {
    let Some(python3) = python_with_numpy() else {
        eprintln!("skipping: no python3 with NumPy here");
        return;
    };
    let scene = common::packing(common::rough, "rough");
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        max_steps: Some(2000),
        ..Default::default()
    };
    run_cpu_with(&scene, &opts, |_| {}).unwrap();
    let ckpt = dir.path().join("checkpoint.bin");
    let script = r#"
import json, sys
sys.path.insert(0, "tools")
import read_checkpoint
header, ck = read_checkpoint.load(sys.argv[1])
c = ck["contacts"]
print(json.dumps({
    "steps": header["steps"],
    "position": ck["position"][7].view("<u8").tolist(),
    "keys": [[int(r["i"]), int(r["j"])] for r in c],
    "normal_force": c["normal_force"].view("<u8").tolist(),
    "sliding": int(c["sliding"].sum()),
}))
"#;
    let python = |path: &Path| {
        std::process::Command::new(&python3)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["-c", script])
            .arg(path)
            .output()
            .unwrap()
    };
    let out = python(&ckpt);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut engine = powder::cpu::CpuEngine::new(&scene).unwrap();
    engine.run_steps(2000).unwrap();
    let net = engine.contact_network();
    let pairs: Vec<_> = net
        .lines
        .iter()
        .filter(|c| matches!(c.partner, powder::cpu::Partner::Particle(_)))
        .collect();
    assert_eq!(v["steps"], 2000);
    // (the bits, as integers: JSON's decimal floats need not round-trip)
    let f = |x: &serde_json::Value| f64::from_bits(x.as_u64().unwrap());
    let p: Vec<f64> = v["position"].as_array().unwrap().iter().map(f).collect();
    assert_eq!(p, engine.positions()[7].to_array());
    // the checkpoint keeps every listed contact; the engaged ones carry the same values
    let keys = v["keys"].as_array().unwrap();
    let forces = v["normal_force"].as_array().unwrap();
    assert!(pairs.len() > 20 && keys.len() >= pairs.len());
    for c in &pairs {
        let powder::cpu::Partner::Particle(j) = c.partner else {
            unreachable!()
        };
        let k = keys
            .iter()
            .position(|k| k[0] == c.i && k[1] == j)
            .unwrap_or_else(|| panic!("contact ({}, {j}) missing", c.i));
        assert_eq!(f(&forces[k]), c.normal_force);
    }
    // another format, named by the reader
    let other = dir.path().join("other.bin");
    std::fs::write(&other, as_next_format(&std::fs::read(&ckpt).unwrap())).unwrap();
    let out = python(&other);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains(&format!("format {NEXT_FORMAT}")),
        "{err}"
    );
}

#[test]
fn a_full_disk_stops_the_cpu_run_and_keeps_the_last_checkpoint() {
    a_full_disk_stops_the_run_and_keeps_the_last_checkpoint("cpu");
}

#[test]
fn a_full_disk_stops_the_gpu_run_and_keeps_the_last_checkpoint() {
    if gpu().is_some() {
        a_full_disk_stops_the_run_and_keeps_the_last_checkpoint("gpu");
    }
}

/// A GPU checkpoint cut short or with a flipped bit is refused as damaged (the same reader
/// as the CPU's: `foreign_or_broken_checkpoints_are_refused`).
#[test]
fn damaged_gpu_checkpoints_are_refused() {
    let scene = cluster();
    let dir = tempfile::tempdir().unwrap();
    let Some(ctx) = gpu() else { return };
    run_gpu_with(&scene, ctx, &options(dir.path(), 200, None), |_| {}).unwrap();
    let bytes = std::fs::read(dir.path().join("checkpoint.bin")).unwrap();
    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 0x10;
    for (what, file) in [
        ("cut", &bytes[..bytes.len() / 2]),
        ("flipped", &flipped[..]),
    ] {
        let broken = dir.path().join("broken.bin");
        std::fs::write(&broken, file).unwrap();
        let Some(ctx) = gpu() else { return };
        let opts = RunOptions {
            resume: Some(broken),
            ..Default::default()
        };
        let err = run_gpu_with(&scene, ctx, &opts, |_| {})
            .unwrap_err()
            .to_string();
        assert!(err.contains("damaged or truncated"), "{what}: {err}");
    }
    // a wall point edited to NaN, the archive otherwise whole (its CRCs made anew): the
    // CPU refused it, the GPU resumed and carried the NaN on
    let archive = npz::Archive::read(&bytes).unwrap();
    let members: Vec<(String, npz::Member)> = archive
        .names()
        .map(|name| {
            let mut raw = archive.raw(name).unwrap().to_vec();
            if name == "wall_point.npy" || name == "wall_point" {
                let at = raw.len() - 8;
                raw[at..].copy_from_slice(&f64::NAN.to_le_bytes());
            }
            (name.to_string(), npz::Member::Raw(raw))
        })
        .collect();
    assert!(members.iter().any(|(n, _)| n.starts_with("wall_point")));
    let edited = dir.path().join("edited.bin");
    std::fs::write(&edited, npz::write(&members)).unwrap();
    let Some(ctx) = gpu() else { return };
    let opts = RunOptions {
        resume: Some(edited.clone()),
        ..Default::default()
    };
    let err = run_gpu_with(&scene, ctx, &opts, |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("wall point") && err.contains("not finite"),
        "{err}"
    );
    // a velocity edited to NaN (the first particle's in the `motion` buffer): refused,
    // naming the field, where the GPU resumed and the monitor stopped the run later
    let members: Vec<(String, npz::Member)> = archive
        .names()
        .map(|name| {
            let mut raw = archive.raw(name).unwrap().to_vec();
            if name.starts_with("buffer.motion") {
                // (after the .npy header, which ends its 10-byte preamble's dict with \n)
                let data = raw[10..].iter().position(|&b| b == b'\n').unwrap() + 11;
                raw[data..data + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            }
            (name.to_string(), npz::Member::Raw(raw))
        })
        .collect();
    std::fs::write(&edited, npz::write(&members)).unwrap();
    let Some(ctx) = gpu() else { return };
    let opts = RunOptions {
        resume: Some(edited),
        ..Default::default()
    };
    let err = run_gpu_with(&scene, ctx, &opts, |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`vel` (velocity (xyz), mass (w)) of particle") && err.contains("not finite"),
        "{err}"
    );
}

/// A run into a folder another live run holds is refused, and so is one that could not
/// write one of its outputs (a folder where its `.pvd` goes): in both cases before the
/// earlier run's outputs are touched. The lock goes with the run.
#[test]
fn a_held_or_unwritable_folder_is_refused_before_anything_changes() {
    let scene = cluster();
    let dir = tempfile::tempdir().unwrap();
    run(&scene, dir.path(), 1000, None);
    assert!(!dir.path().join(powder::output::folder::LOCK).exists());
    let listing = || {
        let mut names: Vec<(String, u64)> = walk(dir.path())
            .into_iter()
            .map(|p| {
                let len = if p.is_dir() {
                    0
                } else {
                    std::fs::metadata(&p).unwrap().len()
                };
                (p.display().to_string(), len)
            })
            .collect();
        names.sort();
        names
    };
    let before = listing();
    // (pid 1 lives as long as the machine)
    let lock = dir.path().join(powder::output::folder::LOCK);
    std::fs::write(&lock, "1").unwrap();
    let err = run_cpu_with(&scene, &options(dir.path(), 2000, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("is held by process 1 "), "{err}");
    std::fs::remove_file(&lock).unwrap();
    assert_eq!(listing(), before);
    let pvd = dir.path().join(format!("{}.pvd", scene.name));
    std::fs::remove_file(&pvd).unwrap();
    std::fs::create_dir(&pvd).unwrap();
    let before = listing();
    let err = run_cpu_with(&scene, &options(dir.path(), 2000, None), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("is a folder where the run writes a file"),
        "{err}"
    );
    assert_eq!(listing(), before);
}

/// Every file under `dir`, recursively.
fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.push(p.clone());
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// A branch under another scene name resumed from a killed run's checkpoint removes that
/// run's snapshots beyond the checkpoint, as a branch under the same name does: they stayed,
/// and the steps after the checkpoint appeared in both scenes' collections.
#[test]
fn a_renamed_branch_removes_the_killed_runs_later_snapshots() {
    let scene = cluster();
    let (killed, at_checkpoint) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    // a run killed after writing rows and snapshots to 1500, its checkpoint at 1000
    run(&scene, killed.path(), 1500, None);
    run(&scene, at_checkpoint.path(), 1000, None);
    let ckpt = killed.path().join("checkpoint.bin");
    std::fs::copy(at_checkpoint.path().join("checkpoint.bin"), &ckpt).unwrap();
    std::fs::remove_file(killed.path().join("summary.json")).unwrap();
    let mut renamed = scene.clone();
    renamed.name = "renamed".into();
    run(&renamed, killed.path(), 2000, Some(&ckpt));
    let (_, _, shots) = run_files(killed.path());
    let name = &scene.name;
    let old: Vec<&String> = shots
        .iter()
        .filter(|f| f.starts_with(name.as_str()))
        .collect();
    assert!(
        old.iter().all(|f| !f.contains("1500")) && old.iter().any(|f| f.contains("1000")),
        "{old:?}"
    );
    let pvd = std::fs::read_to_string(killed.path().join(format!("{name}.pvd"))).unwrap();
    assert!(!pvd.contains("1500") && pvd.contains("1000"), "{pvd}");
    assert!(shots
        .iter()
        .any(|f| f.starts_with("renamed") && f.contains("2000")));
}

/// A run started with SIGHUP ignored (`nohup`) keeps it ignored: a closed terminal does not
/// stop it, SIGTERM still does.
#[cfg(unix)]
#[test]
fn a_run_under_nohup_ignores_sighup() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/jkr_deposition.toml");
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_powder"));
    command
        .args(["run", scene, "--out", dir.path().to_str().unwrap()])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped());
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGHUP, libc::SIG_IGN);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    let kill = |signal: &str, pid: u32| {
        let ok = std::process::Command::new("kill")
            .args([format!("-{signal}"), pid.to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
    };
    std::thread::sleep(std::time::Duration::from_millis(1000));
    kill("HUP", child.id());
    std::thread::sleep(std::time::Duration::from_millis(500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "SIGHUP stopped a nohup run"
    );
    kill("TERM", child.id());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(143));
}
