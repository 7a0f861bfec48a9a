//! Planar walls: their contacts' list, candidates and forces, and what the particles exert
//! on them.

use super::contact::{Contact, ContactRecord, StepLog};
use super::{CpuEngine, Partner};
use crate::cpu::threads::chunks;
use crate::model::{ContactModel, Kinematics, PairGeometry};
use crate::scene::WallPhase;
use glam::DVec3;

/// Particle–wall contacts, sorted by key (wall, particle): every step visits the keys in
/// this order, so the old records are merged into the new list without hashing.
#[derive(Clone, Debug, Default)]
pub(super) struct WallList {
    pub(super) key: Vec<(u32, u32)>,
    pub(super) record: Vec<ContactRecord>,
}

impl WallList {
    pub(super) fn clear(&mut self) {
        self.key.clear();
        self.record.clear();
    }

    pub(super) fn find(&self, key: (u32, u32)) -> Option<&ContactRecord> {
        self.key.binary_search(&key).ok().map(|k| &self.record[k])
    }

    pub(super) fn contacts(&self) -> impl Iterator<Item = ((u32, u32), &ContactRecord)> + '_ {
        self.key.iter().copied().zip(&self.record)
    }
}

/// What the wall contacts read: the particles, the walls and their models, the candidates
/// and the old contacts, and the predicted velocities of the step.
pub(super) struct WallInputs<'a> {
    pub(super) pos: &'a [DVec3],
    pub(super) radius: &'a [f64],
    pub(super) mass: &'a [f64],
    pub(super) material: &'a [usize],
    pub(super) n_materials: usize,
    pub(super) walls: &'a [WallPlane],
    pub(super) wall_models: &'a [ContactModel],
    pub(super) wall_ranges: &'a [f64],
    pub(super) candidates: &'a [u32],
    pub(super) old: &'a WallList,
    pub(super) v_pred: &'a [DVec3],
    pub(super) w_pred: &'a [DVec3],
    pub(super) dt: f64,
}

/// A piece of the wall contacts: candidates of one wall, and the old contacts it books.
pub(super) struct WallPiece {
    pub(super) wall: usize,
    pub(super) candidates: std::ops::Range<usize>,
    pub(super) old: std::ops::Range<usize>,
}

/// What a piece found: the contacts kept, each visited particle's force and torque, its log.
pub(super) struct WallOut {
    pub(super) kept: WallList,
    pub(super) pushes: Vec<(u32, DVec3, DVec3)>,
    pub(super) log: StepLog,
}

impl WallInputs<'_> {
    /// The contacts of one piece, in key order.
    #[inline(never)]
    pub(super) fn piece(&self, p: WallPiece) -> WallOut {
        let rotation = !self.w_pred.is_empty();
        let old = self.old;
        let mut out = WallOut {
            kept: WallList::default(),
            pushes: Vec::with_capacity(p.candidates.len()),
            log: StepLog::new(self.dt, None),
        };
        let mut cursor = p.old.start;
        // books the old contacts before `key` (all of the piece's for None): not visited
        // this step (none while particles stay active), so they left
        let leave = |log: &mut StepLog, cursor: &mut usize, key: Option<(u32, u32)>| {
            while *cursor < p.old.end && key.is_none_or(|k| old.key[*cursor] < k) {
                let (w, i) = old.key[*cursor];
                let wall = &self.walls[w as usize];
                let i = i as usize;
                let delta = wall.overlap(self.pos[i], self.radius[i]);
                log.depart(&old.record[*cursor], delta);
                *cursor += 1;
            }
        };
        let w = p.wall;
        for &i in &self.candidates[p.candidates.clone()] {
            let wall = &self.walls[w];
            let n = wall.normal;
            let i = i as usize;
            let key = (w as u32, i as u32);
            leave(&mut out.log, &mut cursor, Some(key));
            let prior = if cursor < p.old.end && old.key[cursor] == key {
                cursor += 1;
                Some(&old.record[cursor - 1])
            } else {
                None
            };
            // relative to the (possibly moving) wall
            let v = self.v_pred[i] - wall.velocity;
            let delta = wall.overlap(self.pos[i], self.radius[i]);
            let m = w * self.n_materials + self.material[i];
            let (model, range) = (&self.wall_models[m], self.wall_ranges[m]);
            if delta < -range && prior.is_none() {
                continue;
            }
            let geom = PairGeometry::wall(self.radius[i], self.mass[i]);
            let wi = if rotation {
                self.w_pred[i]
            } else {
                DVec3::ZERO
            };
            let v_c = v - self.radius[i] * wi.cross(n);
            let v_t = v_c - n * v_c.dot(n);
            let contact = Contact {
                model,
                geom,
                pair: model.pair_constants(&geom),
                kin: Kinematics {
                    delta,
                    delta_dot: -v.dot(n),
                    n,
                    v_t,
                    // eq. 20 with r_j → ∞: (r_i − r_j)/(r_i + r_j) → −1
                    v_roll: geom.r_eff() * wi.cross(n) - 0.5 * v_t,
                    omega_rel: wi,
                },
                root: None,
                i,
                partner: Partner::Wall(w),
            };
            let (r, couple) = out.log.contact(contact, prior);
            let torque = if rotation {
                -self.radius[i] * n.cross(r.tangential) + couple
            } else {
                DVec3::ZERO
            };
            out.pushes
                .push((i as u32, r.force * n + r.tangential, torque));
            if r.stays(range) {
                out.kept.key.push(key);
                out.kept.record.push(r);
            }
        }
        leave(&mut out.log, &mut cursor, None);
        out
    }
}

/// A planar wall: an infinite-mass body with the contact model of its material pair.
#[derive(Clone, Debug)]
pub(super) struct WallPlane {
    /// A point of the plane now (it moves with the wall).
    pub(super) point: DVec3,
    pub(super) normal: DVec3,
    pub(super) motion: crate::scene::WallMotion,
    /// Velocity over the current step.
    pub(super) velocity: DVec3,
}

impl WallPlane {
    /// Overlap of a sphere of radius `r` centred at `x` with the plane.
    pub(super) fn overlap(&self, x: DVec3, r: f64) -> f64 {
        r - (x - self.point).dot(self.normal)
    }
}

impl CpuEngine {
    /// Overlap of particle `i` with wall `w`. Panics where either is out of range.
    pub fn wall_overlap(&self, w: usize, i: usize) -> f64 {
        let wall = &self.walls[w];
        wall.overlap(self.pos[i], self.radius[i])
    }

    /// Whether some wall moves.
    pub(super) fn moving_walls(&self) -> bool {
        self.walls.iter().any(|w| w.motion.moves())
    }

    /// Where each wall's plane passes now (a point of it) and its velocity over the last
    /// step.
    pub fn walls_now(&self) -> Vec<(DVec3, DVec3)> {
        self.walls.iter().map(|w| (w.point, w.velocity)).collect()
    }

    /// The wall candidates from the positions now: per wall, the active particles whose
    /// overlap exceeds −(range + skin), and those in contact with it, ascending. Pieces of
    /// a chunk of particles of one wall are searched in parallel and joined in order.
    pub(super) fn rebuild_wall_candidates(&mut self) {
        let n = self.pos.len();
        let pieces: Vec<(usize, std::ops::Range<usize>)> = (0..self.walls.len())
            .flat_map(|w| chunks(n, self.threads.chunk()).map(move |r| (w, r)))
            .collect();
        let keys = &self.wall_contacts.key;
        let (pos, radius, active, material) =
            (&self.pos, &self.radius, &self.active, &self.material);
        let (walls, ranges, nm, skin) =
            (&self.walls, &self.wall_ranges, self.n_materials, self.skin);
        let found = self
            .threads
            .map_work(walls.len() * n, pieces, |(w, range)| {
                let wall = &walls[w];
                let first = (w as u32, range.start as u32);
                let mut cursor = keys.partition_point(|k| *k < first);
                let mut out = Vec::new();
                for i in range {
                    if !active[i] {
                        continue;
                    }
                    let key = (w as u32, i as u32);
                    while cursor < keys.len() && keys[cursor] < key {
                        cursor += 1;
                    }
                    let in_contact = keys.get(cursor) == Some(&key);
                    let delta = wall.overlap(pos[i], radius[i]);
                    let range = ranges[w * nm + material[i]];
                    if in_contact || delta > -(range + skin) {
                        out.push(i as u32);
                    }
                }
                (w, out)
            });
        self.wall_start.clear();
        self.wall_candidates.clear();
        self.wall_start.push(0);
        let mut pieces = found.into_iter().peekable();
        for w in 0..self.walls.len() {
            while let Some((_, out)) = pieces.next_if(|(pw, _)| *pw == w) {
                self.wall_candidates.extend(out);
            }
            self.wall_start.push(self.wall_candidates.len());
        }
        self.wall_ref = self.walls.iter().map(|w| w.point).collect();
    }

    /// Forces of the wall contacts (visited in key order (wall, particle), merged with the
    /// old list); returns the step's log of them. The candidates are cut into pieces
    /// evaluated in parallel; their forces are added in key order afterwards.
    #[inline(never)]
    pub(super) fn wall_contact_forces(&mut self, v_pred: &[DVec3], w_pred: &[DVec3]) -> StepLog {
        let chunk = self.threads.chunk();
        let old = std::mem::take(&mut self.wall_contacts);
        // pieces of at most a chunk of candidates of one wall, each booking the old contacts
        // from its first key up to the next piece's (the first from the start, the last
        // to the end): together every old contact, once
        let mut pieces: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
        for w in 0..self.walls.len() {
            let (s, e) = (self.wall_start[w], self.wall_start[w + 1]);
            for c in (s..e).step_by(chunk) {
                pieces.push((w, c..(c + chunk).min(e)));
            }
        }
        if pieces.is_empty() {
            pieces.push((0, 0..0));
        }
        let first_old = |p: usize| match pieces.get(p) {
            _ if p == 0 => 0,
            None => old.key.len(),
            Some((w, r)) => {
                let key = (*w as u32, self.wall_candidates[r.start]);
                old.key.partition_point(|k| *k < key)
            }
        };
        let work: Vec<WallPiece> = (0..pieces.len())
            .map(|p| WallPiece {
                wall: pieces[p].0,
                candidates: pieces[p].1.clone(),
                old: first_old(p)..first_old(p + 1),
            })
            .collect();
        let inputs = WallInputs {
            pos: &self.pos,
            radius: &self.radius,
            mass: &self.mass,
            material: &self.material,
            n_materials: self.n_materials,
            walls: &self.walls,
            wall_models: &self.wall_models,
            wall_ranges: &self.wall_ranges,
            candidates: &self.wall_candidates,
            old: &old,
            v_pred,
            w_pred,
            dt: self.dt,
        };
        let candidates = self.wall_candidates.len();
        let outs = self
            .threads
            .map_work(candidates, work, |piece| inputs.piece(piece));
        let mut log = StepLog::new(self.dt, self.peak);
        let mut new = std::mem::take(&mut self.spare_walls);
        new.clear();
        let rotation = !w_pred.is_empty();
        for out in outs {
            for (i, f, t) in out.pushes {
                self.force[i as usize] += f;
                if rotation {
                    self.torque[i as usize] += t;
                }
            }
            new.key.extend(out.kept.key);
            new.record.extend(out.kept.record);
            log.append(out.log);
        }
        self.wall_contacts = new;
        self.spare_walls = old;
        self.peak = log.peak;
        log
    }

    /// Force the particles exert on each wall now, N (normal and tangential parts).
    pub fn wall_forces(&self) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; self.walls.len()];
        for ((w, _), c) in self.wall_contacts.contacts() {
            let w = w as usize;
            f[w] -= c.force * self.walls[w].normal + c.tangential;
        }
        f
    }

    /// Moves the walls over the step about to be taken and returns the force on each before
    /// it (None where no wall moves). The velocity is the phase's at the step's start:
    /// prescribed, or the servo law from the force of the step before (at rest in the first
    /// step of a servo phase entered during the run).
    pub(super) fn move_walls(&mut self) -> Option<Vec<DVec3>> {
        if !self.moving_walls() {
            return None;
        }
        let before = self.wall_forces();
        let dt = self.dt;
        // (the phases by step k's start k·dt, as the GPU decides them, not the summed
        // time: both switch at the same step)
        let start = |k: u64| k as f64 * dt;
        let steps = self.steps;
        for (w, wall) in self.walls.iter_mut().enumerate() {
            let now = wall.motion.index_at(start(steps));
            let entered = steps > 0 && wall.motion.index_at(start(steps - 1)) != now;
            wall.velocity = match wall.motion.at(start(steps)) {
                WallPhase::Rest => DVec3::ZERO,
                WallPhase::Velocity(v) => DVec3::from_array(v),
                WallPhase::Servo { .. } if entered => DVec3::ZERO,
                WallPhase::Servo {
                    force,
                    gain,
                    max_speed,
                } => {
                    // the normal force the particles exert (they push against −n)
                    let pushed = -before[w].dot(wall.normal);
                    let speed = (gain * (force - pushed)).clamp(-max_speed, max_speed);
                    speed * wall.normal
                }
            };
            wall.point += dt * wall.velocity;
        }
        Some(before)
    }

    /// Books the work the moving walls did on the particles over the step, trapezoidal
    /// from the forces on them before (`before`) and after it.
    pub(super) fn book_wall_work(&mut self, before: &[DVec3]) {
        let after = self.wall_forces();
        for (w, wall) in self.walls.iter().enumerate() {
            // the wall pushes the particles with −(force on the wall)
            self.wall_work -= 0.5 * (before[w] + after[w]).dot(wall.velocity) * self.dt;
        }
    }
}
