//! The GPU engine's machinery against the CPU reference on lavapipe (CI) or any adapter: whole
//! scenes, bitwise determinism across batches, paths, windows and list growth. (Pair
//! collisions on the GPU: `collide_hysteretic.rs`, `collide_jkr.rs`.)

mod common;
use common::builder::COHESIVE;
use common::{example, gpu as context, max_distance, SceneBuilder};

use powder::cpu::CpuEngine;
use powder::gpu::GpuEngine;

#[test]
fn cohesive_cluster_matches_the_cpu_reference() {
    let Some(ctx) = context() else { return };
    let scene = example("cohesive_cluster.toml");
    let mut cpu = powder::cpu::CpuEngine::new(&scene).unwrap();
    let mut gpu = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(cpu.dt(), gpu.dt());
    // f32 on the device (Kahan-compensated velocity and offset updates) against f64: equal
    // to 1e-6 radii while the cloud falls, 1e-4 through the first collisions; later the
    // granular chaos amplifies the difference exponentially (measured 2.3e-7, 6.4e-7,
    // 2.3e-5, 3e-3 radii after 2000, 4000, 6000, 8000 steps; 9e-6, 4e-5, 2e-4, 5e-2
    // without the compensation)
    for round in 0..3 {
        cpu.run_steps(2000).unwrap();
        gpu.run_steps(2000).unwrap();
        let s = gpu.state().unwrap();
        let r = scene.particles[0].radius;
        let worst = max_distance(cpu.positions(), &s.positions);
        eprintln!(
            "round {round}: worst position difference {:.3e} radii",
            worst / r
        );
        assert!(
            worst < [1e-6, 1e-5, 1e-4][round] * r,
            "round {round}: {worst} m"
        );
    }
}

#[test]
fn settled_cluster_rebuilds_rarely_and_still_matches_the_cpu() {
    let Some(ctx) = context() else { return };
    let scene = example("cohesive_cluster.toml");
    let mut cpu = powder::cpu::CpuEngine::new(&scene).unwrap();
    let mut gpu = GpuEngine::new(&scene, ctx).unwrap();
    // the initial build, before the first step
    assert_eq!(gpu.rebuilds().unwrap(), 1);
    // while the cloud falls the lists are rebuilt often, yet not every step
    cpu.run_steps(2000).unwrap();
    gpu.run_steps(2000).unwrap();
    let falling = gpu.rebuilds().unwrap() - 1;
    eprintln!("falling: {falling} rebuilds in 2000 steps");
    assert!(falling > 0 && falling < 2000, "{falling}");
    let r = scene.particles[0].radius;
    let worst = |cpu: &CpuEngine, gpu: &GpuEngine| {
        max_distance(cpu.positions(), &gpu.state().unwrap().positions) / r
    };
    let w = worst(&cpu, &gpu);
    eprintln!("after 2000 steps: worst position difference {w:.3e} radii");
    assert!(w < 1e-4, "{w} radii");
    // late in its settling the heap barely moves: far fewer rebuilds than steps
    gpu.run_steps(28_000).unwrap();
    let before = gpu.rebuilds().unwrap();
    gpu.run_steps(5000).unwrap();
    let settled = gpu.rebuilds().unwrap() - before;
    eprintln!("settled: {settled} rebuilds in 5000 steps");
    assert!(settled < 5000 / 10, "{settled} rebuilds in 5000 steps");
    // the trajectories have long diverged (granular chaos), but the heap is the CPU's:
    // the same centre of mass and the same near-rest
    cpu.run_steps(33_000).unwrap();
    let s = gpu.state().unwrap();
    let centre = |p: &[glam::DVec3]| p.iter().copied().sum::<glam::DVec3>() / p.len() as f64;
    let (zc, zg) = (centre(cpu.positions()), centre(&s.positions));
    let kc: f64 = cpu
        .velocities()
        .iter()
        .zip(cpu.masses())
        .map(|(v, m)| 0.5 * m * v.length_squared())
        .sum();
    let kg = gpu.kinetic_energy(&s);
    eprintln!(
        "settled: centre of mass {:.3e} radii apart; kinetic energy {kc:.3e} J (CPU), {kg:.3e} J (GPU)",
        zc.distance(zg) / r
    );
    assert!(zc.distance(zg) < r, "{zc} {zg}");
    // (the peak is 1e-4 J while the cloud lands)
    assert!(kc < 1e-6 && kg < 1e-6, "{kc} {kg}");
}

#[test]
fn gpu_runs_are_bitwise_deterministic() {
    let Some(ctx) = context() else { return };
    let scene = example("cohesive_cluster.toml");
    let mut a = GpuEngine::new(&scene, ctx).unwrap();
    a.run_steps(1500).unwrap();
    let Some(ctx) = context() else { return };
    let mut b = GpuEngine::new(&scene, ctx).unwrap();
    b.run_steps(1500).unwrap();
    let (sa, sb) = (a.state().unwrap(), b.state().unwrap());
    common::assert_same_bits(&sa, &sb);
}

/// A particle may have any number of neighbours: in a clump of 5×5×5 spheres (pressed
/// together by 0.5 % of a radius) inside a
/// 4 mm non-contact adhesion range, the inner ones list over 100 partners, four times
/// the 24 a particle the capacity rule provides (an error before the lists were
/// compressed rows); 400 spheres far apart leave room in the total. It runs and follows
/// the CPU.
#[test]
fn crowded_particles_beyond_the_capacity_rule_run_and_match_the_cpu() {
    let Some(ctx) = context() else { return };
    let r = 1e-3;
    let mut positions = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..5 {
                let at = |c: i32| 0.006 + 1.995e-3 * c as f64;
                positions.push(format!("[{:e}, {:e}, {:e}]", at(i), at(j), at(k)));
            }
        }
    }
    for i in 0..20 {
        for j in 0..20 {
            let at = |c: i32| 0.03 + 8.5e-3 * c as f64;
            positions.push(format!("[{:e}, {:e}, 0.05]", at(i), at(j)));
        }
    }
    // adhesive with a range beyond the touch (fa, kca), no damping, no gravity
    let law = "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 100.0\nphi_f = 0.05\n\
               fa = 4e-4\nkca = 0.1";
    let scene = SceneBuilder::new("crowded", [0.0; 3], [0.2, 0.2, 0.1], 1.0)
        .simulation("gravity", "[0.0, 0.0, 0.0]")
        .material("m", 2000.0, law)
        .particles(
            "list",
            &format!("radius = {r:e}\npositions = [{}]", positions.join(", ")),
        )
        .build();
    let mut cpu = powder::cpu::CpuEngine::new(&scene).unwrap();
    let mut gpu = GpuEngine::new(&scene, ctx).unwrap();
    // the fixed bound of the engine's earlier slot lists, 5·(1 + r_max/r_min)²·(1 + skin/2)³
    // for equal spheres
    let cap = (5.0f64 * 4.0 * 1.05f64.powi(3)).ceil() as usize;
    // the centre of the clump (id 62) lists more partners than that
    let listed = gpu
        .contact_histories()
        .unwrap()
        .iter()
        .filter(|((i, _), _)| *i == 62)
        .count();
    eprintln!("particle 62 lists {listed} partners, capacity rule {cap}");
    assert!(listed > 2 * cap, "{listed} partners, capacity {cap}");
    cpu.run_steps(400).unwrap();
    gpu.run_steps(400).unwrap();
    let worst = max_distance(cpu.positions(), &gpu.state().unwrap().positions);
    let moved = cpu
        .positions()
        .iter()
        .zip(&scene.particles)
        .map(|(a, p)| a.distance(glam::DVec3::from_array(p.position)))
        .fold(0.0, f64::max);
    eprintln!(
        "moved {:.3e} radii, GPU − CPU {:.3e} radii",
        moved / r,
        worst / r
    );
    // (measured: moved 7.1e-4 radii, GPU − CPU 1.3e-10 radii)
    assert!(moved > 2e-4 * r, "the clump did not move: {moved} m");
    assert!(worst < 1e-7 * r, "{worst} m");
}

/// The compression example with its lid moving from the start (so lists grow while it
/// moves).
fn compression_lid_from_the_start() -> String {
    let text = std::fs::read_to_string(common::example_path("compression.toml")).unwrap();
    let early = text.replace(
        "times = [0.1, 0.3, 0.33, 0.36]",
        "times = [0.0, 0.04, 0.045, 0.05]",
    );
    assert_ne!(early, text);
    early
}

/// A wall contact takes room only where a particle is near the wall (a list entry, after
/// its pairs): 34 walls below the floor, never near a particle, add no bytes a particle
/// and change no bit of the compression with its moving lid — whose six walls now have the
/// indices 34 to 39, beyond the 32 the rebuild's candidate bits once covered.
#[test]
fn far_walls_take_no_room_and_change_no_bit() {
    use common::assert_same_bits;
    let text = compression_lid_from_the_start();
    let far: String = (0..34)
        .map(|i| {
            let z = -0.002 - 0.001 * i as f64;
            format!("[[wall]]\npoint = [0.0, 0.0, {z}]\nnormal = [0.0, 0.0, 1.0]\n\n")
        })
        .collect();
    let first_wall = text.find("[[wall]]").unwrap();
    let many = format!("{}{far}{}", &text[..first_wall], &text[first_wall..]);
    let scene = |t: &str| powder::scene::Scene::from_toml_str(t, "c").unwrap();
    let (six, forty) = (scene(&text), scene(&many));
    assert_eq!(forty.walls.len(), six.walls.len() + 34);
    let Some(ctx) = context() else { return };
    let mut a = GpuEngine::new(&six, ctx).unwrap();
    let mut b = GpuEngine::new(&forty, context().unwrap()).unwrap();
    a.run_steps(3000).unwrap();
    b.run_steps(3000).unwrap();
    assert_same_bits(&a.state().unwrap(), &b.state().unwrap());
    let (fa, fb) = (a.wall_forces().unwrap(), b.wall_forces().unwrap());
    assert!(
        fa.iter().any(|f| f.length() > 0.0),
        "no wall pressed: {fa:?}"
    );
    assert_eq!(fb[34..], fa[..], "the six walls' forces");
    assert!(fb[..34].iter().all(|f| *f == glam::DVec3::ZERO));
    // the same lists; only the walls' own records grow (the wall, its reference point, its
    // pair rows: bytes a wall, not a particle; a record per particle and wall, as before,
    // would add 34 · 144 · 20)
    assert_eq!(a.list_entries(), b.list_entries());
    let n = six.particles.len() as u64;
    let extra = b.buffer_bytes() - a.buffer_bytes();
    assert!(
        extra < 34 * 1024,
        "{extra} bytes more for 34 far walls ({n} particles)"
    );
}

/// The lists grow when a rebuild needs more room: the batch halts at that rebuild and
/// finishes after the growth. Runs that grow mid-run are bitwise the runs whose lists were
/// large from the start — the collapsing cohesive cluster, and the compression with its
/// prescribed lid (walls are written at batch boundaries, which a halt keeps) — and a state
/// saved with the large lists resumes bitwise in an engine with small ones.
#[test]
fn growing_lists_mid_run_change_no_bit() {
    use common::assert_same_bits;
    use powder::gpu::GpuOptions;
    // (the compression's lid moving from the start, so lists grow while it moves)
    let early = compression_lid_from_the_start();
    let scenes = [
        (
            "compression",
            powder::scene::Scene::from_toml_str(&early, "c").unwrap(),
            6000,
        ),
        ("cohesive cluster", example("cohesive_cluster.toml"), 20000),
    ];
    for (name, scene, steps) in scenes {
        let Some(ctx) = context() else { return };
        let n = scene.particles.len() as u64;
        // (from one entry: the first build grows them, the compaction again)
        let small = GpuOptions {
            list_entries: Some(1),
            ..Default::default()
        };
        let mut grown = GpuEngine::with_options(&scene, ctx, small).unwrap();
        let large = GpuOptions {
            list_entries: Some(40 * n),
            ..Default::default()
        };
        let mut fixed = GpuEngine::with_options(&scene, context().unwrap(), large).unwrap();
        let first = grown.list_entries();
        // a snapshot a quarter in, with the lists smaller than at the end
        let early = steps / 4;
        grown.run_steps(early).unwrap();
        let snapshot = grown.save_state().unwrap();
        let snapshot_entries = grown.list_entries();
        grown.run_steps(steps - early).unwrap();
        fixed.run_steps(steps).unwrap();
        eprintln!(
            "{name}: {} growths, {first} -> {} entries ({:.2} a particle)",
            grown.list_growths(),
            grown.list_entries(),
            grown.list_entries() as f64 / n as f64
        );
        assert_eq!(fixed.list_growths(), 0, "{name}");
        assert!(grown.list_growths() >= 2, "{name}: no growth mid-run");
        let (a, b) = (grown.state().unwrap(), fixed.state().unwrap());
        assert_same_bits(&a, &b);
        assert_eq!(
            grown.energies(&a).unwrap().dissipated.to_bits(),
            fixed.energies(&b).unwrap().dissipated.to_bits(),
            "{name}"
        );
        assert_eq!(
            grown.rebuilds().unwrap(),
            fixed.rebuilds().unwrap(),
            "{name}"
        );
        assert_eq!(grown.time().to_bits(), fixed.time().to_bits(), "{name}");
        // back to the snapshot, whose lists are smaller than the grown ones, and on
        // again: the same run (no halt for counts the snapshot does not hold)
        assert!(
            grown.list_entries() > snapshot_entries,
            "{name}: no growth after the snapshot"
        );
        grown.restore_state(snapshot).unwrap();
        assert_eq!(grown.list_entries(), snapshot_entries);
        grown.run_steps(steps - early).unwrap();
        assert_same_bits(&grown.state().unwrap(), &fixed.state().unwrap());
        assert_eq!(
            grown.rebuilds().unwrap(),
            fixed.rebuilds().unwrap(),
            "{name}"
        );
        let mut resumed = GpuEngine::new(&scene, context().unwrap()).unwrap();
        resumed.restore_state(fixed.save_state().unwrap()).unwrap();
        assert_eq!(resumed.list_entries(), 40 * n);
        resumed.run_steps(500).unwrap();
        fixed.run_steps(500).unwrap();
        assert_same_bits(&resumed.state().unwrap(), &fixed.state().unwrap());
    }
}

/// Where the batches end changes no bit: a run stepped in one call and the same run stepped
/// seven steps at a time (so every submission ends elsewhere: a batch's first step drifts
/// with `kick_drift`, the others with `collect_kick_drift`) agree to the bit. A compiler may
/// fuse a multiply and an add (WGSL allows it; NVIDIA's does), and differently in the two
/// kernels: the kick and drift products pass through `opaque` so both round them the same.
#[test]
fn batch_boundaries_change_no_bit() {
    use common::assert_same_bits;
    use powder::measure::bench::{packing, Case};
    let early = compression_lid_from_the_start();
    let scenes = [
        (
            "compression",
            powder::scene::Scene::from_toml_str(&early, "c").unwrap(),
            1500,
        ),
        // (rotation: rolling resistance and friction)
        (
            "JKR packing",
            packing(Case::Jkr, 600, 1.0, 3).unwrap(),
            1500,
        ),
        ("cohesive cluster", example("cohesive_cluster.toml"), 3000),
    ];
    for (name, scene, steps) in scenes {
        let Some(ctx) = context() else { return };
        let mut whole = GpuEngine::new(&scene, ctx).unwrap();
        let mut pieces = GpuEngine::new(&scene, context().unwrap()).unwrap();
        whole.run_steps(steps).unwrap();
        let mut done = 0;
        while done < steps {
            let k = 7.min(steps - done);
            pieces.run_steps(k).unwrap();
            done += k;
        }
        let (a, b) = (whole.state().unwrap(), pieces.state().unwrap());
        assert!(a.positions.iter().all(|p| p.is_finite()), "{name}");
        assert_same_bits(&a, &b);
        let bits = |v: &[glam::DVec3]| {
            v.iter()
                .flat_map(|w| w.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            bits(&a.angular_velocities),
            bits(&b.angular_velocities),
            "{name}"
        );
        assert_eq!(
            whole.rebuilds().unwrap(),
            pieces.rebuilds().unwrap(),
            "{name}"
        );
    }
}

/// The pass profile's timestamps change no bit of a run: a run profiled from its middle
/// ends as one that was not, and the profile names the passes that ran; a context opened
/// without the timestamps refuses to profile.
#[test]
fn a_profiled_run_changes_no_bit() {
    use common::assert_same_bits;
    use powder::measure::bench::{packing, Case};
    // (fast enough that the profiled steps rebuild the lists: the rebuild chain's passes
    // run with the timestamps between them)
    let scene = packing(Case::Jkr, 600, 30.0, 3).unwrap();
    let Some(ctx) = context() else { return };
    let mut plain = GpuEngine::new(&scene, ctx).unwrap();
    let ctx = powder::gpu::GpuContext::with_timestamps().unwrap();
    let mut profiled = GpuEngine::new(&scene, ctx).unwrap();
    plain.run_steps(300).unwrap();
    profiled.run_steps(100).unwrap();
    let profile = profiled.profile(200).unwrap();
    assert_same_bits(&plain.state().unwrap(), &profiled.state().unwrap());
    assert!(profile.rebuilds > 0, "no rebuild in the profiled steps");
    let names: Vec<&str> = profile.passes.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names.contains(&"force") && names.contains(&"kick"),
        "{names:?}"
    );
    assert!(profile.passes.iter().all(|(_, s)| *s >= 0.0));
    assert!(profile.device_seconds_per_step() > 0.0);
    // a context opened without the timestamps says so
    let err = plain.profile(1).unwrap_err().to_string();
    assert!(err.contains("with_timestamps"), "{err}");
}

/// The software adapter's paths (the state read through texture mirrors, quiet batches)
/// and the GPU's (the state's own buffers) give bitwise the same runs, with and without
/// rotation; the GPU path allocates neither mirrors nor quiet copies.
#[test]
fn software_and_gpu_paths_give_the_same_bits() {
    use common::assert_same_bits;
    use powder::gpu::GpuOptions;
    use powder::measure::bench::{packing, Case};
    let scenes = [("JKR packing", packing(Case::Jkr, 600, 1.0, 3).unwrap(), 600)];
    for (name, mut scene, steps) in scenes {
        let Some(ctx) = context() else { return };
        // the particles in a scrambled order, so the rebuilds' re-sorts move them
        let n = scene.particles.len();
        for i in 0..n {
            scene.particles.swap(i, (i * 7919 + 13) % n);
        }
        let path = |software| GpuOptions {
            software_paths: Some(software),
            ..Default::default()
        };
        let mut soft = GpuEngine::with_options(&scene, ctx, path(true)).unwrap();
        let mut hard = GpuEngine::with_options(&scene, context().unwrap(), path(false)).unwrap();
        assert!(soft.software_paths() && !hard.software_paths());
        assert!(soft.variant_name().ends_with("_mirrors"), "{name}");
        let names: Vec<String> = hard.buffers().into_iter().map(|(n, _)| n).collect();
        assert!(
            names
                .iter()
                .all(|n| !n.starts_with("mirror.") && !n.starts_with("quiet.")),
            "{name}: {names:?}"
        );
        assert!(hard.buffer_bytes() < soft.buffer_bytes());
        soft.run_steps(steps).unwrap();
        hard.run_steps(steps).unwrap();
        assert_same_bits(&soft.state().unwrap(), &hard.state().unwrap());
        let (a, b) = (soft.state().unwrap(), hard.state().unwrap());
        let bits = |v: &[glam::DVec3]| {
            v.iter()
                .map(|w| w.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            bits(&a.angular_velocities),
            bits(&b.angular_velocities),
            "{name}"
        );
    }
}

/// Windows (`gpu::window`: every array blocked by ranges of particles, the lists' entries
/// by window, each window's dispatches binding it and its neighbours only) change no bit:
/// positions, velocities, spins, the ledger, the contacts' history and the wall forces of
/// runs in windows of 64 (128) particles are those of one window, on scenes with moving and
/// servo-controlled walls, adhesion, rotation and list growth; a windowed state restores
/// into a windowed engine, not into another layout.
#[test]
fn windows_change_no_bit() {
    use common::assert_same_bits;
    use powder::gpu::GpuOptions;
    use powder::measure::bench::{packing, Case};
    let text = std::fs::read_to_string(common::example_path("compression.toml")).unwrap();
    let early = compression_lid_from_the_start();
    let servo = text.replace(
        "velocities = [[0.0, 0.0, -0.029], [0.0, 0.0, 0.029], [0.0, 0.0, -0.029], [0.0, 0.0, 0.029]]\ntimes = [0.1, 0.3, 0.33, 0.36]",
        "servo_force = 0.02\nservo_gain = 2.0\nservo_max_speed = 0.05",
    );
    // a servo side wall: its contacts span every window
    let side = text.replacen(
        "normal = [1.0, 0.0, 0.0]\n",
        "normal = [1.0, 0.0, 0.0]\nservo_force = 0.01\nservo_gain = 20.0\nservo_max_speed = 0.2\n",
        1,
    );
    assert!(servo != text && side != text);
    let toml = |t: &str| powder::scene::Scene::from_toml_str(t, "c").unwrap();
    let scenes = [
        ("compression", toml(&early), 3000, 64),
        ("servo compression", toml(&servo), 3000, 64),
        ("servo side wall", toml(&side), 3000, 64),
        // (its layers of cells hold about 70 particles)
        (
            "JKR packing",
            packing(Case::Jkr, 600, 1.0, 3).unwrap(),
            600,
            128,
        ),
    ];
    for (name, mut scene, steps, len) in scenes {
        let Some(ctx) = context() else { return };
        // scrambled, so the re-sorts move particles across windows
        let n = scene.particles.len();
        for i in 0..n {
            scene.particles.swap(i, (i * 7919 + 13) % n);
        }
        // (the windowed lists from one entry a window: they grow)
        let options = |window: Option<u64>| GpuOptions {
            software_paths: Some(false),
            window_particles: window,
            list_entries: window.map(|_| 1),
            ..Default::default()
        };
        let mut one = GpuEngine::with_options(&scene, ctx, options(None)).unwrap();
        let mut many =
            GpuEngine::with_options(&scene, context().unwrap(), options(Some(len))).unwrap();
        assert_eq!(one.windows().count, 1);
        assert_eq!(many.windows().count, (n as u64).div_ceil(len), "{name}");
        let half = steps / 2;
        one.run_steps(half).unwrap();
        many.run_steps(half).unwrap();
        let saved = many.save_state().unwrap();
        // another layout refuses it by name
        let mut other = GpuEngine::with_options(&scene, context().unwrap(), options(None)).unwrap();
        let refused = other.restore_state(saved.clone()).unwrap_err().to_string();
        assert!(
            refused.contains(&format!("windows of {len}")),
            "{name}: {refused}"
        );
        one.run_steps(steps - half).unwrap();
        many.run_steps(steps - half).unwrap();
        common::assert_same_run(&one, &many, name);
        // (the compressions' lists fit the first 64 entries a window)
        assert!(many.list_growths() >= 1 || !name.contains("JKR"), "{name}");
        let b = many.state().unwrap();
        // the windowed state resumes in a windowed engine bitwise
        let mut resumed =
            GpuEngine::with_options(&scene, context().unwrap(), options(Some(len))).unwrap();
        resumed.restore_state(saved).unwrap();
        resumed.run_steps(steps - half).unwrap();
        assert_same_bits(&resumed.state().unwrap(), &b);
        eprintln!(
            "{name}: {n} particles in {} windows, {} list entries (one window: {})",
            many.windows().count,
            many.list_entries(),
            one.list_entries()
        );
    }
}

/// Where a particle's neighbours lie beyond the windows its window's dispatches bind (a
/// flat bed of two layers of 289 particles: a particle's neighbours span a layer of cells
/// and more, beyond three windows of 64 or 128), the run is refused
/// at the lists' first build, before anything reads beyond a binding, with a message naming
/// the window size; windows that hold a layer run it.
#[test]
fn neighbours_beyond_the_windows_stop_the_run_with_a_message() {
    use powder::gpu::GpuOptions;
    let Some(ctx) = context() else { return };
    let scene = SceneBuilder::new("bed", [0.0; 3], [0.04, 0.04, 0.01], 0.01)
        .material("m", 2000.0, COHESIVE)
        .particles(
            "lattice",
            "min = [0.0012, 0.0012, 0.0012]\nmax = [0.0388, 0.0388, 0.007]\nradius = 1.0e-3\n\
             spacing = 2.2e-3",
        )
        .build();
    assert_eq!(scene.particles.len(), 578);
    let options = |len| GpuOptions {
        software_paths: Some(false),
        window_particles: Some(len),
        ..Default::default()
    };
    let err = GpuEngine::with_options(&scene, ctx, options(64))
        .err()
        .expect("refused")
        .to_string();
    assert!(err.contains("one window of 64 particles"), "{err}");
    let mut e = GpuEngine::with_options(&scene, context().unwrap(), options(256)).unwrap();
    e.run_steps(100).unwrap();
    assert_eq!(e.windows().count, 3);
}

/// Arrays over the adapter's storage binding limit are split over windows
/// (`gpu::window`, chosen by the engine): on a 75 kB binding limit a 1000-particle packing
/// (its state 80 kB) runs in windows of 128 particles and gives the bits of one window on
/// the adapter's own limits; where even a
/// window and its neighbours do not
/// fit a binding, the run is refused before it starts, naming the array.
#[test]
fn arrays_over_the_binding_limit_are_split_over_windows() {
    use powder::gpu::{GpuContext, GpuOptions};
    use powder::measure::bench::{packing, Case};
    if context().is_none() {
        return;
    }
    // (without the ledger and the force jumps: no per-contact prior)
    let scene = powder::scene::Scene {
        jump_impulses: Some(false),
        ..packing(Case::Hysteretic, 1000, 1.0, 7).unwrap()
    };
    let options = GpuOptions {
        ledger: false,
        software_paths: Some(false),
        ..Default::default()
    };
    let tiny = GpuContext::with_storage_binding_limit(8 * 1000).unwrap();
    let err = GpuEngine::with_options(&scene, tiny, options)
        .err()
        .expect("arrays over the binding limit are refused");
    let msg = err.to_string();
    assert!(msg.contains("storage binding limit of 8000 bytes"), "{msg}");
    let small = GpuContext::with_storage_binding_limit(75_000).unwrap();
    let mut split = GpuEngine::with_options(&scene, small, options).unwrap();
    let mut whole = GpuEngine::with_options(&scene, context().unwrap(), options).unwrap();
    assert_eq!(whole.windows().count, 1);
    assert_eq!((split.windows().len, split.windows().count), (128, 8));
    split.run_steps(300).unwrap();
    whole.run_steps(300).unwrap();
    common::assert_same_bits(&split.state().unwrap(), &whole.state().unwrap());
    assert!(split.buffers().iter().any(|(_, bytes)| *bytes > 75_000));
}

/// Lists that outgrow one binding at the first build (the first guess, two entries a
/// particle, fits; the JKR packing needs more) are windowed then: the engine builds again
/// in windows sized for what it measured, and runs bitwise as in one window. (The H200's
/// first run: JKR at 10⁷ needed 2.8 GB of lists in one 2 GiB binding and stopped.)
#[test]
fn lists_outgrowing_one_binding_at_the_start_are_windowed() {
    use powder::gpu::{GpuContext, GpuOptions};
    use powder::measure::bench::{packing, Case};
    if context().is_none() {
        return;
    }
    let scene = packing(Case::Jkr, 8000, 1.0, 3).unwrap();
    let options = GpuOptions {
        software_paths: Some(false),
        ..Default::default()
    };
    let mut whole = GpuEngine::with_options(&scene, context().unwrap(), options).unwrap();
    assert_eq!(whole.windows().count, 1);
    let entry_bytes = whole
        .buffers()
        .into_iter()
        .find(|(name, _)| name == "A.entries")
        .map(|(_, bytes)| bytes / whole.list_entries())
        .unwrap();
    let first_guess = entry_bytes * (2 * 8000 + 256);
    let needed = entry_bytes * whole.list_entries();
    let limit = 2_000_000;
    // (`needed` holds the growth's headroom, 1.25: the raw need is over the limit too)
    assert!(
        first_guess < limit && limit * 5 / 4 < needed,
        "{first_guess} {needed}"
    );
    let small = GpuContext::with_storage_binding_limit(limit).unwrap();
    let mut split = GpuEngine::with_options(&scene, small, options).unwrap();
    assert!(split.windows().count > 1, "{:?}", split.windows());
    split.run_steps(400).unwrap();
    whole.run_steps(400).unwrap();
    common::assert_same_bits(&split.state().unwrap(), &whole.state().unwrap());
    // asked-for windows are kept as asked: one window stops with a message saying so
    let one = GpuOptions {
        window_particles: Some(16384),
        ..options
    };
    let small = GpuContext::with_storage_binding_limit(limit).unwrap();
    let msg = GpuEngine::with_options(&scene, small, one)
        .err()
        .expect("one window of lists over the binding")
        .to_string();
    assert!(msg.contains("--window-particles"), "{msg}");
}

/// The force pass reads the particles' state from texture mirrors, `MIRROR_WIDTH` (4096)
/// particles a row: packings of two rows, the second partial, for both mirrored layouts
/// (the JKR case also mirrors the predicted angular velocity) follow the CPU reference.
/// A particle of the second row read from the wrong texel would feel garbage forces.
#[test]
fn state_mirrors_past_one_texture_row_match_the_cpu() {
    use powder::measure::bench::{packing, Case};
    for case in [Case::Hysteretic, Case::Jkr] {
        let Some(ctx) = context() else { return };
        let scene = packing(case, 4500, 1.0, 7).unwrap();
        let mut cpu = powder::cpu::CpuEngine::new(&scene).unwrap();
        let mut gpu = GpuEngine::with_options(
            &scene,
            ctx,
            powder::gpu::GpuOptions {
                ledger: false,
                ..Default::default()
            },
        )
        .unwrap();
        cpu.run_steps(60).unwrap();
        gpu.run_steps(60).unwrap();
        let s = gpu.state().unwrap();
        let r = scene.particles[0].radius;
        let moved = cpu
            .positions()
            .iter()
            .zip(&scene.particles)
            .map(|(a, p)| a.distance(glam::DVec3::from_array(p.position)))
            .fold(0.0, f64::max);
        let (worst, at) = cpu
            .positions()
            .iter()
            .zip(&s.positions)
            .map(|(a, b)| a.distance(*b))
            .enumerate()
            .fold((0.0, 0), |m, (i, d)| if d > m.0 { (d, i) } else { m });
        eprintln!(
            "{case:?}: worst difference {:.3e} radii (particle {at}), largest move {:.3e} radii",
            worst / r,
            moved / r
        );
        // the contacts act: the particles move well beyond the tolerance
        assert!(moved > 1e-4 * r, "{moved}");
        assert!(worst < 1e-5 * r, "{case:?}: particle {at} off by {worst} m");
    }
}

/// Where the lists' headroom (25 %) would take the entries past the adapter's storage
/// binding limit, they grow only as far as the limit (the rebuild's need fits): the run
/// goes on, bitwise the same.
#[test]
fn list_growth_stops_at_the_binding_limit() {
    use powder::gpu::{GpuContext, GpuOptions};
    use powder::measure::bench::{packing, Case};
    let Some(ctx) = context() else { return };
    // (without the ledger and the force jumps: no per-contact prior)
    let scene = powder::scene::Scene {
        jump_impulses: Some(false),
        ..packing(Case::Hysteretic, 1000, 1.0, 7).unwrap()
    };
    let options = GpuOptions {
        ledger: false,
        ..Default::default()
    };
    let mut free = GpuEngine::with_options(&scene, ctx, options).unwrap();
    free.run_steps(200).unwrap();
    let grown = free.list_entries();
    let per_entry: u64 = free.entry_fields().iter().map(|(_, b)| b).sum();
    // room for 90 % of the grown capacity: 1.125× the need, less than its 1.25×
    let limit = per_entry * grown * 9 / 10;
    let small = GpuContext::with_storage_binding_limit(limit).unwrap();
    let mut capped = GpuEngine::with_options(&scene, small, options).unwrap();
    capped.run_steps(200).unwrap();
    assert_eq!(capped.list_entries(), limit / per_entry);
    assert!(capped.list_entries() < grown);
    common::assert_same_bits(&free.state().unwrap(), &capped.state().unwrap());
}
