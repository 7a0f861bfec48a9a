//! Helpers shared by the integration tests.

use powder::gpu::GpuContext;

/// The GPU context, or `None` (with a notice) when no adapter exists outside CI; in CI
/// (where lavapipe is installed) a missing adapter fails the test.
pub fn gpu() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("CI").is_none() => {
            eprintln!("skipping GPU test: {e}");
            None
        }
        Err(e) => panic!("CI needs a GPU adapter (lavapipe): {e}"),
    }
}
