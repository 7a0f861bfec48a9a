//! When a collision is decided: the rules that find a pair stuck (turned back, crept to
//! rest, at rest) and the one that finds it undecidable within the step limit.

use super::{MAX_STEPS, REST_SPEED};

/// Consecutive steps an approach below [`REST_SPEED`] must decay as a creep to count as
/// come to rest.
const CREEP_STEPS: u32 = 10;

/// An approach in contact slower than this fraction of the impact speed is projected to its
/// rest ([`SlowCreep`]).
const SLOW_CREEP: f64 = 1e-2;

/// An approach in contact that slows as a creep, its e-folding τ measured over blocks of
/// [`SlowCreep::BLOCK`] steps: where τ has held for [`SlowCreep::STEADY`] blocks, the steps
/// it needs to slow to rest are known long before the step limit finds them out.
#[derive(Default)]
struct SlowCreep {
    /// Steps and approach speed at the start of the current block.
    start: Option<(u64, f64)>,
    /// The last block's e-folding, steps.
    tau: Option<f64>,
    /// Consecutive blocks whose e-folding held within [`SlowCreep::HOLD`].
    steady: u32,
    /// Steps and e-folding where the blocks began to hold.
    since: Option<(u64, f64)>,
    /// The relative change of the speed over a block that the backend's state resolves
    /// (0: f64; a smaller drop counts as this one, a lower bound on the decay's e-folding).
    noise: f64,
    /// Whether a block since `since` dropped by less than `noise`: the projection is then
    /// a lower bound.
    floored: bool,
}

impl SlowCreep {
    /// A fresh rule over a backend whose speeds resolve relative changes of `noise`.
    fn restart(noise: f64) -> Self {
        Self {
            noise,
            ..Self::default()
        }
    }

    const BLOCK: u64 = 1000;
    const HOLD: f64 = 0.1;
    const STEADY: u32 = 10;

    /// After `steps`, approaching at `vn`: the steps to slow to `rest` once τ has held.
    /// Where τ falls over the blocks at r steps a step, the decay speeds up: the speed
    /// reaches rest after τ·(1 − e^(−r·L))/r steps (L = ln(vn/rest); τ·L where it holds
    /// still), which a linear stop (r = 1: τ, the steps to the turn) and a power-law one
    /// (r = 1/q) meet exactly, and noise in r only shortens.
    fn steps_to_rest(&mut self, steps: u64, vn: f64, rest: f64) -> Option<f64> {
        let Some((from, vn_from)) = self.start else {
            self.start = Some((steps, vn));
            return None;
        };
        if steps - from < Self::BLOCK {
            return None;
        }
        // (a speed that rises, beyond the noise, is no creep)
        let drop = (vn_from / vn).ln();
        if vn >= vn_from && drop <= -self.noise {
            *self = Self::restart(self.noise);
            return None;
        }
        let tau = (steps - from) as f64 / drop.max(self.noise);
        let held = self.tau.is_some_and(|t| (tau / t - 1.0).abs() < Self::HOLD);
        self.steady = if held { self.steady + 1 } else { 0 };
        if !held {
            (self.since, self.floored) = (Some((steps, tau)), false);
        }
        self.floored |= drop < self.noise;
        (self.start, self.tau) = (Some((steps, vn)), Some(tau));
        let (since, tau_since) = self.since?;
        if self.steady < Self::STEADY {
            return None;
        }
        let falls = ((tau_since - tau) / (steps - since) as f64).max(0.0);
        let l = (vn / rest).ln().max(0.0);
        Some(match falls > 0.0 {
            true => tau * -(-falls * l).exp_m1() / falls,
            false => tau * l,
        })
    }
}

/// Consecutive steps a pair in contact must move slower than [`REST_SPEED`] of the impact
/// speed to count as at rest (a sub-linear dashpot stops it in finite time, not as a
/// creep). A turn crosses that band within a step or a few (a collision of 5·10⁷ steps
/// in about 60).
const REST_STEPS: u32 = 1000;

/// The stop rules' state over a collision's steps since the first touch.
pub(super) struct StopRules {
    /// The impact's normal speed, m/s.
    vn0: f64,
    /// Whether the pair has receded since it touched.
    pub receding: bool,
    /// Its fastest receding speed so far, m/s.
    fastest_receding: f64,
    /// The last touched step's approach speed (the impact's before), m/s.
    vn_before: f64,
    /// Consecutive steps an approach below [`REST_SPEED`] has decayed as a creep.
    creeping: u32,
    /// The last step's steps to a stop at its deceleration.
    last_to_stop: Option<f64>,
    /// The slow creep's projection.
    slow_creep: SlowCreep,
    /// Consecutive steps in contact slower than [`REST_SPEED`].
    resting: u32,
}

impl StopRules {
    /// The rules of a collision at normal speed `vn0`, on a backend whose speeds resolve
    /// a relative change of `speed_noise` from one block of steps to the next.
    pub(super) fn new(vn0: f64, speed_noise: f64) -> Self {
        Self {
            vn0,
            receding: false,
            fastest_receding: 0.0,
            vn_before: vn0,
            creeping: 0,
            last_to_stop: None,
            slow_creep: SlowCreep::restart(speed_noise),
            resting: 0,
        }
    }

    /// Whether the last projection rests on the backend's speed noise: a lower bound.
    pub(super) fn projection_is_a_bound(&self) -> bool {
        self.slow_creep.floored
    }

    /// After `steps` (the pair has touched), approaching at `vn` (< 0: receding), in
    /// `contact` or not: whether the pair has come to a stop (stuck, where it is in range),
    /// and the steps an approach too slow for the step limit still needs to come to rest.
    pub(super) fn after_step(&mut self, steps: u64, vn: f64, contact: bool) -> (bool, Option<f64>) {
        let vn0 = self.vn0;
        if vn < 0.0 {
            self.receding = true;
            self.fastest_receding = self.fastest_receding.max(-vn);
        }
        let receding = self.receding;
        let turned = receding && vn > 0.0;
        let crept = receding && -vn < REST_SPEED * vn0.min(self.fastest_receding) && contact;
        // an overdamped approach that creeps into its rest without turning back: slower
        // than REST_SPEED of the impact, and decaying as a creep does (its steps to a stop
        // at the current deceleration, vn/Δ, hold; at a turn they fall by one a step)
        let slowing = self.vn_before - vn;
        if !receding && contact && vn > 0.0 && vn < REST_SPEED * vn0 && slowing > 0.0 {
            let to_stop = vn / slowing;
            self.creeping = match self.last_to_stop {
                Some(last) if to_stop > last - 0.5 => self.creeping + 1,
                _ => 0,
            };
            self.last_to_stop = Some(to_stop);
        } else {
            (self.creeping, self.last_to_stop) = (0, None);
        }
        self.vn_before = vn;
        let mut hopeless = None;
        if !receding && contact && vn > 0.0 && vn < SLOW_CREEP * vn0 {
            hopeless = self.slow_creep.steps_to_rest(steps, vn, REST_SPEED * vn0);
            hopeless = hopeless.filter(|&needs| needs > 2.0 * (MAX_STEPS - steps) as f64);
        } else {
            self.slow_creep = SlowCreep::restart(self.slow_creep.noise);
        }
        let crept_in = self.creeping >= CREEP_STEPS;
        self.resting = match contact && vn.abs() < REST_SPEED * vn0 {
            true => self.resting + 1,
            false => 0,
        };
        let at_rest = self.resting >= REST_STEPS;
        (turned || crept || crept_in || at_rest, hopeless)
    }
}

#[cfg(test)]
mod tests {
    use super::SlowCreep;

    /// Feeds `speed(step)` to the creep rule from step 0 until it projects: the step and
    /// its projection.
    fn projected(speed: impl Fn(f64) -> f64, rest: f64) -> (u64, f64) {
        projected_over(speed, rest, 0.0)
    }

    /// [`projected`] on a backend whose speeds resolve relative changes of `noise`.
    fn projected_over(speed: impl Fn(f64) -> f64, rest: f64, noise: f64) -> (u64, f64) {
        let mut creep = SlowCreep::restart(noise);
        (0..1_000_000u64)
            .find_map(|k| {
                creep
                    .steps_to_rest(k, speed(k as f64), rest)
                    .map(|n| (k, n))
            })
            .expect("no projection")
    }

    /// The projection is the steps to rest of an exponential creep, and of a linear and a
    /// power-law stop, whose e-folding falls (projected as exponential, a linear stop 3e5
    /// steps ahead was taken for 9 times as far and stopped as undecidable).
    #[test]
    fn the_creep_projection_follows_how_the_speed_falls() {
        let (v0, rest, t) = (1e-3, 1e-6, 3e5);
        type Curve = Box<dyn Fn(f64) -> f64>;
        // (the speed at step k, and the steps from k to rest)
        let cases: [(&str, Curve, Curve); 3] = [
            (
                "exponential",
                Box::new(move |k| v0 * (-k / 1e9).exp()),
                Box::new(move |k| 1e9 * (v0 * (-k / 1e9).exp() / rest).ln()),
            ),
            (
                "linear",
                Box::new(move |k| v0 * (1.0 - k / t)),
                Box::new(move |k| t * (1.0 - rest / v0) - k),
            ),
            (
                "power law",
                Box::new(move |k| v0 * (1.0 - k / t).powi(2)),
                Box::new(move |k| (t - k) - t * (rest / v0).sqrt()),
            ),
        ];
        for (name, speed, steps_left) in cases {
            let (k, n) = projected(speed, rest);
            let truth = steps_left(k as f64);
            assert!(
                (n / truth - 1.0).abs() < 0.02,
                "{name}: {n:e} at step {k}, not {truth:e}"
            );
        }
    }

    /// A creep slower than the f32 state resolves (5e-7 a block under a sample-to-sample
    /// rounding of 1e-6, as on the GPU) is projected from the noise floor's e-folding, a
    /// lower bound, within a few blocks more than the rule needs in f64 (it used to reset at
    /// every rise and run the 5e7 steps out).
    #[test]
    fn a_creep_below_the_speed_noise_is_projected_from_its_floor() {
        let (v0, rest, tau) = (1e-3, 1e-6, 2e9);
        let speed = move |k: f64| v0 * (-k / tau).exp() * (1.0 + 1e-6 * (0.7 * k).sin());
        let (k, n) = projected_over(speed, rest, 1e-5);
        let truth = tau * (speed(k as f64) / rest).ln();
        assert!(k < 15_000, "projected at step {k}");
        assert!(n <= truth && n > 2.0 * 5e7, "{n:e} against {truth:e}");
    }
}
