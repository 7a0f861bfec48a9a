// rotation_off.wgsl — the step without angular velocity (no contact model of the scene
// exerts tangential forces or torques): the hooks of rotation.wgsl as no-ops, with no
// buffers declared, so none is bound or allocated.

const ROTATION: bool = false;

struct RotState {
    unused: f32,
}

fn rot_load(k: u32) -> RotState {
    return RotState(0.0);
}

fn rot_collect(k: u32, torque: vec3<f32>) -> RotState {
    return RotState(0.0);
}

fn rot_finite(r: RotState) -> bool {
    return true;
}

fn rot_drift(k: u32, r: RotState, pending_kick: bool) {}



fn rot_wpred(k: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn rot_store_partial(k: u32, torque: vec3<f32>) {}


fn rot_pair_store(slot: u32, torque: vec3<f32>) {}

fn rot_pair_load(slot: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn rot_kick(k: u32) {}
