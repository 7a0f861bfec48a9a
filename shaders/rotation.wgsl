// rotation.wgsl — angular velocity for scenes whose contacts exert tangential forces or
// torques (JKR with friction or rolling resistance). Composed into the step instead of
// rotation_off.wgsl, so a scene without them declares (and allocates) none of this.
//
// Per particle, like vel/acc: omega.xyz =
// angular velocity, omega.w = the moment of inertia 2/5·m·r²; alpha.xyz = angular acceleration torque/I. Integrated
// with the same half kicks as the velocity (CPU: `CpuEngine::step`); wpred is the
// predicted omega + dt/2·alpha the forces see (as vpred for the velocity).

const ROTATION: bool = true;

// (omega, alpha, wpred: fields of the state, `gpu::state`)
// (Per entry, this step: the torque the evaluated pair exerts on the partner, the entries'
// `pair_torque`.)

// One particle's angular state as its collect and drift read it, once per pass (on
// lavapipe each storage access in the code is a loop over the SIMD lanes): omega (xyz)
// with the moment of inertia (w), and alpha.
struct RotState {
    omega: vec4<f32>,
    alpha: vec3<f32>,
}

fn rot_load(k: u32) -> RotState {
    return RotState(load_omega(k), load_alpha(k).xyz);
}

// collect: alpha = (the torque of k's own pairs, which force left in alpha, + the partners'
// share)/I, stored.
fn rot_collect(k: u32, torque: vec3<f32>) -> RotState {
    let omega = load_omega(k);
    let alpha = opaque((load_alpha(k).xyz + torque) / omega.w);
    store_alpha(k, vec4<f32>(alpha, 0.0));
    return RotState(omega, alpha);
}

fn rot_finite(r: RotState) -> bool {
    return all_finite(r.alpha);
}

// kick_drift: omega += dt/2·alpha (first the previous step's closing kick when it is
// pending: two roundings, as two kernels give), and the prediction the forces see.
fn rot_drift(k: u32, r: RotState, pending_kick: bool) {
    // (the product through `opaque`, as the velocity's in drift_particle)
    let half = opaque(0.5 * step.dt * r.alpha);
    var w = r.omega.xyz;
    if (pending_kick) {
        w = opaque(w + half);
    }
    w = opaque(w + half);
    store_omega(k, vec4<f32>(w, r.omega.w));
    store_wpred(k, vec4<f32>(w + half, 0.0));
}

// (rot_wpred: the predicted angular velocity, from rotation_mirrors.wgsl or
// rotation_buffers.wgsl)

// force: the torque of k's own pairs and walls (alpha holds it until collect).
fn rot_store_partial(k: u32, torque: vec3<f32>) {
    store_alpha(k, vec4<f32>(torque, 0.0));
}


// force: the torque an evaluated pair exerts on the partner (slot of the pair); collect
// reads it back.
fn rot_pair_store(slot: u32, torque: vec3<f32>) {
    store_pair_torque(slot, torque);
}

fn rot_pair_load(slot: u32) -> vec3<f32> {
    return load_pair_torque_far(slot);
}

// kick: omega += dt/2·alpha.
fn rot_kick(k: u32) {
    store_omega(k, vec4<f32>(load_omega(k).xyz + opaque(0.5 * step.dt * load_alpha(k).xyz), load_omega(k).w));
}
