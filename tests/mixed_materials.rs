//! Scenes that mix the model families: hysteretic spheres and adhesive JKR spheres with
//! friction and rolling resistance in one box, whose ledger closes on both backends; and
//! mixes (JKR laws that differ per pair, Krijt's dissipation beside hysteretic pairs) on the
//! GPU against the CPU reference.

mod common;
use common::backends::backends;
use common::builder::{COHESIVE, HALF_COHESIVE, STICKY};
use common::{gpu, two_lattices};

use powder::gpu::GpuEngine;
use powder::measure::compare::{compare, Tolerances};
use powder::scene::Scene;

/// Hysteretic spheres below and spheres of the JKR-family law `upper` above, thrown down
/// onto them; hysteretic–JKR pairs and the floor use the hysteretic model.
fn plastic_under(upper: &str) -> Scene {
    two_lattices(
        |b| {
            b.material("plastic", 2000.0, COHESIVE)
                .material("sticky", 2000.0, upper)
                .interaction(["plastic", "sticky"], HALF_COHESIVE)
        },
        ["plastic", "sticky", "plastic"],
        2.1e-3,
        [0.0, 0.0, -0.3],
    )
}

/// The mixed scene: [`plastic_under`] JKR with friction, rolling resistance and Tsuji
/// damping.
fn mixed_scene() -> Scene {
    plastic_under(STICKY)
}

/// `scene` on the GPU against the CPU for `steps` steps, sampled every `every`: the
/// comparison passes with more than 5 contacts at the end (and, with `history`, some pair
/// keeping history).
fn matches_the_cpu(scene: &Scene, steps: u64, every: u64, history: bool) {
    let Some(ctx) = gpu() else { return };
    let c = compare(scene, ctx, steps, every, Tolerances::default()).unwrap();
    common::report(&c);
    let last = c.samples.last().unwrap();
    assert!(last.contacts_cpu > 5, "{last:?}");
    assert!(!history || last.history_pairs > 0, "{last:?}");
    assert!(c.passed, "{:?}", last);
}

/// The mixed scene's collapse (35 ms) on each backend: the energy ledger, which books each
/// family's contacts by its own law, closes to 1e-4 of the energy released (kinetic and
/// gravitational; measured 2.4e-6 on the CPU, 1.9e-6 on the GPU), most of it dissipated,
/// and the spheres form a contact network.
#[test]
fn a_mixed_scene_keeps_its_energy_ledger_on_both_backends() {
    const TOL: f64 = 1e-4;
    for mut b in backends(&mixed_scene()) {
        let start = b.observe().energies.ledger().unwrap();
        b.run_steps(6000);
        let o = b.observe();
        let end = o.energies.ledger().unwrap();
        let released = (end.gravitational - start.gravitational).abs() + start.kinetic;
        let drift = end.total() - start.total();
        let stats = o.contacts.unwrap();
        eprintln!(
            "{}: drift {drift:e} of {released:e} released, dissipated {:e}, {stats:?}",
            b.name(),
            end.dissipated
        );
        assert!(
            drift.abs() < TOL * released,
            "{}: drift {drift:e}",
            b.name()
        );
        assert!(end.dissipated > 0.5 * released, "{}", b.name());
        assert!(
            stats.coordination > 1.0 && stats.wall_contacts > 0,
            "{}",
            b.name()
        );
    }
}

#[test]
fn a_mixed_scene_runs_on_the_gpu_and_matches_the_cpu() {
    let scene = mixed_scene();
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(g.kind().name(), "step_hysteretic+jkr+mindlin+jkr_rolling");
    assert!(g.rotates());
    drop(g);
    // (7 ms of the collapse: the GPU and CPU drift apart like any chaotic pair of runs
    // beyond that; dt = 5.8e-6 s, the adhesive zone crossed at the adhesion speed)
    matches_the_cpu(&scene, 1200, 300, true);
}
/// Hertz with power-law damping and Mindlin friction.
const SMOOTH: &str = "model = \"hertz\"\nyoungs = 1e5\npoisson = 0.3\ndissipation = \"powerlaw\"\n\
     D = 1e-3\nalpha = 1.0\nbeta = 1.0\nfriction = 0.3";

/// Adhesive JKR between STICKY and SMOOTH, less adhesive and less damped than STICKY.
const BETWEEN: &str = "model = \"jkr\"\nyoungs = 1e5\npoisson = 0.3\nsurface_energy = 0.02\n\
     restitution = 0.6\nfriction = 0.3\nrolling_hysteresis = 0.5";

/// Adhesive JKR with Krijt's dissipation (the contact radius as per-contact state).
const KRIJT: &str = "model = \"jkr\"\nyoungs = 1e5\npoisson = 0.3\nsurface_energy = 0.05\n\
     dissipation = \"krijt\"\ntvis = 1e-5\nfriction = 0.3";

/// Two JKR-family materials whose pairs differ in dissipation law and adhesion (adhesive
/// JKR with Tsuji damping, Hertz with power-law damping, adhesive JKR between them): the
/// pipelines cannot fold either choice (`JKR_ONE_DISSIPATION`, `JKR_ADHESION` stay at
/// "decide per pair"), so this runs the per-pair branches, against the CPU.
#[test]
fn jkr_pairs_with_different_laws_match_the_cpu() {
    let scene = two_lattices(
        |b| {
            b.material("sticky", 2000.0, STICKY)
                .material("smooth", 2000.0, SMOOTH)
                .interaction(["sticky", "smooth"], BETWEEN)
        },
        ["smooth", "sticky", "sticky"],
        2.02e-3,
        [0.0, 0.0, -0.5],
    );
    matches_the_cpu(&scene, 12000, 2000, false);
}

/// A Krijt JKR material (its contact radius as per-contact state) above hysteretic spheres:
/// both laws and the Krijt sub-model composed into one step, against the CPU.
#[test]
fn krijt_pairs_beside_hysteretic_pairs_match_the_cpu() {
    let scene = plastic_under(KRIJT);
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(g.kind().name(), "step_hysteretic+jkr+krijt+mindlin");
    drop(g);
    // (7 ms of the collapse, as above)
    matches_the_cpu(&scene, 1200, 400, true);
}
