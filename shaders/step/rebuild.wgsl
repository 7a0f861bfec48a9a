// rebuild.wgsl — whether the lists must be rebuilt (`decide`, `decide_lean`) and the
// rebuild's kernels: the grid's gather, the neighbour search into new lists, their
// commit, each entry's history remapped by persistent id and the lists copied back.

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

// Halts the batch (`why`: HALT_GROW or HALT_REBUILD in control[CONTROL_HALT]): every indirect argument
// zeroed, so every later pass of the batch launches nothing; the host finishes it
// (`GpuEngine::run_steps`). True where this call halted it.
fn halt(why: u32) -> bool {
    // (single-invocation kernels, one dispatch after another: no race)
    if (atomicLoad(&control[CONTROL_HALT]) != 0u) {
        return false;
    }
    atomicStore(&control[CONTROL_HALT], why);
    for (var i = 0u; i < arrayLength(&args); i++) {
        args[i] = 0u;
    }
    return true;
}

// One invocation, after kick_drift: whether to rebuild (`rebuild_due`). Writes the flag and
// the indirect arguments of the grid sort and of the rebuild's per-particle passes (zero
// workgroups without a rebuild), and starts the next maximum afresh.
@compute @workgroup_size(1)
fn decide() {
    // a halted batch runs nothing more (`halt`)
    if (atomicLoad(&control[CONTROL_HALT]) != 0u) {
        return;
    }
    atomicAdd(&control[CONTROL_STEPS_BEGUN], 1u);
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
        atomicStore(&control[CONTROL_STEPS_SINCE_REBUILD], 0u);
    } else {
        atomicAdd(&control[CONTROL_STEPS_SINCE_REBUILD], 1u);
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
    if (atomicLoad(&control[CONTROL_HALT]) != 0u) {
        return;
    }
    atomicAdd(&control[CONTROL_STEPS_BEGUN], 1u);
    if (rebuild_due()) {
        halt(HALT_REBUILD);
        return;
    }
    atomicStore(&control[SKIN_REBUILD], 0u);
    atomicAdd(&control[CONTROL_STEPS_SINCE_REBUILD], 1u);
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
// in its cell; a SIMD group loops as long as its longest list (`docs/performance.md`).
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
    // (a particle whose data lies beyond this window's bindings stops the run: `CONTROL_BEYOND_WINDOW`)
    if (!in_bindings(sorted_index[k])) {
        atomicMax(&control[CONTROL_BEYOND_WINDOW], 1u);
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
                        atomicMax(&control[CONTROL_BEYOND_WINDOW], 1u);
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
    atomicMax(&control[CONTROL_LONGEST_LIST], max(c.x, c.y));
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
// particle's neighbours lay beyond the windows bound, `CONTROL_BEYOND_WINDOW`), halt the batch — zero
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
    if (need > step.list_capacity || atomicLoad(&control[CONTROL_BEYOND_WINDOW]) != 0u) {
        atomicMax(&control[CONTROL_ENTRIES_NEEDED], need);
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
