//! `powder accuracy`: error against run time (a work–precision diagram) over the time step,
//! on both backends, for two cases:
//!
//! * **pair** — the head-on hysteretic collision (paper parameters with β = 0.1, no
//!   viscosity, so no sticking) over a log-spaced χ sweep through
//!   [`crate::measure::collide::sweep_on`]; the error is max |e − e_closed| over the sweep against the
//!   closed forms of [`crate::model::analytic`], the run time that of the whole sweep
//!   (each collision builds its engine: on the GPU that includes the pipelines);
//! * **jkr** — head-on JKR collisions (both pull-off rules, equal spheres) from 1.05 to 5
//!   times the sticking speed; the error is max |e − e_closed| over the sweep; on the CPU
//!   also with the force jumps left to plain velocity Verlet (`-verlet` cases), which shows
//!   what placing them inside the step ([`crate::cpu::jump`]) gains;
//! * **packing** — a small cohesive packing ([`crate::measure::bench::packing`], hysteretic with
//!   kc = 100 N/m and viscous damping, under gravity in a box) against a CPU f64 reference
//!   at a much finer time step; after a fixed physical time T = K·tc the error is the RMS
//!   position deviation over the radius, and the relative kinetic-energy deviation is
//!   reported beside it; the run time is that of the stepping (the engine's set-up is
//!   reported apart). The packing is chaotic: over long times any difference (f32 against
//!   f64, or a different dt) grows exponentially, so T must stay short enough that the
//!   error still falls with dt.
//!
//! Time steps are given as divisors D of the contact time tc on the stiffest branch
//! (dt = tc/D; the default time step is tc/50).

use crate::cpu::CpuEngine;
use crate::error::{ParamError, PowderError};
use crate::gpu::{GpuContext, GpuEngine};
use crate::measure::bench::{self, Adapter, Provenance};
use crate::measure::collide::{self, Backend, CollideSpec};
use crate::model::jkr::Pulloff;
use crate::model::{analytic, AdhesionMode, ContactModel, HystereticParams, JkrParams, K2Rule};
use crate::output::plot::{Legend, Plot, Series, Style};
use crate::scene::{DtSetting, Scene};
use glam::DVec3;
use serde::Serialize;
use std::time::Instant;

mod jkr;
mod packing;
mod pair;
mod plot;
mod timing;

use jkr::{jkr_point, jkr_setup};
pub use jkr::{JkrSetup, JkrSweep, JKR_RANGE};
pub use packing::PackingSetup;
use packing::{packing_scene, run_packing};
pub use pair::{pair_params, PairSetup};
use pair::{pair_point, pair_setup, PAIR_DENSITY};
pub use plot::work_precision_plot;
use timing::{repeat_stepping, timed};
pub use timing::{MAX_REPEATS, MIN_TIMING};

/// Smallest accepted divisor: dt above tc/10 is refused by the time-step guard.
pub const MIN_DIVISOR: f64 = 10.0;

/// The finest time step measured, dt = tc/MAX_DIVISOR: beyond it a run takes more steps a
/// contact than its f64 positions resolve the motion of, and hours where tc/800 takes
/// seconds.
pub const MAX_DIVISOR: f64 = 1e6;

/// What to measure.
#[derive(Clone, Debug)]
pub struct AccuracyOptions {
    /// dt = tc/D for each D (each >= [`MIN_DIVISOR`]).
    pub divisors: Vec<f64>,
    /// The backends to run each on.
    pub backends: Vec<Backend>,
    /// Run the pair case.
    pub pair: bool,
    /// Run the JKR pair case.
    pub jkr: bool,
    /// Run the packing case.
    pub packing: bool,
    /// Packing: the CPU reference's divisor (above every divisor).
    pub reference_divisor: f64,
    /// Packing: particle count.
    pub particles: usize,
    /// Packing: physical time compared, in units of tc.
    pub packing_time: u64,
    /// Pair: points of the χ sweep over [`CHI_RANGE`].
    pub chi_points: usize,
    /// Packing: seed of the jitter and velocities.
    pub seed: u64,
}

/// χ range of the pair sweep (log-spaced).
pub const CHI_RANGE: (f64, f64) = (0.1, 5.0);

impl Default for AccuracyOptions {
    fn default() -> Self {
        Self {
            divisors: vec![10.0, 20.0, 50.0, 100.0, 200.0, 400.0],
            backends: vec![Backend::Cpu, Backend::Gpu],
            pair: true,
            jkr: true,
            packing: true,
            reference_divisor: 800.0,
            particles: 216,
            packing_time: 20,
            chi_points: 8,
            seed: 1,
        }
    }
}

impl AccuracyOptions {
    /// Checks the options, naming the offending one.
    pub fn validate(&self) -> Result<(), PowderError> {
        if self.divisors.is_empty() {
            return Err(ParamError::new("divisors", "give at least one divisor").into());
        }
        for &d in &self.divisors {
            if !(d.is_finite() && (MIN_DIVISOR..=MAX_DIVISOR).contains(&d)) {
                return Err(ParamError::new(
                    "divisors",
                    format!("dt = tc/{d}: each divisor must be a number from {MIN_DIVISOR} (a dt above tc/10 is refused by the time-step guard) to {MAX_DIVISOR:e}"),
                )
                .into());
            }
        }
        if !self.pair && !self.jkr && !self.packing {
            return Err(ParamError::new("case", "nothing to measure").into());
        }
        if self.backends.is_empty() {
            return Err(ParamError::new("backend", "nothing to measure").into());
        }
        if self.packing {
            let finest = self.divisors.iter().copied().fold(0.0, f64::max);
            if !(self.reference_divisor > finest && self.reference_divisor <= MAX_DIVISOR) {
                return Err(ParamError::new(
                    "reference-divisor",
                    format!(
                        "the reference (tc/{}) must be finer than every divisor (up to tc/{finest}) and at most tc/{MAX_DIVISOR:e}",
                        self.reference_divisor
                    ),
                )
                .into());
            }
            if !(2..=100_000).contains(&self.particles) {
                return Err(ParamError::new(
                    "particles",
                    format!(
                        "the packing needs 2 ... 100000 particles, got {}",
                        self.particles
                    ),
                )
                .into());
            }
            if self.packing_time == 0 {
                return Err(ParamError::new(
                    "packing-time",
                    "the physical time must be at least 1 tc",
                )
                .into());
            }
        }
        if (self.pair || self.jkr) && !(2..=MAX_CHI_POINTS).contains(&self.chi_points) {
            return Err(ParamError::new(
                "chi-points",
                format!(
                    "the χ and velocity sweeps take 2 to {MAX_CHI_POINTS} points (a collision each on every backend and time step), got {}",
                    self.chi_points
                ),
            )
            .into());
        }
        Ok(())
    }
}

/// The most points a χ or velocity sweep takes (each a collision per backend and time step).
pub const MAX_CHI_POINTS: usize = 10_000;

/// One (case, backend, dt) measurement.
#[derive(Clone, Debug, Serialize)]
pub struct AccuracyPoint {
    /// `pair`, `jkr-displacement`, `jkr-force` (and their `-verlet` forms) or `packing`.
    pub case: &'static str,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// dt = tc/divisor (packing: the divisor its whole number of steps gives, which the
    /// one asked for rounds to).
    pub divisor: f64,
    /// The time step, s.
    pub dt: f64,
    /// Steps of the run (pair: summed over the sweep).
    pub steps: u64,
    /// Run time, s (pair: the whole sweep; packing: the stepping); runs shorter than
    /// [`MIN_TIMING`] are repeated and the mean is reported.
    pub wall_seconds: f64,
    /// Pair: max |e − e_closed| over the sweep; packing: RMS |x − x_ref|/r.
    pub error: f64,
    /// Packing: largest |x − x_ref|/r.
    pub max_position_error: Option<f64>,
    /// Packing: |E_kin − E_kin,ref| / E_kin,ref.
    pub kinetic_error: Option<f64>,
    /// Packing: engine set-up time, s.
    pub setup_seconds: Option<f64>,
}

/// The point of a collision sweep (pair or JKR): steps summed over the sweep.
fn sweep_point(
    case: &'static str,
    backend: Backend,
    divisor: f64,
    dt: f64,
    results: &[collide::CollideResult],
    wall_seconds: f64,
    error: f64,
) -> AccuracyPoint {
    AccuracyPoint {
        case,
        backend: bench::backend_name(backend),
        divisor,
        dt,
        steps: results.iter().map(|r| r.steps).sum(),
        wall_seconds,
        error,
        max_position_error: None,
        kinetic_error: None,
        setup_seconds: None,
    }
}

/// The whole measurement, as `--json` writes it.
#[derive(Clone, Debug, Serialize)]
pub struct AccuracyReport {
    /// Version, commit, date and machine (flattened into the top level of the JSON).
    #[serde(flatten)]
    pub provenance: Provenance,
    /// The GPU adapter (null without the GPU backend).
    pub adapter: Option<Adapter>,
    /// The pair case's set-up, when it ran.
    pub pair: Option<PairSetup>,
    /// The JKR pair case's set-up, when it ran.
    pub jkr: Option<JkrSetup>,
    /// The packing case's set-up and reference, when it ran.
    pub packing: Option<PackingSetup>,
    /// Every (case, backend, dt) measured.
    pub points: Vec<AccuracyPoint>,
    /// What was left out and why (e.g. no GPU adapter).
    pub notes: Vec<String>,
}

/// Runs the work–precision measurement, calling `progress` after every point.
pub fn accuracy(
    opts: &AccuracyOptions,
    mut progress: impl FnMut(&AccuracyPoint),
) -> Result<AccuracyReport, PowderError> {
    opts.validate()?;
    let provenance = Provenance::now();
    let mut notes = Vec::new();
    let mut backends = opts.backends.clone();
    let mut adapter = None;
    if backends.contains(&Backend::Gpu) {
        match GpuContext::new() {
            Ok(ctx) => adapter = Some(Adapter::of(&ctx)),
            Err(e) if backends.len() == 1 => return Err(e),
            Err(e) => {
                notes.push(format!("GPU backend left out: {e}"));
                backends.retain(|&b| b != Backend::Gpu);
            }
        }
    }
    let mut points = Vec::new();
    let mut pair = None;
    if opts.pair {
        let (spec, setup) = pair_setup(opts.chi_points);
        for &backend in &backends {
            for &d in &opts.divisors {
                let p = pair_point(&spec, &setup, d, backend)?;
                progress(&p);
                points.push(p);
            }
        }
        pair = Some(setup);
    }
    let mut jkr = None;
    if opts.jkr {
        let setup = jkr_setup(opts.chi_points);
        for sweep in &setup.rules {
            for &backend in &backends {
                for verlet in [false, true] {
                    if verlet && backend == Backend::Gpu {
                        continue;
                    }
                    for &d in &opts.divisors {
                        let p = jkr_point(&setup, sweep, d, backend, verlet)?;
                        progress(&p);
                        points.push(p);
                    }
                }
            }
        }
        jkr = Some(setup);
    }
    let mut packing = None;
    if opts.packing {
        let base = bench::packing(bench::Case::Hysteretic, opts.particles, 1.0, opts.seed)?;
        let base = Scene {
            name: format!("accuracy_packing_{}", opts.particles),
            ..base
        };
        let tc = crate::setup::Resolved::new(&base)?.time_step.contact_time;
        let time = opts.packing_time as f64 * tc;
        let steps_for = |d: f64| ((opts.packing_time as f64 * d).round() as u64).max(1);
        let ref_steps = steps_for(opts.reference_divisor);
        let ref_scene = packing_scene(&base, time, ref_steps);
        let (ref_pos, ref_ke, _, ref_wall) = run_packing(&ref_scene, ref_steps, Backend::Cpu)?;
        let radius: Vec<f64> = base.particles.iter().map(|p| p.radius).collect();
        packing = Some(PackingSetup {
            particles: opts.particles,
            seed: opts.seed,
            tc,
            time,
            reference_divisor: ref_steps as f64 / opts.packing_time as f64,
            reference_dt: time / ref_steps as f64,
            reference_steps: ref_steps,
            reference_wall_seconds: ref_wall,
            reference_kinetic: ref_ke,
            reference_contacts_per_particle: bench::coordination(&base, &ref_pos, &radius)?,
        });
        for &backend in &backends {
            for &d in &opts.divisors {
                let steps = steps_for(d);
                let scene = packing_scene(&base, time, steps);
                let (pos, ke, setup, wall) = run_packing(&scene, steps, backend)?;
                let dev: Vec<f64> = pos
                    .iter()
                    .zip(&ref_pos)
                    .zip(&radius)
                    .map(|((a, b), r)| a.distance(*b) / r)
                    .collect();
                let rms = (dev.iter().map(|x| x * x).sum::<f64>() / dev.len() as f64).sqrt();
                let p = AccuracyPoint {
                    case: "packing",
                    backend: bench::backend_name(backend),
                    // (the steps are whole: dt = T/steps, tc/dt = steps/packing_time)
                    divisor: steps as f64 / opts.packing_time as f64,
                    dt: time / steps as f64,
                    steps,
                    wall_seconds: wall,
                    error: rms,
                    max_position_error: Some(dev.iter().copied().fold(0.0, f64::max)),
                    kinetic_error: Some((ke - ref_ke).abs() / ref_ke.abs().max(1e-300)),
                    setup_seconds: Some(setup),
                };
                progress(&p);
                points.push(p);
            }
        }
    }
    Ok(AccuracyReport {
        provenance,
        adapter,
        pair,
        jkr,
        packing,
        points,
        notes,
    })
}

/// Parses `--divisors`: comma-separated numbers.
pub fn parse_divisors(text: &str) -> Result<Vec<f64>, PowderError> {
    let mut out = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let d: f64 = item.parse().map_err(|_| {
            PowderError::from(ParamError::new(
                "divisors",
                format!("`{item}` is not a number; expected e.g. 10,20,50,100"),
            ))
        })?;
        out.push(d);
    }
    if out.is_empty() {
        return Err(ParamError::new("divisors", "give at least one divisor, e.g. 10,20,50").into());
    }
    // (coarse to fine, each once: the table's, the JSON's and the plot's order)
    out.sort_by(f64::total_cmp);
    out.dedup();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_sweep_has_no_sticking_and_closed_forms_everywhere() {
        let (_, s) = pair_setup(6);
        assert_eq!(s.chi.len(), 6);
        assert!((s.chi[0] - CHI_RANGE.0).abs() < 1e-12);
        assert!((s.chi[5] - CHI_RANGE.1).abs() < 1e-9);
        for e in &s.e_closed {
            assert!(*e > 0.0 && *e < 1.0, "{e}");
        }
        assert!(s.velocities.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn bad_options_name_the_option() {
        let cases = [
            (
                AccuracyOptions {
                    divisors: vec![5.0],
                    ..Default::default()
                },
                "divisors",
            ),
            (
                AccuracyOptions {
                    reference_divisor: 400.0,
                    ..Default::default()
                },
                "reference-divisor",
            ),
            (
                AccuracyOptions {
                    particles: 1,
                    ..Default::default()
                },
                "particles",
            ),
            (
                AccuracyOptions {
                    chi_points: 1,
                    ..Default::default()
                },
                "chi-points",
            ),
        ];
        for (o, name) in cases {
            let e = o.validate().unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
        assert!(parse_divisors("10, 20").unwrap() == vec![10.0, 20.0]);
        assert!(parse_divisors("x").is_err());
    }
}
