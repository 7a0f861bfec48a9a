//! `powder info`: the adapter, and what the GPU engine builds for a scene (with `--profile`, what each pass costs).

use super::*;

#[derive(Args)]
pub(crate) struct InfoArgs {
    /// A scene: list the GPU kernels and buffers it uses and the bytes per particle.
    scene: Option<PathBuf>,
    /// Print as JSON on stdout: the adapter summary, or with a scene its kernels and
    /// buffers report.
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
    #[arg(long, default_value_t = 64, requires = "profile", value_parser = clap::value_parser!(u64).range(1..))]
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
pub(crate) struct SceneInfo {
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
    /// Buffers the lists' entries are in (`powder::gpu::pages`; 1 without pages).
    entry_pages: u64,
    /// Buffers each of the particle state's two is in (1 without pages).
    state_pages: u64,
    /// Compute dispatches a step records, without and with a rebuild's passes
    /// (`GpuEngine::dispatches_per_step`).
    dispatches_per_step: [usize; 2],
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

pub(crate) fn scene_info(
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
    let entry_pages = engine.entry_pages().count;
    let state_pages = engine.state_pages().count;
    let dispatches_per_step = engine.dispatches_per_step();
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
        entry_pages,
        state_pages,
        dispatches_per_step,
        buffers,
        total_bytes: total,
        bytes_per_particle: total as f64 / particles.max(1) as f64,
        traffic,
        profile_after: a.profile.then_some(a.after),
        profile,
    })
}

pub(crate) fn info_cmd(a: &InfoArgs) -> Result<(), PowderError> {
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
        if info.entry_pages > 1 {
            println!(
                "entry pages      {} (the lists' entries beyond the largest buffer)",
                info.entry_pages
            );
        }
        let [plain, full] = info.dispatches_per_step;
        println!(
            "dispatches       {plain} a step, {full} in a step that rebuilds the lists (every window's)"
        );
        if info.state_pages > 1 {
            println!(
                "state pages      {} each of `state` and `motion` (beyond the largest buffer)",
                info.state_pages
            );
        }
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
