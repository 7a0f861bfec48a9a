//! The f64 CPU reference engine: velocity-Verlet integration, linked-cell contact search,
//! per-contact history keyed by the pair's persistent particle ids, gravity, planar walls
//! and an energy ledger (kinetic, stored, gravitational, dissipated) whose sum is conserved
//! up to the integration error.

use crate::cpu::cells::CellGrid;
use crate::error::PowderError;
use crate::model::{ContactHistory, ContactModel, Kinematics, PairGeometry, Response, TimeStep};
use crate::scene::Scene;
use crate::setup::Resolved;
use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A fast, deterministic hash for pair keys (two u32 ids): a multiply-rotate mix. The
/// standard SipHash cost 10 % of a JKR step (perf) and its random seed made the map's
/// iteration order differ from run to run.
#[derive(Clone, Copy, Debug, Default)]
struct PairHasher(u64);

impl Hasher for PairHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(23) ^ i).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

/// Contacts keyed by the pair's persistent ids.
type PairMap = HashMap<(u32, u32), ContactRecord, BuildHasherDefault<PairHasher>>;

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
struct ContactRecord {
    history: ContactHistory,
    /// Overlap, forces and stored energy at the end of the last step, for the work
    /// integral of the energy ledger.
    delta: f64,
    force: f64,
    tangential: DVec3,
    rolling_torque: DVec3,
    potential: f64,
    /// Tangential contact velocity and relative angular velocity the forces were
    /// evaluated with (the power of friction and rolling is integrated trapezoidally).
    v_t: DVec3,
    omega_rel: DVec3,
}

impl ContactRecord {
    /// Whether the contact takes part in the energy ledger: touched, or exerting a force,
    /// or storing energy (a pair merely within search range is not engaged).
    fn engaged(&self) -> bool {
        self.history.touched || self.potential != 0.0 || self.force != 0.0
    }

    fn new(history: ContactHistory, delta: f64, r: &Response, m: &Motion) -> Self {
        Self {
            history,
            delta,
            force: r.normal.force,
            tangential: r.tangential,
            rolling_torque: r.rolling_torque,
            potential: r.potential,
            v_t: m.v_t,
            omega_rel: m.omega_rel,
        }
    }
}

/// Relative motion of a pair over the last step that the ledger needs.
#[derive(Clone, Copy, Debug, Default)]
struct Motion {
    delta: f64,
    /// Tangential velocity at the contact and relative angular velocity ω_i − ω_j.
    v_t: DVec3,
    omega_rel: DVec3,
}

/// A planar wall: an infinite-mass body with the contact model of its material pair.
#[derive(Clone, Debug)]
struct WallPlane {
    /// A point of the plane now (it moves with the wall).
    point: DVec3,
    normal: DVec3,
    motion: crate::scene::WallMotion,
    /// Velocity over the current step.
    velocity: DVec3,
}

/// Energies of the whole system, J.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Energies {
    /// Translational plus rotational kinetic energy, J.
    pub kinetic: f64,
    /// Stored in contacts (recoverable elastic energy plus the adhesion potential).
    pub elastic: f64,
    /// −Σ m·g·x.
    pub gravitational: f64,
    /// Dissipated so far (plastic, adhesive hysteresis, viscous).
    pub dissipated: f64,
    /// Work done on the particles by moving walls so far.
    pub wall_work: f64,
    /// Kinetic + gravitational energy brought in by particles inserted so far (pouring).
    pub inserted: f64,
}

impl Energies {
    /// The conserved sum: kinetic + stored + gravitational + dissipated − the work moving
    /// walls did on the particles − the energy inserted particles brought in.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravitational + self.dissipated
            - self.wall_work
            - self.inserted
    }
}

/// Contact statistics at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ContactStats {
    /// Particle–particle pairs in mechanical contact (δ > 0).
    pub contacts: usize,
    /// Particle–wall contacts (δ > 0).
    pub wall_contacts: usize,
    /// Contacts engaged without overlap (δ ≤ 0): inside the non-contact adhesion range, or
    /// a JKR neck stretched to negative overlap (particle–particle and particle–wall).
    pub non_contact: usize,
    /// Mean number of mechanical contacts per particle (walls included), 2·C/N + W/N.
    pub coordination: f64,
    /// Largest overlap, m.
    pub max_overlap: f64,
    /// Largest overlap over the pair's reduced radius a12.
    pub max_overlap_ratio: f64,
    /// Mean overlap over a12 of the mechanical contacts (walls included; a12 = 2r for a wall);
    /// 0 without contacts.
    pub mean_overlap_ratio: f64,
}

/// Everything that evolves in a CPU run: what a checkpoint stores to resume bitwise.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CpuState {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    dt: f64,
    pos: Vec<DVec3>,
    vel: Vec<DVec3>,
    acc: Vec<DVec3>,
    force: Vec<DVec3>,
    omega: Vec<DVec3>,
    torque: Vec<DVec3>,
    /// Contacts in key order (the maps are rebuilt in visiting order every step).
    contacts: Vec<((u32, u32), ContactRecord)>,
    wall_contacts: Vec<((u32, u32), ContactRecord)>,
    dissipated: f64,
    /// Wall points and velocities (moving walls) and the work they did.
    wall_points: Vec<DVec3>,
    wall_velocities: Vec<DVec3>,
    wall_work: f64,
    /// Which particles have appeared, and the energy they brought.
    active: Vec<bool>,
    inserted: f64,
}

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
    gravity: DVec3,
    grid: CellGrid,
    cutoff_pad: Vec<f64>,
    contacts: PairMap,
    wall_contacts: PairMap,
    dissipated: f64,
    wall_work: f64,
    domain: (DVec3, DVec3),
    /// Periodic axes (positions wrap into the domain, pairs use the minimum image).
    periodic: [bool; 3],
    /// When each particle appears (pouring), s, and whether it has: a particle that has not
    /// neither moves nor interacts. All true without insertion.
    insert_at: Vec<f64>,
    active: Vec<bool>,
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
    /// Builds the engine from a validated scene, resolving pair models and the time step.
    pub fn new(scene: &Scene) -> Result<Self, PowderError> {
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
        let grid = CellGrid::periodic(domain.0, domain.1, cutoff * (1.0 + 1e-9), n, periodic)
            .ok_or_else(|| {
                PowderError::Scene(format!(
                    "the domain is shorter than 3 interaction cut-offs ({:.4e} m) along a periodic axis: a pair would meet two periodic images; enlarge [domain] or make the axis non-periodic",
                    cutoff
                ))
            })?;
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
                vec![DVec3::ZERO; n],
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
            models,
            walls,
            wall_models,
            gravity: DVec3::from_array(scene.gravity),
            grid,
            cutoff_pad,
            contacts: PairMap::default(),
            wall_contacts: PairMap::default(),
            dissipated: 0.0,
            wall_work: 0.0,
            domain,
            periodic,
            insert_at: scene.particles.iter().map(|p| p.insert_at).collect(),
            active: scene.particles.iter().map(|p| p.insert_at <= 0.0).collect(),
            inserted: 0.0,
            peak: None,
        };
        let v_pred = engine.vel.clone();
        let w_pred = engine.omega.clone();
        engine.compute_forces(&v_pred, &w_pred)?;
        engine.update_acceleration();
        // Contacts present at the start carry stored energy, not dissipation.
        engine.dissipated = 0.0;
        Ok(engine)
    }

    /// The time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The evolving state, for a checkpoint.
    pub fn state(&self) -> CpuState {
        let sorted = |m: &PairMap| {
            let mut v: Vec<_> = m.iter().map(|(k, r)| (*k, *r)).collect();
            v.sort_by_key(|(k, _)| *k);
            v
        };
        CpuState {
            time: self.time,
            steps: self.steps,
            dt: self.dt,
            pos: self.pos.clone(),
            vel: self.vel.clone(),
            acc: self.acc.clone(),
            force: self.force.clone(),
            omega: self.omega.clone(),
            torque: self.torque.clone(),
            contacts: sorted(&self.contacts),
            wall_contacts: sorted(&self.wall_contacts),
            dissipated: self.dissipated,
            wall_points: self.walls.iter().map(|w| w.point).collect(),
            wall_velocities: self.walls.iter().map(|w| w.velocity).collect(),
            wall_work: self.wall_work,
            active: self.active.clone(),
            inserted: self.inserted,
        }
    }

    /// Continues from a checkpointed state of the same scene. The state must come from
    /// this scene (same particle count, time step and rotation); the checkpoint file
    /// checks the scene's identity before this is called.
    pub fn restore(&mut self, s: CpuState) -> Result<(), PowderError> {
        let n = self.pos.len();
        if s.pos.len() != n
            || s.vel.len() != n
            || s.acc.len() != n
            || s.omega.len() != self.omega.len()
        {
            return Err(PowderError::Run(format!(
                "the checkpoint holds {} particles{} but the scene has {n}{}",
                s.pos.len(),
                if s.omega.is_empty() {
                    ""
                } else {
                    " with rotation"
                },
                if self.omega.is_empty() {
                    ""
                } else {
                    " with rotation"
                }
            )));
        }
        if s.dt.to_bits() != self.dt.to_bits() {
            return Err(PowderError::Run(format!(
                "the checkpoint was run with dt = {:e} s but the scene gives dt = {:e} s",
                s.dt, self.dt
            )));
        }
        self.time = s.time;
        self.steps = s.steps;
        self.pos = s.pos;
        self.vel = s.vel;
        self.acc = s.acc;
        self.force = s.force;
        self.omega = s.omega;
        self.torque = s.torque;
        self.contacts = s.contacts.into_iter().collect();
        self.wall_contacts = s.wall_contacts.into_iter().collect();
        self.dissipated = s.dissipated;
        if s.wall_points.len() != self.walls.len() {
            return Err(PowderError::Run(format!(
                "the checkpoint holds {} walls but the scene has {}",
                s.wall_points.len(),
                self.walls.len()
            )));
        }
        for (w, (p, v)) in self
            .walls
            .iter_mut()
            .zip(s.wall_points.into_iter().zip(s.wall_velocities))
        {
            w.point = p;
            w.velocity = v;
        }
        self.wall_work = s.wall_work;
        if s.active.len() == self.active.len() {
            self.active = s.active;
        }
        self.inserted = s.inserted;
        Ok(())
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
        let key = (i.min(j) as u32, i.max(j) as u32);
        self.contacts.get(&key).map(|c| c.history)
    }

    /// History of the contact between particle `i` and wall `w`, if any.
    pub fn wall_contact_history(&self, w: usize, i: usize) -> Option<ContactHistory> {
        self.wall_contacts
            .get(&(w as u32, i as u32))
            .map(|c| c.history)
    }

    /// Overlap δ = r_i + r_j − |x_i − x_j| of a pair (minimum image on periodic axes).
    pub fn overlap(&self, i: usize, j: usize) -> f64 {
        self.radius[i] + self.radius[j] - self.separation(i, j).length()
    }

    /// x_i − x_j, the nearest periodic image on periodic axes.
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

    /// Overlap of particle `i` with wall `w`.
    pub fn wall_overlap(&self, w: usize, i: usize) -> f64 {
        let wall = &self.walls[w];
        self.radius[i] - (self.pos[i] - wall.point).dot(wall.normal)
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

    fn update_acceleration(&mut self) {
        for i in 0..self.pos.len() {
            self.acc[i] = self.force[i] / self.mass[i] + self.gravity;
        }
    }

    /// One velocity-Verlet step. Velocity-dependent forces see the predicted velocity
    /// v + a·dt (and ω + α·dt), which keeps the damped oscillator second-order accurate.
    pub fn step(&mut self) -> Result<(), PowderError> {
        let dt = self.dt;
        self.insert_due();
        let mut v_pred = Vec::with_capacity(self.pos.len());
        for i in 0..self.pos.len() {
            if !self.active[i] {
                v_pred.push(self.vel[i]);
                continue;
            }
            let v_half = self.vel[i] + 0.5 * dt * self.acc[i];
            self.pos[i] += dt * v_half;
            v_pred.push(v_half + 0.5 * dt * self.acc[i]);
            self.vel[i] = v_half;
        }
        if self.periodic.iter().any(|&p| p) {
            self.wrap_positions();
        }
        // Moving walls: the velocity over this step (prescribed at its start, or the servo
        // law from the force of the step before), then the move; the work the walls do
        // on the particles is integrated with the force before and after the step.
        let push_before = self.moving_walls().then(|| self.wall_forces());
        if let Some(before) = &push_before {
            for (w, wall) in self.walls.iter_mut().enumerate() {
                wall.velocity = match &wall.motion {
                    crate::scene::WallMotion::Fixed => DVec3::ZERO,
                    crate::scene::WallMotion::Prescribed(_) => {
                        DVec3::from_array(wall.motion.prescribed_velocity(self.time))
                    }
                    crate::scene::WallMotion::Servo {
                        force,
                        gain,
                        max_speed,
                    } => {
                        // the normal force the particles exert (they push against −n)
                        let pushed = -before[w].dot(wall.normal);
                        let speed = (gain * (force - pushed)).clamp(-max_speed, *max_speed);
                        speed * wall.normal
                    }
                };
                wall.point += dt * wall.velocity;
            }
        }
        let mut w_pred = Vec::with_capacity(self.omega.len());
        for i in 0..self.omega.len() {
            let alpha = self.torque[i] / self.inertia[i];
            self.omega[i] += 0.5 * dt * alpha;
            w_pred.push(self.omega[i] + 0.5 * dt * alpha);
        }
        self.compute_forces(&v_pred, &w_pred)?;
        if let Some(before) = push_before {
            let after = self.wall_forces();
            for (w, wall) in self.walls.iter().enumerate() {
                // the wall pushes the particles with −(force on the wall)
                self.wall_work -= 0.5 * (before[w] + after[w]).dot(wall.velocity) * dt;
            }
        }
        self.update_acceleration();
        for i in 0..self.pos.len() {
            if self.active[i] {
                self.vel[i] += 0.5 * dt * self.acc[i];
            }
        }
        for i in 0..self.omega.len() {
            self.omega[i] += 0.5 * dt * self.torque[i] / self.inertia[i];
        }
        self.time += dt;
        self.steps += 1;
        Ok(())
    }

    /// Activates the particles whose insertion time has come (at the start of a step whose
    /// time has reached it), booking the energy they bring.
    fn insert_due(&mut self) {
        for i in 0..self.pos.len() {
            if !self.active[i] && self.insert_at[i] <= self.time {
                self.active[i] = true;
                self.inserted += 0.5 * self.mass[i] * self.vel[i].length_squared()
                    - self.mass[i] * self.gravity.dot(self.pos[i]);
            }
        }
    }

    /// Whether particle `i` has appeared (pouring: see `ParticleInit::insert_at`).
    pub fn is_active(&self, i: usize) -> bool {
        self.active[i]
    }

    /// Whether some wall moves.
    fn moving_walls(&self) -> bool {
        self.walls.iter().any(|w| w.motion.moves())
    }

    /// Where each wall's plane passes now (a point of it) and its velocity over the last
    /// step.
    pub fn walls_now(&self) -> Vec<(DVec3, DVec3)> {
        self.walls.iter().map(|w| (w.point, w.velocity)).collect()
    }

    /// Runs `n` steps.
    pub fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Energy dissipated by one contact over the last step: the work the pair did on the
    /// contact (trapezoidal: along δ for the normal force, along the tangential and
    /// relative angular motion for friction and rolling) minus the change of its stored
    /// energy. A step that crosses the contact's entry or exit edge integrates the normal
    /// work only over the part inside, from the force just inside the edge (the model's
    /// [`ContactModel::edges`]), so the jumps of JKR and jump-in adhesion are booked right.
    fn book(
        old: Option<&ContactRecord>,
        new: &ContactRecord,
        m: &Motion,
        dt: f64,
        edges: impl FnOnce() -> [(f64, f64); 2],
    ) -> f64 {
        let was_in = old.is_some_and(ContactRecord::engaged);
        let is_in = new.engaged();
        let blank = ContactRecord::default();
        let o = old.unwrap_or(&blank);
        // the edges only where the step crosses one (JKR's cost a contact-radius solve each)
        let edges = if was_in != is_in {
            edges()
        } else {
            [(0.0, 0.0); 2]
        };
        let (d0, f0) = if was_in { (o.delta, o.force) } else { edges[0] };
        let (d1, f1) = if is_in {
            (m.delta, new.force)
        } else {
            edges[1]
        };
        let normal = if was_in || is_in {
            0.5 * (f0 + f1) * (d1 - d0)
        } else {
            0.0
        };
        normal
            - 0.5 * (o.tangential.dot(o.v_t) + new.tangential.dot(m.v_t)) * dt
            - 0.5 * (o.rolling_torque.dot(o.omega_rel) + new.rolling_torque.dot(m.omega_rel)) * dt
            - (new.potential - o.potential)
    }

    /// Books the contacts that left the search range within one step (in key order, so the
    /// sum is reproducible): they leave with their last force.
    fn book_departed(old: PairMap, dt: f64, overlap: impl Fn(usize, usize) -> f64) -> f64 {
        let mut departed: Vec<_> = old.into_iter().collect();
        departed.sort_by_key(|(k, _)| *k);
        departed
            .into_iter()
            .map(|((a, b), c)| {
                let motion = Motion {
                    delta: overlap(a as usize, b as usize),
                    ..Default::default()
                };
                let edges = [(0.0, 0.0), (motion.delta, 0.0)];
                Self::book(Some(&c), &ContactRecord::default(), &motion, dt, || edges)
            })
            .sum()
    }

    fn compute_forces(&mut self, v_pred: &[DVec3], w_pred: &[DVec3]) -> Result<(), PowderError> {
        let dt = self.dt;
        self.force.iter_mut().for_each(|f| *f = DVec3::ZERO);
        self.torque.iter_mut().for_each(|t| *t = DVec3::ZERO);
        self.grid.rebuild(&self.pos);
        let rotation = !w_pred.is_empty();
        let omega_of = |i: usize| if rotation { w_pred[i] } else { DVec3::ZERO };
        let mut old = std::mem::take(&mut self.contacts);
        let mut new = PairMap::with_capacity_and_hasher(old.len().max(16), Default::default());
        let mut dissipated = 0.0;
        let mut failure = None;
        let mut peak = self.peak;
        {
            let pos = &self.pos;
            let radius = &self.radius;
            let pad = &self.cutoff_pad;
            let force = &mut self.force;
            let torque = &mut self.torque;
            let (periodic, domain) = (self.periodic, self.domain);
            let (models, nm, mass, material) =
                (&self.models, self.n_materials, &self.mass, &self.material);
            let active = &self.active;
            self.grid.for_each_pair(pos, |i, j| {
                if !(active[i] && active[j]) {
                    return;
                }
                let d = minimum_image(pos[i] - pos[j], periodic, domain);
                let dist2 = d.length_squared();
                let reach = pad[i] + radius[j];
                if dist2 >= reach * reach {
                    return;
                }
                let key = (i as u32, j as u32);
                let dist = dist2.sqrt();
                let delta = radius[i] + radius[j] - dist;
                let model = &models[material[i] * nm + material[j]];
                let prior = old.remove(&key);
                if delta <= -model.range() && prior.is_none() {
                    return;
                }
                let n = if dist > 0.0 { d / dist } else { DVec3::Z };
                let geom = PairGeometry::spheres(radius[i], radius[j], mass[i], mass[j]);
                let (wi, wj) = (omega_of(i), omega_of(j));
                let v_rel = v_pred[i] - v_pred[j];
                let v_c = v_rel - radius[i] * wi.cross(n) - radius[j] * wj.cross(n);
                let v_t = v_c - n * v_c.dot(n);
                let k = Kinematics {
                    delta,
                    delta_dot: -v_rel.dot(n),
                    n,
                    v_t,
                    v_roll: geom.r_eff() * (wi - wj).cross(n)
                        + 0.5 * (radius[i] - radius[j]) / (radius[i] + radius[j]) * v_t,
                };
                let mut history = prior.map(|c| c.history).unwrap_or_default();
                let r = model.respond(&k, &geom, dt, &mut history);
                if !(r.normal.force.is_finite() && r.tangential.is_finite()) && failure.is_none() {
                    failure = Some(format!(
                        "non-finite contact force between particles {i} and {j} (overlap {delta:e} m)"
                    ));
                }
                let motion = Motion {
                    delta,
                    v_t,
                    omega_rel: wi - wj,
                };
                let record = ContactRecord::new(history, delta, &r, &motion);
                let edges = || model.edges(&geom, k.delta_dot);
                dissipated += Self::book(prior.as_ref(), &record, &motion, dt, edges);
                let ratio = delta / geom.a12;
                if peak.is_none_or(|p: (f64, usize, Partner)| ratio > p.0) {
                    peak = Some((ratio, i, Partner::Particle(j)));
                }
                let f = r.normal.force * n + r.tangential;
                force[i] += f;
                force[j] -= f;
                if rotation {
                    let t = n.cross(r.tangential);
                    torque[i] += -radius[i] * t + r.rolling_torque;
                    torque[j] += -radius[j] * t - r.rolling_torque;
                }
                if delta > -model.range() || history.touched {
                    new.insert(key, record);
                }
            });
        }
        self.peak = peak;
        dissipated += Self::book_departed(old, dt, |i, j| self.overlap(i, j));
        self.contacts = new;

        let mut old_w = std::mem::take(&mut self.wall_contacts);
        let mut new_w = PairMap::with_capacity_and_hasher(old_w.len(), Default::default());
        for (w, wall) in self.walls.iter().enumerate() {
            let n = wall.normal;
            for (i, v_particle) in v_pred.iter().enumerate() {
                if !self.active[i] {
                    continue;
                }
                // relative to the (possibly moving) wall
                let v = &(*v_particle - wall.velocity);
                let delta = self.radius[i] - (self.pos[i] - wall.point).dot(n);
                let model = &self.wall_models[w * self.n_materials + self.material[i]];
                let key = (w as u32, i as u32);
                let prior = old_w.remove(&key);
                if delta <= -model.range() && prior.is_none() {
                    continue;
                }
                let geom = PairGeometry::wall(self.radius[i], self.mass[i]);
                let wi = omega_of(i);
                let v_c = *v - self.radius[i] * wi.cross(n);
                let v_t = v_c - n * v_c.dot(n);
                let k = Kinematics {
                    delta,
                    delta_dot: -v.dot(n),
                    n,
                    v_t,
                    // eq. 20 with r_j → ∞: (r_i − r_j)/(r_i + r_j) → −1
                    v_roll: geom.r_eff() * wi.cross(n) - 0.5 * v_t,
                };
                let mut history = prior.map(|c| c.history).unwrap_or_default();
                let r = model.respond(&k, &geom, dt, &mut history);
                if !(r.normal.force.is_finite() && r.tangential.is_finite()) && failure.is_none() {
                    failure = Some(format!(
                        "non-finite contact force between particle {i} and wall {w} (overlap {delta:e} m)"
                    ));
                }
                let motion = Motion {
                    delta,
                    v_t,
                    omega_rel: wi,
                };
                let record = ContactRecord::new(history, delta, &r, &motion);
                let edges = || model.edges(&geom, k.delta_dot);
                dissipated += Self::book(prior.as_ref(), &record, &motion, dt, edges);
                let ratio = delta / geom.a12;
                if self.peak.is_none_or(|p| ratio > p.0) {
                    self.peak = Some((ratio, i, Partner::Wall(w)));
                }
                self.force[i] += r.normal.force * n + r.tangential;
                if rotation {
                    self.torque[i] += -self.radius[i] * n.cross(r.tangential) + r.rolling_torque;
                }
                if delta > -model.range() || history.touched {
                    new_w.insert(key, record);
                }
            }
        }
        dissipated += Self::book_departed(old_w, dt, |w, i| self.wall_overlap(w, i));
        self.wall_contacts = new_w;
        self.dissipated += dissipated;
        if let Some(msg) = failure {
            return Err(PowderError::Run(format!(
                "step {} (t = {:e} s): {msg}; the time step may be too large for the stiffest contact ({})",
                self.steps + 1,
                self.time + self.dt,
                self.time_step.reason
            )));
        }
        Ok(())
    }

    /// The energy ledger now.
    pub fn energies(&self) -> Energies {
        let mut e = Energies {
            dissipated: self.dissipated,
            wall_work: self.wall_work,
            inserted: self.inserted,
            ..Default::default()
        };
        for i in 0..self.omega.len() {
            e.kinetic += 0.5 * self.inertia[i] * self.omega[i].length_squared();
        }
        // particles that have not appeared yet do not count
        for i in (0..self.pos.len()).filter(|&i| self.active[i]) {
            e.kinetic += 0.5 * self.mass[i] * self.vel[i].length_squared();
            e.gravitational -= self.mass[i] * self.gravity.dot(self.pos[i]);
        }
        // summed in key order, so the value does not depend on the maps' layout
        let mut stored: Vec<((u32, u32, bool), f64)> = self
            .contacts
            .iter()
            .map(|(k, c)| ((k.0, k.1, false), c.potential))
            .chain(
                self.wall_contacts
                    .iter()
                    .map(|(k, c)| ((k.0, k.1, true), c.potential)),
            )
            .collect();
        stored.sort_by_key(|(k, _)| *k);
        e.elastic = stored.iter().map(|(_, u)| u).sum();
        e
    }

    /// Force the particles exert on each wall now, N (normal and tangential parts).
    pub fn wall_forces(&self) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; self.walls.len()];
        let mut keys: Vec<_> = self.wall_contacts.keys().copied().collect();
        keys.sort();
        for k in keys {
            let c = &self.wall_contacts[&k];
            let w = k.0 as usize;
            f[w] -= c.force * self.walls[w].normal + c.tangential;
        }
        f
    }

    /// Every particle–particle contact the engine keeps (in the search range or engaged), as
    /// ((i, j), overlap, history) in key order; the history is i's side (n from j to i).
    pub fn contacts(&self) -> Vec<((u32, u32), f64, ContactHistory)> {
        let mut list: Vec<_> = self
            .contacts
            .iter()
            .map(|(k, c)| (*k, c.delta, c.history))
            .collect();
        list.sort_by_key(|c| c.0);
        list
    }

    /// Contact counts and overlap statistics now.
    pub fn contact_stats(&self) -> ContactStats {
        let mut s = ContactStats::default();
        let mut sum_ratio = 0.0;
        for (&(i, j), c) in &self.contacts {
            if c.delta > 0.0 {
                s.contacts += 1;
                let a12 = 2.0 * self.radius[i as usize] * self.radius[j as usize]
                    / (self.radius[i as usize] + self.radius[j as usize]);
                s.max_overlap = s.max_overlap.max(c.delta);
                s.max_overlap_ratio = s.max_overlap_ratio.max(c.delta / a12);
                sum_ratio += c.delta / a12;
            } else if c.engaged() {
                s.non_contact += 1;
            }
        }
        for (&(_, i), c) in &self.wall_contacts {
            if c.delta > 0.0 {
                s.wall_contacts += 1;
                let a12 = 2.0 * self.radius[i as usize];
                s.max_overlap = s.max_overlap.max(c.delta);
                s.max_overlap_ratio = s.max_overlap_ratio.max(c.delta / a12);
                sum_ratio += c.delta / a12;
            } else if c.engaged() {
                s.non_contact += 1;
            }
        }
        let n = self.pos.len().max(1) as f64;
        s.coordination = (2 * s.contacts + s.wall_contacts) as f64 / n;
        let touching = s.contacts + s.wall_contacts;
        if touching > 0 {
            s.mean_overlap_ratio = sum_ratio / touching as f64;
        }
        s
    }
}
