// model/jkr/rolling.wgsl — the rolling resistance of the JKR family (paper 002 eqs.
// 18–22, Dominik–Tielens/Krijt) in f32: the twin of `JkrParams::rolling_torque` in
// `src/model/jkr/rolling.rs`. Composed in where some JKR pair has rolling resistance; keeps the
// history field `xi` (`model::jkr::rolling::HISTORY`), the same seen from both sides.

// Rolling-resistance torque on i: xi rotated into the tangent plane, xi += v_roll·dt,
// truncated at xi_crit = (a0_unscaled/12)·(delta gamma/gamma); torque −kr·(n × xi) with
// kr = 4·Fc_unscaled·(a/a0)^(3/2). Stores ½·kr·|xi|² with the contact's energy.
fn jkr_rolling_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let p = row.jkr;
    if (p.rolling_hysteresis <= 0.0 || p.fc_unscaled_per_r <= 0.0) {
        return;
    }
    var x = rotate_into_plane((*h).xi, k.n) + k.v_roll * k.dt;
    let r = k.r_eff;
    let xi_crit = p.a0_unscaled_coef * jkr_r23(r) / 12.0 * p.rolling_hysteresis;
    let len = length(x);
    if (len > xi_crit) {
        x = x * (xi_crit / len);
    }
    (*h).xi = x;
    let kr = 4.0 * (p.fc_unscaled_per_r * r) * nf.x * sqrt(nf.x);
    (*c).rolling = -kr * cross(k.n, x);
    (*c).potential += 0.5 * kr * dot(x, x);
}
