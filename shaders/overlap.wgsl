// overlap.wgsl — a pair's overlap to far below f32 rounding of positions (~1e-16 m at a
// mm separation, where an f32 ulp is a sizeable part of a nm adhesion range):
// double-float (hi + lo) arithmetic on the compensated positions x = cell·h + o − c and
// radii r − c_r (the Kahan compensations the drift keeps, and the radius's rounding
// residual, both in the state's `kahan_o`). Why: `docs/architecture.md`, *Overlaps below
// f32 rounding*.
//
// Every intermediate goes through `opaque1` (step/shared.wgsl): Mesa's NIR folds the error terms
// of these exact transformations ((a + b) − a → b) for operations not marked exact.

// a + b = s + e exactly (Knuth's TwoSum).
struct Df {
    hi: f32,
    lo: f32,
}

fn two_sum(a: f32, b: f32) -> Df {
    let s = opaque1(a + b);
    let bb = opaque1(s - a);
    let e = opaque1(a - opaque1(s - bb)) + opaque1(b - bb);
    return Df(s, e);
}

// Veltkamp's split: x = hi + lo with both halves of at most 12 significant bits, so their
// products are exact in f32 (no fused multiply-add needed: WGSL does not promise one).
fn split(x: f32) -> Df {
    let t = opaque1(4097.0 * x);
    let hi = opaque1(t - opaque1(t - x));
    return Df(hi, opaque1(x - hi));
}

// a·b = p + e exactly (Dekker's TwoProduct).
fn two_prod(a: f32, b: f32) -> Df {
    let p = opaque1(a * b);
    let sa = split(a);
    let sb = split(b);
    var e = opaque1(opaque1(sa.hi * sb.hi) - p);
    e = opaque1(e + opaque1(sa.hi * sb.lo));
    e = opaque1(e + opaque1(sa.lo * sb.hi));
    e = opaque1(e + opaque1(sa.lo * sb.lo));
    return Df(p, e);
}

// A separation x_i − x_j as hi + lo per component.
struct Df3 {
    hi: vec3<f32>,
    lo: vec3<f32>,
}

// The periods a nearest-image cell difference added to the raw one, per axis (−1, 0, 1).
fn image_shift(image: vec3<i32>, raw: vec3<i32>) -> vec3<f32> {
    // |d| / dims of non-negative integers: exact (f32 division may be 2.5 ULP off, and
    // GLSL leaves the signed integer division undefined)
    let d = image - raw;
    return vec3<f32>(sign(d) * (abs(d) / vec3<i32>(grid.dims)));
}

// x_i − x_j from cell differences `dc` (nearest image, `shift` periods from the raw one),
// offsets and the compensations (xyz of `ci`, `cj`): the f32 separation the kernels form
// (cell difference·h + (o_i − o_j)) with its rounding recovered exactly, the
// compensations subtracted and, across a periodic seam, the scene's period instead of
// dims·h; then renormalised, so hi is the separation to f32 precision (the normals
// and tangential kinematics take it).
fn precise_separation(dc: vec3<f32>, shift: vec3<f32>, oi: vec3<f32>, oj: vec3<f32>, ci: vec3<f32>, cj: vec3<f32>) -> Df3 {
    var hi = vec3<f32>(0.0);
    var lo = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        // o_i − o_j exactly, then the whole cells (exact for the neighbouring cells a
        // contact spans; their rounding is kept otherwise)
        let o = two_sum(oi[a], -oj[a]);
        let cells = two_prod(dc[a], grid.cell_width[a]);
        let s = two_sum(cells.hi, o.hi);
        // renormalised: hi the nearest f32 to the compensated separation, |lo| within half
        // its ulp (in sparse scenes the compensations reach an ulp of a wide cell's
        // offsets, mm at 1e5 m cells, as large as the separation itself)
        let x = two_sum(s.hi, opaque1(s.lo + o.lo + cells.lo - (ci[a] - cj[a]) + shift[a] * step.period_lo[a]));
        hi[a] = x.hi;
        lo[a] = x.lo;
    }
    return Df3(hi, lo);
}

// The overlap r_i + r_j − |d| of a pair: `d` from `precise_separation`, `ri`, `rj` the
// stored radii and `cri`, `crj` their rounding residuals (r = stored − residual). |d| is
// taken in double-float (|lo| ~ 1e-10 m against |d| ~ 1e-3 m: terms in lo² are below
// 1e-17 m).
fn precise_overlap(d: Df3, ri: f32, rj: f32, cri: f32, crj: f32) -> f32 {
    // |d|² = Σ hi² + 2·hi·lo
    var sq = Df(0.0, 0.0);
    for (var a = 0u; a < 3u; a++) {
        let p = two_prod(d.hi[a], d.hi[a]);
        let s = two_sum(sq.hi, p.hi);
        sq = Df(s.hi, sq.lo + s.lo + p.lo + 2.0 * d.hi[a] * d.lo[a]);
    }
    // |d| = s0 + (sq − s0²)/(2·s0)
    let s0 = sqrt(sq.hi);
    if (s0 <= 0.0) {
        return ri + rj;
    }
    let q = two_prod(s0, s0);
    let dist_lo = (opaque1(opaque1(sq.hi - q.hi) - q.lo) + sq.lo) / (2.0 * s0);
    // r_i + r_j − |d|: the radii's sum exactly, their residuals, then s0 (exact near
    // contact, where the two are within a factor 2)
    let r = two_sum(ri, rj);
    return opaque1(r.hi - s0) + (r.lo - (cri + crj) - dist_lo);
}

// The overlap r − n·d of a particle with a wall plane (d from the plane's stored point to
// the particle, `n` the unit normal as stored and `n_lo` its rounding residual (true −
// stored: a tilted plane would otherwise turn by up to 6e-8 rad about the stored point),
// `cw` the plane's residual n·(stored − true point)).
fn precise_wall_overlap(d: Df3, n: vec3<f32>, n_lo: vec3<f32>, r: f32, cr: f32, cw: f32) -> f32 {
    var dot_n = Df(0.0, 0.0);
    for (var a = 0u; a < 3u; a++) {
        let p = two_prod(n[a], d.hi[a]);
        let s = two_sum(dot_n.hi, p.hi);
        dot_n = Df(s.hi, dot_n.lo + s.lo + p.lo + n[a] * d.lo[a] + n_lo[a] * d.hi[a]);
    }
    return opaque1(r - dot_n.hi) + (-cr - dot_n.lo - cw);
}

// An offset carried into whole cells, exactly: o = carry·h + offset + lo with
// 0 <= offset < h. The remainder's rounding (a step back over a face, o + h, rounds) goes
// to `lo`, which the caller books into its compensation.
struct Carried {
    offset: vec3<f32>,
    carry: vec3<i32>,
    lo: vec3<f32>,
}

fn carry_cells(o: vec3<f32>, h: vec3<f32>) -> Carried {
    var out = Carried(vec3<f32>(0.0), vec3<i32>(0), vec3<f32>(0.0));
    for (var a = 0u; a < 3u; a++) {
        var shift = floor(o[a] / h[a]);
        var r = two_sum(o[a], -opaque1(shift * h[a]));
        // the division may round across an integer: one more or one fewer cell
        if (r.hi >= h[a]) {
            let back = two_sum(r.hi, -h[a]);
            r = Df(back.hi, r.lo + back.lo);
            shift += 1.0;
        } else if (r.hi < 0.0) {
            let up = two_sum(r.hi, h[a]);
            r = Df(up.hi, r.lo + up.lo);
            shift -= 1.0;
        }
        // (r.hi + h may round up to h itself)
        if (r.hi >= h[a]) {
            r = Df(0.0, r.lo + opaque1(r.hi - h[a]));
            shift += 1.0;
        }
        out.offset[a] = r.hi;
        out.carry[a] = i32(shift);
        out.lo[a] = r.lo;
    }
    return out;
}
