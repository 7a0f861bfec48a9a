//! Per-contact history fields, each declared once by the sub-model that keeps it. The GPU
//! layout (stored WGSL struct, load/store, the partner's view, byte size) and the host's
//! decoder of read-back histories follow from these declarations (`gpu::composition`).

use super::ContactHistory;
use glam::DVec3;

/// How a field is stored and worked with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// One f32 word, kept bitwise (the sub-model may pack bits into it).
    Word,
    /// A boolean, stored as 0.0 / 1.0.
    Flag,
    /// A vector, stored as three f32 words.
    Vec3,
}

/// What the partner of a pair sees of a field: histories are stored once per pair, in the
/// evaluating particle's frame, and handed over when the evaluator changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mirror {
    /// The same value (scalars and axial quantities such as the rolling displacement).
    Same,
    /// The negated value (the tangential spring: n and the relative velocity flip).
    Negate,
}

/// The field of [`ContactHistory`] (the f64 reference's history) a stored field decodes into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HostField {
    /// δmax (magnitude) with the sign bit as the touched flag (the hysteretic model).
    DeltaMaxTouched,
    /// The touched flag (or-ed with other laws' flags in a mixed layout).
    Touched,
    /// The tangential spring.
    Tangential,
    /// The rolling displacement ξ.
    Rolling,
    /// The Krijt contact radius a.
    ContactRadius,
    /// `twist` (Luding's twisting spring, a scalar along n).
    Twist,
    /// `slipping` (Luding's sliding law slipped in the last step).
    Slipping,
}

/// One per-contact history field of a sub-model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HistoryField {
    /// The WGSL member name (shared by sub-models that keep the same quantity, e.g. the
    /// tangential spring of every sliding law: a pair uses one of them).
    pub name: &'static str,
    /// How it is stored.
    pub shape: Shape,
    /// What the partner sees.
    pub mirror: Mirror,
    /// Where the host decodes it to.
    pub host: HostField,
    /// One line: what it is.
    pub doc: &'static str,
}

/// The tangential spring, kept in the evaluator's frame (the partner sees it negated):
/// Mindlin's (JKR family) and Luding's sliding law keep it; a pair uses one of them.
pub const TANGENTIAL_SPRING: HistoryField = HistoryField {
    name: "spring",
    shape: Shape::Vec3,
    mirror: Mirror::Negate,
    host: HostField::Tangential,
    doc: "the tangential spring, m",
};

/// The rolling displacement, the same seen from either side: the JKR rolling resistance
/// and Luding's rolling law keep it; a pair uses one of them.
pub const ROLLING_DISPLACEMENT: HistoryField = HistoryField {
    name: "xi",
    shape: Shape::Vec3,
    mirror: Mirror::Same,
    host: HostField::Rolling,
    doc: "the rolling displacement, m",
};

impl HostField {
    /// Every field of [`ContactHistory`], in the order checkpoints store them.
    pub const ALL: [HostField; 7] = [
        HostField::DeltaMaxTouched,
        HostField::Touched,
        HostField::Tangential,
        HostField::Rolling,
        HostField::ContactRadius,
        HostField::Twist,
        HostField::Slipping,
    ];

    /// Whether the field is a flag (its one value 0 or 1).
    pub const fn is_flag(self) -> bool {
        matches!(self, HostField::Touched | HostField::Slipping)
    }

    /// The name of the field's values in the contact network output and how many
    /// components they have (the touched flag of `DeltaMaxTouched` is output as `touched`).
    pub const fn output(self) -> (&'static str, usize) {
        match self {
            HostField::DeltaMaxTouched => ("delta_max", 1),
            HostField::Touched => ("touched", 1),
            HostField::Tangential => ("tangential_spring", 3),
            HostField::Rolling => ("rolling_displacement", 3),
            HostField::ContactRadius => ("contact_radius", 1),
            HostField::Twist => ("twist", 1),
            HostField::Slipping => ("slipping", 1),
        }
    }

    /// The field's value in `h` (the first [`Self::output`] components are meaningful).
    pub fn value(self, h: &ContactHistory) -> [f64; 3] {
        let v = |d: DVec3| d.to_array();
        match self {
            HostField::DeltaMaxTouched => [h.delta_max, 0.0, 0.0],
            HostField::Touched => [f64::from(u8::from(h.touched)), 0.0, 0.0],
            HostField::Tangential => v(h.tangential),
            HostField::Rolling => v(h.rolling),
            HostField::ContactRadius => [h.contact_radius, 0.0, 0.0],
            HostField::Twist => [h.twist, 0.0, 0.0],
            HostField::Slipping => [f64::from(u8::from(h.slipping)), 0.0, 0.0],
        }
    }

    /// Sets the field in `h` to `v` (its first [`Self::output`] components; a flag is set
    /// where `v[0]` is not 0), the inverse of [`Self::value`].
    pub fn set(self, h: &mut ContactHistory, v: [f64; 3]) {
        let d = DVec3::from_array(v);
        match self {
            HostField::DeltaMaxTouched => h.delta_max = v[0],
            HostField::Touched => h.touched = v[0] != 0.0,
            HostField::Tangential => h.tangential = d,
            HostField::Rolling => h.rolling = d,
            HostField::ContactRadius => h.contact_radius = v[0],
            HostField::Twist => h.twist = v[0],
            HostField::Slipping => h.slipping = v[0] != 0.0,
        }
    }
}

impl HistoryField {
    /// Stored f32 words.
    pub fn words(&self) -> usize {
        match self.shape {
            Shape::Word | Shape::Flag => 1,
            Shape::Vec3 => 3,
        }
    }

    /// Decodes the field's stored words `w` into `h`.
    pub fn decode(&self, w: &[f32], h: &mut ContactHistory) {
        let v = || DVec3::new(w[0] as f64, w[1] as f64, w[2] as f64);
        match self.host {
            HostField::DeltaMaxTouched => {
                h.delta_max = w[0].abs() as f64;
                h.touched |= w[0].is_sign_negative();
            }
            HostField::Touched => h.touched |= w[0] != 0.0,
            HostField::Tangential => h.tangential = v(),
            HostField::Rolling => h.rolling = v(),
            HostField::ContactRadius => h.contact_radius = w[0] as f64,
            HostField::Twist => h.twist = w[0] as f64,
            HostField::Slipping => h.slipping = w[0] != 0.0,
        }
    }

    /// `h` as the partner of the pair sees this field.
    pub fn mirror_host(&self, h: &mut ContactHistory) {
        if self.mirror == Mirror::Negate {
            match self.host {
                HostField::Tangential => h.tangential = -h.tangential,
                HostField::Rolling => h.rolling = -h.rolling,
                HostField::ContactRadius => h.contact_radius = -h.contact_radius,
                HostField::Twist => h.twist = -h.twist,
                HostField::DeltaMaxTouched | HostField::Touched | HostField::Slipping => {}
            }
        }
    }
}
