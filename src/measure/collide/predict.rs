//! The papers' closed forms for a collision, where they apply (head-on), beside what the
//! engine measured.

use super::*;

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
pub(super) fn predict(spec: &CollideSpec, geom: &PairGeometry, result: &mut CollideResult) {
    predict_head_on(spec, geom, result);
    if !spec.is_head_on() {
        // the closed forms are those of a head-on collision (see `closed_form_e`)
        result.e_analytic = None;
        result.stuck_analytic = None;
        result.delta_max_analytic = None;
        result.delta_c_analytic = None;
        result.contact_duration_analytic = None;
        let psi = spec.impact_angle.to_radians();
        result.e_tangential_analytic =
            analytic::luding_elastic_sliding(&spec.model).map(|(mu_s, mu_d)| {
                analytic::luding_tangential_restitution(mu_s, mu_d, psi.sin(), psi.cos())
            });
    }
}

/// The closed forms of a head-on collision at the normal speed, and the pair's scales.
pub(super) fn predict_head_on(spec: &CollideSpec, geom: &PairGeometry, result: &mut CollideResult) {
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
            // (a rebound slower than REST_SPEED of the impact reads as resting: stuck)
            result.stuck_analytic = result.e_analytic.map(|e| e < super::REST_SPEED);
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
                    result.delta_max_analytic = Some(analytic::hertz_delta_max(mr, r, e_star, v));
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

/// The warnings on the pair's friction laws: a dashpot overdamping its spring, where
/// Luding's slip reset makes the friction fade (`docs/models.md`).
pub fn friction_warnings(spec: &CollideSpec) -> Vec<String> {
    let g = spec.geometry();
    crate::run::overdamped::law_warnings(&spec.model, &g, spec.velocity, "the pair")
}

/// The warnings on the pair's contact theory: λT below the JKR range, a0 beyond the
/// small-contact range ([`analytic::small_contact_warning`]), naming the pair by its radii.
pub fn theory_warnings(spec: &CollideSpec, tabor: f64, d_min: f64) -> Vec<String> {
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
    let small = match &spec.model {
        ContactModel::Jkr(p) => analytic::small_contact_warning(&pair, p, spec.geometry().r_eff()),
        _ => None,
    };
    analytic::tabor_warning(&pair, tabor, d_min)
        .into_iter()
        .chain(small)
        .collect()
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
