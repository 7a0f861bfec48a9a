//! The rolling resistance of the JKR family (Dominik–Tielens/Krijt, paper 002 eqs. 18–22):
//! the f64 reference of `shaders/model/jkr/rolling.wgsl`.

use super::JkrParams;
use crate::model::friction::rotate_into_plane;
use crate::model::history::{HistoryField, ROLLING_DISPLACEMENT};
use crate::model::{NormalForce, PairGeometry};
use glam::DVec3;

/// The per-contact history of the JKR rolling resistance.
pub const HISTORY: &[HistoryField] = &[ROLLING_DISPLACEMENT];

/// Rolling-resistance torque of one contact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rolling {
    /// Torque on particle i; on j it is the negative.
    pub torque: DVec3,
    /// Rolling stiffness kr = 4Fc·(a/a0)^(3/2), N (the spring energy is ½·kr·|ξ|²).
    pub stiffness: f64,
    /// Whether ξ was truncated to ξcrit (irreversible rolling).
    pub yielding: bool,
}

impl JkrParams {
    /// Rolling-resistance torque on particle i (Dominik–Tielens/Krijt, paper 002
    /// eqs. 18–22).
    ///
    /// `v_roll` is the rolling velocity of eq. 20 and `xi` the stored rolling displacement
    /// ξ: rotated into the tangent plane keeping its length (as the tangential spring),
    /// ξ += v_roll·dt, truncated to |ξ| ≤ ξcrit = (a0/12)·(Δγ/γ) (`yielding` when
    /// truncated). kr = 4Fc·(a/a0)^(3/2) and torque = −kr·(n × ξ) on i (+kr·(n × ξ) on j).
    ///
    /// Direction: with v_roll = R*(ω_i − ω_j) × n, ξ grows along (ω_i − ω_j) × n and
    /// n × ((ω_i − ω_j) × n) is the tangential part of ω_i − ω_j, so the torque on i opposes
    /// the relative rolling rotation ω_i − ω_j.
    ///
    /// Reduced stiffness (paper 002 §3.2): Fc and a0 in ξcrit and in the prefactor 4Fc are
    /// the unscaled values; only the ratio a/a0 uses the modified a and a0.
    /// Zero (and ξ zeroed) without rolling hysteresis, without surface energy or out of
    /// contact.
    pub fn rolling_torque(
        &self,
        n: DVec3,
        v_roll: DVec3,
        normal: &NormalForce,
        geom: &PairGeometry,
        dt: f64,
        xi: &mut DVec3,
    ) -> Rolling {
        if self.rolling_hysteresis == 0.0 || self.surface_energy == 0.0 || !normal.in_contact {
            *xi = DVec3::ZERO;
            return Rolling::default();
        }
        let r = 0.5 * geom.a12;
        let mut x = rotate_into_plane(*xi, n) + v_roll * dt;
        let xi_crit = self.a0_unscaled(r) / 12.0 * self.rolling_hysteresis;
        let len = x.length();
        let yielding = len > xi_crit;
        if yielding {
            x *= xi_crit / len;
        }
        *xi = x;
        let ratio = normal.contact_radius / self.a0(r);
        let kr = 4.0 * self.fc_unscaled(r) * ratio * ratio.sqrt();
        Rolling {
            torque: -kr * n.cross(x),
            stiffness: kr,
            yielding,
        }
    }
}
