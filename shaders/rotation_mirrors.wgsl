// rotation_mirrors.wgsl — the predicted angular velocity from its texture copy (with
// state_mirrors.wgsl, where particles rotate).
@group(0) @binding(83) var m_wpred: texture_storage_2d<rgba32float, read>;

fn rot_wpred(k: u32) -> vec3<f32> {
    return textureLoad(m_wpred, mirror_texel(k)).xyz;
}
