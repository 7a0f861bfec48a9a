//! Luding's sliding friction: the tangential spring ξ_t and dashpot at the contact point
//! with the static/dynamic Coulomb limit ([`super::coulomb`]).
//!
//! v_t is the tangential velocity of particle i relative to j at the contact point (the
//! engine's, with the full radii as lever: v_i − v_j + r_i·n×ω_i + r_j·n×ω_j, projected
//! into the tangent plane). Before each step the stored spring is turned into the current
//! tangent plane keeping its length (Luding eq. 17 per LAMMPS, [`super::rotate_into_plane`]),
//! so a rigid rotation of the pair neither stores nor destroys energy. The force acts on i
//! at the contact point (−it on j); the engine applies the torques −r_i·n×f_t on i and
//! −r_j·n×f_t on j.

use super::coulomb::{CoulombSpring, Step};
use super::rotate_into_plane;
use crate::model::history::{HistoryField, HostField, Mirror, Shape, TANGENTIAL_SPRING};
use glam::DVec3;

/// The per-contact history of Luding's sliding law: the staggered spring (in the
/// evaluator's frame: the partner sees it negated) and whether it slipped in the last step
/// (its limit is then μd, [`super::coulomb`]).
pub const HISTORY: &[HistoryField] = &[
    TANGENTIAL_SPRING,
    HistoryField {
        name: "slipping",
        shape: Shape::Flag,
        mirror: Mirror::Same,
        host: HostField::Slipping,
        doc: "the sliding spring slipped in the last step",
    },
];

/// One step of the sliding law: `stored` is the staggered spring (history `tangential`),
/// `slipping` the flag (history `slipping`).
pub fn step(
    spring: &CoulombSpring,
    n: DVec3,
    v_t: DVec3,
    load: f64,
    dt: f64,
    stored: &mut DVec3,
    slipping: &mut bool,
) -> Step<DVec3> {
    *stored = rotate_into_plane(*stored, n);
    spring.step_slipping(stored, v_t, load, dt, slipping)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spring_follows_the_tangent_plane_and_keeps_its_length() {
        let s = CoulombSpring {
            mu_s: 1.0,
            mu_d: 1.0,
            k: 10.0,
            gamma: 0.0,
        };
        let mut xi = DVec3::new(0.0, 1e-3, 0.0);
        // the normal turned from x towards y by 0.1 rad
        let n = DVec3::new(0.1f64.cos(), 0.1f64.sin(), 0.0);
        let st = step(&s, n, DVec3::ZERO, 1.0, 1e-3, &mut xi, &mut false);
        assert!(xi.dot(n).abs() < 1e-18);
        assert!((xi.length() - 1e-3).abs() < 1e-15);
        assert!((st.force.length() - 1e-2).abs() < 1e-14);
    }
}
