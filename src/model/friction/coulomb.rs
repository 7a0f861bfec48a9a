//! The spring–dashpot with a static and a dynamic Coulomb limit that Luding's sliding,
//! rolling and twisting laws share (Luding 2008 eqs. 17–20 as the sources give them,
//! `docs/luding2008_laws.md` §1 and §7).
//!
//! Per contact and step, with v the relative velocity of the sub-model (sliding v_t,
//! rolling v_r, twisting v_o), ξ its spring and f_N* the Coulomb load:
//!
//! * test force f0 = −k·ξ − γ·v;
//! * **stick** if |f0| ≤ μ·f_N*: f = f0 and the spring grows by v·dt;
//! * **slip** otherwise: f = μd·f_N*·t̂ with t̂ = f0/|f0|, and the spring is reset to the
//!   length that gives that force, ξ = −(f + γ·v)/k.
//!
//! The limit μ is μs, or μd where the contact slipped in its last step (the sliding law's
//! `slipping` flag, [`CoulombSpring::step_slipping`]): a slipping contact keeps slipping at
//! μd·f_N* until its test force falls to that, at any dt. Without the flag it would count as
//! sticking again after each reset until the spring grew back to μs, a saw-tooth whose mean
//! tends to (μs + μd)/2 as dt → 0 (`docs/luding2008_laws.md` §1).
//!
//! **Staggered spring.** The stored spring ξ_s is half a step ahead of the last force: the
//! force at the step's end uses ξ_n = ξ_s + ½·v_n·dt (v_n the predicted velocity), then
//! ξ_s ← ξ_n + ½·v_n·dt (after a slip, from the reset spring). Second order, where Luding's
//! literal order lags half a step, a negative damping (`docs/luding2008_laws.md` §8,
//! `docs/models.md`, *Time discretisation*). The stored energy is ½·k·|ξ_n|², the spring
//! the force used.

use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::ops::{Add, Mul, Neg, Sub};

/// A spring displacement or velocity: a 3-vector (sliding, rolling) or a scalar along the
/// normal (twisting).
pub trait Displacement:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self> + Neg<Output = Self>
{
    /// The length.
    fn norm(self) -> f64;
}

impl Displacement for DVec3 {
    fn norm(self) -> f64 {
        self.length()
    }
}

impl Displacement for f64 {
    fn norm(self) -> f64 {
        self.abs()
    }
}

/// One Luding spring–dashpot with its Coulomb limits. Off when μs = 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CoulombSpring {
    /// Static coefficient μs ≥ 0 (0 = off): stick while |f0| ≤ μs·f_N* (μd·f_N* after a
    /// slip, where the law keeps the flag: [`Self::step_slipping`]).
    pub mu_s: f64,
    /// Dynamic coefficient 0 < μd ≤ μs (0 where off): the force while slipping is μd·f_N*.
    pub mu_d: f64,
    /// Spring stiffness k > 0, N/m (a pseudo-force stiffness for rolling and twisting: the
    /// torque stiffness is k·ℓ² per radian). The JKR family's twisting stores 0 for the
    /// Mindlin-derived stiffness of the current contact radius.
    pub k: f64,
    /// Dashpot γ ≥ 0, kg/s.
    pub gamma: f64,
}

/// What one step of a [`CoulombSpring`] gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step<V> {
    /// The force (rolling, twisting: pseudo-force) on particle i.
    pub force: V,
    /// The spring at the evaluation time the force was computed with (after a reset when
    /// slipping): the stored energy is ½·k·|spring|².
    pub spring: V,
    /// Whether the contact slipped (the Coulomb limit truncated the test force).
    pub sliding: bool,
}

impl CoulombSpring {
    /// Whether the sub-model acts (μs > 0).
    pub fn is_on(&self) -> bool {
        self.mu_s > 0.0
    }

    /// One step with stiffness `k` (the declared one, or the JKR family's current one):
    /// `stored` is the staggered spring ξ_s (updated), `v` the relative velocity, `load` the
    /// Coulomb load f_N* ≥ 0. See the module notes for the discretisation.
    pub fn step_with<V: Displacement>(
        &self,
        k: f64,
        stored: &mut V,
        v: V,
        load: f64,
        dt: f64,
    ) -> Step<V> {
        self.step_limit(k, stored, v, load, dt, self.mu_s)
    }

    /// [`Self::step`] of a spring whose limit remembers slipping: μd where the contact
    /// slipped in its last step (`slipping`, updated), μs otherwise.
    pub fn step_slipping<V: Displacement>(
        &self,
        stored: &mut V,
        v: V,
        load: f64,
        dt: f64,
        slipping: &mut bool,
    ) -> Step<V> {
        let limit = if *slipping { self.mu_d } else { self.mu_s };
        let st = self.step_limit(self.k, stored, v, load, dt, limit);
        *slipping = st.sliding;
        st
    }

    /// One step that sticks while |f0| ≤ `limit`·f_N*.
    fn step_limit<V: Displacement>(
        &self,
        k: f64,
        stored: &mut V,
        v: V,
        load: f64,
        dt: f64,
        limit: f64,
    ) -> Step<V> {
        let half = v * (0.5 * dt);
        let spring = *stored + half;
        let f0 = -(spring * k) - v * self.gamma;
        let magnitude = f0.norm();
        if magnitude <= limit * load {
            *stored = spring + half;
            return Step {
                force: f0,
                spring,
                sliding: false,
            };
        }
        // |f0| > μ·f_N* ≥ 0, so t̂ exists
        let force = f0 * (self.mu_d * load / magnitude);
        let spring = -(force + v * self.gamma) * (1.0 / k);
        *stored = spring + half;
        Step {
            force,
            spring,
            sliding: true,
        }
    }

    /// [`Self::step_with`] with the declared stiffness.
    pub fn step<V: Displacement>(&self, stored: &mut V, v: V, load: f64, dt: f64) -> Step<V> {
        self.step_with(self.k, stored, v, load, dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: CoulombSpring = CoulombSpring {
        mu_s: 0.5,
        mu_d: 0.3,
        k: 100.0,
        gamma: 0.0,
    };

    #[test]
    fn sticks_below_the_static_limit_and_grows_the_spring() {
        let mut xi = 0.0;
        let st = S.step(&mut xi, 1e-3, 1.0, 1e-2);
        // the spring at the evaluation time is half a step's travel
        assert!((st.spring - 0.5e-5).abs() < 1e-18 && !st.sliding);
        assert!((st.force + 100.0 * 0.5e-5).abs() < 1e-15);
        assert!((xi - 1e-5).abs() < 1e-18);
    }

    #[test]
    fn slips_above_it_with_the_dynamic_force_and_a_consistent_spring() {
        let s = CoulombSpring { gamma: 2.0, ..S };
        let mut xi = DVec3::new(0.0, -0.01, 0.0);
        let v = DVec3::new(0.0, 0.1, 0.0);
        let load = 1.0;
        let dt = 1e-3;
        let st = s.step(&mut xi, v, load, dt);
        assert!(st.sliding);
        // the force is μd·f_N* along the test force
        assert!((st.force.length() - s.mu_d * load).abs() < 1e-15);
        assert!(st.force.y > 0.0);
        // the reset spring gives exactly that force with the same velocity
        let again = -s.k * st.spring - s.gamma * v;
        assert!((again - st.force).length() < 1e-14);
        assert!((xi - (st.spring + v * (0.5 * dt))).length() < 1e-18);
        // μs ≠ μd: the static limit decides, the dynamic one is the force
        let mut x = 0.0;
        let between = S.step(&mut x, 0.0, 1.0, 0.0);
        assert!(!between.sliding);
        let mut x = -0.004; // |f0| = 0.4: above μd, below μs
        assert!(!S.step(&mut x, 0.0, 1.0, 0.0).sliding);
        let mut x = -0.006; // 0.6 > μs
        let st = S.step(&mut x, 0.0, 1.0, 0.0);
        assert!(st.sliding && (st.force - 0.3).abs() < 1e-15);
    }

    /// A contact driven at a steady slip speed keeps the dynamic force μd·f_N* at every
    /// step once it slips, whatever dt (without the flag it saw-toothed up to μs), and
    /// sticks again, needing μs, once the drive stops.
    #[test]
    fn a_slipping_contact_keeps_the_dynamic_force_at_any_step() {
        for dt in [1e-3, 1e-5, 1e-7] {
            // from just below the static limit, k·v·dt = 1e-4 ≪ (μs − μd)·f_N* a step
            let (mut xi, mut slipping) = (0.00499, false);
            let mut slipped = false;
            for _ in 0..20_000 {
                let st = S.step_slipping(&mut xi, 1e-6 / dt, 1.0, dt, &mut slipping);
                if slipped {
                    assert!(
                        st.sliding && (st.force + 0.3).abs() < 1e-12,
                        "dt {dt}: {st:?}"
                    );
                }
                slipped |= st.sliding;
            }
            assert!(slipped, "dt {dt}");
            // turned back, the test force falls below μd·f_N*: it sticks, and then a push
            // between μd and μs holds
            let st = S.step_slipping(&mut xi, -2e-6 / dt, 1.0, dt, &mut slipping);
            assert!(!st.sliding && !slipping, "dt {dt}: {st:?}");
            let mut x = -0.004;
            assert!(
                !S.step_slipping(&mut x, 0.0, 1.0, 0.0, &mut slipping)
                    .sliding
            );
        }
    }

    #[test]
    fn zero_load_gives_no_force() {
        let mut xi = DVec3::new(1e-3, 0.0, 0.0);
        let st = S.step(&mut xi, DVec3::new(0.0, 1.0, 0.0), 0.0, 1e-3);
        assert!(st.sliding && st.force == DVec3::ZERO);
    }
}
