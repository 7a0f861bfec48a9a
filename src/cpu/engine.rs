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
use crate::cpu::jump::Crossing;
use crate::cpu::threads::{chunks, Threads};
use crate::error::PowderError;
use crate::gpu::composition::Composition;
use crate::model::{
    ContactHistory, ContactModel, Kinematics, PairConstants, PairGeometry, Response, TimeStep,
};
use crate::output::contacts::{ContactLine, ContactNetwork};
use crate::scene::{Scene, WallPhase};
use crate::setup::Resolved;
use glam::DVec3;

/// Verlet skin of the CPU pair list, in units of the smallest radius: candidate pairs are
/// those closer than r_i + r_j + reach + skin, and the list is rebuilt once two particles
/// may together have moved the skin since the last rebuild (the GPU engine's skin is the
/// same fraction).
pub const SKIN: f64 = 0.1;

/// Candidate pairs (a Verlet list): every active pair i < j closer than
/// r_i + r_j + reach + skin at the last rebuild, plus every contact kept then, as a half
/// list sorted by (i, j) in compressed rows, each entry with its contact record. The hot
/// loop walks it in key order, without hashing.
#[derive(Clone, Debug, Default)]
struct PairList {
    /// Entries of particle i: `start[i]..start[i + 1]` (n + 1 offsets).
    start: Vec<usize>,
    /// Partner j > i of each entry.
    partner: Vec<u32>,
    /// Whether the entry holds a contact (its record is meaningful).
    live: Vec<bool>,
    record: Vec<ContactRecord>,
    /// The entries naming particle j as partner: `incoming[in_start[j]..in_start[j + 1]]`,
    /// ascending (so by i), for summing j's forces in key order.
    in_start: Vec<usize>,
    incoming: Vec<u32>,
}

impl PairList {
    /// An empty list over `n` particles.
    fn empty(n: usize) -> Self {
        Self {
            start: vec![0; n + 1],
            in_start: vec![0; n + 1],
            ..Default::default()
        }
    }

    /// The list holding exactly `contacts` (sorted by key here) over `n` particles.
    fn from_contacts(n: usize, mut contacts: Vec<((u32, u32), ContactRecord)>) -> Self {
        contacts.sort_by_key(|(k, _)| *k);
        let mut list = Self::empty(n);
        for &((i, _), _) in &contacts {
            list.start[i as usize + 1] += 1;
        }
        for i in 0..n {
            list.start[i + 1] += list.start[i];
        }
        list.partner = contacts.iter().map(|((_, j), _)| *j).collect();
        list.live = vec![true; contacts.len()];
        list.record = contacts.into_iter().map(|(_, r)| r).collect();
        list.index_incoming();
        list
    }

    /// Builds the incoming index from the entries.
    fn index_incoming(&mut self) {
        let n = self.start.len().saturating_sub(1);
        self.in_start.clear();
        self.in_start.resize(n + 1, 0);
        for &j in &self.partner {
            self.in_start[j as usize + 1] += 1;
        }
        for j in 0..n {
            self.in_start[j + 1] += self.in_start[j];
        }
        let mut next = self.in_start[..n].to_vec();
        self.incoming.clear();
        self.incoming.resize(self.partner.len(), 0);
        for (k, &j) in self.partner.iter().enumerate() {
            self.incoming[next[j as usize]] = k as u32;
            next[j as usize] += 1;
        }
    }

    /// The entry of pair (i, j), i < j.
    fn find(&self, i: usize, j: usize) -> Option<usize> {
        let (s, e) = (*self.start.get(i)?, *self.start.get(i + 1)?);
        let j = u32::try_from(j).ok()?;
        self.partner[s..e].binary_search(&j).ok().map(|k| s + k)
    }

    /// The contacts, in key order.
    fn contacts(&self) -> impl Iterator<Item = ((u32, u32), &ContactRecord)> + '_ {
        (0..self.start.len().saturating_sub(1)).flat_map(move |i| {
            (self.start[i]..self.start[i + 1])
                .filter(|&k| self.live[k])
                .map(move |k| ((i as u32, self.partner[k]), &self.record[k]))
        })
    }
}

/// Particle–wall contacts, sorted by key (wall, particle): every step visits the keys in
/// this order, so the old records are merged into the new list without hashing.
#[derive(Clone, Debug, Default)]
struct WallList {
    key: Vec<(u32, u32)>,
    record: Vec<ContactRecord>,
}

impl WallList {
    fn clear(&mut self) {
        self.key.clear();
        self.record.clear();
    }

    fn find(&self, key: (u32, u32)) -> Option<&ContactRecord> {
        self.key.binary_search(&key).ok().map(|k| &self.record[k])
    }

    fn contacts(&self) -> impl Iterator<Item = ((u32, u32), &ContactRecord)> + '_ {
        self.key.iter().copied().zip(&self.record)
    }
}

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default)]
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
    /// Whether the contact takes part in the energy ledger: touched, or exerting a force,
    /// or storing energy (a pair merely within search range is not engaged).
    fn engaged(&self) -> bool {
        self.history.touched || self.potential != 0.0 || self.force != 0.0
    }

    /// Whether the contact stays in the list: in the model's interaction range, or
    /// touched (a history that outlives the range until it lets go).
    fn stays(&self, range: f64) -> bool {
        self.delta > -range || self.history.touched
    }

    fn new(history: ContactHistory, delta: f64, r: &Response, m: &Motion) -> Self {
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
struct Motion {
    delta: f64,
    /// Tangential velocity at the contact and relative angular velocity ω_i − ω_j.
    v_t: DVec3,
    omega_rel: DVec3,
}

/// One contact as a force loop measures it over a step (a pair, or a particle and a wall).
struct Contact<'a> {
    model: &'a ContactModel,
    geom: PairGeometry,
    /// The model's constants of this pair ([`ContactModel::pair_constants`]).
    pair: PairConstants,
    kin: Kinematics,
    /// The law's root at `kin.delta` solved ahead ([`ContactModel::root_ahead`]), or None.
    root: Option<f64>,
    /// The particle and its partner, for the peak overlap and the error message.
    i: usize,
    partner: Partner,
}

/// The impulse of a force jump inside a step on particle i (−it on a particle partner),
/// added to the velocities at the end of the step ([`crate::cpu::jump`]).
#[derive(Clone, Copy, Debug)]
struct Jump {
    i: usize,
    partner: Partner,
    impulse: DVec3,
}

/// The error message of a contact whose force is not finite.
#[cold]
#[inline(never)]
fn non_finite(i: usize, partner: Partner, delta: f64) -> String {
    let between = match partner {
        Partner::Particle(j) => format!("particles {i} and {j}"),
        Partner::Wall(w) => format!("particle {i} and wall {w}"),
    };
    format!("non-finite contact force between {between} (overlap {delta:e} m)")
}

/// What the force loops gather over a step (or a chunk of it) besides the forces: the
/// energy the contacts dissipated, the deepest overlap and the first non-finite force.
struct StepLog {
    dt: f64,
    /// The impulses of the force jumps inside the step, in key order.
    jumps: Vec<Jump>,
    /// Energy of the contacts visited, and of those that left without a visit, each
    /// summed in key order.
    dissipated: f64,
    departed: f64,
    peak: Option<(f64, usize, Partner)>,
    failure: Option<String>,
}

impl StepLog {
    fn new(dt: f64, peak: Option<(f64, usize, Partner)>) -> Self {
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
    fn contact(&mut self, c: Contact, prior: Option<&ContactRecord>) -> (ContactRecord, DVec3) {
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
        // the edges only where the step crosses one (JKR's cost a contact-radius solve each)
        let edges = if was_in != is_in {
            c.model.edges(geom, kin.delta_dot)
        } else {
            [(0.0, 0.0); 2]
        };
        self.dissipated += CpuEngine::book(prior, &record, &motion, self.dt, edges);
        // the overlap at the start of the step: the prior record's, or back along δ̇
        let before = prior.map_or(kin.delta - kin.delta_dot * self.dt, |p| p.delta);
        let after = kin.delta;
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
    fn touch(&mut self, c: &Contact, (before, after): (f64, f64), (d0, d1): (f64, f64)) {
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
    fn note_peak(&mut self, ratio: f64, i: usize, partner: Partner) {
        // (a NaN ratio is left out: kept, it would hide every later one)
        if !ratio.is_nan() && self.peak.is_none_or(|p| ratio > p.0) {
            self.peak = Some((ratio, i, partner));
        }
    }

    /// Books a contact that left the range without a visit, with overlap `delta` now.
    fn depart(&mut self, c: &ContactRecord, delta: f64) {
        self.departed += CpuEngine::book_departed(c, delta, self.dt);
    }

    /// Appends the log of the chunk that follows this one (in key order): sums added, the
    /// first failure and the first deepest overlap kept, as one log over both would.
    fn append(&mut self, mut next: StepLog) {
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
    fn total(&self) -> f64 {
        self.dissipated + self.departed
    }
}

/// What a rebuild's neighbour search reads: the positions now, the grid binned from them,
/// and the old list whose contacts carry over.
struct Search<'a> {
    pos: &'a [DVec3],
    radius: &'a [f64],
    active: &'a [bool],
    cutoff_pad: &'a [f64],
    skin: f64,
    periodic: [bool; 3],
    domain: (DVec3, DVec3),
    grid: &'a CellGrid,
    old: &'a PairList,
}

/// The new list's entries of one chunk of particles, and how many each particle has.
struct ChunkList {
    counts: Vec<usize>,
    partner: Vec<u32>,
    /// The old list's entry each kept contact comes from ([`NEW_ENTRY`]: a new entry):
    /// the records are gathered once, into the joined list.
    source: Vec<u32>,
}

/// [`ChunkList::source`] of an entry without an old contact.
const NEW_ENTRY: u32 = u32::MAX;

impl Search<'_> {
    /// The entries of particles `range`: for each, the union of its candidates j > i and
    /// its old list's contacts, both ascending.
    fn chunk(&self, range: std::ops::Range<usize>) -> ChunkList {
        let (pos, radius, active, old) = (self.pos, self.radius, self.active, self.old);
        let any_periodic = self.periodic.iter().any(|&p| p);
        let mut out = ChunkList {
            counts: Vec::with_capacity(range.len()),
            partner: Vec::new(),
            source: Vec::new(),
        };
        let mut cand: Vec<u32> = Vec::new();
        for i in range {
            cand.clear();
            if active[i] {
                let pi = pos[i];
                let pad = self.cutoff_pad[i] + self.skin;
                self.grid.for_each_near(pi, |j| {
                    if j > i && active[j] {
                        let mut d = pi - pos[j];
                        if any_periodic {
                            d = minimum_image(d, self.periodic, self.domain);
                        }
                        let reach = pad + radius[j];
                        if d.length_squared() < reach * reach {
                            cand.push(j as u32);
                        }
                    }
                });
                cand.sort_unstable();
            }
            let before = out.partner.len();
            let (mut a, mut b) = (0, old.start.get(i).copied().unwrap_or(0));
            let end = old.start.get(i + 1).copied().unwrap_or(b);
            loop {
                while b < end && !old.live[b] {
                    b += 1;
                }
                let kept = (b < end).then(|| old.partner[b]);
                let next = cand.get(a).copied();
                let (j, source) = match (next, kept) {
                    (None, None) => break,
                    (Some(c), Some(o)) if c == o => {
                        a += 1;
                        b += 1;
                        (c, b - 1)
                    }
                    (Some(c), o) if o.is_none_or(|o| c < o) => {
                        a += 1;
                        (c, NEW_ENTRY as usize)
                    }
                    (_, Some(o)) => {
                        b += 1;
                        (o, b - 1)
                    }
                    (Some(_), None) => unreachable!(),
                };
                out.partner.push(j);
                // (entries are u32-indexed throughout, as `incoming` is: a list stays below
                // 2³² − 1 entries, whose records alone would fill 600 GB)
                debug_assert!(source <= NEW_ENTRY as usize);
                out.source.push(source as u32);
            }
            out.counts.push(out.partner.len() - before);
        }
        out
    }
}

/// What the pair forces read: the particles, their models, the list's rows and partners,
/// and the predicted velocities of the step.
struct PairInputs<'a> {
    pos: &'a [DVec3],
    radius: &'a [f64],
    pad: &'a [f64],
    mass: &'a [f64],
    material: &'a [usize],
    models: &'a [ContactModel],
    ranges: &'a [f64],
    n_materials: usize,
    periodic: [bool; 3],
    domain: (DVec3, DVec3),
    start: &'a [usize],
    partner: &'a [u32],
    v_pred: &'a [DVec3],
    w_pred: &'a [DVec3],
    dt: f64,
}

/// What the pair loop derives from the two radii and masses and the pair's model (the key):
/// the pair geometry, the rolling factor ½(r_i − r_j)/(r_i + r_j) and the model's pair constants.
#[derive(Clone, Copy)]
struct PairShape {
    key: (u64, u64, u64, u64, usize),
    geom: PairGeometry,
    roll: f64,
    pair: PairConstants,
}

/// One chunk of particles of the pair forces, with what it writes: its entries' records,
/// whether they stay, their forces on i and torques on j, and its particles' own sums.
struct PairChunk<'a> {
    range: std::ops::Range<usize>,
    record: &'a mut [ContactRecord],
    live: &'a mut [bool],
    entry_force: &'a mut [DVec3],
    entry_torque: &'a mut [DVec3],
    own_force: &'a mut [DVec3],
    own_torque: &'a mut [DVec3],
}

/// Entries of a row gauged ahead of their forces at a time (where a law solves roots).
const BLOCK: usize = 8;

/// What the pair loop measures of an entry ahead of its force, for a block of entries side
/// by side (their square roots, divisions and the law's root solve overlap): the distance,
/// its reciprocal and the law's overlap root.
#[derive(Clone, Copy, Default)]
struct Gauge {
    dist: f64,
    inv_dist: f64,
    root: Option<f64>,
}

impl Gauge {
    fn new(dist: f64, root: Option<f64>) -> Self {
        Self {
            dist,
            inv_dist: 1.0 / dist,
            root,
        }
    }
}

impl PairShape {
    /// The shape of pair (i, j) with model index m: `cache`'s if it has the same key, else
    /// computed and cached.
    fn cached<'c>(
        cache: &'c mut Option<PairShape>,
        (i, j, m): (usize, usize, usize),
        radius: &[f64],
        mass: &[f64],
        model: &ContactModel,
    ) -> &'c PairShape {
        let (ri, rj) = (radius[i], radius[j]);
        let key = (
            ri.to_bits(),
            mass[i].to_bits(),
            rj.to_bits(),
            mass[j].to_bits(),
            m,
        );
        if cache.as_ref().is_none_or(|known| known.key != key) {
            let geom = PairGeometry::spheres(ri, rj, mass[i], mass[j]);
            *cache = Some(Self {
                key,
                geom,
                roll: 0.5 * (ri - rj) / (ri + rj),
                pair: model.pair_constants(&geom),
            });
        }
        cache.as_ref().expect("just filled")
    }
}

impl PairInputs<'_> {
    /// The entries of one chunk, in key order; returns the chunk's log. `ROOTS`: some law
    /// solves overlap roots ahead ([`ContactModel::root_ahead`]), so the entries are gauged
    /// ahead of their forces, BLOCK at a time.
    #[inline(never)]
    fn chunk<const ROT: bool, const ROOTS: bool>(&self, c: PairChunk) -> StepLog {
        let omega_of = |i: usize| if ROT { self.w_pred[i] } else { DVec3::ZERO };
        let (pos, radius, pad, mass, material) =
            (self.pos, self.radius, self.pad, self.mass, self.material);
        let (periodic, domain) = (self.periodic, self.domain);
        let any_periodic = periodic.iter().any(|&p| p);
        let nm = self.n_materials;
        let mut log = StepLog::new(self.dt, None);
        let base = self.start[c.range.start];
        // the last pair's shape (the pairs of a packing share few)
        let mut shape: Option<PairShape> = None;
        for (a, i) in c.range.clone().enumerate() {
            let (s, e) = (self.start[i], self.start[i + 1]);
            if s == e {
                continue;
            }
            let (pi, ri, pad_i, mi) = (pos[i], radius[i], pad[i], material[i] * nm);
            let (vi, wi) = (self.v_pred[i], omega_of(i));
            // i's own sums
            let (mut fi, mut ti) = (DVec3::ZERO, DVec3::ZERO);
            let separation = |j: usize| {
                let d = pi - pos[j];
                if any_periodic {
                    minimum_image(d, periodic, domain)
                } else {
                    d
                }
            };
            // whether an entry (live or not, its record) at squared distance dist2 from
            // partner j gets a force: within reach, or an engaged contact beyond it that broke
            // within the step (visited, so its exit edge is booked and its force jump placed,
            // as on the GPU)
            let visited = |(live, record): (bool, &ContactRecord), j: usize, dist2: f64| {
                let reach = pad_i + radius[j];
                dist2 < reach * reach || live && record.engaged()
            };
            // the row in blocks: with roots to solve, each block's gauges first, side by
            // side, then its forces
            for start in (s..e).step_by(BLOCK) {
                let block = start..(start + BLOCK).min(e);
                let mut gauges = [Gauge::default(); BLOCK];
                if ROOTS {
                    for (g, k) in gauges.iter_mut().zip(block.clone()) {
                        let (x, j) = (k - base, self.partner[k] as usize);
                        let dist2 = separation(j).length_squared();
                        let dist = dist2.sqrt();
                        let root = if visited((c.live[x], &c.record[x]), j, dist2) {
                            let m = mi + material[j];
                            let model = &self.models[m];
                            let pair =
                                PairShape::cached(&mut shape, (i, j, m), radius, mass, model);
                            let touched = c.live[x] && c.record[x].history.touched;
                            model.root_ahead(&pair.pair, ri + radius[j] - dist, touched)
                        } else {
                            None
                        };
                        *g = Gauge::new(dist, root);
                    }
                }
                for (g, k) in gauges.iter().zip(block) {
                    let (x, j) = (k - base, self.partner[k] as usize);
                    let d = separation(j);
                    let dist2 = d.length_squared();
                    let live = c.live[x];
                    if !visited((live, &c.record[x]), j, dist2) {
                        if live {
                            let dist = if ROOTS { g.dist } else { dist2.sqrt() };
                            log.depart(&c.record[x], ri + radius[j] - dist);
                            c.live[x] = false;
                        }
                        c.entry_force[x] = DVec3::ZERO;
                        if ROT {
                            c.entry_torque[x] = DVec3::ZERO;
                        }
                        continue;
                    }
                    // (without roots to solve, measured here, where a force needs them)
                    let Gauge {
                        dist,
                        inv_dist,
                        root,
                    } = if ROOTS {
                        *g
                    } else {
                        Gauge::new(dist2.sqrt(), None)
                    };
                    let delta = ri + radius[j] - dist;
                    let m = mi + material[j];
                    let (model, range) = (&self.models[m], self.ranges[m]);
                    if delta <= -range && !live {
                        c.entry_force[x] = DVec3::ZERO;
                        if ROT {
                            c.entry_torque[x] = DVec3::ZERO;
                        }
                        continue;
                    }
                    let prior = live.then(|| &c.record[x]);
                    let n = if dist > 0.0 { d * inv_dist } else { DVec3::Z };
                    let &PairShape {
                        geom, roll, pair, ..
                    } = PairShape::cached(&mut shape, (i, j, m), radius, mass, model);
                    let wj = omega_of(j);
                    let v_rel = vi - self.v_pred[j];
                    let v_c = if ROT {
                        v_rel - ri * wi.cross(n) - radius[j] * wj.cross(n)
                    } else {
                        v_rel
                    };
                    let v_t = v_c - n * v_c.dot(n);
                    // rolling needs rotation: no model reads v_roll without it
                    let v_roll = if ROT {
                        geom.r_eff() * (wi - wj).cross(n) + roll * v_t
                    } else {
                        DVec3::ZERO
                    };
                    let contact = Contact {
                        model,
                        geom,
                        pair,
                        kin: Kinematics {
                            delta,
                            delta_dot: -v_rel.dot(n),
                            n,
                            v_t,
                            v_roll,
                            omega_rel: wi - wj,
                        },
                        root,
                        i,
                        partner: Partner::Particle(j),
                    };
                    let (r, couple) = log.contact(contact, prior);
                    let f = r.force * n + r.tangential;
                    fi += f;
                    c.entry_force[x] = f;
                    if ROT {
                        let t = n.cross(r.tangential);
                        ti += -ri * t + couple;
                        c.entry_torque[x] = -radius[j] * t - couple;
                    }
                    let keep = r.stays(range);
                    if keep {
                        c.record[x] = r;
                    }
                    c.live[x] = keep;
                }
            }
            c.own_force[a] = fi;
            if ROT {
                c.own_torque[a] = ti;
            }
        }
        log
    }
}

/// Keeps the two largest values seen in `top` (largest first).
fn push_top(top: &mut [f64; 2], x: f64) {
    if x > top[1] {
        if x > top[0] {
            top[1] = top[0];
            top[0] = x;
        } else {
            top[1] = x;
        }
    }
}

/// What the wall contacts read: the particles, the walls and their models, the candidates
/// and the old contacts, and the predicted velocities of the step.
struct WallInputs<'a> {
    pos: &'a [DVec3],
    radius: &'a [f64],
    mass: &'a [f64],
    material: &'a [usize],
    n_materials: usize,
    walls: &'a [WallPlane],
    wall_models: &'a [ContactModel],
    wall_ranges: &'a [f64],
    candidates: &'a [u32],
    old: &'a WallList,
    v_pred: &'a [DVec3],
    w_pred: &'a [DVec3],
    dt: f64,
}

/// A piece of the wall contacts: candidates of one wall, and the old contacts it books.
struct WallPiece {
    wall: usize,
    candidates: std::ops::Range<usize>,
    old: std::ops::Range<usize>,
}

/// What a piece found: the contacts kept, each visited particle's force and torque, its log.
struct WallOut {
    kept: WallList,
    pushes: Vec<(u32, DVec3, DVec3)>,
    log: StepLog,
}

impl WallInputs<'_> {
    /// The contacts of one piece, in key order.
    #[inline(never)]
    fn piece(&self, p: WallPiece) -> WallOut {
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
            if delta <= -range && prior.is_none() {
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
struct WallPlane {
    /// A point of the plane now (it moves with the wall).
    point: DVec3,
    normal: DVec3,
    motion: crate::scene::WallMotion,
    /// Velocity over the current step.
    velocity: DVec3,
}

impl WallPlane {
    /// Overlap of a sphere of radius `r` centred at `x` with the plane.
    fn overlap(&self, x: DVec3, r: f64) -> f64 {
        r - (x - self.point).dot(self.normal)
    }
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
                    return Err(PowderError::Scene(format!(
                        "the domain is shorter than 3 interaction cut-offs ({:.4e} m) along a periodic axis: a pair would meet two periodic images; enlarge [domain] or make the axis non-periodic",
                        cutoff
                    )))
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
        if s.wall_points.len() != self.walls.len() || s.wall_velocities.len() != self.walls.len() {
            return Err(PowderError::Run(format!(
                "the checkpoint holds {} walls but the scene has {}",
                s.wall_points.len(),
                self.walls.len()
            )));
        }
        if s.dt.to_bits() != self.dt.to_bits() {
            return Err(PowderError::Run(format!(
                "the checkpoint was run with dt = {:e} s but the scene gives dt = {:e} s",
                s.dt, self.dt
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
        wall.overlap(self.pos[i], self.radius[i])
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
        // Moving walls: the velocity over this step (the phase at its start: prescribed, or
        // the servo law from the force of the step before — at rest in the first step of a
        // servo phase entered during the run), then the move; the work the walls do on the
        // particles is integrated with the force before and after the step.
        let push_before = self.moving_walls().then(|| self.wall_forces());
        if let Some(before) = &push_before {
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
        }
        self.compute_forces()?;
        if let Some(before) = push_before {
            let after = self.wall_forces();
            for (w, wall) in self.walls.iter().enumerate() {
                // the wall pushes the particles with −(force on the wall)
                self.wall_work -= 0.5 * (before[w] + after[w]).dot(wall.velocity) * dt;
            }
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
        let threads = self.threads.clone();
        threads.install(|| {
            for _ in 0..n {
                self.step()?;
            }
            Ok(())
        })
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
        Self::book(Some(c), &ContactRecord::default(), &motion, dt, edges)
    }

    /// Neighbour-list rebuilds so far (since the engine was built; not part of the state).
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Whether the lists may miss a pair or a wall contact now: some pair of active
    /// particles, or a particle and a wall, may have closed the skin since the last
    /// rebuild (the two largest displacements together reach 99 % of it), or a rebuild is
    /// due.
    fn list_stale(&self) -> bool {
        let chunk = self.threads.chunk();
        if self.rebuild_due
            || self.pos_ref.len() != self.pos.len()
            || self.wall_ref.len() != self.walls.len()
            || self.walls.iter().any(|w| !w.point.is_finite())
        {
            return true;
        }
        let wall_moved = self
            .walls
            .iter()
            .zip(&self.wall_ref)
            .map(|(w, r)| (w.point - *r).length())
            .fold(0.0f64, f64::max);
        let any_periodic = self.periodic.iter().any(|&p| p);
        // the two largest squared displacements of each chunk (None: one is NaN)
        let (pos, pos_ref, active) = (&self.pos, &self.pos_ref, &self.active);
        let (periodic, domain) = (self.periodic, self.domain);
        let tops = self
            .threads
            .map(chunks(pos.len(), chunk).collect(), |range| {
                let mut top = [0.0f64; 2];
                for i in range {
                    if !active[i] {
                        continue;
                    }
                    let mut d = pos[i] - pos_ref[i];
                    if any_periodic {
                        d = minimum_image(d, periodic, domain);
                    }
                    let d2 = d.length_squared();
                    if d2.is_nan() {
                        return None;
                    }
                    push_top(&mut top, d2);
                }
                Some(top)
            });
        let (mut m1, mut m2) = (0.0f64, 0.0f64);
        for top in tops {
            let Some(top) = top else {
                return true;
            };
            let mut both = [m1, m2];
            push_top(&mut both, top[0]);
            push_top(&mut both, top[1]);
            [m1, m2] = both;
        }
        m1.sqrt() + m2.sqrt().max(wall_moved) >= 0.99 * self.skin
    }

    /// Rebuilds the pair list from the positions now: every active pair closer than
    /// r_i + r_j + reach + skin, and every contact of the old list (with its record),
    /// in key order. The particles are binned, chunks of them searched, and the records
    /// gathered in parallel; the chunks' partners are joined in order.
    fn rebuild_list(&mut self) {
        let chunk = self.threads.chunk();
        let n = self.pos.len();
        let grid = &self.grid;
        let cells = self.threads.map_slice(&self.pos, |&p| grid.cell_of(p));
        self.grid.link(&cells);
        drop(cells);
        // the old list is freed after the merge (not kept for its allocations: the list is
        // most of the engine's memory, and rebuilds are rare)
        let old = std::mem::take(&mut self.pairs);
        let search = Search {
            pos: &self.pos,
            radius: &self.radius,
            active: &self.active,
            cutoff_pad: &self.cutoff_pad,
            skin: self.skin,
            periodic: self.periodic,
            domain: self.domain,
            grid: &self.grid,
            old: &old,
        };
        let parts = self
            .threads
            .map(chunks(n, chunk).collect(), |range| search.chunk(range));
        let total: usize = parts.iter().map(|p| p.partner.len()).sum();
        let mut new = PairList {
            start: Vec::with_capacity(n + 1),
            partner: Vec::with_capacity(total),
            ..Default::default()
        };
        let mut source = Vec::with_capacity(total);
        new.start.push(0);
        for part in parts {
            for count in part.counts {
                new.start
                    .push(new.start.last().copied().unwrap_or(0) + count);
            }
            new.partner.extend(part.partner);
            source.extend(part.source);
        }
        new.live = self.threads.map_slice(&source, |&s| s != NEW_ENTRY);
        new.record = self.threads.map_slice(&source, |&s| match s {
            NEW_ENTRY => ContactRecord::default(),
            s => old.record[s as usize],
        });
        drop(source);
        new.index_incoming();
        drop(old);
        self.pairs = new;
        self.rebuild_wall_candidates();
        self.pos_ref.clone_from(&self.pos);
        self.rebuild_due = false;
        self.rebuilds += 1;
    }

    /// The wall candidates from the positions now: per wall, the active particles whose
    /// overlap exceeds −(range + skin), and those in contact with it, ascending. Pieces of
    /// a chunk of particles of one wall are searched in parallel and joined in order.
    fn rebuild_wall_candidates(&mut self) {
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

    /// Forces of the particle pairs of the list (visited in key order) for the predicted
    /// velocities; returns the step's log of them. Chunks of particles evaluate their
    /// entries in parallel (each entry's force kept), then each particle sums the forces
    /// of the entries naming it, in key order, before its own: the bits of a serial sweep.
    /// `ROT`: particles rotate (`w_pred` holds their angular velocities).
    #[inline(never)]
    fn pair_forces<const ROT: bool>(&mut self, v_pred: &[DVec3], w_pred: &[DVec3]) -> StepLog {
        let chunk = self.threads.chunk();
        let n = self.pos.len();
        let PairList {
            start,
            partner,
            live,
            record,
            in_start,
            incoming,
        } = &mut self.pairs;
        let entries = partner.len();
        self.entry_force.resize(entries, DVec3::ZERO);
        self.own_force.resize(n, DVec3::ZERO);
        if ROT {
            self.entry_torque.resize(entries, DVec3::ZERO);
            self.own_torque.resize(n, DVec3::ZERO);
        }
        // each chunk's particles and entries, as disjoint mutable slices
        let mut work = Vec::with_capacity(n.div_ceil(chunk));
        {
            let (mut rec, mut liv) = (&mut record[..], &mut live[..]);
            let (mut ef, mut et) = (&mut self.entry_force[..], &mut self.entry_torque[..]);
            let (mut of, mut ot) = (&mut self.own_force[..], &mut self.own_torque[..]);
            for range in chunks(n, chunk) {
                let e = start[range.end] - start[range.start];
                let p = range.len();
                let t = if ROT { e } else { 0 };
                let tp = if ROT { p } else { 0 };
                let (r0, r1) = std::mem::take(&mut rec).split_at_mut(e);
                let (l0, l1) = std::mem::take(&mut liv).split_at_mut(e);
                let (f0, f1) = std::mem::take(&mut ef).split_at_mut(e);
                let (t0, t1) = std::mem::take(&mut et).split_at_mut(t);
                let (o0, o1) = std::mem::take(&mut of).split_at_mut(p);
                let (q0, q1) = std::mem::take(&mut ot).split_at_mut(tp);
                (rec, liv, ef, et, of, ot) = (r1, l1, f1, t1, o1, q1);
                work.push(PairChunk {
                    range,
                    record: r0,
                    live: l0,
                    entry_force: f0,
                    entry_torque: t0,
                    own_force: o0,
                    own_torque: q0,
                });
            }
        }
        let inputs = PairInputs {
            pos: &self.pos,
            radius: &self.radius,
            pad: &self.cutoff_pad,
            mass: &self.mass,
            material: &self.material,
            models: &self.models,
            ranges: &self.ranges,
            n_materials: self.n_materials,
            periodic: self.periodic,
            domain: self.domain,
            start,
            partner,
            v_pred,
            w_pred,
            dt: self.dt,
        };
        let logs = if self.roots_ahead && self.models.iter().any(ContactModel::solves_roots) {
            self.threads.map(work, |c| inputs.chunk::<ROT, true>(c))
        } else {
            self.threads.map(work, |c| inputs.chunk::<ROT, false>(c))
        };
        let mut log = StepLog::new(self.dt, self.peak);
        for l in logs {
            log.append(l);
        }
        // each particle's force: the entries naming it (key order), then its own sum
        let (start, in_start, incoming) = (&*start, &*in_start, &*incoming);
        let (entry_force, entry_torque) = (&self.entry_force, &self.entry_torque);
        let (own_force, own_torque) = (&self.own_force, &self.own_torque);
        let torque_chunks = chunks_or_empty(&mut self.torque, n, chunk);
        let gather: Vec<_> = self
            .force
            .chunks_mut(chunk)
            .zip(torque_chunks)
            .zip(chunks(n, chunk))
            .collect();
        self.threads.map(gather, |((force, torque), range)| {
            for (a, j) in range.enumerate() {
                let (s, e) = (in_start[j], in_start[j + 1]);
                let mut f = DVec3::ZERO;
                let mut t = DVec3::ZERO;
                for &k in &incoming[s..e] {
                    f -= entry_force[k as usize];
                    if ROT {
                        t += entry_torque[k as usize];
                    }
                }
                if start[j] != start[j + 1] {
                    f += own_force[j];
                    if ROT {
                        t += own_torque[j];
                    }
                }
                force[a] = f;
                if ROT {
                    torque[a] = t;
                }
            }
        });
        log
    }

    /// Forces of the wall contacts (visited in key order (wall, particle), merged with the
    /// old list); returns the step's log of them. The candidates are cut into pieces
    /// evaluated in parallel; their forces are added in key order afterwards.
    #[inline(never)]
    fn wall_contact_forces(&mut self, v_pred: &[DVec3], w_pred: &[DVec3]) -> StepLog {
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

    /// Force the particles exert on each wall now, N (normal and tangential parts).
    pub fn wall_forces(&self) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; self.walls.len()];
        for ((w, _), c) in self.wall_contacts.contacts() {
            let w = w as usize;
            f[w] -= c.force * self.walls[w].normal + c.tangential;
        }
        f
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
        let n = self.pos.len().max(1) as f64;
        s.coordination = (2 * s.contacts + s.wall_contacts) as f64 / n;
        let touching = s.contacts + s.wall_contacts;
        if touching > 0 {
            s.mean_overlap_ratio = sum_ratio / touching as f64;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::bench::{packing, Case};

    /// Steps `a` and `b` `steps` times: they must agree bitwise (positions, velocities,
    /// spins, energies, contacts), with contacts.
    fn same_bits(a: &mut CpuEngine, b: &mut CpuEngine, steps: u64) {
        for _ in 0..steps {
            a.step().unwrap();
            b.step().unwrap();
        }
        let bits = |v: &[DVec3]| v.iter().map(|p| p.to_array().map(f64::to_bits)).collect();
        let bits: fn(&[DVec3]) -> Vec<[u64; 3]> = bits;
        assert_eq!(bits(a.positions()), bits(b.positions()));
        assert_eq!(bits(a.velocities()), bits(b.velocities()));
        assert_eq!(bits(a.angular_velocities()), bits(b.angular_velocities()));
        assert_eq!(a.energies(), b.energies());
        assert_eq!(a.contacts(), b.contacts());
        assert!(!a.contacts().is_empty());
    }

    /// Runs `steps` steps with the default skin and without any (a rebuild every step):
    /// the two runs must agree bitwise (the forces do not depend on the list beyond its
    /// contacts), and the skinned one must rebuild less often.
    fn same_without_skin(scene: &Scene, steps: u64) {
        let mut a = CpuEngine::new(scene).unwrap();
        let mut b = CpuEngine::new(scene).unwrap();
        assert!(a.skin > 0.0);
        b.skin = 0.0;
        same_bits(&mut a, &mut b, steps);
        assert!(b.rebuilds() > steps);
        eprintln!("rebuilds {} of {}", a.rebuilds(), b.rebuilds());
        assert!(a.rebuilds() > 2 && a.rebuilds() < b.rebuilds() / 2);
    }

    /// The pair loop that gauges a row's entries and solves JKR's roots ahead, a block at a
    /// time, gives the bits of the loop that does not: JKR with friction and rolling, rows
    /// longer than a block (a wide skin), contacts made and broken, closed and periodic.
    #[test]
    fn roots_solved_ahead_change_no_bit() {
        for periodic in [false, true] {
            let mut scene = packing(Case::Jkr, 512, 300.0, 6).unwrap();
            if periodic {
                scene.domain.periodic = [true, true, false];
                scene.walls.retain(|w| w.normal[2] != 0.0);
            }
            let mut a = CpuEngine::new(&scene).unwrap();
            let mut b = CpuEngine::new(&scene).unwrap();
            assert!(a.models.iter().any(ContactModel::solves_roots));
            b.roots_ahead = false;
            // a skin beyond the lattice's diagonal neighbours (and cells that hold it)
            let r = scene.particles[0].radius;
            for e in [&mut a, &mut b] {
                e.skin = 1.2 * r;
                let (lo, hi) = e.domain;
                e.grid = CellGrid::periodic(lo, hi, 4.0 * r, e.pos.len(), e.periodic).unwrap();
                e.rebuild_list();
            }
            same_bits(&mut a, &mut b, 2000);
            let rows = a.pairs.start.windows(2).map(|w| w[1] - w[0]);
            let longest = rows.max().unwrap();
            eprintln!(
                "periodic {periodic}: longest row {longest}, {} rebuilds",
                a.rebuilds()
            );
            assert!(longest > BLOCK && a.rebuilds() > 2);
        }
    }

    #[test]
    fn results_do_not_depend_on_the_skin() {
        for (case, steps) in [(Case::Hysteretic, 3000), (Case::Jkr, 3000)] {
            let scene = packing(case, 343, 20.0, 3).unwrap();
            same_without_skin(&scene, steps);
        }
    }

    /// A side wall pushing in and then pulling back (the wall candidates follow it).
    #[test]
    fn results_do_not_depend_on_the_skin_moving_wall() {
        let mut scene = packing(Case::Hysteretic, 343, 1.0, 4).unwrap();
        let dt = CpuEngine::new(&scene).unwrap().dt();
        let wall = scene
            .walls
            .iter_mut()
            .find(|w| w.normal == [1.0, 0.0, 0.0])
            .unwrap();
        wall.motion = crate::scene::WallMotion {
            phases: vec![
                (0.0, WallPhase::Velocity([0.05, 0.0, 0.0])),
                (1500.0 * dt, WallPhase::Velocity([-0.1, 0.0, 0.0])),
            ],
        };
        same_without_skin(&scene, 3000);
    }

    #[test]
    fn results_do_not_depend_on_the_skin_periodic_and_pouring() {
        let mut scene = packing(Case::Jkr, 512, 20.0, 5).unwrap();
        scene.domain.periodic = [true, true, false];
        // the side walls go: the box wraps along x and y
        scene.walls.retain(|w| w.normal[2] != 0.0);
        let dt = CpuEngine::new(&scene).unwrap().dt();
        for (k, p) in scene.particles.iter_mut().enumerate() {
            if k % 7 == 3 {
                p.insert_at = (k % 10) as f64 * 20.0 * dt;
                p.position[2] += 4.0 * p.radius;
            }
        }
        same_without_skin(&scene, 300);
    }

    /// A wall contact that leaves without a visit is booked once: the ledger closes. (Its
    /// particle is taken off the wall candidates by hand: they hold every contact
    /// otherwise, so only a particle the list no longer visits leaves this way.)
    #[test]
    fn a_wall_contact_left_unvisited_is_booked_once() {
        let scene = Scene::from_toml_str(
            r#"
[domain]
min = [-0.003, -0.003, -0.003]
max = [0.003, 0.003, 0.003]
[simulation]
duration = 0.1
[[material]]
name = "m"
density = 2000.0
model = "lsd"
k = 1000.0
gamma0 = 2e-3
[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[particles]]
kind = "list"
radius = 1e-3
positions = [[0.0, 0.0, 0.995e-3]]
"#,
            "pressed",
        )
        .unwrap();
        let mut e = CpuEngine::new(&scene).unwrap();
        // pressed 5 µm into the floor: the contact stores ½·k·δ²
        let before = e.energies();
        assert!(e.wall_contact_history(0, 0).is_some());
        assert!((before.elastic - 0.5 * 1000.0 * 25e-12).abs() < 1e-6 * before.elastic);
        e.wall_candidates.clear();
        e.wall_start.fill(0);
        let rebuilds = e.rebuilds();
        e.step().unwrap();
        assert_eq!(e.rebuilds(), rebuilds, "the list was rebuilt: no departure");
        assert!(e.wall_contact_history(0, 0).is_none());
        let after = e.energies();
        assert_eq!(after.elastic, 0.0);
        // off by the half kick's error only: k·dt²/(4m) of the stored energy
        let m = e.masses()[0];
        let bound = 1000.0 * e.dt() * e.dt() / (4.0 * m) * before.elastic;
        let imbalance = (after.total() - before.total()).abs();
        assert!(
            imbalance < 1.01 * bound && bound < 0.01 * before.elastic,
            "ledger {before:?} → {after:?}: off by {imbalance:e} (bound {bound:e})"
        );
    }

    /// A restored state continues bitwise, although the list is rebuilt at once.
    #[test]
    fn restore_continues_bitwise() {
        let scene = packing(Case::Jkr, 343, 20.0, 9).unwrap();
        let mut a = CpuEngine::new(&scene).unwrap();
        a.run_steps(150).unwrap();
        let mut b = CpuEngine::new(&scene).unwrap();
        b.restore(a.state()).unwrap();
        assert_eq!(a.contacts(), b.contacts());
        assert_eq!(a.energies(), b.energies());
        a.run_steps(150).unwrap();
        b.run_steps(150).unwrap();
        assert_eq!(a.positions(), b.positions());
        assert_eq!(a.energies(), b.energies());
        assert_eq!(a.contacts(), b.contacts());
        for (i, j) in [(0, 1), (0, 7), (5, 6)] {
            assert_eq!(a.contact_history(i, j), b.contact_history(j, i));
        }
        assert_eq!(a.wall_contact_history(0, 0), b.wall_contact_history(0, 0));
        // a state whose contacts do not fit the scene is refused
        let mut bad = a.state();
        let repeated = bad.contacts[0];
        bad.contacts.push(repeated);
        assert!(b.restore(bad).is_err());
        let mut bad = a.state();
        bad.contacts[0].0 = (3, 3);
        assert!(b.restore(bad).is_err());
        let mut bad = a.state();
        bad.wall_contacts[0].0 = (99, 0);
        assert!(b.restore(bad).is_err());
        // every array its length, and a refused state leaves the engine as it was
        let before = b.state();
        for cut in [
            |s: &mut CpuState| s.force.truncate(1),
            |s: &mut CpuState| s.torque.clear(),
            |s: &mut CpuState| s.active.truncate(2),
            |s: &mut CpuState| s.wall_velocities.clear(),
        ] {
            let mut bad = a.state();
            cut(&mut bad);
            assert!(b.restore(bad).is_err());
            assert_eq!(b.positions(), before.pos.as_slice());
        }
    }
}
