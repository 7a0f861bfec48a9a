//! Whether an engine was built from the scene a run or a checkpoint is given with.

use crate::error::PowderError;
use crate::scene::{DtSetting, Scene};

/// Refuses an engine of `n` particles with `radii`, `walls` walls and time step `dt` for
/// `scene` when it cannot have been built from it (another scene's engine would write
/// outputs and checkpoints under this scene's name, or index walls it does not have).
pub(crate) fn engine_fits(
    scene: &Scene,
    radii: &[f64],
    walls: usize,
    dt: f64,
) -> Result<(), PowderError> {
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
    Ok(())
}
