//! The contact law of a scene's GPU step, composed from the sub-models its pairs use.
//!
//! A normal law (hysteretic/LSD, JKR/Hertz) or a sub-model attached to one (a dissipation,
//! a tangential, rolling or twisting law) is one WGSL file of `shaders/contact/`, its per-contact
//! history fields (declared once, in its Rust module) and, here, how it plugs in. From the
//! set a scene uses come the pair-table row, the history layout (the stored struct, its
//! load and store, the partner's view, its size and the host's decoder) and the dispatch
//! `pair_contact` / `pair_edges` that `shaders/step/` calls. Nothing a scene does not
//! use is compiled in.

use super::layout::{CoulombSpringRow, HystereticPair, JkrPair, TwistingRow};
use super::records::RecordLayout;
use super::shaders::{
    compose, ShaderVariant, JUMP, JUMP_OFF, LEDGER, LEDGER_OFF, OVERLAP, ROTATION,
    ROTATION_BUFFERS, ROTATION_MIRRORS, ROTATION_OFF, STATE_BUFFERS, STATE_MIRRORS, STEP,
};
use super::state::{Extras, StateLayout};
use crate::model::friction::{rolling, sliding, twisting};
use crate::model::history::{HistoryField, Mirror, Shape};
use crate::model::{hysteretic, jkr, krijt, ContactHistory, ContactModel, CoulombSpring};

/// What a step variant keeps beyond the forces: the energy ledger (`shaders/ledger.wgsl`),
/// the impulses of force jumps inside the step (`shaders/jump.wgsl`) and the contact
/// network output. Each needs each contact as the last step left it (the entries' `prior`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Keeps {
    /// The energy ledger and contact statistics.
    pub ledger: bool,
    /// The force jumps' impulses (the scene's `jump_impulses`).
    pub jumps: bool,
    /// The priors for the contact network output where neither of the others keeps them
    /// ([`Self::new`] sets it only then, so equal layouts have one name).
    pub contacts: bool,
}

impl Keeps {
    /// Every distinct combination, for the tests that compile each variant.
    pub const ALL: [Keeps; 5] = [
        Keeps::new(false, false, false),
        Keeps::new(true, false, false),
        Keeps::new(false, true, false),
        Keeps::new(true, true, false),
        Keeps::new(false, false, true),
    ];

    /// What a run keeps: the ledger, the force jumps, the contact network output.
    pub const fn new(ledger: bool, jumps: bool, contacts: bool) -> Self {
        Self {
            ledger,
            jumps,
            contacts: contacts && !ledger && !jumps,
        }
    }

    /// Whether each contact's state at the end of the last step is kept.
    pub fn prior(&self) -> bool {
        self.ledger || self.jumps || self.contacts
    }
}

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
        source: include_str!("../../shaders/contact/hysteretic.wgsl"),
        row: RowBlock {
            member: "hysteretic",
            wgsl_struct: "HystereticPair",
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
        source: include_str!("../../shaders/contact/jkr.wgsl"),
        row: RowBlock {
            member: "jkr",
            wgsl_struct: "JkrPair",
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
        source: include_str!("../../shaders/contact/krijt.wgsl"),
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
        source: include_str!("../../shaders/contact/mindlin.wgsl"),
        shared: &[],
        row: None,
        laws: &["jkr"],
        history: jkr::mindlin::HISTORY,
        role: Role::Apply("mindlin_apply"),
        uses: |m| matches!(m, ContactModel::Jkr(p) if p.friction > 0.0),
    },
    SubModel {
        name: "jkr_rolling",
        source: include_str!("../../shaders/contact/jkr_rolling.wgsl"),
        shared: &[],
        row: None,
        laws: &["jkr"],
        history: jkr::rolling::HISTORY,
        role: Role::Apply("jkr_rolling_apply"),
        uses: |m| matches!(m, ContactModel::Jkr(p) if p.rolling_hysteresis > 0.0),
    },
    SubModel {
        name: "luding_sliding",
        source: include_str!("../../shaders/contact/luding_sliding.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_sliding",
            wgsl_struct: "CoulombSpring",
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
        source: include_str!("../../shaders/contact/luding_rolling.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_rolling",
            wgsl_struct: "CoulombSpring",
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
        source: include_str!("../../shaders/contact/luding_twisting.wgsl"),
        shared: &[COULOMB],
        row: Some(RowBlock {
            member: "luding_twisting",
            wgsl_struct: "TwistingRow",
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
const COULOMB: &str = include_str!("../../shaders/contact/coulomb.wgsl");

/// Luding's sliding and rolling friction of a hysteretic/LSD pair (the JKR family has its
/// own, Mindlin and Dominik–Tielens).
fn luding_of(m: &ContactModel) -> Option<&crate::model::LudingFriction> {
    match m {
        ContactModel::Hysteretic(p) => Some(&p.luding),
        ContactModel::Lsd(p) => Some(&p.luding),
        ContactModel::Jkr(_) => None,
    }
}

/// The block of a spring that acts.
fn spring_block(s: Option<CoulombSpring>) -> Option<Vec<u8>> {
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

fn bytes<T: bytemuck::Pod>(t: &T) -> Vec<u8> {
    bytemuck::bytes_of(t).to_vec()
}

/// The normal law a pair's model uses (the row block it fills).
fn law_of(m: &ContactModel) -> usize {
    LAWS.iter()
        .position(|l| (l.row.fill)(m).is_some())
        .expect("every contact model has a GPU normal law")
}

/// The sub-models of one scene's step: indices into [`LAWS`] and [`SUB_MODELS`], in
/// their order.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Composition {
    laws: Vec<usize>,
    subs: Vec<usize>,
}

impl Composition {
    /// What the pair models of a scene use.
    pub fn of(models: &[ContactModel]) -> Self {
        let laws = (0..LAWS.len())
            .filter(|&l| models.iter().any(|m| law_of(m) == l))
            .collect();
        let subs = (0..SUB_MODELS.len())
            .filter(|&s| models.iter().any(|m| (SUB_MODELS[s].uses)(m)))
            .collect();
        Self { laws, subs }
    }

    /// Every composition a scene can produce: each non-empty set of normal laws with each
    /// set of the sub-models attached to them.
    pub fn all() -> Vec<Self> {
        let mut out = Vec::new();
        for law_set in 1u32..(1 << LAWS.len()) {
            let laws: Vec<usize> = (0..LAWS.len())
                .filter(|l| law_set & (1 << l) != 0)
                .collect();
            let attachable: Vec<usize> = (0..SUB_MODELS.len())
                .filter(|&s| {
                    SUB_MODELS[s]
                        .laws
                        .iter()
                        .any(|name| laws.iter().any(|&l| LAWS[l].name == *name))
                })
                .collect();
            for sub_set in 0u32..(1 << attachable.len()) {
                let subs = (0..attachable.len())
                    .filter(|i| sub_set & (1 << i) != 0)
                    .map(|i| attachable[i])
                    .collect();
                out.push(Self {
                    laws: laws.clone(),
                    subs,
                });
            }
        }
        out
    }

    fn laws(&self) -> impl Iterator<Item = &'static NormalLaw> + '_ {
        self.laws.iter().map(|&l| &LAWS[l])
    }

    fn subs(&self) -> impl Iterator<Item = &'static SubModel> + '_ {
        self.subs.iter().map(|&s| &SUB_MODELS[s])
    }

    /// The step's name: `step_` and the laws and sub-models joined by `+`.
    pub fn name(&self) -> String {
        let parts: Vec<&str> = self
            .laws()
            .map(|l| l.name)
            .chain(self.subs().map(|s| s.name))
            .collect();
        format!("step_{}", parts.join("+"))
    }

    /// The name of the variant with or without the energy ledger (`_ledger` appended) and
    /// the force jumps (`_jumps`), reading the state from buffers or from texture mirrors
    /// (`_mirrors` appended), the lists' entries in one buffer or in pages (`_paged`,
    /// `gpu::pages`).
    pub fn variant_name(&self, keeps: Keeps, mirrors: bool, paged: bool) -> String {
        let ledger = if keeps.ledger { "_ledger" } else { "" };
        let jumps = if keeps.jumps { "_jumps" } else { "" };
        let contacts = if keeps.contacts { "_contacts" } else { "" };
        let mirrors = if mirrors { "_mirrors" } else { "" };
        let paged = if paged { "_paged" } else { "" };
        format!("{}{ledger}{jumps}{contacts}{mirrors}{paged}", self.name())
    }

    /// Whether particles carry angular velocity: some sub-model exerts tangential forces
    /// or torques.
    pub fn rotation(&self) -> bool {
        self.subs().any(|s| matches!(s.role, Role::Apply(_)))
    }

    /// Whether some pair keeps the contact radius as state (the Krijt dissipations).
    pub fn krijt(&self) -> bool {
        self.subs().any(|s| s.name == "krijt")
    }

    /// The stored history fields: the laws' and the sub-models', each name once (sub-models
    /// that keep the same quantity share it: a pair uses one of them).
    pub fn history(&self) -> Vec<&'static HistoryField> {
        let mut out: Vec<&'static HistoryField> = Vec::new();
        let all = self
            .laws()
            .flat_map(|l| l.history)
            .chain(self.subs().flat_map(|s| s.history));
        for f in all {
            if !out.iter().any(|g| g.name == f.name) {
                out.push(f);
            }
        }
        out
    }

    /// The step's name, its pair-row bytes and its history fields in order: what a saved
    /// GPU state must match to be restored.
    pub fn layout(&self) -> String {
        let fields: Vec<String> = self
            .history()
            .iter()
            .map(|f| format!("{}:{:?}", f.name, f.shape))
            .collect();
        format!(
            "{}, row {} B, history [{}]",
            self.name(),
            self.row_bytes(),
            fields.join(", ")
        )
    }

    /// Bytes of one contact's stored history (`Hist`: f32 words, no padding).
    pub fn history_bytes(&self) -> u64 {
        4 * self.history().iter().map(|f| f.words()).sum::<usize>() as u64
    }

    /// Decodes one stored history into the f64 reference's form.
    pub fn decode_history(&self, b: &[u8]) -> ContactHistory {
        let words: Vec<f32> = bytemuck::pod_collect_to_vec(b);
        let mut h = ContactHistory::default();
        let mut at = 0;
        for f in self.history() {
            f.decode(&words[at..at + f.words()], &mut h);
            at += f.words();
        }
        h
    }

    /// `h` as the partner of the pair sees it.
    pub fn mirror_history(&self, mut h: ContactHistory) -> ContactHistory {
        for f in self.history() {
            f.mirror_host(&mut h);
        }
        h
    }

    /// One pair-table row of a pair's model: the law tag (where the scene has several
    /// laws), then each law's block (zero where the pair does not use it).
    pub fn pair_row(&self, m: &ContactModel) -> Vec<u8> {
        let mut row = Vec::with_capacity(self.row_bytes());
        if self.laws.len() > 1 {
            let tag = self.laws.iter().position(|&l| l == law_of(m)).unwrap_or(0) as u32;
            row.extend_from_slice(&tag.to_le_bytes());
        }
        for block in self.row_blocks() {
            match (block.fill)(m) {
                Some(b) => row.extend_from_slice(&b),
                None => row.resize(row.len() + block.bytes, 0),
            }
        }
        row
    }

    /// The blocks of the pair row after the tag: the laws', then the sub-models' that have one.
    fn row_blocks(&self) -> impl Iterator<Item = &'static RowBlock> + '_ {
        self.laws()
            .map(|l| &l.row)
            .chain(self.subs().filter_map(|s| s.row.as_ref()))
    }

    /// Bytes of one pair-table row.
    pub fn row_bytes(&self) -> usize {
        let tag = if self.laws.len() > 1 { 4 } else { 0 };
        tag + self.row_blocks().map(|b| b.bytes).sum::<usize>()
    }

    /// The generated WGSL: the pair row, the history layout, the laws' hooks and the
    /// dispatch the step calls.
    pub fn interface(&self) -> String {
        let mut w = String::new();
        w.push_str(&format!(
            "// Generated by gpu::composition for {}.\n\n",
            self.name()
        ));
        // the pair row
        w.push_str("struct PairRow {\n");
        if self.laws.len() > 1 {
            w.push_str("    law: u32,\n");
        }
        for block in self.row_blocks() {
            w.push_str(&format!("    {}: {},\n", block.member, block.wgsl_struct));
        }
        w.push_str("}\n\n");
        // the stored history (f32 words) and the working one
        let fields = self.history();
        w.push_str("struct Hist {\n");
        for f in &fields {
            match f.shape {
                Shape::Word | Shape::Flag => w.push_str(&format!("    {}: f32,\n", f.name)),
                Shape::Vec3 => {
                    for c in ["x", "y", "z"] {
                        w.push_str(&format!("    {}_{c}: f32,\n", f.name));
                    }
                }
            }
        }
        w.push_str("}\n\nstruct History {\n");
        for f in &fields {
            let ty = match f.shape {
                Shape::Word => "f32",
                Shape::Flag => "bool",
                Shape::Vec3 => "vec3<f32>",
            };
            w.push_str(&format!("    // {}\n    {}: {ty},\n", f.doc, f.name));
        }
        w.push_str("}\n\n");
        let load: Vec<String> = fields
            .iter()
            .map(|f| match f.shape {
                Shape::Word => format!("h.{}", f.name),
                Shape::Flag => format!("h.{} != 0.0", f.name),
                Shape::Vec3 => format!("vec3<f32>(h.{0}_x, h.{0}_y, h.{0}_z)", f.name),
            })
            .collect();
        w.push_str(&format!(
            "fn hist_load(h: Hist) -> History {{\n    return History({});\n}}\n\n",
            load.join(", ")
        ));
        let words = |f: &HistoryField, value: &dyn Fn(&str) -> String| -> Vec<String> {
            match f.shape {
                Shape::Word => vec![value(&format!("h.{}", f.name))],
                Shape::Flag => vec![format!("select(0.0, 1.0, h.{})", f.name)],
                Shape::Vec3 => ["x", "y", "z"]
                    .iter()
                    .map(|c| value(&format!("h.{}.{c}", f.name)))
                    .collect(),
            }
        };
        let store: Vec<String> = fields
            .iter()
            .flat_map(|f| words(f, &|v| v.to_string()))
            .collect();
        w.push_str(&format!(
            "fn hist_store(h: History) -> Hist {{\n    return Hist({});\n}}\n\n",
            store.join(", ")
        ));
        let n_words: usize = fields.iter().map(|f| f.words()).sum();
        w.push_str(&format!(
            "fn hist_zero() -> Hist {{\n    return Hist({});\n}}\n\n",
            vec!["0.0"; n_words].join(", ")
        ));
        // bitwise: a packed word's sign bit is information
        let same: Vec<String> = fields
            .iter()
            .flat_map(|f| match f.shape {
                Shape::Vec3 => ["x", "y", "z"]
                    .iter()
                    .map(|c| format!("{}_{c}", f.name))
                    .collect(),
                _ => vec![f.name.to_string()],
            })
            .map(|m| format!("bitcast<u32>(a.{m}) == bitcast<u32>(b.{m})"))
            .collect();
        w.push_str(&format!(
            "// Whether two stored histories are the same, bitwise (the step stores one only where it\n// changed).\nfn hist_same(a: Hist, b: Hist) -> bool {{\n    return {};\n}}\n\n",
            same.join("\n        && ")
        ));
        let mirrored: Vec<String> = fields
            .iter()
            .flat_map(|f| match f.shape {
                Shape::Vec3 => ["x", "y", "z"]
                    .iter()
                    .map(|c| (format!("{}_{c}", f.name), f.mirror))
                    .collect(),
                _ => vec![(f.name.to_string(), f.mirror)],
            })
            .map(|(m, mirror)| match mirror {
                Mirror::Same => format!("h.{m}"),
                Mirror::Negate => format!("-h.{m}"),
            })
            .collect();
        w.push_str(&format!(
            "// The history seen from the partner's side (a re-sort that makes the partner the pair's\n// evaluator hands it over with this).\nfn hist_mirror(h: Hist) -> Hist {{\n    return Hist({});\n}}\n\n",
            mirrored.join(", ")
        ));
        // the laws' hooks, answered by the sub-models present
        for l in self.laws() {
            for hook in l.hooks {
                let name = hook_name(hook.signature);
                w.push_str(&format!("{} {{\n", hook.signature));
                for s in self.subs() {
                    if let Role::Hooks(answers) = s.role {
                        for (_, branch) in answers.iter().filter(|(h, _)| *h == name) {
                            w.push_str(&format!("    {branch}\n"));
                        }
                    }
                }
                w.push_str(&format!("    {}\n}}\n\n", hook.default));
            }
        }
        // one contact per law: normal force, then the sub-models acting in contact; the
        // fields of everything but the law are cleared out of contact
        for l in self.laws() {
            let own: Vec<&str> = l.history.iter().map(|f| f.name).collect();
            w.push_str(&format!(
                "fn contact_{0}(p: PairRow, k: Kin, h: ptr<function, History>) -> Contact {{\n    let nf = {1}(p.{0}, k, h);\n    var c = Contact(nf.force, vec3<f32>(0.0), vec3<f32>(0.0), nf.potential, nf.engaged, false);\n",
                l.row.member, l.normal
            ));
            let applies: Vec<&str> = self
                .subs()
                .filter(|s| s.laws.contains(&l.name))
                .filter_map(|s| match s.role {
                    Role::Apply(f) => Some(f),
                    Role::Hooks(_) => None,
                })
                .collect();
            let cleared: Vec<&HistoryField> = fields
                .iter()
                .copied()
                .filter(|f| !own.contains(&f.name))
                .collect();
            if !applies.is_empty() || !cleared.is_empty() {
                w.push_str("    if (nf.in_contact) {\n");
                for f in &applies {
                    w.push_str(&format!("        {f}(p, k, nf, h, &c);\n"));
                }
                w.push_str("    } else {\n");
                for f in &cleared {
                    let zero = match f.shape {
                        Shape::Word => "0.0",
                        Shape::Flag => "false",
                        Shape::Vec3 => "vec3<f32>(0.0)",
                    };
                    w.push_str(&format!("        (*h).{} = {zero};\n", f.name));
                }
                w.push_str("    }\n");
            }
            w.push_str("    return c;\n}\n\n");
        }
        // the step's entry points into the law
        w.push_str("fn pair_contact(p: PairRow, k: Kin, hist: ptr<function, Hist>) -> Contact {\n    var h = hist_load(*hist);\n    var c: Contact;\n");
        self.dispatch(&mut w, &|l| {
            format!("c = contact_{}(p, k, &h);", l.row.member)
        });
        w.push_str("    *hist = hist_store(h);\n    return c;\n}\n\n");
        w.push_str("fn pair_edges(p: PairRow, k: Kin) -> vec4<f32> {\n    var e: vec4<f32>;\n");
        self.dispatch(&mut w, &|l| {
            format!("e = {}(p.{}, k);", l.edges, l.row.member)
        });
        w.push_str("    return e;\n}\n\n");
        w.push_str("fn pair_touch_jump(p: PairRow, k: Kin) -> f32 {\n    var t: f32;\n");
        self.dispatch(&mut w, &|l| {
            format!("t = {}(p.{}, k);", l.touch_jump, l.row.member)
        });
        w.push_str("    return t;\n}\n");
        w
    }

    /// `call` of the pair's law: directly with one law, on the row's tag with several.
    fn dispatch(&self, w: &mut String, call: &dyn Fn(&NormalLaw) -> String) {
        if self.laws.len() == 1 {
            w.push_str(&format!("    {}\n", call(&LAWS[self.laws[0]])));
            return;
        }
        w.push_str("    switch p.law {\n");
        for (tag, l) in self.laws().enumerate() {
            let label = if tag + 1 == self.laws.len() {
                "default".to_string()
            } else {
                format!("case {tag}u")
            };
            w.push_str(&format!("        {label}: {{ {} }}\n", call(l)));
        }
        w.push_str("    }\n");
    }

    /// The f32 members of `struct Hist` (the stored history), in order.
    pub fn hist_members(&self) -> Vec<String> {
        self.history()
            .iter()
            .flat_map(|f| match f.shape {
                Shape::Word | Shape::Flag => vec![f.name.to_string()],
                Shape::Vec3 => ["x", "y", "z"]
                    .iter()
                    .map(|c| format!("{}_{c}", f.name))
                    .collect(),
            })
            .collect()
    }

    /// What the particle state holds beyond every run's fields (`gpu::state`): the
    /// angular fields where particles rotate, the ledger's rows where the variant keeps it.
    pub fn state_extras(&self, keeps: Keeps) -> Extras {
        Extras {
            rotation: self.rotation(),
            ledger: keeps.ledger,
        }
    }

    /// The records of the lists' entries and a rebuild's new lists (`gpu::records`) for
    /// this composition, with what the variant keeps.
    pub fn records(&self, keeps: Keeps) -> [RecordLayout; 2] {
        let hist = self.hist_members();
        let entries = RecordLayout::entries(&hist, self.rotation(), keeps);
        let new = RecordLayout::new_entries(&hist, keeps, &entries);
        [entries, new]
    }

    /// The step's module: common, the state's accessors (`gpu::state`), the records'
    /// (`gpu::records`), the laws' and
    /// sub-models' files, the generated interface,
    /// the rotation and ledger hooks, the state's reads (its buffers, or texture mirrors:
    /// the software adapter's path, `gpu::mirror`), the step.
    pub fn variant(&self, keeps: Keeps, mirrors: bool, paged: bool) -> ShaderVariant {
        let interface = self.interface();
        let state = StateLayout::wgsl(self.state_extras(keeps), paged);
        let records: Vec<String> = self.records(keeps).iter().map(|r| r.wgsl(paged)).collect();
        let mut parts: Vec<&str> = vec![&state];
        parts.extend(records.iter().map(String::as_str));
        parts.extend(self.laws().map(|l| l.source));
        for s in self.subs() {
            for shared in s.shared {
                if !parts.contains(shared) {
                    parts.push(shared);
                }
            }
            parts.push(s.source);
        }
        parts.push(OVERLAP);
        parts.push(&interface);
        parts.push(if self.rotation() {
            ROTATION
        } else {
            ROTATION_OFF
        });
        parts.push(if keeps.ledger { LEDGER } else { LEDGER_OFF });
        parts.push(if keeps.jumps { JUMP } else { JUMP_OFF });
        parts.push(if mirrors {
            STATE_MIRRORS
        } else {
            STATE_BUFFERS
        });
        if self.rotation() {
            parts.push(if mirrors {
                ROTATION_MIRRORS
            } else {
                ROTATION_BUFFERS
            });
        }
        ShaderVariant {
            name: self.variant_name(keeps, mirrors, paged),
            source: compose(&STEP, &parts),
        }
    }
}

/// The function name of a WGSL signature `fn name(...`.
fn hook_name(signature: &str) -> &str {
    let rest = signature.trim_start_matches("fn ").trim_start();
    &rest[..rest.find('(').unwrap_or(rest.len())]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::history::HostField;
    use crate::model::{Dissipation, JkrParams, LsdParams, Pulloff};
    use glam::DVec3;

    fn jkr(friction: f64, rolling: f64, dissipation: Dissipation) -> ContactModel {
        ContactModel::Jkr(JkrParams {
            youngs: 1e8,
            poisson: 0.3,
            surface_energy: 0.1,
            dissipation,
            friction,
            rolling_hysteresis: rolling,
            pulloff: Pulloff::Displacement,
            stiffness_scale: 1.0,
            luding: Default::default(),
        })
    }

    fn lsd() -> ContactModel {
        ContactModel::Lsd(LsdParams {
            k: 1.0,
            gamma0: 0.0,
            luding: Default::default(),
        })
    }

    #[test]
    fn a_scene_composes_only_what_its_pairs_use() {
        let c = Composition::of(&[lsd()]);
        assert_eq!(c.name(), "step_hysteretic");
        assert!(!c.rotation());
        assert_eq!(c.history_bytes(), 4);
        let c = Composition::of(&[jkr(0.3, 0.0, Dissipation::None), lsd()]);
        assert_eq!(c.name(), "step_hysteretic+jkr+mindlin");
        assert!(c.rotation());
        // delta_max word, touched flag, spring
        assert_eq!(c.history_bytes(), 4 * (1 + 1 + 3));
        let krijt = Dissipation::Krijt {
            tvis: 1e-6,
            sigma0: 0.0,
        };
        let c = Composition::of(&[jkr(0.0, 0.5, krijt), jkr(0.0, 0.0, Dissipation::None)]);
        assert_eq!(c.name(), "step_jkr+krijt+jkr_rolling");
        assert!(!c.interface().contains("mindlin_apply"));
        assert!(!c
            .variant(Keeps::default(), false, false)
            .source
            .contains("fn mindlin_apply"));
    }

    #[test]
    fn the_host_decodes_and_mirrors_the_declared_layout() {
        let c = Composition::of(&[lsd(), jkr(0.3, 0.5, Dissipation::None)]);
        // hyst_state (touched, delta_max 2), touched, spring, xi
        let words: [f32; 8] = [-2.0, 1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let h = c.decode_history(bytemuck::cast_slice(&words));
        assert_eq!(h.delta_max, 2.0);
        assert!(h.touched);
        assert_eq!(h.tangential, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(h.rolling, DVec3::new(4.0, 5.0, 6.0));
        let m = c.mirror_history(h);
        assert_eq!(m.tangential, -h.tangential);
        assert_eq!(m.rolling, h.rolling);
        assert_eq!(m.delta_max, h.delta_max);
    }

    /// Each sub-model's WGSL works with the history fields its Rust module declares, and
    /// with no field it does not declare (through `History`).
    #[test]
    fn every_declared_history_field_is_the_one_its_wgsl_uses() {
        let declared: Vec<(&str, &[HistoryField])> = LAWS
            .iter()
            .map(|l| (l.source, l.history))
            .chain(SUB_MODELS.iter().map(|s| (s.source, s.history)))
            .collect();
        let all: Vec<&str> = declared
            .iter()
            .flat_map(|(_, h)| h.iter().map(|f| f.name))
            .collect();
        for (source, fields) in &declared {
            for f in fields.iter() {
                assert!(
                    source.contains(&format!("(*h).{}", f.name)),
                    "{} not used by its WGSL",
                    f.name
                );
            }
            for name in &all {
                if !fields.iter().any(|f| f.name == *name) {
                    assert!(
                        !source.contains(&format!("(*h).{name}")),
                        "a WGSL file uses {name}, which it does not declare"
                    );
                }
            }
        }
        // the host maps each field somewhere
        assert!(declared
            .iter()
            .flat_map(|(_, h)| h.iter())
            .all(|f| f.host != HostField::DeltaMaxTouched || f.shape == Shape::Word));
    }

    /// Sub-models that keep the same quantity share its field (a pair uses one of them), so
    /// their declarations must agree on everything but the comment.
    #[test]
    fn fields_that_share_a_name_agree() {
        let all: Vec<&HistoryField> = LAWS
            .iter()
            .flat_map(|l| l.history)
            .chain(SUB_MODELS.iter().flat_map(|s| s.history))
            .collect();
        for a in &all {
            for b in all.iter().filter(|b| b.name == a.name) {
                assert_eq!(
                    (a.shape, a.mirror, a.host),
                    (b.shape, b.mirror, b.host),
                    "{}",
                    a.name
                );
            }
        }
    }

    /// Luding's three laws on the hysteretic law: their blocks follow the law's in the row
    /// (a pair without one has it zero, which is off), their springs in the history.
    #[test]
    fn luding_friction_adds_its_blocks_and_springs() {
        use crate::model::{CoulombSpring, LudingFriction};
        let spring = |mu: f64| CoulombSpring {
            mu_s: mu,
            mu_d: mu,
            k: 2.0,
            gamma: 0.0,
        };
        let rough = |rolling: f64| {
            ContactModel::Lsd(LsdParams {
                luding: LudingFriction {
                    sliding: spring(0.5),
                    rolling: spring(rolling),
                    twisting: spring(0.1),
                },
                ..LsdParams::new(1.0, 0.0)
            })
        };
        let c = Composition::of(&[rough(0.1), rough(0.0)]);
        assert_eq!(
            c.name(),
            "step_hysteretic+luding_sliding+luding_rolling+luding_twisting"
        );
        assert!(c.rotation());
        // hyst_state, spring, xi, twist
        assert_eq!(c.history_bytes(), 4 * (1 + 3 + 3 + 1));
        let hyst = std::mem::size_of::<HystereticPair>();
        assert_eq!(c.row_bytes(), hyst + 16 + 16 + 20);
        let row = c.pair_row(&rough(0.0));
        let rolling: &[f32] = bytemuck::cast_slice(&row[hyst + 16..hyst + 32]);
        assert_eq!(rolling, &[0.0; 4]);
        let sliding: &[f32] = bytemuck::cast_slice(&row[hyst..hyst + 16]);
        assert_eq!(sliding, &[0.5, 0.5, 2.0, 0.0]);
        let words: [f32; 8] = [1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -7.0];
        let h = c.decode_history(bytemuck::cast_slice(&words));
        assert_eq!(h.twist, -7.0);
        let m = c.mirror_history(h);
        assert_eq!(
            (m.tangential, m.rolling, m.twist),
            (-h.tangential, h.rolling, h.twist)
        );
        // JKR twisting: the stiffness per contact radius where k_o is not given
        let mut j = jkr(0.0, 0.0, Dissipation::None);
        if let ContactModel::Jkr(p) = &mut j {
            p.luding.twisting = CoulombSpring {
                k: 0.0,
                ..spring(0.1)
            };
        }
        let c = Composition::of(&[j]);
        assert_eq!(c.name(), "step_jkr+luding_twisting");
        let row = c.pair_row(&j);
        let twisting: &[f32] = bytemuck::cast_slice(&row[row.len() - 20..]);
        let ContactModel::Jkr(p) = j else {
            unreachable!()
        };
        assert_eq!(twisting[4], (0.4 * 8.0 * p.g_star()) as f32);
    }

    #[test]
    fn pair_rows_have_the_declared_size() {
        let models = [lsd(), jkr(0.3, 0.5, Dissipation::tsuji(0.5))];
        for c in Composition::all() {
            for m in &models {
                if c.laws.contains(&law_of(m)) {
                    assert_eq!(c.pair_row(m).len(), c.row_bytes(), "{}", c.name());
                }
            }
        }
        let c = Composition::of(&models);
        let row = c.pair_row(&models[1]);
        assert_eq!(&row[..4], &1u32.to_le_bytes(), "the JKR law's tag");
    }
}
