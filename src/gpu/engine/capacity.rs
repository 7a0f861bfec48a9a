//! How large the neighbour lists and their windows are: the first plan, the checks against
//! the adapter's limits, the automatic windows, and growing the lists when a rebuild needs more.

use super::*;

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
