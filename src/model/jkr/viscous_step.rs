//! The time step the explicit velocity-dependent forces of the JKR family's dissipations
//! allow: for `krijt` and `stress`, c = 2·T_vis·E*·a/ν² taken at its largest in a head-on
//! collision at the impact velocity, integrated with the law itself (docs/models.md,
//! *Krijt*); for `powerlaw`, dF/dδ̇ at the collision's fastest approach and widest contact.

use std::cell::RefCell;

use super::{Dissipation, JkrParams};
use crate::model::analytic;
use crate::model::krijt::{self, KrijtLaw};
use crate::model::{ContactHistory, PairGeometry};

/// The `krijt`/`stress` viscous force a collision reaches
/// ([`JkrParams::viscous_coefficient_estimate`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscousEstimate {
    /// The largest viscous coefficient c = 2·T_vis·E*·a/ν², kg/s.
    pub c: f64,
    /// The overlap where it was reached, m.
    pub reach: f64,
    /// The step the rule grants, s: the longest one whose integrated collision kept
    /// c·dt/m* within the bound (where none did, within the last round's c).
    pub dt: f64,
}

/// The `powerlaw` dissipation's largest coefficient in a head-on collision
/// ([`JkrParams::power_law_coefficient`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLawEstimate {
    /// c = max(α, 1)·D·E*·v^(α−1)·a^β, kg/s: dF/dδ̇ for α ≥ 1, the chord F/δ̇ at v below.
    pub c: f64,
    /// The approach speed v it is taken at, m/s: the impact speed with the JKR well's
    /// adhesion speed added in quadrature.
    pub speed: f64,
    /// The contact radius a it is taken at, m: a_JKR at the Hertz overlap of that speed.
    pub radius: f64,
}

/// Rounds of [`JkrParams::viscous_coefficient_estimate`] at most (each integrates a
/// collision).
const ROUNDS: usize = 12;
/// A step too long is shortened to this fraction of the one its collision's c allows.
const MARGIN: f64 = 0.98;
/// A step whose collision's c allows less than this factor more is taken as found.
const SETTLED: f64 = 1.25;
/// Past the turn, a c this far below its peak ends a collision: the pair recedes, and c
/// grows again only after a second turn.
const PAST_PEAK: f64 = 0.9;
/// Steps of one collision at most.
const MAX_STEPS: usize = 200_000;
/// Estimates kept per thread (a run asks for the same pairs several times).
const CACHED: usize = 64;

/// The arguments of an estimate and its result.
type Cached = (JkrParams, PairGeometry, [f64; 3], Option<ViscousEstimate>);

thread_local! {
    static CACHE: RefCell<Vec<Cached>> = const { RefCell::new(Vec::new()) };
}

impl JkrParams {
    /// The viscous coefficient c = 2·T_vis·E*·a/ν² of the `krijt`/`stress` dissipations
    /// in a head-on collision at impact speed `v` (None for the other dissipations): the
    /// largest c of the collision integrated ([`Self::viscous_peak`]) at the longest step
    /// tried, at most `dt_trial`, that keeps c·dt/m* ≤ `max_step`.
    pub fn viscous_coefficient_estimate(
        &self,
        geom: &PairGeometry,
        v: f64,
        dt_trial: f64,
        max_step: f64,
    ) -> Option<ViscousEstimate> {
        // (the other dissipations have no such force: nothing to integrate or keep)
        self.dissipation.krijt_law()?;
        let key = [v, dt_trial, max_step];
        let hit = CACHE.with_borrow(|c| {
            c.iter()
                .find(|(p, g, k, _)| p == self && g == geom && k == &key)
                .map(|e| e.3)
        });
        if let Some(found) = hit {
            return found;
        }
        let found = self.integrate_estimate(geom, v, dt_trial, max_step);
        CACHE.with_borrow_mut(|c| {
            if c.len() == CACHED {
                c.remove(0);
            }
            c.push((*self, *geom, key, found));
        });
        found
    }

    /// The largest coefficient c of the `powerlaw` dissipation F = sgn(δ̇)·D·E*·|δ̇|^α·a^β
    /// (paper 001 eq. 19) in a head-on collision at impact speed `v` (None for the other
    /// dissipations): both |δ̇| and a are largest where the explicit step is tested hardest
    /// (α ≥ 1, β ≥ 0). A sub-linear law (α < 1) is taken by its chord at that speed: its
    /// slope grows without bound as δ̇ → 0, where its force vanishes and the step only
    /// chatters about the turn.
    pub fn power_law_coefficient(&self, geom: &PairGeometry, v: f64) -> Option<PowerLawEstimate> {
        let Dissipation::PowerLaw { d, alpha, beta } = self.dissipation else {
            return None;
        };
        let r = geom.r_eff();
        let speed = v.hypot(self.adhesion_speed(r, geom.reduced_mass));
        let deepest = analytic::hertz_delta_max(geom.reduced_mass, r, self.e_star(), speed);
        let radius = self.contact_radius(deepest, r);
        let c = alpha.max(1.0) * d * self.e_star() * speed.powf(alpha - 1.0) * radius.powf(beta);
        Some(PowerLawEstimate { c, speed, radius })
    }

    fn integrate_estimate(
        &self,
        geom: &PairGeometry,
        v: f64,
        dt_trial: f64,
        max_step: f64,
    ) -> Option<ViscousEstimate> {
        let mr = geom.reduced_mass;
        let (mut dt, mut too_long) = (dt_trial, f64::INFINITY);
        let (mut resolved, mut last): (Option<ViscousEstimate>, Option<ViscousEstimate>) =
            (None, None);
        // a step too long for the viscous force makes it oscillate and grow (a larger c):
        // shorten it until the collision is resolved, then lengthen it towards the step
        // its own c allows, short of any found too long
        for _ in 0..ROUNDS {
            let estimate = self.viscous_peak(geom, v, dt)?;
            last = Some(estimate);
            let fits = max_step * mr / estimate.c;
            if fits.is_nan() || fits < dt {
                too_long = too_long.min(dt);
                dt = (MARGIN * fits).max(0.1 * dt);
                continue;
            }
            if resolved.is_none_or(|r| r.dt < dt) {
                resolved = Some(estimate);
            }
            let longer = fits.min(dt_trial).min(MARGIN * too_long);
            if fits < SETTLED * dt || longer <= dt {
                break;
            }
            dt = longer;
        }
        resolved.or(last.map(|l| ViscousEstimate {
            dt: l.dt.min(MARGIN * max_step * mr / l.c),
            ..l
        }))
    }

    /// The largest viscous coefficient c = 2·T_vis·E*·a/ν² (of the contact radius a the
    /// law carries, which lags a_JKR(δ) while the crack moves) in a head-on collision at
    /// speed `v` integrated with step `dt`, and the overlap there; None for the dissipations
    /// without it. The collision ends where the contact breaks, the pair turns back a
    /// second time, or c falls 10 % below its peak after the turn.
    pub fn viscous_peak(&self, geom: &PairGeometry, v: f64, dt: f64) -> Option<ViscousEstimate> {
        let law = self.dissipation.krijt_law()?;
        if self.gamma() == 0.0 {
            return None;
        }
        let r = geom.r_eff();
        let c_of = |a: f64| {
            let c = viscous_coefficient(&law, self, a, r);
            // (a NaN is a T_vis beyond f64: no step resolves it)
            if c.is_nan() {
                f64::INFINITY
            } else {
                c
            }
        };
        let mut history = ContactHistory::default();
        let (mut delta, mut speed, mut acc) = (0.0_f64, v, 0.0);
        let d0 = self.delta0(r);
        // (a stuck pair rests at δ0)
        let mut peak = ViscousEstimate {
            c: c_of(self.contact_radius(d0, r)),
            reach: d0,
            dt,
        };
        let (mut turns, mut peak_step, mut deepest) = (0, 0, 0.0_f64);
        // velocity Verlet with the force at the predicted velocity, as the engines step
        // (the touch's jump impulse left out)
        for step in 0..=MAX_STEPS {
            if step == MAX_STEPS {
                if turns == 0 || peak_step >= MAX_STEPS / 2 {
                    // still compressing, or c still growing while a creeps towards
                    // a_JKR(δ): c at a_JKR of the deepest overlap it can reach bounds it
                    let hertz = analytic::hertz_delta_max(geom.reduced_mass, r, self.e_star(), v);
                    let bound = if turns == 0 {
                        deepest.max(hertz)
                    } else {
                        deepest
                    };
                    let c = c_of(self.contact_radius(bound, r));
                    if c > peak.c {
                        (peak.c, peak.reach) = (c, bound);
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
            let c = c_of(f.contact_radius);
            if c > peak.c {
                (peak.c, peak.reach, peak_step) = (c, delta, step);
            }
            if !c.is_finite() {
                break;
            }
            if (before > 0.0) != (speed > 0.0) {
                turns += 1;
            }
            if turns >= 2 || (turns >= 1 && c < PAST_PEAK * peak.c) {
                break;
            }
        }
        Some(peak)
    }
}

/// c = 2·T_vis·E*·a/ν² of `law` at contact radius `a` (T_vis at that radius), kg/s.
fn viscous_coefficient(law: &KrijtLaw, p: &JkrParams, a: f64, r_eff: f64) -> f64 {
    let m = p.krijt_material();
    krijt::viscous_force(law.relaxation_time_at(a, r_eff, &m), a, 1.0, &m)
}
