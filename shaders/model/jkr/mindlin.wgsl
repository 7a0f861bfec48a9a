// model/jkr/mindlin.wgsl — the tangential spring of the JKR family (paper 002 eqs. 14–17) in
// f32: the twin of `JkrParams::tangential_force` in `src/model/jkr/mindlin.rs`. Composed in where
// some JKR/Hertz pair has friction; keeps the history field `spring`
// (`model::jkr::mindlin::HISTORY`), in the evaluating particle's frame.

// Tangential force on i: the spring rotated into the tangent plane, s += v_t·dt,
// F = −St·s − c_t·v_t with St = 8G*·a and c_t = tsuji·sqrt(8G*·rho·m*) (rho:
// `jkr_tsuji_radius`: a, or paper 002's sqrt(R*·delta)), truncated to
// |F| <= mu_s·|F_el + 2Fc| (the normal law's Coulomb load) with the spring set consistent
// with the truncated force. Stores ½·St·|s|² with the contact's energy.
fn mindlin_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let p = row.jkr;
    if (p.friction <= 0.0) {
        return;
    }
    var s = rotate_into_plane((*h).spring, k.n) + k.v_t * k.dt;
    let st = 8.0 * p.g_star * nf.a;
    var ct = 0.0;
    if (jkr_dissipation_is(p, JKR_DISSIPATION_TSUJI)) {
        // the dashpot's St: the spring's 8G*·a, or paper 002's 8G*·sqrt(R*·delta)
        ct = p.tsuji * sqrt(8.0 * p.g_star * jkr_tsuji_radius(p, nf.a, k.delta, k.r_eff) * k.m_eff);
    }
    var force = -st * s - ct * k.v_t;
    let limit = p.friction * nf.coulomb;
    let magnitude = length(force);
    if (magnitude > limit) {
        (*c).sliding = true;
        force = force * (limit / magnitude);
        if (st > 0.0) {
            s = -(force + ct * k.v_t) / st;
        }
    }
    (*h).spring = s;
    (*c).tangential = force;
    (*c).potential += 4.0 * p.g_star * nf.a * dot(s, s);
}
