//! Luding's sliding, rolling and twisting friction (S. Luding, "Cohesive, frictional
//! powders: contact models for tension", Granular Matter 10:235, 2008; ref. \[15\] of paper
//! 000; the laws as MercuryDPM, LAMMPS, WooDEM and AutoPas give them:
//! `docs/luding2008_laws.md`), one module per sub-model:
//!
//! * [`coulomb`] — the spring–dashpot with a static/dynamic Coulomb limit they share;
//! * [`sliding`] — the tangential spring at the contact point;
//! * [`rolling`] — the rolling pseudo-force and its couple;
//! * [`twisting`] — the twisting pseudo-force and its couple.
//!
//! The hysteretic and LSD laws take all three ([`LudingFriction`] in their parameters); the
//! JKR family takes twisting only (it has its own Mindlin sliding and Dominik–Tielens
//! rolling, `model::jkr`).
//!
//! Conventions: n points from j to i; the lever of rolling and twisting is
//! ℓ = a12 = 2R* = 2·r_i·r_j/(r_i + r_j) (2r against a wall), paper 000's reduced radius and
//! MercuryDPM's convention, so μr and μo are meant with that lever (the largest rolling
//! torque is μr·a12·f_N*). Friction acts only in mechanical contact (δ > 0); the springs are
//! reset when the contact opens. The Coulomb load f_N* is the law's (hysteretic:
//! max(0, f_n + kc·δ + fa), LSD: max(0, f_n); JKR: |F_el + 2Fc|).

pub mod coulomb;
pub mod rolling;
pub mod sliding;
pub mod twisting;

pub use coulomb::CoulombSpring;

use crate::error::ParamError;
use crate::model::params;
use crate::model::{ContactHistory, Kinematics, PairGeometry};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The tangential spring's and dashpot's default share of the normal ones (2/7: the
/// tangential oscillator of two solid spheres then has the normal period; MercuryDPM's).
pub const TANGENTIAL_SHARE: f64 = 2.0 / 7.0;

/// The rolling and twisting springs' and dashpots' default share of the normal ones (2/5:
/// their oscillators then have the normal period for two equal spheres).
pub const ROTATIONAL_SHARE: f64 = 0.4;

/// Luding's three friction sub-models of one pair, with their parameters after the
/// defaults are derived. A sub-model with μs = 0 is off.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LudingFriction {
    /// Sliding: μs = `friction`, μd = `friction_dynamic`, k = `kt`, γ = `gamma_t`.
    #[serde(default)]
    pub sliding: CoulombSpring,
    /// Rolling: μs = μd = `rolling_friction`, k = `kr`, γ = `gamma_r`.
    #[serde(default)]
    pub rolling: CoulombSpring,
    /// Twisting: μs = μd = `twisting_friction`, k = `ko`, γ = `gamma_o`.
    #[serde(default)]
    pub twisting: CoulombSpring,
}

/// What the friction of one contact exerts over a step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrictionResponse {
    /// Tangential force on i at the contact point (−this on j).
    pub tangential: DVec3,
    /// The rolling and twisting couple on i (−this on j).
    pub couple: DVec3,
    /// The springs' energy ½k_t|ξ_t|² + ½k_r|ξ_r|² + ½k_o·ξ_o², J.
    pub potential: f64,
    /// Whether the sliding law slipped (the Coulomb limit truncated the tangential force).
    pub sliding: bool,
}

/// The oscillator of one sub-model for the time-step rule: stiffness, effective mass,
/// dashpot and its name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    /// Stiffness, N/m.
    pub k: f64,
    /// Effective mass, kg.
    pub mass: f64,
    /// Dashpot, kg/s.
    pub gamma: f64,
    /// "tangential", "rolling" or "twisting".
    pub what: &'static str,
}

impl LudingFriction {
    /// Whether some sub-model acts (particles then need angular velocity).
    pub fn is_on(&self) -> bool {
        self.sliding.is_on() || self.rolling.is_on() || self.twisting.is_on()
    }

    /// The parameters' rules: each against its declaration (a stiffness only where its
    /// sub-model acts) and μd ≤ μs.
    pub fn validate(&self) -> Result<(), ParamError> {
        use params::*;
        let (s, r, o) = (&self.sliding, &self.rolling, &self.twisting);
        let checks = [
            (&FRICTION, s.mu_s, true),
            (&FRICTION_DYNAMIC, s.mu_d, s.is_on()),
            (&KT, s.k, s.is_on()),
            (&GAMMA_T, s.gamma, true),
            (&ROLLING_FRICTION, r.mu_s, true),
            (&KR, r.k, r.is_on()),
            (&GAMMA_R, r.gamma, true),
            (&TWISTING_FRICTION, o.mu_s, true),
            (&KO, o.k, o.is_on()),
            (&GAMMA_O, o.gamma, true),
        ];
        for (param, x, applies) in checks {
            if applies {
                param.check(x)?;
            }
        }
        if s.mu_d > s.mu_s {
            return Err(ParamError::new(
                FRICTION_DYNAMIC.key,
                format!(
                    "friction_dynamic ({}) must be <= friction ({}): a sliding contact cannot carry more than the static limit (Luding 2008: mu_d <= mu_s)",
                    s.mu_d, s.mu_s
                ),
            ));
        }
        for (spring, key) in [(r, ROLLING_FRICTION.key), (o, TWISTING_FRICTION.key)] {
            if spring.mu_d != spring.mu_s {
                return Err(ParamError::new(
                    key,
                    format!(
                        "{key} has one coefficient, static = dynamic ({} != {})",
                        spring.mu_s, spring.mu_d
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The forces of one contact over a step: `load` is the Coulomb load f_N* ≥ 0 of the
    /// law, `in_contact` whether δ > 0 (otherwise the springs are reset and nothing acts).
    pub fn respond(
        &self,
        k: &Kinematics,
        geom: &PairGeometry,
        in_contact: bool,
        load: f64,
        dt: f64,
        history: &mut ContactHistory,
    ) -> FrictionResponse {
        let mut r = FrictionResponse::default();
        if !in_contact {
            reset(history);
            return r;
        }
        let lever = geom.a12;
        if self.sliding.is_on() {
            let st = sliding::step(
                &self.sliding,
                k.n,
                k.v_t,
                load,
                dt,
                &mut history.tangential,
                &mut history.slipping,
            );
            r.tangential = st.force;
            r.sliding = st.sliding;
            r.potential += 0.5 * self.sliding.k * st.spring.length_squared();
        }
        if self.rolling.is_on() {
            let (couple, st) = rolling::step(
                &self.rolling,
                k.n,
                k.omega_rel,
                lever,
                load,
                dt,
                &mut history.rolling,
            );
            r.couple += couple;
            r.potential += 0.5 * self.rolling.k * st.spring.length_squared();
        }
        if self.twisting.is_on() {
            let (couple, st) = twisting::step(
                &self.twisting,
                self.twisting.k,
                k.n,
                k.omega_rel,
                lever,
                load,
                dt,
                &mut history.twist,
            );
            r.couple += couple;
            r.potential += 0.5 * self.twisting.k * st.spring * st.spring;
        }
        r
    }

    /// The oscillators of the sub-models that act, for the time step: the tangential one
    /// with the contact-point mass m_t = 2/7·m_r of solid spheres, rolling and twisting with
    /// 1/[ℓ²(1/I_i + 1/I_j)] ([`PairGeometry::rotational_mass`]).
    pub fn oscillators(&self, geom: &PairGeometry) -> Vec<Oscillator> {
        let mut out = Vec::new();
        let mut add = |s: &CoulombSpring, mass: f64, what| {
            if s.is_on() {
                out.push(Oscillator {
                    k: s.k,
                    mass,
                    gamma: s.gamma,
                    what,
                });
            }
        };
        add(&self.sliding, geom.tangential_mass(), "tangential");
        add(&self.rolling, geom.rotational_mass, "rolling");
        add(&self.twisting, geom.rotational_mass, "twisting");
        out
    }
}

/// Forgets the three springs (the contact opened).
pub fn reset(history: &mut ContactHistory) {
    history.tangential = DVec3::ZERO;
    history.slipping = false;
    history.rolling = DVec3::ZERO;
    history.twist = 0.0;
}

/// Rotates `v` into the plane normal to `n`, keeping its length (zero if `v` ∥ `n`).
///
/// The contact frame turns with the pair; projecting alone would shrink a stored spring
/// and so destroy elastic energy (and torque) by frame rotation alone; rescaling to the
/// old length keeps |v| and ½k|v|² (the usual history rotation of LIGGGHTS/LAMMPS, Luding
/// 2008 eq. 17 per LAMMPS).
pub fn rotate_into_plane(v: DVec3, n: DVec3) -> DVec3 {
    let len2 = v.length_squared();
    if len2 == 0.0 {
        return DVec3::ZERO;
    }
    let p = v - n * n.dot(v);
    let lp2 = p.length_squared();
    // |p| > 1e-12·|v|, squared
    if lp2 > 1e-24 * len2 {
        p * (len2 / lp2).sqrt()
    } else {
        DVec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ContactModel, HystereticParams, LsdParams};

    fn luding(mu: f64, mu_r: f64, mu_o: f64, k: f64, gamma: f64) -> LudingFriction {
        let s = |mu: f64, share: f64| CoulombSpring {
            mu_s: mu,
            mu_d: mu,
            k: share * k,
            gamma: share * gamma,
        };
        LudingFriction {
            sliding: s(mu, TANGENTIAL_SHARE),
            rolling: s(mu_r, ROTATIONAL_SHARE),
            twisting: s(mu_o, ROTATIONAL_SHARE),
        }
    }

    /// Luding's defaults give every oscillator the normal period for two equal spheres;
    /// against a wall (lever 2r) rolling and twisting are twice as fast, and the time step
    /// follows them.
    #[test]
    fn the_time_step_sees_the_friction_oscillators() {
        let (k, r, m) = (100.0, 1e-3, 8e-6);
        let lsd = |l: LudingFriction| {
            ContactModel::Lsd(LsdParams {
                luding: l,
                ..LsdParams::new(k, 0.0)
            })
        };
        let plain = lsd(LudingFriction::default());
        let all = lsd(luding(0.5, 0.1, 0.1, k, 0.0));
        let pair = PairGeometry::spheres(r, r, m, m);
        let tc = plain.time_step(&pair, 1.0).contact_time;
        for o in all.friction_oscillators(&pair, 1.0) {
            let t = std::f64::consts::PI * (o.mass / o.k).sqrt();
            assert!((t / tc - 1.0).abs() < 1e-12, "{}: {t} vs {tc}", o.what);
        }
        assert!((all.time_step(&pair, 1.0).contact_time / tc - 1.0).abs() < 1e-12);
        let wall = PairGeometry::wall(r, m);
        let tc = plain.time_step(&wall, 1.0).contact_time;
        let ts = all.time_step(&wall, 1.0);
        assert!((ts.contact_time / tc - 0.5).abs() < 1e-12, "{}", ts.reason);
        assert!(ts.reason.contains("rolling"), "{}", ts.reason);
        // sliding alone keeps the normal period against the wall
        let sliding = lsd(luding(0.5, 0.0, 0.0, k, 0.0));
        assert!((sliding.time_step(&wall, 1.0).contact_time / tc - 1.0).abs() < 1e-12);
        // the dashpots (here binding): γ_r/m_rot = 4·γ0/m_r against a wall (γ_r = 2/5·γ0,
        // m_rot = m/10), γ_t/m_t = γ0/m_r
        let gamma0 = 0.02;
        let visc = |l: LudingFriction| {
            ContactModel::Lsd(LsdParams {
                luding: l,
                ..LsdParams::new(k, gamma0)
            })
            .time_step(&wall, 1.0)
            .max
        };
        let normal = visc(LudingFriction::default());
        assert!((visc(luding(0.5, 0.0, 0.0, k, gamma0)) / normal - 1.0).abs() < 1e-12);
        assert!((visc(luding(0.5, 0.1, 0.0, k, gamma0)) / normal - 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_contact_that_opens_forgets_its_springs() {
        let l = luding(0.5, 0.1, 0.1, 100.0, 0.0);
        let mut h = ContactHistory {
            tangential: DVec3::X,
            rolling: DVec3::Y,
            twist: 1.0,
            slipping: true,
            ..Default::default()
        };
        let kin = Kinematics {
            n: DVec3::Z,
            ..Default::default()
        };
        let geom = PairGeometry::wall(1e-3, 1e-5);
        let r = l.respond(&kin, &geom, false, 1.0, 1e-6, &mut h);
        assert_eq!(r, FrictionResponse::default());
        assert_eq!(
            (h.tangential, h.rolling, h.twist, h.slipping),
            (DVec3::ZERO, DVec3::ZERO, 0.0, false)
        );
        // in contact: the springs' energy is stored
        let kin = Kinematics {
            delta: 1e-6,
            n: DVec3::Z,
            v_t: DVec3::X,
            omega_rel: DVec3::new(1.0, 0.0, 1.0),
            ..Default::default()
        };
        let r = l.respond(&kin, &geom, true, 1.0, 1e-6, &mut h);
        assert!(r.potential > 0.0 && r.couple.x != 0.0 && r.couple.z != 0.0);
    }

    #[test]
    fn validation_names_the_parameter() {
        let bad = |f: fn(&mut LudingFriction)| {
            let mut l = luding(0.5, 0.1, 0.1, 100.0, 1e-3);
            f(&mut l);
            HystereticParams {
                luding: l,
                ..HystereticParams::paper_figure()
            }
            .validate()
            .unwrap_err()
            .param
        };
        assert_eq!(bad(|l| l.sliding.mu_s = -0.1), "friction");
        assert_eq!(bad(|l| l.sliding.mu_d = 0.6), "friction_dynamic");
        // μd = 0 would never end a slip: the test force never falls below 0
        assert_eq!(bad(|l| l.sliding.mu_d = 0.0), "friction_dynamic");
        assert_eq!(bad(|l| l.sliding.k = 0.0), "kt");
        assert_eq!(bad(|l| l.rolling.gamma = -1.0), "gamma_r");
        assert_eq!(bad(|l| l.twisting.k = f64::NAN), "ko");
        assert_eq!(bad(|l| l.rolling.mu_d = 0.05), "rolling_friction");
        // an off sub-model needs no stiffness
        let off = LudingFriction {
            rolling: CoulombSpring::default(),
            ..luding(0.5, 0.0, 0.1, 100.0, 0.0)
        };
        assert!(off.validate().is_ok());
    }
}
