//! The collision's step loop: the approach, the stop and stick rules, the energy ledger
//! and the trace, on either engine.

use super::*;
use backends::CollisionRun;
use stop_rules::StopRules;

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
    let mut rules = StopRules::new(vn0, run.speed_noise());
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
    let mut hopeless = None;
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
        if unmet || run.steps() >= MAX_STEPS || hopeless.is_some() {
            // (no force outside contact pushes the pair apart: it closes at vn0 or faster)
            let what = if let Some(needs) = hopeless {
                // (where f32 speeds floor the decay's measured rate, the count is a bound)
                let about = match rules.projection_is_a_bound() {
                    true => "at least",
                    false => "about",
                };
                format!(
                    "cannot be decided within {MAX_STEPS} steps: after {} its approach decays so slowly that it needs {about} {needs:.1e} more to come to rest",
                    run.steps()
                )
            } else if touched {
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
        let (stop, needs) = rules.after_step(run.steps(), vn, contact);
        hopeless = needs;
        if stop && delta > -reach {
            delta_c = Some(delta);
            break;
        }
        // (a pair whose last step in range turned it back leaves still approaching: it
        // comes back, and the turn above finds it stuck)
        if rules.receding && vn < 0.0 && delta <= -reach && !neck {
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
                .map(|(a, b)| (b - a).abs() / ke0.max(ke1).max(dissipated.map_or(0.0, f64::abs))),
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

#[cfg(test)]
mod tests {
    use super::super::backends::PairView;
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
