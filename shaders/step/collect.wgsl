// collect.wgsl — the step's last passes: each particle adds the forces its partners left
// in their slots (no atomics), its acceleration, and the closing half kick.

// After force, per particle: adds the forces (and torques) of the pairs k's partners
// before it evaluated, in lower-list order (deterministic, no atomics), and stores the
// acceleration (and angular acceleration).
@compute @workgroup_size(WG_SIZE)
fn collect(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k < particle_end()) {
        let c = collect_particle(k, load_vel(k).w, true);
        // the partners' force jumps, at the end of the step (before the closing kick:
        // the sum is the same)
        jump_kick(k, c.dv);
        // the batch ends here (or the initial forces do): its overlap maximum, with this
        // step's, into the monitor (an atomic only where it grows), and a fresh start
        let disp = load_disp(k);
        let ratio = max(disp.w, c.peak);
        let bits = bitcast<u32>(ratio);
        if (bits > atomicLoad(&control[CONTROL_PEAK_OVERLAP])) {
            atomicMax(&control[CONTROL_PEAK_OVERLAP], bits);
        }
        if (ratio > MONITOR_MAX_OVERLAP_RATIO) {
            atomicMax(&control[CONTROL_OVERLAP_PARTICLE], load_ids(k).x + 1u);
        }
        // the displacement since the last rebuild, for the host's rebuild forecast
        let moved = bitcast<u32>(length(disp.xyz));
        if (moved > atomicLoad(&control[CONTROL_DISPLACEMENT])) {
            atomicMax(&control[CONTROL_DISPLACEMENT], moved);
        }
        store_disp(k, vec4<f32>(disp.xyz, 0.0));
    }
}

// What collect leaves for the drift of the same pass.
struct Collected {
    acc: vec3<f32>,
    rot: RotState,
    // The largest overlap/a12 of the force pass just collected.
    peak: f32,
    // The velocity change of the force jumps the partners placed (the end of the step).
    dv: vec3<f32>,
}

// Returns the acceleration (and the angular state, stored); `store`: the acceleration too,
// at the end of a batch (kick, the host and checkpoints read it there). Within a batch
// the drift takes it from here and the next force pass overwrites it: no store.
fn collect_particle(k: u32, mass: f32, store: bool) -> Collected {
    let partial = load_acc(k);
    var f = partial.xyz;
    var torque = vec3<f32>(0.0);
    var impulse = vec3<f32>(0.0);
    let low = lower_first(k);
    for (var s = low; s < low + lower_len(k); s++) {
        let slot = load_lower(s);
        f -= load_pair_force_far(slot);
        torque += rot_pair_load(slot);
        // a force jump's impulse (0 without the force jumps: no field, no load)
        let jump = load_jump_far(slot);
        if (jump != 0.0) {
            impulse -= opaque(jump * load_jump_normal_far(slot));
        }
    }
    // (`opaque`: as in drift_particle, rounded the same in every kernel that collects)
    let acc = opaque(opaque(f / mass) + step.gravity);
    let rot = rot_collect(k, torque);
    if (!all_finite(acc) || !rot_finite(rot)) {
        atomicMax(&control[CONTROL_NON_FINITE], load_ids(k).x + 1u);
    }
    if (store) {
        store_acc(k, vec4<f32>(acc, 0.0));
    }
    return Collected(acc, rot, partial.w, opaque(impulse / mass));
}

@compute @workgroup_size(WG_SIZE)
fn kick(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    if (!has_appeared(load_cell(k))) {
        return;
    }
    let kv = kahan_add(load_vel(k).xyz, load_kahan_v(k).xyz, opaque(0.5 * step.dt * load_acc(k).xyz));
    store_vel(k, vec4<f32>(kv.x, load_vel(k).w));
    store_kahan_v(k, vec4<f32>(kv.c, 0.0));
    rot_kick(k);
}
