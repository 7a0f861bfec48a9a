//! The reduced-stiffness rule of paper 002 (§3, §6.2): what a stiffness scale S ≠ 1 changes.

use super::JkrParams;
use crate::error::fixed;
use std::fmt;

/// What a reduced stiffness S ≠ 1 changes (paper 002 §3, §6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StiffnessScaling {
    /// S = Emod/E.
    pub scale: f64,
    /// γmod/γ = S^(2/5) (paper 002 eq. 24); also the factor on the pull-off force Fc.
    pub surface_energy_factor: f64,
    /// Δtcol,mod/Δtcol = (E/Emod)^(2/5) = S^(−2/5) (paper 002 §6.2).
    pub collision_time_factor: f64,
    /// How much larger the time step may be at a fixed number of steps per collision
    /// (the same factor as the collision time).
    pub dt_gain: f64,
    /// Fc,mod/Fc = S^(2/5): the force needed to separate two particles drops.
    pub pulloff_force_factor: f64,
}

impl fmt::Display for StiffnessScaling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stiffness_scale S = {:.4e}: E -> S*E and surface_energy -> surface_energy*S^(2/5) = {}*surface_energy (paper 002 eq. 24); \
             collisions last S^(-2/5) = {} times longer, so dt can grow by the same factor {} (paper 002 sec. 6.2). \
             Warning: the pull-off force Fc = 3*pi*gamma*R* drops by S^(2/5) = {}; keep external separating forces \
             (drag, shear) well below Fc,mod (paper 002 sec. 6.2)",
            self.scale,
            fixed(self.surface_energy_factor, 4),
            fixed(self.collision_time_factor, 4),
            fixed(self.dt_gain, 4),
            fixed(self.pulloff_force_factor, 4)
        )?;
        if self.scale < 1e-3 {
            write!(
                f,
                ". S < 1e-3 may change the behaviour of dense agglomerates (paper 002 sec. 6.2)"
            )?;
        }
        Ok(())
    }
}

impl JkrParams {
    /// What the stiffness scale changes; `None` when S = 1.
    pub fn stiffness_scaling(&self) -> Option<StiffnessScaling> {
        if self.stiffness_scale == 1.0 {
            return None;
        }
        let g = self.stiffness_scale.powf(0.4);
        Some(StiffnessScaling {
            scale: self.stiffness_scale,
            surface_energy_factor: g,
            collision_time_factor: 1.0 / g,
            dt_gain: 1.0 / g,
            pulloff_force_factor: g,
        })
    }

    /// Human-readable report of [`Self::stiffness_scaling`] (with the pull-off warning of
    /// paper 002 §6.2); `None` when S = 1.
    pub fn stiffness_scaling_report(&self) -> Option<String> {
        self.stiffness_scaling().map(|s| s.to_string())
    }
}
