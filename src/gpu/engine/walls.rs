//! What changes at batch boundaries: prescribed and servo walls, wall programs' phases, and pouring.

use super::*;
use crate::scene::insert_due_at;

/// How many steps from step `steps` on start before time `t` (step k starts at k·dt, the
/// time the phases and insertions are decided at), at least 1: a batch of that many ends
/// where the first step at or after `t` would start, whatever the rounding of the ratio.
pub(super) fn steps_before(steps: u64, dt: f64, t: f64) -> u64 {
    let starts = |k: u64| (steps + k) as f64 * dt;
    let mut j = (((t - starts(0)) / dt).ceil().max(1.0)) as u64;
    while j > 1 && starts(j - 1) >= t {
        j -= 1;
    }
    while starts(j) < t {
        j += 1;
    }
    j
}

/// The device's flags of which particles have appeared (1) or not yet (0).
pub(super) fn appeared_flags(active: &[bool]) -> Vec<u32> {
    active.iter().map(|&a| u32::from(a)).collect()
}

impl GpuEngine {
    /// Writes the prescribed walls' exact points and their velocities at the current time;
    /// returns how many steps the velocities stay valid (until the next switch of a
    /// schedule), at least 1.
    pub(super) fn prescribe_walls(&self) -> u64 {
        let mut valid = u64::MAX;
        for (w, m) in self.wall_motion.iter().enumerate() {
            if let Some(t) = m.next_switch(self.time) {
                // steps that start before the switch keep this phase (as on the CPU)
                valid = valid.min(steps_before(self.steps, self.dt, t));
            }
            if !matches!(m.at(self.time), WallPhase::Velocity(_)) {
                continue;
            }
            let v = m.prescribed_velocity(self.time);
            self.write_wall(w, [v[0] as f32, v[1] as f32, v[2] as f32, 0.0]);
        }
        valid
    }

    /// Writes wall `w` to the device at the host's point, with `velocity` and the motion
    /// of its phase now.
    pub(super) fn write_wall(&self, w: usize, velocity: [f32; 4]) {
        let mut wall = WallGpu::new(
            self.wall_points[w],
            self.wall_normals[w],
            self.origin,
            self.h,
        );
        wall.velocity = velocity;
        wall.motion = WallGpu::motion_code(self.wall_motion[w].at(self.time));
        let at = (w * std::mem::size_of::<WallGpu>()) as u64;
        self.ctx
            .queue
            .write_buffer(&self.b.walls, at, bytemuck::bytes_of(&wall));
    }

    /// Puts each wall whose phase changes at this batch's start into its new phase on the
    /// device, where it starts at rest: a servo wall's point (kept by the device, not the
    /// host) is read back first.
    pub(super) fn switch_wall_phases(&mut self) -> Result<(), PowderError> {
        let changed: Vec<usize> = (0..self.wall_motion.len())
            .filter(|&w| self.wall_motion[w].index_at(self.time) != self.wall_phase[w])
            .collect();
        let servo_before = changed.iter().any(|&w| self.servo_now(w));
        let now = if servo_before {
            self.walls_now()?
        } else {
            Vec::new()
        };
        for w in changed {
            if self.servo_now(w) {
                self.wall_points[w] = now[w].0;
            }
            self.write_wall(w, [0.0; 4]);
            self.wall_phase[w] = self.wall_motion[w].index_at(self.time);
        }
        Ok(())
    }

    /// Whether wall `w` is in a servo phase on the device (the phase of the last step run):
    /// its point is then the device's, not the host's.
    fn servo_now(&self, w: usize) -> bool {
        (self.wall_phase[w])
            .is_some_and(|i| matches!(self.wall_motion[w].phases[i].1, WallPhase::Servo { .. }))
    }

    /// Writes which particles have appeared to the device and into the state (`appear`:
    /// where the scene pours; else all have, and the kernels do not ask).
    pub(super) fn write_appeared(&self) {
        let Some(appear) = &self.bound.appear else {
            return;
        };
        self.ctx.queue.write_buffer(
            &self.b.appeared,
            0,
            bytemuck::cast_slice(&appeared_flags(&self.active)),
        );
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            // (a window's particles: every window's dispatch the same)
            let per_window = (self.n as u64).min(self.windowing.windows.len) as u32;
            for group in &appear.groups {
                appear
                    .kernel
                    .dispatch(&mut pass, group, per_window, self.max_per_dim);
            }
        }
        self.ctx.queue.submit([encoder.finish()]);
    }

    /// Whether particle `i` (the scene's order) has appeared (pouring).
    pub fn has_appeared(&self, i: usize) -> bool {
        self.active.get(i).copied().unwrap_or(false)
    }

    /// Activates the particles whose insertion time has come (at the start of a step whose
    /// time has reached it, as on the CPU), writing the device's flags when they change;
    /// returns how many steps until the next insertion (at least 1).
    pub(super) fn insert_due(&mut self) -> u64 {
        let mut changed = false;
        let mut next = u64::MAX;
        for i in 0..self.active.len() {
            if self.active[i] {
                continue;
            }
            if insert_due_at(self.insert_at[i], self.steps, self.dt) {
                self.active[i] = true;
                self.inserted += self.insert_energy[i];
                changed = true;
            } else {
                next = next.min(steps_before(self.steps, self.dt, self.insert_at[i]));
            }
        }
        if changed {
            self.write_appeared();
            // the lists hold no pair of a particle that had not appeared: rebuild them
            // before the next step's forces, as the CPU does
            self.ctx
                .queue
                .write_buffer(&self.b.control, SKIN_OFFSET, bytemuck::bytes_of(&1u32));
        }
        next
    }

    /// Advances the host's points of the prescribed walls by `steps` steps.
    pub(super) fn advance_prescribed_walls(&mut self, steps: u64) {
        for (w, m) in self.wall_motion.iter().enumerate() {
            if matches!(m.at(self.time), WallPhase::Velocity(_)) {
                let v = DVec3::from_array(m.prescribed_velocity(self.time));
                for _ in 0..steps {
                    self.wall_points[w] += self.dt * v;
                }
            }
        }
    }

    /// Each wall's point now (where its plane passes) and its velocity over the last step,
    /// read back from the device.
    pub fn walls_now(&self) -> Result<Vec<(DVec3, DVec3)>, PowderError> {
        if self.wall_normals.is_empty() {
            return Ok(Vec::new());
        }
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(&self.ctx, encoder, &[(&self.b.walls, self.b.walls.size())])?;
        let walls: Vec<WallGpu> = bytemuck::pod_collect_to_vec(&out[0]);
        Ok(walls
            .iter()
            .take(self.wall_normals.len())
            .enumerate()
            .map(|(i, w)| {
                // the host's exact point but where a servo moves the wall (the device's then:
                // the stored point less its residual along the normal, `WallGpu::offset`)
                let n = DVec3::new(w.normal[0] as f64, w.normal[1] as f64, w.normal[2] as f64);
                let p = match self.servo_now(i) {
                    true => {
                        crate::gpu::layout::decode3(w.cell, w.offset, self.origin, self.h)
                            - w.offset[3] as f64 * n
                    }
                    false => self.wall_points[i],
                };
                let v = DVec3::new(
                    w.velocity[0] as f64,
                    w.velocity[1] as f64,
                    w.velocity[2] as f64,
                );
                (p, v)
            })
            .collect())
    }

    /// Force of the particles on each wall after the last step, N: each wall contact's normal
    /// force (its prior) and tangential force (kept in its entry's pair torque where
    /// particles rotate; there is none otherwise). Right after a restore, until a step has
    /// run, the tangential part is missing (a saved state leaves the per-step fields out).
    pub fn wall_forces(&self) -> Result<Vec<DVec3>, PowderError> {
        let walls = self.wall_normals.len();
        let mut f = vec![DVec3::ZERO; walls];
        if walls == 0 {
            return Ok(f);
        }
        let s = &self.state;
        if s.entry_layout.place("prior").is_none() {
            return Err(PowderError::Run(
                "this GPU run keeps neither the energy ledger (GpuOptions { ledger: false }) nor force jumps, whose per-contact records hold the wall forces".into(),
            ));
        }
        let WallEntries { entries, found, .. } = self.read_wall_entries()?;
        let windows = s.layout.windows();
        // (overlap, normal force, .., 1 while engaged), each wall's particles in order
        for (_, w, e) in found {
            let read = s
                .entry_layout
                .read_vec4(&entries, "prior", (self.entries, windows), e);
            let row = read.unwrap_or_default();
            if row[3] > 0.0 {
                let t = s
                    .entry_layout
                    .read_vec3(&entries, "pair_torque", (self.entries, windows), e)
                    .map_or(DVec3::ZERO, |t| {
                        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
                    });
                f[w] -= row[1] as f64 * self.wall_normals[w] + t;
            }
        }
        Ok(f)
    }
}
