// grid.wgsl — deterministic counting sort of particles by cell key (`src/gpu/grid.rs`).
// Result: sorted_index[k] = original index of the k-th particle ordered by (key, index),
// exactly a stable counting sort; cell_start/cell_count give each cell's range.
//
// Passes, recorded into one compute pass (`GridSort::encode`, `encode_indirect`):
//   clear_counts       per cell      cell_count = 0, large-cell queue emptied
//   cell_keys          per particle  keys[i] = clamped linear cell key of cells[i]
//   count              per particle  atomicAdd(cell_count[keys[i]], 1)
//   scan_blocks/_add   per element   cell_start = multi-level exclusive scan of cell_count
//   scatter            per particle  a slot in its cell by atomicSub on cell_count
//                                    (racy order within the cell)
//   sort_within_cells  per cell      restores cell_count, sorts the slice by index
//                                    (insertion sort up to SMALL_CELL; larger cells queued)
//   sort_large_cells   workgroup per queued cell: bitonic sort of the slice

// Cells queued for the workgroup sort hold more than this many particles.
const SMALL_CELL: u32 = 32u;
// Elements scanned per workgroup by scan_blocks (WG_SIZE invocations x SCAN_ITEMS).
const SCAN_ITEMS: u32 = 4u;
const SCAN_BLOCK: u32 = WG_SIZE * SCAN_ITEMS;

// Integer cell of each particle (xyz; w = material and `NOT_APPEARED`, unused here): the state's
// first field, blocked by window (`state_blocked`).
@group(0) @binding(1) var<storage, read> cells: array<vec4<i32>>;
// Clamped linear cell key of each particle, in original order.
@group(0) @binding(2) var<storage, read_write> keys: array<u32>;
// Particles per cell: an atomic view for count/scatter, a plain one for the rest.
@group(0) @binding(3) var<storage, read_write> cell_count_atomic: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> cell_count: array<u32>;
// First sorted slot of each cell (exclusive scan of cell_count).
@group(0) @binding(5) var<storage, read> cell_start: array<u32>;
// sorted_index[k] = original index of the k-th particle in sorted order.
@group(0) @binding(6) var<storage, read_write> sorted_index: array<u32>;

// Cells with more than SMALL_CELL particles, queued by sort_within_cells.
struct LargeCellsAtomic {
    count: atomic<u32>,
    cells: array<u32>,
}
struct LargeCells {
    count: u32,
    cells: array<u32>,
}
@group(0) @binding(7) var<storage, read_write> large_cells_atomic: LargeCellsAtomic;
@group(0) @binding(8) var<storage, read> large_cells: LargeCells;

// One level of the exclusive scan (`layout::ScanParams`).
@group(0) @binding(10) var<uniform> scan_params: ScanParams;
// (read_write: it may be scan_out's buffer, bound twice)
@group(0) @binding(11) var<storage, read_write> scan_in: array<u32>;
@group(0) @binding(12) var<storage, read_write> scan_out: array<u32>;
@group(0) @binding(13) var<storage, read_write> scan_sums: array<u32>;
@group(0) @binding(14) var<storage, read> scan_carry: array<u32>;

var<workgroup> scan_tmp: array<u32, WG_SIZE>;
var<workgroup> wg_count: u32;
var<workgroup> wg_start: u32;
var<workgroup> wg_len: u32;

@compute @workgroup_size(WG_SIZE)
fn clear_counts(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let c = global_index(wid, nwg, lid);
    if (c == 0u) {
        atomicStore(&large_cells_atomic.count, 0u);
    }
    if (c < grid.n_cells) {
        cell_count[c] = 0u;
    }
}

@compute @workgroup_size(WG_SIZE)
fn cell_keys(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let i = particle_index(wid, nwg, lid);
    if (i < particle_end()) {
        keys[i] = cell_key(cells[state_blocked(grid.window.w, 0u, i)].xyz, grid.dims);
    }
}

@compute @workgroup_size(WG_SIZE)
fn count(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let i = global_index(wid, nwg, lid);
    if (i < grid.n_particles) {
        atomicAdd(&cell_count_atomic[keys[i]], 1u);
    }
}

// Exclusive scan of one SCAN_BLOCK-element block of scan_in into scan_out; the block's
// total goes to scan_sums[block]. Each invocation scans SCAN_ITEMS consecutive elements
// serially, then the WG_SIZE per-invocation totals are scanned in workgroup memory with
// Blelloch's work-efficient up-sweep / down-sweep.
@compute @workgroup_size(WG_SIZE)
fn scan_blocks(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = linear_workgroup(wid, nwg);
    // Uniform per workgroup: the spare workgroups of a split dispatch leave together.
    if (block >= scan_params.n_blocks) {
        return;
    }
    let n = scan_params.n;
    let base = block * SCAN_BLOCK + lid * SCAN_ITEMS;
    var prefix: array<u32, SCAN_ITEMS>;
    var total = 0u;
    for (var k = 0u; k < SCAN_ITEMS; k++) {
        prefix[k] = total;
        if (base + k < n) {
            total += scan_in[scan_params.in_offset + base + k];
        }
    }
    scan_tmp[lid] = total;

    // Up-sweep: scan_tmp becomes a reduction tree, the block total ends in the last slot.
    var offset = 1u;
    for (var d = WG_SIZE >> 1u; d > 0u; d >>= 1u) {
        workgroupBarrier();
        if (lid < d) {
            let ai = offset * (2u * lid + 1u) - 1u;
            let bi = offset * (2u * lid + 2u) - 1u;
            scan_tmp[bi] += scan_tmp[ai];
        }
        offset <<= 1u;
    }
    workgroupBarrier();
    if (lid == 0u) {
        scan_sums[block] = scan_tmp[WG_SIZE - 1u];
        scan_tmp[WG_SIZE - 1u] = 0u;
    }
    // Down-sweep: turns the tree into the exclusive scan of the invocation totals.
    for (var d = 1u; d < WG_SIZE; d <<= 1u) {
        offset >>= 1u;
        workgroupBarrier();
        if (lid < d) {
            let ai = offset * (2u * lid + 1u) - 1u;
            let bi = offset * (2u * lid + 2u) - 1u;
            let t = scan_tmp[ai];
            scan_tmp[ai] = scan_tmp[bi];
            scan_tmp[bi] += t;
        }
    }
    workgroupBarrier();
    let carry = scan_tmp[lid];
    for (var k = 0u; k < SCAN_ITEMS; k++) {
        if (base + k < n) {
            scan_out[scan_params.out_offset + base + k] = carry + prefix[k];
        }
    }
}

// Adds the scanned block sums of the level above back into this level.
@compute @workgroup_size(WG_SIZE)
fn scan_add(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let i = global_index(wid, nwg, lid);
    if (i < scan_params.n) {
        scan_out[scan_params.out_offset + i] += scan_carry[i / SCAN_BLOCK];
    }
}

@compute @workgroup_size(WG_SIZE)
fn scatter(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let i = global_index(wid, nwg, lid);
    if (i < grid.n_particles) {
        let key = keys[i];
        // Counts down to zero; sort_within_cells restores cell_count afterwards.
        let left = atomicSub(&cell_count_atomic[key], 1u);
        sorted_index[cell_start[key] + left - 1u] = i;
    }
}

@compute @workgroup_size(WG_SIZE)
fn sort_within_cells(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let c = global_index(wid, nwg, lid);
    if (c >= grid.n_cells) {
        return;
    }
    let start = cell_start[c];
    var end = grid.n_particles;
    if (c + 1u < grid.n_cells) {
        end = cell_start[c + 1u];
    }
    let len = end - start;
    cell_count[c] = len;
    if (len > SMALL_CELL) {
        let slot = atomicAdd(&large_cells_atomic.count, 1u);
        large_cells_atomic.cells[slot] = c;
        return;
    }
    // Insertion sort by original index; cells hold few particles.
    for (var a = start + 1u; a < end; a++) {
        let v = sorted_index[a];
        var b = a;
        while (b > start && sorted_index[b - 1u] > v) {
            sorted_index[b] = sorted_index[b - 1u];
            b--;
        }
        sorted_index[b] = v;
    }
}

// Compare-exchange of two slots of sorted_index: the smaller index goes first.
fn order_pair(i: u32, j: u32) {
    let a = sorted_index[i];
    let b = sorted_index[j];
    if (a > b) {
        sorted_index[i] = b;
        sorted_index[j] = a;
    }
}

// One workgroup per queued cell (grid-stride over the queue): bitonic sort of the cell's
// slice in place, padded to a power of two p. Every compare-exchange sends the smaller
// value to the lower slot (the "flip" formulation), so the virtual padding (+infinity
// past the slice's end) never moves and pairs reaching past the end are simply skipped.
@compute @workgroup_size(WG_SIZE)
fn sort_large_cells(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    if (lid == 0u) {
        wg_count = large_cells.count;
    }
    let queued = workgroupUniformLoad(&wg_count);
    for (var q = linear_workgroup(wid, nwg); q < queued; q += nwg.x * nwg.y * nwg.z) {
        if (lid == 0u) {
            let c = large_cells.cells[q];
            wg_start = cell_start[c];
            wg_len = cell_count[c];
        }
        let start = workgroupUniformLoad(&wg_start);
        let len = workgroupUniformLoad(&wg_len);
        var p = 1u;
        while (p < len) {
            p <<= 1u;
        }
        let pairs = p >> 1u;
        for (var k = 2u; k <= p; k <<= 1u) {
            let half = k >> 1u;
            for (var t = lid; t < pairs; t += WG_SIZE) {
                let base = (t / half) * k;
                let w = t % half;
                let j = base + k - 1u - w;
                if (j < len) {
                    order_pair(start + base + w, start + j);
                }
            }
            storageBarrier();
            for (var d = half >> 1u; d > 0u; d >>= 1u) {
                for (var t = lid; t < pairs; t += WG_SIZE) {
                    let i = (t / d) * (2u * d) + t % d;
                    if (i + d < len) {
                        order_pair(start + i, start + i + d);
                    }
                }
                storageBarrier();
            }
        }
    }
}
