//! The dense packing the benchmarks and the accuracy study step, built in code so the same
//! scene runs on both engines: particles in contact on a simple cubic lattice (overlaps of
//! 0.1–0.3 % of the diameter), with a small random jitter and small random velocities, in a
//! box (floor and four side walls) under gravity, for either [`Case`].

use crate::cpu::cells::CellGrid;
use crate::error::{ParamError, PowderError};
use crate::model::{
    AdhesionMode, ContactModel, Dissipation, HystereticParams, JkrParams, K2Rule, Pulloff,
};
use crate::scene::{Domain, DtSetting, Material, ParticleInit, Scene, Wall};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Overlap of lattice neighbours, as a fraction of the diameter: the packing starts in
/// contact (a simple cubic lattice, six contacts per inner particle), as a settled one is.
pub const LATTICE_OVERLAP: f64 = 0.002;

/// Which benchmark scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// Frictionless hysteretic packing (radius 1.1 mm, k1 = 100, kp = 500, kc = 100 N/m,
    /// φf = 0.05, γ0 = 10⁻³ kg/s; random velocities up to 2 cm/s).
    Hysteretic,
    /// JKR packing with friction and rolling (radius 5 µm, E = 10⁸ Pa, ν = 0.3,
    /// γ = 0.01 J/m², Tsuji e = 0.5, μs = 0.3, Δγ/γ = 0.5; random velocities up to 2 cm/s).
    Jkr,
}

impl Case {
    /// The name used in tables, JSON and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Case::Hysteretic => "hysteretic",
            Case::Jkr => "jkr",
        }
    }
}

/// A dense packing of `n` particles of `case`'s material: a simple cubic lattice (x fastest,
/// then y, then z; as many layers as needed over a square base of ⌈∛n⌉² sites) whose
/// neighbours overlap by [`LATTICE_OVERLAP`] of the diameter, each particle displaced by up
/// to a quarter of that per axis (so every lattice neighbour and the walls stay in contact,
/// with overlaps of 0.1–0.3 % of the diameter), with random velocities up to
/// `velocity_scale` × 2 cm/s per component, in a box with a floor and four side walls under
/// gravity; seeded, so a given (case, n, seed) is always the same scene.
pub fn packing(case: Case, n: usize, velocity_scale: f64, seed: u64) -> Result<Scene, PowderError> {
    if n == 0 {
        return Err(ParamError::new("sizes", "a packing needs at least one particle").into());
    }
    crate::error::require_non_negative("velocity-scale", velocity_scale, "the velocity scale")?;
    let each = std::mem::size_of::<ParticleInit>() as u64;
    crate::memory::check_particles(n as u64, each, "the packing's particle list")
        .map_err(|why| ParamError::new("sizes", why))?;
    let (radius, density, model, impact_velocity, v0) = match case {
        Case::Hysteretic => (
            1.1e-3,
            2000.0,
            ContactModel::Hysteretic(HystereticParams {
                k1: 100.0,
                kp: 500.0,
                kc: 100.0,
                phi_f: 0.05,
                fa: 0.0,
                kca: 100.0,
                adhesion: AdhesionMode::default(),
                gamma0: 1e-3,
                k2_rule: K2Rule::default(),
                luding: Default::default(),
            }),
            1.0,
            0.02,
        ),
        Case::Jkr => (
            5e-6,
            2500.0,
            ContactModel::Jkr(JkrParams {
                youngs: 1e8,
                poisson: 0.3,
                surface_energy: 0.01,
                dissipation: Dissipation::tsuji(0.5),
                friction: 0.3,
                rolling_hysteresis: 0.5,
                pulloff: Pulloff::default(),
                stiffness_scale: 1.0,
                luding: Default::default(),
            }),
            0.1,
            0.02,
        ),
    };
    let v0 = v0 * velocity_scale;
    let side = ((n as f64).cbrt().ceil() as usize).max(1);
    let layers = n.div_ceil(side * side);
    let spacing = 2.0 * radius * (1.0 - LATTICE_OVERLAP);
    let overlap = 2.0 * radius - spacing;
    let width = side as f64 * spacing;
    // room above the packing for particles thrown up by the random velocities
    let height = (layers + 3) as f64 * spacing;
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut particles = Vec::with_capacity(n);
    for k in 0..n {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let mut position = [0.0; 3];
        for (axis, site) in [i, j, l].into_iter().enumerate() {
            let jitter = rng.random_range(-0.25..=0.25) * overlap;
            position[axis] = (site as f64 + 0.5) * spacing + jitter;
        }
        let velocity = [0, 1, 2].map(|_| {
            if v0 > 0.0 {
                rng.random_range(-v0..=v0)
            } else {
                0.0
            }
        });
        particles.push(ParticleInit {
            position,
            velocity,
            radius,
            material: 0,
            angular_velocity: [0.0; 3],
            insert_at: 0.0,
        });
    }
    let wall = |point: [f64; 3], normal: [f64; 3]| Wall {
        point,
        normal,
        motion: Default::default(),
        material: 0,
    };
    Ok(Scene {
        name: format!("bench_{}_{n}", case.name()),
        domain: Domain {
            min: [0.0; 3],
            max: [width, width, height],
            periodic: [false; 3],
        },
        gravity: [0.0, 0.0, -9.81],
        dt: DtSetting::Auto,
        force_dt: false,
        jump_impulses: None,
        duration: 1.0,
        output_every: 1000,
        contact_output: None,
        impact_velocity,
        checkpoint_every: 10_000,
        materials: vec![Material {
            name: case.name().into(),
            density,
            model,
        }],
        interactions: Vec::new(),
        walls: vec![
            wall([0.0; 3], [0.0, 0.0, 1.0]),
            wall([0.0; 3], [1.0, 0.0, 0.0]),
            wall([width, 0.0, 0.0], [-1.0, 0.0, 0.0]),
            wall([0.0; 3], [0.0, 1.0, 0.0]),
            wall([0.0, width, 0.0], [0.0, -1.0, 0.0]),
        ],
        particles,
    })
}

/// Particle–particle contacts (δ > 0) per particle of a configuration (2·pairs/N).
pub fn coordination(
    scene: &Scene,
    positions: &[DVec3],
    radius: &[f64],
) -> Result<f64, PowderError> {
    if positions.len() != radius.len() {
        return Err(PowderError::Run(format!(
            "coordination: {} positions but {} radii",
            positions.len(),
            radius.len()
        )));
    }
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    let mut grid = CellGrid::new(
        DVec3::from_array(scene.domain.min),
        DVec3::from_array(scene.domain.max),
        2.0 * r_max * (1.0 + 1e-9),
        positions.len(),
    );
    grid.rebuild(positions);
    let mut pairs = 0usize;
    grid.for_each_pair(positions, |i, j| {
        if positions[i].distance(positions[j]) < radius[i] + radius[j] {
            pairs += 1;
        }
    });
    Ok(2.0 * pairs as f64 / positions.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packings_do_not_overlap_and_fill_the_count() {
        for case in [Case::Hysteretic, Case::Jkr] {
            let s = packing(case, 130, 1.0, 3).unwrap();
            assert_eq!(s.particles.len(), 130);
            let pos: Vec<DVec3> = s
                .particles
                .iter()
                .map(|p| DVec3::from_array(p.position))
                .collect();
            let r: Vec<f64> = s.particles.iter().map(|p| p.radius).collect();
            // a 6 x 6 base: 3 full layers and 22 sites (3 rows of 6 and 4) on top; every
            // lattice neighbour in contact and nothing else: x bonds 3·30 + 3·5 + 3,
            // y bonds 3·30 + 4·3 + 2·2, z bonds 2·36 + 22
            let bonds = (90 + 15 + 3) + (90 + 12 + 4) + (72 + 22);
            let z = coordination(&s, &pos, &r).unwrap();
            assert_eq!(z, 2.0 * bonds as f64 / 130.0);
            for (i, p) in pos.iter().enumerate() {
                for q in &pos[i + 1..] {
                    assert!(p.distance(*q) > 2.0 * r[i] * (1.0 - 0.003));
                }
            }
            // in contact with the walls too, by at most 0.3 % of the diameter
            for p in &s.particles {
                for a in 0..3 {
                    assert!(p.position[a] - p.radius > s.domain.min[a] - 0.006 * p.radius);
                    assert!(p.position[a] + p.radius < s.domain.max[a] + 0.006 * p.radius);
                }
            }
            // the same seed gives the same scene, another seed another
            assert_eq!(packing(case, 130, 1.0, 3).unwrap(), s);
            assert_ne!(packing(case, 130, 1.0, 4).unwrap(), s);
        }
    }
}
