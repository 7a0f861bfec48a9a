//! One collision on a backend: what it may be run with (refused before it starts, named
//! by the flag to change) and the result it may be given with.

use super::*;
use crate::cpu::CpuEngine;
use crate::gpu::{GpuContext, GpuEngine};
use backends::{CpuRun, GpuRun};
use run::{run_collision, settle_steps};

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
        // (the count in f64: beyond u64 the cast saturates)
        return Err(PowderError::Run(format!(
            "the settle time {:e} s needs {:.3e} steps of {dt:e} s, over the {MAX_STEPS} a collision may take: shorten --settle or raise --dt",
            spec.settle,
            (spec.settle / dt).ceil()
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
