//! Luding's twisting (torsion) resistance: a pseudo-force spring–dashpot on the spin about
//! the normal (Luding 2008 eq. 16 as MercuryDPM gives it, `docs/luding2008_laws.md` §3).
//!
//! v_o = ℓ·[n·(ω_i − ω_j)]·n with ℓ = a12 = 2R* (as rolling). The spring is kept along n
//! and stored as the scalar ξ_o = n·ξ_o: n and ξ_o both flip when the pair is seen from j, so
//! the scalar is the same from either side. The couple is ℓ·f_o·n on i (−it on j), f_o the
//! scalar pseudo-force, at most ℓ·μo·f_N*; its power ℓ·f_o·n·(ω_i − ω_j) = f_o·v_o.

use super::coulomb::{CoulombSpring, Step};
use crate::model::history::{HistoryField, HostField, Mirror, Shape};
use glam::DVec3;

/// The per-contact history of Luding's twisting spring: a scalar along n, the same seen from
/// the partner.
pub const HISTORY: &[HistoryField] = &[HistoryField {
    name: "twist",
    shape: Shape::Word,
    mirror: Mirror::Same,
    host: HostField::Twist,
    doc: "the twisting spring along n, m",
}];

/// The twisting speed along n, ℓ·n·(ω_i − ω_j).
pub fn velocity(n: DVec3, omega_rel: DVec3, lever: f64) -> f64 {
    lever * n.dot(omega_rel)
}

/// One step of the twisting law with stiffness `k` (the declared k_o, or the JKR family's
/// current one): the couple on i (−it on j) and the spring step; `stored` is the staggered
/// scalar spring (history `twist`).
#[allow(clippy::too_many_arguments)]
pub fn step(
    spring: &CoulombSpring,
    k: f64,
    n: DVec3,
    omega_rel: DVec3,
    lever: f64,
    load: f64,
    dt: f64,
    stored: &mut f64,
) -> (DVec3, Step<f64>) {
    let st = spring.step_with(k, stored, velocity(n, omega_rel, lever), load, dt);
    (lever * st.force * n, st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_couple_opposes_the_spin_and_is_the_same_seen_from_the_partner() {
        let s = CoulombSpring {
            mu_s: 0.2,
            mu_d: 0.2,
            k: 5.0,
            gamma: 0.0,
        };
        let n = DVec3::new(0.0, 0.6, 0.8);
        let w = DVec3::new(1.0, 2.0, 3.0);
        let (mut a, mut b) = (0.0, 0.0);
        for _ in 0..10 {
            let (ti, si) = step(&s, s.k, n, w, 1e-3, 1.0, 1e-3, &mut a);
            let (tj, sj) = step(&s, s.k, -n, -w, 1e-3, 1.0, 1e-3, &mut b);
            assert_eq!(a, b, "the stored scalar is the same from both sides");
            assert_eq!(si.force, sj.force);
            // the couple on j seen from j is −(the couple on i)
            assert!((ti + tj).length() < 1e-18);
            assert!(ti.dot(w) < 0.0);
        }
    }
}
