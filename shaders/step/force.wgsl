// force.wgsl — the contact forces: each particle evaluates the pairs of its list (the
// composed law through `pair_contact`) and its wall entries, leaving each pair's force in
// its slot, with the energy ledger's booking and the force jumps' impulses.

// Rotates v into the plane normal to n keeping its length (`model::rotate_into_plane`): a
// rigid rotation of the pair must not change a stored spring's energy. Zero when v is
// (within f32 rounding) along n.
fn rotate_into_plane(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if (len == 0.0) {
        return vec3<f32>(0.0);
    }
    let q = v - n * dot(n, v);
    let lq = length(q);
    // f64 uses 1e-12; in f32 the projection of a vector along n is rounding noise of
    // ~1e-7·len, so anything below 1e-6·len has no direction worth keeping.
    if (lq > 1e-6 * len) {
        return q * (len / lq);
    }
    return vec3<f32>(0.0);
}

// What one contact does to particle i.
struct Contact {
    // Normal force along n, repulsive positive.
    normal: f32,
    // Tangential force.
    tangential: vec3<f32>,
    // Rolling-resistance torque (the partner gets the negative).
    rolling: vec3<f32>,
    // Stored energy of the contact (energy ledger; `Response::potential`).
    potential: f32,
    // The history's touched flag (energy ledger: the contact is engaged).
    engaged: bool,
    // Whether the tangential force slid at the Coulomb limit (`Response::sliding`).
    sliding: bool,
    // Where within the step the contact broke, if its law resolves it (`Normal::broke`).
    broke: vec2<f32>,
}

// Whether a contact is engaged after the step (the ledger's and the force jumps' "in"):
// the law's touched flag, or a force or stored energy.
fn contact_is_in(c: Contact) -> bool {
    return c.engaged || c.potential != 0.0 || c.normal != 0.0;
}

// What the next step needs of a contact (the entries' `prior`, with the ledger, the force
// jumps or the contact output): (δ, normal force, U − ½·dt·P, 1, or 2 where it slid) while
// it is engaged, (δ, 0, 0, −1) while it is not; a slot a rebuild just made holds zeros.
fn prior_of(k: Kin, c: Contact, power: f32, is_in: bool) -> vec4<f32> {
    if (is_in) {
        return vec4<f32>(k.delta, c.normal, c.potential - 0.5 * k.dt * power, select(1.0, 2.0, c.sliding));
    }
    return vec4<f32>(k.delta, 0.0, 0.0, -1.0);
}

// The overlap at the start of the step: the prior's, or back along the approach speed for
// a contact the last step did not see (a slot a rebuild just made).
fn overlap_before(old: vec4<f32>, k: Kin) -> f32 {
    return select(k.delta - k.delta_dot * k.dt, old.x, old.w != 0.0);
}

// The law's (entry δ, F, exit δ, F) where the step entered or left the contact (for the
// ledger and the force jumps), the exit where the law placed a break within the step.
fn step_edges(row: PairRow, k: Kin, old: vec4<f32>, c: Contact, is_in: bool) -> vec4<f32> {
    var edges = vec4<f32>(0.0);
    if ((LEDGER || JUMPS) && (old.w > 0.0) != is_in) {
        edges = pair_edges(row, k);
        if (c.broke.x >= 0.0) {
            let before = overlap_before(old, k);
            edges.z = before + c.broke.x * (k.delta - before);
            edges.w = c.broke.y;
        }
    }
    return edges;
}

// The force that switched on or off at δ = 0 within the step (`pair_touch_jump`) where
// the contact is engaged on the contact side (inside it, or with an edge crossed in the
// same step); 0 where δ = 0 was not crossed, nothing switches there, or the edge crossed
// is at δ = 0 (its `edges` hold what jumps there).
fn touch_crossed(p: PairRow, k: Kin, old: vec4<f32>, is_in: bool, edges: vec4<f32>) -> f32 {
    let before = overlap_before(old, k);
    let was_in = old.w > 0.0;
    let contact_side_in = select(was_in, is_in, k.delta > 0.0);
    let edge_at_touch = was_in != is_in && select(edges.z, edges.x, is_in) == 0.0;
    if ((LEDGER || JUMPS) && (before > 0.0) != (k.delta > 0.0) && contact_side_in && !edge_at_touch) {
        return pair_touch_jump(p, k);
    }
    return 0.0;
}

@compute @workgroup_size(WG_SIZE)
fn force(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let k = particle_index(wid, nwg, lid);
    // Loaded once, outside any branch and the pair loop: a uniform load every invocation
    // takes together (a SIMD adapter otherwise loops over the lanes for it, docs/design_log.md).
    // Dead, and dropped, unless ONE_MATERIAL.
    let row0 = pairs[0];
    if (k < particle_end()) {
        particle_forces(k, row0);
    }
}

// The forces on particle k, stored in its acceleration's xyz, and its contacts' largest
// overlap/a12 (0 without overlap) in w, for the run monitor (see disp).
// `row0`: pair row 0, the only one of a scene with ONE_MATERIAL.
fn particle_forces(k: u32, row0: PairRow) {
    // (id, first entry, pairs, wall entries: loaded once)
    let ids_k = load_ids(k);
    let first = ids_k.y;
    // (own and partners' state: `own_cell`, from the mirrors on a software adapter)
    let ck = own_cell(k);
    let ok = own_off(k);
    let rk = ok.w;
    // vpred.w holds the mass
    let pk = own_vpred(k);
    let mk = pk.w;
    let vk = pk.xyz;
    let wk = rot_wpred(k);
    let mat_k = material_of(ck);
    // the position's compensation (xyz) and the radius's residual (w): the overlaps are
    // taken from them to below f32 rounding (overlap.wgsl)
    let comp_k = load_kahan_o(k);
    var f = vec3<f32>(0.0);
    var torque = vec3<f32>(0.0);
    var ledger_acc = ledger_new();
    var peak = 0.0;
    // the force jumps' impulses on k (placed at the end of the step)
    var impulse = vec3<f32>(0.0);
    for (var slot = first; slot < first + ids_k.z; slot++) {
        let j = load_nbr(slot);
        let cj = own_cell(j);
        let oj = own_off(j);
        let rj = oj.w;
        // predicted velocity (xyz) and mass (w): one load
        let pj = own_vpred(j);
        let mj = pj.w;
        let dc_raw = ck.xyz - cj.xyz;
        let dc_i = nearest_image(dc_raw);
        let comp_j = load_kahan_o(j);
        let dd = precise_separation(vec3<f32>(dc_i), image_shift(dc_i, dc_raw), ok.xyz, oj.xyz, comp_k.xyz, comp_j.xyz);
        let d = dd.hi;
        let dist = length(d);
        let delta = precise_overlap(dd, rk, rj, comp_k.w, comp_j.w);
        // (one division, not one per component: a division costs several multiplies)
        let inv_dist = 1.0 / dist;
        // A list candidate (within the skin) out of every model's range gets no force and
        // the history a pair out of range has (the models reset it there too). One store
        // site per buffer for both cases: no divergent branch around the stores.
        let old = load_prior(slot);
        let was_in = old.w > 0.0;
        // (an engaged contact that broke beyond the reach within the step is evaluated, so
        // its exit edge is booked and its force jump placed, as on the CPU; without the
        // ledger and the jumps nothing is known of it, and nothing booked)
        let far = delta < -step.reach && !((LEDGER || JUMPS) && was_in);
        var n = vec3<f32>(0.0, 0.0, 1.0);
        if (dist > 0.0) {
            n = d * inv_dist;
        }
        let v_rel = vk - pj.xyz;
        let wj = rot_wpred(j);
        // Mirror-symmetric forms (see the header): (r_i w_i + r_j w_j) is commutative.
        let v_c = v_rel - cross(rk * wk + rj * wj, n);
        let v_t = v_c - n * dot(v_c, n);
        let r_sum = rk + rj;
        let r_eff = rk * rj / r_sum;
        let inv_a12 = r_sum / (2.0 * rk * rj);
        let kin = Kin(
            delta,
            -dot(v_rel, n),
            r_eff,
            mk * mj / (mk + mj),
            step.dt,
            n,
            v_t,
            r_eff * cross(wk - wj, n) + (0.5 * (rk - rj) / r_sum) * v_t,
            inv_a12,
            wk - wj,
        );
        let h0 = load_hist(slot);
        var h = h0;
        var row = row0;
        if (!ONE_MATERIAL) {
            row = pairs[mat_k * step.n_materials + material_of(cj)];
        }
        let c = pair_contact(row, kin, &h);
        let is_in = contact_is_in(c);
        var fp = c.normal * n + c.tangential;
        var t_partner = vec3<f32>(0.0);
        var prior = vec4<f32>(delta, 0.0, 0.0, -1.0);
        var jump = 0.0;
        if (far) {
            h = hist_zero();
            fp = vec3<f32>(0.0);
            ledger_departed(&ledger_acc, old, delta);
        } else {
            peak = max(peak, delta * inv_a12);
            let power = dot(c.tangential, v_t) + dot(c.rolling, wk - wj);
            let edges = step_edges(row, kin, old, c, is_in);
            let touch = touch_crossed(row, kin, old, is_in, edges);
            ledger_pair(&ledger_acc, old, kin, c, power, is_in, edges, touch);
            prior = prior_of(kin, c, power, is_in);
            jump = contact_jump(old, kin, c, is_in, edges, touch);
            // (n stored only in the rare step that places one)
            if (jump != 0.0) {
                impulse += jump * n;
                store_jump_normal(slot, n);
            }
            f += fp;
            if (ROTATION) {
                // the partner sees n and the tangential force negated (their cross product
                // unchanged) and the rolling torque negated
                let t = cross(n, c.tangential);
                torque += -rk * t + c.rolling;
                t_partner = -rj * t - c.rolling;
            }
        }
        // stored only where it changed: most of a packing's list entries are candidates
        // out of contact whose history stays zero, so this saves most of the word's writes
        // in a pass bound by memory traffic
        if (!hist_same(h, h0)) {
            store_hist(slot, h);
        }
        store_pair_force(slot, fp);
        rot_pair_store(slot, t_partner);
        store_prior(slot, prior);
        store_jump(slot, jump);
    }
    // a particle that has not appeared meets no wall
    let present = WALLS && has_appeared(ck);
    // only the walls near at the last rebuild: k's wall entries (a SIMD group loops as
    // often as its lane with the most, mostly 0 in a packing, rather than n_walls times)
    let walls_first = ids_k.y + ids_k.z;
    let walls_end = walls_first + select(0u, ids_k.w, present);
    for (var slot = walls_first; slot < walls_end; slot++) {
        let w = load_nbr(slot) & ~WALL_ENTRY;
        let wall = walls[w];
        let n = wall.normal.xyz;
        let dcw_raw = ck.xyz - wall.cell.xyz;
        let dcw = nearest_image(dcw_raw);
        let dd = precise_separation(vec3<f32>(dcw), image_shift(dcw, dcw_raw), ok.xyz, wall.offset.xyz, comp_k.xyz, vec3<f32>(0.0));
        let delta = precise_wall_overlap(dd, n, wall.normal_lo.xyz, rk, comp_k.w, wall.offset.w);
        // relative to the (possibly moving) wall
        let v_rel = vk - wall.velocity.xyz;
        let v_c = v_rel - cross(rk * wk, n);
        let v_t = v_c - n * dot(v_c, n);
        // eq. 20 with r_j -> inf: (r_i - r_j)/(r_i + r_j) -> -1
        let inv_a12 = 0.5 / rk;
        let kin = Kin(delta, -dot(v_rel, n), rk, mk, step.dt, n, v_t, rk * cross(wk, n) - 0.5 * v_t, inv_a12, wk);
        var h = load_hist(slot);
        let old = load_prior(slot);
        let row = pairs[step.n_materials * step.n_materials + w * step.n_materials + mat_k];
        let c = pair_contact(row, kin, &h);
        store_hist(slot, h);
        peak = max(peak, delta * inv_a12);
        let is_in = contact_is_in(c);
        let power = dot(c.tangential, v_t) + dot(c.rolling, wk);
        let edges = step_edges(row, kin, old, c, is_in);
        let touch = touch_crossed(row, kin, old, is_in, edges);
        let jump = contact_jump(old, kin, c, is_in, edges, touch);
        impulse += jump * n;
        let v_n = dot(n, wall.velocity.xyz);
        // (the wall's velocity along its face: zero for lids and pistons)
        let drag = dot(c.tangential, wall.velocity.xyz - n * v_n);
        ledger_wall(&ledger_acc, old, kin, c, power, is_in, edges, touch, v_n, jump, drag);
        store_prior(slot, prior_of(kin, c, power, is_in));
        if (step.servo_walls != 0u) {
            store_wall_push(slot, c.normal);
        }
        // (a wall takes no torque: its entry's keeps the tangential force, for the output)
        rot_pair_store(slot, c.tangential);
        f += c.normal * n + c.tangential;
        if (ROTATION) {
            torque += -rk * cross(n, c.tangential) + c.rolling;
        }
    }
    // the sums over k's own list and walls; collect adds the pairs evaluated by partners
    store_acc(k, vec4<f32>(f, peak));
    rot_store_partial(k, torque);
    ledger_store(k, ledger_acc);
    // k's share of the force jumps, into its velocity now (the kicks around the end of
    // the step add to it; nothing reads it before): the partners' comes through collect
    jump_kick(k, impulse / mk);
}
