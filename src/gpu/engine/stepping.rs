//! Running steps: batches, the halts that grow the lists, and the software adapter's quiet batches.

use super::*;

/// What quiet batches need: (buffer of the state a batch changes, its batch-start copy),
/// the forecast and the counts.
pub(super) struct Quiet {
    pub(super) mode: QuietBatches,
    pub(super) copies: Vec<Saved>,
    /// The lists' history and priors at a batch's start (the new lists live in the
    /// entries' per-step fields, which the batch writes).
    pub(super) lists: wgpu::Buffer,
    pub(super) forecast: Forecast,
    /// The device's rebuild count at the end of the last batch (u64::MAX: unknown).
    pub(super) rebuilds: u64,
    pub(super) kept: u64,
    pub(super) rolled_back: u64,
}

/// A range of a buffer a quiet batch may change, and where its batch-start copy goes.
#[derive(Clone)]
pub(super) struct Saved {
    pub(super) from: wgpu::Buffer,
    pub(super) from_at: u64,
    pub(super) to: wgpu::Buffer,
    pub(super) to_at: u64,
    pub(super) bytes: u64,
}

impl Saved {
    /// All of `from` into `to`.
    pub(super) fn whole(from: &wgpu::Buffer, to: wgpu::Buffer) -> Self {
        Self {
            from: from.clone(),
            from_at: 0,
            bytes: from.size(),
            to,
            to_at: 0,
        }
    }

    pub(super) fn save(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.from, self.from_at, &self.to, self.to_at, self.bytes);
    }

    pub(super) fn restore(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.to, self.to_at, &self.from, self.from_at, self.bytes);
    }
}

impl GpuEngine {
    /// The forces of the initial state (no drift, no kick), so the first step kicks with them.
    /// Contacts present at the start carry stored energy, not dissipation: the ledger's
    /// dissipation (booked from the contacts' entry edges) is zeroed afterwards, as on the CPU.
    /// `rewindow`: where the lists outgrow one automatic window's binding, the entries
    /// they need (`Some`) instead of an error: the caller builds again in windows.
    pub(super) fn initial_forces(&mut self, rewindow: bool) -> Result<Option<u64>, PowderError> {
        // the initial contacts crossed nothing: no force jump placed
        self.set_jumps(false);
        loop {
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            self.start_batch();
            self.record_step(&mut encoder, Drift::None, Chain::Full);
            self.record_finish(&mut encoder, false);
            let report = self.submit_batch(encoder)?;
            // the first lists did not fit the first guess: grown, built again
            match report.halted() {
                Some(Halt::Grow(need)) => {
                    self.check_windows(&report)?;
                    if rewindow && self.outgrows_one_window(need) {
                        return Ok(Some(need));
                    }
                    self.grow_lists(need)?
                }
                // (a full step: `decide_lean` does not run)
                Some(Halt::Rebuild) | None => break self.apply_monitor(&report)?,
            }
        }
        if self.keeps.ledger {
            let (_, mut motion) = self.read_state()?;
            let l = &self.state.layout;
            let mut energy: Vec<[f32; 4]> = l.unpack(&motion, "ledger_energy");
            for e in &mut energy {
                e[0] = 0.0;
                e[1] = 0.0;
            }
            l.repack(&mut motion, "ledger_energy", &energy);
            write_pages(&self.ctx.queue, &self.state.motion, &motion);
        }
        self.set_jumps(self.keeps.jumps);
        Ok(None)
    }

    /// Runs `steps` steps, `STEPS_PER_SUBMIT` per submission, checking the monitor after
    /// each: a non-finite acceleration is an error naming its particle (the deepest overlap
    /// is [`Self::take_peak_overlap`]'s).
    pub fn run_steps(&mut self, steps: u64) -> Result<(), PowderError> {
        let mut left = steps;
        while left > 0 {
            // the rest of a halted batch starts with the halted step, drifted already, and
            // keeps the batch's boundaries (walls and insertions are set at them)
            let (batch, first) = match self.resume.take() {
                Some(rest) => (rest.min(left), Drift::None),
                None => {
                    self.switch_wall_phases()?;
                    let batch = left
                        .min(STEPS_PER_SUBMIT)
                        .min(self.prescribe_walls())
                        .min(self.insert_due());
                    (batch, Drift::Plain)
                }
            };
            let quiet = match first {
                Drift::Plain => self.quiet_batch(batch)?,
                _ => None,
            };
            let report = match quiet {
                Some(report) => report,
                None => {
                    self.start_batch();
                    let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                    for i in 0..batch {
                        let drift = if i == 0 { first } else { Drift::AfterStep };
                        // (a halted batch's rest starts from the halted step's rebuild)
                        let chain = match self.rebuild_chain {
                            RebuildChain::OnDemand if drift != Drift::None && self.lean => {
                                Chain::Lean
                            }
                            _ => Chain::Full,
                        };
                        self.record_step(&mut encoder, drift, chain);
                    }
                    self.record_finish(&mut encoder, true);
                    self.submit_batch(encoder)?
                }
            };
            let done = match report.halted() {
                Some(_) => report.completed(),
                None => batch,
            };
            // the walls moved in every step begun with a drift
            let moved = (done + u64::from(report.halted().is_some()))
                .saturating_sub(u64::from(first == Drift::None));
            self.advance_prescribed_walls(moved);
            self.steps += done;
            // (steps·dt: the same bits wherever batches end or halt)
            self.time = self.steps as f64 * self.dt;
            left -= done;
            self.apply_monitor(&report)?;
            // lean while rebuilds are rare: a halt costs a submission, and the batch's
            // remaining steps are recorded again (where they come every few steps, the
            // chain in every step is cheaper)
            let rebuilds = report.word(SKIN_REBUILDS) as u64;
            let rebuilt = rebuilds.saturating_sub(self.rebuilds_seen);
            self.rebuilds_seen = rebuilds;
            self.lean = match report.halted() {
                Some(Halt::Rebuild) => done >= MIN_LEAN_STEPS,
                _ => rebuilt * MIN_LEAN_STEPS <= batch,
            };
            match report.halted() {
                Some(Halt::Grow(need)) => {
                    self.check_windows(&report)?;
                    self.grow_lists(need)?;
                    self.resume = Some(batch - done);
                }
                Some(Halt::Rebuild) => {
                    self.lean_halts += 1;
                    self.resume = Some(batch - done);
                }
                None => self.observe(batch, &report),
            }
        }
        Ok(())
    }

    /// How step `i` of a (quiet) batch starts: each step's closing kick goes with the next
    /// step's drift.
    pub(super) fn drift_of(i: u64) -> Drift {
        if i == 0 {
            Drift::Plain
        } else {
            Drift::AfterStep
        }
    }

    /// Tells the rebuild forecast what a kept batch ended with.
    pub(super) fn observe(&mut self, batch: u64, report: &BatchReport) {
        if let Some(q) = &mut self.quiet {
            let rebuilt = report.word(SKIN_REBUILDS) as u64 != q.rebuilds;
            let since = rebuilt.then_some(report.word(CONTROL_STEPS_SINCE_REBUILD) as u64);
            q.forecast.observe(
                batch,
                since,
                f32::from_bits(report.word(CONTROL_DISPLACEMENT)) as f64,
            );
            q.rebuilds = report.word(SKIN_REBUILDS) as u64;
        }
    }

    /// Runs `batch` steps as a quiet batch (`gpu::quiet`) when the scene allows it and the
    /// forecast expects no rebuild: the batch's report when it was kept, `None` when it did
    /// not run or was rolled back (the state is then as before: run it the normal way).
    pub(super) fn quiet_batch(&mut self, batch: u64) -> Result<Option<BatchReport>, PowderError> {
        let Some(q) = &self.quiet else {
            return Ok(None);
        };
        if !q.forecast.quiet(batch, q.mode) {
            return Ok(None);
        }
        let copies = self.quiet_copies(q);
        self.start_batch();
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for c in &copies {
            c.save(&mut encoder);
        }
        for i in 0..batch {
            self.record_step(&mut encoder, Self::drift_of(i), Chain::Quiet);
        }
        self.record_finish(&mut encoder, true);
        let report = self.submit_batch(encoder)?;
        if report.word(SKIN_MOVED) == 0 {
            // no step would have rebuilt: the batch is what the normal one computes
            if let Some(q) = &mut self.quiet {
                q.kept += 1;
            }
            return Ok(Some(report));
        }
        // some step needed a rebuild: back to the batch's start (its monitor is void: the
        // steps after the missed rebuild ran with stale lists)
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for c in &copies {
            c.restore(&mut encoder);
        }
        self.ctx
            .queue
            .write_buffer(&self.b.control, SKIN_OFFSET, bytemuck::bytes_of(&0u32));
        self.ctx.queue.submit([encoder.finish()]);
        if let Some(q) = &mut self.quiet {
            q.rolled_back += 1;
        }
        Ok(None)
    }

    /// (buffer a quiet batch changes, where its batch-start copy goes): the state into the
    /// quiet batches' own copies, the lists' history and priors into `quiet.lists` (the
    /// new lists live in the entries' per-step fields, which the batch writes).
    pub(super) fn quiet_copies(&self, q: &Quiet) -> Vec<Saved> {
        let (a, b) = (&self.state, &self._new_lists);
        let mut v = q.copies.clone();
        let windows = a.layout.windows();
        let (target, layout) = (&q.lists, &b.standalone());
        for w in 0..windows.count {
            let first = windows.record(w, 0);
            for (from, to) in [("hist", "new_hist"), ("prior", "new_prior")] {
                let cap = self.entries;
                if let (Some(at), Some(to_at), Some((_, words))) = (
                    a.entry_layout.byte_of(from, cap, windows, first),
                    layout.byte_of(to, cap, windows, first),
                    a.entry_layout.place(from),
                ) {
                    let (from, at) = a.entry_at(at, cap);
                    v.push(Saved {
                        from: from.clone(),
                        from_at: at,
                        to: target.clone(),
                        to_at,
                        bytes: 4 * words * cap,
                    });
                }
            }
        }
        v
    }

    /// Quiet batches kept and rolled back so far (`gpu::quiet`); (0, 0) where the scene or
    /// the options allow none.
    pub fn quiet_batches(&self) -> (u64, u64) {
        self.quiet
            .as_ref()
            .map_or((0, 0), |q| (q.kept, q.rolled_back))
    }

    /// Neighbour-list rebuilds so far (the first, before the first step, included): reads
    /// the device's counter back.
    pub fn rebuilds(&self) -> Result<u64, PowderError> {
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(&self.ctx, encoder, &[(&self.b.control, CONTROL_BYTES)])?;
        Ok(u32s(&out[0])[SKIN_REBUILDS as usize] as u64)
    }
}
