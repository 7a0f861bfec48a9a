//! `powder run --no-ledger` through the run API: a GPU run without the energy ledger writes
//! the same CSV header with the ledger's cells empty, leaves the ledger's keys out of the
//! JSON, moves exactly as a run with the ledger, and its checkpoints resume bitwise only in
//! a run without the ledger (and the reverse), refused with a message naming the flag.

mod common;
use common::gpu;

use powder::gpu::GpuOptions;
use powder::run::{csv_header, run_gpu_with, RunOptions, RunSummary};
use powder::scene::Scene;
use std::path::Path;

fn cluster() -> Scene {
    common::cluster_with_outputs()
}

fn options(out: &Path, steps: u64, resume: Option<&Path>, ledger: bool) -> RunOptions {
    RunOptions {
        out_dir: Some(out.to_path_buf()),
        resume: resume.map(Path::to_path_buf),
        max_steps: Some(steps),
        gpu: GpuOptions {
            ledger,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Runs on a fresh GPU context; `None` without an adapter (outside CI).
fn run(
    scene: &Scene,
    out: &Path,
    steps: u64,
    resume: Option<&Path>,
    ledger: bool,
) -> Option<Result<RunSummary, powder::PowderError>> {
    let ctx = gpu()?;
    Some(run_gpu_with(
        scene,
        ctx,
        &options(out, steps, resume, ledger),
        |_| {},
    ))
}

fn csv(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("series.csv")).unwrap()
}

/// The named columns of every data row.
fn columns<'a>(text: &'a str, names: &[&str]) -> Vec<Vec<&'a str>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == n).unwrap())
        .collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            at.iter().map(|&i| cells[i]).collect()
        })
        .collect()
}

#[test]
fn gpu_run_without_the_ledger_leaves_its_quantities_out_and_resumes_bitwise() {
    let scene = cluster();
    let (without, with, split) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    // past the first contacts (from about step 4500), so the ledger would have counted some
    let Some(a) = run(&scene, without.path(), 6500, None, false) else {
        return;
    };
    let a = a.unwrap();
    assert!(!a.ledger && a.backend == "gpu");
    assert_eq!(a.energy_balance_error, None);
    assert_eq!(a.wall_forces, None);
    assert!(a.last.contacts.is_none() && a.initial.contacts.is_none());
    assert_eq!(a.last.energies.total(), None);
    assert!(a.last.energies.kinetic > 0.0);
    assert!(
        a.notes.iter().any(|n| n.contains("--no-ledger")),
        "{:?}",
        a.notes
    );

    // the CSV keeps its header; only what the ledger knows is empty
    let text = csv(without.path());
    assert_eq!(text.lines().next().unwrap(), csv_header(&scene.walls));
    assert_eq!(text.lines().count(), 1 + 14);
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let known = ["step", "time", "kinetic", "gravitational", "inserted"];
    let unknown: Vec<&str> = header
        .iter()
        .copied()
        .filter(|h| !known.contains(h))
        .collect();
    assert!(unknown.contains(&"elastic") && unknown.contains(&"wall0_fz"));
    for row in columns(&text, &unknown) {
        assert!(row.iter().all(|c| c.is_empty()), "{row:?}");
    }
    for row in columns(&text, &known) {
        for c in row {
            assert!(c.parse::<f64>().is_ok_and(f64::is_finite), "`{c}`");
        }
    }

    // the JSON leaves the ledger's keys out (absent, not null or 0)
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(without.path().join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["ledger"], false);
    for key in ["energy_balance_error", "wall_forces"] {
        assert!(json.get(key).is_none(), "{key} in {json}");
    }
    for at in ["initial", "last"] {
        assert!(json[at].get("contacts").is_none(), "{json}");
        let e = &json[at]["energies"];
        for key in ["elastic", "dissipated", "wall_work"] {
            assert!(e.get(key).is_none(), "{key} in {e}");
        }
        for key in ["kinetic", "gravitational", "inserted"] {
            assert!(e[key].is_f64(), "{key} in {e}");
        }
    }

    // with the ledger: the same header, and the same trajectory, so the same kinetic and
    // gravitational energy to the bit
    let b = run(&scene, with.path(), 6500, None, true).unwrap().unwrap();
    assert!(b.ledger && b.last.contacts.is_some_and(|c| c.contacts > 0));
    let ledger_text = csv(with.path());
    assert_eq!(
        ledger_text.lines().next(),
        text.lines().next(),
        "the header does not depend on the ledger"
    );
    let state = ["step", "kinetic", "gravitational"];
    assert_eq!(columns(&text, &state), columns(&ledger_text, &state));

    // a checkpoint without the ledger resumes bitwise in a run without it
    run(&scene, split.path(), 5500, None, false)
        .unwrap()
        .unwrap();
    let ckpt = split.path().join("checkpoint.bin");
    let kept = std::fs::read(&ckpt).unwrap();
    let c = run(&scene, split.path(), 6500, Some(&ckpt), false)
        .unwrap()
        .unwrap();
    assert_eq!(c.resumed_from, Some(5500));
    let bytes = |d: &Path| std::fs::read(d.join("checkpoint.bin")).unwrap();
    assert!(
        bytes(without.path()) == bytes(split.path()),
        "resumed run without the ledger differs"
    );
    assert_eq!(csv(without.path()), csv(split.path()));

    // ... and is refused by a run with the ledger, and the reverse, naming the flag
    let at_5500 = split.path().join("at_5500.bin");
    std::fs::write(&at_5500, kept).unwrap();
    let refused = tempfile::tempdir().unwrap();
    let err = run(&scene, refused.path(), 6500, Some(&at_5500), true)
        .unwrap()
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("resume it with --no-ledger") && err.contains("at_5500.bin"),
        "{err}"
    );
    let ledger_ckpt = with.path().join("checkpoint.bin");
    let err = run(&scene, refused.path(), 7000, Some(&ledger_ckpt), false)
        .unwrap()
        .unwrap_err()
        .to_string();
    assert!(err.contains("resume it without --no-ledger"), "{err}");
}

/// Ctrl-C (the interrupt flag) stops a run without the ledger after its chunk with the
/// outputs and a last checkpoint, from which a run without the ledger continues.
#[test]
fn interrupted_gpu_run_without_the_ledger_writes_a_checkpoint_and_resumes() {
    let scene = cluster();
    let dir = tempfile::tempdir().unwrap();
    let Some(ctx) = gpu() else { return };
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let opts = RunOptions {
        interrupt: Some(flag),
        ..options(dir.path(), 3000, None, false)
    };
    let a = run_gpu_with(&scene, ctx, &opts, |_| {}).unwrap();
    assert!(a.interrupted && a.steps == 500, "{} steps", a.steps);
    let text = csv(dir.path());
    assert!(text.lines().last().unwrap().starts_with("500,"), "{text}");
    assert!(dir.path().join("summary.json").exists());
    let ckpt = dir.path().join("checkpoint.bin");
    let b = run(&scene, dir.path(), 1000, Some(&ckpt), false)
        .unwrap()
        .unwrap();
    assert_eq!((b.resumed_from, b.steps), (Some(500), 1000));
    assert!(!b.interrupted && !b.ledger);
}
