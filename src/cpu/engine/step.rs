//! One velocity-Verlet step of the CPU engine: the kicks and drift over the threads' chunks,
//! periodic wrapping, pouring, the force evaluation and the force jumps' impulses.

use super::*;
use crate::cpu::threads::chunks;
use crate::scene::insert_due_at;

/// A particle's acceleration from its force, mass and gravity: one expression for the
/// constructor and the step, so both give the same bits.
#[inline(always)]
fn acceleration(force: DVec3, mass: f64, gravity: DVec3) -> DVec3 {
    force / mass + gravity
}

/// `v` in chunks of `chunk` elements where it holds all `n` particles' values, else one
/// empty slice a chunk (rotations of a scene whose particles do not rotate).
pub(super) fn chunks_or_empty(v: &mut [DVec3], n: usize, chunk: usize) -> Vec<&mut [DVec3]> {
    if v.len() == n {
        v.chunks_mut(chunk).collect()
    } else {
        chunks(n, chunk)
            .map(|_| <&mut [DVec3]>::default())
            .collect()
    }
}

impl CpuEngine {
    /// The accelerations from the forces (at construction; `step` computes them with its
    /// last half kicks).
    pub(super) fn update_acceleration(&mut self) {
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
        self.steps += 1;
        // (k·dt, not a sum, which drifts by 1e-11 over 10⁶ steps: the GPU's clock to the bit)
        self.time = self.steps as f64 * self.dt;
        Ok(())
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

    /// Activates the particles whose insertion time has come (at the start of a step whose
    /// time has reached it), booking the energy they bring.
    fn insert_due(&mut self) {
        if !insert_due_at(self.next_insert, self.steps, self.dt) {
            return;
        }
        for i in 0..self.pos.len() {
            if !self.active[i] && insert_due_at(self.insert_at[i], self.steps, self.dt) {
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
    pub(super) fn earliest_pending(&self) -> f64 {
        (self.insert_at.iter().zip(&self.active))
            .filter(|(_, &a)| !a)
            .map(|(&t, _)| t)
            .fold(f64::INFINITY, f64::min)
    }

    /// Runs `n` steps. An error means a contact law failed; a state gone non-finite or
    /// too deep is not an error here: [`Self::non_finite`] and
    /// [`Self::take_peak_overlap`] tell (the run loop checks them after each chunk).
    pub fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        let threads = self.threads.clone();
        threads.install(|| {
            for _ in 0..n {
                self.step()?;
            }
            Ok(())
        })
    }

    pub(super) fn compute_forces(&mut self) -> Result<(), PowderError> {
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
                "step {} (t = {:.6e} s): {msg}; the time step may be too large for the stiffest contact ({})",
                self.steps + 1,
                self.time + self.dt,
                self.time_step.reason
            )));
        }
        Ok(())
    }
}
