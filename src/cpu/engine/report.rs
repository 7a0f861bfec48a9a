//! What a CPU run reports of its contacts and energies: the ledger, the contact list and
//! network, and contact statistics.

use super::{CpuEngine, Partner};
use crate::gpu::composition::Composition;
use crate::model::{ContactHistory, ContactModel};
use crate::output::contacts::{ContactLine, ContactNetwork};

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
    /// Mean number of mechanical contacts per particle (walls included), 2·C/N + W/N, N
    /// the particles that have appeared (pouring).
    pub coordination: f64,
    /// Largest overlap, m.
    pub max_overlap: f64,
    /// Largest overlap over the pair's reduced radius a12.
    pub max_overlap_ratio: f64,
    /// Mean overlap over a12 of the mechanical contacts (walls included; a12 = 2r for a wall);
    /// 0 without contacts.
    pub mean_overlap_ratio: f64,
}

impl CpuEngine {
    /// The energy ledger now.
    pub fn energies(&self) -> Energies {
        let mut e = Energies {
            dissipated: self.dissipated,
            wall_work: self.wall_work,
            inserted: self.inserted,
            ..Default::default()
        };
        // particles that have not appeared yet do not count (their energy is booked as
        // `inserted` when they appear)
        for i in (0..self.omega.len()).filter(|&i| self.active[i]) {
            e.kinetic += 0.5 * self.inertia[i] * self.omega[i].length_squared();
        }
        for i in (0..self.pos.len()).filter(|&i| self.active[i]) {
            e.kinetic += 0.5 * self.mass[i] * self.vel[i].length_squared();
            e.gravitational -= self.mass[i] * self.gravity.dot(self.pos[i]);
        }
        // summed in key order (pairs and wall contacts merged by (first id, second id),
        // pairs first), so the value does not depend on the lists' layout
        let mut pairs = self.pairs.contacts().peekable();
        let mut walls = self.wall_contacts.contacts().peekable();
        loop {
            let take_pair = match (pairs.peek(), walls.peek()) {
                (None, None) => break,
                (Some(p), Some(w)) => p.0 <= w.0,
                (p, _) => p.is_some(),
            };
            let (_, c) = if take_pair {
                pairs.next()
            } else {
                walls.next()
            }
            .expect("peeked");
            e.elastic += c.potential;
        }
        e
    }

    /// Every particle–particle contact the engine keeps (in the search range or engaged), as
    /// ((i, j), overlap, history) in key order; the history is i's side (n from j to i).
    pub fn contacts(&self) -> Vec<((u32, u32), f64, ContactHistory)> {
        self.pairs
            .contacts()
            .map(|(k, c)| (k, c.delta, c.history))
            .collect()
    }

    /// The engaged contacts now (touching, exerting a force or storing energy): pairs by
    /// (i, j), then wall contacts by (wall, particle), with the scene's history fields.
    pub fn contact_network(&self) -> ContactNetwork {
        let mut lines = Vec::new();
        for ((i, j), c) in self.pairs.contacts().filter(|(_, c)| c.engaged()) {
            let (i, j) = (i as usize, j as usize);
            let n = self.separation(i, j).normalize_or_zero();
            lines.push(ContactLine {
                i,
                partner: Partner::Particle(j),
                normal_force: c.force,
                force: c.force * n + c.tangential,
                overlap: c.delta,
                history: c.history,
                sliding: c.sliding,
            });
        }
        for ((w, i), c) in self.wall_contacts.contacts().filter(|(_, c)| c.engaged()) {
            let w = w as usize;
            lines.push(ContactLine {
                i: i as usize,
                partner: Partner::Wall(w),
                normal_force: c.force,
                force: c.force * self.walls[w].normal + c.tangential,
                overlap: c.delta,
                history: c.history,
                sliding: c.sliding,
            });
        }
        let models: Vec<ContactModel> = self
            .models
            .iter()
            .chain(&self.wall_models)
            .copied()
            .collect();
        ContactNetwork {
            lines,
            fields: Composition::of(&models).history(),
        }
    }

    /// Contact counts and overlap statistics now.
    pub fn contact_stats(&self) -> ContactStats {
        let mut s = ContactStats::default();
        let mut sum_ratio = 0.0;
        for ((i, j), c) in self.pairs.contacts() {
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
        for ((_, i), c) in self.wall_contacts.contacts() {
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
        // (per particle that has appeared: the energies count no other)
        let n = self.active.iter().filter(|&&a| a).count().max(1) as f64;
        s.coordination = (2 * s.contacts + s.wall_contacts) as f64 / n;
        let touching = s.contacts + s.wall_contacts;
        if touching > 0 {
            s.mean_overlap_ratio = sum_ratio / touching as f64;
        }
        s
    }
}
