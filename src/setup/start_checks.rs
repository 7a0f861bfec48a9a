//! What a scene asks that a run at its time step cannot do: positions f64 does not
//! resolve, runs and events beyond the steps a run counts, particles or walls that can pass
//! through each other between two steps.

use super::closing::{velocity_spread, wall_normal_velocity};
use super::{MAX_STEPS, POSITION_RESOLUTION};
use crate::error::{num, PowderError};
use crate::model::TimeStep;
use crate::scene::{DtSetting, Scene};

/// Refuses what the run at `dt` (checked against `time_step`'s rule) cannot do.
pub(super) fn check(scene: &Scene, dt: f64, time_step: &TimeStep) -> Result<(), PowderError> {
    let r_min = (scene.particles.iter())
        .map(|p| p.radius)
        .fold(f64::INFINITY, f64::min);
    resolved_positions(scene, r_min)?;
    countable_steps(scene, dt, time_step)?;
    no_pass_through(scene, dt, r_min)
}

/// Positions are f64 coordinates: they must resolve far below a radius anywhere in the
/// domain (a domain of ±1e20 m rounded every position to 0).
fn resolved_positions(scene: &Scene, r_min: f64) -> Result<(), PowderError> {
    for a in 0..3 {
        let far = scene.domain.min[a].abs().max(scene.domain.max[a].abs());
        let ulp = f64::from_bits(far.to_bits() + 1) - far;
        if ulp > POSITION_RESOLUTION * r_min {
            return Err(PowderError::Scene(format!(
                "the domain reaches {far:e} m on axis {}, where f64 positions resolve only {ulp:e} m, more than {POSITION_RESOLUTION:e} of the smallest radius {r_min:e} m: shrink the domain or move it nearer the origin",
                ["x", "y", "z"][a]
            )));
        }
    }
    Ok(())
}

/// Steps are counted in u64 and times are step·dt in f64: both exact up to 2^53 steps; a
/// run or an event beyond that would never end or never come.
fn countable_steps(scene: &Scene, dt: f64, time_step: &TimeStep) -> Result<(), PowderError> {
    let rule = match scene.dt {
        DtSetting::Auto => format!("the automatic dt, {}", time_step.reason),
        DtSetting::Fixed(_) => "simulation.dt".to_string(),
    };
    let beyond = |t: f64| t.is_nan() || t / dt > MAX_STEPS as f64;
    // (an infinite duration runs until its caller stops it: `collide`)
    if scene.duration.is_finite() && beyond(scene.duration) {
        return Err(PowderError::Scene(format!(
            "simulation.duration = {:e} s is {:.3e} steps of dt = {dt:e} s ({rule}), beyond the {MAX_STEPS} steps a run can count: shorten the run or check the parameter that sets dt",
            scene.duration,
            scene.duration / dt
        )));
    }
    let events = (scene.particles.iter().enumerate())
        .map(|(i, p)| (format!("particle {i}'s insert_at"), p.insert_at))
        .chain(scene.walls.iter().enumerate().flat_map(|(w, wall)| {
            (wall.motion.phases.iter()).map(move |(t, _)| (format!("wall {w}'s phase time"), *t))
        }));
    for (what, t) in events {
        if beyond(t) {
            return Err(PowderError::Scene(format!(
                "{what} {t:e} s is {:.3e} steps of dt = {dt:e} s ({rule}), beyond the {MAX_STEPS} steps a run can count: an event that late never comes; remove it or bring it within the run",
                t / dt
            )));
        }
    }
    Ok(())
}

/// A pair closing more than a radius in one step can pass through each other unseen (the
/// monitor only sees overlaps at the ends of steps): at the start, or where a wall's later
/// phase moves it that fast; a forced dt accepts it.
fn no_pass_through(scene: &Scene, dt: f64, r_min: f64) -> Result<(), PowderError> {
    let closing = velocity_spread(scene);
    if let Some((i, p)) = scene
        .particles
        .iter()
        .enumerate()
        .find(|(_, p)| !scene.force_dt && closing * dt > p.radius)
    {
        // (velocities of opposite signs near f64's limit differ by more than it holds)
        let spread = match (closing.is_finite(), (closing * dt).is_finite()) {
            (true, true) => format!("by up to {closing:e} m/s: a pair (or a particle and a wall) closes {:e} m in a step of {dt:e} s", closing * dt),
            (true, false) => format!("by up to {closing:e} m/s: a pair (or a particle and a wall) closes more than {:e} m in a step of {dt:e} s", f64::MAX),
            _ => format!("by more than f64 holds: a pair (or a particle and a wall) closes farther than f64 measures in a step of {dt:e} s"),
        };
        return Err(PowderError::Scene(format!(
            "the starting velocities differ {spread}, more than the radius {:e} m of particle {i}, and can pass through each other between two steps; lower the velocities or set a smaller simulation.dt (the automatic one follows simulation.impact_velocity for Hertz and JKR contacts), or force_dt = true to run it anyway",
            p.radius
        )));
    }
    // a wall's later phases, which the starting spread does not see
    for (w, wall) in scene.walls.iter().enumerate() {
        for (k, (from, phase)) in wall.motion.phases.iter().enumerate() {
            // (toward the particles' side: one moving away cannot pass them)
            let n = glam::DVec3::from_array(wall.normal).normalize_or_zero();
            let speed = wall_normal_velocity(wall, phase).dot(n).max(0.0);
            let during = *from > 0.0 && *from < scene.duration;
            if !scene.force_dt && during && speed * dt > r_min {
                return Err(PowderError::Scene(format!(
                    "wall {w}'s motion from t = {} s (its phase or schedule entry {k}) moves it at up to {speed:.4e} m/s toward the particles' side: it closes {:.4e} m in a step of {dt:.4e} s, more than the smallest particle radius {} m, and particles can pass through it between two steps; slow that motion or set a smaller simulation.dt, or force_dt = true to run it anyway",
                    num(*from),
                    speed * dt,
                    num(r_min)
                )));
            }
        }
    }
    Ok(())
}
