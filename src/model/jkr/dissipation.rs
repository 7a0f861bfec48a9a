//! The JKR family's dissipation laws: none, Tsuji damping from a target restitution, the
//! power law of paper 001 and the Krijt/stress viscous laws, with their normal force.

use super::{JkrPair, JkrParams};
use crate::model::krijt::{self, KrijtLaw, Relaxation};
use crate::model::params::word_enum;
use crate::model::PairGeometry;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// 2·√(5/6), the prefactor of the Tsuji damping (paper 002 eqs. 11 and 16).
pub(crate) const TSUJI_PREFACTOR: f64 = 1.8257418583505538;

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

impl JkrParams {
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
