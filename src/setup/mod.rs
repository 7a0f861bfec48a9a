//! What every backend derives from a scene before stepping: the pair-model tables, the
//! particle masses, the time step and the largest interaction reach. One place, so the
//! CPU and GPU engines run exactly the same physics set-up.

mod closing;
mod start_checks;
#[cfg(test)]
mod tests;
mod time_step;

use crate::error::PowderError;
use crate::model::{ContactModel, TimeStep};
use crate::scene::{DtSetting, MaterialUse, Scene};

/// The most steps a run counts: steps and times (step·dt) are exact to here.
pub const MAX_STEPS: u64 = 1 << 53;

/// The coarsest f64 position spacing in the domain accepted, over the smallest radius.
pub const POSITION_RESOLUTION: f64 = 1e-6;

/// A scene resolved for stepping.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// Number of materials.
    pub n_materials: usize,
    /// Pair models, n_materials × n_materials (row = first particle's material).
    pub models: Vec<ContactModel>,
    /// Wall models, walls × n_materials.
    pub wall_models: Vec<ContactModel>,
    /// Particle masses, kg, in scene order.
    pub mass: Vec<f64>,
    /// The time step used and the rule it was checked against.
    pub dt: f64,
    /// The most restrictive time-step rule over all material pairs, walls and the Rayleigh
    /// guard (default, largest accepted dt, reason).
    pub time_step: TimeStep,
    /// Largest radius, m.
    pub r_max: f64,
    /// Largest distance beyond touching at which any pair interacts (the non-contact
    /// range, or how far a JKR neck stretches), at the largest radius, m.
    pub max_reach: f64,
    /// Whether some contact model needs angular velocities.
    pub rotation: bool,
}

impl Resolved {
    /// Resolves `scene`: pair and wall models, masses, the time step (checked against its
    /// rule unless `force_dt`), the largest radius and reach.
    pub fn new(scene: &Scene) -> Result<Self, PowderError> {
        // (a scene built in code has not met the reader's checks)
        scene.validate()?;
        let n_materials = scene.materials.len();
        let uses = MaterialUse::of(scene);
        let (models, wall_models) = pair_tables(scene, &uses)?;
        let mass = masses(scene)?;
        let time_step = time_step::resolve(scene, &models, &wall_models, &mass)?;
        check_adhesion_scales(scene, &uses, &models, &wall_models)?;
        let dt = chosen_dt(scene, &time_step)?;
        start_checks::check(scene, dt, &time_step)?;
        let r_max = scene.particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        let max_reach = models
            .iter()
            .map(|m| m.reach(0.5 * r_max))
            .chain(wall_models.iter().map(|m| m.reach(r_max)))
            .fold(0.0, f64::max);
        let rotation = models
            .iter()
            .chain(&wall_models)
            .any(ContactModel::needs_rotation);
        if !rotation {
            no_spin(scene)?;
        }
        Ok(Self {
            n_materials,
            models,
            wall_models,
            mass,
            dt,
            time_step,
            r_max,
            max_reach,
            rotation,
        })
    }
}

/// The pair models, n_materials × n_materials, and the wall models, walls × n_materials: a
/// pair of materials that never meets (no particle of one of them) needs no model; the
/// first material's own stands in, never evaluated.
fn pair_tables(
    scene: &Scene,
    uses: &MaterialUse,
) -> Result<(Vec<ContactModel>, Vec<ContactModel>), PowderError> {
    let n_materials = scene.materials.len();
    let model = |a: usize, b: usize| match scene.pair_model(a, b) {
        Err(_) if !uses.meet(a, b) => Ok(scene.materials[a].model),
        found => found,
    };
    let mut models = Vec::with_capacity(n_materials * n_materials);
    for a in 0..n_materials {
        for b in 0..n_materials {
            models.push(model(a, b)?);
        }
    }
    let mut wall_models = Vec::with_capacity(scene.walls.len() * n_materials);
    for w in &scene.walls {
        for b in 0..n_materials {
            wall_models.push(model(w.material, b)?);
        }
    }
    Ok((models, wall_models))
}

/// Each particle's mass in scene order, kg (a radius and density each in range can still
/// give a mass of 0 or ∞ in f64: refused, naming the particle).
fn masses(scene: &Scene) -> Result<Vec<f64>, PowderError> {
    let mass: Vec<f64> = scene
        .particles
        .iter()
        .map(|p| crate::scene::sphere_mass(scene.materials[p.material].density, p.radius))
        .collect();
    if let Some((i, m)) = mass
        .iter()
        .enumerate()
        .find(|(_, m)| !(m.is_finite() && **m > 0.0))
    {
        let p = &scene.particles[i];
        let material = &scene.materials[p.material];
        return Err(PowderError::Scene(format!(
            "particle {i}: its mass comes out as {m:e} kg (radius {:e} m, density {:e} kg/m^3 of material `{}`): choose a radius and density whose mass 4/3·π·r³·ρ is a finite number above 0",
            p.radius, material.density, material.name
        )));
    }
    Ok(mass)
}

/// A JKR adhesion too weak for f64 at the largest radius of the pair (the weakest),
/// between particles or against a wall, refused naming its materials.
fn check_adhesion_scales(
    scene: &Scene,
    uses: &MaterialUse,
    models: &[ContactModel],
    wall_models: &[ContactModel],
) -> Result<(), PowderError> {
    let n_materials = scene.materials.len();
    let mut largest = vec![0f64; n_materials];
    for p in &scene.particles {
        largest[p.material] = largest[p.material].max(p.radius);
    }
    let pairs = (0..n_materials).flat_map(|a| (0..n_materials).map(move |b| (a, b)));
    for (a, b) in pairs.filter(|&(a, b)| uses.particles[a] && uses.particles[b]) {
        if let ContactModel::Jkr(p) = &models[a * n_materials + b] {
            let r_eff = largest[a] * largest[b] / (largest[a] + largest[b]);
            p.check_adhesion_scale(r_eff).map_err(|e| {
                let names = [a, b].map(|m| scene.materials[m].name.as_str());
                PowderError::Scene(format!("materials `{}` and `{}`: {e}", names[0], names[1]))
            })?;
        }
    }
    for (w, wall) in scene.walls.iter().enumerate() {
        for b in (0..n_materials).filter(|&b| uses.particles[b]) {
            if let ContactModel::Jkr(p) = &wall_models[w * n_materials + b] {
                p.check_adhesion_scale(largest[b]).map_err(|e| {
                    let m = &scene.materials[b].name;
                    PowderError::Scene(format!(
                        "wall {w} (material `{}`) and material `{m}`: {e}",
                        scene.materials[wall.material].name
                    ))
                })?;
            }
        }
    }
    Ok(())
}

/// The step a run takes: the automatic one, or the scene's, refused above the stable limit
/// unless forced.
fn chosen_dt(scene: &Scene, time_step: &TimeStep) -> Result<f64, PowderError> {
    Ok(match scene.dt {
        DtSetting::Auto => time_step.default,
        DtSetting::Fixed(dt) => {
            if dt > time_step.max && !scene.force_dt {
                return Err(PowderError::Scene(format!(
                    "dt = {dt:e} s is above the stable limit {:.4e} s ({}); use dt <= {} s or set force_dt = true",
                    time_step.max,
                    time_step.reason,
                    crate::error::sci_at_most(time_step.max, 4)
                )));
            }
            dt
        }
    })
}

/// A scene whose laws do not turn particles may not start one spinning.
fn no_spin(scene: &Scene) -> Result<(), PowderError> {
    let spinning =
        (scene.particles.iter().enumerate()).find(|(_, p)| p.angular_velocity != [0.0; 3]);
    if let Some((i, p)) = spinning {
        return Err(PowderError::Scene(format!(
            "particle {i} starts with angular_velocity = {:?} rad/s, but no contact model of the scene has friction, rolling or twisting resistance, so particles do not rotate: remove angular_velocity or give the model friction",
            p.angular_velocity
        )));
    }
    Ok(())
}
