//! The CPU engine's own tests: bits that must not depend on the list, the skin or a restore.

use super::pair_forces::BLOCK;
use super::*;
use crate::measure::bench::{packing, Case};
use crate::scene::WallPhase;

/// Steps `a` and `b` `steps` times: they must agree bitwise (positions, velocities,
/// spins, energies, contacts), with contacts.
fn same_bits(a: &mut CpuEngine, b: &mut CpuEngine, steps: u64) {
    for _ in 0..steps {
        a.step().unwrap();
        b.step().unwrap();
    }
    let bits = |v: &[DVec3]| v.iter().map(|p| p.to_array().map(f64::to_bits)).collect();
    let bits: fn(&[DVec3]) -> Vec<[u64; 3]> = bits;
    assert_eq!(bits(a.positions()), bits(b.positions()));
    assert_eq!(bits(a.velocities()), bits(b.velocities()));
    assert_eq!(bits(a.angular_velocities()), bits(b.angular_velocities()));
    assert_eq!(a.energies(), b.energies());
    assert_eq!(a.contacts(), b.contacts());
    assert!(!a.contacts().is_empty());
}

/// Runs `steps` steps with the default skin and without any (a rebuild every step):
/// the two runs must agree bitwise (the forces do not depend on the list beyond its
/// contacts), and the skinned one must rebuild less often.
fn same_without_skin(scene: &Scene, steps: u64) {
    let mut a = CpuEngine::new(scene).unwrap();
    let mut b = CpuEngine::new(scene).unwrap();
    assert!(a.skin > 0.0);
    b.skin = 0.0;
    same_bits(&mut a, &mut b, steps);
    assert!(b.rebuilds() > steps);
    eprintln!("rebuilds {} of {}", a.rebuilds(), b.rebuilds());
    assert!(a.rebuilds() > 2 && a.rebuilds() < b.rebuilds() / 2);
}

/// The pair loop that gauges a row's entries and solves JKR's roots ahead, a block at a
/// time, gives the bits of the loop that does not: JKR with friction and rolling, rows
/// longer than a block (a wide skin), contacts made and broken, closed and periodic.
#[test]
fn roots_solved_ahead_change_no_bit() {
    for periodic in [false, true] {
        let mut scene = packing(Case::Jkr, 512, 300.0, 6).unwrap();
        if periodic {
            scene.domain.periodic = [true, true, false];
            scene.walls.retain(|w| w.normal[2] != 0.0);
        }
        let mut a = CpuEngine::new(&scene).unwrap();
        let mut b = CpuEngine::new(&scene).unwrap();
        assert!(a.models.iter().any(ContactModel::solves_roots));
        b.roots_ahead = false;
        // a skin beyond the lattice's diagonal neighbours (and cells that hold it)
        let r = scene.particles[0].radius;
        for e in [&mut a, &mut b] {
            e.skin = 1.2 * r;
            let (lo, hi) = e.domain;
            e.grid = CellGrid::periodic(lo, hi, 4.0 * r, e.pos.len(), e.periodic).unwrap();
            e.rebuild_list();
        }
        same_bits(&mut a, &mut b, 2000);
        let rows = a.pairs.start.windows(2).map(|w| w[1] - w[0]);
        let longest = rows.max().unwrap();
        eprintln!(
            "periodic {periodic}: longest row {longest}, {} rebuilds",
            a.rebuilds()
        );
        assert!(longest > BLOCK && a.rebuilds() > 2);
    }
}

#[test]
fn results_do_not_depend_on_the_skin() {
    for (case, steps) in [(Case::Hysteretic, 3000), (Case::Jkr, 3000)] {
        let scene = packing(case, 343, 20.0, 3).unwrap();
        same_without_skin(&scene, steps);
    }
}

/// A side wall pushing in and then pulling back (the wall candidates follow it).
#[test]
fn results_do_not_depend_on_the_skin_moving_wall() {
    let mut scene = packing(Case::Hysteretic, 343, 1.0, 4).unwrap();
    let dt = CpuEngine::new(&scene).unwrap().dt();
    let wall = scene
        .walls
        .iter_mut()
        .find(|w| w.normal == [1.0, 0.0, 0.0])
        .unwrap();
    wall.motion = crate::scene::WallMotion {
        phases: vec![
            (0.0, WallPhase::Velocity([0.05, 0.0, 0.0])),
            (1500.0 * dt, WallPhase::Velocity([-0.1, 0.0, 0.0])),
        ],
    };
    same_without_skin(&scene, 3000);
}

#[test]
fn results_do_not_depend_on_the_skin_periodic_and_pouring() {
    let mut scene = packing(Case::Jkr, 512, 20.0, 5).unwrap();
    scene.domain.periodic = [true, true, false];
    // the side walls go: the box wraps along x and y
    scene.walls.retain(|w| w.normal[2] != 0.0);
    let dt = CpuEngine::new(&scene).unwrap().dt();
    for (k, p) in scene.particles.iter_mut().enumerate() {
        if k % 7 == 3 {
            p.insert_at = (k % 10 + 1) as f64 * 20.0 * dt;
            p.position[2] += 4.0 * p.radius;
        }
    }
    same_without_skin(&scene, 300);
}

/// A JKR packing with every seventh particle poured later, raised clear of the rest: at
/// steps 10 to 100 (`dt` its time step).
pub(crate) fn poured_packing() -> (Scene, f64) {
    let mut scene = packing(Case::Jkr, 64, 20.0, 5).unwrap();
    let dt = CpuEngine::new(&scene).unwrap().dt();
    for (k, p) in scene.particles.iter_mut().enumerate() {
        if k % 7 == 3 {
            p.insert_at = (k % 10 + 1) as f64 * 10.0 * dt;
            p.position[2] += 4.0 * p.radius;
        }
    }
    (scene, dt)
}

/// A state whose appeared flags do not fit the scene's pouring (an edited checkpoint) is
/// refused by particle, and the engine left as it was.
#[test]
fn a_state_whose_appearances_do_not_fit_the_pouring_is_refused() {
    let (scene, dt) = poured_packing();
    let mut a = CpuEngine::new(&scene).unwrap();
    a.run_steps(45).unwrap();
    let mut b = CpuEngine::new(&scene).unwrap();
    let early = (0..a.len())
        .find(|&i| scene.particles[i].insert_at > 50.0 * dt)
        .unwrap();
    let late = (0..a.len()).find(|&i| scene.particles[i].insert_at > 0.0 && a.is_active(i));
    let mut bad = a.state();
    bad.active[early] = true;
    let err = b.restore(bad).unwrap_err().to_string();
    assert!(
        err.contains(&format!("particle {early} appeared after 45 steps")),
        "{err}"
    );
    let mut bad = a.state();
    bad.active.iter_mut().for_each(|x| *x = false);
    let err = b.restore(bad).unwrap_err().to_string();
    assert!(
        err.contains("particle 0 not yet appeared after 45 steps"),
        "{err}"
    );
    let mut bad = a.state();
    bad.active[late.unwrap()] = false;
    assert!(b.restore(bad).is_err());
    assert_eq!(b.steps(), 0);
    b.restore(a.state()).unwrap();
    same_bits(&mut a, &mut b, 60);
}

/// A wall contact that leaves without a visit is booked once: the ledger closes. (Its
/// particle is taken off the wall candidates by hand: they hold every contact
/// otherwise, so only a particle the list no longer visits leaves this way.)
#[test]
fn a_wall_contact_left_unvisited_is_booked_once() {
    let scene = Scene::from_toml_str(
        r#"
[domain]
min = [-0.003, -0.003, -0.003]
max = [0.003, 0.003, 0.003]
[simulation]
duration = 0.1
[[material]]
name = "m"
density = 2000.0
model = "lsd"
k = 1000.0
gamma0 = 2e-3
[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[particles]]
kind = "list"
radius = 1e-3
positions = [[0.0, 0.0, 0.995e-3]]
"#,
        "pressed",
    )
    .unwrap();
    let mut e = CpuEngine::new(&scene).unwrap();
    // pressed 5 µm into the floor: the contact stores ½·k·δ²
    let before = e.energies();
    assert!(e.wall_contact_history(0, 0).is_some());
    assert!((before.elastic - 0.5 * 1000.0 * 25e-12).abs() < 1e-6 * before.elastic);
    e.wall_candidates.clear();
    e.wall_start.fill(0);
    let rebuilds = e.rebuilds();
    e.step().unwrap();
    assert_eq!(e.rebuilds(), rebuilds, "the list was rebuilt: no departure");
    assert!(e.wall_contact_history(0, 0).is_none());
    let after = e.energies();
    assert_eq!(after.elastic, 0.0);
    // off by the half kick's error only: k·dt²/(4m) of the stored energy
    let m = e.masses()[0];
    let bound = 1000.0 * e.dt() * e.dt() / (4.0 * m) * before.elastic;
    let imbalance = (after.total() - before.total()).abs();
    assert!(
        imbalance < 1.01 * bound && bound < 0.01 * before.elastic,
        "ledger {before:?} → {after:?}: off by {imbalance:e} (bound {bound:e})"
    );
}

/// A restored state continues bitwise, although the list is rebuilt at once.
#[test]
fn restore_continues_bitwise() {
    let scene = packing(Case::Jkr, 343, 20.0, 9).unwrap();
    let mut a = CpuEngine::new(&scene).unwrap();
    a.run_steps(150).unwrap();
    let mut b = CpuEngine::new(&scene).unwrap();
    b.restore(a.state()).unwrap();
    assert_eq!(a.contacts(), b.contacts());
    assert_eq!(a.energies(), b.energies());
    a.run_steps(150).unwrap();
    b.run_steps(150).unwrap();
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.energies(), b.energies());
    assert_eq!(a.contacts(), b.contacts());
    for (i, j) in [(0, 1), (0, 7), (5, 6)] {
        assert_eq!(a.contact_history(i, j), b.contact_history(i, j));
        assert_eq!(a.contact_history(j, i), b.contact_history(j, i));
    }
    assert_eq!(a.wall_contact_history(0, 0), b.wall_contact_history(0, 0));
    // a state whose contacts do not fit the scene is refused
    let mut bad = a.state();
    let repeated = bad.contacts[0];
    bad.contacts.push(repeated);
    assert!(b.restore(bad).is_err());
    let mut bad = a.state();
    bad.contacts[0].0 = (3, 3);
    assert!(b.restore(bad).is_err());
    let mut bad = a.state();
    bad.wall_contacts[0].0 = (99, 0);
    assert!(b.restore(bad).is_err());
    // every array its length, and a refused state leaves the engine as it was
    let before = b.state();
    for cut in [
        |s: &mut CpuState| s.force.truncate(1),
        |s: &mut CpuState| s.torque.clear(),
        |s: &mut CpuState| s.active.truncate(2),
        |s: &mut CpuState| s.wall_velocities.clear(),
    ] {
        let mut bad = a.state();
        cut(&mut bad);
        assert!(b.restore(bad).is_err());
        assert_eq!(b.positions(), before.pos.as_slice());
    }
    // a time that is not its steps of dt, and values that are not finite
    let mut bad = a.state();
    bad.time *= 2.0;
    let e = b.restore(bad).unwrap_err().to_string();
    assert!(e.contains("is not its 300 steps"), "{e}");
    let mut bad = a.state();
    bad.vel[4].y = f64::NAN;
    let e = b.restore(bad).unwrap_err().to_string();
    assert!(
        e.contains("velocities hold a value that is not finite at index 4"),
        "{e}"
    );
    let mut bad = a.state();
    bad.wall_work = f64::INFINITY;
    let e = b.restore(bad).unwrap_err().to_string();
    assert!(e.contains("wall work is inf"), "{e}");
    // (a contact's overlap, a wall contact's spring: the monitor found them only steps
    // later and blamed the time step)
    let mut bad = a.state();
    bad.contacts[0].1.delta = f64::NAN;
    let ((i, j), _) = bad.contacts[0];
    let e = b.restore(bad).unwrap_err().to_string();
    assert!(
        e.contains(&format!(
            "contact of particles ({i}, {j}) holds a value that is not finite"
        )),
        "{e}"
    );
    let mut bad = a.state();
    bad.wall_contacts[0].1.history.tangential.x = f64::INFINITY;
    assert!(b
        .restore(bad)
        .unwrap_err()
        .to_string()
        .contains("contact of wall and particle"));
    let mut bad = a.state();
    bad.vel.pop();
    let e = b.restore(bad).unwrap_err().to_string();
    assert!(e.contains("holds 343 positions, 342 velocities"), "{e}");
    assert_eq!(b.positions(), before.pos.as_slice());
}

#[test]
fn a_periodic_axis_too_short_is_named() {
    let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.003, 0.01]\nperiodic = [false, true, false]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\n[[particles]]\nkind = \"list\"\npositions = [[0.005, 0.0015, 0.005]]\nradius = 1e-3\n";
    let scene = Scene::from_toml_str(text, "t").unwrap();
    let e = CpuEngine::new(&scene).err().expect("refused").to_string();
    assert!(
        e.contains("3.0000e-3 m long along the periodic axis y"),
        "{e}"
    );
}

/// A spinning particle counts in the kinetic energy once it has appeared, not before (its
/// spin is booked as `inserted` then); a spin set by hand is booked too: the ledger closes.
#[test]
fn spin_counts_from_insertion_and_a_set_spin_is_booked() {
    let scene = Scene::from_toml_str(
        r#"
[domain]
min = [0.0, 0.0, 0.0]
max = [1e-3, 1e-3, 1e-3]
[simulation]
duration = 1.0
[[material]]
name = "m"
density = 2500.0
model = "jkr"
youngs = 1e8
poisson = 0.3
surface_energy = 0.0
friction = 0.3
[[particles]]
kind = "list"
radius = 1e-4
positions = [[5e-4, 5e-4, 5e-4]]
angular_velocity = [0.0, 0.0, 100.0]
insert_at = 1e-6
"#,
        "spin",
    )
    .unwrap();
    let mut e = CpuEngine::new(&scene).unwrap();
    assert!(!e.is_active(0));
    assert_eq!(e.energies().total(), 0.0, "{:?}", e.energies());
    while !e.is_active(0) {
        e.step().unwrap();
    }
    let spin = 0.5 * e.inertia[0] * 1e4;
    let after = e.energies();
    assert_eq!(after.kinetic, spin);
    assert_eq!(after.total(), 0.0, "{after:?}");
    e.set_angular_velocity(0, DVec3::new(0.0, 300.0, 0.0))
        .unwrap();
    assert!(
        e.energies().total().abs() < 1e-12 * spin,
        "{:?}",
        e.energies()
    );
    let bad = e.set_angular_velocity(0, DVec3::new(f64::NAN, 0.0, 0.0));
    assert!(bad.expect_err("NaN refused").to_string().contains("finite"));
}
