//! Who overlaps whom, found on the host from the positions read back: the partner of a
//! particle the GPU's monitor names alone, and a particle poured onto another, named as the
//! cause of a run's failure.

use crate::cpu::engine::minimum_image;
use crate::model::PairGeometry;
use crate::run::simulation::Observation;
use crate::scene::hash_grid::Grid;
use crate::scene::Scene;
use glam::DVec3;

/// When each particle appears, s (0: from the start).
fn insert_at(scene: &Scene, i: usize) -> f64 {
    scene.particles.get(i).map_or(0.0, |p| p.insert_at)
}

/// Particle `i`'s deepest overlap over the pair's a12 with a particle of `partners` or a
/// wall, at the positions `obs` holds (minimum image on periodic axes), as the ratio and
/// "particle i overlaps particle j" (or "wall w"); `None` where it overlaps nothing.
fn deepest_of(
    scene: &Scene,
    obs: &Observation,
    radii: &[f64],
    i: usize,
    partners: impl Iterator<Item = usize>,
) -> Option<(f64, String)> {
    let (x, r) = (*obs.positions.get(i)?, *radii.get(i)?);
    let d = &scene.domain;
    let domain = (DVec3::from_array(d.min), DVec3::from_array(d.max));
    let pairs = partners.filter(|&j| j != i).map(|j| {
        let gap = minimum_image(obs.positions[j] - x, d.periodic, domain);
        // (a12 alone matters: the masses are placeholders)
        let a12 = PairGeometry::spheres(r, radii[j], 1.0, 1.0).a12;
        ((r + radii[j] - gap.length()) / a12, format!("particle {j}"))
    });
    let walls = (scene.walls.iter().zip(&obs.wall_points).enumerate()).map(|(w, (wall, p))| {
        let n = DVec3::from_array(wall.normal).normalize();
        let a12 = PairGeometry::wall(r, 1.0).a12;
        ((r - (x - *p).dot(n)) / a12, format!("wall {w}"))
    });
    let (ratio, partner) = pairs.chain(walls).max_by(|a, b| a.0.total_cmp(&b.0))?;
    (ratio > 0.0).then(|| (ratio, format!("particle {i} overlaps {partner}")))
}

/// The partner (a particle that has `appeared`, or a wall) particle `i` overlaps deepest,
/// for a backend whose monitor names only the particle.
pub(super) fn deepest_partner(
    scene: &Scene,
    obs: &Observation,
    radii: &[f64],
    i: usize,
    appeared: impl Fn(usize) -> bool,
) -> Option<(f64, String)> {
    let partners = (0..obs.positions.len()).filter(|&j| appeared(j));
    deepest_of(scene, obs, radii, i, partners)
}

/// A particle that appeared on top of something (pouring).
pub(super) struct Appeared {
    /// "particle i appeared (insert_at = t s) where something was already: particle i
    /// overlaps particle j (or wall w)".
    pub what: String,
    /// The overlap over the pair's a12.
    pub ratio: f64,
}

/// What to change where particles appear on top of others.
pub(super) const POUR_ADVICE: &str = "the engine does not push particles aside, so a pour's region must have emptied before its next batch appears there: lengthen `batch_interval`, move the region or pour fewer particles a batch (*Pouring* in the README)";

/// Where a particle that appeared (`appeared`, by the engine) in the last few steps of the
/// `steps` taken (pouring) overlaps one that appeared before it, or a wall, by more than
/// `min_ratio` of the pair's a12.
pub(super) fn appeared_inside(
    scene: &Scene,
    obs: &Observation,
    radii: &[f64],
    (steps, dt, appeared): (u64, f64, &dyn Fn(usize) -> bool),
    min_ratio: f64,
) -> Option<Appeared> {
    let n = obs.positions.len().min(radii.len());
    let last_start = steps.saturating_sub(1) as f64 * dt;
    let fresh: Vec<usize> = (0..n)
        .filter(|&i| appeared(i))
        .filter(|&i| insert_at(scene, i) > 0.0 && insert_at(scene, i) > last_start - 3.0 * dt)
        .collect();
    if fresh.is_empty() {
        return None;
    }
    // (the particles that have appeared, in cells as wide as the largest pair's reach, so a
    // large batch costs its size, not its size times the scene's)
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let mut grid = Grid::new(2.0 * r_max);
    for j in (0..n).filter(|&j| appeared(j)) {
        grid.insert(j, obs.positions[j].to_array());
    }
    let periods = scene.periods();
    fresh.into_iter().find_map(|i| {
        let near = grid.near_images(obs.positions[i].to_array(), radii[i] + r_max, periods);
        let earlier = near
            .into_iter()
            .filter(|&j| insert_at(scene, j) < insert_at(scene, i));
        let (ratio, who) = deepest_of(scene, obs, radii, i, earlier)?;
        (ratio > min_ratio).then(|| Appeared {
            what: format!(
                "particle {i} appeared (insert_at = {:e} s) where something was already: {who}",
                insert_at(scene, i)
            ),
            ratio,
        })
    })
}
