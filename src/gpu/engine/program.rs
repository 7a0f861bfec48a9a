//! What the step's program is compiled from for a scene: its composition and pair table,
//! the kernels it runs, the force jumps it places and its pipeline constants.

use super::*;

/// Whether the step places force jumps: as the scene says (`jump_impulses`), by default
/// where some contact law's force can jump (on the CPU they cost nothing where none does;
/// here they are fields and code the step would carry for nothing).
pub(super) fn places_jumps(scene: &Scene, models: &[ContactModel], r_max: f64) -> bool {
    scene.jump_impulses.unwrap_or_else(|| {
        let geom = PairGeometry::spheres(r_max, r_max, 1.0, 1.0);
        models.iter().any(|m| m.has_force_jumps(&geom))
    })
}

/// What the step's program is compiled from besides the composition: the kernels a scene
/// runs, its pipeline constants, the state read through mirrors.
pub(super) struct StepSpec {
    pub(super) wanted: Vec<&'static str>,
    pub(super) constants: Vec<(&'static str, f64)>,
    pub(super) mirrors: bool,
}

impl StepSpec {
    /// The step's program, the lists' entries in one buffer or `paged`.
    pub(super) fn compile(
        &self,
        ctx: &GpuContext,
        (kind, keeps): (&Composition, Keeps),
        paged: bool,
    ) -> Result<Program, PowderError> {
        Program::specialized(
            ctx,
            &kind.variant(keeps, self.mirrors, paged),
            Some(&self.wanted),
            &self.constants,
        )
    }
}

/// The step's kernels a scene runs: the wall kernels only where walls move, `appear` only
/// where particles appear during the run (the others are not compiled).
pub(super) fn wanted_kernels(scene: &Scene) -> Vec<&'static str> {
    let mut wanted = crate::gpu::shaders::STEP_KERNELS.to_vec();
    if scene.walls.iter().any(|w| w.motion.moves()) {
        wanted.push("wall_move");
    }
    if scene.walls.iter().any(|w| w.motion.servo()) {
        wanted.extend(["wall_servo", "wall_servo_apply"]);
    }
    if scene.pours() {
        wanted.push("appear");
    }
    wanted
}

/// The value every item of `values` has, or `mixed` when they differ or there is none.
pub(super) fn common_or<T: PartialEq + Copy>(values: impl IntoIterator<Item = T>, mixed: T) -> T {
    let mut values = values.into_iter();
    match values.next() {
        Some(first) if values.all(|v| v == first) => first,
        _ => mixed,
    }
}

/// The step's pipeline-overridable constants for a scene: what it does not use is folded
/// out of its pipelines (the WGSL `override`s of `shaders/step/` and the model files). The
/// model constants go only to variants that declare them (wgpu refuses unknown names).
pub(super) fn pipeline_constants(
    scene: &Scene,
    r: &Resolved,
    models: &[ContactModel],
) -> Vec<(&'static str, f64)> {
    let flag = |b: bool| f64::from(u8::from(b));
    let mut constants = vec![
        ("ONE_MATERIAL", flag(r.n_materials == 1)),
        ("POURING", flag(scene.pours())),
        ("PERIODIC", flag(scene.domain.periodic.iter().any(|&p| p))),
        ("WALLS", flag(!scene.walls.is_empty())),
    ];
    let hyst: Vec<HystereticPair> = models
        .iter()
        .filter_map(|m| match m {
            ContactModel::Hysteretic(p) => Some(HystereticPair::hysteretic(p)),
            ContactModel::Lsd(p) => Some(HystereticPair::lsd(p)),
            _ => None,
        })
        .collect();
    if !hyst.is_empty() {
        let flags = common_or(hyst.iter().map(|h| h.flags), u32::MAX);
        constants.push(("HYST_ONE_FLAGS", flags as f64));
    }
    let jkr: Vec<JkrPair> = models
        .iter()
        .filter_map(|m| match m {
            ContactModel::Jkr(p) => Some(JkrPair::new(p)),
            _ => None,
        })
        .collect();
    if !jkr.is_empty() {
        // one dissipation code or 255; all Hertz 0 / all adhesive 1 / both 2
        let dissipation = common_or(jkr.iter().map(|j| j.dissipation), 255);
        let adhesion = common_or(jkr.iter().map(|j| u32::from(j.gamma > 0.0)), 2);
        constants.push(("JKR_ONE_DISSIPATION", dissipation as f64));
        constants.push(("JKR_ADHESION", adhesion as f64));
    }
    constants
}

/// The step a scene's pair models need and their pair table as bytes.
pub(super) fn pair_table(models: &[ContactModel]) -> (Composition, Vec<u8>) {
    let kind = Composition::of(models);
    let rows = models.iter().flat_map(|m| kind.pair_row(m)).collect();
    (kind, rows)
}
