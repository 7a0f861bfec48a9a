//! The run's device buffers (the state set, the new lists, the step's others) and how large the lists and their windows are.

use super::*;

/// Creates storage buffers and records their names and sizes (for [`GpuEngine::buffers`]).
/// A buffer that does not fit (bound whole: over the storage binding limit; bound a
/// window's part at a time: a part over it, or the buffer over the largest buffer) is not
/// created: a 4-byte stand-in takes its place and [`Allocator::check`] refuses.
pub(super) struct Allocator<'a> {
    pub(super) device: &'a wgpu::Device,
    pub(super) list: Vec<(String, u64)>,
    /// The largest binding a buffer may be, bytes.
    pub(super) limit: u64,
    /// The largest buffer, bytes.
    pub(super) max_buffer: u64,
    /// What does not fit, said for the user.
    pub(super) refused: Vec<String>,
}

impl<'a> Allocator<'a> {
    pub(super) fn new(device: &'a wgpu::Device, limit: u64) -> Self {
        Self {
            device,
            list: Vec::new(),
            limit: limit.min(4 * u32::MAX as u64),
            max_buffer: device.limits().max_buffer_size,
            refused: Vec::new(),
        }
    }

    /// A buffer bound whole.
    pub(super) fn buffer(&mut self, name: &str, bytes: u64) -> wgpu::Buffer {
        let fits = bytes <= self.limit;
        if !fits {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        }
        self.create(name, bytes, fits)
    }

    /// A buffer blocked by window, `part` bytes of it bound at a time (`gpu::window`).
    pub(super) fn blocked(&mut self, name: &str, bytes: u64, part: u64) -> wgpu::Buffer {
        if part > self.limit {
            self.refused.push(format!(
                "{part} bytes of `{name}` bound at a time (a window and its neighbours), over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        } else if bytes > self.max_buffer {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's largest buffer of {} bytes",
                self.max_buffer
            ));
        }
        let fits = part <= self.limit && bytes <= self.max_buffer;
        self.create(name, bytes, fits)
    }

    pub(super) fn create(&mut self, name: &str, bytes: u64, fits: bool) -> wgpu::Buffer {
        let b = storage_buffer(self.device, name, if fits { bytes } else { 4 });
        self.list
            .push((name.to_string(), if fits { b.size() } else { bytes }));
        b
    }

    /// An error naming the first buffer that does not fit, for `particles` particles.
    /// Call it before anything writes or binds the buffers.
    pub(super) fn check(&self, particles: usize) -> Result<(), PowderError> {
        match self.refused.first() {
            Some(what) => Err(PowderError::Run(format!(
                "{particles} particles need {what}"
            ))),
            None => Ok(()),
        }
    }
}

/// The particle state (A): per particle, in the order of the last rebuild (`gpu::state`),
/// with the neighbour lists' entries, its pairs' and its wall contacts (`gpu::records`).
pub(super) struct StateSet {
    /// Every per-particle field ([`StateLayout`]): `state` (what pairs read of a partner)
    /// and `motion`.
    pub(super) state: wgpu::Buffer,
    pub(super) motion: wgpu::Buffer,
    pub(super) layout: StateLayout,
    /// The lists' entries (partner or wall, `lower`, partner id, history, pair force and
    /// torque, the contact's prior, a force jump's impulse) and their layout.
    pub(super) entries: wgpu::Buffer,
    pub(super) entry_layout: RecordLayout,
}

impl StateSet {
    pub(super) fn new(
        alloc: &mut Allocator,
        (n, entries, windows): (u64, u64, Windows),
        kind: &Composition,
        keeps: Keeps,
    ) -> Self {
        let layout = StateLayout::windowed(n, kind.rotation(), windows);
        let [entry_layout, _] = kind.records(keeps);
        let blocks = Self::blocks_of(&layout, (&entry_layout, entries));
        let mut b = |name: &'static str, bytes: u64| {
            let block = blocks.iter().find(|(n, _)| *n == name).map_or(0, |b| b.1);
            blocked_buffer(alloc, &windows, (&format!("A.{name}"), bytes), block)
        };
        Self {
            state: b("state", layout.bytes(Buffer::State)),
            motion: b("motion", layout.bytes(Buffer::Motion)),
            entries: b("entries", entry_layout.windowed_bytes(entries, &windows)),
            layout,
            entry_layout,
        }
    }

    /// Bytes of a window's block of each blocked buffer of the set (`gpu::window`), by
    /// the name the kernels bind it by, for `entries` list entries a window.
    pub(super) fn blocks_of(
        layout: &StateLayout,
        (entry_layout, entries): (&RecordLayout, u64),
    ) -> Vec<(&'static str, u64)> {
        let len = layout.stride();
        let field = crate::gpu::state::FIELD_BYTES;
        vec![
            ("state", layout.count(Buffer::State) * len * field),
            ("motion", layout.count(Buffer::Motion) * len * field),
            ("entries", entry_layout.block_bytes(entries)),
        ]
    }

    /// [`Self::blocks_of`] this set, with `rows`.
    pub(super) fn blocks(&self, entries: u64) -> Vec<(&'static str, u64)> {
        let mut v = Self::blocks_of(&self.layout, (&self.entry_layout, entries));
        v.push(("rows", 4 * 4 * self.layout.stride()));
        v
    }

    /// The buffers under the names the kernels bind them by.
    pub(super) fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        vec![
            ("state".to_string(), &self.state),
            ("motion".to_string(), &self.motion),
            ("entries".to_string(), &self.entries),
        ]
    }

    /// The record layouts with their records (all windows'): the entries', the new
    /// lists'.
    pub(super) fn records<'a>(
        &'a self,
        new: &'a NewLists,
        entries: u64,
    ) -> [(&'a RecordLayout, u64); 2] {
        let w = self.layout.windows();
        [
            (&self.entry_layout, entries * w.count),
            (&new.layout, entries * w.count),
        ]
    }

    /// The buffer holding state buffer `b`.
    pub(super) fn buffer(&self, b: Buffer) -> &wgpu::Buffer {
        match b {
            Buffer::State => &self.state,
            Buffer::Motion => &self.motion,
        }
    }

    /// The fields a rebuild re-sorts (`gpu::permute`): every per-particle field (two
    /// state fields a dispatch) but the lists (rebuilt).
    pub(super) fn permuted(&self) -> Vec<Field> {
        let stride = 4 * self.layout.stride() as u32;
        let per_move = (ROW_WORDS / 4).max(1) as usize;
        let mut f = Vec::new();
        for b in Buffer::ALL {
            let names: Vec<&str> = self.layout.in_buffer(b).map(|f| f.name).collect();
            let block = stride * names.len() as u32;
            for (c, group) in names.chunks(per_move).enumerate() {
                let first = (c * per_move) as u32;
                f.push(
                    Field::regions(
                        &group.join("+"),
                        self.buffer(b),
                        4,
                        (first * stride, stride, group.len() as u32),
                    )
                    .windowed(block),
                );
            }
        }
        f
    }
}

/// A storage buffer of `bytes` blocked by window, `block` bytes a window: bound whole with
/// one window, else a window and its neighbours at a time.
pub(super) fn blocked_buffer(
    alloc: &mut Allocator,
    windows: &Windows,
    (name, bytes): (&str, u64),
    block: u64,
) -> wgpu::Buffer {
    if windows.count == 1 {
        alloc.buffer(name, bytes)
    } else {
        alloc.blocked(name, bytes, windows.covered() * block)
    }
}

/// The neighbour lists a rebuild builds (B: partner ids, history, priors), copied back
/// into A's at its end: in the entries' per-step fields (`RecordLayout::new_entries`).
pub(super) struct NewLists {
    pub(super) layout: RecordLayout,
}

impl NewLists {
    pub(super) fn new(kind: &Composition, keeps: Keeps) -> Self {
        let [_, layout] = kind.records(keeps);
        Self { layout }
    }

    /// The layout of a copy of their fields in a buffer of its own.
    pub(super) fn standalone(&self) -> RecordLayout {
        RecordLayout {
            host: None,
            ..self.layout.clone()
        }
    }

    /// A buffer for quiet batches' copy of the lists' history (`Quiet::lists`; the
    /// batch writes the per-step fields the new lists live in), for `entries` list
    /// entries a window.
    pub(super) fn quiet_lists(
        &self,
        alloc: &mut Allocator,
        (entries, windows): (u64, &Windows),
    ) -> wgpu::Buffer {
        let bytes = self.standalone().windowed_bytes(entries, windows);
        alloc.buffer("quiet.lists", bytes)
    }

    /// Where they lie, lent to the re-sort as its scratch (nothing reads the new lists
    /// from one rebuild's `copy_back_history` to the next's `remap`, which runs after the
    /// re-sort), for `entries` list entries a window: the entries' per-step fields.
    pub(super) fn lent<'a>(a: &'a StateSet, entries: u64) -> permute::Lent<'a> {
        let (base, words) = a.entry_layout.per_step();
        permute::Lent {
            buffer: &a.entries,
            block: a.entry_layout.block_bytes(entries),
            base: 4 * base * entries,
            bytes: 4 * words * entries,
        }
    }
}

/// The step's buffers besides the particle state and the new lists, and the per-entry
/// arrays the lists' capacity sizes (`nbr`, `lower`, the pair forces and torques).
pub(super) struct StepBuffers {
    pub(super) step: wgpu::Buffer,
    pub(super) pairs: wgpu::Buffer,
    pub(super) walls: wgpu::Buffer,
    /// Each wall's point at the last rebuild (the trigger for moving walls: state).
    pub(super) wall_ref: wgpu::Buffer,
    /// Which particles have appeared (pouring), by persistent id.
    pub(super) appeared: wgpu::Buffer,
    /// The monitor (zeroed per batch) and the Verlet skin state (`control` in
    /// `shaders/step.wgsl`): [0] some particle moved more than skin/2 since the last
    /// rebuild, [1] rebuild flag, [2] rebuilds so far.
    pub(super) control: wgpu::Buffer,
    /// The indirect dispatch arguments: a rebuild's (written by `decide` each step), then
    /// every step's (written by the host at each batch's start; zeroed by a halt).
    pub(super) args: wgpu::Buffer,
    pub(super) full_args: wgpu::Buffer,
    /// Per particle (by persistent id): contact counts, overlaps, dissipated and stored
    /// energy (`particle_ledger` in `shaders/ledger.wgsl`); only with the ledger.
    pub(super) particle_ledger: Option<wgpu::Buffer>,
    /// The new lists' and the `lower` lists' lengths and first entries (`rows` in
    /// `shaders/step.wgsl`: four regions a window, blocked like the state).
    pub(super) rows: wgpu::Buffer,
    /// Each servo wall's pushes this step, summed per lane of a workgroup.
    pub(super) servo_lanes: wgpu::Buffer,
}

impl StepBuffers {
    /// Every buffer under the name the kernels bind it by.
    pub(super) fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        let mut list: Vec<(&str, &wgpu::Buffer)> = vec![
            ("step", &self.step),
            ("pairs", &self.pairs),
            ("walls", &self.walls),
            ("wall_ref", &self.wall_ref),
            ("appeared", &self.appeared),
            ("control", &self.control),
            ("args", &self.args),
            ("full_args", &self.full_args),
            ("rows", &self.rows),
            ("servo_lanes", &self.servo_lanes),
        ];
        list.extend(
            self.particle_ledger
                .as_ref()
                .map(|l| ("particle_ledger", l)),
        );
        list.into_iter().map(|(n, b)| (n.to_string(), b)).collect()
    }
}

/// An error when `entries` list entries a window of `words` words each (the entries'
/// records) do not fit: a window's numbering, the adapter's storage binding limit (the
/// whole buffer with one window, a window and its neighbours with several), its largest
/// buffer, or u32 word indices.
pub(super) fn check_entries(
    (entries, windows): (u64, &Windows),
    words: u64,
    particles: u64,
    (limit, max_buffer): (u64, u64),
) -> Result<(), PowderError> {
    if entries > windows.max_records() {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {entries} entries in a window of {} particles, more than the {} a window's entries are numbered with (about 2^32 entries in all)",
            windows.len,
            windows.max_records()
        )));
    }
    let bytes = 4 * words;
    let total = entries * windows.count;
    let bound = entries * windows.covered();
    let per_particle = total as f64 / particles.max(1) as f64;
    let what = format!("{total} entries ({per_particle:.1} a particle) of {bytes} bytes each (partner, history, pair force, ...)");
    if total * words > u32::MAX as u64 {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}: more than 2^32 words, which the kernels' u32 indices cannot reach"
        )));
    }
    if bound * bytes > limit {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}, {} bytes bound at a time, over the adapter's storage binding limit of {limit} bytes{}",
            bound * bytes,
            if windows.count == 1 {
                "; windows hold them (`--window-particles N`, a power of two, GpuOptions::window_particles)"
            } else {
                "; smaller windows hold fewer (`--window-particles N`)"
            }
        )));
    }
    if total * bytes > max_buffer {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}, over the adapter's largest buffer of {max_buffer} bytes"
        )));
    }
    Ok(())
}

/// List entries a window rounded up so a window's block of entries is a whole number of
/// 256 bytes where there are several (binding offsets).
pub(super) fn window_entries(windows: &Windows, entries: u64) -> u64 {
    match windows.count {
        1 => entries,
        _ => entries.div_ceil(MIN_WINDOW) * MIN_WINDOW,
    }
}

/// The windows chosen where none are asked for: one where the per-particle arrays and the
/// lists fit a binding each — the lists' first guess (INITIAL_ENTRIES_PER_PARTICLE a
/// particle), or the `measured` entries of a first build that outgrew it — else windows
/// with room for WINDOW_ENTRIES_PER_PARTICLE entries a particle (or the measured ones and
/// their headroom, where more).
pub(super) fn automatic_windows(
    layout: &StateLayout,
    [entry, new]: [RecordLayout; 2],
    n: u64,
    limit: u64,
    measured: Option<u64>,
) -> Windows {
    let per_particle = [
        layout.count(Buffer::State) * crate::gpu::state::FIELD_BYTES,
        layout.count(Buffer::Motion) * crate::gpu::state::FIELD_BYTES,
        4 * ROW_WORDS as u64,
    ]
    .into_iter()
    .max()
    .unwrap_or(1);
    let words = entry.words().max(new.words());
    let first = match measured {
        Some(m) => (m as f64 * LIST_HEADROOM).ceil() as u64,
        None => INITIAL_ENTRIES_PER_PARTICLE * n + 256,
    };
    if n * per_particle <= limit && 4 * words * first <= limit {
        return Windows::one(n);
    }
    let a_particle = match measured {
        Some(m) => ((m as f64 * LIST_HEADROOM) / n.max(1) as f64).ceil() as u64,
        None => 0,
    };
    let lists = 4 * WINDOW_ENTRIES_PER_PARTICLE.max(a_particle) * words;
    Windows::choose(n, per_particle.max(lists), limit)
}

impl GpuEngine {
    /// Grows the neighbour lists to `need` entries and headroom (`commit` halted a batch
    /// for them), keeping the current lists' history: the rebuild that needed the room
    /// runs again and remaps it.
    pub(super) fn grow_lists(&mut self, need: u64) -> Result<(), PowderError> {
        // the headroom only as far as the bindings and the largest buffer hold (`need`
        // itself is checked)
        let windows = *self.state.layout.windows();
        let bytes = 4 * self.state.entry_layout.words();
        let max_buffer = self.ctx.limits().max_buffer_size;
        let most = (self.ctx.max_storage_binding() / (bytes * windows.covered()))
            .min(max_buffer / (bytes * windows.count))
            .min(windows.max_records());
        // (a window's block a whole number of 256 bytes where there are several)
        let most = match windows.count {
            1 => most,
            _ => most / MIN_WINDOW * MIN_WINDOW,
        };
        let entries = window_entries(
            &windows,
            ((need as f64 * LIST_HEADROOM).ceil() as u64).max(need + 64),
        )
        .min(most)
        .max(window_entries(&windows, need));
        self.growths += 1;
        self.resize_lists(entries, true)
    }

    /// Reallocates the lists' entries for `entries` entries (copying A's partner ids,
    /// history and ledger values when `keep`), tells the kernels, and binds them again.
    pub(super) fn resize_lists(&mut self, entries: u64, keep: bool) -> Result<(), PowderError> {
        let layout = self.state.entry_layout.clone();
        let windows = *self.state.layout.windows();
        check_entries(
            (entries, &windows),
            layout.words(),
            self.n as u64,
            (
                self.ctx.max_storage_binding(),
                self.ctx.limits().max_buffer_size,
            ),
        )?;
        let device = &self.ctx.device;
        let mut alloc = Allocator::new(device, self.ctx.max_storage_binding());
        let mut encoder = device.create_command_encoder(&Default::default());
        let old = (self.state.entries.clone(), self.entries);
        let bytes = layout.windowed_bytes(entries, &windows);
        let block = layout.block_bytes(entries);
        let new = blocked_buffer(&mut alloc, &windows, ("A.entries", bytes), block);
        alloc.check(self.n as usize)?;
        if keep {
            // window by window, region by region: each region's start moves with the
            // capacity
            for w in 0..windows.count {
                for name in ["hist_pid", "hist", "prior"] {
                    if let Some((_, words)) = layout.place(name) {
                        let first = windows.record(w, 0);
                        let from = layout.byte_of(name, old.1, &windows, first).unwrap_or(0);
                        let to = layout.byte_of(name, entries, &windows, first).unwrap_or(0);
                        let bytes = 4 * words * old.1.min(entries);
                        encoder.copy_buffer_to_buffer(&old.0, from, &new, to, bytes);
                    }
                }
            }
        }
        self.state.entries = new;
        if let Some(q) = &mut self.quiet {
            // (a copy, never bound: no binding limit, as at the start)
            let mut copies = Allocator::new(device, u64::MAX);
            q.lists = self
                ._new_lists
                .quiet_lists(&mut copies, (entries, &windows));
            alloc.list.extend(copies.list);
        }
        self.ctx.queue.submit([encoder.finish()]);
        // the re-sort's scratch: the new lists' room again, or its own where a window's
        // block of it no longer holds it
        self.permutation.bind(
            &self.ctx,
            (self.grid.params(), self.grid.sorted_index()),
            self.n,
            &self.state.permuted(),
            (&self.windowing, Some(NewLists::lent(&self.state, entries))),
        )?;
        alloc
            .list
            .push(("permute.scratch".into(), self.permutation.scratch_bytes()));
        for (name, bytes) in alloc.list {
            if let Some(entry) = self.buffers.iter_mut().find(|(n, _)| *n == name) {
                entry.1 = bytes;
            }
        }
        self.entries = entries;
        self.ctx.queue.write_buffer(
            &self.b.step,
            std::mem::offset_of!(StepParams, list_capacity) as u64,
            bytemuck::bytes_of(&(entries as u32)),
        );
        self.bound = bind_all(
            &self.ctx.device,
            &self.program,
            (
                &self.state.layout,
                &self.state.records(&self._new_lists, entries),
                &self.state.blocks(entries),
            ),
            (&self.mirrors, &self.windowing),
            &self.grid,
            [self.state.named(), self.b.named()],
        )?;
        Ok(())
    }

    /// Whether `need` list entries overflow the one window's binding while their buffer
    /// would still fit the largest (what windows fix).
    pub(super) fn outgrows_one_window(&self, need: u64) -> bool {
        let windows = *self.state.layout.windows();
        let words = self.state.entry_layout.words();
        let max_buffer = self.ctx.limits().max_buffer_size;
        windows.count == 1
            && 4 * words * need > self.ctx.max_storage_binding()
            && 4 * words * need <= max_buffer
            && need * words <= u32::MAX as u64
    }
}
