//! The run monitor: what must stop a run (non-finite values, overlaps beyond what the
//! papers calibrate, energy growth, particles leaving the domain), with a hint.

use super::overlap_partner::{appeared_inside, deepest_partner, POUR_ADVICE};
use super::*;

/// Largest overlap over the reduced radius a12 the run monitor accepts: beyond it the
/// contact model is outside anything the papers calibrate (overlaps of half a radius).
pub const MAX_OVERLAP_RATIO: f64 = 0.5;

/// Largest growth of the total energy (kinetic + stored + gravitational + dissipated),
/// relative to the run's energy scale, that the monitor accepts: none of the models
/// injects energy, so growth means the integration has gone wrong.
pub const MAX_ENERGY_GROWTH: f64 = 0.05;

/// What the energy check measures against: the run's energies at its start and the
/// energy scale it has reached. A checkpoint carries it, so a resumed run checks (and
/// reports its balance) as the straight run does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MonitorReference {
    /// The energies at the run's first step.
    pub initial: ObservedEnergies,
    /// The largest energy scale so far (`energy_scale`), J.
    pub scale: f64,
}

/// Ulps of the energy terms' magnitudes, times √n, that the total may grow by through
/// rounding alone (the sums over n particles of terms far larger than the energy in play,
/// e.g. gravitational energy when a tiny particle sets a tiny time step).
pub const ROUNDING_ULPS: f64 = 16.0;

/// The run monitor: what must stop a run, with the step, the particles and a hint.
/// `obs` is the observation now (`None` where the run took none: without the ledger it
/// needs only the engine's own watch, and observes where a check fails) and `start` the
/// energies at the start; without the ledger (no total) the energy-growth check is
/// skipped. What that loses: a slow blow-up (a time step a
/// little too large for the stiffest contact, pumping energy in a few per cent per
/// chunk) is caught only once it shows as a non-finite value, an overlap beyond
/// [`MAX_OVERLAP_RATIO`] or a particle leaving the domain, which the other checks watch
/// every step, with or without the ledger. Kinetic energy alone is no substitute: stored
/// adhesion and moving walls legitimately feed it.
pub(super) fn monitor(
    engine: &mut impl Simulation,
    dt_rule: &str,
    scene: &Scene,
    (obs, start): (Option<&Observation>, &ObservedEnergies),
    scale: f64,
) -> Result<(), PowderError> {
    let steps = engine.steps();
    // (a batch poured onto particles still in its region overlaps them: no push aside)
    let poured = match scene.pours() {
        true => ", or particles appeared where earlier ones still were (a pour's region must have emptied before its next batch: *Pouring* in the README)",
        false => "",
    };
    let hint = format!(
        "the time step ({:.4e} s; {dt_rule}) may be too large for this scene{poured}",
        engine.dt(),
    );
    if let Some(i) = engine.non_finite() {
        return Err(PowderError::Run(format!(
            "step {steps}: particle {i} has a non-finite position, velocity or spin; {hint}"
        )));
    }
    if let Some(peak) = engine.take_peak_overlap() {
        if peak.ratio > MAX_OVERLAP_RATIO {
            let taken;
            let obs = match obs {
                Some(obs) => obs,
                None => {
                    taken = engine.observe()?;
                    &taken
                }
            };
            let (radii, dt) = (engine.radii(), engine.dt());
            let appeared = |i: usize| engine.has_appeared(i);
            if let Some(a) =
                appeared_inside(scene, obs, radii, (steps, dt, &appeared), MAX_OVERLAP_RATIO)
            {
                return Err(PowderError::Run(format!(
                    "step {steps}: {} by {} of the reduced radius (limit {MAX_OVERLAP_RATIO}); {POUR_ADVICE}",
                    a.what,
                    ratio_text(a.ratio)
                )));
            }
            // (a backend that knows only a particle beyond the limit, not necessarily the
            // deepest: its partner, and their own overlap, from the positions)
            let (ratio, who) = peak
                .unnamed
                .and_then(|i| deepest_partner(scene, obs, radii, i, appeared))
                .unwrap_or((peak.ratio, peak.who));
            return Err(PowderError::Run(format!(
                "step {steps}: {who} by {} of the reduced radius (limit {MAX_OVERLAP_RATIO}); an impact or a load (gravity, adhesion, a wall) is too strong for the contact stiffness, or {hint}",
                ratio_text(ratio)
            )));
        }
    }
    if let Some((name, value)) = obs.and_then(|o| o.energies.non_finite()) {
        return Err(PowderError::Run(format!(
            "step {steps}: the {name} energy is {value} (beyond f64's range: a velocity, spin or wall speed far too large for the scene?); {hint}"
        )));
    }
    let escaped = engine.escaped(5);
    if !escaped.is_empty() {
        return Err(PowderError::Run(format!(
            "step {steps}: particles {escaped:?} left the domain box; enlarge [domain] or add walls (or {hint})"
        )));
    }
    let Some(obs) = obs else {
        return Ok(());
    };
    let now = &obs.energies;
    let Some((total, initial_total)) = now.total().zip(start.total()) else {
        return Ok(());
    };
    let rounding = ROUNDING_ULPS
        * (engine.len() as f64).sqrt()
        * f64::EPSILON
        * (now.magnitude() + start.magnitude());
    let allowed = MAX_ENERGY_GROWTH * scale + rounding;
    if allowed > 0.0 && total - initial_total > allowed {
        // (a particle poured onto another brings the overlap's stored energy unbooked; one
        // within the 1 % a scene's placement allows is not blamed)
        let (radii, dt) = (engine.radii(), engine.dt());
        let appeared = |i: usize| engine.has_appeared(i);
        if let Some(a) = appeared_inside(scene, obs, radii, (steps, dt, &appeared), 0.01) {
            return Err(PowderError::Run(format!(
                "step {steps}: the total energy grew by {:.3e} J, beyond the {allowed:.3e} J allowed, as {} by {} of the reduced radius: the energy stored in that overlap enters the run unbooked; {POUR_ADVICE}",
                total - initial_total,
                a.what,
                ratio_text(a.ratio)
            )));
        }
        return Err(PowderError::Run(format!(
            "step {steps}: the total energy grew by {:.3e} J, beyond the {allowed:.3e} J allowed ({}% of the run's energy scale {scale:.3e} J, and {rounding:.1e} J of rounding), which no contact model can inject; {hint}",
            total - initial_total,
            100.0 * MAX_ENERGY_GROWTH,
        )));
    }
    Ok(())
}

/// An overlap over a12 in three decimals, or three digits in `e` notation far from 1.
fn ratio_text(ratio: f64) -> String {
    match (1e-3..1e3).contains(&ratio) {
        true => format!("{ratio:.3}"),
        false => format!("{ratio:.3e}"),
    }
}

/// Runs a chunk that failed again from its start, restored in `engine`, a step at a time
/// with the monitor after each, for the first step that fails: its error (which names the
/// step).
/// `None` where none does (the engines are deterministic, so the failure recurs unless it
/// was the chunk's energy check, now judged earlier with a smaller scale; the caller then
/// keeps the chunk's own error). `light`: as the run, without the ledger, observing only
/// where a check fails (each step's full observation reads a GPU's state back).
pub(super) fn first_failure(
    engine: &mut impl Simulation,
    steps: u64,
    (dt_rule, scene): (&str, &Scene),
    start: &ObservedEnergies,
    mut scale: f64,
    light: bool,
) -> Option<PowderError> {
    // (the failed chunk's overlap record, which a restore may keep)
    engine.take_peak_overlap();
    for _ in 0..steps {
        let stepped = engine.run_steps(1).and_then(|()| {
            if light {
                return monitor(engine, dt_rule, scene, (None, start), scale);
            }
            let obs = engine.observe_for_checks()?;
            scale = energy_scale(scale, &obs.energies, start);
            monitor(engine, dt_rule, scene, (Some(&obs), start), scale)
        });
        if let Err(e) = stepped {
            return Some(e);
        }
    }
    None
}

/// The run's energy scale so far, grown by `now`: the largest kinetic and stored energy,
/// gravitational change and work of the moving walls seen (the stored part and the walls'
/// work only with the ledger). The ledger's integration error grows with the energy that
/// flows through the contacts, which walls that drive a packing supply many times over its
/// kinetic energy; so the energy check loosens as the walls work.
pub(super) fn energy_scale(scale: f64, now: &ObservedEnergies, initial: &ObservedEnergies) -> f64 {
    let walls = now
        .wall_work
        .zip(initial.wall_work)
        .map_or(0.0, |(w, w0)| w - w0);
    scale
        .max(now.kinetic.abs())
        .max(now.elastic.unwrap_or(0.0).abs())
        .max((now.gravitational - initial.gravitational).abs())
        .max(walls.abs())
}
