//! Whether an engine was built from the scene a run or a checkpoint is given with.

use crate::error::PowderError;
use crate::run::simulation::Simulation;
use crate::scene::{DtSetting, Scene};

/// Refuses `engine` for `scene` when it was not built from it (another scene's engine would
/// write outputs and checkpoints under this scene's name, or index walls it does not
/// have): its particles' count and radii, walls, dt, and then every part of the scene but
/// its name, duration and output cadences (by digest, naming the parts).
pub(crate) fn engine_fits<S: Simulation>(scene: &Scene, engine: &S) -> Result<(), PowderError> {
    let (radii, walls, dt) = (engine.radii(), engine.wall_count(), engine.dt());
    let refuse = |what: String| {
        Err(PowderError::Run(format!(
            "the engine was not built from scene `{}`: {what}; build the engine from the scene the run is given",
            scene.name
        )))
    };
    if radii.len() != scene.particles.len() || walls != scene.walls.len() {
        return refuse(format!(
            "it has {} particles and {walls} walls, the scene {} and {}",
            radii.len(),
            scene.particles.len(),
            scene.walls.len()
        ));
    }
    if let Some(i) =
        (0..radii.len()).find(|&i| radii[i].to_bits() != scene.particles[i].radius.to_bits())
    {
        return refuse(format!(
            "particle {i}'s radius is {:e} m there, {:e} m in the scene",
            radii[i], scene.particles[i].radius
        ));
    }
    if let DtSetting::Fixed(d) = scene.dt {
        if d.to_bits() != dt.to_bits() {
            return refuse(format!("its dt is {dt:e} s, the scene's {d:e} s"));
        }
    }
    let ours = crate::checkpoint::run_digests(scene, f64::INFINITY).1;
    let theirs = engine.scene_parts();
    let differ: Vec<&str> = (ours.iter().chain(theirs))
        .filter(|part| !(ours.contains(part) && theirs.contains(part)))
        .map(|(name, _)| name.as_str())
        .fold(Vec::new(), |mut v, n| {
            if !v.contains(&n) {
                v.push(n);
            }
            v
        });
    if !differ.is_empty() {
        return refuse(format!("they differ in {}", differ.join(", ")));
    }
    Ok(())
}
