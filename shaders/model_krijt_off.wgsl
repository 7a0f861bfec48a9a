// model_krijt_off.wgsl — the JKR steps without the Krijt contact-radius dynamics (no pair
// of the scene uses the `krijt` or `stress` dissipation, and the history stores no contact
// radius): the hooks of model_krijt.wgsl as no-ops. model_jkr.wgsl calls them only when
// KRIJT is true, so they are never evaluated.

const KRIJT: bool = false;

fn krijt_normal(p: JkrPair, k: Kin, a0: f32, d0: f32, fc: f32, x_eq: f32, a_old: f32) -> vec3<f32> {
    return vec3<f32>(x_eq, 0.0, 0.0);
}

fn krijt_viscous(p: JkrPair, a: f32, a0: f32, r: f32, delta_dot: f32) -> f32 {
    return 0.0;
}
