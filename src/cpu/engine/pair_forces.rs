//! The pair forces: chunks of particles evaluate their list entries in parallel, then each
//! particle sums the forces naming it in key order (the bits of a serial sweep).

use super::contact::{Contact, ContactRecord, StepLog};
use super::pair_list::PairList;
use super::step::chunks_or_empty;
use super::{minimum_image, CpuEngine, Partner};
use crate::cpu::threads::chunks;
use crate::model::{ContactModel, Kinematics, PairConstants, PairGeometry};
use glam::DVec3;

/// What the pair forces read: the particles, their models, the list's rows and partners,
/// and the predicted velocities of the step.
pub(super) struct PairInputs<'a> {
    pub(super) pos: &'a [DVec3],
    pub(super) radius: &'a [f64],
    pub(super) pad: &'a [f64],
    pub(super) mass: &'a [f64],
    pub(super) material: &'a [usize],
    pub(super) models: &'a [ContactModel],
    pub(super) ranges: &'a [f64],
    pub(super) n_materials: usize,
    pub(super) periodic: [bool; 3],
    pub(super) domain: (DVec3, DVec3),
    pub(super) start: &'a [usize],
    pub(super) partner: &'a [u32],
    pub(super) v_pred: &'a [DVec3],
    pub(super) w_pred: &'a [DVec3],
    pub(super) dt: f64,
}

/// What the pair loop derives from the two radii and masses and the pair's model (the key):
/// the pair geometry, the rolling factor ½(r_i − r_j)/(r_i + r_j) and the model's pair constants.
#[derive(Clone, Copy)]
pub(super) struct PairShape {
    pub(super) key: (u64, u64, u64, u64, usize),
    pub(super) geom: PairGeometry,
    pub(super) roll: f64,
    pub(super) pair: PairConstants,
}

/// One chunk of particles of the pair forces, with what it writes: its entries' records,
/// whether they stay, their forces on i and torques on j, and its particles' own sums.
pub(super) struct PairChunk<'a> {
    pub(super) range: std::ops::Range<usize>,
    pub(super) record: &'a mut [ContactRecord],
    pub(super) live: &'a mut [bool],
    pub(super) entry_force: &'a mut [DVec3],
    pub(super) entry_torque: &'a mut [DVec3],
    pub(super) own_force: &'a mut [DVec3],
    pub(super) own_torque: &'a mut [DVec3],
}

/// Entries of a row gauged ahead of their forces at a time (where a law solves roots).
pub(super) const BLOCK: usize = 8;

/// What the pair loop measures of an entry ahead of its force, for a block of entries side
/// by side (their square roots, divisions and the law's root solve overlap): the distance,
/// its reciprocal and the law's overlap root.
#[derive(Clone, Copy, Default)]
pub(super) struct Gauge {
    pub(super) dist: f64,
    pub(super) inv_dist: f64,
    pub(super) root: Option<f64>,
}

impl Gauge {
    pub(super) fn new(dist: f64, root: Option<f64>) -> Self {
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
    pub(super) fn cached<'c>(
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
    pub(super) fn chunk<const ROT: bool, const ROOTS: bool>(&self, c: PairChunk) -> StepLog {
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
                dist2 <= reach * reach || live && record.engaged()
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
                    if delta < -range && !live {
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

impl CpuEngine {
    /// Forces of the particle pairs of the list (visited in key order) for the predicted
    /// velocities; returns the step's log of them. Chunks of particles evaluate their
    /// entries in parallel (each entry's force kept), then each particle sums the forces
    /// of the entries naming it, in key order, before its own: the bits of a serial sweep.
    /// `ROT`: particles rotate (`w_pred` holds their angular velocities).
    #[inline(never)]
    pub(super) fn pair_forces<const ROT: bool>(
        &mut self,
        v_pred: &[DVec3],
        w_pred: &[DVec3],
    ) -> StepLog {
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
}
