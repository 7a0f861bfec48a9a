//! The evolving state of a CPU run, taken for a checkpoint and restored from one.

use super::contact::ContactRecord;
use super::pair_list::PairList;
use super::walls::WallList;
use super::CpuEngine;
use crate::error::PowderError;
use glam::DVec3;

/// Everything that evolves in a CPU run: what a checkpoint stores to resume bitwise.
#[derive(Clone, Debug)]
pub struct CpuState {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    pub(crate) dt: f64,
    pub(crate) pos: Vec<DVec3>,
    pub(crate) vel: Vec<DVec3>,
    pub(crate) acc: Vec<DVec3>,
    pub(crate) force: Vec<DVec3>,
    pub(crate) omega: Vec<DVec3>,
    pub(crate) torque: Vec<DVec3>,
    /// Contacts in key order (particle pairs, then particle–wall contacts by (wall, particle)).
    pub(crate) contacts: Vec<((u32, u32), ContactRecord)>,
    pub(crate) wall_contacts: Vec<((u32, u32), ContactRecord)>,
    pub(crate) dissipated: f64,
    /// Wall points and velocities (moving walls) and the work they did.
    pub(crate) wall_points: Vec<DVec3>,
    pub(crate) wall_velocities: Vec<DVec3>,
    pub(crate) wall_work: f64,
    /// Which particles have appeared, and the energy they brought.
    pub(crate) active: Vec<bool>,
    pub(crate) inserted: f64,
}

impl CpuEngine {
    /// The evolving state, for a checkpoint.
    pub fn state(&self) -> CpuState {
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
            contacts: self.pairs.contacts().map(|(k, r)| (k, *r)).collect(),
            wall_contacts: self
                .wall_contacts
                .contacts()
                .map(|(k, r)| (k, *r))
                .collect(),
            dissipated: self.dissipated,
            wall_points: self.walls.iter().map(|w| w.point).collect(),
            wall_velocities: self.walls.iter().map(|w| w.velocity).collect(),
            wall_work: self.wall_work,
            active: self.active.clone(),
            inserted: self.inserted,
        }
    }

    /// Continues from a checkpointed state of the same scene. The state must come from
    /// this scene (same particle count, time step, rotation and walls, every array its
    /// length); the checkpoint file checks the scene's identity before this is called. A
    /// refused state leaves the engine as it was.
    pub fn restore(&mut self, s: CpuState) -> Result<(), PowderError> {
        let n = self.pos.len();
        if s.pos.len() != n
            || s.vel.len() != n
            || s.acc.len() != n
            || s.force.len() != n
            || s.active.len() != n
            || s.omega.len() != self.omega.len()
            || s.torque.len() != self.omega.len()
        {
            let rotation = |o: &[DVec3]| if o.is_empty() { "" } else { " with rotation" };
            return Err(PowderError::Run(format!(
                "the checkpoint's state does not fit the scene's {n} particles{}: it holds {} positions, {} velocities, {} accelerations, {} forces, {} active flags, {} angular velocities and {} torques{} (a checkpoint of another scene, or damaged or edited)",
                rotation(&self.omega),
                s.pos.len(),
                s.vel.len(),
                s.acc.len(),
                s.force.len(),
                s.active.len(),
                s.omega.len(),
                s.torque.len(),
                rotation(&s.omega),
            )));
        }
        if s.wall_points.len() != self.walls.len() || s.wall_velocities.len() != self.walls.len() {
            return Err(PowderError::Run(format!(
                "the checkpoint holds {} walls but the scene has {}",
                s.wall_points.len(),
                self.walls.len()
            )));
        }
        if !(s.dt.is_finite() && s.dt > 0.0) {
            return Err(PowderError::Run(format!(
                "the checkpoint's dt is {:e} s, not a time step: the checkpoint was damaged or edited; rerun the scene, or resume an intact checkpoint",
                s.dt
            )));
        }
        if s.dt.to_bits() != self.dt.to_bits() {
            return Err(PowderError::Run(format!(
                "the checkpoint was run with dt = {:e} s but the scene gives dt = {:e} s; to continue it, set simulation.dt = {:?} (an automatic dt's rule can change between powder versions)",
                s.dt, self.dt, s.dt
            )));
        }
        // (time advances by dt a step: only rounding may separate it from steps·dt)
        let expected = s.steps as f64 * self.dt;
        let off = (s.time - expected).abs();
        if off.is_nan() || off > 1e-6 * expected.max(self.dt) {
            return Err(PowderError::Run(format!(
                "the checkpoint's time {:e} s is not its {} steps of dt = {:e} s ({expected:e} s): the checkpoint is damaged or was edited",
                s.time, s.steps, self.dt
            )));
        }
        let vectors = [
            ("positions", &s.pos),
            ("velocities", &s.vel),
            ("accelerations", &s.acc),
            ("forces", &s.force),
            ("angular velocities", &s.omega),
            ("torques", &s.torque),
            ("wall points", &s.wall_points),
            ("wall velocities", &s.wall_velocities),
        ];
        for (what, v) in vectors {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(PowderError::Run(format!(
                    "the checkpoint's {what} hold a value that is not finite at index {i} ({}): the checkpoint is damaged or was edited",
                    v[i]
                )));
            }
        }
        for (what, x) in [
            ("dissipated energy", s.dissipated),
            ("wall work", s.wall_work),
            ("inserted energy", s.inserted),
        ] {
            if !x.is_finite() {
                return Err(PowderError::Run(format!(
                    "the checkpoint's {what} is {x}, not finite: the checkpoint is damaged or was edited"
                )));
            }
        }
        if let Some(why) =
            crate::scene::misfit_appearance(&self.insert_at, &s.active, s.steps, self.dt)
        {
            return Err(PowderError::Run(format!(
                "the checkpoint does not fit the scene's pouring: {why} (the checkpoint is damaged or was edited)"
            )));
        }
        // contact keys: pairs i < j < n and walls (w, i) with i < n, each once
        let mut pair_keys: Vec<(u32, u32)> = s.contacts.iter().map(|(k, _)| *k).collect();
        let mut wall_keys: Vec<(u32, u32)> = s.wall_contacts.iter().map(|(k, _)| *k).collect();
        pair_keys.sort_unstable();
        wall_keys.sort_unstable();
        let bad_pair = pair_keys
            .iter()
            .find(|&&(i, j)| i >= j || j as usize >= n)
            .or_else(|| pair_keys.windows(2).find(|w| w[0] == w[1]).map(|w| &w[0]));
        let bad_wall = wall_keys
            .iter()
            .find(|&&(w, i)| w as usize >= self.walls.len() || i as usize >= n)
            .or_else(|| wall_keys.windows(2).find(|w| w[0] == w[1]).map(|w| &w[0]));
        if let Some((a, b)) = bad_pair.or(bad_wall) {
            return Err(PowderError::Run(format!(
                "the checkpoint holds an invalid or repeated contact ({a}, {b}) for {n} particles and {} walls",
                self.walls.len()
            )));
        }
        let records = (s
            .contacts
            .iter()
            .map(|(k, r)| ("contact of particles", k, r)))
        .chain(
            s.wall_contacts
                .iter()
                .map(|(k, r)| ("contact of wall and particle", k, r)),
        );
        for (what, (a, b), r) in records {
            if !r.is_finite() {
                return Err(PowderError::Run(format!(
                    "the checkpoint's {what} ({a}, {b}) holds a value that is not finite: the checkpoint is damaged or was edited"
                )));
            }
        }
        self.time = s.time;
        self.steps = s.steps;
        self.pos = s.pos;
        self.vel = s.vel;
        self.acc = s.acc;
        self.force = s.force;
        self.omega = s.omega;
        self.torque = s.torque;
        // the list holds the contacts until the next force evaluation rebuilds it around
        // them (the forces do not depend on the list beyond its contacts)
        self.pairs = PairList::from_contacts(n, s.contacts);
        self.rebuild_due = true;
        let mut walls = s.wall_contacts;
        walls.sort_by_key(|(k, _)| *k);
        self.wall_contacts = WallList {
            key: walls.iter().map(|(k, _)| *k).collect(),
            record: walls.into_iter().map(|(_, r)| r).collect(),
        };
        self.dissipated = s.dissipated;
        for (w, (p, v)) in self
            .walls
            .iter_mut()
            .zip(s.wall_points.into_iter().zip(s.wall_velocities))
        {
            w.point = p;
            w.velocity = v;
        }
        self.wall_work = s.wall_work;
        self.active = s.active;
        self.next_insert = self.earliest_pending();
        self.inserted = s.inserted;
        Ok(())
    }
}
