//! The per-particle state in two storage buffers, declared once here: each field is one
//! 16-byte vector a particle, laid out field-major within each window of its buffer
//! (field f of particle k at element (w·F + f)·len + i for k = i of window w, F fields in
//! the buffer; with one window, f·len + k, len = the particles rounded up to 16), so a kernel
//! touching any number of fields binds at most two buffers and each field is read
//! coalesced. `state` holds what the force pass reads of a partner (position, predicted
//! velocity, compensation, ids), `motion` the rest (each buffer must fit one binding:
//! two halves reach twice as many particles as one). The WGSL accessors
//! (`load_<field>`, `store_<field>`), the host's offsets, the re-sort's fields and the
//! traffic estimate all follow from [`FIELDS`].

use std::fmt::Write;

use crate::gpu::window::Windows;

/// The scalar type of a field's four components (the buffer holds `vec4<u32>`; the
/// accessors bitcast).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `vec4<f32>`.
    F32,
    /// `vec4<i32>`.
    I32,
    /// `vec4<u32>`.
    U32,
}

impl Scalar {
    fn wgsl(self) -> &'static str {
        match self {
            Scalar::F32 => "vec4<f32>",
            Scalar::I32 => "vec4<i32>",
            Scalar::U32 => "vec4<u32>",
        }
    }
}

/// The buffer a field lives in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Buffer {
    /// `state`: what the force pass reads of a partner (and the grid sort's cells).
    State,
    /// `motion`: the rest.
    Motion,
}

impl Buffer {
    /// Both, in binding order.
    pub const ALL: [Buffer; 2] = [Buffer::State, Buffer::Motion];

    /// The WGSL global (and host buffer) name.
    pub fn name(self) -> &'static str {
        match self {
            Buffer::State => "state",
            Buffer::Motion => "motion",
        }
    }

    fn binding(self) -> u32 {
        match self {
            Buffer::State => 21,
            Buffer::Motion => 22,
        }
    }
}

/// Which runs a field of the state exists in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Only {
    /// Every run.
    All,
    /// Where the scene's particles rotate.
    Rotation,
    /// Where the run keeps the energy ledger (`GpuOptions::ledger`).
    Ledger,
}

/// What a run's state holds beyond the fields every run has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Extras {
    /// The angular fields (the scene's particles rotate).
    pub rotation: bool,
    /// The energy ledger's per-particle rows.
    pub ledger: bool,
}

impl Extras {
    fn has(self, only: Only) -> bool {
        match only {
            Only::All => true,
            Only::Rotation => self.rotation,
            Only::Ledger => self.ledger,
        }
    }
}

/// One per-particle field of the state.
#[derive(Debug)]
pub struct StateField {
    /// Name (the accessors are `load_<name>` and `store_<name>`).
    pub name: &'static str,
    /// Which buffer holds it.
    pub buffer: Buffer,
    /// Component type.
    pub scalar: Scalar,
    /// Which runs have it.
    pub only: Only,
    /// What the four components hold.
    pub doc: &'static str,
}

const fn field(
    name: &'static str,
    buffer: Buffer,
    scalar: Scalar,
    only: Only,
    doc: &'static str,
) -> StateField {
    StateField {
        name,
        buffer,
        scalar,
        only,
        doc,
    }
}

/// Every field, in buffer order. `cell` comes first: the grid sort reads the cells as the
/// `state` buffer's first n elements.
pub const FIELDS: &[StateField] = &[
    field(
        "cell",
        Buffer::State,
        Scalar::I32,
        Only::All,
        "integer cell (xyz), material (w; with NOT_APPEARED until the particle appears)",
    ),
    field(
        "off",
        Buffer::State,
        Scalar::F32,
        Only::All,
        "offset inside the cell (xyz), radius (w)",
    ),
    field(
        "vel",
        Buffer::Motion,
        Scalar::F32,
        Only::All,
        "velocity (xyz), mass (w)",
    ),
    field(
        "acc",
        Buffer::Motion,
        Scalar::F32,
        Only::All,
        "acceleration (xyz), the last force pass's largest overlap/a12 (w)",
    ),
    field(
        "vpred",
        Buffer::State,
        Scalar::F32,
        Only::All,
        "predicted velocity v + dt/2·a (xyz), mass (w)",
    ),
    field(
        "kahan_v",
        Buffer::Motion,
        Scalar::F32,
        Only::All,
        "the velocity's Kahan compensation (xyz; true = stored − c)",
    ),
    field(
        "kahan_o",
        Buffer::State,
        Scalar::F32,
        Only::All,
        "the offset's compensation (xyz), the radius's rounding residual (w)",
    ),
    field(
        "disp",
        Buffer::Motion,
        Scalar::F32,
        Only::All,
        "displacement since the last rebuild (xyz), the batch's largest overlap/a12 (w)",
    ),
    field(
        "ids",
        Buffer::State,
        Scalar::U32,
        Only::All,
        "persistent id, first list entry, pairs in the list, wall entries after them",
    ),
    field(
        "omega",
        Buffer::Motion,
        Scalar::F32,
        Only::Rotation,
        "angular velocity (xyz), moment of inertia (w)",
    ),
    field(
        "alpha",
        Buffer::Motion,
        Scalar::F32,
        Only::Rotation,
        "angular acceleration torque/I (xyz)",
    ),
    field(
        "wpred",
        Buffer::State,
        Scalar::F32,
        Only::Rotation,
        "predicted angular velocity ω + dt/2·α (xyz)",
    ),
    field(
        "ledger_counts",
        Buffer::Motion,
        Scalar::F32,
        Only::Ledger,
        "the ledger: pairs overlapping, walls overlapping, pairs and walls engaged without overlap",
    ),
    field(
        "ledger_overlaps",
        Buffer::Motion,
        Scalar::F32,
        Only::Ledger,
        "the ledger: largest overlap, largest overlap/a12, their sums over pairs and walls",
    ),
    field(
        "ledger_energy",
        Buffer::Motion,
        Scalar::F32,
        Only::Ledger,
        "the ledger: energy dissipated so far (Kahan sum, compensation), stored now",
    ),
    field(
        "ledger_wall",
        Buffer::Motion,
        Scalar::F32,
        Only::Ledger,
        "the ledger: work moving walls did so far (Kahan sum, compensation)",
    ),
];

/// The bit of `cell.w` (above the material) set while a particle has not appeared yet
/// (pouring): the step reads it there, not from the flags by persistent id.
pub const NOT_APPEARED: i32 = 1 << 30;

/// Bytes of one field of one particle.
pub const FIELD_BYTES: u64 = 16;

/// Particles a field's region is rounded up to (so every region starts 256-byte aligned,
/// as buffer-to-texture copies and binding offsets want).
pub const STRIDE_ALIGN: u64 = 16;

/// Elements from one per-particle region of a buffer to the next, for `n` particles (the
/// state's fields, `rows` in the step): `n` rounded up to [`STRIDE_ALIGN`].
pub fn particle_stride(n: u64) -> u64 {
    n.div_ceil(STRIDE_ALIGN) * STRIDE_ALIGN
}

/// The fields of a scene's state (with or without the angular ones) for `n` particles.
#[derive(Clone, Debug)]
pub struct StateLayout {
    fields: Vec<&'static StateField>,
    n: u64,
    windows: Windows,
}

impl StateLayout {
    /// The layout for `n` particles in one window, with the fields of `extras`.
    pub fn new(n: u64, extras: Extras) -> Self {
        Self::windowed(n, extras, Windows::one(n))
    }

    /// The layout for `n` particles blocked into `windows`.
    pub fn windowed(n: u64, extras: Extras, windows: Windows) -> Self {
        Self {
            fields: fields(extras).collect(),
            n,
            windows,
        }
    }

    /// The windows it is blocked into.
    pub fn windows(&self) -> &Windows {
        &self.windows
    }

    /// Field names, `state`'s then `motion`'s, each in buffer order.
    pub fn names(&self) -> Vec<&'static str> {
        Buffer::ALL
            .iter()
            .flat_map(|&b| self.in_buffer(b))
            .map(|f| f.name)
            .collect()
    }

    /// The fields of buffer `b`, in order.
    pub fn in_buffer(&self, b: Buffer) -> impl Iterator<Item = &'static StateField> + '_ {
        self.fields.iter().copied().filter(move |f| f.buffer == b)
    }

    /// Elements (particles) from one field's region to the next within a window.
    pub fn stride(&self) -> u64 {
        self.windows.len
    }

    /// Fields of buffer `b`.
    pub fn count(&self, b: Buffer) -> u64 {
        self.in_buffer(b).count() as u64
    }

    /// Bytes of buffer `b` (at least one element).
    pub fn bytes(&self, b: Buffer) -> u64 {
        (self.windows.count * self.count(b) * self.windows.len * FIELD_BYTES).max(FIELD_BYTES)
    }

    /// The buffer of field `name` and the byte offset of its region in the first window,
    /// if the layout has it.
    pub fn place(&self, name: &str) -> Option<(Buffer, u64)> {
        let f = self.fields.iter().find(|f| f.name == name)?;
        let at = self.in_buffer(f.buffer).position(|g| g.name == name)?;
        Some((f.buffer, at as u64 * self.windows.len * FIELD_BYTES))
    }

    /// The buffer of field `name` and its position among that buffer's fields.
    fn position(&self, name: &str) -> Option<(Buffer, u64)> {
        let f = self.fields.iter().find(|f| f.name == name)?;
        let at = self.in_buffer(f.buffer).position(|g| g.name == name)?;
        Some((f.buffer, at as u64))
    }

    /// Bytes of one field's `n` particles.
    pub fn field_bytes(&self) -> u64 {
        self.n * FIELD_BYTES
    }

    /// Bytes of the fields of buffer `b` a kernel calling `calls` touches (through their
    /// accessors), for the traffic estimate: each field's `n` vectors once.
    pub fn touched_bytes(&self, b: Buffer, calls: &std::collections::BTreeSet<String>) -> u64 {
        let used = self
            .in_buffer(b)
            .filter(|f| {
                calls.contains(&format!("load_{}", f.name))
                    || calls.contains(&format!("store_{}", f.name))
            })
            .count();
        used as u64 * self.field_bytes()
    }

    /// Buffer `b`'s contents from `values(name)` per field (`n` vectors each; a field it
    /// gives none for is zero).
    pub fn pack(&self, b: Buffer, values: &dyn Fn(&str) -> Option<Vec<[u32; 4]>>) -> Vec<u8> {
        let mut out = vec![0u8; self.bytes(b) as usize];
        let fields = self.count(b);
        for f in self.in_buffer(b) {
            if let (Some(v), Some((_, at))) = (values(f.name), self.position(f.name)) {
                for (k, x) in v.iter().take(self.n as usize).enumerate() {
                    let e = (self.windows.element(fields, at, k as u64) * FIELD_BYTES) as usize;
                    out[e..e + FIELD_BYTES as usize].copy_from_slice(bytemuck::bytes_of(x));
                }
            }
        }
        out
    }

    /// Field `name`'s `n` vectors from its buffer's bytes (empty when absent or short).
    pub fn unpack<T: bytemuck::Pod>(&self, bytes: &[u8], name: &str) -> Vec<T> {
        let Some((b, at)) = self.position(name) else {
            return Vec::new();
        };
        let (fields, size) = (self.count(b), std::mem::size_of::<T>());
        let mut out = Vec::with_capacity(self.n as usize);
        for k in 0..self.n {
            let e = (self.windows.element(fields, at, k) * FIELD_BYTES) as usize;
            match bytes.get(e..e + size) {
                Some(x) => out.push(bytemuck::pod_read_unaligned(x)),
                None => return Vec::new(),
            }
        }
        out
    }

    /// Field `name`'s `n` vectors written into its buffer's bytes (nothing where the
    /// layout lacks it or the bytes are short).
    pub fn repack<T: bytemuck::Pod>(&self, bytes: &mut [u8], name: &str, values: &[T]) {
        let Some((b, at)) = self.position(name) else {
            return;
        };
        let fields = self.count(b);
        for (k, v) in values.iter().enumerate().take(self.n as usize) {
            let e = (self.windows.element(fields, at, k as u64) * FIELD_BYTES) as usize;
            let v = bytemuck::bytes_of(v);
            if let Some(x) = bytes.get_mut(e..e + v.len()) {
                x.copy_from_slice(v);
            }
        }
    }

    /// The WGSL of the state: the two bindings and each field's accessors; `paged`: the
    /// state in pages of whole windows (`gpu::pages`), each dispatch binding its window's
    /// page and the other page as `state_x`, from which the loads of `state` read a
    /// particle of a neighbouring window that lies there (`motion` is read and written
    /// for the dispatch's own particles only).
    pub fn wgsl(extras: Extras, paged: bool) -> String {
        let mut w = String::from(
            "// The particle state (`src/gpu/state.rs`, generated): one vec4 per particle and\n\
             // field, field-major within each window (`state_blocked`) of two buffers.\n",
        );
        let _ = writeln!(w, "const NOT_APPEARED: i32 = {NOT_APPEARED};");
        for b in Buffer::ALL {
            let _ = writeln!(
                w,
                "@group(0) @binding({}) var<storage, read_write> {}: array<vec4<u32>>;",
                b.binding(),
                b.name()
            );
        }
        let layout = Self::new(0, extras);
        if paged {
            let fields = layout.count(Buffer::State);
            let _ = writeln!(
                w,
                "@group(0) @binding({STATE_X_BINDING}) var<storage, read> state_x: array<vec4<u32>>;\n\n\
                 // Element `at` (`state_blocked`) of particle k's `state`, which may lie in the other page.\n\
                 fn state_far(k: u32, at: u32) -> vec4<u32> {{\n    \
                 let w = win_of(k);\n    \
                 if (w >= win.st_base && w < win.st_end) {{\n        return state[at];\n    }}\n    \
                 return state_x[at + (win.st_base - win.st_other) * ({fields}u * grid.window.y)];\n}}\n"
            );
        }
        for field in fields(extras) {
            let ty = field.scalar.wgsl();
            let buf = field.buffer.name();
            let f = layout
                .in_buffer(field.buffer)
                .position(|g| g.name == field.name)
                .unwrap_or(0);
            let at = format!("state_blocked({}u, {f}u, k)", layout.count(field.buffer));
            let load = match (paged, field.buffer) {
                (true, Buffer::State) => format!("state_far(k, {at})"),
                _ => format!("{buf}[{at}]"),
            };
            let _ = writeln!(w, "// {}", field.doc);
            let _ = writeln!(
                w,
                "fn load_{n}(k: u32) -> {ty} {{\n    return bitcast<{ty}>({load});\n}}\n",
                n = field.name
            );
            let _ = writeln!(
                w,
                "fn store_{n}(k: u32, v: {ty}) {{\n    {buf}[{at}] = bitcast<vec4<u32>>(v);\n}}\n",
                n = field.name
            );
        }
        w
    }
}

/// The binding of `state_x`, the other page of the state (`StateLayout::wgsl`).
pub const STATE_X_BINDING: u32 = 23;

/// The energy ledger's fields, in the order of its rows (`shaders/ledger.wgsl`).
pub fn ledger_fields() -> impl Iterator<Item = &'static str> {
    FIELDS
        .iter()
        .filter(|f| f.only == Only::Ledger)
        .map(|f| f.name)
}

/// The fields of a scene's state.
fn fields(extras: Extras) -> impl Iterator<Item = &'static StateField> {
    FIELDS.iter().filter(move |f| extras.has(f.only))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_layout_regions_are_aligned_and_disjoint() {
        for (n, rotation, ledger) in [
            (0, false, false),
            (1, false, true),
            (17, true, false),
            (1000, true, true),
        ] {
            let l = StateLayout::new(n, Extras { rotation, ledger });
            for b in Buffer::ALL {
                let mut last_end = 0;
                for f in l.in_buffer(b) {
                    let (buffer, at) = l.place(f.name).expect("a field of the layout");
                    assert_eq!(buffer, b);
                    assert_eq!(at % 256, 0, "{} at {at}", f.name);
                    assert!(at >= last_end);
                    last_end = at + l.field_bytes();
                }
                assert!(last_end <= l.bytes(b));
            }
            assert_eq!(l.place("omega").is_some(), rotation);
            assert_eq!(l.place("ledger_energy").is_some(), ledger);
            // the grid sort reads the cells at the start of `state`
            assert_eq!(l.place("cell"), Some((Buffer::State, 0)));
        }
    }

    #[test]
    fn state_pack_and_unpack_round_trip() {
        let l = StateLayout::new(3, Extras::default());
        let ids = vec![[1u32, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12]];
        let bytes = l.pack(Buffer::State, &|name| (name == "ids").then(|| ids.clone()));
        assert_eq!(l.unpack::<[u32; 4]>(&bytes, "ids"), ids);
        assert_eq!(l.unpack::<[u32; 4]>(&bytes, "cell"), vec![[0; 4]; 3]);
        assert!(l.unpack::<[u32; 4]>(&bytes, "omega").is_empty());
        let mut bytes = bytes;
        let cells = vec![[7u32, 8, 9, 10]; 3];
        l.repack(&mut bytes, "cell", &cells);
        assert_eq!(l.unpack::<[u32; 4]>(&bytes, "cell"), cells);
        assert_eq!(l.unpack::<[u32; 4]>(&bytes, "ids"), ids);
    }
}
