//! The linear spring–dashpot (LSD) model, f = k·δ + γ0·δ̇ (paper 000 eq. 2), the simplest
//! model and the check of the integrator against a closed form. As in eq. 2 the force is
//! not clamped at zero: the closed forms (eqs. 3–4) assume the same.

use crate::error::ParamError;
use crate::model::{LudingFriction, NormalForce};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
/// Parameters of the linear spring–dashpot model (paper 000 eq. 2).
pub struct LsdParams {
    /// Spring stiffness k, N/m.
    pub k: f64,
    /// Viscous damping γ0, kg/s.
    pub gamma0: f64,
    /// Luding's sliding, rolling and twisting friction ([`crate::model::friction`]); off by
    /// default. The Coulomb load is [`Self::coulomb_load`].
    #[serde(default)]
    pub luding: LudingFriction,
}

impl LsdParams {
    /// The spring–dashpot k, γ0 without friction.
    pub fn new(k: f64, gamma0: f64) -> Self {
        Self {
            k,
            gamma0,
            luding: LudingFriction::default(),
        }
    }

    /// Checks k > 0 and γ0 ≥ 0 (both finite) and the friction's rules.
    pub fn validate(&self) -> Result<(), ParamError> {
        crate::model::params::K.check(self.k)?;
        crate::model::params::GAMMA0.check(self.gamma0)?;
        self.luding.validate()
    }

    /// The Coulomb load of Luding's friction, f_N* = max(0, f_n) with f_n = k·δ + γ0·δ̇ (no
    /// adhesion to add).
    pub fn coulomb_load(&self, normal: &NormalForce) -> f64 {
        normal.force.max(0.0)
    }

    /// Normal force at overlap `delta` (m) and approach speed `delta_dot` (m/s): k·δ + γ0·δ̇
    /// for δ > 0 (not clamped at zero), nothing otherwise.
    pub fn force(&self, delta: f64, delta_dot: f64) -> NormalForce {
        if delta > 0.0 {
            let conservative = self.k * delta;
            NormalForce {
                force: conservative + self.gamma0 * delta_dot,
                conservative,
                potential: 0.5 * self.k * delta * delta,
                in_contact: true,
                contact_radius: 0.0,
                broke_within: None,
            }
        } else {
            NormalForce::default()
        }
    }
}
