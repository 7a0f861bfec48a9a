//! The JKR contact radius: the root of 3s⁴ − 2s = δ/δ0 on the stable branch, s = √(a/a0),
//! in f64 (a tabulated start and one Newton step) and its f32 twin (the WGSL kernel's
//! arithmetic).

use super::{D_PULLOFF_DISPLACEMENT, S_MIN};
use std::sync::LazyLock;

/// c = 2·s_min, of the deflated solve (see `solve_t_iterative`).
pub(crate) const C_T: f64 = 2.0 * S_MIN;
/// b = 2·s_min², of the deflated solve.
pub(crate) const B_T: f64 = 2.0 * S_MIN * S_MIN;
/// √3.
pub(crate) const SQRT3: f64 = 1.7320508075688772;
const INV_SQRT3: f64 = 0.5773502691896258;
/// √18·s_min = dk/dt at t = 0.
pub(crate) const SLOPE0: f64 = 2.3348151486780315;

/// Nodes of the table per unit of r = √(δ/δ0 − δc/δ0).
const TABLE_DENSITY: f64 = 32.0;
/// Intervals of the table: it covers r ∈ [0, 32), δ/δ0 up to ≈ 1023.
const TABLE_INTERVALS: usize = 1024;
/// Intervals (r < 1/4) where the start's relative error is too large for the polynomial
/// Newton step (13 ulp after it at i = 1, 3.4 ulp from i = 4 on): the deflated step there.
const SMALL: usize = 8;

/// One Newton step on k(t) = √3·t·√w − r, w = (t + c)² + b, written without cancellation;
/// `r3` = r/√3.
#[inline]
fn newton_step(t: f64, r3: f64) -> f64 {
    let tc = t + C_T;
    let w = tc * tc + B_T;
    (t * t * tc + r3 * w.sqrt()) / (w + t * tc)
}

/// Solves 3s⁴ − 2s = d for s = s_min + t on the stable branch, given e = d − d_min ≥ 0,
/// returning t ≥ 0 to rounding (within 4 ulp of [`solve_t_iterative`], as
/// `tabulated_solve_matches_the_iterative_one` checks).
///
/// For δ/δ0 < 1023: a cubic Hermite interpolation of t(r), r = √e, on a uniform table and
/// one Newton step (error ∝ the start's squared: at rounding), on the polynomial 3t²w − e
/// (no square root) except near the pull-off point. Beyond that, the iterative solve.
pub(super) fn solve_t_f64(e: f64) -> f64 {
    let r = e.max(0.0).sqrt();
    let u = r * TABLE_DENSITY;
    if u >= TABLE_INTERVALS as f64 {
        return solve_t_iterative(e);
    }
    let i = u as usize;
    let f = u - i as f64;
    let [t0, m0] = TABLE[i];
    let [t1, m1] = TABLE[i + 1];
    // Hermite basis on [0, 1]; m are the slopes dt/du
    let g = 1.0 - f;
    let t = (t0 * (1.0 + 2.0 * f) + m0 * f) * g * g + (t1 * (3.0 - 2.0 * f) - m1 * g) * f * f;
    if i < SMALL {
        return newton_step(t.max(0.0), r * INV_SQRT3);
    }
    // Newton on the polynomial 3t²w − e (no square root): from a start within 1e-9·t its
    // relative error squares (halved), like the deflated step's
    let tc = t + C_T;
    let w = tc * tc + B_T;
    t - (3.0 * t * t * w - e) / (6.0 * t * (w + t * tc))
}

/// The table of [`solve_t_f64`]: (t, dt/du) at u = 0, 1, …, 1024, u = 32·r.
static TABLE: LazyLock<Vec<[f64; 2]>> = LazyLock::new(|| {
    (0..=TABLE_INTERVALS)
        .map(|i| {
            let r = i as f64 / TABLE_DENSITY;
            let t = solve_t_iterative(r * r);
            // dk/dt = √3·(w + t(t + c))/√w; dt/du = 1/(32·dk/dt)
            let tc = t + C_T;
            let w = tc * tc + B_T;
            let slope = SQRT3 * (w + t * tc) / w.sqrt();
            [t, 1.0 / (TABLE_DENSITY * slope)]
        })
        .collect()
});

/// The reference solve of 3s⁴ − 2s = d (see [`solve_t_f64`]) from a bracket: guarded Newton
/// on a deflated function, stopped after a step below 1e-8 of the root (then at rounding;
/// 3–5 steps).
///
/// With s = s_min + t and 12·s_min³ = 2 the linear term cancels:
/// 3s⁴ − 2s − d = 3t²·((t + c)² + b) − e with c = 2s_min, b = 2s_min²: a double root at
/// t = 0 when e = 0. Newton is therefore run on the deflated function
/// k(t) = √3·t·√((t + c)² + b) − √e, which is increasing and convex on t ≥ 0 with
/// k'(0) = √18·s_min > 0 (no double root), started from an upper bound so it decreases
/// monotonically. Upper bounds: k ≥ √18·s_min·t and k ≥ √3·t·(t + c); t0 is the smaller
/// of their roots, within a few % of the root everywhere.
pub(super) fn solve_t_iterative(e: f64) -> f64 {
    let r = e.max(0.0).sqrt();
    let q = 2.0 * r / SQRT3;
    let mut t = (r / SLOPE0).min(q / (C_T + (C_T * C_T + 2.0 * q).sqrt()));
    let r3 = r * INV_SQRT3;
    for _ in 0..super::NEWTON_ITERATIONS_F64 {
        let next = newton_step(t, r3);
        // quadratic convergence: after a step of at most 1e-8·t the error is at rounding
        // (the iterates are 9e-2, 1.5e-3, 4.5e-7, 4e-14 off at s = 1)
        let converged = (t - next).abs() <= 1e-8 * next;
        t = next;
        if converged {
            break;
        }
    }
    t
}

/// The f32 twin of [`super::JkrParams::contact_radius`]: the same deflated guarded Newton
/// from the bracket ([`super::NEWTON_ITERATIONS_F32`] iterations), only +, −, ×, ÷, sqrt
/// and min, as in the WGSL kernel. `a0` = 0 or `delta0` = 0 means Hertz: a = √(R·max(δ, 0)).
///
/// Measured relative error against the f64 solve of the same f32 inputs: see
/// [`super::JkrParams::contact_radius`].
pub fn contact_radius_f32(delta: f32, r_eff: f32, a0: f32, delta0: f32) -> f32 {
    contact_radius_f32_iterations(delta, r_eff, a0, delta0, super::NEWTON_ITERATIONS_F32)
}

pub(super) fn contact_radius_f32_iterations(
    delta: f32,
    r_eff: f32,
    a0: f32,
    delta0: f32,
    iterations: usize,
) -> f32 {
    if a0 <= 0.0 || delta0 <= 0.0 {
        return (r_eff * delta.max(0.0)).sqrt();
    }
    const SMIN: f32 = S_MIN as f32;
    const DMIN: f32 = D_PULLOFF_DISPLACEMENT as f32;
    const C: f32 = C_T as f32;
    const B: f32 = B_T as f32;
    const S3: f32 = SQRT3 as f32;
    const K0: f32 = SLOPE0 as f32;
    let e = (delta / delta0 - DMIN).max(0.0);
    let r = e.sqrt();
    let q = 2.0 * r / S3;
    let mut t = (r / K0).min(q / (C + (C * C + 2.0 * q).sqrt()));
    for _ in 0..iterations {
        let tc = t + C;
        let w = tc * tc + B;
        t = (t * t * tc + r * w.sqrt() / S3) / (w + t * tc);
    }
    let s = SMIN + t;
    a0 * s * s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tabulated start plus one Newton step gives the iterative solve's root to a few
    /// ulp everywhere it is used (and the iterative one beyond).
    #[test]
    fn tabulated_solve_matches_the_iterative_one() {
        let mut es: Vec<f64> = vec![0.0, 1e-300, 1e-30];
        es.extend((0..=40_000).map(|i| 10f64.powf(-16.0 + i as f64 * 5e-4)));
        // every interval of the table, at its nodes and in between
        es.extend((0..=TABLE_INTERVALS * 16).map(|i| {
            let r = i as f64 / (16.0 * TABLE_DENSITY);
            r * r
        }));
        let mut worst: f64 = 0.0;
        for &e in &es {
            let (a, b) = (solve_t_f64(e), solve_t_iterative(e));
            let ulp = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
            worst = worst.max((a - b).abs() / ulp);
        }
        eprintln!("tabulated vs iterative contact-radius solve: worst {worst:.2} ulp");
        assert!(worst <= 4.0, "worst {worst} ulp");
        // past the table: the iterative solve itself
        for e in [1024.0, 1030.0, 1e5, 1e8] {
            assert_eq!(solve_t_f64(e), solve_t_iterative(e));
        }
        assert_eq!(solve_t_f64(-1.0), 0.0);
    }
}
