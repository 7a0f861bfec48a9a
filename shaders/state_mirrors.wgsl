// state_mirrors.wgsl — how the step reads the particle state on a software adapter: from
// read-only texture copies of the state's cell, off and vpred, made right before each force pass
// (`gpu::mirror`). On lavapipe a read-only storage-texture load is one gather where a
// storage-buffer load is a loop over the SIMD lanes (measured: docs/design_log.md). The
// twin for GPUs is state_buffers.wgsl.
const MIRROR_WIDTH: u32 = 4096u;
@group(0) @binding(80) var m_cell: texture_storage_2d<rgba32sint, read>;
@group(0) @binding(81) var m_off: texture_storage_2d<rgba32float, read>;
@group(0) @binding(82) var m_vpred: texture_storage_2d<rgba32float, read>;
// The cell and offset mirrors as a rebuild's `gather` writes them (the same textures): the
// positions in the new order, which the neighbour search reads; the copy before the force
// pass writes A's again.
@group(0) @binding(88) var m_cell_out: texture_storage_2d<rgba32sint, write>;
@group(0) @binding(89) var m_off_out: texture_storage_2d<rgba32float, write>;

fn mirror_texel(k: u32) -> vec2<u32> {
    return vec2<u32>(k % MIRROR_WIDTH, k / MIRROR_WIDTH);
}

// Particle k's cell, offset (w: radius) and predicted velocity (w: mass) as the last force
// pass saw them.
fn own_cell(k: u32) -> vec4<i32> {
    return textureLoad(m_cell, mirror_texel(k));
}

fn own_off(k: u32) -> vec4<f32> {
    return textureLoad(m_off, mirror_texel(k));
}

fn own_vpred(k: u32) -> vec4<f32> {
    return textureLoad(m_vpred, mirror_texel(k));
}

// The k-th particle of a rebuild's new order, before the state is re-sorted.
fn sorted_cell(k: u32) -> vec4<i32> {
    return textureLoad(m_cell, mirror_texel(k));
}

fn sorted_off(k: u32) -> vec4<f32> {
    return textureLoad(m_off, mirror_texel(k));
}

// gather: the new order's positions into the mirrors.
fn mirror_sorted(k: u32, o: u32) {
    textureStore(m_cell_out, mirror_texel(k), load_cell(o));
    textureStore(m_off_out, mirror_texel(k), load_off(o));
}
