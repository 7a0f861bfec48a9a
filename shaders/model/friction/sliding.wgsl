// model/friction/sliding.wgsl — Luding's sliding friction in f32: the twin of
// `model::friction::sliding`. Composed in where some hysteretic/LSD pair has friction;
// keeps the history field `spring` (`friction::sliding::HISTORY`), in the evaluator's frame.

// Tangential force on i: the staggered spring rotated into the tangent plane, one Coulomb
// step with the velocity v_t at the contact point and the law's Coulomb load.
fn luding_sliding_apply(row: PairRow, k: Kin, nf: Normal, h: ptr<function, History>, c: ptr<function, Contact>) {
    let s = row.luding_sliding;
    if (s.mu_s <= 0.0) {
        return;
    }
    let st = coulomb3(s, s.k, rotate_into_plane((*h).spring, k.n), k.v_t, nf.coulomb, k.dt);
    (*h).spring = st.stored;
    (*c).tangential = st.force;
    (*c).sliding = st.sliding;
    (*c).potential += 0.5 * s.k * dot(st.spring, st.spring);
}
