//! WGSL sources of the GPU engine, their composition into shader modules, and their
//! validation with naga (no GPU needed).
//!
//! Every module is `shaders/common.wgsl` (shared structs, constants and helpers)
//! followed by snippets followed by the stage's files (`shaders/grid.wgsl`, or the step's
//! six of `shaders/step/`). The
//! step's snippets are the contact sub-models a scene uses and the interface generated for
//! them (`gpu::composition`). A [`ShaderVariant`] is one such composition under a name;
//! [`all_variants`] lists every variant the engine can build, and the unit test validates
//! each of them with naga's WGSL front end and validator, so a broken kernel fails
//! `cargo test` on any machine.
//!
//! Validation uses [`naga::valid::Capabilities::empty`]: only core WGSL passes (no f64,
//! no 64-bit integers, no float atomics, no subgroups, no push constants), so whatever
//! validates here runs on every backend and adapter wgpu supports.

use super::composition::{Composition, Keeps};
use crate::model::ContactModel;

/// Shared declarations, prepended to every stage.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");
/// The counting sort of particles by cell (see `shaders/grid.wgsl`).
pub const GRID: &str = include_str!("../../shaders/grid.wgsl");
/// Angular velocity and torques (a snippet of the step for scenes that rotate).
pub const ROTATION: &str = include_str!("../../shaders/rotation.wgsl");
/// The rotation hooks as no-ops (a snippet of the step for scenes that do not rotate).
pub const ROTATION_OFF: &str = include_str!("../../shaders/rotation_off.wgsl");
/// The step's reads of the particle state on a GPU: the state's own buffers.
pub const STATE_BUFFERS: &str = include_str!("../../shaders/state_buffers.wgsl");
/// The step's reads of the particle state on a software adapter: texture mirrors.
pub const STATE_MIRRORS: &str = include_str!("../../shaders/state_mirrors.wgsl");
/// The predicted angular velocity from its buffer (with [`STATE_BUFFERS`]).
pub const ROTATION_BUFFERS: &str = include_str!("../../shaders/rotation_buffers.wgsl");
/// The predicted angular velocity from its mirror (with [`STATE_MIRRORS`]).
pub const ROTATION_MIRRORS: &str = include_str!("../../shaders/rotation_mirrors.wgsl");
/// The energy ledger and contact statistics (a snippet of the step, when a run wants them).
pub const LEDGER: &str = include_str!("../../shaders/ledger.wgsl");
/// The ledger hooks as no-ops (a snippet of the step for runs without the ledger).
pub const LEDGER_OFF: &str = include_str!("../../shaders/ledger_off.wgsl");
/// The impulse velocity Verlet misplaces where a contact's force jumps inside the step
/// (twin of `cpu::jump`), for the variants that place it.
pub const JUMP: &str = include_str!("../../shaders/jump.wgsl");
/// The force-jump hooks as no-ops (a snippet of the step for scenes that place none).
pub const JUMP_OFF: &str = include_str!("../../shaders/jump_off.wgsl");
/// Overlaps to below f32 rounding of positions (double-float on the compensated state).
pub const OVERLAP: &str = include_str!("../../shaders/overlap.wgsl");
/// A rebuild's in-place re-sort of the particle state through one scratch buffer.
pub const PERMUTE: &str = include_str!("../../shaders/permute.wgsl");
/// One time step, a file a phase (path, source): what the kernels share, the drift, a
/// rebuild's kernels, the forces, the collect and closing kick, walls and pouring.
pub const STEP: [(&str, &str); 6] = [
    (
        "shaders/step/shared.wgsl",
        include_str!("../../shaders/step/shared.wgsl"),
    ),
    (
        "shaders/step/drift.wgsl",
        include_str!("../../shaders/step/drift.wgsl"),
    ),
    (
        "shaders/step/rebuild.wgsl",
        include_str!("../../shaders/step/rebuild.wgsl"),
    ),
    (
        "shaders/step/force.wgsl",
        include_str!("../../shaders/step/force.wgsl"),
    ),
    (
        "shaders/step/collect.wgsl",
        include_str!("../../shaders/step/collect.wgsl"),
    ),
    (
        "shaders/step/walls.wgsl",
        include_str!("../../shaders/step/walls.wgsl"),
    ),
];

/// The step of a hysteretic/LSD scene, with the energy ledger.
pub fn step_variant() -> ShaderVariant {
    let lsd = ContactModel::Lsd(crate::model::LsdParams {
        k: 1.0,
        gamma0: 0.0,
        luding: Default::default(),
    });
    Composition::of(&[lsd]).variant(Keeps::new(true, false, false), false, false)
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
pub const STAGES: &[Stage] = &[
    Stage {
        name: "grid",
        path: "shaders/grid.wgsl",
        source: GRID,
    },
    Stage {
        name: "permute",
        path: "shaders/permute.wgsl",
        source: PERMUTE,
    },
];

/// A complete WGSL module: common declarations, snippets and a stage's files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderVariant {
    /// Variant name (also the shader module's label).
    pub name: String,
    /// The composed WGSL source.
    pub source: String,
}

/// `common.wgsl`, the structs and constants shared with the host
/// ([`declarations`](super::layout::declarations)), then each snippet, then the stage's files
/// (path, source), each part headed by a comment naming where it comes from (so naga's error
/// excerpts are easy to place).
pub fn compose(stage: &[(&str, &str)], snippets: &[&str]) -> String {
    let bytes: usize = stage.iter().map(|(_, src)| src.len()).sum();
    let shared = super::layout::declarations();
    let mut s = String::with_capacity(COMMON.len() + shared.len() + bytes + 256);
    s.push_str("// ---- shaders/common.wgsl ----\n");
    s.push_str(COMMON);
    s.push_str("\n// ---- generated: gpu::layout::declarations ----\n");
    s.push_str(&shared);
    for (i, snippet) in snippets.iter().enumerate() {
        s.push_str(&format!("\n// ---- snippet {i} ----\n"));
        s.push_str(snippet);
    }
    for (path, source) in stage {
        s.push_str(&format!("\n// ---- {path} ----\n"));
        s.push_str(source);
    }
    s
}

/// The stage file called `name` ([`STAGES`]), composed without snippets.
pub fn stage(name: &str) -> Option<ShaderVariant> {
    STAGES
        .iter()
        .find(|st| st.name == name)
        .map(|st| ShaderVariant {
            name: st.name.to_string(),
            source: compose(&[(st.path, st.source)], &[]),
        })
}

/// The kernels every step variant has and every run builds (besides the wall kernels
/// where walls move and `appear` where particles are poured).
pub const STEP_KERNELS: [&str; 13] = [
    "kick_drift",
    "decide",
    "decide_lean",
    "gather",
    "count_neighbours",
    "neighbours",
    "commit",
    "remap",
    "copy_back_history",
    "force",
    "kick",
    "collect_kick_drift",
    "collect",
];

/// Every shader module the engine builds.
pub fn all_variants() -> Vec<ShaderVariant> {
    let mut all: Vec<ShaderVariant> = STAGES
        .iter()
        .map(|st| ShaderVariant {
            name: st.name.to_string(),
            source: compose(&[(st.path, st.source)], &[]),
        })
        .collect();
    for c in Composition::all() {
        for (mirrors, paged) in [(false, false), (true, false), (false, true), (true, true)] {
            all.extend(Keeps::ALL.map(|keeps| c.variant(keeps, mirrors, paged)));
        }
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

    /// Every entry point of every variant fits wgpu's default limits (WebGPU's): at most 8
    /// storage buffers and 4 storage textures a stage, workgroups of at most 256
    /// invocations and 16 KiB of workgroup memory — so the engine runs on GL (16 storage
    /// buffers) and within a browser's limits.
    #[test]
    fn gpu_shaders_every_kernel_fits_the_default_limits() {
        let limits = wgpu::Limits::default();
        for v in all_variants() {
            let (module, info) = validate(&v.source).unwrap();
            for (index, ep) in module.entry_points.iter().enumerate() {
                let uses = info.get_entry_point(index);
                let (mut buffers, mut textures, mut shared) = (0, 0, 0);
                for (handle, var) in module.global_variables.iter() {
                    if uses[handle].is_empty() {
                        continue;
                    }
                    match var.space {
                        naga::AddressSpace::Storage { .. } => buffers += 1,
                        naga::AddressSpace::WorkGroup => {
                            shared += module.types[var.ty].inner.size(module.to_ctx())
                        }
                        naga::AddressSpace::Handle => {
                            if matches!(
                                module.types[var.ty].inner,
                                naga::TypeInner::Image {
                                    class: naga::ImageClass::Storage { .. },
                                    ..
                                }
                            ) {
                                textures += 1;
                            }
                        }
                        _ => {}
                    }
                }
                let what = format!("{}::{}", v.name, ep.name);
                assert!(
                    buffers <= limits.max_storage_buffers_per_shader_stage,
                    "{what}: {buffers} storage buffers"
                );
                assert!(
                    textures <= limits.max_storage_textures_per_shader_stage,
                    "{what}: {textures} storage textures"
                );
                assert!(
                    shared <= limits.max_compute_workgroup_storage_size,
                    "{what}: {shared} bytes of workgroup memory"
                );
                let size: u32 = ep.workgroup_size.iter().product();
                assert!(
                    size <= limits.max_compute_invocations_per_workgroup,
                    "{what}: workgroups of {size}"
                );
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
        let names: Vec<String> = all_variants().into_iter().map(|v| v.name).collect();
        for (kind, keeps, mirrors) in Composition::all().into_iter().flat_map(|k| {
            Keeps::ALL
                .into_iter()
                .flat_map(move |keeps| [false, true].map(|mirrors| (keeps, mirrors)))
                .map(move |(keeps, mirrors)| (k.clone(), keeps, mirrors))
        }) {
            let v = kind.variant(keeps, mirrors, false);
            let (module, _) = validate(&v.source).unwrap();
            let eps = compute_entry_points(&module);
            for name in STEP_KERNELS.iter().chain(&["appear"]) {
                assert!(
                    eps.iter().any(|e| e == name),
                    "{}: no kernel {name}",
                    v.name
                );
            }
            // the angular state and pair torques exist only where particles rotate
            let declared = |name: &str| {
                module
                    .global_variables
                    .iter()
                    .any(|(_, g)| g.name.as_deref() == Some(name))
                    || module
                        .functions
                        .iter()
                        .any(|(_, f)| f.name.as_deref() == Some(name))
            };
            for name in ["load_omega", "load_alpha", "load_wpred", "load_pair_torque"] {
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
            // and the ledger's fields of the state only where the run keeps one
            assert_eq!(declared("load_ledger_energy"), keeps.ledger, "{}", v.name);
            // the contacts' priors with the ledger or the force jumps, the impulses for
            // the partners with the force jumps: each field of the entries only where kept
            let kept = |name: &str| kind.records(keeps).iter().any(|r| r.place(name).is_some());
            for name in ["prior", "new_prior"] {
                assert_eq!(kept(name), keeps.prior(), "{}: {name}", v.name);
            }
            for name in ["jump", "jump_normal"] {
                assert_eq!(kept(name), keeps.jumps, "{}: {name}", v.name);
            }
            // and without the force jumps the force pass touches no velocity
            let force = module
                .entry_points
                .iter()
                .find(|e| e.name == "force")
                .unwrap();
            let calls = crate::gpu::kernel::called_functions(&module, &force.function);
            assert_eq!(
                calls.contains("store_vel"),
                keeps.jumps,
                "{}: the force pass's velocity kick",
                v.name
            );
            // the texture mirrors only on the software adapter's path
            assert_eq!(declared("m_cell"), mirrors, "{}: m_cell", v.name);
            assert_eq!(
                declared("m_wpred"),
                mirrors && kind.rotation(),
                "{}: m_wpred",
                v.name
            );
            assert!(names.contains(&v.name), "{} not in all_variants", v.name);
        }
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
        let s = compose(
            &[("shaders/x.wgsl", "fn stage() {}")],
            &["const A: u32 = 1u;"],
        );
        let common = s.find("struct GridParams").unwrap();
        let snippet = s.find("const A").unwrap();
        let stage = s.find("fn stage").unwrap();
        assert!(common < snippet && snippet < stage);
        validate(&s).unwrap();
    }

    /// A step variant holds common.wgsl, then its snippets, then the step's six files in
    /// `STEP`'s order, each once.
    #[test]
    fn the_step_files_follow_the_snippets_in_order() {
        let v = step_variant();
        let at: Vec<usize> = (STEP.iter())
            .map(|(path, _)| {
                let mark = format!("// ---- {path} ----");
                assert_eq!(v.source.matches(&mark).count(), 1, "{path}");
                v.source.find(&mark).unwrap()
            })
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{at:?}");
        let common = v.source.find("// ---- shaders/common.wgsl ----").unwrap();
        let snippet = v.source.find("// ---- snippet 0 ----").unwrap();
        assert!(common < snippet && snippet < at[0]);
    }
}
