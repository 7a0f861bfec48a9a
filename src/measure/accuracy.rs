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

/// Smallest accepted divisor: dt above tc/10 is refused by the time-step guard.
pub const MIN_DIVISOR: f64 = 10.0;

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
            if !(d.is_finite() && d >= MIN_DIVISOR) {
                return Err(ParamError::new(
                    "divisors",
                    format!("dt = tc/{d}: each divisor must be a finite number >= {MIN_DIVISOR} (a dt above tc/10 is refused by the time-step guard)"),
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
            if !(self.reference_divisor.is_finite() && self.reference_divisor > finest) {
                return Err(ParamError::new(
                    "reference-divisor",
                    format!(
                        "the reference (tc/{}) must be finer than every divisor (up to tc/{finest})",
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
        if (self.pair || self.jkr) && self.chi_points < 2 {
            return Err(ParamError::new(
                "chi-points",
                "the χ and velocity sweeps need at least 2 points",
            )
            .into());
        }
        Ok(())
    }
}

/// One (case, backend, dt) measurement.
#[derive(Clone, Debug, Serialize)]
pub struct AccuracyPoint {
    /// `pair` or `packing`.
    pub case: &'static str,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// dt = tc/divisor.
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

/// The pair case's set-up.
#[derive(Clone, Debug, Serialize)]
pub struct PairSetup {
    /// Loading stiffness, N/m.
    pub k1: f64,
    /// Limit stiffness, N/m.
    pub kp: f64,
    /// Tensile-branch stiffness, N/m.
    pub kc: f64,
    /// Plasticity depth.
    pub phi_f: f64,
    /// Radius of both spheres, m.
    pub radius: f64,
    /// kg/m³.
    pub density: f64,
    /// Contact time on kp, s.
    pub tc: f64,
    /// The sweep's χ = v/vp.
    pub chi: Vec<f64>,
    /// The impact speeds, m/s.
    pub velocities: Vec<f64>,
    /// The closed-form restitution at each.
    pub e_closed: Vec<f64>,
}

/// The JKR pair case's set-up: one sweep per pull-off rule.
#[derive(Clone, Debug, Serialize)]
pub struct JkrSetup {
    /// Young's modulus, Pa.
    pub youngs: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Surface energy per surface, J/m².
    pub surface_energy: f64,
    /// Radius of both spheres, m.
    pub radius: f64,
    /// kg/m³.
    pub density: f64,
    /// The contact time of the time-step rule at the fastest impact, s (dt = tc/D).
    pub tc: f64,
    /// The sweeps.
    pub rules: Vec<JkrSweep>,
}

/// One pull-off rule's sweep of the JKR pair case.
#[derive(Clone, Debug, Serialize)]
pub struct JkrSweep {
    /// The pull-off rule.
    pub pulloff: Pulloff,
    /// The sticking speed √(2W/m*), m/s.
    pub sticking_velocity: f64,
    /// The impact speeds (1.05 … 5 times the sticking speed, log-spaced), m/s.
    pub velocities: Vec<f64>,
    /// The closed-form restitution √(1 − W/(½m*v²)) at each.
    pub e_closed: Vec<f64>,
}

/// The JKR material of the pair case (the e(v) example of `docs/models.md`: sticking below 0.66 m/s).
const JKR_MATERIAL: (f64, f64, f64) = (1e9, 0.3, 0.05);
const JKR_RADIUS: f64 = 1e-6;
/// The JKR sweep's range of v/v_stick.
pub const JKR_RANGE: (f64, f64) = (1.05, 5.0);

fn jkr_spec(pulloff: Pulloff) -> CollideSpec {
    let (youngs, poisson, gamma) = JKR_MATERIAL;
    let p = JkrParams {
        pulloff,
        ..JkrParams::jkr(youngs, poisson, gamma)
    };
    CollideSpec::head_on(ContactModel::Jkr(p), JKR_RADIUS, PAIR_DENSITY, 1.0)
}

fn jkr_setup(points: usize) -> JkrSetup {
    let (lo, hi) = JKR_RANGE;
    let mut tc = f64::INFINITY;
    let rules = [Pulloff::Displacement, Pulloff::Force]
        .into_iter()
        .map(|pulloff| {
            let spec = jkr_spec(pulloff);
            let g = spec.geometry();
            let ContactModel::Jkr(p) = spec.model else {
                unreachable!("a JKR spec")
            };
            let r = g.r_eff();
            let w = analytic::jkr_loss(pulloff) * p.fc(r) * p.delta0(r);
            let v_stick = analytic::jkr_sticking_velocity(w, g.reduced_mass);
            let velocities: Vec<f64> = (0..points)
                .map(|k| v_stick * lo * (hi / lo).powf(k as f64 / (points - 1) as f64))
                .collect();
            let fastest = CollideSpec {
                velocity: v_stick * hi,
                ..spec.clone()
            };
            tc = tc.min(fastest.time_step().contact_time);
            JkrSweep {
                pulloff,
                sticking_velocity: v_stick,
                e_closed: velocities
                    .iter()
                    .map(|&v| analytic::jkr_restitution(w, g.reduced_mass, v).unwrap_or(f64::NAN))
                    .collect(),
                velocities,
            }
        })
        .collect();
    let (youngs, poisson, surface_energy) = JKR_MATERIAL;
    JkrSetup {
        youngs,
        poisson,
        surface_energy,
        radius: JKR_RADIUS,
        density: PAIR_DENSITY,
        tc,
        rules,
    }
}

/// One JKR sweep at dt = tc/`divisor`; `verlet` leaves the force jumps to plain velocity
/// Verlet (CPU).
fn jkr_point(
    setup: &JkrSetup,
    sweep: &JkrSweep,
    divisor: f64,
    backend: Backend,
    verlet: bool,
) -> Result<AccuracyPoint, PowderError> {
    let pulloff = sweep.pulloff;
    let dt = setup.tc / divisor;
    let spec = CollideSpec {
        dt: Some(dt),
        force: true,
        jump_impulses: verlet.then_some(false),
        ..jkr_spec(pulloff)
    };
    let (results, wall) = timed(|| collide::sweep_on(&spec, &sweep.velocities, backend))?;
    debug_assert_eq!(results.len(), sweep.e_closed.len());
    // a NaN (no closed form, a failed run) must show, not vanish in the max
    let error = results
        .iter()
        .zip(&sweep.e_closed)
        .map(|(r, e)| (r.e - e).abs())
        .fold(0.0, |worst: f64, x| {
            if x.is_nan() || worst.is_nan() {
                f64::NAN
            } else {
                worst.max(x)
            }
        });
    let case = match (pulloff, verlet) {
        (Pulloff::Force, false) => "jkr-force",
        (Pulloff::Force, true) => "jkr-force-verlet",
        (_, false) => "jkr-displacement",
        (_, true) => "jkr-displacement-verlet",
    };
    Ok(sweep_point(
        case, backend, divisor, dt, &results, wall, error,
    ))
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

/// The packing case's set-up and reference.
#[derive(Clone, Debug, Serialize)]
pub struct PackingSetup {
    /// N.
    pub particles: usize,
    /// Seed of the packing's jitter and velocities.
    pub seed: u64,
    /// Contact time on the stiffest branch, s.
    pub tc: f64,
    /// Physical time compared, s (`packing_time`·tc).
    pub time: f64,
    /// The reference's dt = tc/reference_divisor.
    pub reference_divisor: f64,
    /// s.
    pub reference_dt: f64,
    /// Steps of the reference run.
    pub reference_steps: u64,
    /// Its stepping time, s.
    pub reference_wall_seconds: f64,
    /// Its kinetic energy at `time`, J.
    pub reference_kinetic: f64,
    /// Particle–particle contacts per particle of the reference at `time`.
    pub reference_contacts_per_particle: f64,
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

/// The pair's hysteretic parameters: the paper's with kc = 10 N/m (β = 0.1 < β* = 1/3, so
/// no sticking at any χ), no viscosity (the closed forms exclude it).
pub fn pair_params() -> HystereticParams {
    HystereticParams {
        k1: 100.0,
        kp: 500.0,
        kc: 10.0,
        phi_f: 0.05,
        fa: 0.0,
        kca: 10.0,
        adhesion: AdhesionMode::default(),
        gamma0: 0.0,
        k2_rule: K2Rule::default(),
        luding: Default::default(),
    }
}

const PAIR_RADIUS: f64 = 1.1e-3;
const PAIR_DENSITY: f64 = 2000.0;

fn pair_setup(points: usize) -> (CollideSpec, PairSetup) {
    let p = pair_params();
    let spec = CollideSpec::head_on(ContactModel::Hysteretic(p), PAIR_RADIUS, PAIR_DENSITY, 1.0);
    let geom = spec.geometry();
    let (lo, hi) = CHI_RANGE;
    let chi: Vec<f64> = (0..points)
        .map(|k| lo * (hi / lo).powf(k as f64 / (points - 1) as f64))
        .collect();
    let velocities: Vec<f64> = chi
        .iter()
        .map(|&c| analytic::velocity_for_chi(&p, geom.a12, geom.reduced_mass, c))
        .collect();
    let e_closed = velocities
        .iter()
        .map(|&v| {
            collide::closed_form_e(&CollideSpec {
                velocity: v,
                ..spec.clone()
            })
            .unwrap_or(f64::NAN)
        })
        .collect();
    let tc = spec.time_step().contact_time;
    let setup = PairSetup {
        k1: p.k1,
        kp: p.kp,
        kc: p.kc,
        phi_f: p.phi_f,
        radius: PAIR_RADIUS,
        density: PAIR_DENSITY,
        tc,
        chi,
        velocities,
        e_closed,
    };
    (spec, setup)
}

fn pair_point(
    spec: &CollideSpec,
    setup: &PairSetup,
    divisor: f64,
    backend: Backend,
) -> Result<AccuracyPoint, PowderError> {
    let dt = setup.tc / divisor;
    let spec = CollideSpec {
        dt: Some(dt),
        force: true,
        ..spec.clone()
    };
    let (results, wall) = timed(|| collide::sweep_on(&spec, &setup.velocities, backend))?;
    let error = results
        .iter()
        .filter_map(|r| r.e_analytic.map(|ea| (r.e - ea).abs()))
        .fold(0.0, f64::max);
    Ok(sweep_point(
        "pair", backend, divisor, dt, &results, wall, error,
    ))
}

/// The packing scene with dt = `time`/`steps` exactly.
fn packing_scene(base: &Scene, time: f64, steps: u64) -> Scene {
    Scene {
        dt: DtSetting::Fixed(time / steps as f64),
        force_dt: true,
        ..base.clone()
    }
}

/// A run shorter than this is repeated (up to [`MAX_REPEATS`] times) and its mean wall time
/// reported, so that millisecond runs are not timer and scheduler noise, s.
pub const MIN_TIMING: f64 = 0.2;
/// Most repetitions of one short run.
pub const MAX_REPEATS: u32 = 50;

/// Runs `f` once, then again until [`MIN_TIMING`] has passed (at most [`MAX_REPEATS`]
/// times); the result of the first run and the mean wall time per run.
fn timed<T>(mut f: impl FnMut() -> Result<T, PowderError>) -> Result<(T, f64), PowderError> {
    let t0 = Instant::now();
    let first = f()?;
    let mut runs = 1;
    while t0.elapsed().as_secs_f64() < MIN_TIMING && runs < MAX_REPEATS {
        f()?;
        runs += 1;
    }
    Ok((first, t0.elapsed().as_secs_f64() / runs as f64))
}

/// Builds an engine with `make` and steps it with `step`; while less than [`MIN_TIMING`]
/// of stepping has passed, does it again with a fresh engine (at most [`MAX_REPEATS`]
/// times). Returns the first engine, the set-up time of the first and the mean stepping time.
fn repeat_stepping<E>(
    mut make: impl FnMut() -> Result<E, PowderError>,
    mut step: impl FnMut(&mut E) -> Result<(), PowderError>,
) -> Result<(E, f64, f64), PowderError> {
    let t0 = Instant::now();
    let mut first = make()?;
    let setup = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    step(&mut first)?;
    let mut stepping = t1.elapsed().as_secs_f64();
    let mut runs = 1;
    while stepping < MIN_TIMING && runs < MAX_REPEATS {
        let mut again = make()?;
        let t1 = Instant::now();
        step(&mut again)?;
        stepping += t1.elapsed().as_secs_f64();
        runs += 1;
    }
    Ok((first, setup, stepping / runs as f64))
}

/// Positions and kinetic energy after `steps` steps on `backend`, with the set-up and
/// stepping times (a short run repeated, see [`MIN_TIMING`]).
fn run_packing(
    scene: &Scene,
    steps: u64,
    backend: Backend,
) -> Result<(Vec<DVec3>, f64, f64, f64), PowderError> {
    match backend {
        Backend::Cpu => {
            let (e, setup, wall) =
                repeat_stepping(|| CpuEngine::new(scene), |e| e.run_steps(steps))?;
            Ok((e.positions().to_vec(), e.energies().kinetic, setup, wall))
        }
        Backend::Gpu => {
            let (e, setup, wall) = repeat_stepping(
                || GpuEngine::new(scene, GpuContext::new()?),
                |e| e.run_steps(steps),
            )?;
            let s = e.state()?;
            let ke = e.kinetic_energy(&s);
            Ok((s.positions, ke, setup, wall))
        }
    }
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
            reference_divisor: opts.reference_divisor,
            reference_dt: time / ref_steps as f64,
            reference_steps: ref_steps,
            reference_wall_seconds: ref_wall,
            reference_kinetic: ref_ke,
            reference_contacts_per_particle: bench::coordination(&base, &ref_pos, &radius),
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
                    divisor: d,
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

/// The work–precision diagram: error against wall time, log-log, one line per case and
/// backend (the packing's kinetic-energy error dashed).
pub fn work_precision_plot(report: &AccuracyReport) -> Plot {
    let mut series = Vec::new();
    let adapter = report.adapter.as_ref().map_or_else(
        || "GPU f32".to_string(),
        |a| format!("GPU f32, {}", a.name.split(" (").next().unwrap_or(&a.name)),
    );
    for (case, label) in [
        ("pair", "pair, max |e - e_closed| over chi"),
        (
            "jkr-displacement",
            "JKR displacement pull-off, max |e - e_closed|",
        ),
        (
            "jkr-displacement-verlet",
            "JKR displacement pull-off, jumps left to Verlet",
        ),
        ("jkr-force", "JKR force pull-off, max |e - e_closed|"),
        (
            "jkr-force-verlet",
            "JKR force pull-off, jumps left to Verlet",
        ),
        ("packing", "packing, RMS |x - x_ref|/r"),
    ] {
        for backend in ["cpu", "gpu"] {
            let pts: Vec<&AccuracyPoint> = report
                .points
                .iter()
                .filter(|p| p.case == case && p.backend == backend)
                .collect();
            if pts.is_empty() {
                continue;
            }
            let who = if backend == "cpu" {
                "CPU f64".to_string()
            } else {
                adapter.clone()
            };
            series.push(Series {
                label: format!("{label} ({who})"),
                points: pts.iter().map(|p| (p.wall_seconds, p.error)).collect(),
                style: Style::Line,
            });
            if case == "packing" {
                series.push(Series {
                    label: format!("packing, |dE_kin|/E_kin ({who})"),
                    points: pts
                        .iter()
                        .filter_map(|p| p.kinetic_error.map(|k| (p.wall_seconds, k)))
                        .collect(),
                    style: Style::DashedLine,
                });
            }
        }
    }
    let divisors: Vec<String> = {
        let mut d: Vec<f64> = report.points.iter().map(|p| p.divisor).collect();
        d.sort_by(f64::total_cmp);
        d.dedup();
        d.iter().map(|x| format!("{x}")).collect()
    };
    Plot {
        title: format!("Work-precision, dt = tc/({})", divisors.join(", ")),
        x_label: "wall time (s)".into(),
        y_label: "error".into(),
        log_x: true,
        log_y: true,
        series,
        // a band below the data for the legend
        y_range: lowest_error(report).map(|lo| (lo * 3e-3, highest_error(report) * 3.0)),
        legend: Legend::LowerRight,
    }
}

fn errors(report: &AccuracyReport) -> impl Iterator<Item = f64> + '_ {
    report
        .points
        .iter()
        .flat_map(|p| [Some(p.error), p.kinetic_error])
        .flatten()
        .filter(|e| e.is_finite() && *e > 0.0)
}

fn lowest_error(report: &AccuracyReport) -> Option<f64> {
    errors(report).reduce(f64::min)
}

fn highest_error(report: &AccuracyReport) -> f64 {
    errors(report).fold(0.0, f64::max)
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
