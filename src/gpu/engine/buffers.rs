//! The run's device buffers (the state set, the new lists, the step's others) and how large the lists and their windows are.

use super::*;
use crate::gpu::records::ROWS_REGION_COUNT;

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
    /// and `motion`, each one buffer or pages of whole windows where that would exceed
    /// the largest (`gpu::pages`; both cut alike, `state_pages`).
    pub(super) state: Vec<wgpu::Buffer>,
    pub(super) motion: Vec<wgpu::Buffer>,
    pub(super) state_pages: Pages,
    pub(super) layout: StateLayout,
    /// The lists' entries (partner or wall, `lower`, partner id, history, pair force and
    /// torque, the contact's prior, a force jump's impulse) and their layout: one buffer,
    /// or pages of whole windows where that would exceed the largest (`gpu::pages`).
    pub(super) entries: Vec<wgpu::Buffer>,
    pub(super) pages: Pages,
    pub(super) entry_layout: RecordLayout,
}

impl StateSet {
    pub(super) fn new(
        alloc: &mut Allocator,
        (n, entries, windows, [pages, state_pages]): (u64, u64, Windows, [Pages; 2]),
        kind: &Composition,
        keeps: Keeps,
    ) -> Self {
        let layout = StateLayout::windowed(n, kind.state_extras(keeps), windows);
        let [entry_layout, _] = kind.records(keeps);
        let blocks = Self::blocks_of(&layout, (&entry_layout, entries));
        let mut b = |b: Buffer| {
            let name = b.name();
            let block = blocks.iter().find(|(n, _)| *n == name).map_or(0, |b| b.1);
            if !state_pages.paged() {
                let bytes = layout.bytes(b);
                return vec![blocked_buffer(
                    alloc,
                    &windows,
                    (&format!("A.{name}"), bytes),
                    block,
                )];
            }
            (0..state_pages.count)
                .map(|p| {
                    let (_, len) = state_pages.range(p, windows.count);
                    alloc.buffer(&format!("A.{name}[{p}]"), len * block)
                })
                .collect()
        };
        let state = b(Buffer::State);
        let motion = b(Buffer::Motion);
        let entries = entry_buffers(alloc, (&windows, &pages), &entry_layout, entries);
        Self {
            state,
            motion,
            state_pages,
            entries,
            pages,
            layout,
            entry_layout,
        }
    }

    /// The pages of the particle state for `windows` (one where both buffers fit
    /// `largest` bytes), or an error when a page of at most a binding (`limit`) and
    /// `largest` holds fewer than [`MIN_PAGE_WINDOWS`] windows.
    pub(super) fn pages_of(
        layout: &StateLayout,
        windows: &Windows,
        (limit, largest): (u64, u64),
    ) -> Result<Pages, PowderError> {
        let block = Buffer::ALL
            .iter()
            .map(|&b| layout.count(b) * windows.len * crate::gpu::state::FIELD_BYTES)
            .max()
            .unwrap_or(0);
        let page = largest.min(limit);
        Pages::of(windows, block, (largest, page)).ok_or_else(|| {
            PowderError::Run(format!(
                "the particle state needs {} bytes a buffer, over the largest buffer of {largest} bytes, and a page of at most {page} bytes holds fewer than {MIN_PAGE_WINDOWS} windows' blocks of {block} bytes; smaller windows hold fewer (`--window-particles N`)",
                windows.count * block
            ))
        })
    }

    /// Whether the step's variant reads through pages (`_paged`): the entries' or the
    /// state's.
    pub(super) fn far(&self) -> bool {
        self.pages.paged() || self.state_pages.paged()
    }

    /// Buffer `b`'s pages read back one after the other: the bytes of one buffer.
    pub(super) fn sources(&self, b: Buffer) -> Vec<(&wgpu::Buffer, u64)> {
        self.buffer(b).iter().map(|p| (p, p.size())).collect()
    }

    /// The buffers bound page by page (`WindowBindings::groups`).
    pub(super) fn paged(&self) -> [Paged<'_>; 3] {
        [
            Paged {
                name: "entries",
                pages: &self.entries,
                layout: self.pages,
                other: Some("entries_x"),
            },
            Paged {
                name: "state",
                pages: &self.state,
                layout: self.state_pages,
                other: Some("state_x"),
            },
            Paged {
                name: "motion",
                pages: &self.motion,
                layout: self.state_pages,
                other: None,
            },
        ]
    }

    /// The entries' buffers read back one after the other: the bytes of one buffer.
    pub(super) fn entry_sources(&self) -> Vec<(&wgpu::Buffer, u64)> {
        self.entries.iter().map(|b| (b, b.size())).collect()
    }

    /// The entries' buffer holding byte `at` of the one they stand for, and where, for
    /// `entries` entries a window.
    pub(super) fn entry_at(&self, at: u64, entries: u64) -> (&wgpu::Buffer, u64) {
        let (page, at) = self
            .pages
            .locate(at, self.entry_layout.block_bytes(entries));
        (&self.entries[page as usize], at)
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
        v.push(("rows", 4 * ROWS_REGION_COUNT as u64 * self.layout.stride()));
        v
    }

    /// The buffers under the names the kernels bind them by (the entries' first page:
    /// [`WindowBindings::groups`] binds each window's).
    pub(super) fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        vec![
            ("state".to_string(), &self.state[0]),
            ("motion".to_string(), &self.motion[0]),
            ("entries".to_string(), &self.entries[0]),
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

    /// The buffers (pages) holding state buffer `b`.
    pub(super) fn buffer(&self, b: Buffer) -> &[wgpu::Buffer] {
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
                let field = Field::regions(
                    &group.join("+"),
                    &self.buffer(b)[0],
                    4,
                    (first * stride, stride, group.len() as u32),
                )
                .windowed(block);
                f.push(match self.state_pages.paged() {
                    true => field.in_pages(self.buffer(b)),
                    false => field,
                });
            }
        }
        f
    }
}

/// Writes `bytes` into `pages` one after the other (the bytes of the one buffer they
/// stand for).
pub(super) fn write_pages(queue: &wgpu::Queue, pages: &[wgpu::Buffer], bytes: &[u8]) {
    let mut at = 0;
    for page in pages {
        let end = (at + page.size() as usize).min(bytes.len());
        queue.write_buffer(page, 0, &bytes[at..end]);
        at = end;
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

/// The buffers of `entries` list entries a window of `layout`: one blocked by window, or
/// one a page (bound whole).
pub(super) fn entry_buffers(
    alloc: &mut Allocator,
    (windows, pages): (&Windows, &Pages),
    layout: &RecordLayout,
    entries: u64,
) -> Vec<wgpu::Buffer> {
    let block = layout.block_bytes(entries);
    if !pages.paged() {
        let bytes = layout.windowed_bytes(entries, windows);
        return vec![blocked_buffer(alloc, windows, ("A.entries", bytes), block)];
    }
    (0..pages.count)
        .map(|p| {
            let (_, len) = pages.range(p, windows.count);
            alloc.buffer(&format!("A.entries[{p}]"), len * block)
        })
        .collect()
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
    /// None where the entries are in pages (a window and its neighbours may span two).
    pub(super) fn lent<'a>(a: &'a StateSet, entries: u64) -> Option<permute::Lent<'a>> {
        let (base, words) = a.entry_layout.per_step();
        (!a.pages.paged()).then(|| permute::Lent {
            buffer: &a.entries[0],
            block: a.entry_layout.block_bytes(entries),
            base: 4 * base * entries,
            bytes: 4 * words * entries,
        })
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
    /// `shaders/step/shared.wgsl`): [0] some particle moved more than skin/2 since the last
    /// rebuild, [1] rebuild flag, [2] rebuilds so far.
    pub(super) control: wgpu::Buffer,
    /// The indirect dispatch arguments: a rebuild's (written by `decide` each step), then
    /// every step's (written by the host at each batch's start; zeroed by a halt).
    pub(super) args: wgpu::Buffer,
    pub(super) full_args: wgpu::Buffer,
    /// The new lists' and the `lower` lists' lengths and first entries (`rows` in
    /// `shaders/step/shared.wgsl`: four regions a window, blocked like the state).
    pub(super) rows: wgpu::Buffer,
    /// Each servo wall's pushes this step, summed per lane of a workgroup.
    pub(super) servo_lanes: wgpu::Buffer,
}

impl StepBuffers {
    /// Every buffer under the name the kernels bind it by.
    pub(super) fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        [
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
        ]
        .into_iter()
        .map(|(n, b)| (n.to_string(), b))
        .collect()
    }
}

/// How the lists' entries and the state are stored: entries a window and their pages, the
/// state's pages, and the largest buffer the entries' pages may take (bytes).
pub(super) struct Storage {
    pub(super) entries: u64,
    pub(super) pages: Pages,
    pub(super) state_pages: Pages,
    pub(super) largest: u64,
}

impl Storage {
    /// The storage of `n` particles in `windows` for the composition `kind` keeping `keeps`:
    /// the list entries a window a first guess (`options.list_entries`, or
    /// `INITIAL_ENTRIES_PER_PARTICLE` a particle; the first rebuild grows them to what it
    /// needs), the pages within the adapter's limits and the page sizes `options` asks for.
    pub(super) fn plan(
        ctx: &GpuContext,
        options: &GpuOptions,
        (kind, keeps): (&Composition, Keeps),
        (n, windows): (u64, &Windows),
    ) -> Result<Self, PowderError> {
        let per_window = if windows.count == 1 { n } else { windows.len };
        let entries = options
            .list_entries
            .unwrap_or(INITIAL_ENTRIES_PER_PARTICLE * per_window + 256)
            .max(1);
        let entries = window_entries(windows, entries);
        let [entry_layout, ..] = kind.records(keeps);
        let largest = entry_buffer_limit(ctx, options.entry_page_bytes);
        let pages = check_entries(
            (entries, windows),
            entry_layout.words(),
            n,
            (ctx.max_storage_binding(), largest),
        )?;
        let state_pages = StateSet::pages_of(
            &StateLayout::windowed(n, kind.state_extras(keeps), *windows),
            windows,
            (
                ctx.max_storage_binding(),
                entry_buffer_limit(ctx, options.state_page_bytes),
            ),
        )?;
        Ok(Self {
            entries,
            pages,
            state_pages,
            largest,
        })
    }
}

/// The pages of `entries` list entries a window of `words` words each (the entries'
/// records), or an error when they do not fit: a window's numbering, the adapter's storage
/// binding limit (the whole buffer with one window, a window and its neighbours with
/// several), or a page of `largest` bytes (the largest buffer, [`entry_buffer_limit`])
/// holding fewer than three windows.
pub(super) fn check_entries(
    (entries, windows): (u64, &Windows),
    words: u64,
    particles: u64,
    (limit, largest): (u64, u64),
) -> Result<Pages, PowderError> {
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
    let block = entries * bytes;
    let page = largest.min(limit);
    Pages::of(windows, block, (largest, page)).ok_or_else(|| {
        PowderError::Run(format!(
            "the neighbour lists need {what}, over the largest buffer of {largest} bytes, and a page of at most {page} bytes holds fewer than {MIN_PAGE_WINDOWS} windows' blocks of {block} bytes; smaller windows hold fewer (`--window-particles N`)"
        ))
    })
}

/// The largest buffer the lists' entries take before they are cut into pages: the
/// adapter's largest buffer, at most 2^32 words (the kernels' u32 indices), or less where
/// [`GpuOptions::entry_page_bytes`] asks.
pub(super) fn entry_buffer_limit(ctx: &GpuContext, asked: Option<u64>) -> u64 {
    let largest = ctx.limits().max_buffer_size.min(4 * u32::MAX as u64);
    asked.map_or(largest, |a| a.min(largest))
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
        // (a window and its neighbours within a binding; where the entries outgrow the
        // largest buffer, pages of at least MIN_PAGE_WINDOWS windows)
        let binding = self.ctx.max_storage_binding();
        let page = binding.min(self.largest_entries);
        let mut most = (binding / (bytes * windows.covered()))
            .min(page / (bytes * MIN_PAGE_WINDOWS.min(windows.count)))
            .min(windows.max_records());
        // and no headroom into pages where what is needed fits one buffer
        let one_buffer = self.largest_entries / (bytes * windows.count);
        if window_entries(&windows, need) <= one_buffer {
            most = most.min(one_buffer);
        }
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
        let pages = check_entries(
            (entries, &windows),
            layout.words(),
            self.n as u64,
            (self.ctx.max_storage_binding(), self.largest_entries),
        )?;
        // (the paged variant's far reads: compiled before anything changes)
        let far = pages.paged() || self.state.state_pages.paged();
        let program = match far != self.state.far() {
            true => Some(
                self.spec
                    .compile(&self.ctx, (&self.kind, self.keeps), far)?,
            ),
            false => None,
        };
        let device = &self.ctx.device;
        let mut alloc = Allocator::new(device, self.ctx.max_storage_binding());
        let mut encoder = device.create_command_encoder(&Default::default());
        let new = entry_buffers(&mut alloc, (&windows, &pages), &layout, entries);
        alloc.check(self.n as usize)?;
        if keep {
            // window by window, region by region: each region's start moves with the
            // capacity (a window's region lies in one page)
            let new_block = layout.block_bytes(entries);
            for w in 0..windows.count {
                for name in ["hist_pid", "hist", "prior"] {
                    if let Some((_, words)) = layout.place(name) {
                        let first = windows.record(w, 0);
                        let from = layout.byte_of(name, self.entries, &windows, first);
                        let to = layout.byte_of(name, entries, &windows, first);
                        let (from, at) = self.state.entry_at(from.unwrap_or(0), self.entries);
                        let (page, to) = pages.locate(to.unwrap_or(0), new_block);
                        let bytes = 4 * words * self.entries.min(entries);
                        encoder.copy_buffer_to_buffer(from, at, &new[page as usize], to, bytes);
                    }
                }
            }
        }
        self.state.entries = new;
        if let Some(program) = program {
            self.program = program;
        }
        if pages != self.state.pages {
            self.state.pages = pages;
            self.windowing.set_pages(&self.ctx.queue, pages);
        }
        if pages.paged() && self.quiet.is_some() {
            // quiet batches stop (bitwise the same run): their copy of the lists would be
            // one buffer beyond the largest
            self.quiet = None;
            self.buffers.retain(|(n, _)| !n.starts_with("quiet."));
        }
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
            (&self.windowing, NewLists::lent(&self.state, entries)),
        )?;
        alloc
            .list
            .push(("permute.scratch".into(), self.permutation.scratch_bytes()));
        // (the entries' pages may be more or fewer now)
        self.buffers.retain(|(n, _)| !n.starts_with("A.entries"));
        for (name, bytes) in alloc.list {
            match self.buffers.iter_mut().find(|(n, _)| *n == name) {
                Some(entry) => entry.1 = bytes,
                None => self.buffers.push((name, bytes)),
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
            ([self.state.named(), self.b.named()], &self.state.paged()),
        )?;
        Ok(())
    }

    /// Whether `need` list entries overflow the one window's binding (what windows fix;
    /// pages then hold what outgrows the largest buffer).
    pub(super) fn outgrows_one_window(&self, need: u64) -> bool {
        let windows = *self.state.layout.windows();
        let words = self.state.entry_layout.words();
        windows.count == 1 && 4 * words * need > self.ctx.max_storage_binding()
    }
}
