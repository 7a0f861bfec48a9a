//! The energy ledger: it closes on both backends (cohesive piles dropped onto a floor, with
//! and without Luding's friction), the GPU's stored and dissipated energy and contact
//! statistics follow the CPU's, it is an option on the GPU, and `compare` checks energies
//! and history.

mod common;
use common::backends::{backends, Backend};
use common::builder::MICRO;
use common::model_scene::{floor, particle, scene};
use common::{example, gpu as context, SceneBuilder};

use powder::cpu::CpuEngine;
use powder::gpu::{GpuEngine, GpuOptions};
use powder::measure::compare::{compare, Tolerances};
use powder::model::{ContactModel, CoulombSpring, HystereticParams, LudingFriction};
use powder::scene::Scene;

/// 36 spheres (r = 1 mm) in a 3 × 3 × 4 stack above a floor under gravity, of the
/// hysteretic law `p`; `sideways`: each layer shifted by 0.2 mm, the spheres thrown
/// sideways at up to 1 cm/s and spinning at ~30 rad/s, so they drop onto each other off
/// centre.
fn pile(p: HystereticParams, sideways: bool) -> Scene {
    let mut particles = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for l in 0..4 {
                let shift = if sideways { 2e-4 * l as f64 } else { 0.0 };
                let v = if sideways {
                    [0.01 * (j as f64 - 1.0), 0.01 * (i as f64 - 1.0), 0.0]
                } else {
                    [0.0; 3]
                };
                let mut s = particle(
                    [
                        -2.2e-3 + 2.2e-3 * i as f64 + shift,
                        -2.2e-3 + 2.2e-3 * j as f64,
                        1.5e-3 + 2.3e-3 * l as f64,
                    ],
                    v,
                );
                if sideways {
                    let k = particles.len() as f64;
                    s.angular_velocity = [20.0 * k.sin(), 20.0 * k.cos(), 30.0];
                }
                particles.push(s);
            }
        }
    }
    scene(ContactModel::Hysteretic(p), particles, vec![floor()], -9.81)
}

/// Drops `scene`'s pile for 40 000 steps on each backend: the ledger's total stays within
/// `tol` of the gravitational energy released (the integration error), something was
/// dissipated and the spheres touch; returns the runs for further checks.
fn pile_ledger_closes(scene: &Scene, tol: f64) -> Vec<Backend> {
    let mut runs = backends(scene);
    for b in &mut runs {
        let start = b.observe().energies.ledger().unwrap();
        b.run_steps(40_000);
        let o = b.observe();
        let end = o.energies.ledger().unwrap();
        let moved = (end.gravitational - start.gravitational).abs();
        let drift = end.total() - start.total();
        eprintln!("{}: drift {drift:e} of {moved:e} released", b.name());
        assert!(moved > 0.0 && end.dissipated > 0.0, "{}", b.name());
        assert!(
            drift.abs() < tol * moved,
            "{}: drift {drift} vs gravitational change {moved}",
            b.name()
        );
        assert!(o.contacts.unwrap().coordination > 1.0, "{}", b.name());
    }
    runs
}

/// A cohesive pile (adhesion fa with a range, damping) closes its ledger to 1e-4 of the
/// gravitational energy released, on both backends (measured 4.4e-6 on the CPU, 4.6e-6 on
/// the GPU; the frictional pile 1.7e-5 on both).
#[test]
fn cohesive_pile_keeps_its_energy_ledger() {
    let p = HystereticParams {
        fa: 2e-6,
        kca: 100.0,
        gamma0: 1e-3,
        ..HystereticParams::paper_figure()
    };
    pile_ledger_closes(&pile(p, false), 1e-4);
}

/// The ledger closes with Luding's sliding, rolling and twisting friction on (hysteretic
/// with adhesion and damping, μs > μd): the springs' energy is in the contacts' potential
/// and the couples' work is booked along ω_i − ω_j; on both backends.
#[test]
fn cohesive_frictional_pile_keeps_its_energy_ledger() {
    let spring = |mu: f64, mu_d: f64, k: f64, gamma: f64| CoulombSpring {
        mu_s: mu,
        mu_d,
        k,
        gamma,
    };
    let p = HystereticParams {
        fa: 2e-6,
        kca: 100.0,
        gamma0: 1e-3,
        luding: LudingFriction {
            sliding: spring(0.5, 0.4, 100.0 * 2.0 / 7.0, 1e-3 * 2.0 / 7.0),
            rolling: spring(0.1, 0.1, 40.0, 4e-4),
            twisting: spring(0.1, 0.1, 40.0, 4e-4),
        },
        ..HystereticParams::paper_figure()
    };
    for b in pile_ledger_closes(&pile(p, true), 1e-4) {
        // the friction acted: the spins are damped
        let o = b.observe();
        assert!(
            o.angular_velocities.iter().all(|w| w.length() < 20.0),
            "{}",
            b.name()
        );
        // and some contact keeps a stretched spring
        if let Backend::Cpu(e) = &b {
            assert!(e
                .contacts()
                .iter()
                .any(|(_, d, h)| *d > 0.0 && h.tangential.length() > 0.0 && h.twist != 0.0));
        }
    }
}

/// Adhesive micro-spheres with friction, rolling resistance and Tsuji damping thrown
/// onto a plate and into each other: every part of the JKR ledger (normal work across
/// the touch and pull-off jumps, tangential and rolling springs and their slip).
fn jkr_cluster() -> Scene {
    // two layers of 3 x 3 spheres (r = 5 µm) starting in contact (overlap 0.001 r, below
    // the equilibrium overlap δ0 = 0.003 r: bound by adhesion from the start) 0.01 r above
    // the plate, each with its own velocity (up to 0.1 m/s, with tangential parts)
    let (r, gap) = (5e-6, -5e-9);
    let (mut pos, mut vel) = (Vec::new(), Vec::new());
    for layer in 0..2 {
        for j in 0..3 {
            for i in 0..3 {
                let at = |k: i32| 1e-5 + k as f64 * (2.0 * r + gap);
                let z = r + 5e-8 + layer as f64 * (2.0 * r + gap);
                pos.push(format!("[{:e}, {:e}, {z:e}]", at(i), at(j)));
                let (vx, vy) = (0.03 * (1 - i) as f64, 0.02 * (j - 1) as f64);
                vel.push(format!(
                    "[{vx:e}, {vy:e}, {:e}]",
                    -0.1 + 0.04 * (i + j) as f64
                ));
            }
        }
    }
    SceneBuilder::new("jkr_cluster", [0.0; 3], [6e-5; 3], 1e-3)
        .simulation("impact_velocity", "0.2")
        .gravity()
        .material("micro", 2500.0, MICRO)
        .floor()
        .particles(
            "list",
            &format!(
                "radius = {r:e}\npositions = [{}]\nvelocities = [{}]",
                pos.join(", "),
                vel.join(", ")
            ),
        )
        .build()
}

/// Stored energy, dissipation and the contact statistics of the GPU follow the CPU's
/// while the trajectories agree, and the GPU's total energy is conserved as well as the
/// CPU's.
fn ledgers_agree(scene: &Scene, rounds: usize, steps: u64, energy_tol: f64) {
    let Some(ctx) = context() else { return };
    let mut cpu = CpuEngine::new(scene).unwrap();
    let mut gpu = GpuEngine::new(scene, ctx).unwrap();
    let total0 = cpu.energies().total();
    let mut last_dissipated = 0.0;
    for round in 0..rounds {
        cpu.run_steps(steps).unwrap();
        gpu.run_steps(steps).unwrap();
        let ec = cpu.energies();
        let eg = gpu.energies(&gpu.state().unwrap()).unwrap();
        let (sc, sg) = (cpu.contact_stats(), gpu.contact_stats().unwrap());
        eprintln!(
            "{} round {round}:\n  cpu {ec:?}\n  gpu {eg:?}\n  cpu {sc:?}\n  gpu {sg:?}",
            scene.name
        );
        let in_play = ec.kinetic + ec.elastic.abs() + ec.dissipated;
        for (what, c, g) in [
            ("kinetic", ec.kinetic, eg.kinetic),
            ("stored", ec.elastic, eg.elastic),
            ("dissipated", ec.dissipated, eg.dissipated),
        ] {
            assert!(
                (c - g).abs() <= energy_tol * in_play,
                "round {round}: {what} cpu {c:e} gpu {g:e} (energy in play {in_play:e})"
            );
        }
        // the ledger closes on the device too: kinetic + stored + gravitational +
        // dissipated stays at its start value to the integration error (CPU: same bound)
        for (who, e) in [("cpu", ec), ("gpu", eg)] {
            assert!(
                (e.total() - total0).abs() < 1e-2 * in_play.max(1e-300),
                "{who} round {round}: total {:e} vs {total0:e}",
                e.total()
            );
        }
        assert_eq!(sc.contacts, sg.contacts, "round {round}");
        assert_eq!(sc.wall_contacts, sg.wall_contacts, "round {round}");
        assert_eq!(sc.non_contact, sg.non_contact, "round {round}");
        if sc.contacts + sc.wall_contacts > 0 {
            let rel = (sc.max_overlap - sg.max_overlap).abs() / sc.max_overlap;
            assert!(rel < 1e-2, "round {round}: max overlap {rel:e}");
            let rel = (sc.mean_overlap_ratio - sg.mean_overlap_ratio).abs() / sc.mean_overlap_ratio;
            assert!(rel < 1e-2, "round {round}: mean overlap {rel:e}");
        }
        assert!(eg.dissipated >= last_dissipated - 1e-3 * in_play);
        last_dissipated = eg.dissipated;
        assert_eq!(gpu.dropped_contacts(), 0);
    }
    assert!(
        last_dissipated > 0.0,
        "nothing dissipated: the test saw no contact"
    );
}

#[test]
fn gpu_ledger_matches_the_cpu_in_the_cohesive_cluster() {
    // (contacts begin after ~4500 steps; trajectories agree to 2e-4 radii until 6000)
    ledgers_agree(&example("cohesive_cluster.toml"), 6, 1000, 1e-3);
}

#[test]
fn gpu_ledger_matches_the_cpu_for_jkr_with_friction_and_rolling() {
    ledgers_agree(&jkr_cluster(), 4, 500, 1e-3);
}

/// The ledger is an option: without it no ledger buffer is allocated, the kernels are the
/// ledger-free variant, the trajectory is bitwise the same, and asking for energies says why
/// there are none.
#[test]
fn gpu_without_ledger_allocates_none_and_moves_the_same() {
    let Some(ctx) = context() else { return };
    let Some(ctx2) = context() else { return };
    let scene = example("cohesive_cluster.toml");
    let mut with = GpuEngine::new(&scene, ctx).unwrap();
    let mut without = GpuEngine::with_options(
        &scene,
        ctx2,
        GpuOptions {
            ledger: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(with.has_ledger() && !without.has_ledger());
    // (`_mirrors`: the software adapter's path, which the tests' lavapipe takes)
    let m = if with.software_paths() {
        "_mirrors"
    } else {
        ""
    };
    // (`_jumps`: the cluster's jump-in adhesion has its force jumps placed by default)
    assert!(with.places_jumps() && without.places_jumps());
    assert_eq!(without.variant_name(), format!("step_hysteretic_jumps{m}"));
    assert_eq!(
        with.variant_name(),
        format!("step_hysteretic_ledger_jumps{m}")
    );
    assert!(without.buffers().iter().all(|(n, _)| !n.contains("ledger")));
    // (the ledger's rows: four fields of the particle state)
    assert!(with.state_fields().contains(&"ledger_energy"));
    assert!(!without.state_fields().contains(&"ledger_energy"));
    assert!(without.buffer_bytes() < with.buffer_bytes());
    with.run_steps(5000).unwrap();
    without.run_steps(5000).unwrap();
    let (a, b) = (with.state().unwrap(), without.state().unwrap());
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.velocities, b.velocities);
    let e = without.energies(&b).unwrap_err().to_string();
    assert!(e.contains("no energy ledger"), "{e}");
}

/// `compare` checks stored and dissipated energy and the contacts' history values.
#[test]
fn compare_reports_energies_and_history() {
    let Some(ctx) = context() else { return };
    let scene = jkr_cluster();
    let c = compare(&scene, ctx, 1500, 500, Tolerances::default()).unwrap();
    for s in &c.samples {
        eprintln!(
            "step {}: pos {:.2e} energy {:.2e} history {:.2e} (max {:.2e}) over {} pairs, {} missing, stored {:e}/{:e}, dissipated {:e}/{:e}",
            s.step, s.position, s.energy, s.history, s.history_max, s.history_pairs, s.history_missing,
            s.elastic_cpu, s.elastic_gpu, s.dissipated_cpu, s.dissipated_gpu
        );
    }
    assert!(c.passed, "{:?}", c.samples.last());
    let last = c.samples.last().unwrap();
    assert!(last.history_pairs > 0 && last.dissipated_cpu > 0.0);
    // the thresholds bite: a zero tolerance on the history fails where contacts exist
    let Some(ctx) = context() else { return };
    let strict = Tolerances {
        history: 0.0,
        ..Tolerances::default()
    };
    let c = compare(&scene, ctx, 1500, 500, strict).unwrap();
    assert!(!c.passed);
    assert!(c.samples.iter().any(|s| s.exceeded.contains(&"history")));
}
