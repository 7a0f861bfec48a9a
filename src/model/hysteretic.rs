//! The piece-wise linear hysteretic adhesive elasto-plastic contact model of
//! Luding / Singh–Magnanimo–Luding (paper 000 §2.2–2.3, paper 003 §2), in f64.
//!
//! Sign convention: δ > 0 is overlap, δ̇ is the approach speed, a positive force is
//! repulsive. The force is the superposition of
//! * the contact force f_hys (eq. 5): k1·δ on loading, k2(δmax)·(δ−δ0) on un-/re-loading,
//!   −kc·δ on the irreversible tensile branch, k2 ≤ kp on the limit branch (eqs. 9–11);
//! * the non-contact adhesion (eq. 14 reversible, eq. 15 jump-in): −fa while in contact,
//!   −kc_a·δ − fa for δa < δ ≤ 0 with δa = −fa/kc_a;
//! * the viscous force γ0·δ̇ while in contact (eq. 2).

use crate::error::{require_positive, ParamError};
use crate::model::history::{HistoryField, HostField, Mirror, Shape};
use crate::model::params::word_enum;
use crate::model::{ContactHistory, LudingFriction, NormalForce};
use serde::{Deserialize, Serialize};

/// The per-contact history the hysteretic and LSD laws keep on the GPU: δmax (never
/// negative) with the sign bit as the touched flag, one word.
pub const HISTORY: &[HistoryField] = &[HistoryField {
    name: "hyst_state",
    shape: Shape::Word,
    mirror: Mirror::Same,
    host: HostField::DeltaMaxTouched,
    doc: "delta_max with the sign bit as the touched flag",
}];

word_enum! {
/// How the un-/re-loading stiffness k2 grows with the history δmax below the limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum K2Rule {
    /// k2 = k1 + (kp − k1)·δmax/δmax^p (paper 000 eq. 9, paper 003 eq. 10).
    #[default]
    Linear = "linear",
    /// k2 = k1 + (kp − k1)·√(δmax/δmax^p) (paper 000 appendix D, eq. D.1).
    Sqrt = "sqrt",
}
}

word_enum! {
/// How the non-contact adhesion acts before the first mechanical contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum AdhesionMode {
    /// Reversible linear attraction within the range δa (eq. 14), on approach and separation.
    Reversible = "reversible",
    /// Irreversible jump-in (eq. 15): no force on first approach, −fa from the first touch
    /// on, and the reversible pull-off branch on separation.
    #[default]
    JumpIn = "jump-in",
}
}

/// Parameters of the hysteretic model. Stiffnesses in N/m, forces in N, γ0 in kg/s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HystereticParams {
    /// Initial (plastic) loading stiffness k1.
    pub k1: f64,
    /// Maximal (elastic limit) un-/re-loading stiffness kp ≥ k1.
    pub kp: f64,
    /// Slope of the irreversible tensile (adhesive) branch kc ≥ 0.
    pub kc: f64,
    /// Dimensionless plasticity depth φf ∈ (0, 1].
    pub phi_f: f64,
    /// Non-contact adhesive force magnitude fa ≥ 0.
    pub fa: f64,
    /// Non-contact adhesive stiffness kc_a > 0; `f64::INFINITY` gives zero range.
    pub kca: f64,
    /// How the non-contact adhesion acts before the first mechanical contact (eqs. 14/15).
    pub adhesion: AdhesionMode,
    /// Linear viscous damping coefficient γ0 ≥ 0 (eq. 2), active in mechanical contact.
    pub gamma0: f64,
    /// Interpolation of the un-/re-loading stiffness k2 between k1 and kp (eq. 9 or D.1).
    pub k2_rule: K2Rule,
    /// Luding's sliding, rolling and twisting friction ([`crate::model::friction`]); off by
    /// default. The Coulomb load is [`Self::coulomb_load`].
    #[serde(default)]
    pub luding: LudingFriction,
}

impl HystereticParams {
    /// The paper's figure parameters (k1 = 100, kp = 500, kc = 100 N/m, φf = 0.05), no fa.
    pub fn paper_figure() -> Self {
        Self {
            k1: 100.0,
            kp: 500.0,
            kc: 100.0,
            phi_f: 0.05,
            fa: 0.0,
            kca: f64::INFINITY,
            adhesion: AdhesionMode::JumpIn,
            gamma0: 0.0,
            k2_rule: K2Rule::Linear,
            luding: LudingFriction::default(),
        }
    }

    /// Checks every rule of the model; the error names the parameter and the rule.
    pub fn validate(&self) -> Result<(), ParamError> {
        use crate::model::params as p;
        for (param, x) in [
            (&p::K1, self.k1),
            (&p::KP, self.kp),
            (&p::KC, self.kc),
            (&p::PHI_F, self.phi_f),
            (&p::FA, self.fa),
            (&p::KCA, self.kca),
            (&p::GAMMA0, self.gamma0),
        ] {
            param.check(x)?;
        }
        self.luding.validate()?;
        if self.kp < self.k1 {
            return Err(ParamError::new(
                "kp",
                format!(
                    "kp ({}) must be >= k1 ({}): the limit branch is the stiffest (k1 <= k2 <= kp, paper 000 eq. 5)",
                    crate::error::num(self.kp),
                    crate::error::num(self.k1)
                ),
            ));
        }
        Ok(())
    }

    /// Plastic flow limit overlap δmax^p = kp/(kp−k1)·φf·a12 (eq. 10); infinite when kp = k1.
    pub fn delta_max_p(&self, a12: f64) -> f64 {
        if self.kp > self.k1 {
            self.kp / (self.kp - self.k1) * self.phi_f * a12
        } else {
            f64::INFINITY
        }
    }

    /// Force-free overlap on the limit branch δ0^p = φf·a12 (eq. 11).
    pub fn delta0_p(&self, a12: f64) -> f64 {
        self.phi_f * a12
    }

    /// Un-/re-loading stiffness k2(δmax) (eq. 9 or D.1).
    pub fn k2(&self, delta_max: f64, a12: f64) -> f64 {
        let x = delta_max / self.delta_max_p(a12);
        if x >= 1.0 {
            return self.kp;
        }
        let x = x.max(0.0);
        let shape = match self.k2_rule {
            K2Rule::Linear => x,
            K2Rule::Sqrt => x.sqrt(),
        };
        self.k1 + (self.kp - self.k1) * shape
    }

    /// Force-free overlap δ0(δmax) of the un-/re-loading line (eq. 7, eq. 11 beyond the limit).
    pub fn delta0(&self, delta_max: f64, a12: f64) -> f64 {
        if delta_max >= self.delta_max_p(a12) {
            self.delta0_p(a12)
        } else {
            (1.0 - self.k1 / self.k2(delta_max, a12)) * delta_max
        }
    }

    /// The overlap δmin^p = kp·δ0^p/(kp + kc) where the limit line meets the tensile branch:
    /// below it the history moves under the limit.
    pub fn tensile_limit(&self, a12: f64) -> f64 {
        self.kp * self.delta0_p(a12) / (self.kp + self.kc)
    }

    /// (k1 + kc)/(kp − k1), of the k2 line through a point of the tensile branch (0 when
    /// kp ≤ k1: the lines never meet it).
    pub fn tensile_coefficient(&self) -> f64 {
        if self.kp > self.k1 {
            (self.k1 + self.kc) / (self.kp - self.k1)
        } else {
            0.0
        }
    }

    /// Range of the non-contact force |δa| = fa/kc_a (0 without fa or with kc_a = ∞).
    pub fn range(&self) -> f64 {
        if self.fa > 0.0 && self.kca.is_finite() {
            self.fa / self.kca
        } else {
            0.0
        }
    }

    /// Stiffest active branch, for the time step: the largest of kp, kc (the tensile
    /// branch's slope, where it is reached: a pair on it parts or sticks within √(m_r/kc))
    /// and kc_a where finite.
    pub fn stiffest(&self) -> f64 {
        // (with kp = k1 the k2 lines never meet the tensile branch: kc is never reached)
        let k = if self.kp > self.k1 {
            self.kp.max(self.kc)
        } else {
            self.kp
        };
        if self.fa > 0.0 && self.kca.is_finite() {
            k.max(self.kca)
        } else {
            k
        }
    }

    /// The history δmax whose k2 line passes through (δ, −kc·δ): where the tensile branch
    /// hands over to re-loading. Solves k2(x)·(δ − δ0(x)) = −kc·δ for x.
    pub fn delta_max_on_tensile_branch(&self, delta: f64, a12: f64) -> f64 {
        let dp = self.delta_max_p(a12);
        let (k1, kp, kc) = (self.k1, self.kp, self.kc);
        if kp <= k1 {
            // k2 = k1, δ0 = 0: the line is k1·δ, which never meets −kc·δ at δ > 0.
            return 0.0;
        }
        // beyond δmin^p the history stays at the limit; below it k2 < kp
        if delta >= self.tensile_limit(a12) {
            return dp;
        }
        match self.k2_rule {
            K2Rule::Linear => {
                // (k1 + s·x + kc)·δ = s·x², s = (kp−k1)/δmax^p.
                let s = (kp - k1) / dp;
                0.5 * delta + (0.25 * delta * delta + (k1 + kc) * delta / s).sqrt()
            }
            K2Rule::Sqrt => {
                // (k1 + s·u + kc)·δ = s·u³ with u = √x, s = (kp−k1)/√δmax^p; the cubic
                // s·u³ − s·δ·u − (k1+kc)·δ has one positive root above √δ: bisection + Newton.
                let s = (kp - k1) / dp.sqrt();
                let g = |u: f64| s * u * u * u - s * delta * u - (k1 + kc) * delta;
                let (mut lo, mut hi) = (delta.sqrt(), dp.sqrt());
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if g(mid) > 0.0 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                    if hi - lo <= 1e-15 * hi {
                        break;
                    }
                }
                let u = 0.5 * (lo + hi);
                u * u
            }
        }
    }

    /// The mechanical contact force f_hys(δ) for δ > 0 (eq. 5), updating δmax.
    pub fn contact_force(&self, delta: f64, a12: f64, history: &mut ContactHistory) -> f64 {
        if delta >= history.delta_max {
            // Loading: along k1 below the limit, along the limit branch kp(δ − δ0^p) beyond.
            history.delta_max = delta;
            let dp = self.delta_max_p(a12);
            return if delta < dp {
                self.k1 * delta
            } else {
                self.kp * (delta - self.delta0_p(a12))
            };
        }
        let k2 = self.k2(history.delta_max, a12);
        let d0 = self.delta0(history.delta_max, a12);
        let elastic = k2 * (delta - d0);
        // Re-loading meets the k1 line only at δmax (handled above); the clamp guards
        // rounding. On the limit branch (δmax ≥ δmax^p) the kp line lies above k1.
        if elastic >= self.k1 * delta && history.delta_max < self.delta_max_p(a12) {
            self.k1 * delta
        } else if elastic <= -self.kc * delta {
            // Irreversible tensile branch: re-loading must leave it along a k2 line through
            // the current point, so the history moves with it.
            history.delta_max = self
                .delta_max_on_tensile_branch(delta, a12)
                .min(history.delta_max);
            -self.kc * delta
        } else {
            elastic
        }
    }

    /// Energy recoverable along the current un-/re-loading line, ½·k2·(δ−δ0)².
    pub fn available_energy(&self, delta: f64, a12: f64, history: &ContactHistory) -> f64 {
        let k2 = self.k2(history.delta_max, a12);
        let d = delta - self.delta0(history.delta_max, a12);
        0.5 * k2 * d * d
    }

    /// Potential of the (reversible) non-contact adhesion, zero beyond the range.
    fn adhesion_potential(&self, delta: f64) -> f64 {
        let well = if self.kca.is_finite() {
            0.5 * self.fa * self.fa / self.kca
        } else {
            0.0
        };
        if delta > 0.0 {
            -self.fa * delta - well
        } else {
            -0.5 * self.kca * delta * delta - self.fa * delta - well
        }
    }

    /// The Coulomb load of Luding's friction, f_N* = max(0, f_n + kc·δ + fa) with f_n the
    /// total normal force (f_hys − fa + γ0·δ̇): the normal force measured from the adhesive
    /// limit −kc·δ − fa rather than from zero (Luding 2008 as WooDEM and AutoPas give it,
    /// `docs/luding2008_laws.md` §1b; + fa extends it to the non-contact adhesion of paper
    /// 000 eqs. 14–15, as LAMMPS's `epa_linear` adds f_0). A contact held together by
    /// adhesion at zero net force can still carry friction; the limit vanishes only on the
    /// tensile branch f_hys = −kc·δ, where the contact is about to break.
    pub fn coulomb_load(&self, normal: &NormalForce, delta: f64) -> f64 {
        (normal.force + self.kc * delta + self.fa).max(0.0)
    }

    /// Total normal force for overlap `delta` and approach speed `delta_dot`.
    pub fn force(
        &self,
        delta: f64,
        delta_dot: f64,
        a12: f64,
        history: &mut ContactHistory,
    ) -> NormalForce {
        let range = self.range();
        if delta > 0.0 {
            history.touched = true;
            let f_hys = self.contact_force(delta, a12, history);
            let conservative = f_hys - self.fa;
            let potential = self.available_energy(delta, a12, history)
                + if self.fa > 0.0 {
                    self.adhesion_potential(delta)
                } else {
                    0.0
                };
            NormalForce {
                force: conservative + self.gamma0 * delta_dot,
                conservative,
                potential,
                in_contact: true,
                contact_radius: 0.0,
                broke_within: None,
            }
        } else if delta > -range {
            // Non-contact range: a later mechanical contact starts afresh (paper 000 §2.2.5),
            // but "has touched" is kept until the pair leaves the range.
            history.delta_max = 0.0;
            if delta == 0.0 {
                history.touched = true;
            }
            let active = self.adhesion == AdhesionMode::Reversible || history.touched;
            let (force, potential) = if active {
                (-self.kca * delta - self.fa, self.adhesion_potential(delta))
            } else {
                (0.0, 0.0)
            };
            NormalForce {
                force,
                conservative: force,
                potential,
                in_contact: false,
                contact_radius: 0.0,
                broke_within: None,
            }
        } else {
            // Beyond the interaction range the pair forgets its contact (paper 000, footnote 3).
            *history = ContactHistory::default();
            NormalForce::default()
        }
    }

    /// Appendix A: the limit stiffness kp′ that keeps the low-velocity behaviour when the
    /// plasticity depth is changed to `phi_f_new` (eq. A.3).
    pub fn kp_for_phi_f(&self, phi_f_new: f64) -> Result<f64, ParamError> {
        require_positive("phi_f", phi_f_new, "the new plasticity depth phi_f'")?;
        Ok(crate::model::analytic::tuned_limit_stiffness(
            self.k1, self.kp, self.phi_f, phi_f_new,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A12: f64 = 1.1e-3;

    fn params() -> HystereticParams {
        HystereticParams::paper_figure()
    }

    #[test]
    fn loading_follows_k1_and_unloading_k2() {
        let p = params();
        let mut h = ContactHistory::default();
        let dmax = 0.5 * p.delta_max_p(A12);
        assert_eq!(p.contact_force(dmax, A12, &mut h), p.k1 * dmax);
        let k2 = p.k2(dmax, A12);
        assert!((k2 - (p.k1 + 0.5 * (p.kp - p.k1))).abs() < 1e-9);
        let d = 0.9 * dmax;
        let f = p.contact_force(d, A12, &mut h);
        let d0 = (1.0 - p.k1 / k2) * dmax;
        assert!((f - k2 * (d - d0)).abs() < 1e-12);
        // re-loading below δmax stays on the same line, history unchanged
        let f2 = p.contact_force(0.95 * dmax, A12, &mut h);
        assert!((f2 - k2 * (0.95 * dmax - d0)).abs() < 1e-12);
        assert_eq!(h.delta_max, dmax);
    }

    #[test]
    fn limit_branch_uses_kp_and_fixed_delta0() {
        let p = params();
        let dp = p.delta_max_p(A12);
        let mut h = ContactHistory::default();
        let f = p.contact_force(1.5 * dp, A12, &mut h);
        let expect = p.kp * (1.5 * dp - p.phi_f * A12);
        assert!((f - expect).abs() < 1e-12 * expect.abs());
        // beyond δmax^p the limit branch is steeper than k1 (paper 000 eq. 23b: loading
        // continues along kp), so it lies above the k1 line
        assert!(f > p.k1 * 1.5 * dp);
        // continuity of δ0 at the limit
        assert!((p.delta0(dp * (1.0 - 1e-12), A12) - p.delta0_p(A12)).abs() < 1e-12);
    }

    #[test]
    fn tensile_branch_moves_history_onto_a_consistent_k2_line() {
        for rule in [K2Rule::Linear, K2Rule::Sqrt] {
            let p = HystereticParams {
                k2_rule: rule,
                ..params()
            };
            let mut h = ContactHistory::default();
            let dmax = 0.8 * p.delta_max_p(A12);
            p.contact_force(dmax, A12, &mut h);
            let dmin = (p.k2(dmax, A12) - p.k1) / (p.k2(dmax, A12) + p.kc) * dmax;
            let d = 0.5 * dmin;
            let f = p.contact_force(d, A12, &mut h);
            assert!((f + p.kc * d).abs() < 1e-15, "on the -kc branch");
            assert!(h.delta_max < dmax, "history moved");
            // the new line passes through the current point with k2 = k2(new δmax)
            let k2 = p.k2(h.delta_max, A12);
            let line = k2 * (d - p.delta0(h.delta_max, A12));
            assert!(
                (line + p.kc * d).abs() < 1e-9 * p.kc * d,
                "{rule:?}: {line} vs {}",
                -p.kc * d
            );
            // re-loading leaves the branch along that line
            let d2 = 1.2 * d;
            let f2 = p.contact_force(d2, A12, &mut h);
            assert!((f2 - k2 * (d2 - p.delta0(h.delta_max, A12))).abs() < 1e-12);
            assert!(f2 > -p.kc * d2);
        }
    }

    #[test]
    fn history_is_forgotten_beyond_range_and_touched_kept_inside() {
        let p = HystereticParams {
            fa: 1e-6,
            kca: 100.0,
            ..params()
        };
        let mut h = ContactHistory::default();
        // jump-in: nothing on first approach within range
        let nf = p.force(-0.5 * p.range(), -1.0, A12, &mut h);
        assert_eq!(nf.force, 0.0);
        p.force(1e-5, 1.0, A12, &mut h);
        assert!(h.touched);
        let nf = p.force(-0.5 * p.range(), -1.0, A12, &mut h);
        assert!((nf.force - (-p.fa + p.kca * 0.5 * p.range())).abs() < 1e-18);
        assert!(h.touched);
        p.force(-1.5 * p.range(), -1.0, A12, &mut h);
        assert_eq!(h, ContactHistory::default());
    }

    #[test]
    fn appendix_a_keeps_low_velocity_slope() {
        let p = params();
        let kp2 = p.kp_for_phi_f(0.5).unwrap();
        let q = HystereticParams {
            kp: kp2,
            phi_f: 0.5,
            ..p
        };
        let d = 1e-3 * p.delta_max_p(A12);
        assert!((p.k2(d, A12) - q.k2(d, A12)).abs() < 1e-9 * p.k2(d, A12));
        assert!(q.delta_max_p(A12) > p.delta_max_p(A12));
    }

    #[test]
    fn validation_names_parameter_and_rule() {
        let bad = |f: fn(&mut HystereticParams)| {
            let mut p = params();
            f(&mut p);
            p.validate().unwrap_err()
        };
        let e = bad(|p| p.kp = 50.0);
        assert_eq!(e.param, "kp");
        assert!(e.message.contains("k1"));
        assert_eq!(bad(|p| p.phi_f = 0.0).param, "phi_f");
        assert_eq!(bad(|p| p.phi_f = 1.5).param, "phi_f");
        assert_eq!(bad(|p| p.kc = -1.0).param, "kc");
        assert_eq!(bad(|p| p.fa = -1.0).param, "fa");
        assert_eq!(bad(|p| p.gamma0 = -1.0).param, "gamma0");
        assert_eq!(bad(|p| p.kca = 0.0).param, "kca");
        assert_eq!(bad(|p| p.k1 = f64::NAN).param, "k1");
        assert!(params().validate().is_ok());
    }
}
