//! A scene built in code checked for what the engines rely on: what the scene reader
//! guarantees for a file (every index in range, every number finite and in its range,
//! every contact law valid), so a library user's mistake is an error, not a panic or NaN.

use super::declared::{check, Section};
use super::hash_grid::Grid;
use super::{sphere_mass, DtSetting, Scene, WallPhase};
use crate::cpu::engine::minimum_image;
use crate::error::PowderError;
use glam::DVec3;

fn bad(what: String) -> Result<(), PowderError> {
    Err(PowderError::Scene(format!("scene: {what}")))
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Whether a scene named `name` can name files inside an output folder: non-empty, not
/// `.` or `..`, without `/`, `\\` or control characters.
pub(crate) fn can_name_files(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && !name
            .chars()
            .any(|c| c == '/' || c == '\\' || c.is_control())
}

impl Scene {
    /// Gravity along a periodic axis (particles would fall forever: the gravitational
    /// energy is unbounded) or a wall facing one (it would cut the periodic images).
    pub(super) fn periodic_conflict(&self) -> Option<String> {
        let d = &self.domain;
        for (a, axis) in ["x", "y", "z"]
            .iter()
            .enumerate()
            .filter(|(a, _)| d.periodic[*a])
        {
            if self.gravity[a] != 0.0 {
                return Some(format!(
                    "gravity has a component along the periodic axis {axis} ({:?}): particles would fall forever and the gravitational energy is unbounded; make the axis non-periodic (with walls) or gravity perpendicular to it",
                    self.gravity
                ));
            }
            // (relative to the normal's length: one built in code need not be a unit vector)
            let across = |w: &super::Wall| {
                let len = w.normal.iter().map(|c| c * c).sum::<f64>().sqrt();
                w.normal[a].abs() > 1e-12 * len
            };
            if let Some(w) = self.walls.iter().position(across) {
                return Some(format!(
                    "wall {w} faces the periodic axis {axis} ([[wall]] #{}, normal {:?}): a wall across a periodic axis would cut the periodic images; make the axis non-periodic or remove the wall",
                    w + 1,
                    self.walls[w].normal
                ));
            }
        }
        None
    }

    /// Checks what the engines rely on; the error names the particle, wall, material or
    /// setting. The scene reader's scenes pass; [`crate::setup::Resolved::new`] (every
    /// engine) calls it.
    pub fn validate(&self) -> Result<(), PowderError> {
        self.validate_settings()?;
        let wall = |w: usize| format!("wall {w}");
        super::checks::placement(self, &|_| String::new(), &wall)
            .map_err(|why| PowderError::Scene(format!("scene: {why}")))
    }

    /// [`Self::validate`] but for the particles' placement (inside the domain, clear of each
    /// other and of the walls: an O(N) pass over a grid), for callers whose engine holds the
    /// particles already (the run loop).
    pub fn validate_settings(&self) -> Result<(), PowderError> {
        let n = self.materials.len();
        let d = &self.domain;
        for a in 0..3 {
            if !(d.min[a].is_finite() && d.max[a].is_finite() && d.min[a] < d.max[a]) {
                return bad(format!(
                    "the domain must have finite min < max on every axis, got {:?} to {:?}",
                    d.min, d.max
                ));
            }
        }
        if !finite3(&self.gravity) {
            return bad(format!("gravity must be finite, got {:?}", self.gravity));
        }
        if let Some(why) = self.periodic_conflict() {
            return Err(PowderError::Scene(format!("scene: {why}")));
        }
        // the scalar settings by their declared rules (`declared.rs`)
        let sim = |key: &str, x: f64| check(Section::Simulation, key, x, "[simulation]");
        if let DtSetting::Fixed(dt) = self.dt {
            sim("dt", dt).or_else(bad)?;
        }
        // (∞: until the caller stops, as `collide` does)
        if self.duration.is_nan() || self.duration <= 0.0 {
            return bad(format!("duration must be > 0 s, got {}", self.duration));
        }
        sim("output_every", self.output_every as f64).or_else(bad)?;
        sim("checkpoint_every", self.checkpoint_every as f64).or_else(bad)?;
        sim("impact_velocity", self.impact_velocity).or_else(bad)?;
        if n == 0 {
            return bad("it has no materials".into());
        }
        for (m, material) in self.materials.iter().enumerate() {
            // (names label the warnings, the time step's reason and the summary)
            if material.name.trim().is_empty() {
                return bad(format!("material {m} has an empty name: give each a name"));
            }
            if let Some(j) = self.materials[..m]
                .iter()
                .position(|x| x.name == material.name)
            {
                return bad(format!(
                    "materials {j} and {m} are both named `{}`: names must be unique",
                    material.name
                ));
            }
            let what = format!("material {m} (`{}`)", material.name);
            check(Section::Material, "density", material.density, &what).or_else(bad)?;
            material.model.validate().map_err(|e| {
                PowderError::Scene(format!("scene: material {m} (`{}`): {e}", material.name))
            })?;
        }
        for (k, it) in self.interactions.iter().enumerate() {
            if it.materials.iter().any(|&m| m >= n) {
                return bad(format!(
                    "interaction {k} names materials {:?}, but there are {n}",
                    it.materials
                ));
            }
            it.model
                .validate()
                .map_err(|e| PowderError::Scene(format!("scene: interaction {k}: {e}")))?;
            let [a, b] = it.materials;
            if a == b {
                return bad(format!(
                    "interaction {k} pairs material {a} with itself: a material's own law is its model; an interaction is between two different materials"
                ));
            }
            if let Some(j) = (self.interactions[..k].iter())
                .position(|x| x.materials == [a, b] || x.materials == [b, a])
            {
                return bad(format!(
                    "interactions {j} and {k} both set materials {a} and {b}: give one"
                ));
            }
        }
        for (w, wall) in self.walls.iter().enumerate() {
            let len2: f64 = wall.normal.iter().map(|c| c * c).sum();
            if !(finite3(&wall.point) && finite3(&wall.normal) && len2 > 0.0 && len2.is_finite()) {
                return bad(format!(
                    "wall {w} needs a finite point and a finite non-zero normal, got {:?} and {:?}",
                    wall.point, wall.normal
                ));
            }
            if wall.material >= n {
                return bad(format!(
                    "wall {w} has material {}, but there are {n}",
                    wall.material
                ));
            }
            if wall.motion.phases.windows(2).any(|p| p[1].0 <= p[0].0) {
                return bad(format!(
                    "wall {w}: its phases must start at increasing times, got {:?}",
                    wall.motion.phases.iter().map(|p| p.0).collect::<Vec<_>>()
                ));
            }
            for (from, phase) in &wall.motion.phases {
                let what = format!("wall {w}, the phase from t = {from} s");
                check(Section::Phase, "from", *from, &what).or_else(bad)?;
                match *phase {
                    WallPhase::Rest => {}
                    WallPhase::Velocity(v) if finite3(&v) => {}
                    WallPhase::Velocity(v) => {
                        return bad(format!("{what}: its velocity must be finite, got {v:?}"))
                    }
                    WallPhase::Servo {
                        force,
                        gain,
                        max_speed,
                    } => {
                        let servo = |key: &str, x: f64| check(Section::Motion, key, x, &what);
                        servo("servo_force", force).or_else(bad)?;
                        servo("servo_gain", gain).or_else(bad)?;
                        servo("servo_max_speed", max_speed).or_else(bad)?;
                    }
                }
            }
        }
        if self.particles.is_empty() {
            return bad("it has no particles".into());
        }
        for (i, p) in self.particles.iter().enumerate() {
            if p.material >= n {
                return bad(format!(
                    "particle {i} has material {}, but there are {n}",
                    p.material
                ));
            }
            let what = format!("particle {i}");
            check(Section::Particles, "radius", p.radius, &what).or_else(bad)?;
            if !(finite3(&p.position) && finite3(&p.velocity) && finite3(&p.angular_velocity)) {
                return bad(format!(
                    "particle {i}: position, velocity and angular velocity must be finite, got {:?}, {:?}, {:?}",
                    p.position, p.velocity, p.angular_velocity
                ));
            }
            check(Section::Particles, "insert_at", p.insert_at, &what).or_else(bad)?;
        }
        Ok(())
    }

    /// Refuses a name that cannot name files inside an output folder (the run's outputs
    /// are named after the scene): empty, `.`, `..`, or with `/`, `\\` or control characters.
    pub fn check_file_name(&self) -> Result<(), PowderError> {
        let name = &self.name;
        if !can_name_files(name) {
            return bad(format!(
                "the scene's name {name:?} cannot name files in the output folder: it must be non-empty, not `.` or `..`, without `/`, `\\` or control characters"
            ));
        }
        Ok(())
    }

    /// The period of each periodic axis (`None` on the others).
    pub fn periods(&self) -> [Option<f64>; 3] {
        let d = &self.domain;
        [0, 1, 2].map(|a| d.periodic[a].then(|| d.max[a] - d.min[a]))
    }

    /// The particles by insertion time (the ones present from the start first), one group
    /// for each time.
    fn insertion_groups(&self) -> Vec<Vec<usize>> {
        let time = |i: usize| self.particles[i].insert_at.max(0.0);
        let mut order: Vec<usize> = (0..self.particles.len()).collect();
        order.sort_by(|&a, &b| time(a).total_cmp(&time(b)));
        order
            .chunk_by(|&a, &b| time(a) == time(b))
            .map(<[usize]>::to_vec)
            .collect()
    }

    /// A warning when a particle appears where one of the insertion before it would still
    /// be, had that one flown freely since it appeared (its velocity and gravity, no
    /// collisions): the pour's region has likely not emptied, and the run will stop there
    /// (the engines do not push particles aside). Each insertion time is checked against
    /// the one before it (the particles present from the start for the first).
    pub fn pour_onto_earlier(&self) -> Option<String> {
        let time = |i: usize| self.particles[i].insert_at.max(0.0);
        let groups = self.insertion_groups();
        let r_max = self.particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        let g = self.gravity;
        let (lo, periods) = (self.domain.min, self.periods());
        for pair in groups.windows(2) {
            let (before, at) = (time(pair[0][0]), time(pair[1][0]));
            let dt = at - before;
            let mut grid = Grid::new(2.0 * r_max);
            let mut flown = Vec::new();
            for &j in &pair[0] {
                let p = &self.particles[j];
                let x: [f64; 3] = std::array::from_fn(|a| {
                    let x = p.position[a] + p.velocity[a] * dt + 0.5 * g[a] * dt * dt;
                    match periods[a] {
                        Some(l) => lo[a] + (x - lo[a]).rem_euclid(l),
                        None => x,
                    }
                });
                grid.insert(flown.len(), x);
                flown.push((j, x));
            }
            for &i in &pair[1] {
                let p = &self.particles[i];
                for k in grid.near_images(p.position, p.radius + r_max, periods) {
                    let (j, x) = flown[k];
                    let gap = image_distance(self, p.position, x);
                    if gap < p.radius + self.particles[j].radius {
                        return Some(format!(
                            "particle {i} appears at {at:e} s where particle {j}, which appeared at {before:e} s, would still be had it flown freely since (its velocity and gravity, no collisions): the pour's region has likely not emptied, and the run would stop where a particle lands on another (the engines do not push particles aside); lengthen `batch_interval` or move the region"
                        ));
                    }
                }
            }
        }
        None
    }

    /// A warning when particles that appear together, or a particle and a wall, start
    /// touching to within rounding (|gap| ≤ 10⁻¹² of their radii, or a few ulps of the
    /// domain's coordinates) under a law whose force jumps at the touch (JKR with adhesion,
    /// jump-in adhesion): whether each such pair starts in contact, and so bonds, is decided
    /// by the last bits of its positions, and the two engines decide differently. O(N)
    /// through a hash grid, and nothing where no law of the scene jumps at the touch.
    pub fn touching_at_start(&self) -> Option<String> {
        let n = self.materials.len();
        let r_max = self.particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        // (whether a law's force jumps at the touch does not depend on the radii)
        let jumps =
            |model: Result<crate::model::ContactModel, PowderError>, wall: bool, a: usize| {
                let m = sphere_mass(self.materials[a].density, r_max);
                let geom = if wall {
                    crate::model::PairGeometry::wall(r_max, m)
                } else {
                    crate::model::PairGeometry::spheres(r_max, r_max, m, m)
                };
                model.is_ok_and(|m| m.edges(&geom, 0.0, 0.0)[0].1 != 0.0)
            };
        let pairs: Vec<bool> = (0..n * n)
            .map(|k| jumps(self.pair_model(k / n, k % n), false, k % n))
            .collect();
        let walls: Vec<bool> = (0..self.walls.len() * n)
            .map(|k| {
                jumps(
                    self.pair_model(self.walls[k / n].material, k % n),
                    true,
                    k % n,
                )
            })
            .collect();
        if !pairs.iter().chain(&walls).any(|&j| j) {
            return None;
        }
        let d = &self.domain;
        let coords = (0..3).fold(0.0f64, |m, a| m.max(d.min[a].abs()).max(d.max[a].abs()));
        let tol = |r: f64| 1e-12 * r + 8.0 * f64::EPSILON * coords;
        let (mut count, mut first) = (0usize, None::<String>);
        let mut found = |what: String| {
            count += 1;
            first.get_or_insert(what);
        };
        for (w, wall) in self.walls.iter().enumerate() {
            let normal = DVec3::from_array(wall.normal).normalize();
            let point = DVec3::from_array(wall.point);
            for (i, p) in self.particles.iter().enumerate() {
                if !walls[w * n + p.material] {
                    continue;
                }
                let gap = normal.dot(DVec3::from_array(p.position) - point) - p.radius;
                if gap.abs() <= tol(p.radius) {
                    found(format!(
                        "particle {i} and wall {w}, gap {gap:e} m: materials `{}` and `{}`",
                        self.materials[p.material].name, self.materials[wall.material].name
                    ));
                }
            }
        }
        let periods = self.periods();
        for group in self.insertion_groups() {
            let mut grid = Grid::new(2.0 * r_max);
            for &i in &group {
                grid.insert(i, self.particles[i].position);
            }
            for &i in &group {
                let p = &self.particles[i];
                for j in grid.near_images(p.position, p.radius + r_max, periods) {
                    let q = &self.particles[j];
                    if j <= i || !pairs[p.material * n + q.material] {
                        continue;
                    }
                    let gap = image_distance(self, p.position, q.position) - p.radius - q.radius;
                    if gap.abs() <= tol(p.radius + q.radius) {
                        found(format!(
                            "particles {i} and {j}, gap {gap:e} m: materials `{}` and `{}`",
                            self.materials[p.material].name, self.materials[q.material].name
                        ));
                    }
                }
            }
        }
        Some(format!(
            "{count} pairs start touching to within rounding (the first: {}) under a law whose force jumps at the touch (JKR with adhesion, or jump-in adhesion): whether each such pair starts in contact, and so bonds, is decided by the last bits of its positions, and the CPU and GPU decide differently; leave a clear gap (a lattice: a region that holds its spacing above 2·radius) or a clear overlap",
            first?
        ))
    }

    /// A warning when particles appear only after the last step of a run begins, at
    /// `last_start` s (particles appear at the start of a step): they never appear (valid,
    /// since a resume may run further, but rarely meant).
    pub fn late_insertions(&self, last_start: f64) -> Option<String> {
        let late: Vec<usize> = (0..self.particles.len())
            .filter(|&i| self.particles[i].insert_at > last_start)
            .collect();
        let &first = late.first()?;
        Some(format!(
            "{} of the {} particles (the first: particle {first}, insert_at = {:e} s) appear after the run's last step begins at {last_start:e} s: this run ends before they appear",
            late.len(),
            self.particles.len(),
            self.particles[first].insert_at
        ))
    }
}

/// The distance from `a` to the nearest image of `b` in `scene`'s domain.
fn image_distance(scene: &Scene, a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = &scene.domain;
    let domain = (DVec3::from_array(d.min), DVec3::from_array(d.max));
    minimum_image(
        DVec3::from_array(a) - DVec3::from_array(b),
        d.periodic,
        domain,
    )
    .length()
}
