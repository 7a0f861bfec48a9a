//! Every normal law and sub-model the GPU step can compose, declared once: its WGSL file,
//! its pair-table row block, its history fields and hooks. A new law or sub-model is one
//! entry here (`LAWS`, `SUB_MODELS`).

use super::*;

/// A block of the pair-table row: a WGSL struct of f32/u32 scalars (so blocks concatenate
/// without padding) and how a pair's model fills it.
pub struct RowBlock {
    /// The member name in `PairRow`.
    pub member: &'static str,
    /// The WGSL struct of the block.
    pub wgsl_struct: &'static str,
    /// Its size in bytes.
    pub bytes: usize,
    /// The block of a pair's model (`None`: the pair does not use it; the block is zero).
    pub fill: fn(&ContactModel) -> Option<Vec<u8>>,
}

/// A dispatch point of a normal law, answered by the sub-models attached to it for the
/// pairs they apply to; `default` is the law's own answer.
pub struct Hook {
    /// The WGSL signature, `fn name(...) -> T`.
    pub signature: &'static str,
    /// The body's last statement where no sub-model takes over.
    pub default: &'static str,
}

/// A normal law on the GPU.
pub struct NormalLaw {
    /// Its name in variant names.
    pub name: &'static str,
    /// The WGSL file.
    pub source: &'static str,
    /// Its parameter block.
    pub row: RowBlock,
    /// Its history fields.
    pub history: &'static [HistoryField],
    /// `fn(p: <row struct>, k: Kin, h: ptr<function, History>) -> Normal`.
    pub normal: &'static str,
    /// `fn(p: <row struct>, k: Kin) -> vec4<f32>`: the energy ledger's contact edges.
    pub edges: &'static str,
    /// `fn(p: <row struct>, k: Kin) -> f32`: the force that switches on at δ = 0 inside an
    /// engaged contact (`ContactModel::touch_jump`).
    pub touch_jump: &'static str,
    /// Its hooks.
    pub hooks: &'static [Hook],
}

/// How a sub-model plugs into its normal laws.
pub enum Role {
    /// It answers hooks of the normal law: (hook name, a WGSL statement that returns where
    /// the sub-model applies to the pair).
    Hooks(&'static [(&'static str, &'static str)]),
    /// In mechanical contact it adds forces or torques: `fn(row: PairRow, k: Kin,
    /// nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>)`; particles rotate.
    Apply(&'static str),
}

/// A sub-model attached to normal laws.
pub struct SubModel {
    /// Its name in variant names.
    pub name: &'static str,
    /// The WGSL file.
    pub source: &'static str,
    /// WGSL files it shares with other sub-models (composed in once).
    pub shared: &'static [&'static str],
    /// Its parameter block, where it has its own.
    pub row: Option<RowBlock>,
    /// The normal laws it attaches to.
    pub laws: &'static [&'static str],
    /// Its history fields.
    pub history: &'static [HistoryField],
    /// How it plugs in.
    pub role: Role,
    /// Whether a pair's model uses it.
    pub uses: fn(&ContactModel) -> bool,
}

/// The normal laws, in the order of the pair row.
pub const LAWS: &[NormalLaw] = &[
    NormalLaw {
        name: "hysteretic",
        source: include_str!("../../../shaders/model/hysteretic.wgsl"),
        row: RowBlock {
            member: "hysteretic",
            wgsl_struct: HystereticPair::WGSL_NAME,
            bytes: std::mem::size_of::<HystereticPair>(),
            fill: |m| match m {
                ContactModel::Hysteretic(p) => Some(bytes(&HystereticPair::hysteretic(p))),
                ContactModel::Lsd(p) => Some(bytes(&HystereticPair::lsd(p))),
                ContactModel::Jkr(_) => None,
            },
        },
        history: hysteretic::HISTORY,
        normal: "hyst_normal",
        edges: "hyst_edges",
        touch_jump: "hyst_touch_jump",
        hooks: &[],
    },
    NormalLaw {
        name: "jkr",
        source: include_str!("../../../shaders/model/jkr.wgsl"),
        row: RowBlock {
            member: "jkr",
            wgsl_struct: JkrPair::WGSL_NAME,
            bytes: std::mem::size_of::<JkrPair>(),
            fill: |m| match m {
                ContactModel::Jkr(p) => Some(bytes(&JkrPair::new(p))),
                _ => None,
            },
        },
        history: jkr::HISTORY,
        normal: "jkr_normal",
        edges: "jkr_edges",
        touch_jump: "jkr_touch_jump",
        hooks: &[
            Hook {
                signature: "fn jkr_damping(p: JkrPair, a: f32, a0: f32, k: Kin) -> f32",
                default: "return jkr_dissipation(p, a, k.delta, a0, k.delta_dot, k.m_eff, k.r_eff);",
            },
            Hook {
                signature: "fn jkr_radius_state(p: JkrPair, k: Kin, a0: f32, d0: f32, fc: f32, x_eq: f32, h: ptr<function, History>) -> vec4<f32>",
                default: "return vec4<f32>(x_eq, 0.0, 0.0, 0.0);",
            },
        ],
    },
];

/// The sub-models, in the order they act (dissipations, then the tangential, rolling and
/// twisting laws).
pub const SUB_MODELS: &[SubModel] = &[
    SubModel {
        name: "krijt",
        source: include_str!("../../../shaders/model/krijt.wgsl"),
        shared: &[],
        row: None,
        laws: &["jkr"],
        history: krijt::HISTORY,
        role: Role::Hooks(&[
            (
                "jkr_damping",
                "if (jkr_radius_dynamics(p)) { return krijt_viscous(p, a, a0, k.r_eff, k.delta_dot); }",
            ),
            (
                "jkr_radius_state",
                "if (jkr_radius_dynamics(p)) { return krijt_state(p, k, a0, d0, fc, x_eq, h); }",
            ),
        ]),
        uses: |m| matches!(m, ContactModel::Jkr(p) if p.dissipation.krijt_law().is_some()),
    },
    SubModel {
        name: "mindlin",
        source: include_str!("../../../shaders/model/jkr/mindlin.wgsl"),
        shared: &[],
        row: None,
        laws: &["jkr"],
        history: jkr::mindlin::HISTORY,
        role: Role::Apply("mindlin_apply"),
        uses: |m| matches!(m, ContactModel::Jkr(p) if p.friction > 0.0),
    },
    SubModel {
        name: "jkr_rolling",
        source: include_str!("../../../shaders/model/jkr/rolling.wgsl"),
        shared: &[],
        row: None,
        laws: &["jkr"],
        history: jkr::rolling::HISTORY,
        role: Role::Apply("jkr_rolling_apply"),
        uses: |m| matches!(m, ContactModel::Jkr(p) if p.rolling_hysteresis > 0.0),
    },
    SubModel {
        name: "luding_sliding",
        source: include_str!("../../../shaders/model/friction/sliding.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_sliding",
            wgsl_struct: CoulombSpringRow::WGSL_NAME,
            bytes: std::mem::size_of::<CoulombSpringRow>(),
            fill: |m| spring_block(luding_of(m).map(|l| l.sliding)),
        }),
        laws: &["hysteretic"],
        history: sliding::HISTORY,
        role: Role::Apply("luding_sliding_apply"),
        uses: |m| luding_of(m).is_some_and(|l| l.sliding.is_on()),
    },
    SubModel {
        name: "luding_rolling",
        source: include_str!("../../../shaders/model/friction/rolling.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_rolling",
            wgsl_struct: CoulombSpringRow::WGSL_NAME,
            bytes: std::mem::size_of::<CoulombSpringRow>(),
            fill: |m| spring_block(luding_of(m).map(|l| l.rolling)),
        }),
        laws: &["hysteretic"],
        history: rolling::HISTORY,
        role: Role::Apply("luding_rolling_apply"),
        uses: |m| luding_of(m).is_some_and(|l| l.rolling.is_on()),
    },
    SubModel {
        name: "luding_twisting",
        source: include_str!("../../../shaders/model/friction/twisting.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_twisting",
            wgsl_struct: TwistingRow::WGSL_NAME,
            bytes: std::mem::size_of::<TwistingRow>(),
            fill: |m| TwistingRow::new(m).map(|r| bytes(&r)),
        }),
        laws: &["hysteretic", "jkr"],
        history: twisting::HISTORY,
        role: Role::Apply("luding_twisting_apply"),
        uses: |m| TwistingRow::new(m).is_some(),
    },
];

/// Luding's Coulomb spring, shared by his sliding, rolling and twisting laws.
pub(super) const COULOMB: &str = include_str!("../../../shaders/model/friction/coulomb.wgsl");

/// Luding's sliding and rolling friction of a hysteretic/LSD pair (the JKR family has its
/// own, Mindlin and Dominik–Tielens).
pub(super) fn luding_of(m: &ContactModel) -> Option<&crate::model::LudingFriction> {
    match m {
        ContactModel::Hysteretic(p) => Some(&p.luding),
        ContactModel::Lsd(p) => Some(&p.luding),
        ContactModel::Jkr(_) => None,
    }
}

/// The block of a spring that acts.
pub(super) fn spring_block(s: Option<CoulombSpring>) -> Option<Vec<u8>> {
    s.filter(CoulombSpring::is_on)
        .map(|s| bytes(&CoulombSpringRow::new(&s)))
}

/// The normal law called `name`.
pub fn law(name: &str) -> Option<&'static NormalLaw> {
    LAWS.iter().find(|l| l.name == name)
}

/// The sub-model called `name`.
pub fn sub_model(name: &str) -> Option<&'static SubModel> {
    SUB_MODELS.iter().find(|s| s.name == name)
}

pub(super) fn bytes<T: bytemuck::Pod>(t: &T) -> Vec<u8> {
    bytemuck::bytes_of(t).to_vec()
}

/// The normal law a pair's model uses (the row block it fills).
pub(super) fn law_of(m: &ContactModel) -> usize {
    LAWS.iter()
        .position(|l| (l.row.fill)(m).is_some())
        .expect("every contact model has a GPU normal law")
}
