//! Stiff and extreme cases, and the run monitor (issue 6): each within a stated tolerance
//! of the closed forms, or stopped with a message that names the step and the particles.

mod common;
use common::{gpu, SceneBuilder};

use powder::cpu::CpuEngine;
use powder::measure::collide::{collide, CollideSpec};
use powder::model::analytic::{self, en_no_fa};
use powder::model::{ContactModel, HystereticParams, JkrParams, LsdParams, PairGeometry};
use powder::run::{run_cpu_with, RunOptions};
use powder::scene::{Domain, DtSetting, Material, ParticleInit, Scene};

fn hyst(kp: f64, kc: f64) -> HystereticParams {
    HystereticParams {
        kp,
        kc,
        ..HystereticParams::paper_figure()
    }
}

fn spec(p: HystereticParams, r2: f64, v: f64) -> CollideSpec {
    CollideSpec {
        radius2: r2,
        ..CollideSpec::head_on(ContactModel::Hysteretic(p), 1.1e-3, 2000.0, v)
    }
}

fn v_for(p: &HystereticParams, r2: f64, chi: f64) -> f64 {
    let m = |r: f64| 2000.0 * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let g = PairGeometry::spheres(1.1e-3, r2, m(1.1e-3), m(r2));
    analytic::velocity_for_chi(p, g.a12, g.reduced_mass, chi)
}

#[test]
fn very_plastic_contacts_kp_over_k1_1000() {
    let p = hyst(1e5, 10.0);
    let (eta, beta) = (999.0, 0.1);
    let mut worst: f64 = 0.0;
    for chi in [1e-3, 1e-2, 0.1, 0.5, 2.0, 20.0] {
        let r = collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, chi))).unwrap();
        let e = en_no_fa(eta, beta, chi);
        worst = worst.max((r.e - e).abs());
        eprintln!("kp/k1 = 1000, chi {chi}: e {} vs {e}", r.e);
        assert!(
            (r.e * r.e - e * e).abs() < 0.01,
            "chi {chi}: {} vs {e}",
            r.e
        );
    }
}

#[test]
fn violent_impacts_up_to_chi_20() {
    let p = hyst(500.0, 100.0);
    for chi in [5.0, 10.0, 20.0] {
        let r = collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, chi))).unwrap();
        let e = en_no_fa(4.0, 1.0, chi);
        eprintln!(
            "chi {chi}: e {} vs {e}, delta_max/a {}",
            r.e,
            r.delta_max / 1.1e-3
        );
        assert!((r.e - e).abs() < 5e-3, "chi {chi}: {} vs {e}", r.e);
    }
    // at χ = 20 the overlap exceeds half the radius: δmax = φf·a12 + δmax^p·χ·√(k1/kp)
    let r = collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, 20.0))).unwrap();
    assert!(
        r.delta_max / 1.1e-3 > 0.5,
        "δmax/a {}",
        r.delta_max / 1.1e-3
    );
}

#[test]
fn adhesivity_just_above_beta_star_sticks_only_near_chi_1() {
    let eta = 4.0;
    let beta = 1.05 * analytic::beta_star(eta);
    let p = hyst(500.0, beta * 100.0);
    let (lo, hi) = (analytic::chi_c_b(eta, beta), analytic::chi_c_c(eta, beta));
    assert!(lo < 1.0 && hi > 1.0 && hi - lo < 0.2, "window ({lo}, {hi})");
    assert!(
        collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, 1.0)))
            .unwrap()
            .stuck
    );
    assert!(
        !collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, lo - 0.05)))
            .unwrap()
            .stuck
    );
    assert!(
        !collide(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, hi + 0.05)))
            .unwrap()
            .stuck
    );
    // β ≫ β*: sticks over a wide window
    let strong = hyst(500.0, 1000.0);
    for chi in [0.4, 1.0, 1.5] {
        assert!(
            collide(&spec(strong, 1.1e-3, v_for(&strong, 1.1e-3, chi)))
                .unwrap()
                .stuck,
            "chi {chi}"
        );
    }
}

#[test]
fn size_ratio_1_to_10() {
    let p = hyst(500.0, 10.0);
    for r2 in [0.11e-3, 11e-3] {
        for chi in [0.1, 0.7, 2.0] {
            let r = collide(&spec(p, r2, v_for(&p, r2, chi))).unwrap();
            let e = en_no_fa(4.0, 0.1, chi);
            eprintln!("size ratio r2 {r2}, chi {chi}: e {} vs {e}", r.e);
            assert!((r.e - e).abs() < 5e-3, "r2 {r2} chi {chi}: {} vs {e}", r.e);
        }
    }
}

#[test]
fn tiny_stiff_silica_spheres() {
    // silica, radius 1 µm, E = 70 GPa, γ = 0.025 J/m²: dt ~ 1e-11 s
    let p = JkrParams::jkr(7e10, 0.17, 0.025);
    let s = CollideSpec::head_on(ContactModel::Jkr(p), 1e-6, 2200.0, 5.0);
    let r = collide(&s).unwrap();
    assert!(r.dt < 1e-10 && r.dt > 1e-13, "dt {}", r.dt);
    let e = r.e_analytic.unwrap();
    eprintln!(
        "silica: dt {:e}, e {} vs {e}, balance {:e}",
        r.dt,
        r.e,
        r.energy.balance_error.unwrap()
    );
    assert!((r.e - e).abs() < 5e-3, "{} vs {e}", r.e);
    assert!(r.energy.balance_error.unwrap() < 1e-3);
}

#[test]
fn adhesion_so_weak_nothing_sticks_and_so_strong_everything_sticks() {
    let weak = JkrParams::jkr(1e9, 0.3, 1e-6);
    let strong = JkrParams::jkr(1e9, 0.3, 50.0);
    for v in [0.05, 0.5, 5.0] {
        let w = collide(&CollideSpec::head_on(
            ContactModel::Jkr(weak),
            1e-6,
            2000.0,
            v,
        ))
        .unwrap();
        assert!(!w.stuck && w.e > 0.99, "weak, v {v}: {}", w.e);
        let s = collide(&CollideSpec::head_on(
            ContactModel::Jkr(strong),
            1e-6,
            2000.0,
            v,
        ))
        .unwrap();
        assert!(s.stuck, "strong, v {v}");
    }
}

/// Paper 000 appendix B: a stuck pair oscillates on its k2 branch with constant amplitude
/// without viscosity, and settles at a fixed overlap with it.
#[test]
fn sticking_oscillations_keep_their_amplitude_or_settle() {
    let scene = |gamma0: f64| Scene {
        name: "stick".into(),
        domain: Domain {
            min: [-0.01; 3],
            max: [0.01; 3],
            periodic: [false; 3],
        },
        gravity: [0.0; 3],
        dt: DtSetting::Auto,
        force_dt: false,
        jump_impulses: None,
        duration: 1.0,
        output_every: 1000,
        impact_velocity: 1.0,
        checkpoint_every: 10_000,
        contact_output: None,
        materials: vec![Material {
            name: "m".into(),
            density: 2000.0,
            model: ContactModel::Hysteretic(HystereticParams {
                gamma0,
                ..hyst(500.0, 100.0)
            }),
        }],
        interactions: vec![],
        walls: vec![],
        // χ = 0.8: inside the sticking window (0.5, 1.155)
        particles: vec![
            ParticleInit {
                position: [0.0; 3],
                velocity: [0.1165, 0.0, 0.0],
                angular_velocity: [0.0; 3],
                radius: 1.1e-3,
                material: 0,
                insert_at: 0.0,
            },
            ParticleInit {
                position: [2.2001e-3, 0.0, 0.0],
                velocity: [-0.1165, 0.0, 0.0],
                angular_velocity: [0.0; 3],
                radius: 1.1e-3,
                material: 0,
                insert_at: 0.0,
            },
        ],
    };
    let amplitude = |e: &mut CpuEngine, steps: u64| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for _ in 0..steps {
            e.step().unwrap();
            let d = e.overlap(0, 1);
            lo = lo.min(d);
            hi = hi.max(d);
        }
        (lo, hi)
    };
    let mut undamped = CpuEngine::new(&scene(0.0)).unwrap();
    amplitude(&mut undamped, 2_000);
    let (lo1, hi1) = amplitude(&mut undamped, 20_000);
    let (lo2, hi2) = amplitude(&mut undamped, 20_000);
    eprintln!(
        "undamped sticking: amplitude {:e} then {:e}",
        hi1 - lo1,
        hi2 - lo2
    );
    assert!(lo1 > 0.0, "stays in contact");
    assert!(
        ((hi2 - lo2) - (hi1 - lo1)).abs() < 1e-3 * (hi1 - lo1),
        "amplitude kept: {} vs {}",
        hi2 - lo2,
        hi1 - lo1
    );
    let mut damped = CpuEngine::new(&scene(5e-3)).unwrap();
    amplitude(&mut damped, 100_000);
    let (lo, hi) = amplitude(&mut damped, 5_000);
    eprintln!("damped sticking: settled at {lo:e}..{hi:e}");
    assert!(lo > 0.0 && hi - lo < 1e-6 * hi, "settled: {lo}..{hi}");
}

fn pair_scene(dt: DtSetting, force_dt: bool, v: f64, domain: f64) -> Scene {
    Scene {
        name: "pair".into(),
        domain: Domain {
            min: [-domain; 3],
            max: [domain; 3],
            periodic: [false; 3],
        },
        gravity: [0.0; 3],
        dt,
        force_dt,
        jump_impulses: None,
        duration: 0.01,
        output_every: 100,
        impact_velocity: 1.0,
        checkpoint_every: 100,
        contact_output: None,
        materials: vec![Material {
            name: "m".into(),
            density: 2000.0,
            model: ContactModel::Lsd(LsdParams::new(100.0, 0.0)),
        }],
        interactions: vec![],
        walls: vec![],
        particles: vec![
            ParticleInit {
                position: [-1.2e-3, 0.0, 0.0],
                velocity: [v, 0.0, 0.0],
                angular_velocity: [0.0; 3],
                radius: 1e-3,
                material: 0,
                insert_at: 0.0,
            },
            ParticleInit {
                position: [1.2e-3, 0.0, 0.0],
                velocity: [-v, 0.0, 0.0],
                angular_velocity: [0.0; 3],
                radius: 1e-3,
                material: 0,
                insert_at: 0.0,
            },
        ],
    }
}

#[test]
fn the_monitor_stops_runs_that_go_wrong_and_keeps_the_last_good_state() {
    let dir = tempfile::tempdir().unwrap();
    // a forced time step far above the limit
    let s = pair_scene(DtSetting::Fixed(2e-3), true, 0.5, 0.1);
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    let err = run_cpu_with(&s, &opts, |_| {}).unwrap_err().to_string();
    assert!(
        err.contains("step") && err.contains("particle") && err.contains("time step"),
        "{err}"
    );
    assert!(err.contains("checkpoint.bin"), "{err}");
    assert!(dir.path().join("checkpoint.bin").exists());
    // refused without force_dt, with the limit and the reason
    let err = CpuEngine::new(&pair_scene(DtSetting::Fixed(2e-3), false, 0.5, 0.1))
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("stable limit") && err.contains("force_dt"),
        "{err}"
    );
    // a violent impact: overlap beyond half the reduced radius
    let err = run_cpu_with(
        &pair_scene(DtSetting::Auto, false, 3.0, 0.1),
        &RunOptions::default(),
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("overlaps particle") && err.contains("reduced radius"),
        "{err}"
    );
    // particles leaving the domain
    let mut s = pair_scene(DtSetting::Auto, false, -0.5, 3e-3);
    s.duration = 0.05;
    let err = run_cpu_with(&s, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("left the domain") && err.contains("[0, 1]"),
        "{err}"
    );
}

/// The step a monitor error names ("step N: ...").
fn step_of(err: &str) -> u64 {
    err.strip_prefix("step ")
        .and_then(|r| r.split(':').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no step in {err}"))
}

/// A failing chunk stepped again from a copy of the state taken chunks before it (as a
/// GPU run at 10^7 particles copies its state seldom) gives the same error and the same
/// checkpoint of the chunk's start as one copied just before it, on both backends.
#[test]
fn a_failing_chunk_is_found_from_an_older_copy_of_the_state() {
    use powder::run::run_gpu_with;
    // the pair flies apart and leaves the domain after some 360 steps: chunks of 100
    let mut s = pair_scene(DtSetting::Auto, false, -0.5, 3e-3);
    s.duration = 0.05;
    type Run = fn(&Scene, &RunOptions) -> Option<String>;
    let backends: [(&str, Run); 2] = [
        ("cpu", |s, o| {
            Some(run_cpu_with(s, o, |_| {}).unwrap_err().to_string())
        }),
        ("gpu", |s, o| {
            Some(run_gpu_with(s, gpu()?, o, |_| {}).unwrap_err().to_string())
        }),
    ];
    for (backend, run) in backends {
        let outcome = |every: u64| {
            let dir = tempfile::tempdir().unwrap();
            let opts = RunOptions {
                out_dir: Some(dir.path().to_path_buf()),
                copy_every: Some(every),
                ..Default::default()
            };
            let err = run(&s, &opts)?;
            let ckpt = std::fs::read(dir.path().join("checkpoint.bin")).unwrap();
            Some((err.replace(dir.path().to_str().unwrap(), "DIR"), ckpt))
        };
        let Some((err, ckpt)) = outcome(1) else {
            continue;
        };
        assert!(
            step_of(&err) > 200 && err.contains("left the domain"),
            "{backend}: {err}"
        );
        let (err_old, ckpt_old) = outcome(u64::MAX).unwrap();
        assert_eq!(err_old, err, "{backend}");
        assert!(ckpt_old == ckpt, "{backend}: the checkpoints differ");
    }
}

/// A run that goes wrong inside a chunk of steps names the step it went wrong at, not the
/// chunk's end: the same error on any output cadence, on both backends (the failed chunk is
/// run again a step at a time; before, a GPU run named the chunk's end with the overlap
/// reached by then, ~10⁹ of the reduced radius).
#[test]
fn a_failure_is_named_at_its_own_step_on_any_cadence() {
    use powder::run::run_gpu_with;
    // a forced time step five times beyond Verlet's limit; the pair meets after ~8 steps
    let mut s = pair_scene(DtSetting::Fixed(1e-3), true, 0.5, 0.1);
    s.particles[0].position[0] = -5e-3;
    s.particles[1].position[0] = 5e-3;
    s.duration = 1.0;
    let every = |n: u64| {
        let mut s = s.clone();
        (s.output_every, s.checkpoint_every) = (n, n);
        s
    };
    // the error up to its note on the checkpoint
    let named = |e: powder::PowderError| {
        e.to_string()
            .split("; the state")
            .next()
            .unwrap()
            .to_string()
    };
    let run = |s: &Scene| {
        let dir = tempfile::tempdir().unwrap();
        let opts = RunOptions {
            out_dir: Some(dir.path().to_path_buf()),
            ..Default::default()
        };
        named(run_cpu_with(s, &opts, |_| {}).unwrap_err())
    };
    let (chunked, stepwise) = (run(&every(100)), run(&every(1)));
    assert_eq!(chunked, stepwise);
    let at = step_of(&chunked);
    assert!((8..100).contains(&at), "{chunked}");
    let Some(ctx) = gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    let on_gpu = named(run_gpu_with(&every(100), ctx, &opts, |_| {}).unwrap_err());
    let Some(ctx) = gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    let on_gpu_stepwise = named(run_gpu_with(&every(1), ctx, &opts, |_| {}).unwrap_err());
    assert_eq!(on_gpu, on_gpu_stepwise);
    // without the ledger the chunk is searched without observing each step: the same error
    let Some(ctx) = gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        gpu: powder::gpu::GpuOptions {
            ledger: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let without_ledger = named(run_gpu_with(&every(100), ctx, &opts, |_| {}).unwrap_err());
    assert_eq!(without_ledger, on_gpu);
    let gpu_at = step_of(&on_gpu);
    assert!(gpu_at.abs_diff(at) <= 1, "{on_gpu} against {chunked}");
    // an overlap beyond the limit names the partner on both backends (the GPU's monitor
    // keeps the particle only: the run finds the partner from the positions)
    let violent = pair_scene(DtSetting::Auto, false, 3.0, 0.1);
    let cpu_err = run_cpu_with(&violent, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    let Some(ctx) = gpu() else { return };
    let gpu_err = run_gpu_with(&violent, ctx, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    for e in [&cpu_err, &gpu_err] {
        let named = e.contains("particle 0 overlaps particle 1")
            || e.contains("particle 1 overlaps particle 0");
        assert!(named && e.contains("reduced radius"), "{e}");
    }
}

/// A settled cohesive packing held for 10⁶ steps: the energy ledger may not drift by more
/// than 10⁻⁹ of the gravitational energy released while settling (measured 1.5·10⁻¹³).
#[test]
fn a_packing_held_for_a_million_steps_does_not_drift() {
    // (the cohesive law, damped twice as much; a floor and four side walls)
    let law = common::builder::COHESIVE.replace("gamma0 = 1e-3", "gamma0 = 2e-3");
    let scene = common::builder::SceneBuilder::new("held", [0.0; 3], [0.008, 0.008, 0.012], 100.0)
        .gravity()
        .material("powder", 2000.0, &law)
        .floor()
        .wall([0.0; 3], [1.0, 0.0, 0.0])
        .wall([0.0; 3], [0.0, 1.0, 0.0])
        .wall([0.0055, 0.0, 0.0], [-1.0, 0.0, 0.0])
        .wall([0.0, 0.0055, 0.0], [0.0, -1.0, 0.0])
        .particles(
            "lattice",
            "min = [0.001, 0.001, 0.0005]\nmax = [0.0075, 0.0075, 0.0072]\nradius = 1.1e-3\n\
             spacing = 2.25e-3\njitter = 0.3",
        )
        .build();
    let mut e = CpuEngine::new(&scene).unwrap();
    assert_eq!(e.len(), 12);
    let start = e.energies();
    e.run_steps(300_000).unwrap();
    let settled = e.energies();
    let released = start.gravitational - settled.gravitational;
    assert!(
        released > 0.0 && settled.kinetic < 1e-3 * released,
        "settled: {settled:?}"
    );
    e.run_steps(1_000_000).unwrap();
    let held = e.energies();
    let drift = (held.total() - settled.total()).abs();
    eprintln!(
        "held 1e6 steps: drift {drift:e} J = {:e} of the released {released:e} J",
        drift / released
    );
    assert!(
        drift < 1e-9 * released,
        "drift {drift:e} J over 1e6 steps, released {released:e} J"
    );
    assert!(e.contact_stats().coordination > 2.0);
}

/// The device checks of the GPU run monitor, run with `gpu` (with or without the ledger):
/// a forced, far too large time step stops with a checkpoint of the last good state (in
/// `out`; returned with the run options and scene, to resume), a violent impact and an
/// escape stop too. `None` without an adapter.
fn gpu_monitor_stops_each_failure(
    gpu_options: powder::gpu::GpuOptions,
    out: &std::path::Path,
) -> Option<(std::path::PathBuf, RunOptions, Scene)> {
    use powder::run::run_gpu_with;
    let opts = RunOptions {
        out_dir: Some(out.to_path_buf()),
        gpu: gpu_options,
        ..Default::default()
    };
    // a forced time step far above the limit
    let ctx = gpu()?;
    let s = pair_scene(DtSetting::Fixed(2e-3), true, 0.5, 0.1);
    let err = run_gpu_with(&s, ctx, &opts, |_| {})
        .unwrap_err()
        .to_string();
    eprintln!("forced dt: {err}");
    assert!(
        err.contains("step") && err.contains("particle") && err.contains("time step"),
        "{err}"
    );
    assert!(err.contains("checkpoint.bin"), "{err}");
    let ckpt = out.join("checkpoint.bin");
    assert!(ckpt.exists());
    // a violent impact: overlap beyond half the reduced radius, seen on the device
    let quiet = RunOptions {
        gpu: gpu_options,
        ..Default::default()
    };
    let err = run_gpu_with(
        &pair_scene(DtSetting::Auto, false, 3.0, 0.1),
        gpu()?,
        &quiet,
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("particle") && err.contains("reduced radius"),
        "{err}"
    );
    // particles leaving the domain
    let mut escape = pair_scene(DtSetting::Auto, false, -0.5, 3e-3);
    escape.duration = 0.05;
    let err = run_gpu_with(&escape, gpu()?, &quiet, |_| {})
        .unwrap_err()
        .to_string();
    eprintln!("escape: {err}");
    assert!(err.contains("left the domain"), "{err}");
    Some((ckpt, opts, s))
}

/// The run monitor on the GPU backend: the failures are detected on the device (overlap,
/// escape, non-finite forces; checked once per batch of steps, no per-step read-back) and
/// the run stops with a checkpoint of the last state that passed.
#[test]
fn the_gpu_monitor_stops_runs_that_go_wrong_and_keeps_the_last_good_state() {
    use powder::run::run_gpu_with;
    let dir = tempfile::tempdir().unwrap();
    let Some((ckpt, opts, s)) = gpu_monitor_stops_each_failure(Default::default(), dir.path())
    else {
        return;
    };
    // the checkpoint holds the last good state: it resumes (and fails again further on)
    let Some(ctx) = gpu() else { return };
    let resumed = RunOptions {
        resume: Some(ckpt),
        ..opts
    };
    let again = run_gpu_with(&s, ctx, &resumed, |_| {})
        .unwrap_err()
        .to_string();
    assert!(again.contains("step"), "{again}");
}

/// `compare` on a scene whose CPU reference itself goes wrong (a forced time step far above
/// the limit) stops with that, not with a table of CPU/GPU deviations (it reported both
/// engines blowing up as a disagreement).
#[test]
fn compare_names_an_unstable_reference_run() {
    let Some(ctx) = gpu() else { return };
    let s = pair_scene(DtSetting::Fixed(2e-3), true, 0.5, 0.1);
    let err = powder::measure::compare::compare(&s, ctx, 4000, 100, Default::default())
        .expect_err("the comparison is refused")
        .to_string();
    assert!(
        err.contains("the CPU reference went wrong") && err.contains("unstable"),
        "{err}"
    );
}

/// Without the energy ledger (`powder run --no-ledger`) the monitor has no energy-growth
/// check, but its device checks still stop a forced, far too large time step, a violent
/// impact and an escape, with a checkpoint of the last good state.
#[test]
fn the_gpu_monitor_without_the_ledger_still_stops_runs_that_go_wrong() {
    let dir = tempfile::tempdir().unwrap();
    gpu_monitor_stops_each_failure(
        powder::gpu::GpuOptions {
            ledger: false,
            ..Default::default()
        },
        dir.path(),
    );
}

/// The Rayleigh time bounds dt for elastic spheres when slow impacts make the Hertz
/// contact time long: silica spheres (r = 1 µm) meeting at 0.1 mm/s.
#[test]
fn the_rayleigh_time_bounds_dt_for_slow_hertz_contacts() {
    // silica spheres 1 µm apart, the time step `dt`
    let text = |dt: &str| {
        SceneBuilder::new("slow", [-1e-5; 3], [1e-5; 3], 1e-6)
            .simulation("impact_velocity", "1e-4")
            .simulation("dt", dt)
            .material(
                "silica",
                2650.0,
                "model = \"hertz\"\nyoungs = 7e10\npoisson = 0.17",
            )
            .particles(
                "list",
                "radius = 1e-6\npositions = [[0.0, 0.0, 0.0], [3e-6, 0.0, 0.0]]",
            )
            .toml()
    };
    let scene = Scene::from_toml_str(&text("\"auto\""), "slow").unwrap();
    let r = powder::setup::Resolved::new(&scene).unwrap();
    // T_R = pi·r·sqrt(rho/G)/(0.1631·nu + 0.8766), G = E/(2(1 + nu))
    let g: f64 = 7e10 / (2.0 * 1.17);
    let t_r = std::f64::consts::PI * 1e-6 * (2650.0_f64 / g).sqrt() / (0.1631 * 0.17 + 0.8766);
    eprintln!(
        "T_R = {t_r:e} s; dt = {:e} s ({})",
        r.dt, r.time_step.reason
    );
    assert!(
        r.time_step.reason.contains("Rayleigh"),
        "{}",
        r.time_step.reason
    );
    assert!((r.time_step.max - 0.4 * t_r).abs() < 1e-9 * t_r);
    assert!((r.dt - 0.2 * t_r).abs() < 1e-9 * t_r);
    let err = Scene::from_toml_str(&text(&format!("{:e}", 0.5 * t_r)), "slow")
        .and_then(|s| powder::setup::Resolved::new(&s).map(|_| ()))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("Rayleigh") && err.contains("force_dt"),
        "{err}"
    );
}

/// The stiff and extreme pair cases on the GPU backend (f32 on the device, the full GPU
/// pipeline): each within a stated tolerance of the closed forms and of the CPU.
#[test]
fn stiff_and_extreme_cases_on_the_gpu() {
    use powder::measure::collide::{collide_on, Backend};
    if gpu().is_none() {
        return;
    }
    let on_gpu = |s: &CollideSpec| collide_on(s, Backend::Gpu).unwrap();
    // kp/k1 = 1000 (η = 999, β = 0.1) from slow to violent impacts
    let p = hyst(1e5, 10.0);
    for chi in [1e-2, 0.5, 2.0] {
        let r = on_gpu(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, chi)));
        let e = en_no_fa(999.0, 0.1, chi);
        eprintln!("gpu kp/k1 = 1000, chi {chi}: e {} vs {e}", r.e);
        assert!(
            (r.e * r.e - e * e).abs() < 0.01,
            "chi {chi}: {} vs {e}",
            r.e
        );
    }
    // χ = 20: overlaps beyond half the radius
    let p = hyst(500.0, 100.0);
    let r = on_gpu(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, 20.0)));
    let e = en_no_fa(4.0, 1.0, 20.0);
    eprintln!(
        "gpu chi 20: e {} vs {e}, delta_max/a {}",
        r.e,
        r.delta_max / 1.1e-3
    );
    assert!((r.e - e).abs() < 5e-3 && r.delta_max / 1.1e-3 > 0.5);
    // β just above β*: sticks at χ = 1 only
    let beta = 1.05 * analytic::beta_star(4.0);
    let p = hyst(500.0, beta * 100.0);
    let (lo, hi) = (analytic::chi_c_b(4.0, beta), analytic::chi_c_c(4.0, beta));
    assert!(on_gpu(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, 1.0))).stuck);
    assert!(!on_gpu(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, lo - 0.05))).stuck);
    assert!(!on_gpu(&spec(p, 1.1e-3, v_for(&p, 1.1e-3, hi + 0.05))).stuck);
    // size ratio 1:10
    let p = hyst(500.0, 10.0);
    for r2 in [0.11e-3, 11e-3] {
        let r = on_gpu(&spec(p, r2, v_for(&p, r2, 0.7)));
        let e = en_no_fa(4.0, 0.1, 0.7);
        eprintln!("gpu size ratio r2 {r2}: e {} vs {e}", r.e);
        assert!((r.e - e).abs() < 5e-3, "r2 {r2}: {} vs {e}", r.e);
    }
    // tiny stiff silica spheres (dt ~ 1e-12 s)
    let silica = JkrParams::jkr(7e10, 0.17, 0.025);
    let s = CollideSpec::head_on(ContactModel::Jkr(silica), 1e-6, 2200.0, 5.0);
    let (g, c) = (on_gpu(&s), collide(&s).unwrap());
    eprintln!(
        "gpu silica: e {} (cpu {}, closed form {}), balance {:e}",
        g.e,
        c.e,
        g.e_analytic.unwrap(),
        g.energy.balance_error.unwrap()
    );
    assert!((g.e - c.e).abs() < 1e-3, "{} vs {}", g.e, c.e);
    assert!(g.energy.balance_error.unwrap() < 1e-3);
    // adhesion so strong everything sticks, so weak nothing does (the weak zone is
    // crossed at the adhesion speed: 70 steps at 0.05 m/s, 1.5·10⁶ when it was crossed at
    // the impact speed)
    let strong = JkrParams::jkr(1e9, 0.3, 50.0);
    let weak = JkrParams::jkr(1e9, 0.3, 1e-6);
    for v in [0.05, 5.0] {
        let s = on_gpu(&CollideSpec::head_on(
            ContactModel::Jkr(strong),
            1e-6,
            2000.0,
            v,
        ));
        assert!(s.stuck, "strong, v {v}");
        let w = on_gpu(&CollideSpec::head_on(
            ContactModel::Jkr(weak),
            1e-6,
            2000.0,
            v,
        ));
        assert!(!w.stuck && w.e > 0.99, "weak, v {v}: {}", w.e);
    }
}

/// The energy check allows what rounding alone gives: the cohesive cluster at dt = 1e-11 s
/// (a tiny step, as a tiny sphere sets) moves its total by ulps of the gravitational energy,
/// 10^4 times the energy in play after 1000 steps, which once stopped it for "energy
/// growth". A start whose kinetic energy overflows is refused before anything is written.
#[test]
fn the_energy_check_allows_rounding_and_refuses_overflowing_starts() {
    let mut scene = common::cluster_with_outputs();
    scene.dt = DtSetting::Fixed(1e-11);
    let opts = RunOptions {
        max_steps: Some(1000),
        ..Default::default()
    };
    let s = run_cpu_with(&scene, &opts, |_| {}).unwrap();
    assert_eq!(s.steps, 1000);
    // (a spin: a speed that large would be refused first, as a step longer than a radius)
    let mut scene = common::packing(common::rough, "rough");
    scene.particles[3].angular_velocity = [1e200, 0.0, 0.0];
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        max_steps: Some(10),
        ..Default::default()
    };
    let err = run_cpu_with(&scene, &opts, |_| {}).unwrap_err().to_string();
    assert!(err.contains("kinetic energy at step 0 is inf"), "{err}");
    assert!(!dir.path().join("series.csv").exists());
}
