//! The GPU engine: the time step of `shaders/step.wgsl` driven from the host, for the
//! hysteretic/LSD models and the JKR family (JKR, Hertz: damping including the Krijt and
//! stress-dependent dissipations, friction, rolling resistance, reduced stiffness) with
//! walls and gravity.
//!
//! The step's source is composed per scene ([`Composition`]): the contact sub-models its
//! pairs use, the per-contact history layout they declare, and, only when some contact
//! exerts tangential forces or torques, the angular state (ω with the moment of inertia,
//! angular acceleration, predicted ω). What a scene does not need is neither declared nor
//! allocated ([`GpuEngine::buffers`] lists what is). A scene may mix any laws: each pair
//! row carries its law's tag.
//!
//! The particle state lives in one buffer set, A, in the order of the last neighbour-list
//! rebuild. Each step drifts A (accumulating each particle's displacement since the last
//! rebuild), decides on the device whether to rebuild, and on a rebuild sorts A by cell,
//! re-sorts it in place ([`Permutation`]), builds the new neighbour lists (B) from the
//! grid, remaps every contact's history from A's lists by the partner's persistent id and
//! copies the lists back into A. Then it computes the forces and kicks, in place. A step
//! without a rebuild (most of them) copies nothing. Many steps are recorded per submission and the host reads back only a
//! 16-byte monitor per batch (neighbour-capacity overflow, non-finite forces) and whatever
//! output needs.
//!
//! Verlet skin: the lists hold every pair within r_i + r_j + reach + skin (skin =
//! [`SKIN`]·r_min; the grid cell is at least 2·r_max + reach + skin wide) and are rebuilt
//! only once some particle has moved more than skin/2 since the last rebuild. `kick_drift`
//! raises a flag where a particle's displacement exceeds skin/2; the one-invocation
//! `decide` kernel reads and clears it and writes the rebuild flag and the grid
//! sort's indirect dispatch arguments (the full sort's, or zero workgroups): the sort is
//! recorded with `dispatch_workgroups_indirect` ([`GridSort::encode_indirect`]);
//! the rebuild's own per-particle passes (gather, re-sort, neighbours, remap, copy back) are
//! indirect too. Indirect rather than a flag read by each kernel: a skipped rebuild then
//! launches no workgroups at all, on any adapter, and `GridSort`'s kernels stay unaware of
//! the skin. On lavapipe both measured alike (3.1·10⁵ particle-steps/s for the
//! cohesive cluster, up to 3.8·10⁵ for the indirect one, on a noisy 2-core machine),
//! because wgpu validates every indirect dispatch with an extra dispatch of its own
//! (`InstanceFlags::VALIDATION_INDIRECT_CALL`, on by default): clearing that flag where
//! the instance is created (`gpu::context`) measured 2x faster (5.5·10⁵ against 2.8·10⁵
//! over the first 20 000 steps).
//! Every run stays bitwise deterministic (the decision is a pure function of the state).

use crate::cpu::{ContactStats, Energies, Partner};
use crate::error::PowderError;
use crate::gpu::composition::{Composition, Keeps};
use crate::gpu::context::GpuContext;
use crate::gpu::grid::{ExclusiveScan, GridSort};
use crate::gpu::kernel::{
    split_workgroups, storage_buffer, submit_and_read, u32s, uniform_buffer, Kernel, Part, Program,
};
use crate::gpu::layout::{encode3, gpu_cell_width, HystereticPair, JkrPair, StepParams, WallGpu};
use crate::gpu::mirror::Mirrors;
use crate::gpu::permute::{self, Field, Permutation, ROW_WORDS};
use crate::gpu::quiet::{Forecast, QuietBatches};
use crate::gpu::records::{RecordLayout, WALL_ENTRY};
use crate::gpu::state::{Buffer, StateLayout};
use crate::gpu::timestamps::{PassClock, PassProfile};
use crate::gpu::traffic::{PassTraffic, When};
use crate::gpu::window::{Blocks, WindowBindings, Windows, MIN_WINDOW};
use crate::model::{ContactHistory, ContactModel, PairGeometry};
use crate::output::contacts::{ContactLine, ContactNetwork};
use crate::scene::{Scene, WallPhase};
use crate::setup::Resolved;
use glam::DVec3;

/// The Verlet skin in units of the smallest radius: lists hold the pairs within
/// r_i + r_j + reach + skin, rebuilt once some particle has moved more than skin/2.
pub const SKIN: f64 = 0.1;

/// The neighbour lists' first capacity, entries a particle (+256): the first rebuild
/// grows them to what it needs (`GpuEngine::grow_lists`).
const INITIAL_ENTRIES_PER_PARTICLE: u64 = 2;

/// Headroom of a grown capacity over what a rebuild needed (less where the entries'
/// binding limit leaves less).
const LIST_HEADROOM: f64 = 1.25;

/// Bytes of the device monitor, the first part of `control` in `shaders/step.wgsl`.
const MONITOR_BYTES: u64 = 48;

/// Where the Verlet skin state follows it in `control` (4 words: moved, rebuild flag,
/// rebuilds so far, unused).
const SKIN_OFFSET: u64 = MONITOR_BYTES;

/// Bytes of `control`.
const CONTROL_BYTES: u64 = SKIN_OFFSET + 16;

/// Whether the step places force jumps: as the scene says (`jump_impulses`), by default
/// where some contact law's force can jump (on the CPU they cost nothing where none does;
/// here they are fields and code the step would carry for nothing).
fn places_jumps(scene: &Scene, models: &[ContactModel], r_max: f64) -> bool {
    scene.jump_impulses.unwrap_or_else(|| {
        let geom = PairGeometry::spheres(r_max, r_max, 1.0, 1.0);
        models.iter().any(|m| m.has_force_jumps(&geom))
    })
}

/// Steps recorded into one submission.
pub const STEPS_PER_SUBMIT: u64 = 64;

/// The particles (by index into `cells`) in the order of the grid sort (`grid.wgsl`):
/// by clamped linear cell key, x fastest, then by index.
fn grid_order(cells: &[[i32; 4]], dims: [u32; 3]) -> Vec<usize> {
    let key = |c: &[i32; 4]| {
        let k: [u64; 3] = [0, 1, 2].map(|a| c[a].clamp(0, dims[a] as i32 - 1) as u64);
        k[0] + dims[0] as u64 * (k[1] + dims[1] as u64 * k[2])
    };
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by_key(|&i| (key(&cells[i]), i));
    order
}

/// Creates storage buffers and records their names and sizes (for [`GpuEngine::buffers`]).
/// A buffer that does not fit (bound whole: over the storage binding limit; bound a
/// window's part at a time: a part over it, or the buffer over the largest buffer) is not
/// created: a 4-byte stand-in takes its place and [`Allocator::check`] refuses.
struct Allocator<'a> {
    device: &'a wgpu::Device,
    list: Vec<(String, u64)>,
    /// The largest binding a buffer may be, bytes.
    limit: u64,
    /// The largest buffer, bytes.
    max_buffer: u64,
    /// What does not fit, said for the user.
    refused: Vec<String>,
}

impl<'a> Allocator<'a> {
    fn new(device: &'a wgpu::Device, limit: u64) -> Self {
        Self {
            device,
            list: Vec::new(),
            limit: limit.min(4 * u32::MAX as u64),
            max_buffer: device.limits().max_buffer_size,
            refused: Vec::new(),
        }
    }

    /// A buffer bound whole.
    fn buffer(&mut self, name: &str, bytes: u64) -> wgpu::Buffer {
        let fits = bytes <= self.limit;
        if !fits {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        }
        self.create(name, bytes, fits)
    }

    /// A buffer blocked by window, `part` bytes of it bound at a time (`gpu::window`).
    fn blocked(&mut self, name: &str, bytes: u64, part: u64) -> wgpu::Buffer {
        if part > self.limit {
            self.refused.push(format!(
                "{part} bytes of `{name}` bound at a time (a window and its neighbours), over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        } else if bytes > self.max_buffer {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's largest buffer of {} bytes",
                self.max_buffer
            ));
        }
        let fits = part <= self.limit && bytes <= self.max_buffer;
        self.create(name, bytes, fits)
    }

    fn create(&mut self, name: &str, bytes: u64, fits: bool) -> wgpu::Buffer {
        let b = storage_buffer(self.device, name, if fits { bytes } else { 4 });
        self.list
            .push((name.to_string(), if fits { b.size() } else { bytes }));
        b
    }

    /// An error naming the first buffer that does not fit, for `particles` particles.
    /// Call it before anything writes or binds the buffers.
    fn check(&self, particles: usize) -> Result<(), PowderError> {
        match self.refused.first() {
            Some(what) => Err(PowderError::Run(format!(
                "{particles} particles need {what}"
            ))),
            None => Ok(()),
        }
    }
}

/// The particle state (A): per particle, in the order of the last rebuild (`gpu::state`),
/// with the neighbour lists' entries, its pairs' and its wall contacts (`gpu::records`).
struct StateSet {
    /// Every per-particle field ([`StateLayout`]): `state` (what pairs read of a partner)
    /// and `motion`.
    state: wgpu::Buffer,
    motion: wgpu::Buffer,
    layout: StateLayout,
    /// The lists' entries (partner or wall, `lower`, partner id, history, pair force and
    /// torque, the contact's prior, a force jump's impulse) and their layout.
    entries: wgpu::Buffer,
    entry_layout: RecordLayout,
}

impl StateSet {
    fn new(
        alloc: &mut Allocator,
        (n, entries, windows): (u64, u64, Windows),
        kind: &Composition,
        keeps: Keeps,
    ) -> Self {
        let layout = StateLayout::windowed(n, kind.rotation(), windows);
        let [entry_layout, _] = kind.records(keeps);
        let blocks = Self::blocks_of(&layout, (&entry_layout, entries));
        let mut b = |name: &'static str, bytes: u64| {
            let block = blocks.iter().find(|(n, _)| *n == name).map_or(0, |b| b.1);
            blocked_buffer(alloc, &windows, (&format!("A.{name}"), bytes), block)
        };
        Self {
            state: b("state", layout.bytes(Buffer::State)),
            motion: b("motion", layout.bytes(Buffer::Motion)),
            entries: b("entries", entry_layout.windowed_bytes(entries, &windows)),
            layout,
            entry_layout,
        }
    }

    /// Bytes of a window's block of each blocked buffer of the set (`gpu::window`), by
    /// the name the kernels bind it by, for `entries` list entries a window.
    fn blocks_of(
        layout: &StateLayout,
        (entry_layout, entries): (&RecordLayout, u64),
    ) -> Vec<(&'static str, u64)> {
        let len = layout.stride();
        let field = crate::gpu::state::FIELD_BYTES;
        vec![
            ("state", layout.count(Buffer::State) * len * field),
            ("motion", layout.count(Buffer::Motion) * len * field),
            ("entries", entry_layout.block_bytes(entries)),
        ]
    }

    /// [`Self::blocks_of`] this set, with `rows`.
    fn blocks(&self, entries: u64) -> Vec<(&'static str, u64)> {
        let mut v = Self::blocks_of(&self.layout, (&self.entry_layout, entries));
        v.push(("rows", 4 * 4 * self.layout.stride()));
        v
    }

    /// The buffers under the names the kernels bind them by.
    fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        vec![
            ("state".to_string(), &self.state),
            ("motion".to_string(), &self.motion),
            ("entries".to_string(), &self.entries),
        ]
    }

    /// The record layouts with their records (all windows'): the entries', the new
    /// lists'.
    fn records<'a>(&'a self, new: &'a NewLists, entries: u64) -> [(&'a RecordLayout, u64); 2] {
        let w = self.layout.windows();
        [
            (&self.entry_layout, entries * w.count),
            (&new.layout, entries * w.count),
        ]
    }

    /// The buffer holding state buffer `b`.
    fn buffer(&self, b: Buffer) -> &wgpu::Buffer {
        match b {
            Buffer::State => &self.state,
            Buffer::Motion => &self.motion,
        }
    }

    /// The fields a rebuild re-sorts (`gpu::permute`): every per-particle field (two
    /// state fields a dispatch) but the lists (rebuilt).
    fn permuted(&self) -> Vec<Field> {
        let stride = 4 * self.layout.stride() as u32;
        let per_move = (ROW_WORDS / 4).max(1) as usize;
        let mut f = Vec::new();
        for b in Buffer::ALL {
            let names: Vec<&str> = self.layout.in_buffer(b).map(|f| f.name).collect();
            let block = stride * names.len() as u32;
            for (c, group) in names.chunks(per_move).enumerate() {
                let first = (c * per_move) as u32;
                f.push(
                    Field::regions(
                        &group.join("+"),
                        self.buffer(b),
                        4,
                        (first * stride, stride, group.len() as u32),
                    )
                    .windowed(block),
                );
            }
        }
        f
    }
}

/// A storage buffer of `bytes` blocked by window, `block` bytes a window: bound whole with
/// one window, else a window and its neighbours at a time.
fn blocked_buffer(
    alloc: &mut Allocator,
    windows: &Windows,
    (name, bytes): (&str, u64),
    block: u64,
) -> wgpu::Buffer {
    if windows.count == 1 {
        alloc.buffer(name, bytes)
    } else {
        alloc.blocked(name, bytes, windows.covered() * block)
    }
}

/// The neighbour lists a rebuild builds (B: partner ids, history, priors), copied back
/// into A's at its end: in the entries' per-step fields (`RecordLayout::new_entries`).
struct NewLists {
    layout: RecordLayout,
}

impl NewLists {
    fn new(kind: &Composition, keeps: Keeps) -> Self {
        let [_, layout] = kind.records(keeps);
        Self { layout }
    }

    /// The layout of a copy of their fields in a buffer of its own.
    fn standalone(&self) -> RecordLayout {
        RecordLayout {
            host: None,
            ..self.layout.clone()
        }
    }

    /// A buffer for quiet batches' copy of the lists' history (`Quiet::lists`; the
    /// batch writes the per-step fields the new lists live in), for `entries` list
    /// entries a window.
    fn quiet_lists(
        &self,
        alloc: &mut Allocator,
        (entries, windows): (u64, &Windows),
    ) -> wgpu::Buffer {
        let bytes = self.standalone().windowed_bytes(entries, windows);
        alloc.buffer("quiet.lists", bytes)
    }

    /// Where they lie, lent to the re-sort as its scratch (nothing reads the new lists
    /// from one rebuild's `copy_back_history` to the next's `remap`, which runs after the
    /// re-sort), for `entries` list entries a window: the entries' per-step fields.
    fn lent<'a>(a: &'a StateSet, entries: u64) -> permute::Lent<'a> {
        let (base, words) = a.entry_layout.per_step();
        permute::Lent {
            buffer: &a.entries,
            block: a.entry_layout.block_bytes(entries),
            base: 4 * base * entries,
            bytes: 4 * words * entries,
        }
    }
}

/// The step's buffers besides the particle state and the new lists, and the per-entry
/// arrays the lists' capacity sizes (`nbr`, `lower`, the pair forces and torques).
struct StepBuffers {
    step: wgpu::Buffer,
    pairs: wgpu::Buffer,
    walls: wgpu::Buffer,
    /// Each wall's point at the last rebuild (the trigger for moving walls: state).
    wall_ref: wgpu::Buffer,
    /// Which particles have appeared (pouring), by persistent id.
    appeared: wgpu::Buffer,
    /// The monitor (zeroed per batch) and the Verlet skin state (`control` in
    /// `shaders/step.wgsl`): [0] some particle moved more than skin/2 since the last
    /// rebuild, [1] rebuild flag, [2] rebuilds so far.
    control: wgpu::Buffer,
    /// The indirect dispatch arguments: a rebuild's (written by `decide` each step), then
    /// every step's (written by the host at each batch's start; zeroed by a halt).
    args: wgpu::Buffer,
    full_args: wgpu::Buffer,
    /// Per particle (by persistent id): contact counts, overlaps, dissipated and stored
    /// energy (`particle_ledger` in `shaders/ledger.wgsl`); only with the ledger.
    particle_ledger: Option<wgpu::Buffer>,
    /// The new lists' and the `lower` lists' lengths and first entries (`rows` in
    /// `shaders/step.wgsl`: four regions a window, blocked like the state).
    rows: wgpu::Buffer,
    /// Each servo wall's pushes this step, summed per lane of a workgroup.
    servo_lanes: wgpu::Buffer,
}

impl StepBuffers {
    /// Every buffer under the name the kernels bind it by.
    fn named(&self) -> Vec<(String, &wgpu::Buffer)> {
        let mut list: Vec<(&str, &wgpu::Buffer)> = vec![
            ("step", &self.step),
            ("pairs", &self.pairs),
            ("walls", &self.walls),
            ("wall_ref", &self.wall_ref),
            ("appeared", &self.appeared),
            ("control", &self.control),
            ("args", &self.args),
            ("full_args", &self.full_args),
            ("rows", &self.rows),
            ("servo_lanes", &self.servo_lanes),
        ];
        list.extend(
            self.particle_ledger
                .as_ref()
                .map(|l| ("particle_ledger", l)),
        );
        list.into_iter().map(|(n, b)| (n.to_string(), b)).collect()
    }
}

/// An error when `entries` list entries a window of `words` words each (the entries'
/// records) do not fit: a window's numbering, the adapter's storage binding limit (the
/// whole buffer with one window, a window and its neighbours with several), its largest
/// buffer, or u32 word indices.
fn check_entries(
    (entries, windows): (u64, &Windows),
    words: u64,
    particles: u64,
    (limit, max_buffer): (u64, u64),
) -> Result<(), PowderError> {
    if entries > windows.max_records() {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {entries} entries in a window of {} particles, more than the {} a window's entries are numbered with (about 2^32 entries in all)",
            windows.len,
            windows.max_records()
        )));
    }
    let bytes = 4 * words;
    let total = entries * windows.count;
    let bound = entries * windows.covered();
    let per_particle = total as f64 / particles.max(1) as f64;
    let what = format!("{total} entries ({per_particle:.1} a particle) of {bytes} bytes each (partner, history, pair force, ...)");
    if total * words > u32::MAX as u64 {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}: more than 2^32 words, which the kernels' u32 indices cannot reach"
        )));
    }
    if bound * bytes > limit {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}, {} bytes bound at a time, over the adapter's storage binding limit of {limit} bytes{}",
            bound * bytes,
            if windows.count == 1 {
                "; windows hold them (`--window-particles N`, a power of two, GpuOptions::window_particles)"
            } else {
                "; smaller windows hold fewer (`--window-particles N`)"
            }
        )));
    }
    if total * bytes > max_buffer {
        return Err(PowderError::Run(format!(
            "the neighbour lists need {what}, over the adapter's largest buffer of {max_buffer} bytes"
        )));
    }
    Ok(())
}

/// List entries a window rounded up so a window's block of entries is a whole number of
/// 256 bytes where there are several (binding offsets).
fn window_entries(windows: &Windows, entries: u64) -> u64 {
    match windows.count {
        1 => entries,
        _ => entries.div_ceil(MIN_WINDOW) * MIN_WINDOW,
    }
}

/// The windows chosen where none are asked for: one where the per-particle arrays and the
/// lists fit a binding each — the lists' first guess (INITIAL_ENTRIES_PER_PARTICLE a
/// particle), or the `measured` entries of a first build that outgrew it — else windows
/// with room for WINDOW_ENTRIES_PER_PARTICLE entries a particle (or the measured ones and
/// their headroom, where more).
fn automatic_windows(
    layout: &StateLayout,
    [entry, new]: [RecordLayout; 2],
    n: u64,
    limit: u64,
    measured: Option<u64>,
) -> Windows {
    let per_particle = [
        layout.count(Buffer::State) * crate::gpu::state::FIELD_BYTES,
        layout.count(Buffer::Motion) * crate::gpu::state::FIELD_BYTES,
        4 * ROW_WORDS as u64,
    ]
    .into_iter()
    .max()
    .unwrap_or(1);
    let words = entry.words().max(new.words());
    let first = match measured {
        Some(m) => (m as f64 * LIST_HEADROOM).ceil() as u64,
        None => INITIAL_ENTRIES_PER_PARTICLE * n + 256,
    };
    if n * per_particle <= limit && 4 * words * first <= limit {
        return Windows::one(n);
    }
    let a_particle = match measured {
        Some(m) => ((m as f64 * LIST_HEADROOM) / n.max(1) as f64).ceil() as u64,
        None => 0,
    };
    let lists = 4 * WINDOW_ENTRIES_PER_PARTICLE.max(a_particle) * words;
    Windows::choose(n, per_particle.max(lists), limit)
}

/// List entries a particle the automatic windows leave room for (the lists hold 3.7–3.8 a
/// particle with their headroom and wall entries on the dense bench packings, `powder
/// bench`).
const WINDOW_ENTRIES_PER_PARTICLE: u64 = 6;

/// Binds every kernel of the step to the run's buffers and the mirrors' textures, window
/// by window where a kernel works on windows (`blocks`: the blocked buffers' bytes a
/// window).
fn bind_all(
    device: &wgpu::Device,
    program: &Program,
    (layout, records, blocks): (&StateLayout, &[(&RecordLayout, u64)], &Blocks),
    (mirrors, windows): (&Mirrors, &WindowBindings),
    grid: &GridSort,
    buffers: [Vec<(String, &wgpu::Buffer)>; 2],
) -> Result<Bound, PowderError> {
    let mut list: Vec<(String, &wgpu::Buffer)> = buffers.into_iter().flatten().collect();
    list.push(("grid".into(), grid.params()));
    list.push(("sorted_index".into(), grid.sorted_index()));
    list.push(("cell_start".into(), grid.cell_start()));
    let refs: Vec<(&str, &wgpu::Buffer)> = list.iter().map(|(n, b)| (n.as_str(), *b)).collect();
    let textures = mirrors.view_bytes();
    let pass = |name: &str| -> Result<Pass, PowderError> {
        let kernel = program.kernel(name)?.clone();
        let groups = windows.groups(device, &kernel, (&refs, blocks), &mirrors.views())?;
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
    })
}

/// The step's kernels, bound to the run's buffers.
struct Bound {
    kick_drift: Pass,
    decide: Pass,
    gather: Pass,
    count_neighbours: Pass,
    neighbours: Pass,
    commit: Pass,
    remap: Pass,
    copy_back_history: Pass,
    force: Pass,
    kick: Pass,
    collect_kick_drift: Pass,
    collect: Pass,
    /// The moving-wall kernels, only for scenes with moving / servo-controlled walls.
    wall_move: Option<Pass>,
    wall_servo: Option<Pass>,
    wall_servo_apply: Option<Pass>,
}

/// One kernel with its bind groups: one a window where it works on windows, else one.
struct Pass {
    kernel: Kernel,
    groups: Vec<wgpu::BindGroup>,
    /// (global name, bytes) of every distinct resource the group binds (`gpu::traffic`).
    bound: Vec<(String, u64)>,
}

impl Pass {
    /// One workgroup (a window).
    fn once(&self, pass: &mut wgpu::ComputePass<'_>, max_per_dim: u32) {
        for group in &self.groups {
            self.kernel.dispatch_workgroups(pass, group, 1, max_per_dim);
        }
    }

    /// Workgroup counts from `args` at byte `offset` (each window's dispatch the same).
    fn indirect(&self, pass: &mut wgpu::ComputePass<'_>, args: &wgpu::Buffer, offset: u64) {
        for group in &self.groups {
            self.kernel.dispatch_indirect(pass, group, args, offset);
        }
    }
}

/// A compute pass, its start timestamped while the pass profile runs.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    clock: Option<&PassClock>,
) -> wgpu::ComputePass<'e> {
    let mut pass = encoder.begin_compute_pass(&Default::default());
    if let Some(c) = clock {
        c.start(&mut pass);
    }
    pass
}

/// The end of `name`'s dispatches, timestamped while the pass profile runs.
fn mark(pass: &mut wgpu::ComputePass<'_>, clock: Option<&PassClock>, name: &'static str) {
    if let Some(c) = clock {
        c.mark(pass, name);
    }
}

/// How a recorded step starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Drift {
    /// No drift (the initial forces).
    None,
    /// `kick_drift`: the first step of a batch.
    Plain,
    /// `collect_kick_drift`: the previous step's collect and closing kick, then the drift.
    AfterStep,
}

/// A snapshot read back from the device, in the scene's particle order.
#[derive(Clone, Debug)]
pub struct GpuState {
    /// Particle centres, m (f32 on the device, widened to f64).
    pub positions: Vec<DVec3>,
    /// Particle velocities, m/s (f32 on the device, widened to f64).
    pub velocities: Vec<DVec3>,
    /// Angular velocities; empty when the scene does not rotate (as
    /// `CpuEngine::angular_velocities`).
    pub angular_velocities: Vec<DVec3>,
}

/// One contact's history keyed by (particle, partner) persistent ids.
pub type KeyedHistory = ((u32, u32), ContactHistory);

/// Choices of a GPU run that are not part of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuOptions {
    /// Keep the energy ledger and contact statistics on the device
    /// ([`GpuEngine::energies`], [`GpuEngine::contact_stats`], [`GpuEngine::wall_forces`]):
    /// 32 bytes per neighbour slot and 64 per particle more, and about 20 % of the step.
    /// Default on; `powder run --no-ledger` turns it off.
    pub ledger: bool,
    /// Quiet batches (`gpu::quiet`): batches recorded without the per-step rebuild
    /// decision where no rebuild is expected, run again with it where one was needed.
    /// Results are bitwise the same either way. Default [`QuietBatches::Auto`].
    pub quiet: QuietBatches,
    /// The neighbour lists' first capacity, entries a window (all entries with one
    /// window; default: a guess the first rebuild
    /// grows to 1.25× what it needs). Lists grow whenever a rebuild needs more — the batch
    /// halts at that rebuild and finishes after the growth, bitwise as without it — so
    /// this only saves those halts where the need is known.
    pub list_entries: Option<u64>,
    /// The software adapter's paths: the state read through texture mirrors, and quiet
    /// batches under [`QuietBatches::Auto`] (`None`: by the adapter kind,
    /// `GpuContext::is_software`). Results are bitwise the same either way.
    pub software_paths: Option<bool>,
    /// Particles a window holds (`gpu::window`: a power of two; every array blocked by
    /// window), `None` for one window holding all. Results are bitwise the same either
    /// way; more windows take more list entries (each window's block is sized for the
    /// fullest).
    pub window_particles: Option<u64>,
    /// Keep what [`GpuEngine::contact_network`] reads (each contact's prior) where neither
    /// the ledger nor the force jumps keep it: 12 bytes a list entry, and as much or more
    /// in the rebuild's new lists (about 24–32 bytes a list entry in all). Default off;
    /// `powder run` turns it on for the scene's `contact_output`.
    pub contacts: bool,
}

impl Default for GpuOptions {
    fn default() -> Self {
        Self {
            ledger: true,
            quiet: QuietBatches::Auto,
            list_entries: None,
            software_paths: None,
            window_particles: None,
            contacts: false,
        }
    }
}

/// What quiet batches need: (buffer of the state a batch changes, its batch-start copy),
/// the forecast and the counts.
struct Quiet {
    mode: QuietBatches,
    copies: Vec<Saved>,
    /// The lists' history and priors at a batch's start (the new lists live in the
    /// entries' per-step fields, which the batch writes).
    lists: wgpu::Buffer,
    forecast: Forecast,
    /// The device's rebuild count at the end of the last batch (u64::MAX: unknown).
    rebuilds: u64,
    kept: u64,
    rolled_back: u64,
}

/// A range of a buffer a quiet batch may change, and where its batch-start copy goes.
#[derive(Clone)]
struct Saved {
    from: wgpu::Buffer,
    from_at: u64,
    to: wgpu::Buffer,
    to_at: u64,
    bytes: u64,
}

impl Saved {
    /// All of `from` into `to`.
    fn whole(from: &wgpu::Buffer, to: wgpu::Buffer) -> Self {
        Self {
            from: from.clone(),
            from_at: 0,
            bytes: from.size(),
            to,
            to_at: 0,
        }
    }

    fn save(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.from, self.from_at, &self.to, self.to_at, self.bytes);
    }

    fn restore(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.to, self.to_at, &self.from, self.from_at, self.bytes);
    }
}

/// The lists' wall entries read back (`GpuEngine::read_wall_entries`).
struct WallEntries {
    /// Each particle's `ids` (state order).
    ids: Vec<[u32; 4]>,
    /// The entries buffer's bytes.
    entries: Vec<u8>,
    /// (particle k in state order, wall, record index), in k's order.
    found: Vec<(usize, usize, u64)>,
}

/// What the host reads after a batch: the monitor and the skin state.
struct BatchReport {
    monitor: Vec<u32>,
    skin: Vec<u32>,
}

impl BatchReport {
    /// The list entries a rebuild needed when the batch halted for them (`commit`).
    fn halted(&self) -> Option<u64> {
        (self.monitor[7] != 0).then_some(self.monitor[11] as u64)
    }

    /// Steps of a halted batch completed before the one that halted (`decide` counts the
    /// steps begun).
    fn completed(&self) -> u64 {
        (self.monitor[10] as u64).saturating_sub(1)
    }
}

/// The GPU simulation of one scene.
pub struct GpuEngine {
    ctx: GpuContext,
    /// Simulated time, s (kept in f64 on the host).
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    dt: f64,
    n: u32,
    /// Entries the neighbour lists have room for (grown when a rebuild needs more).
    entries: u64,
    origin: DVec3,
    /// Cell width per axis (the f32 values the kernels use), m.
    h: DVec3,
    radius: Vec<f64>,
    mass: Vec<f64>,
    grid: GridSort,
    /// The grid sort's key pass bound to A's cells (made once: the buffer never changes).
    /// The grid sort's `cell_keys` bind groups, one a window.
    grid_keys: Vec<wgpu::BindGroup>,
    /// The windows and their uniforms (`gpu::window`).
    windowing: WindowBindings,
    /// The state (A).
    state: StateSet,
    /// Texture copies of A's cells, offsets and predictions for the force pass.
    mirrors: Mirrors,
    /// Quiet batches, where the scene allows them (no moving walls, no pouring).
    quiet: Option<Quiet>,
    /// The lists a rebuild builds (B; bound in the kernels, never read by the host).
    _new_lists: NewLists,
    /// A rebuild's in-place re-sort of the state.
    permutation: Permutation,
    /// The step's other buffers.
    b: StepBuffers,
    /// Offsets in `b.args`: the rebuild's per-particle passes', and every step's
    /// (per particle, then one workgroup), with the values the latter take.
    rebuild_args: u64,
    step_args: u64,
    step_args_full: [[u32; 3]; 2],
    /// A halted batch's remaining steps, the first without its drift (`run_steps`).
    resume: Option<u64>,
    /// The pass profile's timestamps while it runs ([`Self::time_passes`]).
    clock: Option<PassClock>,
    /// Times the lists grew (each a halted batch, or the first build).
    growths: u64,
    program: Program,
    bound: Bound,
    max_per_dim: u32,
    kind: Composition,
    /// What the step variant keeps beyond the forces (ledger, force jumps).
    keeps: Keeps,
    n_walls: u32,
    /// (name, bytes) of every buffer allocated for the run.
    buffers: Vec<(String, u64)>,
    gravity: DVec3,
    /// Engaged contacts that left the neighbour lists within one step (monitor[3]).
    dropped: u64,
    /// Deepest overlap/a12 since the run monitor last looked, and a particle with a
    /// contact beyond `run::MAX_OVERLAP_RATIO` if any (monitor[4], [5]).
    peak: Option<(f64, Option<usize>)>,
    /// A particle whose centre left the domain box (monitor[6]).
    escaped: Option<usize>,
    /// A rebuild's scans of the new lists' lengths into their first entries (the pair
    /// lists', `lower`'s), dispatched indirectly from `args` at `scan_args`.
    /// Two a window, in window order (`lower`'s after each window's pair lists').
    scans: Vec<ExclusiveScan>,
    scan_args: [u64; 2],
    /// Unit normals of the walls (into the domain).
    wall_normals: Vec<DVec3>,
    /// How each wall moves, and the walls on the device (they move: state).
    wall_motion: Vec<crate::scene::WallMotion>,
    /// The phase (`WallMotion::index_at`) each wall is in on the device.
    wall_phase: Vec<Option<usize>>,
    /// The prescribed walls' points in f64, integrated on the host (v·dt per step, as the
    /// CPU does) and written to the device at every batch, so f32 rounding of the device's
    /// per-step moves never accumulates.
    wall_points: Vec<DVec3>,
    /// Pouring: when each particle (persistent id) appears, whether it has (mirrored in
    /// the device's `active` buffer, written at the batch where that changes), the energy
    /// it brings (½mv² − m·g·x at its insertion, which it keeps until then) and the sum
    /// brought so far.
    insert_at: Vec<f64>,
    active: Vec<bool>,
    insert_energy: Vec<f64>,
    inserted: f64,
}

/// Everything that evolves in a GPU run, read back from the device: what a checkpoint
/// stores to resume bitwise on the same adapter, and what the run monitor restores when it
/// stops a run. The buffers are the current state set (the other set is rewritten by every
/// step before it is read), the neighbour lists, the Verlet-skin state and the
/// per-particle ledger.
#[derive(Clone, Debug)]
pub struct GpuSavedState {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    pub(crate) dropped: u64,
    /// The adapter it ran on (a resume elsewhere continues, but not bitwise).
    pub adapter: String,
    /// (name, bytes), in a fixed order.
    pub(crate) buffers: Vec<(String, Vec<u8>)>,
    /// The host's f64 points of the walls.
    pub(crate) wall_points: Vec<DVec3>,
    /// Which particles have appeared, and the energy they brought.
    pub(crate) active: Vec<bool>,
    pub(crate) inserted: f64,
    /// The composed contact law's layout (`Composition::layout`): the history words in the
    /// buffers mean what it says.
    pub(crate) layout: String,
}

impl GpuSavedState {
    /// Whether the state was taken by a run that keeps the energy ledger
    /// ([`GpuOptions::ledger`]): it then holds the per-particle ledger, and restores only
    /// into an engine that keeps it too (and the reverse).
    pub fn has_ledger(&self) -> bool {
        self.buffers
            .iter()
            .any(|(name, _)| name == "particle_ledger")
    }
}

/// The value every item of `values` has, or `mixed` when they differ or there is none.
fn common_or<T: PartialEq + Copy>(values: impl IntoIterator<Item = T>, mixed: T) -> T {
    let mut values = values.into_iter();
    match values.next() {
        Some(first) if values.all(|v| v == first) => first,
        _ => mixed,
    }
}

/// The step's pipeline-overridable constants for a scene: what it does not use is folded
/// out of its pipelines (the WGSL `override`s of step.wgsl and the model files). The
/// model constants go only to variants that declare them (wgpu refuses unknown names).
fn pipeline_constants(
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

/// How many steps from step `steps` on start before time `t` (step k starts at k·dt, the
/// time the phases and insertions are decided at), at least 1: a batch of that many ends
/// where the first step at or after `t` would start, whatever the rounding of the ratio.
fn steps_before(steps: u64, dt: f64, t: f64) -> u64 {
    let starts = |k: u64| (steps + k) as f64 * dt;
    let mut j = (((t - starts(0)) / dt).ceil().max(1.0)) as u64;
    while j > 1 && starts(j - 1) >= t {
        j -= 1;
    }
    while starts(j) < t {
        j += 1;
    }
    j
}

/// The device's flags of which particles have appeared (1) or not yet (0).
fn appeared_flags(active: &[bool]) -> Vec<u32> {
    active.iter().map(|&a| u32::from(a)).collect()
}

/// The step a scene's pair models need and their pair table as bytes.
fn pair_table(models: &[ContactModel]) -> (Composition, Vec<u8>) {
    let kind = Composition::of(models);
    let rows = models.iter().flat_map(|m| kind.pair_row(m)).collect();
    (kind, rows)
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
    fn build(
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
        let target_cells = (4 * n).max(64) as f64;
        let h0 = gpu_cell_width(
            cutoff.max((extent.x * extent.y * extent.z / target_cells).cbrt()) * (1.0 + 1e-6),
        );
        // A periodic axis holds a whole number of cells, at least 3 (so the 27 cells around
        // a particle are distinct and a pair meets one image): its cells are period/count
        // wide, rounded to f32, so the device's period is dims·h (within 2^-24 of the
        // scene's; see README).
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
        let mut grid =
            GridSort::with_cell_widths(&ctx, n as u32, dims, [h.x as f32, h.y as f32, h.z as f32])?;
        // the windows (`gpu::window`): asked for, or one where every array fits a binding
        let n_walls = scene.walls.len() as u64;
        let layout0 = StateLayout::new(0, kind.rotation());
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
        let windowing = WindowBindings::new(&ctx.device, windows);
        let device = &ctx.device;
        let mut alloc = Allocator::new(device, ctx.max_storage_binding());
        alloc.list = vec![
            ("grid.params".into(), grid.params().size()),
            ("grid.keys".into(), grid.keys().size()),
            ("grid.cell_count".into(), grid.cell_count().size()),
            ("grid.cell_start".into(), grid.cell_start().size()),
            ("grid.sorted_index".into(), grid.sorted_index().size()),
        ];
        // list entries a window: a first guess, grown by the first rebuild to what it needs
        let per_window = if windows.count == 1 {
            n as u64
        } else {
            windows.len
        };
        let entries = options
            .list_entries
            .unwrap_or(INITIAL_ENTRIES_PER_PARTICLE * per_window + 256)
            .max(1);
        let entries = window_entries(&windows, entries);
        let [entry_layout, ..] = kind.records(keeps);
        check_entries(
            (entries, &windows),
            entry_layout.words(),
            n as u64,
            (ctx.max_storage_binding(), alloc.max_buffer),
        )?;
        let servo_walls = scene.walls.iter().any(|w| w.motion.servo());
        let state = StateSet::new(&mut alloc, (n as u64, entries, windows), &kind, keeps);
        let new_lists = NewLists::new(&kind, keeps);
        let dt32 = r.dt as f32;
        let particle_ledger = ledger.then(|| alloc.buffer("particle_ledger", 64 * n as u64));
        // the per-particle buffers fit before the initial state is written into them
        alloc.check(n)?;
        // Initial state, in scene order (the first sort orders it).
        let mut cells = Vec::with_capacity(n);
        let mut offs = Vec::with_capacity(n);
        let mut vels = Vec::with_capacity(n);
        // the compensations (stored − true) of velocity and position, and the radius's
        // rounding residual: the kernels' x − c is the scene's value to ~1e-16 relative
        let mut kahan_v: Vec<[f32; 4]> = Vec::with_capacity(n);
        let mut kahan_o: Vec<[f32; 4]> = Vec::with_capacity(n);
        for (p, m) in scene.particles.iter().zip(&r.mass) {
            let x = DVec3::from_array(p.position);
            let (mut c, mut o) = encode3(x, origin, h);
            c[3] = p.material as i32;
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
        // the prediction kick_drift writes each step, for the initial forces
        let vpred0: Vec<[f32; 4]> = vels
            .iter()
            .map(|v| {
                let p = |i: usize| v[i] + 0.5 * dt32 * acc0[i];
                [p(0), p(1), p(2), v[3]]
            })
            .collect();
        // uploaded in the grid's order (the first sort keeps it): every particle starts in
        // its window, and a window's neighbours hold its partners (`gpu::window`)
        let order = grid_order(&cells, dims);
        let words = |v: &[[f32; 4]]| -> Vec<[u32; 4]> {
            order.iter().map(|&i| bytemuck::cast(v[i])).collect()
        };
        let initial = |name: &str| -> Option<Vec<[u32; 4]>> {
            match name {
                "cell" => Some(order.iter().map(|&i| bytemuck::cast(cells[i])).collect()),
                "off" => Some(words(&offs)),
                "vel" => Some(words(&vels)),
                "acc" => Some(words(&vec![acc0; n])),
                "vpred" => Some(words(&vpred0)),
                "kahan_v" => Some(words(&kahan_v)),
                "kahan_o" => Some(words(&kahan_o)),
                // persistent id; the lists and wall entries come with the first rebuild
                "ids" => Some(order.iter().map(|&i| [i as u32, 0, 0, 0]).collect()),
                // ω as the scene gives it, w = I = 2/5·m·r²
                "omega" => {
                    let omega: Vec<[f32; 4]> = scene
                        .particles
                        .iter()
                        .zip(&r.mass)
                        .map(|(p, m)| {
                            let [x, y, z] = p.angular_velocity.map(|c| c as f32);
                            [x, y, z, (0.4 * m * p.radius * p.radius) as f32]
                        })
                        .collect();
                    Some(words(&omega))
                }
                _ => None,
            }
        };
        let q0 = &ctx.queue;
        for b in Buffer::ALL {
            q0.write_buffer(state.buffer(b), 0, &state.layout.pack(b, &initial));
        }
        let walls: Vec<WallGpu> = scene
            .walls
            .iter()
            .map(|w| WallGpu::from_scene(w, origin, h))
            .collect();
        let moving_walls = scene.walls.iter().any(|w| w.motion.moves());
        let step = StepParams {
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
        };
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
        let mut wanted = vec![
            "kick_drift",
            "decide",
            "gather",
            "count_neighbours",
            "neighbours",
            "commit",
            "remap",
            "copy_back_history",
            "force",
            "kick",
            "collect_kick_drift",
            "collect",
        ];
        // the wall kernels only where walls move (not compiled otherwise)
        if moving_walls {
            wanted.push("wall_move");
        }
        if servo_walls {
            wanted.extend(["wall_servo", "wall_servo_apply"]);
        }
        let constants = pipeline_constants(scene, &r, &all_models);
        let program = Program::specialized(
            &ctx,
            &kind.variant(keeps, software),
            Some(&wanted),
            &constants,
        )?;
        let max_per_dim = ctx.limits().max_compute_workgroups_per_dimension;
        // the scans that place the new lists (counts -> first entries)
        let scan_program = Program::with_entry_points(
            &ctx,
            &crate::gpu::shaders::stage("grid").expect("grid is a stage"),
            Some(&["scan_blocks", "scan_add"]),
        )?;
        // each window's: a window's n (the last one's counts beyond n stay 0)
        let scanned = if windows.count == 1 {
            n as u32
        } else {
            windows.len as u32
        };
        let region = windows.len as u32;
        let mut scans = Vec::new();
        for w in 0..windows.count {
            // (window w's block of `rows`: B's counts and rows, then `lower`'s)
            let block = 4 * 4 * windows.len;
            let part = match windows.count {
                1 => Part::whole(&rows),
                _ => Part {
                    buffer: &rows,
                    offset: w * block,
                    size: Some(block),
                },
            };
            for (count, row) in [(0, 1), (2, 3)] {
                scans.push(ExclusiveScan::with_parts(
                    &ctx,
                    &scan_program,
                    (part, count * region),
                    (part, row * region),
                    scanned,
                )?);
            }
        }
        // the indirect arguments of a rebuild (the grid sort's, one per-particle pass's,
        // the scans'), and the ones decide writes each step (those, or zeros)
        let sort_args = grid.indirect_args();
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
        let particle_args = split_workgroups(per_window.div_ceil(per_group), max_per_dim);
        // (every window's scans have the first window's dispatches)
        let rebuild_args = 12 * sort_args.len() as u64;
        let scan_args = [
            rebuild_args + 12,
            rebuild_args + 12 + 12 * scans[0].indirect_args().len() as u64,
        ];
        let full: Vec<u32> = sort_args
            .into_iter()
            .chain([particle_args])
            .chain(scans[0].indirect_args())
            .chain(scans[1].indirect_args())
            .flatten()
            .collect();
        let full_args = alloc.buffer("full_args", 4 * full.len() as u64);
        q0.write_buffer(&full_args, 0, bytemuck::cast_slice(&full));
        // then every step's: one invocation per particle, one workgroup
        let step_args = 4 * full.len() as u64;
        let args = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("args"),
            size: step_args + 24,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        alloc.list.push(("args".into(), args.size()));
        // the force pass's read-only copies of what it loads per pair (`gpu::mirror`)
        let s0 = &state;
        let at = |name: &str| s0.layout.place(name).map_or(0, |(_, at)| at);
        let mut mirrored = vec![
            (
                "m_cell",
                Some("m_cell_out"),
                &s0.state,
                at("cell"),
                wgpu::TextureFormat::Rgba32Sint,
            ),
            (
                "m_off",
                Some("m_off_out"),
                &s0.state,
                at("off"),
                wgpu::TextureFormat::Rgba32Float,
            ),
            (
                "m_vpred",
                None,
                &s0.state,
                at("vpred"),
                wgpu::TextureFormat::Rgba32Float,
            ),
        ];
        if let Some((_, w)) = s0.layout.place("wpred") {
            mirrored.push((
                "m_wpred",
                None,
                &s0.state,
                w,
                wgpu::TextureFormat::Rgba32Float,
            ));
        }
        // (only on the software adapter's path)
        if !software {
            mirrored.clear();
        }
        let mirrors = Mirrors::new(device, n as u32, &mirrored)?;
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
            (&windowing, Some(NewLists::lent(&state, entries))),
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
            particle_ledger,
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
            [state.named(), b.named()],
        )?;
        // the grid sort's keys, a window at a time
        let state_block = state_fields * windows.len * crate::gpu::state::FIELD_BYTES;
        let grid_keys = (0..windows.count)
            .map(|w| {
                let cells = windowing.part(&state.state, state_block, w);
                grid.keys_bind_group_part(cells, &windowing.uniforms[w as usize])
            })
            .collect::<Result<Vec<_>, _>>()?;
        // quiet batches: not where walls move (their rebuild trigger is decide's) nor where
        // particles appear (an insertion rebuilds)
        let pouring = scene.pours();
        let mode = options.quiet.on(software);
        let quiet = (mode != QuietBatches::Off && !moving_walls && !pouring).then(|| {
            // copies of buffers that fit
            let mut alloc = Allocator::new(device, u64::MAX);
            // the state into copies of its own (the lists' history into `quiet.lists`:
            // `quiet_copies`)
            let mut copies = Vec::new();
            let a = &state;
            let own = [
                ("state", Some(&a.state)),
                ("motion", Some(&a.motion)),
                ("particle_ledger", b.particle_ledger.as_ref()),
            ];
            for (name, b) in own {
                if let Some(b) = b {
                    let copy = alloc.buffer(&format!("quiet.{name}"), b.size());
                    copies.push(Saved::whole(b, copy));
                }
            }
            let lists = new_lists.quiet_lists(&mut alloc, (entries, &windows));
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
        });
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
            rebuild_args,
            step_args,
            step_args_full: [particle_args, [1, 1, 1]],
            resume: None,
            clock: None,
            growths: 0,
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
            scan_args,
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
            insert_energy: scene
                .particles
                .iter()
                .zip(&mass)
                .map(|(p, m)| {
                    let spin = 0.2 * m * p.radius * p.radius;
                    0.5 * m * DVec3::from_array(p.velocity).length_squared()
                        + spin * DVec3::from_array(p.angular_velocity).length_squared()
                        - m * DVec3::from_array(scene.gravity).dot(DVec3::from_array(p.position))
                })
                .collect(),
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

    /// The time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.n as usize
    }

    /// Whether the scene has no particles.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Times the neighbour lists grew so far: each a batch that halted at a rebuild whose
    /// lists did not fit, finished after the growth (the first build included).
    pub fn list_growths(&self) -> u64 {
        self.growths
    }

    /// Entries the neighbour lists have room for now, all windows' (each pair a particle
    /// evaluates takes one, and its partner's `lower` one): grown by a rebuild that needs
    /// more.
    pub fn list_entries(&self) -> u64 {
        self.entries * self.state.layout.windows().count
    }

    /// The windows the particles are blocked into (`gpu::window`).
    pub fn windows(&self) -> Windows {
        *self.state.layout.windows()
    }

    /// Whether the engine takes the software adapter's paths (texture mirrors, quiet
    /// batches; `GpuOptions::software_paths`).
    pub fn adapter_is_software(&self) -> bool {
        !self.mirrors.is_empty()
    }

    /// Name of the adapter the engine runs on.
    pub fn adapter(&self) -> &str {
        &self.ctx.summary.name
    }

    /// Particle radii in the scene's order, m (f64, as given).
    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

    /// Particle masses in the scene's order, kg (f64).
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Whether particles carry angular velocity (some contact model has friction or
    /// rolling resistance), as `CpuEngine::rotates`.
    pub fn rotates(&self) -> bool {
        self.kind.rotation()
    }

    /// Whether the run keeps the energy ledger and contact statistics ([`GpuOptions`]).
    pub fn has_ledger(&self) -> bool {
        self.b.particle_ledger.is_some()
    }

    /// Whether the run places the impulses of force jumps inside the step (the scene's
    /// `jump_impulses`).
    pub fn places_jumps(&self) -> bool {
        self.keeps.jumps
    }

    /// The name of the step's shader module (`Composition::variant_name`).
    pub fn variant_name(&self) -> String {
        self.kind.variant_name(self.keeps, !self.mirrors.is_empty())
    }

    /// The step's kernels this engine built pipelines for (entry points of the step
    /// variant, and the re-sort's `permute`; the moving-wall kernels only where walls
    /// move), in recording order.
    pub fn kernel_names(&self) -> Vec<String> {
        let b = &self.bound;
        [
            Some(&b.kick_drift),
            Some(&b.collect_kick_drift),
            b.wall_move.as_ref(),
            Some(&b.decide),
            Some(&b.gather),
            Some(&b.count_neighbours),
            Some(&b.neighbours),
            Some(&b.commit),
            Some(&b.remap),
            Some(&b.copy_back_history),
            Some(&b.force),
            b.wall_servo.as_ref(),
            Some(&b.collect),
            Some(&b.kick),
        ]
        .into_iter()
        .flatten()
        .map(|p| p.kernel.name.clone())
        .flat_map(|name| {
            // the re-sort's kernel (its own module) once the new lists are known to fit
            let permute = (name == "commit").then(|| "permute".to_string());
            std::iter::once(name).chain(permute)
        })
        .collect()
    }

    /// The fields of the particle state, in buffer order (`gpu::state`).
    pub fn state_fields(&self) -> Vec<&'static str> {
        self.state.layout.names()
    }

    /// The fields of a list entry (`gpu::records`) with their bytes, in buffer order: the
    /// entries buffer (`A.entries`) holds this many bytes per entry of capacity.
    pub fn entry_fields(&self) -> Vec<(&'static str, u64)> {
        let l = &self.state.entry_layout;
        l.fields
            .iter()
            .map(|f| (f.name, 4 * f.kind.words()))
            .collect()
    }

    /// (kernel, storage buffers it binds) of every kernel built for the step, the most
    /// first: wgpu limits them per shader stage (WebGPU's default: 8).
    pub fn storage_bindings(&self) -> Vec<(String, u32)> {
        let mut v: Vec<(String, u32)> = self
            .program
            .kernels
            .values()
            .map(|k| (k.name.clone(), k.storage_buffers))
            .collect();
        v.sort_by_key(|(name, b)| (std::cmp::Reverse(*b), name.clone()));
        v
    }

    /// The step variant this scene runs (see [`Self::variant_name`]).
    pub fn kind(&self) -> &Composition {
        &self.kind
    }

    /// Every device buffer allocated for the run, as (name, bytes), in allocation order:
    /// the grid sort's index buffers (`grid.*`; its internal scan and large-cell scratch,
    /// a few bytes per cell / 32 particles, are not listed), the particle state (`A.*`),
    /// the lists a rebuild builds (`B.*`), the uniform step parameters, the pair table,
    /// walls, the per-step scratch, the re-sort's scratch (`permute.scratch`) and the
    /// quiet batches' copies (`quiet.*`). Angular buffers (`A.omega`, `A.alpha`,
    /// `A.wpred`) appear only when the scene rotates.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        self.buffers.clone()
    }

    /// Total bytes of [`Self::buffers`].
    pub fn buffer_bytes(&self) -> u64 {
        self.buffers.iter().map(|(_, b)| b).sum()
    }

    /// What each pass of a step binds, for the estimate of the bytes a step moves
    /// (`gpu::traffic`, where the counting is explained): the passes of every step in
    /// recording order (`collect_kick_drift`, the wall kernels where walls move, `decide`,
    /// the mirror copies, `force`), then those of a rebuild (the cell sort's as `grid.*`,
    /// `gather`, `count_neighbours`, the lists' scans as `lists.*`, `neighbours`, `commit`,
    /// the re-sort's `permute *`, `remap`, `copy_back_history`).
    pub fn traffic(&self) -> Vec<PassTraffic> {
        let b = &self.bound;
        let pass = |p: &Pass, when| PassTraffic::new(p.kernel.name.clone(), when, p.bound.clone());
        let mut out = vec![pass(&b.collect_kick_drift, When::Step)];
        out.extend(b.wall_move.as_ref().map(|p| pass(p, When::Step)));
        out.push(pass(&b.decide, When::Step));
        if !self.mirrors.is_empty() {
            out.push(PassTraffic::new(
                "mirror copies",
                When::Step,
                self.mirrors.copy_traffic(),
            ));
        }
        out.push(pass(&b.force, When::Step));
        out.extend(b.wall_servo.as_ref().map(|p| pass(p, When::Step)));
        for (name, mut bound) in self.grid.traffic(&self.state.state) {
            // the sort reads the state's first field, the cells
            for (global, bytes) in &mut bound {
                if global == "cells" {
                    *bytes = self.state.layout.field_bytes();
                }
            }
            out.push(PassTraffic::new(
                format!("grid.{name}"),
                When::Rebuild,
                bound,
            ));
        }
        if !self.mirrors.is_empty() {
            out.push(pass(&b.gather, When::Rebuild));
        }
        out.push(pass(&b.count_neighbours, When::Rebuild));
        for scan in &self.scans {
            for (name, bound) in scan.traffic() {
                out.push(PassTraffic::new(
                    format!("lists.{name}"),
                    When::Rebuild,
                    bound,
                ));
            }
        }
        out.push(pass(&b.neighbours, When::Rebuild));
        out.push(pass(&b.commit, When::Rebuild));
        for (name, bound) in self.permutation.traffic() {
            out.push(PassTraffic::new(name, When::Rebuild, bound));
        }
        for p in [&b.remap, &b.copy_back_history] {
            out.push(pass(p, When::Rebuild));
        }
        out
    }

    /// Records one step: drift, decide whether to rebuild, on a rebuild (indirect: no
    /// workgroups otherwise) sort, build the new lists in B (count, place, fill), re-sort
    /// the state in place, remap the history and copy the lists back; then the forces. Their collect and the closing kick are recorded
    /// with the next step (`Drift::AfterStep`) or by [`Self::record_finish`]. `quiet`:
    /// without `decide` and the rebuild chain (a quiet batch, `gpu::quiet`).
    fn record_step(&self, encoder: &mut wgpu::CommandEncoder, drift: Drift, quiet: bool) {
        let bound = &self.bound;
        let max = self.max_per_dim;
        let clock = self.clock.as_ref();
        let (args, at, step) = (&self.b.args, self.rebuild_args, self.step_args);
        {
            let mut pass = begin(encoder, clock);
            if drift != Drift::None {
                let (first, name) = match drift {
                    Drift::AfterStep => (&bound.collect_kick_drift, "collect_kick_drift"),
                    _ => (&bound.kick_drift, "kick_drift"),
                };
                first.indirect(&mut pass, args, step);
                mark(&mut pass, clock, name);
                if let Some(p) = &bound.wall_move {
                    p.indirect(&mut pass, args, step + 12);
                    mark(&mut pass, clock, "wall_move");
                }
            }
            if !quiet {
                bound.decide.once(&mut pass, max);
                mark(&mut pass, clock, "decide");
            }
        }
        if !quiet {
            clock.inspect(|c| c.start_between(encoder));
            self.grid.encode_indirect(encoder, &self.grid_keys, args, 0);
            clock.inspect(|c| c.mark_between(encoder, "grid sort"));
            let mut pass = begin(encoder, clock);
            if !self.mirrors.is_empty() {
                bound.gather.indirect(&mut pass, args, at);
                mark(&mut pass, clock, "gather");
            }
            bound.count_neighbours.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "count_neighbours");
            for (scan, &offset) in self.scans.iter().zip(self.scan_args.iter().cycle()) {
                scan.record_indirect(&mut pass, args, offset);
            }
            mark(&mut pass, clock, "list scans");
            bound.neighbours.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "neighbours");
            bound.commit.once(&mut pass, max);
            mark(&mut pass, clock, "commit");
            self.permutation.encode_indirect(&mut pass, args, at);
            mark(&mut pass, clock, "permute");
            bound.remap.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "remap");
            bound.copy_back_history.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "copy_back_history");
        }
        // the state the forces see, drifted (and re-sorted on a rebuild)
        if !self.mirrors.is_empty() {
            clock.inspect(|c| c.start_between(encoder));
            self.mirrors.encode(encoder);
            clock.inspect(|c| c.mark_between(encoder, "mirror copies"));
        }
        let mut pass = begin(encoder, clock);
        bound.force.indirect(&mut pass, args, step);
        mark(&mut pass, clock, "force");
        if let Some(p) = &bound.wall_servo {
            p.indirect(&mut pass, args, step + 12);
            mark(&mut pass, clock, "wall_servo");
        }
        if let Some(p) = &bound.wall_servo_apply {
            p.indirect(&mut pass, args, step + 12);
            mark(&mut pass, clock, "wall_servo_apply");
        }
    }

    /// Records `collect` (the forces of the step just recorded are then complete) and,
    /// with `kick`, the closing kick: at the end of a batch, or without the kick after the
    /// initial forces.
    fn record_finish(&self, encoder: &mut wgpu::CommandEncoder, kick: bool) {
        let (args, at) = (&self.b.args, self.step_args);
        let clock = self.clock.as_ref();
        let mut pass = begin(encoder, clock);
        self.bound.collect.indirect(&mut pass, args, at);
        mark(&mut pass, clock, "collect");
        if kick {
            self.bound.kick.indirect(&mut pass, args, at);
            mark(&mut pass, clock, "kick");
        }
    }

    /// Before a batch is submitted: the monitor zeroed, every step's dispatch arguments
    /// set (a halt zeroes them).
    fn start_batch(&self) {
        let q = &self.ctx.queue;
        q.write_buffer(&self.b.control, 0, &[0u8; MONITOR_BYTES as usize]);
        q.write_buffer(
            &self.b.args,
            self.step_args,
            bytemuck::cast_slice(&self.step_args_full),
        );
    }

    /// Grows the neighbour lists to `need` entries and headroom (`commit` halted a batch
    /// for them), keeping the current lists' history: the rebuild that needed the room
    /// runs again and remaps it.
    fn grow_lists(&mut self, need: u64) -> Result<(), PowderError> {
        // the headroom only as far as the bindings and the largest buffer hold (`need`
        // itself is checked)
        let windows = *self.state.layout.windows();
        let bytes = 4 * self.state.entry_layout.words();
        let max_buffer = self.ctx.limits().max_buffer_size;
        let most = (self.ctx.max_storage_binding() / (bytes * windows.covered()))
            .min(max_buffer / (bytes * windows.count))
            .min(windows.max_records());
        // (a window's block a whole number of 256 bytes where there are several)
        let most = match windows.count {
            1 => most,
            _ => most / MIN_WINDOW * MIN_WINDOW,
        };
        let entries = window_entries(
            &windows,
            ((need as f64 * LIST_HEADROOM).ceil() as u64).max(need + 64),
        )
        .min(most)
        .max(window_entries(&windows, need));
        self.growths += 1;
        self.resize_lists(entries, true)
    }

    /// Reallocates the lists' entries for `entries` entries (copying A's partner ids,
    /// history and ledger values when `keep`), tells the kernels, and binds them again.
    fn resize_lists(&mut self, entries: u64, keep: bool) -> Result<(), PowderError> {
        let layout = self.state.entry_layout.clone();
        let windows = *self.state.layout.windows();
        check_entries(
            (entries, &windows),
            layout.words(),
            self.n as u64,
            (
                self.ctx.max_storage_binding(),
                self.ctx.limits().max_buffer_size,
            ),
        )?;
        let device = &self.ctx.device;
        let mut alloc = Allocator::new(device, self.ctx.max_storage_binding());
        let mut encoder = device.create_command_encoder(&Default::default());
        let old = (self.state.entries.clone(), self.entries);
        let bytes = layout.windowed_bytes(entries, &windows);
        let block = layout.block_bytes(entries);
        let new = blocked_buffer(&mut alloc, &windows, ("A.entries", bytes), block);
        alloc.check(self.n as usize)?;
        if keep {
            // window by window, region by region: each region's start moves with the
            // capacity
            for w in 0..windows.count {
                for name in ["hist_pid", "hist", "prior"] {
                    if let Some((_, words)) = layout.place(name) {
                        let first = windows.record(w, 0);
                        let from = layout.byte_of(name, old.1, &windows, first).unwrap_or(0);
                        let to = layout.byte_of(name, entries, &windows, first).unwrap_or(0);
                        let bytes = 4 * words * old.1.min(entries);
                        encoder.copy_buffer_to_buffer(&old.0, from, &new, to, bytes);
                    }
                }
            }
        }
        self.state.entries = new;
        if let Some(q) = &mut self.quiet {
            // (a copy, never bound: no binding limit, as at the start)
            let mut copies = Allocator::new(device, u64::MAX);
            q.lists = self
                ._new_lists
                .quiet_lists(&mut copies, (entries, &windows));
            alloc.list.extend(copies.list);
        }
        self.ctx.queue.submit([encoder.finish()]);
        // the re-sort's scratch: the new lists' room again, or its own where a window's
        // block of it no longer holds it
        self.permutation.bind(
            &self.ctx,
            (self.grid.params(), self.grid.sorted_index()),
            self.n,
            &self.state.permuted(),
            (&self.windowing, Some(NewLists::lent(&self.state, entries))),
        )?;
        alloc
            .list
            .push(("permute.scratch".into(), self.permutation.scratch_bytes()));
        for (name, bytes) in alloc.list {
            if let Some(entry) = self.buffers.iter_mut().find(|(n, _)| *n == name) {
                entry.1 = bytes;
            }
        }
        self.entries = entries;
        self.ctx.queue.write_buffer(
            &self.b.step,
            std::mem::offset_of!(StepParams, list_capacity) as u64,
            bytemuck::bytes_of(&(entries as u32)),
        );
        self.bound = bind_all(
            &self.ctx.device,
            &self.program,
            (
                &self.state.layout,
                &self.state.records(&self._new_lists, entries),
                &self.state.blocks(entries),
            ),
            (&self.mirrors, &self.windowing),
            &self.grid,
            [self.state.named(), self.b.named()],
        )?;
        Ok(())
    }

    /// Runs `steps` steps with a GPU timestamp after every pass (all windows'
    /// dispatches of it) and returns the device time each pass took: a real run's, its
    /// rebuilds where they fall. An error where the adapter gives no timestamps inside
    /// compute passes (`gpu::timestamps::FEATURES`).
    pub fn profile(&mut self, steps: u64) -> Result<PassProfile, PowderError> {
        self.clock = Some(PassClock::new(&self.ctx)?);
        let before = self.rebuilds()?;
        let t = std::time::Instant::now();
        let ran = self.run_steps(steps);
        let wall_seconds = t.elapsed().as_secs_f64();
        let clock = self.clock.take();
        ran?;
        let clock = clock.expect("the clock runs until here");
        if clock.overflowed() {
            return Err(PowderError::Run(format!(
                "a batch of the pass profile wrote more than {} timestamps",
                wgpu::QUERY_SET_MAX_QUERIES
            )));
        }
        Ok(PassProfile {
            steps,
            rebuilds: self.rebuilds()? - before,
            wall_seconds,
            passes: clock
                .totals()
                .into_iter()
                .map(|(name, s)| (name.to_string(), s))
                .collect(),
        })
    }

    /// Neighbour-list rebuilds so far (the first, before the first step, included): reads
    /// the device's counter back.
    pub fn rebuilds(&self) -> Result<u64, PowderError> {
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(&self.ctx, encoder, &[(&self.b.control, CONTROL_BYTES)])?;
        Ok(u32s(&out[0])[SKIN_OFFSET as usize / 4 + 2] as u64)
    }

    /// The forces of the initial state (no drift, no kick), so the first step kicks with them.
    /// Contacts present at the start carry stored energy, not dissipation: the ledger's
    /// dissipation (booked from the contacts' entry edges) is zeroed afterwards, as on the CPU.
    /// `rewindow`: where the lists outgrow one automatic window's binding (but not the
    /// largest buffer), the entries they need (`Some`) instead of an error: the caller
    /// builds again in windows.
    fn initial_forces(&mut self, rewindow: bool) -> Result<Option<u64>, PowderError> {
        // the initial contacts crossed nothing: no force jump placed
        self.set_jumps(false);
        loop {
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            self.start_batch();
            self.record_step(&mut encoder, Drift::None, false);
            self.record_finish(&mut encoder, false);
            let report = self.submit_batch(encoder)?;
            // the first lists did not fit the first guess: grown, built again
            match report.halted() {
                Some(need) => {
                    self.check_windows(&report.monitor)?;
                    if rewindow && self.outgrows_one_window(need) {
                        return Ok(Some(need));
                    }
                    self.grow_lists(need)?
                }
                None => break self.apply_monitor(&report.monitor)?,
            }
        }
        if let Some(buf) = &self.b.particle_ledger {
            let mut rows = self.read_particle_ledger()?;
            for p in rows.chunks_mut(4) {
                p[2][0] = 0.0;
                p[2][1] = 0.0;
            }
            self.ctx
                .queue
                .write_buffer(buf, 0, bytemuck::cast_slice(&rows));
        }
        self.set_jumps(self.keeps.jumps);
        Ok(None)
    }

    /// Whether `need` list entries overflow the one window's binding while their buffer
    /// would still fit the largest (what windows fix).
    fn outgrows_one_window(&self, need: u64) -> bool {
        let windows = *self.state.layout.windows();
        let words = self.state.entry_layout.words();
        let max_buffer = self.ctx.limits().max_buffer_size;
        windows.count == 1
            && 4 * words * need > self.ctx.max_storage_binding()
            && 4 * words * need <= max_buffer
            && need * words <= u32::MAX as u64
    }

    /// Whether the steps recorded from now on place the force jumps (`StepParams::jumps`).
    fn set_jumps(&self, on: bool) {
        let at = std::mem::offset_of!(StepParams, jumps) as u64;
        self.ctx
            .queue
            .write_buffer(&self.b.step, at, bytemuck::bytes_of(&u32::from(on)));
    }

    /// Submits a recorded batch and reads the monitor and the skin state back.
    fn submit_batch(&self, mut encoder: wgpu::CommandEncoder) -> Result<BatchReport, PowderError> {
        let mut sources = vec![(&self.b.control, CONTROL_BYTES)];
        let stamps = self.clock.as_ref().and_then(|c| c.resolve(&mut encoder));
        sources.extend(stamps);
        let out = submit_and_read(&self.ctx, encoder, &sources)?;
        if let (Some(clock), Some(stamps)) = (&self.clock, out.get(1)) {
            clock.take(stamps);
        }
        let words = u32s(&out[0]);
        let (monitor, skin) = words.split_at(MONITOR_BYTES as usize / 4);
        Ok(BatchReport {
            monitor: monitor.to_vec(),
            skin: skin.to_vec(),
        })
    }

    /// Takes in what a batch's monitor holds: its records, and an error for what stops a run.
    /// An error where a rebuild found a particle's neighbours beyond its window's
    /// bindings (monitor[1]): the batch halted before anything read them.
    fn check_windows(&self, m: &[u32]) -> Result<(), PowderError> {
        if m[1] == 0 {
            return Ok(());
        }
        let w = self.state.layout.windows();
        Err(PowderError::Run(format!(
            "step {}: a particle's neighbours lie more than one window of {} particles away in the sorted order (a window's dispatches bind it and its neighbours only): the packing's layers of cells hold more particles than a window; run with larger windows where the adapter's binding limit allows (`--window-particles`, GpuOptions::window_particles)",
            self.steps, w.len
        )))
    }

    fn apply_monitor(&mut self, m: &[u32]) -> Result<(), PowderError> {
        self.dropped += m[3] as u64;
        let ratio = f32::from_bits(m[4]) as f64;
        let beyond = (m[5] != 0).then(|| m[5] as usize - 1);
        if self.peak.is_none_or(|(r, _)| ratio > r) {
            self.peak = Some((ratio, beyond.or(self.peak.and_then(|p| p.1))));
        }
        if m[6] != 0 && self.escaped.is_none() {
            self.escaped = Some(m[6] as usize - 1);
        }
        if m[2] != 0 {
            return Err(PowderError::Run(format!(
                "step {}: {} particles got a non-finite acceleration; the time step may be too large",
                self.steps, m[2]
            )));
        }
        Ok(())
    }

    /// Writes the prescribed walls' exact points and their velocities at the current time;
    /// returns how many steps the velocities stay valid (until the next switch of a
    /// schedule), at least 1.
    fn prescribe_walls(&self) -> u64 {
        let mut valid = u64::MAX;
        for (w, m) in self.wall_motion.iter().enumerate() {
            if let Some(t) = m.next_switch(self.time) {
                // steps that start before the switch keep this phase (as on the CPU)
                valid = valid.min(steps_before(self.steps, self.dt, t));
            }
            if !matches!(m.at(self.time), WallPhase::Velocity(_)) {
                continue;
            }
            let v = m.prescribed_velocity(self.time);
            self.write_wall(w, [v[0] as f32, v[1] as f32, v[2] as f32, 0.0]);
        }
        valid
    }

    /// Writes wall `w` to the device at the host's point, with `velocity` and the motion
    /// of its phase now.
    fn write_wall(&self, w: usize, velocity: [f32; 4]) {
        let mut wall = WallGpu::new(
            self.wall_points[w],
            self.wall_normals[w],
            self.origin,
            self.h,
        );
        wall.velocity = velocity;
        wall.motion = WallGpu::motion_code(self.wall_motion[w].at(self.time));
        let at = (w * std::mem::size_of::<WallGpu>()) as u64;
        self.ctx
            .queue
            .write_buffer(&self.b.walls, at, bytemuck::bytes_of(&wall));
    }

    /// Puts each wall whose phase changes at this batch's start into its new phase on the
    /// device, where it starts at rest: a servo wall's point (kept by the device, not the
    /// host) is read back first.
    fn switch_wall_phases(&mut self) -> Result<(), PowderError> {
        let changed: Vec<usize> = (0..self.wall_motion.len())
            .filter(|&w| self.wall_motion[w].index_at(self.time) != self.wall_phase[w])
            .collect();
        let phase_of = |w: usize, i: Option<usize>| {
            i.map_or(WallPhase::Rest, |i| self.wall_motion[w].phases[i].1)
        };
        let servo_before = changed
            .iter()
            .any(|&w| matches!(phase_of(w, self.wall_phase[w]), WallPhase::Servo { .. }));
        let now = if servo_before {
            self.walls_now()?
        } else {
            Vec::new()
        };
        for w in changed {
            if matches!(phase_of(w, self.wall_phase[w]), WallPhase::Servo { .. }) {
                self.wall_points[w] = now[w].0;
            }
            self.write_wall(w, [0.0; 4]);
            self.wall_phase[w] = self.wall_motion[w].index_at(self.time);
        }
        Ok(())
    }

    /// Writes which particles have appeared to the device (where the scene pours: else
    /// all have, and the kernels do not ask).
    fn write_appeared(&self) {
        if self.b.appeared.size() >= 4 * self.active.len() as u64 {
            self.ctx.queue.write_buffer(
                &self.b.appeared,
                0,
                bytemuck::cast_slice(&appeared_flags(&self.active)),
            );
        }
    }

    /// Activates the particles whose insertion time has come (at the start of a step whose
    /// time has reached it, as on the CPU), writing the device's flags when they change;
    /// returns how many steps until the next insertion (at least 1).
    fn insert_due(&mut self) -> u64 {
        let mut changed = false;
        let mut next = u64::MAX;
        for i in 0..self.active.len() {
            if self.active[i] {
                continue;
            }
            if self.insert_at[i] <= self.time {
                self.active[i] = true;
                self.inserted += self.insert_energy[i];
                changed = true;
            } else {
                next = next.min(steps_before(self.steps, self.dt, self.insert_at[i]));
            }
        }
        if changed {
            self.write_appeared();
        }
        next
    }

    /// Advances the host's points of the prescribed walls by `steps` steps.
    fn advance_prescribed_walls(&mut self, steps: u64) {
        for (w, m) in self.wall_motion.iter().enumerate() {
            if matches!(m.at(self.time), WallPhase::Velocity(_)) {
                let v = DVec3::from_array(m.prescribed_velocity(self.time));
                for _ in 0..steps {
                    self.wall_points[w] += self.dt * v;
                }
            }
        }
    }

    /// Each wall's point now (where its plane passes) and its velocity over the last step,
    /// read back from the device.
    pub fn walls_now(&self) -> Result<Vec<(DVec3, DVec3)>, PowderError> {
        if self.wall_normals.is_empty() {
            return Ok(Vec::new());
        }
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(&self.ctx, encoder, &[(&self.b.walls, self.b.walls.size())])?;
        let walls: Vec<WallGpu> = bytemuck::pod_collect_to_vec(&out[0]);
        Ok(walls
            .iter()
            .take(self.wall_normals.len())
            .map(|w| {
                // the stored point less its residual along the normal (`WallGpu::offset`)
                let n = DVec3::new(w.normal[0] as f64, w.normal[1] as f64, w.normal[2] as f64);
                let p = crate::gpu::layout::decode3(w.cell, w.offset, self.origin, self.h)
                    - w.offset[3] as f64 * n;
                let v = DVec3::new(
                    w.velocity[0] as f64,
                    w.velocity[1] as f64,
                    w.velocity[2] as f64,
                );
                (p, v)
            })
            .collect())
    }

    /// Runs `steps` steps, `STEPS_PER_SUBMIT` per submission, checking the monitor after each.
    pub fn run_steps(&mut self, steps: u64) -> Result<(), PowderError> {
        let mut left = steps;
        while left > 0 {
            // the rest of a halted batch starts with the halted step, drifted already, and
            // keeps the batch's boundaries (walls and insertions are set at them)
            let (batch, first) = match self.resume.take() {
                Some(rest) => (rest.min(left), Drift::None),
                None => {
                    self.switch_wall_phases()?;
                    let batch = left
                        .min(STEPS_PER_SUBMIT)
                        .min(self.prescribe_walls())
                        .min(self.insert_due());
                    (batch, Drift::Plain)
                }
            };
            let quiet = match first {
                Drift::Plain => self.quiet_batch(batch)?,
                _ => None,
            };
            let report = match quiet {
                Some(report) => report,
                None => {
                    self.start_batch();
                    let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                    for i in 0..batch {
                        let drift = if i == 0 { first } else { Drift::AfterStep };
                        self.record_step(&mut encoder, drift, false);
                    }
                    self.record_finish(&mut encoder, true);
                    self.submit_batch(encoder)?
                }
            };
            let done = match report.halted() {
                Some(_) => report.completed(),
                None => batch,
            };
            // the walls moved in every step begun with a drift
            let moved = (done + u64::from(report.halted().is_some()))
                .saturating_sub(u64::from(first == Drift::None));
            self.advance_prescribed_walls(moved);
            self.steps += done;
            // (steps·dt: the same bits wherever batches end or halt)
            self.time = self.steps as f64 * self.dt;
            left -= done;
            self.apply_monitor(&report.monitor)?;
            match report.halted() {
                Some(need) => {
                    self.check_windows(&report.monitor)?;
                    self.grow_lists(need)?;
                    self.resume = Some(batch - done);
                }
                None => self.observe(batch, &report),
            }
        }
        Ok(())
    }

    /// How step `i` of a (quiet) batch starts: each step's closing kick goes with the next
    /// step's drift.
    fn drift_of(i: u64) -> Drift {
        if i == 0 {
            Drift::Plain
        } else {
            Drift::AfterStep
        }
    }

    /// Tells the rebuild forecast what a kept batch ended with.
    fn observe(&mut self, batch: u64, report: &BatchReport) {
        if let Some(q) = &mut self.quiet {
            let rebuilt = report.skin[2] as u64 != q.rebuilds;
            let since = rebuilt.then_some(report.monitor[9] as u64);
            q.forecast
                .observe(batch, since, f32::from_bits(report.monitor[8]) as f64);
            q.rebuilds = report.skin[2] as u64;
        }
    }

    /// Runs `batch` steps as a quiet batch (`gpu::quiet`) when the scene allows it and the
    /// forecast expects no rebuild: the batch's report when it was kept, `None` when it did
    /// not run or was rolled back (the state is then as before: run it the normal way).
    fn quiet_batch(&mut self, batch: u64) -> Result<Option<BatchReport>, PowderError> {
        let Some(q) = &self.quiet else {
            return Ok(None);
        };
        if !q.forecast.quiet(batch, q.mode) {
            return Ok(None);
        }
        let copies = self.quiet_copies(q);
        self.start_batch();
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for c in &copies {
            c.save(&mut encoder);
        }
        for i in 0..batch {
            self.record_step(&mut encoder, Self::drift_of(i), true);
        }
        self.record_finish(&mut encoder, true);
        let report = self.submit_batch(encoder)?;
        if report.skin[0] == 0 {
            // no step would have rebuilt: the batch is what the normal one computes
            if let Some(q) = &mut self.quiet {
                q.kept += 1;
            }
            return Ok(Some(report));
        }
        // some step needed a rebuild: back to the batch's start (its monitor is void: the
        // steps after the missed rebuild ran with stale lists)
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for c in &copies {
            c.restore(&mut encoder);
        }
        self.ctx
            .queue
            .write_buffer(&self.b.control, SKIN_OFFSET, bytemuck::bytes_of(&0u32));
        self.ctx.queue.submit([encoder.finish()]);
        if let Some(q) = &mut self.quiet {
            q.rolled_back += 1;
        }
        Ok(None)
    }

    /// (buffer a quiet batch changes, where its batch-start copy goes): the state into the
    /// quiet batches' own copies, the lists' history and priors into `quiet.lists` (the
    /// new lists live in the entries' per-step fields, which the batch writes).
    fn quiet_copies(&self, q: &Quiet) -> Vec<Saved> {
        let (a, b) = (&self.state, &self._new_lists);
        let mut v = q.copies.clone();
        let windows = a.layout.windows();
        let (target, layout) = (&q.lists, &b.standalone());
        for w in 0..windows.count {
            let first = windows.record(w, 0);
            for (from, to) in [("hist", "new_hist"), ("prior", "new_prior")] {
                let cap = self.entries;
                if let (Some(at), Some(to_at), Some((_, words))) = (
                    a.entry_layout.byte_of(from, cap, windows, first),
                    layout.byte_of(to, cap, windows, first),
                    a.entry_layout.place(from),
                ) {
                    v.push(Saved {
                        from: a.entries.clone(),
                        from_at: at,
                        to: target.clone(),
                        to_at,
                        bytes: 4 * words * cap,
                    });
                }
            }
        }
        v
    }

    /// Quiet batches kept and rolled back so far (`gpu::quiet`); (0, 0) where the scene or
    /// the options allow none.
    pub fn quiet_batches(&self) -> (u64, u64) {
        self.quiet
            .as_ref()
            .map_or((0, 0), |q| (q.kept, q.rolled_back))
    }

    /// Reads positions, velocities and (when the scene rotates) angular velocities back,
    /// in the scene's particle order.
    pub fn state(&self) -> Result<GpuState, PowderError> {
        let s = &self.state;
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(
            &self.ctx,
            encoder,
            &[(&s.state, s.state.size()), (&s.motion, s.motion.size())],
        )?;
        let l = &s.layout;
        let (state, motion) = (&out[0], &out[1]);
        let cells: Vec<[i32; 4]> = l.unpack(state, "cell");
        let offs: Vec<[f32; 4]> = l.unpack(state, "off");
        let vels: Vec<[f32; 4]> = l.unpack(motion, "vel");
        let ids: Vec<[u32; 4]> = l.unpack(state, "ids");
        let kahan_v: Vec<[f32; 4]> = l.unpack(motion, "kahan_v");
        let kahan_o: Vec<[f32; 4]> = l.unpack(state, "kahan_o");
        let omegas: Vec<[f32; 4]> = l.unpack(motion, "omega");
        let vec3 = |v: [f32; 4]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
        let mut positions = vec![DVec3::ZERO; self.n as usize];
        let mut velocities = vec![DVec3::ZERO; self.n as usize];
        let mut angular_velocities = vec![DVec3::ZERO; omegas.len()];
        for k in 0..self.n as usize {
            let i = ids[k][0] as usize;
            // the compensated values: x − c
            positions[i] = crate::gpu::layout::decode3(cells[k], offs[k], self.origin, self.h)
                - vec3(kahan_o[k]);
            velocities[i] = vec3(vels[k]) - vec3(kahan_v[k]);
            if let Some(w) = omegas.get(k) {
                angular_velocities[i] = vec3(*w);
            }
        }
        Ok(GpuState {
            positions,
            velocities,
            angular_velocities,
        })
    }

    /// The state buffers, named as in [`GpuSavedState`].
    fn state_buffers(&self) -> Vec<(String, &wgpu::Buffer)> {
        let mut list = self.state.named();
        list.push(("rows".into(), &self.b.rows));
        list.push(("control".into(), &self.b.control));
        list.push(("walls".into(), &self.b.walls));
        list.push(("wall_ref".into(), &self.b.wall_ref));
        if let Some(l) = &self.b.particle_ledger {
            list.push(("particle_ledger".into(), l));
        }
        list
    }

    /// Reads the complete evolving state back (see [`GpuSavedState`]).
    pub fn save_state(&self) -> Result<GpuSavedState, PowderError> {
        let list = self.state_buffers();
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let sources: Vec<(&wgpu::Buffer, u64)> = list.iter().map(|(_, b)| (*b, b.size())).collect();
        let mut out = submit_and_read(&self.ctx, encoder, &sources)?;
        // the monitor words are a batch's scratch (zeroed when one starts): left out, so a
        // state saved after a quiet batch (no `decide` counting steps) and one saved after
        // a normal batch are the same bytes
        // so are the entries' per-step fields (pair forces and torques, the jumps' impulses:
        // the batch's last collect consumed them; `jump_normal` is written only in a step
        // that places a jump, so a rolled-back quiet batch may leave other bytes there)
        for ((name, _), bytes) in list.iter().zip(&mut out) {
            if name == "control" {
                bytes[..MONITOR_BYTES as usize].fill(0);
            }
            if name == "entries" {
                let layout = &self.state.entry_layout;
                let windows = self.state.layout.windows();
                for w in 0..windows.count {
                    let first = windows.record(w, 0);
                    for field in ["pair_force", "pair_torque", "jump", "jump_normal"] {
                        if let (Some(at), Some((_, words))) = (
                            layout.byte_of(field, self.entries, windows, first),
                            layout.place(field),
                        ) {
                            let (at, len) = (at as usize, (4 * words * self.entries) as usize);
                            bytes[at..at + len].fill(0);
                        }
                    }
                }
            }
        }
        Ok(GpuSavedState {
            time: self.time,
            steps: self.steps,
            dropped: self.dropped,
            adapter: self.ctx.summary.name.clone(),
            buffers: list.into_iter().map(|(n, _)| n).zip(out).collect(),
            wall_points: self.wall_points.clone(),
            active: self.active.clone(),
            inserted: self.inserted,
            layout: self.saved_layout(),
        })
    }

    /// What a saved state's words mean: the contact law's layout (`Composition::layout`),
    /// the list entries' fields (which the options change: the priors) and the windows
    /// where there are several.
    fn saved_layout(&self) -> String {
        let w = self.state.layout.windows();
        let fields: Vec<&str> = self
            .state
            .entry_layout
            .fields
            .iter()
            .map(|f| f.name)
            .collect();
        let law = format!("{}, entries [{}]", self.kind.layout(), fields.join(", "));
        match w.count {
            1 => law,
            _ => format!("{law} in windows of {} particles", w.len),
        }
    }

    /// Writes a saved state back: the run continues exactly as it would have from there.
    /// Refused when it does not fit this engine: taken with the other ledger option (the
    /// message names `--no-ledger`), or naming the buffer (another scene or step variant).
    pub fn restore_state(&mut self, saved: GpuSavedState) -> Result<(), PowderError> {
        // the ledger cannot be made up for steps already taken, nor dropped silently
        match (saved.has_ledger(), self.has_ledger()) {
            (true, false) => {
                return Err(PowderError::Run(
                    "the saved GPU state was taken with the energy ledger, and this run keeps none (`powder run --no-ledger`, GpuOptions { ledger: false }): resume it without --no-ledger".into(),
                ))
            }
            (false, true) => {
                return Err(PowderError::Run(
                    "the saved GPU state was taken without the energy ledger (`powder run --no-ledger`, GpuOptions { ledger: false }), and this run keeps it: resume it with --no-ledger (the ledger of the steps already taken cannot be rebuilt)".into(),
                ))
            }
            _ => {}
        }
        if saved.layout != self.saved_layout() {
            return Err(PowderError::Run(format!(
                "the saved GPU state's contact law is laid out as `{}`, this run's as `{}` (another scene, window size, contact output option or powder version): rerun the scene from the start, or resume it with the options it was taken with",
                saved.layout,
                self.saved_layout()
            )));
        }
        // the lists' capacity the state was saved with (its entries' size)
        let windows = *self.state.layout.windows();
        let entry_bytes = 4 * self.state.entry_layout.words() * windows.count;
        let entries = saved
            .buffers
            .iter()
            .find(|(name, _)| name == "entries")
            .map_or(self.entries, |(_, bytes)| bytes.len() as u64 / entry_bytes);
        let list = self.state_buffers();
        let names: Vec<&String> = list.iter().map(|(n, _)| n).collect();
        let saved_names: Vec<&String> = saved.buffers.iter().map(|(n, _)| n).collect();
        if names != saved_names {
            return Err(PowderError::Run(format!(
                "the saved GPU state holds buffers {saved_names:?}, this run needs {names:?} (another scene or step variant)"
            )));
        }
        // every size checked before anything changes (the per-entry arrays at the saved
        // capacity)
        for ((name, buf), (_, bytes)) in list.iter().zip(&saved.buffers) {
            let expected = if name == "entries" {
                (entry_bytes * entries).max(4)
            } else {
                buf.size()
            };
            if bytes.len() as u64 != expected {
                return Err(PowderError::Run(format!(
                    "the saved GPU buffer `{name}` has {} bytes, this run's has {expected} (another scene?)",
                    bytes.len(),
                )));
            }
        }
        if entries != self.entries {
            self.resize_lists(entries, false)?;
        }
        for ((_, buf), (_, bytes)) in self.state_buffers().iter().zip(&saved.buffers) {
            self.ctx.queue.write_buffer(buf, 0, bytes);
        }
        if saved.wall_points.len() == self.wall_points.len() {
            self.wall_points = saved.wall_points;
        }
        // the device's walls are in the phase of the last step run
        let last = saved.steps.saturating_sub(1) as f64 * self.dt;
        self.wall_phase = self.wall_motion.iter().map(|m| m.index_at(last)).collect();
        if saved.active.len() == self.active.len() {
            self.active = saved.active;
            self.write_appeared();
        }
        if let Some(q) = &mut self.quiet {
            q.forecast.forget();
            q.rebuilds = u64::MAX;
        }
        self.inserted = saved.inserted;
        self.time = saved.time;
        self.steps = saved.steps;
        self.dropped = saved.dropped;
        self.peak = None;
        self.escaped = None;
        Ok(())
    }

    /// The deepest overlap over a12 of any contact in any step since the last call, and a
    /// particle with a contact beyond `run::MAX_OVERLAP_RATIO` (0.5) if there was one.
    /// Resets the record. Measured on the device every step (a workgroup maximum, then one
    /// atomic per workgroup), read back once per batch of steps.
    pub fn take_peak_overlap(&mut self) -> Option<(f64, Option<usize>)> {
        self.peak.take()
    }

    /// A particle (persistent id) whose centre has left the domain box, checked on the
    /// device every step; `None` while all are inside.
    pub fn escaped(&self) -> Option<usize> {
        self.escaped
    }

    /// Engaged contacts (touching, or inside a non-contact adhesion range) that left the
    /// neighbour lists within a single step: each moved more than the skin (0.1·r_min) in
    /// one step. The ledger books them without the normal work of that last step; a
    /// non-zero count means the time step is far too large for the speeds in the scene.
    pub fn dropped_contacts(&self) -> u64 {
        self.dropped
    }

    /// The per-particle ledger rows (4 × vec4 per persistent id), or an error naming why
    /// there are none.
    fn read_particle_ledger(&self) -> Result<Vec<[f32; 4]>, PowderError> {
        let Some(buf) = &self.b.particle_ledger else {
            return Err(PowderError::Run(
                "this GPU run keeps no energy ledger (GpuOptions { ledger: false })".into(),
            ));
        };
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(&self.ctx, encoder, &[(buf, 64 * self.n as u64)])?;
        Ok(bytemuck::pod_collect_to_vec(&out[0]))
    }

    /// The energy ledger for a read-back state (kinetic and gravitational from it; stored
    /// and dissipated read from the device and summed in f64 in particle order), J. The
    /// same quantities as `CpuEngine::energies`.
    pub fn energies(&self, state: &GpuState) -> Result<Energies, PowderError> {
        Ok(self.energies_of(&self.read_particle_ledger()?, state))
    }

    /// [`Self::energies`] and [`Self::contact_stats`] from one read-back of the ledger.
    pub fn energies_and_contact_stats(
        &self,
        state: &GpuState,
    ) -> Result<(Energies, ContactStats), PowderError> {
        let rows = self.read_particle_ledger()?;
        Ok((self.energies_of(&rows, state), self.contact_stats_of(&rows)))
    }

    fn energies_of(&self, rows: &[[f32; 4]], state: &GpuState) -> Energies {
        let mut e = Energies {
            kinetic: self.kinetic_energy(state),
            gravitational: self.gravitational_energy(state),
            inserted: self.inserted_energy(),
            ..Default::default()
        };
        for p in rows.chunks(4) {
            e.dissipated += p[2][0] as f64 - p[2][1] as f64;
            e.elastic += p[2][2] as f64;
            e.wall_work += p[3][0] as f64 - p[3][1] as f64;
        }
        e
    }

    /// Contact counts and overlap statistics after the last step, as
    /// `CpuEngine::contact_stats` (each pair's evaluator counts it twice on the device).
    pub fn contact_stats(&self) -> Result<ContactStats, PowderError> {
        Ok(self.contact_stats_of(&self.read_particle_ledger()?))
    }

    fn contact_stats_of(&self, rows: &[[f32; 4]]) -> ContactStats {
        let mut counts = [0.0f64; 4];
        let mut sums = [0.0f64; 2];
        let mut s = ContactStats::default();
        for p in rows.chunks(4) {
            for c in 0..4 {
                counts[c] += p[0][c] as f64;
            }
            s.max_overlap = s.max_overlap.max(p[1][0] as f64);
            s.max_overlap_ratio = s.max_overlap_ratio.max(p[1][1] as f64);
            sums[0] += p[1][2] as f64;
            sums[1] += p[1][3] as f64;
        }
        s.contacts = (counts[0] / 2.0).round() as usize;
        s.wall_contacts = counts[1].round() as usize;
        s.non_contact = (counts[2] / 2.0 + counts[3]).round() as usize;
        let n = (self.n as f64).max(1.0);
        s.coordination = (2 * s.contacts + s.wall_contacts) as f64 / n;
        let touching = s.contacts + s.wall_contacts;
        if touching > 0 {
            s.mean_overlap_ratio = (sums[0] / 2.0 + sums[1]) / touching as f64;
        }
        s
    }

    /// Force of the particles on each wall after the last step, N: each wall contact's normal
    /// force (its prior) and tangential force (kept in its entry's pair torque where
    /// particles rotate; there is none otherwise). Right after a restore, until a step has
    /// run, the tangential part is missing (a saved state leaves the per-step fields out).
    pub fn wall_forces(&self) -> Result<Vec<DVec3>, PowderError> {
        let walls = self.wall_normals.len();
        let mut f = vec![DVec3::ZERO; walls];
        if walls == 0 {
            return Ok(f);
        }
        let s = &self.state;
        if s.entry_layout.place("prior").is_none() {
            return Err(PowderError::Run(
                "this GPU run keeps neither the energy ledger (GpuOptions { ledger: false }) nor force jumps, whose per-contact records hold the wall forces".into(),
            ));
        }
        let WallEntries { entries, found, .. } = self.read_wall_entries()?;
        let windows = s.layout.windows();
        // (overlap, normal force, .., 1 while engaged), each wall's particles in order
        for (_, w, e) in found {
            let read = s
                .entry_layout
                .read_vec4(&entries, "prior", (self.entries, windows), e);
            let row = read.unwrap_or_default();
            if row[3] > 0.0 {
                let t = s
                    .entry_layout
                    .read_vec3(&entries, "pair_torque", (self.entries, windows), e)
                    .map_or(DVec3::ZERO, |t| {
                        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
                    });
                f[w] -= row[1] as f64 * self.wall_normals[w] + t;
            }
        }
        Ok(f)
    }

    /// The lists read back: each particle's ids (persistent id, row, pairs, walls; in the
    /// device's order) and the entries' bytes.
    fn read_lists(&self) -> Result<(Vec<[u32; 4]>, Vec<u8>), PowderError> {
        let s = &self.state;
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let mut out = submit_and_read(
            &self.ctx,
            encoder,
            &[(&s.state, s.state.size()), (&s.entries, s.entries.size())],
        )?;
        let entries = out.pop().unwrap_or_default();
        Ok((s.layout.unpack(&out[0], "ids"), entries))
    }

    /// The wall entries of the lists (`WALL_ENTRY` in `shaders/step.wgsl`: particle k's
    /// contacts with the walls near it, after its pairs), read back.
    fn read_wall_entries(&self) -> Result<WallEntries, PowderError> {
        let s = &self.state;
        let (ids, entries) = self.read_lists()?;
        let windows = s.layout.windows();
        let mut found = Vec::new();
        for (k, &[_, row, pairs, walls]) in ids.iter().enumerate() {
            for e in (row + pairs) as u64..(row + pairs + walls) as u64 {
                // (the id, not `nbr`: a halted rebuild has refilled `nbr` but left the
                // old rows' ids, which `ids` still describe)
                let at = s.entry_layout.byte_of("hist_pid", self.entries, windows, e);
                let id = at.and_then(|at| entries.get(at as usize..at as usize + 4));
                if let Some(&[a, b, c, d]) = id {
                    let id = u32::from_le_bytes([a, b, c, d]);
                    if id & WALL_ENTRY != 0 && ((id & !WALL_ENTRY) as usize) < self.n_walls as usize
                    {
                        found.push((k, (id & !WALL_ENTRY) as usize, e));
                    }
                }
            }
        }
        Ok(WallEntries {
            ids,
            entries,
            found,
        })
    }

    /// The contact force on each particle after the last step, m·(a − g) from the device's
    /// accelerations, in the scene's particle order (N). For traces and diagnostics.
    pub fn contact_forces(&self) -> Result<Vec<DVec3>, PowderError> {
        let s = &self.state;
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        let out = submit_and_read(
            &self.ctx,
            encoder,
            &[(&s.state, s.state.size()), (&s.motion, s.motion.size())],
        )?;
        let acc: Vec<[f32; 4]> = s.layout.unpack(&out[1], "acc");
        let ids: Vec<[u32; 4]> = s.layout.unpack(&out[0], "ids");
        let mut f = vec![DVec3::ZERO; self.n as usize];
        for k in 0..self.n as usize {
            let i = ids[k][0] as usize;
            let a = DVec3::new(acc[k][0] as f64, acc[k][1] as f64, acc[k][2] as f64);
            f[i] = self.mass[i] * (a - self.gravity);
        }
        Ok(f)
    }

    /// Gravitational energy −Σ m·g·x of a read-back state (particles that have appeared),
    /// J; known with or without the ledger.
    pub fn gravitational_energy(&self, state: &GpuState) -> f64 {
        state
            .positions
            .iter()
            .zip(&self.mass)
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .fold(0.0, |g, ((x, m), _)| g - m * self.gravity.dot(*x))
    }

    /// Kinetic + gravitational energy brought in by the particles inserted so far (pouring;
    /// booked on the host), J; known with or without the ledger.
    pub fn inserted_energy(&self) -> f64 {
        self.inserted
    }

    /// Kinetic energy of a read-back state, translational plus rotational (I = 2/5·m·r²,
    /// as the CPU ledger), J; known with or without the ledger.
    pub fn kinetic_energy(&self, state: &GpuState) -> f64 {
        // particles that have not appeared yet do not count
        let translational: f64 = state
            .velocities
            .iter()
            .zip(&self.mass)
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .map(|((v, m), _)| 0.5 * m * v.length_squared())
            .sum();
        let rotational: f64 = state
            .angular_velocities
            .iter()
            .zip(self.mass.iter().zip(&self.radius))
            .zip(&self.active)
            .filter(|(_, &a)| a)
            .map(|((w, (m, r)), _)| 0.5 * 0.4 * m * r * r * w.length_squared())
            .sum();
        translational + rotational
    }

    /// Decodes one stored history element (the layout the composition declares).
    fn decode_history(&self, b: &[u8]) -> ContactHistory {
        self.kind.decode_history(b)
    }

    /// The history particle `i` keeps of its contact with particle `j` (persistent ids)
    /// after the last step, if `j` is in `i`'s neighbour list. Each side keeps its own
    /// copy: `contact_history(j, i)` has the same flags and ξ, and the negated tangential
    /// spring (see `shaders/step.wgsl`). For tests and diagnostics: reads buffers back.
    pub fn contact_history(
        &self,
        i: usize,
        j: usize,
    ) -> Result<Option<ContactHistory>, PowderError> {
        let key = (i as u32, j as u32);
        Ok(self
            .contact_histories()?
            .into_iter()
            .find(|(k, _)| *k == key)
            .map(|(_, h)| h))
    }

    /// Every listed contact's history, as ((i, j), history of i's side) by persistent ids,
    /// sorted: both orientations of each pair appear (one is stored, the other derived).
    /// For comparisons and diagnostics: reads the lists back.
    pub fn contact_histories(&self) -> Result<Vec<KeyedHistory>, PowderError> {
        let s = &self.state;
        let hb = self.kind.history_bytes();
        let (ids, entries) = self.read_lists()?;
        let cap = self.entries;
        let windows = s.layout.windows();
        let at = |name: &str, e: u64| s.entry_layout.byte_of(name, cap, windows, e).unwrap_or(0);
        let hb = hb as usize;
        let mut list = Vec::new();
        for &[pid, row, count, _] in &ids {
            // a particle's entries (ids.y, ids.z as in shaders/step.wgsl)
            for e in row as u64..(row + count) as u64 {
                let partner = u32s(&entries[at("hist_pid", e) as usize..][..4])[0];
                let h = at("hist", e) as usize;
                // one stored history per pair, in its evaluator's frame; the partner sees
                // it mirrored (the tangential spring negated)
                let h = self.decode_history(&entries[h..h + hb]);
                let seen_by_partner = self.kind.mirror_history(h);
                list.push(((pid, partner), h));
                list.push(((partner, pid), seen_by_partner));
            }
        }
        list.sort_by_key(|c| c.0);
        Ok(list)
    }

    /// The engaged contacts after the last step (touching, exerting a force or storing
    /// energy), as [`CpuEngine::contact_network`](crate::cpu::CpuEngine::contact_network)
    /// gives them: each pair from its lower id's side, pairs by (i, j), then wall contacts
    /// by (wall, particle). Reads the lists back; needs the contacts' priors (the ledger,
    /// the force jumps or [`GpuOptions::contacts`]). Right after a restore the forces are
    /// those of the next step's first evaluation: zero until a step has run.
    pub fn contact_network(&self) -> Result<ContactNetwork, PowderError> {
        let s = &self.state;
        if !self.keeps.prior() {
            return Err(PowderError::Run(
                "this GPU run keeps no per-contact state to output (it has no energy ledger and no force jumps): run it with GpuOptions { contacts: true } (`powder run` does where the scene's contact_output is on)".into(),
            ));
        }
        let hb = self.kind.history_bytes() as usize;
        let (ids, entries) = self.read_lists()?;
        let entries = &entries;
        let (cap, windows) = (self.entries, s.layout.windows());
        let layout = &s.entry_layout;
        let id_of = |e: u64| {
            let at = layout.byte_of("hist_pid", cap, windows, e)? as usize;
            entries
                .get(at..at + 4)
                .map(bytemuck::pod_read_unaligned::<u32>)
        };
        let vec3 = |name: &str, e: u64| {
            let v = layout.read_vec3(entries, name, (cap, windows), e);
            v.map_or(DVec3::ZERO, |v| {
                DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
            })
        };
        let history = |e: u64| -> Option<ContactHistory> {
            let at = layout.byte_of("hist", cap, windows, e)? as usize;
            Some(self.decode_history(entries.get(at..at + hb)?))
        };
        let mut pairs = Vec::new();
        let mut walls = Vec::new();
        for &[pid, row, count, near_walls] in &ids {
            for e in row as u64..(row + count + near_walls) as u64 {
                let (Some(partner), Some(prior), Some(h)) = (
                    id_of(e),
                    layout.read_vec4(entries, "prior", (cap, windows), e),
                    history(e),
                ) else {
                    continue;
                };
                if prior[3] <= 0.0 {
                    continue;
                }
                let mut line = ContactLine {
                    i: pid as usize,
                    partner: Partner::Particle(partner as usize),
                    normal_force: prior[1] as f64,
                    force: vec3("pair_force", e),
                    overlap: prior[0] as f64,
                    history: h,
                    sliding: prior[3] > 1.5,
                };
                if partner & WALL_ENTRY != 0 {
                    let w = (partner & !WALL_ENTRY) as usize;
                    if w >= self.wall_normals.len() {
                        continue;
                    }
                    // the normal force from the prior, the tangential one kept in the
                    // entry's pair torque (a wall takes none)
                    line.partner = Partner::Wall(w);
                    line.force = line.normal_force * self.wall_normals[w] + vec3("pair_torque", e);
                    walls.push(((w, pid), line));
                } else {
                    if partner < pid {
                        // the pair from its lower id's side: the force on it, its view
                        line.i = partner as usize;
                        line.partner = Partner::Particle(pid as usize);
                        line.force = -line.force;
                        line.history = self.kind.mirror_history(h);
                    }
                    pairs.push(line);
                }
            }
        }
        pairs.sort_by_key(|c| match c.partner {
            Partner::Particle(j) => (c.i, j),
            Partner::Wall(w) => (c.i, w),
        });
        walls.sort_by_key(|(k, _)| *k);
        pairs.extend(walls.into_iter().map(|(_, c)| c));
        Ok(ContactNetwork {
            lines: pairs,
            fields: self.kind.history(),
        })
    }

    /// The history of particle `i`'s contact with wall `w` after the last step (zero when
    /// they are apart). For tests and diagnostics: reads buffers back.
    pub fn wall_contact_history(&self, w: usize, i: usize) -> Result<ContactHistory, PowderError> {
        let walls = self.n_walls as usize;
        if w >= walls {
            return Err(PowderError::Run(format!(
                "wall {w} does not exist (the scene has {walls})"
            )));
        }
        let hb = self.kind.history_bytes() as usize;
        let WallEntries {
            ids,
            entries,
            found,
        } = self.read_wall_entries()?;
        let k = ids
            .iter()
            .position(|p| p[0] as usize == i)
            .ok_or_else(|| PowderError::Run(format!("particle {i} does not exist")))?;
        let s = &self.state;
        let at = found
            .into_iter()
            .find(|&(kk, ww, _)| kk == k && ww == w)
            .and_then(|(_, _, e)| {
                s.entry_layout
                    .byte_of("hist", self.entries, s.layout.windows(), e)
            });
        // no entry: the wall was beyond reach + skin at the last rebuild, no history
        Ok(match at {
            Some(at) => self.decode_history(&entries[at as usize..at as usize + hb]),
            None => self.decode_history(&vec![0u8; hb]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::{self, wgsl_u32_const};

    #[test]
    fn gpu_control_layout_matches_wgsl() {
        let (module, _) = shaders::validate(&shaders::step_variant().source).unwrap();
        let (_, control) = module
            .global_variables
            .iter()
            .find(|(_, g)| g.name.as_deref() == Some("control"))
            .expect("the step declares `control`");
        let bytes = module.types[control.ty].inner.size(module.to_ctx());
        assert_eq!(bytes as u64, CONTROL_BYTES);
        assert_eq!(
            wgsl_u32_const(&module, "SKIN_MOVED") as u64 * 4,
            SKIN_OFFSET
        );
        assert_eq!(wgsl_u32_const(&module, "SKIN_REBUILDS"), 14);
        assert_eq!(wgsl_u32_const(&module, "WALL_ENTRY"), WALL_ENTRY);
    }
}
