//! Arrays of records packed into one `array<u32>` buffer each, declared once here: the
//! neighbour lists' entries (`entries`: pairs and, after each particle's pairs, its
//! contacts with the walls near it) and a rebuild's new lists (`new_entries`). Each window (`gpu::window`) has a block of
//! `capacity` records; in it a record's fields lie in regions, one after the other, each
//! `capacity × width` words, a record's words consecutive within its region (local record
//! i's field at `before · capacity + i · width` of its window's block). So a kernel binds one
//! buffer for all of a record's fields; the WGSL accessors (`load_<field>`,
//! `store_<field>`), the host's offsets and the traffic estimate follow from the layout.

use std::collections::BTreeSet;
use std::fmt::Write;

use crate::gpu::composition::Keeps;
use crate::gpu::window::Windows;

crate::gpu::layout::wgsl_consts! {
    /// The marks of a list entry's partner.
    pub ENTRY_MARKS: u32 = {
        /// A list entry whose `nbr` (and partner id) is `WALL_ENTRY | w` is its particle's
        /// contact with wall w (particle indices and ids stay below 2^31).
        WALL_ENTRY = 0x8000_0000,
    }
}

crate::gpu::layout::wgsl_consts! {
    /// The regions of `rows`, one u32 a particle each (blocked by window like the state).
    pub ROWS_REGIONS: u32 = {
        /// The lengths of the lists a rebuild builds (B).
        ROWS_B_COUNT = 0,
        /// Their first entries (the scan of [`ROWS_B_COUNT`]).
        ROWS_B_ROW = 1,
        /// The lengths of the `lower` lists.
        ROWS_LOWER_COUNT = 2,
        /// Their first entries (the scan of [`ROWS_LOWER_COUNT`]).
        ROWS_LOWER_ROW = 3,
        /// How many regions `rows` holds.
        ROWS_REGION_COUNT = 4,
    }
}

/// What one field of a record holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// One `u32`.
    U32,
    /// One `f32`.
    F32,
    /// A `vec3<f32>` (three words).
    Vec3,
    /// A `vec4<f32>` (four words).
    Vec4,
    /// A `vec4<f32>` whose z is not kept (three words: x, y, w; z loads as 0).
    Vec4Xyw,
    /// A contact's stored history, `struct Hist` of the composition: its f32 members, in
    /// order.
    Hist(Vec<String>),
    /// Words kept free for another layout living in the buffer (no accessors).
    Spare(u64),
}

impl Kind {
    /// Words a record takes in the field's region.
    pub fn words(&self) -> u64 {
        match self {
            Kind::U32 | Kind::F32 => 1,
            Kind::Vec3 | Kind::Vec4Xyw => 3,
            Kind::Vec4 => 4,
            Kind::Hist(members) => members.len().max(1) as u64,
            Kind::Spare(words) => *words,
        }
    }

    fn wgsl_type(&self) -> &'static str {
        match self {
            Kind::U32 => "u32",
            Kind::F32 => "f32",
            Kind::Vec3 => "vec3<f32>",
            Kind::Vec4 | Kind::Vec4Xyw => "vec4<f32>",
            Kind::Hist(_) => "Hist",
            Kind::Spare(_) => "u32",
        }
    }
}

/// One field of a record.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Name: the accessors are `load_<name>` and `store_<name>`.
    pub name: &'static str,
    /// What it holds.
    pub kind: Kind,
}

/// The records of one buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordLayout {
    /// The WGSL global (and host buffer) name; the accessors' prefix.
    pub global: &'static str,
    /// Where the records share another layout's buffer instead (`new_entries` in the
    /// entries' per-step fields).
    pub host: Option<Host>,
    /// Its binding.
    pub binding: u32,
    /// The WGSL expression for the records a window's block holds (the regions'
    /// capacity).
    pub capacity_wgsl: &'static str,
    /// The fields, in region order.
    pub fields: Vec<Field>,
    /// Optional fields this composition leaves out: their accessors are no-ops (a load
    /// returns zeros), so the kernels call them unconditionally and the compiler drops them.
    pub absent: Vec<Field>,
}

/// A region of another layout's records a layout lives in.
#[derive(Clone, Debug, PartialEq)]
pub struct Host {
    /// The host's WGSL global (and buffer).
    pub global: &'static str,
    /// Words of one host record (the stride of a window's block: capacity × this).
    pub words: u64,
    /// The host's words a record before the region (its first field's offset: capacity ×
    /// this).
    pub base: u64,
}

impl RecordLayout {
    /// The neighbour lists' entries: each entry's partner (`nbr`; a wall's `WALL_ENTRY | w`
    /// in `shaders/step/shared.wgsl`), the slot of its pair in
    /// the partner's list for the `lower` list at the same index, the partner's persistent
    /// id and the contact's history, the contact at the end of the last step (`prior`:
    /// with the ledger or the force jumps), this step's pair force (a servo wall's push on
    /// a wall entry) and torque on the partner where particles rotate, and with the force
    /// jumps this step's impulse of the
    /// pair's force jump along n on the evaluator (`jump`, 0 without one; the partner
    /// subtracts it) and n (`jump_normal`, written only where `jump` is not 0). The
    /// per-step fields come last ([`Self::per_step`]), widened by spare words where a
    /// rebuild's new lists ([`Self::new_entries`]) need more room than they have.
    pub fn entries(hist: &[String], rotation: bool, keeps: Keeps) -> Self {
        let mut layout = Self {
            global: "entries",
            host: None,
            binding: 27,
            capacity_wgsl: "step.list_capacity",
            fields: vec![
                field("nbr", Kind::U32),
                field("lower", Kind::U32),
                field("hist_pid", Kind::U32),
                field("hist", Kind::Hist(hist.to_vec())),
            ],
            absent: Vec::new(),
        }
        .optional(field("prior", prior_kind(keeps)), keeps.prior());
        layout.fields.push(field("pair_force", Kind::Vec3));
        if rotation {
            layout.fields.push(field("pair_torque", Kind::Vec3));
        }
        let mut layout = layout
            .optional(field("jump", Kind::F32), keeps.jumps)
            .optional(field("jump_normal", Kind::Vec3), keeps.jumps);
        let (_, per_step) = layout.per_step();
        let new = Self::new_fields(hist, keeps)
            .iter()
            .map(|f| f.kind.words())
            .sum::<u64>();
        if new > per_step {
            layout
                .fields
                .push(field("spare", Kind::Spare(new - per_step)));
        }
        layout
    }

    /// The fields of a rebuild's new lists: partner id, history, and the prior where the
    /// composition keeps one.
    fn new_fields(hist: &[String], keeps: Keeps) -> Vec<Field> {
        let mut fields = vec![
            field("new_hist_pid", Kind::U32),
            field("new_hist", Kind::Hist(hist.to_vec())),
        ];
        if keeps.prior() {
            fields.push(field("new_prior", prior_kind(keeps)));
        }
        fields
    }

    /// The entries' fields of one step (from `pair_force` on: what the force pass leaves
    /// for the batch's next collect), as (words a record before them, their words a
    /// record): nothing reads them between that collect and the next force pass, in which
    /// a rebuild runs.
    pub fn per_step(&self) -> (u64, u64) {
        let (before, _) = self.place("pair_force").unwrap_or((self.words(), 0));
        (before, self.words() - before)
    }

    /// The lists a rebuild builds: each entry's partner id and history (and the contact
    /// at the end of the last step), remapped from the old lists and copied back into
    /// [`Self::entries`]. They live in the entries' per-step fields (written by `remap`,
    /// read by `copy_back_history`: within a rebuild, when nothing reads those), which
    /// [`Self::entries`] made wide enough.
    pub fn new_entries(hist: &[String], keeps: Keeps, entries: &RecordLayout) -> Self {
        let (base, words) = entries.per_step();
        // (without a prior, its accessors are no-ops)
        let absent = match keeps.prior() {
            true => Vec::new(),
            false => vec![field("new_prior", prior_kind(keeps))],
        };
        let layout = Self {
            global: "new_entries",
            host: Some(Host {
                global: entries.global,
                words: entries.words(),
                base,
            }),
            binding: 37,
            capacity_wgsl: "step.list_capacity",
            fields: Self::new_fields(hist, keeps),
            absent,
        };
        debug_assert!(
            layout.words() <= words,
            "the entries leave the new lists room"
        );
        layout
    }

    /// The buffer (and WGSL global) the records live in.
    pub fn array(&self) -> &'static str {
        self.host.as_ref().map_or(self.global, |h| h.global)
    }

    /// Words a record of a window's block takes (the host's where the records have one).
    fn stride(&self) -> u64 {
        self.host.as_ref().map_or(self.words(), |h| h.words)
    }

    /// Words a record before the first region (in the host's block).
    fn base(&self) -> u64 {
        self.host.as_ref().map_or(0, |h| h.base)
    }

    /// `f` appended to the fields when `present`, else to the absent ones.
    fn optional(mut self, f: Field, present: bool) -> Self {
        if present {
            self.fields.push(f);
        } else {
            self.absent.push(f);
        }
        self
    }

    /// Words of one record, all fields.
    pub fn words(&self) -> u64 {
        self.fields.iter().map(|f| f.kind.words()).sum()
    }

    /// (words of the regions before field `name`, the field's words), if there is one.
    pub fn place(&self, name: &str) -> Option<(u64, u64)> {
        let mut before = 0;
        for f in &self.fields {
            if f.name == name {
                return Some((before, f.kind.words()));
            }
            before += f.kind.words();
        }
        None
    }

    /// Byte offset of field `name`'s region in window 0's block of `capacity` records.
    pub fn offset(&self, name: &str, capacity: u64) -> Option<u64> {
        self.place(name)
            .map(|(before, _)| 4 * (self.base() + before) * capacity)
    }

    /// Byte offset of field `name` of record `r` (a [`Windows::record`] index) in a
    /// buffer of `capacity` records a window.
    pub fn byte_of(&self, name: &str, capacity: u64, windows: &Windows, r: u64) -> Option<u64> {
        let (before, width) = self.place(name)?;
        let (w, i) = windows.split_record(r);
        Some(4 * (w * capacity * self.stride() + (self.base() + before) * capacity + i * width))
    }

    /// Field `name` (a `Vec4` or `Vec4Xyw`) of record `r` from a buffer's `bytes` of
    /// `capacity` records a window, as (x, y, z, w) (z 0 where it is not kept).
    pub fn read_vec4(
        &self,
        bytes: &[u8],
        name: &str,
        (capacity, windows): (u64, &Windows),
        r: u64,
    ) -> Option<[f32; 4]> {
        let kind = &self.fields.iter().find(|f| f.name == name)?.kind;
        let at = self.byte_of(name, capacity, windows, r)? as usize;
        let word = |i: usize| -> Option<f32> {
            bytes
                .get(at + 4 * i..at + 4 * i + 4)
                .map(bytemuck::pod_read_unaligned)
        };
        match kind {
            Kind::Vec4 => Some([word(0)?, word(1)?, word(2)?, word(3)?]),
            Kind::Vec4Xyw => Some([word(0)?, word(1)?, 0.0, word(2)?]),
            _ => None,
        }
    }

    /// Record `r`'s `vec3<f32>` field `name` from the read-back bytes of its buffer.
    pub fn read_vec3(
        &self,
        bytes: &[u8],
        name: &str,
        (capacity, windows): (u64, &Windows),
        r: u64,
    ) -> Option<[f32; 3]> {
        let kind = &self.fields.iter().find(|f| f.name == name)?.kind;
        let at = self.byte_of(name, capacity, windows, r)? as usize;
        let words: &[u8] = bytes.get(at..at + 12)?;
        match kind {
            Kind::Vec3 => Some(bytemuck::pod_read_unaligned(words)),
            _ => None,
        }
    }

    /// Bytes of one window's block of `capacity` records (all fields; the host's block
    /// where the records have one).
    pub fn block_bytes(&self, capacity: u64) -> u64 {
        4 * capacity * self.stride()
    }

    /// Bytes of a buffer of `capacity` records a window over `windows` (at least 4).
    pub fn windowed_bytes(&self, capacity: u64, windows: &Windows) -> u64 {
        (self.block_bytes(capacity) * windows.count).max(4)
    }

    /// Bytes of the fields a kernel calling `calls` touches, for `capacity` records (the
    /// traffic estimate).
    pub fn touched_bytes(&self, calls: &BTreeSet<String>, capacity: u64) -> u64 {
        self.fields
            .iter()
            .filter(|f| {
                ["load_", "store_"]
                    .iter()
                    .any(|p| calls.contains(&format!("{p}{}", f.name)))
                    || calls.contains(&format!("load_{}_far", f.name))
            })
            .map(|f| 4 * f.kind.words() * capacity)
            .sum()
    }

    /// The binding and every field's accessors; `paged`: the entries in several pages
    /// (`gpu::pages`), the other page bound as `<global>_x`. `load_<field>_far` reads a
    /// record that may lie in a neighbouring window (a partner's entries, a particle's old
    /// row): from the other page where it lies there (layouts of their own buffer only).
    pub fn wgsl(&self, paged: bool) -> String {
        let (g, a) = (self.global, self.array());
        let own = self.host.is_none();
        let mut w = String::new();
        let declare = match &self.host {
            None => format!(
                "@group(0) @binding({}) var<storage, read_write> {g}: array<u32>;\n",
                self.binding
            ),
            Some(h) => format!(
                "// (in `{a}`'s records, {} words each, from their word {})\n",
                h.words, h.base
            ),
        };
        let base = match self.base() {
            0 => String::new(),
            b => format!(" + {b}u"),
        };
        let _ = writeln!(
            w,
            "// `{g}` (`src/gpu/records.rs`, generated): {} words a record.\n\
             {declare}\n\
             fn {g}_at(before: u32, width: u32, r: u32) -> u32 {{\n    \
             let capacity = {};\n    \
             return (rec_window(r) - win.rec_base) * (capacity * {}u) + (before{base}) * capacity + rec_local(r) * width;\n}}\n",
            self.words(),
            self.capacity_wgsl,
            self.stride(),
        );
        if own {
            let far = match paged {
                false => format!("    return {g}[at];\n"),
                true => format!(
                    "    let w = rec_window(r);\n    \
                     if (w >= win.rec_base && w < win.rec_end) {{\n        return {g}[at];\n    }}\n    \
                     return {g}_x[at + (win.rec_base - win.rec_other) * ({} * {}u)];\n",
                    self.capacity_wgsl,
                    self.stride()
                ),
            };
            if paged {
                let _ = writeln!(
                    w,
                    "@group(0) @binding({}) var<storage, read> {g}_x: array<u32>;\n",
                    self.binding + 1
                );
            }
            let _ = writeln!(
                w,
                "// Word `at` (`{g}_at`) of record r, which may lie in a neighbouring window's page.\n\
                 fn {g}_far(r: u32, at: u32) -> u32 {{\n{far}}}\n"
            );
        }
        let mut before = 0;
        for f in &self.fields {
            let (n, ty, width) = (f.name, f.kind.wgsl_type(), f.kind.words());
            if let Kind::Spare(words) = f.kind {
                before += words;
                continue;
            }
            let at = format!("{g}_at({before}u, {width}u, r)");
            let bind_at = format!("    let at = {at};\n");
            let near = |i: u64| format!("{a}[at + {i}u]");
            let far = |i: u64| format!("{g}_far(r, at + {i}u)");
            let (load, store) = field_code(&f.kind, &near);
            let _ = writeln!(
                w,
                "fn load_{n}(r: u32) -> {ty} {{\n{bind_at}    return {load};\n}}\n\n\
                 fn store_{n}(r: u32, v: {ty}) {{\n{bind_at}    {}\n}}\n",
                store.join("\n    ")
            );
            if own {
                let (load, _) = field_code(&f.kind, &far);
                let _ = writeln!(
                    w,
                    "fn load_{n}_far(r: u32) -> {ty} {{\n{bind_at}    return {load};\n}}\n"
                );
            }
            before += width;
        }
        for f in &self.absent {
            let (n, ty) = (f.name, f.kind.wgsl_type());
            let zero = match f.kind {
                Kind::U32 => "0u".to_string(),
                Kind::Hist(_) => "hist_zero()".to_string(),
                _ => format!("{ty}()"),
            };
            let _ = writeln!(
                w,
                "// `{n}`: not kept by this composition\n\
                 fn load_{n}(r: u32) -> {ty} {{\n    return {zero};\n}}\n\n\
                 fn store_{n}(r: u32, v: {ty}) {{}}\n"
            );
            if own {
                let _ = writeln!(
                    w,
                    "fn load_{n}_far(r: u32) -> {ty} {{\n    return {zero};\n}}\n"
                );
            }
        }
        w
    }
}

/// A field's load expression and store statements from `word(i)`, the expression of its
/// i-th word (`at` in scope).
fn field_code(kind: &Kind, word: &dyn Fn(u64) -> String) -> (String, Vec<String>) {
    let width = kind.words();
    let store = |i: u64, v: &str| format!("{} = bitcast<u32>({v});", word(i));
    match kind {
        Kind::U32 => (word(0), vec![format!("{} = v;", word(0))]),
        Kind::F32 => (format!("bitcast<f32>({})", word(0)), vec![store(0, "v")]),
        Kind::Vec3 | Kind::Vec4 => {
            let parts: Vec<String> = (0..width)
                .map(|i| format!("bitcast<f32>({})", word(i)))
                .collect();
            let comps = ["x", "y", "z", "w"];
            (
                format!("{}({})", kind.wgsl_type(), parts.join(", ")),
                (0..width)
                    .map(|i| store(i, &format!("v.{}", comps[i as usize])))
                    .collect(),
            )
        }
        Kind::Vec4Xyw => (
            format!(
                "vec4<f32>(bitcast<f32>({}), bitcast<f32>({}), 0.0, bitcast<f32>({}))",
                word(0),
                word(1),
                word(2)
            ),
            vec![store(0, "v.x"), store(1, "v.y"), store(2, "v.w")],
        ),
        Kind::Hist(members) => {
            let parts: Vec<String> = (0..width)
                .map(|i| format!("bitcast<f32>({})", word(i)))
                .collect();
            (
                format!("Hist({})", parts.join(", ")),
                members
                    .iter()
                    .enumerate()
                    .map(|(i, m)| store(i as u64, &format!("v.{m}")))
                    .collect(),
            )
        }
        Kind::Spare(_) => unreachable!("spare words have no accessors"),
    }
}

/// A contact's prior: (δ, F_n, U − ½·dt·P, state), the third only for the ledger.
fn prior_kind(keeps: Keeps) -> Kind {
    if keeps.ledger {
        Kind::Vec4
    } else {
        Kind::Vec4Xyw
    }
}

fn field(name: &'static str, kind: Kind) -> Field {
    Field { name, kind }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_place_fields_one_region_after_another() {
        let hist = vec!["a".to_string(), "b".to_string()];
        let keeps = Keeps::new(true, false, false);
        let e = RecordLayout::entries(&hist, true, keeps);
        // (one spare word: the new lists' 1 + 2 + 4 in the per-step fields' 3 + 3)
        assert_eq!(e.words(), 1 + 1 + 1 + 2 + 4 + 3 + 3 + 1);
        // the force jumps' impulses left out: no-op accessors, no words
        assert_eq!(e.place("jump_normal"), None);
        assert!(e
            .wgsl(false)
            .contains("fn store_jump_normal(r: u32, v: vec3<f32>) {}"));
        assert_eq!(e.place("hist"), Some((3, 2)));
        assert_eq!(e.offset("pair_force", 10), Some(4 * 9 * 10));
        assert_eq!(e.place("missing"), None);
        assert_eq!(e.windowed_bytes(7, &Windows::one(7)), 4 * e.words() * 7);
        let calls: BTreeSet<String> = ["load_hist".to_string(), "store_nbr".to_string()].into();
        assert_eq!(e.touched_bytes(&calls, 10), 4 * (2 + 1) * 10);
        let far: BTreeSet<String> = ["load_pair_force_far".to_string()].into();
        assert_eq!(e.touched_bytes(&far, 10), 4 * 3 * 10);
        // without the ledger the prior keeps (δ, F, state): three words, z reads 0
        let jumps = Keeps::new(false, true, false);
        let j = RecordLayout::entries(&hist, false, jumps);
        assert_eq!(j.place("prior"), Some((5, 3)));
        assert_eq!(j.words(), 8 + 3 + 1 + 3);
        // the per-step fields last: a rebuild's new lists live there where they fit
        assert_eq!(j.per_step(), (8, 7));
        let new = RecordLayout::new_entries(&hist, jumps, &j);
        assert_eq!(new.words(), 6);
        assert_eq!(new.array(), "entries");
        assert_eq!(new.block_bytes(4), j.block_bytes(4));
        // record 1's `new_prior`: after the 8 words of the entries and the new ones' 3
        assert_eq!(
            new.byte_of("new_prior", 4, &Windows::one(4), 1),
            Some(4 * ((8 + 3) * 4 + 3))
        );
        let source = new.wgsl(false);
        assert!(!source.contains("var<storage, read_write> new_entries"));
        assert!(source.contains("entries[at + 2u]"));
        assert_eq!(e.per_step(), (9, 7));
        let wide = RecordLayout::new_entries(&hist, keeps, &e);
        assert_eq!((wide.words(), wide.array()), (7, "entries"));
        assert_eq!(
            wide.byte_of("new_prior", 4, &Windows::one(4), 0),
            Some(4 * (9 + 3) * 4)
        );
        assert!(!e.wgsl(false).contains("spare"));
        assert!(j
            .wgsl(false)
            .contains("0.0, bitcast<f32>(entries[at + 2u]))"));
        // paged: far loads read the other page where the record lies there; the new lists
        // (hosted) have none
        let paged = j.wgsl(true);
        assert!(paged.contains("var<storage, read> entries_x: array<u32>"));
        assert!(paged.contains("entries_far(r, at + 2u)"));
        assert!(paged.contains("fn load_jump_far(r: u32) -> f32"));
        assert!(!j.wgsl(false).contains("entries_x"));
        assert!(!new.wgsl(true).contains("_far"));
        let windows = Windows::one(4);
        let mut bytes = vec![0u8; j.block_bytes(4) as usize];
        let at = j.byte_of("prior", 4, &windows, 1).unwrap() as usize;
        bytes[at..at + 12].copy_from_slice(bytemuck::cast_slice(&[1.0f32, 2.0, 3.0]));
        let read = j.read_vec4(&bytes, "prior", (4, &windows), 1);
        assert_eq!(read, Some([1.0, 2.0, 0.0, 3.0]));
    }
}
