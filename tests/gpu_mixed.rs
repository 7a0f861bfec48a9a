//! Scenes that mix the model families on the GPU: hysteretic spheres and adhesive JKR
//! spheres with friction and rolling resistance in one box, against the CPU reference.

mod common;
use common::{gpu, two_lattices};

use powder::gpu::GpuEngine;
use powder::measure::compare::{compare, Tolerances};
use powder::scene::Scene;

/// Hysteretic spheres below and JKR (friction, rolling resistance, Tsuji damping) above,
/// thrown down onto them; hysteretic–JKR pairs and the floor use the hysteretic model.
fn mixed_scene() -> Scene {
    two_lattices(
        r#"
[[material]]
name = "plastic"
density = 2000.0
model = "hysteretic"
k1 = 100.0
kp = 500.0
kc = 100.0
phi_f = 0.05
gamma0 = 1e-3
[[material]]
name = "sticky"
density = 2000.0
model = "jkr"
youngs = 1e5
poisson = 0.3
surface_energy = 0.05
restitution = 0.5
friction = 0.3
rolling_hysteresis = 0.5
[[interaction]]
materials = ["plastic", "sticky"]
model = "hysteretic"
k1 = 100.0
kp = 500.0
kc = 50.0
phi_f = 0.05
gamma0 = 1e-3
"#,
        ["plastic", "sticky", "plastic"],
        2.1e-3,
        [0.0, 0.0, -0.3],
    )
}

#[test]
fn a_mixed_scene_runs_on_the_gpu_and_matches_the_cpu() {
    let scene = mixed_scene();
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(g.kind().name(), "step_hysteretic+jkr+mindlin+jkr_rolling");
    assert!(g.rotates());
    drop(g);
    let Some(ctx) = gpu() else { return };
    // (7 ms of the collapse: the GPU and CPU drift apart like any chaotic pair of runs
    // beyond that; dt = 5.8e-6 s, the adhesive zone crossed at the adhesion speed)
    let c = compare(&scene, ctx, 1200, 300, Tolerances::default()).unwrap();
    for s in &c.samples {
        eprintln!(
            "step {}: pos {:.2e} vel {:.2e} energy {:.2e} contacts {}/{} history {:.2e} over {}",
            s.step,
            s.position,
            s.velocity,
            s.energy,
            s.contacts_cpu,
            s.contacts_gpu,
            s.history,
            s.history_pairs
        );
    }
    let last = c.samples.last().unwrap();
    assert!(last.contacts_cpu > 5 && last.history_pairs > 0, "{last:?}");
    assert!(c.passed, "{:?}", last);
}

/// Two JKR-family materials whose pairs differ in dissipation law and adhesion (adhesive
/// JKR with Tsuji damping, Hertz with power-law damping, adhesive JKR between them): the
/// pipelines cannot fold either choice (`JKR_ONE_DISSIPATION`, `JKR_ADHESION` stay at
/// "decide per pair"), so this runs the per-pair branches, against the CPU.
#[test]
fn jkr_pairs_with_different_laws_match_the_cpu() {
    let scene = two_lattices(
        r#"
[[material]]
name = "sticky"
density = 2000.0
model = "jkr"
youngs = 1e5
poisson = 0.3
surface_energy = 0.05
restitution = 0.5
friction = 0.3
rolling_hysteresis = 0.5
[[material]]
name = "smooth"
density = 2000.0
model = "hertz"
youngs = 1e5
poisson = 0.3
dissipation = "powerlaw"
D = 1e-3
alpha = 1.0
beta = 1.0
friction = 0.3
[[interaction]]
materials = ["sticky", "smooth"]
model = "jkr"
youngs = 1e5
poisson = 0.3
surface_energy = 0.02
restitution = 0.6
friction = 0.3
rolling_hysteresis = 0.5
"#,
        ["smooth", "sticky", "sticky"],
        2.02e-3,
        [0.0, 0.0, -0.5],
    );
    let Some(ctx) = gpu() else { return };
    let c = compare(&scene, ctx, 12000, 2000, Tolerances::default()).unwrap();
    let last = c.samples.last().unwrap();
    eprintln!("{last:?}");
    assert!(last.contacts_cpu > 5, "{last:?}");
    assert!(c.passed, "{:?}", last);
}

/// A Krijt JKR material (its contact radius as per-contact state) above hysteretic spheres:
/// both laws and the Krijt sub-model composed into one step, against the CPU.
#[test]
fn krijt_pairs_beside_hysteretic_pairs_match_the_cpu() {
    let scene = two_lattices(
        r#"
[[material]]
name = "plastic"
density = 2000.0
model = "hysteretic"
k1 = 100.0
kp = 500.0
kc = 100.0
phi_f = 0.05
gamma0 = 1e-3
[[material]]
name = "sticky"
density = 2000.0
model = "jkr"
youngs = 1e5
poisson = 0.3
surface_energy = 0.05
dissipation = "krijt"
tvis = 1e-5
friction = 0.3
[[interaction]]
materials = ["plastic", "sticky"]
model = "hysteretic"
k1 = 100.0
kp = 500.0
kc = 50.0
phi_f = 0.05
gamma0 = 1e-3
"#,
        ["plastic", "sticky", "plastic"],
        2.1e-3,
        [0.0, 0.0, -0.3],
    );
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(g.kind().name(), "step_hysteretic+jkr+krijt+mindlin");
    drop(g);
    let Some(ctx) = gpu() else { return };
    // (7 ms of the collapse, as above)
    let c = compare(&scene, ctx, 1200, 400, Tolerances::default()).unwrap();
    let last = c.samples.last().unwrap();
    eprintln!("{last:?}");
    assert!(last.contacts_cpu > 5 && last.history_pairs > 0, "{last:?}");
    assert!(c.passed, "{:?}", last);
}
