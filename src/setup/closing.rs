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

/// A bound on every closing speed at the start: the diagonal of the bounding box of the
/// particles' starting velocities, or a wall's speed along its normal (a prescribed one,
/// or a servo's first step, min(gain·force, max_speed)) less the slowest particle's there,
/// the larger; particles moving together close nothing, nor does a wall moving away.
pub(super) fn velocity_spread(scene: &Scene) -> f64 {
    let particles = || (scene.particles.iter()).map(|p| DVec3::from_array(p.velocity));
    let (lo, hi) = particles().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    let d = (hi - lo).max(DVec3::ZERO);
    // (components beyond 1.3e154 overflow the squares of a length f64 holds)
    let pairs = match (d.length(), d.max_element()) {
        (length, m) if length.is_infinite() && m.is_finite() => (d / m).length() * m,
        (length, _) => length,
    };
    // a wall closes at its speed toward the particles' side less the slowest particle's
    // along its normal (a receding wall closes on none)
    let walls = scene.walls.iter().map(|w| {
        let n = DVec3::from_array(w.normal).normalize_or_zero();
        let wall = wall_normal_velocity(w, &w.motion.at(0.0)).dot(n);
        let slowest = particles().map(|v| v.dot(n)).fold(f64::INFINITY, f64::min);
        (wall - slowest).max(0.0)
    });
    walls.fold(pairs, f64::max)
}
