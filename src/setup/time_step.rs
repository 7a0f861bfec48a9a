//! The time-step rule of a scene: the most demanding contact's, over every pair of
//! materials, every wall and the Rayleigh guard.

use super::closing::starting_closing_speed;
use crate::error::PowderError;
use crate::model::{ContactModel, PairGeometry, TimeStep};
use crate::scene::Scene;

/// The most demanding pair of materials, with the lightest particles of each, and each
/// against the other's heaviest (a rolling or twisting oscillator is stiffest for a small
/// sphere on a large one); walls count as infinite mass.
pub(super) fn resolve(
    scene: &Scene,
    models: &[ContactModel],
    wall_models: &[ContactModel],
    mass: &[f64],
) -> Result<TimeStep, PowderError> {
    let n_materials = scene.materials.len();
    let mut lightest: Vec<Option<(f64, f64)>> = vec![None; n_materials];
    let mut heaviest: Vec<Option<(f64, f64)>> = vec![None; n_materials];
    for (p, &m) in scene.particles.iter().zip(mass) {
        let slot = &mut lightest[p.material];
        if slot.is_none_or(|(lm, _)| m < lm) {
            *slot = Some((m, p.radius));
        }
        let slot = &mut heaviest[p.material];
        if slot.is_none_or(|(hm, _)| m > hm) {
            *slot = Some((m, p.radius));
        }
    }
    // the rule with the smallest limit, and the one with the smallest default step: a
    // contact's default (a fraction of its contact time) may be shorter than that of the
    // contact whose viscous limit binds
    let mut time_step: Option<TimeStep> = None;
    let mut shortest: Option<TimeStep> = None;
    // (the first rule whose step is not a finite number above 0: it would stop time)
    let mut unusable: Option<TimeStep> = None;
    // (each rule names its contact: in a scene of several materials, which to change)
    let mut consider = |mut ts: TimeStep, contact: String| {
        ts.reason = format!("{} [{contact}]", ts.reason);
        let usable = |t: f64| t.is_finite() && t > 0.0;
        if !(usable(ts.max) && usable(ts.default)) {
            unusable.get_or_insert(ts);
            return;
        }
        if shortest.as_ref().is_none_or(|t| ts.default < t.default) {
            shortest = Some(ts.clone());
        }
        if time_step.as_ref().is_none_or(|t| ts.max < t.max) {
            time_step = Some(ts);
        }
    };
    // the Hertz/JKR contact time follows the impact speed: the larger of the expected
    // one and the fastest closing the starting velocities allow
    let starting = starting_closing_speed(scene);
    let v_imp = if starting > scene.impact_velocity * (1.0 + 1e-9) {
        starting
    } else {
        scene.impact_velocity
    };
    for a in 0..n_materials {
        let Some((ma, ra)) = lightest[a] else {
            continue;
        };
        for b in 0..n_materials {
            let (Some(light), Some(heavy)) = (lightest[b], heaviest[b]) else {
                continue;
            };
            let contact = match a == b {
                true => format!("material `{}`", scene.materials[a].name),
                false => format!(
                    "materials `{}` and `{}`",
                    scene.materials[a].name, scene.materials[b].name
                ),
            };
            for (mb, rb) in [light, heavy] {
                let geom = PairGeometry::spheres(ra, rb, ma, mb);
                consider(
                    models[a * n_materials + b].time_step(&geom, v_imp),
                    contact.clone(),
                );
            }
        }
        for w in 0..scene.walls.len() {
            let geom = PairGeometry::wall(ra, ma);
            consider(
                wall_models[w * n_materials + a].time_step(&geom, v_imp),
                format!("wall {w} and material `{}`", scene.materials[a].name),
            );
        }
    }
    // the Rayleigh time of each JKR/Hertz material's smallest sphere
    for (a, material) in scene.materials.iter().enumerate() {
        if let (ContactModel::Jkr(p), Some((_, r))) = (&material.model, lightest[a]) {
            let t_r = p.rayleigh_time(r, material.density);
            consider(
                TimeStep::rayleigh(t_r, &material.name, r),
                format!("material `{}`", material.name),
            );
        }
    }
    if let Some(ts) = unusable {
        return Err(PowderError::Scene(format!(
            "the time step comes out as {:e} s (largest stable {:e} s; {}): the parameters of that contact are beyond what a time step can resolve (a stiffness, damping or velocity, or a density or radius that sets the mass, out of range)",
            ts.default, ts.max, ts.reason
        )));
    }
    let mut time_step =
        time_step.ok_or_else(|| PowderError::Scene("the scene has no particles".into()))?;
    if let Some(other) = shortest.filter(|o| o.default < time_step.default) {
        time_step.default = other.default;
        time_step.contact_time = time_step.contact_time.min(other.contact_time);
        time_step.reason += &format!(
            "; the default step {:.4e} s is another contact's ({})",
            other.default, other.reason
        );
    }
    if v_imp > scene.impact_velocity && time_step.reason.contains("impact velocity") {
        time_step.reason += &format!(
            " (the starting velocities close a pair at up to {v_imp:e} m/s, above simulation.impact_velocity = {:e} m/s)",
            scene.impact_velocity
        );
    }
    Ok(time_step)
}
