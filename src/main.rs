//! The `powder` command line: `run` a scene headless, `collide` two spheres.

use clap::{Args, Parser, Subcommand, ValueEnum};
use powder::collide::{self, CollideResult, CollideSpec};
use powder::model::flags::LawArgs;
use powder::model::ContactModel;
use powder::scene::Scene;
use powder::{ParamError, PowderError};
use std::path::PathBuf;
use std::process::ExitCode;

mod analytic_cmd;

#[derive(Parser)]
#[command(name = "powder", version, about = "DEM engine for cohesive powders")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene headless and print a summary.
    Run(RunArgs),
    /// Collide two spheres head-on and compare with the papers' closed forms.
    Collide(Box<CollideArgs>),
    /// Run a scene on both backends and report their deviations over time.
    Compare(CompareArgs),
    /// Show the GPU adapter the GPU engine would use (POWDER_ADAPTER overrides it).
    Info(InfoArgs),
    /// Measure particle-steps per second and GPU bytes per particle against N.
    Bench(BenchArgs),
    /// Error against run time (work-precision) over the time step, on both backends.
    Accuracy(AccuracyArgs),
    /// Closed forms without a simulation: kp' (paper 000 eq. A.3), Thornton-Ning e_TN and
    /// e_pl (paper 001 eqs. 13-14), the Tabor parameter (paper 002 eq. 1).
    Analytic(analytic_cmd::AnalyticArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BackendChoice {
    /// A hardware GPU if there is one, else the CPU engine (see `powder run --help`).
    Auto,
    Cpu,
    Gpu,
    Both,
}

/// The engine `--backend auto` picks (a hardware GPU, else the CPU), its reason on stderr.
fn auto_backend() -> Result<collide::Backend, PowderError> {
    let chosen = powder::backend::choose(powder::backend::BackendRequest::Auto)?;
    eprintln!("backend: {}", chosen.reason);
    Ok(match chosen.gpu {
        Some(_) => collide::Backend::Gpu,
        None => collide::Backend::Cpu,
    })
}

impl BackendChoice {
    fn list(self) -> Result<Vec<collide::Backend>, PowderError> {
        Ok(match self {
            BackendChoice::Auto => vec![auto_backend()?],
            BackendChoice::Cpu => vec![collide::Backend::Cpu],
            BackendChoice::Gpu => vec![collide::Backend::Gpu],
            BackendChoice::Both => vec![collide::Backend::Cpu, collide::Backend::Gpu],
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BenchCase {
    /// Frictionless hysteretic packing.
    Hysteretic,
    /// JKR packing with friction and rolling resistance.
    Jkr,
    Both,
}

#[derive(Args)]
#[command(allow_negative_numbers = true)]
struct BenchArgs {
    /// Particle counts, comma-separated (e.g. 1e3,1e4,1e5,1e6).
    #[arg(long, default_value = "1e3,1e4,1e5,1e6")]
    sizes: String,
    /// Timed steps per size.
    #[arg(long, default_value_t = 128)]
    steps: u64,
    /// Untimed warm-up steps before the timed ones.
    #[arg(long, default_value_t = 32)]
    warmup: u64,
    /// `auto`: a hardware GPU if there is one, else the CPU engine; `both` measures the CPU
    /// engine and the GPU engine (the software adapter where there is no GPU).
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendChoice,
    #[arg(long = "case", value_enum, default_value = "both")]
    case: BenchCase,
    /// Time budget per case and backend, s: a size predicted (from the previous size's
    /// rate) to take longer is skipped, and so are the larger ones.
    #[arg(long = "max-seconds", default_value_t = 120.0)]
    max_seconds: f64,
    /// Multiplies the packing's random velocities (more neighbour-list rebuilds).
    #[arg(long = "velocity-scale", default_value_t = 1.0)]
    velocity_scale: f64,
    /// Seed of the packing's jitter and velocities.
    #[arg(long, default_value_t = 1)]
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
    #[arg(long, default_value_t = 1)]
    repeats: u32,
    /// CPU thread counts, comma-separated, each measured (0: every core); `1,2` shows the
    /// speed-up from 1 to 2 threads.
    #[arg(long, default_value = "0")]
    threads: String,
    /// Write the report (rows, machine, adapter, version, commit, date) as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// `--software-paths` (`GpuOptions::software_paths`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum SoftwarePaths {
    /// By the adapter kind.
    Auto,
    /// The software adapter's paths on any adapter.
    On,
    /// The GPU's paths on any adapter.
    Off,
}

impl SoftwarePaths {
    fn choice(self) -> Option<bool> {
        match self {
            Self::Auto => None,
            Self::On => Some(true),
            Self::Off => Some(false),
        }
    }
}

/// `--quiet-batches`: how the GPU engine uses quiet batches (`powder::gpu::QuietBatches`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum QuietChoice {
    /// Every batch checks each step whether to rebuild the neighbour lists.
    Off,
    /// On a software adapter, batches run without the per-step check where no rebuild is
    /// expected, and again with it where one was needed (results bitwise the same); on a
    /// GPU as `off` (the copies they need cost as much memory as the state).
    Auto,
    /// Every batch tries to run without the check (diagnostics).
    Always,
}

impl From<QuietChoice> for powder::gpu::QuietBatches {
    fn from(q: QuietChoice) -> Self {
        match q {
            QuietChoice::Off => Self::Off,
            QuietChoice::Auto => Self::Auto,
            QuietChoice::Always => Self::Always,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum AccuracyCase {
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
struct AccuracyArgs {
    /// Time steps as divisors of the contact time tc: dt = tc/D, comma-separated (D >= 10).
    #[arg(long, default_value = "10,20,50,100,200,400")]
    divisors: String,
    #[arg(long, value_enum, default_value = "both")]
    backend: BackendChoice,
    #[arg(long = "case", value_enum, default_value = "all")]
    case: AccuracyCase,
    /// Packing: the reference's divisor (CPU, f64, dt = tc/D); above every --divisors.
    #[arg(long = "reference-divisor", default_value_t = 800.0)]
    reference_divisor: f64,
    /// Packing: particles (a lattice with random jitter and velocities).
    #[arg(long, default_value_t = 216)]
    particles: usize,
    /// Packing: the physical time compared, in units of tc.
    #[arg(long = "packing-time", default_value_t = 20)]
    packing_time: u64,
    /// Pair: points of the chi sweep (log-spaced over chi = 0.1 ... 5); jkr: of the
    /// velocity sweep (log-spaced over 1.05 ... 5 times the sticking speed).
    #[arg(long = "chi-points", default_value_t = 8)]
    chi_points: usize,
    /// Write the report as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Draw the work-precision diagram (log-log error against wall time) as SVG.
    #[arg(long)]
    plot: Option<PathBuf>,
}

fn write_json<T: serde::Serialize>(path: &std::path::Path, value: &T) -> Result<(), PowderError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
    powder::output::atomic::write_atomic(path, text.as_bytes())?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Parses `--threads`: comma-separated thread counts (0: every core).
fn parse_threads(text: &str) -> Result<Vec<usize>, PowderError> {
    text.split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse().map_err(|_| {
                powder::ParamError::new(
                    "threads",
                    format!("`{t}` is not a thread count; expected e.g. 1,2 (0: every core)"),
                )
                .into()
            })
        })
        .collect()
}

fn bench_cmd(a: &BenchArgs) -> Result<(), PowderError> {
    use powder::bench::{self, BenchOptions, Case};
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
        software_paths: a.software_paths.choice(),
        window_particles: a.window_particles,
        profile: a.profile,
        repeats: a.repeats,
        threads: parse_threads(&a.threads)?,
    };
    opts.validate()?;
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
    if let Some(path) = &a.json {
        write_json(path, &report)?;
    }
    Ok(())
}

#[derive(Args)]
struct InfoArgs {
    /// A scene: list the GPU kernels and buffers it uses and the bytes per particle.
    scene: Option<PathBuf>,
    /// Print the adapter summary as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// With a scene: run its GPU step with a timestamp after every pass and print the
    /// device time of each (µs a step), as `powder bench --profile` does for the bench
    /// packings.
    #[arg(long, requires = "scene")]
    profile: bool,
    /// With --profile: run this many steps first (profile a settled state, not the
    /// initial one).
    #[arg(long, default_value_t = 0, requires = "profile")]
    after: u64,
    /// With --profile: the steps profiled.
    #[arg(long, default_value_t = 64, requires = "profile")]
    profile_steps: u64,
    /// Build the GPU engine without its energy ledger (as `powder run --no-ledger`).
    #[arg(long, requires = "scene")]
    no_ledger: bool,
    /// Change a scene value, KEY=VALUE, as `powder run --set` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", requires = "scene")]
    set: Vec<String>,
}

/// What the GPU engine builds for a scene (`powder info SCENE`).
#[derive(serde::Serialize)]
struct SceneInfo {
    scene: String,
    adapter: String,
    particles: usize,
    step_variant: String,
    kernels: Vec<String>,
    rotation: bool,
    /// The particle state's fields (one buffer, `powder::gpu::state`).
    state_fields: Vec<String>,
    /// (kernel, storage buffers it binds), the most first.
    storage_bindings: Vec<(String, u32)>,
    /// (field, bytes) of a list entry (`powder::gpu::records`).
    entry_fields: Vec<(String, u64)>,
    list_entries: u64,
    /// (particles a window, windows): `powder::gpu::window`.
    windows: (u64, u64),
    buffers: Vec<(String, u64)>,
    total_bytes: u64,
    bytes_per_particle: f64,
    /// What each pass of the step binds and the bytes per particle-step it adds up to
    /// without rebuilds (`powder::gpu::traffic`, an upper bound).
    traffic: powder::gpu::TrafficEstimate,
    /// With --profile: the device time of each pass, after `profile_after` steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    profile: Option<powder::gpu::timestamps::PassProfile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    profile_after: Option<u64>,
}

fn scene_info(
    path: &std::path::Path,
    ctx: powder::gpu::GpuContext,
    a: &InfoArgs,
) -> Result<SceneInfo, PowderError> {
    let scene = Scene::load_with(path, &a.set)?;
    let adapter = ctx.summary.name.clone();
    let options = powder::gpu::GpuOptions {
        ledger: !a.no_ledger,
        ..Default::default()
    };
    let mut engine = powder::gpu::GpuEngine::with_options(&scene, ctx, options)?;
    let variant_name = engine.variant_name();
    let mut kernels = vec![
        "grid: clear_counts, cell_keys, count, scan, scatter, sort_within_cells, sort_large_cells"
            .to_string(),
    ];
    // the kernels built for this scene (not every entry point of the variant)
    kernels.extend(engine.kernel_names());
    let total = engine.buffer_bytes();
    let (buffers, particles) = (engine.buffers(), engine.len());
    let (rotation, list_entries) = (engine.rotates(), engine.list_entries());
    let windows = (engine.windows().len, engine.windows().count);
    let state_fields = engine
        .state_fields()
        .iter()
        .map(|f| f.to_string())
        .collect();
    let storage_bindings = engine.storage_bindings();
    let entry_fields = engine
        .entry_fields()
        .into_iter()
        .map(|(f, b)| (f.to_string(), b))
        .collect();
    let traffic = powder::gpu::TrafficEstimate::new(engine.traffic(), particles, 0, 0);
    let profile = if a.profile {
        engine.run_steps(a.after)?;
        Some(engine.profile(a.profile_steps)?)
    } else {
        None
    };
    Ok(SceneInfo {
        scene: scene.name.clone(),
        adapter,
        particles,
        step_variant: variant_name,
        kernels,
        rotation,
        state_fields,
        storage_bindings,
        entry_fields,
        list_entries,
        windows,
        buffers,
        total_bytes: total,
        bytes_per_particle: total as f64 / particles.max(1) as f64,
        traffic,
        profile_after: a.profile.then_some(a.after),
        profile,
    })
}

fn info_cmd(a: &InfoArgs) -> Result<(), PowderError> {
    let ctx = match a.profile {
        true => powder::gpu::GpuContext::with_timestamps()?,
        false => powder::gpu::GpuContext::new()?,
    };
    if let Some(path) = &a.scene {
        let info = scene_info(path, ctx, a)?;
        if a.json {
            let text = serde_json::to_string_pretty(&info)
                .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
            println!("{text}");
            return Ok(());
        }
        println!(
            "scene            {} ({} particles) on {}",
            info.scene, info.particles, info.adapter
        );
        println!(
            "step variant     {} (rotation {})",
            info.step_variant,
            if info.rotation { "on" } else { "off" }
        );
        println!("kernels          {}", info.kernels.join(", "));
        println!("state fields     {}", info.state_fields.join(", "));
        let entry: Vec<String> = info
            .entry_fields
            .iter()
            .map(|(f, b)| format!("{f} {b}"))
            .collect();
        println!("entry fields     {} (bytes)", entry.join(", "));
        if let Some((pass, most)) = info.storage_bindings.first() {
            println!("storage buffers  at most {most} a pass ({pass})");
        }
        println!(
            "list entries     {} ({:.2} a particle, after the first rebuild)",
            info.list_entries,
            info.list_entries as f64 / info.particles as f64
        );
        println!(
            "windows          {} of {} particles (each window's dispatches bind it and its neighbours)",
            info.windows.1, info.windows.0
        );
        println!("buffers:");
        for (name, bytes) in &info.buffers {
            println!("  {name:<20} {bytes:>14} bytes");
        }
        println!(
            "total            {} bytes = {:.1} bytes per particle",
            info.total_bytes, info.bytes_per_particle
        );
        let t = &info.traffic;
        println!(
            "traffic          {:.0} bytes per particle a step, {:.0} more on a rebuild (bound by its passes: an upper bound)",
            t.step_bytes_per_particle, t.rebuild_bytes_per_particle
        );
        if let Some(p) = &info.profile {
            let steps = p.steps.max(1) as f64;
            println!(
                "passes (µs a step over {} steps after {}, {} rebuilds; device {:.1} of {:.1} µs a step):",
                p.steps,
                info.profile_after.unwrap_or(0),
                p.rebuilds,
                p.device_seconds_per_step() * 1e6,
                p.wall_seconds / steps * 1e6
            );
            for (name, s) in &p.passes {
                println!("  {name:<20} {:>12.1}", s / steps * 1e6);
            }
        }
        return Ok(());
    }
    if a.json {
        let text = serde_json::to_string_pretty(&ctx.summary)
            .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
        println!("{text}");
    } else {
        println!("{}", ctx.summary);
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// A hardware GPU if there is one, else the CPU engine on every core (the software
    /// adapter only when asked for: `--backend gpu`, or `POWDER_ADAPTER` set).
    Auto,
    /// The f64 CPU reference engine.
    Cpu,
    /// The wgpu engine (every model; the same outputs, checkpoints and run monitor).
    Gpu,
}

impl Backend {
    fn collide(self) -> Result<collide::Backend, PowderError> {
        Ok(match self {
            Backend::Auto => auto_backend()?,
            Backend::Cpu => collide::Backend::Cpu,
            Backend::Gpu => collide::Backend::Gpu,
        })
    }

    fn request(self) -> powder::backend::BackendRequest {
        use powder::backend::BackendRequest as R;
        match self {
            Backend::Auto => R::Auto,
            Backend::Cpu => R::Cpu,
            Backend::Gpu => R::Gpu,
        }
    }
}

#[derive(Args)]
struct RunArgs {
    /// Scene file (TOML); see the README for the schema. Without one, the built-in
    /// cohesive cluster (examples/cohesive_cluster.toml) runs.
    scene: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "auto")]
    backend: Backend,
    /// Stop after this many steps in total (default: the scene's duration).
    #[arg(long)]
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
    /// Run the GPU engine without its energy ledger (about 20 % of the GPU step, and 32
    /// bytes per neighbour slot): stored and dissipated energy, the energy balance, contact
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
    // ---- reports (issue 14) ----
    /// D_min of the Tabor parameter (paper 002 eq. 1) in the scene's length unit, default
    /// 1.65e-10 (m, the paper's value). The summary lists lambda_T of every JKR pair of
    /// materials; a pair below the JKR range (lambda_T <= 3) is warned about on stderr.
    #[arg(long = "tabor-dmin")]
    tabor_dmin: Option<f64>,
    /// GPU: particles a window holds (a power of two ≥ 64; default: one window where the
    /// arrays fit a binding, else the largest windows that fit). Bitwise the same results.
    #[arg(long = "window-particles")]
    window_particles: Option<u64>,
}

#[derive(Args)]
struct CompareArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Steps to run (default: the scene's duration, at most 2000).
    #[arg(long)]
    steps: Option<u64>,
    /// Steps between samples (default: steps/10).
    #[arg(long)]
    every: Option<u64>,
    /// A threshold, KEY=VALUE with KEY one of position (over the smallest radius, default
    /// 1e-3), velocity (over the largest speed, 1e-2), kinetic (relative, 1e-2), contacts
    /// (relative count difference, 0.05), energy (stored and dissipated energy difference
    /// over the energy in play, 1e-2), history (δmax, tangential spring, rolling
    /// displacement of the common contacts, relative, 1e-2); repeatable.
    #[arg(long = "tolerance", value_name = "KEY=VALUE")]
    tolerance: Vec<String>,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
#[command(allow_negative_numbers = true)]
struct CollideArgs {
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
    /// tangential approach (paper 002 §5.3's F_ext; with --wall).
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
    #[arg(long)]
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
    // ---- reports beyond the collision (issue 14) ----
    /// JKR: D_min of the Tabor parameter (paper 002 eq. 1) in the unit of --radius,
    /// default 1.65e-10 (m, the paper's value).
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

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), |v| format!("{v:.6}"))
}

/// What `collide` reports beyond the collision, from the options of issue 14.
struct CollideReport {
    /// D_min of the Tabor parameter.
    tabor_dmin: f64,
    /// Yield velocity of the Thornton-Ning estimate (given, or from the yield stress).
    v_yield: Option<f64>,
    /// The yield stress v_yield came from, if given.
    yield_stress: Option<f64>,
}

/// Checks the report options against the model (kept apart from `contact_model`).
fn collide_report(a: &CollideArgs, spec: &CollideSpec) -> Result<CollideReport, PowderError> {
    let model = &spec.model;
    let jkr = matches!(model, ContactModel::Jkr(p) if p.surface_energy > 0.0);
    let family = matches!(model, ContactModel::Jkr(_));
    let v_yield = match (a.yield_velocity, a.yield_stress) {
        (None, None) => None,
        _ if !family => {
            let name = if a.yield_velocity.is_some() {
                "yield_velocity"
            } else {
                "yield_stress"
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
            "yield_velocity",
            v,
            "the yield velocity (--yield-velocity)",
        )?),
        (None, Some(y)) => {
            let y = powder::error::require_positive(
                "yield_stress",
                y,
                "the yield stress (--yield-stress)",
            )?;
            collide::yield_velocity(spec, y)
        }
    };
    let tabor_dmin = match a.tabor_dmin {
        Some(_) if !jkr => {
            return Err(ParamError::new(
                "tabor_dmin",
                "--tabor-dmin applies to --model jkr (the Tabor parameter of a JKR pair)",
            )
            .into())
        }
        Some(d) => powder::error::require_positive(
            "tabor_dmin",
            d,
            "D_min of the Tabor parameter (--tabor-dmin)",
        )?,
        None => powder::model::analytic::TABOR_MIN_SEPARATION,
    };
    Ok(CollideReport {
        tabor_dmin,
        v_yield,
        yield_stress: a.yield_stress,
    })
}

/// Adds the reports to the results, warns about a pair outside the JKR range and prints.
fn finish_collide(
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
        if let Some(w) = collide::tabor_warning(spec, t, report.tabor_dmin) {
            eprintln!("warning: {w}");
        }
    }
    print_results(a, &results, report)
}

/// One column of the collide table: header, width and the cell of a result.
type Column = (&'static str, usize, fn(&CollideResult) -> String);

fn print_table(results: &[CollideResult], report: &CollideReport) {
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
                "Tabor parameter {t:.4}: {} regime (paper 002 eq. 1, D_min = {:e}; JKR holds above 3)",
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

fn collide_cmd(a: &CollideArgs) -> Result<(), PowderError> {
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
            std::fs::write(path, text)
                .map_err(|e| PowderError::io(format!("cannot write {}", path.display()), e))?;
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

fn print_results(
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

fn accuracy_cmd(a: &AccuracyArgs) -> Result<(), PowderError> {
    use powder::accuracy::{self, AccuracyOptions};
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

/// Runs `compare`; `Ok(false)` when a threshold was exceeded.
fn compare_cmd(a: &CompareArgs) -> Result<bool, PowderError> {
    use powder::compare::{compare, Tolerances};
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
    let c = compare(&scene, ctx, steps, every, tol)?;
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
            "{:>7} {:>10} {:>9} {:>9} {:>9} {:>5} {:>5} {:>10} {:>10} {:>9} {:>9} {:>9}  exceeded",
            "step",
            "t (s)",
            "pos/rmin",
            "vel/vmax",
            "rel.Ekin",
            "Zcpu",
            "Zgpu",
            "δ cpu",
            "E_dis cpu",
            "rel.E",
            "history",
            "pairs"
        );
        for s in &c.samples {
            println!(
                "{:>7} {:>10.3e} {:>9.2e} {:>9.2e} {:>9.2e} {:>5} {:>5} {:>10.3e} {:>10.3e} {:>9.2e} {:>9.2e} {:>9}  {}",
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
                s.exceeded.join(",")
            );
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
    }
    Ok(c.passed)
}

/// Set when `run` stopped on Ctrl-C (exit status 130, as shells report SIGINT).
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// The scene runs without a file: the cohesive cluster of examples/.
const DEFAULT_SCENE: &str = include_str!("../examples/cohesive_cluster.toml");

fn run_cmd(a: &RunArgs) -> Result<(), PowderError> {
    let threads = powder::cpu::Threads::new(a.threads)?;
    let scene = match &a.scene {
        Some(path) => Scene::load_with(path, &a.set)?,
        None => {
            eprintln!("no scene given: running the built-in cohesive cluster (examples/cohesive_cluster.toml)");
            Scene::from_toml_str(
                &powder::overrides::apply(DEFAULT_SCENE, &a.set)?,
                "cohesive_cluster",
            )?
        }
    };
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
    let interrupt = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let flag = interrupt.clone();
        // a second Ctrl-C while the first is being handled is ignored: the checkpoint
        // being written must not be cut
        let _ = ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed));
    }
    let out_dir = if a.no_output {
        None
    } else {
        Some(
            a.out
                .clone()
                .unwrap_or_else(|| PathBuf::from("out").join(&scene.name)),
        )
    };
    if let Some(d) = &out_dir {
        std::fs::create_dir_all(d).map_err(|e| {
            PowderError::io(
                format!("cannot create the output directory `{}`", d.display()),
                e,
            )
        })?;
    }
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
        backend_reason: Some(chosen.reason),
        no_snapshots: a.no_snapshots,
    };
    let summary = match gpu {
        Some(ctx) => powder::run::run_gpu_with(&scene, ctx, &opts, |_| {})?,
        None => {
            if a.no_ledger {
                // accepted so one command line serves both backends (and the fallback)
                eprintln!("notice: --no-ledger has no effect on the CPU backend, which always keeps its energy ledger (it costs little there)");
            }
            powder::run::run_cpu_with(&scene, &opts, |_| {})?
        }
    };
    if summary.interrupted {
        INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
        eprintln!(
            "interrupted at step {}: checkpoint written to {}/checkpoint.bin; resume with --resume",
            summary.steps,
            summary
                .out_dir
                .as_deref()
                .unwrap_or("(no output directory)")
        );
    }
    if a.json {
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| PowderError::Run(format!("cannot encode JSON: {e}")))?;
        println!("{text}");
        return Ok(());
    }
    print_summary(&summary);
    Ok(())
}

/// What a run without the energy ledger prints for what only the ledger knows.
const NO_LEDGER: &str = "n/a (--no-ledger)";

/// The human-readable summary of `powder run`.
fn print_summary(summary: &powder::run::RunSummary) {
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
        "wall time        {:.2} s ({:.3e} particle-steps/s)",
        summary.wall_seconds, summary.particle_steps_per_second
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
        println!(
            "outputs          {d}/ ({}.pvd{contacts} for ParaView, series.csv, checkpoint.bin, summary.json)",
            summary.scene
        );
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
fn print_tabor(pairs: &[powder::run::TaborPair]) {
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run_cmd(a),
        Command::Collide(a) => collide_cmd(a),
        Command::Info(a) => info_cmd(a),
        Command::Bench(a) => bench_cmd(a),
        Command::Accuracy(a) => accuracy_cmd(a),
        Command::Analytic(a) => analytic_cmd::analytic_cmd(a),
        Command::Compare(a) => match compare_cmd(a) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::from(1),
            Err(e) => Err(e),
        },
    };
    match result {
        Ok(()) if INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed) => ExitCode::from(130),
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
