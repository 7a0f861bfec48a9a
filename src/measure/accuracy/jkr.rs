//! The JKR case: head-on JKR collisions from 1.05 to 5 times the sticking speed, both
//! pull-off rules, against the closed form.

use super::*;

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
pub(super) const JKR_MATERIAL: (f64, f64, f64) = (1e9, 0.3, 0.05);

pub(super) const JKR_RADIUS: f64 = 1e-6;

/// The JKR sweep's range of v/v_stick.
pub const JKR_RANGE: (f64, f64) = (1.05, 5.0);

pub(super) fn jkr_spec(pulloff: Pulloff) -> CollideSpec {
    let (youngs, poisson, gamma) = JKR_MATERIAL;
    let p = JkrParams {
        pulloff,
        ..JkrParams::jkr(youngs, poisson, gamma)
    };
    CollideSpec::head_on(ContactModel::Jkr(p), JKR_RADIUS, PAIR_DENSITY, 1.0)
}

pub(super) fn jkr_setup(points: usize) -> JkrSetup {
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
pub(super) fn jkr_point(
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
