//! Contact models, one module per model, in f64: the physics reference that the GPU
//! kernels are checked against.

pub mod analytic;
pub mod hysteretic;
pub mod jkr;
pub mod lsd;

pub use hysteretic::{AdhesionMode, HystereticParams, K2Rule};
pub use lsd::LsdParams;

use crate::error::ParamError;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Per-contact history that survives between steps (and, on the GPU, re-sorting).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactHistory {
    /// Largest overlap reached on the current branch family (δmax).
    pub delta_max: f64,
    /// Whether the pair has touched since it last left the interaction range
    /// (jump-in adhesion acts only after the first touch; a JKR contact persists into
    /// negative overlap until pull-off).
    pub touched: bool,
    /// Tangential spring displacement, kept in the current tangent plane (JKR friction).
    pub tangential: DVec3,
    /// Rolling displacement ξ, kept in the current tangent plane (JKR rolling resistance).
    pub rolling: DVec3,
}

/// The normal force of one contact and what the energy bookkeeping needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NormalForce {
    /// Total normal force, repulsive positive (conservative + viscous).
    pub force: f64,
    /// The rate-independent part (no viscous term).
    pub conservative: f64,
    /// Stored (recoverable) energy of the contact in its current state.
    pub potential: f64,
    /// Mechanical contact, as opposed to the non-contact range (for JKR: from the first
    /// touch until pull-off, also at negative overlap).
    pub in_contact: bool,
    /// Contact radius a, m (JKR/Hertz; 0 for the piece-wise linear models).
    pub contact_radius: f64,
}

/// Pair properties the normal force laws need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairGeometry {
    /// Reduced radius a12 = 2·a1·a2/(a1 + a2) (paper 000 eq. 11); 2·a for a wall.
    pub a12: f64,
    /// Reduced mass m1·m2/(m1 + m2); m for a wall.
    pub reduced_mass: f64,
}

impl PairGeometry {
    pub fn spheres(r1: f64, r2: f64, m1: f64, m2: f64) -> Self {
        Self {
            a12: 2.0 * r1 * r2 / (r1 + r2),
            reduced_mass: m1 * m2 / (m1 + m2),
        }
    }

    pub fn wall(r: f64, m: f64) -> Self {
        Self {
            a12: 2.0 * r,
            reduced_mass: m,
        }
    }
}

/// A normal contact model with its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum ContactModel {
    Hysteretic(HystereticParams),
    Lsd(LsdParams),
}

impl ContactModel {
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Self::Hysteretic(p) => p.validate(),
            Self::Lsd(p) => p.validate(),
        }
    }

    /// Non-contact interaction range (how far beyond touching a pair still interacts), m.
    pub fn range(&self) -> f64 {
        match self {
            Self::Hysteretic(p) => p.range(),
            Self::Lsd(_) => 0.0,
        }
    }

    /// Stiffest branch, N/m, for the time-step rule.
    pub fn stiffest(&self) -> f64 {
        match self {
            Self::Hysteretic(p) => p.stiffest(),
            Self::Lsd(p) => p.k,
        }
    }

    pub fn gamma0(&self) -> f64 {
        match self {
            Self::Hysteretic(p) => p.gamma0,
            Self::Lsd(p) => p.gamma0,
        }
    }

    /// Normal force for overlap δ and approach speed δ̇, updating the history.
    pub fn force(
        &self,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        history: &mut ContactHistory,
    ) -> NormalForce {
        match self {
            Self::Hysteretic(p) => p.force(delta, delta_dot, geom.a12, history),
            Self::Lsd(p) => p.force(delta, delta_dot),
        }
    }

    /// Contact duration on the stiffest branch without damping, tc = π·√(m_r/k_max)
    /// (paper 000 eq. 3 with η0 = 0): the shortest time scale the integrator must resolve.
    pub fn stiff_contact_time(&self, reduced_mass: f64) -> f64 {
        std::f64::consts::PI * (reduced_mass / self.stiffest()).sqrt()
    }

    /// Time-step limits for a pair of reduced mass `reduced_mass`.
    pub fn time_step(&self, reduced_mass: f64) -> TimeStep {
        let tc = self.stiff_contact_time(reduced_mass);
        let mut max = tc / MAX_DT_FRACTION;
        let mut reason = format!(
            "dt <= tc/{MAX_DT_FRACTION} with tc = pi*sqrt(m_r/k) = {tc:.4e} s on the stiffest branch k = {:.4e} N/m",
            self.stiffest()
        );
        let g = self.gamma0();
        if g > 0.0 {
            // explicit viscous force: keep γ0·dt/m_r small (the exact decay per step is
            // exp(−γ0·dt/m_r); the explicit update is unstable beyond γ0·dt/m_r = 2).
            let visc = MAX_VISCOUS_STEP * reduced_mass / g;
            if visc < max {
                max = visc;
                reason = format!(
                    "dt <= {MAX_VISCOUS_STEP}*m_r/gamma0 = {visc:.4e} s for the viscous damping gamma0 = {g:.4e} kg/s"
                );
            }
        }
        TimeStep {
            default: (tc / DEFAULT_DT_FRACTION).min(max),
            max,
            contact_time: tc,
            reason,
        }
    }
}

/// Default dt = tc/50 (MercuryDPM, paper 002: Δtcol/δt ≈ 50).
pub const DEFAULT_DT_FRACTION: f64 = 50.0;
/// Largest accepted dt without `--force`: tc/10. Velocity Verlet is stable up to
/// tc·2/π ≈ 0.64·tc, but restitution and overlap errors grow quickly beyond tc/10.
pub const MAX_DT_FRACTION: f64 = 10.0;
/// Largest accepted γ0·dt/m_r.
pub const MAX_VISCOUS_STEP: f64 = 0.2;

/// The time-step rule of one pair: the default, the largest accepted value and why.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeStep {
    pub default: f64,
    pub max: f64,
    /// Undamped contact time on the stiffest branch.
    pub contact_time: f64,
    /// Human-readable statement of the binding limit.
    pub reason: String,
}
