// model/krijt.wgsl — the Krijt viscoelastic JKR contact and the stress-dependent
// relaxation time (paper 001 §II C, appendix B, §V A) in f32: the twin of
// `src/model/krijt.rs`. A dissipation sub-model of model/jkr.wgsl: it answers the JKR
// law's hooks `jkr_radius_state` and `jkr_damping` for the pairs that use it
// (`src/gpu/composition/`). The contact radius a is per-contact history
// (`contact_radius`, 0 = unset), advanced by a backward-Euler step of eq. B2 solved by
// bisection between the old radius and the JKR root (never past the equilibrium).
//
// Everything is normalised, x = a/a0 and d = delta/delta0, so that f32 intermediates stay
// O(1) or O(Fc):
//   G_eff/gamma = (3x² − d)²/(4x)                           (eq. B1)
//   F_E         = 2·Fc·x·(d − x²)                            (eq. 11)
//   U           = Fc·delta0·x·(9/5·x⁴ − 2x²·d + d² − 2x)     (eq. 7; = P(x) on the JKR curve)
//   p_c/E*      = 2·a0/(pi·R*)·(x − 1/(3·sqrt(x)))           (eq. 9)
//   v_c·dt/a0   = (2E*·gamma/sigma0²)/a0 · dt/T_vis           (eq. B2)

// `KRIJT_BETA_MIN`, `KRIJT_BETA_MAX` (where the crack speed of eq. B2 diverges),
// `KRIJT_X_TOUCH` (a/a0 at the first touch) and `KRIJT_BISECTION_ITERATIONS` are rounded
// from the Rust model's (`gpu::layout::solver_consts`).

// The dimensionless crack speed f(beta) = sigma0²·T_vis·da/dt/(2E*·gamma) of eq. B2 for
// KRIJT_BETA_MIN < beta < KRIJT_BETA_MAX (`krijt::crack_speed_shape`), clamped to ±1e30
// where a logarithm rounds to 0 next to those ends.
fn krijt_shape(beta: f32) -> f32 {
    if (beta <= 0.29) {
        return 0.15 / max(beta * log(0.98 / (1.0 - beta)), 1.5e-31);
    }
    if (beta < 1.0) {
        let x = 1.0 / beta - 1.0;
        if (x <= 0.0) {
            return 0.0;
        }
        return (0.1035 * x + 0.3421) * pow(x, 1.1160);
    }
    if (beta == 1.0) {
        return 0.0;
    }
    if (beta < 3.7) {
        let x = beta - 1.0;
        return -(0.2112 * x + 0.3939) * pow(x, 1.1403);
    }
    return -0.24 * beta / max(log(0.98 / (1.0 - 1.0 / beta)), 2.4e-31 * beta);
}

// The signed beta = sgn(a² − delta·R*)·G_eff/gamma for x = a/a0, d = delta/delta0
// (`krijt::energy_release_ratio`).
fn krijt_ratio(x: f32, d: f32) -> f32 {
    let u = 3.0 * x * x - d;
    let g = u * u / (4.0 * x);
    return select(-g, g, u >= 0.0);
}

// The backward-Euler residual x − x_old − c·f(beta(x)); at the limiting crack speeds only
// its sign matters (`krijt::advance_radius`).
fn krijt_residual(x: f32, x_old: f32, d: f32, c: f32) -> f32 {
    let beta = krijt_ratio(x, d);
    if (beta <= KRIJT_BETA_MIN) {
        return -1.0;
    }
    if (beta >= KRIJT_BETA_MAX) {
        return 1.0;
    }
    return x - x_old - c * krijt_shape(beta);
}

// The root of the residual between x_old and the JKR root x_eq, by bisection (the
// residual increases with x on the stable branch, so the root is unique and bracketed).
fn krijt_advance(x_old: f32, x_eq: f32, d: f32, c: f32) -> f32 {
    if (x_old == x_eq) {
        return x_eq;
    }
    var lo = min(x_old, x_eq);
    var hi = max(x_old, x_eq);
    for (var i = 0; i < KRIJT_BISECTION_ITERATIONS; i++) {
        let mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) {
            break;
        }
        let r = krijt_residual(mid, x_old, d, c);
        if (r == 0.0) {
            return mid;
        }
        if (r < 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return 0.5 * (lo + hi);
}

// A step of a crack that recedes with no equilibrium below x_old (`krijt::recede_radius`),
// 0 where it closes: the backward-Euler root above x_min = sqrt(−d)/3, where G_eff is
// smallest at this overlap, where one exists; else it runs at the slowest speed of its
// path, f(beta) at max(x_min, x_old).
fn krijt_recede(x_old: f32, d: f32, c: f32) -> f32 {
    let x_min = sqrt(max(-d, 0.0)) / 3.0;
    var at = x_old;
    if (x_old > x_min) {
        if (krijt_residual(x_min, x_old, d, c) <= 0.0) {
            return krijt_advance(x_old, x_min, d, c);
        }
        at = x_min;
    }
    let beta = krijt_ratio(at, d);
    if (beta >= KRIJT_BETA_MAX) {
        return 0.0;
    }
    return max(x_old + c * krijt_shape(beta), 0.0);
}

// T_vis at x = a/a0 (`KrijtLaw::relaxation_time_at`): constant, or
// C·R·exp[(B·p_c/E*)^zeta] for p_c > 0 (C·R otherwise) with R = 2R* and p_c of eq. 9.
fn krijt_tvis(p: JkrPair, x: f32, a0: f32, r: f32) -> f32 {
    if (!jkr_dissipation_is(p, JKR_DISSIPATION_STRESS)) {
        return p.tvis;
    }
    let t0 = p.tvis * (2.0 * r);
    let pc = 2.0 * a0 / (JKR_PI * r) * (x - 1.0 / (3.0 * sqrt(x)));
    let base = p.stress_b * pc;
    if (base > 0.0) {
        return t0 * exp(pow(base, p.stress_zeta));
    }
    return t0;
}

// One step dt of the contact radius x = a/a0 from x_old at d = delta/delta0, x_eq the JKR
// root there (`KrijtLaw::step_radius_to_zero`): 0 where a `crack_break` contact has closed
// (receding beyond the turning point d < JKR_D_MIN, or below the unstable root).
fn krijt_step(p: JkrPair, x_old: f32, x_eq: f32, d: f32, dt: f32, a0: f32, r: f32) -> f32 {
    // T_vis at the start of the step drives the crack; v_c·dt/a0 = crack/a0·dt/T_vis,
    // crack = 2E*·gamma/sigma0² (0: sigma0 = 0, a follows the JKR curve instantly)
    let tvis = krijt_tvis(p, x_old, a0, r);
    let recede = p.crack_break != 0u
        && (d < JKR_D_MIN || (x_old < x_eq && krijt_ratio(x_old, d) > 1.0));
    var x = x_eq;
    if (recede) {
        x = 0.0;
    }
    if (p.crack > 0.0 && tvis > 0.0) {
        let c = (p.crack / a0) * (dt / tvis);
        if (c <= 0.0) {
            x = x_old;
        } else if (c < 1e30) {
            if (recede) {
                x = krijt_recede(x_old, d, c);
            } else {
                x = krijt_advance(x_old, x_eq, d, c);
            }
        }
    }
    return x;
}

// The contact of a touched Krijt pair at overlap delta (`JkrParams::normal_force_step`):
// a_old the stored radius (0 at the first touch: a_JKR(0)), x_eq the JKR root a(delta)/a0.
// Returns (x = a/a0 after the step, the elastic force F_E, the stored energy from the JKR
// break point Fc·delta0·(U(x, d) − P(x_break)), −1). A `crack_break` contact whose step
// ends at negative overlap takes KRIJT_NECK_SUBSTEPS sub-steps along delta linear in time
// (`KrijtLaw::step_neck`); where its neck closes it returns (0, the force just before,
// the fraction of the step, 1).
fn krijt_normal(p: JkrPair, k: Kin, a0: f32, d0: f32, fc: f32, x_eq: f32, a_old: f32) -> vec4<f32> {
    let d = k.delta / d0;
    var x_old = KRIJT_X_TOUCH;
    if (a_old > 0.0) {
        x_old = a_old / a0;
    }
    var x = x_old;
    if (p.crack_break != 0u && k.delta < 0.0 && k.dt > 0.0) {
        let n = f32(KRIJT_NECK_SUBSTEPS);
        for (var j = 1; j <= KRIJT_NECK_SUBSTEPS; j++) {
            // (the last sub-step ends at delta, whose JKR root x_eq is known)
            var dj = d;
            var xj = x_eq;
            if (j < KRIJT_NECK_SUBSTEPS) {
                let delta_j = k.delta - k.delta_dot * k.dt * (1.0 - f32(j) / n);
                dj = delta_j / d0;
                let sj = jkr_solve_s(delta_j, d0);
                xj = sj * sj;
            }
            let next = krijt_step(p, x, xj, dj, k.dt / n, a0, k.r_eff);
            if (next <= 0.0) {
                // (closed in sub-step j: at its middle, with the radius before it)
                let t = (f32(j) - 0.5) / n;
                let dx = (k.delta - k.delta_dot * k.dt * (1.0 - t)) / d0;
                let force = 2.0 * fc * x * (dx - x * x) + krijt_viscous(p, a0 * x, a0, k.r_eff, k.delta_dot);
                return vec4<f32>(0.0, force, t, 1.0);
            }
            x = next;
        }
    } else {
        x = krijt_step(p, x_old, x_eq, d, k.dt, a0, k.r_eff);
    }
    let x2 = x * x;
    let elastic = 2.0 * fc * x * (d - x2);
    let u = x * (1.8 * x2 * x2 - 2.0 * x2 * d + d * d - 2.0 * x);
    return vec4<f32>(x, elastic, fc * d0 * (u - p.p_break), -1.0);
}

// The viscous force of eq. 12, (2·T_vis·E*/nu²)·a·delta_dot with T_vis at a, repulsive
// positive (`krijt::viscous_force`); visc = 2E*/nu².
fn krijt_viscous(p: JkrPair, a: f32, a0: f32, r: f32, delta_dot: f32) -> f32 {
    return p.visc * krijt_tvis(p, a / a0, a0, r) * a * delta_dot;
}

// The JKR law's `jkr_radius_state` for a Krijt pair: advances the stored contact radius.
fn krijt_state(p: JkrPair, k: Kin, a0: f32, d0: f32, fc: f32, x_eq: f32, h: ptr<function, History>) -> vec4<f32> {
    let kn = krijt_normal(p, k, a0, d0, fc, x_eq, (*h).contact_radius);
    (*h).contact_radius = a0 * kn.x;
    if (kn.x <= 0.0 && kn.w < 0.0) {
        // (closed at the end of the step: no place within it)
        return vec4<f32>(0.0, 0.0, -1.0, 1.0);
    }
    return vec4<f32>(kn.xyz, 1.0);
}
