// jump.wgsl — the impulse velocity Verlet misplaces where a contact's normal force jumps
// inside the step (JKR at the touch and at pull-off, jump-in adhesion, a viscous first
// touch), to be added at the end of the step: the twin of `cpu::jump`, which derives it
// (and docs/force_jumps.md). Composed into the step instead of jump_off.wgsl where the
// scene places them (`jump_impulses`); `step.jumps` turns them off for the initial forces.

const JUMPS: bool = true;

// The fraction of the step before the overlap reached `edge`, linear in time, in [0, 1].
fn jump_fraction(before: f32, after: f32, edge: f32) -> f32 {
    let span = after - before;
    if (span == 0.0) {
        return 0.5;
    }
    return clamp((edge - before) / span, 0.0, 1.0);
}

// Whether the overlap passed `edge` between `before` and `after` (in either direction).
fn jump_passed(before: f32, after: f32, edge: f32) -> bool {
    return (before <= edge && edge <= after) || (after <= edge && edge <= before);
}

// The normal impulse (repulsive positive) of a contact that entered (or left) within a
// step of length dt, from the overlaps before and after, the edge (δ, F just inside) and
// the force inside at the other end of the step (after an entry, before an exit): what
// the force delivered minus what velocity Verlet gave, both trapezoidal over the part of
// the step inside the contact; 0 without a jump or where the edge was not passed.
fn jump_impulse(entered: bool, before: f32, after: f32, edge: vec2<f32>, force: f32, dt: f32) -> f32 {
    if (edge.y == 0.0 || !jump_passed(before, after, edge.x)) {
        return 0.0;
    }
    let t = jump_fraction(before, after, edge.x);
    let inside = select(t, 1.0 - t, entered);
    return (inside * 0.5 * (edge.y + force) - 0.5 * force) * dt;
}

// One contact's force jump over the step, along n on the evaluator: `old` the contact as
// the last step left it (the entries' `prior`), `is_in` whether it is engaged now, `edges`
// the law's (entry δ, F, exit δ, F) where the step crossed one (`pair_edges`), `touch` the
// force that switched at δ = 0 inside the engaged contact (`touch_crossed`).
fn contact_jump(old: vec4<f32>, k: Kin, c: Contact, is_in: bool, edges: vec4<f32>, touch: f32) -> f32 {
    let was_in = old.w > 0.0;
    if (step.jumps == 0u) {
        return 0.0;
    }
    let before = overlap_before(old, k);
    var j = 0.0;
    if (touch != 0.0) {
        j = jump_impulse(k.delta > 0.0, before, k.delta, vec2<f32>(0.0, touch), touch, k.dt);
    }
    if (was_in != is_in && is_in) {
        j += jump_impulse(true, before, k.delta, edges.xy, c.normal, k.dt);
    } else if (was_in != is_in) {
        j += jump_impulse(false, before, k.delta, edges.zw, old.y, k.dt);
    }
    return j;
}

// Adds a velocity change (a force jump's impulse over the mass) to particle k's velocity,
// Kahan-compensated as the kicks are.
fn jump_kick(k: u32, dv: vec3<f32>) {
    if (any(dv != vec3<f32>(0.0))) {
        let vel = load_vel(k);
        let kv = kahan_add_nonzero(vel.xyz, load_kahan_v(k).xyz, dv);
        store_vel(k, vec4<f32>(kv.x, vel.w));
        store_kahan_v(k, vec4<f32>(kv.c, 0.0));
    }
}

