// model/friction/twisting.wgsl — Luding's twisting friction in f32: the twin of
// `model::friction::twisting` (and `JkrParams::twisting`). Composed in where some pair has
// twisting friction; keeps the history field `twist` (`friction::twisting::HISTORY`), a
// scalar along n, the same seen from both sides.

// The twisting block of the pair row is `TwistingRow` (`gpu::layout`): the spring, and the
// stiffness per contact radius of the JKR family's default k_o = 2/5·8G*·a.

// Twisting couple on i (−it on j): the pseudo-force of one Coulomb step with the twisting
// velocity v_o = a12·n·(w_i − w_j), applied at the lever a12 = 2R* along n.
fn luding_twisting_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let p = row.luding_twisting;
    if (p.spring.mu_s <= 0.0) {
        return;
    }
    let ko = p.spring.k + p.k_per_a * nf.a;
    if (ko <= 0.0) {
        (*h).twist = 0.0;
        return;
    }
    let lever = 2.0 * k.r_eff;
    let st = coulomb1(p.spring, ko, (*h).twist, lever * dot(k.n, k.w_rel), nf.coulomb, k.dt);
    (*h).twist = st.stored;
    (*c).rolling += lever * st.force * k.n;
    (*c).potential += 0.5 * ko * st.spring * st.spring;
}
