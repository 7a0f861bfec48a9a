//! How well each servo wall held its target force: the normal force on it over the last
//! quarter of the time the run spent in its last servo phase. A gain too high for the
//! bed (stable while gain·k_bed·dt < 1, where k_bed is the packing's) makes the wall swing
//! about its target; a wall still travelling stays off it. `powder run` reports both.

use crate::scene::{Scene, WallPhase};
use glam::DVec3;
use serde::Serialize;

/// The root-mean-square deviation from the target, over |target|, beyond which a servo wall
/// did not hold its target (a rearranging bed's fluctuations stay well below it).
pub const SERVO_RMS_MAX: f64 = 0.1;

/// The samples a verdict needs: fewer leave the wall unjudged.
const MIN_SAMPLES: usize = 4;

/// One servo wall's normal force over the last quarter of its last servo phase in this
/// run (a resumed run judges its own part only).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ServoHold {
    /// The wall's index in the scene.
    pub wall: usize,
    /// The target normal force of that servo phase, N.
    pub target: f64,
    /// That phase's gain, m/s per N.
    pub gain: f64,
    /// The least normal force sampled (after every chunk of steps: a swing faster than the
    /// chunks is seen through its samples), N.
    pub min: f64,
    /// The largest, N.
    pub max: f64,
    /// The mean, N.
    pub mean: f64,
    /// The root-mean-square deviation from the target, N.
    pub rms: f64,
    /// How many samples.
    pub samples: usize,
    /// How many of the samples found the wall moving at its phase's `servo_max_speed`
    /// (within 1 %): a wall holding its force moves slower; one pinned there at most samples
    /// swings a step each way, however small its force's ripple.
    pub at_speed_limit: usize,
    /// Whether `rms` is within [`SERVO_RMS_MAX`] of the target and the wall was at its
    /// speed limit at no more than half the samples.
    pub held: bool,
}

impl ServoHold {
    /// Whether the wall was at its speed limit at more than half the samples.
    fn pinned(&self) -> bool {
        2 * self.at_speed_limit > self.samples
    }

    /// The warning when the wall did not hold its target: swinging about it, or off it.
    pub fn warning(&self, dt: f64) -> Option<String> {
        // (swinging about the target crosses it, at its speed limit a step each way; a wall
        // short of it never crosses it)
        let crosses = self.min <= self.target && self.target <= self.max;
        let what = match self.pinned() && crosses {
            true => format!(
                "wall {}'s servo did not hold its target {:e} N: it moved at servo_max_speed at {} of its {} samples over the last quarter of its servo phase, a step each way about the target (the force ranged from {:e} to {:e} N)",
                self.wall, self.target, self.at_speed_limit, self.samples, self.min, self.max
            ),
            false => format!(
                "wall {}'s servo did not hold its target {:e} N: the normal force on it ranged from {:e} to {:e} N (mean {:e} N) over the last quarter of its servo phase",
                self.wall, self.target, self.min, self.max, self.mean
            ),
        };
        let advice = if crosses {
            format!(
                "lower servo_gain ({:e} m/s per N; it is stable while gain·k_bed·dt < 1 with dt = {dt:e} s and k_bed the packing's stiffness under the wall)",
                self.gain
            )
        } else {
            "the wall had not reached it (a longer run, or a larger servo_max_speed)".into()
        };
        (!self.held).then(|| format!("{what}; {advice}"))
    }
}

/// A warning for each servo wall whose gain makes it overshoot as soon as one particle
/// touches it: gain·k·dt ≥ 1 (the documented bound), k the normal stiffness of that
/// particle's contact with the wall under the servo's force (a bed under the wall is
/// stiffer still). Such a wall moves at its largest speed a step each way.
pub fn unstable_gains(scene: &Scene, dt: f64) -> Vec<String> {
    let mut largest = vec![0.0f64; scene.materials.len()];
    for p in &scene.particles {
        largest[p.material] = largest[p.material].max(p.radius);
    }
    let mut out = Vec::new();
    for (w, wall) in scene.walls.iter().enumerate() {
        for (from, phase) in &wall.motion.phases {
            let WallPhase::Servo { force, gain, .. } = *phase else {
                continue;
            };
            // each material's largest sphere: a Hertz contact stiffens with the radius
            let stiffest = (largest.iter().enumerate())
                .filter(|(_, &r)| r > 0.0)
                .filter_map(|(a, &r)| {
                    let model = scene.pair_model(wall.material, a).ok()?;
                    Some(model.normal_stiffness(r, force.abs()))
                })
                .fold(0.0, f64::max);
            let margin = gain * stiffest * dt;
            if margin >= 1.0 {
                out.push(format!(
                    "wall {w}'s servo phase from t = {from:e} s: servo_gain {gain:e} m/s per N overshoots as soon as one particle touches the wall: gain·k·dt = {} ≥ 1 with k = {stiffest:.4e} N/m (the normal stiffness of a particle's contact with the wall under the servo force) and dt = {dt:e} s; the wall would swing at servo_max_speed a step each way instead of holding its force; a gain below {:.4e} m/s per N holds with one contact (a bed under the wall is stiffer: less still)",
                    crate::error::fixed(margin, 3),
                    1.0 / (stiffest * dt)
                ));
                break;
            }
        }
    }
    out
}

/// One watched wall: its index, its unit normal and its samples (time, normal force the
/// particles push on it, its speed along the normal).
type Watched = (usize, DVec3, Vec<(f64, f64, f64)>);

/// The normal forces on the servo walls, sampled after every chunk of a run.
pub(super) struct ServoWatch {
    walls: Vec<Watched>,
}

impl ServoWatch {
    /// Watches every wall with a servo phase.
    pub(super) fn new(scene: &Scene) -> Self {
        let walls = (scene.walls.iter().enumerate())
            .filter(|(_, w)| w.motion.servo())
            .map(|(i, w)| (i, DVec3::from_array(w.normal).normalize(), Vec::new()))
            .collect();
        Self { walls }
    }

    /// Samples the walls' forces and speeds at time `t` (none without the ledger).
    pub(super) fn record(&mut self, t: f64, forces: Option<&[DVec3]>, velocities: &[DVec3]) {
        let Some(forces) = forces else { return };
        for (w, n, samples) in &mut self.walls {
            if let (Some(f), Some(v)) = (forces.get(*w), velocities.get(*w)) {
                // (the particles push against the wall's normal; + 0.0: no wall without
                // contacts reports −0)
                samples.push((t, -f.dot(*n) + 0.0, v.dot(*n).abs()));
            }
        }
    }

    /// Each watched wall's last servo phase within this run (from `start` to `end`): its
    /// force over the last quarter of the time the run spent in it; and a note for each
    /// wall sampled too rarely there to judge.
    pub(super) fn holds(
        &self,
        scene: &Scene,
        start: f64,
        end: f64,
    ) -> (Vec<ServoHold>, Vec<String>) {
        let (mut out, mut unjudged) = (Vec::new(), Vec::new());
        for (w, _, samples) in &self.walls {
            let phases = &scene.walls[*w].motion.phases;
            let last = phases
                .iter()
                .rposition(|(from, p)| *from < end && matches!(p, WallPhase::Servo { .. }));
            let Some(i) = last else { continue };
            let (
                from,
                WallPhase::Servo {
                    force,
                    gain,
                    max_speed,
                },
            ) = phases[i]
            else {
                continue;
            };
            let to = phases.get(i + 1).map_or(end, |(next, _)| next.min(end));
            // (a phase that ended before a resumed run began is the earlier run's to judge)
            let begun = from.max(start);
            if to <= begun {
                continue;
            }
            let since = to - 0.25 * (to - begun);
            let sampled: Vec<(f64, f64)> = (samples.iter())
                .filter(|(t, _, _)| *t >= since && *t <= to)
                .map(|&(_, f, v)| (f, v))
                .collect();
            let window: Vec<f64> = sampled.iter().map(|s| s.0).collect();
            let at_speed_limit = (sampled.iter())
                .filter(|s| s.1 >= 0.99 * max_speed.abs())
                .count();
            if window.len() < MIN_SAMPLES {
                unjudged.push(format!(
                    "wall {w}'s servo phase from t = {from:e} s was sampled {} times in the last quarter of its time in this run ({MIN_SAMPLES} needed; once every chunk of at most 1000 steps and at every output): whether it held its target {force:e} N is not judged; a smaller simulation.output_every samples it more often",
                    window.len()
                ));
                continue;
            }
            let k = window.len() as f64;
            let rms = (window.iter().map(|f| (f - force).powi(2)).sum::<f64>() / k).sqrt();
            out.push(ServoHold {
                wall: *w,
                target: force,
                gain,
                min: window.iter().copied().fold(f64::INFINITY, f64::min),
                max: window.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                mean: window.iter().sum::<f64>() / k,
                rms,
                samples: window.len(),
                at_speed_limit,
                held: rms <= SERVO_RMS_MAX * force.abs() && 2 * at_speed_limit <= window.len(),
            });
        }
        (out, unjudged)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lid on one sphere (k = 100 N/m, dt = 1.29e-5 s): a gain of 1000 m/s per N is
    /// unstable with that one contact (gain·k·dt = 1.29; it chattered a step each way and
    /// was judged held), 100 is not; the warning names the wall and a stable gain.
    #[test]
    fn a_gain_unstable_with_one_contact_is_warned_of() {
        let rough = |gain: f64, friction: &str| {
            let text = format!(
                "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 0.01]\n[simulation]\nduration = 0.05\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\ngamma0 = 1e-3\n{friction}\n[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n[[wall]]\npoint = [0.0, 0.0, 0.003]\nnormal = [0.0, 0.0, -1.0]\nservo_force = 0.01\nservo_gain = {gain:?}\nservo_max_speed = 0.5\n[[particles]]\nkind = \"list\"\npositions = [[0.005, 0.005, 0.001]]\nradius = 1e-3\n"
            );
            Scene::from_toml_str(&text, "servo").unwrap()
        };
        let scene = |gain: f64| rough(gain, "");
        let dt = crate::setup::Resolved::new(&scene(1.0)).unwrap().dt;
        let w = unstable_gains(&scene(1000.0), dt);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("wall 1's servo phase from t = 0e0 s: servo_gain 1e3"),
            "{}",
            w[0]
        );
        assert!(w[0].contains("k = 1.0000e2 N/m"), "{}", w[0]);
        assert!(unstable_gains(&scene(100.0), dt).is_empty());
        // a stiff tangential spring shortens the time step, not the normal stiffness: a gain
        // at half the bound is not warned of (the contact time of the tangential
        // oscillator, taken for the normal one, overstated k)
        let stiff = rough(1.0, "friction = 0.5\nkt = 1e4");
        let dt = crate::setup::Resolved::new(&stiff).unwrap().dt;
        let half = 0.5 / (100.0 * dt);
        assert!(unstable_gains(&rough(half, "friction = 0.5\nkt = 1e4"), dt).is_empty());
        assert_eq!(
            unstable_gains(&rough(2.5 * half, "friction = 0.5\nkt = 1e4"), dt).len(),
            1
        );
        // a wall at its speed limit at most samples swings a step each way: not held, though
        // its force's ripple (8 %, as that lid's) is within the 10 % allowed
        let held = |speed: f64| {
            let s = scene(1000.0);
            let mut watch = ServoWatch::new(&s);
            for k in 0..10 {
                let f = if k % 2 == 0 { 0.0092 } else { 0.0108 };
                let forces = [DVec3::ZERO, DVec3::new(0.0, 0.0, f)];
                let velocities = [DVec3::ZERO, DVec3::new(0.0, 0.0, speed)];
                watch.record(0.04 + 0.001 * k as f64, Some(&forces), &velocities);
            }
            let (holds, _) = watch.holds(&s, 0.0, 0.05);
            holds[0].clone()
        };
        let chatter = held(0.5);
        assert_eq!((chatter.at_speed_limit, chatter.held), (10, false));
        let w = chatter.warning(dt).unwrap();
        assert!(
            w.contains("it moved at servo_max_speed at 10 of its 10 samples"),
            "{w}"
        );
        let steady = held(0.01);
        assert_eq!((steady.at_speed_limit, steady.held), (0, true));
    }
}
