//! Building an engine for a scene: its composition, pipelines, buffers and bind groups, and the first lists and forces.

use super::*;

/// Whether the step places force jumps: as the scene says (`jump_impulses`), by default
/// where some contact law's force can jump (on the CPU they cost nothing where none does;
/// here they are fields and code the step would carry for nothing).
pub(super) fn places_jumps(scene: &Scene, models: &[ContactModel], r_max: f64) -> bool {
    scene.jump_impulses.unwrap_or_else(|| {
        let geom = PairGeometry::spheres(r_max, r_max, 1.0, 1.0);
        models.iter().any(|m| m.has_force_jumps(&geom))
    })
}

/// The particles (by index into `cells`) in the order of the grid sort (`grid.wgsl`):
/// by clamped linear cell key, x fastest, then by index.
pub(super) fn grid_order(cells: &[[i32; 4]], dims: [u32; 3]) -> Vec<usize> {
    let key = |c: &[i32; 4]| {
        let k: [u64; 3] = [0, 1, 2].map(|a| c[a].clamp(0, dims[a] as i32 - 1) as u64);
        k[0] + dims[0] as u64 * (k[1] + dims[1] as u64 * k[2])
    };
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by_key(|&i| (key(&cells[i]), i));
    order
}

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
        let block = 4 * 4 * windows.len;
        let part = match windows.count {
            1 => Part::whole(rows),
            _ => Part {
                buffer: rows,
                offset: w * block,
                size: Some(block),
            },
        };
        for (count, row) in [(0, 1), (2, 3)] {
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

/// What the step's program is compiled from besides the composition: the kernels a scene
/// runs, its pipeline constants, the state read through mirrors.
pub(super) struct StepSpec {
    pub(super) wanted: Vec<&'static str>,
    pub(super) constants: Vec<(&'static str, f64)>,
    pub(super) mirrors: bool,
}

impl StepSpec {
    /// The step's program, the lists' entries in one buffer or `paged`.
    pub(super) fn compile(
        &self,
        ctx: &GpuContext,
        (kind, keeps): (&Composition, Keeps),
        paged: bool,
    ) -> Result<Program, PowderError> {
        Program::specialized(
            ctx,
            &kind.variant(keeps, self.mirrors, paged),
            Some(&self.wanted),
            &self.constants,
        )
    }
}

/// The step's kernels a scene runs: the wall kernels only where walls move, `appear` only
/// where particles appear during the run (the others are not compiled).
fn wanted_kernels(scene: &Scene) -> Vec<&'static str> {
    let mut wanted = crate::gpu::shaders::STEP_KERNELS.to_vec();
    if scene.walls.iter().any(|w| w.motion.moves()) {
        wanted.push("wall_move");
    }
    if scene.walls.iter().any(|w| w.motion.servo()) {
        wanted.extend(["wall_servo", "wall_servo_apply"]);
    }
    if scene.pours() {
        wanted.push("appear");
    }
    wanted
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

/// The buffers the step binds by name: the state set's and the step's others.
pub(super) type NamedBuffers<'a> = [Vec<(String, &'a wgpu::Buffer)>; 2];

/// Binds every kernel of the step to the run's buffers and the mirrors' textures, window
/// by window where a kernel works on windows (`blocks`: the blocked buffers' bytes a
/// window).
pub(super) fn bind_all(
    device: &wgpu::Device,
    program: &Program,
    (layout, records, blocks): (&StateLayout, &[(&RecordLayout, u64)], &Blocks),
    (mirrors, windows): (&Mirrors, &WindowBindings),
    grid: &GridSort,
    (buffers, paged): (NamedBuffers, &[Paged]),
) -> Result<Bound, PowderError> {
    let mut list: Vec<(String, &wgpu::Buffer)> = buffers.into_iter().flatten().collect();
    list.push(("grid".into(), grid.params()));
    list.push(("sorted_index".into(), grid.sorted_index()));
    list.push(("cell_start".into(), grid.cell_start()));
    let refs: Vec<(&str, &wgpu::Buffer)> = list.iter().map(|(n, b)| (n.as_str(), *b)).collect();
    let textures = mirrors.view_bytes();
    let pass = |name: &str| -> Result<Pass, PowderError> {
        let kernel = program.kernel(name)?.clone();
        let groups = windows.groups(device, &kernel, (&refs, blocks), &mirrors.views(), paged)?;
        let mut bound = kernel.bound_bytes(&refs, &textures);
        // the state: the fields the kernel's accessors touch, not the whole buffers
        for (name, bytes) in &mut bound {
            if let Some(b) = Buffer::ALL.into_iter().find(|b| b.name() == name) {
                *bytes = layout.touched_bytes(b, &kernel.calls);
            }
            // and the records: the fields it touches (of every layout living in the buffer)
            let mut living = records.iter().filter(|(r, _)| r.array() == name).peekable();
            if living.peek().is_some() {
                *bytes = living
                    .map(|(r, capacity)| r.touched_bytes(&kernel.calls, *capacity))
                    .sum();
            }
        }
        Ok(Pass {
            kernel,
            groups,
            bound,
        })
    };
    let optional = |name: &str| program.kernels.contains_key(name).then(|| pass(name));
    Ok(Bound {
        kick_drift: pass("kick_drift")?,
        decide: pass("decide")?,
        decide_lean: pass("decide_lean")?,
        gather: pass("gather")?,
        count_neighbours: pass("count_neighbours")?,
        neighbours: pass("neighbours")?,
        commit: pass("commit")?,
        remap: pass("remap")?,
        copy_back_history: pass("copy_back_history")?,
        force: pass("force")?,
        kick: pass("kick")?,
        collect_kick_drift: pass("collect_kick_drift")?,
        collect: pass("collect")?,
        wall_move: optional("wall_move").transpose()?,
        wall_servo: optional("wall_servo").transpose()?,
        wall_servo_apply: optional("wall_servo_apply").transpose()?,
        appear: optional("appear").transpose()?,
    })
}

/// The value every item of `values` has, or `mixed` when they differ or there is none.
pub(super) fn common_or<T: PartialEq + Copy>(values: impl IntoIterator<Item = T>, mixed: T) -> T {
    let mut values = values.into_iter();
    match values.next() {
        Some(first) if values.all(|v| v == first) => first,
        _ => mixed,
    }
}

/// The step's pipeline-overridable constants for a scene: what it does not use is folded
/// out of its pipelines (the WGSL `override`s of step.wgsl and the model files). The
/// model constants go only to variants that declare them (wgpu refuses unknown names).
pub(super) fn pipeline_constants(
    scene: &Scene,
    r: &Resolved,
    models: &[ContactModel],
) -> Vec<(&'static str, f64)> {
    let flag = |b: bool| f64::from(u8::from(b));
    let mut constants = vec![
        ("ONE_MATERIAL", flag(r.n_materials == 1)),
        ("POURING", flag(scene.pours())),
        ("PERIODIC", flag(scene.domain.periodic.iter().any(|&p| p))),
        ("WALLS", flag(!scene.walls.is_empty())),
    ];
    let hyst: Vec<HystereticPair> = models
        .iter()
        .filter_map(|m| match m {
            ContactModel::Hysteretic(p) => Some(HystereticPair::hysteretic(p)),
            ContactModel::Lsd(p) => Some(HystereticPair::lsd(p)),
            _ => None,
        })
        .collect();
    if !hyst.is_empty() {
        let flags = common_or(hyst.iter().map(|h| h.flags), u32::MAX);
        constants.push(("HYST_ONE_FLAGS", flags as f64));
    }
    let jkr: Vec<JkrPair> = models
        .iter()
        .filter_map(|m| match m {
            ContactModel::Jkr(p) => Some(JkrPair::new(p)),
            _ => None,
        })
        .collect();
    if !jkr.is_empty() {
        // one dissipation code or 255; all Hertz 0 / all adhesive 1 / both 2
        let dissipation = common_or(jkr.iter().map(|j| j.dissipation), 255);
        let adhesion = common_or(jkr.iter().map(|j| u32::from(j.gamma > 0.0)), 2);
        constants.push(("JKR_ONE_DISSIPATION", dissipation as f64));
        constants.push(("JKR_ADHESION", adhesion as f64));
    }
    constants
}

/// The step a scene's pair models need and their pair table as bytes.
pub(super) fn pair_table(models: &[ContactModel]) -> (Composition, Vec<u8>) {
    let kind = Composition::of(models);
    let rows = models.iter().flat_map(|m| kind.pair_row(m)).collect();
    (kind, rows)
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

/// A run's initial particle state as the state's fields want it, each particle's values
/// in the grid's order (the first sort keeps it: every particle starts in its window, and
/// a window's neighbours hold its partners, `gpu::window`).
struct InitialState {
    /// Scene index of each particle, in upload order.
    order: Vec<usize>,
    cells: Vec<[i32; 4]>,
    offs: Vec<[f32; 4]>,
    vels: Vec<[f32; 4]>,
    acc0: [f32; 4],
    /// The prediction `kick_drift` writes each step, for the initial forces.
    vpred0: Vec<[f32; 4]>,
    /// The compensations (stored − true) of velocity and position, and the radius's
    /// rounding residual: the kernels' x − c is the scene's value to ~1e-16 relative.
    kahan_v: Vec<[f32; 4]>,
    kahan_o: Vec<[f32; 4]>,
    /// ω as the scene gives it, w = I = 2/5·m·r².
    omega: Vec<[f32; 4]>,
}

impl InitialState {
    /// The scene's particles in cells of width `h` from `origin` (`dims` per axis).
    fn new(
        scene: &Scene,
        r: &Resolved,
        (origin, h, dims): (DVec3, DVec3, [u32; 3]),
        dt32: f32,
    ) -> Self {
        let n = scene.particles.len();
        let mut cells = Vec::with_capacity(n);
        let mut offs = Vec::with_capacity(n);
        let mut vels = Vec::with_capacity(n);
        let mut kahan_v: Vec<[f32; 4]> = Vec::with_capacity(n);
        let mut kahan_o: Vec<[f32; 4]> = Vec::with_capacity(n);
        for (p, m) in scene.particles.iter().zip(&r.mass) {
            let x = DVec3::from_array(p.position);
            let (mut c, mut o) = encode3(x, origin, h);
            c[3] = p.material as i32;
            if p.insert_at > 0.0 {
                c[3] |= NOT_APPEARED;
            }
            o[3] = p.radius as f32;
            let dx = crate::gpu::layout::decode3(c, o, origin, h) - x;
            let v = p.velocity;
            let v32 = v.map(|c| c as f32);
            let cv = [0, 1, 2].map(|a| (v32[a] as f64 - v[a]) as f32);
            kahan_v.push([cv[0], cv[1], cv[2], 0.0]);
            kahan_o.push([
                dx.x as f32,
                dx.y as f32,
                dx.z as f32,
                (o[3] as f64 - p.radius) as f32,
            ]);
            cells.push(c);
            offs.push(o);
            vels.push([v32[0], v32[1], v32[2], *m as f32]);
        }
        let g = scene.gravity;
        let acc0 = [g[0] as f32, g[1] as f32, g[2] as f32, 0.0];
        let vpred0: Vec<[f32; 4]> = vels
            .iter()
            .map(|v| {
                let p = |i: usize| v[i] + 0.5 * dt32 * acc0[i];
                [p(0), p(1), p(2), v[3]]
            })
            .collect();
        let omega = scene
            .particles
            .iter()
            .zip(&r.mass)
            .map(|(p, m)| {
                let [x, y, z] = p.angular_velocity.map(|c| c as f32);
                [x, y, z, (0.4 * m * p.radius * p.radius) as f32]
            })
            .collect();
        Self {
            order: grid_order(&cells, dims),
            cells,
            offs,
            vels,
            acc0,
            vpred0,
            kahan_v,
            kahan_o,
            omega,
        }
    }

    /// The state field `name`'s initial words in upload order (`None`: zero).
    fn field(&self, name: &str) -> Option<Vec<[u32; 4]>> {
        let words = |v: &[[f32; 4]]| -> Vec<[u32; 4]> {
            self.order.iter().map(|&i| bytemuck::cast(v[i])).collect()
        };
        match name {
            "cell" => Some(
                self.order
                    .iter()
                    .map(|&i| bytemuck::cast(self.cells[i]))
                    .collect(),
            ),
            "off" => Some(words(&self.offs)),
            "vel" => Some(words(&self.vels)),
            "acc" => Some(vec![bytemuck::cast(self.acc0); self.order.len()]),
            "vpred" => Some(words(&self.vpred0)),
            "kahan_v" => Some(words(&self.kahan_v)),
            "kahan_o" => Some(words(&self.kahan_o)),
            // persistent id; the lists and wall entries come with the first rebuild
            "ids" => Some(self.order.iter().map(|&i| [i as u32, 0, 0, 0]).collect()),
            "omega" => Some(words(&self.omega)),
            _ => None,
        }
    }
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
        // the windows (`gpu::window`): asked for, or one where every array fits a binding
        let n_walls = scene.walls.len() as u64;
        let layout0 = StateLayout::new(0, kind.state_extras(keeps));
        let state_fields = layout0.count(Buffer::State);
        let windows = match options.window_particles {
            Some(len) => Windows::of(n as u64, len)?,
            None => automatic_windows(
                &layout0,
                kind.records(keeps),
                n as u64,
                ctx.max_storage_binding(),
                measured,
            ),
        };
        grid.set_windows(&ctx.queue, &windows, state_fields as u32);
        let device = &ctx.device;
        let mut alloc = Allocator::new(device, ctx.max_storage_binding());
        alloc.list = vec![
            ("grid.params".into(), grid.params().size()),
            ("grid.keys".into(), grid.keys().size()),
            ("grid.cell_count".into(), grid.cell_count().size()),
            ("grid.cell_start".into(), grid.cell_start().size()),
            ("grid.sorted_index".into(), grid.sorted_index().size()),
        ];
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
        let walls: Vec<WallGpu> = scene
            .walls
            .iter()
            .map(|w| WallGpu::from_scene(w, origin, h))
            .collect();
        let moving_walls = scene.walls.iter().any(|w| w.motion.moves());
        let step = step_params(scene, &r, (extent, h, dims), (entries, skin));
        let step_buf = uniform_buffer(device, "step", bytemuck::bytes_of(&step));
        alloc.list.push(("step".into(), step_buf.size()));
        let pairs_buf = alloc.buffer("pairs", pairs.len() as u64);
        q0.write_buffer(&pairs_buf, 0, &pairs);
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
        let active: Vec<bool> = scene.particles.iter().map(|p| p.insert_at <= 0.0).collect();
        let pouring = scene.pours();
        let active_buf = alloc.buffer("active", 4 * if pouring { n as u64 } else { 1 });
        if pouring {
            q0.write_buffer(
                &active_buf,
                0,
                bytemuck::cast_slice(&appeared_flags(&active)),
            );
        }
        // the new lists' and the `lower` lists' rows (four regions a window)
        let rows = blocked_buffer(
            &mut alloc,
            &windows,
            ("rows", 4 * 4 * windows.len * windows.count),
            4 * 4 * windows.len,
        );
        let control = alloc.buffer("control", CONTROL_BYTES);
        // moved beyond skin/2 (flag set): the first step builds the lists
        let skin_init = [1u32, 0, 0, 0];
        q0.write_buffer(&control, SKIN_OFFSET, bytemuck::cast_slice(&skin_init));
        // the software adapter's paths (texture mirrors; quiet batches under `auto`)
        // (the mirrors copy a field's region: one window only)
        let software = options
            .software_paths
            .unwrap_or_else(|| ctx.is_software() && windows.count == 1);
        if software && windows.count > 1 {
            return Err(PowderError::Run(format!(
                "the software adapter's paths (texture mirrors) need one window, and {} particles in windows of {} make {}: turn them off (`--software-paths off`, GpuOptions::software_paths)",
                n, windows.len, windows.count
            )));
        }
        let constants = pipeline_constants(scene, &r, &all_models);
        let spec = StepSpec {
            wanted: wanted_kernels(scene),
            constants,
            mirrors: software,
        };
        let program = spec.compile(&ctx, (&kind, keeps), pages.paged() || state_pages.paged())?;
        let max_per_dim = ctx.limits().max_compute_workgroups_per_dimension;
        // the scans that place the new lists (counts -> first entries)
        let scans = list_scans(&ctx, &rows, (&windows, n as u32))?;
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
        let buffers = alloc.list;
        let b = StepBuffers {
            step: step_buf,
            pairs: pairs_buf,
            walls: walls_buf,
            wall_ref,
            appeared: active_buf,
            control,
            args,
            full_args,
            rows,
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
        // the grid sort's keys, a window at a time (its page where the state has pages)
        let state_block = state_fields * windows.len * crate::gpu::state::FIELD_BYTES;
        let grid_keys = (0..windows.count)
            .map(|w| {
                let cells = match state_pages.paged() {
                    true => Part::whole(&state.state[state_pages.page_of(w) as usize]),
                    false => windowing.part(&state.state[0], state_block, w),
                };
                grid.keys_bind_group_part(cells, &windowing.uniforms[w as usize])
            })
            .collect::<Result<Vec<_>, _>>()?;
        // quiet batches: not where walls move (their rebuild trigger is decide's) nor where
        // particles appear (an insertion rebuilds)
        let pouring = scene.pours();
        let mode = options.quiet.on(software);
        // (nor where the lists' entries or the state are in pages: the copies would be one
        // buffer)
        let paged = pages.paged() || state_pages.paged();
        let quiet = (mode != QuietBatches::Off && !moving_walls && !pouring && !paged)
            .then(|| quiet_batches(device, mode, &state, (&new_lists, entries), skin));
        let mut buffers = buffers;
        let quiet = quiet.map(|(q, list)| {
            buffers.extend(list);
            q
        });
        let radius = scene.particles.iter().map(|p| p.radius).collect();
        let mass = r.mass.clone();
        let mut engine = Self {
            time: 0.0,
            steps: 0,
            dt: r.dt,
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
    StepParams {
        gravity: [g[0] as f32, g[1] as f32, g[2] as f32],
        dt: r.dt as f32,
        list_capacity: entries as u32,
        n_materials: r.n_materials as u32,
        n_walls: n_walls as u32,
        reach: r.max_reach as f32,
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
        _pad: [0; 2],
        period_lo: [0, 1, 2].map(|a| {
            if periodic[a] {
                (extent[a] - dims[a] as f64 * h[a]) as f32
            } else {
                0.0
            }
        }),
        _pad_end: 0,
    }
}

/// The energy each particle brings when it appears (kinetic, rotational about its centre,
/// gravitational), J: the ledger books it at its insertion.
fn insert_energies(scene: &Scene, mass: &[f64]) -> Vec<f64> {
    scene
        .particles
        .iter()
        .zip(mass)
        .map(|(p, m)| {
            let spin = 0.2 * m * p.radius * p.radius;
            0.5 * m * DVec3::from_array(p.velocity).length_squared()
                + spin * DVec3::from_array(p.angular_velocity).length_squared()
                - m * DVec3::from_array(scene.gravity).dot(DVec3::from_array(p.position))
        })
        .collect()
}
