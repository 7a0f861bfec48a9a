//! `powder collide`: two spheres head-on against the papers' closed forms.

use super::*;

#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub(crate) struct CollideArgs {
    /// The contact law and its parameters (declared in `model::params`).
    #[command(flatten)]
    law: LawArgs,
    /// Angle between the approach velocity and the tangent plane, degrees (90 = head-on).
    #[arg(long = "impact-angle", default_value_t = 90.0)]
    impact_angle: f64,
    /// Collide one sphere with a plane of the same material.
    #[arg(long)]
    wall: bool,
    /// A constant force on the sphere along the wall, N, in the direction of its
    /// tangential approach (+y, which a head-on impact also takes; paper 002 §5.3's F_ext;
    /// with --wall).
    #[arg(long = "tangential-force", default_value_t = 0.0)]
    tangential_force: f64,
    /// Seconds to go on after the sphere sticks, then tell whether it rests or rolls
    /// (`outcome` in --json).
    #[arg(long, default_value_t = 0.0)]
    settle: f64,
    /// Place the impulse of a force jump (JKR touch and pull-off) inside the step: true or
    /// false (plain velocity Verlet); default true, on both backends.
    #[arg(long = "jump-impulses", value_name = "BOOL")]
    jump_impulses: Option<bool>,
    /// Radius of sphere 1, m.
    #[arg(long)]
    radius: f64,
    /// Radius of sphere 2, m (default: --radius).
    #[arg(long, conflicts_with = "wall")]
    radius2: Option<f64>,
    /// Density, kg/m^3.
    #[arg(long)]
    density: f64,
    /// Relative approach speed, m/s.
    #[arg(long, required_unless_present = "sweep_velocity")]
    velocity: Option<f64>,
    /// Sweep the velocity: FROM:TO:N.
    #[arg(long = "sweep-velocity")]
    sweep_velocity: Option<String>,
    /// Logarithmic sweep spacing (and log velocity axis in --plot).
    #[arg(long)]
    log: bool,
    /// Draw e against v (and chi) with the closed form on top, as SVG; for a single
    /// --velocity of a JKR model (with surface energy) on the CPU backend: F/Fc and a/a0
    /// against delta/delta0 beside the JKR equilibrium curves.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Write every step of a single collision as CSV: t, delta, delta_dot, F, a, a_JKR(delta)
    /// (CPU backend).
    #[arg(long)]
    trace: Option<PathBuf>,
    /// Time step, s (default tc/50 on the stiffest branch).
    #[arg(long)]
    dt: Option<f64>,
    /// Accept a --dt above the stable limit.
    #[arg(long)]
    force: bool,
    #[arg(long, value_enum, default_value = "cpu")]
    backend: Backend,
    /// Print JSON on stdout (one object, or an array for a sweep).
    #[arg(long)]
    json: bool,
    // ---- reports beyond the collision ----
    /// JKR: D_min of the Tabor parameter (paper 002 eq. 1), in the unit of --radius (m in
    /// SI; default 1.65e-10, the paper's value in m).
    #[arg(long = "tabor-dmin")]
    tabor_dmin: Option<f64>,
    /// JKR/Hertz: yield velocity v_Y, m/s: adds the Thornton-Ning e_TN and
    /// e_pl = sqrt(e^2 - (1 - e_TN^2)) (paper 001 eqs. 13-14) beside e.
    #[arg(long = "yield-velocity", conflicts_with = "yield_stress")]
    yield_velocity: Option<f64>,
    /// JKR/Hertz: yield stress Y, Pa: v_Y is the Hertz impact whose centre pressure reaches
    /// 1.6 Y (paper 001 sec. IV A 3), then as --yield-velocity.
    #[arg(long = "yield-stress")]
    yield_stress: Option<f64>,
}

pub(crate) fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), |v| format!("{v:.6}"))
}

/// What `collide` reports beyond the collision, from `--tabor-dmin`, `--yield-velocity`
/// and `--yield-stress`.
pub(crate) struct CollideReport {
    /// D_min of the Tabor parameter.
    tabor_dmin: f64,
    /// Yield velocity of the Thornton-Ning estimate (given, or from the yield stress).
    v_yield: Option<f64>,
    /// The yield stress v_yield came from, if given.
    yield_stress: Option<f64>,
}

/// Checks the report options against the model (kept apart from `contact_model`).
pub(crate) fn collide_report(
    a: &CollideArgs,
    spec: &CollideSpec,
) -> Result<CollideReport, PowderError> {
    let model = &spec.model;
    let jkr = matches!(model, ContactModel::Jkr(p) if p.surface_energy > 0.0);
    let family = matches!(model, ContactModel::Jkr(_));
    let v_yield = match (a.yield_velocity, a.yield_stress) {
        (None, None) => None,
        _ if !family => {
            let name = if a.yield_velocity.is_some() {
                "yield-velocity"
            } else {
                "yield-stress"
            };
            return Err(ParamError::new(
                name,
                format!(
                    "--{} applies to --model jkr or hertz (Thornton-Ning, paper 001 eqs. 13-14; the hysteretic model has its own plasticity)",
                    name.replace('_', "-")
                ),
            )
            .into());
        }
        (Some(v), _) => Some(powder::error::require_positive(
            "yield-velocity",
            v,
            "the yield velocity (--yield-velocity)",
        )?),
        (None, Some(y)) => {
            let y = powder::error::require_positive(
                "yield-stress",
                y,
                "the yield stress (--yield-stress)",
            )?;
            let v = collide::yield_velocity(spec, y);
            derived_finite(
                v,
                "yield-stress",
                "the yield velocity v_Y from --yield-stress",
                true,
            )?
        }
    };
    let tabor_dmin = match a.tabor_dmin {
        Some(_) if !jkr => {
            return Err(ParamError::new(
                "tabor-dmin",
                "--tabor-dmin applies to --model jkr (the Tabor parameter of a JKR pair)",
            )
            .into())
        }
        Some(d) => powder::error::require_positive(
            "tabor-dmin",
            d,
            "D_min of the Tabor parameter (--tabor-dmin)",
        )?,
        None => powder::model::analytic::TABOR_MIN_SEPARATION,
    };
    // (the flag the user gave, else the inputs of (R*·γ²/(E*²·D_min³))^(1/3))
    let (param, what) = if a.tabor_dmin.is_some() {
        ("tabor-dmin", "the Tabor parameter at this --tabor-dmin")
    } else {
        (
            "surface-energy",
            "the Tabor parameter (R*·γ²/(E*²·D_min³))^(1/3) of --surface-energy, --youngs and --radius",
        )
    };
    derived_finite(collide::tabor(spec, tabor_dmin), param, what, false)?;
    Ok(CollideReport {
        tabor_dmin,
        v_yield,
        yield_stress: a.yield_stress,
    })
}

/// A value derived from in-range inputs that came out beyond f64 (JSON would write an
/// infinity as null), or at 0 where it must be positive.
fn derived_finite(
    x: Option<f64>,
    param: &'static str,
    what: &str,
    positive: bool,
) -> Result<Option<f64>, PowderError> {
    match x {
        Some(v) if !v.is_finite() || (positive && v <= 0.0) => Err(ParamError::new(
            param,
            format!(
                "{what} comes out as {v}: the inputs combine beyond what f64 holds; check their units"
            ),
        )
        .into()),
        _ => Ok(x),
    }
}

/// Adds the reports to the results, warns about a pair outside the JKR range and prints.
pub(crate) fn finish_collide(
    a: &CollideArgs,
    spec: &CollideSpec,
    report: &CollideReport,
    mut results: Vec<CollideResult>,
) -> Result<(), PowderError> {
    for r in &mut results {
        r.tabor = collide::tabor(spec, report.tabor_dmin);
        if let Some(vy) = report.v_yield {
            collide::add_plastic_restitution(spec, r, vy);
        }
    }
    // one pair for every velocity: one warning
    if let Some(t) = results.first().and_then(|r| r.tabor) {
        for w in collide::theory_warnings(spec, t, report.tabor_dmin) {
            eprintln!("warning: {w}");
        }
    }
    for w in collide::friction_warnings(spec) {
        eprintln!("warning: {w}");
    }
    // no contact law here adds energy: e above 1 on a dissipative law is the integrator's
    // error (beyond rounding: f32 on the GPU); an elastic law's e sits on either side of 1
    let rounding = |r: &CollideResult| if r.backend == "gpu" { 1e-6 } else { 1e-9 };
    let over = |r: &&CollideResult| r.e > 1.0 + rounding(r);
    if let Some(r) = results
        .iter()
        .find(over)
        .filter(|_| !spec.model.elastic_normal())
    {
        let dissipated = r
            .energy
            .dissipated
            .map_or("not kept".into(), |d| format!("{d:e} J"));
        eprintln!(
            "warning: e = {} > 1 at v = {:e} m/s (dissipated: {dissipated}): the time step's error (dt = {:e} s) exceeds what the law dissipates there; a smaller --dt brings e under 1",
            r.e, r.velocity, r.dt
        );
    }
    print_results(a, &results, report)
}

/// One column of the collide table: header, width and the cell of a result.
pub(crate) type Column = (&'static str, usize, fn(&CollideResult) -> String);

pub(crate) fn print_table(results: &[CollideResult], report: &CollideReport) {
    let mut columns: Vec<Column> = vec![
        ("v (m/s)", 12, |r| format!("{:.5e}", r.velocity)),
        ("chi", 9, |r| {
            r.chi.map_or_else(|| "-".into(), |c| format!("{c:.4}"))
        }),
        ("e", 10, |r| format!("{:.6}", r.e)),
    ];
    // only where some row has the value: the closed form applies head-on only, the
    // tangential restitution to oblique impacts only
    if results.iter().any(|r| r.e_analytic.is_some()) {
        columns.push(("e_analytic", 10, |r| fmt_opt(r.e_analytic)));
    }
    if results.iter().any(|r| r.e_tangential.is_some()) {
        columns.push(("e_t", 10, |r| fmt_opt(r.e_tangential)));
    }
    if results.iter().any(|r| r.e_tangential_analytic.is_some()) {
        columns.push(("e_t_analytic", 12, |r| fmt_opt(r.e_tangential_analytic)));
    }
    if report.v_yield.is_some() {
        columns.push(("e_TN", 10, |r| fmt_opt(r.e_tn)));
        columns.push(("e_pl", 10, |r| fmt_opt(r.e_pl)));
    }
    columns.extend([
        (
            "stuck",
            6,
            (|r| r.stuck.to_string()) as fn(&CollideResult) -> String,
        ),
        ("outcome", 9, |r| r.outcome.to_string()),
        ("delta_max", 12, |r| format!("{:.5e}", r.delta_max)),
        ("delta_c", 12, |r| {
            r.delta_c.map_or_else(|| "-".into(), |d| format!("{d:.5e}"))
        }),
        ("t_contact", 12, |r| {
            r.contact_duration
                .map_or_else(|| "-".into(), |t| format!("{t:.5e}"))
        }),
        ("steps", 9, |r| r.steps.to_string()),
        ("E_balance", 10, |r| {
            r.energy
                .balance_error
                .map_or_else(|| "-".into(), |b| format!("{b:.2e}"))
        }),
    ]);
    let line = |cells: Vec<String>| {
        let padded: Vec<String> = cells
            .iter()
            .zip(&columns)
            .map(|(c, (_, w, _))| format!("{c:>w$}"))
            .collect();
        println!("{}", padded.join(" "));
    };
    line(columns.iter().map(|c| c.0.to_string()).collect());
    for r in results {
        line(columns.iter().map(|c| (c.2)(r)).collect());
    }
    if let Some(r) = results.first() {
        match &r.adapter {
            Some(a) => println!("backend {} ({a}), dt = {:.4e} s", r.backend, r.dt),
            None => println!("backend {}, dt = {:.4e} s", r.backend, r.dt),
        }
        if let Some(t) = r.tabor {
            println!(
                "Tabor parameter {}: {} regime (paper 002 eq. 1, D_min = {:e}; JKR holds above 3)",
                powder::error::fixed(t, 4),
                powder::model::analytic::tabor_regime(t),
                report.tabor_dmin
            );
        }
        if let Some(vy) = report.v_yield {
            let from = report.yield_stress.map_or_else(String::new, |y| {
                format!(" (from Y = {y:e} Pa: Hertz centre pressure 1.6 Y)")
            });
            println!("yield velocity {vy:.6e} m/s{from}: e_TN, e_pl of paper 001 eqs. 13-14");
        }
    }
}

pub(crate) fn collide_cmd(a: &CollideArgs) -> Result<(), PowderError> {
    powder::output::folder::check_output_files(&[
        (a.plot.as_deref(), "--plot"),
        (a.trace.as_deref(), "--trace"),
    ])?;
    let model = a.law.contact_model()?;
    let spec = CollideSpec {
        model,
        radius1: a.radius,
        radius2: a.radius2.unwrap_or(a.radius),
        density: a.density,
        velocity: a.velocity.unwrap_or(1.0),
        dt: a.dt,
        force: a.force,
        wall: a.wall,
        impact_angle: a.impact_angle,
        jump_impulses: a.jump_impulses,
        tangential_force: a.tangential_force,
        settle: a.settle,
    };
    let report = collide_report(a, &spec)?;
    if let ContactModel::Jkr(p) = &spec.model {
        if let Some(note) = p.stiffness_scaling_report() {
            eprintln!("note: {note}");
        }
    }
    let single_jkr = a.sweep_velocity.is_none()
        && matches!(&spec.model, ContactModel::Jkr(p) if p.surface_energy > 0.0);
    if a.trace.is_some() || (a.plot.is_some() && single_jkr) {
        if a.sweep_velocity.is_some() {
            return Err(ParamError::new(
                "trace",
                "--trace records one collision: give --velocity, not --sweep-velocity",
            )
            .into());
        }
        let (result, rows) = collide::collide_traced_on(&spec, a.backend.collide()?)?;
        if let Some(path) = &a.trace {
            let mut text = String::from(collide::TraceRow::CSV_HEADER);
            text.push('\n');
            for row in &rows {
                text.push_str(&row.csv());
                text.push('\n');
            }
            powder::output::atomic::write_atomic(path, text.as_bytes())?;
            eprintln!("wrote {} ({} steps)", path.display(), rows.len());
        }
        if let Some(path) = &a.plot {
            match collide::trace_plot(&spec, &result, &rows) {
                Some(plot) => plot.write_svg(path)?,
                None => collide::restitution_plot(&spec, std::slice::from_ref(&result), a.log)
                    .write_svg(path)?,
            }
            eprintln!("wrote {}", path.display());
        }
        return finish_collide(a, &spec, &report, vec![result]);
    }
    let results = match &a.sweep_velocity {
        Some(text) => {
            if a.velocity.is_some() {
                return Err(ParamError::new(
                    "velocity",
                    "give either --velocity or --sweep-velocity, not both",
                )
                .into());
            }
            let vs = collide::sweep_velocities(text, a.log)?;
            spec.validate()?;
            collide::sweep_on(&spec, &vs, a.backend.collide()?)?
        }
        None => vec![collide::collide_on(&spec, a.backend.collide()?)?],
    };
    if let Some(path) = &a.plot {
        collide::restitution_plot(&spec, &results, a.log).write_svg(path)?;
        eprintln!("wrote {}", path.display());
    }
    finish_collide(a, &spec, &report, results)
}

pub(crate) fn print_results(
    a: &CollideArgs,
    results: &[CollideResult],
    report: &CollideReport,
) -> Result<(), PowderError> {
    if a.json {
        let text = if a.sweep_velocity.is_some() {
            serde_json::to_string_pretty(&results)
        } else {
            serde_json::to_string_pretty(&results[0])
        }
        .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
        println!("{text}");
    } else {
        print_table(results, report);
    }
    Ok(())
}
