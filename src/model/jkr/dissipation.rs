//! The JKR family's dissipation laws: none, Tsuji damping from a target restitution, the
//! power law of paper 001 and the Krijt/stress viscous laws, with their normal force.

use super::{JkrPair, JkrParams};
use crate::model::krijt::{self, KrijtLaw, Relaxation};
use crate::model::params::word_enum;
use crate::model::{ContactHistory, PairGeometry};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// 2·√(5/6), the prefactor of the Tsuji damping (paper 002 eqs. 11 and 16).
pub(super) const TSUJI_PREFACTOR: f64 = 1.8257418583505538;

/// Normal (and tangential) dissipation of the JKR family.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Dissipation {
    /// No dissipation: the only loss is the JKR contact hysteresis.
    #[default]
    None,
    /// Tsuji-type damping calibrated from a target restitution e ∈ (0, 1]
    /// (paper 002 eqs. 11–13 normal and 16 tangential). For Hertz (γ = 0) the restitution
    /// of a head-on collision equals the target, independent of the impact velocity, up to
    /// the integration error (`tsuji_damping_calibration` in `jkr/tests.rs`, `docs/models.md`). With
    /// adhesion the JKR loss comes on top.
    Tsuji {
        /// Target coefficient of restitution e ∈ (0, 1].
        restitution: f64,
        /// The stiffness of the dashpots: the JKR contact radius (default) or paper 002's
        /// Hertz form.
        #[serde(default)]
        stiffness: TsujiStiffness,
    },
    /// Power-law dissipation F_dis = sgn(δ̇)·D·E*·|δ̇|^α·a^β (paper 001 eq. 19), in any
    /// consistent unit system (D carries the units). Normal direction only.
    PowerLaw {
        /// Prefactor D, m^(2−α−β)·s^α in SI (so that F_dis is in N).
        #[serde(rename = "D", alias = "d")]
        d: f64,
        /// Exponent α of the approach speed |δ̇|.
        alpha: f64,
        /// Exponent β of the contact radius a.
        beta: f64,
    },
    /// The Krijt viscoelastic JKR contact (paper 001 §II C, eqs. 10–12 and appendix B; see
    /// [`crate::model::krijt`]): the contact radius is its own state variable, driven by
    /// the crack speed of eq. B2, and a viscous force (2·T_vis·E*/ν²)·a·δ̇ acts. Normal
    /// direction only. Needs γ > 0 and ν ≠ 0.
    Krijt {
        /// Relaxation time T_vis ≥ 0, s.
        tvis: f64,
        /// σ0 ≈ γ/(atomic spacing) ≥ 0, Pa, of the crack speed (eq. B2); 0 (default) = the
        /// contact radius follows the JKR curve instantly.
        #[serde(default)]
        sigma0: f64,
    },
    /// The stress-dependent Krijt model of paper 001 §V A (eqs. 17–18):
    /// T_vis = C·R·exp[(B·p_c/E*)^ζ] for p_c > 0 (C·R otherwise), p_c the JKR centre
    /// pressure (eq. 9), R = 2R* (the particle radius for equal spheres).
    Stress {
        /// C ≥ 0, s/m: T_vis,0 = C·R (eq. 18).
        tvis0_per_radius: f64,
        /// B ≥ 0 (eq. 17).
        #[serde(rename = "B", alias = "b")]
        b: f64,
        /// ζ > 0 (eq. 17).
        zeta: f64,
        /// σ0 ≥ 0, Pa, as for `krijt`.
        #[serde(default)]
        sigma0: f64,
    },
}

word_enum! {
/// The stiffness in the Tsuji dashpots, Sn = 2E*·ρ (normal, paper 002 eqs. 11–13) and
/// St = 8G*·ρ (tangential, eq. 16), with ρ a contact radius.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TsujiStiffness {
    /// ρ = a, the JKR contact radius: it exists (and the dashpots act) also at negative
    /// overlap while a JKR contact holds, and exceeds √(R*δ) at positive overlap.
    #[default]
    ContactRadius = "contact-radius",
    /// ρ = √(R*·δ), zero at δ ≤ 0: paper 002's Hertz forms Sn = 2E*√(R*δ) (eq. 13) and
    /// St = 8G*√(R*δ) (below eq. 14), for which Tsuji's β(e) calibration was derived. The
    /// same as `ContactRadius` for Hertz (γ = 0), where a = √(R*δ).
    Hertz = "hertz",
}
}

impl TsujiStiffness {
    /// ρ of Sn = 2E*·ρ and St = 8G*·ρ for contact radius `a` at overlap `delta`.
    pub fn radius(self, a: f64, delta: f64, r_eff: f64) -> f64 {
        match self {
            Self::ContactRadius => a,
            Self::Hertz => (r_eff * delta.max(0.0)).sqrt(),
        }
    }
}

impl Dissipation {
    /// Tsuji damping with target restitution `restitution` and the default stiffness
    /// ([`TsujiStiffness::ContactRadius`]).
    pub fn tsuji(restitution: f64) -> Self {
        Self::Tsuji {
            restitution,
            stiffness: TsujiStiffness::ContactRadius,
        }
    }

    /// The Krijt law of the `krijt` and `stress` dissipations.
    pub fn krijt_law(&self) -> Option<KrijtLaw> {
        match *self {
            Self::Krijt { tvis, sigma0 } => Some(KrijtLaw {
                relaxation: Relaxation::Constant { tvis },
                sigma0,
            }),
            Self::Stress {
                tvis0_per_radius,
                b,
                zeta,
                sigma0,
            } => Some(KrijtLaw {
                relaxation: Relaxation::Stress {
                    c: tvis0_per_radius,
                    b,
                    zeta,
                },
                sigma0,
            }),
            _ => None,
        }
    }

    /// The name used in scenes and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Tsuji { .. } => "tsuji",
            Self::PowerLaw { .. } => "powerlaw",
            Self::Krijt { .. } => "krijt",
            Self::Stress { .. } => "stress",
        }
    }
}

/// The Tsuji damping ratio β = ln e/√(ln²e + π²) (paper 002 eq. 12), ≤ 0.
pub fn tsuji_beta(restitution: f64) -> f64 {
    // the last value, per thread: asked for once per pair shape, with the same restitution
    thread_local!(static LAST: std::cell::Cell<(u64, f64)> = const { std::cell::Cell::new((u64::MAX, 0.0)) });
    LAST.with(|last| {
        let (bits, beta) = last.get();
        if bits == restitution.to_bits() {
            return beta;
        }
        let l = restitution.ln();
        let beta = l / (l * l + PI * PI).sqrt();
        last.set((restitution.to_bits(), beta));
        beta
    })
}

/// The `krijt`/`stress` viscous force a collision reaches
/// ([`JkrParams::viscous_coefficient_estimate`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscousEstimate {
    /// The largest viscous coefficient c = 2·T_vis·E*·a/ν², kg/s.
    pub c: f64,
    /// The overlap where it was reached, m.
    pub reach: f64,
    /// The step the collision was integrated with, s.
    pub dt: f64,
}

/// Rounds of [`JkrParams::viscous_coefficient_estimate`] at most (each integrates a
/// collision).
const VISCOUS_ROUNDS: usize = 12;
/// A step too long is shortened to this fraction of the one its collision's c allows.
const VISCOUS_MARGIN: f64 = 0.98;
/// A step within this fraction of the one its collision's c allows is taken as found.
const VISCOUS_SETTLED: f64 = 1.25;
/// Past the turn, a c this far below its peak ends [`JkrParams::viscous_peak`]'s
/// collision: the pair recedes, and c grows again only after a second turn.
const VISCOUS_PAST_PEAK: f64 = 0.9;
/// Steps of [`JkrParams::viscous_peak`]'s collision at most.
pub const VISCOUS_STEPS: usize = 200_000;

impl JkrParams {
    /// The viscous coefficient c = 2·T_vis·E*·a/ν² of the `krijt`/`stress` dissipations
    /// in a head-on collision at impact speed `v` (None for the other dissipations): the
    /// largest c of the collision integrated ([`Self::viscous_peak`]) at the largest step
    /// tried, at most `dt_trial`, with c·dt/m* ≤ `max_step`.
    pub fn viscous_coefficient_estimate(
        &self,
        geom: &PairGeometry,
        v: f64,
        dt_trial: f64,
        max_step: f64,
    ) -> Option<ViscousEstimate> {
        let mr = geom.reduced_mass;
        let mut dt = dt_trial;
        let (mut resolved, mut last): (Option<ViscousEstimate>, Option<ViscousEstimate>) =
            (None, None);
        // a step too long for the viscous force makes it oscillate and grow (a larger c):
        // shorten it until the collision is resolved, then lengthen it towards the step
        // its own c allows
        for _ in 0..VISCOUS_ROUNDS {
            let estimate = self.viscous_peak(geom, v, dt)?;
            last = Some(estimate);
            let fits = max_step * mr / estimate.c;
            if fits.is_nan() || fits < dt {
                dt = (VISCOUS_MARGIN * fits).max(0.1 * dt);
                continue;
            }
            if resolved.is_none_or(|r| r.dt < dt) {
                resolved = Some(estimate);
            }
            if fits < VISCOUS_SETTLED * dt || dt >= dt_trial {
                break;
            }
            dt = fits.min(dt_trial);
        }
        // (never resolved in all the rounds: the last c, at the step it allows)
        resolved.or(last.map(|l| ViscousEstimate {
            dt: max_step * mr / l.c,
            ..l
        }))
    }

    /// The largest viscous coefficient c = 2·T_vis·E*·a/ν² (of the contact radius a the
    /// law carries, which lags a_JKR(δ) while the crack moves) of a head-on collision at
    /// speed `v` under the `krijt`/`stress` law, integrated with step `dt` from the touch
    /// until the contact breaks, the pair turns back a second time (stuck: each later
    /// compression is shallower) or c falls 10 % below its peak, and the overlap there
    /// (None for the other dissipations). Where c still grows after [`VISCOUS_STEPS`] (a
    /// slow creep at the deepest point), c on the JKR curve at the deepest overlap, which
    /// the contact radius grows towards. With T_vis growing with the pressure (`stress`)
    /// the compression stops far short of the Hertz δmax, whose T_vis would ask for a dt
    /// thousands of times smaller.
    pub fn viscous_peak(&self, geom: &PairGeometry, v: f64, dt: f64) -> Option<ViscousEstimate> {
        let law = self.dissipation.krijt_law()?;
        if self.gamma() == 0.0 {
            return None;
        }
        let (r, m) = (geom.r_eff(), self.krijt_material());
        let mut history = ContactHistory::default();
        let (mut delta, mut speed, mut acc) = (0.0_f64, v, 0.0);
        let mut peak = ViscousEstimate {
            c: self.viscous_coefficient_at(self.delta0(r), r),
            reach: self.delta0(r),
            dt,
        };
        let (mut turns, mut peak_step, mut deepest) = (0, 0, 0.0_f64);
        // velocity Verlet as the engines step, the force at the predicted velocity
        for step in 0..=VISCOUS_STEPS {
            if step == VISCOUS_STEPS {
                // c still grew in the second half of the steps: a grows towards a_JKR(δ),
                // so c at a_JKR of the deepest overlap bounds it
                if peak_step >= VISCOUS_STEPS / 2 {
                    let bound = self.viscous_coefficient_at(deepest, r);
                    if bound > peak.c {
                        (peak.c, peak.reach) = (bound, deepest);
                    }
                }
                break;
            }
            let half = speed + 0.5 * dt * acc;
            delta += dt * half;
            let predicted = half + 0.5 * dt * acc;
            let f = self.normal_force_step(delta, predicted, geom, dt, &mut history);
            if !f.in_contact {
                break;
            }
            acc = -f.force / geom.reduced_mass;
            deepest = deepest.max(delta);
            let before = speed;
            speed = half + 0.5 * dt * acc;
            let a = f.contact_radius;
            let c = krijt::viscous_force(law.relaxation_time_at(a, r, &m), a, 1.0, &m);
            if !c.is_finite() {
                peak.c = f64::INFINITY;
                break;
            }
            if c > peak.c {
                (peak.c, peak.reach, peak_step) = (c, delta, step);
            }
            if (before > 0.0) != (speed > 0.0) {
                turns += 1;
            }
            if turns >= 2 || (turns >= 1 && c < VISCOUS_PAST_PEAK * peak.c) {
                break;
            }
        }
        Some(peak)
    }

    /// c = 2·T_vis·E*·a/ν² at overlap `delta` on the JKR curve (T_vis at that contact
    /// radius), kg/s; 0 for the dissipations without it.
    fn viscous_coefficient_at(&self, delta: f64, r_eff: f64) -> f64 {
        let Some(law) = self.dissipation.krijt_law() else {
            return 0.0;
        };
        let a = self.contact_radius(delta, r_eff);
        let m = self.krijt_material();
        let tvis = law.relaxation_time_at(a, r_eff, &m);
        krijt::viscous_force(tvis, a, 1.0, &m)
    }

    /// The dissipative normal force for contact radius `a` at overlap `delta` and approach
    /// speed `delta_dot`, repulsive positive (it opposes δ̇).
    pub(super) fn normal_dissipation(
        &self,
        a: f64,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        pair: &JkrPair,
    ) -> f64 {
        let (m, es) = (geom.reduced_mass, pair.es);
        match self.dissipation {
            Dissipation::None => 0.0,
            Dissipation::Tsuji { stiffness, .. } => {
                // Sn = 2E*·a by default (paper 002 eq. 13 writes 2E*√(Rδ), which is 2E*·a
                // for Hertz; the contact radius also exists at negative overlap in JKR), or
                // paper 002's 2E*·√(R*δ) (zero at δ ≤ 0)
                let sn = 2.0 * es * stiffness.radius(a, delta, geom.r_eff());
                -TSUJI_PREFACTOR * pair.beta * (sn * m).sqrt() * delta_dot
            }
            Dissipation::PowerLaw { d, alpha, beta } => {
                if delta_dot == 0.0 {
                    0.0
                } else {
                    delta_dot.signum() * d * es * delta_dot.abs().powf(alpha) * a.powf(beta)
                }
            }
            Dissipation::Krijt { .. } | Dissipation::Stress { .. } => {
                let Some(law) = self.dissipation.krijt_law() else {
                    return 0.0;
                };
                let mat = self.krijt_material();
                let tvis = law.relaxation_time_at(a, geom.r_eff(), &mat);
                krijt::viscous_force(tvis, a, delta_dot, &mat)
            }
        }
    }
}
