//! A scene built in code meets no reader: the engines and the run loop check it
//! themselves, and a mistake is an error that names it, never a panic, NaN or lost output.

mod common;

use powder::cpu::CpuEngine;
use powder::gpu::{GpuContext, GpuEngine};
use powder::model::{ContactModel, HystereticParams, LsdParams};
use powder::run::{run_cpu_with, RunOptions};
use powder::scene::{
    Domain, DtSetting, Interaction, Material, ParticleInit, Scene, Wall, WallMotion, WallPhase,
};

fn particle(x: f64) -> ParticleInit {
    ParticleInit {
        position: [x, 0.005, 0.002],
        velocity: [0.0; 3],
        angular_velocity: [0.0; 3],
        radius: 1e-3,
        material: 0,
        insert_at: 0.0,
    }
}

/// Two spheres above a floor: a valid scene that each case breaks in one place.
fn scene() -> Scene {
    Scene {
        name: "library_input".into(),
        domain: Domain {
            min: [0.0; 3],
            max: [0.01, 0.01, 0.01],
            periodic: [false; 3],
        },
        gravity: [0.0, 0.0, -9.81],
        dt: DtSetting::Auto,
        force_dt: false,
        jump_impulses: None,
        duration: 0.001,
        output_every: 50,
        impact_velocity: 1.0,
        checkpoint_every: 100,
        contact_output: None,
        materials: vec![Material {
            name: "powder".into(),
            density: 2000.0,
            model: ContactModel::Lsd(LsdParams::new(300.0, 1e-3)),
        }],
        interactions: Vec::new(),
        walls: vec![Wall {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            motion: WallMotion::fixed(),
            material: 0,
        }],
        particles: vec![particle(0.003), particle(0.006)],
    }
}

fn refused(s: &Scene, part: &str) {
    let e = match CpuEngine::new(s) {
        Ok(_) => panic!("accepted a scene that should fail with {part:?}"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains(part), "{e:?} lacks {part:?}");
}

#[test]
fn engines_refuse_a_scene_built_wrong_in_code() {
    CpuEngine::new(&scene()).unwrap();
    let mut s = scene();
    s.particles[1].material = 3;
    refused(&s, "particle 1 has material 3, but there are 1");
    let mut s = scene();
    s.walls[0].motion = WallMotion::always(WallPhase::Servo {
        force: 1.0,
        gain: 1e-3,
        max_speed: -0.01,
    });
    refused(
        &s,
        "wall 0, the phase from t = 0 s: `servo_max_speed` (the servo's largest speed, in m/s) must be > 0, got -0.01",
    );
    let mut s = scene();
    s.walls[0].normal = [0.0; 3];
    refused(
        &s,
        "wall 0 needs a finite point and a finite non-zero normal",
    );
    let mut s = scene();
    s.particles[0].position[2] = f64::NAN;
    refused(
        &s,
        "particle 0: position, velocity and angular velocity must be finite",
    );
    let mut s = scene();
    s.dt = DtSetting::Fixed(0.0);
    refused(&s, "[simulation]: `dt` (the time step");
    refused(&s, "must be > 0, got 0");
    let mut s = scene();
    s.domain.max[0] = -1.0;
    refused(&s, "the domain must have finite min < max");
    let mut s = scene();
    s.materials[0].model = ContactModel::Hysteretic(HystereticParams {
        kp: 50.0,
        ..HystereticParams::paper_figure()
    });
    refused(&s, "material 0 (`powder`)");
    let mut s = scene();
    s.particles[0].insert_at = f64::NAN;
    refused(
        &s,
        "particle 0: `insert_at` (when the block's particles appear",
    );
    refused(&s, "must be a finite number, got NaN");
    let mut s = scene();
    s.particles[1].velocity[0] = f64::INFINITY;
    refused(
        &s,
        "particle 1: position, velocity and angular velocity must be finite",
    );
    let mut s = scene();
    s.gravity[2] = f64::NAN;
    refused(&s, "gravity must be finite");
    let mut s = scene();
    s.dt = DtSetting::Fixed(-1e-6);
    refused(&s, "`dt` (the time step");
    refused(&s, "must be > 0, got -1e-6");
    let mut s = scene();
    s.checkpoint_every = 0;
    refused(
        &s,
        "[simulation]: `checkpoint_every` (steps between checkpoints",
    );
    refused(&s, "must be > 0, got 0");
    let mut s = scene();
    s.walls[0].point[0] = f64::NAN;
    refused(&s, "wall 0 needs a finite point");
    let mut s = scene();
    s.walls[0].motion = WallMotion::always(WallPhase::Velocity([0.0, 0.0, f64::NAN]));
    refused(
        &s,
        "wall 0, the phase from t = 0 s: its velocity must be finite",
    );
    let mut s = scene();
    s.walls[0].motion.phases = vec![(1e-3, WallPhase::Rest), (0.0, WallPhase::Rest)];
    refused(&s, "wall 0: its phases must start at increasing times");
    let mut s = scene();
    s.interactions.push(Interaction {
        materials: [0, 7],
        model: ContactModel::Lsd(LsdParams::new(300.0, 1e-3)),
    });
    refused(&s, "interaction 0 names materials [0, 7], but there are 1");
    let mut s = scene();
    s.domain.periodic[0] = true;
    s.gravity = [1.0, 0.0, -9.81];
    refused(&s, "gravity has a component along the periodic axis x");
    let mut s = scene();
    s.domain.periodic[2] = true;
    s.gravity = [0.0; 3];
    refused(&s, "wall 0 faces the periodic axis z");
    // what the reader checks of placement, interactions and walls holds in code too
    let mut s = scene();
    s.particles[1].position[0] = 5.0;
    refused(
        &s,
        "particle 1 at [5, 0.005, 0.002] with radius 0.001 is not inside the domain",
    );
    let mut s = scene();
    s.particles[1].position[0] = 0.0031;
    refused(&s, "particles 0 at [0.003, 0.005, 0.002] and 1 at");
    let mut s = scene();
    s.walls[0].point[2] = 5e-4;
    s.particles[1].position[2] = 1.2e-3;
    refused(
        &s,
        "particle 1 at [0.006, 0.005, 0.0012] with radius 0.001 overlaps wall 0",
    );
    let mut s = scene();
    s.interactions.push(Interaction {
        materials: [0, 0],
        model: ContactModel::Lsd(LsdParams::new(300.0, 1e-3)),
    });
    refused(&s, "interaction 0 pairs material 0 with itself");
    let mut s = scene();
    s.materials.push(Material {
        name: "glass".into(),
        ..s.materials[0].clone()
    });
    for _ in 0..2 {
        s.interactions.push(Interaction {
            materials: [0, 1],
            model: ContactModel::Lsd(LsdParams::new(300.0, 1e-3)),
        });
    }
    refused(&s, "interactions 0 and 1 both set materials 0 and 1");
    let mut s = scene();
    s.walls[0].motion = WallMotion::always(WallPhase::Servo {
        force: -1.0,
        gain: 1e-3,
        max_speed: 0.01,
    });
    refused(
        &s,
        "`servo_force` (the normal force the servo holds, in N) must be > 0",
    );
    let mut s = scene();
    s.walls[0].motion.phases = vec![(-1e-3, WallPhase::Rest)];
    refused(
        &s,
        "wall 0, the phase from t = -0.001 s: `from` (when the phase starts, in s) must be >= 0",
    );
}

/// A scene's name names its output files: one that cannot (`../escaped` wrote outside the
/// folder) is refused where a run writes them, and allowed where it writes none.
#[test]
fn a_name_that_cannot_name_files_is_refused_where_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let writes = RunOptions {
        out_dir: Some(dir.path().join("out")),
        max_steps: Some(10),
        ..Default::default()
    };
    for name in ["", "..", "../escaped", "a/b", "/abs", "tab\there"] {
        let mut s = scene();
        s.name = name.into();
        let e = run_cpu_with(&s, &writes, |_| {}).unwrap_err().to_string();
        assert!(
            e.contains("cannot name files in the output folder"),
            "{name:?}: {e}"
        );
        assert!(!dir.path().join("out").exists() && !dir.path().join("escaped.pvd").exists());
        let quiet = RunOptions {
            max_steps: Some(10),
            ..Default::default()
        };
        run_cpu_with(&s, &quiet, |_| {}).unwrap();
    }
}

/// An engine built from one scene and run or checkpointed with another is refused before
/// anything is written (it indexed walls the other scene lacks, or wrote the wrong scene's
/// checkpoint).
#[test]
fn an_engine_of_another_scene_is_refused() {
    use powder::run::run_with;
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        max_steps: Some(10),
        ..Default::default()
    };
    let mut other = scene();
    other.walls.clear();
    let engine = CpuEngine::new(&other).unwrap();
    let e = run_with(&scene(), engine, "", &opts, |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the engine was not built from scene `library_input`: it has 2 particles and 0 walls, the scene 2 and 1"),
        "{e}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // the same particles and walls of another material, or gravity: named by the part
    let mut stiffer = scene();
    stiffer.materials[0].model = ContactModel::Lsd(LsdParams::new(600.0, 1e-3));
    stiffer.gravity[2] *= 2.0;
    let engine = CpuEngine::new(&stiffer).unwrap();
    let e = run_with(&scene(), engine, "", &opts, |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("they differ in simulation.gravity, material 0;"),
        "{e}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // but for its name, duration and cadences
    let mut renamed = scene();
    (renamed.name, renamed.duration, renamed.output_every) = ("b".into(), 1.0, 7);
    let engine = CpuEngine::new(&renamed).unwrap();
    run_with(&scene(), engine, "", &opts, |_| {}).unwrap();
    let mut bigger = scene();
    bigger.particles[1].radius = 1.5e-3;
    let engine = CpuEngine::new(&bigger).unwrap();
    let path = dir.path().join("other.npz");
    let e = powder::checkpoint::save(&path, &scene(), &engine, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particle 1's radius is 1.5e-3 m there, 1e-3 m in the scene"),
        "{e}"
    );
    assert!(!path.exists());
}

/// A scene without an end runs only with a step limit; a Tabor parameter beyond f64 is
/// refused rather than written as `null`.
#[test]
fn a_run_needs_an_end_and_a_finite_tabor_parameter() {
    let mut s = scene();
    s.duration = f64::INFINITY;
    let e = run_cpu_with(&s, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("has an infinite duration"), "{e}");
    let opts = RunOptions {
        max_steps: Some(5),
        ..Default::default()
    };
    assert_eq!(run_cpu_with(&s, &opts, |_| {}).unwrap().steps, 5);
    let mut s = scene();
    s.materials[0].model = ContactModel::Jkr(powder::model::JkrParams::jkr(1e8, 0.3, 0.01));
    let opts = RunOptions {
        max_steps: Some(5),
        tabor_dmin: Some(1e-300),
        ..Default::default()
    };
    let e = run_cpu_with(&s, &opts, |_| {}).unwrap_err().to_string();
    assert!(
        e.contains("the Tabor parameter of materials `powder`-`powder` comes out as inf"),
        "{e}"
    );
}

#[test]
fn a_run_refuses_a_bad_scene_before_it_touches_the_output() {
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        max_steps: Some(100),
        ..Default::default()
    };
    run_cpu_with(&scene(), &opts, |_| {}).unwrap();
    let listing = |p: &std::path::Path| {
        let mut names: Vec<_> = std::fs::read_dir(p)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    };
    let before = listing(dir.path());
    let series = std::fs::read(dir.path().join("series.csv")).unwrap();
    let mut bad = scene();
    bad.output_every = 0;
    let e = run_cpu_with(&bad, &opts, |_| {}).unwrap_err().to_string();
    assert!(
        e.contains("`output_every` (steps between outputs") && e.contains("must be > 0, got 0"),
        "{e}"
    );
    assert_eq!(listing(dir.path()), before);
    assert_eq!(
        std::fs::read(dir.path().join("series.csv")).unwrap(),
        series
    );
}

#[test]
fn an_empty_sweep_is_empty() {
    use powder::measure::collide::{sweep, CollideSpec};
    let spec = CollideSpec::head_on(
        ContactModel::Hysteretic(HystereticParams::paper_figure()),
        1.1e-3,
        2000.0,
        1.0,
    );
    assert!(sweep(&spec, &[]).unwrap().is_empty());
}

#[test]
fn a_gpu_state_of_another_time_step_is_refused() {
    let Some(ctx) = common::gpu() else { return };
    let mut a = GpuEngine::new(&scene(), ctx).unwrap();
    a.run_steps(10).unwrap();
    let saved = a.save_state().unwrap();
    let mut s = scene();
    s.dt = DtSetting::Fixed(1e-7);
    let mut b = GpuEngine::new(&s, GpuContext::new().unwrap()).unwrap();
    let e = b.restore_state(saved).unwrap_err().to_string();
    assert!(e.contains("it was taken with another time step"), "{e}");
}

/// A comparison with a NaN tolerance (which every sample would pass) or no step is refused.
#[test]
fn a_comparison_needs_its_tolerances_and_a_step() {
    use powder::measure::compare::{compare, Tolerances};
    let Some(ctx) = common::gpu() else { return };
    let tol = Tolerances {
        kinetic: f64::NAN,
        ..Default::default()
    };
    let e = compare(&scene(), ctx, 10, 5, tol).unwrap_err().to_string();
    assert!(
        e.contains("the kinetic tolerance must be a number >= 0, got NaN"),
        "{e}"
    );
    let ctx = GpuContext::new().unwrap();
    let e = compare(&scene(), ctx, 0, 5, Tolerances::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least one step"), "{e}");
}
