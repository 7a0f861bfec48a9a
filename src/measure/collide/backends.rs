//! The two engines behind a collision: the pair read back after a step, the engine's
//! ledger and the trace's force and history, on the CPU and the GPU.

use super::*;
use crate::cpu::CpuEngine;
use crate::gpu::GpuEngine;

/// The pair as a backend reports it after a step.
pub(super) struct PairView {
    pub(super) pos: [DVec3; 2],
    pub(super) vel: [DVec3; 2],
    pub(super) omega: [DVec3; 2],
    /// Whether the contact persists (JKR necks at negative overlap); `None` when the
    /// backend cannot say, then δ > 0 decides.
    pub(super) in_contact: Option<bool>,
}

/// What the collision loop needs of an engine.
pub(super) trait CollisionRun {
    fn step(&mut self) -> Result<(), PowderError>;
    /// `n` steps with nothing read between them (the GPU batches them).
    fn advance(&mut self, n: u64) -> Result<(), PowderError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }
    fn view(&self) -> Result<PairView, PowderError>;
    fn time(&self) -> f64;
    fn steps(&self) -> u64;
    /// (kinetic, total) energy; total is `None` where the backend keeps no ledger.
    fn energy(&self, view: &PairView) -> (f64, Option<f64>, Option<f64>);
    fn rotates(&self) -> bool;
    /// Force on sphere 1 and the pair's contact history (CPU only, for the trace).
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)>;
    /// The relative change of a speed over a block of steps that the state resolves: 0 in
    /// f64; on the GPU, f32 rounding moves a slow creep's speed by up to ~1e-6 of itself
    /// from sample to sample (measured), so 1e-5.
    fn speed_noise(&self) -> f64 {
        0.0
    }
}

pub(super) struct CpuRun {
    pub(super) engine: CpuEngine,
    pub(super) wall: bool,
}

impl CollisionRun for CpuRun {
    fn step(&mut self) -> Result<(), PowderError> {
        self.engine.step()
    }
    fn view(&self) -> Result<PairView, PowderError> {
        let e = &self.engine;
        let two = |s: &[DVec3]| {
            [
                s.first().copied().unwrap_or_default(),
                s.get(1).copied().unwrap_or_default(),
            ]
        };
        let history = if self.wall {
            e.wall_contact_history(0, 0)
        } else {
            e.contact_history(0, 1)
        };
        Ok(PairView {
            pos: two(e.positions()),
            vel: two(e.velocities()),
            omega: two(e.angular_velocities()),
            in_contact: Some(history.is_some_and(|h| h.touched)),
        })
    }
    fn time(&self) -> f64 {
        self.engine.time
    }
    fn steps(&self) -> u64 {
        self.engine.steps
    }
    fn energy(&self, _: &PairView) -> (f64, Option<f64>, Option<f64>) {
        let e = self.engine.energies();
        (e.kinetic, Some(e.total()), Some(e.dissipated))
    }
    fn rotates(&self) -> bool {
        self.engine.rotates()
    }
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)> {
        let history = if self.wall {
            self.engine.wall_contact_history(0, 0)
        } else {
            self.engine.contact_history(0, 1)
        };
        Some((self.engine.forces()[0], history))
    }
}

pub(super) struct GpuRun {
    pub(super) engine: GpuEngine,
    pub(super) wall: bool,
}

impl CollisionRun for GpuRun {
    fn step(&mut self) -> Result<(), PowderError> {
        self.engine.run_steps(1)
    }
    fn speed_noise(&self) -> f64 {
        1e-5
    }
    fn advance(&mut self, n: u64) -> Result<(), PowderError> {
        self.engine.run_steps(n)
    }
    fn view(&self) -> Result<PairView, PowderError> {
        let s = self.engine.state()?;
        let two = |v: &[DVec3]| {
            [
                v.first().copied().unwrap_or_default(),
                v.get(1).copied().unwrap_or_default(),
            ]
        };
        // the contact's own flag: a JKR neck persists at negative overlap
        let touched = if self.wall {
            self.engine.wall_contact_history(0, 0)?.touched
        } else {
            self.engine
                .contact_history(0, 1)?
                .is_some_and(|h| h.touched)
        };
        Ok(PairView {
            pos: two(&s.positions),
            vel: two(&s.velocities),
            omega: two(&s.angular_velocities),
            in_contact: Some(touched),
        })
    }
    fn time(&self) -> f64 {
        self.engine.time
    }
    fn steps(&self) -> u64 {
        self.engine.steps
    }
    fn energy(&self, view: &PairView) -> (f64, Option<f64>, Option<f64>) {
        let n = self.engine.len();
        let state = crate::gpu::GpuState {
            positions: view.pos[..n].to_vec(),
            velocities: view.vel[..n].to_vec(),
            angular_velocities: if self.engine.rotates() {
                view.omega[..n].to_vec()
            } else {
                Vec::new()
            },
        };
        match self.engine.energies(&state) {
            Ok(e) => (e.kinetic, Some(e.total()), Some(e.dissipated)),
            // a run without the ledger: kinetic energy only
            Err(_) => (self.engine.kinetic_energy(&state), None, None),
        }
    }
    fn rotates(&self) -> bool {
        self.engine.rotates()
    }
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)> {
        let force = self.engine.contact_forces().ok()?[0];
        let history = if self.wall {
            Some(self.engine.wall_contact_history(0, 0).ok()?)
        } else {
            self.engine.contact_history(0, 1).ok()?
        };
        Some((force, history))
    }
}

impl CollideSpec {
    /// Relative motion of the colliding pair: overlap, normal approach speed, unit normal
    /// (from the partner to sphere 1) and the tangential contact-point velocity.
    pub(super) fn pair_state(&self, p: &PairView, wall_x: f64) -> (f64, f64, DVec3, DVec3) {
        let r1 = self.radius1;
        if self.wall {
            // the plane x = x_w faces −x; x_w = r1 + gap from the scene
            let n = DVec3::new(-1.0, 0.0, 0.0);
            let v = p.vel[0];
            let vc = v - r1 * p.omega[0].cross(n);
            let delta = r1 - (wall_x - p.pos[0].x);
            (delta, -v.dot(n), n, vc - n * vc.dot(n))
        } else {
            let d = p.pos[0] - p.pos[1];
            let dist = d.length();
            let n = d / dist;
            let v = p.vel[0] - p.vel[1];
            let vc = v - r1 * p.omega[0].cross(n) - self.radius2 * p.omega[1].cross(n);
            (r1 + self.radius2 - dist, -v.dot(n), n, vc - n * vc.dot(n))
        }
    }
}
