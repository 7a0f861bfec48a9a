//! The compositions' own tests: what a scene composes, the declared layouts against the
//! WGSL, the pair rows' sizes.

use super::*;
use crate::model::history::HostField;
use crate::model::{Dissipation, JkrParams, LsdParams, Pulloff};
use glam::DVec3;

fn jkr(friction: f64, rolling: f64, dissipation: Dissipation) -> ContactModel {
    ContactModel::Jkr(JkrParams {
        youngs: 1e8,
        poisson: 0.3,
        surface_energy: 0.1,
        dissipation,
        friction,
        rolling_hysteresis: rolling,
        pulloff: Pulloff::Displacement,
        stiffness_scale: 1.0,
        luding: Default::default(),
    })
}

fn lsd() -> ContactModel {
    ContactModel::Lsd(LsdParams {
        k: 1.0,
        gamma0: 0.0,
        luding: Default::default(),
    })
}

#[test]
fn a_scene_composes_only_what_its_pairs_use() {
    let c = Composition::of(&[lsd()]);
    assert_eq!(c.name(), "step_hysteretic");
    assert!(!c.rotation());
    assert_eq!(c.history_bytes(), 4);
    let c = Composition::of(&[jkr(0.3, 0.0, Dissipation::None), lsd()]);
    assert_eq!(c.name(), "step_hysteretic+jkr+mindlin");
    assert!(c.rotation());
    // delta_max word, touched flag, spring
    assert_eq!(c.history_bytes(), 4 * (1 + 1 + 3));
    let krijt = Dissipation::Krijt {
        tvis: 1e-6,
        sigma0: 0.0,
    };
    let c = Composition::of(&[jkr(0.0, 0.5, krijt), jkr(0.0, 0.0, Dissipation::None)]);
    assert_eq!(c.name(), "step_jkr+krijt+jkr_rolling");
    assert!(!c.interface().contains("mindlin_apply"));
    assert!(!c
        .variant(Keeps::default(), false, false)
        .source
        .contains("fn mindlin_apply"));
}

#[test]
fn the_host_decodes_and_mirrors_the_declared_layout() {
    let c = Composition::of(&[lsd(), jkr(0.3, 0.5, Dissipation::None)]);
    // hyst_state (touched, delta_max 2), touched, spring, xi
    let words: [f32; 8] = [-2.0, 1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
    let h = c.decode_history(bytemuck::cast_slice(&words));
    assert_eq!(h.delta_max, 2.0);
    assert!(h.touched);
    assert_eq!(h.tangential, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(h.rolling, DVec3::new(4.0, 5.0, 6.0));
    let m = c.mirror_history(h);
    assert_eq!(m.tangential, -h.tangential);
    assert_eq!(m.rolling, h.rolling);
    assert_eq!(m.delta_max, h.delta_max);
}

/// Each sub-model's WGSL works with the history fields its Rust module declares, and
/// with no field it does not declare (through `History`).
#[test]
fn every_declared_history_field_is_the_one_its_wgsl_uses() {
    let declared: Vec<(&str, &[HistoryField])> = LAWS
        .iter()
        .map(|l| (l.source, l.history))
        .chain(SUB_MODELS.iter().map(|s| (s.source, s.history)))
        .collect();
    let all: Vec<&str> = declared
        .iter()
        .flat_map(|(_, h)| h.iter().map(|f| f.name))
        .collect();
    for (source, fields) in &declared {
        for f in fields.iter() {
            assert!(
                source.contains(&format!("(*h).{}", f.name)),
                "{} not used by its WGSL",
                f.name
            );
        }
        for name in &all {
            if !fields.iter().any(|f| f.name == *name) {
                assert!(
                    !source.contains(&format!("(*h).{name}")),
                    "a WGSL file uses {name}, which it does not declare"
                );
            }
        }
    }
    // the host maps each field somewhere
    assert!(declared
        .iter()
        .flat_map(|(_, h)| h.iter())
        .all(|f| f.host != HostField::DeltaMaxTouched || f.shape == Shape::Word));
}

/// Sub-models that keep the same quantity share its field (a pair uses one of them), so
/// their declarations must agree on everything but the comment.
#[test]
fn fields_that_share_a_name_agree() {
    let all: Vec<&HistoryField> = LAWS
        .iter()
        .flat_map(|l| l.history)
        .chain(SUB_MODELS.iter().flat_map(|s| s.history))
        .collect();
    for a in &all {
        for b in all.iter().filter(|b| b.name == a.name) {
            assert_eq!(
                (a.shape, a.mirror, a.host),
                (b.shape, b.mirror, b.host),
                "{}",
                a.name
            );
        }
    }
}

/// Luding's three laws on the hysteretic law: their blocks follow the law's in the row
/// (a pair without one has it zero, which is off), their springs in the history.
#[test]
fn luding_friction_adds_its_blocks_and_springs() {
    use crate::model::{CoulombSpring, LudingFriction};
    let spring = |mu: f64| CoulombSpring {
        mu_s: mu,
        mu_d: mu,
        k: 2.0,
        gamma: 0.0,
    };
    let rough = |rolling: f64| {
        ContactModel::Lsd(LsdParams {
            luding: LudingFriction {
                sliding: spring(0.5),
                rolling: spring(rolling),
                twisting: spring(0.1),
            },
            ..LsdParams::new(1.0, 0.0)
        })
    };
    let c = Composition::of(&[rough(0.1), rough(0.0)]);
    assert_eq!(
        c.name(),
        "step_hysteretic+luding_sliding+luding_rolling+luding_twisting"
    );
    assert!(c.rotation());
    // hyst_state, spring, slipping, xi, twist
    assert_eq!(c.history_bytes(), 4 * (1 + 3 + 1 + 3 + 1));
    let hyst = std::mem::size_of::<HystereticPair>();
    assert_eq!(c.row_bytes(), hyst + 16 + 16 + 20);
    let row = c.pair_row(&rough(0.0));
    let rolling: &[f32] = bytemuck::cast_slice(&row[hyst + 16..hyst + 32]);
    assert_eq!(rolling, &[0.0; 4]);
    let sliding: &[f32] = bytemuck::cast_slice(&row[hyst..hyst + 16]);
    assert_eq!(sliding, &[0.5, 0.5, 2.0, 0.0]);
    let words: [f32; 9] = [1.0, 1.0, 2.0, 3.0, 1.0, 4.0, 5.0, 6.0, -7.0];
    let h = c.decode_history(bytemuck::cast_slice(&words));
    assert_eq!((h.twist, h.slipping), (-7.0, true));
    let m = c.mirror_history(h);
    assert_eq!(
        (m.tangential, m.rolling, m.twist, m.slipping),
        (-h.tangential, h.rolling, h.twist, true)
    );
    // JKR twisting: the stiffness per contact radius where k_o is not given
    let mut j = jkr(0.0, 0.0, Dissipation::None);
    if let ContactModel::Jkr(p) = &mut j {
        p.luding.twisting = CoulombSpring {
            k: 0.0,
            ..spring(0.1)
        };
    }
    let c = Composition::of(&[j]);
    assert_eq!(c.name(), "step_jkr+luding_twisting");
    let row = c.pair_row(&j);
    let twisting: &[f32] = bytemuck::cast_slice(&row[row.len() - 20..]);
    let ContactModel::Jkr(p) = j else {
        unreachable!()
    };
    assert_eq!(twisting[4], (0.4 * 8.0 * p.g_star()) as f32);
}

#[test]
fn pair_rows_have_the_declared_size() {
    let models = [lsd(), jkr(0.3, 0.5, Dissipation::tsuji(0.5))];
    for c in Composition::all() {
        for m in &models {
            if c.laws.contains(&law_of(m)) {
                assert_eq!(c.pair_row(m).len(), c.row_bytes(), "{}", c.name());
            }
        }
    }
    let c = Composition::of(&models);
    let row = c.pair_row(&models[1]);
    assert_eq!(&row[..4], &1u32.to_le_bytes(), "the JKR law's tag");
}
