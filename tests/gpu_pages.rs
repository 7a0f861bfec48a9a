//! The lists' entries and the particle state in pages of whole windows (`gpu::pages`):
//! what lets them outgrow the adapter's largest buffer, bitwise the run in one buffer.

mod common;
use common::{assert_same_bits, gpu as context};
use powder::gpu::{GpuEngine, GpuOptions};
use powder::measure::bench::{packing, Case};

fn options(window: u64, first_entries: u64, page: Option<u64>) -> GpuOptions {
    GpuOptions {
        software_paths: Some(false),
        window_particles: Some(window),
        list_entries: Some(first_entries),
        entry_page_bytes: page,
        ..Default::default()
    }
}

/// The scene's particles scrambled, so the re-sorts move them across windows (and pages);
/// returns how many there are.
fn scramble(scene: &mut powder::scene::Scene) -> usize {
    let n = scene.particles.len();
    for i in 0..n {
        scene.particles.swap(i, (i * 7919 + 13) % n);
    }
    n
}

/// Bytes of one window's block of the larger of the particle state's two buffers.
fn state_block_bytes(engine: &GpuEngine) -> u64 {
    let largest = engine
        .buffers()
        .into_iter()
        .filter(|(n, _)| n == "A.state" || n == "A.motion")
        .map(|(_, b)| b)
        .max()
        .unwrap_or(0);
    largest / engine.windows().count
}

/// Bytes of one window's block of the entries.
fn block_bytes(engine: &GpuEngine) -> u64 {
    let record: u64 = engine.entry_fields().iter().map(|(_, b)| b).sum();
    record * engine.list_entries() / engine.windows().count
}

/// A hysteretic packing in a box (walls, the ledger, the force jumps; its lists grow from
/// one entry a window, so the entries go into pages at the first build and the step is
/// compiled again) and a JKR
/// packing with rotation (pages from the start): pages of three windows give the bits of
/// one buffer, and a paged checkpoint resumes bitwise in one buffer.
#[test]
fn entries_in_pages_change_no_bit() {
    let scenes = [
        (
            "hysteretic packing",
            packing(Case::Hysteretic, 1200, 1.0, 3).unwrap(),
            600,
            256,
            false,
        ),
        (
            "JKR packing",
            // (7 windows in pages of three: a middle page, a last page of one window)
            packing(Case::Jkr, 850, 1.0, 3).unwrap(),
            600,
            // (its layers of cells hold about 70 particles)
            128,
            true,
        ),
    ];
    for (name, mut scene, steps, len, paged_from_the_start) in scenes {
        let Some(ctx) = context() else { return };
        let n = scramble(&mut scene);
        let mut one = GpuEngine::with_options(&scene, ctx, options(len, 1, None)).unwrap();
        let half = steps / 2;
        one.run_steps(half).unwrap();
        let mid = one.state().unwrap();
        one.run_steps(steps - half).unwrap();
        assert!(!one.variant_name().ends_with("_paged"), "{name}");
        eprintln!(
            "{name}: {n} particles, {} windows, {} entries, {} rebuilds",
            one.windows().count,
            one.list_entries(),
            one.rebuilds().unwrap()
        );
        // pages of three windows at the final capacity
        let block = block_bytes(&one);
        let page = 3 * block + block / 2;
        let first = match paged_from_the_start {
            true => one.list_entries() / one.windows().count,
            false => 1,
        };
        let options = options(len, first, Some(page));
        let mut paged = GpuEngine::with_options(&scene, context().unwrap(), options).unwrap();
        // (from one entry a window the first build grows the lists into pages: the step
        // compiled again)
        assert!(paged.variant_name().ends_with("_paged"), "{name}");
        assert_eq!(paged.list_growths() > 0, !paged_from_the_start, "{name}");
        paged.run_steps(half).unwrap();
        assert_same_bits(&mid, &paged.state().unwrap());
        let saved = paged.save_state().unwrap();
        paged.run_steps(steps - half).unwrap();
        assert!(paged.variant_name().ends_with("_paged"), "{name}");
        let pages: Vec<String> = paged
            .buffers()
            .into_iter()
            .map(|(n, _)| n)
            .filter(|n| n.starts_with("A.entries"))
            .collect();
        assert!(
            pages.len() >= 2 && pages[1] == "A.entries[1]",
            "{name}: {pages:?}"
        );
        assert_eq!(paged.entry_pages().count, pages.len() as u64, "{name}");
        common::assert_same_run(&one, &paged, name);
        let b = paged.state().unwrap();
        // the paged state resumes in one buffer bitwise (the pages' bytes are its bytes)
        let mut resumed =
            GpuEngine::with_options(&scene, context().unwrap(), self::options(len, 1, None))
                .unwrap();
        resumed.restore_state(saved).unwrap();
        resumed.run_steps(steps - half).unwrap();
        assert_same_bits(&resumed.state().unwrap(), &b);
        eprintln!(
            "{name}: {n} particles in {} windows, {} pages of {page} bytes at most, {} list entries",
            paged.windows().count,
            pages.len(),
            paged.list_entries()
        );
    }
}

/// The particle state in pages of whole windows (`state` and `motion`,
/// `GpuOptions::state_page_bytes`), alone (hysteretic) and with the entries in pages too
/// (JKR with rotation: 7 windows, a middle page and a last page of one window), gives the
/// bits of one buffer; a checkpoint taken paged resumes bitwise in one buffer.
#[test]
fn state_in_pages_changes_no_bit() {
    let scenes = [
        // (10× the bench's velocities: the re-sorts move particles across pages)
        (
            "hysteretic packing",
            packing(Case::Hysteretic, 1200, 10.0, 3).unwrap(),
            256,
            false,
        ),
        (
            "JKR packing",
            packing(Case::Jkr, 850, 10.0, 3).unwrap(),
            128,
            true,
        ),
    ];
    let (steps, half) = (600, 300);
    for (name, mut scene, len, entries_too) in scenes {
        let Some(ctx) = context() else { return };
        let n = scramble(&mut scene);
        let mut one = GpuEngine::with_options(&scene, ctx, options(len, 1, None)).unwrap();
        one.run_steps(half).unwrap();
        let mid = one.state().unwrap();
        one.run_steps(steps - half).unwrap();
        let (windows, block) = (one.windows().count, state_block_bytes(&one));
        let entry_page = entries_too.then(|| 3 * block_bytes(&one) + block_bytes(&one) / 2);
        let first = one.list_entries() / windows;
        let options = GpuOptions {
            state_page_bytes: Some(3 * block + block / 2),
            ..options(len, first, entry_page)
        };
        let mut paged = GpuEngine::with_options(&scene, context().unwrap(), options).unwrap();
        assert!(paged.variant_name().ends_with("_paged"), "{name}");
        let pages = paged.state_pages();
        assert_eq!(
            (pages.windows, pages.count),
            (3, windows.div_ceil(3)),
            "{name}"
        );
        assert_eq!(paged.entry_pages().paged(), entries_too, "{name}");
        let names: Vec<String> = paged.buffers().into_iter().map(|(n, _)| n).collect();
        for b in ["A.state[1]", "A.motion[1]"] {
            assert!(names.iter().any(|n| n == b), "{name}: {names:?}");
        }
        paged.run_steps(half).unwrap();
        assert_same_bits(&mid, &paged.state().unwrap());
        let saved = paged.save_state().unwrap();
        paged.run_steps(steps - half).unwrap();
        common::assert_same_run(&one, &paged, name);
        let mut resumed =
            GpuEngine::with_options(&scene, context().unwrap(), self::options(len, 1, None))
                .unwrap();
        resumed.restore_state(saved).unwrap();
        resumed.run_steps(steps - half).unwrap();
        assert_same_bits(&resumed.state().unwrap(), &paged.state().unwrap());
        eprintln!(
            "{name}: {n} particles in {windows} windows, the state in {} pages",
            pages.count
        );
    }
}

/// Particles poured in batches appear in a paged state (`appear` writes each window's
/// page) bitwise as in one buffer: 400 cohesive spheres, a quarter each at 0, 1, 2 and
/// 3 ms, in 4 windows of 128, the state in pages of three; at 2.5 ms exactly the first
/// three quarters have moved.
#[test]
fn poured_particles_appear_in_pages() {
    use common::builder::{SceneBuilder, COHESIVE};
    let text = SceneBuilder::new("pour", [0.0; 3], [0.012, 0.012, 0.03], 0.2)
        .periodic([true, true, false])
        .gravity()
        .material("powder", 2000.0, COHESIVE)
        .floor()
        .particles(
            "random",
            "count = 400\nmin = [0.0, 0.0, 0.012]\nmax = [0.012, 0.012, 0.028]\n\
             radius = 0.5e-3\nvelocity = [0.0, 0.0, -0.3]\nseed = 3",
        )
        .toml();
    let mut scene = powder::scene::Scene::from_toml_str(&text, "pour").unwrap();
    // (placed clear of each other at once, so the batches need not fall apart first)
    for (i, p) in scene.particles.iter_mut().enumerate() {
        p.insert_at = 1e-3 * (i % 4) as f64;
    }
    let run = |paged: bool| {
        let options = |state_page| GpuOptions {
            state_page_bytes: state_page,
            ..options(128, 512, None)
        };
        let mut e = GpuEngine::with_options(&scene, context()?, options(None)).unwrap();
        if paged {
            let page = 3 * state_block_bytes(&e) + 100;
            e = GpuEngine::with_options(&scene, context()?, options(Some(page))).unwrap();
            assert_eq!(e.state_pages().count, 2);
        }
        // between the third batch's appearance and the last's: exactly the first three
        // batches have moved (in 4 windows: both runs could share a windowed bug)
        let start = e.state().unwrap();
        let steps = (2.5e-3 / e.dt()).round() as u64;
        e.run_steps(steps).unwrap();
        let now = e.state().unwrap();
        for (i, p) in scene.particles.iter().enumerate() {
            let moved = now.positions[i] != start.positions[i];
            assert_eq!(moved, p.insert_at < 2.5e-3, "particle {i}, paged {paged}");
        }
        Some(e)
    };
    let (Some(one), Some(paged)) = (run(false), run(true)) else {
        return;
    };
    common::assert_same_run(&one, &paged, "pour");
}

/// Pages too small for three windows' entries are refused by name, before the run.
#[test]
fn pages_of_fewer_than_three_windows_are_refused() {
    let Some(ctx) = context() else { return };
    let scene = packing(Case::Jkr, 600, 1.0, 3).unwrap();
    let err = GpuEngine::with_options(&scene, ctx, options(64, 64, Some(4096)))
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("a page of at most 4096 bytes holds fewer than 3 windows"),
        "{err}"
    );
    // and the state's likewise
    let small_state = GpuOptions {
        state_page_bytes: Some(4096),
        ..options(64, 64, None)
    };
    let err = GpuEngine::with_options(&scene, context().unwrap(), small_state)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("the particle state needs")
            && err.contains("a page of at most 4096 bytes holds fewer than 3 windows"),
        "{err}"
    );
}

/// Quiet batches (the software path's) stop where the entries go into pages — their copy
/// of the lists would be one buffer — and the run stays bitwise the run with them.
#[test]
fn quiet_batches_stop_where_the_entries_go_into_pages() {
    use powder::gpu::QuietBatches;
    let Some(ctx) = context() else { return };
    let scene = packing(Case::Hysteretic, 1200, 1.0, 3).unwrap();
    let quiet = |page| GpuOptions {
        quiet: QuietBatches::Always,
        ..options(256, 1, page)
    };
    let mut one = GpuEngine::with_options(&scene, ctx, quiet(None)).unwrap();
    one.run_steps(400).unwrap();
    assert!(one.quiet_batches().0 > 0);
    let block = block_bytes(&one);
    let mut paged =
        GpuEngine::with_options(&scene, context().unwrap(), quiet(Some(3 * block))).unwrap();
    assert!(paged.variant_name().ends_with("_paged"));
    assert!(!paged.buffers().iter().any(|(n, _)| n.starts_with("quiet.")));
    paged.run_steps(400).unwrap();
    assert_eq!(paged.quiet_batches(), (0, 0));
    assert_same_bits(&one.state().unwrap(), &paged.state().unwrap());
}
