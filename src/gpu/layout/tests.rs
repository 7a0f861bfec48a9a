//! The host layouts against naga's and the position encoding's precision.

use super::*;
use crate::gpu::composition::Keeps;
use crate::gpu::shaders;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::mem::size_of;

fn norm_f32(d: [f32; 3]) -> f32 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

#[test]
fn gpu_layout_round_trip_error_is_below_h_2_pow_minus_23() {
    let mut rng = Pcg64::seed_from_u64(7);
    for &h in &[2.2, 1e-4, 3.0e-6, 0.5, 17.0] {
        let origin = DVec3::new(-3.5, 12.25, -1e3) * h;
        let bound = h * 2f64.powi(-23);
        let width = 1e4 * h;
        let mut worst = 0f64;
        for k in 0..20_000 {
            let mut p = origin + DVec3::new(rng.random(), rng.random(), rng.random()) * width;
            if k % 100 == 0 {
                // Exactly on a cell face, and just below one.
                let c = (rng.random::<f64>() * 1e4).floor();
                p.x = origin.x + c * h;
                p.y = origin.y + c * h - h * 1e-12;
            }
            let (cell, off) = encode(p, origin, h);
            for o in &off[..3] {
                assert!(
                    *o >= 0.0 && (*o as f64) < h,
                    "offset {o} outside [0, {h}) for {p}"
                );
            }
            let q = decode(cell, off, origin, h);
            worst = worst.max((q - p).abs().max_element());
        }
        assert!(
            worst <= bound,
            "h = {h}: worst round-trip error {worst:e} > h 2^-23 = {bound:e}"
        );
    }
}

/// Worst relative overlap errors over random pairs of touching spheres (radius 1,
/// overlap 1e-3) near cell 1e4 of a grid of width h = 2.2: (f32 cell/offset
/// arithmetic vs the stored state in f64, stored state vs the true overlap, f32
/// cell/offset vs the true overlap, naive absolute f32 vs the true overlap).
fn overlap_errors(axis_aligned: bool) -> [f64; 4] {
    // The kernels' h is f32: encode with exactly that value (see gpu_cell_width).
    let h = gpu_cell_width(2.2);
    let h32 = h as f32;
    let origin = DVec3::ZERO;
    let (r, overlap) = (1.0f64, 1e-3f64);
    let mut rng = Pcg64::seed_from_u64(11);
    let mut worst = [0f64; 4];
    for k in 0..20_000 {
        let centre = DVec3::new(rng.random(), rng.random(), rng.random()) * 100.0 * h
            + DVec3::splat(1e4 * h);
        let dir = if axis_aligned {
            let mut v = DVec3::ZERO;
            v[k % 3] = if (k / 3) % 2 == 0 { 1.0 } else { -1.0 };
            v
        } else {
            loop {
                let v = DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - DVec3::ONE;
                if v.length() > 0.1 && v.length() < 1.0 {
                    break v.normalize();
                }
            }
        };
        let pi = centre;
        let pj = centre + dir * (2.0 * r - overlap);
        let (ci, oi) = encode(pi, origin, h);
        let (cj, oj) = encode(pj, origin, h);
        assert!(ci[0] >= 10_000 && ci[0] < 10_200);
        // GPU way: cell and offset differences in f32.
        let gpu = (2.0 * r as f32 - norm_f32(separation_f32(ci, oi, cj, oj, h32))) as f64;
        // The stored state evaluated in f64.
        let stored = 2.0 * r - (decode(ci, oi, origin, h) - decode(cj, oj, origin, h)).length();
        // Naive: absolute f32 positions.
        let naive = (2.0 * r as f32 - (pi.as_vec3() - pj.as_vec3()).length()) as f64;
        let errs = [
            (gpu - stored).abs(),
            (stored - overlap).abs(),
            (gpu - overlap).abs(),
            (naive - overlap).abs(),
        ];
        for (w, e) in worst.iter_mut().zip(errs) {
            *w = w.max(e / overlap);
        }
    }
    worst
}

#[test]
fn gpu_layout_far_from_origin_overlap_survives_f32() {
    let (h, overlap) = (gpu_cell_width(2.2), 1e-3);
    // Storing a position rounds each axis by at most h 2^-24 (half an f32 ulp of the
    // offset); that moves a pair's distance by at most 2 h 2^-24 along an axis and
    // 2 sqrt(3) h 2^-24 in general, i.e. 2.6e-4 / 4.5e-4 of this overlap, anywhere in
    // the domain (it is the position resolution, not a loss far from the origin).
    let storage_axis = 2.0 * h * 2f64.powi(-24) / overlap;
    let storage_any = 3f64.sqrt() * storage_axis;

    // Head-on contacts along the axes: the f32 arithmetic on cells and offsets
    // reproduces the stored state's overlap to < 1e-4.
    let [arith, stored, total, naive] = overlap_errors(true);
    eprintln!(
        "axis-aligned, overlap 1e-3 near cell 1e4: relative error of cell/offset f32 \
         {arith:.2e} vs the stored state, {total:.2e} vs the true positions \
         (storage {stored:.2e}); naive absolute f32 {naive:.2e}"
    );
    assert!(arith < 1e-4, "cell/offset f32 arithmetic error {arith:e}");
    assert!(stored <= storage_axis, "storage error {stored:e}");
    assert!(
        total < 1e-4 + storage_axis,
        "cell/offset f32 total error {total:e}"
    );
    // Absolute f32 positions near 2.2e4 are spaced 2^-9 ~ 2e-3 apart: the overlap
    // is lost entirely.
    assert!(
        naive > 0.1,
        "naive f32 unexpectedly kept the overlap: {naive:e}"
    );

    // Arbitrary directions: forming |d| ~ 2 in f32 (three components, squares, sum,
    // sqrt) costs about one f32 ulp of 2 (2.4e-7), i.e. ~2e-4 of this overlap.
    // Still three to four orders of magnitude better than absolute f32.
    let [arith, stored, total, naive] = overlap_errors(false);
    eprintln!(
        "any direction, overlap 1e-3 near cell 1e4: relative error of cell/offset f32 \
         {arith:.2e} vs the stored state, {total:.2e} vs the true positions \
         (storage {stored:.2e}); naive absolute f32 {naive:.2e}"
    );
    assert!(arith < 3e-4, "cell/offset f32 arithmetic error {arith:e}");
    assert!(stored <= storage_any, "storage error {stored:e}");
    assert!(
        total < 3e-4 + storage_any,
        "cell/offset f32 total error {total:e}"
    );
    assert!(
        naive > 0.1,
        "naive f32 unexpectedly kept the overlap: {naive:e}"
    );
}

#[test]
fn gpu_layout_touching_spheres_at_cell_1e4() {
    // The worked example: radius 1, h = 2.2 (as f32), centres 1.999 apart along x
    // around cell 1e4 (x ~ 2.2e4). Particle i is stored exactly, j to 1.5e-8.
    let h = gpu_cell_width(2.2);
    let origin = DVec3::ZERO;
    let pi = DVec3::new(10_000.0 * h + 0.625, 10_000.0 * h + 1.0, 10_000.0 * h + 1.0);
    let pj = pi + DVec3::new(1.999, 0.0, 0.0);
    let (ci, oi) = encode(pi, origin, h);
    let (cj, oj) = encode(pj, origin, h);
    assert_eq!(ci[0], 10_000);
    assert_eq!(cj[0], 10_001);
    let gpu = 2.0 - norm_f32(separation_f32(cj, oj, ci, oi, h as f32)) as f64;
    assert!(
        ((gpu - 1e-3) / 1e-3).abs() < 1e-4,
        "cell/offset overlap {gpu:e}"
    );
    let naive = 2.0 - (pj.as_vec3() - pi.as_vec3()).length() as f64;
    assert!(
        ((naive - 1e-3) / 1e-3).abs() > 0.1,
        "naive overlap {naive:e}"
    );
}

#[test]
fn gpu_layout_packed_position_carries_material_and_radius() {
    let p = PackedPosition::new(DVec3::new(1.0, -2.0, 3.5), DVec3::splat(-4.0), 0.75, 3, 0.3);
    assert_eq!(p.material(), 3);
    assert_eq!(p.radius(), 0.3f32);
    assert!((p.position(DVec3::splat(-4.0), 0.75) - DVec3::new(1.0, -2.0, 3.5)).length() < 1e-6);
    assert_eq!(size_of::<PackedPosition>(), 32);
    assert_eq!(bytemuck::bytes_of(&p).len(), 32);
}

/// Size and member offsets of a WGSL struct as naga lays it out.
fn wgsl_struct(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                return (
                    *span,
                    members
                        .iter()
                        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                        .collect(),
                );
            }
        }
    }
    panic!("struct {name} not found in the WGSL module");
}

/// Every struct the host shares with the kernels has, in its generated WGSL, naga's
/// layout of the Rust struct: the same size and each member at the field's offset (a
/// field whose WGSL alignment differs from Rust's fails here).
#[test]
fn gpu_layout_shared_structs_match_naga() {
    for module in [
        shaders::variant("grid").expect("grid variant").source,
        shaders::step_variant().source,
    ] {
        let (module, _) = shaders::validate(&module).unwrap();
        for s in shared_structs() {
            let (size, members) = wgsl_struct(&module, s.name);
            assert_eq!(size as usize, s.size, "{} size", s.name);
            let expect: Vec<(String, u32)> = (s.members.iter())
                .map(|(n, o)| (n.clone(), *o as u32))
                .collect();
            assert_eq!(members, expect, "{}", s.name);
        }
    }
    assert_eq!(size_of::<CellCoord>(), 16);
    assert_eq!(size_of::<CellOffset>(), 16);
}

/// Every constant the host shares with the kernels reads back through naga to the bit.
#[test]
fn gpu_layout_shared_constants_match_naga() {
    let (module, _) = shaders::validate(&shaders::step_variant().source).unwrap();
    let consts = shared_consts();
    assert!(consts.len() >= 25, "{}", consts.len());
    for (name, ty, bits) in consts {
        let (_, c) = (module.constants.iter())
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no constant {name}"));
        let got = match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => (v, "u32"),
            naga::Expression::Literal(naga::Literal::F32(v)) => (v.to_bits(), "f32"),
            naga::Expression::Literal(naga::Literal::I32(v)) => (v as u32, "i32"),
            ref e => panic!("constant {name} is {e:?}"),
        };
        assert_eq!(got, (bits, ty), "{name}");
    }
}

#[test]
fn gpu_layout_pair_row_matches_wgsl() {
    // a scene with every law: the pair row is the tag and each law's block, unpadded
    use crate::gpu::composition::Composition;
    let all = Composition::all()
        .into_iter()
        .max_by_key(|c| c.history_bytes())
        .unwrap();
    let (jkr, _) = shaders::validate(&all.variant(Keeps::ALL[3], true, false).source).unwrap();
    let (wsize, members) = wgsl_struct(&jkr, "PairRow");
    assert_eq!(wsize as usize, all.row_bytes(), "PairRow size");
    let jkr_at = 4 + size_of::<HystereticPair>() as u32;
    let sliding_at = jkr_at + size_of::<JkrPair>() as u32;
    let spring = size_of::<CoulombSpringRow>() as u32;
    assert_eq!(
        members,
        vec![
            ("law".to_string(), 0),
            ("hysteretic".to_string(), 4),
            ("jkr".to_string(), jkr_at),
            ("luding_sliding".to_string(), sliding_at),
            ("luding_rolling".to_string(), sliding_at + spring),
            ("luding_twisting".to_string(), sliding_at + 2 * spring),
        ]
    );
}

/// The stored history of each composition is as large as the host allocates
/// (`Composition::history_bytes`): `struct Hist` in naga's layout, and the history
/// fields of the entries (pairs' and walls') and the new lists.
#[test]
fn gpu_layout_history_strides_match_wgsl() {
    for kind in crate::gpu::composition::Composition::all() {
        let (module, _) =
            shaders::validate(&kind.variant(Keeps::ALL[3], false, false).source).unwrap();
        let (_, hist) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Hist"))
            .unwrap_or_else(|| panic!("{}: no Hist", kind.name()));
        assert_eq!(
            hist.inner.size(module.to_ctx()) as u64,
            kind.history_bytes(),
            "{}",
            kind.name()
        );
        let records = kind.records(Keeps::ALL[3]);
        for (r, name) in records.iter().zip(["hist", "new_hist"]) {
            let (_, words) = r.place(name).expect("a history field");
            assert_eq!(4 * words, kind.history_bytes(), "{}: {name}", kind.name());
        }
    }
}
