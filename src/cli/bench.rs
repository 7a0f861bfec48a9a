//! `powder bench`: throughput and GPU memory against N.

use super::*;
use powder::measure::bench::BenchOptions;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum BenchCase {
    /// Frictionless hysteretic packing.
    Hysteretic,
    /// JKR packing with friction and rolling resistance.
    Jkr,
    Both,
}

#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub(crate) struct BenchArgs {
    /// Particle counts, comma-separated (e.g. 1e3,1e4,1e5,1e6).
    #[arg(long, default_value_t = list_text(&BenchOptions::default().sizes))]
    sizes: String,
    /// Timed steps per size.
    #[arg(long, default_value_t = BenchOptions::default().steps)]
    steps: u64,
    /// Untimed warm-up steps before the timed ones.
    #[arg(long, default_value_t = BenchOptions::default().warmup)]
    warmup: u64,
    /// `auto`: a hardware GPU if there is one, else the CPU engine; `both` measures the CPU
    /// engine and the GPU engine (the software adapter where there is no GPU).
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendChoice,
    #[arg(long = "case", value_enum, default_value = "both")]
    case: BenchCase,
    /// Time budget per case and backend, s: a size predicted (from the previous size's
    /// rate) to take longer is skipped, and so are the larger ones.
    #[arg(long = "max-seconds", default_value_t = BenchOptions::default().max_seconds)]
    max_seconds: f64,
    /// Multiplies the packing's random velocities (more neighbour-list rebuilds).
    #[arg(long = "velocity-scale", default_value_t = BenchOptions::default().velocity_scale)]
    velocity_scale: f64,
    /// Seed of the packing's jitter and velocities.
    #[arg(long, default_value_t = BenchOptions::default().seed)]
    seed: u64,
    /// Keep the GPU energy ledger during the timed steps (off: the step's own cost).
    #[arg(long)]
    ledger: bool,
    /// After the timed steps, as many more with a GPU timestamp after every pass (which
    /// pass costs what on the device; windowed runs too).
    #[arg(long)]
    profile: bool,
    /// GPU quiet batches: batches without the per-step rebuild check where none is expected.
    #[arg(long = "quiet-batches", value_enum, default_value = "auto")]
    quiet_batches: QuietChoice,
    /// GPU: how the steps hold a neighbour-list rebuild (`on-demand`: a step records only
    /// the decision and halts its batch where one is due; `every-step`: every step records
    /// the rebuild's passes, empty where none is due). Bitwise the same results.
    #[arg(long = "rebuild-chain", value_enum, default_value = "on-demand")]
    rebuild_chain: ChainChoice,
    /// GPU: the software adapter's paths (texture mirrors of the state, quiet batches under
    /// `auto`): `on`, `off`, or `auto` by the adapter kind (results are bitwise the same).
    #[arg(long = "software-paths", value_enum, default_value = "auto")]
    software_paths: SoftwarePaths,
    /// GPU: particles a window holds (a power of two ≥ 64; default: one window where the
    /// arrays fit a binding, else the largest windows that fit). Bitwise the same results.
    #[arg(long = "window-particles")]
    window_particles: Option<u64>,
    /// Runs per case, backend and size (fresh engines); the table shows the fastest, the
    /// JSON every run's rate.
    #[arg(long, default_value_t = BenchOptions::default().repeats)]
    repeats: u32,
    /// CPU thread counts, comma-separated, each measured (0: every core); `1,2` shows the
    /// speed-up from 1 to 2 threads.
    #[arg(long, default_value_t = list_text(&BenchOptions::default().threads))]
    threads: String,
    /// Write the report (rows, machine, adapter, version, commit, date) as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

pub(crate) fn bench_cmd(a: &BenchArgs) -> Result<(), PowderError> {
    use powder::measure::bench::{self, Case};
    if let Some(path) = &a.json {
        powder::output::folder::check_output_file(path, "--json")?;
    }
    let opts = BenchOptions {
        sizes: bench::parse_sizes(&a.sizes)?,
        cases: match a.case {
            BenchCase::Hysteretic => vec![Case::Hysteretic],
            BenchCase::Jkr => vec![Case::Jkr],
            BenchCase::Both => vec![Case::Hysteretic, Case::Jkr],
        },
        backends: a.backend.list()?,
        steps: a.steps,
        warmup: a.warmup,
        max_seconds: a.max_seconds,
        velocity_scale: a.velocity_scale,
        seed: a.seed,
        ledger: a.ledger,
        quiet: a.quiet_batches.into(),
        rebuild_chain: a.rebuild_chain.into(),
        software_paths: a.software_paths.choice(),
        window_particles: a.window_particles,
        profile: a.profile,
        repeats: a.repeats,
        threads: bench_threads(&a.threads)?,
    };
    opts.validate()?;
    // (GPU-only options on a CPU-only bench change nothing: said, not silently dropped)
    if !opts
        .backends
        .contains(&powder::measure::collide::Backend::Gpu)
    {
        let gpu_only = [
            (a.profile, "--profile"),
            (a.ledger, "--ledger"),
            (a.window_particles.is_some(), "--window-particles"),
            (a.quiet_batches != QuietChoice::Auto, "--quiet-batches"),
        ];
        for (_, flag) in gpu_only.iter().filter(|(given, _)| *given) {
            eprintln!("notice: {flag} has no effect on the CPU backend (a GPU engine option)");
        }
        let cpu_unused = [
            (a.rebuild_chain != ChainChoice::OnDemand, "--rebuild-chain"),
            (a.software_paths != SoftwarePaths::Auto, "--software-paths"),
        ];
        for (_, flag) in cpu_unused.iter().filter(|(given, _)| *given) {
            eprintln!("notice: {flag} has no effect on the CPU backend (a GPU engine option)");
        }
    }
    if !opts
        .backends
        .contains(&powder::measure::collide::Backend::Cpu)
        && a.threads != list_text(&BenchOptions::default().threads)
    {
        eprintln!("notice: --threads has no effect on the GPU backend (a CPU engine option)");
    }
    println!("{}", bench::table_header());
    let report = bench::bench(&opts, |row| println!("{}", bench::table_line(row)))?;
    let p = &report.provenance;
    println!(
        "machine: {} ({} logical CPUs, {} usable, load average {} at the start); powder {}{}; {}",
        p.machine.cpu_model.as_deref().unwrap_or("unknown CPU"),
        p.machine
            .logical_cpus
            .map_or_else(|| "?".into(), |c| c.to_string()),
        p.machine.available_parallelism,
        p.machine
            .load_average
            .map_or_else(|| "?".into(), |l| format!("{l:.2}")),
        p.powder_version,
        p.git_commit
            .as_deref()
            .map_or_else(String::new, |c| format!(" ({c})")),
        p.date
    );
    if let Some(ad) = &report.adapter {
        println!(
            "adapter: {} ({}, {}, {} {})",
            ad.name, ad.backend, ad.device_type, ad.driver, ad.driver_info
        );
    }
    // (a size that failed or was skipped beside others that ran is the benchmark's finding;
    // none running is a failed command, which leaves an existing --json file as it was)
    if !report.rows.iter().any(|r| r.status == "ran") {
        let first = report.rows.first().and_then(|r| r.note.as_deref());
        let kept = a
            .json
            .as_ref()
            .map_or_else(String::new, |p| format!("; {} not written", p.display()));
        return Err(PowderError::Run(format!(
            "no size ran: every row was skipped or failed (the first: {}){kept}",
            first.unwrap_or("no reason given")
        )));
    }
    if let Some(path) = &a.json {
        write_json(path, &report)?;
    }
    Ok(())
}

/// `--threads` in the given order, a count that means one given before (0 is every core)
/// left out, so that no count is measured twice and each row's speed-up is over the first;
/// a count above the usable cores is measured, with a notice.
fn bench_threads(text: &str) -> Result<Vec<usize>, PowderError> {
    let usable = std::thread::available_parallelism().map_or(1, |n| n.get());
    let resolved = |t: usize| if t == 0 { usable } else { t };
    let mut out: Vec<usize> = Vec::new();
    for t in parse_threads(text)? {
        if t > usable {
            eprintln!(
                "notice: --threads {t} is more than the {usable} usable here (measured as asked)"
            );
        }
        if out.iter().any(|&o| resolved(o) == resolved(t)) {
            eprintln!("notice: --threads {t} is given twice (0 is every core, {usable} here): measured once");
        } else {
            out.push(t);
        }
    }
    Ok(out)
}
