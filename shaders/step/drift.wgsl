// drift.wgsl — the step's first pass: the half kick and drift of every particle, and the
// Verlet skin's watch (each particle's displacement since the last rebuild).

@compute @workgroup_size(WG_SIZE)
fn kick_drift(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    drift(particle_index(wid, nwg, lid));
}

// The previous step's collect and closing kick and this step's kick_drift in one pass
// (every step of a batch but the first; the batch ends with collect and kick): each needs
// only its own particle's results of the one before (collect reads the pair forces the
// whole force pass left), so this is bitwise the same as the three kernels, two dispatches
// and two sweeps over the state fewer.
@compute @workgroup_size(WG_SIZE)
fn collect_kick_drift(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = particle_index(wid, nwg, lid);
    if (i < particle_end()) {
        let vel = load_vel(i);
        let c = collect_particle(i, vel.w, false);
        if (has_appeared(load_cell(i))) {
            drift_particle(i, vel, c.acc, c.rot, true, c.peak, c.dv);
        }
    }
}

fn drift(i: u32) {
    if (i < particle_end() && has_appeared(load_cell(i))) {
        drift_particle(i, load_vel(i), load_acc(i).xyz, rot_load(i), false, 0.0, vec3<f32>(0.0));
    }
}

// Each buffer is read once and written once (the caller passes what it read already): on
// lavapipe every access in the code is a loop over the SIMD lanes.
// `peak`: the largest overlap/a12 of the last force pass (0 when it was folded already).
// `pending_kick`: called from collect_kick_drift, within a batch, where the mirrors still
// hold the cell and offset the last force pass saw (nothing wrote them since): read from
// there (a gather on lavapipe, not a loop over the lanes). At a batch's first step the host
// may have written the state since (a restore): read the buffers.
// `jump_dv`: with the pending kick, the partners' force jumps at the end of that step.
fn drift_particle(i: u32, vel: vec4<f32>, acc: vec3<f32>, rot: RotState, pending_kick: bool, peak: f32, jump_dv: vec3<f32>) {
    let h = grid.cell_width;
    // (products through `opaque`: fused into the adds or not, as this kernel and `kick`
    // may differ, they would round differently; batches of any length give the same bits)
    let half_dv = opaque(0.5 * step.dt * acc);
    var v0 = vel.xyz;
    var c0 = load_kahan_v(i).xyz;
    if (pending_kick) {
        // the partners' force jumps first, as collect adds them at a batch's end
        let kj = kahan_add_nonzero(v0, c0, jump_dv);
        let kk = kahan_add(kj.x, kj.c, half_dv);
        v0 = kk.x;
        c0 = kk.c;
    }
    let kv = kahan_add(v0, c0, half_dv);
    let v = kv.x;
    store_vel(i, vec4<f32>(v, vel.w));
    store_kahan_v(i, vec4<f32>(kv.c, 0.0));
    // vel.w holds the mass
    store_vpred(i, vec4<f32>(v + half_dv, vel.w));
    rot_drift(i, rot, pending_kick);
    let disp0 = load_disp(i);
    let dx = opaque(step.dt * v);
    let disp = disp0.xyz + dx;
    store_disp(i, vec4<f32>(disp, max(disp0.w, peak)));
    // (NaN forces a rebuild too; the squares and sums through `opaque`, as the products
    // above: a tie at the threshold must go the same way in both drift kernels)
    let sq = opaque(disp * disp);
    let half_skin = 0.5 * skin_width();
    if (!(opaque1(sq.x + sq.y) + sq.z <= half_skin * half_skin)) {
        atomicStore(&control[SKIN_MOVED], 1u);
    }
    // the move with the compensated velocity, carried into whole cells (below)
    var off: vec4<f32>;
    var cell0: vec4<i32>;
    if (pending_kick) {
        off = own_off(i);
        cell0 = own_cell(i);
    } else {
        off = load_off(i);
        cell0 = load_cell(i);
    }
    // the true step dt·(v − c_v): the velocity's compensation joins the offset's (v − c_v
    // itself rounds back to v); w: the radius's rounding residual, kept
    let c_off = load_kahan_o(i);
    let ko = kahan_add(off.xyz, c_off.xyz + opaque(step.dt * kv.c), dx);
    // whole cells carried exactly, their rounding booked into the compensation
    let carried = carry_cells(ko.x, h);
    store_kahan_o(i, vec4<f32>(ko.c - carried.lo, c_off.w));
    let o = carried.offset;
    let carry = carried.carry;
    let raw = cell0.xyz + carry;
    let cell = wrap_cell(raw);
    // a wrap moves the stored position by dims·h, the true one by the period L
    let wraps = image_shift(cell, raw);
    if (any(wraps != vec3<f32>(0.0))) {
        let c = load_kahan_o(i);
        store_kahan_o(i, vec4<f32>(c.xyz - wraps * step.period_lo, c.w));
    }
    // stored only where it changes (rarely): a masked store skips the work of idle lanes
    if (any(carry != vec3<i32>(0))) {
        store_cell(i, vec4<i32>(cell, cell0.w));
    }
    store_off(i, vec4<f32>(o, off.w));
    let at = vec3<f32>(cell) + o / h;
    let outside = (at < vec3<f32>(0.0)) | (at > step.extent_cells);
    if (any(outside & !periodic_axes())) {
        atomicMax(&control[CONTROL_ESCAPED_PARTICLE], load_ids(i).x + 1u);
    }
}
