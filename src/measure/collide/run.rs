//! Running a collision on either engine: the pair read back each step, the stop and stick
//! rules, the energy ledger and the trace.

use super::*;
use crate::cpu::CpuEngine;
use crate::gpu::{GpuContext, GpuEngine};

/// The pair as a backend reports it after a step.
pub(super) struct PairView {
    pos: [DVec3; 2],
    vel: [DVec3; 2],
    omega: [DVec3; 2],
    /// Whether the contact persists (JKR necks at negative overlap); `None` when the
    /// backend cannot say, then δ > 0 decides.
    in_contact: Option<bool>,
}

/// What the collision loop needs of an engine.
pub(super) trait CollisionRun {
    fn step(&mut self) -> Result<(), PowderError>;
    /// `n` steps with nothing read between them (the GPU batches them).
    fn advance(&mut self, n: u64) -> Result<(), PowderError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }
    fn view(&self) -> Result<PairView, PowderError>;
    fn time(&self) -> f64;
    fn steps(&self) -> u64;
    /// (kinetic, total) energy; total is `None` where the backend keeps no ledger.
    fn energy(&self, view: &PairView) -> (f64, Option<f64>, Option<f64>);
    fn rotates(&self) -> bool;
    /// Force on sphere 1 and the pair's contact history (CPU only, for the trace).
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)>;
}

pub(super) struct CpuRun {
    engine: CpuEngine,
    wall: bool,
}

impl CollisionRun for CpuRun {
    fn step(&mut self) -> Result<(), PowderError> {
        self.engine.step()
    }
    fn view(&self) -> Result<PairView, PowderError> {
        let e = &self.engine;
        let two = |s: &[DVec3]| {
            [
                s.first().copied().unwrap_or_default(),
                s.get(1).copied().unwrap_or_default(),
            ]
        };
        let history = if self.wall {
            e.wall_contact_history(0, 0)
        } else {
            e.contact_history(0, 1)
        };
        Ok(PairView {
            pos: two(e.positions()),
            vel: two(e.velocities()),
            omega: two(e.angular_velocities()),
            in_contact: Some(history.is_some_and(|h| h.touched)),
        })
    }
    fn time(&self) -> f64 {
        self.engine.time
    }
    fn steps(&self) -> u64 {
        self.engine.steps
    }
    fn energy(&self, _: &PairView) -> (f64, Option<f64>, Option<f64>) {
        let e = self.engine.energies();
        (e.kinetic, Some(e.total()), Some(e.dissipated))
    }
    fn rotates(&self) -> bool {
        self.engine.rotates()
    }
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)> {
        let history = if self.wall {
            self.engine.wall_contact_history(0, 0)
        } else {
            self.engine.contact_history(0, 1)
        };
        Some((self.engine.forces()[0], history))
    }
}

pub(super) struct GpuRun {
    engine: GpuEngine,
    wall: bool,
}

impl CollisionRun for GpuRun {
    fn step(&mut self) -> Result<(), PowderError> {
        self.engine.run_steps(1)
    }
    fn advance(&mut self, n: u64) -> Result<(), PowderError> {
        self.engine.run_steps(n)
    }
    fn view(&self) -> Result<PairView, PowderError> {
        let s = self.engine.state()?;
        let two = |v: &[DVec3]| {
            [
                v.first().copied().unwrap_or_default(),
                v.get(1).copied().unwrap_or_default(),
            ]
        };
        // the contact's own flag: a JKR neck persists at negative overlap
        let touched = if self.wall {
            self.engine.wall_contact_history(0, 0)?.touched
        } else {
            self.engine
                .contact_history(0, 1)?
                .is_some_and(|h| h.touched)
        };
        Ok(PairView {
            pos: two(&s.positions),
            vel: two(&s.velocities),
            omega: two(&s.angular_velocities),
            in_contact: Some(touched),
        })
    }
    fn time(&self) -> f64 {
        self.engine.time
    }
    fn steps(&self) -> u64 {
        self.engine.steps
    }
    fn energy(&self, view: &PairView) -> (f64, Option<f64>, Option<f64>) {
        let n = self.engine.len();
        let state = crate::gpu::GpuState {
            positions: view.pos[..n].to_vec(),
            velocities: view.vel[..n].to_vec(),
            angular_velocities: if self.engine.rotates() {
                view.omega[..n].to_vec()
            } else {
                Vec::new()
            },
        };
        match self.engine.energies(&state) {
            Ok(e) => (e.kinetic, Some(e.total()), Some(e.dissipated)),
            // a run without the ledger: kinetic energy only
            Err(_) => (self.engine.kinetic_energy(&state), None, None),
        }
    }
    fn rotates(&self) -> bool {
        self.engine.rotates()
    }
    fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)> {
        let force = self.engine.contact_forces().ok()?[0];
        let history = if self.wall {
            Some(self.engine.wall_contact_history(0, 0).ok()?)
        } else {
            self.engine.contact_history(0, 1).ok()?
        };
        Some((force, history))
    }
}

impl CollideSpec {
    /// Relative motion of the colliding pair: overlap, normal approach speed, unit normal
    /// (from the partner to sphere 1) and the tangential contact-point velocity.
    fn pair_state(&self, p: &PairView, wall_x: f64) -> (f64, f64, DVec3, DVec3) {
        let r1 = self.radius1;
        if self.wall {
            // the plane x = x_w faces −x; x_w = r1 + gap from the scene
            let n = DVec3::new(-1.0, 0.0, 0.0);
            let v = p.vel[0];
            let vc = v - r1 * p.omega[0].cross(n);
            let delta = r1 - (wall_x - p.pos[0].x);
            (delta, -v.dot(n), n, vc - n * vc.dot(n))
        } else {
            let d = p.pos[0] - p.pos[1];
            let dist = d.length();
            let n = d / dist;
            let v = p.vel[0] - p.vel[1];
            let vc = v - r1 * p.omega[0].cross(n) - self.radius2 * p.omega[1].cross(n);
            (r1 + self.radius2 - dist, -v.dot(n), n, vc - n * vc.dot(n))
        }
    }
}

/// Steps that close a gap of `gap` m at `vn` m/s (at least 1; saturating).
fn approach_steps(gap: f64, vn: f64, dt: f64) -> u64 {
    ((gap.max(0.0) / (vn * dt)).ceil() as u64).max(1)
}

/// Steps after which a pair that has not touched is an error: twice the closing steps and
/// 100 more (rounding, an f32 engine), at most [`MAX_STEPS`].
fn approach_limit(gap: f64, vn: f64, dt: f64) -> u64 {
    approach_steps(gap, vn, dt)
        .saturating_mul(2)
        .saturating_add(100)
        .min(MAX_STEPS)
}

/// Consecutive steps an approach below [`REST_SPEED`] must decay as a creep to count as
/// come to rest.
const CREEP_STEPS: u32 = 10;

/// Consecutive steps a pair in contact must move slower than [`REST_SPEED`] of the impact
/// speed to count as at rest (a sub-linear dashpot stops it in finite time, not as a
/// creep). A turn crosses that band within a step or a few (a collision of 5·10⁷ steps
/// in about 60).
const REST_STEPS: u32 = 1000;

/// The settle time in steps of `dt` (at least 4: its last quarter is one step or more).
pub(super) fn settle_steps(spec: &CollideSpec, dt: f64) -> u64 {
    ((spec.settle / dt).ceil() as u64).max(4)
}

pub(super) fn run_collision(
    spec: &CollideSpec,
    mut run: impl CollisionRun,
    wall_x: f64,
    dt: f64,
    backend: &'static str,
    adapter: Option<String>,
    mut trace: Option<&mut Vec<TraceRow>>,
) -> Result<CollideResult, PowderError> {
    let geom = spec.geometry();
    let reach = spec.model.reach(geom.r_eff());
    let vn0 = spec.normal_speed();
    let view0 = run.view()?;
    let (ke0, total0, _) = run.energy(&view0);
    let mut touched = false;
    let mut receding = false;
    let mut fastest_receding: f64 = 0.0;
    let (mut vn_before, mut creeping, mut last_to_stop) = (vn0, 0, None);
    let mut resting = 0;
    let mut first_contact = None;
    let mut last_contact = 0.0;
    let mut delta_max: f64 = 0.0;
    let mut delta_c = None;
    let mut vt_in = None;
    let mut e = 0.0;
    let mut vt_out = DVec3::ZERO;
    let (delta0, _, _, mut vt_before) = spec.pair_state(&view0, wall_x);
    // (placed outside the interaction range: a range of metres or more, from a huge fa
    // against kc_a, leaves a gap no collision closes)
    let closing = approach_steps(-delta0, vn0, dt);
    if !delta0.is_finite() || closing >= MAX_STEPS {
        return Err(PowderError::Run(format!(
            "the spheres start {:e} m apart (outside the interaction range, {reach:e} m), which at {vn0:e} m/s takes {closing} steps of {dt:e} s, over the {MAX_STEPS} a collision may take: shorten the range (a non-contact adhesion range is fa/kc_a: lower --fa or raise --kca) or raise --velocity",
            -delta0
        )));
    }
    let approach = approach_limit(-delta0, vn0, dt);
    let mut last;
    loop {
        run.step()?;
        let view = run.view()?;
        let (delta, vn, n, vt) = spec.pair_state(&view, wall_x);
        let unmet = !touched && delta <= 0.0 && run.steps() >= approach;
        if unmet && delta < delta0 {
            // (a grazing impact: the pair passed by, the gap grew)
            return Err(PowderError::Run(format!(
                "the spheres at v = {} m/s and {}° passed each other without touching (the gap grew from {:e} to {:e} m after {} steps): raise --impact-angle",
                spec.velocity,
                spec.impact_angle,
                -delta0,
                -delta,
                run.steps()
            )));
        }
        if unmet || run.steps() >= MAX_STEPS {
            // (no force outside contact pushes the pair apart: it closes at vn0 or faster)
            let what = if touched {
                format!("was not decided after {} steps", run.steps())
            } else {
                format!(
                    "had not touched after {} steps, where closing the gap of {:e} m at {vn0:e} m/s takes {}",
                    run.steps(),
                    -delta0,
                    approach_steps(-delta0, vn0, dt)
                )
            };
            // (a pair that touched and is still in contact creeps: too strongly damped for
            // the steps, or slowly pulled apart against its adhesion)
            let creeps = touched && (delta > 0.0 || view.in_contact.unwrap_or(false));
            let why = if creeps {
                format!(
                    "the pair is still in contact, {} at {:e} m/s ({:.1e} of the impact speed): a creep slower than the steps resolve (a contact damped so strongly that it relaxes over more steps than the stable step allows, its step bound by that damping); lower the dissipation",
                    if vn < 0.0 { "receding" } else { "approaching" },
                    vn.abs(),
                    vn.abs() / vn0
                )
            } else {
                "the pair neither separated nor turned back; try a larger --dt or --velocity, and report it if the other backend decides it".to_string()
            };
            return Err(PowderError::Run(format!(
                "the collision at v = {} m/s {what} (t = {:e} s, {} backend; overlap {delta:e} m, approach speed {vn:e} m/s, contact flag {:?}): {why}",
                spec.velocity,
                run.time(),
                backend,
                view.in_contact
            )));
        }
        if let Some(rows) = trace.as_deref_mut() {
            if let Some((f, history)) = run.trace_sample() {
                rows.push(trace_row(
                    spec,
                    &geom,
                    run.time(),
                    delta,
                    vn,
                    f.dot(n),
                    history,
                ));
            }
        }
        let neck = view.in_contact.unwrap_or(delta > 0.0);
        let contact = delta > 0.0 || (touched && neck);
        if contact {
            if !touched {
                vt_in = Some(vt_before);
            }
            touched = true;
            first_contact.get_or_insert(run.time() - dt);
            last_contact = run.time();
            delta_max = delta_max.max(delta);
        }
        vt_before = vt;
        last = view;
        if !touched {
            continue;
        }
        if vn < 0.0 {
            receding = true;
            fastest_receding = fastest_receding.max(-vn);
        }
        let turned = receding && vn > 0.0;
        let crept = receding && -vn < REST_SPEED * vn0.min(fastest_receding) && contact;
        // an overdamped approach that creeps into its rest without turning back: slower
        // than REST_SPEED of the impact, and decaying as a creep does (its steps to a stop
        // at the current deceleration, vn/Δ, hold; at a turn they fall by one a step)
        let slowing = vn_before - vn;
        if !receding && contact && vn > 0.0 && vn < REST_SPEED * vn0 && slowing > 0.0 {
            let to_stop = vn / slowing;
            creeping = match last_to_stop {
                Some(last) if to_stop > last - 0.5 => creeping + 1,
                _ => 0,
            };
            last_to_stop = Some(to_stop);
        } else {
            (creeping, last_to_stop) = (0, None);
        }
        vn_before = vn;
        let crept_in = creeping >= CREEP_STEPS;
        resting = match contact && vn.abs() < REST_SPEED * vn0 {
            true => resting + 1,
            false => 0,
        };
        let at_rest = resting >= REST_STEPS;
        if (turned || crept || crept_in || at_rest) && delta > -reach {
            delta_c = Some(delta);
            break;
        }
        // (a pair whose last step in range turned it back leaves still approaching: it
        // comes back, and the turn above finds it stuck)
        if receding && vn < 0.0 && delta <= -reach && !neck {
            e = -vn / vn0;
            vt_out = vt;
            break;
        }
    }
    let stuck = delta_c.is_some();
    let mut outcome = if stuck { "stuck" } else { "rebound" };
    let mut settled_speed = None;
    if stuck && spec.settle > 0.0 {
        // (in two runs of steps: to three quarters of the settle time, and the rest)
        let total = settle_steps(spec, dt);
        let first = total - total / 4;
        run.advance(first)?;
        let quarter = run.view()?.pos[0];
        let quarter_time = run.time();
        run.advance(total - first)?;
        last = run.view()?;
        let (delta, ..) = spec.pair_state(&last, wall_x);
        // along the wall only (the plane faces −x): a normal vibration is no roll
        let moved = (last.pos[0] - quarter).y.hypot((last.pos[0] - quarter).z);
        outcome = if !(delta > 0.0 || last.in_contact.unwrap_or(false)) {
            "detached"
        } else if moved > ROLLING_TRAVEL * spec.radius1 {
            "rolling"
        } else {
            "resting"
        };
        settled_speed = Some(moved / (run.time() - quarter_time));
    }
    let (ke1, total1, dissipated) = run.energy(&last);
    let rotates = run.rotates();
    let mut result = CollideResult {
        model: spec.model.law_name(),
        velocity: spec.velocity,
        e,
        stuck,
        outcome,
        settled_speed,
        e_analytic: None,
        stuck_analytic: None,
        e_tangential: (rotates && !stuck && !spec.is_head_on())
            .then(|| {
                vt_in
                    .filter(|v| v.length() > 0.0)
                    .map(|v| vt_out.dot(v) / v.length_squared())
            })
            .flatten(),
        e_tangential_analytic: None,
        omega_final: rotates.then(|| last.omega[0].length()),
        delta_max,
        delta_max_analytic: None,
        chi: None,
        v_p: None,
        delta_c,
        delta_c_analytic: None,
        contact_duration: (!stuck).then(|| last_contact - first_contact.unwrap_or(0.0)),
        contact_duration_analytic: None,
        jkr: None,
        tabor: None,
        v_yield: None,
        e_tn: None,
        e_pl: None,
        dt,
        steps: run.steps(),
        backend,
        adapter,
        energy: CollisionEnergy {
            initial_kinetic: ke0,
            final_kinetic: ke1,
            dissipated,
            balance_error: total0
                .zip(total1)
                .map(|(a, b)| (b - a).abs() / ke0.max(dissipated.map_or(0.0, f64::abs))),
        },
    };
    predict(spec, &geom, &mut result);
    Ok(result)
}

pub(super) fn trace_row(
    spec: &CollideSpec,
    geom: &PairGeometry,
    t: f64,
    delta: f64,
    delta_dot: f64,
    force: f64,
    history: Option<crate::model::ContactHistory>,
) -> TraceRow {
    let mut row = TraceRow {
        t,
        delta,
        delta_dot,
        force,
        ..Default::default()
    };
    if let ContactModel::Jkr(p) = &spec.model {
        let touched = history.is_some_and(|h| h.touched);
        if touched || (p.gamma() == 0.0 && delta > 0.0) {
            let r = geom.r_eff();
            row.a_jkr = p.contact_radius(delta, r);
            row.a = match history {
                Some(h) if h.contact_radius > 0.0 => h.contact_radius,
                _ => row.a_jkr,
            };
        }
    }
    row
}

/// Runs one collision on `backend`, each step's row into `trace` where one is given.
pub(super) fn collide_with(
    spec: &CollideSpec,
    backend: Backend,
    trace: Option<&mut Vec<TraceRow>>,
) -> Result<CollideResult, PowderError> {
    spec.validate()?;
    let (m1, m2) = spec.masses();
    if !(m1.is_finite() && m1 > 0.0 && m2.is_finite() && m2 > 0.0) {
        return Err(PowderError::Scene(format!(
            "the spheres' masses come out as {m1:e} and {m2:e} kg: choose --radius and --density whose mass 4/3·π·r³·ρ is a finite number above 0"
        )));
    }
    // (which rule set dt, for the messages below)
    let mut rule = "--dt".to_string();
    let dt = match spec.dt {
        Some(dt) => dt,
        None => {
            let ts = spec.time_step();
            rule = format!("the automatic dt: {}", ts.reason);
            if !(ts.default.is_finite() && ts.default > 0.0) {
                return Err(PowderError::Scene(format!(
                    "the time step comes out as {:e} s ({}): the contact's parameters, masses or --velocity are beyond what a time step can resolve",
                    ts.default, ts.reason
                )));
            }
            ts.default
        }
    };
    if let crate::model::ContactModel::Jkr(p) = &spec.model {
        let r_eff = spec.geometry().r_eff();
        p.check_adhesion_scale(r_eff).map_err(PowderError::Scene)?;
    }
    // (with the smaller sphere's centre past the other's surface, or past the wall, the
    // spheres pass through each other: no contact law holds, and e comes out above 1)
    let reach = if spec.wall {
        spec.radius1
    } else {
        spec.radius1.min(spec.radius2)
    };
    if spec.normal_speed() * dt > reach {
        return Err(PowderError::Scene(format!(
            "at v = {} m/s the {} by {:e} m a step of {dt:e} s, more than the smaller radius {reach:e} m: they can pass through each other between two steps; lower --velocity or --dt",
            spec.velocity,
            if spec.wall {
                "sphere approaches the wall"
            } else {
                "spheres approach"
            },
            spec.normal_speed() * dt
        )));
    }
    if spec.settle > 0.0 && settle_steps(spec, dt) >= MAX_STEPS {
        return Err(PowderError::Run(format!(
            "the settle time {:e} s needs {} steps of {dt:e} s, over the {MAX_STEPS} a collision may take: shorten --settle or raise --dt",
            spec.settle,
            settle_steps(spec, dt)
        )));
    }
    // (a range or travel beyond f64's resolution is named by its flag before the
    // approach's resolution below, which it would otherwise trip)
    let scene = spec.scene(dt);
    if let Some(e) = unresolved_domain(spec, dt, &scene) {
        return Err(e.into());
    }
    // (an approach per step within f64's resolution of the positions closes the gap in
    // rounding steps: e comes out anywhere, even above 1)
    // (sphere 2 starts beyond r1 + r2 and the interaction range: the positions' scale)
    let range = spec.model.reach(reach);
    let range = if range.is_finite() {
        range.max(0.0)
    } else {
        0.0
    };
    let resolution = 1024.0 * f64::EPSILON * (spec.radius1 + spec.radius2 + range);
    let step = spec.normal_speed() * dt;
    if step > 0.0 && step < resolution {
        // (a larger dt helps only up to the stable limit)
        let stable = spec.time_step().max;
        let advice = if spec.normal_speed() * stable >= resolution {
            format!("raise --dt (the stable limit is {stable:e} s)")
        } else {
            format!("no stable dt resolves it (at most {stable:e} s, by the time-step rule): change the parameter that sets that rule, or raise --velocity")
        };
        return Err(PowderError::Scene(format!(
            "at v = {:e} m/s the approach is {step:e} m a step of {dt:e} s ({rule}), within 1024 ulps of the positions ({resolution:e} m): f64 cannot resolve it; {advice}",
            spec.velocity
        )));
    }
    let wall_x = scene.walls.first().map_or(0.0, |w| w.point[0]);
    let wall = spec.wall;
    let result = match backend {
        Backend::Cpu => {
            let run = CpuRun {
                engine: CpuEngine::new(&scene)?,
                wall,
            };
            run_collision(spec, run, wall_x, dt, "cpu", None, trace)
        }
        Backend::Gpu => {
            let engine = GpuEngine::new(&scene, GpuContext::new()?)?;
            let adapter = Some(engine.adapter().to_string());
            let run = GpuRun { engine, wall };
            run_collision(spec, run, wall_x, dt, "gpu", adapter, trace)
        }
    }?;
    // (the geometry first: a pair pressed through each other explains a result that cannot
    // be right)
    let result = finite_result(result)?;
    if result.delta_max > reach {
        return Err(PowderError::Run(format!(
            "the collision at v = {} m/s overlapped by {:e} m, more than the smaller radius {reach:e} m (a centre passed the other sphere's surface or the wall), beyond the contact law's geometry: the impact is too violent, or the adhesion too strong, for the contact stiffness; lower --velocity or stiffen the contact",
            result.velocity, result.delta_max
        )));
    }
    sound_result(result, &rule)
}

/// Largest energy-balance error ([`CollisionEnergy::balance_error`]) a collision's result
/// is given with: beyond it the integration went wrong (a collision the step resolves
/// balances to ~10⁻³ or better; f32's ledger on the GPU to a few per cent over millions of
/// steps).
pub const MAX_BALANCE_ERROR: f64 = 0.5;

/// The result, or an error where it cannot be a collision's (a pair that came out still
/// approaching, or energy gained or lost beyond [`MAX_BALANCE_ERROR`]): the step `rule`
/// chose is unstable for the contact.
fn sound_result(r: CollideResult, rule: &str) -> Result<CollideResult, PowderError> {
    let why = if r.e < 0.0 {
        format!("the pair came out still approaching (e = {:.4e})", r.e)
    } else if let Some(b) = r.energy.balance_error.filter(|&b| b > MAX_BALANCE_ERROR) {
        format!(
            "its energy balance is off by {b:.3e} of the energy in play (limit {MAX_BALANCE_ERROR})"
        )
    } else {
        return Ok(r);
    };
    Err(PowderError::Run(format!(
        "the collision at v = {} m/s cannot be right: {why}; the step of {:e} s ({rule}) is unstable for this contact: lower --dt, and report it where the automatic dt chose it",
        r.velocity, r.dt
    )))
}

/// The result, or an error where a number of it is not finite (a parameter or speed that
/// drove a force or energy beyond f64's range).
fn finite_result(r: CollideResult) -> Result<CollideResult, PowderError> {
    let en = &r.energy;
    let numbers = [
        ("e", Some(r.e)),
        ("delta_max", Some(r.delta_max)),
        ("initial_kinetic", Some(en.initial_kinetic)),
        ("final_kinetic", Some(en.final_kinetic)),
        ("dissipated", en.dissipated),
        ("balance_error", en.balance_error),
    ];
    match numbers.iter().find(|(_, x)| x.is_some_and(|x| !x.is_finite())) {
        Some((name, x)) => Err(PowderError::Run(format!(
            "the collision at v = {} m/s gave {name} = {:e}, not a finite number: a parameter of the contact law or the velocity is beyond what the step can resolve in f64",
            r.velocity,
            x.unwrap_or(f64::NAN)
        ))),
        None => Ok(r),
    }
}

/// What makes the domain a collision builds reach where f64 positions no longer resolve
/// its spheres ([`crate::setup::POSITION_RESOLUTION`] of the smallest radius), named as
/// the flag to change: the interaction range, else the room for the sphere's travel along
/// the wall (the tangential force, the settle time, the impact velocity); None where it
/// resolves them.
fn unresolved_domain(
    spec: &CollideSpec,
    dt: f64,
    scene: &Scene,
) -> Option<crate::error::ParamError> {
    let r_min = if spec.wall {
        spec.radius1
    } else {
        spec.radius1.min(spec.radius2)
    };
    let resolves = |s: &Scene| {
        s.domain.min.iter().chain(&s.domain.max).all(|v| {
            let far = v.abs();
            far.is_finite()
                && f64::from_bits(far.to_bits() + 1) - far
                    <= crate::setup::POSITION_RESOLUTION * r_min
        })
    };
    if resolves(scene) {
        return None;
    }
    let without = |force: bool, settle: bool| {
        resolves(
            &CollideSpec {
                tangential_force: if force { 0.0 } else { spec.tangential_force },
                settle: if settle { 0.0 } else { spec.settle },
                ..spec.clone()
            }
            .scene(dt),
        )
    };
    let force = spec.tangential_force;
    let range = spec.model.range();
    let (param, what) = if !without(true, true) && range > 0.0 {
        // (no travel along the wall: the gap and the room around the pair, the range's)
        (
            "fa",
            format!("the interaction range {range:e} m (a non-contact adhesion range fa/kc_a) needs a domain that"),
        )
    } else if !without(true, true) {
        (
            "velocity",
            format!(
                "the impact velocity {:e} m/s needs a gap so wide that the domain",
                spec.velocity
            ),
        )
    } else if force != 0.0 && without(true, false) {
        (
            "tangential-force",
            format!("the tangential force {force:e} N carries the sphere so far along the wall that the domain"),
        )
    } else if spec.settle != 0.0 && without(false, true) {
        (
            "settle",
            format!("the settle time {:e} s lets the sphere travel so far along the wall that the domain", spec.settle),
        )
    } else {
        (
            "tangential-force",
            format!("the tangential force {force:e} N over the settle time {:e} s carries the sphere so far along the wall that the domain", spec.settle),
        )
    };
    Some(crate::error::ParamError::new(
        param,
        format!(
            "{what} reaches where f64 positions no longer resolve the spheres (radius {r_min:e} m): {}",
            if param == "fa" {
                "lower --fa or raise --kca"
            } else {
                "choose a smaller one"
            }
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ContactModel, HystereticParams};

    /// An engine that never moves the pair.
    struct Still {
        steps: u64,
        x2: f64,
    }

    impl CollisionRun for Still {
        fn step(&mut self) -> Result<(), PowderError> {
            self.steps += 1;
            Ok(())
        }
        fn view(&self) -> Result<PairView, PowderError> {
            Ok(PairView {
                pos: [DVec3::ZERO, DVec3::new(self.x2, 0.0, 0.0)],
                vel: [DVec3::ZERO; 2],
                omega: [DVec3::ZERO; 2],
                in_contact: Some(false),
            })
        }
        fn time(&self) -> f64 {
            self.steps as f64 * 1e-6
        }
        fn steps(&self) -> u64 {
            self.steps
        }
        fn energy(&self, _: &PairView) -> (f64, Option<f64>, Option<f64>) {
            (0.0, None, None)
        }
        fn rotates(&self) -> bool {
            false
        }
        fn trace_sample(&self) -> Option<(DVec3, Option<crate::model::ContactHistory>)> {
            None
        }
    }

    /// A pair the engine never brings together is an error within twice the closing
    /// steps (and 100), not after MAX_STEPS.
    #[test]
    fn a_pair_that_never_touches_is_an_error_soon() {
        let law = ContactModel::Hysteretic(HystereticParams::paper_figure());
        let spec = CollideSpec::head_on(law, 1e-3, 2000.0, 0.5);
        // a gap of 1e-4 m closes in 200 steps of 1e-6 s at 0.5 m/s
        let still = Still {
            steps: 0,
            x2: 2e-3 + 1e-4,
        };
        let err = run_collision(&spec, still, 0.0, 1e-6, "test", None, None)
            .unwrap_err()
            .to_string();
        let steps: u64 = err
            .split("had not touched after ")
            .nth(1)
            .and_then(|rest| rest.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{err}"));
        assert!((500..=502).contains(&steps), "{err}");
        assert!(err.contains("takes 200 "), "{err}");
        assert!(err.contains("test backend"), "{err}");
    }

    /// A gap no collision closes within MAX_STEPS is refused before the first step.
    #[test]
    fn a_gap_beyond_max_steps_is_refused_at_once() {
        let law = ContactModel::Hysteretic(HystereticParams::paper_figure());
        let spec = CollideSpec::head_on(law, 1e-3, 2000.0, 0.5);
        // 100 m at 0.5 m/s: 2e8 steps of 1e-6 s
        let still = Still {
            steps: 0,
            x2: 2e-3 + 100.0,
        };
        let err = run_collision(&spec, still, 0.0, 1e-6, "test", None, None)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("start 1e2 m apart") && err.contains("--fa"),
            "{err}"
        );
        let still = Still {
            steps: 0,
            x2: f64::INFINITY,
        };
        let err = run_collision(&spec, still, 0.0, 1e-6, "test", None, None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("start inf m apart"), "{err}");
    }

    /// An approach below f64's resolution of the positions a step is refused (it once gave
    /// e = 1.01 for a dissipative law at 1e-15 m/s).
    #[test]
    fn an_approach_below_f64_resolution_is_refused() {
        let law = ContactModel::Hysteretic(HystereticParams::paper_figure());
        let spec = CollideSpec::head_on(law, 1e-3, 2000.0, 1e-15);
        let err = collide_on(&spec, Backend::Cpu).unwrap_err().to_string();
        assert!(err.contains("f64 cannot resolve it"), "{err}");
        assert!(err.contains("(the automatic dt: dt <= tc/10"), "{err}");
        assert!(err.contains("no stable dt"), "{err}");
    }

    /// A grazing impact whose spheres pass each other is named as such (CPU engine).
    #[test]
    fn a_grazing_miss_names_the_impact_angle() {
        let law = ContactModel::Hysteretic(HystereticParams::paper_figure());
        let spec = CollideSpec {
            impact_angle: 1e-4,
            ..CollideSpec::head_on(law, 1e-3, 2000.0, 0.1)
        };
        let err = collide_on(&spec, Backend::Cpu).unwrap_err().to_string();
        assert!(err.contains("passed each other without touching"), "{err}");
        assert!(err.contains("--impact-angle"), "{err}");
    }
}
