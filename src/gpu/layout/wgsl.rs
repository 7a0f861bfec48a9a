//! Structs and constants the host and the kernels share, declared once in Rust: the
//! macros [`wgsl_struct!`](crate::gpu::layout::wgsl_struct) and
//! [`wgsl_consts!`](crate::gpu::layout::wgsl_consts) define them and emit their WGSL,
//! which every shader module gets ([`declarations`]).

/// One WGSL member a field of a shared struct becomes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WgslMember {
    /// Appended to the field's name (padding splits into one member a word).
    pub suffix: String,
    /// The WGSL type.
    pub ty: String,
    /// Bytes from the field's start.
    pub offset: usize,
}

/// A Rust type a shared struct's field may have, with its WGSL form.
pub trait WgslType {
    /// The WGSL members a field of this type becomes.
    fn members() -> Vec<WgslMember>;
}

fn one(ty: &str) -> Vec<WgslMember> {
    vec![WgslMember {
        suffix: String::new(),
        ty: ty.to_string(),
        offset: 0,
    }]
}

macro_rules! wgsl_scalar {
    ($($rust:ty => $wgsl:literal),* $(,)?) => {
        $(impl WgslType for $rust {
            fn members() -> Vec<WgslMember> {
                one($wgsl)
            }
        })*
    };
}

wgsl_scalar!(
    f32 => "f32", u32 => "u32", i32 => "i32",
    [f32; 3] => "vec3<f32>", [u32; 3] => "vec3<u32>", [i32; 3] => "vec3<i32>",
    [f32; 4] => "vec4<f32>", [u32; 4] => "vec4<u32>", [i32; 4] => "vec4<i32>",
);

/// Explicit padding of `N` words (zero): one `u32` member a word in the WGSL, so the
/// two sides have the same size without arrays (a uniform array wants a 16-byte stride).
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pad<const N: usize>([u32; N]);

impl<const N: usize> Pad<N> {
    /// Zero words.
    pub const ZERO: Self = Self([0; N]);
}

impl<const N: usize> Default for Pad<N> {
    fn default() -> Self {
        Self::ZERO
    }
}

// SAFETY: a transparent wrapper of [u32; N], which is Pod for every N.
unsafe impl<const N: usize> bytemuck::Zeroable for Pad<N> {}
// SAFETY: as above.
unsafe impl<const N: usize> bytemuck::Pod for Pad<N> {}

impl<const N: usize> WgslType for Pad<N> {
    fn members() -> Vec<WgslMember> {
        (0..N)
            .map(|i| WgslMember {
                suffix: format!("_{i}"),
                ty: "u32".to_string(),
                offset: 4 * i,
            })
            .collect()
    }
}

/// A field of a shared struct: its name, place and documentation.
#[derive(Clone, Debug)]
pub struct WgslField {
    /// The field's name, in both languages.
    pub name: &'static str,
    /// Bytes from the struct's start.
    pub offset: usize,
    /// What it is in WGSL.
    pub members: Vec<WgslMember>,
    /// Its documentation (the lines of its doc comment).
    pub doc: &'static [&'static str],
}

/// A `#[repr(C)]` struct the kernels read, defined by `wgsl_struct!`.
pub trait WgslStruct {
    /// Its WGSL name.
    const WGSL_NAME: &'static str;
    /// Its size in bytes.
    const SIZE: usize;
    /// Its fields in order.
    fn wgsl_fields() -> Vec<WgslField>;

    /// The WGSL members (name, byte offset) in order, as naga must lay them out.
    fn wgsl_members() -> Vec<(String, usize)> {
        Self::wgsl_fields()
            .iter()
            .flat_map(|f| {
                (f.members.iter()).map(|m| (format!("{}{}", f.name, m.suffix), f.offset + m.offset))
            })
            .collect()
    }

    /// Its WGSL declaration, each field's documentation as comments.
    fn wgsl_declaration() -> String {
        let mut w = format!("struct {} {{\n", Self::WGSL_NAME);
        for f in Self::wgsl_fields() {
            for line in f.doc {
                w.push_str(&format!("    //{line}\n"));
            }
            for m in &f.members {
                w.push_str(&format!("    {}{}: {},\n", f.name, m.suffix, m.ty));
            }
        }
        w.push_str("}\n");
        w
    }
}

/// Defines a `#[repr(C)]` struct the kernels read and its WGSL twin: the attribute
/// `#[wgsl("Name")]` names the WGSL struct; fields take doc comments only.
macro_rules! wgsl_struct {
    (
        $(#[doc = $doc:expr])*
        #[wgsl($wgsl:literal)]
        #[derive($($derive:path),* $(,)?)]
        $vis:vis struct $name:ident {
            $( $(#[doc = $fdoc:expr])* $fvis:vis $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        #[repr(C)]
        #[derive($($derive),*)]
        $vis struct $name {
            $( $(#[doc = $fdoc])* $fvis $field: $ty ),*
        }

        impl $crate::gpu::layout::WgslStruct for $name {
            const WGSL_NAME: &'static str = $wgsl;
            const SIZE: usize = std::mem::size_of::<$name>();
            fn wgsl_fields() -> Vec<$crate::gpu::layout::WgslField> {
                vec![$(
                    $crate::gpu::layout::WgslField {
                        name: stringify!($field),
                        offset: std::mem::offset_of!($name, $field),
                        members: <$ty as $crate::gpu::layout::WgslType>::members(),
                        doc: &[$($fdoc),*],
                    }
                ),*]
            }
        }

        impl $crate::gpu::layout::WgslType for $name {
            fn members() -> Vec<$crate::gpu::layout::WgslMember> {
                vec![$crate::gpu::layout::WgslMember {
                    suffix: String::new(),
                    ty: $wgsl.to_string(),
                    offset: 0,
                }]
            }
        }
    };
}
pub(crate) use wgsl_struct;

/// A constant's value as a WGSL literal of its type.
pub trait WgslLiteral: Copy {
    /// The WGSL type.
    const TY: &'static str;
    /// The literal.
    fn literal(self) -> String;
}

impl WgslLiteral for u32 {
    const TY: &'static str = "u32";
    fn literal(self) -> String {
        format!("{self}u")
    }
}

impl WgslLiteral for i32 {
    const TY: &'static str = "i32";
    fn literal(self) -> String {
        format!("{self}i")
    }
}

impl WgslLiteral for f32 {
    const TY: &'static str = "f32";
    fn literal(self) -> String {
        // the shortest decimal that reads back as the same f32 (checked through naga)
        format!("{self:?}")
    }
}

/// Defines a list of constants the kernels share: each a `pub const` in Rust and a
/// `const` of the same name in WGSL; `LIST` names them all, for [`declarations`].
macro_rules! wgsl_consts {
    (
        $(#[doc = $ldoc:expr])*
        $vis:vis $list:ident: $ty:ty = {
            $( $(#[doc = $doc:expr])* $name:ident = $value:expr ),* $(,)?
        }
    ) => {
        $( $(#[doc = $doc])* $vis const $name: $ty = $value; )*
        $(#[doc = $ldoc])*
        $vis const $list: &[(&str, $ty)] = &[$((stringify!($name), $name)),*];
    };
}
pub(crate) use wgsl_consts;

/// A shared struct, type-erased: what [`declarations`] writes and the tests check.
pub struct SharedStruct {
    /// Its WGSL name.
    pub name: &'static str,
    /// Its size in bytes.
    pub size: usize,
    /// Its WGSL members (name, byte offset) in order.
    pub members: Vec<(String, usize)>,
    /// Its WGSL declaration.
    pub declaration: String,
}

fn shared<T: WgslStruct>() -> SharedStruct {
    SharedStruct {
        name: T::WGSL_NAME,
        size: T::SIZE,
        members: T::wgsl_members(),
        declaration: T::wgsl_declaration(),
    }
}

/// Every struct the host shares with the kernels.
pub fn shared_structs() -> Vec<SharedStruct> {
    use super::*;
    use crate::gpu::window::WindowParams;
    vec![
        shared::<GridParams>(),
        shared::<WindowParams>(),
        shared::<ScanParams>(),
        shared::<StepParams>(),
        shared::<WallGpu>(),
        shared::<HystereticPair>(),
        shared::<JkrPair>(),
        shared::<CoulombSpringRow>(),
        shared::<TwistingRow>(),
    ]
}

/// Every constant the host shares with the kernels: (name, WGSL type, value's bits).
pub fn shared_consts() -> Vec<(&'static str, &'static str, u32)> {
    use super::*;
    use crate::gpu::{control, records};
    let u32s = [
        HYST_FLAGS,
        JKR_DISSIPATIONS,
        records::ENTRY_MARKS,
        records::ROWS_REGIONS,
        control::CONTROL_WORDS,
        control::HALTS,
    ];
    let i32s = [SOLVER_ITERATIONS];
    let f32s = [
        WALL_MOTIONS,
        control::MONITOR_LIMITS,
        JKR_SOLVER,
        KRIJT_SOLVER,
    ];
    let words = u32s
        .iter()
        .flat_map(|l| l.iter().map(|&(n, v)| (n, u32::TY, v)));
    let ints = (i32s.iter()).flat_map(|l| l.iter().map(|&(n, v)| (n, i32::TY, v as u32)));
    let floats = (f32s.iter()).flat_map(|l| l.iter().map(|&(n, v)| (n, f32::TY, v.to_bits())));
    words.chain(ints).chain(floats).collect()
}

/// Every struct and constant the host shares with the kernels, in WGSL: each shader
/// module has them (`gpu::shaders::compose`), so no WGSL file writes them again.
pub fn declarations() -> String {
    let mut w = String::new();
    for s in shared_structs() {
        w.push_str(&s.declaration);
        w.push('\n');
    }
    for (name, ty, bits) in shared_consts() {
        let literal = match ty {
            "f32" => f32::from_bits(bits).literal(),
            "i32" => (bits as i32).literal(),
            _ => bits.literal(),
        };
        w.push_str(&format!("const {name}: {ty} = {literal};\n"));
    }
    w
}
