//! The linear spring–dashpot (LSD) model, f = k·δ + γ0·δ̇ (paper 000 eq. 2), the simplest
//! model and the check of the integrator against a closed form. As in eq. 2 the force is
//! not clamped at zero: the closed forms (eqs. 3–4) assume the same.

use crate::error::ParamError;
use crate::model::NormalForce;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
/// Parameters of the linear spring–dashpot model (paper 000 eq. 2).
pub struct LsdParams {
    /// Spring stiffness k, N/m.
    pub k: f64,
    /// Viscous damping γ0, kg/s.
    pub gamma0: f64,
}

impl LsdParams {
    /// Checks k > 0 and γ0 ≥ 0 (both finite).
    pub fn validate(&self) -> Result<(), ParamError> {
        crate::model::params::K.check(self.k)?;
        crate::model::params::GAMMA0.check(self.gamma0)
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
            }
        } else {
            NormalForce::default()
        }
    }
}
