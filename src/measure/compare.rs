//! `powder compare`: one scene on both backends, side by side over time, with thresholds.
//!
//! Both engines start from the same scene and step with the same dt; every `every` steps
//! the GPU state is read back and compared with the CPU reference: positions (over the
//! smallest radius), velocities (over the largest CPU speed), contact counts and the
//! largest overlap (each engine's own contact statistics), the energy ledger (kinetic,
//! stored, dissipated) and the per-contact history values (δmax, tangential spring,
//! rolling displacement, twisting spring, Krijt contact radius) of every contact both
//! engines hold. Granular flows are chaotic, so f32 and f64 trajectories separate exponentially once collisions chain up; compare
//! over the early steps, or judge the aggregate quantities (energy, contacts) later on.

use crate::cpu::{CpuEngine, Partner};
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine};
use crate::model::ContactHistory;
use crate::run::MAX_OVERLAP_RATIO;
use crate::scene::Scene;
use serde::Serialize;
use std::collections::HashMap;

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
    /// Stored and dissipated energy differences over the energy in play (the CPU's
    /// kinetic + |stored| + dissipated, at least 1e-30 J).
    pub energy: f64,
    /// History values of the contacts with overlap both engines hold: the RMS difference
    /// of δmax over the RMS of the CPU's δmax, and likewise for the tangential spring and
    /// the rolling and twisting displacements and the Krijt contact radius; the largest of
    /// the five. RMS rather than the
    /// worst contact: on the tensile branch δmax ∝ √δ near δ = 0, so a contact about to
    /// open turns an f32 rounding of its overlap into a large δmax difference (the worst
    /// one is reported as `history_max`).
    pub history: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Self {
            position: 1e-3,
            velocity: 1e-2,
            kinetic: 1e-2,
            contacts: 0.05,
            energy: 1e-2,
            history: 1e-2,
        }
    }
}

impl Tolerances {
    /// Each tolerance a number >= 0 (infinity: not checked); NaN would pass every sample.
    pub fn validate(&self) -> Result<(), PowderError> {
        let named = [
            ("position", self.position),
            ("velocity", self.velocity),
            ("kinetic", self.kinetic),
            ("contacts", self.contacts),
            ("energy", self.energy),
            ("history", self.history),
        ];
        match named.iter().find(|(_, v)| v.is_nan() || *v < 0.0) {
            Some((name, v)) => Err(crate::ParamError::new(
                "tolerance",
                format!("the {name} tolerance must be a number >= 0, got {v}"),
            )
            .into()),
            None => Ok(()),
        }
    }
}

/// The deviations at one sample.
#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    /// Steps taken by both engines when sampled.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Largest particle position difference |x_cpu − x_gpu| over the smallest radius.
    pub position: f64,
    /// Largest velocity difference |v_cpu − v_gpu| over the largest CPU speed (plus 1e-12 m/s).
    pub velocity: f64,
    /// CPU kinetic energy (translational + rotational), J.
    pub kinetic_cpu: f64,
    /// GPU kinetic energy (translational + rotational), J.
    pub kinetic_gpu: f64,
    /// |kinetic_cpu − kinetic_gpu| over the larger of the two (at least 1e-30 J).
    pub kinetic: f64,
    /// CPU mechanical contacts (δ > 0), particle–particle plus particle–wall.
    pub contacts_cpu: usize,
    /// GPU mechanical contacts (δ > 0), particle–particle plus particle–wall.
    pub contacts_gpu: usize,
    /// |contacts_cpu − contacts_gpu| over contacts_cpu (at least 1).
    pub contacts: f64,
    /// Largest overlap on the CPU, m.
    pub max_overlap_cpu: f64,
    /// Largest overlap on the GPU, m.
    pub max_overlap_gpu: f64,
    /// Energy stored in contacts on the CPU (elastic plus adhesion potential), J.
    pub elastic_cpu: f64,
    /// Energy stored in contacts on the GPU (elastic plus adhesion potential), J.
    pub elastic_gpu: f64,
    /// Energy dissipated so far on the CPU, J.
    pub dissipated_cpu: f64,
    /// Energy dissipated so far on the GPU, J.
    pub dissipated_gpu: f64,
    /// max(|Δ stored|, |Δ dissipated|) over the energy in play.
    pub energy: f64,
    /// Contacts with overlap both engines hold whose history was compared.
    pub history_pairs: usize,
    /// Contacts with overlap on the CPU that the GPU does not list.
    pub history_missing: usize,
    /// The relative RMS history deviation (see [`Tolerances::history`]).
    pub history: f64,
    /// The largest single-contact deviation, over the largest CPU value of its quantity.
    pub history_max: f64,
    /// Which thresholds this sample exceeds.
    pub exceeded: Vec<&'static str>,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Name of the scene compared.
    pub scene: String,
    /// Name of the GPU adapter that ran the GPU side.
    pub adapter: String,
    /// Number of particles.
    pub particles: usize,
    /// Time step shared by both engines, s.
    pub dt: f64,
    /// Steps run in all.
    pub steps: u64,
    /// The thresholds each sample was checked against.
    pub tolerances: Tolerances,
    /// One sample every `every` steps (and at the end).
    pub samples: Vec<Sample>,
    /// True when no sample exceeds a threshold.
    pub passed: bool,
}

/// History deviations of the contacts with overlap that the CPU holds.
struct HistoryDeviation {
    compared: usize,
    missing: usize,
    rms: f64,
    max: f64,
}

/// Compares δmax (pairs of the hysteretic model: `keeps_delta_max`), the tangential
/// spring, ξ, the twisting spring and the Krijt contact radius of every CPU contact with
/// overlap against the GPU's copy of the same side.
fn history_deviation(
    cpu: &[((u32, u32), f64, ContactHistory)],
    gpu: &[((u32, u32), ContactHistory)],
    keeps_delta_max: impl Fn(u32, u32) -> bool,
) -> HistoryDeviation {
    let gpu: HashMap<(u32, u32), ContactHistory> = gpu.iter().copied().collect();
    let (mut compared, mut missing) = (0, 0);
    // per quantity: largest difference, largest value, Σ difference², Σ value²
    let mut q = [[0.0f64; 4]; 5];
    let mut add = |k: usize, diff: f64, value: f64| {
        q[k][0] = q[k][0].max(diff);
        q[k][1] = q[k][1].max(value);
        q[k][2] += diff * diff;
        q[k][3] += value * value;
    };
    for (key, _, c) in cpu.iter().filter(|c| c.1 > 0.0) {
        let Some(g) = gpu.get(key) else {
            missing += 1;
            continue;
        };
        compared += 1;
        if keeps_delta_max(key.0, key.1) {
            add(0, (g.delta_max - c.delta_max).abs(), c.delta_max);
        }
        add(
            1,
            g.tangential.distance(c.tangential),
            c.tangential.length(),
        );
        add(2, g.rolling.distance(c.rolling), c.rolling.length());
        add(
            3,
            (g.contact_radius - c.contact_radius).abs(),
            c.contact_radius,
        );
        add(4, (g.twist - c.twist).abs(), c.twist.abs());
    }
    let of =
        |f: &dyn Fn(&[f64; 4]) -> f64| q.iter().filter(|x| x[1] > 0.0).map(f).fold(0.0, f64::max);
    HistoryDeviation {
        compared,
        missing,
        rms: of(&|x| (x[2] / x[3]).sqrt()),
        max: of(&|x| x[0] / x[1]),
    }
}

/// Whether a deviation is beyond its tolerance: one that is not a number is (NaN compares
/// false with any tolerance, which would pass a run whose state went NaN).
fn over(deviation: f64, tolerance: f64) -> bool {
    deviation.is_nan() || deviation > tolerance
}

/// An error where the CPU reference has gone unstable as `powder run`'s monitor would stop
/// it (a non-finite particle, a contact beyond [`MAX_OVERLAP_RATIO`]): its engines'
/// differences then say nothing. (A particle leaving the domain is the scene's choice here.)
fn reference_holds(cpu: &mut CpuEngine) -> Result<(), PowderError> {
    let why = if let Some(i) = cpu.non_finite() {
        format!("particle {i} has a non-finite position or velocity")
    } else if let Some((ratio, i, partner)) =
        cpu.take_peak_overlap().filter(|p| p.0 > MAX_OVERLAP_RATIO)
    {
        let other = match partner {
            Partner::Particle(j) => format!("particle {j}"),
            Partner::Wall(w) => format!("wall {w}"),
        };
        format!("particle {i} overlaps {other} by {ratio:.3} of the reduced radius (limit {MAX_OVERLAP_RATIO})")
    } else {
        return Ok(());
    };
    Err(PowderError::Run(format!(
        "by step {}: the CPU reference went wrong ({why}): the scene itself is unstable (a time step too large for it, an impact too violent, or particles poured onto others), so its engines are not compared; `powder run --backend cpu` stops there too, naming the step and the cause",
        cpu.steps
    )))
}

/// Runs `scene` on both backends for `steps` steps, sampling every `every` steps.
pub fn compare(
    scene: &Scene,
    ctx: GpuContext,
    steps: u64,
    every: u64,
    tol: Tolerances,
) -> Result<Comparison, PowderError> {
    tol.validate()?;
    if steps == 0 {
        return Err(crate::ParamError::new(
            "steps",
            "a comparison needs at least one step (nothing would be compared)",
        )
        .into());
    }
    let mut cpu = CpuEngine::new(scene)?;
    let mut gpu = GpuEngine::new(scene, ctx)?;
    let radius = cpu.radii().to_vec();
    let r_min = radius.iter().copied().fold(f64::INFINITY, f64::min);
    // the pairs whose model keeps δmax on the device (the hysteretic model; JKR keeps it
    // on the CPU only)
    let keeps_delta_max = |i: u32, j: u32| {
        let (a, b) = (
            scene.particles[i as usize].material,
            scene.particles[j as usize].material,
        );
        matches!(
            scene.pair_model(a, b),
            Ok(crate::model::ContactModel::Hysteretic(_))
        )
    };
    let every = every.max(1);
    let mut samples = Vec::new();
    let mut done = 0;
    while done < steps {
        let chunk = every.min(steps - done);
        cpu.run_steps(chunk)?;
        reference_holds(&mut cpu)?;
        gpu.run_steps(chunk)?;
        done += chunk;
        let g = gpu.state()?;
        // (the nearest periodic image: a particle at a periodic face may have wrapped on
        // one backend and not yet on the other)
        let box_ = (
            glam::DVec3::from_array(scene.domain.min),
            glam::DVec3::from_array(scene.domain.max),
        );
        let position = cpu
            .positions()
            .iter()
            .zip(&g.positions)
            .map(|(a, b)| {
                crate::cpu::engine::minimum_image(*a - *b, scene.domain.periodic, box_).length()
            })
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
        let (ec, eg) = (cpu.energies(), gpu.energies(&g)?);
        let (kinetic_cpu, kinetic_gpu) = (ec.kinetic, eg.kinetic);
        let kinetic =
            (kinetic_cpu - kinetic_gpu).abs() / kinetic_cpu.abs().max(kinetic_gpu.abs()).max(1e-30);
        let in_play = (ec.kinetic + ec.elastic.abs() + ec.dissipated).max(1e-30);
        let energy = (ec.elastic - eg.elastic)
            .abs()
            .max((ec.dissipated - eg.dissipated).abs())
            / in_play;
        let (sc, sg) = (cpu.contact_stats(), gpu.contact_stats()?);
        let (contacts_cpu, contacts_gpu) = (
            sc.contacts + sc.wall_contacts,
            sg.contacts + sg.wall_contacts,
        );
        let contacts = contacts_cpu.abs_diff(contacts_gpu) as f64 / contacts_cpu.max(1) as f64;
        let h = history_deviation(&cpu.contacts(), &gpu.contact_histories()?, keeps_delta_max);
        let history = h.rms;
        let mut exceeded = Vec::new();
        if over(position, tol.position) {
            exceeded.push("position");
        }
        if over(velocity, tol.velocity) {
            exceeded.push("velocity");
        }
        if over(kinetic, tol.kinetic) {
            exceeded.push("kinetic");
        }
        if over(contacts, tol.contacts) {
            exceeded.push("contacts");
        }
        if over(energy, tol.energy) {
            exceeded.push("energy");
        }
        if over(history, tol.history) {
            exceeded.push("history");
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
            max_overlap_cpu: sc.max_overlap,
            max_overlap_gpu: sg.max_overlap,
            elastic_cpu: ec.elastic,
            elastic_gpu: eg.elastic,
            dissipated_cpu: ec.dissipated,
            dissipated_gpu: eg.dissipated,
            energy,
            history_pairs: h.compared,
            history_missing: h.missing,
            history,
            history_max: h.max,
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

#[cfg(test)]
mod tests {
    use super::over;

    #[test]
    fn a_deviation_that_is_not_a_number_fails() {
        assert!(over(f64::NAN, 1e-3) && over(2e-3, 1e-3) && over(f64::INFINITY, 1e-3));
        assert!(!over(1e-3, 1e-3) && !over(0.0, 1e-3));
    }
}
