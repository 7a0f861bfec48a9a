//! The JKR family's tests against the papers' closed forms.

use super::*;
use crate::model::Kinematics;
use approx::assert_relative_eq;
use glam::DVec3;

// Silica-like micro-spheres: r = 1 µm each, E = 70 GPa, ν = 0.17, γ = 0.05 J/m².
const R1: f64 = 1e-6;

fn params() -> JkrParams {
    JkrParams::jkr(70e9, 0.17, 0.05)
}

fn geom() -> PairGeometry {
    let m = 2200.0 * 4.0 / 3.0 * PI * R1.powi(3);
    PairGeometry::spheres(R1, R1, m, m)
}

fn reff() -> f64 {
    0.5 * geom().a12
}

/// The kinematics the tangential force reads: normal, tangential velocity, overlap.
fn kin(n: DVec3, v_t: DVec3, delta: f64) -> Kinematics {
    Kinematics {
        n,
        v_t,
        delta,
        ..Default::default()
    }
}

/// Force with a fresh, touched history (the stable branch).
fn touched_force(p: &JkrParams, delta: f64) -> NormalForce {
    let mut h = ContactHistory {
        touched: true,
        ..Default::default()
    };
    p.normal_force(delta, 0.0, &geom(), &mut h)
}

/// A force loop solves a root ahead exactly where the normal force solves one, and the
/// force given it is the force that solves it: same force, same history, bit for bit.
#[test]
fn roots_are_solved_ahead_where_the_force_needs_them() {
    let g = geom();
    let r = reff();
    let base = params();
    let tsuji = JkrParams {
        dissipation: Dissipation::Tsuji {
            restitution: 0.5,
            stiffness: TsujiStiffness::default(),
        },
        ..base
    };
    let krijt = JkrParams {
        dissipation: Dissipation::Krijt {
            tvis: 1e-9,
            sigma0: 0.0,
        },
        ..base
    };
    let mut ahead = 0;
    for p0 in [base, tsuji, krijt] {
        for pulloff in [Pulloff::Displacement, Pulloff::Force, Pulloff::Zero] {
            let p = JkrParams { pulloff, ..p0 };
            let pair = p.pair(r);
            let d0 = p.delta0(r);
            for step in -300..=600 {
                let delta = step as f64 * 0.01 * d0;
                for touched in [false, true] {
                    let h0 = ContactHistory {
                        touched,
                        contact_radius: if touched { 0.9 * p.a0(r) } else { 0.0 },
                        ..Default::default()
                    };
                    let (mut h1, mut h2) = (h0, h0);
                    let kin = (delta, -0.01);
                    let solved = p.normal_force_of_pair(&pair, kin, &g, 1e-9, &mut h1);
                    let root = p.root_ahead(&pair, delta, touched);
                    let given = p.normal_force_rooted(&pair, kin, root, &g, 1e-9, &mut h2);
                    assert_eq!(
                        solved, given,
                        "{pulloff:?} δ = {delta:e}, touched {touched}"
                    );
                    assert_eq!(h1, h2);
                    // every solve is done ahead (else the force loop gains nothing)
                    assert_eq!(root.is_some(), solved.in_contact, "δ = {delta:e}");
                    ahead += usize::from(root.is_some());
                }
            }
        }
    }
    assert!(ahead > 1000, "{ahead}");
}

#[test]
fn landmarks_of_the_normalised_curve() {
    assert_relative_eq!(S_MIN, 6f64.powf(-1.0 / 3.0), max_relative = 1e-15);
    assert_relative_eq!(
        D_PULLOFF_DISPLACEMENT,
        -(0.75f64).powf(2.0 / 3.0),
        max_relative = 1e-15
    );
    assert_relative_eq!(D_PULLOFF_DISPLACEMENT, -1.5 * S_MIN, max_relative = 1e-15);
    assert_relative_eq!(
        D_PULLOFF_FORCE,
        -(2f64).powf(-4.0 / 3.0),
        max_relative = 1e-15
    );
    assert_relative_eq!(X_PULLOFF_DISPLACEMENT, S_MIN * S_MIN, max_relative = 1e-15);
    // where the least G_eff/γ over a, (4/3)·|δ/δ0|^(3/2), reaches the crack law's limit
    assert_relative_eq!(
        D_PULLOFF_CRACK,
        -(0.75 * crate::model::krijt::BETA_MAX).powf(2.0 / 3.0),
        max_relative = 1e-15
    );
    assert_relative_eq!(
        X_PULLOFF_FORCE,
        0.5f64.powf(2.0 / 3.0),
        max_relative = 1e-15
    );
    assert_relative_eq!(
        X_TOUCH,
        (2.0f64 / 3.0).powf(2.0 / 3.0),
        max_relative = 1e-15
    );
    // d(x) = 3x² − 2√x at the landmarks
    let d = |x: f64| 3.0 * x * x - 2.0 * x.sqrt();
    assert!(d(X_TOUCH).abs() < 1e-15);
    assert_relative_eq!(d(X_PULLOFF_FORCE), D_PULLOFF_FORCE, max_relative = 1e-14);
    assert_relative_eq!(
        d(X_PULLOFF_DISPLACEMENT),
        D_PULLOFF_DISPLACEMENT,
        max_relative = 1e-14
    );
}

#[test]
fn break_potential_shapes_are_the_potential_at_the_break() {
    for rule in [Pulloff::Displacement, Pulloff::Force, Pulloff::Zero] {
        assert_eq!(
            rule.break_potential_shape(),
            potential_shape(rule.break_radius_ratio()),
            "{rule:?}"
        );
    }
}

#[test]
fn contact_radius_round_trips() {
    let p = params();
    let r = reff();
    let (a0, d0) = (p.a0(r), p.delta0(r));
    // δ → a → δ: well conditioned everywhere, including the pull-off point
    let mut worst: f64 = 0.0;
    let mut ds: Vec<f64> = (0..=2000)
        .map(|i| D_PULLOFF_DISPLACEMENT + 1e-14 * 10f64.powf(i as f64 * 0.0075))
        .collect();
    ds.extend((0..=4000).map(|i| -0.9 + i as f64 * 1e-3));
    ds.extend((0..=600).map(|i| 10f64.powf(-3.0 + i as f64 * 0.02)));
    for &d in &ds {
        let delta = d * d0;
        let a = p.contact_radius(delta, r);
        let back = p.overlap_for_radius(a, r);
        let expect = delta.max(D_PULLOFF_DISPLACEMENT * d0);
        let err = (back - expect).abs() / (d0 * d.abs().max(1.0));
        worst = worst.max(err);
    }
    assert!(worst < 1e-12, "δ(a(δ)) worst relative error {worst:e}");
    // a → δ → a: ill-conditioned only right at the pull-off point (da/dδ = ∞ there)
    for i in 0..=1000 {
        let x = X_PULLOFF_DISPLACEMENT * (1.0 + 1e-3) + i as f64 * 0.01;
        let a = x * a0;
        let back = p.contact_radius(p.overlap_for_radius(a, r), r);
        assert_relative_eq!(back, a, max_relative = 1e-12);
    }
    let a = X_PULLOFF_DISPLACEMENT * a0;
    assert_relative_eq!(
        p.contact_radius(D_PULLOFF_DISPLACEMENT * d0, r),
        a,
        max_relative = 1e-7
    );
    // below the pull-off overlap the radius is clamped to the pull-off radius
    assert_relative_eq!(p.contact_radius(-2.0 * d0, r), a, max_relative = 1e-14);
    // equilibrium
    assert_relative_eq!(p.contact_radius(d0, r), a0, max_relative = 1e-14);
}

#[test]
fn f64_solver_converges_far_out() {
    // very large δ/δ0 (nearly Hertz): the solver still converges in its fixed count
    let p = params();
    let r = reff();
    let d0 = p.delta0(r);
    for d in [1e3, 1e5, 1e8] {
        let a = p.contact_radius(d * d0, r);
        assert_relative_eq!(p.overlap_for_radius(a, r), d * d0, max_relative = 1e-13);
    }
}

#[test]
fn force_landmarks() {
    let p = params();
    let r = reff();
    let (fc, d0) = (p.fc(r), p.delta0(r));
    let f = |d: f64| p.elastic_force(p.contact_radius(d * d0, r), r);
    assert_relative_eq!(f(0.0), -8.0 / 9.0 * fc, max_relative = 1e-12);
    assert_relative_eq!(f(D_PULLOFF_FORCE), -fc, max_relative = 1e-12);
    assert_relative_eq!(
        f(D_PULLOFF_DISPLACEMENT),
        -5.0 / 9.0 * fc,
        max_relative = 1e-7
    );
    assert!(f(1.0).abs() < 1e-12 * fc);
    // −Fc is the minimum along the branch
    for i in 0..200 {
        let d = D_PULLOFF_DISPLACEMENT + i as f64 * 0.01;
        assert!(f(d) >= -fc * (1.0 + 1e-12));
    }
    // pull-off overlaps
    assert_relative_eq!(
        p.pulloff_overlap(r),
        -(0.75f64).powf(2.0 / 3.0) * d0,
        max_relative = 1e-14
    );
    let q = JkrParams {
        pulloff: Pulloff::Force,
        ..p
    };
    assert_relative_eq!(
        q.pulloff_overlap(r),
        -0.3968502629920499 * d0,
        max_relative = 1e-14
    );
    assert_eq!(JkrParams::hertz(1e9, 0.3).pulloff_overlap(r), 0.0);
    // the paper-001 numbers: Fc = 3πγR*, δ0 = a0²/(3R*)
    assert_relative_eq!(fc, 3.0 * PI * 0.05 * r, max_relative = 1e-15);
    let es = 70e9 / (2.0 * (1.0 - 0.17 * 0.17));
    assert_relative_eq!(p.e_star(), es, max_relative = 1e-15);
    assert_relative_eq!(
        p.a0(r),
        (9.0 * PI * 0.05 * r * r / es).cbrt(),
        max_relative = 1e-15
    );
}

#[test]
fn hertz_limit() {
    let r = reff();
    let h = JkrParams::hertz(70e9, 0.17);
    let es = h.e_star();
    for delta in [1e-10, 1e-9, 1e-8] {
        let f = touched_force(&h, delta);
        let expect = 4.0 / 3.0 * es * r.sqrt() * delta.powf(1.5);
        assert_relative_eq!(f.conservative, expect, max_relative = 1e-14);
        assert_relative_eq!(
            f.potential,
            8.0 / 15.0 * es * r.sqrt() * delta.powf(2.5),
            max_relative = 1e-14
        );
        // JKR with a vanishing surface energy tends to Hertz
        let j = JkrParams::jkr(70e9, 0.17, 1e-12);
        let fj = touched_force(&j, delta);
        assert_relative_eq!(fj.conservative, expect, max_relative = 1e-3);
        let jj = JkrParams::jkr(70e9, 0.17, 1e-16);
        let fjj = touched_force(&jj, delta);
        assert_relative_eq!(fjj.conservative, expect, max_relative = 3e-5);
        assert!((fjj.conservative - expect).abs() < (fj.conservative - expect).abs());
    }
    // Hertz: no contact at δ ≤ 0, even after touching
    let mut hist = ContactHistory::default();
    assert!(h.normal_force(1e-9, 0.0, &geom(), &mut hist).in_contact);
    let f = h.normal_force(-1e-12, 0.0, &geom(), &mut hist);
    assert!(!f.in_contact && f.force == 0.0 && !hist.touched);
}

#[test]
fn potential_is_the_integral_of_the_force() {
    let p = params();
    let r = reff();
    let (fc, d0) = (p.fc(r), p.delta0(r));
    for d in [-0.8, -0.5, -0.2, 0.0, 0.3, 1.0, 2.0, 10.0] {
        let h = 1e-5 * d0;
        let up = touched_force(&p, d * d0 + h).potential;
        let down = touched_force(&p, d * d0 - h).potential;
        let f = touched_force(&p, d * d0).conservative;
        assert!(
            ((up - down) / (2.0 * h) - f).abs() < 1e-7 * fc,
            "dU/dδ at d = {d}: {} vs {f}",
            (up - down) / (2.0 * h)
        );
    }
    // Hertz
    let hz = JkrParams::hertz(70e9, 0.17);
    let delta = 1e-9;
    let h = 1e-14;
    let du = (touched_force(&hz, delta + h).potential - touched_force(&hz, delta - h).potential)
        / (2.0 * h);
    assert_relative_eq!(
        du,
        touched_force(&hz, delta).conservative,
        max_relative = 1e-7
    );
    // P(x) is the antiderivative: P'(x) = F/Fc·dδ/dx /δ0
    for x in [0.3, 0.5, 0.9, 1.5] {
        let h = 1e-6;
        let dp = (potential_shape(x + h) - potential_shape(x - h)) / (2.0 * h);
        let integrand = (4.0 * x.powi(3) - 4.0 * x.powf(1.5)) * (6.0 * x - x.powf(-0.5));
        assert_relative_eq!(dp, integrand, max_relative = 1e-8);
    }
    // the potential vanishes at the break point
    let at_break = touched_force(&p, D_PULLOFF_DISPLACEMENT * d0 * (1.0 - 1e-12)).potential;
    assert!(at_break.abs() < 1e-6 * fc * d0);
    equilibrium_stiffness_fd(&p);
}

/// dF/dδ at δ0 by finite differences equals 1.2·Fc/δ0.
fn equilibrium_stiffness_fd(p: &JkrParams) {
    let r = reff();
    let d0 = p.delta0(r);
    let h = 1e-6 * d0;
    let k =
        (touched_force(p, d0 + h).conservative - touched_force(p, d0 - h).conservative) / (2.0 * h);
    assert_relative_eq!(k, p.equilibrium_stiffness(r), max_relative = 1e-8);
    assert_relative_eq!(
        p.equilibrium_stiffness(r),
        1.2 * p.fc(r) / d0,
        max_relative = 1e-15
    );
}

#[test]
fn cycle_loss_from_the_potential() {
    let p = params();
    let r = reff();
    let (fc, d0) = (p.fc(r), p.delta0(r));
    // the potential just after the touch is −(energy lost over the cycle): the
    // bookkeeping drops by W at the touch and is continuous at the break
    let w = -touched_force(&p, 1e-13 * d0).potential;
    assert_relative_eq!(w / (fc * d0), 0.7722, max_relative = 1e-4);
    assert_relative_eq!(w / (fc * d0), 0.7722405328755862, max_relative = 1e-9);
    let q = JkrParams {
        pulloff: Pulloff::Force,
        ..p
    };
    let wq = -touched_force(&q, 1e-13 * d0).potential;
    assert_relative_eq!(wq / (fc * d0), 0.3813841613953991, max_relative = 1e-9);
}

/// Head-on pair integrated with velocity Verlet (the engine's scheme), δ from the
/// separation. Returns (approach speed at the end (negative: separating), stuck, contact
/// time).
fn collide(p: &JkrParams, v: f64, steps_per_d0: f64) -> (f64, bool, f64) {
    let g = geom();
    let r = reff();
    let m = g.reduced_mass;
    let scale = if p.gamma() > 0.0 {
        p.delta0(r)
    } else {
        // Hertz: the largest overlap
        (15.0 * m * v * v / (16.0 * p.e_star() * r.sqrt())).powf(0.4)
    };
    let dt = scale / steps_per_d0 / v;
    let mut hist = ContactHistory::default();
    let mut delta = -1e-3 * scale;
    let mut vel = v;
    let mut f = p.normal_force(delta, vel, &g, &mut hist).force;
    let mut t_contact = 0.0;
    let mut was_in = false;
    for _ in 0..200_000_000u64 {
        let vh = vel - 0.5 * dt * f / m;
        delta += vh * dt;
        // velocity-dependent force: evaluate with the half-step velocity predictor
        let nf = p.normal_force(delta, vh - 0.5 * dt * f / m, &g, &mut hist);
        f = nf.force;
        vel = vh - 0.5 * dt * f / m;
        if nf.in_contact {
            t_contact += dt;
            was_in = true;
        } else if was_in {
            return (vel, false, t_contact);
        }
        if t_contact > 0.0 && delta < -2.0 * scale {
            return (vel, false, t_contact);
        }
    }
    (vel, true, t_contact)
}

#[test]
fn undamped_jkr_collision_loses_the_cycle_energy() {
    let p = params();
    let r = reff();
    let m = geom().reduced_mass;
    let w = p.fc(r) * p.delta0(r) * 0.7722405328755862;
    let v_stick = (2.0 * w / m).sqrt();
    for factor in [1.5, 3.0] {
        let v = factor * v_stick;
        let (vout, stuck, _) = collide(&p, v, 2e5);
        assert!(!stuck);
        let lost = 0.5 * m * (v * v - vout * vout);
        assert_relative_eq!(lost, w, max_relative = 1e-4);
        let e = -vout / v;
        assert_relative_eq!(e, (1.0 - w / (0.5 * m * v * v)).sqrt(), max_relative = 1e-4);
    }
}

#[test]
fn hysteresis_of_touch_and_pulloff() {
    let p = params();
    let r = reff();
    let g = geom();
    let d0 = p.delta0(r);
    let mut h = ContactHistory::default();
    // approaching from δ < 0: nothing
    for d in [-0.9, -0.5, -0.1, 0.0] {
        let f = p.normal_force(d * d0, 1.0, &g, &mut h);
        assert_eq!(f, NormalForce::default());
        assert!(!h.touched);
    }
    // touch
    let f = p.normal_force(1e-9 * d0, 1.0, &g, &mut h);
    assert!(h.touched && f.in_contact);
    assert_relative_eq!(f.conservative, -8.0 / 9.0 * p.fc(r), max_relative = 1e-6);
    h.tangential = DVec3::new(1e-9, 0.0, 0.0);
    h.rolling = DVec3::new(0.0, 1e-9, 0.0);
    // separating into negative overlap: still in contact, attractive
    let f = p.normal_force(-0.1 * d0, -1.0, &g, &mut h);
    assert!(f.in_contact && f.force < 0.0 && f.contact_radius > 0.0);
    let f = p.normal_force(-0.8254 * d0, -1.0, &g, &mut h);
    assert!(f.in_contact);
    assert_relative_eq!(f.conservative, -5.0 / 9.0 * p.fc(r), max_relative = 5e-2);
    // past δc: broken, history reset
    let f = p.normal_force(-0.826 * d0, -1.0, &g, &mut h);
    assert_eq!(f, NormalForce::default());
    assert_eq!(h, ContactHistory::default());
    // and no force on the way back in until δ > 0
    let f = p.normal_force(-0.1 * d0, 1.0, &g, &mut h);
    assert_eq!(f, NormalForce::default());
    // force-controlled pull-off breaks at −0.397·δ0
    let q = JkrParams {
        pulloff: Pulloff::Force,
        ..p
    };
    let mut h = ContactHistory::default();
    q.normal_force(0.5 * d0, 0.0, &g, &mut h);
    assert!(q.normal_force(-0.39 * d0, 0.0, &g, &mut h).in_contact);
    assert!(!q.normal_force(-0.40 * d0, 0.0, &g, &mut h).in_contact);
}

#[test]
fn f32_solver_accuracy() {
    let p = params();
    let r = reff();
    let (a0, d0) = (p.a0(r) as f32, p.delta0(r) as f32);
    let mut ds: Vec<f64> = vec![-0.8255, D_PULLOFF_DISPLACEMENT];
    // near the pull-off point, logarithmically in the distance d − dc
    ds.extend((0..=3000).map(|i| D_PULLOFF_DISPLACEMENT + 10f64.powf(-12.0 + i as f64 * 0.004)));
    // the whole attractive range and around 0
    ds.extend((0..=200_000).map(|i| -0.8255 + i as f64 * 1e-5));
    ds.extend((0..=2000).map(|i| -1e-3 + i as f64 * 1e-6));
    // logarithmically up to 1000
    ds.extend((0..=20_000).map(|i| 10f64.powf(-8.0 + i as f64 * 5.5e-4)));
    // worst error per band of e = d − dc: [< 1e-6, < 1e-4, < 1e-2, ≥ 1e-2], against the
    // f64 solve of the same f32 inputs (total), and against the f64 solve of the same
    // f32-rounded d (the solver's own error)
    let mut total = [0.0f64; 4];
    let mut own = 0.0f64;
    for &d in &ds {
        let delta = (d * d0 as f64) as f32;
        let a32 = contact_radius_f32(delta, r as f32, a0, d0) as f64;
        let exact_d = delta as f64 / d0 as f64;
        let s = S_MIN + solve_t_f64(exact_d - D_PULLOFF_DISPLACEMENT);
        let a64 = a0 as f64 * s * s;
        let e = exact_d - D_PULLOFF_DISPLACEMENT;
        let band = match e {
            e if e < 1e-6 => 0,
            e if e < 1e-4 => 1,
            e if e < 1e-2 => 2,
            _ => 3,
        };
        total[band] = total[band].max((a32 - a64).abs() / a64);
        let rounded_d = (delta / d0) as f64;
        let s = S_MIN + solve_t_f64(rounded_d - (D_PULLOFF_DISPLACEMENT as f32) as f64);
        let a64 = a0 as f64 * s * s;
        own = own.max((a32 - a64).abs() / a64);
    }
    eprintln!(
        "f32 contact radius ({NEWTON_ITERATIONS_F32} iterations): relative error by \
         d - dc in [<1e-6, <1e-4, <1e-2, >=1e-2]: {:.3e} {:.3e} {:.3e} {:.3e}; \
         solver's own (same rounded d): {own:.3e}",
        total[0], total[1], total[2], total[3]
    );
    assert!(own < 6e-7, "solver error {own:e}");
    assert!(total[3] < 6e-7, "{total:?}");
    assert!(total[2] < 5e-6, "{total:?}");
    assert!(total[1] < 5e-5, "{total:?}");
    assert!(total[0] < 2e-4, "{total:?}");
    // equilibrium
    assert_relative_eq!(
        contact_radius_f32(d0, r as f32, a0, d0) as f64,
        a0 as f64,
        max_relative = 3e-7
    );
    // Hertz fallback
    let a = contact_radius_f32(1e-9, 1e-6, 0.0, 0.0);
    assert_relative_eq!(a as f64, (1e-15f64).sqrt(), max_relative = 1e-6);
    assert_eq!(contact_radius_f32(-1e-9, 1e-6, 0.0, 0.0), 0.0);
}

/// RK4 integration of a head-on Hertz + Tsuji collision: (restitution, contact time).
fn tsuji_collision(p: &JkrParams, v: f64) -> (f64, f64) {
    let g = geom();
    let m = g.reduced_mass;
    let tc = p.hertz_contact_time(reff(), m, v);
    let dt = tc / 200_000.0;
    let acc = |d: f64, dd: f64| -> f64 {
        let mut h = ContactHistory::default();
        -p.normal_force(d, dd, &g, &mut h).force / m
    };
    let (mut d, mut dd, mut t) = (0.0f64, v, 0.0f64);
    for _ in 0..100_000_000u64 {
        let (k1x, k1v) = (dd, acc(d, dd));
        let (k2x, k2v) = (
            dd + 0.5 * dt * k1v,
            acc(d + 0.5 * dt * k1x, dd + 0.5 * dt * k1v),
        );
        let (k3x, k3v) = (
            dd + 0.5 * dt * k2v,
            acc(d + 0.5 * dt * k2x, dd + 0.5 * dt * k2v),
        );
        let (k4x, k4v) = (dd + dt * k3v, acc(d + dt * k3x, dd + dt * k3v));
        let nd = d + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let ndd = dd + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if nd <= 0.0 && t > 0.0 {
            // linear interpolation to δ = 0
            let frac = d / (d - nd);
            return (-(dd + frac * (ndd - dd)) / v, t + frac * dt);
        }
        d = nd;
        dd = ndd;
        t += dt;
    }
    panic!("the pair did not separate (e_target too small?)");
}

#[test]
fn tsuji_damping_calibration() {
    let hz = JkrParams::hertz(70e9, 0.17);
    // undamped: e = 1 and the Hertz contact time 2.87·(m²/(R E² v))^(1/5)
    let (e, t) = tsuji_collision(&hz, 0.1);
    assert_relative_eq!(e, 1.0, max_relative = 1e-9);
    assert_relative_eq!(
        t,
        hz.hertz_contact_time(reff(), geom().reduced_mass, 0.1),
        max_relative = 2e-3
    );
    let mut report = String::new();
    for target in [0.95, 0.9, 0.7, 0.5, 0.3, 0.1] {
        let p = JkrParams {
            dissipation: Dissipation::tsuji(target),
            ..hz
        };
        // paper 002's Hertz stiffness rule: for Hertz a = √(R*δ), so bitwise the same
        let q = JkrParams {
            dissipation: Dissipation::Tsuji {
                restitution: target,
                stiffness: TsujiStiffness::Hertz,
            },
            ..hz
        };
        let mut es = Vec::new();
        for v in [1e-3, 0.1, 10.0] {
            let (e, _) = tsuji_collision(&p, v);
            assert_eq!(e.to_bits(), tsuji_collision(&q, v).0.to_bits());
            es.push(e);
        }
        // velocity-independent (the damping ∝ δ^(1/4)·δ̇ keeps Hertz self-similar)
        for e in &es {
            assert_relative_eq!(*e, es[0], max_relative = 1e-12);
        }
        let rel = es[0] / target - 1.0;
        report.push_str(&format!(
            "e_target {target}: e = {:.9} ({rel:+.2e})\n",
            es[0]
        ));
        // measured: the calibration is exact for Hertz up to the integration error
        // (+2.5e-7 at dt = tc/2e5, +1.6e-8 at tc/1e6, shrinking with dt)
        assert!(rel.abs() < 1e-6, "target {target}: e = {}", es[0]);
    }
    eprintln!("{report}");
}

#[test]
fn power_law_dissipation() {
    let p = JkrParams {
        dissipation: Dissipation::PowerLaw {
            d: 118.0,
            alpha: 3.0,
            beta: 1.5,
        },
        ..params()
    };
    let r = reff();
    let g = geom();
    let d0 = p.delta0(r);
    let mut h = ContactHistory::default();
    let f = p.normal_force(0.5 * d0, 0.2, &g, &mut h);
    let expect = 118.0 * p.e_star() * 0.2f64.powi(3) * f.contact_radius.powf(1.5);
    assert_relative_eq!(f.force - f.conservative, expect, max_relative = 1e-12);
    // opposes the motion on the way out, zero at rest
    let f = p.normal_force(0.5 * d0, -0.2, &g, &mut h);
    assert_relative_eq!(f.force - f.conservative, -expect, max_relative = 1e-12);
    let f = p.normal_force(0.5 * d0, 0.0, &g, &mut h);
    assert_eq!(f.force, f.conservative);
    // Tsuji acts at negative overlap too (a > 0 there)
    let t = JkrParams {
        dissipation: Dissipation::tsuji(0.5),
        ..params()
    };
    let f = t.normal_force(-0.5 * d0, -0.1, &g, &mut h);
    assert!(f.in_contact && f.force < f.conservative);
}

/// Paper 002's stiffness rule for the Tsuji dashpots: Sn = 2E*·√(R*δ) and
/// St = 8G*·√(R*δ), zero at δ ≤ 0, where the default uses the JKR contact radius a
/// (larger than √(R*δ) at δ > 0, and positive at δ ≤ 0 while the contact holds).
#[test]
fn tsuji_hertz_stiffness_rule() {
    let hertz_rule = |p: JkrParams| JkrParams {
        dissipation: Dissipation::Tsuji {
            restitution: 0.5,
            stiffness: TsujiStiffness::Hertz,
        },
        ..p
    };
    let (p, q) = (
        JkrParams {
            friction: 0.3,
            dissipation: Dissipation::tsuji(0.5),
            ..params()
        },
        hertz_rule(JkrParams {
            friction: 0.3,
            ..params()
        }),
    );
    let (r, g) = (reff(), geom());
    let (d0, m) = (p.delta0(r), g.reduced_mass);
    let c = -TSUJI_PREFACTOR * tsuji_beta(0.5);
    let touched = || ContactHistory {
        touched: true,
        ..Default::default()
    };
    for d in [0.3, 1.0, 5.0] {
        let delta = d * d0;
        let (fp, fq) = (
            p.normal_force(delta, 0.2, &g, &mut touched()),
            q.normal_force(delta, 0.2, &g, &mut touched()),
        );
        // the same elastic force, the damping from √(R*δ) instead of a
        assert_eq!(fp.conservative, fq.conservative);
        let rho = (r * delta).sqrt();
        assert!(rho < fp.contact_radius);
        assert_relative_eq!(
            fq.force - fq.conservative,
            c * (2.0 * q.e_star() * rho * m).sqrt() * 0.2,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            fp.force - fp.conservative,
            c * (2.0 * p.e_star() * fp.contact_radius * m).sqrt() * 0.2,
            max_relative = 1e-12
        );
        // tangential: the spring keeps 8G*·a, the dashpot takes 8G*·√(R*δ)
        let v = DVec3::new(0.0, 1e-3, 0.0);
        let (mut sp, mut sq) = (DVec3::ZERO, DVec3::ZERO);
        let tp = p.tangential_force(&kin(DVec3::X, v, delta), &fp, &g, 1e-12, &mut sp);
        let tq = q.tangential_force(&kin(DVec3::X, v, delta), &fq, &g, 1e-12, &mut sq);
        assert_eq!(tp.stiffness, tq.stiffness);
        assert_eq!(sp, sq);
        let st = 8.0 * q.g_star() * fq.contact_radius;
        let ct = c * (8.0 * q.g_star() * rho * m).sqrt();
        assert!(!tq.sliding);
        assert!((tq.force - (-st * sq - ct * v)).length() < 1e-12 * tq.force.length());
        assert!(tq.force.length() < tp.force.length());
    }
    // negative overlap: the contact holds and attracts, the Hertz-rule dashpots are off
    let delta = -0.5 * d0;
    let (fp, fq) = (
        p.normal_force(delta, -0.2, &g, &mut touched()),
        q.normal_force(delta, -0.2, &g, &mut touched()),
    );
    assert!(fq.in_contact && fq.contact_radius > 0.0);
    assert_eq!(fq.force, fq.conservative);
    assert!(fp.force < fp.conservative);
    let v = DVec3::new(0.0, 1e-3, 0.0);
    let mut sq = DVec3::ZERO;
    let tq = q.tangential_force(&kin(DVec3::X, v, delta), &fq, &g, 1e-12, &mut sq);
    assert!((tq.force + tq.stiffness * sq).length() <= 1e-15 * tq.force.length());
    // no damping at the contact's edges (δ = 0 and the pull-off overlap)
    for (delta, f) in q.edge_forces(&g, -1.0, 1.0) {
        let a = q.contact_radius(delta, r);
        assert_eq!(f, q.elastic_force(a, r), "edge at {delta}");
    }
    // validation and serde: the default is the contact radius; "hertz" round-trips
    assert!(q.validate().is_ok());
    let json = serde_json::to_string(&q).unwrap();
    assert!(json.contains("\"stiffness\":\"hertz\""), "{json}");
    assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), q);
    assert_eq!(TsujiStiffness::default(), TsujiStiffness::ContactRadius);
    assert_eq!(TsujiStiffness::Hertz.word(), "hertz");
}

#[test]
fn tangential_spring_and_coulomb_limit() {
    let p = JkrParams {
        friction: 0.3,
        dissipation: Dissipation::tsuji(0.5),
        ..params()
    };
    let r = reff();
    let g = geom();
    let d0 = p.delta0(r);
    let mut h = ContactHistory::default();
    let normal = p.normal_force(d0, 0.0, &g, &mut h);
    let n = DVec3::X;
    let st = 8.0 * p.g_star() * normal.contact_radius;
    let ct = -TSUJI_PREFACTOR * tsuji_beta(0.5) * (st * g.reduced_mass).sqrt();
    assert!(ct > 0.0);
    let limit = 0.3 * (normal.conservative + 2.0 * p.fc(r)).abs();
    // below the limit: F = −St·s − c·v_t
    let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
    let v = DVec3::new(0.0, 0.0, 1e-6);
    let dt = 1e-9;
    let t = p.tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
    let s_expect = DVec3::new(0.0, 1e-3 * d0, 1e-15);
    assert!((s - s_expect).length() < 1e-12 * s_expect.length());
    let f_expect = -st * s_expect - ct * v;
    assert!(!t.sliding && (t.force - f_expect).length() < 1e-12 * f_expect.length());
    assert!(f_expect.length() < limit);
    assert_relative_eq!(t.stiffness, st, max_relative = 1e-15);
    // above the limit: |F| = μs·|F_N + 2Fc| exactly, spring consistent with the force
    let mut s = DVec3::new(0.0, 10.0 * d0, 0.0);
    let t = p.tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
    assert!(t.sliding);
    assert_relative_eq!(t.force.length(), limit, max_relative = 1e-14);
    assert!((-st * s - ct * v - t.force).length() < 1e-12 * limit);
    assert!(t.force.y < 0.0);
    // a new tangent plane: the spring is rotated, keeping its length
    let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
    let n2 = DVec3::new(0.6, 0.8, 0.0);
    let t2 = p.tangential_force(&kin(n2, DVec3::ZERO, d0), &normal, &g, dt, &mut s);
    assert!(s.dot(n2).abs() < 1e-15 * s.length());
    assert_relative_eq!(s.length(), 1e-3 * d0, max_relative = 1e-14);
    assert_relative_eq!(t2.force.length(), st * 1e-3 * d0, max_relative = 1e-14);
    // no friction, or no contact: spring zeroed, no force
    let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
    let t = params().tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
    assert_eq!((t, s), (Tangential::default(), DVec3::ZERO));
    let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
    let t = p.tangential_force(&kin(n, v, d0), &NormalForce::default(), &g, dt, &mut s);
    assert_eq!((t, s), (Tangential::default(), DVec3::ZERO));
    // Hertz: the limit is μs·F_N
    let hz = JkrParams {
        friction: 0.3,
        ..JkrParams::hertz(70e9, 0.17)
    };
    let nh = hz.normal_force(1e-9, 0.0, &g, &mut ContactHistory::default());
    let mut s = DVec3::new(0.0, 1e-6, 0.0);
    let t = hz.tangential_force(&kin(n, DVec3::ZERO, 1e-9), &nh, &g, dt, &mut s);
    assert_relative_eq!(
        t.force.length(),
        0.3 * nh.conservative,
        max_relative = 1e-14
    );
}

#[test]
fn rolling_resistance() {
    let p = JkrParams {
        rolling_hysteresis: 0.5,
        ..params()
    };
    let r = reff();
    let g = geom();
    let d0 = p.delta0(r);
    let mut h = ContactHistory::default();
    let normal = p.normal_force(d0, 0.0, &g, &mut h);
    let n = DVec3::X;
    // particle i spins about +y, j at rest: v_roll = R*·(ω_i − ω_j) × n
    let omega_i = DVec3::new(0.0, 2.0, 0.0);
    let v_roll = r * omega_i.cross(n);
    let xi_crit = p.a0_unscaled(r) / 12.0 * 0.5;
    let mut xi = DVec3::ZERO;
    let dt = 1e-3 * xi_crit / v_roll.length();
    let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
    assert!(!m.yielding);
    assert!(m.torque.dot(omega_i) < 0.0, "opposes ω_i − ω_j");
    assert!(m.torque.normalize().dot(-omega_i.normalize()) > 1.0 - 1e-12);
    // kr = 4Fc at equilibrium (a = a0)
    assert_relative_eq!(m.stiffness, 4.0 * p.fc(r), max_relative = 1e-12);
    assert_relative_eq!(
        m.torque.length(),
        m.stiffness * xi.length(),
        max_relative = 1e-14
    );
    // keep rolling: |ξ| never exceeds ξcrit, and yields
    let mut yielded = false;
    for _ in 0..5000 {
        let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
        assert!(xi.length() <= xi_crit * (1.0 + 1e-14));
        yielded |= m.yielding;
    }
    assert!(yielded);
    assert_relative_eq!(xi.length(), xi_crit, max_relative = 1e-14);
    // the largest torque is the Krijt yield torque 4Fc·ξcrit at a = a0
    let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
    assert_relative_eq!(
        m.torque.length(),
        4.0 * p.fc(r) * xi_crit,
        max_relative = 1e-12
    );
    // rotated into a new tangent plane with its length kept
    let n2 = DVec3::new(0.8, 0.0, 0.6);
    p.rolling_torque(n2, DVec3::ZERO, &normal, &g, dt, &mut xi);
    assert!(xi.dot(n2).abs() < 1e-14 * xi.length());
    assert_relative_eq!(xi.length(), xi_crit, max_relative = 1e-14);
    // off without hysteresis or out of contact
    let m = params().rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
    assert_eq!((m, xi), (Rolling::default(), DVec3::ZERO));
    xi = DVec3::Y;
    let m = p.rolling_torque(n, v_roll, &NormalForce::default(), &g, dt, &mut xi);
    assert_eq!((m, xi), (Rolling::default(), DVec3::ZERO));
}

#[test]
fn stiffness_scaling_keeps_the_cycle_energy() {
    let p = params();
    let s = 0.01;
    let q = JkrParams {
        stiffness_scale: s,
        rolling_hysteresis: 0.5,
        ..p
    };
    let r = reff();
    assert_relative_eq!(q.e_star(), s * p.e_star(), max_relative = 1e-15);
    assert_relative_eq!(q.g_star(), s * p.g_star(), max_relative = 1e-15);
    assert_relative_eq!(q.gamma(), 0.05 * s.powf(0.4), max_relative = 1e-15);
    // paper 002 eqs. 23–24: Fc·δ0 (hence the cycle loss 0.7722·Fc·δ0) is unchanged
    let w = |p: &JkrParams| p.fc(r) * p.delta0(r) * 0.7722405328755862;
    assert_relative_eq!(w(&q), w(&p), max_relative = 1e-12);
    // and so is the work from touch to equilibrium (eq. 23) and the sticking velocity
    let work = |p: &JkrParams| {
        touched_force(p, 1e-13 * p.delta0(r)).potential - touched_force(p, p.delta0(r)).potential
    };
    assert_relative_eq!(work(&q), work(&p), max_relative = 1e-9);
    let m = geom().reduced_mass;
    let v = 2.0 * (2.0 * w(&p) / m).sqrt();
    let (vp, _, tp) = collide(&p, v, 2e4);
    let (vq, _, tq) = collide(&q, v, 2e4);
    // the undamped JKR dynamics are self-similar in δ0 and sqrt(m*·δ0/Fc) ∝ S^(−2/5):
    // same outcome, collisions last S^(−2/5) times longer (paper 002 §6.2)
    assert_relative_eq!(vp, vq, max_relative = 1e-9);
    let factor = q.stiffness_scaling().unwrap().collision_time_factor;
    assert_relative_eq!(factor, s.powf(-0.4), max_relative = 1e-15);
    assert_relative_eq!(tq / tp, factor, max_relative = 1e-6);
    // the pull-off force drops by S^(2/5)
    assert_relative_eq!(q.fc(r) / p.fc(r), s.powf(0.4), max_relative = 1e-14);
    // rolling: at equilibrium kr = 4·Fc (unscaled) and ξcrit with the unscaled a0
    let mut h = ContactHistory::default();
    let nq = q.normal_force(q.delta0(r), 0.0, &geom(), &mut h);
    let mut xi = DVec3::ZERO;
    let m = q.rolling_torque(DVec3::X, DVec3::Y, &nq, &geom(), 1.0, &mut xi);
    assert_relative_eq!(m.stiffness, 4.0 * p.fc(r), max_relative = 1e-12);
    assert_relative_eq!(xi.length(), p.a0(r) / 12.0 * 0.5, max_relative = 1e-12);
    // report only when S ≠ 1
    assert!(p.stiffness_scaling_report().is_none());
    let text = q.stiffness_scaling_report().unwrap();
    assert!(
        text.contains("pull-off") && text.contains("6.3096"),
        "{text}"
    );
}

#[test]
fn hertz_contact_time_matches_the_closed_form() {
    let p = JkrParams::hertz(1e9, 0.3);
    let (r, m, v) = (1e-3, 1e-5, 0.5);
    let es = p.e_star();
    assert_relative_eq!(
        p.hertz_contact_time(r, m, v),
        2.87 * (m * m / (r * es * es * v)).powf(0.2),
        max_relative = 1e-15
    );
    assert_eq!(p.equilibrium_stiffness(r), 0.0);
}

/// The time step crosses the adhesive zone in 50 steps at the impact velocity, but
/// never at more than the adhesion speed: faster impacts get the same dt (until the
/// Hertz time binds), and the sticking speeds of both pull-off rules are below it.
#[test]
fn zone_rule_stops_at_the_adhesion_speed() {
    let p = JkrParams::jkr(1e9, 0.3, 0.05);
    let m = 2000.0 * 4.0 / 3.0 * PI * R1.powi(3);
    let g = PairGeometry::spheres(R1, R1, m, m);
    let (r, m) = (g.r_eff(), g.reduced_mass);
    let va = p.adhesion_speed(r, m);
    let slow = crate::model::ContactModel::Jkr(p).time_step(&g, 0.5 * va);
    assert_relative_eq!(
        slow.contact_time,
        2.0 * p.delta0(r) / va,
        max_relative = 1e-12
    );
    let at = |v: f64| format!("at {v:.4e} m/s");
    assert!(slow.reason.contains(&at(0.5 * va)), "{}", slow.reason);
    for f in [1.0, 3.0, 10.0] {
        let fast = crate::model::ContactModel::Jkr(p).time_step(&g, f * va);
        assert_relative_eq!(fast.contact_time, p.delta0(r) / va, max_relative = 1e-12);
        assert!(fast.reason.contains(&at(va)), "{}", fast.reason);
    }
    for pulloff in [Pulloff::Displacement, Pulloff::Force] {
        let w = crate::model::analytic::jkr_loss(pulloff) * p.fc(r) * p.delta0(r);
        let v_stick = crate::model::analytic::jkr_sticking_velocity(w, m);
        assert!(v_stick < va, "{pulloff:?}");
    }
}

#[test]
fn krijt_state_force_and_potential() {
    let krijt = |tvis, sigma0| JkrParams {
        dissipation: Dissipation::Krijt { tvis, sigma0 },
        ..params()
    };
    let p = krijt(1e-9, 1e3);
    let (r, g) = (reff(), geom());
    let (a0, d0) = (p.a0(r), p.delta0(r));
    let mut h = ContactHistory::default();
    // nothing before the touch; at the touch a starts at a_JKR(0) = (2/3)^(2/3)·a0
    assert_eq!(
        p.normal_force_step(-0.1 * d0, 1.0, &g, 1e-9, &mut h),
        NormalForce::default()
    );
    let f = p.normal_force_step(1e-12 * d0, 0.0, &g, 0.0, &mut h);
    assert_relative_eq!(f.contact_radius, X_TOUCH * a0, max_relative = 1e-12);
    assert_relative_eq!(h.contact_radius, X_TOUCH * a0, max_relative = 1e-12);
    assert_relative_eq!(f.conservative, -8.0 / 9.0 * p.fc(r), max_relative = 1e-6);
    // at equilibrium a the force and the stored energy are the JKR ones
    for d in [-0.5, 0.3, 1.0, 4.0] {
        let mut h = ContactHistory {
            touched: true,
            contact_radius: p.contact_radius(d * d0, r),
            ..Default::default()
        };
        let f = p.normal_force_step(d * d0, 0.0, &g, 1.0, &mut h);
        let j = touched_force(&params(), d * d0);
        assert_relative_eq!(f.conservative, j.conservative, epsilon = 1e-9 * p.fc(r));
        assert_relative_eq!(f.potential, j.potential, epsilon = 1e-9 * p.fc(r) * d0);
    }
    // with a delay, a lags: loading from the touch radius it stays below a_JKR(δ)
    let q = krijt(1e-3, 1e6);
    let mut h = ContactHistory::default();
    q.normal_force_step(1e-12 * d0, 0.0, &g, 0.0, &mut h);
    let f = q.normal_force_step(2.0 * d0, 0.0, &g, 1e-9, &mut h);
    assert!(f.contact_radius > X_TOUCH * a0 && f.contact_radius < p.contact_radius(2.0 * d0, r));
    // then F_E(a, δ) is above the JKR force (a smaller punch), and the viscous force
    // is 2·T_vis·E*/ν²·a·δ̇
    assert!(f.conservative > touched_force(&params(), 2.0 * d0).conservative);
    let moving = q.normal_force_step(2.0 * d0, 0.5, &g, 0.0, &mut h);
    let visc = 2.0 * 1e-3 * q.e_star() / (0.17f64 * 0.17) * moving.contact_radius * 0.5;
    assert_relative_eq!(
        moving.force - moving.conservative,
        visc,
        max_relative = 1e-12
    );
    // breaking resets the state
    q.normal_force_step(-0.9 * d0, -1.0, &g, 1e-9, &mut h);
    assert_eq!(h, ContactHistory::default());
    // validation: the rule and the parameter are named
    let bad = |d: Dissipation| {
        JkrParams {
            dissipation: d,
            ..params()
        }
        .validate()
        .unwrap_err()
    };
    assert_eq!(
        bad(Dissipation::Krijt {
            tvis: -1.0,
            sigma0: 0.0
        })
        .param,
        "tvis"
    );
    assert_eq!(
        bad(Dissipation::Krijt {
            tvis: 1.0,
            sigma0: -1.0
        })
        .param,
        "sigma0"
    );
    let st = |c, b, zeta| Dissipation::Stress {
        tvis0_per_radius: c,
        b,
        zeta,
        sigma0: 0.0,
    };
    assert_eq!(bad(st(-1.0, 6.2, 4.0)).param, "tvis0_per_radius");
    assert_eq!(bad(st(2e-4, f64::NAN, 4.0)).param, "B");
    assert_eq!(bad(st(2e-4, 6.2, 0.0)).param, "zeta");
    let e = JkrParams {
        dissipation: st(2e-4, 6.2, 4.0),
        ..JkrParams::hertz(1e9, 0.3)
    }
    .validate()
    .unwrap_err();
    assert!(
        e.param == "dissipation" && e.message.contains("surface_energy"),
        "{e}"
    );
    let e = JkrParams {
        dissipation: Dissipation::Krijt {
            tvis: 1.0,
            sigma0: 0.0,
        },
        ..JkrParams::jkr(1e9, 0.0, 0.1)
    }
    .validate()
    .unwrap_err();
    assert_eq!(e.param, "poisson");
    // serde names: kind = "krijt" / "stress", B
    let s = JkrParams {
        dissipation: st(2.1e-4, 6.2, 4.0),
        ..params()
    };
    let json = serde_json::to_string(&s).unwrap();
    assert!(
        json.contains("\"kind\":\"stress\"") && json.contains("\"B\":6.2"),
        "{json}"
    );
    assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), s);
}

#[test]
fn validation_names_parameter_and_rule() {
    let bad = |f: fn(&mut JkrParams)| {
        let mut p = params();
        f(&mut p);
        p.validate().unwrap_err()
    };
    assert_eq!(bad(|p| p.youngs = 0.0).param, "youngs");
    assert_eq!(bad(|p| p.youngs = f64::NAN).param, "youngs");
    let e = bad(|p| p.poisson = 0.5);
    assert_eq!(e.param, "poisson");
    assert!(e.message.contains("0.5"));
    assert_eq!(bad(|p| p.poisson = -1.0).param, "poisson");
    assert_eq!(bad(|p| p.surface_energy = -1.0).param, "surface_energy");
    assert_eq!(
        bad(|p| p.dissipation = Dissipation::tsuji(0.0)).param,
        "restitution"
    );
    assert_eq!(
        bad(|p| p.dissipation = Dissipation::tsuji(1.1)).param,
        "restitution"
    );
    let pl = |d, alpha, beta| Dissipation::PowerLaw { d, alpha, beta };
    let mut q = params();
    q.dissipation = pl(-1.0, 3.0, 1.5);
    assert_eq!(q.validate().unwrap_err().param, "D");
    q.dissipation = pl(1.0, -3.0, 1.5);
    assert_eq!(q.validate().unwrap_err().param, "alpha");
    q.dissipation = pl(1.0, 3.0, f64::INFINITY);
    assert_eq!(q.validate().unwrap_err().param, "beta");
    assert_eq!(bad(|p| p.friction = -0.1).param, "friction");
    assert_eq!(
        bad(|p| p.rolling_hysteresis = -0.1).param,
        "rolling_hysteresis"
    );
    let e = bad(|p| {
        p.rolling_hysteresis = 0.3;
        p.surface_energy = 0.0
    });
    assert_eq!(e.param, "rolling_hysteresis");
    assert!(e.message.contains("surface_energy"));
    assert_eq!(bad(|p| p.stiffness_scale = 0.0).param, "stiffness_scale");
    assert!(params().validate().is_ok());
    assert!(JkrParams::hertz(1e9, 0.3).validate().is_ok());
    let e = bad(|p| p.youngs = -1.0);
    assert!(e.to_string().contains("`youngs`"), "{e}");
}

#[test]
fn serde_names() {
    let p = JkrParams {
        dissipation: Dissipation::PowerLaw {
            d: 118.0,
            alpha: 3.0,
            beta: 1.5,
        },
        ..params()
    };
    let json = serde_json::to_string(&p).unwrap();
    assert!(
        json.contains("\"kind\":\"power-law\"") && json.contains("\"D\":118"),
        "{json}"
    );
    assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), p);
    // optional fields default
    let q: JkrParams = serde_json::from_str(
        r#"{"youngs": 1e9, "poisson": 0.3, "surface_energy": 0.1,
            "dissipation": {"kind": "tsuji", "restitution": 0.5}, "pulloff": "force"}"#,
    )
    .unwrap();
    assert_eq!(q.stiffness_scale, 1.0);
    assert_eq!(q.pulloff, Pulloff::Force);
    assert_eq!(q.dissipation, Dissipation::tsuji(0.5));
}
