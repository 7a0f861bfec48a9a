//! Checks of a whole parsed scene: periodic axes, particle placement and overlaps, and a
//! contact model for every pair of materials that can meet.

use super::hash_grid::{dist2, Grid};
use super::particles::Origin;
use super::toml_reader::{fmt_vec, Res, Src, AXES};
use super::{Domain, Scene, OVERLAP_TOLERANCE};
use crate::error::PowderError;

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
    let ps = &scene.particles;
    if ps.is_empty() {
        return Err(src.err(
            None,
            "the scene has no particles: the [[particles]] blocks create none (check `count` and `positions`)",
        ));
    }
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
                return Err(src.err(
                    None,
                    format!(
                        "particle {i} (from [[particles]] #{}) at {} with radius {} is not inside the domain {} to {} on axis {}: move it, or enlarge [domain]",
                        origin[i],
                        fmt_vec(p.position),
                        p.radius,
                        fmt_vec(d.min),
                        fmt_vec(d.max),
                        axis
                    ),
                ));
            }
        }
    }
    let rmax = ps.iter().map(|p| p.radius).fold(0.0, f64::max);
    let mut grid = Grid::new(2.0 * rmax);
    for (i, p) in ps.iter().enumerate() {
        // (across a periodic seam the partner is an image: p's images near the seam too)
        let first = periodic_images(p.position, p.radius + rmax, d)
            .into_iter()
            .flat_map(|at| {
                grid.neighbours(at, p.radius + rmax).filter_map(move |j| {
                    let q = &ps[j];
                    let overlap = p.radius + q.radius - dist2(at, q.position).sqrt();
                    // particles that appear at different times may share a place (pouring)
                    (q.insert_at == p.insert_at
                        && overlap > OVERLAP_TOLERANCE * p.radius.min(q.radius))
                    .then_some((j, overlap, at != p.position))
                })
            })
            .min_by_key(|&(j, _, _)| j);
        if let Some((j, overlap, seam)) = first {
            let q = &ps[j];
            return Err(src.err(
                None,
                format!(
                    "particles {j} (from [[particles]] #{}, at {}) and {i} (from [[particles]] #{}, at {}) overlap by {overlap:.3e} m at the start{}, more than {}% of the smaller radius: move them apart",
                    origin[j],
                    fmt_vec(q.position),
                    origin[i],
                    fmt_vec(p.position),
                    if seam { " across the periodic seam" } else { "" },
                    OVERLAP_TOLERANCE * 100.0
                ),
            ));
        }
        grid.insert(i, p.position);
    }
    for (w, wall) in scene.walls.iter().enumerate() {
        for (i, p) in ps.iter().enumerate() {
            let rel = [
                p.position[0] - wall.point[0],
                p.position[1] - wall.point[1],
                p.position[2] - wall.point[2],
            ];
            let dist = rel[0] * wall.normal[0] + rel[1] * wall.normal[1] + rel[2] * wall.normal[2];
            let overlap = p.radius - dist;
            if overlap > OVERLAP_TOLERANCE * p.radius {
                return Err(src.err(
                    None,
                    format!(
                        "particle {i} (from [[particles]] #{}) at {} with radius {} overlaps [[wall]] #{} (point {}, normal {}) by {overlap:.3e} m at the start, more than {}% of its radius: move it to the side the normal points to",
                        origin[i],
                        fmt_vec(p.position),
                        p.radius,
                        w + 1,
                        fmt_vec(wall.point),
                        fmt_vec(wall.normal),
                        OVERLAP_TOLERANCE * 100.0
                    ),
                ));
            }
        }
    }
    Ok(())
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
