//! Building an engine for a scene: its composition, pipelines, buffers and bind groups, and the first lists and forces.

use super::*;
use crate::gpu::records::{
    ROWS_B_COUNT, ROWS_B_ROW, ROWS_LOWER_COUNT, ROWS_LOWER_ROW, ROWS_REGION_COUNT,
};

/// The scans that place a rebuild's new lists (counts into first entries): two a window,
/// the pair lists' and `lower`'s, over the window's block of `rows`; each window's counts
/// of its `n` particles (one window) or `len` (several: the last one's counts beyond n
/// stay 0).
fn list_scans(
    ctx: &GpuContext,
    rows: &wgpu::Buffer,
    (windows, n): (&Windows, u32),
) -> Result<Vec<ExclusiveScan>, PowderError> {
    let scan_program = Program::with_entry_points(
        ctx,
        &crate::gpu::shaders::stage("grid").expect("grid is a stage"),
        Some(&["scan_blocks", "scan_add"]),
    )?;
    let scanned = if windows.count == 1 {
        n
    } else {
        windows.len as u32
    };
    let region = windows.len as u32;
    let mut scans = Vec::new();
    for w in 0..windows.count {
        // (window w's block of `rows`: B's counts and rows, then `lower`'s)
        let block = 4 * ROWS_REGION_COUNT as u64 * windows.len;
        let part = match windows.count {
            1 => Part::whole(rows),
            _ => Part {
                buffer: rows,
                offset: w * block,
                size: Some(block),
            },
        };
        for (count, row) in [
            (ROWS_B_COUNT, ROWS_B_ROW),
            (ROWS_LOWER_COUNT, ROWS_LOWER_ROW),
        ] {
            scans.push(ExclusiveScan::with_parts(
                ctx,
                &scan_program,
                (part, count * region),
                (part, row * region),
                scanned,
            )?);
        }
    }
    Ok(scans)
}

/// Quiet batches' state (`gpu::quiet`): copies of the state set (the ledger's rows with
/// it), and of the lists' history (`quiet.lists`: `quiet_copies`), with the buffers'
/// names and sizes.
fn quiet_batches(
    device: &wgpu::Device,
    mode: QuietBatches,
    state: &StateSet,
    (new_lists, entries): (&NewLists, u64),
    skin: f64,
) -> (Quiet, Vec<(String, u64)>) {
    // copies of buffers that fit
    let mut alloc = Allocator::new(device, u64::MAX);
    let mut copies = Vec::new();
    let own = [
        ("state", Some(&state.state[0])),
        ("motion", Some(&state.motion[0])),
    ];
    for (name, b) in own {
        if let Some(b) = b {
            let copy = alloc.buffer(&format!("quiet.{name}"), b.size());
            copies.push(Saved::whole(b, copy));
        }
    }
    let lists = new_lists.quiet_lists(&mut alloc, (entries, state.layout.windows()));
    let q = Quiet {
        mode,
        copies,
        lists,
        forecast: Forecast::new(skin),
        // the initial forces build the lists once
        rebuilds: 1,
        kept: 0,
        rolled_back: 0,
    };
    (q, alloc.list)
}

/// The force pass's read-only texture copies of what it loads per pair (`gpu::mirror`):
/// the cells, offsets, predictions (and angular predictions) of `state`, on the software
/// adapter's path only (none otherwise).
fn state_mirrors(
    device: &wgpu::Device,
    state: &StateSet,
    (n, software): (u32, bool),
) -> Result<Mirrors, PowderError> {
    if !software {
        return Mirrors::new(device, n, &[]);
    }
    let at = |name: &str| state.layout.place(name).map_or(0, |(_, at)| at);
    let (sint, float) = (
        wgpu::TextureFormat::Rgba32Sint,
        wgpu::TextureFormat::Rgba32Float,
    );
    let s = &state.state[0];
    let mut mirrored = vec![
        ("m_cell", Some("m_cell_out"), s, at("cell"), sint),
        ("m_off", Some("m_off_out"), s, at("off"), float),
        ("m_vpred", None, s, at("vpred"), float),
    ];
    if let Some((_, w)) = state.layout.place("wpred") {
        mirrored.push(("m_wpred", None, s, w, float));
    }
    Mirrors::new(device, n, &mirrored)
}

/// The neighbour grid's cell widths (m) and counts per axis for `n` particles whose pairs
/// reach at most `cutoff` (skin included): cells at least `cutoff` wide, about four
/// particles a cell.
fn cell_grid(scene: &Scene, n: usize, cutoff: f64) -> Result<(DVec3, [u32; 3]), PowderError> {
    let extent = DVec3::from_array(scene.domain.max) - DVec3::from_array(scene.domain.min);
    let target_cells = (4 * n).max(64) as f64;
    let h0 = gpu_cell_width(
        cutoff.max((extent.x * extent.y * extent.z / target_cells).cbrt()) * (1.0 + 1e-6),
    );
    // A periodic axis holds a whole number of cells, at least 3 (so the 27 cells around
    // a particle are distinct and a pair meets one image): its cells are period/count
    // wide, rounded to f32, so the device's period is dims·h (within 2^-24 of the
    // scene's; docs/architecture.md).
    let periodic = scene.domain.periodic;
    let mut h = DVec3::splat(h0);
    let mut dims = [0u32; 3];
    for a in 0..3 {
        if periodic[a] {
            let count = (extent[a] / (cutoff * (1.0 + 1e-6))).floor();
            if count < 3.0 {
                return Err(PowderError::Scene(format!(
                    "the domain is {:.4e} m long along the periodic axis {}, shorter than 3 interaction cut-offs plus the Verlet skin ({:.4e} m): a pair would meet two periodic images; enlarge [domain] or make the axis non-periodic",
                    extent[a],
                    ["x", "y", "z"][a],
                    3.0 * cutoff
                )));
            }
            let count = count.min((extent[a] / h0).ceil()).max(3.0);
            h[a] = gpu_cell_width(extent[a] / count);
            dims[a] = count as u32;
        } else {
            dims[a] = ((extent[a] / h0).ceil() as u32).clamp(1, 1 << 20);
        }
    }
    Ok((h, dims))
}

impl GpuEngine {
    /// Uploads the scene and builds the pipelines, with the energy ledger.
    pub fn new(scene: &Scene, ctx: GpuContext) -> Result<Self, PowderError> {
        Self::with_options(scene, ctx, GpuOptions::default())
    }

    /// Uploads the scene and builds the pipelines the options ask for.
    pub fn with_options(
        scene: &Scene,
        ctx: GpuContext,
        options: GpuOptions,
    ) -> Result<Self, PowderError> {
        Self::build(scene, ctx, options, None)
    }

    /// `with_options`; `measured`: the list entries a first build in one automatic window
    /// needed, over one binding (the windows are then chosen for them).
    pub(super) fn build(
        scene: &Scene,
        ctx: GpuContext,
        options: GpuOptions,
        measured: Option<u64>,
    ) -> Result<Self, PowderError> {
        let ledger = options.ledger;
        let r = Resolved::new(scene)?;
        let n = scene.particles.len();
        // (a list entry's partner has bit 31 free: `WALL_ENTRY`)
        if n as u64 >= WALL_ENTRY as u64 {
            return Err(PowderError::Run(format!(
                "{n} particles: the GPU engine numbers at most {} (2^31 − 1)",
                WALL_ENTRY - 1
            )));
        }
        let all_models: Vec<ContactModel> =
            r.models.iter().chain(&r.wall_models).copied().collect();
        let keeps = Keeps::new(
            ledger,
            places_jumps(scene, &all_models, r.r_max),
            options.contacts,
        );
        let (kind, pairs) = pair_table(&all_models);
        debug_assert_eq!(kind.rotation(), r.rotation);
        check_f32_range(scene, &r, (&pairs, &kind), ledger)?;
        let r_min = scene
            .particles
            .iter()
            .map(|p| p.radius)
            .fold(f64::INFINITY, f64::min);
        let skin = SKIN * r_min;
        let origin = DVec3::from_array(scene.domain.min);
        let extent = DVec3::from_array(scene.domain.max) - origin;
        let cutoff = 2.0 * r.r_max + r.max_reach + skin;
        let (h, dims) = cell_grid(scene, n, cutoff)?;
        let mut grid =
            GridSort::with_cell_widths(&ctx, n as u32, dims, [h.x as f32, h.y as f32, h.z as f32])?;
        let n_walls = scene.walls.len() as u64;
        let layout0 = StateLayout::new(0, kind.state_extras(keeps));
        let state_fields = layout0.count(Buffer::State);
        let windows = plan_windows(
            &ctx,
            &options,
            (&layout0, kind.records(keeps)),
            n as u64,
            measured,
        )?;
        grid.set_windows(&ctx.queue, &windows, state_fields as u32);
        let device = &ctx.device;
        let mut alloc = Allocator::new(device, ctx.max_storage_binding());
        alloc.list = grid_sizes(&grid);
        let Storage {
            entries,
            pages,
            state_pages,
            largest,
        } = Storage::plan(&ctx, &options, (&kind, keeps), (n as u64, &windows))?;
        let windowing = WindowBindings::new(&ctx.device, windows, pages, state_pages);
        let servo_walls = scene.walls.iter().any(|w| w.motion.servo());
        let state = StateSet::new(
            &mut alloc,
            (n as u64, entries, windows, [pages, state_pages]),
            &kind,
            keeps,
        );
        let new_lists = NewLists::new(&kind, keeps);
        let dt32 = r.dt as f32;
        // the per-particle buffers fit before the initial state is written into them
        alloc.check(n)?;
        let initial = InitialState::new(scene, &r, (origin, h, dims), dt32);
        let q0 = &ctx.queue;
        for b in Buffer::ALL {
            write_pages(
                q0,
                state.buffer(b),
                &state.layout.pack(b, &|f| initial.field(f)),
            );
        }
        let moving_walls = scene.walls.iter().any(|w| w.motion.moves());
        let step = step_params(scene, &r, (extent, h, dims), (entries, skin));
        let active: Vec<bool> = scene.particles.iter().map(|p| p.insert_at <= 0.0).collect();
        let small = SceneBuffers::upload(
            (&mut alloc, q0),
            scene,
            (&step, &pairs, &active),
            (origin, h),
            &windows,
        );
        let software = software_paths(&options, &ctx, &windows, n)?;
        let constants = pipeline_constants(scene, &r, &all_models);
        let spec = StepSpec {
            wanted: wanted_kernels(scene),
            constants,
            mirrors: software,
        };
        let program = spec.compile(&ctx, (&kind, keeps), pages.paged() || state_pages.paged())?;
        let max_per_dim = ctx.limits().max_compute_workgroups_per_dimension;
        // the scans that place the new lists (counts -> first entries)
        let scans = list_scans(&ctx, &small.rows, (&windows, n as u32))?;
        let per_group = program
            .kernel("gather")?
            .workgroup_size
            .iter()
            .product::<u32>();
        // the servo walls' pushes summed per lane of a workgroup (`wall_servo`; only read
        // where some wall is servo-controlled)
        let lanes = if servo_walls {
            n_walls * per_group as u64
        } else {
            0
        };
        let servo_lanes = alloc.buffer("servo_lanes", 4 * lanes.max(1));
        // (a window's particles: every window's dispatch the same)
        let per_window = (n as u64).min(windows.len) as u32;
        let (dispatch, full_args, args) =
            Dispatches::new(&ctx, &mut alloc, (&grid, &scans), (per_window, per_group));
        let mirrors = state_mirrors(device, &state, (n as u32, software))?;
        alloc.list.extend(mirrors.sizes());
        // (before anything binds them)
        alloc.check(n)?;
        // (the re-sort's scratch in the new lists' buffer, idle until `remap`, where a
        // window's block holds it)
        let permutation = Permutation::new(
            &ctx,
            (grid.params(), grid.sorted_index()),
            n as u32,
            &state.permuted(),
            (&windowing, NewLists::lent(&state, entries)),
        )?;
        alloc
            .list
            .push(("permute.scratch".into(), permutation.scratch_bytes()));
        let mut buffers = alloc.list;
        let b = StepBuffers {
            step: small.step,
            pairs: small.pairs,
            walls: small.walls,
            wall_ref: small.wall_ref,
            appeared: small.appeared,
            control: small.control,
            args,
            full_args,
            rows: small.rows,
            servo_lanes,
        };
        let bound = bind_all(
            device,
            &program,
            (
                &state.layout,
                &state.records(&new_lists, entries),
                &state.blocks(entries),
            ),
            (&mirrors, &windowing),
            &grid,
            ([state.named(), b.named()], &state.paged()),
        )?;
        let grid_keys = grid_keys(&grid, &state, &windowing, (state_fields, state_pages))?;
        // quiet batches: not where walls move (their rebuild trigger is decide's), nor where
        // particles appear (an insertion rebuilds), nor in pages (the copies are one buffer)
        let mode = options.quiet.on(software);
        let paged = pages.paged() || state_pages.paged();
        let quiet =
            (mode != QuietBatches::Off && !moving_walls && !scene.pours() && !paged).then(|| {
                let (q, list) = quiet_batches(device, mode, &state, (&new_lists, entries), skin);
                buffers.extend(list);
                q
            });
        let radius = scene.particles.iter().map(|p| p.radius).collect();
        let mass = r.mass.clone();
        let mut engine = Self {
            time: 0.0,
            steps: 0,
            dt: r.dt,
            time_step: r.time_step.clone(),
            scene_parts: crate::checkpoint::run_digests(scene, f64::INFINITY).1,
            n: n as u32,
            entries,
            largest_entries: largest,
            spec,
            origin,
            h,
            radius,
            mass: mass.clone(),
            grid_keys,
            windowing,
            mirrors,
            quiet,
            grid,
            state,
            _new_lists: new_lists,
            permutation,
            b,
            dispatch,
            resume: None,
            clock: None,
            growths: 0,
            rebuild_chain: options.rebuild_chain,
            lean_halts: 0,
            lean: true,
            rebuilds_seen: 0,
            program,
            bound,
            max_per_dim,
            kind,
            keeps,
            n_walls: n_walls as u32,
            buffers,
            gravity: DVec3::from_array(scene.gravity),
            dropped: 0,
            peak: None,
            escaped: None,
            scans,
            wall_normals: scene
                .walls
                .iter()
                .map(|w| DVec3::from_array(w.normal).normalize())
                .collect(),
            wall_motion: scene.walls.iter().map(|w| w.motion.clone()).collect(),
            wall_phase: scene.walls.iter().map(|w| w.motion.index_at(0.0)).collect(),
            wall_points: scene
                .walls
                .iter()
                .map(|w| DVec3::from_array(w.point))
                .collect(),
            insert_at: scene.particles.iter().map(|p| p.insert_at).collect(),
            insert_energy: insert_energies(scene, &mass),
            active,
            inserted: 0.0,
            ctx,
        };
        // automatic windows: a second build where the first lists outgrew one binding
        let rewindow = options.window_particles.is_none() && measured.is_none();
        match engine.initial_forces(rewindow)? {
            None => Ok(engine),
            Some(need) => {
                let ctx = engine.ctx.clone();
                drop(engine);
                // (its buffers freed before the second build takes as much again)
                let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
                Self::build(scene, ctx, options, Some(need))
            }
        }
    }
}

/// How far the neighbour search's separations may be off: it forms them in f32 from the
/// offsets without their compensations, each component within a few ulp of the cell's
/// width (an 8 mm ulp at 1e5 m cells, in a sparse scene), and across a periodic seam with
/// the device's period dims·h, `period_lo` short of the scene's; so pairs that close
/// within reach + skin are listed however wide the cells, m.
fn search_slack(h: DVec3, period_lo: [f32; 3]) -> f64 {
    let ulp = |w: f64| {
        let w = w as f32;
        f64::from(f32::from_bits(w.to_bits() + 1) - w)
    };
    let seam = DVec3::from_array(period_lo.map(|p| f64::from(p).abs())).length();
    4.0 * DVec3::new(ulp(h.x), ulp(h.y), ulp(h.z)).length() + seam
}

/// The step's uniform parameters for a scene (`r` resolved from it; the cell grid's origin
/// offset `extent`, widths `h` and `dims`; the lists' `entries` a window and the `skin`).
fn step_params(
    scene: &Scene,
    r: &Resolved,
    (extent, h, dims): (DVec3, DVec3, [u32; 3]),
    (entries, skin): (u64, f64),
) -> StepParams {
    let g = scene.gravity;
    let periodic = scene.domain.periodic;
    let n_walls = scene.walls.len();
    let servo_walls = scene.walls.iter().any(|w| w.motion.servo());
    let period_lo = [0, 1, 2].map(|a| {
        if periodic[a] {
            (extent[a] - dims[a] as f64 * h[a]) as f32
        } else {
            0.0
        }
    });
    StepParams {
        gravity: [g[0] as f32, g[1] as f32, g[2] as f32],
        dt: r.dt as f32,
        list_capacity: entries as u32,
        n_materials: r.n_materials as u32,
        n_walls: n_walls as u32,
        reach: (r.max_reach + search_slack(h, period_lo)) as f32,
        extent_cells: [
            (extent.x / h.x) as f32,
            (extent.y / h.y) as f32,
            (extent.z / h.z) as f32,
        ],
        servo_walls: servo_walls as u32,
        periodic: periodic.map(u32::from),
        zero: 0,
        skin: skin as f32,
        // on once the initial forces are in (`initial_forces`)
        jumps: 0,
        _pad: crate::gpu::layout::Pad::ZERO,
        period_lo,
        _pad_end: 0,
    }
}

/// The step's buffers a scene fills before its program is built: the uniform parameters,
/// the pair table, the walls and each one's point at the last rebuild, which particles
/// have appeared, the new lists' rows and `control`.
struct SceneBuffers {
    step: wgpu::Buffer,
    pairs: wgpu::Buffer,
    walls: wgpu::Buffer,
    wall_ref: wgpu::Buffer,
    appeared: wgpu::Buffer,
    rows: wgpu::Buffer,
    control: wgpu::Buffer,
}

impl SceneBuffers {
    /// Allocates and writes them: `active` tells which particles have appeared, the walls
    /// are placed in the cells of width `h` from `origin`.
    fn upload(
        (alloc, q0): (&mut Allocator, &wgpu::Queue),
        scene: &Scene,
        (step, pairs, active): (&StepParams, &[u8], &[bool]),
        (origin, h): (DVec3, DVec3),
        windows: &Windows,
    ) -> Self {
        let walls: Vec<WallGpu> = scene
            .walls
            .iter()
            .map(|w| WallGpu::from_scene(w, origin, h))
            .collect();
        let step_buf = uniform_buffer(alloc.device, "step", bytemuck::bytes_of(step));
        alloc.list.push(("step".into(), step_buf.size()));
        let pairs_buf = alloc.buffer("pairs", pairs.len() as u64);
        q0.write_buffer(&pairs_buf, 0, pairs);
        let walls_buf = alloc.buffer(
            "walls",
            (walls.len().max(1) * std::mem::size_of::<WallGpu>()) as u64,
        );
        if !walls.is_empty() {
            q0.write_buffer(&walls_buf, 0, bytemuck::cast_slice(&walls));
        }
        // each wall's point at the last rebuild (decide); 32 bytes a wall
        let wall_ref = alloc.buffer("wall_ref", 32 * walls.len().max(1) as u64);
        // which particles have appeared, by persistent id: a word each where the scene
        // pours (`POURING`), else one word nothing reads
        let pouring = scene.pours();
        let n = active.len() as u64;
        let appeared = alloc.buffer("active", 4 * if pouring { n } else { 1 });
        if pouring {
            q0.write_buffer(&appeared, 0, bytemuck::cast_slice(&appeared_flags(active)));
        }
        // the new lists' and the `lower` lists' rows (four regions a window)
        let rows = blocked_buffer(
            alloc,
            windows,
            (
                "rows",
                4 * ROWS_REGION_COUNT as u64 * windows.len * windows.count,
            ),
            4 * ROWS_REGION_COUNT as u64 * windows.len,
        );
        let control = alloc.buffer("control", CONTROL_BYTES);
        // moved beyond skin/2 (flag set): the first step builds the lists
        let skin_init = [1u32, 0, 0, 0];
        q0.write_buffer(&control, SKIN_OFFSET, bytemuck::cast_slice(&skin_init));
        Self {
            step: step_buf,
            pairs: pairs_buf,
            walls: walls_buf,
            wall_ref,
            appeared,
            rows,
            control,
        }
    }
}

/// Whether the run takes the software adapter's paths (texture mirrors; quiet batches
/// under `auto`): as the options say, by default on a software adapter with one window
/// (the mirrors copy a field's region, so they need one).
fn software_paths(
    options: &GpuOptions,
    ctx: &GpuContext,
    windows: &Windows,
    n: usize,
) -> Result<bool, PowderError> {
    let software = options
        .software_paths
        .unwrap_or_else(|| ctx.is_software() && windows.count == 1);
    if software && windows.count > 1 {
        return Err(PowderError::Run(format!(
            "the software adapter's paths (texture mirrors) need one window, and {} particles in windows of {} make {}: turn them off (`--software-paths off`, GpuOptions::software_paths)",
            n, windows.len, windows.count
        )));
    }
    Ok(software)
}

/// The grid sort's bind groups for the cells' keys, a window each (its page where the
/// state has pages; `state_fields` fields a particle in the state buffer).
fn grid_keys(
    grid: &GridSort,
    state: &StateSet,
    windowing: &WindowBindings,
    (state_fields, state_pages): (u64, Pages),
) -> Result<Vec<wgpu::BindGroup>, PowderError> {
    let windows = state.layout.windows();
    let state_block = state_fields * windows.len * crate::gpu::state::FIELD_BYTES;
    (0..windows.count)
        .map(|w| {
            let cells = match state_pages.paged() {
                true => Part::whole(&state.state[state_pages.page_of(w) as usize]),
                false => windowing.part(&state.state[0], state_block, w),
            };
            grid.keys_bind_group_part(cells, &windowing.uniforms[w as usize])
        })
        .collect()
}

/// The windows (`gpu::window`): as the options ask, or the fewest where every array fits
/// one binding (`measured`: the list entries a first build needed, where it outgrew one).
fn plan_windows(
    ctx: &GpuContext,
    options: &GpuOptions,
    (layout, records): (&StateLayout, [RecordLayout; 2]),
    n: u64,
    measured: Option<u64>,
) -> Result<Windows, PowderError> {
    Ok(match options.window_particles {
        Some(len) => Windows::of(n, len)?,
        None => automatic_windows(layout, records, n, ctx.max_storage_binding(), measured),
    })
}

/// The grid sort's buffers, named with their sizes (bytes).
fn grid_sizes(grid: &GridSort) -> Vec<(String, u64)> {
    [
        ("grid.params", grid.params()),
        ("grid.keys", grid.keys()),
        ("grid.cell_count", grid.cell_count()),
        ("grid.cell_start", grid.cell_start()),
        ("grid.sorted_index", grid.sorted_index()),
    ]
    .map(|(name, b)| (name.to_string(), b.size()))
    .to_vec()
}
