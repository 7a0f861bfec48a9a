//! Reading the run back: the state, energies, contact statistics, forces, histories and the contact network.

use super::*;

/// The lists' wall entries read back (`GpuEngine::read_wall_entries`).
pub(super) struct WallEntries {
    /// Each particle's `ids` (state order).
    pub(super) ids: Vec<[u32; 4]>,
    /// The entries buffer's bytes.
    pub(super) entries: Vec<u8>,
    /// (particle k in state order, wall, record index), in k's order.
    pub(super) found: Vec<(usize, usize, u64)>,
}

impl GpuEngine {
    /// Reads positions, velocities and (when the scene rotates) angular velocities back,
    /// in the scene's particle order.
    pub fn state(&self) -> Result<GpuState, PowderError> {
        Ok(self.read_state_fields(false)?.0)
    }

    /// [`Self::state`] with its energies and contact statistics
    /// ([`Self::energies_and_contact_stats`]) from one read-back: what a run observes.
    pub fn state_energies_and_contact_stats(
        &self,
    ) -> Result<(GpuState, Energies, ContactStats), PowderError> {
        self.require_ledger()?;
        let (state, rows) = self.read_state_fields(true)?;
        let energies = self.energies_of(&rows, &state);
        Ok((state, energies, self.contact_stats_of(&rows)))
    }

    /// The state's fields read back (only those it is made of, not the whole buffers: the
    /// run reads them after chunks), with the ledger's rows where `ledger` and kept (else
    /// none).
    fn read_state_fields(&self, ledger: bool) -> Result<(GpuState, Vec<[f32; 4]>), PowderError> {
        let rotates = self.state.layout.place("omega").is_some();
        let ledger = ledger && self.keeps.ledger;
        let mut names = vec!["cell", "off", "ids", "kahan_o", "vel", "kahan_v"];
        names.extend(rotates.then_some("omega"));
        let ledger_at = names.len();
        if ledger {
            names.extend(crate::gpu::state::ledger_fields());
        }
        let f = self.read_fields(&names)?;
        let [cells, offs, ids, kahan_o, vels, kahan_v] = [0, 1, 2, 3, 4, 5].map(|i| &f[i]);
        let omegas: &[[u32; 4]] = if rotates { &f[6] } else { &[] };
        let vec3 = |v: [u32; 4]| {
            let v: [f32; 4] = bytemuck::cast(v);
            DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
        };
        let mut positions = vec![DVec3::ZERO; self.n as usize];
        let mut velocities = vec![DVec3::ZERO; self.n as usize];
        let mut angular_velocities = vec![DVec3::ZERO; omegas.len()];
        for k in 0..self.n as usize {
            let i = ids[k][0] as usize;
            let (cell, off): ([i32; 4], [f32; 4]) =
                (bytemuck::cast(cells[k]), bytemuck::cast(offs[k]));
            // the compensated values: x − c
            positions[i] =
                crate::gpu::layout::decode3(cell, off, self.origin, self.h) - vec3(kahan_o[k]);
            velocities[i] = vec3(vels[k]) - vec3(kahan_v[k]);
            if let Some(w) = omegas.get(k) {
                angular_velocities[i] = vec3(*w);
            }
        }
        let state = GpuState {
            positions,
            velocities,
            angular_velocities,
        };
        let rows = match ledger {
            true => self.ledger_rows(ids, &f[ledger_at..]),
            false => Vec::new(),
        };
        Ok((state, rows))
    }

    /// The deepest overlap over a12 of any contact in any step since the last call, and a
    /// particle with a contact beyond `run::MAX_OVERLAP_RATIO` if there was one.
    /// Resets the record. Measured on the device every step (a workgroup maximum, then one
    /// atomic per workgroup), read back once per batch of steps.
    pub fn take_peak_overlap(&mut self) -> Option<(f64, Option<usize>)> {
        self.peak.take()
    }

    /// A particle (persistent id) whose centre has left the domain box, checked on the
    /// device every step; `None` while all are inside.
    pub fn escaped(&self) -> Option<usize> {
        self.escaped
    }

    /// Engaged contacts (touching, or inside a non-contact adhesion range) that left the
    /// neighbour lists within a single step: each moved more than the skin (0.1·r_min) in
    /// one step. The ledger books them without the normal work of that last step; a
    /// non-zero count means the time step is far too large for the speeds in the scene.
    pub fn dropped_contacts(&self) -> u64 {
        self.dropped
    }

    /// The per-particle ledger rows (4 × vec4 per persistent id: the state's
    /// `gpu::state::ledger_fields`), or an error naming why there are none.
    pub(super) fn read_particle_ledger(&self) -> Result<Vec<[f32; 4]>, PowderError> {
        self.require_ledger()?;
        // (only the ids and the ledger's fields: 80 bytes a particle)
        let names: Vec<&str> = std::iter::once("ids")
            .chain(crate::gpu::state::ledger_fields())
            .collect();
        let fields = self.read_fields(&names)?;
        Ok(self.ledger_rows(&fields[0], &fields[1..]))
    }

    fn require_ledger(&self) -> Result<(), PowderError> {
        match self.keeps.ledger {
            true => Ok(()),
            false => Err(PowderError::Run(
                "this GPU run keeps no energy ledger (GpuOptions { ledger: false })".into(),
            )),
        }
    }

    /// The ledger's fields (device order) as rows per persistent id, 4 a particle.
    fn ledger_rows(&self, ids: &[[u32; 4]], fields: &[Vec<[u32; 4]>]) -> Vec<[f32; 4]> {
        let mut rows = vec![[0.0f32; 4]; 4 * self.n as usize];
        for (f, values) in fields.iter().enumerate() {
            for (k, v) in values.iter().enumerate() {
                rows[4 * ids[k][0] as usize + f] = bytemuck::cast(*v);
            }
        }
        rows
    }

    /// The state fields `names` read back, each its `n` vectors in the device's order:
    /// only their regions, window by window (and page by page), in one submission.
    pub(super) fn read_fields(&self, names: &[&str]) -> Result<Vec<Vec<[u32; 4]>>, PowderError> {
        let s = &self.state;
        let (l, windows) = (&s.layout, s.layout.windows());
        let field = crate::gpu::state::FIELD_BYTES;
        let region = windows.len * field;
        let mut parts = Vec::new();
        for name in names {
            let Some((b, at)) = l.place(name) else {
                return Err(PowderError::Run(format!("the state has no field `{name}`")));
            };
            let block = l.count(b) * region;
            for w in 0..windows.count {
                let (page, offset) = s.state_pages.locate(w * block + at, block);
                parts.push((&s.buffer(b)[page as usize], offset, region));
            }
        }
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = crate::gpu::kernel::submit_and_read_parts(&self.ctx, encoder, &parts)?;
        let n = self.n as usize;
        Ok(out
            .chunks(windows.count as usize)
            .map(|regions| {
                let mut v: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&regions.concat());
                v.truncate(n);
                v
            })
            .collect())
    }

    /// The energy ledger for a read-back state (kinetic and gravitational from it; stored
    /// and dissipated read from the device and summed in f64 in particle order), J. The
    /// same quantities as `CpuEngine::energies`.
    pub fn energies(&self, state: &GpuState) -> Result<Energies, PowderError> {
        Ok(self.energies_of(&self.read_particle_ledger()?, state))
    }

    /// [`Self::energies`] and [`Self::contact_stats`] from one read-back of the ledger.
    pub fn energies_and_contact_stats(
        &self,
        state: &GpuState,
    ) -> Result<(Energies, ContactStats), PowderError> {
        let rows = self.read_particle_ledger()?;
        Ok((self.energies_of(&rows, state), self.contact_stats_of(&rows)))
    }

    pub(super) fn energies_of(&self, rows: &[[f32; 4]], state: &GpuState) -> Energies {
        let mut e = Energies {
            kinetic: self.kinetic_energy(state),
            gravitational: self.gravitational_energy(state),
            inserted: self.inserted_energy(),
            ..Default::default()
        };
        for p in rows.chunks(4) {
            e.dissipated += p[2][0] as f64 - p[2][1] as f64;
            e.elastic += p[2][2] as f64;
            e.wall_work += p[3][0] as f64 - p[3][1] as f64;
        }
        e
    }

    /// Contact counts and overlap statistics after the last step, as
    /// `CpuEngine::contact_stats` (each pair's evaluator counts it twice on the device).
    pub fn contact_stats(&self) -> Result<ContactStats, PowderError> {
        Ok(self.contact_stats_of(&self.read_particle_ledger()?))
    }

    pub(super) fn contact_stats_of(&self, rows: &[[f32; 4]]) -> ContactStats {
        let mut counts = [0.0f64; 4];
        let mut sums = [0.0f64; 2];
        let mut s = ContactStats::default();
        for p in rows.chunks(4) {
            for c in 0..4 {
                counts[c] += p[0][c] as f64;
            }
            s.max_overlap = s.max_overlap.max(p[1][0] as f64);
            s.max_overlap_ratio = s.max_overlap_ratio.max(p[1][1] as f64);
            sums[0] += p[1][2] as f64;
            sums[1] += p[1][3] as f64;
        }
        s.contacts = (counts[0] / 2.0).round() as usize;
        s.wall_contacts = counts[1].round() as usize;
        s.non_contact = (counts[2] / 2.0 + counts[3]).round() as usize;
        // (per particle that has appeared: the energies count no other)
        let n = self.active.iter().filter(|&&a| a).count().max(1) as f64;
        s.coordination = (2 * s.contacts + s.wall_contacts) as f64 / n;
        let touching = s.contacts + s.wall_contacts;
        if touching > 0 {
            s.mean_overlap_ratio = (sums[0] / 2.0 + sums[1]) / touching as f64;
        }
        s
    }

    /// The lists read back: each particle's ids (persistent id, row, pairs, walls; in the
    /// device's order) and the entries' bytes.
    pub(super) fn read_lists(&self) -> Result<(Vec<[u32; 4]>, Vec<u8>), PowderError> {
        let s = &self.state;
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let groups = [whole(s.sources(Buffer::State)), whole(s.entry_sources())];
        let [state, entries]: [Vec<u8>; 2] =
            read_joined(&self.ctx, encoder, &groups)?
                .try_into()
                .map_err(|_| PowderError::Run("a short read-back of the lists".into()))?;
        Ok((s.layout.unpack(&state, "ids"), entries))
    }

    /// The particle state's two buffers read back (`state`, `motion`; their pages one
    /// after the other).
    pub(super) fn read_state(&self) -> Result<(Vec<u8>, Vec<u8>), PowderError> {
        let s = &self.state;
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let groups = [
            whole(s.sources(Buffer::State)),
            whole(s.sources(Buffer::Motion)),
        ];
        let [state, motion]: [Vec<u8>; 2] = read_joined(&self.ctx, encoder, &groups)?
            .try_into()
            .map_err(|_| PowderError::Run("a short read-back of the state".into()))?;
        Ok((state, motion))
    }

    /// The wall entries of the lists (`WALL_ENTRY` in `gpu::records`: particle k's
    /// contacts with the walls near it, after its pairs), read back.
    pub(super) fn read_wall_entries(&self) -> Result<WallEntries, PowderError> {
        let s = &self.state;
        let (ids, entries) = self.read_lists()?;
        let windows = s.layout.windows();
        let mut found = Vec::new();
        for (k, &[_, row, pairs, walls]) in ids.iter().enumerate() {
            for e in (row + pairs) as u64..(row + pairs + walls) as u64 {
                // (the id, not `nbr`: a halted rebuild has refilled `nbr` but left the
                // old rows' ids, which `ids` still describe)
                let at = s.entry_layout.byte_of("hist_pid", self.entries, windows, e);
                let id = at.and_then(|at| entries.get(at as usize..at as usize + 4));
                if let Some(&[a, b, c, d]) = id {
                    let id = u32::from_le_bytes([a, b, c, d]);
                    if id & WALL_ENTRY != 0 && ((id & !WALL_ENTRY) as usize) < self.n_walls as usize
                    {
                        found.push((k, (id & !WALL_ENTRY) as usize, e));
                    }
                }
            }
        }
        Ok(WallEntries {
            ids,
            entries,
            found,
        })
    }

    /// The contact force on each particle after the last step, m·(a − g) from the device's
    /// accelerations, in the scene's particle order (N). For traces and diagnostics.
    pub fn contact_forces(&self) -> Result<Vec<DVec3>, PowderError> {
        let s = &self.state;
        let (state, motion) = self.read_state()?;
        let acc: Vec<[f32; 4]> = s.layout.unpack(&motion, "acc");
        let ids: Vec<[u32; 4]> = s.layout.unpack(&state, "ids");
        let mut f = vec![DVec3::ZERO; self.n as usize];
        for k in 0..self.n as usize {
            let i = ids[k][0] as usize;
            let a = DVec3::new(acc[k][0] as f64, acc[k][1] as f64, acc[k][2] as f64);
            f[i] = self.mass[i] * (a - self.gravity);
        }
        Ok(f)
    }

    /// Gravitational energy −Σ m·g·x of a read-back state (particles that have appeared),
    /// J; known with or without the ledger.
    pub fn gravitational_energy(&self, state: &GpuState) -> f64 {
        state
            .positions
            .iter()
            .zip(&self.mass)
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .fold(0.0, |g, ((x, m), _)| g - m * self.gravity.dot(*x))
    }

    /// Kinetic + gravitational energy brought in by the particles inserted so far (pouring;
    /// booked on the host), J; known with or without the ledger.
    pub fn inserted_energy(&self) -> f64 {
        self.inserted
    }

    /// Kinetic energy of a read-back state, translational plus rotational (I = 2/5·m·r²,
    /// as the CPU ledger), J; known with or without the ledger.
    pub fn kinetic_energy(&self, state: &GpuState) -> f64 {
        // particles that have not appeared yet do not count
        let translational: f64 = state
            .velocities
            .iter()
            .zip(&self.mass)
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .map(|((v, m), _)| 0.5 * m * v.length_squared())
            .sum();
        let rotational: f64 = state
            .angular_velocities
            .iter()
            .zip(self.mass.iter().zip(&self.radius))
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .map(|((w, (&m, &r)), _)| 0.5 * crate::scene::sphere_inertia(m, r) * w.length_squared())
            .sum();
        translational + rotational
    }

    /// Decodes one stored history element (the layout the composition declares).
    pub(super) fn decode_history(&self, b: &[u8]) -> ContactHistory {
        self.kind.decode_history(b)
    }

    /// The history particle `i` keeps of its contact with particle `j` (persistent ids)
    /// after the last step, if `j` is in `i`'s neighbour list. Each side keeps its own
    /// copy: `contact_history(j, i)` has the same flags and ξ, and the negated tangential
    /// spring (`hist_mirror`, `remap` in `shaders/step/rebuild.wgsl`). For tests and diagnostics: reads buffers back.
    pub fn contact_history(
        &self,
        i: usize,
        j: usize,
    ) -> Result<Option<ContactHistory>, PowderError> {
        // (no particle beyond u32: no contact)
        let (Ok(i), Ok(j)) = (u32::try_from(i), u32::try_from(j)) else {
            return Ok(None);
        };
        let key = (i, j);
        Ok(self
            .contact_histories()?
            .into_iter()
            .find(|(k, _)| *k == key)
            .map(|(_, h)| h))
    }

    /// Every listed contact's history, as ((i, j), history of i's side) by persistent ids,
    /// sorted: both orientations of each pair appear (one is stored, the other derived).
    /// For comparisons and diagnostics: reads the lists back.
    pub fn contact_histories(&self) -> Result<Vec<KeyedHistory>, PowderError> {
        let s = &self.state;
        let hb = self.kind.history_bytes();
        let (ids, entries) = self.read_lists()?;
        let cap = self.entries;
        let windows = s.layout.windows();
        let at = |name: &str, e: u64| s.entry_layout.byte_of(name, cap, windows, e).unwrap_or(0);
        let hb = hb as usize;
        let mut list = Vec::new();
        for &[pid, row, count, _] in &ids {
            // a particle's entries (ids.y, ids.z as in shaders/step/shared.wgsl)
            for e in row as u64..(row + count) as u64 {
                let partner = u32s(&entries[at("hist_pid", e) as usize..][..4])[0];
                let h = at("hist", e) as usize;
                // one stored history per pair, in its evaluator's frame; the partner sees
                // it mirrored (the tangential spring negated)
                let h = self.decode_history(&entries[h..h + hb]);
                let seen_by_partner = self.kind.mirror_history(h);
                list.push(((pid, partner), h));
                list.push(((partner, pid), seen_by_partner));
            }
        }
        list.sort_by_key(|c| c.0);
        Ok(list)
    }

    /// The engaged contacts after the last step (touching, exerting a force or storing
    /// energy), as [`CpuEngine::contact_network`](crate::cpu::CpuEngine::contact_network)
    /// gives them: each pair from its lower id's side, pairs by (i, j), then wall contacts
    /// by (wall, particle). Reads the lists back; needs the contacts' priors (the ledger,
    /// the force jumps or [`GpuOptions::contacts`]). Right after a restore the forces are
    /// those of the next step's first evaluation: zero until a step has run.
    pub fn contact_network(&self) -> Result<ContactNetwork, PowderError> {
        let s = &self.state;
        if !self.keeps.prior() {
            return Err(PowderError::Run(
                "this GPU run keeps no per-contact state to output (it has no energy ledger and no force jumps): run it with GpuOptions { contacts: true } (`powder run` does where the scene's contact_output is on)".into(),
            ));
        }
        let hb = self.kind.history_bytes() as usize;
        let (ids, entries) = self.read_lists()?;
        let entries = &entries;
        let (cap, windows) = (self.entries, s.layout.windows());
        let layout = &s.entry_layout;
        let id_of = |e: u64| {
            let at = layout.byte_of("hist_pid", cap, windows, e)? as usize;
            entries
                .get(at..at + 4)
                .map(bytemuck::pod_read_unaligned::<u32>)
        };
        let vec3 = |name: &str, e: u64| {
            let v = layout.read_vec3(entries, name, (cap, windows), e);
            v.map_or(DVec3::ZERO, |v| {
                DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
            })
        };
        let history = |e: u64| -> Option<ContactHistory> {
            let at = layout.byte_of("hist", cap, windows, e)? as usize;
            Some(self.decode_history(entries.get(at..at + hb)?))
        };
        let mut pairs = Vec::new();
        let mut walls = Vec::new();
        for &[pid, row, count, near_walls] in &ids {
            for e in row as u64..(row + count + near_walls) as u64 {
                let (Some(partner), Some(prior), Some(h)) = (
                    id_of(e),
                    layout.read_vec4(entries, "prior", (cap, windows), e),
                    history(e),
                ) else {
                    continue;
                };
                if prior[3] <= 0.0 {
                    continue;
                }
                let mut line = ContactLine {
                    i: pid as usize,
                    partner: Partner::Particle(partner as usize),
                    normal_force: prior[1] as f64,
                    force: vec3("pair_force", e),
                    overlap: prior[0] as f64,
                    history: h,
                    sliding: prior[3] > 1.5,
                };
                if partner & WALL_ENTRY != 0 {
                    let w = (partner & !WALL_ENTRY) as usize;
                    if w >= self.wall_normals.len() {
                        continue;
                    }
                    // the normal force from the prior, the tangential one kept in the
                    // entry's pair torque (a wall takes none)
                    line.partner = Partner::Wall(w);
                    line.force = line.normal_force * self.wall_normals[w] + vec3("pair_torque", e);
                    walls.push(((w, pid), line));
                } else {
                    if partner < pid {
                        // the pair from its lower id's side: the force on it, its view
                        line.i = partner as usize;
                        line.partner = Partner::Particle(pid as usize);
                        line.force = -line.force;
                        line.history = self.kind.mirror_history(h);
                    }
                    pairs.push(line);
                }
            }
        }
        pairs.sort_by_key(|c| match c.partner {
            Partner::Particle(j) => (c.i, j),
            Partner::Wall(w) => (c.i, w),
        });
        walls.sort_by_key(|(k, _)| *k);
        pairs.extend(walls.into_iter().map(|(_, c)| c));
        Ok(ContactNetwork {
            lines: pairs,
            fields: self.kind.history(),
        })
    }

    /// The history of particle `i`'s contact with wall `w` after the last step (zero when
    /// they are apart). For tests and diagnostics: reads buffers back.
    pub fn wall_contact_history(&self, w: usize, i: usize) -> Result<ContactHistory, PowderError> {
        let walls = self.n_walls as usize;
        if w >= walls {
            return Err(PowderError::Run(format!(
                "wall {w} does not exist (the scene has {walls})"
            )));
        }
        let hb = self.kind.history_bytes() as usize;
        let WallEntries {
            ids,
            entries,
            found,
        } = self.read_wall_entries()?;
        let k = ids
            .iter()
            .position(|p| p[0] as usize == i)
            .ok_or_else(|| PowderError::Run(format!("particle {i} does not exist")))?;
        let s = &self.state;
        let at = found
            .into_iter()
            .find(|&(kk, ww, _)| kk == k && ww == w)
            .and_then(|(_, _, e)| {
                s.entry_layout
                    .byte_of("hist", self.entries, s.layout.windows(), e)
            });
        // no entry: the wall was beyond reach + skin at the last rebuild, no history
        Ok(match at {
            Some(at) => self.decode_history(&entries[at as usize..at as usize + hb]),
            None => self.decode_history(&vec![0u8; hb]),
        })
    }
}
