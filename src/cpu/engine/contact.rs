//! One contact's work over a step, the same for pairs and walls: its response, the record it
//! keeps, the energy booked in the ledger and the impulses of its force jumps.

use super::Partner;
use crate::cpu::jump::Crossing;
use crate::model::{
    ContactHistory, ContactModel, Kinematics, PairConstants, PairGeometry, Response,
};
use glam::DVec3;

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ContactRecord {
    pub(crate) history: ContactHistory,
    /// Overlap, forces and stored energy at the end of the last step, for the work
    /// integral of the energy ledger.
    pub(crate) delta: f64,
    pub(crate) force: f64,
    /// The tangential force on i (a wall's reaction reads it).
    pub(crate) tangential: DVec3,
    pub(crate) potential: f64,
    /// The power of friction (F_t · v_t) and of the couple on i (rolling and twisting
    /// resistance, M · (ω_i − ω_j)) at the forces' evaluation: the ledger integrates
    /// them trapezoidally.
    pub(crate) friction_power: f64,
    pub(crate) couple_power: f64,
    /// Whether the tangential force slid at the Coulomb limit (the contact network output).
    pub(crate) sliding: bool,
}

impl ContactRecord {
    /// Whether every number it holds is finite (a checkpoint's are checked on restore).
    pub(super) fn is_finite(&self) -> bool {
        let h = &self.history;
        [
            self.delta,
            self.force,
            self.potential,
            self.friction_power,
            self.couple_power,
            h.delta_max,
            h.contact_radius,
            h.twist,
        ]
        .iter()
        .all(|x| x.is_finite())
            && [self.tangential, h.tangential, h.rolling]
                .iter()
                .all(|v| v.is_finite())
    }

    /// Whether the contact takes part in the energy ledger: touched, or exerting a force,
    /// or storing energy (a pair merely within search range is not engaged).
    pub(super) fn engaged(&self) -> bool {
        self.history.touched || self.potential != 0.0 || self.force != 0.0
    }

    /// Whether the contact stays in the list: in the model's interaction range, or
    /// touched (a history that outlives the range until it lets go).
    pub(super) fn stays(&self, range: f64) -> bool {
        self.delta >= -range || self.history.touched
    }

    pub(super) fn new(history: ContactHistory, delta: f64, r: &Response, m: &Motion) -> Self {
        Self {
            history,
            delta,
            force: r.normal.force,
            tangential: r.tangential,
            potential: r.potential,
            friction_power: r.tangential.dot(m.v_t),
            couple_power: r.couple.dot(m.omega_rel),
            sliding: r.sliding,
        }
    }
}

/// Relative motion of a pair over the last step that the ledger needs.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Motion {
    pub(super) delta: f64,
    /// Tangential velocity at the contact and relative angular velocity ω_i − ω_j.
    pub(super) v_t: DVec3,
    pub(super) omega_rel: DVec3,
}

/// One contact as a force loop measures it over a step (a pair, or a particle and a wall).
pub(super) struct Contact<'a> {
    pub(super) model: &'a ContactModel,
    pub(super) geom: PairGeometry,
    /// The model's constants of this pair ([`ContactModel::pair_constants`]).
    pub(super) pair: PairConstants,
    pub(super) kin: Kinematics,
    /// The law's root at `kin.delta` solved ahead ([`ContactModel::root_ahead`]), or None.
    pub(super) root: Option<f64>,
    /// The particle and its partner, for the peak overlap and the error message.
    pub(super) i: usize,
    pub(super) partner: Partner,
}

/// The impulse of a force jump inside a step on particle i (−it on a particle partner),
/// added to the velocities at the end of the step ([`crate::cpu::jump`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Jump {
    pub(super) i: usize,
    pub(super) partner: Partner,
    pub(super) impulse: DVec3,
}

/// The error message of a contact whose force is not finite.
#[cold]
#[inline(never)]
pub(super) fn non_finite(i: usize, partner: Partner, delta: f64) -> String {
    let between = match partner {
        Partner::Particle(j) => format!("particles {i} and {j}"),
        Partner::Wall(w) => format!("particle {i} and wall {w}"),
    };
    format!("non-finite contact force between {between} (overlap {delta:e} m)")
}

/// What the force loops gather over a step (or a chunk of it) besides the forces: the
/// energy the contacts dissipated, the deepest overlap and the first non-finite force.
pub(super) struct StepLog {
    pub(super) dt: f64,
    /// The impulses of the force jumps inside the step, in key order.
    pub(super) jumps: Vec<Jump>,
    /// Energy of the contacts visited, and of those that left without a visit, each
    /// summed in key order.
    pub(super) dissipated: f64,
    pub(super) departed: f64,
    pub(super) peak: Option<(f64, usize, Partner)>,
    pub(super) failure: Option<String>,
}

impl StepLog {
    pub(super) fn new(dt: f64, peak: Option<(f64, usize, Partner)>) -> Self {
        Self {
            dt,
            jumps: Vec::new(),
            dissipated: 0.0,
            departed: 0.0,
            peak,
            failure: None,
        }
    }

    /// The work of one contact over the step, the same for pairs and walls: the model's
    /// response (from the prior record's history), its energy booked, the peak overlap,
    /// and its new record (with the forces on i) and the couple on i.
    #[inline(always)]
    pub(super) fn contact(
        &mut self,
        c: Contact,
        prior: Option<&ContactRecord>,
    ) -> (ContactRecord, DVec3) {
        let (kin, geom) = (&c.kin, &c.geom);
        let mut history = prior.map(|p| p.history).unwrap_or_default();
        let r = c
            .model
            .respond_rooted(&c.pair, kin, c.root, geom, self.dt, &mut history);
        if !(r.normal.force.is_finite() && r.tangential.is_finite()) && self.failure.is_none() {
            self.failure = Some(non_finite(c.i, c.partner, kin.delta));
        }
        let motion = Motion {
            delta: kin.delta,
            v_t: kin.v_t,
            omega_rel: kin.omega_rel,
        };
        let record = ContactRecord::new(history, kin.delta, &r, &motion);
        let was_in = prior.is_some_and(ContactRecord::engaged);
        let is_in = record.engaged();
        // the overlap at the start of the step: the prior record's, or back along δ̇
        let before = prior.map_or(kin.delta - kin.delta_dot * self.dt, |p| p.delta);
        let after = kin.delta;
        // the edges only where the step crosses one (JKR's cost a contact-radius solve each)
        let mut edges = if was_in != is_in {
            c.model.edges(geom, kin.delta, kin.delta_dot)
        } else {
            [(0.0, 0.0); 2]
        };
        // a break the law placed within the step leaves there
        if let (true, Some((fraction, force))) = (was_in && !is_in, r.normal.broke_within) {
            edges[1] = (before + fraction * (after - before), force);
        }
        self.dissipated += book(prior, &record, &motion, self.dt, edges);
        // δ = 0 crossed with the contact side engaged (inside the contact, or with an edge
        // in the same step): the trapezoid the ledger booked spans the edge it used
        let contact_side_in = if after > 0.0 { is_in } else { was_in };
        // (an edge crossed at δ = 0 already placed what jumps there)
        let edge_at_touch = was_in != is_in && edges[usize::from(!is_in)].0 == 0.0;
        if (before > 0.0) != (after > 0.0) && contact_side_in && !edge_at_touch {
            let d0 = if was_in { before } else { edges[0].0 };
            let d1 = if is_in { after } else { edges[1].0 };
            self.touch(&c, (before, after), (d0, d1));
        }
        if was_in != is_in {
            let crossing = if is_in {
                Crossing::Entry {
                    before,
                    after,
                    edge: edges[0],
                    force_after: record.force,
                }
            } else {
                Crossing::Exit {
                    before,
                    after,
                    force_before: prior.map_or(0.0, |p| p.force),
                    edge: edges[1],
                }
            };
            let impulse = crossing.impulse(self.dt);
            if impulse != 0.0 {
                self.jumps.push(Jump {
                    i: c.i,
                    partner: c.partner,
                    impulse: impulse * kin.n,
                });
            }
        }
        self.note_peak(kin.delta / geom.a12, c.i, c.partner);
        (record, r.couple)
    }

    /// A contact that crossed δ = 0 within the step, engaged on the contact side, where a
    /// force switches on or off ([`ContactModel::touch_jump`]): its impulse placed as at an
    /// edge, from the overlaps (before, after), and the work the ledger's trapezoid over
    /// (d0, d1) gave the jump corrected to the part of the step on the contact side.
    pub(super) fn touch(&mut self, c: &Contact, (before, after): (f64, f64), (d0, d1): (f64, f64)) {
        let j = c.model.touch_jump(c.kin.delta_dot);
        if j == 0.0 {
            return;
        }
        let (crossing, inside) = if after > 0.0 {
            let entry = Crossing::Entry {
                before,
                after,
                edge: (0.0, j),
                force_after: j,
            };
            (entry, d1)
        } else {
            let exit = Crossing::Exit {
                before,
                after,
                force_before: j,
                edge: (0.0, j),
            };
            (exit, -d0)
        };
        self.dissipated += j * inside - 0.5 * j * (d1 - d0);
        let impulse = crossing.impulse(self.dt);
        if impulse != 0.0 {
            self.jumps.push(Jump {
                i: c.i,
                partner: c.partner,
                impulse: impulse * c.kin.n,
            });
        }
    }

    /// Keeps the deepest overlap ratio, the first one seen among equals.
    pub(super) fn note_peak(&mut self, ratio: f64, i: usize, partner: Partner) {
        // (a NaN ratio is left out: kept, it would hide every later one)
        if !ratio.is_nan() && self.peak.is_none_or(|p| ratio > p.0) {
            self.peak = Some((ratio, i, partner));
        }
    }

    /// Books a contact that left the range without a visit, with overlap `delta` now.
    pub(super) fn depart(&mut self, c: &ContactRecord, delta: f64) {
        self.departed += book_departed(c, delta, self.dt);
    }

    /// Appends the log of the chunk that follows this one (in key order): sums added, the
    /// first failure and the first deepest overlap kept, as one log over both would.
    pub(super) fn append(&mut self, mut next: StepLog) {
        self.jumps.append(&mut next.jumps);
        self.dissipated += next.dissipated;
        self.departed += next.departed;
        if let Some((ratio, i, partner)) = next.peak {
            self.note_peak(ratio, i, partner);
        }
        if self.failure.is_none() {
            self.failure = next.failure;
        }
    }

    /// The energy dissipated over the step.
    pub(super) fn total(&self) -> f64 {
        self.dissipated + self.departed
    }
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
    edges: [(f64, f64); 2],
) -> f64 {
    let was_in = old.is_some_and(ContactRecord::engaged);
    let is_in = new.engaged();
    let blank = ContactRecord::default();
    let o = old.unwrap_or(&blank);
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
        - 0.5 * (o.friction_power + new.friction_power) * dt
        - 0.5 * (o.couple_power + new.couple_power) * dt
        - (new.potential - o.potential)
}

/// Energy booked for a contact that left the interaction range within one step, with
/// overlap `delta` now: it leaves with its last force.
fn book_departed(c: &ContactRecord, delta: f64, dt: f64) -> f64 {
    let motion = Motion {
        delta,
        ..Default::default()
    };
    let edges = [(0.0, 0.0), (motion.delta, 0.0)];
    book(Some(c), &ContactRecord::default(), &motion, dt, edges)
}
