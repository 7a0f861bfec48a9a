// model/friction/rolling.wgsl — Luding's rolling friction in f32: the twin of
// `model::friction::rolling`. Composed in where some hysteretic/LSD pair has rolling
// friction; keeps the history field `xi` (`friction::rolling::HISTORY`), the same seen from
// both sides.

// Rolling couple on i (−it on j): the pseudo-force of one Coulomb step with the rolling
// velocity v_r = −a12·n × (w_i − w_j), applied at the lever a12 = 2R*: a12·n × f_r.
fn luding_rolling_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let s = row.luding_rolling;
    if (s.mu_s <= 0.0) {
        return;
    }
    let lever = 2.0 * k.r_eff;
    let v = -lever * cross(k.n, k.w_rel);
    let st = coulomb3(s, s.k, rotate_into_plane((*h).xi, k.n), v, nf.coulomb, s.mu_s, k.dt);
    (*h).xi = st.stored;
    (*c).rolling += lever * cross(k.n, st.force);
    (*c).potential += 0.5 * s.k * dot(st.spring, st.spring);
}
