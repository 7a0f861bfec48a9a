//! The pair list: candidate pairs in compressed rows with their contacts, when it is stale,
//! and its rebuild by a linked-cell search that carries the old contacts over.

use super::contact::ContactRecord;
use super::{minimum_image, CpuEngine};
use crate::cpu::cells::CellGrid;
use crate::cpu::threads::chunks;
use glam::DVec3;

/// Candidate pairs (a Verlet list): every active pair i < j closer than
/// r_i + r_j + reach + skin at the last rebuild, plus every contact kept then, as a half
/// list sorted by (i, j) in compressed rows, each entry with its contact record. The hot
/// loop walks it in key order, without hashing.
#[derive(Clone, Debug, Default)]
pub(super) struct PairList {
    /// Entries of particle i: `start[i]..start[i + 1]` (n + 1 offsets).
    pub(super) start: Vec<usize>,
    /// Partner j > i of each entry.
    pub(super) partner: Vec<u32>,
    /// Whether the entry holds a contact (its record is meaningful).
    pub(super) live: Vec<bool>,
    pub(super) record: Vec<ContactRecord>,
    /// The entries naming particle j as partner: `incoming[in_start[j]..in_start[j + 1]]`,
    /// ascending (so by i), for summing j's forces in key order.
    pub(super) in_start: Vec<usize>,
    pub(super) incoming: Vec<u32>,
}

impl PairList {
    /// An empty list over `n` particles.
    pub(super) fn empty(n: usize) -> Self {
        Self {
            start: vec![0; n + 1],
            in_start: vec![0; n + 1],
            ..Default::default()
        }
    }

    /// The list holding exactly `contacts` (sorted by key here) over `n` particles.
    pub(super) fn from_contacts(n: usize, mut contacts: Vec<((u32, u32), ContactRecord)>) -> Self {
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
    pub(super) fn index_incoming(&mut self) {
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
    pub(super) fn find(&self, i: usize, j: usize) -> Option<usize> {
        let (s, e) = (*self.start.get(i)?, *self.start.get(i + 1)?);
        let j = u32::try_from(j).ok()?;
        self.partner[s..e].binary_search(&j).ok().map(|k| s + k)
    }

    /// The contacts, in key order.
    pub(super) fn contacts(&self) -> impl Iterator<Item = ((u32, u32), &ContactRecord)> + '_ {
        (0..self.start.len().saturating_sub(1)).flat_map(move |i| {
            (self.start[i]..self.start[i + 1])
                .filter(|&k| self.live[k])
                .map(move |k| ((i as u32, self.partner[k]), &self.record[k]))
        })
    }
}

/// What a rebuild's neighbour search reads: the positions now, the grid binned from them,
/// and the old list whose contacts carry over.
pub(super) struct Search<'a> {
    pub(super) pos: &'a [DVec3],
    pub(super) radius: &'a [f64],
    pub(super) active: &'a [bool],
    pub(super) cutoff_pad: &'a [f64],
    pub(super) skin: f64,
    pub(super) periodic: [bool; 3],
    pub(super) domain: (DVec3, DVec3),
    pub(super) grid: &'a CellGrid,
    pub(super) old: &'a PairList,
}

/// The new list's entries of one chunk of particles, and how many each particle has.
pub(super) struct ChunkList {
    pub(super) counts: Vec<usize>,
    pub(super) partner: Vec<u32>,
    /// The old list's entry each kept contact comes from ([`NEW_ENTRY`]: a new entry):
    /// the records are gathered once, into the joined list.
    pub(super) source: Vec<u32>,
}

/// [`ChunkList::source`] of an entry without an old contact.
pub(super) const NEW_ENTRY: u32 = u32::MAX;

impl Search<'_> {
    /// The entries of particles `range`: for each, the union of its candidates j > i and
    /// its old list's contacts, both ascending.
    pub(super) fn chunk(&self, range: std::ops::Range<usize>) -> ChunkList {
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

/// Keeps the two largest values seen in `top` (largest first).
pub(super) fn push_top(top: &mut [f64; 2], x: f64) {
    if x > top[1] {
        if x > top[0] {
            top[1] = top[0];
            top[0] = x;
        } else {
            top[1] = x;
        }
    }
}

impl CpuEngine {
    /// Whether the lists may miss a pair or a wall contact now: some pair of active
    /// particles, or a particle and a wall, may have closed the skin since the last
    /// rebuild (the two largest displacements together reach 99 % of it), or a rebuild is
    /// due.
    pub(super) fn list_stale(&self) -> bool {
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
    pub(super) fn rebuild_list(&mut self) {
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
}
