// shared.wgsl — what the step's kernels share: its parameters, bindings, the lists' rows
// and helpers. The step is composed per scene (`Composition::variant` in
// `src/gpu/composition/mod.rs`) after common.wgsl, the state's and records' accessors, the
// contact laws and sub-models the scene uses, overlap.wgsl, the generated interface the
// step calls (`PairRow`, `Hist`, `hist_*`, `pair_contact`, `pair_edges`,
// `pair_touch_jump`), the rotation, ledger and force-jump hooks (or their no-op twins)
// and the state's reads (buffers, or texture mirrors); then this file and the kernels by
// phase: drift.wgsl, rebuild.wgsl, force.wgsl, collect.wgsl, walls.wgsl.
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
// `StepParams`, `Wall` and the constants shared with the host are generated from Rust
// (`gpu::layout::declarations`).

// x, hidden from the compiler behind `step.zero`, so Kahan compensations are not folded.
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


// The lists are compressed rows: particle k's entries are ids.y .. ids.y + ids.z of the
// entries' fields (nbr, hist_pid, hist, prior, the pair force and torque, ...), in
// sorted order, so consecutive particles' rows are consecutive within a window; its wall
// contacts follow, ids.w of them (`WALL_ENTRY`). `rows`
// holds four per-particle regions (blocked by window like the state's): the lengths and
// first entries of the lists a rebuild builds (B) and of the `lower` lists; the scans of
// `gpu::grid` turn each window's count region into its row region.
@group(0) @binding(90) var<storage, read_write> rows: array<u32>;
// (its regions: `ROWS_B_COUNT`, `ROWS_B_ROW`, `ROWS_LOWER_COUNT`, `ROWS_LOWER_ROW`, of
// `ROWS_REGION_COUNT`: `gpu::records`)

// (blocked by window like the state; the rows are local to the particle's window: the
// lists of a window's particles fill its block of entries, `gpu::window`)
fn row_at(region: u32, k: u32) -> u32 {
    return blocked(ROWS_REGION_COUNT, region, k);
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
// pairs of its row. So a wall contact takes room only where a particle is near a wall, and
// its history survives the re-sort as a pair's does (`remap`, by this id).

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

// The control words (`gpu::control`, named there: `CONTROL_*` the monitor, zeroed per
// batch of steps and read back after it, with no per-step read-back; `SKIN_*` the Verlet
// skin state, persistent across batches).
@group(0) @binding(48) var<storage, read_write> control: array<atomic<u32>, CONTROL_END>;

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
    // A contact that broke within the step at a time the law resolves (a `crack` neck
    // closing; `NormalForce::broke_within`): the fraction of the step and the normal force
    // just before; x < 0: none.
    broke: vec2<f32>,
}
