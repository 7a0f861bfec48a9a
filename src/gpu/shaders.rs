//! WGSL sources of the GPU engine, their composition into shader modules, and their
//! validation with naga (no GPU needed).
//!
//! Every module is `shaders/common.wgsl` (shared structs, constants and helpers)
//! followed by optional snippets (feature switches, e.g. `const MODEL: u32 = 2u;`)
//! followed by one stage file (`shaders/grid.wgsl`, ...). A [`ShaderVariant`] is one such
//! composition under a name; [`all_variants`] lists every variant the engine builds, and
//! the unit test validates each of them with naga's WGSL front end and validator, so a
//! broken kernel fails `cargo test` on any machine.
//!
//! Adding a stage (the force kernels, one variant per contact model) means adding a
//! `shaders/<stage>.wgsl` file and an entry in [`STAGES`], or entries built with
//! [`compose`] and per-model snippets in [`all_variants`]; run-time switches that need
//! no recompilation of the WGSL text can use WGSL `override` constants instead, set
//! through `wgpu::PipelineCompilationOptions::constants` when the pipelines are built.
//!
//! Validation uses [`naga::valid::Capabilities::empty`]: only core WGSL passes (no f64,
//! no 64-bit integers, no float atomics, no subgroups, no push constants), so whatever
//! validates here runs on every backend and adapter wgpu supports.

/// Shared declarations, prepended to every stage.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");
/// The counting sort of particles by cell (see `shaders/grid.wgsl`).
pub const GRID: &str = include_str!("../../shaders/grid.wgsl");
/// The hysteretic and LSD force laws in f32 (a snippet of the step).
pub const MODEL_HYSTERETIC: &str = include_str!("../../shaders/model_hysteretic.wgsl");
/// The JKR family (JKR, Hertz) in f32 (a snippet of the step; needs a history layout).
pub const MODEL_JKR: &str = include_str!("../../shaders/model_jkr.wgsl");
/// The Krijt contact-radius dynamics (the `krijt` and `stress` dissipations of the JKR
/// family; a snippet of the step for scenes that use them, with a history that stores a).
pub const MODEL_KRIJT: &str = include_str!("../../shaders/model_krijt.wgsl");
/// The Krijt hooks as no-ops (a snippet of the JKR steps without a stored contact radius).
pub const MODEL_KRIJT_OFF: &str = include_str!("../../shaders/model_krijt_off.wgsl");
/// Angular velocity and torques (a snippet of the step for scenes that rotate).
pub const ROTATION: &str = include_str!("../../shaders/rotation.wgsl");
/// The rotation hooks as no-ops (a snippet of the step for scenes that do not rotate).
pub const ROTATION_OFF: &str = include_str!("../../shaders/rotation_off.wgsl");
/// The energy ledger and contact statistics (a snippet of the step, when a run wants them).
pub const LEDGER: &str = include_str!("../../shaders/ledger.wgsl");
/// The ledger hooks as no-ops (a snippet of the step for runs without the ledger).
pub const LEDGER_OFF: &str = include_str!("../../shaders/ledger_off.wgsl");
/// One time step: drift, (on a rebuild: gather, neighbours, history remap, copy back),
/// forces, kick.
pub const STEP: &str = include_str!("../../shaders/step.wgsl");

/// JKR history layout without friction or rolling: only the "touched" flag (4 bytes).
pub const JKR_HISTORY_TOUCHED: &str = "\
// JKR history layout: the touched flag only (no friction, no rolling in this scene).
const JKR_TANGENTIAL: bool = false;
const JKR_ROLLING: bool = false;
alias Hist = f32;
fn hist_zero() -> Hist { return 0.0; }
fn hist_same(a: Hist, b: Hist) -> bool { return a == b; }
fn jkr_unpack(h: Hist) -> JkrHistory { return JkrHistory(h != 0.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0); }
fn jkr_pack(h: JkrHistory) -> Hist { return select(0.0, 1.0, h.touched); }
";

/// JKR history layout of the Krijt dissipations without friction or rolling: the touched
/// flag (x) and the contact radius a (y) (8 bytes).
pub const JKR_HISTORY_TOUCHED_RADIUS: &str = "\
// JKR history layout: touched (x) and the Krijt contact radius (y); no friction, no rolling.
const JKR_TANGENTIAL: bool = false;
const JKR_ROLLING: bool = false;
alias Hist = vec2<f32>;
fn hist_zero() -> Hist { return vec2<f32>(0.0); }
fn hist_same(a: Hist, b: Hist) -> bool { return all(a == b); }
fn jkr_unpack(h: Hist) -> JkrHistory { return JkrHistory(h.x != 0.0, vec3<f32>(0.0), vec3<f32>(0.0), h.y); }
fn jkr_pack(h: JkrHistory) -> Hist { return vec2<f32>(select(0.0, 1.0, h.touched), h.a); }
";

/// JKR history layout with the tangential spring: xyz = spring, w = touched (16 bytes).
pub const JKR_HISTORY_TANGENTIAL: &str = "\
// JKR history layout: tangential spring (xyz) and touched (w); no rolling in this scene.
const JKR_TANGENTIAL: bool = true;
const JKR_ROLLING: bool = false;
alias Hist = vec4<f32>;
fn hist_zero() -> Hist { return vec4<f32>(0.0); }
fn hist_same(a: Hist, b: Hist) -> bool { return all(a == b); }
fn jkr_unpack(h: Hist) -> JkrHistory { return JkrHistory(h.w != 0.0, h.xyz, vec3<f32>(0.0), 0.0); }
fn jkr_pack(h: JkrHistory) -> Hist { return vec4<f32>(h.spring, select(0.0, 1.0, h.touched)); }
";

/// JKR history layout of the Krijt dissipations with the tangential spring: spring, touched
/// and the contact radius as five f32 (20 bytes; scalars, so no padding to 32).
pub const JKR_HISTORY_TANGENTIAL_RADIUS: &str = "\
// JKR history layout: tangential spring, touched and the Krijt contact radius; no rolling.
const JKR_TANGENTIAL: bool = true;
const JKR_ROLLING: bool = false;
struct JkrStoredSpring {
    sx: f32,
    sy: f32,
    sz: f32,
    touched: f32,
    a: f32,
}
alias Hist = JkrStoredSpring;
fn hist_zero() -> Hist { return JkrStoredSpring(0.0, 0.0, 0.0, 0.0, 0.0); }
fn hist_same(a: Hist, b: Hist) -> bool {
    return a.sx == b.sx && a.sy == b.sy && a.sz == b.sz && a.touched == b.touched && a.a == b.a;
}
fn jkr_unpack(h: Hist) -> JkrHistory {
    return JkrHistory(h.touched != 0.0, vec3<f32>(h.sx, h.sy, h.sz), vec3<f32>(0.0), h.a);
}
fn jkr_pack(h: JkrHistory) -> Hist {
    return JkrStoredSpring(h.spring.x, h.spring.y, h.spring.z, select(0.0, 1.0, h.touched), h.a);
}
";

/// JKR history layout with the tangential spring and the rolling displacement (32 bytes);
/// the Krijt contact radius fills the padding (xi.w; 0 without the Krijt dissipations).
pub const JKR_HISTORY_ROLLING: &str = "\
// JKR history layout: tangential spring (spring.xyz), touched (spring.w), rolling
// displacement (xi.xyz), Krijt contact radius (xi.w).
const JKR_TANGENTIAL: bool = true;
const JKR_ROLLING: bool = true;
struct JkrStored {
    spring: vec4<f32>,
    xi: vec4<f32>,
}
alias Hist = JkrStored;
fn hist_zero() -> Hist { return JkrStored(vec4<f32>(0.0), vec4<f32>(0.0)); }
fn hist_same(a: Hist, b: Hist) -> bool { return all(a.spring == b.spring) && all(a.xi == b.xi); }
fn jkr_unpack(h: Hist) -> JkrHistory { return JkrHistory(h.spring.w != 0.0, h.spring.xyz, h.xi.xyz, h.xi.w); }
fn jkr_pack(h: JkrHistory) -> Hist {
    return JkrStored(vec4<f32>(h.spring, select(0.0, 1.0, h.touched)), vec4<f32>(h.xi, h.a));
}
";

/// Which step a scene runs: the model family and what its contacts need stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepKind {
    /// Hysteretic and LSD pairs: normal force with (δmax, touched) history, no rotation.
    Hysteretic,
    /// JKR/Hertz without friction or rolling resistance: the touched flag, no rotation.
    Jkr,
    /// JKR/Hertz with friction (no rolling resistance): the tangential spring, rotation.
    JkrFriction,
    /// JKR/Hertz with rolling resistance (and friction): spring and ξ, rotation.
    JkrRolling,
    /// [`Self::Jkr`] where some pair uses the `krijt`/`stress` dissipation: touched and the
    /// contact radius a, and the Krijt snippet.
    JkrKrijt,
    /// [`Self::JkrFriction`] with the contact radius (`krijt`/`stress`).
    JkrKrijtFriction,
    /// [`Self::JkrRolling`] with the contact radius (`krijt`/`stress`; a fills ξ's padding).
    JkrKrijtRolling,
    /// Hysteretic/LSD and JKR/Hertz pairs in one scene (no Krijt): the JKR touched flag and
    /// the hysteretic (δmax, touched), no rotation.
    Mixed,
    /// As `Mixed`, with friction on some JKR pair: the tangential spring, rotation.
    MixedFriction,
    /// As `Mixed`, with rolling resistance on some JKR pair: spring and ξ, rotation.
    MixedRolling,
}

impl StepKind {
    /// Every step kind, in declaration order.
    pub const ALL: [StepKind; 10] = [
        StepKind::Hysteretic,
        StepKind::Jkr,
        StepKind::JkrFriction,
        StepKind::JkrRolling,
        StepKind::JkrKrijt,
        StepKind::JkrKrijtFriction,
        StepKind::JkrKrijtRolling,
        StepKind::Mixed,
        StepKind::MixedFriction,
        StepKind::MixedRolling,
    ];

    /// The mixed step (hysteretic/LSD with JKR-family pairs) whose JKR history covers what
    /// its JKR pairs need.
    pub fn mixed(friction: bool, rolling: bool) -> Self {
        match (rolling, friction) {
            (true, _) => Self::MixedRolling,
            (false, true) => Self::MixedFriction,
            (false, false) => Self::Mixed,
        }
    }

    /// The JKR step for a scene: with the tangential spring (`friction`), ξ (`rolling`,
    /// implies the spring) and the Krijt contact radius (`krijt`) stored where some pair
    /// needs them.
    pub fn jkr(friction: bool, rolling: bool, krijt: bool) -> Self {
        match (rolling, friction, krijt) {
            (true, _, false) => Self::JkrRolling,
            (true, _, true) => Self::JkrKrijtRolling,
            (false, true, false) => Self::JkrFriction,
            (false, true, true) => Self::JkrKrijtFriction,
            (false, false, false) => Self::Jkr,
            (false, false, true) => Self::JkrKrijt,
        }
    }

    /// The name of the variant without the energy ledger (with it: `_ledger` appended).
    pub fn name(self) -> &'static str {
        match self {
            Self::Hysteretic => "step_hysteretic",
            Self::Jkr => "step_jkr",
            Self::JkrFriction => "step_jkr_friction",
            Self::JkrRolling => "step_jkr_rolling",
            Self::JkrKrijt => "step_jkr_krijt",
            Self::JkrKrijtFriction => "step_jkr_krijt_friction",
            Self::JkrKrijtRolling => "step_jkr_krijt_rolling",
            Self::Mixed => "step_mixed",
            Self::MixedFriction => "step_mixed_friction",
            Self::MixedRolling => "step_mixed_rolling",
        }
    }

    /// Whether particles carry angular velocity (the rotation snippet is composed in).
    pub fn rotation(self) -> bool {
        matches!(
            self,
            Self::JkrFriction
                | Self::JkrRolling
                | Self::JkrKrijtFriction
                | Self::JkrKrijtRolling
                | Self::MixedFriction
                | Self::MixedRolling
        )
    }

    /// Whether the history stores the Krijt contact radius (model_krijt.wgsl is composed in).
    pub fn krijt(self) -> bool {
        matches!(
            self,
            Self::JkrKrijt | Self::JkrKrijtFriction | Self::JkrKrijtRolling
        )
    }

    /// Bytes of one contact's stored history (`Hist`; checked against naga in
    /// `layout::tests`).
    pub fn history_bytes(self) -> u64 {
        match self {
            Self::Hysteretic => 4,
            Self::Jkr => 4,
            Self::JkrFriction => 16,
            Self::JkrRolling => 32,
            Self::JkrKrijt => 8,
            Self::JkrKrijtFriction => 20,
            Self::JkrKrijtRolling => 32,
            // struct { JKR layout, f32 }: the f32 at offset 4, 16, 32 (the struct 16-byte
            // aligned for the vector layouts)
            Self::Mixed => 8,
            Self::MixedFriction => 32,
            Self::MixedRolling => 48,
        }
    }

    /// The variant's name (also the shader module's label).
    pub fn variant_name(self, ledger: bool) -> String {
        if ledger {
            format!("{}_ledger", self.name())
        } else {
            self.name().to_string()
        }
    }

    /// The composed module: common, model (JKR: with the Krijt snippet or its no-op
    /// hooks), history layout, rotation hooks, ledger hooks, step.
    pub fn variant(self, ledger: bool) -> ShaderVariant {
        let rotation = if self.rotation() {
            ROTATION
        } else {
            ROTATION_OFF
        };
        let ledger_snippet = if ledger { LEDGER } else { LEDGER_OFF };
        let mut snippets: Vec<&str> = match self {
            Self::Hysteretic => vec![MODEL_HYSTERETIC, rotation],
            Self::Jkr => vec![MODEL_JKR, MODEL_KRIJT_OFF, JKR_HISTORY_TOUCHED, rotation],
            Self::JkrFriction => vec![MODEL_JKR, MODEL_KRIJT_OFF, JKR_HISTORY_TANGENTIAL, rotation],
            Self::JkrRolling => vec![MODEL_JKR, MODEL_KRIJT_OFF, JKR_HISTORY_ROLLING, rotation],
            Self::JkrKrijt => vec![MODEL_JKR, MODEL_KRIJT, JKR_HISTORY_TOUCHED_RADIUS, rotation],
            Self::JkrKrijtFriction => vec![
                MODEL_JKR,
                MODEL_KRIJT,
                JKR_HISTORY_TANGENTIAL_RADIUS,
                rotation,
            ],
            Self::JkrKrijtRolling => vec![MODEL_JKR, MODEL_KRIJT, JKR_HISTORY_ROLLING, rotation],
            Self::Mixed | Self::MixedFriction | Self::MixedRolling => {
                let layout = match self {
                    Self::Mixed => JKR_HISTORY_TOUCHED,
                    Self::MixedFriction => JKR_HISTORY_TANGENTIAL,
                    _ => JKR_HISTORY_ROLLING,
                };
                return mixed_variant(self, layout, rotation, ledger_snippet, ledger);
            }
        };
        snippets.push(ledger_snippet);
        ShaderVariant {
            name: self.variant_name(ledger),
            source: compose("shaders/step.wgsl", STEP, &snippets),
        }
    }
}

/// `src` with every identifier in `map` renamed (whole identifiers only): composes two
/// model files whose step interfaces (`PairRow`, `Hist`, `hist_zero`, `pair_contact`,
/// `pair_edges`) would otherwise clash.
fn rename_idents(src: &str, map: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(src.len() + 64);
    let mut ident = String::new();
    let flush = |ident: &mut String, out: &mut String| {
        let name = map
            .iter()
            .find(|(from, _)| *from == ident.as_str())
            .map_or(ident.as_str(), |(_, to)| to);
        out.push_str(name);
        ident.clear();
    };
    for c in src.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            ident.push(c);
        } else {
            if !ident.is_empty() {
                flush(&mut ident, &mut out);
            }
            out.push(c);
        }
    }
    if !ident.is_empty() {
        flush(&mut ident, &mut out);
    }
    out
}

/// The interface of a scene mixing hysteretic/LSD and JKR-family pairs: a tagged pair row
/// holding both parameter sets and a history holding both layouts; each pair dispatches to
/// its own model (the renamed interfaces of the two model files).
pub const MIXED: &str = "\
// Mixed scenes: hysteretic/LSD pairs (kind 0) and JKR-family pairs (kind 1) in one step.
struct MixedPair {
    kind: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    hyst: HystereticPair,
    jkr: JkrPair,
}
alias PairRow = MixedPair;
struct MixedHist {
    jkr: JkrHist,
    hyst: HystHist,
}
alias Hist = MixedHist;
fn hist_zero() -> Hist { return MixedHist(jkr_hist_zero(), hyst_hist_zero()); }
fn hist_mirror(h: Hist) -> Hist { return MixedHist(jkr_hist_mirror(h.jkr), hyst_hist_mirror(h.hyst)); }
fn hist_same(a: Hist, b: Hist) -> bool { return jkr_hist_same(a.jkr, b.jkr) && hyst_hist_same(a.hyst, b.hyst); }
fn pair_contact(p: MixedPair, k: Kin, hist: ptr<function, Hist>) -> Contact {
    if (p.kind == 0u) {
        var h = (*hist).hyst;
        let c = hyst_pair_contact(p.hyst, k, &h);
        (*hist).hyst = h;
        return c;
    }
    var h = (*hist).jkr;
    let c = jkr_pair_contact(p.jkr, k, &h);
    (*hist).jkr = h;
    return c;
}
fn pair_edges(p: MixedPair, k: Kin) -> vec4<f32> {
    if (p.kind == 0u) {
        return hyst_pair_edges(p.hyst, k);
    }
    return jkr_pair_edges(p.jkr, k);
}
";

fn mixed_variant(
    kind: StepKind,
    jkr_layout: &str,
    rotation: &str,
    ledger_snippet: &str,
    ledger: bool,
) -> ShaderVariant {
    let hyst = rename_idents(
        MODEL_HYSTERETIC,
        &[
            ("PairRow", "HystPairRow"),
            ("Hist", "HystHist"),
            ("hist_zero", "hyst_hist_zero"),
            ("hist_mirror", "hyst_hist_mirror"),
            ("hist_same", "hyst_hist_same"),
            ("pair_contact", "hyst_pair_contact"),
            ("pair_edges", "hyst_pair_edges"),
        ],
    );
    let jkr_map = [
        ("PairRow", "JkrPairRow"),
        ("Hist", "JkrHist"),
        ("hist_zero", "jkr_hist_zero"),
        ("hist_mirror", "jkr_hist_mirror"),
        ("hist_same", "jkr_hist_same"),
        ("pair_contact", "jkr_pair_contact"),
        ("pair_edges", "jkr_pair_edges"),
    ];
    let jkr = rename_idents(MODEL_JKR, &jkr_map);
    let krijt_off = rename_idents(MODEL_KRIJT_OFF, &jkr_map);
    let layout = rename_idents(jkr_layout, &jkr_map);
    let snippets: Vec<&str> = vec![
        &hyst,
        &jkr,
        &krijt_off,
        &layout,
        MIXED,
        rotation,
        ledger_snippet,
    ];
    ShaderVariant {
        name: kind.variant_name(ledger),
        source: compose("shaders/step.wgsl", STEP, &snippets),
    }
}

/// The step for the normal-force models (hysteretic, LSD), with the energy ledger.
pub fn step_variant() -> ShaderVariant {
    StepKind::Hysteretic.variant(true)
}

/// A shader stage: one file of `shaders/`.
#[derive(Clone, Copy, Debug)]
pub struct Stage {
    /// Variant name (also the module's label).
    pub name: &'static str,
    /// Path of the stage file, for error messages.
    pub path: &'static str,
    /// The stage's WGSL source, embedded at build time.
    pub source: &'static str,
}

/// Every stage file, composed without snippets.
pub const STAGES: &[Stage] = &[Stage {
    name: "grid",
    path: "shaders/grid.wgsl",
    source: GRID,
}];

/// A complete WGSL module: common declarations, snippets and one stage.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderVariant {
    /// Variant name (also the shader module's label).
    pub name: String,
    /// The composed WGSL source.
    pub source: String,
}

/// `common.wgsl`, then each snippet, then the stage, each part headed by a comment
/// naming where it comes from (so naga's error excerpts are easy to place).
pub fn compose(stage_path: &str, stage_source: &str, snippets: &[&str]) -> String {
    let mut s = String::with_capacity(COMMON.len() + stage_source.len() + 256);
    s.push_str("// ---- shaders/common.wgsl ----\n");
    s.push_str(COMMON);
    for (i, snippet) in snippets.iter().enumerate() {
        s.push_str(&format!("\n// ---- snippet {i} ----\n"));
        s.push_str(snippet);
    }
    s.push_str(&format!("\n// ---- {stage_path} ----\n"));
    s.push_str(stage_source);
    s
}

/// Every shader module the engine builds.
pub fn all_variants() -> Vec<ShaderVariant> {
    let mut all: Vec<ShaderVariant> = STAGES
        .iter()
        .map(|st| ShaderVariant {
            name: st.name.to_string(),
            source: compose(st.path, st.source, &[]),
        })
        .collect();
    for ledger in [false, true] {
        all.extend(StepKind::ALL.iter().map(|k| k.variant(ledger)));
    }
    all
}

/// The variant called `name`.
pub fn variant(name: &str) -> Option<ShaderVariant> {
    all_variants().into_iter().find(|v| v.name == name)
}

/// Parses and validates WGSL with naga (core WGSL only, all validation flags); the
/// error is naga's own report, with the offending source excerpt.
pub fn validate(source: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    );
    let info = validator
        .validate(&module)
        .map_err(|e| e.emit_to_string(source))?;
    Ok((module, info))
}

/// Names of the compute entry points of a module.
pub fn compute_entry_points(module: &naga::Module) -> Vec<String> {
    module
        .entry_points
        .iter()
        .filter(|ep| ep.stage == naga::ShaderStage::Compute)
        .map(|ep| ep.name.clone())
        .collect()
}

/// The value of the WGSL `const NAME: u32` in `module` (tests tie host constants to
/// their WGSL twins with it).
#[cfg(test)]
pub(crate) fn wgsl_u32_const(module: &naga::Module, name: &str) -> u32 {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no constant {name}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        ref e => panic!("constant {name} is {e:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_shaders_every_variant_validates() {
        let variants = all_variants();
        assert!(!variants.is_empty());
        for v in &variants {
            match validate(&v.source) {
                Ok((module, _)) => {
                    assert!(
                        !compute_entry_points(&module).is_empty(),
                        "variant {} has no compute entry point",
                        v.name
                    );
                }
                Err(e) => panic!("shader variant `{}` does not validate:\n{e}", v.name),
            }
        }
    }

    #[test]
    fn gpu_shaders_grid_has_the_sort_kernels() {
        let (module, _) = validate(&variant("grid").unwrap().source).unwrap();
        let eps = compute_entry_points(&module);
        for name in [
            "clear_counts",
            "cell_keys",
            "count",
            "scan_blocks",
            "scan_add",
            "scatter",
            "sort_within_cells",
            "sort_large_cells",
        ] {
            assert!(eps.iter().any(|e| e == name), "missing kernel {name}");
        }
    }

    #[test]
    fn gpu_shaders_every_step_variant_has_the_step_kernels() {
        for (kind, ledger) in StepKind::ALL
            .into_iter()
            .flat_map(|k| [(k, false), (k, true)])
        {
            let v = kind.variant(ledger);
            let (module, _) = validate(&v.source).unwrap();
            let eps = compute_entry_points(&module);
            for name in [
                "kick_drift",
                "decide",
                "gather",
                "neighbours",
                "remap",
                "copy_back",
                "copy_back_history",
                "force",
                "kick",
            ] {
                assert!(
                    eps.iter().any(|e| e == name),
                    "{}: no kernel {name}",
                    v.name
                );
            }
            // the angular buffers exist only where particles rotate
            let declared = |name: &str| {
                module
                    .global_variables
                    .iter()
                    .any(|(_, g)| g.name.as_deref() == Some(name))
            };
            for name in [
                "a_omega", "a_alpha", "b_omega", "b_alpha", "a_wpred", "b_wpred",
            ] {
                assert_eq!(declared(name), kind.rotation(), "{}: {name}", v.name);
            }
            // the Krijt dynamics only where the history stores the contact radius
            let has_fn = |name: &str| {
                module
                    .functions
                    .iter()
                    .any(|(_, f)| f.name.as_deref() == Some(name))
            };
            assert_eq!(
                has_fn("krijt_advance"),
                kind.krijt(),
                "{}: krijt_advance",
                v.name
            );
            assert!(
                !kind.krijt() || v.source.contains("const KRIJT: bool = true;"),
                "{}",
                v.name
            );
            // and the ledger's only where the run keeps one
            for name in [
                "a_ledger",
                "b_ledger",
                "a_wall_ledger",
                "b_wall_ledger",
                "particle_ledger",
            ] {
                assert_eq!(declared(name), ledger, "{}: {name}", v.name);
            }
            assert!(
                variant(&kind.variant_name(ledger)).is_some(),
                "{} not in all_variants",
                v.name
            );
        }
    }

    /// The f32 literals of model_jkr.wgsl are the f32 roundings of the Rust constants of
    /// `jkr::contact_radius_f32` (the two solvers must be the same function).
    #[test]
    fn gpu_shaders_jkr_constants_match_the_rust_solver() {
        use crate::model::jkr::{D_PULLOFF_DISPLACEMENT, NEWTON_ITERATIONS_F32, S_MIN};
        let literal = |name: &str| -> f64 {
            let key = format!("const {name}: ");
            let line = MODEL_JKR
                .lines()
                .find(|l| l.starts_with(&key))
                .unwrap_or_else(|| panic!("{name} not in model_jkr.wgsl"));
            let value = line.split('=').nth(1).unwrap().trim().trim_end_matches(';');
            value.trim_end_matches('u').parse().unwrap()
        };
        let f32_of = |name: &str| literal(name) as f32;
        assert_eq!(f32_of("JKR_S_MIN"), S_MIN as f32);
        assert_eq!(f32_of("JKR_D_MIN"), D_PULLOFF_DISPLACEMENT as f32);
        assert_eq!(f32_of("JKR_C"), (2.0 * S_MIN) as f32);
        assert_eq!(f32_of("JKR_B"), (2.0 * S_MIN * S_MIN) as f32);
        assert_eq!(f32_of("JKR_SQRT3"), 3f64.sqrt() as f32);
        assert_eq!(f32_of("JKR_SLOPE0"), (18f64.sqrt() * S_MIN) as f32);
        assert_eq!(f32_of("JKR_PI"), std::f64::consts::PI as f32);
        assert_eq!(
            literal("JKR_NEWTON_ITERATIONS") as usize,
            NEWTON_ITERATIONS_F32
        );
    }

    /// The Krijt constants of model_krijt.wgsl are the f32 roundings of `model::krijt`'s and
    /// `jkr::X_TOUCH`; the dissipation codes match `gpu::layout`'s.
    #[test]
    fn gpu_shaders_krijt_constants_match_the_rust_model() {
        use crate::gpu::layout::{JKR_DISSIPATION_KRIJT, JKR_DISSIPATION_STRESS};
        use crate::model::jkr::X_TOUCH;
        use crate::model::krijt::{BETA_MAX, BETA_MIN};
        let literal = |source: &str, name: &str| -> f64 {
            let key = format!("const {name}: ");
            let line = source
                .lines()
                .find(|l| l.starts_with(&key))
                .unwrap_or_else(|| panic!("{name} not found"));
            let value = line.split('=').nth(1).unwrap().trim().trim_end_matches(';');
            value.trim_end_matches('u').parse().unwrap()
        };
        let f32_of = |name: &str| literal(MODEL_KRIJT, name) as f32;
        assert_eq!(f32_of("KRIJT_BETA_MIN"), BETA_MIN as f32);
        assert_eq!(f32_of("KRIJT_BETA_MAX"), BETA_MAX as f32);
        assert_eq!(f32_of("KRIJT_X_TOUCH"), X_TOUCH as f32);
        // 30 halvings take any bracket up to 2^6·x to one f32 ulp of x
        assert!(literal(MODEL_KRIJT, "KRIJT_BISECTION_ITERATIONS") >= 24.0);
        assert_eq!(
            literal(MODEL_JKR, "JKR_DISSIPATION_KRIJT") as u32,
            JKR_DISSIPATION_KRIJT
        );
        assert_eq!(
            literal(MODEL_JKR, "JKR_DISSIPATION_STRESS") as u32,
            JKR_DISSIPATION_STRESS
        );
    }

    #[test]
    fn gpu_shaders_validation_reports_naga_text() {
        let e = validate("fn f() -> u32 { return 1.5; }").unwrap_err();
        assert!(!e.is_empty());
        // Core WGSL only: f64 needs a capability we do not grant.
        let e = validate("fn f(x: f64) -> f64 { return x; }").unwrap_err();
        assert!(
            e.to_lowercase().contains("f64") || e.contains("Float"),
            "{e}"
        );
    }

    #[test]
    fn gpu_shaders_compose_keeps_parts_in_order() {
        let s = compose("shaders/x.wgsl", "fn stage() {}", &["const A: u32 = 1u;"]);
        let common = s.find("struct GridParams").unwrap();
        let snippet = s.find("const A").unwrap();
        let stage = s.find("fn stage").unwrap();
        assert!(common < snippet && snippet < stage);
        validate(&s).unwrap();
    }
}
