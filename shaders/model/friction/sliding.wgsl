// model/friction/sliding.wgsl — Luding's sliding friction in f32: the twin of
// `model::friction::sliding`. Composed in where some hysteretic/LSD pair has friction;
// keeps the history fields `spring`, in the evaluator's frame, and `slipping`
// (`friction::sliding::HISTORY`).

// Tangential force on i: the staggered spring rotated into the tangent plane, one Coulomb
// step with the velocity v_t at the contact point and the law's Coulomb load, its limit
// mu_d where the contact slipped in its last step.
fn luding_sliding_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let s = row.luding_sliding;
    if (s.mu_s <= 0.0) {
        return;
    }
    let limit = select(s.mu_s, s.mu_d, (*h).slipping);
    let st = coulomb3(s, s.k, rotate_into_plane((*h).spring, k.n), k.v_t, nf.coulomb, limit, k.dt);
    (*h).spring = st.stored;
    (*h).slipping = st.sliding;
    (*c).tangential = st.force;
    (*c).sliding = st.sliding;
    (*c).potential += 0.5 * s.k * dot(st.spring, st.spring);
}
