//! The head-on collision of two spheres, run through the full engine, measured against the
//! papers' closed forms. This is what `powder collide` prints.
//!
//! The spheres start two steps' travel outside the interaction range, approaching with
//! relative speed v. The run ends when they have separated beyond the range again
//! (e = separation speed / approach speed), or is declared **stuck** when, after the
//! first touch, their relative normal velocity turns from separating back to approaching
//! while they are still inside the range: a head-on pair with forces that only conserve
//! or dissipate energy can then never escape (it oscillates on an elastic k2 branch or in
//! the adhesive well), so e = 0. A pair that, receding in contact, has slowed below
//! [`REST_SPEED`] of the impact speed and of its own fastest receding has come to rest
//! (an overdamped contact creeps back and never turns): stuck too, as is one that creeps
//! in, approaching slower than [`REST_SPEED`] of the impact speed without turning back.

use crate::error::PowderError;
use crate::model::{analytic, ContactModel, Dissipation, PairGeometry};
use crate::scene::{Domain, DtSetting, Material, ParticleInit, Scene, Wall};
use glam::DVec3;
use serde::Serialize;

mod backends;
mod collision;
mod plot;
mod predict;
mod run;
mod stop_rules;
mod sweep;

use collision::collide_with;
pub use plot::{restitution_plot, trace_plot};
use predict::predict;
pub use predict::{
    add_plastic_restitution, closed_form_e, friction_warnings, tabor, theory_warnings,
    yield_velocity,
};
pub use sweep::{sweep, sweep_on, sweep_velocities};

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
    /// approach (+y; along +y too for a head-on impact), from the start (paper 002 §5.3's
    /// F_ext); wall impacts only.
    pub tangential_force: f64,
    /// Seconds to go on after the sphere stuck before telling whether it rests or rolls
    /// ([`CollideResult::outcome`]); 0: the run ends when it sticks.
    pub settle: f64,
}

/// A pair receding inside its interaction range slower than this fraction of the impact
/// speed, and of its fastest receding so far, has come to rest: stuck (e below it
/// whatever follows, since the contact only slows it further). So has a pair in contact
/// approaching slower than this fraction of the impact speed whose speed decays as a creep
/// does, its steps to a stop at the current deceleration holding for ten steps (at a turn
/// they fall by one a step), and a pair in contact moving slower than it for a thousand
/// steps.
pub const REST_SPEED: f64 = 1e-6;

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
    /// |E_total(end) − E_total(start)| over the largest of E_kinetic(start), E_kinetic(end)
    /// and the energy dissipated (a stuck adhesive pair dissipates its well's depth, which
    /// can dwarf the impact's kinetic energy; a tangential force's work can dwarf both).
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
    /// inside the interaction range, or, receding in it, fell below [`REST_SPEED`] of the
    /// impact speed and of its own peak, or approaching crept below it (an overdamped pair
    /// creeps to rest and never turns).
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

impl CollideSpec {
    fn masses(&self) -> (f64, f64) {
        let m = |r: f64| crate::scene::sphere_mass(self.density, r);
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
                        "dt = {dt:e} s is above the stable limit {:.4e} s ({}); use --dt {} or less, or --force",
                        ts.max,
                        ts.reason,
                        crate::error::sci_at_most(ts.max, 3)
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
    let mut rows = Vec::new();
    let result = collide_with(spec, backend, Some(&mut rows))?;
    Ok((result, rows))
}

/// Runs one collision on the chosen backend.
pub fn collide_on(spec: &CollideSpec, backend: Backend) -> Result<CollideResult, PowderError> {
    collide_with(spec, backend, None)
}
