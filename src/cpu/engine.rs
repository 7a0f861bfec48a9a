//! The f64 CPU reference engine: velocity-Verlet integration, linked-cell contact search,
//! per-contact history keyed by the pair's persistent particle ids, gravity, planar walls
//! and an energy ledger (kinetic, stored, gravitational, dissipated) whose sum is conserved
//! up to the integration error.

use crate::cpu::cells::CellGrid;
use crate::error::PowderError;
use crate::model::{ContactHistory, ContactModel, PairGeometry, TimeStep};
use crate::scene::{DtSetting, Scene};
use glam::DVec3;
use std::collections::HashMap;

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default)]
struct ContactRecord {
    history: ContactHistory,
    /// Overlap, total normal force and stored energy at the end of the last step, for the
    /// work integral of the energy ledger.
    delta: f64,
    force: f64,
    potential: f64,
}

/// A planar wall: an infinite-mass body with the contact model of its material pair.
#[derive(Clone, Copy, Debug)]
struct WallPlane {
    point: DVec3,
    normal: DVec3,
}

/// Energies of the whole system, J.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Energies {
    pub kinetic: f64,
    /// Stored in contacts (recoverable elastic energy plus the adhesion potential).
    pub elastic: f64,
    /// −Σ m·g·x.
    pub gravitational: f64,
    /// Dissipated so far (plastic, adhesive hysteresis, viscous).
    pub dissipated: f64,
}

impl Energies {
    /// The conserved sum.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravitational + self.dissipated
    }
}

/// Contact statistics at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ContactStats {
    /// Particle–particle pairs in mechanical contact (δ > 0).
    pub contacts: usize,
    /// Particle–wall contacts (δ > 0).
    pub wall_contacts: usize,
    /// Pairs interacting without touching (non-contact adhesion range).
    pub non_contact: usize,
    /// Mean number of mechanical contacts per particle (walls included), 2·C/N + W/N.
    pub coordination: f64,
    /// Largest overlap, m.
    pub max_overlap: f64,
    /// Largest overlap over the pair's reduced radius a12.
    pub max_overlap_ratio: f64,
    pub mean_overlap_ratio: f64,
}

/// The CPU reference simulation.
pub struct CpuEngine {
    pub time: f64,
    pub steps: u64,
    dt: f64,
    time_step: TimeStep,
    pos: Vec<DVec3>,
    vel: Vec<DVec3>,
    acc: Vec<DVec3>,
    force: Vec<DVec3>,
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
    contacts: HashMap<(u32, u32), ContactRecord>,
    wall_contacts: HashMap<(u32, u32), ContactRecord>,
    dissipated: f64,
    domain: (DVec3, DVec3),
}

impl CpuEngine {
    /// Builds the engine from a validated scene, resolving pair models and the time step.
    pub fn new(scene: &Scene) -> Result<Self, PowderError> {
        let n_materials = scene.materials.len();
        let n = scene.particles.len();
        let mut models = Vec::with_capacity(n_materials * n_materials);
        for a in 0..n_materials {
            for b in 0..n_materials {
                models.push(scene.pair_model(a, b)?);
            }
        }
        let mut wall_models = Vec::with_capacity(scene.walls.len() * n_materials);
        for w in &scene.walls {
            for b in 0..n_materials {
                wall_models.push(scene.pair_model(w.material, b)?);
            }
        }
        let mut pos = Vec::with_capacity(n);
        let mut vel = Vec::with_capacity(n);
        let mut radius = Vec::with_capacity(n);
        let mut mass = Vec::with_capacity(n);
        let mut material = Vec::with_capacity(n);
        for p in &scene.particles {
            let rho = scene.materials[p.material].density;
            pos.push(DVec3::from_array(p.position));
            vel.push(DVec3::from_array(p.velocity));
            radius.push(p.radius);
            mass.push(rho * 4.0 / 3.0 * std::f64::consts::PI * p.radius.powi(3));
            material.push(p.material);
        }
        // Time step: the most demanding pair of materials, with the lightest particles of
        // each (walls count as infinite mass).
        let mut lightest = vec![f64::INFINITY; n_materials];
        for (m, &mat) in mass.iter().zip(&material) {
            lightest[mat] = lightest[mat].min(*m);
        }
        let mut time_step: Option<TimeStep> = None;
        let mut consider = |ts: TimeStep| {
            if time_step.as_ref().is_none_or(|t| ts.max < t.max) {
                time_step = Some(ts);
            }
        };
        for a in 0..n_materials {
            for b in 0..n_materials {
                if lightest[a].is_finite() && lightest[b].is_finite() {
                    let mr = lightest[a] * lightest[b] / (lightest[a] + lightest[b]);
                    consider(models[a * n_materials + b].time_step(mr));
                }
            }
            for w in 0..scene.walls.len() {
                if lightest[a].is_finite() {
                    consider(wall_models[w * n_materials + a].time_step(lightest[a]));
                }
            }
        }
        let time_step =
            time_step.ok_or_else(|| PowderError::Scene("the scene has no particles".into()))?;
        let dt = match scene.dt {
            DtSetting::Auto => time_step.default,
            DtSetting::Fixed(dt) => {
                if dt > time_step.max && !scene.force_dt {
                    return Err(PowderError::Scene(format!(
                        "dt = {dt:e} s is above the stable limit {:.4e} s ({}); use dt <= {:.4e} s or set force_dt = true",
                        time_step.max, time_step.reason, time_step.max
                    )));
                }
                dt
            }
        };
        let max_range = models
            .iter()
            .chain(&wall_models)
            .map(ContactModel::range)
            .fold(0.0, f64::max);
        let r_max = radius.iter().copied().fold(0.0, f64::max);
        let cutoff = 2.0 * r_max + max_range;
        let domain = (
            DVec3::from_array(scene.domain.min),
            DVec3::from_array(scene.domain.max),
        );
        let grid = CellGrid::new(domain.0, domain.1, cutoff * (1.0 + 1e-9), n);
        let walls = scene
            .walls
            .iter()
            .map(|w| WallPlane {
                point: DVec3::from_array(w.point),
                normal: DVec3::from_array(w.normal).normalize(),
            })
            .collect();
        let cutoff_pad = radius.iter().map(|r| r + max_range).collect();
        let mut engine = Self {
            time: 0.0,
            steps: 0,
            dt,
            time_step,
            acc: vec![DVec3::ZERO; n],
            force: vec![DVec3::ZERO; n],
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
            contacts: HashMap::new(),
            wall_contacts: HashMap::new(),
            dissipated: 0.0,
            domain,
        };
        let v_pred = engine.vel.clone();
        engine.compute_forces(&v_pred)?;
        engine.update_acceleration();
        // Contacts present at the start carry stored energy, not dissipation.
        engine.dissipated = 0.0;
        Ok(engine)
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The time-step rule the scene was checked against.
    pub fn time_step(&self) -> &TimeStep {
        &self.time_step
    }

    pub fn len(&self) -> usize {
        self.pos.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    pub fn positions(&self) -> &[DVec3] {
        &self.pos
    }

    pub fn velocities(&self) -> &[DVec3] {
        &self.vel
    }

    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

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

    /// Overlap δ = r_i + r_j − |x_i − x_j| of a pair.
    pub fn overlap(&self, i: usize, j: usize) -> f64 {
        self.radius[i] + self.radius[j] - self.pos[i].distance(self.pos[j])
    }

    /// Particles outside the domain box (informational; they still interact).
    pub fn outside_domain(&self) -> usize {
        let (lo, hi) = self.domain;
        self.pos
            .iter()
            .filter(|p| p.cmplt(lo).any() || p.cmpgt(hi).any())
            .count()
    }

    fn update_acceleration(&mut self) {
        for i in 0..self.pos.len() {
            self.acc[i] = self.force[i] / self.mass[i] + self.gravity;
        }
    }

    /// One velocity-Verlet step. The viscous forces see the predicted velocity
    /// v + a·dt, which keeps the damped oscillator second-order accurate.
    pub fn step(&mut self) -> Result<(), PowderError> {
        let dt = self.dt;
        let mut v_pred = Vec::with_capacity(self.pos.len());
        for i in 0..self.pos.len() {
            let v_half = self.vel[i] + 0.5 * dt * self.acc[i];
            self.pos[i] += dt * v_half;
            v_pred.push(v_half + 0.5 * dt * self.acc[i]);
            self.vel[i] = v_half;
        }
        self.compute_forces(&v_pred)?;
        self.update_acceleration();
        for i in 0..self.pos.len() {
            self.vel[i] += 0.5 * dt * self.acc[i];
        }
        self.time += dt;
        self.steps += 1;
        Ok(())
    }

    /// Runs `n` steps.
    pub fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Books the energy of one contact over the last step: the work the pair did on the
    /// contact (trapezoidal in δ) minus the change of its stored energy is dissipated.
    /// A new contact enters at the edge of the range, δ = −range, with no force or energy.
    fn book(
        old: Option<&ContactRecord>,
        range: f64,
        delta: f64,
        force: f64,
        potential: f64,
    ) -> f64 {
        let (d0, f0, u0) = old.map_or((-range, 0.0, 0.0), |c| (c.delta, c.force, c.potential));
        0.5 * (f0 + force) * (delta - d0) - (potential - u0)
    }

    fn compute_forces(&mut self, v_pred: &[DVec3]) -> Result<(), PowderError> {
        self.force.iter_mut().for_each(|f| *f = DVec3::ZERO);
        self.grid.rebuild(&self.pos);
        let mut old = std::mem::take(&mut self.contacts);
        let mut new = HashMap::with_capacity(old.len().max(16));
        let mut dissipated = 0.0;
        let mut failure = None;
        {
            let pos = &self.pos;
            let radius = &self.radius;
            let pad = &self.cutoff_pad;
            let force = &mut self.force;
            let (models, nm, mass, material) =
                (&self.models, self.n_materials, &self.mass, &self.material);
            self.grid.for_each_pair(pos, |i, j| {
                let d = pos[i] - pos[j];
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
                let delta_dot = -(v_pred[i] - v_pred[j]).dot(n);
                let geom = PairGeometry::spheres(radius[i], radius[j], mass[i], mass[j]);
                let mut history = prior.map(|c| c.history).unwrap_or_default();
                let nf = model.force(delta, delta_dot, &geom, &mut history);
                if !nf.force.is_finite() && failure.is_none() {
                    failure = Some(format!(
                        "non-finite contact force between particles {i} and {j} (overlap {delta:e} m)"
                    ));
                }
                dissipated += Self::book(prior.as_ref(), model.range(), delta, nf.force, nf.potential);
                force[i] += nf.force * n;
                force[j] -= nf.force * n;
                if delta > -model.range() {
                    new.insert(
                        key,
                        ContactRecord {
                            history,
                            delta,
                            force: nf.force,
                            potential: nf.potential,
                        },
                    );
                }
            });
        }
        // Pairs that jumped beyond the cutoff in one step leave with their last force.
        for ((i, j), c) in old.drain() {
            let delta = self.overlap(i as usize, j as usize);
            dissipated += Self::book(Some(&c), 0.0, delta, 0.0, 0.0);
        }
        self.contacts = new;

        let mut old_w = std::mem::take(&mut self.wall_contacts);
        let mut new_w = HashMap::with_capacity(old_w.len());
        for (w, wall) in self.walls.iter().enumerate() {
            for (i, v) in v_pred.iter().enumerate() {
                let delta = self.radius[i] - (self.pos[i] - wall.point).dot(wall.normal);
                let model = &self.wall_models[w * self.n_materials + self.material[i]];
                let key = (w as u32, i as u32);
                let prior = old_w.remove(&key);
                if delta <= -model.range() && prior.is_none() {
                    continue;
                }
                let delta_dot = -v.dot(wall.normal);
                let geom = PairGeometry::wall(self.radius[i], self.mass[i]);
                let mut history = prior.map(|c| c.history).unwrap_or_default();
                let nf = model.force(delta, delta_dot, &geom, &mut history);
                if !nf.force.is_finite() && failure.is_none() {
                    failure = Some(format!(
                        "non-finite contact force between particle {i} and wall {w} (overlap {delta:e} m)"
                    ));
                }
                dissipated +=
                    Self::book(prior.as_ref(), model.range(), delta, nf.force, nf.potential);
                self.force[i] += nf.force * wall.normal;
                if delta > -model.range() {
                    new_w.insert(
                        key,
                        ContactRecord {
                            history,
                            delta,
                            force: nf.force,
                            potential: nf.potential,
                        },
                    );
                }
            }
        }
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
            ..Default::default()
        };
        for i in 0..self.pos.len() {
            e.kinetic += 0.5 * self.mass[i] * self.vel[i].length_squared();
            e.gravitational -= self.mass[i] * self.gravity.dot(self.pos[i]);
        }
        e.elastic = self
            .contacts
            .values()
            .chain(self.wall_contacts.values())
            .map(|c| c.potential)
            .sum();
        e
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
            } else {
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
            } else {
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
