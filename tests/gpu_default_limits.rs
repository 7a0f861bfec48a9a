//! The GPU engine on a device opened with wgpu's default limits (WebGPU's: 8 storage
//! buffers a stage, 128 MiB a binding, 256 MiB a buffer, workgroups of 256): every kind
//! of step runs there, bitwise as on the adapter's own limits. (That every composed
//! variant's kernels fit those limits is `gpu::shaders`' naga test, which needs no GPU.)

mod common;

use powder::gpu::{GpuContext, GpuEngine, GpuOptions};
use powder::measure::bench::{packing, Case};
use powder::scene::Scene;

/// `scene` for `steps` steps on both devices, with `software_paths` (the texture mirrors
/// and quiet batches) on or off: the same bits.
fn same_bits_within_default_limits(scene: &Scene, steps: u64, software_paths: bool) {
    let Some(own) = common::gpu() else { return };
    let small = GpuContext::with_default_limits().unwrap();
    assert_eq!(small.limits().max_storage_buffers_per_shader_stage, 8);
    let options = GpuOptions {
        software_paths: Some(software_paths),
        ..Default::default()
    };
    let mut a = GpuEngine::with_options(scene, own, options).unwrap();
    let mut b = GpuEngine::with_options(scene, small, options).unwrap();
    a.run_steps(steps).unwrap();
    b.run_steps(steps).unwrap();
    common::assert_same_bits(&a.state().unwrap(), &b.state().unwrap());
    assert_eq!(a.rebuilds().unwrap(), b.rebuilds().unwrap());
}

/// The hysteretic model with adhesion, the energy ledger and a wall.
#[test]
fn the_cohesive_cluster_runs_within_the_default_limits() {
    let scene = common::example("cohesive_cluster.toml");
    same_bits_within_default_limits(&scene, 1500, false);
    same_bits_within_default_limits(&scene, 1500, true);
}

/// JKR with friction and rolling resistance (rotation, the widest history), five walls.
#[test]
fn a_jkr_packing_runs_within_the_default_limits() {
    let scene = packing(Case::Jkr, 300, 1.0, 5).unwrap();
    same_bits_within_default_limits(&scene, 600, false);
}

/// A lid that moves (the wall kernels) compressing a packing, the lists growing.
#[test]
fn a_compression_runs_within_the_default_limits() {
    let scene = common::example("compression.toml");
    same_bits_within_default_limits(&scene, 1500, false);
}
