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
use crate::cpu::threads::{chunks, Threads};
use crate::error::PowderError;
use crate::model::{ContactHistory, ContactModel, TimeStep};
use crate::scene::Scene;
use crate::setup::Resolved;
use glam::DVec3;

mod contact;
mod pair_forces;
mod pair_list;
mod report;
mod state;
#[cfg(test)]
mod tests;
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
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    dt: f64,
    time_step: TimeStep,
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

/// A particle's acceleration from its force, mass and gravity: one expression for the
/// constructor and the step, so both give the same bits.
#[inline(always)]
fn acceleration(force: DVec3, mass: f64, gravity: DVec3) -> DVec3 {
    force / mass + gravity
}

/// `v` in chunks of `chunk` elements where it holds all `n` particles' values, else one
/// empty slice a chunk (rotations of a scene whose particles do not rotate).
fn chunks_or_empty(v: &mut [DVec3], n: usize, chunk: usize) -> Vec<&mut [DVec3]> {
    if v.len() == n {
        v.chunks_mut(chunk).collect()
    } else {
        chunks(n, chunk)
            .map(|_| <&mut [DVec3]>::default())
            .collect()
    }
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

    /// [`Self::new`] on `threads` (the first force evaluation included).
    pub fn with_threads(scene: &Scene, threads: Threads) -> Result<Self, PowderError> {
        let Resolved {
            n_materials,
            models,
            wall_models,
            mass,
            dt,
            time_step,
            r_max,
            max_reach,
            rotation,
        } = Resolved::new(scene)?;
        let n = scene.particles.len();
        let pos: Vec<DVec3> = scene
            .particles
            .iter()
            .map(|p| DVec3::from_array(p.position))
            .collect();
        let vel: Vec<DVec3> = scene
            .particles
            .iter()
            .map(|p| DVec3::from_array(p.velocity))
            .collect();
        let radius: Vec<f64> = scene.particles.iter().map(|p| p.radius).collect();
        let material: Vec<usize> = scene.particles.iter().map(|p| p.material).collect();
        let cutoff = 2.0 * r_max + max_reach;
        let domain = (
            DVec3::from_array(scene.domain.min),
            DVec3::from_array(scene.domain.max),
        );
        let periodic = scene.domain.periodic;
        let r_min = radius.iter().copied().fold(f64::INFINITY, f64::min);
        // the skin, halved until a periodic axis holds 3 cells of cut-off + skin (without
        // any skin, the list is rebuilt every step)
        let mut skin = if r_min.is_finite() { SKIN * r_min } else { 0.0 };
        let grid = loop {
            let grid = CellGrid::periodic(
                domain.0,
                domain.1,
                (cutoff + skin) * (1.0 + 1e-9),
                n,
                periodic,
            );
            match grid {
                Some(grid) => break grid,
                None if skin > 1e-3 * cutoff => skin *= 0.5,
                None if skin > 0.0 => skin = 0.0,
                None => {
                    let extent = domain.1 - domain.0;
                    let (axis, length) = (0..3)
                        .filter(|&a| periodic[a])
                        .map(|a| (["x", "y", "z"][a], extent[a]))
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .unwrap_or(("?", f64::NAN));
                    return Err(PowderError::Scene(format!(
                        "the domain is {length:.4e} m long along the periodic axis {axis}, shorter than 3 interaction cut-offs ({:.4e} m): a pair would meet two periodic images; enlarge [domain] or make the axis non-periodic",
                        3.0 * cutoff
                    )));
                }
            }
        };
        let walls = scene
            .walls
            .iter()
            .map(|w| WallPlane {
                point: DVec3::from_array(w.point),
                normal: DVec3::from_array(w.normal).normalize(),
                motion: w.motion.clone(),
                velocity: DVec3::ZERO,
            })
            .collect();
        let cutoff_pad = radius.iter().map(|r| r + max_reach).collect();
        let (omega, torque, inertia) = if rotation {
            (
                scene
                    .particles
                    .iter()
                    .map(|p| DVec3::from_array(p.angular_velocity))
                    .collect(),
                vec![DVec3::ZERO; n],
                mass.iter()
                    .zip(&radius)
                    .map(|(m, r)| 0.4 * m * r * r)
                    .collect(),
            )
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        let mut engine = Self {
            time: 0.0,
            steps: 0,
            dt,
            time_step,
            acc: vec![DVec3::ZERO; n],
            force: vec![DVec3::ZERO; n],
            omega,
            torque,
            inertia,
            pos,
            vel,
            radius,
            mass,
            material,
            n_materials,
            ranges: models.iter().map(ContactModel::range).collect(),
            wall_ranges: wall_models.iter().map(ContactModel::range).collect(),
            models,
            walls,
            wall_models,
            gravity: DVec3::from_array(scene.gravity),
            grid,
            cutoff_pad,
            skin,
            roots_ahead: true,
            pairs: PairList::empty(n),
            pos_ref: Vec::new(),
            rebuild_due: true,
            rebuilds: 0,
            threads,
            entry_force: Vec::new(),
            entry_torque: Vec::new(),
            own_force: Vec::new(),
            own_torque: Vec::new(),
            wall_contacts: WallList::default(),
            spare_walls: WallList::default(),
            jumps: Vec::new(),
            jump_impulses: scene.jump_impulses.unwrap_or(true),
            wall_start: Vec::new(),
            wall_candidates: Vec::new(),
            wall_ref: Vec::new(),
            v_pred: Vec::new(),
            w_pred: Vec::new(),
            dissipated: 0.0,
            wall_work: 0.0,
            domain,
            periodic,
            insert_at: scene.particles.iter().map(|p| p.insert_at).collect(),
            active: scene.particles.iter().map(|p| p.insert_at <= 0.0).collect(),
            next_insert: 0.0,
            inserted: 0.0,
            peak: None,
        };
        engine.next_insert = engine.earliest_pending();
        engine.v_pred.clone_from(&engine.vel);
        engine.w_pred.clone_from(&engine.omega);
        engine.compute_forces()?;
        engine.update_acceleration();
        // Contacts present at the start carry stored energy, not dissipation, and
        // crossed no edge.
        engine.dissipated = 0.0;
        engine.jumps.clear();
        Ok(engine)
    }

    /// Spreads the step over `threads` (every core by default). The results are bitwise
    /// the same on any number of threads.
    pub fn set_threads(&mut self, threads: Threads) {
        self.threads = threads;
    }

    /// The number of threads the step is spread over.
    pub fn threads(&self) -> usize {
        self.threads.count()
    }

    /// The time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The time-step rule the scene was checked against.
    pub fn time_step(&self) -> &TimeStep {
        &self.time_step
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// Whether the scene has no particles.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Particle centres, m.
    pub fn positions(&self) -> &[DVec3] {
        &self.pos
    }

    /// Particle velocities, m/s.
    pub fn velocities(&self) -> &[DVec3] {
        &self.vel
    }

    /// Angular velocities; empty when no contact model needs rotation.
    pub fn angular_velocities(&self) -> &[DVec3] {
        &self.omega
    }

    /// Sets particle `i`'s angular velocity, rad/s (scenes start without spin: an initial
    /// spin for tests and studies). Only where particles rotate (some contact model exerts
    /// tangential forces or torques).
    pub fn set_angular_velocity(&mut self, i: usize, omega: DVec3) -> Result<(), PowderError> {
        if self.omega.is_empty() {
            return Err(PowderError::Run(
                "the particles do not rotate: no contact model has friction, rolling or twisting resistance".into(),
            ));
        }
        let n = self.omega.len();
        let w = self.omega.get_mut(i).ok_or_else(|| {
            PowderError::Run(format!("particle {i} does not exist ({n} particles)"))
        })?;
        *w = omega;
        Ok(())
    }

    /// Whether particles rotate in this scene.
    pub fn rotates(&self) -> bool {
        !self.omega.is_empty()
    }

    /// Particle radii, m.
    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

    /// Particle masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Net contact force on each particle from the last force evaluation.
    pub fn forces(&self) -> &[DVec3] {
        &self.force
    }

    /// History of the contact between particles `i` and `j` (persistent ids), if any.
    pub fn contact_history(&self, i: usize, j: usize) -> Option<ContactHistory> {
        let k = self.pairs.find(i.min(j), i.max(j))?;
        self.pairs.live[k].then(|| self.pairs.record[k].history)
    }

    /// History of the contact between particle `i` and wall `w`, if any.
    pub fn wall_contact_history(&self, w: usize, i: usize) -> Option<ContactHistory> {
        self.wall_contacts
            .find((u32::try_from(w).ok()?, u32::try_from(i).ok()?))
            .map(|c| c.history)
    }

    /// Overlap δ = r_i + r_j − |x_i − x_j| of a pair (minimum image on periodic axes).
    /// Panics where `i` or `j` is not a particle (as a slice index does).
    pub fn overlap(&self, i: usize, j: usize) -> f64 {
        self.radius[i] + self.radius[j] - self.separation(i, j).length()
    }

    /// x_i − x_j, the nearest periodic image on periodic axes. Panics where `i` or `j` is
    /// not a particle.
    pub fn separation(&self, i: usize, j: usize) -> DVec3 {
        minimum_image(self.pos[i] - self.pos[j], self.periodic, self.domain)
    }

    /// Wraps positions into the domain along periodic axes.
    fn wrap_positions(&mut self) {
        let (lo, hi) = self.domain;
        for a in 0..3 {
            if self.periodic[a] {
                let l = hi[a] - lo[a];
                for p in &mut self.pos {
                    let x = lo[a] + (p[a] - lo[a]).rem_euclid(l);
                    // rem_euclid can round up to l itself
                    p[a] = if x >= hi[a] { lo[a] } else { x };
                }
            }
        }
    }

    /// Particles outside the domain box (informational; they still interact).
    pub fn outside_domain(&self) -> usize {
        let (lo, hi) = self.domain;
        self.pos
            .iter()
            .filter(|p| p.cmplt(lo).any() || p.cmpgt(hi).any())
            .count()
    }

    /// Ids of the particles whose centre is outside the domain box (at most `limit`).
    pub fn escaped(&self, limit: usize) -> Vec<usize> {
        let (lo, hi) = self.domain;
        self.pos
            .iter()
            .enumerate()
            .filter(|(_, p)| p.cmplt(lo).any() || p.cmpgt(hi).any())
            .map(|(i, _)| i)
            .take(limit)
            .collect()
    }

    /// The particle with a non-finite position or velocity, if any.
    pub fn non_finite(&self) -> Option<usize> {
        (0..self.pos.len()).find(|&i| !(self.pos[i].is_finite() && self.vel[i].is_finite()))
    }

    /// The deepest overlap over the reduced radius a12 reached by any contact in any step
    /// since the last call: `(ratio, particle, partner)`. Resets the record.
    pub fn take_peak_overlap(&mut self) -> Option<(f64, usize, Partner)> {
        self.peak.take()
    }

    /// The accelerations from the forces (at construction; `step` computes them with its
    /// last half kicks).
    fn update_acceleration(&mut self) {
        let chunk = self.threads.chunk();
        let (force, mass, gravity) = (&self.force, &self.mass, self.gravity);
        let work: Vec<_> = (self.acc.chunks_mut(chunk))
            .zip(chunks(self.pos.len(), chunk))
            .collect();
        self.threads.map(work, |(acc, range)| {
            for (a, i) in range.enumerate() {
                acc[a] = acceleration(force[i], mass[i], gravity);
            }
        });
    }

    /// One velocity-Verlet step. Velocity-dependent forces see the predicted velocity
    /// v + a·dt (and ω + α·dt), which keeps the damped oscillator second-order accurate.
    /// After an error the positions and velocities are those of the failed step while the
    /// clock is not: restore a state taken before ([`CpuEngine::state`]) to go on, as
    /// `powder run` does.
    pub fn step(&mut self) -> Result<(), PowderError> {
        let chunk = self.threads.chunk();
        let dt = self.dt;
        self.insert_due();
        let n = self.pos.len();
        self.v_pred.resize(n, DVec3::ZERO);
        self.w_pred.resize(self.omega.len(), DVec3::ZERO);
        let (acc, active) = (&self.acc, &self.active);
        let (torque, inertia) = (&self.torque, &self.inertia);
        // the half kick and drift of the translations, and the half kick of the rotations
        // where particles rotate, in one pass over the chunks
        let work: Vec<_> = (self.pos.chunks_mut(chunk))
            .zip(self.vel.chunks_mut(chunk))
            .zip(self.v_pred.chunks_mut(chunk))
            .zip(chunks_or_empty(&mut self.omega, n, chunk))
            .zip(chunks_or_empty(&mut self.w_pred, n, chunk))
            .zip(chunks(n, chunk))
            .collect();
        self.threads
            .map(work, |(((((pos, vel), v_pred), omega), w_pred), range)| {
                for (a, i) in range.clone().enumerate() {
                    if !active[i] {
                        v_pred[a] = vel[a];
                        continue;
                    }
                    let v_half = vel[a] + 0.5 * dt * acc[i];
                    pos[a] += dt * v_half;
                    v_pred[a] = v_half + 0.5 * dt * acc[i];
                    vel[a] = v_half;
                }
                for (a, i) in range.take(omega.len()).enumerate() {
                    let alpha = torque[i] / inertia[i];
                    omega[a] += 0.5 * dt * alpha;
                    w_pred[a] = omega[a] + 0.5 * dt * alpha;
                }
            });
        if self.periodic.iter().any(|&p| p) {
            self.wrap_positions();
        }
        // moving walls move first; their work is integrated over the step's forces
        let push_before = self.move_walls();
        self.compute_forces()?;
        if let Some(before) = push_before {
            self.book_wall_work(&before);
        }
        // the new accelerations and the second half kicks, in one pass over the chunks
        let (force, mass, gravity, active) = (&self.force, &self.mass, self.gravity, &self.active);
        let (torque, inertia) = (&self.torque, &self.inertia);
        let work: Vec<_> = (self.acc.chunks_mut(chunk))
            .zip(self.vel.chunks_mut(chunk))
            .zip(chunks_or_empty(&mut self.omega, n, chunk))
            .zip(chunks(n, chunk))
            .collect();
        self.threads.map(work, |(((acc, vel), omega), range)| {
            for (a, i) in range.clone().enumerate() {
                acc[a] = acceleration(force[i], mass[i], gravity);
                if active[i] {
                    vel[a] += 0.5 * dt * acc[a];
                }
            }
            for (a, i) in range.take(omega.len()).enumerate() {
                omega[a] += 0.5 * dt * torque[i] / inertia[i];
            }
        });
        // the impulses velocity Verlet misplaced at force jumps, in key order
        let jumps = std::mem::take(&mut self.jumps);
        if self.jump_impulses {
            for jump in jumps {
                self.vel[jump.i] += jump.impulse / self.mass[jump.i];
                match jump.partner {
                    Partner::Particle(j) => self.vel[j] -= jump.impulse / self.mass[j],
                    // a moving wall does the impulse's work on the particle
                    Partner::Wall(w) => {
                        self.wall_work += jump.impulse.dot(self.walls[w].velocity);
                    }
                }
            }
        }
        self.time += dt;
        self.steps += 1;
        Ok(())
    }

    /// Activates the particles whose insertion time has come (at the start of a step whose
    /// time has reached it), booking the energy they bring.
    fn insert_due(&mut self) {
        if self.time < self.next_insert {
            return;
        }
        for i in 0..self.pos.len() {
            if !self.active[i] && self.insert_at[i] <= self.time {
                self.active[i] = true;
                // the list must take the newcomer's pairs
                self.rebuild_due = true;
                self.inserted += 0.5 * self.mass[i] * self.vel[i].length_squared()
                    - self.mass[i] * self.gravity.dot(self.pos[i]);
                if let Some(w) = self.omega.get(i) {
                    self.inserted += 0.5 * self.inertia[i] * w.length_squared();
                }
            }
        }
        self.next_insert = self.earliest_pending();
    }

    /// The earliest insertion time of the particles not yet active (∞ when none is left).
    fn earliest_pending(&self) -> f64 {
        (self.insert_at.iter().zip(&self.active))
            .filter(|(_, &a)| !a)
            .map(|(&t, _)| t)
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether particle `i` has appeared (pouring: see `ParticleInit::insert_at`). Panics
    /// where `i` is not a particle.
    pub fn is_active(&self, i: usize) -> bool {
        self.active[i]
    }

    /// Runs `n` steps.
    pub fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        let threads = self.threads.clone();
        threads.install(|| {
            for _ in 0..n {
                self.step()?;
            }
            Ok(())
        })
    }

    /// Neighbour-list rebuilds so far (since the engine was built; not part of the state).
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    fn compute_forces(&mut self) -> Result<(), PowderError> {
        // the pair forces overwrite every force and torque, the walls' add to them
        if self.list_stale() {
            self.rebuild_list();
        }
        let v_pred = std::mem::take(&mut self.v_pred);
        let w_pred = std::mem::take(&mut self.w_pred);
        let pairs = if w_pred.is_empty() {
            self.pair_forces::<false>(&v_pred, &w_pred)
        } else {
            self.pair_forces::<true>(&v_pred, &w_pred)
        };
        self.peak = pairs.peak;
        let walls = self.wall_contact_forces(&v_pred, &w_pred);
        self.v_pred = v_pred;
        self.w_pred = w_pred;
        self.dissipated += pairs.total() + walls.total();
        self.jumps = pairs.jumps;
        self.jumps.extend(walls.jumps);
        if let Some(msg) = pairs.failure.or(walls.failure) {
            return Err(PowderError::Run(format!(
                "step {} (t = {:e} s): {msg}; the time step may be too large for the stiffest contact ({})",
                self.steps + 1,
                self.time + self.dt,
                self.time_step.reason
            )));
        }
        Ok(())
    }
}
