//! Periodic axes on both backends: pairs meet across a periodic face (minimum image),
//! particles wrap, and the GPU follows the CPU.

mod common;
use common::builder::SceneBuilder;
use common::gpu;

use powder::cpu::CpuEngine;
use powder::gpu::GpuEngine;
use powder::measure::compare::{compare, Tolerances};
use powder::model::analytic;
use powder::scene::Scene;

/// Two LSD spheres (r = 1 mm) 1 mm apart *through* the periodic x face of a 1 cm box,
/// flying toward it: they collide across the face with the closed-form restitution.
fn pair_text(extra: &str) -> String {
    let text = SceneBuilder::new("pair", [0.0; 3], [0.01, 0.01, 0.01], 0.01)
        .periodic([true, false, false])
        .material("m", 2000.0, "model = \"lsd\"\nk = 100.0\ngamma0 = 2e-3")
        .particles(
            "list",
            "radius = 1e-3\npositions = [[0.0015, 0.005, 0.005], [0.0085, 0.005, 0.005]]\n\
             velocities = [[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]",
        )
        .toml();
    format!("{text}{extra}\n")
}

#[test]
fn a_pair_collides_across_the_periodic_face() {
    let scene = Scene::from_toml_str(&pair_text(""), "pair").unwrap();
    let m = 2000.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-9;
    let e = analytic::lsd_restitution(100.0, 2e-3, 0.5 * m).unwrap();
    // each backend against the closed form
    for mut b in common::backends::backends(&scene) {
        b.run_steps((0.03 / b.dt()) as u64);
        let o = b.observe();
        let e_run = (o.velocities[0].x - o.velocities[1].x) / 0.2;
        let name = b.name();
        let x = [o.positions[0].x, o.positions[1].x];
        eprintln!("{name}: e = {e_run} (closed form {e}); x = {x:?}");
        assert!((e_run - e).abs() < 2e-3, "{name}: e {e_run} vs {e}");
        // they bounced back: each is again inside the box, on its own side
        assert!(x.iter().all(|x| (0.0..0.01).contains(x)), "{name}: {x:?}");
    }
}

/// A particle crossing a periodic face comes back through the opposite one, on both.
#[test]
fn particles_wrap_around() {
    let scene = Scene::from_toml_str(
        &pair_text("")
            .replace(
                "velocities = [[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]",
                "velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]",
            )
            .replace(
                "positions = [[0.0015, 0.005, 0.005], [0.0085, 0.005, 0.005]]",
                "positions = [[0.0015, 0.005, 0.005], [0.0055, 0.005, 0.005]]",
            )
            .replace(
                "[[particles]]",
                "[[particles]]\nvelocity = [-0.2, 0.0, 0.0]",
            )
            .replace("velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n", ""),
        "wrap",
    )
    .unwrap();
    let mut cpu = CpuEngine::new(&scene).unwrap();
    // 0.02 s at 0.2 m/s: 4 mm to the left, through x = 0
    let steps = (0.02 / cpu.dt()).round() as u64;
    cpu.run_steps(steps).unwrap();
    let x = cpu.positions()[0].x;
    let t = cpu.time();
    let expected = 0.0015 - 0.2 * t + 0.01;
    assert!(
        (x - expected).abs() < 1e-12,
        "cpu x {x}, expected {expected}"
    );
    let Some(ctx) = gpu() else { return };
    let mut g = GpuEngine::new(&scene, ctx).unwrap();
    g.run_steps(steps).unwrap();
    let xg = g.state().unwrap().positions[0].x;
    // (f32 offsets: the per-step move is rounded, 3.9e-8 m after 3500 steps measured)
    assert!(
        (xg - expected).abs() < 1e-7,
        "gpu x {xg}, expected {expected}"
    );
}

/// A cohesive cluster in a box periodic in x and y (floor, gravity along z): the GPU
/// follows the CPU while the particles cross the periodic faces and touch across them.
#[test]
fn a_periodic_cluster_matches_the_cpu() {
    let scene = common::builder::periodic_cluster();
    let Some(ctx) = gpu() else { return };
    // (trajectories agree to 1e-4 radii for 5000 steps; then granular chaos takes over)
    let c = compare(&scene, ctx, 5000, 1000, Tolerances::default()).unwrap();
    for s in &c.samples {
        eprintln!(
            "step {}: pos {:.2e} energy {:.2e} contacts {}/{} history {:.2e}",
            s.step, s.position, s.energy, s.contacts_cpu, s.contacts_gpu, s.history
        );
    }
    let last = c.samples.last().unwrap();
    assert!(last.contacts_cpu > 0, "no contacts formed");
    assert!(c.passed, "{:?}", c.samples);
}

#[test]
fn bad_periodic_scenes_are_refused() {
    let err = |t: String| Scene::from_toml_str(&t, "x").unwrap_err().to_string();
    let e = err(pair_text("").replace("[simulation]", "[simulation]\ngravity = [-9.81, 0.0, 0.0]"));
    assert!(
        e.contains("periodic axis x") && e.contains("gravity"),
        "{e}"
    );
    let e = err(pair_text(
        "[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]",
    ));
    assert!(e.contains("faces the periodic axis x"), "{e}");
    let e = err(pair_text("").replace(
        "periodic = [true, false, false]",
        "periodic = [true, 1, false]",
    ));
    assert!(e.contains("periodic"), "{e}");
    // too short for three cut-offs
    let short = pair_text("")
        .replace("max = [0.01, 0.01, 0.01]", "max = [0.005, 0.01, 0.01]")
        .replace(
            "positions = [[0.0015, 0.005, 0.005], [0.0085, 0.005, 0.005]]",
            "positions = [[0.0015, 0.005, 0.005], [0.0015, 0.0075, 0.005]]",
        );
    let scene = Scene::from_toml_str(&short, "short").unwrap();
    let e = CpuEngine::new(&scene).err().unwrap().to_string();
    assert!(e.contains("periodic"), "{e}");
    if let Some(ctx) = gpu() {
        let e = GpuEngine::new(&scene, ctx).err().unwrap().to_string();
        assert!(e.contains("periodic"), "{e}");
    }
}
