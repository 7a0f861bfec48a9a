//! The tangential spring of the JKR family (Mindlin with Thornton's adhesive Coulomb limit,
//! paper 002 eqs. 14–17): the f64 reference of `shaders/model/jkr/mindlin.wgsl`.

use super::{Dissipation, JkrPair, JkrParams, TSUJI_PREFACTOR};
use crate::model::friction::rotate_into_plane;
use crate::model::history::{HistoryField, TANGENTIAL_SPRING};
use crate::model::{Kinematics, NormalForce, PairGeometry};
use glam::DVec3;

/// The per-contact history of the Mindlin tangential spring (kept in the evaluator's frame).
pub const HISTORY: &[HistoryField] = &[TANGENTIAL_SPRING];

/// Tangential force of one contact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tangential {
    /// Force on particle i (−this on j), N.
    pub force: DVec3,
    /// Tangential stiffness St = 8G*·a, N/m (the spring energy is ½·St·|s|²).
    pub stiffness: f64,
    /// Whether the Coulomb limit truncated the force.
    pub sliding: bool,
}

impl JkrParams {
    /// Tangential force on particle i (paper 002 eqs. 14–17).
    ///
    /// Of the kinematics `k` it takes the normal n, the overlap δ and `v_t`, the tangential
    /// velocity of i relative to j at the contact point (already in the tangent plane);
    /// `spring` is the stored displacement s (history). Steps: the spring
    /// is rotated into the current tangent plane keeping its length (see
    /// `rotate_into_plane`: a rigid rotation of the pair must not change the stored
    /// energy), s += v_t·dt, St = 8G*·a, and
    /// F = −St·s − c_t·v_t with c_t = −2√(5/6)·β·√(St'·m*) ≥ 0 (Tsuji only; β < 0), where
    /// St' = 8G*·ρ with ρ of [`TsujiStiffness`](super::TsujiStiffness) (a, or √(R*·δ)).
    /// The force is truncated to |F| ≤ μs·|F_N + 2Fc| (eq. 17) with F_N the conservative
    /// (elastic) normal force; when truncated, F is set to the limit along its direction and
    /// the spring to s = −(F + c_t·v_t)/St, and `sliding` is true.
    /// Without friction or contact the spring is zeroed and there is no force.
    pub fn tangential_force(
        &self,
        k: &Kinematics,
        normal: &NormalForce,
        geom: &PairGeometry,
        dt: f64,
        spring: &mut DVec3,
    ) -> Tangential {
        let pair = self.pair(0.5 * geom.a12);
        self.tangential_force_of_pair(&pair, (k, normal), geom, dt, spring)
    }

    /// [`Self::tangential_force`] with the pair's constants ([`JkrParams::pair`] of
    /// R* = a12/2).
    pub fn tangential_force_of_pair(
        &self,
        pair: &JkrPair,
        (k, normal): (&Kinematics, &NormalForce),
        geom: &PairGeometry,
        dt: f64,
        spring: &mut DVec3,
    ) -> Tangential {
        if self.friction == 0.0 || !normal.in_contact {
            *spring = DVec3::ZERO;
            return Tangential::default();
        }
        let (n, v_t, delta) = (k.n, k.v_t, k.delta);
        let r = 0.5 * geom.a12;
        let mut s = rotate_into_plane(*spring, n) + v_t * dt;
        let gs8 = 8.0 * pair.gs;
        let st = gs8 * normal.contact_radius;
        let ct = match self.dissipation {
            Dissipation::Tsuji { stiffness, .. } => {
                // the dashpot's St: the spring's 8G*·a, or paper 002's 8G*·√(R*δ)
                let st_damp = gs8 * stiffness.radius(normal.contact_radius, delta, r);
                -TSUJI_PREFACTOR * pair.beta * (st_damp * geom.reduced_mass).sqrt()
            }
            _ => 0.0,
        };
        let mut force = -st * s - ct * v_t;
        let limit = self.friction * (normal.conservative + 2.0 * pair.fc).abs();
        let magnitude2 = force.length_squared();
        let mut sliding = false;
        if magnitude2 > limit * limit {
            sliding = true;
            force *= limit / magnitude2.sqrt();
            if st > 0.0 {
                s = -(force + ct * v_t) / st;
            }
        }
        *spring = s;
        Tangential {
            force,
            stiffness: st,
            sliding,
        }
    }
}
