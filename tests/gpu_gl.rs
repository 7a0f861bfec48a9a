//! A representative subset of the GPU tests on the OpenGL backend (llvmpipe in CI; every
//! GPU test also passes with `POWDER_ADAPTER=gl`): the GLSL that naga writes for GL and
//! the SPIR-V it writes for Vulkan differ in what they leave to the driver (e.g. GLSL's `%`
//! of a negative integer is undefined), so the step must hold on both.

mod common;
use common::gl;

use powder::gpu::{GpuEngine, GpuOptions};
use powder::measure::compare::{compare, Tolerances};
use powder::scene::Scene;

/// Runs `scene` on GL against the CPU reference with the default tolerances.
fn follows_the_cpu(scene: &Scene, steps: u64) {
    let Some(ctx) = gl() else { return };
    let c = compare(scene, ctx, steps, steps / 4, Tolerances::default()).unwrap();
    for s in &c.samples {
        eprintln!(
            "{} step {}: pos {:.2e} energy {:.2e} contacts {}/{} history {:.2e}",
            c.scene, s.step, s.position, s.energy, s.contacts_cpu, s.contacts_gpu, s.history
        );
    }
    assert!(
        c.samples.last().unwrap().contacts_cpu > 0,
        "no contacts formed"
    );
    assert!(c.passed, "{:?}", c.samples);
}

/// The hysteretic model with the ledger, a wall, adhesion (the packing example's law).
#[test]
fn the_cohesive_cluster_follows_the_cpu_on_gl() {
    follows_the_cpu(&common::example("cohesive_cluster.toml"), 8000);
}

/// A dense JKR packing with friction and rolling resistance (`powder bench`'s case):
/// rotation, the largest history, five walls.
#[test]
fn a_jkr_packing_follows_the_cpu_on_gl() {
    let scene =
        powder::measure::bench::packing(powder::measure::bench::Case::Jkr, 300, 1.0, 3).unwrap();
    follows_the_cpu(&scene, 2000);
}

/// Two periodic axes: particles wrap and pairs meet across the seams (the cell wrap is
/// where GL's integer remainder differed).
#[test]
fn a_periodic_cluster_follows_the_cpu_on_gl() {
    let scene = common::builder::periodic_cluster();
    follows_the_cpu(&scene, 5000);
}

/// The software adapter's path (texture mirrors) and the GPU path (the state's buffer)
/// give bitwise the same run on GL too, with a moving lid (indirect dispatches, wall
/// kernels) and list growth.
#[test]
fn both_state_paths_give_the_same_bits_on_gl() {
    let scene = common::example("compression.toml");
    let run = |software: bool| {
        let ctx = gl()?;
        let options = GpuOptions {
            software_paths: Some(software),
            ..Default::default()
        };
        let mut e = GpuEngine::with_options(&scene, ctx, options).unwrap();
        e.run_steps(1500).unwrap();
        Some(e.state().unwrap())
    };
    let (Some(a), Some(b)) = (run(true), run(false)) else {
        return;
    };
    common::assert_same_bits(&a, &b);
}

/// Windows (`gpu::window`: each window's dispatches binding parts of the buffers at
/// offsets) give the bits of one window on GL too: the compression in windows of 64.
#[test]
fn windows_give_the_same_bits_on_gl() {
    let scene = common::example("compression.toml");
    let run = |window: Option<u64>| {
        let ctx = gl()?;
        let options = GpuOptions {
            software_paths: Some(false),
            window_particles: window,
            ..Default::default()
        };
        let mut e = GpuEngine::with_options(&scene, ctx, options).unwrap();
        assert_eq!(e.windows().count > 1, window.is_some());
        e.run_steps(1500).unwrap();
        Some(e.state().unwrap())
    };
    let (Some(a), Some(b)) = (run(None), run(Some(64))) else {
        return;
    };
    common::assert_same_bits(&a, &b);
}

/// The lists' entries and the particle state in pages (`gpu::pages`: a window's page and
/// the other one bound whole) give the bits of one buffer on GL too: a JKR packing in
/// windows of 128, pages of three windows.
#[test]
fn pages_give_the_same_bits_on_gl() {
    let scene =
        powder::measure::bench::packing(powder::measure::bench::Case::Jkr, 600, 1.0, 3).unwrap();
    let run = |paged: bool| {
        let options = |page: Option<u64>, state_page: Option<u64>| GpuOptions {
            software_paths: Some(false),
            window_particles: Some(128),
            list_entries: Some(640),
            entry_page_bytes: page,
            state_page_bytes: state_page,
            ..Default::default()
        };
        let mut e = GpuEngine::with_options(&scene, gl()?, options(None, None)).unwrap();
        if paged {
            // pages of three windows' blocks of 640 entries, and of the state's larger
            // buffer
            let record: u64 = e.entry_fields().iter().map(|(_, b)| b).sum();
            let page = Some(3 * 640 * record + 100);
            let state = e.buffers().into_iter();
            let state = state.filter(|(n, _)| n == "A.state" || n == "A.motion");
            let block = state.map(|(_, b)| b).max().unwrap() / e.windows().count;
            let state_page = Some(3 * block + 100);
            e = GpuEngine::with_options(&scene, gl()?, options(page, state_page)).unwrap();
            assert_eq!(e.state_pages().count, 2);
        }
        assert_eq!(e.list_growths(), 0);
        assert_eq!(e.variant_name().ends_with("_paged"), paged);
        e.run_steps(600).unwrap();
        Some(e.state().unwrap())
    };
    let (Some(a), Some(b)) = (run(false), run(true)) else {
        return;
    };
    common::assert_same_bits(&a, &b);
}
