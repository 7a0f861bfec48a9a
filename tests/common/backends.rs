//! One feature test on both backends: the f64 CPU reference and the GPU engine (where an
//! adapter is present; in CI lavapipe), each driven as `powder run` drives it.

#![allow(dead_code)]

use powder::cpu::CpuEngine;
use powder::gpu::GpuEngine;
use powder::run::simulation::{Observation, Simulation};
use powder::scene::Scene;

/// A scene's run on one backend.
pub enum Backend {
    /// The CPU reference.
    Cpu(Box<CpuEngine>),
    /// The GPU engine.
    Gpu(Box<GpuEngine>),
}

impl Backend {
    /// "cpu" or "gpu", for assertion messages.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Cpu(e) => e.backend(),
            Self::Gpu(e) => e.backend(),
        }
    }

    /// The time step, s.
    pub fn dt(&self) -> f64 {
        match self {
            Self::Cpu(e) => Simulation::dt(e.as_ref()),
            Self::Gpu(e) => Simulation::dt(e.as_ref()),
        }
    }

    /// The simulated time, s.
    pub fn time(&self) -> f64 {
        match self {
            Self::Cpu(e) => Simulation::time(e.as_ref()),
            Self::Gpu(e) => Simulation::time(e.as_ref()),
        }
    }

    /// The steps taken.
    pub fn steps(&self) -> u64 {
        match self {
            Self::Cpu(e) => Simulation::steps(e.as_ref()),
            Self::Gpu(e) => Simulation::steps(e.as_ref()),
        }
    }

    /// Advances to the first step at or after time `t` (s).
    pub fn run_to(&mut self, t: f64) {
        let target = (t / self.dt()).ceil() as u64;
        self.run_steps(target.saturating_sub(self.steps()));
    }

    /// Whether this is the GPU engine (f32: the looser of a test's two tolerances).
    pub fn is_gpu(&self) -> bool {
        matches!(self, Self::Gpu(_))
    }

    /// Advances `n` steps (a failure is the test's).
    pub fn run_steps(&mut self, n: u64) {
        let done = match self {
            Self::Cpu(e) => Simulation::run_steps(e.as_mut(), n),
            Self::Gpu(e) => Simulation::run_steps(e.as_mut(), n),
        };
        done.unwrap_or_else(|err| panic!("{}: {err}", self.name()));
    }

    /// The state, energies, contact statistics and wall forces now.
    pub fn observe(&self) -> Observation {
        match self {
            Self::Cpu(e) => e.observe(),
            Self::Gpu(e) => e.observe(),
        }
        .unwrap_or_else(|err| panic!("{}: {err}", self.name()))
    }
}

/// `scene` on the CPU engine and, where there is an adapter, on the GPU engine.
pub fn backends(scene: &Scene) -> Vec<Backend> {
    let mut out = vec![Backend::Cpu(Box::new(CpuEngine::new(scene).unwrap()))];
    if let Some(ctx) = super::gpu() {
        out.push(Backend::Gpu(Box::new(GpuEngine::new(scene, ctx).unwrap())));
    }
    out
}
