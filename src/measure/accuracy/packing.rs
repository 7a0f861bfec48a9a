//! The packing case: a small cohesive packing against an f64 reference at a much finer
//! time step, compared after a fixed physical time.

use super::*;

/// The packing case's set-up and reference.
#[derive(Clone, Debug, Serialize)]
pub struct PackingSetup {
    /// N.
    pub particles: usize,
    /// Seed of the packing's jitter and velocities.
    pub seed: u64,
    /// Contact time on the stiffest branch, s.
    pub tc: f64,
    /// Physical time compared, s (`packing_time`·tc).
    pub time: f64,
    /// The reference's dt = tc/reference_divisor.
    pub reference_divisor: f64,
    /// s.
    pub reference_dt: f64,
    /// Steps of the reference run.
    pub reference_steps: u64,
    /// Its stepping time, s.
    pub reference_wall_seconds: f64,
    /// Its kinetic energy at `time`, J.
    pub reference_kinetic: f64,
    /// Particle–particle contacts per particle of the reference at `time`.
    pub reference_contacts_per_particle: f64,
}

/// The packing scene with dt = `time`/`steps` exactly.
pub(super) fn packing_scene(base: &Scene, time: f64, steps: u64) -> Scene {
    Scene {
        dt: DtSetting::Fixed(time / steps as f64),
        force_dt: true,
        ..base.clone()
    }
}

/// Positions and kinetic energy after `steps` steps on `backend`, with the set-up and
/// stepping times (a short run repeated, see [`MIN_TIMING`]).
pub(super) fn run_packing(
    scene: &Scene,
    steps: u64,
    backend: Backend,
) -> Result<(Vec<DVec3>, f64, f64, f64), PowderError> {
    match backend {
        Backend::Cpu => {
            let (e, setup, wall) =
                repeat_stepping(|| CpuEngine::new(scene), |e| e.run_steps(steps))?;
            Ok((e.positions().to_vec(), e.energies().kinetic, setup, wall))
        }
        Backend::Gpu => {
            let (e, setup, wall) = repeat_stepping(
                || GpuEngine::new(scene, GpuContext::new()?),
                |e| e.run_steps(steps),
            )?;
            let s = e.state()?;
            let ke = e.kinetic_energy(&s);
            Ok((s.positions, ke, setup, wall))
        }
    }
}
