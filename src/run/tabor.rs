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
    /// The equilibrium contact radius over R*, a0/R* (as simulated, after the stiffness
    /// scale): JKR assumes it small ([`JKR_SMALL_CONTACT_MAX`](crate::model::analytic::JKR_SMALL_CONTACT_MAX)).
    pub a0_over_r: f64,
    /// The warning on a0/R*, if any.
    #[serde(skip)]
    small_contact: Option<String>,
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

    /// The warnings on the pair's contact theory, naming the pair: λT below the JKR range,
    /// a0 beyond the small-contact range.
    pub fn warnings(&self) -> Vec<String> {
        let tabor = crate::model::analytic::tabor_warning(&self.who(), self.tabor, self.d_min);
        tabor
            .into_iter()
            .chain(self.small_contact.clone())
            .collect()
    }

    /// The pair in a warning.
    fn who(&self) -> String {
        who(&self.materials, self.wall, self.r_eff)
    }
}

fn who([a, b]: &[String; 2], wall: bool, r_eff: f64) -> String {
    let what = if wall {
        "the wall-particle pair"
    } else {
        "the material pair"
    };
    format!("{what} `{a}`-`{b}` (R* = {r_eff:.4e})")
}

/// The Tabor parameter of each JKR pair (surface energy > 0) of materials that can meet in
/// `scene`: particle pairs (the same material only with two particles of it) and wall–
/// particle pairs, with R* of the smallest particles of each material and D_min `d_min`.
pub fn tabor_pairs(scene: &Scene, d_min: f64) -> Vec<TaborPair> {
    use crate::model::{analytic, ContactModel};
    let n = scene.materials.len();
    let (mut r_min, mut count) = (vec![f64::INFINITY; n], vec![0usize; n]);
    // (a material index beyond the list is `Scene::validate`'s to refuse: skipped here)
    for p in scene.particles.iter().filter(|p| p.material < n) {
        r_min[p.material] = r_min[p.material].min(p.radius);
        count[p.material] += 1;
    }
    let entry = |a: usize, b: usize, wall: bool, r_eff: f64| match scene.pair_model(a, b) {
        Ok(ContactModel::Jkr(p)) if p.surface_energy > 0.0 => {
            let tabor = analytic::jkr_tabor(&p, r_eff, d_min);
            let materials = [a, b].map(|m| scene.materials[m].name.clone());
            let who = who(&materials, wall, r_eff);
            Some(TaborPair {
                small_contact: analytic::small_contact_warning(&who, &p, r_eff),
                materials,
                wall,
                r_eff,
                d_min,
                tabor,
                jkr_range: tabor > analytic::TABOR_JKR_MIN,
                a0_over_r: p.a0(r_eff) / r_eff,
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
    let mut wall_materials: Vec<usize> = (scene.walls.iter().map(|w| w.material))
        .filter(|&m| m < n)
        .collect();
    wall_materials.sort_unstable();
    wall_materials.dedup();
    for w in wall_materials {
        for b in (0..n).filter(|&b| count[b] > 0) {
            pairs.extend(entry(w, b, true, r_min[b]));
        }
    }
    pairs
}
