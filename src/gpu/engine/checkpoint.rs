//! Saving the device state for a checkpoint and restoring it, bitwise.

use super::*;

/// Everything that evolves in a GPU run, read back from the device: what a checkpoint
/// stores to resume bitwise on the same adapter, and what the run monitor restores when it
/// stops a run. The buffers are the current state set (the other set is rewritten by every
/// step before it is read), the neighbour lists, the Verlet-skin state and the
/// per-particle ledger.
#[derive(Clone, Debug)]
pub struct GpuSavedState {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    pub(crate) dropped: u64,
    /// The adapter it ran on (a resume elsewhere continues, but not bitwise).
    pub adapter: String,
    /// (name, bytes), in a fixed order.
    pub(crate) buffers: Vec<(String, Vec<u8>)>,
    /// The host's f64 points of the walls.
    pub(crate) wall_points: Vec<DVec3>,
    /// Which particles have appeared, and the energy they brought.
    pub(crate) active: Vec<bool>,
    pub(crate) inserted: f64,
    /// The composed contact law's layout (`Composition::layout`): the history words in the
    /// buffers mean what it says.
    pub(crate) layout: String,
    /// Whether the run kept the energy ledger (its rows are fields of the state).
    pub(crate) ledger: bool,
}

impl GpuSavedState {
    /// Whether the state was taken by a run that keeps the energy ledger
    /// ([`GpuOptions::ledger`]): it then holds the per-particle ledger, and restores only
    /// into an engine that keeps it too (and the reverse).
    pub fn has_ledger(&self) -> bool {
        // (before the ledger's rows joined the particle state they were a buffer of their own)
        self.ledger
            || self
                .buffers
                .iter()
                .any(|(name, _)| name == "particle_ledger")
    }
}

impl GpuEngine {
    /// The state buffers, named as in [`GpuSavedState`], each with the buffers its bytes
    /// lie in one after the other (the entries' pages; one buffer for the others).
    pub(super) fn state_buffers(&self) -> Vec<(String, Vec<&wgpu::Buffer>)> {
        let mut list: Vec<(String, Vec<&wgpu::Buffer>)> = self
            .state
            .named()
            .into_iter()
            .map(|(name, b)| match name.as_str() {
                "entries" => (name, self.state.entries.iter().collect()),
                "state" => (name, self.state.state.iter().collect()),
                "motion" => (name, self.state.motion.iter().collect()),
                _ => (name, vec![b]),
            })
            .collect();
        list.push(("rows".into(), vec![&self.b.rows]));
        list.push(("control".into(), vec![&self.b.control]));
        list.push(("walls".into(), vec![&self.b.walls]));
        list.push(("wall_ref".into(), vec![&self.b.wall_ref]));
        list
    }

    /// Reads the complete evolving state back (see [`GpuSavedState`]).
    pub fn save_state(&self) -> Result<GpuSavedState, PowderError> {
        let list = self.state_buffers();
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let groups: Vec<_> = list
            .iter()
            .map(|(_, bs)| bs.iter().map(|b| (*b, 0, b.size())).collect())
            .collect();
        let mut out = read_joined(&self.ctx, encoder, &groups)?;
        // the monitor words are a batch's scratch (zeroed when one starts): left out, so a
        // state saved after a quiet batch (no `decide` counting steps) and one saved after
        // a normal batch are the same bytes
        // so are the entries' per-step fields (pair forces and torques, the jumps' impulses:
        // the batch's last collect consumed them; `jump_normal` is written only in a step
        // that places a jump, so a rolled-back quiet batch may leave other bytes there)
        for ((name, _), bytes) in list.iter().zip(&mut out) {
            if name == "control" {
                bytes[..MONITOR_BYTES as usize].fill(0);
            }
            if name == "entries" {
                let layout = &self.state.entry_layout;
                let windows = self.state.layout.windows();
                for w in 0..windows.count {
                    let first = windows.record(w, 0);
                    for field in ["pair_force", "pair_torque", "jump", "jump_normal"] {
                        if let (Some(at), Some((_, words))) = (
                            layout.byte_of(field, self.entries, windows, first),
                            layout.place(field),
                        ) {
                            let (at, len) = (at as usize, (4 * words * self.entries) as usize);
                            bytes[at..at + len].fill(0);
                        }
                    }
                }
            }
        }
        Ok(GpuSavedState {
            time: self.time,
            steps: self.steps,
            dropped: self.dropped,
            adapter: self.ctx.summary.name.clone(),
            buffers: list.into_iter().map(|(n, _)| n).zip(out).collect(),
            wall_points: self.wall_points.clone(),
            active: self.active.clone(),
            inserted: self.inserted,
            layout: self.saved_layout(),
            ledger: self.keeps.ledger,
        })
    }

    /// What a saved state's words mean: the contact law's layout (`Composition::layout`),
    /// the list entries' fields (which the options change: the priors) and the windows
    /// where there are several.
    pub(super) fn saved_layout(&self) -> String {
        let w = self.state.layout.windows();
        let fields: Vec<&str> = self
            .state
            .entry_layout
            .fields
            .iter()
            .map(|f| f.name)
            .collect();
        let law = format!("{}, entries [{}]", self.kind.layout(), fields.join(", "));
        match w.count {
            1 => law,
            _ => format!("{law} in windows of {} particles", w.len),
        }
    }

    /// Refuses a saved particle state with a value that is not finite (a damaged or edited
    /// checkpoint, or one of a run that had already diverged), naming the field and the
    /// particle.
    fn check_finite(&self, buffers: &[(String, Vec<u8>)]) -> Result<(), PowderError> {
        use crate::gpu::state::{Buffer, Scalar};
        let l = &self.state.layout;
        let bytes = |b: Buffer| buffers.iter().find(|(n, _)| n == b.name()).map(|(_, v)| v);
        let (Some(state), Some(_)) = (bytes(Buffer::State), bytes(Buffer::Motion)) else {
            return Ok(());
        };
        let ids: Vec<[u32; 4]> = l.unpack(state, "ids");
        for b in [Buffer::State, Buffer::Motion] {
            let Some(data) = bytes(b) else { continue };
            for f in l.in_buffer(b).filter(|f| f.scalar == Scalar::F32) {
                let values: Vec<[f32; 4]> = l.unpack(data, f.name);
                if let Some(k) = values.iter().position(|v| v.iter().any(|x| !x.is_finite())) {
                    let id = ids.get(k).map_or(k as u32, |i| i[0]);
                    return Err(PowderError::Run(format!(
                        "the saved GPU state's `{}` ({}) of particle {id} is {:?}, not finite: the checkpoint is damaged or was edited, or its run had already diverged",
                        f.name, f.doc, values[k]
                    )));
                }
            }
        }
        Ok(())
    }

    /// Writes a saved state back: the run continues exactly as it would have from there.
    /// Refused when it does not fit this engine: taken with the other ledger option (the
    /// message names `--no-ledger`), or naming the buffer (another scene or step variant).
    pub fn restore_state(&mut self, saved: GpuSavedState) -> Result<(), PowderError> {
        if saved
            .buffers
            .iter()
            .any(|(name, _)| name == "particle_ledger")
        {
            return Err(PowderError::Run(
                "the saved GPU state was written by a powder version that kept the energy ledger in a buffer of its own (`particle_ledger`; its rows are fields of the particle state now): rerun the scene from the start with this version".into(),
            ));
        }
        // (the engine's clock is steps·dt: a state taken with another dt does not fit it)
        if saved.time.to_bits() != (saved.steps as f64 * self.dt).to_bits() {
            return Err(PowderError::Run(format!(
                "the saved GPU state is at t = {:e} s after {} steps, which is not {} steps of this run's dt = {:e} s: it was taken with another time step (about {:e} s; to continue it, set simulation.dt to that run's, since an automatic dt's rule can change between powder versions)",
                saved.time, saved.steps, saved.steps, self.dt, saved.time / saved.steps.max(1) as f64
            )));
        }
        // the ledger cannot be made up for steps already taken, nor dropped silently
        match (saved.has_ledger(), self.has_ledger()) {
            (true, false) => {
                return Err(PowderError::Run(
                    "the saved GPU state was taken with the energy ledger, and this run keeps none (`powder run --no-ledger`, GpuOptions { ledger: false }): resume it without --no-ledger".into(),
                ))
            }
            (false, true) => {
                return Err(PowderError::Run(
                    "the saved GPU state was taken without the energy ledger (`powder run --no-ledger`, GpuOptions { ledger: false }), and this run keeps it: resume it with --no-ledger (the ledger of the steps already taken cannot be rebuilt)".into(),
                ))
            }
            _ => {}
        }
        if saved.layout != self.saved_layout() {
            return Err(PowderError::Run(format!(
                "the saved GPU state's contact law is laid out as `{}`, this run's as `{}` (another scene, window size, contact output option or powder version): rerun the scene from the start, or resume it with the options it was taken with",
                saved.layout,
                self.saved_layout()
            )));
        }
        if let Some(why) =
            crate::scene::misfit_appearance(&self.insert_at, &saved.active, saved.steps, self.dt)
        {
            return Err(PowderError::Run(format!(
                "the saved GPU state does not fit the scene's pouring: {why} (the checkpoint is damaged or was edited)"
            )));
        }
        if saved.wall_points.len() != self.wall_points.len() {
            return Err(PowderError::Run(format!(
                "the saved GPU state holds {} walls but the scene has {}",
                saved.wall_points.len(),
                self.wall_points.len()
            )));
        }
        if let Some(i) = saved.wall_points.iter().position(|p| !p.is_finite()) {
            return Err(PowderError::Run(format!(
                "the saved GPU state's wall point {i} is {:?}, not finite: the checkpoint is damaged or was edited",
                saved.wall_points[i]
            )));
        }
        // the lists' capacity the state was saved with (its entries' size)
        let windows = *self.state.layout.windows();
        let entry_bytes = 4 * self.state.entry_layout.words() * windows.count;
        let entries = saved
            .buffers
            .iter()
            .find(|(name, _)| name == "entries")
            .map_or(self.entries, |(_, bytes)| bytes.len() as u64 / entry_bytes);
        let list = self.state_buffers();
        let names: Vec<&String> = list.iter().map(|(n, _)| n).collect();
        let saved_names: Vec<&String> = saved.buffers.iter().map(|(n, _)| n).collect();
        if names != saved_names {
            return Err(PowderError::Run(format!(
                "the saved GPU state holds buffers {saved_names:?}, this run needs {names:?} (another scene or step variant)"
            )));
        }
        // every size checked before anything changes (the per-entry arrays at the saved
        // capacity)
        for ((name, bufs), (_, bytes)) in list.iter().zip(&saved.buffers) {
            let expected = if name == "entries" {
                (entry_bytes * entries).max(4)
            } else {
                bufs.iter().map(|b| b.size()).sum()
            };
            if bytes.len() as u64 != expected {
                return Err(PowderError::Run(format!(
                    "the saved GPU buffer `{name}` has {} bytes, this run's has {expected} (another scene?)",
                    bytes.len(),
                )));
            }
        }
        self.check_finite(&saved.buffers)?;
        if entries != self.entries {
            self.resize_lists(entries, false)?;
        }
        for ((_, bufs), (_, bytes)) in self.state_buffers().iter().zip(&saved.buffers) {
            let bufs: Vec<wgpu::Buffer> = bufs.iter().map(|&b| b.clone()).collect();
            write_pages(&self.ctx.queue, &bufs, bytes);
        }
        self.wall_points = saved.wall_points;
        // the device's walls are in the phase of the last step run
        let last = saved.steps.saturating_sub(1) as f64 * self.dt;
        self.wall_phase = self.wall_motion.iter().map(|m| m.index_at(last)).collect();
        self.active = saved.active;
        self.write_appeared();
        if let Some(q) = &mut self.quiet {
            q.forecast.forget();
            q.rebuilds = u64::MAX;
        }
        self.inserted = saved.inserted;
        self.time = saved.time;
        self.steps = saved.steps;
        self.dropped = saved.dropped;
        self.peak = None;
        self.escaped = None;
        Ok(())
    }
}
