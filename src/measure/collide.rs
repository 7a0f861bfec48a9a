//! The head-on collision of two spheres, run through the full engine, measured against the
//! papers' closed forms. This is what `powder collide` prints.
//!
//! The spheres start two steps' travel outside the interaction range, approaching with
//! relative speed v. The run ends when they have separated beyond the range again
//! (e = separation speed / approach speed), or is declared **stuck** when, after the
//! first touch, their relative normal velocity turns from separating back to approaching
//! while they are still inside the range: a head-on pair with forces that only conserve
//! or dissipate energy can then never escape (it oscillates on an elastic k2 branch or in
//! the adhesive well), so e = 0.

use crate::cpu::CpuEngine;
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine};
use crate::model::{analytic, ContactModel, Dissipation, PairGeometry};
use crate::output::plot::{Legend, Plot, Series, Style};
use crate::scene::{Domain, DtSetting, Material, ParticleInit, Scene, Wall};
use glam::DVec3;
use serde::Serialize;
use std::f64::consts::PI;

/// What to collide.
#[derive(Clone, Debug)]
pub struct CollideSpec {
    /// Normal contact model of the pair (and of sphere–wall contact when `wall`).
    pub model: ContactModel,
    /// Radius of sphere 1, m.
    pub radius1: f64,
    /// Radius of sphere 2, m (ignored when `wall`).
    pub radius2: f64,
    /// Material density of both spheres, kg/m³.
    pub density: f64,
    /// Relative approach speed from beyond the interaction range, m/s.
    pub velocity: f64,
    /// Time step; `None` = tc/50 on the stiffest branch.
    pub dt: Option<f64>,
    /// Accept a dt above the stable limit.
    pub force: bool,
    /// Collide sphere 1 with a plane of the same material instead of sphere 2.
    pub wall: bool,
    /// Angle between the approach velocity and the tangent plane at contact, degrees
    /// (90 = head-on, as ψ in paper 002 §5).
    pub impact_angle: f64,
    /// Place the impulses of force jumps inside the step (the scene's `jump_impulses`);
    /// `None`: the engine's default (yes, where the law's force can jump).
    pub jump_impulses: Option<bool>,
    /// A constant force on the sphere along the wall, N, in the direction of its tangential
    /// approach (+y), from the start (paper 002 §5.3's F_ext); wall impacts only.
    pub tangential_force: f64,
    /// Seconds to go on after the sphere stuck before telling whether it rests or rolls
    /// ([`CollideResult::outcome`]); 0: the run ends when it sticks.
    pub settle: f64,
}

/// A settled sphere whose centre moved along the wall more than this many radii over the
/// last quarter of the settle time rolls; one that moved less rests.
pub const ROLLING_TRAVEL: f64 = 1e-3;

impl CollideSpec {
    /// A head-on sphere–sphere collision.
    pub fn head_on(model: ContactModel, radius: f64, density: f64, velocity: f64) -> Self {
        Self {
            model,
            radius1: radius,
            radius2: radius,
            density,
            velocity,
            dt: None,
            force: false,
            wall: false,
            impact_angle: 90.0,
            jump_impulses: None,
            tangential_force: 0.0,
            settle: 0.0,
        }
    }
}

/// The energy ledger of the collision, J.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CollisionEnergy {
    /// Kinetic energy of the pair at the start (translational + rotational), J.
    pub initial_kinetic: f64,
    /// Kinetic energy of the pair at the end, J.
    pub final_kinetic: f64,
    /// From the energy ledger (both backends; the GPU keeps it on the device in f32).
    pub dissipated: Option<f64>,
    /// |E_total(end) − E_total(start)| / E_kinetic(start).
    pub balance_error: Option<f64>,
}

/// JKR characteristic scales of the pair (with the stiffness scale applied).
#[derive(Clone, Debug, Serialize)]
pub struct JkrScales {
    /// Pull-off force Fc = 3πγR*, N.
    pub fc: f64,
    /// Equilibrium contact radius a0, m.
    pub a0: f64,
    /// Equilibrium overlap δ0 = a0²/(3R*), m.
    pub delta0: f64,
    /// Overlap where the contact breaks (negative), m.
    pub pulloff_overlap: f64,
    /// Reduced-stiffness note (paper 002 §3, §6.2), when a stiffness scale is set.
    pub stiffness_scaling: Option<String>,
}

/// One collision's outcome, measured and predicted.
#[derive(Clone, Debug, Serialize)]
pub struct CollideResult {
    /// Model name: `"hysteretic"`, `"lsd"`, `"hertz"` (JKR without surface energy) or `"jkr"`.
    pub model: &'static str,
    /// Relative approach speed, m/s (as given in [`CollideSpec::velocity`]).
    pub velocity: f64,
    /// Normal separation speed / normal approach speed; 0 when stuck.
    pub e: f64,
    /// Whether the pair stuck (e = 0): the relative normal velocity turned back to approaching
    /// inside the interaction range.
    pub stuck: bool,
    /// `"rebound"`, `"stuck"`, or after a settle time (`CollideSpec::settle`) `"resting"`
    /// (the centre moved less than [`ROLLING_TRAVEL`] radii along the wall over its last
    /// quarter), `"rolling"` (more) or `"detached"` (out of contact at its end).
    pub outcome: &'static str,
    /// The sphere's mean speed along the wall over the last quarter of the settle time (its
    /// centre's displacement over that time), m/s: a resting sphere may still vibrate.
    pub settled_speed: Option<f64>,
    /// Closed-form restitution where one applies: head-on impacts only (every `*_analytic`
    /// is `None` for an oblique one), no viscosity for the hysteretic model, no dissipation,
    /// friction or rolling resistance for JKR.
    pub e_analytic: Option<f64>,
    /// Whether the closed form predicts sticking (where `e_analytic` applies).
    pub stuck_analytic: Option<bool>,
    /// Tangential restitution: the tangential contact-point velocity after, along its
    /// direction before, over the speed before (−1: reversed, as an elastic sphere that
    /// sticks throughout; 1: kept). Oblique impacts of models that rotate (friction, rolling
    /// or twisting on); `None` head-on, where there is no tangential motion to restitute.
    pub e_tangential: Option<f64>,
    /// Closed form of `e_tangential` where one applies: an elastic hysteretic or LSD pair
    /// (k1 = kp, kc = fa = 0, γ0 = 0) with Luding's sliding friction only, k_t = 2/7·k, γ_t = 0,
    /// μs = μd = μ: −1 for u_t ≤ 3.5·μ·v_n (sticking throughout), else 1 − 7·μ·v_n/u_t
    /// ([`analytic::luding_tangential_restitution`]); oblique impacts only.
    pub e_tangential_analytic: Option<f64>,
    /// Angular speed of sphere 1 at the end, rad/s (models with friction or rolling).
    pub omega_final: Option<f64>,
    /// Largest overlap reached, m.
    pub delta_max: f64,
    /// Closed-form largest overlap, m (hysteretic without viscosity; undamped LSD and Hertz).
    pub delta_max_analytic: Option<f64>,
    /// Scaled impact velocity χ = δmax/δmax^p of the closed form (hysteretic).
    pub chi: Option<f64>,
    /// Plastic limit velocity vp (eq. 19), m/s.
    pub v_p: Option<f64>,
    /// Overlap where the kinetic energy first vanished when stuck (δc), m.
    pub delta_c: Option<f64>,
    /// Closed-form sticking overlap δc, m (paper 000 eqs. 36/38/39; hysteretic without fa).
    pub delta_c_analytic: Option<f64>,
    /// Time in mechanical contact, s (JKR: until pull-off); null when stuck.
    pub contact_duration: Option<f64>,
    /// Closed-form contact duration, s (LSD, paper 000 eq. 3; Hertz).
    pub contact_duration_analytic: Option<f64>,
    /// JKR scales of the pair (JKR with surface energy > 0).
    pub jkr: Option<JkrScales>,
    /// Tabor parameter λT of the pair (paper 002 eq. 1; JKR with surface energy > 0):
    /// the JKR model holds for λT > 3. D_min = 1.65 Å unless set ([`tabor`]).
    pub tabor: Option<f64>,
    /// Yield velocity v_Y of the Thornton–Ning estimate, m/s, when one was given
    /// ([`add_plastic_restitution`]; JKR family).
    pub v_yield: Option<f64>,
    /// Thornton–Ning restitution e_TN at the normal impact speed (paper 001 eq. 13).
    pub e_tn: Option<f64>,
    /// e_pl = √(e² − (1 − e_TN²)) with the measured e (paper 001 eq. 14), 0 when the
    /// plastic loss takes all that is left.
    pub e_pl: Option<f64>,
    /// Time step used, s.
    pub dt: f64,
    /// Steps run.
    pub steps: u64,
    /// The backend that ran the collision: `"cpu"` or `"gpu"`.
    pub backend: &'static str,
    /// The GPU adapter (GPU backend).
    pub adapter: Option<String>,
    /// Energy ledger of the collision.
    pub energy: CollisionEnergy,
}

fn model_name(m: &ContactModel) -> &'static str {
    match m {
        ContactModel::Hysteretic(_) => "hysteretic",
        ContactModel::Lsd(_) => "lsd",
        ContactModel::Jkr(p) if p.surface_energy == 0.0 => "hertz",
        ContactModel::Jkr(_) => "jkr",
    }
}

impl CollideSpec {
    fn masses(&self) -> (f64, f64) {
        let m = |r: f64| self.density * 4.0 / 3.0 * PI * r.powi(3);
        (m(self.radius1), m(self.radius2))
    }

    /// Effective radius and mass of the pair (the plane is an infinite body).
    pub fn geometry(&self) -> PairGeometry {
        let (m1, m2) = self.masses();
        if self.wall {
            PairGeometry::wall(self.radius1, m1)
        } else {
            PairGeometry::spheres(self.radius1, self.radius2, m1, m2)
        }
    }

    /// Normal component of the approach speed.
    fn normal_speed(&self) -> f64 {
        self.velocity * self.impact_angle.to_radians().sin()
    }

    /// Whether the impact is head-on (`impact_angle` = 90°): the closed forms apply only
    /// then, and there is no tangential restitution.
    pub fn is_head_on(&self) -> bool {
        self.impact_angle == 90.0
    }

    /// Time-step rule for this pair at this impact speed.
    pub fn time_step(&self) -> crate::model::TimeStep {
        self.model.time_step(&self.geometry(), self.normal_speed())
    }

    /// Checks the inputs, naming the offending option.
    pub fn validate(&self) -> Result<(), PowderError> {
        use crate::error::{require_positive, ParamError};
        self.model.validate()?;
        require_positive("radius", self.radius1, "the radius")?;
        if !self.wall {
            require_positive("radius2", self.radius2, "the second radius")?;
        }
        require_positive("density", self.density, "the density")?;
        require_positive("velocity", self.velocity, "the impact velocity")?;
        if (self.tangential_force != 0.0 || self.settle != 0.0) && !self.wall {
            return Err(ParamError::new(
                if self.settle != 0.0 { "settle" } else { "tangential-force" },
                "the tangential force and the settle time are for a sphere on a wall (--wall): a pair that stuck spins about its centre of mass",
            )
            .into());
        }
        if !self.tangential_force.is_finite() {
            return Err(ParamError::new(
                "tangential-force",
                format!(
                    "the tangential force must be finite, got {}",
                    self.tangential_force
                ),
            )
            .into());
        }
        crate::error::require_non_negative("settle", self.settle, "the settle time")?;
        if !self.settle.is_finite() {
            return Err(ParamError::new("settle", "the settle time must be finite").into());
        }
        if !(self.impact_angle > 0.0 && self.impact_angle <= 90.0) {
            return Err(ParamError::new(
                "impact-angle",
                format!(
                    "the impact angle must be in (0, 90] degrees from the tangent plane (90 = head-on), got {}",
                    self.impact_angle
                ),
            )
            .into());
        }
        if let Some(dt) = self.dt {
            require_positive("dt", dt, "the time step")?;
            let ts = self.time_step();
            if dt > ts.max && !self.force {
                return Err(ParamError::new(
                    "dt",
                    format!(
                        "dt = {dt:e} s is above the stable limit {:.4e} s ({}); use --dt {:.3e} or less, or --force",
                        ts.max, ts.reason, ts.max
                    ),
                )
                .into());
            }
        }
        Ok(())
    }

    /// The collision as a scene: sphere 1 at the origin; sphere 2 on +x (or a plane
    /// x = x_w facing −x), approaching along x with the normal speed and along y with the
    /// tangential one (the line of centres at first touch is x).
    fn scene(&self, dt: f64) -> Scene {
        let (m1, m2) = self.masses();
        let geom = self.geometry();
        let reach = self.model.reach(geom.r_eff());
        let vn = self.normal_speed();
        // exactly 0 head-on (cos of 90° in radians is 6e-17, not 0)
        let vt = if self.is_head_on() {
            0.0
        } else {
            self.velocity * self.impact_angle.to_radians().cos()
        };
        let gap = self.model.range() + 2.5 * vn * dt;
        let r = self.radius1.max(if self.wall { 0.0 } else { self.radius2 });
        // room for the tangential travel during the collision
        let side = 4.0 * r + 10.0 * reach;
        // the tangential force as a uniform acceleration of the one sphere (walls do not move)
        let accel = self.tangential_force / m1;
        // and room along y for what it and vt carry the sphere over the approach (a hundred
        // gap crossings), the contact and the settle time
        let span = self.settle + 100.0 * (gap + reach) / vn + 1e4 * dt;
        let travel = if self.settle > 0.0 || accel != 0.0 {
            vt.abs() * span + 0.5 * accel.abs() * span * span
        } else {
            0.0
        };
        let mut particles = vec![ParticleInit {
            position: [0.0; 3],
            velocity: [0.0; 3],
            radius: self.radius1,
            material: 0,
            angular_velocity: [0.0; 3],
            insert_at: 0.0,
        }];
        let mut walls = vec![];
        let x2 = if self.wall {
            let xw = self.radius1 + gap;
            particles[0].velocity = [vn, vt, 0.0];
            walls.push(Wall {
                point: [xw, 0.0, 0.0],
                normal: [-1.0, 0.0, 0.0],
                motion: Default::default(),
                material: 0,
            });
            xw
        } else {
            let x2 = self.radius1 + self.radius2 + gap;
            let f1 = m2 / (m1 + m2);
            let f2 = m1 / (m1 + m2);
            particles[0].velocity = [vn * f1, vt * f1, 0.0];
            particles.push(ParticleInit {
                position: [x2, 0.0, 0.0],
                velocity: [-vn * f2, -vt * f2, 0.0],
                radius: self.radius2,
                material: 0,
                angular_velocity: [0.0; 3],
                insert_at: 0.0,
            });
            x2
        };
        Scene {
            name: "collide".into(),
            domain: Domain {
                min: [-side, -side - travel, -side],
                max: [x2 + side, side + travel, side],
                periodic: [false; 3],
            },
            gravity: [0.0, accel, 0.0],
            dt: DtSetting::Fixed(dt),
            force_dt: true,
            jump_impulses: self.jump_impulses,
            duration: f64::INFINITY,
            output_every: u64::MAX,
            contact_output: None,
            impact_velocity: vn,
            checkpoint_every: u64::MAX,
            materials: vec![Material {
                name: "collide".into(),
                density: self.density,
                model: self.model,
            }],
            interactions: vec![],
            walls,
            particles,
        }
    }
}

/// Largest number of steps one collision may take before it is reported as undecided.
pub const MAX_STEPS: u64 = 50_000_000;

/// Which engine runs the collision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Backend {
    /// The f64 CPU reference engine.
    #[default]
    Cpu,
    /// The wgpu engine (the full GPU pipeline, reading the pair back every step).
    Gpu,
}

/// The pair as a backend reports it after a step.
struct PairView {
    pos: [DVec3; 2],
    vel: [DVec3; 2],
    omega: [DVec3; 2],
    /// Whether the contact persists (JKR necks at negative overlap); `None` when the
    /// backend cannot say, then δ > 0 decides.
    in_contact: Option<bool>,
}

/// One step of a traced collision (`powder collide --trace`), in the scene's units.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TraceRow {
    /// Time since the start of the run.
    pub t: f64,
    /// Overlap δ (> 0: compressed).
    pub delta: f64,
    /// Approach speed δ̇ (> 0: approaching).
    pub delta_dot: f64,
    /// Normal contact force, repulsive positive.
    pub force: f64,
    /// The model's contact radius a (JKR family: the state variable of the krijt/stress
    /// dissipations, else a_JKR(δ)); 0 out of contact or for other models.
    pub a: f64,
    /// The JKR equilibrium radius a_JKR(δ) at this overlap (JKR family, in contact), else 0.
    pub a_jkr: f64,
}

impl TraceRow {
    /// Header line of [`TraceRow::csv`].
    pub const CSV_HEADER: &'static str = "t,delta,delta_dot,force,a,a_jkr";

    /// The row as one CSV line (no newline), columns as in [`TraceRow::CSV_HEADER`].
    pub fn csv(&self) -> String {
        format!(
            "{:e},{:e},{:e},{:e},{:e},{:e}",
            self.t, self.delta, self.delta_dot, self.force, self.a, self.a_jkr
        )
    }
}

/// What the collision loop needs of an engine.
trait CollisionRun {
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

struct CpuRun {
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

struct GpuRun {
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

/// Runs one collision on the CPU reference backend.
pub fn collide(spec: &CollideSpec) -> Result<CollideResult, PowderError> {
    collide_on(spec, Backend::Cpu)
}

/// Runs one collision on the CPU backend and records every step (see [`TraceRow`]).
pub fn collide_traced(spec: &CollideSpec) -> Result<(CollideResult, Vec<TraceRow>), PowderError> {
    collide_traced_on(spec, Backend::Cpu)
}

/// Runs one collision on the chosen backend and records every step (see [`TraceRow`]; the
/// GPU's force is m·a read back each step, its contact radius the device's history).
pub fn collide_traced_on(
    spec: &CollideSpec,
    backend: Backend,
) -> Result<(CollideResult, Vec<TraceRow>), PowderError> {
    spec.validate()?;
    let dt = spec.dt.unwrap_or_else(|| spec.time_step().default);
    let scene = spec.scene(dt);
    let wall_x = scene.walls.first().map_or(0.0, |w| w.point[0]);
    let mut rows = Vec::new();
    let result = match backend {
        Backend::Cpu => {
            let run = CpuRun {
                engine: CpuEngine::new(&scene)?,
                wall: spec.wall,
            };
            run_collision(spec, run, wall_x, dt, "cpu", None, Some(&mut rows))?
        }
        Backend::Gpu => {
            let engine = GpuEngine::new(&scene, GpuContext::new()?)?;
            let adapter = engine.adapter().to_string();
            let run = GpuRun {
                engine,
                wall: spec.wall,
            };
            run_collision(spec, run, wall_x, dt, "gpu", Some(adapter), Some(&mut rows))?
        }
    };
    Ok((result, rows))
}

/// Runs one collision on the chosen backend.
pub fn collide_on(spec: &CollideSpec, backend: Backend) -> Result<CollideResult, PowderError> {
    spec.validate()?;
    let dt = spec.dt.unwrap_or_else(|| spec.time_step().default);
    let scene = spec.scene(dt);
    let wall_x = scene.walls.first().map_or(0.0, |w| w.point[0]);
    match backend {
        Backend::Cpu => {
            let engine = CpuEngine::new(&scene)?;
            let run = CpuRun {
                engine,
                wall: spec.wall,
            };
            run_collision(spec, run, wall_x, dt, "cpu", None, None)
        }
        Backend::Gpu => {
            let engine = GpuEngine::new(&scene, GpuContext::new()?)?;
            let adapter = engine.adapter().to_string();
            let run = GpuRun {
                engine,
                wall: spec.wall,
            };
            run_collision(spec, run, wall_x, dt, "gpu", Some(adapter), None)
        }
    }
}

/// The settle time in steps of `dt` (at least 4: its last quarter is one step or more).
fn settle_steps(spec: &CollideSpec, dt: f64) -> u64 {
    ((spec.settle / dt).ceil() as u64).max(4)
}

fn run_collision(
    spec: &CollideSpec,
    mut run: impl CollisionRun,
    wall_x: f64,
    dt: f64,
    backend: &'static str,
    adapter: Option<String>,
    mut trace: Option<&mut Vec<TraceRow>>,
) -> Result<CollideResult, PowderError> {
    if spec.settle > 0.0 && settle_steps(spec, dt) >= MAX_STEPS {
        return Err(PowderError::Run(format!(
            "the settle time {} s needs {} steps of {dt:e} s, over the {MAX_STEPS} a collision may take: shorten --settle or raise --dt",
            spec.settle,
            settle_steps(spec, dt)
        )));
    }
    let geom = spec.geometry();
    let reach = spec.model.reach(geom.r_eff());
    let vn0 = spec.normal_speed();
    let view0 = run.view()?;
    let (ke0, total0, _) = run.energy(&view0);
    let mut touched = false;
    let mut receding = false;
    let mut first_contact = None;
    let mut last_contact = 0.0;
    let mut delta_max: f64 = 0.0;
    let mut delta_c = None;
    let mut vt_in = None;
    let mut e = 0.0;
    let mut vt_out = DVec3::ZERO;
    let mut vt_before = spec.pair_state(&view0, wall_x).3;
    let mut last;
    loop {
        if run.steps() >= MAX_STEPS {
            return Err(PowderError::Run(format!(
                "the collision at v = {} m/s was not decided after {MAX_STEPS} steps (t = {:e} s): the pair neither separated nor turned back; try a larger --dt or --velocity",
                spec.velocity,
                run.time()
            )));
        }
        run.step()?;
        let view = run.view()?;
        let (delta, vn, n, vt) = spec.pair_state(&view, wall_x);
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
        }
        if receding && vn > 0.0 && delta > -reach {
            delta_c = Some(delta);
            break;
        }
        if receding && delta <= -reach && !neck {
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
        model: model_name(&spec.model),
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
            balance_error: total0.zip(total1).map(|(a, b)| (b - a).abs() / ke0),
        },
    };
    predict(spec, &geom, &mut result);
    Ok(result)
}

fn trace_row(
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

/// F(δ) and a(δ) of a traced JKR-family collision beside the JKR equilibrium curves, as
/// F/Fc and a/a0 against δ/δ0 (in contact only).
pub fn trace_plot(spec: &CollideSpec, result: &CollideResult, rows: &[TraceRow]) -> Option<Plot> {
    let ContactModel::Jkr(p) = &spec.model else {
        return None;
    };
    let r = spec.geometry().r_eff();
    if p.gamma() == 0.0 {
        return None;
    }
    let (fc, a0, d0) = (p.fc(r), p.a0(r), p.delta0(r));
    let inside: Vec<&TraceRow> = rows.iter().filter(|row| row.a > 0.0).collect();
    let dmax = inside.iter().fold(1.0f64, |m, row| m.max(row.delta / d0));
    let dmin = p.pulloff_overlap(r) / d0;
    let samples = 400;
    let curve: Vec<(f64, f64, f64)> = (0..=samples)
        .map(|k| {
            let d = dmin + (dmax - dmin) * k as f64 / samples as f64;
            let a = p.contact_radius(d * d0, r);
            (d, p.elastic_force(a, r) / fc, a / a0)
        })
        .collect();
    let series = vec![
        Series {
            label: "F/Fc, JKR equilibrium (paper 001 eq. 6)".into(),
            points: curve.iter().map(|c| (c.0, c.1)).collect(),
            style: Style::DashedLine,
        },
        Series {
            label: format!("F/Fc, powder collide ({})", p.dissipation.name()),
            points: inside
                .iter()
                .map(|row| (row.delta / d0, row.force / fc))
                .collect(),
            style: Style::Line,
        },
        Series {
            label: "a/a0, JKR equilibrium (paper 001 eq. 5)".into(),
            points: curve.iter().map(|c| (c.0, c.2)).collect(),
            style: Style::DashedLine,
        },
        Series {
            label: format!("a/a0, powder collide ({})", p.dissipation.name()),
            points: inside
                .iter()
                .map(|row| (row.delta / d0, row.a / a0))
                .collect(),
            style: Style::Line,
        },
    ];
    Some(Plot {
        title: format!(
            "Head-on JKR collision at v = {} ({} dissipation, e = {:.4})",
            result.velocity,
            p.dissipation.name(),
            result.e
        ),
        x_label: format!("overlap delta/delta0  (delta0 = {d0:.4e})"),
        y_label: format!("F/Fc  and  a/a0  (Fc = {fc:.4e}, a0 = {a0:.4e})"),
        log_x: false,
        log_y: false,
        series,
        y_range: None,
        legend: Legend::UpperLeft,
    })
}

/// The closed-form restitution of this collision, where one applies: head-on only (an
/// oblique pair turns its line of centres during the contact, and friction couples the
/// directions, so the head-on value at the normal speed would mislead).
pub fn closed_form_e(spec: &CollideSpec) -> Option<f64> {
    if !spec.is_head_on() {
        return None;
    }
    let geom = spec.geometry();
    let v = spec.normal_speed();
    match &spec.model {
        ContactModel::Hysteretic(p) => {
            analytic::hysteretic_collision(p, geom.a12, geom.reduced_mass, v).map(|r| r.e)
        }
        ContactModel::Lsd(p) => analytic::lsd_restitution(p.k, p.gamma0, geom.reduced_mass),
        ContactModel::Jkr(p) => {
            let undamped = matches!(p.dissipation, Dissipation::None);
            let plain = p.friction == 0.0 && p.rolling_hysteresis == 0.0;
            if !undamped || !plain {
                None
            } else if p.surface_energy == 0.0 {
                Some(1.0)
            } else {
                let r = geom.r_eff();
                let w = analytic::jkr_loss(p.pulloff) * p.fc(r) * p.delta0(r);
                Some(analytic::jkr_restitution(w, geom.reduced_mass, v).unwrap_or(0.0))
            }
        }
    }
}

/// Fills in the closed forms that apply to this collision.
fn predict(spec: &CollideSpec, geom: &PairGeometry, result: &mut CollideResult) {
    predict_head_on(spec, geom, result);
    if !spec.is_head_on() {
        // the closed forms are those of a head-on collision (see `closed_form_e`)
        result.e_analytic = None;
        result.stuck_analytic = None;
        result.delta_max_analytic = None;
        result.delta_c_analytic = None;
        result.contact_duration_analytic = None;
        let psi = spec.impact_angle.to_radians();
        result.e_tangential_analytic = analytic::luding_elastic_sliding(&spec.model)
            .map(|mu| analytic::luding_tangential_restitution(mu, psi.sin(), psi.cos()));
    }
}

/// The closed forms of a head-on collision at the normal speed, and the pair's scales.
fn predict_head_on(spec: &CollideSpec, geom: &PairGeometry, result: &mut CollideResult) {
    let v = spec.normal_speed();
    match &spec.model {
        ContactModel::Hysteretic(p) => {
            if let Some(pred) = analytic::hysteretic_collision(p, geom.a12, geom.reduced_mass, v) {
                result.e_analytic = Some(pred.e);
                result.stuck_analytic = Some(pred.stuck);
                result.delta_max_analytic = Some(pred.delta_max);
                result.chi = Some(pred.chi);
                result.v_p = Some(pred.v_p);
                if pred.stuck && p.fa == 0.0 {
                    let eta = analytic::plasticity(p.k1, p.kp);
                    let beta = analytic::adhesivity(p.k1, p.kc);
                    result.delta_c_analytic = analytic::sticking_overlap(eta, beta, pred.chi)
                        .map(|x| x * p.delta_max_p(geom.a12));
                }
            }
        }
        ContactModel::Lsd(p) => {
            result.e_analytic = analytic::lsd_restitution(p.k, p.gamma0, geom.reduced_mass);
            result.stuck_analytic = result.e_analytic.map(|_| false);
            result.contact_duration_analytic =
                analytic::lsd_contact_time(p.k, p.gamma0, geom.reduced_mass);
            if p.gamma0 == 0.0 {
                result.delta_max_analytic = Some(v * (geom.reduced_mass / p.k).sqrt());
            }
        }
        ContactModel::Jkr(p) => {
            let r = geom.r_eff();
            let mr = geom.reduced_mass;
            let e_star = p.e_star();
            let undamped = matches!(p.dissipation, Dissipation::None);
            result.e_analytic = closed_form_e(spec);
            result.stuck_analytic = result.e_analytic.map(|e| e == 0.0);
            if p.surface_energy == 0.0 {
                result.contact_duration_analytic =
                    Some(analytic::hertz_contact_time(mr, r, e_star, v));
                if undamped {
                    // ½m*v² = 8/15·E*·√R*·δ^(5/2)
                    result.delta_max_analytic =
                        Some((15.0 * mr * v * v / (16.0 * e_star * r.sqrt())).powf(0.4));
                }
            } else {
                result.tabor = tabor(spec, analytic::TABOR_MIN_SEPARATION);
                result.jkr = Some(JkrScales {
                    fc: p.fc(r),
                    a0: p.a0(r),
                    delta0: p.delta0(r),
                    pulloff_overlap: p.pulloff_overlap(r),
                    stiffness_scaling: p.stiffness_scaling_report(),
                });
            }
        }
    }
}

/// The Tabor parameter λT of the pair (paper 002 eq. 1) with minimum separation `d_min`
/// (in the length unit of the radii); `None` unless the model is JKR with surface energy.
pub fn tabor(spec: &CollideSpec, d_min: f64) -> Option<f64> {
    match &spec.model {
        ContactModel::Jkr(p) if p.surface_energy > 0.0 => {
            Some(analytic::jkr_tabor(p, spec.geometry().r_eff(), d_min))
        }
        _ => None,
    }
}

/// The warning when the pair's λT is below the JKR range, naming the pair by its radii.
pub fn tabor_warning(spec: &CollideSpec, tabor: f64, d_min: f64) -> Option<String> {
    let pair = if spec.wall {
        format!("the sphere of radius {:e} on the wall", spec.radius1)
    } else {
        format!(
            "the pair of radii {:e} and {:e} (R* = {:.4e})",
            spec.radius1,
            spec.radius2,
            spec.geometry().r_eff()
        )
    };
    analytic::tabor_warning(&pair, tabor, d_min)
}

/// Yield velocity of the pair for yield stress `yield_stress` (Pa): the Hertz impact whose
/// centre pressure reaches 1.6·Y (paper 001 §IV A 3, [`analytic::yield_velocity`]), with
/// the material's own E*; `None` unless the model is of the JKR family.
pub fn yield_velocity(spec: &CollideSpec, yield_stress: f64) -> Option<f64> {
    let ContactModel::Jkr(p) = &spec.model else {
        return None;
    };
    let geom = spec.geometry();
    Some(analytic::yield_velocity(
        yield_stress,
        p.e_star_unscaled(),
        geom.r_eff(),
        geom.reduced_mass,
    ))
}

/// Adds the Thornton–Ning plastic loss for yield velocity `v_yield` (paper 001 eqs. 13–14):
/// e_TN at the result's normal impact speed and e_pl from the measured e.
pub fn add_plastic_restitution(spec: &CollideSpec, result: &mut CollideResult, v_yield: f64) {
    let vn = result.velocity * spec.impact_angle.to_radians().sin();
    let e_tn = analytic::thornton_ning_restitution(vn, v_yield);
    result.v_yield = Some(v_yield);
    result.e_tn = Some(e_tn);
    result.e_pl = Some(analytic::plastic_restitution(result.e, e_tn));
}

/// Velocities of a sweep `FROM:TO:N`, linear or logarithmic.
pub fn sweep_velocities(text: &str, log: bool) -> Result<Vec<f64>, PowderError> {
    let bad = |why: &str| {
        PowderError::Param(crate::error::ParamError::new(
            "sweep-velocity",
            format!("`{text}` {why}; expected FROM:TO:N, e.g. 0.01:1:20"),
        ))
    };
    let parts: Vec<&str> = text.split(':').collect();
    if parts.len() != 3 {
        return Err(bad("does not have three fields"));
    }
    let from: f64 = parts[0]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable FROM"))?;
    let to: f64 = parts[1]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable TO"))?;
    let n: usize = parts[2]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable N"))?;
    if !(from > 0.0 && to > 0.0 && from.is_finite() && to.is_finite()) {
        return Err(bad("needs positive finite velocities"));
    }
    if n == 0 {
        return Err(bad("needs N >= 1"));
    }
    if n == 1 {
        return Ok(vec![from]);
    }
    Ok((0..n)
        .map(|k| {
            let t = k as f64 / (n - 1) as f64;
            if log {
                from * (to / from).powf(t)
            } else {
                from + (to - from) * t
            }
        })
        .collect())
}

/// Runs one collision per velocity on `backend`; results in input order. The CPU
/// backend spreads them over the cores; the GPU runs them one after another.
pub fn sweep_on(
    spec: &CollideSpec,
    velocities: &[f64],
    backend: Backend,
) -> Result<Vec<CollideResult>, PowderError> {
    if backend == Backend::Gpu {
        return velocities
            .iter()
            .map(|&velocity| {
                collide_on(
                    &CollideSpec {
                        velocity,
                        ..spec.clone()
                    },
                    backend,
                )
            })
            .collect();
    }
    sweep(spec, velocities)
}

/// Runs one collision per velocity, spread over the available cores; results in input order.
pub fn sweep(spec: &CollideSpec, velocities: &[f64]) -> Result<Vec<CollideResult>, PowderError> {
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(velocities.len().max(1));
    let mut slots: Vec<Option<Result<CollideResult, PowderError>>> =
        (0..velocities.len()).map(|_| None).collect();
    std::thread::scope(|s| {
        for (t, chunk) in slots
            .chunks_mut(velocities.len().div_ceil(threads))
            .enumerate()
        {
            let base = t * velocities.len().div_ceil(threads);
            s.spawn(move || {
                for (k, slot) in chunk.iter_mut().enumerate() {
                    let one = CollideSpec {
                        velocity: velocities[base + k],
                        ..spec.clone()
                    };
                    *slot = Some(collide(&one));
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|r| r.expect("every slot is filled"))
        .collect()
}

/// The e(v) figure: simulated points over the closed form, against χ = v/vp for the
/// hysteretic model (with vp in the axis label) and against v for LSD.
pub fn restitution_plot(spec: &CollideSpec, results: &[CollideResult], log: bool) -> Plot {
    let geom = spec.geometry();
    let (vmin, vmax) = results.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| {
        (a.min(r.velocity), b.max(r.velocity))
    });
    let vp = match &spec.model {
        ContactModel::Hysteretic(p) => {
            // vp (eq. 19) does not depend on viscosity, which the closed form excludes.
            let elastic_plastic = crate::model::HystereticParams { gamma0: 0.0, ..*p };
            analytic::hysteretic_collision(&elastic_plastic, geom.a12, geom.reduced_mass, vmin)
                .map(|pred| pred.v_p)
        }
        _ => None,
    };
    let scale = vp.filter(|v| v.is_finite() && *v > 0.0);
    let x_of = |v: f64| scale.map_or(v, |vp| v / vp);
    let mut curve = Vec::new();
    let samples = 400;
    for k in 0..=samples {
        let t = k as f64 / samples as f64;
        let v = if log && vmin > 0.0 {
            vmin * (vmax / vmin).powf(t)
        } else {
            vmin + (vmax - vmin) * t
        };
        if let Some(e) = closed_form_e(&CollideSpec {
            velocity: v,
            ..spec.clone()
        }) {
            curve.push((x_of(v), e));
        }
    }
    let mut series = Vec::new();
    if !curve.is_empty() {
        series.push(Series {
            label: match spec.model {
                ContactModel::Hysteretic(_) => "closed form (paper 000 eqs. 16-25)".into(),
                ContactModel::Lsd(_) => "closed form (paper 000 eq. 4)".into(),
                ContactModel::Jkr(_) => "closed form (JKR loss 0.7722 Fc d0, paper 001)".into(),
            },
            points: curve,
            style: Style::Line,
        });
    }
    // a dissipative JKR model: the undamped JKR closed form for reference
    if let ContactModel::Jkr(p) = &spec.model {
        if series.is_empty() && p.surface_energy > 0.0 && p.dissipation != Dissipation::None {
            let plain = CollideSpec {
                model: ContactModel::Jkr(crate::model::JkrParams {
                    dissipation: Dissipation::None,
                    ..*p
                }),
                ..spec.clone()
            };
            let points: Vec<(f64, f64)> = (0..=samples)
                .filter_map(|k| {
                    let t = k as f64 / samples as f64;
                    let v = if log && vmin > 0.0 {
                        vmin * (vmax / vmin).powf(t)
                    } else {
                        vmin + (vmax - vmin) * t
                    };
                    closed_form_e(&CollideSpec {
                        velocity: v,
                        ..plain.clone()
                    })
                    .map(|e| (x_of(v), e))
                })
                .collect();
            series.push(Series {
                label: "JKR without dissipation (closed form, loss 0.7722 Fc d0)".into(),
                points,
                style: Style::DashedLine,
            });
        }
    }
    series.push(Series {
        label: format!(
            "powder collide (CPU f64){}",
            match &spec.model {
                ContactModel::Jkr(p) if p.dissipation != Dissipation::None =>
                    format!(", {} dissipation", p.dissipation.name()),
                _ => String::new(),
            }
        ),
        points: results.iter().map(|r| (x_of(r.velocity), r.e)).collect(),
        style: Style::Markers,
    });
    let x_label = match scale {
        Some(vp) => format!("scaled impact velocity chi = v/vp  (vp = {vp:.4} m/s)"),
        None => "impact velocity v (m/s)".into(),
    };
    Plot {
        title: format!(
            "Coefficient of restitution, {} model",
            model_name(&spec.model)
        ),
        x_label,
        y_label: "e".into(),
        log_x: log,
        log_y: false,
        series,
        y_range: Some((0.0, 1.05)),
        // the e(v) curves leave the lower left (hysteretic: low χ has e near 1) or the
        // upper left (JKR: sticking at low v) empty
        legend: match spec.model {
            ContactModel::Jkr(_) => Legend::UpperLeft,
            _ => Legend::LowerLeft,
        },
    }
}
