//! The collision's figures: e(v) against the closed form, and a traced F(δ), a(δ).

use super::*;
use crate::output::plot::{Legend, Plot, Series, Style};

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
    // (the equilibrium curve ends at the turning point; a `crack` contact reaches beyond)
    let dmin = p
        .pulloff_overlap(r)
        .max(crate::model::jkr::D_PULLOFF_DISPLACEMENT * d0)
        / d0;
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
            colour: None,
        },
        Series {
            label: format!("F/Fc, powder collide ({})", p.dissipation.name()),
            points: inside
                .iter()
                .map(|row| (row.delta / d0, row.force / fc))
                .collect(),
            style: Style::Line,
            colour: None,
        },
        Series {
            label: "a/a0, JKR equilibrium (paper 001 eq. 5)".into(),
            points: curve.iter().map(|c| (c.0, c.2)).collect(),
            style: Style::DashedLine,
            colour: None,
        },
        Series {
            label: format!("a/a0, powder collide ({})", p.dissipation.name()),
            points: inside
                .iter()
                .map(|row| (row.delta / d0, row.a / a0))
                .collect(),
            style: Style::Line,
            colour: None,
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
            colour: None,
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
                colour: None,
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
        colour: None,
    });
    let x_label = match scale {
        Some(vp) => format!("scaled impact velocity chi = v/vp  (vp = {vp:.4} m/s)"),
        None => "impact velocity v (m/s)".into(),
    };
    Plot {
        title: format!(
            "Coefficient of restitution, {} model",
            spec.model.law_name()
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
