//! The rebuild chain on demand (`RebuildChain::OnDemand`: steps record only `decide_lean`,
//! which halts the batch where the lists must be rebuilt) against the chain in every step:
//! bitwise the same runs, with the batches halted once a rebuild while rebuilds are rare.

mod common;
use common::{assert_same_run, gpu as context};
use powder::gpu::{GpuEngine, GpuOptions, QuietBatches, RebuildChain};
use powder::measure::bench::{packing, Case};
use powder::scene::{Scene, WallMotion, WallPhase};

/// How the engine is set up besides the chain: the GPU's paths in one window, the software
/// adapter's (texture mirrors; quiet batches off, so every batch records its steps), or
/// windows of 256 particles.
#[derive(Clone, Copy, Debug)]
enum Setup {
    Gpu,
    Software,
    Windows,
}

fn run(scene: &Scene, chain: RebuildChain, setup: Setup, steps: u64) -> Option<GpuEngine> {
    let options = GpuOptions {
        rebuild_chain: chain,
        software_paths: Some(matches!(setup, Setup::Software)),
        quiet: QuietBatches::Off,
        window_particles: matches!(setup, Setup::Windows).then_some(256),
        ..Default::default()
    };
    let mut e = GpuEngine::with_options(scene, context()?, options).unwrap();
    // (in two calls: a halted batch's rest is finished within each)
    e.run_steps(steps / 2).unwrap();
    e.run_steps(steps - steps / 2).unwrap();
    Some(e)
}

/// `scene` with its last wall (a side wall) moving at `speed` m/s along its normal
/// (into the box where positive).
fn with_moving_wall(mut scene: Scene, speed: f64) -> Scene {
    let w = scene.walls.len() - 1;
    let n = scene.walls[w].normal;
    scene.walls[w].motion = WallMotion::always(WallPhase::Velocity(n.map(|c| speed * c)));
    scene
}

/// A hysteretic packing at 10× the bench's velocities (walls, the ledger; many rebuilds),
/// the same with its side wall pushed in at a prescribed speed (the walls' own rebuild
/// trigger), and a JKR packing with rotation; each in one window on the GPU's paths, on the
/// software adapter's (texture mirrors) and in windows.
#[test]
fn rebuilds_on_demand_give_the_bits_of_the_chain_in_every_step() {
    let hysteretic = packing(Case::Hysteretic, 600, 10.0, 3).unwrap();
    let scenes = [
        ("hysteretic packing", hysteretic.clone(), 400),
        (
            "hysteretic packing, a wall pushed in",
            with_moving_wall(hysteretic, 0.05),
            400,
        ),
        // (300× the bench's velocities: 0.6 m/s, a rebuild every 15 steps or so)
        (
            "JKR packing",
            packing(Case::Jkr, 600, 300.0, 3).unwrap(),
            1200,
        ),
    ];
    for (name, scene, steps) in scenes {
        for setup in [Setup::Gpu, Setup::Software, Setup::Windows] {
            let what = format!("{name} ({setup:?})");
            let Some(every) = run(&scene, RebuildChain::EveryStep, setup, steps) else {
                return;
            };
            let on_demand = run(&scene, RebuildChain::OnDemand, setup, steps).unwrap();
            let rebuilds = every.rebuilds().unwrap();
            eprintln!(
                "{what}: {rebuilds} rebuilds, {} batches halted for one",
                on_demand.rebuild_halts()
            );
            assert!(rebuilds > 2, "{what}: {rebuilds} rebuilds");
            assert_eq!(every.rebuild_halts(), 0, "{what}");
            // (a rebuild in a resumed batch's first step halts nothing)
            assert!(on_demand.rebuild_halts() > 0, "{what}");
            assert!(on_demand.rebuild_halts() <= rebuilds, "{what}");
            assert_same_run(&every, &on_demand, &what);
        }
    }
}

/// Where rebuilds come every few steps (a side wall drawn out fast: its move alone calls
/// for one), the steps record the rebuild's passes again after the first short lean
/// stretch, rather than halting a batch every few steps: few halts, the same bits.
#[test]
fn frequent_rebuilds_take_the_chain_in_every_step() {
    let scene = with_moving_wall(packing(Case::Hysteretic, 600, 1.0, 3).unwrap(), -5.0);
    let Some(every) = run(&scene, RebuildChain::EveryStep, Setup::Gpu, 400) else {
        return;
    };
    let on_demand = run(&scene, RebuildChain::OnDemand, Setup::Gpu, 400).unwrap();
    let (rebuilds, halts) = (every.rebuilds().unwrap(), on_demand.rebuild_halts());
    eprintln!("{rebuilds} rebuilds in 400 steps, {halts} batches halted for one");
    assert!(rebuilds > 100, "{rebuilds} rebuilds");
    assert!(halts <= 4, "{halts} halts");
    assert_same_run(&every, &on_demand, "a wall drawn out");
}
