//! `powder compare`: one scene on both backends, side by side over time, with thresholds.
//!
//! Both engines start from the same scene and step with the same dt; every `every` steps
//! the GPU state is read back and compared with the CPU reference: positions (over the
//! smallest radius), velocities (over the largest CPU speed), contact counts and the
//! largest overlap (from the positions of each, with the same contact rule), and the
//! kinetic energy. Granular flows are chaotic, so f32 and f64 trajectories separate
//! exponentially once collisions chain up; compare over the early steps, or judge the
//! aggregate quantities (energy, contacts) later on.

use crate::cpu::cells::CellGrid;
use crate::cpu::CpuEngine;
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine};
use crate::scene::Scene;
use glam::DVec3;
use serde::Serialize;

/// Largest deviations allowed before `compare` fails.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tolerances {
    /// Position difference over the smallest radius.
    pub position: f64,
    /// Velocity difference over the largest CPU speed (plus 1e-12 m/s).
    pub velocity: f64,
    /// Relative kinetic-energy difference (over the largest of the two and 1e-30 J).
    pub kinetic: f64,
    /// Difference in the number of contacts, relative to the CPU count (at least 1).
    pub contacts: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Self {
            position: 1e-3,
            velocity: 1e-2,
            kinetic: 1e-2,
            contacts: 0.05,
        }
    }
}

/// The deviations at one sample.
#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    pub step: u64,
    pub time: f64,
    pub position: f64,
    pub velocity: f64,
    pub kinetic_cpu: f64,
    pub kinetic_gpu: f64,
    pub kinetic: f64,
    pub contacts_cpu: usize,
    pub contacts_gpu: usize,
    pub contacts: f64,
    pub max_overlap_cpu: f64,
    pub max_overlap_gpu: f64,
    /// Which thresholds this sample exceeds.
    pub exceeded: Vec<&'static str>,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub scene: String,
    pub adapter: String,
    pub particles: usize,
    pub dt: f64,
    pub steps: u64,
    pub tolerances: Tolerances,
    pub samples: Vec<Sample>,
    pub passed: bool,
}

/// Contacts (δ > 0 with a particle or a wall) and the largest overlap of a configuration.
fn contacts(scene: &Scene, pos: &[DVec3], radius: &[f64], r_max: f64) -> (usize, f64) {
    let mut grid = CellGrid::new(
        DVec3::from_array(scene.domain.min),
        DVec3::from_array(scene.domain.max),
        2.0 * r_max * (1.0 + 1e-9),
        pos.len(),
    );
    grid.rebuild(pos);
    let mut count = 0;
    let mut max: f64 = 0.0;
    grid.for_each_pair(pos, |i, j| {
        let d = radius[i] + radius[j] - pos[i].distance(pos[j]);
        if d > 0.0 {
            count += 1;
            max = max.max(d);
        }
    });
    for w in &scene.walls {
        let (p, n) = (
            DVec3::from_array(w.point),
            DVec3::from_array(w.normal).normalize(),
        );
        for (x, r) in pos.iter().zip(radius) {
            let d = r - (*x - p).dot(n);
            if d > 0.0 {
                count += 1;
                max = max.max(d);
            }
        }
    }
    (count, max)
}

/// Runs `scene` on both backends for `steps` steps, sampling every `every` steps.
pub fn compare(
    scene: &Scene,
    ctx: GpuContext,
    steps: u64,
    every: u64,
    tol: Tolerances,
) -> Result<Comparison, PowderError> {
    let mut cpu = CpuEngine::new(scene)?;
    let mut gpu = GpuEngine::new(scene, ctx)?;
    let radius = cpu.radii().to_vec();
    let r_min = radius.iter().copied().fold(f64::INFINITY, f64::min);
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    let every = every.max(1);
    let mut samples = Vec::new();
    let mut done = 0;
    while done < steps {
        let chunk = every.min(steps - done);
        cpu.run_steps(chunk)?;
        gpu.run_steps(chunk)?;
        done += chunk;
        let g = gpu.state()?;
        let position = cpu
            .positions()
            .iter()
            .zip(&g.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max)
            / r_min;
        let v_scale = cpu
            .velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max)
            + 1e-12;
        let velocity = cpu
            .velocities()
            .iter()
            .zip(&g.velocities)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max)
            / v_scale;
        let kinetic_cpu = cpu.energies().kinetic;
        let kinetic_gpu = gpu.kinetic_energy(&g);
        let kinetic =
            (kinetic_cpu - kinetic_gpu).abs() / kinetic_cpu.abs().max(kinetic_gpu.abs()).max(1e-30);
        let (contacts_cpu, max_overlap_cpu) = contacts(scene, cpu.positions(), &radius, r_max);
        let (contacts_gpu, max_overlap_gpu) = contacts(scene, &g.positions, &radius, r_max);
        let contacts = contacts_cpu.abs_diff(contacts_gpu) as f64 / contacts_cpu.max(1) as f64;
        let mut exceeded = Vec::new();
        if position > tol.position {
            exceeded.push("position");
        }
        if velocity > tol.velocity {
            exceeded.push("velocity");
        }
        if kinetic > tol.kinetic {
            exceeded.push("kinetic");
        }
        if contacts > tol.contacts {
            exceeded.push("contacts");
        }
        samples.push(Sample {
            step: cpu.steps,
            time: cpu.time,
            position,
            velocity,
            kinetic_cpu,
            kinetic_gpu,
            kinetic,
            contacts_cpu,
            contacts_gpu,
            contacts,
            max_overlap_cpu,
            max_overlap_gpu,
            exceeded,
        });
    }
    let passed = samples.iter().all(|s| s.exceeded.is_empty());
    Ok(Comparison {
        scene: scene.name.clone(),
        adapter: gpu.adapter().to_string(),
        particles: cpu.len(),
        dt: cpu.dt(),
        steps,
        tolerances: tol,
        samples,
        passed,
    })
}
