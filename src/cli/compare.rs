//! `powder compare`: one scene on both backends, side by side.

use super::*;

#[derive(Args)]
pub(crate) struct CompareArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Steps to run, >= 1 (default: the scene's duration, at most 2000).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    steps: Option<u64>,
    /// Steps between samples, >= 1 (default: steps/10).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// A threshold, KEY=VALUE with KEY one of position (over the smallest radius, default
    /// 1e-3), velocity (over the largest speed, 1e-2), kinetic (relative, 1e-2), contacts
    /// (relative count difference, 0.05), energy (stored and dissipated energy difference
    /// over the energy in play, 1e-2), history (δmax, tangential spring, rolling
    /// displacement of the common contacts, relative, 1e-2); repeatable.
    #[arg(long = "tolerance", value_name = "KEY=VALUE")]
    tolerance: Vec<String>,
    /// Also run the CPU reference from positions moved by SIZE × each radius (default 1e-6:
    /// a force-balanced cohesive cluster separates from the reference on the GPU's f32 as
    /// fast as with 1e-6, a falling cloud as with 1e-7) and judge each measure only until that
    /// run separates beyond a tenth of its tolerance: the scene's chaos horizon, past which
    /// no run that differs by rounding can follow the reference.
    #[arg(long, value_name = "SIZE", num_args = 0..=1, default_missing_value = "1e-6")]
    perturbed: Option<f64>,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// Runs `compare`; `Ok(false)` when a threshold was exceeded.
pub(crate) fn compare_cmd(a: &CompareArgs) -> Result<bool, PowderError> {
    use powder::measure::compare::{compare_perturbed, Tolerances, CHAOS_MARGIN};
    let mut tol = Tolerances::default();
    for t in &a.tolerance {
        let bad = || {
            PowderError::from(ParamError::new(
                "tolerance",
                format!("`{t}` is not KEY=VALUE with KEY position, velocity, kinetic, contacts, energy or history and VALUE >= 0"),
            ))
        };
        let (key, value) = t.split_once('=').ok_or_else(bad)?;
        let value: f64 = value.trim().parse().map_err(|_| bad())?;
        if value.is_nan() || value < 0.0 {
            return Err(bad());
        }
        match key.trim() {
            "position" => tol.position = value,
            "velocity" => tol.velocity = value,
            "kinetic" => tol.kinetic = value,
            "contacts" => tol.contacts = value,
            "energy" => tol.energy = value,
            "history" => tol.history = value,
            _ => return Err(bad()),
        }
    }
    let scene = Scene::load(&a.scene)?;
    let ctx = powder::gpu::GpuContext::new()?;
    let total = powder::setup::Resolved::new(&scene)
        .map(|r| ((scene.duration / r.dt).ceil() as u64).clamp(1, 2000))?;
    let steps = a.steps.unwrap_or(total);
    let every = a.every.unwrap_or((steps / 10).max(1));
    let c = compare_perturbed(&scene, ctx, steps, every, tol, a.perturbed)?;
    if a.json {
        let text = serde_json::to_string_pretty(&c)
            .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
        println!("{text}");
    } else {
        println!(
            "compare `{}`: {} particles, dt = {:.4e} s, CPU (f64) against GPU ({})",
            c.scene, c.particles, c.dt, c.adapter
        );
        println!(
            "{:>7} {:>10} {:>9} {:>9} {:>9} {:>12} {:>12} {:>10} {:>10} {:>9} {:>9} {:>9}  exceeded",
            "step",
            "t (s)",
            "pos/rmin",
            "vel/vmax",
            "rel.Ekin",
            "contacts cpu",
            "contacts gpu",
            "δ cpu",
            "E_dis cpu",
            "rel.E",
            "history",
            "pairs"
        );
        for s in &c.samples {
            println!(
                "{:>7} {:>10.3e} {:>9.2e} {:>9.2e} {:>9.2e} {:>12} {:>12} {:>10.3e} {:>10.3e} {:>9.2e} {:>9.2e} {:>9}  {}",
                s.step,
                s.time,
                s.position,
                s.velocity,
                s.kinetic,
                s.contacts_cpu,
                s.contacts_gpu,
                s.max_overlap_cpu,
                s.dissipated_cpu,
                s.energy,
                s.history,
                s.history_pairs,
                s.exceeded.join(","),
            );
            // the perturbed reference's own deviations, under the GPU's
            if let Some(f) = &s.floor {
                println!(
                    "{:>7} {:>10} {:>9.2e} {:>9.2e} {:>9.2e} {:>12} {:>12} {:>10} {:>10} {:>9.2e} {:>9.2e} {:>9}  {}",
                    "",
                    "perturbed",
                    f["position"],
                    f["velocity"],
                    f["kinetic"],
                    "",
                    format!("Δ {:.2e}", f["contacts"]),
                    "",
                    "",
                    f["energy"],
                    f["history"],
                    "",
                    match s.chaotic.is_empty() {
                        true => String::new(),
                        false => format!("not judged: {}", s.chaotic.join(",")),
                    }
                );
            }
        }
        let t = &c.tolerances;
        println!(
            "thresholds: position {:e}, velocity {:e}, kinetic {:e}, contacts {:e}, energy {:e}, history {:e} -> {}",
            t.position,
            t.velocity,
            t.kinetic,
            t.contacts,
            t.energy,
            t.history,
            if c.passed { "PASS" } else { "FAIL" }
        );
        let no_contact =
            |s: &powder::measure::compare::Sample| s.contacts_cpu + s.contacts_gpu == 0;
        if !c.samples.is_empty() && c.samples.iter().all(no_contact) {
            println!(
                "note: no sample held a contact on either engine: only free flight was compared; run more --steps (or sample with --every) to compare the contact laws"
            );
        }
        if let Some(p) = c.perturbation {
            let from: Vec<String> = (c.horizon.iter())
                .map(|(name, step)| format!("{name} from step {step}"))
                .collect();
            println!(
                "chaos horizon (a CPU run from positions moved by {p:e} of each radius beyond 1/{CHAOS_MARGIN} of a tolerance): {}",
                match from.is_empty() {
                    true => "not reached; every measure judged at every sample".to_string(),
                    false => from.join(", "),
                }
            );
            if !c.never_judged.is_empty() {
                println!(
                    "never judged (past the horizon at the first sample), so no pass: {}; sample sooner (--every), or leave a measure out with --tolerance KEY=inf",
                    c.never_judged.join(", ")
                );
            }
        }
    }
    Ok(c.passed)
}
