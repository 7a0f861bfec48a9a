// state_buffers.wgsl — how the step reads the particle state on a GPU: from the state's
// own buffers (the software adapter's twin, with texture copies, is state_mirrors.wgsl).

// Particle k's cell, offset (w: radius) and predicted velocity (w: mass).
fn own_cell(k: u32) -> vec4<i32> {
    return load_cell(k);
}

fn own_off(k: u32) -> vec4<f32> {
    return load_off(k);
}

fn own_vpred(k: u32) -> vec4<f32> {
    return load_vpred(k);
}

// The k-th particle of a rebuild's new order, before the state is re-sorted.
fn sorted_cell(k: u32) -> vec4<i32> {
    return load_cell(sorted_index[k]);
}

fn sorted_off(k: u32) -> vec4<f32> {
    return load_off(sorted_index[k]);
}

// gather: nothing to copy.
fn mirror_sorted(k: u32, o: u32) {}
