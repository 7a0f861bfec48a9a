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
/// One time step: drift, gather, neighbours, history remap, forces, kick.
pub const STEP: &str = include_str!("../../shaders/step.wgsl");

/// The step for the normal-force models (hysteretic, LSD).
pub fn step_variant() -> ShaderVariant {
    ShaderVariant {
        name: "step_hysteretic".into(),
        source: compose("shaders/step.wgsl", STEP, &[MODEL_HYSTERETIC]),
    }
}

/// A shader stage: one file of `shaders/`.
#[derive(Clone, Copy, Debug)]
pub struct Stage {
    /// Variant name (also the module's label).
    pub name: &'static str,
    /// Path of the stage file, for error messages.
    pub path: &'static str,
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
    pub name: String,
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
    all.push(step_variant());
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
