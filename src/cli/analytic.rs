//! `powder analytic`: closed forms of the papers from the command line, without running a
//! collision (a module of the binary; the formulas live in `powder::model::analytic`).

use clap::{Arg, Args, Subcommand};
use powder::error::{fixed, num, require_positive};
use powder::model::flags::{ParamArgs, ParamSet};
use powder::model::params::{self as declared, Param};
use powder::model::{analytic, HystereticParams, JkrParams, PairGeometry};
use powder::{ParamError, PowderError};
use serde::Serialize;

#[derive(Args)]
pub struct AnalyticArgs {
    #[command(subcommand)]
    which: Which,
}

#[derive(Subcommand)]
enum Which {
    /// Paper 000 appendix A: the limit stiffness kp' that keeps the collisions below the
    /// old plastic limit when the plasticity depth grows from --phi-f to --phi-f-new (eq. A.3).
    KpPrime(KpPrimeArgs),
    /// Thornton-Ning restitution e_TN (paper 001 eq. 13) at given impact speeds, and
    /// e_pl = sqrt(e^2 - (1 - e_TN^2)) (eq. 14) for a restitution e without plasticity.
    ThorntonNing(ThorntonNingArgs),
    /// Tabor parameter of a JKR pair (paper 002 eq. 1) and the contact theory it selects.
    Tabor(TaborArgs),
}

/// The contact-law parameters each subcommand takes, as flags generated from their
/// declarations in `model::params` (flag, help, unit, rule).
struct HystereticStiffnesses;

impl ParamSet for HystereticStiffnesses {
    const PARAMS: &'static [&'static Param] = &[&declared::K1, &declared::KP, &declared::PHI_F];
}

/// E and ν of `thornton-ning --yield-stress`.
struct YieldMaterial;

impl ParamSet for YieldMaterial {
    const PARAMS: &'static [&'static Param] = &[&declared::YOUNGS, &declared::POISSON];

    fn adjust(arg: Arg, _p: &'static Param) -> Arg {
        let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
        arg.requires("yield_stress")
            .help(format!("{help} (with --yield-stress)"))
    }
}

/// E, ν and γ of `tabor`.
struct JkrMaterial;

impl ParamSet for JkrMaterial {
    const PARAMS: &'static [&'static Param] = &[
        &declared::YOUNGS,
        &declared::POISSON,
        &declared::SURFACE_ENERGY,
    ];
}

#[derive(Args)]
struct KpPrimeArgs {
    /// k1, kp and phi_f of the hysteretic law.
    #[command(flatten)]
    law: ParamArgs<HystereticStiffnesses>,
    /// The new plasticity depth phi_f' in (0, 1] (appendix A raises phi_f; eq. A.3 holds
    /// either way).
    #[arg(long = "phi-f-new")]
    phi_f_new: f64,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// The pair of spheres (or a sphere and a wall) of `thornton-ning` and `tabor`.
#[derive(Args)]
struct PairArgs {
    /// Radius of sphere 1, m.
    #[arg(long)]
    radius: Option<f64>,
    /// Radius of sphere 2, m (default: --radius).
    #[arg(long, conflicts_with = "wall")]
    radius2: Option<f64>,
    /// Sphere 1 against a plane of the same material.
    #[arg(long)]
    wall: bool,
}

impl PairArgs {
    /// R* (r for a wall) and the reduced mass at `density` (1 when none is needed).
    fn geometry(&self, density: f64) -> Result<PairGeometry, PowderError> {
        let r1 = self.radius.ok_or_else(|| {
            PowderError::from(ParamError::new("radius", "--radius is required here"))
        })?;
        require_positive("radius", r1, "the radius")?;
        let m = |r: f64| powder::scene::sphere_mass(density, r);
        if self.wall {
            return Ok(PairGeometry::wall(r1, m(r1)));
        }
        let r2 = require_positive("radius2", self.radius2.unwrap_or(r1), "the second radius")?;
        let g = PairGeometry::spheres(r1, r2, m(r1), m(r2));
        // (radii of subnormal size: R* = r1·r2/(r1 + r2) underflows or loses its digits; an
        // overflow is named by the result it makes infinite)
        if g.r_eff().is_nan() || g.r_eff() < f64::MIN_POSITIVE {
            return Err(ParamError::new(
                "radius2",
                format!(
                    "the reduced radius R* = r1·r2/(r1 + r2) of --radius {r1:e} and --radius2 {r2:e} comes out as {:e}, below what f64 holds; check their units",
                    g.r_eff()
                ),
            )
            .into());
        }
        Ok(g)
    }
}

#[derive(Args)]
#[command(group(clap::ArgGroup::new("yield").required(true).args(["yield_velocity", "yield_stress"])))]
struct ThorntonNingArgs {
    /// Normal impact speeds, m/s, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    velocity: Vec<f64>,
    /// Yield velocity v_Y, m/s.
    #[arg(long = "yield-velocity")]
    yield_velocity: Option<f64>,
    /// Yield stress Y, Pa: v_Y is the Hertz impact whose centre pressure reaches 1.6 Y
    /// (paper 001 sec. IV A 3); needs --youngs, --poisson, --density and the pair.
    #[arg(long = "yield-stress", requires_all = ["youngs", "poisson", "density", "radius"])]
    yield_stress: Option<f64>,
    /// Restitution e without plasticity (e.g. e of `powder collide`): one for every
    /// speed, or one per speed, comma-separated; adds e_pl.
    #[arg(long, value_delimiter = ',')]
    restitution: Vec<f64>,
    /// E and ν of the material (with --yield-stress).
    #[command(flatten)]
    material: ParamArgs<YieldMaterial>,
    /// Density, kg/m^3 (with --yield-stress).
    #[arg(long, requires = "yield_stress")]
    density: Option<f64>,
    #[command(flatten)]
    pair: PairArgs,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct TaborArgs {
    /// E, ν and γ of the JKR material.
    #[command(flatten)]
    material: ParamArgs<JkrMaterial>,
    #[command(flatten)]
    pair: PairArgs,
    /// D_min of eq. 1, in the unit of --radius (m in SI; default 1.65e-10, the paper's value
    /// in m).
    #[arg(long = "tabor-dmin")]
    tabor_dmin: Option<f64>,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// Runs `powder analytic`.
pub fn analytic_cmd(a: &AnalyticArgs) -> Result<(), PowderError> {
    match &a.which {
        Which::KpPrime(k) => kp_prime(k),
        Which::ThorntonNing(t) => thornton_ning(t),
        Which::Tabor(t) => tabor(t),
    }
}

/// `x`, or an error where the closed form overflowed (inputs each in range, but their
/// combination beyond f64).
fn finite(x: f64, what: &str) -> Result<f64, PowderError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(PowderError::Run(format!(
            "{what} comes out as {x}: the inputs, each in range, combine beyond what f64 holds; check their units"
        )))
    }
}

fn print_json<T: Serialize>(value: &T) -> Result<(), PowderError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
    println!("{text}");
    Ok(())
}

#[derive(Serialize)]
struct KpPrime {
    k1: f64,
    kp: f64,
    phi_f: f64,
    phi_f_new: f64,
    kp_prime: f64,
    /// δmax^p/a12 = kp/(kp − k1)·φf (eq. 10) before and after.
    delta_max_p_over_a12: [f64; 2],
}

fn kp_prime(a: &KpPrimeArgs) -> Result<(), PowderError> {
    let p = HystereticParams {
        k1: a.law.number(&declared::K1)?,
        kp: a.law.number(&declared::KP)?,
        phi_f: a.law.number(&declared::PHI_F)?,
        kc: 0.0,
        ..HystereticParams::paper_figure()
    };
    p.validate()?;
    if !declared::PHI_F.rule.holds(a.phi_f_new) {
        return Err(ParamError::new(
            "phi-f-new",
            format!(
                "the new plasticity depth --phi-f-new must be {}, got {}",
                declared::PHI_F.rule.requirement(a.phi_f_new),
                powder::error::num(a.phi_f_new)
            ),
        )
        .into());
    }
    // (kp = k1: no elastic limit, so no plasticity depth to tune; eq. A.3 divides by 0)
    if p.kp == p.k1 {
        return Err(ParamError::new(
            "kp",
            format!(
                "kp = k1 = {} N/m has no elastic limit (the contact stays on its plastic branch), so kp' for another phi_f is undefined: give kp > k1",
                p.k1
            ),
        )
        .into());
    }
    let kp_prime = finite(p.kp_for_phi_f(a.phi_f_new)?, "kp'")?;
    let tuned = HystereticParams {
        kp: kp_prime,
        phi_f: a.phi_f_new,
        ..p
    };
    let out = KpPrime {
        k1: p.k1,
        kp: p.kp,
        phi_f: p.phi_f,
        phi_f_new: a.phi_f_new,
        kp_prime,
        delta_max_p_over_a12: [
            finite(p.delta_max_p(1.0), "delta_max^p/a12")?,
            finite(tuned.delta_max_p(1.0), "delta_max^p/a12 after the change")?,
        ],
    };
    if a.json {
        return print_json(&out);
    }
    println!(
        "kp' = {} N/m (paper 000 eq. A.3: k1 = {}, kp = {} N/m, phi_f = {} -> {})",
        fixed(kp_prime, 6),
        num(p.k1),
        num(p.kp),
        num(p.phi_f),
        num(a.phi_f_new)
    );
    println!(
        "plastic limit overlap delta_max^p/a12 (eq. 10): {} -> {}",
        fixed(out.delta_max_p_over_a12[0], 6),
        fixed(out.delta_max_p_over_a12[1], 6)
    );
    Ok(())
}

#[derive(Serialize)]
struct ThorntonNingRow {
    velocity: f64,
    e_tn: f64,
    e: Option<f64>,
    e_pl: Option<f64>,
}

#[derive(Serialize)]
struct ThorntonNing {
    v_yield: f64,
    yield_stress: Option<f64>,
    rows: Vec<ThorntonNingRow>,
}

fn thornton_ning(a: &ThorntonNingArgs) -> Result<(), PowderError> {
    let v_yield = match (a.yield_velocity, a.yield_stress) {
        (Some(v), _) => require_positive("yield-velocity", v, "the yield velocity")?,
        (None, Some(y)) => {
            require_positive("yield-stress", y, "the yield stress")?;
            let (e, nu, rho) = (
                a.material.number(&declared::YOUNGS)?,
                a.material.number(&declared::POISSON)?,
                a.density.unwrap_or_default(),
            );
            let material = JkrParams::hertz(e, nu);
            material.validate()?;
            require_positive("density", rho, "the density")?;
            let g = a.pair.geometry(rho)?;
            finite(
                analytic::yield_velocity(y, material.e_star(), g.r_eff(), g.reduced_mass),
                "the yield velocity v_Y",
            )?
        }
        (None, None) => unreachable!("clap requires one of them"),
    };
    let n = a.velocity.len();
    if !(a.restitution.is_empty() || a.restitution.len() == 1 || a.restitution.len() == n) {
        return Err(ParamError::new(
            "restitution",
            format!(
                "--restitution needs one value or one per velocity ({n}), got {}",
                a.restitution.len()
            ),
        )
        .into());
    }
    let mut rows = Vec::with_capacity(n);
    for (k, &v) in a.velocity.iter().enumerate() {
        require_positive("velocity", v, "the impact speed")?;
        let e = a.restitution.get(k).or(a.restitution.first()).copied();
        if let Some(e) = e {
            if !(0.0..=1.0).contains(&e) {
                return Err(ParamError::new(
                    "restitution",
                    format!("the restitution e must be in [0, 1], got {e}"),
                )
                .into());
            }
        }
        let e_tn = finite(analytic::thornton_ning_restitution(v, v_yield), "e_TN")?;
        let e_pl = match e {
            Some(e) => Some(finite(analytic::plastic_restitution(e, e_tn), "e_pl")?),
            None => None,
        };
        rows.push(ThorntonNingRow {
            velocity: v,
            e_tn,
            e,
            e_pl,
        });
    }
    let out = ThorntonNing {
        v_yield,
        yield_stress: a.yield_stress.filter(|_| a.yield_velocity.is_none()),
        rows,
    };
    if a.json {
        return print_json(&out);
    }
    match out.yield_stress {
        Some(y) => println!(
            "yield velocity v_Y = {v_yield:.6e} m/s (Y = {y:e} Pa: the Hertz impact with centre pressure 1.6 Y, paper 001 sec. IV A 3)"
        ),
        None => println!("yield velocity v_Y = {v_yield:.6e} m/s"),
    }
    let with_e = !a.restitution.is_empty();
    if with_e {
        println!(
            "{:>12} {:>10} {:>10} {:>10}",
            "v (m/s)", "e_TN", "e", "e_pl"
        );
    } else {
        println!("{:>12} {:>10}", "v (m/s)", "e_TN");
    }
    for r in &out.rows {
        match (r.e, r.e_pl) {
            (Some(e), Some(e_pl)) => println!(
                "{:>12.5e} {:>10.6} {e:>10.6} {e_pl:>10.6}",
                r.velocity, r.e_tn
            ),
            _ => println!("{:>12.5e} {:>10.6}", r.velocity, r.e_tn),
        }
    }
    println!("e_TN: paper 001 eq. 13 (1 up to v_Y); e_pl = sqrt(e^2 - (1 - e_TN^2)): eq. 14");
    Ok(())
}

#[derive(Serialize)]
struct Tabor {
    r_eff: f64,
    d_min: f64,
    tabor: f64,
    regime: &'static str,
    jkr_range: bool,
}

fn tabor(a: &TaborArgs) -> Result<(), PowderError> {
    let p = JkrParams::jkr(
        a.material.number(&declared::YOUNGS)?,
        a.material.number(&declared::POISSON)?,
        a.material.number(&declared::SURFACE_ENERGY)?,
    );
    p.validate()?;
    let d_min = match a.tabor_dmin {
        Some(d) => require_positive("tabor-dmin", d, "D_min of the Tabor parameter")?,
        None => analytic::TABOR_MIN_SEPARATION,
    };
    let r_eff = a.pair.geometry(1.0)?.r_eff();
    let t = finite(analytic::jkr_tabor(&p, r_eff, d_min), "the Tabor parameter")?;
    let out = Tabor {
        r_eff,
        d_min,
        tabor: t,
        regime: analytic::tabor_regime(t),
        jkr_range: t > analytic::TABOR_JKR_MIN,
    };
    if a.json {
        return print_json(&out);
    }
    println!(
        "Tabor parameter {} at R* = {r_eff:e}, D_min = {d_min:e}: {} regime (paper 002 eq. 1; JKR above 3, DMT below 0.1)",
        fixed(t, 6),
        out.regime
    );
    Ok(())
}
