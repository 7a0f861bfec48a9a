//! The pair case: the head-on hysteretic collision over a χ sweep against the closed forms.

use super::*;

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

pub(super) const PAIR_RADIUS: f64 = 1.1e-3;

pub(super) const PAIR_DENSITY: f64 = 2000.0;

pub(super) fn pair_setup(points: usize) -> (CollideSpec, PairSetup) {
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

pub(super) fn pair_point(
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
