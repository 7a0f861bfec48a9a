//! Temporary diagnostics for the hardware run (not committed).
mod common;
use common::gpu;
use powder::bench::{packing, Case};
use powder::gpu::GpuEngine;

fn words(s: &powder::gpu::GpuState) -> [Vec<f64>; 3] {
    let f = |v: &[glam::DVec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>();
    [f(&s.positions), f(&s.velocities), f(&s.angular_velocities)]
}

fn diff(a: &powder::gpu::GpuState, b: &powder::gpu::GpuState) -> String {
    let (wa, wb) = (words(a), words(b));
    let mut out = String::new();
    for (k, name) in ["pos", "vel", "omega"].iter().enumerate() {
        let n = wa[k]
            .iter()
            .zip(&wb[k])
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        let m = wa[k]
            .iter()
            .zip(&wb[k])
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let first = wa[k]
            .iter()
            .zip(&wb[k])
            .position(|(x, y)| x.to_bits() != y.to_bits());
        out += &format!(" {name}: {n} differ (max {m:.2e}, first {first:?})");
    }
    out
}

#[test]
fn diag_boundaries() {
    for (name, case) in [("jkr", Case::Jkr), ("hysteretic", Case::Hysteretic)] {
        let scene = packing(case, 600, 1.0, 3).unwrap();
        let mut e7 = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
        let mut e7b = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
        let mut e64 = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
        let mut e1 = GpuEngine::new(&scene, gpu().unwrap()).unwrap();
        eprintln!("{name}: variant {}", e7.variant_name());
        let (mut det, mut bnd, mut one) = (None, None, None);
        for round in 1..=4u64 {
            // 448 = 7 * 64 steps
            for _ in 0..64 {
                e7.run_steps(7).unwrap();
                e7b.run_steps(7).unwrap();
            }
            e64.run_steps(448).unwrap();
            if one.is_none() {
                for _ in 0..448 {
                    e1.run_steps(1).unwrap();
                }
            }
            let (a, b, c) = (
                e7.state().unwrap(),
                e7b.state().unwrap(),
                e64.state().unwrap(),
            );
            let step = round * 448;
            if det.is_none() && words(&a) != words(&b) {
                eprintln!("{name}: 7 vs 7 differ at {step}:{}", diff(&a, &b));
                det = Some(step);
            }
            if bnd.is_none() && words(&a) != words(&c) {
                eprintln!("{name}: 7 vs 448 differ at {step}:{}", diff(&a, &c));
                bnd = Some(step);
            }
            if one.is_none() {
                let d = e1.state().unwrap();
                if words(&c) != words(&d) {
                    eprintln!("{name}: 1 vs 448 differ at {step}:{}", diff(&c, &d));
                    one = Some(step);
                }
            }
        }
        eprintln!("{name}: determinism {det:?}, 7 vs 448 {bnd:?}, 1 vs 448 {one:?}");
    }
}
