//! Pouring: particles inserted over time (`insert_at`, `batches`, `batch_interval`) on both
//! backends; the energy ledger books what they bring.

mod common;
use common::gpu;

use powder::cpu::CpuEngine;
use powder::gpu::GpuEngine;
use powder::scene::Scene;

/// 60 cohesive spheres poured in 4 batches, 40 ms apart, into the same region above a
/// floor: each batch is placed clear of itself only, because the earlier ones have fallen
/// out of the region by the time it appears (2.8 cm in 40 ms at 0.3 m/s and g).
fn pour_text(extra: &str) -> String {
    common::builder::SceneBuilder::new("pour", [0.0; 3], [0.012, 0.012, 0.03], 0.2)
        .periodic([true, true, false])
        .gravity()
        .material("powder", 2000.0, common::builder::COHESIVE)
        .floor()
        .particles(
            "random",
            &format!(
                "count = 60\nmin = [0.0, 0.0, 0.012]\nmax = [0.012, 0.012, 0.028]\n\
                 radius = 1.0e-3\nvelocity = [0.0, 0.0, -0.3]\nseed = 3\nbatches = 4\n\
                 batch_interval = 0.04\n{extra}"
            ),
        )
        .toml()
}

#[test]
fn batches_appear_on_time_and_the_ledger_books_them() {
    let scene = Scene::from_toml_str(&pour_text(""), "pour").unwrap();
    let times: Vec<f64> = scene.particles.iter().map(|p| p.insert_at).collect();
    for k in 0..4 {
        let n = times.iter().filter(|&&t| t == 0.04 * k as f64).count();
        assert_eq!(n, 15, "batch {k}");
    }
    let mut cpu = powder::cpu::CpuEngine::new(&scene).unwrap();
    let total0 = cpu.energies().total();
    let dt = cpu.dt();
    let active = |e: &CpuEngine| (0..e.len()).filter(|&i| e.is_active(i)).count();
    assert_eq!(active(&cpu), 15);
    let mut scale: f64 = 0.0;
    for k in 1..=5 {
        cpu.run_steps((0.04 / dt).round() as u64).unwrap();
        let e = cpu.energies();
        scale = scale.max(e.inserted.abs()).max(e.dissipated).max(e.kinetic);
        eprintln!("t {:.3}: {} active, {e:?}", cpu.time(), active(&cpu));
        // a batch appears at the start of the first step whose time has reached its time
        let due = times.iter().filter(|&&t| t <= cpu.time() - dt).count();
        assert_eq!(active(&cpu), due, "t {}", cpu.time());
        assert!(due >= (15 * k).min(60));
        // inactive particles do not move
        for i in (0..cpu.len()).filter(|&i| !cpu.is_active(i)) {
            assert_eq!(cpu.positions()[i].to_array(), scene.particles[i].position);
        }
        assert!(
            (e.total() - total0).abs() < 1e-3 * scale,
            "ledger: {:e} vs {total0:e} (scale {scale:e})",
            e.total()
        );
    }
    let e = cpu.energies();
    assert!(e.dissipated > 0.0 && e.inserted > 0.0, "{e:?}");
    // the GPU inserts at the same steps and keeps the same ledger
    let Some(ctx) = gpu() else { return };
    let mut c = powder::cpu::CpuEngine::new(&scene).unwrap();
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    let s0 = g.state().unwrap();
    // which particles have appeared: a word each where the scene pours, one where none does
    let active = |g: &GpuEngine| {
        g.buffers()
            .into_iter()
            .find(|(n, _)| n == "active")
            .unwrap()
            .1
    };
    assert_eq!(active(&g), 4 * scene.particles.len() as u64);
    // (the first batch alone: later batches share its places)
    let mut at_once = scene.clone();
    let first = scene.particles[0].insert_at;
    at_once.particles.retain(|p| p.insert_at == first);
    for p in &mut at_once.particles {
        p.insert_at = 0.0;
    }
    assert_eq!(
        active(&GpuEngine::new(&at_once, gpu().unwrap()).unwrap()),
        4
    );
    // (two samples before the second batch lands: once collisions chain up, f32 and f64
    // separate as in every granular flow)
    for _ in 0..2 {
        let n = (0.02 / dt).round() as u64;
        c.run_steps(n).unwrap();
        g.run_steps(n).unwrap();
        let s = g.state().unwrap();
        let worst = common::max_distance(c.positions(), &s.positions);
        let (ec, eg) = (c.energies(), g.energies(&s).unwrap());
        eprintln!(
            "t {:.3}: worst {worst:e} m; cpu {ec:?}; gpu {eg:?}",
            c.time()
        );
        // (with the Kahan-compensated updates: 7.2e-10 m after 0.02 s, 3.8e-9 m after the
        // first collisions at 0.04 s; 1.0e-6 and 4.2e-6 m without them, see `docs/architecture.md`)
        assert!(worst < 2e-8, "positions differ by {worst} m");
        assert!((ec.inserted - eg.inserted).abs() <= 1e-9 * ec.inserted.abs());
        assert!((ec.kinetic - eg.kinetic).abs() < 1e-5 * ec.kinetic);
    }
    // the second batch appears during the run (`appear` flags it in the device's state):
    // on both backends exactly those particles move, and the new batch falls alike
    let n = (0.01 / dt).round() as u64;
    c.run_steps(n).unwrap();
    g.run_steps(n).unwrap();
    let s = g.state().unwrap();
    assert_eq!((0..c.len()).filter(|&i| c.is_active(i)).count(), 30);
    for (i, p) in scene.particles.iter().enumerate() {
        let moved = s.positions[i] != s0.positions[i];
        assert_eq!(
            moved,
            c.is_active(i),
            "particle {i} (insert_at {})",
            p.insert_at
        );
        if p.insert_at == 0.04 {
            let d = (s.positions[i] - c.positions()[i]).length();
            assert!(d < 1e-8, "particle {i} of the second batch: {d:e} m apart");
        }
    }
}

/// A sphere at rest at the box's centre and one of the same radius 1 mm that appears at
/// `insert_at` s with its centre at x = `x` beside it (no gravity).
fn arrival(name: &str, x: f64, insert_at: &str) -> Scene {
    let r = 1.0e-3;
    let text = common::builder::SceneBuilder::new(name, [0.0; 3], [0.01, 0.01, 0.01], 0.002)
        .material("powder", 2000.0, common::builder::COHESIVE)
        .particles(
            "list",
            &format!("positions = [[0.005, 0.005, 0.005]]\nradius = {r}"),
        )
        .particles(
            "list",
            &format!("positions = [[{x}, 0.005, 0.005]]\nradius = {r}\ninsert_at = {insert_at}"),
        )
        .toml();
    Scene::from_toml_str(&text, name).unwrap()
}

/// A particle that appears next to one at rest interacts with it from the step it appears
/// in: the lists are rebuilt then (the GPU rebuilt them only once something had moved half
/// the skin, so a pair formed by an appearance waited, or never came, as here).
#[test]
fn a_particle_appearing_in_contact_is_pushed_from_its_first_step() {
    let r = 1.0e-3;
    let scene = arrival("appear", 0.005 + 1.99 * r, "2e-4");
    let mut cpu = CpuEngine::new(&scene).unwrap();
    let n = (4e-4 / cpu.dt()).round() as u64;
    cpu.run_steps(n).unwrap();
    let pushed = |x: &[glam::DVec3]| (x[1].x - x[0].x) - 1.99 * r;
    let moved = pushed(cpu.positions());
    assert!(moved > 1e-6 * r, "the CPU pair moved apart by {moved:e} m");
    let Some(ctx) = gpu() else { return };
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    g.run_steps(n).unwrap();
    let s = g.state().unwrap();
    let worst = common::max_distance(cpu.positions(), &s.positions);
    assert!(
        worst < 1e-3 * moved,
        "the GPU pair moved apart by {:e} m, the CPU's by {moved:e} m",
        pushed(&s.positions)
    );
}

/// A particle enters at the start of the first step k whose k·dt has reached its time, on
/// both backends: the CPU had compared the summed time, which rounds below 1000·dt after
/// 1000 steps of 1e-5 s, and inserted a step after the GPU (the reviewer's case).
#[test]
fn both_backends_insert_at_the_step_whose_start_reaches_the_time() {
    let r = 1.0e-3;
    let text = common::builder::SceneBuilder::new("late", [0.0; 3], [0.02, 0.02, 0.02], 0.0102)
        .simulation("dt", "1e-5")
        .material("powder", 2000.0, common::builder::COHESIVE)
        .particles(
            "list",
            &format!("positions = [[0.005, 0.005, 0.01]]\nradius = {r}"),
        )
        .particles(
            "list",
            &format!(
                "positions = [[0.015, 0.015, 0.01]]\nradius = {r}\ninsert_at = 0.01\n\
                 velocity = [0.0, 0.0, -1.0]"
            ),
        )
        .toml();
    let scene = Scene::from_toml_str(&text, "late").unwrap();
    let mut cpu = CpuEngine::new(&scene).unwrap();
    let first = (1..)
        .find(|&k: &u64| (k - 1) as f64 * 1e-5 >= 0.01)
        .unwrap();
    cpu.run_steps(first - 1).unwrap();
    assert!(!cpu.is_active(1), "active after {} steps", first - 1);
    cpu.run_steps(1).unwrap();
    assert!(cpu.is_active(1), "not active after {first} steps");
    cpu.run_steps(9).unwrap();
    let Some(ctx) = gpu() else { return };
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    g.run_steps(first + 9).unwrap();
    let d = (g.state().unwrap().positions[1] - cpu.positions()[1]).length();
    assert!(d < 1e-6 * r, "the poured particle {d:e} m apart");
}

/// A particle poured onto one still there stops the run at the step it appears in, with
/// that cause named (the engines do not push particles aside), on both backends; a
/// particle due a step later, though already where it will appear, is not named.
#[test]
fn a_particle_appearing_inside_another_is_named_as_the_cause() {
    use powder::run::{run_cpu_with, run_gpu_with, RunOptions};
    let r = 1.0e-3;
    let scene = |late: f64| {
        let text = common::builder::SceneBuilder::new("onto", [0.0; 3], [0.01, 0.01, 0.01], 0.002)
            .material("powder", 2000.0, common::builder::COHESIVE)
            .particles(
                "list",
                &format!("positions = [[0.005, 0.005, 0.005]]\nradius = {r}"),
            )
            .particles(
                "list",
                &format!(
                    "positions = [[0.0042, 0.005, 0.005]]\nradius = {r}\ninsert_at = {late:e}"
                ),
            )
            .particles(
                "list",
                &format!("positions = [[0.0058, 0.005, 0.005]]\nradius = {r}\ninsert_at = 2e-4"),
            )
            .toml();
        Scene::from_toml_str(&text, "onto").unwrap()
    };
    let dt = CpuEngine::new(&scene(1.0)).unwrap().dt();
    // (particle 2 appears at the start of the first step whose k·dt has reached 2e-4 s,
    // particle 1 at the next)
    let step = (1..).find(|&k| (k - 1) as f64 * dt >= 2e-4).unwrap();
    let scene = scene((step - 1) as f64 * dt + 0.3 * dt);
    let expected = format!(
        "step {step}: particle 2 appeared (insert_at = 2e-4 s) where something was already: particle 2 overlaps particle 0 by 1.200"
    );
    let cpu = run_cpu_with(&scene, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        cpu.starts_with(&expected) && cpu.contains("batch_interval"),
        "{cpu}"
    );
    let Some(ctx) = gpu() else { return };
    let on_gpu = run_gpu_with(&scene, ctx, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(on_gpu.starts_with(&expected), "{on_gpu}");
}

/// A particle that appears overlapping another by less than the limit brings the
/// overlap's stored energy unbooked: the energy check stops the run at that step and names
/// the particle, not the time step, on both backends.
#[test]
fn a_particle_appearing_with_a_small_overlap_is_named_when_the_energy_jumps() {
    use powder::run::{run_cpu_with, run_gpu_with, RunOptions};
    let scene = arrival("onto", 0.0067, "2e-4");
    let dt = CpuEngine::new(&scene).unwrap().dt();
    let step = (1..).find(|&k| (k - 1) as f64 * dt >= 2e-4).unwrap();
    let named = |e: String| {
        e.starts_with(&format!("step {step}: the total energy grew"))
            && e.contains("particle 1 appeared (insert_at = 2e-4 s) where something was already: particle 1 overlaps particle 0 by 0.300")
            && e.contains("unbooked")
    };
    let cpu = run_cpu_with(&scene, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(named(cpu.clone()), "{cpu}");
    let Some(ctx) = gpu() else { return };
    let on_gpu = run_gpu_with(&scene, ctx, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(named(on_gpu.clone()), "{on_gpu}");
}

/// An overlap beyond the limit names a partner that has appeared: a sphere driven through
/// the floor, where a particle due later already sits, overlaps the floor on both backends
/// (the GPU's partner search, from the positions, had named the particle not yet there).
#[test]
fn an_overlap_names_no_particle_that_has_not_appeared() {
    use powder::run::{run_cpu_with, run_gpu_with, RunOptions};
    let r = 1.0e-3;
    let text = common::builder::SceneBuilder::new("through", [0.0; 3], [0.01, 0.01, 0.01], 0.002)
        .material("powder", 2000.0, common::builder::COHESIVE)
        .floor()
        .particles(
            "list",
            &format!(
                "positions = [[0.005, 0.005, 0.0035]]\nradius = {r}\nvelocity = [0.0, 0.0, -30.0]"
            ),
        )
        .particles(
            "list",
            &format!("positions = [[0.005, 0.005, 0.0012]]\nradius = {r}\ninsert_at = 1e-3"),
        )
        .toml();
    let scene = Scene::from_toml_str(&text, "through").unwrap();
    let cpu = run_cpu_with(&scene, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(cpu.contains("particle 0 overlaps wall 0 by"), "{cpu}");
    let Some(ctx) = gpu() else { return };
    let on_gpu = run_gpu_with(&scene, ctx, &RunOptions::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(on_gpu.contains("particle 0 overlaps wall 0 by"), "{on_gpu}");
}

#[test]
fn bad_pours_are_refused() {
    let err = |t: String| Scene::from_toml_str(&t, "x").unwrap_err().to_string();
    let e = err(pour_text("").replace("batch_interval = 0.04", ""));
    assert!(e.contains("batch_interval"), "{e}");
    let e = err(pour_text("insert_at = -1.0"));
    assert!(e.contains("insert_at") && e.contains(">= 0"), "{e}");
}

/// The coordination counts the particles that have appeared (as the energies do): a
/// touching pair and a third particle still to come is 1, not 2/3. And both engines' clocks
/// are k·dt to the bit (the CPU's was a sum, 1e-11 off after 10⁶ steps).
#[test]
fn coordination_counts_the_particles_that_have_appeared() {
    let r = 1.0e-3;
    let text = common::builder::SceneBuilder::new("coord", [0.0; 3], [0.01, 0.01, 0.01], 0.002)
        .material("powder", 2000.0, common::builder::COHESIVE)
        .particles(
            "list",
            &format!("positions = [[0.004, 0.005, 0.005], [0.005995, 0.005, 0.005]]\nradius = {r}"),
        )
        .particles(
            "list",
            &format!("positions = [[0.005, 0.005, 0.008]]\nradius = {r}\ninsert_at = 1.0"),
        )
        .toml();
    let scene = Scene::from_toml_str(&text, "coord").unwrap();
    let mut cpu = CpuEngine::new(&scene).unwrap();
    cpu.run_steps(3).unwrap();
    let c = cpu.contact_stats();
    assert_eq!((c.contacts, c.wall_contacts), (1, 0));
    assert_eq!(c.coordination, 1.0);
    cpu.run_steps(9997).unwrap();
    assert_eq!(cpu.time().to_bits(), (10000.0 * cpu.dt()).to_bits());
    let Some(ctx) = gpu() else { return };
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    g.run_steps(3).unwrap();
    assert_eq!(g.contact_stats().unwrap().coordination, 1.0);
    g.run_steps(9997).unwrap();
    assert_eq!(g.time().to_bits(), cpu.time().to_bits());
}
