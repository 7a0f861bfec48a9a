//! The f64 CPU reference engine: velocity-Verlet integration, a Verlet pair list (built
//! with linked cells, rebuilt when particles may have closed its skin), per-contact history
//! kept with the pair's list entry (keyed by the persistent particle ids), gravity, planar
//! walls and an energy ledger (kinetic, stored, gravitational, dissipated) whose sum is
//! conserved up to the integration error.
//!
//! The forces do not depend on the list beyond the contacts it holds: every step visits the
//! pairs in key order (i, j) and skips those out of range, so a run gives the same bits
//! whenever the list is rebuilt (a restored checkpoint rebuilds it around its contacts).

use crate::cpu::cells::CellGrid;
use crate::cpu::threads::Threads;
use crate::error::PowderError;
use crate::model::{ContactModel, TimeStep};
use crate::scene::Scene;
use glam::DVec3;

mod access;
mod build;
mod contact;
mod pair_forces;
mod pair_list;
mod report;
mod state;
mod step;
#[cfg(test)]
pub(crate) mod tests;
mod walls;

pub(crate) use contact::ContactRecord;
use contact::Jump;
use pair_list::PairList;
pub use report::{ContactStats, Energies};
pub use state::CpuState;
use walls::{WallList, WallPlane};

/// Verlet skin of the CPU pair list, in units of the smallest radius: candidate pairs are
/// those closer than r_i + r_j + reach + skin, and the list is rebuilt once two particles
/// may together have moved the skin since the last rebuild (the GPU engine's skin is the
/// same fraction).
pub const SKIN: f64 = 0.1;

/// The CPU reference simulation.
pub struct CpuEngine {
    /// Simulated time, s (read with `time()`: a checkpoint holds it with the steps).
    pub(crate) time: f64,
    /// Steps taken.
    pub(crate) steps: u64,
    dt: f64,
    time_step: TimeStep,
    /// The digests of the scene's parts it was built from (`checkpoint::run_digests`).
    scene_parts: Vec<(String, u64)>,
    pos: Vec<DVec3>,
    vel: Vec<DVec3>,
    acc: Vec<DVec3>,
    force: Vec<DVec3>,
    /// Angular velocity, torque and moment of inertia: empty unless some contact model
    /// exerts tangential forces or torques (a scene without friction does not pay for them).
    omega: Vec<DVec3>,
    torque: Vec<DVec3>,
    inertia: Vec<f64>,
    radius: Vec<f64>,
    mass: Vec<f64>,
    material: Vec<usize>,
    n_materials: usize,
    /// Pair models, n_materials × n_materials.
    models: Vec<ContactModel>,
    walls: Vec<WallPlane>,
    /// Wall models, walls × n_materials.
    wall_models: Vec<ContactModel>,
    /// `range()` of each pair and wall model (the same layout).
    ranges: Vec<f64>,
    wall_ranges: Vec<f64>,
    gravity: DVec3,
    /// Cells at least as wide as the largest list distance 2·r_max + reach + skin.
    grid: CellGrid,
    /// r_i + the largest reach: pairs closer than this + r_j interact.
    cutoff_pad: Vec<f64>,
    /// Verlet skin, m ([`SKIN`]·r_min, less on a periodic axis too short for it).
    skin: f64,
    /// Whether the pair loop solves the laws' roots ahead where a law has them (a test
    /// compares it with the loop that does not).
    roots_ahead: bool,
    /// Candidate pairs with their contacts.
    pairs: PairList,
    /// Positions at the last rebuild.
    pos_ref: Vec<DVec3>,
    /// The list must be rebuilt before the next force evaluation (start, restore,
    /// insertion).
    rebuild_due: bool,
    /// List rebuilds so far (not part of the state).
    rebuilds: u64,
    /// The threads the step is spread over.
    threads: Threads,
    /// Scratch of the pair forces: each entry's force on i (and torque on its partner j),
    /// each particle's sum over its own entries.
    entry_force: Vec<DVec3>,
    entry_torque: Vec<DVec3>,
    own_force: Vec<DVec3>,
    own_torque: Vec<DVec3>,
    wall_contacts: WallList,
    spare_walls: WallList,
    /// The impulses of the force jumps of the step being taken (pairs, then walls).
    jumps: Vec<Jump>,
    /// Whether they are added (the scene's `jump_impulses`, default on).
    jump_impulses: bool,
    /// Wall candidates, rebuilt with the pair list: the active particles within
    /// range + skin of wall w then, or in contact with it, ascending, at
    /// `wall_candidates[wall_start[w]..wall_start[w + 1]]`.
    wall_start: Vec<usize>,
    wall_candidates: Vec<u32>,
    /// Wall points at the last rebuild.
    wall_ref: Vec<DVec3>,
    /// Scratch: predicted velocities of the step.
    v_pred: Vec<DVec3>,
    w_pred: Vec<DVec3>,
    dissipated: f64,
    wall_work: f64,
    domain: (DVec3, DVec3),
    /// Periodic axes (positions wrap into the domain, pairs use the minimum image).
    periodic: [bool; 3],
    /// When each particle appears (pouring), s, and whether it has: a particle that has not
    /// neither moves nor interacts. All true without insertion.
    insert_at: Vec<f64>,
    active: Vec<bool>,
    /// The earliest `insert_at` of a particle not yet active (∞ when all are): a step
    /// before it looks at none of them.
    next_insert: f64,
    /// Kinetic + gravitational energy the inserted particles brought in, J.
    inserted: f64,
    /// Deepest overlap over a12 since the monitor last looked: (ratio, i, partner).
    peak: Option<(f64, usize, Partner)>,
}

/// `d` with each periodic axis's component replaced by its nearest periodic image.
pub fn minimum_image(mut d: DVec3, periodic: [bool; 3], domain: (DVec3, DVec3)) -> DVec3 {
    for a in 0..3 {
        if periodic[a] {
            let l = domain.1[a] - domain.0[a];
            d[a] -= l * (d[a] / l).round();
        }
    }
    d
}

/// The other side of a contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Partner {
    /// Another particle, by index.
    Particle(usize),
    /// A wall, by index into the scene's walls.
    Wall(usize),
}
impl CpuEngine {
    /// Builds the engine from a validated scene, resolving pair models and the time step;
    /// it runs on every core ([`Threads::default`]).
    pub fn new(scene: &Scene) -> Result<Self, PowderError> {
        Self::with_threads(scene, Threads::default())
    }
}
