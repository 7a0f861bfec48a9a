//! Choices several commands share: the backend, the GPU's software paths and quiet batches, thread counts, JSON output.

use super::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendChoice {
    /// A hardware GPU if there is one, else the CPU engine (see `powder run --help`).
    Auto,
    Cpu,
    Gpu,
    Both,
}

/// The engine `--backend auto` picks (a hardware GPU, else the CPU), its reason on stderr.
pub(crate) fn auto_backend() -> Result<collide::Backend, PowderError> {
    let chosen = powder::backend::choose(powder::backend::BackendRequest::Auto)?;
    eprintln!("backend: {}", chosen.reason);
    Ok(match chosen.gpu {
        Some(_) => collide::Backend::Gpu,
        None => collide::Backend::Cpu,
    })
}

impl BackendChoice {
    pub(crate) fn list(self) -> Result<Vec<collide::Backend>, PowderError> {
        Ok(match self {
            BackendChoice::Auto => vec![auto_backend()?],
            BackendChoice::Cpu => vec![collide::Backend::Cpu],
            BackendChoice::Gpu => vec![collide::Backend::Gpu],
            BackendChoice::Both => vec![collide::Backend::Cpu, collide::Backend::Gpu],
        })
    }
}

/// `--software-paths` (`GpuOptions::software_paths`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum SoftwarePaths {
    /// By the adapter kind.
    Auto,
    /// The software adapter's paths on any adapter.
    On,
    /// The GPU's paths on any adapter.
    Off,
}

impl SoftwarePaths {
    pub(crate) fn choice(self) -> Option<bool> {
        match self {
            Self::Auto => None,
            Self::On => Some(true),
            Self::Off => Some(false),
        }
    }
}

/// `--quiet-batches`: how the GPU engine uses quiet batches (`powder::gpu::QuietBatches`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum QuietChoice {
    /// Every batch checks each step whether to rebuild the neighbour lists.
    Off,
    /// On a software adapter, batches run without the per-step check where no rebuild is
    /// expected, and again with it where one was needed (results bitwise the same); on a
    /// GPU as `off` (the copies they need cost as much memory as the state).
    Auto,
    /// Every batch tries to run without the check (diagnostics).
    Always,
}

impl From<QuietChoice> for powder::gpu::QuietBatches {
    fn from(q: QuietChoice) -> Self {
        match q {
            QuietChoice::Off => Self::Off,
            QuietChoice::Auto => Self::Auto,
            QuietChoice::Always => Self::Always,
        }
    }
}

/// `--rebuild-chain`: how the GPU's steps hold a neighbour-list rebuild
/// (`powder::gpu::RebuildChain`; results bitwise the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum ChainChoice {
    /// Every step records the rebuild's passes (dispatched empty where none is due).
    EveryStep,
    /// Steps record only the decision, which halts the batch where a rebuild is due.
    OnDemand,
}

impl From<ChainChoice> for powder::gpu::RebuildChain {
    fn from(c: ChainChoice) -> Self {
        match c {
            ChainChoice::EveryStep => Self::EveryStep,
            ChainChoice::OnDemand => Self::OnDemand,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum Backend {
    /// A hardware GPU if there is one, else the CPU engine on every core (the software
    /// adapter only when asked for: `--backend gpu`, or `POWDER_ADAPTER` set).
    Auto,
    /// The f64 CPU reference engine.
    Cpu,
    /// The wgpu engine (every model; the same outputs, checkpoints and run monitor).
    Gpu,
}

impl Backend {
    pub(crate) fn collide(self) -> Result<collide::Backend, PowderError> {
        Ok(match self {
            Backend::Auto => auto_backend()?,
            Backend::Cpu => collide::Backend::Cpu,
            Backend::Gpu => collide::Backend::Gpu,
        })
    }

    pub(crate) fn request(self) -> powder::backend::BackendRequest {
        use powder::backend::BackendRequest as R;
        match self {
            Backend::Auto => R::Auto,
            Backend::Cpu => R::Cpu,
            Backend::Gpu => R::Gpu,
        }
    }
}

pub(crate) fn write_json<T: serde::Serialize>(
    path: &std::path::Path,
    value: &T,
) -> Result<(), PowderError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
    powder::output::atomic::write_atomic(path, text.as_bytes())?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Parses `--threads`: comma-separated thread counts (0: every core).
pub(crate) fn parse_threads(text: &str) -> Result<Vec<usize>, PowderError> {
    text.split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse().map_err(|_| {
                powder::ParamError::new(
                    "threads",
                    format!("`{t}` is not a thread count; expected e.g. 1,2 (0: every core)"),
                )
                .into()
            })
        })
        .collect()
}
