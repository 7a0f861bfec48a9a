//! Recording a step's passes into a batch, submitting it and reading its monitor back.

use super::*;

/// The step's kernels, bound to the run's buffers.
pub(super) struct Bound {
    pub(super) kick_drift: Pass,
    pub(super) decide: Pass,
    pub(super) decide_lean: Pass,
    pub(super) gather: Pass,
    pub(super) count_neighbours: Pass,
    pub(super) neighbours: Pass,
    pub(super) commit: Pass,
    pub(super) remap: Pass,
    pub(super) copy_back_history: Pass,
    pub(super) force: Pass,
    pub(super) kick: Pass,
    pub(super) collect_kick_drift: Pass,
    pub(super) collect: Pass,
    /// The moving-wall kernels, only for scenes with moving / servo-controlled walls.
    pub(super) wall_move: Option<Pass>,
    pub(super) wall_servo: Option<Pass>,
    pub(super) wall_servo_apply: Option<Pass>,
    /// The appeared flags into the state, only for scenes that pour.
    pub(super) appear: Option<Pass>,
}

/// One kernel with its bind groups: one a window where it works on windows, else one.
pub(super) struct Pass {
    pub(super) kernel: Kernel,
    pub(super) groups: Vec<wgpu::BindGroup>,
    /// (global name, bytes) of every distinct resource the group binds (`gpu::traffic`).
    pub(super) bound: Vec<(String, u64)>,
}

impl Pass {
    /// One workgroup (a window); returns the dispatches recorded.
    pub(super) fn once(&self, pass: &mut wgpu::ComputePass<'_>, max_per_dim: u32) -> usize {
        for group in &self.groups {
            self.kernel.dispatch_workgroups(pass, group, 1, max_per_dim);
        }
        self.groups.len()
    }

    /// Workgroup counts from `args` at byte `offset` (each window's dispatch the same);
    /// returns the dispatches recorded.
    pub(super) fn indirect(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        args: &wgpu::Buffer,
        offset: u64,
    ) -> usize {
        for group in &self.groups {
            self.kernel.dispatch_indirect(pass, group, args, offset);
        }
        self.groups.len()
    }
}

/// A compute pass, its start timestamped while the pass profile runs.
pub(super) fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    clock: Option<&PassClock>,
) -> wgpu::ComputePass<'e> {
    let mut pass = encoder.begin_compute_pass(&Default::default());
    if let Some(c) = clock {
        c.start(&mut pass);
    }
    pass
}

/// The end of `name`'s dispatches, timestamped while the pass profile runs.
pub(super) fn mark(
    pass: &mut wgpu::ComputePass<'_>,
    clock: Option<&PassClock>,
    name: &'static str,
) {
    if let Some(c) = clock {
        c.mark(pass, name);
    }
}

/// How a recorded step starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Drift {
    /// No drift (the initial forces).
    None,
    /// `kick_drift`: the first step of a batch.
    Plain,
    /// `collect_kick_drift`: the previous step's collect and closing kick, then the drift.
    AfterStep,
}

/// How the steps of a batch hold a rebuild of the neighbour lists (bitwise the same run
/// either way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RebuildChain {
    /// Every step records the rebuild's passes, dispatched with no workgroups where
    /// `decide` finds no rebuild due (about 30 dispatches a step, each a barrier).
    EveryStep,
    /// Steps record only `decide_lean`, which halts the batch where a rebuild is due; the
    /// host runs that step again from its rebuild (one more submission a rebuild).
    #[default]
    OnDemand,
}

/// What a recorded step holds of a rebuild.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Chain {
    /// `decide` and the rebuild's passes.
    Full,
    /// `decide_lean` only ([`RebuildChain::OnDemand`]).
    Lean,
    /// Neither (a quiet batch, `gpu::quiet`).
    Quiet,
}

/// Why a batch halted ([`CONTROL_HALT`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Halt {
    /// A rebuild's new lists need this many entries (`commit`).
    Grow(u64),
    /// A rebuild is due in a step recorded without one (`decide_lean`).
    Rebuild,
}

/// What the host reads after a batch: the control words, the monitor and the skin state
/// (`gpu::control`).
pub(super) struct BatchReport {
    pub(super) control: Vec<u32>,
}

impl BatchReport {
    /// The control word `i` (one of [`CONTROL_WORDS`]).
    pub(super) fn word(&self, i: u32) -> u32 {
        self.control[i as usize]
    }

    /// Why the batch halted, if it did (`halt` in `shaders/step/rebuild.wgsl`).
    pub(super) fn halted(&self) -> Option<Halt> {
        match self.word(CONTROL_HALT) {
            0 => None,
            HALT_REBUILD => Some(Halt::Rebuild),
            _ => Some(Halt::Grow(self.word(CONTROL_ENTRIES_NEEDED) as u64)),
        }
    }

    /// Steps of a halted batch completed before the one that halted (`decide` and
    /// `decide_lean` count the steps begun).
    pub(super) fn completed(&self) -> u64 {
        (self.word(CONTROL_STEPS_BEGUN) as u64).saturating_sub(1)
    }
}

impl GpuEngine {
    /// Records one step: drift, decide whether to rebuild, on a rebuild (indirect: no
    /// workgroups otherwise) sort, build the new lists in B (count, place, fill), re-sort
    /// the state in place, remap the history and copy the lists back; then the forces.
    /// Their collect and the closing kick are recorded with the next step
    /// (`Drift::AfterStep`) or by [`Self::record_finish`]. `chain`: with the rebuild's
    /// passes, `decide_lean` alone, or neither ([`Chain`]). Returns the dispatches recorded.
    pub(super) fn record_step(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        drift: Drift,
        chain: Chain,
    ) -> usize {
        let bound = &self.bound;
        let max = self.max_per_dim;
        let clock = self.clock.as_ref();
        let (args, at, step) = (&self.b.args, self.dispatch.rebuild, self.dispatch.step);
        let mut n = 0;
        {
            let mut pass = begin(encoder, clock);
            if drift != Drift::None {
                let (first, name) = match drift {
                    Drift::AfterStep => (&bound.collect_kick_drift, "collect_kick_drift"),
                    _ => (&bound.kick_drift, "kick_drift"),
                };
                n += first.indirect(&mut pass, args, step);
                mark(&mut pass, clock, name);
                if let Some(p) = &bound.wall_move {
                    n += p.indirect(&mut pass, args, step + 12);
                    mark(&mut pass, clock, "wall_move");
                }
            }
            match chain {
                Chain::Full => {
                    n += bound.decide.once(&mut pass, max);
                    mark(&mut pass, clock, "decide");
                }
                Chain::Lean => {
                    n += bound.decide_lean.once(&mut pass, max);
                    mark(&mut pass, clock, "decide_lean");
                }
                Chain::Quiet => {}
            }
        }
        if chain == Chain::Full {
            clock.inspect(|c| c.start_between(encoder));
            n += self.grid.encode_indirect(encoder, &self.grid_keys, args, 0);
            clock.inspect(|c| c.mark_between(encoder, "grid sort"));
            let mut pass = begin(encoder, clock);
            if !self.mirrors.is_empty() {
                n += bound.gather.indirect(&mut pass, args, at);
                mark(&mut pass, clock, "gather");
            }
            n += bound.count_neighbours.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "count_neighbours");
            for (scan, &offset) in self.scans.iter().zip(self.dispatch.scans.iter().cycle()) {
                n += scan.record_indirect(&mut pass, args, offset);
            }
            mark(&mut pass, clock, "list scans");
            n += bound.neighbours.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "neighbours");
            n += bound.commit.once(&mut pass, max);
            mark(&mut pass, clock, "commit");
            n += self.permutation.encode_indirect(&mut pass, args, at);
            mark(&mut pass, clock, "permute");
            n += bound.remap.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "remap");
            n += bound.copy_back_history.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "copy_back_history");
        }
        // the state the forces see, drifted (and re-sorted on a rebuild)
        if !self.mirrors.is_empty() {
            clock.inspect(|c| c.start_between(encoder));
            self.mirrors.encode(encoder);
            clock.inspect(|c| c.mark_between(encoder, "mirror copies"));
        }
        let mut pass = begin(encoder, clock);
        n += bound.force.indirect(&mut pass, args, step);
        mark(&mut pass, clock, "force");
        if let Some(p) = &bound.wall_servo {
            n += p.indirect(&mut pass, args, step + 12);
            mark(&mut pass, clock, "wall_servo");
        }
        if let Some(p) = &bound.wall_servo_apply {
            n += p.indirect(&mut pass, args, step + 12);
            mark(&mut pass, clock, "wall_servo_apply");
        }
        n
    }

    /// The compute dispatches a step records (each window's counts, empty ones too): one
    /// that holds no rebuild's passes as this run records them ([`RebuildChain`]), and one
    /// that does. Recorded into an encoder that is never submitted.
    pub fn dispatches_per_step(&self) -> [usize; 2] {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        let plain = match self.rebuild_chain {
            RebuildChain::OnDemand => Chain::Lean,
            RebuildChain::EveryStep => Chain::Full,
        };
        let plain = self.record_step(&mut encoder, Drift::AfterStep, plain);
        let full = self.record_step(&mut encoder, Drift::AfterStep, Chain::Full);
        [plain, full]
    }

    /// Records `collect` (the forces of the step just recorded are then complete) and,
    /// with `kick`, the closing kick: at the end of a batch, or without the kick after the
    /// initial forces.
    pub(super) fn record_finish(&self, encoder: &mut wgpu::CommandEncoder, kick: bool) {
        let (args, at) = (&self.b.args, self.dispatch.step);
        let clock = self.clock.as_ref();
        let mut pass = begin(encoder, clock);
        self.bound.collect.indirect(&mut pass, args, at);
        mark(&mut pass, clock, "collect");
        if kick {
            self.bound.kick.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "kick");
        }
    }

    /// Before a batch is submitted: the monitor zeroed, every step's dispatch arguments
    /// set (a halt zeroes them).
    pub(super) fn start_batch(&self) {
        let q = &self.ctx.queue;
        q.write_buffer(&self.b.control, 0, &[0u8; MONITOR_BYTES as usize]);
        q.write_buffer(
            &self.b.args,
            self.dispatch.step,
            bytemuck::cast_slice(&self.dispatch.step_full),
        );
    }

    /// Submits a recorded batch and reads the monitor and the skin state back.
    pub(super) fn submit_batch(
        &self,
        mut encoder: wgpu::CommandEncoder,
    ) -> Result<BatchReport, PowderError> {
        let mut sources = vec![(&self.b.control, CONTROL_BYTES)];
        let stamps = self.clock.as_ref().and_then(|c| c.resolve(&mut encoder));
        sources.extend(stamps);
        let out = submit_and_read(&self.ctx, encoder, &sources)?;
        if let (Some(clock), Some(stamps)) = (&self.clock, out.get(1)) {
            clock.take(stamps);
        }
        Ok(BatchReport {
            control: u32s(&out[0]).to_vec(),
        })
    }

    /// Whether the steps recorded from now on place the force jumps (`StepParams::jumps`).
    pub(super) fn set_jumps(&self, on: bool) {
        let at = std::mem::offset_of!(StepParams, jumps) as u64;
        self.ctx
            .queue
            .write_buffer(&self.b.step, at, bytemuck::bytes_of(&u32::from(on)));
    }

    /// Takes in what a batch's monitor holds: its records, and an error for what stops a run.
    /// An error where a rebuild found a particle's neighbours beyond its window's
    /// bindings: the batch halted before anything read them.
    pub(super) fn check_windows(&self, report: &BatchReport) -> Result<(), PowderError> {
        if report.word(CONTROL_BEYOND_WINDOW) == 0 {
            return Ok(());
        }
        let w = self.state.layout.windows();
        Err(PowderError::Run(format!(
            "step {}: a particle's neighbours lie more than one window of {} particles away in the sorted order (a window's dispatches bind it and its neighbours only): the packing's layers of cells hold more particles than a window; run with larger windows where the adapter's binding limit allows (`--window-particles`, GpuOptions::window_particles)",
            self.steps, w.len
        )))
    }

    pub(super) fn apply_monitor(&mut self, report: &BatchReport) -> Result<(), PowderError> {
        let m = |i| report.word(i);
        self.dropped += m(CONTROL_DROPPED) as u64;
        let ratio = f32::from_bits(m(CONTROL_PEAK_OVERLAP)) as f64;
        let at = m(CONTROL_OVERLAP_PARTICLE);
        let beyond = (at != 0).then(|| at as usize - 1);
        if self.peak.is_none_or(|(r, _)| ratio > r) {
            self.peak = Some((ratio, beyond.or(self.peak.and_then(|p| p.1))));
        }
        let escaped = m(CONTROL_ESCAPED_PARTICLE);
        if escaped != 0 && self.escaped.is_none() {
            self.escaped = Some(escaped as usize - 1);
        }
        let non_finite = m(CONTROL_NON_FINITE);
        if non_finite != 0 {
            return Err(PowderError::Run(format!(
                "by step {}: particle {} got a non-finite acceleration (force/mass or torque/inertia beyond f32's range of ±3.4e38, or a NaN; the largest such id of the batch): the time step may be too large, or the scene's units put its accelerations beyond what the GPU's f32 holds (rescale the units, or run --backend cpu in f64)",
                self.steps,
                non_finite - 1
            )));
        }
        Ok(())
    }
}
