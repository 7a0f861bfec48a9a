// common.wgsl — shared by every shader stage of the GPU engine.
//
// `src/gpu/shaders.rs` prepends this file to each stage file (grid.wgsl, permute.wgsl,
// and the step's files), so everything here is visible to every stage. Keep it
// to declarations that every stage can share: constants and pure helpers. The structs
// and constants the host shares follow it, generated from their Rust declarations
// (`gpu::layout::declarations`).
//
// Core WGSL only: no f64, no float atomics, no subgroups, so the kernels run on every
// wgpu backend (Vulkan, Metal, DX12, GL) and every adapter, the software ones included.

// Invocations per workgroup for every 1-D kernel. The host computes dispatch sizes from
// the workgroup size it reads back from naga, so changing this needs no Rust edit.
const WG_SIZE: u32 = 256u;

// The grid of a run (`layout::GridParams`).
@group(0) @binding(0) var<uniform> grid: GridParams;

// The window a dispatch works on (`window::WindowParams`).
@group(0) @binding(19) var<uniform> win: WindowParams;

// The particle of this invocation of a per-particle dispatch over the window, and the end
// of the window's particles.
fn particle_index(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> u32 {
    return win.first + global_index(wid, nwg, lid);
}

fn particle_end() -> u32 {
    return min(win.first + grid.window.y, grid.n_particles);
}

// Whether particle k's data is in this dispatch's bindings.
fn in_bindings(k: u32) -> bool {
    return k >> grid.window.x >= win.bound && (k >> grid.window.x) - win.bound < 3u;
}

// Particle k's window and its index within (one window: 0 and k).
fn win_of(k: u32) -> u32 {
    return k >> grid.window.x;
}

fn win_local(k: u32) -> u32 {
    return k & ((1u << grid.window.x) - 1u);
}

// Element of particle k in an array blocked by window with `fields` per-particle regions
// (region f of window w at (w·fields + f)·len), in this dispatch's binding of it.
fn blocked(fields: u32, f: u32, k: u32) -> u32 {
    return ((win_of(k) - win.bound) * fields + f) * grid.window.y + win_local(k);
}

// Element of particle k in a binding of the particle state (`state`, `motion`): like
// `blocked`, from the first window of the state's binding (its page where it is in pages).
fn state_blocked(fields: u32, f: u32, k: u32) -> u32 {
    return ((win_of(k) - win.st_base) * fields + f) * grid.window.y + win_local(k);
}

// A record index: local record i of window w, and back.
fn record_index(w: u32, i: u32) -> u32 {
    return (w << grid.window.z) | i;
}

fn rec_window(r: u32) -> u32 {
    return r >> grid.window.z;
}

fn rec_local(r: u32) -> u32 {
    return r & ((1u << grid.window.z) - 1u);
}

// Linear cell key of an integer cell coordinate: each component clamped to
// [0, dims - 1] (particles outside the grid land in its boundary cells), x fastest.
fn cell_key(cell: vec3<i32>, dims: vec3<u32>) -> u32 {
    let hi = vec3<i32>(dims) - vec3<i32>(1);
    let c = vec3<u32>(clamp(cell, vec3<i32>(0), hi));
    return c.x + dims.x * (c.y + dims.y * c.z);
}

// Index of a workgroup in a (possibly 2-D or 3-D) dispatch, x fastest. Dispatches larger
// than max_compute_workgroups_per_dimension are split over y by the host.
fn linear_workgroup(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + nwg.x * (wid.y + nwg.y * wid.z);
}

// Global invocation index of a 1-D kernel (workgroup size WG_SIZE) under a split dispatch.
fn global_index(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> u32 {
    return linear_workgroup(wid, nwg) * WG_SIZE + lid;
}

// Whether every component is finite: by the exponent bits, which a compiler that assumes
// no NaN or infinity (as WGSL lets it) cannot fold away, where `x != x` it may.
fn all_finite(v: vec3<f32>) -> bool {
    let exponent = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(exponent != vec3<u32>(0x7f800000u));
}
