//! What the CPU engine answers about its particles and contacts, and its thread count.

use super::*;
use crate::gpu::composition::Composition;
use crate::model::ContactHistory;

impl CpuEngine {
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

    /// Sets particle `i`'s angular velocity, rad/s, at any time (a scene's initial spin is
    /// `ParticleInit::angular_velocity`). The energy it adds or takes away from a particle
    /// that has appeared is booked as `inserted`, so the ledger still closes. Only where
    /// particles rotate (some contact model exerts tangential forces or torques).
    pub fn set_angular_velocity(&mut self, i: usize, omega: DVec3) -> Result<(), PowderError> {
        if self.omega.is_empty() {
            return Err(PowderError::Run(
                "the particles do not rotate: no contact model has friction, rolling or twisting resistance".into(),
            ));
        }
        if !omega.is_finite() {
            return Err(PowderError::Run(format!(
                "the angular velocity of particle {i} must be finite, got {omega}"
            )));
        }
        let n = self.omega.len();
        let w = self.omega.get_mut(i).ok_or_else(|| {
            PowderError::Run(format!("particle {i} does not exist ({n} particles)"))
        })?;
        if self.active[i] {
            self.inserted += 0.5 * self.inertia[i] * (omega.length_squared() - w.length_squared());
        }
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

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Number of walls.
    pub fn wall_count(&self) -> usize {
        self.walls.len()
    }

    /// The digests of the parts of the scene it was built from, named as in the scene
    /// file (`checkpoint::run_digests`, all wall phases).
    pub fn scene_parts(&self) -> &[(String, u64)] {
        &self.scene_parts
    }

    /// Particle masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Net contact force on each particle from the last force evaluation.
    pub fn forces(&self) -> &[DVec3] {
        &self.force
    }

    /// History of the contact between particles `i` and `j` (persistent ids), if any, as
    /// `i` sees it (as `GpuEngine::contact_history` gives it): `contact_history(j, i)` has
    /// the same flags and ξ, and each field its declaration mirrors (the tangential spring)
    /// negated.
    pub fn contact_history(&self, i: usize, j: usize) -> Option<ContactHistory> {
        let k = self.pairs.find(i.min(j), i.max(j))?;
        // (stored as the lower id sees it)
        let h = self.pairs.live[k].then(|| self.pairs.record[k].history)?;
        if i < j {
            return Some(h);
        }
        let model = self.models[self.material[i] * self.n_materials + self.material[j]];
        Some(Composition::of(&[model]).mirror_history(h))
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

    /// The particle with a non-finite position, velocity or angular velocity, if any.
    pub fn non_finite(&self) -> Option<usize> {
        (0..self.pos.len()).find(|&i| {
            !(self.pos[i].is_finite()
                && self.vel[i].is_finite()
                && self.omega.get(i).is_none_or(|w| w.is_finite()))
        })
    }

    /// The deepest overlap over the reduced radius a12 reached by any contact in any step
    /// since the last call: `(ratio, particle, partner)`. Resets the record.
    pub fn take_peak_overlap(&mut self) -> Option<(f64, usize, Partner)> {
        self.peak.take()
    }

    /// Whether particle `i` has appeared (pouring: see `ParticleInit::insert_at`). Panics
    /// where `i` is not a particle.
    pub fn is_active(&self, i: usize) -> bool {
        self.active[i]
    }

    /// Neighbour-list rebuilds so far (since the engine was built; not part of the state).
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }
}
