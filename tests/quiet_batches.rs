//! Quiet batches (`gpu::quiet`): batches recorded without the per-step rebuild check are
//! kept only where no step needed a rebuild, and rolled back and run again with the check
//! otherwise, so a run is bitwise the same whichever way its batches ran.

mod common;
use common::{assert_same_bits, example, example_path, gpu as context};

use powder::gpu::{GpuEngine, GpuOptions, QuietBatches};
use powder::measure::bench::{packing, Case};

/// Runs `steps` steps of `case`'s bench packing (velocities scaled by `shake`: more
/// rebuilds) with the ledger and the given quiet mode; returns the engine.
fn run(case: Case, shake: f64, quiet: QuietBatches, steps: u64) -> Option<GpuEngine> {
    let ctx = context()?;
    let scene = packing(case, 1500, shake, 3).unwrap();
    let mut e = GpuEngine::with_options(
        &scene,
        ctx,
        GpuOptions {
            ledger: true,
            quiet,
            ..Default::default()
        },
    )
    .unwrap();
    e.run_steps(steps).unwrap();
    Some(e)
}

#[test]
fn quiet_batches_give_the_same_bits_kept_or_rolled_back() {
    for (case, shake, steps) in [(Case::Hysteretic, 2.0, 700), (Case::Jkr, 24.0, 700)] {
        let Some(off) = run(case, shake, QuietBatches::Off, steps) else {
            return;
        };
        let always = run(case, shake, QuietBatches::Always, steps).unwrap();
        let auto = run(case, shake, QuietBatches::Auto, steps).unwrap();
        let rebuilds = off.rebuilds().unwrap();
        eprintln!(
            "{case:?}: {rebuilds} rebuilds; quiet batches (kept, rolled back): always {:?}, auto {:?}",
            always.quiet_batches(),
            auto.quiet_batches()
        );
        assert_eq!(off.quiet_batches(), (0, 0));
        // the shaken packing rebuilds in some batches and not in others: both paths ran
        let (kept, back) = always.quiet_batches();
        assert!(
            kept > 0 && back > 0,
            "{case:?}: {kept} kept, {back} rolled back"
        );
        // `auto` runs quiet batches only on the software path, chosen by the adapter kind
        if auto.software_paths() {
            assert!(
                auto.quiet_batches().0 > 0,
                "{case:?}: {:?}",
                auto.quiet_batches()
            );
        } else {
            assert_eq!(auto.quiet_batches(), (0, 0), "{case:?}");
        }
        let reference = off.state().unwrap();
        for e in [&always, &auto] {
            assert_eq!(e.rebuilds().unwrap(), rebuilds);
            let s = e.state().unwrap();
            assert_same_bits(&s, &reference);
            assert_eq!(s.angular_velocities, reference.angular_velocities);
            // the ledger too: the rolled-back batches left nothing behind
            let (a, b) = (e.energies(&s).unwrap(), off.energies(&reference).unwrap());
            assert_eq!(a.elastic.to_bits(), b.elastic.to_bits(), "{case:?}");
            assert_eq!(a.dissipated.to_bits(), b.dissipated.to_bits(), "{case:?}");
            assert_eq!(
                e.contact_stats().unwrap().contacts,
                off.contact_stats().unwrap().contacts
            );
        }
    }
}

/// The packing example cut to a 8 × 8-site periodic column (832 spheres): the falling bed
/// first moves too little to rebuild in a batch, then too much, so `always` keeps some
/// batches and rolls others back, across the periodic faces; the same bits as `off`.
#[test]
fn quiet_batches_in_a_periodic_settling_bed() {
    let text = std::fs::read_to_string(example_path("packing.toml")).unwrap();
    // (set as `powder run --set` sets them, whatever the file's formatting: a text
    // replace would silently miss a reformatted line)
    let sets = [
        "domain.max=[0.0184, 0.0184, 0.04]",
        "particles[0].max=[0.0173, 0.0173, 0.03]",
    ];
    let scene =
        powder::scene::Scene::from_toml_str_with(&text, "column", &sets.map(String::from)).unwrap();
    assert!(scene.particles.len() > 500, "{}", scene.particles.len());
    let mut states = Vec::new();
    for quiet in [QuietBatches::Off, QuietBatches::Always] {
        let Some(ctx) = context() else { return };
        let options = GpuOptions {
            ledger: false,
            quiet,
            ..Default::default()
        };
        let mut e = GpuEngine::with_options(&scene, ctx, options).unwrap();
        e.run_steps(1600).unwrap();
        eprintln!(
            "{quiet:?}: {} rebuilds, quiet batches {:?}",
            e.rebuilds().unwrap(),
            e.quiet_batches()
        );
        if quiet == QuietBatches::Always {
            let (kept, back) = e.quiet_batches();
            assert!(kept > 0 && back > 0, "{kept} kept, {back} rolled back");
        }
        states.push((e.rebuilds().unwrap(), e.state().unwrap()));
    }
    assert_eq!(states[0].0, states[1].0);
    assert_same_bits(&states[0].1, &states[1].1);
}

/// Where walls move (their rebuild trigger is `decide`'s) or particles are poured in (an
/// insertion rebuilds), no batch runs quiet, even when asked to always.
#[test]
fn no_quiet_batches_with_moving_walls_or_pouring() {
    let mut poured = example("cohesive_cluster.toml");
    for (i, p) in poured.particles.iter_mut().enumerate() {
        p.insert_at = if i % 2 == 0 { 0.0 } else { 1e-3 };
    }
    for scene in [example("compression.toml"), poured] {
        let Some(ctx) = context() else { return };
        let options = GpuOptions {
            ledger: false,
            quiet: QuietBatches::Always,
            ..Default::default()
        };
        let mut e = GpuEngine::with_options(&scene, ctx, options).unwrap();
        e.run_steps(200).unwrap();
        assert_eq!(e.quiet_batches(), (0, 0));
    }
}
