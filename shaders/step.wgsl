// step.wgsl — one time step of the GPU engine: drift, a rebuild of the neighbour lists
// where one is due, forces, kick. Composed per scene (`Composition::variant` in
// `src/gpu/composition.rs`) after common.wgsl, the state's and records' accessors, the
// contact laws and sub-models the scene uses, overlap.wgsl, the generated interface this
// file calls (`PairRow`, `Hist`, `hist_*`, `pair_contact`, `pair_edges`,
// `pair_touch_jump`), the rotation, ledger and force-jump hooks (or their no-op twins)
// and the state's reads (buffers, or texture mirrors).
//
// The state lives in one buffer set, A, in the order of the last rebuild, updated in
// place. A step records `kick_drift` (within a batch `collect_kick_drift`, finishing the
// step before), `decide_lean`, `force` (`collect` and `kick` close a batch); `decide_lean`
// halts the batch where a particle or moving wall moved more than skin/2, and the host
// runs that step again with `decide` and the rebuild's passes (grid sort, `gather`,
// `count_neighbours`, scans, `neighbours`, `commit`, permute.wgsl, `remap`,
// `copy_back_history`; `RebuildChain` in `src/gpu/engine/record.rs`). The passes:
// `docs/architecture.md`, *The GPU engine*.
//
// One evaluation per pair: a rebuild splits each particle's neighbours (`evaluates`); k
// evaluates the pairs with the partners ahead of it along the separation's dominant axis
// (its list, with their history) and finds the others through `lower`. `force` leaves
// each pair's force (and the partner's torque) in the pair's slot, `collect` subtracts it
// from the partner: action = −reaction bitwise, one history per contact, handed over by
// `hist_mirror` where a re-sort makes the partner the evaluator (why not both sides:
// `docs/design_log.md`).
//
// `dt` first: with `gravity` at offset 0 Mesa lavapipe 22.3 ran slower and leaked
// (docs/design_log.md, *Measurements moved out of the code*).
struct StepParams {
    dt: f32,
    // Entries the neighbour lists have room for (each of the per-entry arrays).
    list_capacity: u32,
    n_materials: u32,
    n_walls: u32,
    gravity: vec3<f32>,
    // Largest distance beyond touching at which any pair interacts.
    reach: f32,
    // The domain box's extent in cells (the run monitor: a centre beyond it has left).
    extent_cells: vec3<f32>,
    // 1 when some wall is servo-controlled: the force kernel then writes each wall
    // entry's push (`store_wall_push`).
    servo_walls: u32,
    // 1 on periodic axes: cells wrap around (the axis holds a whole number >= 3 of cells,
    // so dims·cell_width is the period) and separations take the nearest image.
    periodic: vec3<u32>,
    // Always 0, but only known at run time: `opaque` hides a value behind it, so the
    // shader compiler cannot fold Kahan compensations ((x + y) − x) − y to 0 (Mesa's NIR
    // does, for floating-point operations not marked exact: measured on lavapipe).
    zero: u32,
    // The Verlet skin (m). A uniform rather than a storage value: on lavapipe each storage
    // access is a loop over the SIMD lanes.
    skin: f32,
    // 1 when the variant's force jumps are placed (`jump.wgsl`); 0 for the initial forces,
    // whose contacts crossed nothing.
    jumps: u32,
    // Per periodic axis, the scene's period less dims·h (h is rounded to f32), m: a wrap
    // and a separation across the seam add it (overlap.wgsl; 0 on other axes).
    period_lo: vec3<f32>,
}

fn opaque(x: vec3<f32>) -> vec3<f32> {
    return select(x, vec3<f32>(0.0), step.zero != 0u);
}

fn opaque1(x: f32) -> f32 {
    return select(x, 0.0, step.zero != 0u);
}

// False for a scene without periodic axes (set per pipeline by `gpu::engine`): the
// compiler then drops the wrapping from every separation and cell step.
override PERIODIC: bool = true;

fn periodic_axes() -> vec3<bool> {
    return vec3<bool>(PERIODIC) & (step.periodic != vec3<u32>(0u));
}

// A cell difference wrapped to the nearest periodic image on periodic axes.
fn nearest_image(dc: vec3<i32>) -> vec3<i32> {
    let n = vec3<i32>(grid.dims);
    let half = n / vec3<i32>(2);
    let p = periodic_axes();
    var w = select(dc, dc - n, p & (dc > half));
    w = select(w, w + n, p & (w < -half));
    return w;
}

// A cell coordinate wrapped into the grid on periodic axes. (Only non-negative operands
// of % and /: WGSL's remainder truncates, GLSL's % of a negative number is undefined.)
fn wrap_cell(c: vec3<i32>) -> vec3<i32> {
    let n = vec3<i32>(grid.dims);
    let periods = select(vec3<i32>(0), max(-c - vec3<i32>(1), vec3<i32>(0)) / n + vec3<i32>(1), c < vec3<i32>(0));
    return select(c, (c + periods * n) % n, periodic_axes());
}

// The run monitor's overlap limit over a12 (`run::MAX_OVERLAP_RATIO`; a test ties them).
const MONITOR_MAX_OVERLAP_RATIO: f32 = 0.5;

struct Wall {
    // A point of the plane as cell + offset (like particle positions); moves with the wall.
    // offset.w: the plane's rounding residual (`WallGpu::offset`).
    cell: vec4<i32>,
    offset: vec4<f32>,
    // Unit normal into the domain (xyz).
    normal: vec4<f32>,
    // Velocity over the current step (xyz): written by the host for prescribed motion (per
    // batch, split at the schedule's switch times), by wall_servo for servo control.
    velocity: vec4<f32>,
    // x: 0 fixed, 1 prescribed, 2 servo; y: the servo's force (N), z: its gain (m/s per
    // N), w: its largest speed (m/s).
    motion: vec4<f32>,
    // The normal's rounding residual (xyz: true − stored): the overlap's plane is the
    // true one also far from the stored point (`WallGpu::normal_lo`).
    normal_lo: vec4<f32>,
}

const WALL_SERVO: f32 = 2.0;

// False for a scene without walls (set per pipeline by `gpu::engine`): no kernel then
// contains wall code (on a SIMD adapter a loop body runs at least once per group of lanes,
// even when no lane has an iteration to do).
override WALLS: bool = true;

// The number of walls the kernels loop over (0 for a scene without: the loops vanish).
fn wall_count() -> u32 {
    return select(0u, step.n_walls, WALLS);
}

// True for a scene with one material (set per pipeline by `gpu::engine`): every pair reads
// pair row 0, an address the compiler then knows is the same for all invocations (one load,
// not a gather of the 64-byte row per lane and pair).
override ONE_MATERIAL: bool = false;

@group(0) @binding(20) var<uniform> step: StepParams;

// The particle state (the buffers `state` and `motion`: the generated
// load_<field>/store_<field> of `gpu::state`, composed before this file), in the order of
// the last rebuild; a rebuild re-sorts it in place. Its fields: cell (w: material, with `NOT_APPEARED` until it appears), off (w: radius), vel (w: mass),
// acc (w: the force pass's largest overlap/a12), vpred = v + dt/2·a (w: mass; the force
// pass reads one vec4 per partner for both), kahan_v and kahan_o (the Kahan compensations
// of the velocity and the offset: the f32 updates v += dt/2·a and o += dt·v add
// increments of a few ulps whose rounding would otherwise accumulate; true = stored − c),
// disp (the displacement since the last rebuild, w: the batch's largest overlap/a12 so
// far, folded in by the drift and reduced into the monitor by the batch-end collect),
// ids (persistent id, first list entry, pairs in the list, wall entries) and, where
// particles rotate, omega, alpha, wpred.
// (own_cell, own_off, own_vpred, sorted_cell, sorted_off, mirror_sorted: the state's
// reads, from state_mirrors.wgsl or state_buffers.wgsl)

// The neighbour lists' entries (`entries`: partner or wall, `lower`, partner id, history,
// prior; then this step's pair force and torque and force jump) and a rebuild's new lists
// (`new_entries`): the generated load_<field>/store_<field> of `gpu::records`.

// x + dx with Kahan compensation c (x_true = x − c): returns (x', c').
struct Compensated {
    x: vec3<f32>,
    c: vec3<f32>,
}

fn kahan_add(x: vec3<f32>, c: vec3<f32>, dx: vec3<f32>) -> Compensated {
    let y = dx - c;
    let t = opaque(x + y);
    return Compensated(t, (t - x) - y);
}

// kahan_add, leaving (x, c) as they are where dx is zero (a force jump's velocity change,
// zero in most steps: added the same way at a batch's end and within it, so batches of
// any length give the same bits).
fn kahan_add_nonzero(x: vec3<f32>, c: vec3<f32>, dx: vec3<f32>) -> Compensated {
    if (all(dx == vec3<f32>(0.0))) {
        return Compensated(x, c);
    }
    return kahan_add(x, c, dx);
}

// Whether each particle (by persistent id) has appeared (pouring: written by the host at the
// batch where its insertion time comes); `appear` copies it into the state (`NOT_APPEARED`
// in cell.w), where the step reads it. One that has not neither moves nor interacts.
@group(0) @binding(65) var<storage, read> appeared: array<u32>;

// False for a scene without pouring (set per pipeline): every particle is there from the
// start, and no kernel reads the flags.
override POURING: bool = true;

// Whether the particle whose cell is c has appeared.
fn has_appeared(c: vec4<i32>) -> bool {
    return !POURING || (c.w & NOT_APPEARED) == 0;
}

// The material of the particle whose cell is c.
fn material_of(c: vec4<i32>) -> u32 {
    return u32(c.w & ~NOT_APPEARED);
}

// Where particles appeared (the host wrote `appeared`): each one's flag into its cell.w.
@compute @workgroup_size(WG_SIZE)
fn appear(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    let c = load_cell(k);
    let flag = select(NOT_APPEARED, 0, appeared[load_ids(k).x] != 0u);
    store_cell(k, vec4<i32>(c.xyz, (c.w & ~NOT_APPEARED) | flag));
}

// The lists are compressed rows: particle k's entries are ids.y .. ids.y + ids.z of the
// entries' fields (nbr, hist_pid, hist, prior, the pair force and torque, ...), in
// sorted order, so consecutive particles' rows are consecutive within a window; its wall
// contacts follow, ids.w of them (`WALL_ENTRY`). `rows`
// holds four per-particle regions (blocked by window like the state's): the lengths and
// first entries of the lists a rebuild builds (B) and of the `lower` lists; the scans of
// `gpu::grid` turn each window's count region into its row region.
@group(0) @binding(90) var<storage, read_write> rows: array<u32>;
const ROWS_B_COUNT: u32 = 0u;
const ROWS_B_ROW: u32 = 1u;
const ROWS_LOWER_COUNT: u32 = 2u;
const ROWS_LOWER_ROW: u32 = 3u;

// (blocked by window like the state; the rows are local to the particle's window: the
// lists of a window's particles fill its block of entries, `gpu::window`)
fn row_at(region: u32, k: u32) -> u32 {
    return blocked(4u, region, k);
}

// Particle k's new list (B) and its `lower` list: the first entry (a record index) and
// the length.
fn b_first(k: u32) -> u32 {
    return record_index(win_of(k), rows[row_at(ROWS_B_ROW, k)]);
}

fn b_len(k: u32) -> u32 {
    return rows[row_at(ROWS_B_COUNT, k)];
}

fn lower_first(k: u32) -> u32 {
    return record_index(win_of(k), rows[row_at(ROWS_LOWER_ROW, k)]);
}

fn lower_len(k: u32) -> u32 {
    return rows[row_at(ROWS_LOWER_COUNT, k)];
}

// A list entry whose partner (`nbr`, and `hist_pid`) is WALL_ENTRY | w holds the
// particle's contact with wall w: the walls within reach + skin at the rebuild, after the
// pairs of its row (particle indices and ids stay below 2^31). So a wall contact takes
// room only where a particle is near a wall, and its history survives the re-sort as a
// pair's does (`remap`, by this id).
const WALL_ENTRY: u32 = 0x80000000u;

// A servo wall's push on a wall entry this step (the normal force, written by every force
// pass): kept in the entry's pair force, which a wall contact has no other use for.
fn store_wall_push(e: u32, push: f32) {
    store_pair_force(e, vec3<f32>(push, 0.0, 0.0));
}

fn load_wall_push(e: u32) -> f32 {
    return load_pair_force(e).x;
}

// The particle whose new list (ROWS_B_ROW, ROWS_B_COUNT) holds entry e: the last of e's
// window whose first entry is <= e
// (particles with empty lists share the next one's row).
fn entry_owner(e: u32) -> u32 {
    let w = rec_window(e);
    let local = rec_local(e);
    var lo = w * grid.window.y;
    var hi = min(lo + grid.window.y, grid.n_particles);
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (rows[row_at(ROWS_B_ROW, mid)] <= local) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Half lists (Newton's third law: each pair evaluated once): particle k's list (`nbr`,
// ids.z long, with the history slots) holds the partners whose pairs k evaluates
// (`evaluates`), `lower` (ROWS_LOWER_COUNT long) holds, for each other partner j, the slot of
// the pair in j's list, where `force` leaves the pair's force for `collect` (the
// entries' `lower` field: as many entries as the lists).
// (Per entry, this step: the force the evaluated pair exerts on the evaluator, xyz, which
// `collect` subtracts from the partner: `store_pair_force`, `load_pair_force`.)

// From the grid sort.
@group(0) @binding(43) var<storage, read> sorted_index: array<u32>;
@group(0) @binding(44) var<storage, read> cell_start: array<u32>;

// The end of cell `key`'s range of the sorted order: the next cell's start (`cell_start`
// is an exclusive scan over every cell, `grid.wgsl`).
fn cell_end(key: u32) -> u32 {
    if (key + 1u < grid.n_cells) {
        return cell_start[key + 1u];
    }
    return grid.n_particles;
}

// Pair models: materials x materials, then walls x materials.
@group(0) @binding(46) var<storage, read> pairs: array<PairRow>;
@group(0) @binding(47) var<storage, read_write> walls: array<Wall>;

// Each wall's point at the last rebuild (`decide`): a moving wall that has since moved more
// than skin/2 along its normal triggers the next one.
struct WallRef {
    cell: vec4<i32>,
    offset: vec4<f32>,
}

@group(0) @binding(74) var<storage, read_write> wall_ref: array<WallRef>;

// Between rebuilds a particle moves less than skin/2 and a wall less than skin/2 along its
// normal, so a wall beyond reach + skin at the rebuild stays out of range: `force`
// evaluates only the wall entries (and a far wall's contact has no history).

// The control words: [0, 12) the monitor, zeroed per batch of steps and read back after
// it (no per-step read-back):
// [0] = largest list length seen (atomicMax; a particle's list, walls included, or its
// `lower` list), [1] = 1 when a rebuild found a particle's neighbours beyond its window's
// bindings (`search`), [2] = non-finite
// acceleration count, [3] = engaged
// contacts dropped by a rebuild (ledger.wgsl), [4] = largest overlap/a12 of any contact
// (f32 bits, atomicMax; non-negative f32 bits order as the values), [5] = persistent id
// (+1) of a particle with a contact beyond MONITOR_MAX_OVERLAP_RATIO, [6] = persistent id
// (+1) of a particle whose centre left the domain box, [7] = why the batch halted (`halt`:
// HALT_GROW from `commit`, the new lists did not fit; HALT_REBUILD from `decide_lean`, a
// rebuild is due); for the host's forecast of the next rebuild
// (`gpu::quiet`): [8] = the largest displacement since the last rebuild at the batch's end
// (f32 bits; `collect`), [9] = the steps since this batch's last rebuild (`decide`,
// `decide_lean`: 0 on a rebuild, +1 on any other step); [10] = the steps begun before any
// halt (`decide`, `decide_lean`), [11] = the list entries a halted rebuild needed.
@group(0) @binding(48) var<storage, read_write> control: array<atomic<u32>, 16>;

// [12, 16): the Verlet skin state, persistent across batches: SKIN_MOVED = 1 once some
// particle has moved more
// than skin/2 since the last rebuild (set by kick_drift, only there: a store where it
// happens rather than a maximum over all particles, which cost workgroup atomics and
// barriers every step), SKIN_REBUILD = 1 when this step rebuilds (written by decide),
// SKIN_REBUILDS = rebuilds so far.
const SKIN_MOVED: u32 = 12u;
const SKIN_REBUILD: u32 = 13u;
const SKIN_REBUILDS: u32 = 14u;
// Indirect dispatch arguments: first those of a rebuild (the grid sort's, the per-particle
// passes', the list scans'), which decide copies from full_args or zeroes each step; then
// those of every step's passes (per particle, one workgroup), which the host writes at
// each batch's start and `halt` zeroes.
@group(0) @binding(57) var<storage, read_write> args: array<u32>;
@group(0) @binding(58) var<storage, read> full_args: array<u32>;

fn skin_width() -> f32 {
    return step.skin;
}

// Separation x_i - x_j from cell + offset positions.
fn separation(ci: vec4<i32>, oi: vec4<f32>, cj: vec4<i32>, oj: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(nearest_image(ci.xyz - cj.xyz)) * grid.cell_width + (oi.xyz - oj.xyz);
}

@compute @workgroup_size(WG_SIZE)
fn kick_drift(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    drift(particle_index(wid, nwg, lid));
}

// The previous step's collect and closing kick and this step's kick_drift in one pass
// (every step of a batch but the first; the batch ends with collect and kick): each needs
// only its own particle's results of the one before (collect reads the pair forces the
// whole force pass left), so this is bitwise the same as the three kernels, two dispatches
// and two sweeps over the state fewer.
@compute @workgroup_size(WG_SIZE)
fn collect_kick_drift(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = particle_index(wid, nwg, lid);
    if (i < particle_end()) {
        let vel = load_vel(i);
        let c = collect_particle(i, vel.w, false);
        if (has_appeared(load_cell(i))) {
            drift_particle(i, vel, c.acc, c.rot, true, c.peak, c.dv);
        }
    }
}

fn drift(i: u32) {
    if (i < particle_end() && has_appeared(load_cell(i))) {
        drift_particle(i, load_vel(i), load_acc(i).xyz, rot_load(i), false, 0.0, vec3<f32>(0.0));
    }
}

// Each buffer is read once and written once (the caller passes what it read already): on
// lavapipe every access in the code is a loop over the SIMD lanes.
// `peak`: the largest overlap/a12 of the last force pass (0 when it was folded already).
// `pending_kick`: called from collect_kick_drift, within a batch, where the mirrors still
// hold the cell and offset the last force pass saw (nothing wrote them since): read from
// there (a gather on lavapipe, not a loop over the lanes). At a batch's first step the host
// may have written the state since (a restore): read the buffers.
// `jump_dv`: with the pending kick, the partners' force jumps at the end of that step.
fn drift_particle(i: u32, vel: vec4<f32>, acc: vec3<f32>, rot: RotState, pending_kick: bool, peak: f32, jump_dv: vec3<f32>) {
    let h = grid.cell_width;
    // (products through `opaque`: fused into the adds or not, as this kernel and `kick`
    // may differ, they would round differently; batches of any length give the same bits)
    let half_dv = opaque(0.5 * step.dt * acc);
    var v0 = vel.xyz;
    var c0 = load_kahan_v(i).xyz;
    if (pending_kick) {
        // the partners' force jumps first, as collect adds them at a batch's end
        let kj = kahan_add_nonzero(v0, c0, jump_dv);
        let kk = kahan_add(kj.x, kj.c, half_dv);
        v0 = kk.x;
        c0 = kk.c;
    }
    let kv = kahan_add(v0, c0, half_dv);
    let v = kv.x;
    store_vel(i, vec4<f32>(v, vel.w));
    store_kahan_v(i, vec4<f32>(kv.c, 0.0));
    // vel.w holds the mass
    store_vpred(i, vec4<f32>(v + half_dv, vel.w));
    rot_drift(i, rot, pending_kick);
    let disp0 = load_disp(i);
    let dx = opaque(step.dt * v);
    let disp = disp0.xyz + dx;
    store_disp(i, vec4<f32>(disp, max(disp0.w, peak)));
    // (NaN forces a rebuild too; the squares and sums through `opaque`, as the products
    // above: a tie at the threshold must go the same way in both drift kernels)
    let sq = opaque(disp * disp);
    let half_skin = 0.5 * skin_width();
    if (!(opaque1(sq.x + sq.y) + sq.z <= half_skin * half_skin)) {
        atomicStore(&control[SKIN_MOVED], 1u);
    }
    // the move with the compensated velocity, carried into whole cells (below)
    var off: vec4<f32>;
    var cell0: vec4<i32>;
    if (pending_kick) {
        off = own_off(i);
        cell0 = own_cell(i);
    } else {
        off = load_off(i);
        cell0 = load_cell(i);
    }
    // the true step dt·(v − c_v): the velocity's compensation joins the offset's (v − c_v
    // itself rounds back to v); w: the radius's rounding residual, kept
    let c_off = load_kahan_o(i);
    let ko = kahan_add(off.xyz, c_off.xyz + opaque(step.dt * kv.c), dx);
    // whole cells carried exactly, their rounding booked into the compensation
    let carried = carry_cells(ko.x, h);
    store_kahan_o(i, vec4<f32>(ko.c - carried.lo, c_off.w));
    let o = carried.offset;
    let carry = carried.carry;
    let raw = cell0.xyz + carry;
    let cell = wrap_cell(raw);
    // a wrap moves the stored position by dims·h, the true one by the period L
    let wraps = image_shift(cell, raw);
    if (any(wraps != vec3<f32>(0.0))) {
        let c = load_kahan_o(i);
        store_kahan_o(i, vec4<f32>(c.xyz - wraps * step.period_lo, c.w));
    }
    // stored only where it changes (rarely): a masked store skips the work of idle lanes
    if (any(carry != vec3<i32>(0))) {
        store_cell(i, vec4<i32>(cell, cell0.w));
    }
    store_off(i, vec4<f32>(o, off.w));
    let at = vec3<f32>(cell) + o / h;
    let outside = (at < vec3<f32>(0.0)) | (at > step.extent_cells);
    if (any(outside & !periodic_axes())) {
        atomicMax(&control[6], load_ids(i).x + 1u);
    }
}

// Whether the lists must be rebuilt before this step's forces: unless every particle moved
// at most half the skin since the last rebuild (then no pair can have closed by more than
// the skin, so every pair within r_i + r_j + reach is still in the lists built with
// r_i + r_j + reach + skin). Moving walls count too (their move since the last rebuild).
fn rebuild_due() -> bool {
    var rebuild = atomicLoad(&control[SKIN_MOVED]) != 0u;
    // A moving wall that has moved more than skin/2 along its normal since the last rebuild
    // invalidates the particles' wall entries as a particle's move does.
    for (var w = 0u; w < wall_count(); w++) {
        let wall = walls[w];
        if (wall.motion.x != 0.0) {
            let moved = dot(separation(wall.cell, wall.offset, wall_ref[w].cell, wall_ref[w].offset), wall.normal.xyz);
            if (!(abs(moved) <= 0.5 * skin_width())) {
                rebuild = true;
            }
        }
    }
    return rebuild;
}

// Halts the batch (`why`: HALT_GROW or HALT_REBUILD in monitor[7]): every indirect argument
// zeroed, so every later pass of the batch launches nothing; the host finishes it
// (`GpuEngine::run_steps`). True where this call halted it.
fn halt(why: u32) -> bool {
    // (single-invocation kernels, one dispatch after another: no race)
    if (atomicLoad(&control[7]) != 0u) {
        return false;
    }
    atomicStore(&control[7], why);
    for (var i = 0u; i < arrayLength(&args); i++) {
        args[i] = 0u;
    }
    return true;
}

const HALT_GROW: u32 = 1u;
const HALT_REBUILD: u32 = 2u;

// One invocation, after kick_drift: whether to rebuild (`rebuild_due`). Writes the flag and
// the indirect arguments of the grid sort and of the rebuild's per-particle passes (zero
// workgroups without a rebuild), and starts the next maximum afresh.
@compute @workgroup_size(1)
fn decide() {
    // a halted batch runs nothing more (`halt`)
    if (atomicLoad(&control[7]) != 0u) {
        return;
    }
    atomicAdd(&control[10], 1u);
    let rebuild = rebuild_due();
    if (rebuild) {
        for (var w = 0u; w < wall_count(); w++) {
            wall_ref[w] = WallRef(walls[w].cell, walls[w].offset);
        }
    }
    atomicStore(&control[SKIN_MOVED], 0u);
    atomicStore(&control[SKIN_REBUILD], select(0u, 1u, rebuild));
    if (rebuild) {
        atomicAdd(&control[SKIN_REBUILDS], 1u);
        atomicStore(&control[9], 0u);
    } else {
        atomicAdd(&control[9], 1u);
    }
    for (var i = 0u; i < arrayLength(&full_args); i++) {
        args[i] = select(0u, full_args[i], rebuild);
    }
}

// `decide` of a step recorded without the rebuild's passes (`RebuildChain::OnDemand`):
// where a rebuild is due, halt the batch before this step's forces and leave the skin flag
// raised; the host runs this step again from its rebuild, recorded in full.
@compute @workgroup_size(1)
fn decide_lean() {
    if (atomicLoad(&control[7]) != 0u) {
        return;
    }
    atomicAdd(&control[10], 1u);
    if (rebuild_due()) {
        halt(HALT_REBUILD);
        return;
    }
    atomicStore(&control[SKIN_REBUILD], 0u);
    atomicAdd(&control[9], 1u);
}

// On a rebuild, before the state is re-sorted: the cell and offset mirrors in the new
// order, for `neighbours`.
@compute @workgroup_size(WG_SIZE)
fn gather(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    mirror_sorted(k, sorted_index[k]);
}

// Whether particle k evaluates its pair with j (d = x_k − x_j): when j lies ahead of k
// along the separation's dominant axis (z, then y, then x on equal magnitudes; by the sorted
// order when they coincide). Antisymmetric — j's side computes −d bitwise (integer cell
// differences, negated offsets) — so exactly one of the two evaluates. Against "the later
// one in the sorted order" it evens out the lists' lengths: each gets the partners of one
// half-space, not those of the later cells, whose share depends on where a particle sits
// in its cell. A SIMD group loops as long as its longest list: on the settled packing
// example the force and collect loops run 13–14 % fewer iterations (max of 8 consecutive
// lists 5.9 -> 5.2; the longest list 10 -> 7), and the bench lattice still gets exactly
// its +x, +y, +z neighbours.
fn evaluates(d: vec3<f32>, k: u32, j: u32) -> bool {
    let a = abs(d);
    var c = d.x;
    if (a.z >= a.y && a.z >= a.x) {
        c = d.z;
    } else if (a.y >= a.x) {
        c = d.y;
    }
    if (c == 0.0) {
        return j > k;
    }
    return c < 0.0;
}

// The neighbour search of particle k (in the new order, before the state is re-sorted):
// the partners within r_i + r_j + reach + skin from the 27 cells, in a fixed order, and
// then the walls within r_k + reach + skin (`WALL_ENTRY`), as (evaluated by k, evaluated
// by the partner) counts; `fill`: also written to the new lists at b_row[k] and
// lower_row[k], which the counts' scans placed.
fn search(k: u32, fill: bool) -> vec2<u32> {
    // (a particle whose data lies beyond this window's bindings stops the run: monitor[1])
    if (!in_bindings(sorted_index[k])) {
        atomicMax(&control[1], 1u);
        return vec2<u32>(0u);
    }
    // (the positions in the new order: `sorted_cell`)
    let ck = sorted_cell(k);
    let ok = sorted_off(k);
    let hi = vec3<i32>(grid.dims) - vec3<i32>(1);
    let home = clamp(ck.xyz, vec3<i32>(0), hi);
    let cap = step.list_capacity;
    // the half lists: the partners whose pairs k evaluates, and the others (their
    // evaluations reach k through `lower`)
    var up = 0u;
    var down = 0u;
    // a particle that has not appeared lists no neighbours (and is listed by none)
    let here = has_appeared(ck);
    // Without wrapping along x, the three cells x−1, x, x+1 of a row are consecutive keys
    // and their particles one range of the sorted order: 9 ranges instead of 27 cells.
    let row_ranges = !periodic_axes().x;
    // (read once, not per candidate)
    // (r_k + r_j first: both sides of a pair get bitwise the same cut-off)
    let margin = step.reach + skin_width();
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                if (row_ranges && dx != 0) {
                    continue;
                }
                let c = wrap_cell(home + vec3<i32>(dx, dy, dz));
                if (any(c < vec3<i32>(0)) || any(c > hi)) {
                    continue;
                }
                // (each form's loads only under its branch: without periodic axes `row_ranges`
                // is a constant and the other form is compiled out; on lavapipe every
                // load in the code costs, taken or not)
                var start = 0u;
                var end = 0u;
                if (row_ranges) {
                    let first = vec3<i32>(max(c.x - 1, 0), c.y, c.z);
                    let last = vec3<i32>(min(c.x + 1, hi.x), c.y, c.z);
                    start = cell_start[cell_key(first, grid.dims)];
                    end = cell_end(cell_key(last, grid.dims));
                } else {
                    let key = cell_key(c, grid.dims);
                    start = cell_start[key];
                    end = cell_end(key);
                }
                for (var j = start; j < end; j++) {
                    if (j == k || !here) {
                        continue;
                    }
                    if (!in_bindings(j) || !in_bindings(sorted_index[j])) {
                        atomicMax(&control[1], 1u);
                        continue;
                    }
                    let cj = sorted_cell(j);
                    if (!has_appeared(cj)) {
                        continue;
                    }
                    let oj = sorted_off(j);
                    let d = separation(ck, ok, cj, oj);
                    let reach = (ok.w + oj.w) + margin;
                    if (dot(d, d) < reach * reach) {
                        if (evaluates(d, k, j)) {
                            if (fill && rows[row_at(ROWS_B_ROW, k)] + up < cap) {
                                store_nbr(b_first(k) + up, j);
                            }
                            up += 1u;
                        } else {
                            if (fill && rows[row_at(ROWS_LOWER_ROW, k)] + down < cap) {
                                store_lower(lower_first(k) + down, j);
                            }
                            down += 1u;
                        }
                    }
                }
            }
        }
    }
    // the walls (also of a particle that has not appeared: it may appear before the next
    // rebuild; `force` skips them until then)
    for (var w = 0u; w < wall_count(); w++) {
        let wall = walls[w];
        let delta = ok.w - dot(separation(ck, ok, wall.cell, wall.offset), wall.normal.xyz);
        if (!(delta < -margin)) {
            if (fill && rows[row_at(ROWS_B_ROW, k)] + up < cap) {
                store_nbr(b_first(k) + up, WALL_ENTRY | w);
            }
            up += 1u;
        }
    }
    return vec2<u32>(up, down);
}

// On a rebuild: each particle's list lengths, for the scans that place the lists.
@compute @workgroup_size(WG_SIZE)
fn count_neighbours(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    let c = search(k, false);
    atomicMax(&control[0], max(c.x, c.y));
    rows[row_at(ROWS_B_COUNT, k)] = c.x;
    rows[row_at(ROWS_LOWER_COUNT, k)] = c.y;
}

// On a rebuild, after the scans: the lists, each particle's at its place (what does not fit
// the capacity is not written; `commit` halts then).
@compute @workgroup_size(WG_SIZE)
fn neighbours(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    search(k, true);
}

// On a rebuild, after the lists are filled and before anything is re-sorted, once per
// window: when the window's new lists need more entries than its block has (or a
// particle's neighbours lay beyond the windows bound, monitor[1]), halt the batch — zero
// every indirect argument, so the rest of this rebuild and every later pass of the batch
// launches nothing — and leave the skin flag raised. The host grows the lists (or stops)
// and finishes the batch from this step's rebuild (`GpuEngine::run_steps`): the state is
// as the drift left it, the old lists whole. (Later steps of a halted batch see the same
// counts: the same need, the halt's bookkeeping done once.)
@compute @workgroup_size(1)
fn commit() {
    if (atomicLoad(&control[SKIN_REBUILD]) == 0u || win.first >= grid.n_particles) {
        return;
    }
    let last = particle_end() - 1u;
    let need = max(rows[row_at(ROWS_B_ROW, last)] + b_len(last), rows[row_at(ROWS_LOWER_ROW, last)] + lower_len(last));
    if (need > step.list_capacity || atomicLoad(&control[1]) != 0u) {
        atomicMax(&control[11], need);
        if (halt(HALT_GROW)) {
            atomicStore(&control[SKIN_MOVED], 1u);
            atomicSub(&control[SKIN_REBUILDS], 1u);
        }
    }
}

@compute @workgroup_size(WG_SIZE)
fn remap(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    // the lower list: each such partner j lists k in its own list; keep that entry
    let low = lower_first(k);
    for (var s = 0u; s < lower_len(k); s++) {
        let j = load_lower(low + s);
        let row_j = b_first(j);
        for (var m = 0u; m < b_len(j); m++) {
            if (load_nbr_far(row_j + m) == k) {
                store_lower(low + s, row_j + m);
                break;
            }
        }
    }
    // each new slot's history: from k's old list, or (when the pair's evaluator changed
    // with the new order) from the partner's, seen from the other side
    // (the re-sort carried each particle's old list row and length with it in `ids`)
    // (a wall entry's id is its `nbr`; pairs and walls never share an id)
    let ids = load_ids(k);
    let me = ids.x;
    let old_row = ids.y;
    let old_n = ids.z + ids.w;
    let row = b_first(k);
    for (var s = 0u; s < b_len(k); s++) {
        let e = row + s;
        let j = load_nbr(e);
        let wall = (j & WALL_ENTRY) != 0u;
        var partner = j;
        if (!wall) {
            partner = load_ids(j).x;
        }
        var h = hist_zero();
        store_new_prior(e, vec4<f32>(0.0));
        var found = false;
        for (var m = 0u; m < old_n; m++) {
            if (load_hist_pid_far(old_row + m) == partner) {
                h = load_hist_far(old_row + m);
                store_new_prior(e, load_prior_far(old_row + m));
                found = true;
                break;
            }
        }
        if (!found && !wall) {
            let mj = load_ids(j);
            let row_j = mj.y;
            for (var m = 0u; m < mj.z; m++) {
                if (load_hist_pid_far(row_j + m) == me) {
                    h = hist_mirror(load_hist_far(row_j + m));
                    store_new_prior(e, load_prior_far(row_j + m));
                    break;
                }
            }
        }
        store_new_hist(e, h);
        store_new_hist_pid(e, partner);
    }
    ledger_dropped(old_row, old_n, k);
}

// On a rebuild, last: the new lists' history returns to A, the displacements start
// afresh, and the row's wall entries (its last) are counted into ids.w.
@compute @workgroup_size(WG_SIZE)
fn copy_back_history(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    let n = b_len(k);
    let row = b_first(k);
    var n_walls = 0u;
    for (var e = row; e < row + n; e++) {
        let id = load_new_hist_pid(e);
        store_hist(e, load_new_hist(e));
        store_hist_pid(e, id);
        store_prior(e, load_new_prior(e));
        if ((id & WALL_ENTRY) != 0u) {
            n_walls += 1u;
        }
    }
    // (w: the batch's largest overlap so far, which the re-sort carried)
    store_disp(k, vec4<f32>(0.0, 0.0, 0.0, load_disp(k).w));
    store_ids(k, vec4<u32>(load_ids(k).x, row, n - n_walls, n_walls));
}

// The relative motion of one contact, as the model sees it (`model::Kinematics` plus the
// pair geometry and the time step).
struct Kin {
    // Overlap and approach speed.
    delta: f32,
    delta_dot: f32,
    // R* = r_i·r_j/(r_i + r_j) (r for a wall; a12 = 2R*) and m* (m for a wall).
    r_eff: f32,
    m_eff: f32,
    dt: f32,
    // Unit normal from j (or the wall) to i.
    n: vec3<f32>,
    // Tangential velocity of i relative to j at the contact point.
    v_t: vec3<f32>,
    // Rolling velocity R*·(w_i − w_j) × n + ½·(r_i − r_j)/(r_i + r_j)·v_t (paper 002 eq. 20).
    v_roll: vec3<f32>,
    // 1/a12 = 1/(2R*) (the step needs it for the overlap monitor; the hysteretic model
    // multiplies by it where the reference divides by a12).
    inv_a12: f32,
    // Relative angular velocity w_i − w_j (w_i for a wall): Luding's rolling and twisting.
    w_rel: vec3<f32>,
}

// A normal law's result, what the composition and the friction sub-models need of it.
struct Normal {
    // Mechanical contact: the tangential, rolling and twisting laws act (their history
    // is cleared otherwise).
    in_contact: bool,
    // The energy ledger's "engaged" (the law's touched flag).
    engaged: bool,
    // Normal force along n, repulsive positive, and the stored energy.
    force: f32,
    potential: f32,
    // Contact radius a and a/a0 (JKR family; 0 for the linear laws).
    a: f32,
    x: f32,
    // The load of the Coulomb limits (>= 0): |F_el + 2Fc| for JKR, Luding's
    // f_n + kc·delta + fa for the hysteretic law.
    coulomb: f32,
}

// Rotates v into the plane normal to n keeping its length (`model::rotate_into_plane`): a
// rigid rotation of the pair must not change a stored spring's energy. Zero when v is
// (within f32 rounding) along n.
fn rotate_into_plane(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if (len == 0.0) {
        return vec3<f32>(0.0);
    }
    let q = v - n * dot(n, v);
    let lq = length(q);
    // f64 uses 1e-12; in f32 the projection of a vector along n is rounding noise of
    // ~1e-7·len, so anything below 1e-6·len has no direction worth keeping.
    if (lq > 1e-6 * len) {
        return q * (len / lq);
    }
    return vec3<f32>(0.0);
}

// What one contact does to particle i.
struct Contact {
    // Normal force along n, repulsive positive.
    normal: f32,
    // Tangential force.
    tangential: vec3<f32>,
    // Rolling-resistance torque (the partner gets the negative).
    rolling: vec3<f32>,
    // Stored energy of the contact (energy ledger; `Response::potential`).
    potential: f32,
    // The history's touched flag (energy ledger: the contact is engaged).
    engaged: bool,
    // Whether the tangential force slid at the Coulomb limit (`Response::sliding`).
    sliding: bool,
}

// Whether a contact is engaged after the step (the ledger's and the force jumps' "in"):
// the law's touched flag, or a force or stored energy.
fn contact_is_in(c: Contact) -> bool {
    return c.engaged || c.potential != 0.0 || c.normal != 0.0;
}

// What the next step needs of a contact (the entries' `prior`, with the ledger, the force
// jumps or the contact output): (δ, normal force, U − ½·dt·P, 1, or 2 where it slid) while
// it is engaged, (δ, 0, 0, −1) while it is not; a slot a rebuild just made holds zeros.
fn prior_of(k: Kin, c: Contact, power: f32, is_in: bool) -> vec4<f32> {
    if (is_in) {
        return vec4<f32>(k.delta, c.normal, c.potential - 0.5 * k.dt * power, select(1.0, 2.0, c.sliding));
    }
    return vec4<f32>(k.delta, 0.0, 0.0, -1.0);
}

// The overlap at the start of the step: the prior's, or back along the approach speed for
// a contact the last step did not see (a slot a rebuild just made).
fn overlap_before(old: vec4<f32>, k: Kin) -> f32 {
    return select(k.delta - k.delta_dot * k.dt, old.x, old.w != 0.0);
}

// The force that switched on or off at δ = 0 within the step (`pair_touch_jump`) where
// the contact is engaged on the contact side (inside it, or with an edge crossed in the
// same step); 0 where δ = 0 was not crossed, nothing switches there, or the edge crossed
// is at δ = 0 (its `edges` hold what jumps there).
fn touch_crossed(p: PairRow, k: Kin, old: vec4<f32>, is_in: bool, edges: vec4<f32>) -> f32 {
    let before = overlap_before(old, k);
    let was_in = old.w > 0.0;
    let contact_side_in = select(was_in, is_in, k.delta > 0.0);
    let edge_at_touch = was_in != is_in && select(edges.z, edges.x, is_in) == 0.0;
    if ((LEDGER || JUMPS) && (before > 0.0) != (k.delta > 0.0) && contact_side_in && !edge_at_touch) {
        return pair_touch_jump(p, k);
    }
    return 0.0;
}

@compute @workgroup_size(WG_SIZE)
fn force(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    // Loaded here, outside any branch: lavapipe loads a uniform address as one scalar only
    // where invocation 0 is known to be active; inside the pair loop each word was a loop
    // over the SIMD lanes (docs/design_log.md). Dead, and dropped, unless ONE_MATERIAL.
    let row0 = pairs[0];
    if (k < particle_end()) {
        particle_forces(k, row0);
    }
}

// The forces on particle k, stored in its acceleration's xyz, and its contacts' largest
// overlap/a12 (0 without overlap) in w, for the run monitor (see disp).
// `row0`: pair row 0, the only one of a scene with ONE_MATERIAL.
fn particle_forces(k: u32, row0: PairRow) {
    // (id, first entry, pairs, wall entries: loaded once)
    let ids_k = load_ids(k);
    let first = ids_k.y;
    // (own and partners' state: `own_cell`, from the mirrors on a software adapter)
    let ck = own_cell(k);
    let ok = own_off(k);
    let rk = ok.w;
    // vpred.w holds the mass
    let pk = own_vpred(k);
    let mk = pk.w;
    let vk = pk.xyz;
    let wk = rot_wpred(k);
    let mat_k = material_of(ck);
    // the position's compensation (xyz) and the radius's residual (w): the overlaps are
    // taken from them to below f32 rounding (overlap.wgsl)
    let comp_k = load_kahan_o(k);
    var f = vec3<f32>(0.0);
    var torque = vec3<f32>(0.0);
    var ledger_acc = ledger_new();
    var peak = 0.0;
    // the force jumps' impulses on k (placed at the end of the step)
    var impulse = vec3<f32>(0.0);
    for (var slot = first; slot < first + ids_k.z; slot++) {
        let j = load_nbr(slot);
        let cj = own_cell(j);
        let oj = own_off(j);
        let rj = oj.w;
        // predicted velocity (xyz) and mass (w): one load
        let pj = own_vpred(j);
        let mj = pj.w;
        let dc_raw = ck.xyz - cj.xyz;
        let dc_i = nearest_image(dc_raw);
        let comp_j = load_kahan_o(j);
        let dd = precise_separation(vec3<f32>(dc_i), image_shift(dc_i, dc_raw), ok.xyz, oj.xyz, comp_k.xyz, comp_j.xyz);
        let d = dd.hi;
        let dist = length(d);
        let delta = precise_overlap(dd, rk, rj, comp_k.w, comp_j.w);
        // (one division, not one per component: on a SIMD adapter every division in the
        // code runs for every pair)
        let inv_dist = 1.0 / dist;
        // A list candidate (within the skin) out of every model's range gets no force and
        // the history a pair out of range has (the models reset it there too). One store
        // site per buffer for both cases: on a SIMD adapter (lavapipe) every store in the
        // code costs a loop over the lanes, whether any lane takes its branch or not.
        let old = load_prior(slot);
        let was_in = old.w > 0.0;
        // (an engaged contact that broke beyond the reach within the step is evaluated, so
        // its exit edge is booked and its force jump placed, as on the CPU; without the
        // ledger and the jumps nothing is known of it, and nothing booked)
        let far = delta < -step.reach && !((LEDGER || JUMPS) && was_in);
        var n = vec3<f32>(0.0, 0.0, 1.0);
        if (dist > 0.0) {
            n = d * inv_dist;
        }
        let v_rel = vk - pj.xyz;
        let wj = rot_wpred(j);
        // Mirror-symmetric forms (see the header): (r_i w_i + r_j w_j) is commutative.
        let v_c = v_rel - cross(rk * wk + rj * wj, n);
        let v_t = v_c - n * dot(v_c, n);
        let r_sum = rk + rj;
        let r_eff = rk * rj / r_sum;
        let inv_a12 = r_sum / (2.0 * rk * rj);
        let kin = Kin(
            delta,
            -dot(v_rel, n),
            r_eff,
            mk * mj / (mk + mj),
            step.dt,
            n,
            v_t,
            r_eff * cross(wk - wj, n) + (0.5 * (rk - rj) / r_sum) * v_t,
            inv_a12,
            wk - wj,
        );
        let h0 = load_hist(slot);
        var h = h0;
        var row = row0;
        if (!ONE_MATERIAL) {
            row = pairs[mat_k * step.n_materials + material_of(cj)];
        }
        let c = pair_contact(row, kin, &h);
        let is_in = contact_is_in(c);
        var fp = c.normal * n + c.tangential;
        var t_partner = vec3<f32>(0.0);
        var prior = vec4<f32>(delta, 0.0, 0.0, -1.0);
        var jump = 0.0;
        if (far) {
            h = hist_zero();
            fp = vec3<f32>(0.0);
            ledger_departed(&ledger_acc, old, delta);
        } else {
            peak = max(peak, delta * inv_a12);
            let power = dot(c.tangential, v_t) + dot(c.rolling, wk - wj);
            var edges = vec4<f32>(0.0);
            if ((LEDGER || JUMPS) && was_in != is_in) {
                edges = pair_edges(row, kin);
            }
            let touch = touch_crossed(row, kin, old, is_in, edges);
            ledger_pair(&ledger_acc, old, kin, c, power, is_in, edges, touch);
            prior = prior_of(kin, c, power, is_in);
            jump = contact_jump(old, kin, c, is_in, edges, touch);
            // (n stored only in the rare step that places one)
            if (jump != 0.0) {
                impulse += jump * n;
                store_jump_normal(slot, n);
            }
            f += fp;
            if (ROTATION) {
                // the partner sees n and the tangential force negated (their cross product
                // unchanged) and the rolling torque negated
                let t = cross(n, c.tangential);
                torque += -rk * t + c.rolling;
                t_partner = -rj * t - c.rolling;
            }
        }
        // stored only where it changed: most of a packing's list entries are candidates
        // out of contact whose history stays zero, and a masked store skips the idle
        // lanes' work on lavapipe
        if (!hist_same(h, h0)) {
            store_hist(slot, h);
        }
        store_pair_force(slot, fp);
        rot_pair_store(slot, t_partner);
        store_prior(slot, prior);
        store_jump(slot, jump);
    }
    // a particle that has not appeared meets no wall
    let present = WALLS && has_appeared(ck);
    // only the walls near at the last rebuild: k's wall entries (a SIMD group loops as
    // often as its lane with the most, mostly 0 in a packing, rather than n_walls times)
    let walls_first = ids_k.y + ids_k.z;
    let walls_end = walls_first + select(0u, ids_k.w, present);
    for (var slot = walls_first; slot < walls_end; slot++) {
        let w = load_nbr(slot) & ~WALL_ENTRY;
        let wall = walls[w];
        let n = wall.normal.xyz;
        let dcw_raw = ck.xyz - wall.cell.xyz;
        let dcw = nearest_image(dcw_raw);
        let dd = precise_separation(vec3<f32>(dcw), image_shift(dcw, dcw_raw), ok.xyz, wall.offset.xyz, comp_k.xyz, vec3<f32>(0.0));
        let delta = precise_wall_overlap(dd, n, wall.normal_lo.xyz, rk, comp_k.w, wall.offset.w);
        // relative to the (possibly moving) wall
        let v_rel = vk - wall.velocity.xyz;
        let v_c = v_rel - cross(rk * wk, n);
        let v_t = v_c - n * dot(v_c, n);
        // eq. 20 with r_j -> inf: (r_i - r_j)/(r_i + r_j) -> -1
        let inv_a12 = 0.5 / rk;
        let kin = Kin(delta, -dot(v_rel, n), rk, mk, step.dt, n, v_t, rk * cross(wk, n) - 0.5 * v_t, inv_a12, wk);
        var h = load_hist(slot);
        let old = load_prior(slot);
        let row = pairs[step.n_materials * step.n_materials + w * step.n_materials + mat_k];
        let c = pair_contact(row, kin, &h);
        store_hist(slot, h);
        peak = max(peak, delta * inv_a12);
        let is_in = contact_is_in(c);
        let power = dot(c.tangential, v_t) + dot(c.rolling, wk);
        var edges = vec4<f32>(0.0);
        if ((LEDGER || JUMPS) && (old.w > 0.0) != is_in) {
            edges = pair_edges(row, kin);
        }
        let touch = touch_crossed(row, kin, old, is_in, edges);
        let jump = contact_jump(old, kin, c, is_in, edges, touch);
        impulse += jump * n;
        ledger_wall(&ledger_acc, old, kin, c, power, is_in, edges, touch, dot(n, wall.velocity.xyz), jump);
        store_prior(slot, prior_of(kin, c, power, is_in));
        if (step.servo_walls != 0u) {
            store_wall_push(slot, c.normal);
        }
        // (a wall takes no torque: its entry's keeps the tangential force, for the output)
        rot_pair_store(slot, c.tangential);
        f += c.normal * n + c.tangential;
        if (ROTATION) {
            torque += -rk * cross(n, c.tangential) + c.rolling;
        }
    }
    // the sums over k's own list and walls; collect adds the pairs evaluated by partners
    store_acc(k, vec4<f32>(f, peak));
    rot_store_partial(k, torque);
    ledger_store(k, ledger_acc);
    // k's share of the force jumps, into its velocity now (the kicks around the end of
    // the step add to it; nothing reads it before): the partners' comes through collect
    jump_kick(k, impulse / mk);
}

// After force, per particle: adds the forces (and torques) of the pairs k's partners
// before it evaluated, in lower-list order (deterministic, no atomics), and stores the
// acceleration (and angular acceleration).
@compute @workgroup_size(WG_SIZE)
fn collect(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k < particle_end()) {
        let c = collect_particle(k, load_vel(k).w, true);
        // the partners' force jumps, at the end of the step (before the closing kick:
        // the sum is the same)
        jump_kick(k, c.dv);
        // the batch ends here (or the initial forces do): its overlap maximum, with this
        // step's, into the monitor (an atomic only where it grows), and a fresh start
        let disp = load_disp(k);
        let ratio = max(disp.w, c.peak);
        let bits = bitcast<u32>(ratio);
        if (bits > atomicLoad(&control[4])) {
            atomicMax(&control[4], bits);
        }
        if (ratio > MONITOR_MAX_OVERLAP_RATIO) {
            atomicMax(&control[5], load_ids(k).x + 1u);
        }
        // the displacement since the last rebuild, for the host's rebuild forecast
        let moved = bitcast<u32>(length(disp.xyz));
        if (moved > atomicLoad(&control[8])) {
            atomicMax(&control[8], moved);
        }
        store_disp(k, vec4<f32>(disp.xyz, 0.0));
    }
}

// What collect leaves for the drift of the same pass.
struct Collected {
    acc: vec3<f32>,
    rot: RotState,
    // The largest overlap/a12 of the force pass just collected.
    peak: f32,
    // The velocity change of the force jumps the partners placed (the end of the step).
    dv: vec3<f32>,
}

// Returns the acceleration (and the angular state, stored); `store`: the acceleration too,
// at the end of a batch (kick, the host and checkpoints read it there). Within a batch
// the drift takes it from here and the next force pass overwrites it: no store.
fn collect_particle(k: u32, mass: f32, store: bool) -> Collected {
    let partial = load_acc(k);
    var f = partial.xyz;
    var torque = vec3<f32>(0.0);
    var impulse = vec3<f32>(0.0);
    let low = lower_first(k);
    for (var s = low; s < low + lower_len(k); s++) {
        let slot = load_lower(s);
        f -= load_pair_force_far(slot);
        torque += rot_pair_load(slot);
        // a force jump's impulse (0 without the force jumps: no field, no load)
        let jump = load_jump_far(slot);
        if (jump != 0.0) {
            impulse -= opaque(jump * load_jump_normal_far(slot));
        }
    }
    // (`opaque`: as in drift_particle, rounded the same in every kernel that collects)
    let acc = opaque(opaque(f / mass) + step.gravity);
    let rot = rot_collect(k, torque);
    if (any(acc != acc) || any(abs(acc) > vec3<f32>(3.0e38)) || !rot_finite(rot)) {
        atomicAdd(&control[2], 1u);
    }
    if (store) {
        store_acc(k, vec4<f32>(acc, 0.0));
    }
    return Collected(acc, rot, partial.w, opaque(impulse / mass));
}

@compute @workgroup_size(WG_SIZE)
fn kick(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    if (!has_appeared(load_cell(k))) {
        return;
    }
    let kv = kahan_add(load_vel(k).xyz, load_kahan_v(k).xyz, opaque(0.5 * step.dt * load_acc(k).xyz));
    store_vel(k, vec4<f32>(kv.x, load_vel(k).w));
    store_kahan_v(k, vec4<f32>(kv.c, 0.0));
    rot_kick(k);
}

// Moving walls, after kick_drift (dispatched only when some wall moves): each moving wall's
// point advances by its velocity over the step, carried into its cell like a particle's.
@compute @workgroup_size(1)
fn wall_move() {
    let h = grid.cell_width;
    for (var w = 0u; w < wall_count(); w++) {
        if (walls[w].motion.x == 0.0) {
            continue;
        }
        let o0 = walls[w].offset;
        // (`opaque`: two_sum needs the rounded product, not one fused into its add)
        let dx = opaque(step.dt * walls[w].velocity.xyz);
        var sum = vec3<f32>(0.0);
        var lo = vec3<f32>(0.0);
        for (var a = 0u; a < 3u; a++) {
            let s = two_sum(o0[a], dx[a]);
            sum[a] = s.hi;
            lo[a] = s.lo;
        }
        let carried = carry_cells(sum, h);
        walls[w].cell = vec4<i32>(walls[w].cell.xyz + carried.carry, 0);
        // the plane's residual n·(stored − true) takes the move's rounding
        let residual = o0.w - dot(walls[w].normal.xyz, lo + carried.lo);
        walls[w].offset = vec4<f32>(carried.offset, residual);
    }
}

// Servo control, after force (dispatched only when some wall is servo-controlled): each
// servo wall's normal force summed over the particles in a fixed order, so the result is
// reproducible and the same in any windows: lane l of `servo_lanes` adds the pushes of the
// particles l, l + WG_SIZE, l + 2·WG_SIZE, ... in order (one invocation a lane and window,
// the windows in order), then wall_servo_apply adds the lanes as a tree and sets the
// wall's velocity for the next step: clamp(gain·(force − pushed), ±max_speed) along n.
var<workgroup> wg_push: array<f32, WG_SIZE>;

// Per wall and lane, the pushes summed so far this step (zeroed by wall_servo_apply).
@group(0) @binding(76) var<storage, read_write> servo_lanes: array<f32>;

// Particle k's push on wall w this step (0 without a wall entry, not near at the rebuild,
// or before k has appeared: the force pass writes the pushes of the others every step).
fn wall_push_of(k: u32, w: u32) -> f32 {
    if (!has_appeared(load_cell(k))) {
        return 0.0;
    }
    let ids = load_ids(k);
    for (var e = ids.y + ids.z; e < ids.y + ids.z + ids.w; e++) {
        if (load_nbr(e) == (WALL_ENTRY | w)) {
            return load_wall_push(e);
        }
    }
    return 0.0;
}

@compute @workgroup_size(WG_SIZE)
fn wall_servo(@builtin(local_invocation_index) lid: u32) {
    let first = win.first + lid;
    if (first >= particle_end()) {
        return;
    }
    let lane = first % WG_SIZE;
    for (var w = 0u; w < wall_count(); w++) {
        if (walls[w].motion.x != WALL_SERVO) {
            continue;
        }
        var sum = servo_lanes[w * WG_SIZE + lane];
        for (var k = first; k < particle_end(); k += WG_SIZE) {
            sum += wall_push_of(k, w);
        }
        servo_lanes[w * WG_SIZE + lane] = sum;
    }
}

// After every window's wall_servo: each servo wall's push, the lanes added as a tree, and
// its velocity; the lanes start afresh.
@compute @workgroup_size(WG_SIZE)
fn wall_servo_apply(@builtin(local_invocation_index) lid: u32) {
    for (var w = 0u; w < wall_count(); w++) {
        // uniform control flow: every invocation reads the same wall
        let m = walls[w].motion;
        if (m.x != WALL_SERVO) {
            continue;
        }
        wg_push[lid] = servo_lanes[w * WG_SIZE + lid];
        servo_lanes[w * WG_SIZE + lid] = 0.0;
        workgroupBarrier();
        for (var half = WG_SIZE / 2u; half > 0u; half /= 2u) {
            if (lid < half) {
                wg_push[lid] += wg_push[lid + half];
            }
            workgroupBarrier();
        }
        if (lid == 0u) {
            let speed = clamp(m.z * (m.y - wg_push[0]), -m.w, m.w);
            walls[w].velocity = vec4<f32>(speed * walls[w].normal.xyz, 0.0);
        }
        workgroupBarrier();
    }
}
