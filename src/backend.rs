//! Which engine a command runs on. `auto` takes a hardware GPU when there is one and the
//! CPU engine (on every core) otherwise: the software adapter is slower than the CPU
//! engine, so it runs only when asked for (`--backend gpu`, or `POWDER_ADAPTER` set).

use crate::gpu::adapter::{adapter_infos, ADAPTER_ENV};
use crate::gpu::{AdapterPreference, GpuContext};
use crate::PowderError;

/// What the user asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendRequest {
    /// A hardware GPU if present, else the CPU engine.
    Auto,
    /// The CPU engine.
    Cpu,
    /// The GPU engine on the adapter `POWDER_ADAPTER` picks (the software one if no other).
    Gpu,
}

/// The engine chosen, and why.
pub struct Chosen {
    /// The device of the GPU engine; `None`: the CPU engine.
    pub gpu: Option<GpuContext>,
    /// Why, in a sentence for stderr and the summary.
    pub reason: String,
}

/// Chooses the engine for `request`. `--backend gpu` without any adapter falls back to the
/// CPU engine (saying so in the reason); an adapter `POWDER_ADAPTER` names that cannot be
/// opened is an error, with either request.
pub fn choose(request: BackendRequest) -> Result<Chosen, PowderError> {
    let gpu = |ctx: GpuContext, why: String| Chosen {
        reason: format!(
            "{why}: {} ({}, {}; `powder info` shows its limits)",
            ctx.summary.name, ctx.summary.backend, ctx.summary.device_type
        ),
        gpu: Some(ctx),
    };
    match request {
        BackendRequest::Cpu => Ok(Chosen {
            gpu: None,
            reason: "--backend cpu".into(),
        }),
        BackendRequest::Gpu => match GpuContext::new() {
            Ok(ctx) => Ok(gpu(ctx, "--backend gpu".into())),
            // (an adapter asked for by name is not replaced by the CPU engine)
            Err(e) if AdapterPreference::from_env() != AdapterPreference::Auto => Err(e),
            Err(e) => Ok(Chosen {
                gpu: None,
                reason: format!("--backend gpu, but {e}; the CPU engine runs instead"),
            }),
        },
        BackendRequest::Auto => {
            let pref = AdapterPreference::from_env();
            if pref != AdapterPreference::Auto {
                let ctx = GpuContext::with_preference(&pref)?;
                let value = std::env::var(ADAPTER_ENV).unwrap_or_default();
                return Ok(gpu(ctx, format!("{ADAPTER_ENV}={value}")));
            }
            let infos = adapter_infos();
            let found: Vec<String> = (infos.iter())
                .map(|info| {
                    let api = info.backend.to_str();
                    format!("{} ({api}, {:?})", info.name, info.device_type)
                })
                .collect();
            // (why a GPU did not open matters only where there is one)
            let hardware = (infos.iter()).any(|i| i.device_type != wgpu::DeviceType::Cpu);
            match GpuContext::with_preference(&AdapterPreference::Hardware) {
                Ok(ctx) => Ok(gpu(ctx, "--backend auto found a hardware GPU".into())),
                Err(e) => Ok(Chosen {
                    gpu: None,
                    reason: format!(
                        "--backend auto found no hardware GPU{}: the CPU engine, faster here than the software adapter (--backend gpu runs that)",
                        if found.is_empty() {
                            " (no adapter at all)".to_string()
                        } else if hardware {
                            format!(" that opens (adapters: {}; {e})", found.join(", "))
                        } else {
                            format!(" (adapters: {})", found.join(", "))
                        }
                    ),
                }),
            }
        }
    }
}
