//! The rebuild chain on demand (`RebuildChain::OnDemand`: steps record only `decide_lean`,
//! which halts the batch where the lists must be rebuilt) against the chain in every step:
//! bitwise the same runs, with the batches halted once a rebuild.

mod common;
use common::{assert_same_run, gpu as context};
use powder::gpu::{GpuEngine, GpuOptions, RebuildChain};
use powder::measure::bench::{packing, Case};
use powder::scene::{Scene, WallMotion, WallPhase};

fn run(scene: &Scene, chain: RebuildChain, steps: u64) -> Option<GpuEngine> {
    let options = GpuOptions {
        rebuild_chain: chain,
        software_paths: Some(false),
        ..Default::default()
    };
    let mut e = GpuEngine::with_options(scene, context()?, options).unwrap();
    // (in two calls: a halted batch's rest is finished within each)
    e.run_steps(steps / 2).unwrap();
    e.run_steps(steps - steps / 2).unwrap();
    Some(e)
}

/// A hysteretic packing at 10× the bench's velocities (walls, the ledger; many rebuilds),
/// the same with its side wall pushed in at a prescribed speed (the walls' own rebuild
/// trigger), and a JKR packing with rotation.
#[test]
fn rebuilds_on_demand_give_the_bits_of_the_chain_in_every_step() {
    let hysteretic = packing(Case::Hysteretic, 600, 10.0, 3).unwrap();
    let mut pushed = hysteretic.clone();
    let w = pushed.walls.len() - 1;
    let n = pushed.walls[w].normal;
    pushed.walls[w].motion = WallMotion::always(WallPhase::Velocity(n.map(|c| 0.05 * c)));
    let scenes = [
        ("hysteretic packing", hysteretic, 400),
        ("hysteretic packing, a wall pushed in", pushed, 400),
        // (300× the bench's velocities: 0.6 m/s, a rebuild every few hundred steps)
        (
            "JKR packing",
            packing(Case::Jkr, 600, 300.0, 3).unwrap(),
            1200,
        ),
    ];
    for (name, scene, steps) in scenes {
        let Some(every) = run(&scene, RebuildChain::EveryStep, steps) else {
            return;
        };
        let on_demand = run(&scene, RebuildChain::OnDemand, steps).unwrap();
        let rebuilds = every.rebuilds().unwrap();
        eprintln!(
            "{name}: {rebuilds} rebuilds, {} batches halted for one",
            on_demand.rebuild_halts()
        );
        assert!(rebuilds > 2, "{name}: {rebuilds} rebuilds");
        assert_eq!(every.rebuild_halts(), 0, "{name}");
        // (a rebuild in a batch's first step halts nothing: a resumed batch starts full)
        assert!(on_demand.rebuild_halts() > 0, "{name}");
        assert!(on_demand.rebuild_halts() <= rebuilds, "{name}");
        assert_same_run(&every, &on_demand, name);
    }
}
