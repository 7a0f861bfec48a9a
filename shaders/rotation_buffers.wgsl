// rotation_buffers.wgsl — the predicted angular velocity from its buffer (with
// state_buffers.wgsl, where particles rotate).
fn rot_wpred(k: u32) -> vec3<f32> {
    return load_wpred(k).xyz;
}
