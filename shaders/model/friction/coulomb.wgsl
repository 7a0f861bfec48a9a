// model/friction/coulomb.wgsl — the spring–dashpot with a static and a dynamic Coulomb limit that
// Luding's sliding, rolling and twisting laws share, in f32: the twin of
// `CoulombSpring::step_with` in `src/model/friction/coulomb.rs`. The stored spring is half
// a step ahead of the evaluation (staggered, second order; see the Rust module).

// One spring's block of the pair row is `CoulombSpring` (`gpu::layout::CoulombSpringRow`);
// mu_s = 0 is off.

// One step of a vector spring: the force on i, the spring it was computed with (the stored
// energy is ½·k·|spring|²) and the spring to store.
struct Coulomb3 {
    force: vec3<f32>,
    spring: vec3<f32>,
    stored: vec3<f32>,
    sliding: bool,
}

// Test force f0 = −k·ξ − γ·v with ξ = stored + ½·v·dt; stick while |f0| <= limit·load
// (mu_s, or mu_d after a slip where the law remembers it), else slip at mu_d·load along f0
// with the spring reset to the force's length.
fn coulomb3(s: CoulombSpring, k: f32, stored: vec3<f32>, v: vec3<f32>, load: f32, limit: f32, dt: f32) -> Coulomb3 {
    let half = v * (0.5 * dt);
    let spring = stored + half;
    let f0 = -k * spring - s.gamma * v;
    let magnitude = length(f0);
    if (magnitude <= limit * load) {
        return Coulomb3(f0, spring, spring + half, false);
    }
    let force = f0 * (s.mu_d * load / magnitude);
    let reset = -(force + s.gamma * v) / k;
    return Coulomb3(force, reset, reset + half, true);
}

// The scalar spring (twisting): as `coulomb3`.
struct Coulomb1 {
    force: f32,
    spring: f32,
    stored: f32,
}

fn coulomb1(s: CoulombSpring, k: f32, stored: f32, v: f32, load: f32, dt: f32) -> Coulomb1 {
    let half = v * (0.5 * dt);
    let spring = stored + half;
    let f0 = -k * spring - s.gamma * v;
    let magnitude = abs(f0);
    if (magnitude <= s.mu_s * load) {
        return Coulomb1(f0, spring, spring + half);
    }
    let force = f0 * (s.mu_d * load / magnitude);
    let reset = -(force + s.gamma * v) / k;
    return Coulomb1(force, reset, reset + half);
}
