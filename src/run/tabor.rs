//! The Tabor parameter of every JKR pair of materials of a scene (paper 002 eq. 1), which
//! a run reports.

use super::*;

/// The Tabor parameter λT (paper 002 eq. 1) of one JKR pair of materials of a scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TaborPair {
    /// The two material names; for a wall pair the wall's material comes first.
    pub materials: [String; 2],
    /// A wall and a particle (the plane has infinite radius).
    pub wall: bool,
    /// R* of the pair's smallest particles (the smallest radius of each material; a
    /// particle's own radius against a wall), m: λT ∝ R*^(1/3), so this is the pair's
    /// lowest λT.
    pub r_eff: f64,
    /// D_min of eq. 1, m.
    pub d_min: f64,
    /// λT = (4R*γ²/(E*²D_min³))^(1/3), from the materials' own E, ν, γ.
    pub tabor: f64,
    /// Whether λT is in the JKR range λT > 3.
    pub jkr_range: bool,
}

impl TaborPair {
    /// The pair for people: `a`-`b`, or wall `w`-`b`.
    pub fn label(&self) -> String {
        let [a, b] = &self.materials;
        if self.wall {
            format!("wall `{a}`-`{b}`")
        } else {
            format!("`{a}`-`{b}`")
        }
    }

    /// The warning when λT is below the JKR range, naming the pair.
    pub fn warning(&self) -> Option<String> {
        let [a, b] = &self.materials;
        let what = if self.wall {
            "the wall-particle pair"
        } else {
            "the material pair"
        };
        crate::model::analytic::tabor_warning(
            &format!("{what} `{a}`-`{b}` (R* = {:.4e})", self.r_eff),
            self.tabor,
            self.d_min,
        )
    }
}

/// The Tabor parameter of each JKR pair (surface energy > 0) of materials that can meet in
/// `scene`: particle pairs (the same material only with two particles of it) and wall–
/// particle pairs, with R* of the smallest particles of each material and D_min `d_min`.
pub fn tabor_pairs(scene: &Scene, d_min: f64) -> Vec<TaborPair> {
    use crate::model::{analytic, ContactModel};
    let n = scene.materials.len();
    let (mut r_min, mut count) = (vec![f64::INFINITY; n], vec![0usize; n]);
    for p in &scene.particles {
        r_min[p.material] = r_min[p.material].min(p.radius);
        count[p.material] += 1;
    }
    let entry = |a: usize, b: usize, wall: bool, r_eff: f64| match scene.pair_model(a, b) {
        Ok(ContactModel::Jkr(p)) if p.surface_energy > 0.0 => {
            let tabor = analytic::jkr_tabor(&p, r_eff, d_min);
            Some(TaborPair {
                materials: [a, b].map(|m| scene.materials[m].name.clone()),
                wall,
                r_eff,
                d_min,
                tabor,
                jkr_range: tabor > analytic::TABOR_JKR_MIN,
            })
        }
        _ => None,
    };
    let mut pairs = Vec::new();
    for a in 0..n {
        for b in a..n {
            if count[a] > 0 && count[b] > 0 && (a != b || count[a] > 1) {
                let r_eff = r_min[a] * r_min[b] / (r_min[a] + r_min[b]);
                pairs.extend(entry(a, b, false, r_eff));
            }
        }
    }
    let mut wall_materials: Vec<usize> = scene.walls.iter().map(|w| w.material).collect();
    wall_materials.sort_unstable();
    wall_materials.dedup();
    for w in wall_materials {
        for b in (0..n).filter(|&b| count[b] > 0) {
            pairs.extend(entry(w, b, true, r_min[b]));
        }
    }
    pairs
}
