// model/hysteretic.wgsl — the piece-wise linear hysteretic adhesive elasto-plastic model
// (paper 000 §2.2–2.3) and the linear spring–dashpot, in f32. The f64 reference is
// `src/model/hysteretic.rs` / `src/model/lsd.rs`; tests tie the two together.
//
// Sign convention as in Rust: delta > 0 is overlap, delta_dot the approach speed, a
// positive force is repulsive.

// A pair's parameters: `HystereticPair` and the `HYST_*` flags (`gpu::layout`). LSD shares
// the row and takes its own branch (`HYST_LSD`): a spring-dashpot only while overlapping.

// Set per pipeline (`gpu::engine`) when every hysteretic/LSD row of the scene has the same
// flags (0xffffffff: they differ, each pair reads its own): the compiler then drops the
// branches of the rules no pair uses; on a SIMD adapter a branch costs whether a lane
// takes it or not.
override HYST_ONE_FLAGS: u32 = 0xffffffffu;

fn hyst_flag(p: HystereticPair, bit: u32) -> bool {
    if (HYST_ONE_FLAGS != 0xffffffffu) {
        return (HYST_ONE_FLAGS & bit) != 0u;
    }
    return (p.flags & bit) != 0u;
}

// The contact's history: delta_max and the "has touched" flag.
struct HystHistory {
    delta_max: f32,
    touched: bool,
}

struct HystForce {
    force: f32,
    history: HystHistory,
    // Stored energy (energy ledger): ½·k2·(delta − delta0)² along the current un-/re-
    // loading line plus the adhesion potential (`HystereticParams::force`).
    potential: f32,
}

fn hyst_range(p: HystereticPair) -> f32 {
    if (p.fa > 0.0 && p.kca > 0.0) {
        return p.fa / p.kca;
    }
    return 0.0;
}

// k2 at x = delta_max/delta_max^p.
fn hyst_k2(p: HystereticPair, x: f32) -> f32 {
    if (x >= 1.0) {
        return p.kp;
    }
    var shape = max(x, 0.0);
    if (hyst_flag(p, HYST_SQRT_RULE)) {
        shape = sqrt(shape);
    }
    return p.k1 + (p.kp - p.k1) * shape;
}

// delta0 for the k2 of delta_max (the caller has it: one division fewer per pair).
fn hyst_delta0(p: HystereticPair, delta_max: f32, dmaxp: f32, a12: f32, k2: f32) -> f32 {
    if (delta_max >= dmaxp) {
        return p.phi_f * a12;
    }
    return (1.0 - p.k1 / k2) * delta_max;
}

// The un-/re-loading line of delta_max: (k2, delta0). `inv_a12` = 1/a12.
fn hyst_line(p: HystereticPair, delta_max: f32, dmaxp: f32, a12: f32, inv_a12: f32) -> vec2<f32> {
    let k2 = hyst_k2(p, delta_max * p.inv_dmaxp_per_a12 * inv_a12);
    return vec2<f32>(k2, hyst_delta0(p, delta_max, dmaxp, a12, k2));
}

// The delta_max whose k2 line passes through (delta, -kc*delta): where the tensile branch
// hands over to re-loading (see `delta_max_on_tensile_branch` in Rust).
fn hyst_tensile_history(p: HystereticPair, delta: f32, dmaxp: f32, a12: f32) -> f32 {
    if (p.kp <= p.k1) {
        return 0.0;
    }
    if (delta >= p.tensile_limit_per_a12 * a12) {
        return dmaxp;
    }
    if (!hyst_flag(p, HYST_SQRT_RULE)) {
        // (k1 + kc)·delta/s with s = (kp − k1)/dmaxp
        return 0.5 * delta + sqrt(0.25 * delta * delta + p.tensile_c * delta * dmaxp);
    }
    // sqrt rule: s*u^3 - s*delta*u - (k1 + kc)*delta = 0, u = sqrt(delta_max): bisection
    // (f32 converges in 24 halvings; 40 leaves margin).
    let s = (p.kp - p.k1) / sqrt(dmaxp);
    var lo = sqrt(delta);
    var hi = sqrt(dmaxp);
    for (var i = 0; i < 40; i++) {
        let mid = 0.5 * (lo + hi);
        if (s * mid * mid * mid - s * delta * mid - (p.k1 + p.kc) * delta > 0.0) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let u = 0.5 * (lo + hi);
    return u * u;
}

// The mechanical contact force f_hys for delta > 0 (paper 000 eq. 5), updating delta_max.
fn hyst_contact_force(p: HystereticPair, delta: f32, a12: f32, inv_a12: f32, h: ptr<function, HystHistory>) -> f32 {
    let dmaxp = p.dmaxp_per_a12 * a12;
    if (delta >= (*h).delta_max) {
        (*h).delta_max = delta;
        if (delta < dmaxp) {
            return p.k1 * delta;
        }
        return p.kp * (delta - p.phi_f * a12);
    }
    let line = hyst_line(p, (*h).delta_max, dmaxp, a12, inv_a12);
    let elastic = line.x * (delta - line.y);
    if (elastic >= p.k1 * delta && (*h).delta_max < dmaxp) {
        return p.k1 * delta;
    }
    if (elastic <= -p.kc * delta) {
        (*h).delta_max = min(hyst_tensile_history(p, delta, dmaxp, a12), (*h).delta_max);
        return -p.kc * delta;
    }
    return elastic;
}

// Potential of the reversible non-contact adhesion, zero beyond the range
// (`adhesion_potential` in Rust; kca = 0 encodes zero range).
fn hyst_adhesion_potential(p: HystereticPair, delta: f32) -> f32 {
    var well = 0.0;
    if (p.kca > 0.0) {
        well = 0.5 * p.fa * p.fa / p.kca;
    }
    if (delta > 0.0) {
        return -p.fa * delta - well;
    }
    return -0.5 * p.kca * delta * delta - p.fa * delta - well;
}

// Total normal force of the pair (contact + non-contact adhesion + viscosity).
fn hyst_force(p: HystereticPair, delta: f32, delta_dot: f32, a12: f32, inv_a12: f32, history: HystHistory) -> HystForce {
    var h = history;
    if (hyst_flag(p, HYST_LSD)) {
        if (delta > 0.0) {
            return HystForce(p.k1 * delta + p.gamma0 * delta_dot, HystHistory(0.0, false), 0.5 * p.k1 * delta * delta);
        }
        return HystForce(0.0, HystHistory(0.0, false), 0.0);
    }
    let range = hyst_range(p);
    if (delta > 0.0) {
        h.touched = true;
        let f = hyst_contact_force(p, delta, a12, inv_a12, &h) - p.fa + p.gamma0 * delta_dot;
        let line = hyst_line(p, h.delta_max, p.dmaxp_per_a12 * a12, a12, inv_a12);
        let d = delta - line.y;
        var u = 0.5 * line.x * d * d;
        if (p.fa > 0.0) {
            u += hyst_adhesion_potential(p, delta);
        }
        return HystForce(f, h, u);
    }
    if (delta > -range) {
        h.delta_max = 0.0;
        if (delta == 0.0) {
            h.touched = true;
        }
        if (!hyst_flag(p, HYST_JUMP_IN) || h.touched) {
            return HystForce(-p.kca * delta - p.fa, h, hyst_adhesion_potential(p, delta));
        }
        return HystForce(0.0, h, 0.0);
    }
    return HystForce(0.0, HystHistory(0.0, false), 0.0);
}

// ---- the sub-model interface (see `src/gpu/composition/interface.rs`) ----

// The stored history word `hyst_state` (`model::hysteretic::HISTORY`): delta_max (never
// negative) with the sign bit as the "touched" flag. +0.0, the zeroed buffer's value, is
// untouched; -0.0 is touched at delta_max = 0. One word a contact: a storage binding holds
// twice the contacts of a vec2.
const HYST_TOUCHED_BIT: u32 = 0x80000000u;

fn hyst_history_in(h: f32) -> HystHistory {
    let bits = bitcast<u32>(h);
    return HystHistory(bitcast<f32>(bits & ~HYST_TOUCHED_BIT), (bits & HYST_TOUCHED_BIT) != 0u);
}

fn hyst_history_out(h: HystHistory) -> f32 {
    // (abs: delta_max >= 0 by construction; a -0.0 must not read as touched)
    let bits = bitcast<u32>(abs(h.delta_max));
    return bitcast<f32>(bits | select(0u, HYST_TOUCHED_BIT, h.touched));
}

// The normal force (a12 = 2·R*, 2r for a wall). In mechanical contact (delta > 0) the
// Coulomb limits of the friction laws act on Luding's load f_n + kc·delta + fa, the
// normal force with the adhesive parts taken out, never negative.
fn hyst_normal(p: HystereticPair, k: Kin, h: ptr<function, History>) -> Normal {
    let r = hyst_force(p, k.delta, k.delta_dot, 2.0 * k.r_eff, k.inv_a12, hyst_history_in((*h).hyst_state));
    (*h).hyst_state = hyst_history_out(r.history);
    let coulomb = max(0.0, r.force + p.kc * k.delta + p.fa);
    return Normal(k.delta > 0.0, r.history.touched, r.force, r.potential, 0.0, 0.0, coulomb, vec2<f32>(-1.0, 0.0));
}

// Where a contact starts and ends and the force just inside those edges, for the energy
// ledger (`ContactModel::edges`): (entry delta, entry force, exit delta, exit force).
// At the first touch the force jumps by the adhesion -fa and the viscous
// gamma0·delta_dot (LSD: fa = 0); with a non-contact range a contact leaves at -range with
// zero force, and enters there too where the adhesion is reversible (jump-in: an untouched
// pair feels nothing in the range, it enters at the touch).
fn hyst_edges(p: HystereticPair, k: Kin) -> vec4<f32> {
    let range = hyst_range(p);
    let f = -p.fa + p.gamma0 * k.delta_dot;
    if (range == 0.0) {
        return vec4<f32>(0.0, f, 0.0, f);
    }
    if (hyst_flag(p, HYST_JUMP_IN)) {
        return vec4<f32>(0.0, f, -range, 0.0);
    }
    return vec4<f32>(-range, 0.0, -range, 0.0);
}

// The force that switches on at delta = 0 inside an engaged contact
// (`ContactModel::touch_jump`): the viscous gamma0·delta_dot where a non-contact range
// surrounds the touch (there the contact and non-contact forces meet at -fa).
fn hyst_touch_jump(p: HystereticPair, k: Kin) -> f32 {
    return select(0.0, p.gamma0 * k.delta_dot, hyst_range(p) > 0.0);
}
