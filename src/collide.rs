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
use crate::model::{analytic, ContactModel, PairGeometry};
use crate::output::plot::{Plot, Series, Style};
use crate::scene::{Domain, DtSetting, Material, ParticleInit, Scene};
use serde::Serialize;
use std::f64::consts::PI;

/// What to collide.
#[derive(Clone, Debug)]
pub struct CollideSpec {
    pub model: ContactModel,
    pub radius1: f64,
    pub radius2: f64,
    pub density: f64,
    /// Relative approach speed from beyond the interaction range, m/s.
    pub velocity: f64,
    /// Time step; `None` = tc/50 on the stiffest branch.
    pub dt: Option<f64>,
    /// Accept a dt above the stable limit.
    pub force: bool,
}

/// The energy ledger of the collision, J.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CollisionEnergy {
    pub initial_kinetic: f64,
    pub final_kinetic: f64,
    pub dissipated: f64,
    /// |E_total(end) − E_total(start)| / E_kinetic(start).
    pub balance_error: f64,
}

/// One collision's outcome, measured and predicted.
#[derive(Clone, Debug, Serialize)]
pub struct CollideResult {
    pub model: &'static str,
    pub velocity: f64,
    /// Separation speed / approach speed; 0 when stuck.
    pub e: f64,
    pub stuck: bool,
    /// Closed-form restitution where one applies (no viscosity for the hysteretic model).
    pub e_analytic: Option<f64>,
    pub stuck_analytic: Option<bool>,
    /// Largest overlap reached, m.
    pub delta_max: f64,
    pub delta_max_analytic: Option<f64>,
    /// Scaled impact velocity χ = δmax/δmax^p of the closed form (hysteretic).
    pub chi: Option<f64>,
    /// Plastic limit velocity vp (eq. 19), m/s.
    pub v_p: Option<f64>,
    /// Overlap where the kinetic energy first vanished when stuck (δc), m.
    pub delta_c: Option<f64>,
    pub delta_c_analytic: Option<f64>,
    /// Time in mechanical contact (δ > 0), s; null when stuck.
    pub contact_duration: Option<f64>,
    pub contact_duration_analytic: Option<f64>,
    pub dt: f64,
    pub steps: u64,
    pub backend: &'static str,
    pub energy: CollisionEnergy,
}

fn model_name(m: &ContactModel) -> &'static str {
    match m {
        ContactModel::Hysteretic(_) => "hysteretic",
        ContactModel::Lsd(_) => "lsd",
    }
}

impl CollideSpec {
    fn masses(&self) -> (f64, f64) {
        let m = |r: f64| self.density * 4.0 / 3.0 * PI * r.powi(3);
        (m(self.radius1), m(self.radius2))
    }

    fn geometry(&self) -> PairGeometry {
        let (m1, m2) = self.masses();
        PairGeometry::spheres(self.radius1, self.radius2, m1, m2)
    }

    /// Checks the inputs, naming the offending option.
    pub fn validate(&self) -> Result<(), PowderError> {
        use crate::error::{require_positive, ParamError};
        self.model.validate()?;
        require_positive("radius", self.radius1, "the radius")?;
        require_positive("radius2", self.radius2, "the second radius")?;
        require_positive("density", self.density, "the density")?;
        require_positive("velocity", self.velocity, "the impact velocity")?;
        if let Some(dt) = self.dt {
            require_positive("dt", dt, "the time step")?;
            let ts = self.model.time_step(self.geometry().reduced_mass);
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

    /// The two-particle scene: sphere 1 at the origin, sphere 2 on +x, both moving
    /// towards each other in the centre-of-mass frame.
    fn scene(&self, dt: f64) -> Scene {
        let (m1, m2) = self.masses();
        let range = self.model.range();
        let gap = range + 2.0 * self.velocity * dt;
        let x2 = self.radius1 + self.radius2 + gap;
        let v = self.velocity;
        let r = self.radius1.max(self.radius2);
        Scene {
            name: "collide".into(),
            domain: Domain {
                min: [-2.0 * r, -2.0 * r, -2.0 * r],
                max: [x2 + 2.0 * r, 2.0 * r, 2.0 * r],
            },
            gravity: [0.0; 3],
            dt: DtSetting::Fixed(dt),
            force_dt: true,
            duration: f64::INFINITY,
            output_every: u64::MAX,
            materials: vec![Material {
                name: "collide".into(),
                density: self.density,
                model: self.model,
            }],
            interactions: vec![],
            walls: vec![],
            particles: vec![
                ParticleInit {
                    position: [0.0; 3],
                    velocity: [v * m2 / (m1 + m2), 0.0, 0.0],
                    radius: self.radius1,
                    material: 0,
                },
                ParticleInit {
                    position: [x2, 0.0, 0.0],
                    velocity: [-v * m1 / (m1 + m2), 0.0, 0.0],
                    radius: self.radius2,
                    material: 0,
                },
            ],
        }
    }
}

/// Largest number of steps one collision may take before it is reported as undecided.
pub const MAX_STEPS: u64 = 50_000_000;

/// Runs one head-on collision on the CPU reference backend.
pub fn collide(spec: &CollideSpec) -> Result<CollideResult, PowderError> {
    spec.validate()?;
    let geom = spec.geometry();
    let dt = spec
        .dt
        .unwrap_or_else(|| spec.model.time_step(geom.reduced_mass).default);
    let mut engine = CpuEngine::new(&spec.scene(dt))?;
    let range = spec.model.range();
    let start = engine.energies();

    let approach_speed = |e: &CpuEngine| {
        let n = (e.positions()[0] - e.positions()[1]).normalize();
        -(e.velocities()[0] - e.velocities()[1]).dot(n)
    };
    let mut touched = false;
    let mut receding = false;
    let mut first_contact = None;
    let mut last_contact = 0.0;
    let mut delta_max: f64 = 0.0;
    let mut delta_c = None;
    let mut e = 0.0;
    loop {
        if engine.steps >= MAX_STEPS {
            return Err(PowderError::Run(format!(
                "the collision at v = {} m/s was not decided after {MAX_STEPS} steps (t = {:e} s): the pair neither separated nor turned back; try a larger --dt or --velocity",
                spec.velocity, engine.time
            )));
        }
        engine.step()?;
        let delta = engine.overlap(0, 1);
        let vn = approach_speed(&engine);
        if delta > 0.0 {
            touched = true;
            first_contact.get_or_insert(engine.time - dt);
            last_contact = engine.time;
            delta_max = delta_max.max(delta);
        }
        if !touched {
            continue;
        }
        if vn < 0.0 {
            receding = true;
        }
        if receding && vn > 0.0 && delta > -range {
            delta_c = Some(delta);
            break;
        }
        if receding && delta <= -range {
            e = -vn / spec.velocity;
            break;
        }
    }
    let stuck = delta_c.is_some();
    let end = engine.energies();
    let mut result = CollideResult {
        model: model_name(&spec.model),
        velocity: spec.velocity,
        e,
        stuck,
        e_analytic: None,
        stuck_analytic: None,
        delta_max,
        delta_max_analytic: None,
        chi: None,
        v_p: None,
        delta_c,
        delta_c_analytic: None,
        contact_duration: (!stuck).then(|| last_contact - first_contact.unwrap_or(0.0)),
        contact_duration_analytic: None,
        dt,
        steps: engine.steps,
        backend: "cpu",
        energy: CollisionEnergy {
            initial_kinetic: start.kinetic,
            final_kinetic: end.kinetic,
            dissipated: end.dissipated,
            balance_error: (end.total() - start.total()).abs() / start.kinetic,
        },
    };
    match &spec.model {
        ContactModel::Hysteretic(p) => {
            if let Some(pred) =
                analytic::hysteretic_collision(p, geom.a12, geom.reduced_mass, spec.velocity)
            {
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
                result.delta_max_analytic = Some(spec.velocity * (geom.reduced_mass / p.k).sqrt());
            }
        }
    }
    Ok(result)
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
        ContactModel::Lsd(_) => None,
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
        let e = match &spec.model {
            ContactModel::Hysteretic(p) => {
                analytic::hysteretic_collision(p, geom.a12, geom.reduced_mass, v).map(|r| r.e)
            }
            ContactModel::Lsd(p) => analytic::lsd_restitution(p.k, p.gamma0, geom.reduced_mass),
        };
        if let Some(e) = e {
            curve.push((x_of(v), e));
        }
    }
    let mut series = Vec::new();
    if !curve.is_empty() {
        series.push(Series {
            label: "closed form (paper 000 eqs. 16-25)".into(),
            points: curve,
            style: Style::Line,
        });
    }
    series.push(Series {
        label: "powder collide (CPU f64)".into(),
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
    }
}
