//! Moving walls (prescribed velocity schedules and servo control) on both backends: the
//! wall follows its schedule, the servo holds its force, the energy ledger closes with the
//! walls' work, and the GPU follows the CPU.

mod common;
use common::builder::SceneBuilder;
use common::gpu;

use powder::cpu::CpuEngine;
use powder::gpu::GpuEngine;
use powder::scene::Scene;

/// A column of three damped hysteretic spheres (r = 1 mm) 0.1 µm apart from each other and the
/// floor, without gravity, under a lid 0.5 mm above the top one; `lid` is the lid's
/// motion keys.
fn column_text(lid: &str) -> String {
    SceneBuilder::new("column", [-0.003, -0.003, 0.0], [0.003, 0.003, 0.01], 0.2)
        .material(
            "m",
            2000.0,
            "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 100.0\nphi_f = 0.05\ngamma0 = 2e-3",
        )
        .floor()
        .wall_with([0.0, 0.0, 0.0065], [0.0, 0.0, -1.0], lid)
        .particles(
            "list",
            "radius = 1e-3\npositions = [[0.0, 0.0, 0.0010001], [0.0, 0.0, 0.0030002], [0.0, 0.0, 0.0050003]]",
        )
        .toml()
}

fn column(lid: &str) -> Scene {
    Scene::from_toml_str(&column_text(lid), "column").unwrap()
}

fn lid_force_z(f: &[glam::DVec3]) -> f64 {
    f[1].z
}

/// The lid comes down 1 mm at 1 cm/s, goes back up: the force on it rises while it
/// presses, turns tensile on the way back (the adhesive branch −kc·δ holds the top sphere)
/// and vanishes once it lets go; the ledger closes with the lid's work.
#[test]
fn a_prescribed_lid_loads_and_unloads_and_the_ledger_closes() {
    let scene = column("velocities = [[0.0, 0.0, -0.01], [0.0, 0.0, 0.01]]\ntimes = [0.0, 0.1]");
    let mut peak: f64 = 0.0;
    let mut wall_work: f64 = 0.0;
    for mut b in common::backends::backends(&scene) {
        let name = b.name();
        let dt = b.dt();
        let total0 = b.observe().energies.ledger().unwrap().total();
        let mut trace = Vec::new();
        for k in 1..=40 {
            b.run_steps((0.005 / dt).round() as u64);
            let o = b.observe();
            let t = k as f64 * (0.005 / dt).round() * dt;
            trace.push((
                t,
                o.wall_points[1].z,
                lid_force_z(o.wall_forces.as_deref().unwrap()),
            ));
        }
        // the lid follows its schedule exactly: down 1 mm by 0.1 s, back by 0.2 s
        for (t, z, _) in &trace {
            let expected = if *t <= 0.1 {
                0.0065 - 0.01 * t
            } else {
                0.0055 + 0.01 * (t - 0.1)
            };
            // (the switch falls within a step: down for up to one step too long, so up to
            // two steps of travel off after it)
            assert!(
                (z - expected).abs() < 0.01 * dt * 2.01,
                "{name}: t {t}: lid at {z}, expected {expected}"
            );
        }
        // (the force of the particles on a lid facing -z is +z while they push it)
        let push = trace.iter().map(|t| t.2).fold(0.0, f64::max);
        let pull = trace.iter().map(|t| t.2).fold(0.0, f64::min);
        eprintln!("lid ({name}): peak push {push:e} N, largest pull {pull:e} N");
        assert!(push > 0.01, "{name}: the lid never pressed: {push}");
        assert!(pull < 0.0, "{name}: no adhesive pull on unloading: {pull}");
        let e = b.observe().energies.ledger().unwrap();
        assert!(e.wall_work > 0.0 && e.dissipated > 0.0, "{name}: {e:?}");
        assert!(
            (e.total() - total0).abs() < 1e-3 * e.wall_work,
            "{name}: ledger: total {:e} vs {total0:e}, wall work {:e}",
            e.total(),
            e.wall_work
        );
        if name == "cpu" {
            (peak, wall_work) = (push, e.wall_work);
        }
    }

    // and the GPU follows the CPU: lid position, lid force, wall work and dissipation
    let Some(ctx) = gpu() else { return };
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    let mut c = CpuEngine::new(&scene).unwrap();
    let n = (0.025 / c.dt()).round() as u64;
    for _ in 0..8 {
        c.run_steps(n).unwrap();
        g.run_steps(n).unwrap();
        // (a prescribed wall's point is the host's f64 on both: the same bits; the GPU had
        // reported the device's f32 encoding, 2e-13 m off)
        let (wc, wg) = (c.walls_now()[1].0.z, g.walls_now().unwrap()[1].0.z);
        assert_eq!(
            wc.to_bits(),
            wg.to_bits(),
            "lid at {wc} (cpu) vs {wg} (gpu)"
        );
        let (fc, fg) = (
            lid_force_z(&c.wall_forces()),
            lid_force_z(&g.wall_forces().unwrap()),
        );
        eprintln!(
            "t {:.3}: lid {wc:.9e} / {wg:.9e}, force {fc:e} / {fg:e}, top sphere z {:e} / {:e}",
            c.time(),
            c.positions()[2].z,
            g.state().unwrap().positions[2].z
        );
        assert!(
            (fc - fg).abs() < 1e-3 * peak,
            "lid force {fc} (cpu) vs {fg} (gpu)"
        );
        let (ec, eg) = (c.energies(), g.energies(&g.state().unwrap()).unwrap());
        assert!(
            (ec.wall_work - eg.wall_work).abs() < 1e-3 * wall_work,
            "{ec:?} {eg:?}"
        );
        assert!(
            (ec.dissipated - eg.dissipated).abs() < 1e-3 * wall_work,
            "{ec:?} {eg:?}"
        );
    }
}

/// A servo-controlled lid holds its force: it comes down, presses the column and settles
/// at the target on both backends.
#[test]
fn a_servo_lid_holds_its_force() {
    let scene = column("servo_force = 0.02\nservo_gain = 2.0\nservo_max_speed = 0.02");
    for mut b in common::backends::backends(&scene) {
        let start = b.observe().energies.ledger().unwrap().total();
        b.run_steps((0.2 / b.dt()) as u64);
        let o = b.observe();
        let f = lid_force_z(o.wall_forces.as_deref().unwrap());
        let name = b.name();
        eprintln!(
            "servo lid ({name}): {f:e} N at z = {:e}",
            o.wall_points[1].z
        );
        assert!((f - 0.02).abs() < 1e-3 * 0.02, "{name}: servo force {f}");
        // the ledger closes with the lid's work
        let e = o.energies.ledger().unwrap();
        assert!(e.wall_work > 0.0, "{name}: {e:?}");
        assert!(
            (e.total() - start).abs() < 1e-3 * e.wall_work,
            "{name}: {e:?}"
        );
    }
}

/// Bad wall motions are refused with the reason.
#[test]
fn bad_wall_motions_are_refused() {
    let err = |lid: &str| {
        Scene::from_toml_str(&column_text(lid), "column")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_else(|| panic!("accepted: {lid}"))
    };
    let e = err("velocity = [0.0, 0.0, -0.01]\nservo_force = 1.0");
    assert!(e.contains("mixes kinds of motion"), "{e}");
    let e = err("velocities = [[0.0, 0.0, -0.01]]\ntimes = [0.0, 0.1]");
    assert!(
        e.contains("`times`") && e.contains("one start time per velocity"),
        "{e}"
    );
    let e = err("velocities = [[0.0, 0.0, -0.01], [0.0, 0.0, 0.01]]\ntimes = [0.1, 0.1]");
    assert!(e.contains("increase strictly"), "{e}");
    let e = err("velocities = [[0.0, 0.0, -0.01]]");
    assert!(e.contains("times"), "{e}");
    let e = err("servo_force = 1.0\nservo_gain = 0.1");
    assert!(e.contains("servo_max_speed"), "{e}");
    let e = err("servo_force = -1.0\nservo_gain = 0.1\nservo_max_speed = 0.01");
    assert!(e.contains("servo_force"), "{e}");
    // programs: one kind of motion a phase, increasing start times, no motion beside them
    let e = err("[[wall.phase]]\nfrom = 0.0\nvelocity = [0.0, 0.0, 0.01]\nservo_force = 1.0");
    assert!(e.contains("phase #1") && e.contains("mixes kinds"), "{e}");
    let e = err("[[wall.phase]]\nfrom = 0.1\n[[wall.phase]]\nfrom = 0.05");
    assert!(e.contains("increase strictly"), "{e}");
    let e = err("[[wall.phase]]\nvelocity = [0.0, 0.0, 0.01]");
    assert!(e.contains("`from`"), "{e}");
    let e = err("[[wall.phase]]\nfrom = 0.0\nservo_forse = 1.0");
    assert!(e.contains("servo_force"), "{e}");
    let e = err("velocity = [0.0, 0.0, 0.01]\n[[wall.phase]]\nfrom = 0.0");
    assert!(e.contains("mixes kinds of motion"), "{e}");
}

/// A lid run by a program of phases — servo at 0.02 N (sintering), servo at 0.002 N
/// (release), pulled up at 5 mm/s (the adhesive lid pulls the column), at rest — holds each
/// force, enters each servo phase at rest, pulls, stops, and the ledger closes; the GPU
/// follows the CPU, and a GPU run saved where a phase starts and restored elsewhere ends
/// in the same bits.
#[test]
fn a_lid_program_sinters_releases_pulls_and_stops() {
    let program = "[[wall.phase]]\nfrom = 0.0\nservo_force = 0.02\nservo_gain = 2.0\nservo_max_speed = 0.02\n\
                   [[wall.phase]]\nfrom = 0.1\nservo_force = 0.002\nservo_gain = 2.0\nservo_max_speed = 0.02\n\
                   [[wall.phase]]\nfrom = 0.15\nvelocity = [0.0, 0.0, 0.005]\n\
                   [[wall.phase]]\nfrom = 0.19";
    let scene = column(program);
    let mut cpu = CpuEngine::new(&scene).unwrap();
    let dt = cpu.dt();
    let total0 = cpu.energies().total();
    // steps that start before time t
    let before = |t: f64| (t / dt).ceil() as u64;
    cpu.run_steps(before(0.1)).unwrap();
    let sintered = lid_force_z(&cpu.wall_forces());
    assert!(
        (sintered - 0.02).abs() < 1e-3 * 0.02,
        "sintering force {sintered}"
    );
    // the release's servo phase starts at rest
    let z = cpu.walls_now()[1].0.z;
    cpu.run_steps(1).unwrap();
    assert_eq!(
        cpu.walls_now()[1].0.z,
        z,
        "the lid moved in a servo phase's first step"
    );
    cpu.run_steps(before(0.15) - before(0.1) - 1).unwrap();
    let released = lid_force_z(&cpu.wall_forces());
    assert!(
        (released - 0.002).abs() < 1e-3 * 0.002,
        "release force {released}"
    );
    // pulled up at the prescribed speed: the force turns tensile
    let z0 = cpu.walls_now()[1].0.z;
    let mut pull: f64 = 0.0;
    for _ in 0..8 {
        cpu.run_steps((before(0.19) - before(0.15)) / 8).unwrap();
        pull = pull.min(lid_force_z(&cpu.wall_forces()));
    }
    cpu.run_steps(before(0.19) - cpu.steps()).unwrap();
    let z1 = cpu.walls_now()[1].0.z;
    let travel = (before(0.19) - before(0.15)) as f64 * dt * 0.005;
    assert!(
        (z1 - z0 - travel).abs() < 1e-12,
        "pulled {:e}, expected {travel:e}",
        z1 - z0
    );
    assert!(pull < 0.0, "the adhesive lid never pulled: {pull}");
    eprintln!("lid program (cpu): {sintered:e} N, {released:e} N, pull {pull:e} N");
    // at rest from 0.19 s on
    cpu.run_steps(200).unwrap();
    assert_eq!(cpu.walls_now()[1].0.z, z1, "the lid moved at rest");
    let e = cpu.energies();
    assert!(
        (e.total() - total0).abs() < 1e-3 * e.wall_work.abs().max(e.dissipated),
        "ledger: {e:?} from {total0:e}"
    );

    let Some(ctx) = gpu() else { return };
    let mut c = CpuEngine::new(&scene).unwrap();
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    for t in [0.05, 0.1, 0.125, 0.15, 0.17, 0.19, 0.2] {
        c.run_steps(before(t) - c.steps()).unwrap();
        g.run_steps(before(t) - g.steps()).unwrap();
        let (wc, wg) = (c.walls_now()[1].0.z, g.walls_now().unwrap()[1].0.z);
        let (fc, fg) = (
            lid_force_z(&c.wall_forces()),
            lid_force_z(&g.wall_forces().unwrap()),
        );
        eprintln!("t {t}: lid {wc:.9e} / {wg:.9e}, force {fc:e} / {fg:e}");
        assert!(
            (wc - wg).abs() < 1e-8,
            "t {t}: lid at {wc} (cpu) vs {wg} (gpu)"
        );
        assert!(
            (fc - fg).abs() < 2e-3 * 0.02,
            "t {t}: lid force {fc} (cpu) vs {fg} (gpu)"
        );
    }
    // saved where the release starts (a batch ends at a switch), restored into another engine
    let mut a = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
    a.run_steps(before(0.1)).unwrap();
    let saved = a.save_state().unwrap();
    let mut b = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
    b.restore_state(saved).unwrap();
    let rest = before(0.17) - before(0.1);
    a.run_steps(rest).unwrap();
    b.run_steps(rest).unwrap();
    common::assert_same_bits(&a.state().unwrap(), &b.state().unwrap());
    assert_eq!(a.walls_now().unwrap(), b.walls_now().unwrap());
}

/// A phase starts at the step whose start k·dt first reaches it, on both backends and
/// wherever the GPU's batches begin: with dt = 1e-5 s and a switch at 0.00442 s (step 442,
/// where (t − dt)/dt rounds up past 441), a GPU run stepped once and then on switches at
/// the same step as one stepped at once, and as the CPU.
#[test]
fn a_phase_starts_at_the_same_step_wherever_batches_begin() {
    let text = column_text(
        "[[wall.phase]]\nfrom = 0.0\nvelocity = [0.0, 0.0, -0.01]\n[[wall.phase]]\nfrom = 0.00442\nvelocity = [0.0, 0.0, 0.01]",
    )
    .replace("duration = 0.2", "duration = 0.2\ndt = 1e-5");
    let scene = Scene::from_toml_str(&text, "column").unwrap();
    let dt = 1e-5;
    let down = (0u64..).find(|&k| k as f64 * dt >= 0.00442).unwrap();
    assert_eq!(down, 442);
    let steps = 600;
    let mut cpu = CpuEngine::new(&scene).unwrap();
    assert_eq!(cpu.dt(), dt);
    cpu.run_steps(steps).unwrap();
    let expected = 0.0065 - 0.01 * dt * down as f64 + 0.01 * dt * (steps - down) as f64;
    let z = cpu.walls_now()[1].0.z;
    assert!(
        (z - expected).abs() < 1e-15,
        "cpu lid at {z}, expected {expected}"
    );
    let Some(ctx) = gpu() else { return };
    let mut once = GpuEngine::new(&scene, ctx).unwrap();
    once.run_steps(steps).unwrap();
    let mut split = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
    split.run_steps(1).unwrap();
    split.run_steps(steps - 1).unwrap();
    assert_eq!(once.walls_now().unwrap(), split.walls_now().unwrap());
    common::assert_same_bits(&once.state().unwrap(), &split.state().unwrap());
    let zg = once.walls_now().unwrap()[1].0.z;
    assert!(
        (zg - expected).abs() < 1e-12,
        "gpu lid at {zg}, expected {expected}"
    );
}

/// A lid sliding along its face over frictional spheres while it presses them: the wall's
/// tangential work is in both engines' ledgers, which close, and the GPU's wall work
/// follows the CPU's (the GPU once booked the normal part only, and its run monitor
/// stopped such a run for "energy growth").
#[test]
fn a_lid_sliding_along_its_face_does_work_on_both_backends() {
    let text = r#"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.01, 0.01, 0.01]
[simulation]
duration = 0.01
output_every = 500
[[material]]
name = "m"
density = 2000.0
model = "lsd"
k = 100.0
gamma0 = 1e-3
friction = 0.5
[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[wall]]
point = [0.0, 0.0, 0.00685]
normal = [0.0, 0.0, -1.0]
velocity = [0.1, 0.0, -0.01]
[[particles]]
kind = "lattice"
min = [0.001, 0.001, 0.0]
max = [0.009, 0.009, 0.0073]
radius = 1e-3
spacing = 2.4e-3
"#;
    let scene = Scene::from_toml_str(text, "shear").unwrap();
    let opts = powder::run::RunOptions {
        max_steps: Some(3000),
        ..Default::default()
    };
    let cpu = powder::run::run_cpu_with(&scene, &opts, |_| {}).unwrap();
    let work = |s: &powder::run::RunSummary| s.last.energies.wall_work.unwrap();
    let w_cpu = work(&cpu);
    // the sliding does most of the work: far more than the normal push alone
    let pressed = Scene::from_toml_str(
        &text.replace(
            "velocity = [0.1, 0.0, -0.01]",
            "velocity = [0.0, 0.0, -0.01]",
        ),
        "pressed",
    )
    .unwrap();
    let w_normal = work(&powder::run::run_cpu_with(&pressed, &opts, |_| {}).unwrap());
    eprintln!("wall work: sliding and pressing {w_cpu:e} J, pressing only {w_normal:e} J");
    assert!(
        w_normal > 0.0 && w_cpu > 3.0 * w_normal,
        "{w_cpu:e} {w_normal:e}"
    );
    assert!(cpu.energy_balance_error.unwrap() < 1e-3, "{cpu:?}");
    let Some(ctx) = gpu() else { return };
    let g = powder::run::run_gpu_with(&scene, ctx, &opts, |_| {}).unwrap();
    let w_gpu = work(&g);
    assert!(
        (w_gpu - w_cpu).abs() < 1e-2 * w_cpu,
        "wall work: GPU {w_gpu:e}, CPU {w_cpu:e}"
    );
    assert!(g.energy_balance_error.unwrap() < 1e-2, "{g:?}");
}
