//! The particle state's buffers (A): the per-particle fields and the lists' entries, whole
//! or in pages, and the views the passes bind of them.

use super::*;
use crate::gpu::records::ROWS_REGION_COUNT;

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
