//! What `powder run` reports at the end, and the measures of the final state it adds.

use serde::Serialize;

use crate::run::servo::ServoHold;
use crate::run::snapshot::Snapshot;
use crate::run::tabor::TaborPair;
use crate::scene::Scene;

/// What `powder run` reports at the end.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// Scene name.
    pub scene: String,
    /// `"cpu"` or `"gpu"`.
    pub backend: &'static str,
    /// The GPU adapter (GPU backend).
    pub adapter: Option<String>,
    /// The CPU threads the step ran on (CPU backend; the results do not depend on it).
    pub threads: Option<usize>,
    /// Why this backend ran (`--backend auto`: what was found), when it was chosen.
    pub backend_reason: Option<String>,
    /// Number of particles.
    pub particles: usize,
    /// Whether the run kept the energy ledger (off: `powder run --no-ledger` on the GPU;
    /// the ledger's quantities are then left out).
    pub ledger: bool,
    /// Time step, s.
    pub dt: f64,
    /// What chose dt (the scene's `simulation.dt`, or the automatic tc/50) and the
    /// stability limit it was checked against (the binding one), in words.
    pub dt_rule: String,
    /// Steps taken at the end, in all (a resumed run includes the steps before the checkpoint).
    pub steps: u64,
    /// Simulated time at the end, s.
    pub time: f64,
    /// Wall-clock time of this run, s.
    pub wall_seconds: f64,
    /// The part of `wall_seconds` spent inside the engine's steps; the rest went to reading
    /// the state back after each chunk, the monitor's checks and the outputs, s.
    pub stepping_seconds: f64,
    /// Particles × steps of this run over `wall_seconds`, 1/s.
    pub particle_steps_per_second: f64,
    /// State at the start of this run (the checkpoint's state on resume).
    pub initial: Snapshot,
    /// State at the end.
    pub last: Snapshot,
    /// |E_total(end) − E_total(start)| relative to the run's energy scale (the largest
    /// kinetic and stored energy, gravitational change and walls' work seen; 0 when nothing
    /// moved); absent without the ledger.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_balance_error: Option<f64>,
    /// Particles whose centre is outside the domain box at the end.
    pub outside_domain: usize,
    /// Particle volume over the domain box, and over the box enclosing the particles.
    pub solid_fraction_domain: f64,
    /// Particle volume over the box enclosing the particles (centres ± radii).
    pub solid_fraction_bounding_box: f64,
    /// Force on each wall at the end, N; absent without the ledger.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_forces: Option<Vec<[f64; 3]>>,
    /// The step the run resumed from, if it did.
    pub resumed_from: Option<u64>,
    /// Stopped early by an interrupt (Ctrl-C) after writing a last checkpoint.
    pub interrupted: bool,
    /// The output directory, if outputs were written.
    pub out_dir: Option<String>,
    /// Whether the contact network was written with the snapshots (`contacts/`).
    pub contact_network: bool,
    /// Neighbour-list rebuilds so far, as the backend counts them (the GPU's initial
    /// build included; the CPU's since this run's engine was built).
    pub rebuilds: u64,
    /// GPU: quiet batches kept and rolled back in this run (`gpu::quiet`); absent on the
    /// CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quiet_batches: Option<[u64; 2]>,
    /// Remarks: the backend's (GPU: neighbour-list rebuilds, contacts that left the lists)
    /// and servo walls sampled too rarely to judge.
    pub notes: Vec<String>,
    /// The Tabor parameter of every JKR pair of materials that can meet ([`crate::run::tabor_pairs`]);
    /// empty without JKR pairs.
    pub tabor: Vec<TaborPair>,
    /// How each servo wall held its target over the last quarter of the run
    /// ([`ServoHold`]); empty without servo walls or the ledger.
    pub servo: Vec<ServoHold>,
}

/// Solid fraction of the particles in the domain box and in the box that encloses them.
pub(super) fn solid_fractions(
    scene: &Scene,
    positions: &[glam::DVec3],
    radii: &[f64],
) -> (f64, f64) {
    let vol: f64 = radii.iter().map(|&r| crate::scene::sphere_volume(r)).sum();
    let d = scene.domain;
    let domain = (0..3).map(|a| d.max[a] - d.min[a]).product::<f64>();
    let mut lo = glam::DVec3::splat(f64::INFINITY);
    let mut hi = glam::DVec3::splat(f64::NEG_INFINITY);
    for (p, r) in positions.iter().zip(radii) {
        lo = lo.min(*p - *r);
        hi = hi.max(*p + *r);
    }
    let b = hi - lo;
    (vol / domain, vol / (b.x * b.y * b.z))
}

/// Particles whose centre is outside the domain box.
pub(super) fn outside_domain(scene: &Scene, positions: &[glam::DVec3]) -> usize {
    let (lo, hi) = (
        glam::DVec3::from_array(scene.domain.min),
        glam::DVec3::from_array(scene.domain.max),
    );
    positions
        .iter()
        .filter(|p| p.cmplt(lo).any() || p.cmpgt(hi).any())
        .count()
}
