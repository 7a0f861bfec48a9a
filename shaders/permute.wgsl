// permute.wgsl — a rebuild's re-sort of the particle state, in place, a group of fields
// (up to `ROW_WORDS` words a particle) at a time through one scratch buffer
// (`src/gpu/permute.rs`).
//
// Dispatch i stores group i−1 from the scratch into its sorted place and loads group i of
// the particle that sorts to k into the scratch. Invocation k touches only scratch row k
// and sorted place k, so one dispatch does both without a race.

// Where a field lies in its buffer: `blocks` blocks (state fields moved together, else 1)
// of `words` u32 per particle, block b at word base + b·stride
// of the particle's window's block (`window` words a window, `gpu::window`).
struct Field {
    words: u32,
    blocks: u32,
    base: u32,
    stride: u32,
}

// One dispatch: the field it stores (words 0: none), the one it loads (words 0: none) and
// the scratch's words per particle, and the words of a window's block of the stored and
// the loaded field's buffer and of the scratch, and the scratch's first word in a block
// (a lent buffer's part).
// Layout: mirrored by `permute::MoveParams`.
struct Move {
    store: Field,
    load: Field,
    row: u32,
    store_window: u32,
    load_window: u32,
    scratch_window: u32,
    scratch_base: u32,
}

@group(0) @binding(1) var<uniform> mv: Move;
@group(0) @binding(2) var<storage, read> sorted_index: array<u32>;
@group(0) @binding(3) var<storage, read_write> scratch: array<u32>;
// (both read_write: the stored and the loaded field may lie in one buffer, bound twice)
@group(0) @binding(4) var<storage, read_write> stored: array<u32>;
@group(0) @binding(5) var<storage, read_write> loaded: array<u32>;
// The loaded field's other page where the state is in pages (`gpu::pages`): the particle
// that sorts to k may lie in a neighbouring window there.
@group(0) @binding(6) var<storage, read> loaded_x: array<u32>;

@compute @workgroup_size(WG_SIZE)
fn permute(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    // (the scratch is blocked by window like the state, `scratch_window` words a window:
    // `gpu::window`)
    let row = (win_of(k) - win.bound) * mv.scratch_window + mv.scratch_base + win_local(k) * mv.row;
    var s = row;
    for (var b = 0u; b < mv.store.blocks; b++) {
        let at = (win_of(k) - win.st_base) * mv.store_window + mv.store.base + b * mv.store.stride + win_local(k) * mv.store.words;
        for (var c = 0u; c < mv.store.words; c++) {
            stored[at + c] = scratch[s];
            s++;
        }
    }
    let o = sorted_index[k];
    let near = win_of(o) >= win.st_base && win_of(o) < win.st_end;
    let far = (win.st_base - win.st_other) * mv.load_window;
    s = row;
    for (var b = 0u; b < mv.load.blocks; b++) {
        let at = (win_of(o) - win.st_base) * mv.load_window + mv.load.base + b * mv.load.stride + win_local(o) * mv.load.words;
        for (var c = 0u; c < mv.load.words; c++) {
            if (near) {
                scratch[s] = loaded[at + c];
            } else {
                scratch[s] = loaded_x[at + far + c];
            }
            s++;
        }
    }
}
