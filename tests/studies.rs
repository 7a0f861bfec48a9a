//! The papers' example studies run to the end on the CPU, and the fast ones reproduce the
//! CSVs their pages quote (a change of `collide`'s verdicts had stopped two of them
//! unnoticed). Needs `python3` (the standard library only).

use std::path::Path;
use std::process::Command;

/// Runs `examples/studies/<script>` with `args` into a fresh folder; returns the folder.
fn study(script: &str, args: &[&str]) -> tempfile::TempDir {
    let out = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let run = Command::new("python3")
        .arg(Path::new(root).join("examples/studies").join(script))
        .args(["--powder", env!("CARGO_BIN_EXE_powder"), "--out"])
        .arg(out.path())
        .args(args)
        .output()
        .expect("python3 runs (the studies need it)");
    assert!(
        run.status.success(),
        "{script}: {}\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

/// The study's CSV is the one in `docs/`, byte for byte.
fn same_as_docs(out: &tempfile::TempDir, csv: &str) {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs").join(csv);
    let made = std::fs::read_to_string(out.path().join(csv)).unwrap();
    assert!(
        made == std::fs::read_to_string(&docs).unwrap(),
        "{csv} differs from docs/{csv}: rerun the study and update its page"
    );
}

#[test]
fn paper001_restitution_reproduces_its_page() {
    same_as_docs(
        &study("paper001_restitution.py", &[]),
        "paper001_restitution.csv",
    );
}

#[test]
fn paper002_binary_reproduces_its_page() {
    same_as_docs(&study("paper002_binary.py", &[]), "paper002_binary.csv");
}

#[test]
fn paper002_collision_time_runs() {
    let out = study("paper002_collision_time.py", &[]);
    assert!(out.path().join("paper002_collision_time.svg").exists());
}

/// The quick deposition (its full run takes minutes): every part runs, and the map has all
/// three outcomes.
#[test]
fn paper002_deposition_quick_runs() {
    let out = study("paper002_deposition.py", &["--quick"]);
    let csv = std::fs::read_to_string(out.path().join("paper002_deposition.csv")).unwrap();
    for outcome in ["rebound", "resting", "rolling"] {
        assert!(csv.contains(outcome), "{outcome} missing:\n{csv}");
    }
}
