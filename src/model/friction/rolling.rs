//! Luding's rolling resistance: a pseudo-force spring–dashpot on the rolling velocity
//! (Luding 2008 eq. 15 as MercuryDPM and AutoPas give it, `docs/luding2008_laws.md` §2).
//!
//! v_r = −ℓ·n×(ω_i − ω_j) with the lever ℓ = a12 = 2R* (paper 000's reduced radius,
//! MercuryDPM's convention: the particle radius for two equal spheres, 2r against a wall).
//! The spring ξ_r is kept in the tangent plane like the sliding spring. The pseudo-force f_r
//! exerts no force; its couple is ℓ·n×f_r on i and −ℓ·n×f_r on j, at most ℓ·μr·f_N*. The
//! couple's power ℓ(n×f_r)·(ω_i − ω_j) = f_r·v_r, so the energy ledger sees the pseudo-force
//! work. v_r does not change sign when the pair is seen from j (n and ω_i − ω_j both flip),
//! so neither does ξ_r.

use super::coulomb::{CoulombSpring, Step};
use super::rotate_into_plane;
use crate::model::history::{HistoryField, ROLLING_DISPLACEMENT};
use glam::DVec3;

/// The per-contact history of Luding's rolling spring (staggered; v_r and so the spring are
/// the same seen from the partner).
pub const HISTORY: &[HistoryField] = &[ROLLING_DISPLACEMENT];

/// The rolling velocity v_r = −ℓ·n×(ω_i − ω_j).
pub fn velocity(n: DVec3, omega_rel: DVec3, lever: f64) -> DVec3 {
    -lever * n.cross(omega_rel)
}

/// One step of the rolling law: the couple on i (−it on j) and the spring step; `stored` is
/// the staggered spring (history `rolling`).
pub fn step(
    spring: &CoulombSpring,
    n: DVec3,
    omega_rel: DVec3,
    lever: f64,
    load: f64,
    dt: f64,
    stored: &mut DVec3,
) -> (DVec3, Step<DVec3>) {
    *stored = rotate_into_plane(*stored, n);
    let st = spring.step(stored, velocity(n, omega_rel, lever), load, dt);
    (lever * n.cross(st.force), st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_couple_opposes_the_relative_rolling_rotation_up_to_its_limit() {
        let s = CoulombSpring {
            mu_s: 0.1,
            mu_d: 0.1,
            k: 1.0,
            gamma: 1e-3,
        };
        let n = DVec3::Z;
        let w = DVec3::new(0.0, 2.0, 0.0);
        let mut xi = DVec3::ZERO;
        let (torque, st) = step(&s, n, w, 1e-3, 1.0, 1e-4, &mut xi);
        assert!(!st.sliding);
        assert!(torque.dot(w) < 0.0, "{torque}");
        // the power of the couple is that of the pseudo-force on v_r
        let p = torque.dot(w) - st.force.dot(velocity(n, w, 1e-3));
        assert!(p.abs() < 1e-18);
        // a fast relative rotation saturates at ℓ·μr·f_N*
        let mut xi = DVec3::ZERO;
        let (torque, st) = step(&s, n, 1e6 * w, 1e-3, 1.0, 1e-4, &mut xi);
        assert!(st.sliding);
        assert!((torque.length() - 1e-3 * 0.1).abs() < 1e-15);
        assert!(torque.dot(w) < 0.0);
    }
}
