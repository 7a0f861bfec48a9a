//! The contact law of a scene's GPU step, composed from the sub-models its pairs use.
//!
//! A normal law (hysteretic/LSD, JKR/Hertz) or a sub-model attached to one (a dissipation,
//! a tangential, rolling or twisting law) is one WGSL file of `shaders/model/` (the folder mirrors `src/model/`), its per-contact
//! history fields (declared once, in its Rust module) and, here, how it plugs in. From the
//! set a scene uses come the pair-table row, the history layout (the stored struct, its
//! load and store, the partner's view, its size and the host's decoder) and the dispatch
//! `pair_contact` / `pair_edges` that `shaders/step/` calls. Nothing a scene does not
//! use is compiled in.

use super::layout::{CoulombSpringRow, HystereticPair, JkrPair, TwistingRow, WgslStruct};
use super::records::RecordLayout;
use super::shaders::{
    compose, ShaderVariant, JUMP, JUMP_OFF, LEDGER, LEDGER_OFF, OVERLAP, ROTATION,
    ROTATION_BUFFERS, ROTATION_MIRRORS, ROTATION_OFF, STATE_BUFFERS, STATE_MIRRORS, STEP,
};
use super::state::{Extras, StateLayout};
use crate::model::friction::{rolling, sliding, twisting};
use crate::model::history::{HistoryField, Mirror, Shape};
use crate::model::{hysteretic, jkr, krijt, ContactHistory, ContactModel, CoulombSpring};

mod interface;
mod registry;
#[cfg(test)]
mod tests;

use registry::law_of;
pub use registry::{law, sub_model, Hook, NormalLaw, Role, RowBlock, SubModel, LAWS, SUB_MODELS};

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

    /// The pair-row member holding byte `at` of a row, `block.field` (`tag` for the law's
    /// tag), for messages; `None` beyond the row.
    pub fn row_member_at(&self, at: usize) -> Option<String> {
        let mut start = if self.laws.len() > 1 { 4 } else { 0 };
        if at < start {
            return Some("tag".into());
        }
        for b in self.row_blocks() {
            if at < start + b.bytes {
                let block = (crate::gpu::layout::shared_structs().into_iter())
                    .find(|s| s.name == b.wgsl_struct)?;
                let (field, _) =
                    (block.members.iter()).rfind(|(_, offset)| *offset <= at - start)?;
                return Some(format!("{}.{field}", b.member));
            }
            start += b.bytes;
        }
        None
    }

    /// Bytes of one pair-table row.
    pub fn row_bytes(&self) -> usize {
        let tag = if self.laws.len() > 1 { 4 } else { 0 };
        tag + self.row_blocks().map(|b| b.bytes).sum::<usize>()
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
