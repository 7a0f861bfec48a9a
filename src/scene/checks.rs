//! Checks of a whole parsed scene: periodic axes, particle placement and overlaps, and a
//! contact model for every pair of materials that can meet.

use super::hash_grid::{dist2, Grid};
use super::particles::Origin;
use super::toml_reader::{fmt_vec, Res, Src, AXES};
use super::{Domain, ParticleInit, Scene, OVERLAP_TOLERANCE};
use crate::cpu::cells::CellGrid;
use crate::error::PowderError;
use glam::DVec3;
use rayon::prelude::*;

/// Periodic axes: no wall may face one and gravity may not point along one
/// ([`Scene::periodic_conflict`], which scenes built in code meet too).
pub(super) fn check_periodic(src: &Src, scene: &Scene) -> Res<()> {
    match scene.periodic_conflict() {
        Some(why) => Err(src.err(None, why)),
        None => Ok(()),
    }
}

/// `x` and, along each periodic axis where it lies within `reach` of a seam, its images
/// one period over: the places a partner within `reach` of x may be found.
fn periodic_images(x: [f64; 3], reach: f64, d: &Domain) -> Vec<[f64; 3]> {
    let mut images = vec![x];
    for a in 0..3 {
        if !d.periodic[a] {
            continue;
        }
        let period = d.max[a] - d.min[a];
        // (both, where the period is shorter than 2·reach)
        let shifts = [
            (x[a] - d.min[a] < reach).then_some(period),
            (d.max[a] - x[a] < reach).then_some(-period),
        ];
        for shift in shifts.into_iter().flatten() {
            for k in 0..images.len() {
                if images[k][a] == x[a] {
                    let mut image = images[k];
                    image[a] += shift;
                    images.push(image);
                }
            }
        }
    }
    images
}

pub(super) fn check_particles(src: &Src, scene: &Scene, origin: &Origin) -> Res<()> {
    if scene.particles.is_empty() {
        return Err(src.err(
            None,
            "the scene has no particles: the [[particles]] blocks create none (check `count` and `positions`)",
        ));
    }
    let from = |i: usize| format!(" (from [[particles]] #{})", origin[i]);
    let wall = |w: usize| format!("[[wall]] #{}", w + 1);
    placement(scene, &from, &wall).map_err(|why| src.err(None, why))
}

/// Every particle inside the domain (on a periodic axis its centre in [min, max)), and no
/// two particles (appearing at the same time) nor a particle and a wall overlapping by more
/// than [`OVERLAP_TOLERANCE`] of the smaller radius: the first that is not, in words.
/// `from(i)` adds where particle i came from, `wall(w)` names wall w.
pub(super) fn placement(
    scene: &Scene,
    from: &dyn Fn(usize) -> String,
    wall_name: &dyn Fn(usize) -> String,
) -> Result<(), String> {
    let ps = &scene.particles;
    let d = &scene.domain;
    for (i, p) in ps.iter().enumerate() {
        let tol = OVERLAP_TOLERANCE * p.radius;
        for (a, axis) in AXES.iter().enumerate() {
            let x = p.position[a];
            // on a periodic axis the centre must lie in [min, max); the sphere may cross
            let inside = if d.periodic[a] {
                x >= d.min[a] && x < d.max[a]
            } else {
                x - p.radius >= d.min[a] - tol && x + p.radius <= d.max[a] + tol
            };
            if !inside {
                return Err(format!(
                    "particle {i}{} at {} with radius {} is not inside the domain {} to {} on axis {}: {}",
                    from(i),
                    fmt_vec(p.position),
                    crate::error::num(p.radius),
                    fmt_vec(d.min),
                    fmt_vec(d.max),
                    axis,
                    match d.periodic[a] {
                        true => "the axis is periodic: its centre must lie in [min, max) (wrap it by the period)",
                        false => "move it, or enlarge [domain]",
                    }
                ));
            }
        }
    }
    if let Some((j, i, overlap, seam)) = first_pair_overlap(scene) {
        return Err(format!(
            "particles {j}{} at {} and {i}{} at {} overlap by {overlap:.3e} m at the start{}, more than {}% of the smaller radius: move them apart",
            from(j),
            fmt_vec(ps[j].position),
            from(i),
            fmt_vec(ps[i].position),
            if seam { " across the periodic seam" } else { "" },
            OVERLAP_TOLERANCE * 100.0
        ));
    }
    for (w, wall) in scene.walls.iter().enumerate() {
        // (the normal as given: the reader's is a unit vector, one built in code may not be)
        let len = wall.normal.iter().map(|c| c * c).sum::<f64>().sqrt();
        for (i, p) in ps.iter().enumerate() {
            let rel = [
                p.position[0] - wall.point[0],
                p.position[1] - wall.point[1],
                p.position[2] - wall.point[2],
            ];
            let dist =
                (rel[0] * wall.normal[0] + rel[1] * wall.normal[1] + rel[2] * wall.normal[2]) / len;
            let overlap = p.radius - dist;
            if overlap > OVERLAP_TOLERANCE * p.radius {
                return Err(format!(
                    "particle {i}{} at {} with radius {} overlaps {} (point {}, normal {}) by {overlap:.3e} m at the start, more than {}% of its radius: move it to the side the normal points to",
                    from(i),
                    fmt_vec(p.position),
                    p.radius,
                    wall_name(w),
                    fmt_vec(wall.point),
                    fmt_vec(wall.normal),
                    OVERLAP_TOLERANCE * 100.0
                ));
            }
        }
    }
    Ok(())
}

/// The first pair (j, i), j < i, by i and then j, of particles appearing at the same time
/// that overlap by more than [`OVERLAP_TOLERANCE`] of the smaller radius: (j, i, overlap,
/// across a periodic seam). Every particle must lie inside the domain.
fn first_pair_overlap(scene: &Scene) -> Option<(usize, usize, f64, bool)> {
    let ps = &scene.particles;
    let d = &scene.domain;
    let rmax = ps.iter().map(|p| p.radius).fold(0.0, f64::max);
    let (min, max) = (DVec3::from(d.min), DVec3::from(d.max));
    let too_much = |p: &ParticleInit, q: &ParticleInit, overlap: f64| {
        // particles that appear at different times may share a place (pouring)
        q.insert_at == p.insert_at && overlap > OVERLAP_TOLERANCE * p.radius.min(q.radius)
    };
    // the engines' linked cells where they are cut-off wide (O(N), no allocation a cell);
    // a hash grid where the box is too short for them or the particles are clustered
    match CellGrid::periodic(min, max, 2.0 * rmax, ps.len(), d.periodic) {
        Some(mut grid) if grid.width() <= 4.0 * rmax => {
            let pos: Vec<DVec3> = ps.iter().map(|p| DVec3::from(p.position)).collect();
            grid.rebuild(&pos);
            let period = max - min;
            // (in parallel, the first in order: the answer of the serial loop)
            (0..ps.len())
                .into_par_iter()
                .with_min_len(4096)
                .find_map_first(|i| {
                    let mut first: Option<(usize, f64, bool)> = None;
                    grid.for_each_near(pos[i], |j| {
                        if j >= i || first.is_some_and(|f| f.0 < j) {
                            return;
                        }
                        // the nearest image along periodic axes
                        let mut r = pos[i] - pos[j];
                        for a in 0..3 {
                            if d.periodic[a] {
                                r[a] -= period[a] * (r[a] / period[a]).round();
                            }
                        }
                        let overlap = ps[i].radius + ps[j].radius - r.length();
                        if too_much(&ps[i], &ps[j], overlap) {
                            first = Some((j, overlap, r != pos[i] - pos[j]));
                        }
                    });
                    first.map(|(j, overlap, seam)| (j, i, overlap, seam))
                })
        }
        _ => {
            let mut grid = Grid::new(2.0 * rmax);
            for (i, p) in ps.iter().enumerate() {
                // (across a periodic seam the partner is an image: p's images near it too)
                let first = periodic_images(p.position, p.radius + rmax, d)
                    .into_iter()
                    .flat_map(|at| {
                        grid.neighbours(at, p.radius + rmax).filter_map(move |j| {
                            let q = &ps[j];
                            let overlap = p.radius + q.radius - dist2(at, q.position).sqrt();
                            too_much(p, q, overlap).then_some((j, overlap, at != p.position))
                        })
                    })
                    .min_by_key(|&(j, _, _)| j);
                if let Some((j, overlap, seam)) = first {
                    return Some((j, i, overlap, seam));
                }
                grid.insert(i, p.position);
            }
            None
        }
    }
}

/// Which materials particles and walls use: the pairs of materials that can meet.
pub struct MaterialUse {
    /// Material a is some particle's.
    pub particles: Vec<bool>,
    /// Material a is some wall's.
    pub walls: Vec<bool>,
}

impl MaterialUse {
    /// The materials `scene`'s particles and walls use.
    pub fn of(scene: &Scene) -> Self {
        let n = scene.materials.len();
        let (mut particles, mut walls) = (vec![false; n], vec![false; n]);
        for p in &scene.particles {
            particles[p.material] = true;
        }
        for w in &scene.walls {
            walls[w.material] = true;
        }
        Self { particles, walls }
    }

    /// Whether materials a and b can touch: particles of both, or a wall of one and
    /// particles of the other.
    pub fn meet(&self, a: usize, b: usize) -> bool {
        let (p, w) = (&self.particles, &self.walls);
        (p[a] && (p[b] || w[b])) || (w[a] && p[b])
    }
}

/// Every pair of materials that can meet needs a contact model.
pub(super) fn check_pair_models(src: &Src, scene: &Scene) -> Res<()> {
    let n = scene.materials.len();
    let uses = MaterialUse::of(scene);
    let used = &uses.particles;
    for a in 0..n {
        for b in a..n {
            if uses.meet(a, b) {
                if let Err(PowderError::Scene(msg)) = scene.pair_model(a, b) {
                    let what = if used[a] && used[b] {
                        "particles of both materials"
                    } else {
                        "a wall and particles of these materials"
                    };
                    return Err(src.err(None, format!("{msg} ({what} can touch)")));
                }
            }
        }
    }
    Ok(())
}
