//! Luding's sliding, rolling and twisting friction on the GPU (`shaders/contact/luding_*.wgsl`)
//! against the closed forms and the f64 CPU reference: oblique elastic impacts on both
//! branches, packings of hysteretic spheres with all three laws (alone and beside JKR pairs
//! with twisting friction), and a sphere spinning and rolling on a floor.

mod common;
use common::builder::{HALF_COHESIVE, STICKY};
use common::{floor_scene, gpu, law, packing, rough};

use powder::gpu::GpuEngine;
use powder::measure::collide::{collide_on, Backend, CollideSpec};
use powder::measure::compare::{compare, Tolerances};
use powder::model::analytic;
use std::f64::consts::PI;

const R: f64 = 1e-3;
const RHO: f64 = 2000.0;
const G: f64 = 9.81;

/// Elastic oblique impacts on a wall against Luding's closed form, sticking (60°) and
/// sliding (32°, 20°), and against the CPU's e_t. Measured: 9.3e-5 off the closed form
/// (the CPU's discretisation error, 1e-3 allowed as there), 1.4e-6 off the CPU (1e-5).
#[test]
fn oblique_impacts_on_the_gpu_follow_the_closed_form() {
    if gpu().is_none() {
        return;
    }
    let mu = 0.3;
    let model = law(
        "hysteretic",
        &[
            ("k1", 100.0),
            ("kp", 100.0),
            ("kc", 0.0),
            ("phi_f", 0.05),
            ("friction", mu),
        ],
    );
    for angle in [60.0f64, 32.0, 20.0] {
        let spec = CollideSpec {
            wall: true,
            impact_angle: angle,
            ..CollideSpec::head_on(model, R, RHO, 0.1)
        };
        let g = collide_on(&spec, Backend::Gpu).unwrap();
        let c = collide_on(&spec, Backend::Cpu).unwrap();
        assert_eq!(g.backend, "gpu");
        let psi = angle.to_radians();
        let expect = analytic::luding_tangential_restitution(mu, psi.sin(), psi.cos());
        let (eg, ec) = (g.e_tangential.unwrap(), c.e_tangential.unwrap());
        eprintln!("{angle}°: e_t gpu {eg} cpu {ec} closed form {expect}");
        assert!((eg - expect).abs() < 1e-3, "{angle}°: {eg} vs {expect}");
        assert!((eg - ec).abs() < 1e-5, "{angle}°: gpu {eg} vs cpu {ec}");
        assert!((g.e - 1.0).abs() < 3e-3, "elastic normal: {}", g.e);
    }
}

fn report(c: &powder::measure::compare::Comparison) {
    for s in &c.samples {
        eprintln!(
            "step {}: pos {:.2e} vel {:.2e} energy {:.2e} contacts {}/{} history {:.2e} over {}",
            s.step,
            s.position,
            s.velocity,
            s.energy,
            s.contacts_cpu,
            s.contacts_gpu,
            s.history,
            s.history_pairs
        );
    }
}

/// Adhesive elasto-plastic spheres with Luding's sliding (μs > μd), rolling and twisting
/// friction: one pair law and its three sub-models, against the CPU. The thrown spheres'
/// sideways speed makes this box chaotic: f32 and f64 separate by a factor ~2 per 250 steps
/// after the first impacts, with or without friction (3e-5 radii at step 2000, 1e-2 at
/// 4000), so the comparison covers the first 2400 steps (~60 contacts).
#[test]
fn a_packing_with_luding_friction_matches_the_cpu() {
    let scene = packing(rough, "rough");
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(
        g.kind().name(),
        "step_hysteretic+luding_sliding+luding_rolling+luding_twisting"
    );
    assert!(g.rotates());
    drop(g);
    let Some(ctx) = gpu() else { return };
    let c = compare(&scene, ctx, 2400, 600, Tolerances::default()).unwrap();
    report(&c);
    let last = c.samples.last().unwrap();
    assert!(
        last.contacts_cpu > 30 && last.history_pairs > 30,
        "{last:?}"
    );
    assert!(c.passed, "{last:?}");
}

/// JKR spheres with Mindlin friction, rolling resistance and Luding's twisting friction
/// (its stiffness following the contact radius) above the rough hysteretic ones: both laws
/// and five sub-models in one step, against the CPU. The packing is chaotic: the f32
/// rounding's trace grows about tenfold every 1500 steps (position 1.5e-6 at step 2000,
/// 9e-5 at 6000, 3e-4 at 8000 on lavapipe; 1.2e-4 at 6000, 1.3e-3 at 8000 on an H200,
/// whose compiler fuses multiply-adds), so it is compared over 6000 steps.
#[test]
fn jkr_twisting_beside_luding_friction_matches_the_cpu() {
    let twisting = format!("{STICKY}\ntwisting_friction = 0.1");
    let between = format!("{HALF_COHESIVE}\nfriction = 0.3");
    let materials = |b| {
        rough(b)
            .material("sticky", 2000.0, &twisting)
            .interaction(["rough", "sticky"], &between)
    };
    let scene = packing(materials, "sticky");
    let Some(ctx) = gpu() else { return };
    let g = GpuEngine::new(&scene, ctx).unwrap();
    assert_eq!(
        g.kind().name(),
        "step_hysteretic+jkr+mindlin+jkr_rolling+luding_sliding+luding_rolling+luding_twisting"
    );
    drop(g);
    let Some(ctx) = gpu() else { return };
    let c = compare(&scene, ctx, 6000, 2000, Tolerances::default()).unwrap();
    report(&c);
    let last = c.samples.last().unwrap();
    assert!(last.contacts_cpu > 5 && last.history_pairs > 0, "{last:?}");
    assert!(c.passed, "{last:?}");
}

/// A sphere resting on a floor of the elastic law k = 100 N/m (γ0 = `gamma0`) with the
/// friction keys `extra`, starting with velocity `v` and spin `w`, on the GPU.
fn on_floor(extra: &str, gamma0: f64, v: [f64; 3], w: [f64; 3]) -> Option<GpuEngine> {
    let m = RHO * 4.0 / 3.0 * PI * R.powi(3);
    let z = R - m * G / 100.0;
    let keys = format!(
        "model = \"hysteretic\"\nk1 = 100.0\nkp = 100.0\nkc = 0.0\nphi_f = 0.05\ngamma0 = {gamma0:e}\n{extra}"
    );
    let scene = floor_scene(&keys, [R, RHO], [0.0, 0.0, -G], z, v, w);
    let ctx = gpu()?;
    Some(GpuEngine::new(&scene, ctx).unwrap())
}

/// Steps `e` to time `t`; the time reached and the sphere's velocity and spin.
fn run_to(e: &mut GpuEngine, t: f64) -> (f64, glam::DVec3, glam::DVec3) {
    let steps = (t / e.dt()).ceil() as u64 - e.steps;
    e.run_steps(steps).unwrap();
    let s = e.state().unwrap();
    (e.time, s.velocities[0], s.angular_velocities[0])
}

/// Spinning about the floor's normal stops at dω/dt = −(5/2)·μo·ℓ·g/r² with ℓ = 2r, as on
/// the CPU (`tests/friction.rs`, exact there): the twisting law alone, saturated throughout.
/// Measured 3.3e-5 off in f32; 1e-3 allowed.
#[test]
fn spinning_on_a_floor_decelerates_at_five_halves_mu_o_lever_g_on_the_gpu() {
    let mu_o = 0.05;
    let extra = format!("twisting_friction = {mu_o}");
    let Some(mut e) = on_floor(&extra, 0.0, [0.0; 3], [0.0, 0.0, 100.0]) else {
        return;
    };
    assert_eq!(e.kind().name(), "step_hysteretic+luding_twisting");
    let (t1, _, w1) = run_to(&mut e, 0.005);
    let (t2, v2, w2) = run_to(&mut e, 0.03);
    let rate = (w1.z - w2.z) / (t2 - t1);
    let expect = 2.5 * mu_o * 2.0 * R * G / (R * R);
    eprintln!("spin-down {rate} vs {expect} rad/s^2");
    assert!((rate / expect - 1.0).abs() < 1e-3, "{rate} vs {expect}");
    assert!(v2.x.abs() < 1e-9 && w2.x.abs() < 1e-6, "{v2} {w2}");
}

/// Rolling on a floor decelerates at (5/7)·μr·(ℓ/r)·g with ℓ = 2r, the sliding friction
/// keeping it rolling, as on the CPU: sliding and rolling laws together on the device.
/// Measured 3.1e-4 off (3.2e-4 on the CPU: the sliding spring's remaining oscillation);
/// 1e-3 allowed.
#[test]
fn rolling_on_a_floor_decelerates_at_five_sevenths_mu_r_lever_g_on_the_gpu() {
    let mu_r = 0.05;
    let m = RHO * 4.0 / 3.0 * PI * R.powi(3);
    let gamma0 = 0.2 * (100.0 * m).sqrt();
    let extra = format!("friction = 0.5\nrolling_friction = {mu_r}");
    let Some(mut e) = on_floor(&extra, gamma0, [0.05, 0.0, 0.0], [0.0, 0.05 / R, 0.0]) else {
        return;
    };
    assert_eq!(
        e.kind().name(),
        "step_hysteretic+luding_sliding+luding_rolling"
    );
    let (t1, v1, _) = run_to(&mut e, 0.01);
    let (t2, v2, w2) = run_to(&mut e, 0.05);
    let decel = (v1.x - v2.x) / (t2 - t1);
    let expect = 5.0 / 7.0 * mu_r * 2.0 * G;
    eprintln!(
        "deceleration {decel} vs {expect} m/s^2, slip {}",
        v2.x - w2.y * R
    );
    assert!((decel / expect - 1.0).abs() < 1e-3, "{decel} vs {expect}");
    assert!(
        (v2.x - w2.y * R).abs() < 1e-3 * v2.x,
        "slip {}",
        v2.x - w2.y * R
    );
}

/// A saved GPU state restores only into a step of the same layout: sliding-only and
/// rolling-only scenes have buffers of the same names and sizes (4 + 12 bytes of history),
/// but their history words mean different springs.
#[test]
fn a_saved_state_restores_only_into_the_same_contact_layout() {
    let Some(sliding) = on_floor("friction = 0.5", 0.0, [0.01, 0.0, 0.0], [0.0; 3]) else {
        return;
    };
    let Some(mut rolling) = on_floor("rolling_friction = 0.1", 0.0, [0.01, 0.0, 0.0], [0.0; 3])
    else {
        return;
    };
    let saved = sliding.save_state().unwrap();
    let e = rolling
        .restore_state(saved.clone())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("luding_sliding") && e.contains("luding_rolling") && e.contains("history ["),
        "{e}"
    );
    let Some(mut again) = on_floor("friction = 0.5", 0.0, [0.01, 0.0, 0.0], [0.0; 3]) else {
        return;
    };
    again.restore_state(saved).unwrap();
}

/// Paper 002 §5.3 on the GPU: a JKR sphere deposited on a wall under a constant force along
/// it rests below the rolling yield force and rolls above it, as on the CPU
/// (`tests/collide_jkr.rs`), the tangential force a uniform acceleration on both engines.
#[test]
fn a_deposited_sphere_rests_or_rolls_on_the_gpu_as_on_the_cpu() {
    use powder::model::{
        ContactModel, Dissipation, JkrParams, PairGeometry, Pulloff, TsujiStiffness,
    };
    if gpu().is_none() {
        return;
    }
    let (r, rho): (f64, f64) = (1e-6, 2000.0);
    let p = JkrParams {
        friction: 0.3,
        rolling_hysteresis: 0.5,
        dissipation: Dissipation::Tsuji {
            restitution: 0.3,
            stiffness: TsujiStiffness::Hertz,
        },
        pulloff: Pulloff::Zero,
        ..JkrParams::jkr(1e9, 0.3, 0.05)
    };
    let m = rho * 4.0 / 3.0 * PI * r.powi(3);
    let wall = PairGeometry::wall(r, m);
    let f_yield = 4.0 * p.fc(wall.r_eff()) * (p.a0_unscaled(wall.r_eff()) * 0.5 / 12.0) / r;
    let base = CollideSpec {
        wall: true,
        impact_angle: 45.0,
        ..CollideSpec::head_on(ContactModel::Jkr(p), r, rho, 0.05)
    };
    let dt = collide_on(&base, Backend::Cpu).unwrap().dt;
    for (fraction, expect) in [(0.8, "resting"), (1.25, "rolling")] {
        let spec = CollideSpec {
            tangential_force: fraction * f_yield,
            settle: 400.0 * 50.0 * dt,
            ..base.clone()
        };
        let (g, c) = (
            collide_on(&spec, Backend::Gpu).unwrap(),
            collide_on(&spec, Backend::Cpu).unwrap(),
        );
        assert_eq!((g.outcome, c.outcome), (expect, expect), "{fraction}");
        let (sg, sc) = (g.settled_speed.unwrap(), c.settled_speed.unwrap());
        eprintln!("F/F_yield = {fraction}: mean speed gpu {sg:e}, cpu {sc:e} m/s");
        if expect == "rolling" {
            assert!((sg - sc).abs() < 1e-3 * sc, "{sg} {sc}");
        }
    }
}
