//! The contact network output: each engaged contact with its forces, overlap, history and
//! sliding state, the same from the GPU engine as from the f64 CPU reference, and written
//! by `powder run` with each snapshot (`contacts/<scene>_<step>.vtp` and its `.pvd`).

mod common;
use common::builder::{ROUGH, STICKY};
use common::{gpu, packing, rough};

use powder::cpu::{CpuEngine, Partner};
use powder::gpu::{GpuEngine, GpuOptions};
use powder::output::appended::read_array;
use powder::output::contacts::ContactNetwork;

fn key(c: &powder::output::contacts::ContactLine) -> (usize, i64) {
    match c.partner {
        Partner::Particle(j) => (c.i, j as i64),
        Partner::Wall(w) => (c.i, -1 - w as i64),
    }
}

/// (contacts, wall contacts, sliding, sliding on a wall)
fn summary(n: &ContactNetwork) -> [usize; 4] {
    let wall = |c: &&powder::output::contacts::ContactLine| matches!(c.partner, Partner::Wall(_));
    let walls = n.lines.iter().filter(wall).count();
    let sliding = n.lines.iter().filter(|c| c.sliding).count();
    let sliding_walls = n.lines.iter().filter(wall).filter(|c| c.sliding).count();
    [n.lines.len(), walls, sliding, sliding_walls]
}

/// Runs `scene` on both engines and compares their networks after each of `chunks` steps:
/// the same contacts (pairs by (i, j), then walls), touched and sliding flags, and forces
/// (relative to the largest, `tol[0]`), overlaps (`tol[1]`, m) and springs to f32 accuracy.
/// Returns the last sample's [`summary`] and the largest sideways floor force seen.
fn same_networks(
    scene: &powder::scene::Scene,
    chunks: &[u64],
    tol: [f64; 2],
) -> Option<([usize; 4], f64)> {
    let options = GpuOptions {
        ledger: false,
        contacts: true,
        ..Default::default()
    };
    let mut g = GpuEngine::with_options(scene, gpu()?, options).unwrap();
    // (with the ledger: the same trajectory, and the priors the ledger keeps)
    let mut ledger = GpuEngine::new(scene, gpu()?).unwrap();
    let mut c = CpuEngine::new(scene).unwrap();
    let mut last = [0; 4];
    let mut sideways = 0.0f64;
    for &steps in chunks {
        g.run_steps(steps).unwrap();
        ledger.run_steps(steps).unwrap();
        c.run_steps(steps).unwrap();
        let (gn, cn) = (g.contact_network().unwrap(), c.contact_network());
        assert_eq!(ledger.contact_network().unwrap(), gn);
        eprintln!("cpu {:?} gpu {:?}", summary(&cn), summary(&gn));
        assert_eq!(gn.fields, cn.fields);
        // f32 and f64 may disagree on a contact at the edge of a threshold (in range or
        // not, sliding or not): a few are allowed (none seen on lavapipe)
        let keys = |n: &ContactNetwork| n.lines.iter().map(key).collect::<Vec<_>>();
        let (gk, ck) = (keys(&gn), keys(&cn));
        let odd = gk.iter().filter(|k| !ck.contains(k)).count()
            + ck.iter().filter(|k| !gk.contains(k)).count();
        assert!(
            odd <= cn.lines.len() / 50,
            "{odd} contacts on one side only: {gk:?} vs {ck:?}"
        );
        let scale = cn
            .lines
            .iter()
            .map(|l| l.force.length())
            .fold(0.0, f64::max);
        let mut worst = [0.0f64; 5];
        let mut flags_differ = 0;
        for b in &cn.lines {
            let Some(a) = gn.lines.iter().find(|a| key(a) == key(b)) else {
                continue;
            };
            worst[0] = worst[0].max((a.normal_force - b.normal_force).abs() / scale);
            worst[1] = worst[1].max((a.force - b.force).length() / scale);
            worst[2] = worst[2].max((a.overlap - b.overlap).abs());
            worst[3] = worst[3].max((a.history.tangential - b.history.tangential).length());
            worst[4] = worst[4]
                .max((a.history.rolling - b.history.rolling).length())
                .max((a.history.twist - b.history.twist).abs());
            if a.sliding != b.sliding || a.history.touched != b.history.touched {
                flags_differ += 1;
            }
        }
        eprintln!("force scale {scale:e}: worst {worst:?}, {odd} odd contacts, {flags_differ} flags differ");
        assert!(
            flags_differ <= cn.lines.len() / 50,
            "{flags_differ} flags differ"
        );
        assert!(worst[0] < tol[0] && worst[1] < tol[0], "{worst:?}");
        assert!(
            worst[2] < tol[1] && worst[3] < 3e-8 && worst[4] < 3e-8,
            "{worst:?}"
        );
        last = summary(&cn);
        // the wall forces sum the same contacts, tangential parts included
        let (gw, cw) = (g.wall_forces().unwrap(), c.wall_forces());
        let off = (gw[0] - cw[0]).length() / cw[0].length().max(1e-300);
        eprintln!("floor force cpu {} gpu {} ({off:.1e})", cw[0], gw[0]);
        assert!(off < 1e-3, "{} vs {}", gw[0], cw[0]);
        sideways = sideways.max(cw[0].truncate().length());
    }
    Some((last, sideways))
}

/// What [`same_networks`] allows where the trajectories stay close (measured, 1 mm spheres:
/// up to 1.2e-4 of the largest force, 1.8e-9 m overlap, 8.4e-9 m springs).
const CLOSE: [f64; 2] = [1e-3, 1e-8];

/// Rough adhesive elasto-plastic spheres (Luding's sliding, rolling and twisting friction)
/// thrown onto a floor, with a low sliding coefficient so that some contacts slide: pairs
/// and wall contacts, sliding and sticking, in the compared networks.
#[test]
fn the_gpu_network_is_the_cpu_network_with_luding_friction() {
    let scene = |mu_d: &str| {
        let keys = ROUGH.replace(
            "friction = 0.5\nfriction_dynamic = 0.4",
            &format!("friction = 0.05\nfriction_dynamic = {mu_d}"),
        );
        assert_ne!(keys, ROUGH);
        packing(
            |b: common::SceneBuilder| b.material("rough", 2000.0, &keys),
            "rough",
        )
    };
    let Some((last, sideways)) = same_networks(&scene("0.05"), &[1500, 500, 400], CLOSE) else {
        return;
    };
    assert!(
        last[0] > 50 && last[1] > 5 && last[2] > 10 && last[2] < last[0] && last[3] > 0,
        "{last:?}"
    );
    // (friction pushes the floor sideways: the part only the tangential forces give)
    assert!(sideways > 1e-6, "{sideways}");
    // μs > μd: a slip stays at μd until the contact sticks, and any force between μd and μs
    // is stable, so a slip's onset decided by rounding lasts and the engines part sooner
    // (measured over these steps: 2.3e-3 of the largest force, 2.5e-8 m overlap, 1.5e-8 m
    // springs; the CPU perturbed by 1e-10 m a particle parts by 1.6e-4, with μs = μd by
    // 5e-5; by step 2400 the engines differ by 1.5e-2)
    let (last, _) = same_networks(&scene("0.04"), &[1000, 150, 150], [5e-3, 5e-8]).unwrap();
    assert!(last[0] > 30 && last[2] > 10, "{last:?}");
}

/// The same with JKR spheres, Mindlin friction (its own Coulomb limit) and rolling
/// resistance.
#[test]
fn the_gpu_network_is_the_cpu_network_with_jkr_friction() {
    // (STICKY with a low sliding coefficient)
    let slippery = STICKY.replace("friction = 0.3", "friction = 0.05");
    assert_ne!(slippery, STICKY);
    let jkr = |b: common::SceneBuilder| b.material("rough", 2000.0, &slippery);
    let Some((last, sideways)) = same_networks(&packing(jkr, "rough"), &[1500, 500, 400], CLOSE)
    else {
        return;
    };
    assert!(
        last[0] > 50 && last[1] > 5 && last[2] > 5 && last[2] < last[0],
        "{last:?}"
    );
    assert!(sideways > 1e-6, "{sideways}");
}

/// One data array of a contact network file, as f64.
fn array(doc: &[u8], name: &str) -> Vec<f64> {
    read_array(doc, name).unwrap_or_else(|| panic!("no array {name}"))
}

/// `powder run` writes the network with each snapshot and its collection; its contacts
/// in touch are the series' counts, the forces the engine's; `contact_output = false`
/// writes none.
#[test]
fn a_run_writes_the_network_with_each_snapshot() {
    use powder::run::{run_cpu_with, RunOptions};
    let mut scene = packing(rough, "rough");
    scene.output_every = 500;
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(dir.path().to_path_buf()),
        max_steps: Some(2000),
        ..Default::default()
    };
    assert!(run_cpu_with(&scene, &opts, |_| {}).unwrap().contact_network);
    let pvd = std::fs::read_to_string(dir.path().join("packing_contacts.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 5, "{pvd}");
    assert!(pvd.contains(r#"file="contacts/packing_0000002000.vtp""#));
    let doc = std::fs::read(dir.path().join("contacts/packing_0000002000.vtp")).unwrap();
    let csv = std::fs::read_to_string(dir.path().join("series.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
    let col = |name: &str| {
        last[header.iter().position(|h| *h == name).unwrap()]
            .parse::<usize>()
            .unwrap()
    };
    let (overlap, partner) = (array(&doc, "overlap"), array(&doc, "partner"));
    let touching = |wall: bool| {
        overlap
            .iter()
            .zip(&partner)
            .filter(|(d, p)| **d > 0.0 && (**p < 0.0) == wall)
            .count()
    };
    assert!(col("contacts") > 20, "{csv}");
    assert_eq!(touching(false), col("contacts"));
    assert_eq!(touching(true), col("wall_contacts"));
    // the lines are the engine's contacts, each force the one on particle i
    let mut engine = CpuEngine::new(&scene).unwrap();
    engine.run_steps(2000).unwrap();
    let net = engine.contact_network();
    let force = array(&doc, "force");
    assert_eq!(force.len(), 3 * net.lines.len());
    for (k, c) in net.lines.iter().enumerate() {
        assert_eq!(force[3 * k..3 * k + 3], c.force.to_array());
    }
    for name in [
        "normal_force",
        "sliding",
        "touched",
        "i",
        "delta_max",
        "tangential_spring",
        "rolling_displacement",
        "twist",
    ] {
        array(&doc, name);
    }
    // off: no folder, no collection
    scene.contact_output = Some(false);
    let off = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        out_dir: Some(off.path().to_path_buf()),
        max_steps: Some(500),
        ..Default::default()
    };
    assert!(!run_cpu_with(&scene, &opts, |_| {}).unwrap().contact_network);
    assert!(!off.path().join("contacts").exists());
    assert!(!off.path().join("packing_contacts.pvd").exists());
    assert!(off.path().join("packing.pvd").exists());
}
