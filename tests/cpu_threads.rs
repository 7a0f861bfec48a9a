//! The CPU engine spread over threads: the same bits on any thread count.

use powder::cpu::threads::CHUNK;
use powder::cpu::{CpuEngine, Threads};
use powder::measure::bench::{packing, Case};
use powder::scene::Scene;
use std::process::Command;

/// Runs the `powder` binary, which must succeed; returns its (stdout, stderr).
fn powder_ok<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_powder"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    (String::from_utf8_lossy(&out.stdout).into_owned(), stderr)
}

/// Runs `scene` for `steps` on `threads` threads; returns the checkpoint state's bytes.
fn state_after(scene: &Scene, threads: usize, steps: u64) -> Vec<u8> {
    let mut e = CpuEngine::with_threads(scene, Threads::new(threads).unwrap()).unwrap();
    assert_eq!(e.threads(), threads);
    e.run_steps(steps).unwrap();
    let energies = e.energies();
    let mut bytes = powder::checkpoint::npz::write(&powder::checkpoint::cpu::arrays(&e.state()));
    bytes.extend(serde_json::to_vec(&energies).unwrap());
    bytes
}

fn same_on_1_2_and_3_threads(scene: &Scene, steps: u64) {
    // several chunks, or the test would prove nothing
    assert!(scene.particles.len() > 3 * CHUNK);
    let one = state_after(scene, 1, steps);
    for t in [2, 3] {
        assert!(
            one == state_after(scene, t, steps),
            "{t} threads differ from 1"
        );
    }
}

#[test]
fn jkr_packing_with_rotation_and_walls_is_bitwise_the_same_on_any_thread_count() {
    // fast random velocities: contacts form and break, the lists are rebuilt
    let scene = packing(Case::Jkr, 2500, 20.0, 3).unwrap();
    same_on_1_2_and_3_threads(&scene, 120);
}

/// The thread count changed between steps (`CpuEngine::set_threads`) changes no bit.
#[test]
fn threads_changed_mid_run_change_no_bit() {
    let scene = packing(Case::Hysteretic, 2500, 20.0, 4).unwrap();
    let mut e = CpuEngine::with_threads(&scene, Threads::new(1).unwrap()).unwrap();
    e.run_steps(100).unwrap();
    e.set_threads(Threads::new(3).unwrap());
    assert_eq!(e.threads(), 3);
    e.run_steps(100).unwrap();
    let mut bytes = powder::checkpoint::npz::write(&powder::checkpoint::cpu::arrays(&e.state()));
    bytes.extend(serde_json::to_vec(&e.energies()).unwrap());
    assert!(bytes == state_after(&scene, 1, 200));
}

#[test]
fn hysteretic_packing_is_bitwise_the_same_on_any_thread_count() {
    let scene = packing(Case::Hysteretic, 2500, 20.0, 4).unwrap();
    same_on_1_2_and_3_threads(&scene, 200);
}

#[test]
fn run_checkpoints_are_the_same_with_1_and_2_threads() {
    let dir = tempfile::tempdir().unwrap();
    let cluster = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/cohesive_cluster.toml"
    );
    let run = |threads: &str| {
        let out = dir.path().join(format!("t{threads}"));
        let out_dir = out.to_str().unwrap();
        powder_ok(&[
            "run",
            cluster,
            "--backend",
            "cpu",
            "--threads",
            threads,
            "--steps",
            "6000",
            // 1600 smaller spheres (several chunks) under stronger gravity: a heap
            // with ~2200 contacts by the end
            "--set",
            "particles[0].count=1600",
            "--set",
            "particles[0].radius=5e-4",
            "--set",
            "particles[0].max=[0.019,0.019,0.02]",
            "--set",
            "simulation.gravity=[0.0,0.0,-200.0]",
            "--set",
            "simulation.output_every=2000",
            "--out",
            out_dir,
        ]);
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["threads"], threads.parse::<u64>().unwrap());
        assert!(summary["last"]["contacts"]["contacts"].as_u64().unwrap() > 1000);
        (
            std::fs::read(out.join("checkpoint.bin")).unwrap(),
            std::fs::read(out.join("series.csv")).unwrap(),
        )
    };
    let one = run("1");
    let two = run("2");
    assert!(one.0 == two.0, "the checkpoints of 1 and 2 threads differ");
    assert!(one.1 == two.1, "the series of 1 and 2 threads differ");
}

#[test]
fn auto_backend_says_what_it_chose_and_why() {
    let (stdout, stderr) = powder_ok(&["run", "--steps", "20", "--no-output", "--json"]);
    let summary: serde_json::Value =
        serde_json::from_str(&stdout[stdout.find('{').unwrap()..]).unwrap();
    let reason = summary["backend_reason"].as_str().unwrap();
    assert!(stderr.contains(&format!("backend: {reason}")), "{stderr}");
    match summary["backend"].as_str().unwrap() {
        // no hardware GPU (CI): the CPU engine on every core
        "cpu" => {
            assert!(reason.contains("no hardware GPU"), "{reason}");
            assert!(summary["threads"].as_u64().unwrap() >= 1);
        }
        // a hardware GPU, or the adapter POWDER_ADAPTER names
        _ => assert!(
            reason.contains("hardware GPU") || reason.contains("POWDER_ADAPTER"),
            "{reason}"
        ),
    }
}

/// An adapter named in `POWDER_ADAPTER` that does not open is an error with `--backend
/// gpu` as with `auto` (`gpu` fell back to the CPU engine, `auto` refused).
#[test]
fn an_unmatched_adapter_name_is_refused_by_every_backend_request() {
    for backend in ["gpu", "auto"] {
        let out = Command::new(env!("CARGO_BIN_EXE_powder"))
            .args(["run", "--backend", backend, "--steps", "1", "--no-output"])
            .env("POWDER_ADAPTER", "nosuchadapter")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--backend {backend}: {err}");
        assert!(
            err.contains("no GPU adapter matches POWDER_ADAPTER=nosuchadapter"),
            "--backend {backend}: {err}"
        );
    }
}

#[test]
fn bad_thread_counts_are_refused_with_the_option_named() {
    for (cmd, value) in [("run", "x"), ("bench", "1,x"), ("run", "5000")] {
        let out = Command::new(env!("CARGO_BIN_EXE_powder"))
            .args([cmd, "--threads", value, "--backend", "cpu", "--steps", "1"])
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("threads"), "{cmd} --threads {value}: {err}");
    }
}

/// The trajectory does not depend on where chunks and wall pieces end (only the energy
/// ledger's last bits do): chunks of 7 particles put a chunk boundary between most pairs
/// and cut each wall's ~200 candidates into ~30 pieces, with contacts forming and leaving.
#[test]
fn chunk_and_piece_boundaries_change_no_trajectory_bit() {
    for (case, seed) in [(Case::Hysteretic, 5), (Case::Jkr, 6)] {
        let scene = packing(case, 2500, 20.0, seed).unwrap();
        let run = |chunk: usize| {
            let threads = Threads::new(2).unwrap().with_chunk(chunk);
            let mut e = CpuEngine::with_threads(&scene, threads).unwrap();
            e.run_steps(150).unwrap();
            e
        };
        let (a, b) = (run(512), run(7));
        // (JSON writes each finite f64 as its shortest round-trip decimal: equal text, equal
        // bits; a non-finite value would show as null, and fail the run first)
        let bits = |e: &CpuEngine| {
            serde_json::to_vec(&(
                e.positions(),
                e.velocities(),
                e.angular_velocities(),
                e.forces(),
                e.contacts(),
                e.wall_forces(),
            ))
            .unwrap()
        };
        assert!(bits(&a) == bits(&b), "{case:?}: the trajectory moved");
        let (da, db) = (a.energies().dissipated, b.energies().dissipated);
        assert!(
            da > 0.0 && (da - db).abs() <= 1e-9 * da,
            "{case:?}: {da} vs {db}"
        );
    }
}

#[test]
fn auto_resumes_on_the_backend_that_wrote_the_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let powder = |args: &[&str]| powder_ok(&[args, &["--out", out]].concat()).1;
    powder(&["run", "--backend", "cpu", "--steps", "200"]);
    let checkpoint = dir.path().join("checkpoint.bin");
    // with a GPU (or POWDER_ADAPTER set) auto alone would pick the GPU and refuse it
    let err = powder(&[
        "run",
        "--steps",
        "400",
        "--resume",
        checkpoint.to_str().unwrap(),
    ]);
    assert!(
        err.contains("resumes on the checkpoint's backend (--backend cpu)"),
        "{err}"
    );
}
