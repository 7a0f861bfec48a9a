//! `powder accuracy`: error against run time over the time step.

use super::*;
use powder::measure::accuracy::AccuracyOptions;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum AccuracyCase {
    /// The hysteretic pair over a chi sweep against the closed forms.
    Pair,
    /// JKR pairs (both pull-off rules) from 1.05 to 5 times the sticking speed against
    /// the closed form.
    Jkr,
    /// A small cohesive packing against a fine-dt CPU reference.
    Packing,
    /// The hysteretic pair and the packing.
    Both,
    /// All three.
    All,
}

#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub(crate) struct AccuracyArgs {
    /// Time steps as divisors of the contact time tc: dt = tc/D, comma-separated (D >= 10).
    #[arg(long, default_value_t = list_text(&AccuracyOptions::default().divisors))]
    divisors: String,
    #[arg(long, value_enum, default_value = "both")]
    backend: BackendChoice,
    #[arg(long = "case", value_enum, default_value = "all")]
    case: AccuracyCase,
    /// Packing: the reference's divisor (CPU, f64, dt = tc/D); above every --divisors.
    #[arg(long = "reference-divisor", default_value_t = AccuracyOptions::default().reference_divisor)]
    reference_divisor: f64,
    /// Packing: particles (a lattice with random jitter and velocities).
    #[arg(long, default_value_t = AccuracyOptions::default().particles)]
    particles: usize,
    /// Packing: the physical time compared, a whole number of tc.
    #[arg(long = "packing-time", default_value_t = AccuracyOptions::default().packing_time)]
    packing_time: u64,
    /// Pair: points of the chi sweep (log-spaced over chi = 0.1 ... 5); jkr: of the
    /// velocity sweep (log-spaced over 1.05 ... 5 times the sticking speed).
    #[arg(long = "chi-points", default_value_t = AccuracyOptions::default().chi_points)]
    chi_points: usize,
    /// Write the report as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Draw the work-precision diagram (log-log error against wall time) as SVG.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub(crate) fn accuracy_cmd(a: &AccuracyArgs) -> Result<(), PowderError> {
    use powder::measure::accuracy;
    powder::output::folder::check_output_files(&[
        (a.json.as_deref(), "--json"),
        (a.plot.as_deref(), "--plot"),
    ])?;
    let opts = AccuracyOptions {
        divisors: accuracy::parse_divisors(&a.divisors)?,
        backends: a.backend.list()?,
        pair: matches!(
            a.case,
            AccuracyCase::Pair | AccuracyCase::Both | AccuracyCase::All
        ),
        jkr: matches!(a.case, AccuracyCase::Jkr | AccuracyCase::All),
        packing: matches!(
            a.case,
            AccuracyCase::Packing | AccuracyCase::Both | AccuracyCase::All
        ),
        reference_divisor: a.reference_divisor,
        particles: a.particles,
        packing_time: a.packing_time,
        chi_points: a.chi_points,
        seed: 1,
    };
    opts.validate()?;
    if let Some(plot) = &a.plot {
        if plot
            .extension()
            .is_none_or(|x| !x.eq_ignore_ascii_case("svg"))
        {
            eprintln!("notice: --plot {} is written as SVG", plot.display());
        }
    }
    println!(
        "{:<23} {:<4} {:>6} {:>11} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "case", "back", "dt/tc", "dt (s)", "steps", "wall s", "error", "max dx/r", "dE_kin"
    );
    let report = accuracy::accuracy(&opts, |p| {
        let opt = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |v| format!("{v:.3e}"));
        println!(
            "{:<23} {:<4} {:>6} {:>11.4e} {:>8} {:>10.3e} {:>10.3e} {:>10} {:>10}",
            p.case,
            p.backend,
            format!("1/{}", p.divisor),
            p.dt,
            p.steps,
            p.wall_seconds,
            p.error,
            opt(p.max_position_error),
            opt(p.kinetic_error)
        );
    })?;
    if let Some(pk) = &report.packing {
        println!(
            "packing: {} particles, T = {:.4e} s = {} tc (tc = {:.4e} s), reference CPU f64 at dt = tc/{} ({} steps, {:.2} s), {:.2} contacts per particle at T",
            pk.particles,
            pk.time,
            a.packing_time,
            pk.tc,
            pk.reference_divisor,
            pk.reference_steps,
            pk.reference_wall_seconds,
            pk.reference_contacts_per_particle
        );
    }
    if let Some(pr) = &report.pair {
        println!(
            "pair: hysteretic k1 = {}, kp = {}, kc = {} N/m, phi_f = {}, {} impacts over chi = {} ... {} (tc = {:.4e} s); error = max |e - e_closed|",
            pr.k1,
            pr.kp,
            pr.kc,
            pr.phi_f,
            pr.chi.len(),
            pr.chi[0],
            pr.chi[pr.chi.len() - 1],
            pr.tc
        );
    }
    if let Some(j) = &report.jkr {
        println!(
            "jkr: E = {} Pa, nu = {}, gamma = {} J/m^2, radius {} m, {} kg/m^3, {} impacts over {} ... {} times the sticking speed ({}) (tc = {:.4e} s); error = max |e - e_closed|; -verlet: the force jumps left to velocity Verlet",
            j.youngs,
            j.poisson,
            j.surface_energy,
            j.radius,
            j.density,
            j.rules[0].velocities.len(),
            accuracy::JKR_RANGE.0,
            accuracy::JKR_RANGE.1,
            j.rules
                .iter()
                .map(|r| format!("{:?}: {:.4} m/s", r.pulloff, r.sticking_velocity))
                .collect::<Vec<_>>()
                .join(", "),
            j.tc
        );
    }
    for n in &report.notes {
        println!("note: {n}");
    }
    if let Some(ad) = &report.adapter {
        println!(
            "adapter: {} ({}, {} {})",
            ad.name, ad.backend, ad.driver, ad.driver_info
        );
    }
    if let Some(path) = &a.plot {
        accuracy::work_precision_plot(&report).write_svg(path)?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = &a.json {
        write_json(path, &report)?;
    }
    Ok(())
}
