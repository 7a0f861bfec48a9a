//! How fast particles and walls can close at the start: what the time step and the
//! pass-through checks bound.

use crate::scene::{Scene, Wall, WallPhase};
use glam::DVec3;

/// The fastest a pair (or a particle and a wall) can close at the start, m/s: with two
/// particles moving on straight lines (no walls, periodic axes or pours) their approach
/// along the line of centres (0 when they part), otherwise [`velocity_spread`].
pub(super) fn starting_closing_speed(scene: &Scene) -> f64 {
    let v = |i: usize| DVec3::from_array(scene.particles[i].velocity);
    let alone = scene.walls.is_empty() && !scene.domain.any_periodic() && !scene.pours();
    if scene.particles.len() == 2 && alone {
        let x = |i: usize| DVec3::from_array(scene.particles[i].position);
        let n = (x(1) - x(0)).normalize_or_zero();
        return (v(0) - v(1)).dot(n).max(0.0);
    }
    velocity_spread(scene)
}

/// The velocity along its normal a wall moves with in `phase` (under servo control the
/// largest it starts with), m/s.
pub(super) fn wall_normal_velocity(w: &Wall, phase: &WallPhase) -> DVec3 {
    let n = DVec3::from_array(w.normal).normalize_or_zero();
    match *phase {
        WallPhase::Rest => DVec3::ZERO,
        WallPhase::Velocity(v) => n * DVec3::from_array(v).dot(n),
        WallPhase::Servo {
            force,
            gain,
            max_speed,
        } => n * (gain * force).min(max_speed),
    }
}

/// A bound on every relative speed at the start: the diagonal of the bounding box of the
/// particles' starting velocities and the walls' along their normals (a prescribed one, or
/// a servo's first step, min(gain·force, max_speed)); particles moving together close
/// nothing.
pub(super) fn velocity_spread(scene: &Scene) -> f64 {
    let velocities = (scene.particles.iter())
        .map(|p| DVec3::from_array(p.velocity))
        .chain((scene.walls.iter()).map(|w| wall_normal_velocity(w, &w.motion.at(0.0))));
    let (lo, hi) = velocities.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    let d = (hi - lo).max(DVec3::ZERO);
    // (components beyond 1.3e154 overflow the squares of a length f64 holds)
    match (d.length(), d.max_element()) {
        (length, m) if length.is_infinite() && m.is_finite() => (d / m).length() * m,
        (length, _) => length,
    }
}
