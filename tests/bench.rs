//! `powder bench` and `powder accuracy`: smoke tests of the documented JSON (tiny sizes, few
//! steps). Timings are measured, never asserted; only that they are positive.

use std::process::Command;

fn powder(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_powder"))
        .args(args)
        .env("NODEVICE_SELECT", "1")
        .output()
        .expect("the binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Whether a GPU adapter exists; outside CI the GPU parts are skipped without one.
fn gpu_available() -> bool {
    let ok = powder(&["info"]).0;
    if !ok && std::env::var_os("CI").is_some() {
        panic!("CI needs a GPU adapter (lavapipe)");
    }
    ok
}

fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn bench_json_reports_both_backends_and_cases() {
    let gpu = gpu_available();
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let backend = if gpu { "both" } else { "cpu" };
    let (ok, out, err) = powder(&[
        "bench",
        "--sizes",
        "27,64",
        "--steps",
        "8",
        "--warmup",
        "2",
        "--backend",
        backend,
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("p-steps/s"), "{out}");
    let v = read_json(&json);
    for key in [
        "powder_version",
        "date",
        "machine",
        "adapter",
        "rows",
        "steps",
        "ledger",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}`");
    }
    // the command that measured, its options with it
    let command: Vec<&str> = v["command"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    assert!(
        command.contains(&"bench") && command.contains(&"--json"),
        "{command:?}"
    );
    assert!(v["machine"]["available_parallelism"].as_u64().unwrap() >= 1);
    let rows = v["rows"].as_array().unwrap();
    let backends: &[&str] = if gpu { &["cpu", "gpu"] } else { &["cpu"] };
    assert_eq!(rows.len(), 2 * 2 * backends.len());
    for case in ["hysteretic", "jkr"] {
        for &b in backends {
            for n in [27, 64] {
                let r = rows
                    .iter()
                    .find(|r| r["case"] == case && r["backend"] == b && r["particles"] == n)
                    .unwrap_or_else(|| panic!("no row {case} {b} {n}"));
                assert_eq!(r["status"], "ran", "{r}");
                assert_eq!(r["steps"], 8);
                assert!(r["particle_steps_per_second"].as_f64().unwrap() > 0.0);
                assert!(r["seconds_per_step"].as_f64().unwrap() > 0.0);
                // a packing in contact: 3 x 3 x 3 sites have 54 bonds
                if n == 27 {
                    assert!(r["contacts_per_particle"].as_f64().unwrap() > 2.0, "{r}");
                }
                let bytes = r["gpu_bytes_per_particle"].as_f64();
                if b == "gpu" {
                    assert!(bytes.unwrap() > 100.0, "{r}");
                    assert!(r["rebuilds"].as_u64().is_some());
                } else {
                    assert!(bytes.is_none());
                }
            }
        }
    }
    if gpu {
        assert!(v["adapter"]["name"].as_str().is_some());
        // the same packing needs more device memory per particle with friction and rolling
        let bpp = |case: &str| {
            rows.iter()
                .find(|r| r["case"] == case && r["backend"] == "gpu" && r["particles"] == 64)
                .unwrap()["gpu_bytes_per_particle"]
                .as_f64()
                .unwrap()
        };
        assert!(bpp("jkr") > bpp("hysteretic"));
    }
}

#[test]
fn bench_skips_sizes_beyond_the_time_budget_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let (ok, _, err) = powder(&[
        "bench",
        "--sizes",
        "8,1e7,1e8",
        "--steps",
        "4",
        "--warmup",
        "0",
        "--backend",
        "cpu",
        "--case",
        "hysteretic",
        "--max-seconds",
        "0.5",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let rows = read_json(&json)["rows"].as_array().unwrap().clone();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[0]["status"], "ran");
    for r in &rows[1..] {
        assert_eq!(r["status"], "skipped", "{r}");
        assert!(r["particle_steps_per_second"].is_null());
    }
    let note = rows[1]["note"].as_str().unwrap();
    assert!(
        note.contains("--max-seconds") || note.contains("memory"),
        "{note}"
    );
    assert!(rows[2]["note"].as_str().unwrap().contains("not run"));
}

#[test]
fn accuracy_json_plot_and_convergence() {
    let gpu = gpu_available();
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("acc.json");
    let svg = dir.path().join("acc.svg");
    let (ok, out, err) = powder(&[
        "accuracy",
        "--divisors",
        "10,20",
        "--reference-divisor",
        "80",
        "--packing-time",
        "4",
        "--particles",
        "27",
        "--chi-points",
        "3",
        "--backend",
        if gpu { "both" } else { "cpu" },
        "--json",
        json.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("error"), "{out}");
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    let v = read_json(&json);
    for key in [
        "powder_version",
        "machine",
        "pair",
        "jkr",
        "packing",
        "points",
        "command",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}`");
    }
    let points = v["points"].as_array().unwrap();
    // pair and packing on each backend; jkr: two rules, placed and (CPU) Verlet
    let backends = if gpu { 2 } else { 1 };
    assert_eq!(points.len(), 2 * (2 * backends + 2 * (backends + 1)));
    let get = |case: &str, b: &str, d: f64| {
        points
            .iter()
            .find(|p| p["case"] == case && p["backend"] == b && p["divisor"] == d)
            .unwrap_or_else(|| panic!("no point {case} {b} {d}"))
    };
    for p in points {
        assert!(p["wall_seconds"].as_f64().unwrap() > 0.0);
        assert!(p["error"].as_f64().unwrap().is_finite());
    }
    // the CPU converges: halving dt shrinks both errors (second order for the pair: the
    // measured ratio is about 6; the packing about 4)
    for case in ["pair", "packing"] {
        let coarse = get(case, "cpu", 10.0)["error"].as_f64().unwrap();
        let fine = get(case, "cpu", 20.0)["error"].as_f64().unwrap();
        assert!(fine < 0.5 * coarse, "{case}: {coarse} -> {fine}");
    }
    assert!(get("packing", "cpu", 10.0)["kinetic_error"]
        .as_f64()
        .is_some());
    // JKR: the placed jumps converge at second order (measured: 8.8x for the force rule),
    // and beat velocity Verlet with the jumps left to it (measured: errors 0.23x and 0.08x
    // of Verlet's at tc/10 and tc/20 for the displacement rule, 0.014x and 0.006x for the
    // force rule)
    let error = |case: &str, d: f64| get(case, "cpu", d)["error"].as_f64().unwrap();
    assert!(error("jkr-force", 20.0) < 0.25 * error("jkr-force", 10.0));
    for rule in ["jkr-force", "jkr-displacement"] {
        let verlet = format!("{rule}-verlet");
        for d in [10.0, 20.0] {
            assert!(error(rule, d) < 0.4 * error(&verlet, d), "{rule} tc/{d}");
        }
    }
}

#[test]
fn bad_bench_and_accuracy_input_is_an_error_not_a_panic() {
    let cases: [(&[&str], &str); 11] = [
        (&["bench", "--sizes", "0"], "sizes"),
        (
            &["bench", "--sizes", "10", "--window-particles", "3"],
            "window-particles",
        ),
        // every size failing (here too fast to resolve) is a failed command
        (
            &[
                "bench",
                "--sizes",
                "1e3",
                "--steps",
                "5",
                "--backend",
                "cpu",
                "--velocity-scale",
                "1e6",
            ],
            "no size ran",
        ),
        // every size skipped (here beyond the host memory) too
        (
            &[
                "bench",
                "--sizes",
                "1e8",
                "--steps",
                "4",
                "--backend",
                "cpu",
                "--case",
                "hysteretic",
            ],
            "no size ran: every row was skipped or failed",
        ),
        (&["bench", "--sizes", "1e3,abc"], "sizes"),
        (&["bench", "--steps", "0", "--sizes", "10"], "steps"),
        (
            &["bench", "--max-seconds", "-1", "--sizes", "10"],
            "max-seconds",
        ),
        (&["accuracy", "--divisors", "5,10"], "divisors"),
        (&["accuracy", "--divisors", "1e300"], "divisors"),
        (
            &[
                "accuracy",
                "--case",
                "packing",
                "--divisors",
                "10",
                "--reference-divisor",
                "1e300",
            ],
            "reference-divisor",
        ),
        (
            &[
                "accuracy",
                "--divisors",
                "10,1000",
                "--reference-divisor",
                "800",
            ],
            "reference-divisor",
        ),
    ];
    // (1e8 particles need about 215 GiB on the CPU: skipped on any machine with less)
    let roomy = std::fs::read_to_string("/proc/meminfo").map_or(true, |m| {
        m.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
            .is_none_or(|kb| kb > 150.0 * 1024.0 * 1024.0)
    });
    for (args, needle) in cases {
        if roomy && args.contains(&"1e8") {
            continue;
        }
        let (ok, _, err) = powder(args);
        assert!(!ok, "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: `{err}` lacks `{needle}`");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A bench in which no size ran is a failed command: it leaves an existing `--json` file as
/// it was (it used to replace it with the failed rows).
#[test]
fn a_failed_bench_keeps_the_json_file_it_was_given() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("earlier.json");
    std::fs::write(&json, "{\"kept\": true}").unwrap();
    let (ok, _, err) = powder(&[
        "bench",
        "--sizes",
        "100",
        "--steps",
        "4",
        "--backend",
        "cpu",
        "--velocity-scale",
        "1e6",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("no size ran") && err.contains("not written"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&json).unwrap(), "{\"kept\": true}");
}

/// `--profile` runs as many steps again with a GPU timestamp after every pass and reports
/// each pass's device time in the table and the JSON, windowed runs too.
#[test]
fn bench_profile_reports_every_pass() {
    if !gpu_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (size, window) in [("64", None), ("512", Some("128"))] {
        let json = dir.path().join(format!("bench_{size}.json"));
        let mut args = vec![
            "bench",
            "--sizes",
            size,
            "--steps",
            "4",
            "--warmup",
            "1",
            "--backend",
            "gpu",
            "--case",
            "hysteretic",
            "--quiet-batches",
            "off",
            // (every pass in every step, so the profile has each: on demand the rebuild's
            // run only where one is due)
            "--rebuild-chain",
            "every-step",
            "--profile",
            "--json",
            json.to_str().unwrap(),
        ];
        if let Some(w) = window {
            args.extend(["--window-particles", w]);
        }
        let (ok, out, err) = powder(&args);
        assert!(ok, "{err}");
        // (no CPU option was given: none is noticed)
        assert!(!err.contains("--threads"), "{err}");
        assert!(out.contains("passes (µs a step over 4 steps"), "{out}");
        let v = read_json(&json);
        let row = &v["rows"][0];
        if window.is_some() {
            assert!(row["note"].as_str().unwrap().contains("4 windows"), "{row}");
        }
        assert_eq!(row["rebuild_halts"], 0, "{row}");
        let profile = &row["passes"];
        assert_eq!(profile["steps"], 4);
        let passes = profile["passes"].as_array().unwrap();
        let names: Vec<&str> = passes.iter().map(|p| p[0].as_str().unwrap()).collect();
        for name in [
            "kick_drift",
            "decide",
            "grid sort",
            "count_neighbours",
            "list scans",
            "neighbours",
            "commit",
            "permute",
            "remap",
            "copy_back_history",
            "force",
            "collect_kick_drift",
            "collect",
            "kick",
        ] {
            assert!(names.contains(&name), "{name} missing: {names:?}");
        }
        let seconds: Vec<f64> = passes.iter().map(|p| p[1].as_f64().unwrap()).collect();
        assert!(seconds.iter().all(|&s| s >= 0.0), "{passes:?}");
        // the device worked: the force pass took time, and the passes fit the wall clock
        let force = seconds[names.iter().position(|&n| n == "force").unwrap()];
        let wall = profile["wall_seconds"].as_f64().unwrap();
        assert!(
            force > 0.0 && seconds.iter().sum::<f64>() <= wall,
            "{profile}"
        );
    }
}

/// `--repeats N`: every (case, backend, size) runs N times on fresh engines; the row is the
/// fastest run and `runs` lists every run's rate. `--repeats 0` is refused.
#[test]
fn bench_repeats_keep_the_fastest_run() {
    let gpu = gpu_available();
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let backend = if gpu { "both" } else { "cpu" };
    let (ok, _, err) = powder(&[
        "bench",
        "--sizes",
        "27",
        "--steps",
        "8",
        "--warmup",
        "2",
        "--case",
        "hysteretic",
        "--backend",
        backend,
        "--repeats",
        "3",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let rows = read_json(&json)["rows"].as_array().unwrap().clone();
    assert_eq!(rows.len(), if gpu { 2 } else { 1 });
    for r in &rows {
        let runs: Vec<f64> = r["runs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(runs.len(), 3, "{r}");
        assert!(runs.iter().all(|&x| x > 0.0), "{r}");
        let best = runs.iter().cloned().fold(0.0, f64::max);
        assert_eq!(
            r["particle_steps_per_second"].as_f64().unwrap(),
            best,
            "{r}"
        );
    }
    let (ok, _, err) = powder(&["bench", "--sizes", "27", "--repeats", "0"]);
    assert!(!ok && err.contains("repeats"), "{err}");
}

/// The GPU rows carry the estimate of bytes moved per particle-step (`gpu::traffic`) and the
/// adapter its limits; `powder info SCENE --json --set ...` reports the same estimate for a
/// scaled scene.
#[test]
fn bench_and_info_report_the_traffic_estimate() {
    if !gpu_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let (ok, out, err) = powder(&[
        "bench",
        "--sizes",
        "64",
        "--steps",
        "4",
        "--warmup",
        "1",
        "--backend",
        "gpu",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("B/p-step"), "{out}");
    let v = read_json(&json);
    let limits = &v["adapter"]["limits"];
    for key in [
        "max_storage_buffer_binding_size",
        "max_buffer_size",
        "max_storage_buffers_per_shader_stage",
    ] {
        assert!(limits[key].as_u64().unwrap() > 0, "{key}: {limits}");
    }
    let mut step = Vec::new();
    for r in v["rows"].as_array().unwrap() {
        let t = &r["traffic"];
        let per_step = t["step_bytes_per_particle"].as_f64().unwrap();
        let rebuild = t["rebuild_bytes_per_particle"].as_f64().unwrap();
        let rate = t["rebuilds_per_step"].as_f64().unwrap();
        assert!(per_step > 100.0 && rebuild > 100.0, "{t}");
        let total = t["bytes_per_particle_step"].as_f64().unwrap();
        assert!(
            (total - (per_step + rate * rebuild)).abs() <= 1e-9 * total,
            "{t}"
        );
        let passes = t["passes"].as_array().unwrap();
        let pass = |name: &str| {
            passes
                .iter()
                .find(|p| p["pass"] == name)
                .unwrap_or_else(|| panic!("no pass {name}: {t}"))
        };
        assert_eq!(pass("force")["when"], "step");
        assert_eq!(pass("neighbours")["when"], "rebuild");
        assert_eq!(pass("grid.cell_keys")["when"], "rebuild");
        // the texture mirrors: the software adapter's path only (chosen by the adapter kind)
        if v["adapter"]["device_type"] == "Cpu" {
            assert!(pass("mirror copies")["bytes"].as_u64().unwrap() >= 6 * 16 * 64);
        } else {
            assert!(passes.iter().all(|p| p["pass"] != "mirror copies"), "{t}");
        }
        // the force pass binds the lists' entries once, counted by the fields it touches:
        // partner, history, pair force (at least 5 words an entry), not `lower` (1 word)
        let bound = pass("force")["bound"].as_array().unwrap();
        let e: Vec<_> = bound.iter().filter(|b| b[0] == "entries").collect();
        assert_eq!(e.len(), 1, "{bound:?}");
        let entries = r["list_entries"].as_u64().unwrap();
        let touched = e[0][1].as_u64().unwrap();
        assert_eq!(touched % (4 * entries), 0, "{touched}");
        assert!(touched >= 5 * 4 * entries, "{touched}");
        let collect = pass("collect_kick_drift")["bound"].as_array().unwrap();
        let c = collect.iter().find(|b| b[0] == "entries").unwrap();
        // collect reads `lower` and the pair forces (and torques): less than force's
        assert!(c[1].as_u64().unwrap() < touched, "{collect:?}");
        step.push((r["case"].as_str().unwrap().to_string(), per_step));
    }
    // friction and rolling bind more per step
    assert_eq!(step.len(), 2);
    assert!(step[1].1 > step[0].1, "{step:?}");
    // info: the estimate of a scene, scaled by --set
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/cohesive_cluster.toml"
    );
    let (ok, out, err) = powder(&[
        "info",
        scene,
        "--json",
        "--no-ledger",
        "--set",
        "particles[0].count=300",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["particles"], 300);
    assert!(v["traffic"]["step_bytes_per_particle"].as_f64().unwrap() > 100.0);
    assert_eq!(v["traffic"]["rebuilds_per_step"], 0.0);
}

#[test]
fn bench_measures_each_thread_count_and_its_speedup() {
    let gpu = gpu_available();
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let (ok, out, err) = powder(&[
        "bench",
        "--sizes",
        "1200",
        "--steps",
        "4",
        "--warmup",
        "1",
        "--case",
        "hysteretic",
        "--backend",
        if gpu { "both" } else { "cpu" },
        "--threads",
        "1,2",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("cpu×2"), "{out}");
    let v = read_json(&json);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), if gpu { 3 } else { 2 });
    for r in rows {
        assert_eq!(r["status"], "ran", "{r}");
        match (r["backend"].as_str().unwrap(), r["threads"].as_u64()) {
            // the first count is the baseline; the second its rate over the first's
            ("cpu", Some(1)) => assert!(r["speedup"].is_null(), "{r}"),
            ("cpu", Some(2)) => assert!(r["speedup"].as_f64().unwrap() > 0.0, "{r}"),
            ("gpu", None) => assert!(r["speedup"].is_null(), "{r}"),
            _ => panic!("unexpected row {r}"),
        }
    }
}
