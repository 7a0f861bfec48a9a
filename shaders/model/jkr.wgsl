// model/jkr.wgsl — the JKR family's normal law (JKR, Hertz) in f32, with contact
// hysteresis and the Tsuji or power-law damping: the twin of `src/model/jkr/mod.rs`
// (papers 001 §II and 002 §2–3), tied to it through whole collisions
// (`tests/collide_jkr.rs`, `mod on_the_gpu`). The Krijt dissipations, Mindlin friction and
// rolling resistance are sub-models in their own files, composed in where some pair uses
// them. Signs as in Rust: delta > 0 overlap, delta_dot the approach speed, repulsive force
// positive, n from j to i.
//
// Needs, from the composition (`src/gpu/composition/`): `Kin`, `Normal`, `History` with
// the field `touched`, and the dissipation hooks, generated from the sub-models present:
//   fn jkr_damping(p: JkrPair, a: f32, a0: f32, k: Kin) -> f32      the dissipative force;
//   fn jkr_radius_state(p: JkrPair, k: Kin, a0: f32, d0: f32, fc: f32, x_eq: f32,
//                       h: ptr<function, History>) -> vec4<f32>
//     (x, elastic force, stored energy, 1) where a sub-model keeps the contact radius as
//     state, (x_eq, 0, 0, 0) where the JKR curve gives it.

// A pair's parameters: `JkrPair` and the `JKR_DISSIPATION_*` kinds (`gpu::layout`), filled
// from `JkrParams` on the host (in f64, then rounded).

// Set per pipeline (`gpu::engine`) when every JKR-family row of the scene has the same
// dissipation (its code; 255: they differ, each pair reads its own) and the same adhesion
// (0: all Hertz, 1: all adhesive; 2: they differ). The compiler then drops the branches no
// pair takes; on a SIMD adapter a branch costs whether a lane takes it or not.
override JKR_ONE_DISSIPATION: u32 = 255u;
override JKR_ADHESION: u32 = 2u;

fn jkr_dissipation_is(p: JkrPair, d: u32) -> bool {
    if (JKR_ONE_DISSIPATION != 255u) {
        return JKR_ONE_DISSIPATION == d;
    }
    return p.dissipation == d;
}

// The contact radius is state (model/krijt.wgsl).
fn jkr_radius_dynamics(p: JkrPair) -> bool {
    if (JKR_ONE_DISSIPATION != 255u) {
        return JKR_ONE_DISSIPATION >= JKR_DISSIPATION_KRIJT;
    }
    return p.dissipation >= JKR_DISSIPATION_KRIJT;
}

fn jkr_hertz(p: JkrPair) -> bool {
    if (JKR_ADHESION != 2u) {
        return JKR_ADHESION == 0u;
    }
    return p.gamma == 0.0;
}
// The solver's constants, `JKR_S_MIN`, `JKR_D_MIN`, `JKR_C`, `JKR_B`, `JKR_SQRT3`,
// `JKR_SLOPE0`, `JKR_PI` and `JKR_NEWTON_ITERATIONS`, are rounded from the Rust solver's
// (`gpu::layout::solver_consts`).

// s = sqrt(a/a0), the stable root of 3s⁴ − 2s = delta/delta0: the guarded Newton of
// `jkr::contact_radius_f32`, step for step.
fn jkr_solve_s(delta: f32, delta0: f32) -> f32 {
    let e = max(delta / delta0 - JKR_D_MIN, 0.0);
    let r = sqrt(e);
    let q = 2.0 * r / JKR_SQRT3;
    var t = min(r / JKR_SLOPE0, q / (JKR_C + sqrt(JKR_C * JKR_C + 2.0 * q)));
    for (var i = 0; i < JKR_NEWTON_ITERATIONS; i++) {
        let tc = t + JKR_C;
        let w = tc * tc + JKR_B;
        t = (t * t * tc + r * sqrt(w) / JKR_SQRT3) / (w + t * tc);
    }
    return JKR_S_MIN + t;
}

// R*^(2/3) (R* > 0): a0 and xi_crit scale with it.
fn jkr_r23(r: f32) -> f32 {
    return pow(r, 2.0 / 3.0);
}

// The radius rho of the Tsuji dashpots Sn = 2E*·rho, St = 8G*·rho (`TsujiStiffness::radius`):
// the contact radius a, or sqrt(R*·max(delta, 0)) (paper 002 eq. 13).
fn jkr_tsuji_radius(p: JkrPair, a: f32, delta: f32, r: f32) -> f32 {
    if (p.tsuji_hertz != 0u) {
        return sqrt(r * max(delta, 0.0));
    }
    return a;
}

// The dissipative normal force for contact radius a at overlap delta
// (`JkrParams::normal_dissipation`); a0 and R* for the Krijt viscous force.
fn jkr_dissipation(p: JkrPair, a: f32, delta: f32, a0: f32, delta_dot: f32, m: f32, r: f32) -> f32 {
    if (jkr_dissipation_is(p, JKR_DISSIPATION_TSUJI)) {
        // Sn = 2E*·a (paper 002 eq. 13 for Hertz; a exists at negative overlap in JKR), or
        // paper 002's 2E*·sqrt(R*·delta)
        let sn = 2.0 * p.e_star * jkr_tsuji_radius(p, a, delta, r);
        return p.tsuji * sqrt(sn * m) * delta_dot;
    }
    if (jkr_dissipation_is(p, JKR_DISSIPATION_POWER)) {
        if (delta_dot == 0.0) {
            return 0.0;
        }
        // WGSL's pow(x, y) is undefined for x < 0 (and for x = 0, y <= 0): raise |delta_dot|
        // and a >= 0, and apply the sign apart. Exponent 0 gives 1, as powf does.
        var va = 1.0;
        if (p.power_alpha != 0.0) {
            va = pow(abs(delta_dot), p.power_alpha);
        }
        var ab = 1.0;
        if (p.power_beta != 0.0) {
            ab = select(0.0, pow(a, p.power_beta), a > 0.0);
        }
        return sign(delta_dot) * p.power_d * p.e_star * va * ab;
    }
    return 0.0;
}

// Normal force with the JKR contact hysteresis (`JkrParams::normal_force`):
// * no force before the first touch (delta <= 0, not touched);
// * from delta > 0 the contact persists (also at negative overlap) until delta falls to
//   break_ratio·delta0, or with `crack_break` until the Krijt crack has closed (x = 0),
//   where it breaks and the whole history is forgotten (the composition clears the other
//   sub-models' fields when a pair is out of contact);
// * Hertz (gamma = 0): contact only while delta > 0.
// The elastic force is evaluated in the normalised form F = 4·Fc·(x³ − x^(3/2)), x = a/a0
// = s², which equals 4E*a³/(3R*) − 4·sqrt(pi·gamma·E*·a³) (a0³ = 9·pi·gamma·R*²/E*) and
// keeps every intermediate O(Fc) in f32. Where a sub-model keeps the contact radius as
// state (the Krijt dissipations) `jkr_radius_state` gives x, the force and the energy.
// The friction laws' Coulomb load is |F_el + 2Fc| (paper 002 eq. 17).
fn jkr_normal(p: JkrPair, k: Kin, h: ptr<function, History>) -> Normal {
    var out = Normal(false, false, 0.0, 0.0, 0.0, 0.0, 0.0, vec2<f32>(-1.0, 0.0));
    let r = k.r_eff;
    var a0 = 0.0;
    var elastic = 0.0;
    var fc = 0.0;
    if (jkr_hertz(p)) {
        if (k.delta <= 0.0) {
            (*h).touched = false;
            return out;
        }
        let a = sqrt(r * k.delta);
        elastic = 4.0 * p.e_star * a * a * a / (3.0 * r);
        out.a = a;
        out.potential = 0.4 * elastic * k.delta;
    } else {
        if (!(*h).touched && k.delta <= 0.0) {
            return out;
        }
        a0 = p.a0_coef * jkr_r23(r);
        let d0 = a0 * a0 / (3.0 * r);
        if (k.delta <= p.break_ratio * d0) {
            (*h).touched = false;
            return out;
        }
        let s = jkr_solve_s(k.delta, d0);
        var x = s * s;
        fc = 3.0 * JKR_PI * p.gamma * r;
        let state = jkr_radius_state(p, k, a0, d0, fc, x, h);
        if (state.w != 0.0) {
            if (state.x <= 0.0) {
                // the crack has closed the neck (`crack_break`): the contact breaks, where
                // within the step the state says (fraction, force just before)
                (*h).touched = false;
                out.broke = state.zy;
                return out;
            }
            x = state.x;
            elastic = state.y;
            out.potential = state.z;
        } else {
            elastic = 4.0 * fc * (x * x * x - x * s);
            out.potential = fc * d0 * (jkr_potential_shape(x, s) - p.p_break);
        }
        out.a = a0 * x;
        out.x = x;
    }
    (*h).touched = true;
    out.in_contact = true;
    out.engaged = true;
    out.force = elastic + jkr_damping(p, out.a, a0, k);
    out.coulomb = abs(elastic + 2.0 * fc);
    return out;
}

fn jkr_potential_shape(x: f32, s: f32) -> f32 {
    let x2 = x * x;
    return 4.8 * x2 * x2 * x - 8.0 * x2 * x * s + 2.0 * x2;
}

// The kinematics k at the overlap delta of a contact's edge: the damping hook reads the
// overlap (paper 002's Tsuji stiffness sqrt(R*·delta) is zero at both edges).
fn jkr_at_edge(k: Kin, delta: f32) -> Kin {
    var e = k;
    e.delta = delta;
    return e;
}

// Where a contact starts and ends and the force just inside those edges, for the energy
// ledger (`JkrParams::edge_forces`): (entry delta, entry force, exit delta, exit force),
// with the JKR radius at both edges also for the Krijt dissipations (as on the CPU).
fn jkr_edges(p: JkrPair, k: Kin) -> vec4<f32> {
    if (jkr_hertz(p)) {
        // Hertz: a = 0 at the single edge delta = 0
        let f = jkr_damping(p, 0.0, 0.0, jkr_at_edge(k, 0.0));
        return vec4<f32>(0.0, f, 0.0, f);
    }
    let r = k.r_eff;
    let a0 = p.a0_coef * jkr_r23(r);
    let d0 = a0 * a0 / (3.0 * r);
    let fc = 3.0 * JKR_PI * p.gamma * r;
    let s_in = jkr_solve_s(0.0, d0);
    let x_in = s_in * s_in;
    let f_in = 4.0 * fc * (x_in * x_in * x_in - x_in * s_in) + jkr_damping(p, a0 * x_in, a0, jkr_at_edge(k, 0.0));
    if (p.crack_break != 0u) {
        // the crack closed with a = 0 and no force where the step ends
        return vec4<f32>(0.0, f_in, k.delta, 0.0);
    }
    let d_out = p.break_ratio * d0;
    let s_out = jkr_solve_s(d_out, d0);
    let x_out = s_out * s_out;
    let f_out = 4.0 * fc * (x_out * x_out * x_out - x_out * s_out) + jkr_damping(p, a0 * x_out, a0, jkr_at_edge(k, d_out));
    return vec4<f32>(0.0, f_in, d_out, f_out);
}

// The force that switches on at delta = 0 inside an engaged contact
// (`ContactModel::touch_jump`): none, the JKR force is continuous there.
fn jkr_touch_jump(p: JkrPair, k: Kin) -> f32 {
    return 0.0;
}
