//! The step's buffers besides the particle state: the new lists a rebuild builds and the
//! step's parameters, tables, control words and rows.

use super::*;

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
