// walls.wgsl — moving and servo-controlled walls, and particles that appear (pouring).

// Moving walls, after kick_drift (dispatched only when some wall moves): each moving wall's
// point advances by its velocity over the step, carried into its cell like a particle's.
@compute @workgroup_size(1)
fn wall_move() {
    let h = grid.cell_width;
    for (var w = 0u; w < wall_count(); w++) {
        if (walls[w].motion.x == 0.0) {
            continue;
        }
        let o0 = walls[w].offset;
        // (`opaque`: two_sum needs the rounded product, not one fused into its add)
        let dx = opaque(step.dt * walls[w].velocity.xyz);
        var sum = vec3<f32>(0.0);
        var lo = vec3<f32>(0.0);
        for (var a = 0u; a < 3u; a++) {
            let s = two_sum(o0[a], dx[a]);
            sum[a] = s.hi;
            lo[a] = s.lo;
        }
        let carried = carry_cells(sum, h);
        walls[w].cell = vec4<i32>(walls[w].cell.xyz + carried.carry, 0);
        // the plane's residual n·(stored − true) takes the move's rounding
        let residual = o0.w - dot(walls[w].normal.xyz, lo + carried.lo);
        walls[w].offset = vec4<f32>(carried.offset, residual);
    }
}

// Servo control, after force (dispatched only when some wall is servo-controlled): each
// servo wall's normal force summed over the particles in a fixed order, so the result is
// reproducible and the same in any windows: lane l of `servo_lanes` adds the pushes of the
// particles l, l + WG_SIZE, l + 2·WG_SIZE, ... in order (one invocation a lane and window,
// the windows in order), then wall_servo_apply adds the lanes as a tree and sets the
// wall's velocity for the next step: clamp(gain·(force − pushed), ±max_speed) along n.
var<workgroup> wg_push: array<f32, WG_SIZE>;

// Per wall and lane, the pushes summed so far this step (zeroed by wall_servo_apply).
@group(0) @binding(76) var<storage, read_write> servo_lanes: array<f32>;

// Particle k's push on wall w this step (0 without a wall entry, not near at the rebuild,
// or before k has appeared: the force pass writes the pushes of the others every step).
fn wall_push_of(k: u32, w: u32) -> f32 {
    if (!has_appeared(load_cell(k))) {
        return 0.0;
    }
    let ids = load_ids(k);
    for (var e = ids.y + ids.z; e < ids.y + ids.z + ids.w; e++) {
        if (load_nbr(e) == (WALL_ENTRY | w)) {
            return load_wall_push(e);
        }
    }
    return 0.0;
}

@compute @workgroup_size(WG_SIZE)
fn wall_servo(@builtin(local_invocation_index) lid: u32) {
    let first = win.first + lid;
    if (first >= particle_end()) {
        return;
    }
    let lane = first % WG_SIZE;
    for (var w = 0u; w < wall_count(); w++) {
        if (walls[w].motion.x != WALL_SERVO) {
            continue;
        }
        var sum = servo_lanes[w * WG_SIZE + lane];
        for (var k = first; k < particle_end(); k += WG_SIZE) {
            sum += wall_push_of(k, w);
        }
        servo_lanes[w * WG_SIZE + lane] = sum;
    }
}

// After every window's wall_servo: each servo wall's push, the lanes added as a tree, and
// its velocity; the lanes start afresh.
@compute @workgroup_size(WG_SIZE)
fn wall_servo_apply(@builtin(local_invocation_index) lid: u32) {
    for (var w = 0u; w < wall_count(); w++) {
        // uniform control flow: every invocation reads the same wall
        let m = walls[w].motion;
        if (m.x != WALL_SERVO) {
            continue;
        }
        wg_push[lid] = servo_lanes[w * WG_SIZE + lid];
        servo_lanes[w * WG_SIZE + lid] = 0.0;
        workgroupBarrier();
        for (var half = WG_SIZE / 2u; half > 0u; half /= 2u) {
            if (lid < half) {
                wg_push[lid] += wg_push[lid + half];
            }
            workgroupBarrier();
        }
        if (lid == 0u) {
            let speed = clamp(m.z * (m.y - wg_push[0]), -m.w, m.w);
            walls[w].velocity = vec4<f32>(speed * walls[w].normal.xyz, 0.0);
        }
        workgroupBarrier();
    }
}

// Where particles appeared (the host wrote `appeared`): each one's flag into its cell.w.
@compute @workgroup_size(WG_SIZE)
fn appear(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    if (k >= particle_end()) {
        return;
    }
    let c = load_cell(k);
    let flag = select(NOT_APPEARED, 0, appeared[load_ids(k).x] != 0u);
    store_cell(k, vec4<i32>(c.xyz, (c.w & ~NOT_APPEARED) | flag));
}
