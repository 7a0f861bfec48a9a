//! `powder run`: a scene headless, with its summary.

use super::*;

#[derive(Args)]
pub(crate) struct RunArgs {
    /// Scene file (TOML); see the README for the schema. Without one, the built-in
    /// cohesive cluster (examples/cohesive_cluster.toml) runs.
    scene: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "auto")]
    backend: Backend,
    /// Stop after at most this many steps in total (the scene's duration ends the run
    /// sooner where it comes first; default: the duration), >= 1.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    steps: Option<u64>,
    /// CPU engine threads (0: every core); the results are bitwise the same on any count.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output directory: VTK snapshots (and the contact network) with .pvd collections for
    /// ParaView, series.csv, checkpoint.bin, summary.json (default: out/<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write no output files.
    #[arg(long, conflicts_with_all = ["out", "resume"])]
    no_output: bool,
    /// Write no VTK snapshots (nor the contact network): series.csv, checkpoint.bin and
    /// summary.json only.
    #[arg(long, conflicts_with = "no_output")]
    no_snapshots: bool,
    /// Replace an earlier run's outputs in the output directory (a fresh run), or the
    /// results beyond the checkpoint's step (a resume): without it, such a run is refused
    /// before anything there changes.
    #[arg(long, conflicts_with = "no_output")]
    overwrite: bool,
    /// Resume from a checkpoint of the same scene (bitwise identical continuation), or of a
    /// scene that changes only its duration, output cadences or the wall phases from the
    /// checkpoint's time on (a branch: docs/checkpoints.md).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Change a scene value, KEY=VALUE with KEY a dotted path (particles[0].count,
    /// domain.max, simulation.duration) and VALUE a TOML value; repeatable. Scales the
    /// examples up without editing them.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Run the GPU engine without its energy ledger (less device memory and time): stored
    /// and dissipated energy, the energy balance, contact
    /// statistics and wall forces are then absent (empty CSV cells, keys left out of the
    /// JSON), and the run monitor has no energy-growth check. A checkpoint resumes only in
    /// a run with the same choice. The CPU backend always keeps its (cheap) ledger and
    /// says it ignores the flag.
    #[arg(long)]
    no_ledger: bool,
    /// GPU quiet batches: batches without the per-step neighbour-list rebuild check where
    /// the forecast expects no rebuild, run again with it where one was needed; the results
    /// are bitwise the same whatever the choice.
    #[arg(long = "quiet-batches", value_enum, default_value = "auto")]
    quiet_batches: QuietChoice,
    // ---- reports ----
    /// D_min of the Tabor parameter (paper 002 eq. 1), in the scene's length unit like every
    /// length (m in SI; default 1.65e-10, the paper's value in m). The summary lists lambda_T of every JKR pair of
    /// materials; a pair below the JKR range (lambda_T <= 3) is warned about on stderr.
    #[arg(long = "tabor-dmin")]
    tabor_dmin: Option<f64>,
    /// GPU: particles a window holds (a power of two ≥ 64; default: one window where the
    /// arrays fit a binding, else the largest windows that fit). Bitwise the same results.
    #[arg(long = "window-particles")]
    window_particles: Option<u64>,
}

/// Set when `run` stopped on a signal (exit status [`super::exit_status`]).
pub(crate) static INTERRUPTED: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// The scene runs without a file: the cohesive cluster of examples/.
pub(crate) const DEFAULT_SCENE: &str = include_str!("../../examples/cohesive_cluster.toml");

pub(crate) fn run_cmd(a: &RunArgs) -> Result<(), PowderError> {
    // (first: every thread started after this blocks the stop signals; one taken during
    // set-up ends the process at once, as it would have by default)
    let interrupt = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    super::stop_signals::install(interrupt.clone());
    let threads = powder::cpu::Threads::new(a.threads)?;
    // (the reader's placement check runs on the threads asked for)
    let scene = threads.install_all(|| match &a.scene {
        Some(path) => Scene::load_with(path, &a.set),
        None => {
            eprintln!("no scene given: running the built-in cohesive cluster (examples/cohesive_cluster.toml)");
            Scene::from_toml_str_with(DEFAULT_SCENE, "cohesive_cluster", &a.set)
        }
    })?;
    // auto resumes a checkpoint on the backend that wrote it
    let request = match (&a.resume, a.backend) {
        (Some(path), Backend::Auto) => match powder::checkpoint::backend_of(path)?.as_str() {
            "gpu" => powder::backend::BackendRequest::Gpu,
            _ => powder::backend::BackendRequest::Cpu,
        },
        _ => a.backend.request(),
    };
    let mut chosen = powder::backend::choose(request)?;
    if a.resume.is_some() && a.backend == Backend::Auto {
        chosen.reason = format!(
            "--backend auto resumes on the checkpoint's backend ({})",
            chosen.reason
        );
    }
    eprintln!("backend: {}", chosen.reason);
    let gpu = chosen.gpu;
    let out_dir = if a.no_output {
        None
    } else {
        Some(
            a.out
                .clone()
                .unwrap_or_else(|| PathBuf::from("out").join(&scene.name)),
        )
    };
    // (the folders this command creates are removed again where the run fails before
    // writing)
    let created = match &out_dir {
        Some(d) => create_out_dir(d)?,
        None => Vec::new(),
    };
    let summary = run_in(a, scene, gpu, out_dir, interrupt, threads, chosen.reason);
    if summary.is_err() {
        // (innermost first, each only where empty: remove_dir refuses a folder with files)
        for d in &created {
            if std::fs::remove_dir(d).is_err() {
                break;
            }
        }
    }
    let summary = summary?;
    if summary.interrupted {
        INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
        match summary.out_dir.as_deref() {
            Some(dir) => eprintln!(
                "interrupted at step {}: checkpoint written to {dir}/checkpoint.bin; resume with --resume",
                summary.steps
            ),
            None => eprintln!(
                "interrupted at step {}: no checkpoint (--no-output writes none)",
                summary.steps
            ),
        }
    }
    if a.json {
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
        println!("{text}");
        return Ok(());
    }
    print_summary(&summary, !a.no_snapshots);
    Ok(())
}

/// The run itself, once the scene, backend and folder are settled.
fn run_in(
    a: &RunArgs,
    scene: Scene,
    gpu: Option<powder::gpu::GpuContext>,
    out_dir: Option<PathBuf>,
    interrupt: std::sync::Arc<std::sync::atomic::AtomicBool>,
    threads: powder::cpu::Threads,
    reason: String,
) -> Result<powder::run::RunSummary, PowderError> {
    let opts = powder::run::RunOptions {
        out_dir,
        resume: a.resume.clone(),
        max_steps: a.steps,
        progress_bar: std::io::IsTerminal::is_terminal(&std::io::stderr()),
        verbose: true,
        interrupt: Some(interrupt),
        gpu: powder::gpu::GpuOptions {
            ledger: !a.no_ledger,
            quiet: a.quiet_batches.into(),
            window_particles: a.window_particles,
            ..Default::default()
        },
        tabor_dmin: a.tabor_dmin,
        threads,
        backend_reason: Some(reason),
        no_snapshots: a.no_snapshots,
        overwrite: a.overwrite,
        copy_every: None,
    };
    // (the first progress call comes when the set-up is done: stop signals stop the run
    // gracefully from then on)
    let begun = |_: &powder::run::Snapshot| super::stop_signals::running();
    match gpu {
        Some(ctx) => powder::run::run_gpu_with(&scene, ctx, &opts, begun),
        None => {
            if a.no_ledger {
                // accepted so one command line serves both backends (and the fallback)
                eprintln!("notice: --no-ledger has no effect on the CPU backend, which always keeps its energy ledger (it costs little there)");
            }
            if let Some(w) = a.window_particles {
                eprintln!("notice: --window-particles {w} has no effect on the CPU backend (the GPU engine's windows)");
            }
            if a.quiet_batches != QuietChoice::Auto {
                eprintln!("notice: --quiet-batches has no effect on the CPU backend (the GPU engine's batches)");
            }
            powder::run::run_cpu_with(&scene, &opts, begun)
        }
    }
}

/// What a run without the energy ledger prints for what only the ledger knows.
pub(crate) const NO_LEDGER: &str = "n/a (--no-ledger)";

/// The human-readable summary of `powder run` (`snapshots`: the run wrote them).
pub(crate) fn print_summary(summary: &powder::run::RunSummary, snapshots: bool) {
    let l = &summary.last;
    println!("scene            {}", summary.scene);
    println!(
        "backend          {}{} ({} particles)",
        summary.backend,
        summary
            .adapter
            .as_ref()
            .map(|a| format!(": {a}"))
            .unwrap_or_default(),
        summary.particles
    );
    println!(
        "dt               {:.4e} s ({})",
        summary.dt, summary.dt_rule
    );
    println!(
        "steps            {} (t = {:.4e} s)",
        summary.steps, summary.time
    );
    println!(
        "wall time        {:.2} s ({:.3e} particle-steps/s; {:.2} s stepping, the rest reading back, checking and writing)",
        summary.wall_seconds, summary.particle_steps_per_second, summary.stepping_seconds
    );
    let e = &l.energies;
    let ledger = |v: Option<f64>| v.map_or(NO_LEDGER.to_string(), |v| format!("{v:.4e}"));
    println!(
        "energies (J)     kinetic {:.4e}, elastic {}, gravitational {:.4e}, dissipated {}",
        e.kinetic,
        ledger(e.elastic),
        e.gravitational,
        ledger(e.dissipated)
    );
    match summary.energy_balance_error {
        Some(b) => println!("energy balance   {b:.3e} (relative)"),
        None => println!("energy balance   {NO_LEDGER}"),
    }
    match &l.contacts {
        Some(c) => {
            println!(
                "contacts         {} particle-particle, {} wall, {} non-contact; {:.3} per particle",
                c.contacts, c.wall_contacts, c.non_contact, c.coordination
            );
            println!(
                "overlap          max {:.4e} m (max δ/a12 {:.4e}, mean δ/a12 {:.4e})",
                c.max_overlap, c.max_overlap_ratio, c.mean_overlap_ratio
            );
        }
        None => {
            println!("contacts         {NO_LEDGER}");
            println!("overlap          {NO_LEDGER}");
        }
    }
    println!(
        "solid fraction   {:.4} of the domain, {:.4} of the particles' bounding box",
        summary.solid_fraction_domain, summary.solid_fraction_bounding_box
    );
    match &summary.wall_forces {
        Some(forces) => {
            for (w, f) in forces.iter().enumerate() {
                println!(
                    "wall {w} force     ({:.4e}, {:.4e}, {:.4e}) N",
                    f[0], f[1], f[2]
                );
            }
        }
        None => println!("wall forces      {NO_LEDGER}"),
    }
    if let Some(d) = &summary.out_dir {
        let contacts = if summary.contact_network {
            format!(" and {}_contacts.pvd", summary.scene)
        } else {
            String::new()
        };
        let paraview = if snapshots {
            format!("{}.pvd{contacts} for ParaView, ", summary.scene)
        } else {
            String::new()
        };
        println!("outputs          {d}/ ({paraview}series.csv, checkpoint.bin, summary.json)");
    }
    if summary.outside_domain > 0 {
        println!(
            "warning          {} particles ended outside the domain box",
            summary.outside_domain
        );
    }
    print_tabor(&summary.tabor);
    for note in &summary.notes {
        println!("note             {note}");
    }
}

/// The Tabor parameters of a run's JKR pairs (paper 002 eq. 1), one line each.
pub(crate) fn print_tabor(pairs: &[powder::run::TaborPair]) {
    for (k, t) in pairs.iter().enumerate() {
        println!(
            "{:<17}{} (R* = {:.4e}): {:.4} ({}{}, D_min = {:e})",
            if k == 0 { "tabor" } else { "" },
            t.label(),
            t.r_eff,
            t.tabor,
            powder::model::analytic::tabor_regime(t.tabor),
            if t.jkr_range {
                ""
            } else {
                ", below the JKR range > 3"
            },
            t.d_min
        );
    }
}

/// Creates the output folder `d` a component at a time: the folders it created, innermost
/// first (a `..` resolves against the folders as they are then: `x/../y/z` with `x` new
/// and `y` there creates `x` and `y/z`, and only those).
fn create_out_dir(d: &std::path::Path) -> Result<Vec<PathBuf>, PowderError> {
    let mut created: Vec<PathBuf> = Vec::new();
    let mut at = PathBuf::new();
    let failed = |created: &mut Vec<PathBuf>, e: std::io::Error| {
        for c in created.iter().rev() {
            let _ = std::fs::remove_dir(c);
        }
        PowderError::io(
            format!("cannot create the output directory `{}`", d.display()),
            e,
        )
    };
    for c in d.components() {
        at.push(c);
        if matches!(c, std::path::Component::Normal(_)) && !at.exists() {
            match std::fs::create_dir(&at) {
                Ok(()) => created.push(at.clone()),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(failed(&mut created, e)),
            }
        }
    }
    if !d.is_dir() {
        let e = std::io::Error::other("it exists and is not a folder");
        return Err(failed(&mut created, e));
    }
    created.reverse();
    Ok(created)
}
