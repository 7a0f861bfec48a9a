// ledger.wgsl — the energy ledger and contact statistics on the device, composed into the
// step instead of ledger_off.wgsl when a run wants them (`GpuOptions::ledger`); the twin
// of the CPU engine's (`book` in `src/cpu/engine/contact.rs`, `CpuEngine::contact_stats`).
//
// A contact dissipates over a step the work done on it less the change of its stored
// energy: 0.5·(f0 + f1)·(delta1 − delta0) − ½·dt·(P0 + P1) − (U1 − U0), with
// P = tangential force · tangential velocity + rolling torque · relative angular velocity,
// the normal work of a step that crosses the entry or exit edge taken only over the part
// inside (`pair_edges`), so force jumps are booked right. The last step's values come
// from the entries' `prior`. A pair's evaluator (step/force.wgsl) books all of it and counts it
// for both particles; a wall contact's particle books it, and a moving wall's work on it
// (its normal force's and a placed force jump's over the step, its tangential force's at
// the step's end).
//
// Each particle's totals are four fields of its state (`ledger_*` in `gpu::state`,
// re-sorted with it); each invocation writes only its own, so no atomics and sums that
// are bitwise reproducible. The host reads them only when asked and sums in f64 in id order.

const LEDGER: bool = true;

// What the force kernel gathers for one particle during a step.
struct LedgerAcc {
    dissipated: f32,
    wall_work: f32,
    stored: f32,
    counts: vec4<f32>,
    // largest overlap, largest overlap/a12, sums of overlap/a12 over pairs and walls
    overlaps: vec4<f32>,
}

fn ledger_new() -> LedgerAcc {
    return LedgerAcc(0.0, 0.0, 0.0, vec4<f32>(0.0), vec4<f32>(0.0));
}

// The energy one contact dissipated this step: `old` its prior, `is_in` whether it is
// engaged now, `edges` the law's where the step crossed one, `touch` the force that
// switched at δ = 0 inside it (its work only over the part of the step on the contact
// side, not the trapezoid's).
fn ledger_book(old: vec4<f32>, k: Kin, c: Contact, power: f32, is_in: bool, edges: vec4<f32>, touch: f32) -> f32 {
    let was_in = old.w > 0.0;
    var d0 = old.x;
    var f0 = old.y;
    var d1 = k.delta;
    var f1 = c.normal;
    if (!was_in) {
        d0 = edges.x;
        f0 = edges.y;
    }
    if (!is_in) {
        d1 = edges.z;
        f1 = edges.w;
    }
    var normal = 0.0;
    if (was_in || is_in) {
        normal = 0.5 * (f0 + f1) * (d1 - d0);
    }
    if (touch != 0.0) {
        let inside = select(-d0, d1, d1 > 0.0);
        normal += touch * inside - 0.5 * touch * (d1 - d0);
    }
    // old.z = U0 − ½·dt·P0 (zero when the contact was not engaged)
    return normal - 0.5 * k.dt * power - c.potential + old.z;
}

fn ledger_count(acc: ptr<function, LedgerAcc>, k: Kin, engaged: bool, wall: bool) {
    let o = select(0u, 1u, wall);
    // a pair counts for both its particles (its evaluator books both: half lists)
    let weight = select(2.0, 1.0, wall);
    if (k.delta > 0.0) {
        let ratio = k.delta / (2.0 * k.r_eff);
        (*acc).counts[o] += weight;
        (*acc).overlaps.x = max((*acc).overlaps.x, k.delta);
        (*acc).overlaps.y = max((*acc).overlaps.y, ratio);
        (*acc).overlaps[2u + o] += weight * ratio;
    } else if (engaged) {
        (*acc).counts[2u + o] += weight;
    }
}

// One evaluated particle–particle contact (after pair_contact), whose prior was `old`.
fn ledger_pair(acc: ptr<function, LedgerAcc>, old: vec4<f32>, k: Kin, c: Contact, power: f32, is_in: bool, edges: vec4<f32>, touch: f32) {
    (*acc).dissipated += ledger_book(old, k, c, power, is_in, edges, touch);
    (*acc).stored += c.potential;
    ledger_count(acc, k, is_in, false);
}

// One evaluated wall contact; v_n is the wall's velocity along n, `jump` the impulse of a
// force jump placed at the end of the step (the wall does its work too), `drag` the power
// of the tangential force at the wall's velocity (at the step's end: no prior tangential
// force is kept; over a constant velocity the sum differs from the trapezoid's by a
// boundary term only).
fn ledger_wall(acc: ptr<function, LedgerAcc>, old: vec4<f32>, k: Kin, c: Contact, power: f32, is_in: bool, edges: vec4<f32>, touch: f32, v_n: f32, jump: f32, drag: f32) {
    if (v_n != 0.0) {
        (*acc).wall_work += (0.5 * (select(0.0, old.y, old.w > 0.0) + c.normal) * k.dt + jump) * v_n;
    }
    if (drag != 0.0) {
        (*acc).wall_work += drag * k.dt;
    }
    (*acc).dissipated += ledger_book(old, k, c, power, is_in, edges, touch);
    (*acc).stored += c.potential;
    ledger_count(acc, k, is_in, true);
}

// A listed pair beyond every model's reach whose prior was `old`: if it was engaged it
// leaves with its last force, as the CPU's `book_departed`:
// 0.5·f0·(delta − delta0) + U0 − ½·dt·P0.
fn ledger_departed(acc: ptr<function, LedgerAcc>, old: vec4<f32>, delta: f32) {
    if (old.w > 0.0) {
        (*acc).dissipated += 0.5 * old.y * (delta - old.x) + old.z;
    }
}

// Kahan summation of the step's dissipation into the particle's running total: the f32
// total of a long run would otherwise lose the small per-step increments.
fn ledger_store(k: u32, acc: LedgerAcc) {
    let e = load_ledger_energy(k);
    let y = acc.dissipated - e.y;
    // (opaque: see step/shared.wgsl; without it the compiler folds the compensation to 0)
    let t = opaque1(e.x + y);
    let comp = (t - e.x) - y;
    store_ledger_counts(k, acc.counts);
    store_ledger_overlaps(k, acc.overlaps);
    store_ledger_energy(k, vec4<f32>(t, comp, acc.stored, 0.0));
    if (acc.wall_work != 0.0) {
        let ew = load_ledger_wall(k);
        let yw = acc.wall_work - ew.y;
        let tw = opaque1(ew.x + yw);
        store_ledger_wall(k, vec4<f32>(tw, (tw - ew.x) - yw, 0.0, 0.0));
    }
}

// remap on a rebuild: an engaged contact of the old list (a pair's or a wall's) in no new
// list moved out of reach + skin within one step (only a violent step does that). It is
// booked as having left at its last overlap (U0 − ½·dt·P0; the CPU also adds the normal
// work 0.5·f0·(delta − delta0) at its current overlap, which is not at hand here) and
// counted in `CONTROL_DROPPED`, so the host can say so.
fn ledger_dropped(old_row: u32, old_n: u32, k: u32) {
    var lost = 0.0;
    for (var m = 0u; m < old_n; m++) {
        let old = load_prior_far(old_row + m);
        if (old.w <= 0.0) {
            continue;
        }
        // the pair is in k's new list, or in a partner's that lists k (`lower`, resolved)
        let partner = load_hist_pid_far(old_row + m);
        var found = false;
        let row = b_first(k);
        for (var e = row; e < row + b_len(k); e++) {
            if (load_new_hist_pid(e) == partner) {
                found = true;
                break;
            }
        }
        let low = lower_first(k);
        for (var s = low; s < low + lower_len(k) && !found; s++) {
            if (load_ids(entry_owner(load_lower(s))).x == partner) {
                found = true;
            }
        }
        if (!found) {
            lost += old.z;
            atomicAdd(&control[CONTROL_DROPPED], 1u);
        }
    }
    if (lost != 0.0) {
        var e = load_ledger_energy(k);
        let y = lost - e.y;
        let t = opaque1(e.x + y);
        e.y = (t - e.x) - y;
        e.x = t;
        store_ledger_energy(k, e);
    }
}
