//! `powder compare`: one scene on both backends, side by side over time, with thresholds.
//!
//! Both engines start from the same scene and step with the same dt; every `every` steps
//! the GPU state is read back and compared with the CPU reference: positions (over the
//! smallest radius), velocities (over the largest CPU speed), contact counts and the
//! largest overlap (each engine's own contact statistics), the energy ledger (kinetic,
//! stored, dissipated) and the per-contact history values (δmax, tangential spring,
//! rolling displacement, twisting spring, Krijt contact radius) of every contact both
//! engines hold. Granular flows are chaotic, so f32 and f64 trajectories separate
//! exponentially once collisions chain up: [`compare_perturbed`] judges each measure only
//! up to the scene's chaos horizon, measured with a perturbed second CPU run.

mod deviation;

use crate::cpu::{CpuEngine, Partner};
use crate::error::PowderError;
use crate::gpu::{GpuContext, GpuEngine};
use crate::run::MAX_OVERLAP_RATIO;
use crate::scene::Scene;
use deviation::{deviations, Other, Reference};
use serde::Serialize;
use std::collections::BTreeMap;

/// Largest deviations allowed before `compare` fails.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tolerances {
    /// Position difference over the smallest radius.
    pub position: f64,
    /// Velocity difference over the largest CPU speed (plus 10⁻¹² of the scene's
    /// `impact_velocity`).
    pub velocity: f64,
    /// Relative kinetic-energy difference (over the largest of the two and 10⁻²⁴ of the
    /// particles' energy ½·Σm·v² at the scene's `impact_velocity`).
    pub kinetic: f64,
    /// Difference in the number of contacts, relative to the CPU count (at least 1).
    pub contacts: f64,
    /// Stored and dissipated energy differences over the energy in play (the CPU's
    /// kinetic + |stored| + dissipated, at least 10⁻²⁴ of ½·Σm·v² at `impact_velocity`).
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

/// The six measures, by the names of their tolerances (and `--tolerance` keys).
pub const MEASURES: [&str; 6] = [
    "position", "velocity", "kinetic", "contacts", "energy", "history",
];

impl Tolerances {
    /// The six tolerances by name, in [`MEASURES`]' order.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        let t = [
            self.position,
            self.velocity,
            self.kinetic,
            self.contacts,
            self.energy,
            self.history,
        ];
        std::array::from_fn(|k| (MEASURES[k], t[k]))
    }

    /// Each tolerance a number >= 0 (infinity: not checked); NaN would pass every sample.
    pub fn validate(&self) -> Result<(), PowderError> {
        match self
            .named()
            .into_iter()
            .find(|(_, v)| v.is_nan() || *v < 0.0)
        {
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
    /// Largest velocity difference |v_cpu − v_gpu| over the largest CPU speed (plus 10⁻¹² of
    /// the scene's `impact_velocity`).
    pub velocity: f64,
    /// CPU kinetic energy (translational + rotational), J.
    pub kinetic_cpu: f64,
    /// GPU kinetic energy (translational + rotational), J.
    pub kinetic_gpu: f64,
    /// |kinetic_cpu − kinetic_gpu| over the larger of the two (at least 10⁻²⁴ of ½·Σm·v² at
    /// the scene's `impact_velocity`).
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
    /// Which thresholds this sample exceeds (of the measures judged).
    pub exceeded: Vec<&'static str>,
    /// With a perturbed reference ([`Comparison::perturbation`]): its deviations from the
    /// reference, by measure.
    pub floor: Option<BTreeMap<&'static str, f64>>,
    /// The measures past their chaos horizon, not judged (see [`compare_perturbed`]).
    pub chaotic: Vec<&'static str>,
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
    /// The perturbed reference's displacement of each particle, over its radius (`None`:
    /// none ran; every measure judged at every sample).
    pub perturbation: Option<f64>,
    /// Each measure's chaos horizon: the first sample's step at which the perturbed
    /// reference had separated beyond a tenth of that measure's tolerance.
    pub horizon: BTreeMap<&'static str, u64>,
    /// The measures past their horizon at the first sample, so never judged: the
    /// comparison does not pass (sample sooner, or leave the measure out with an infinite
    /// tolerance).
    pub never_judged: Vec<&'static str>,
    /// The measures left out with an infinite tolerance (JSON has no infinity: their
    /// `tolerances` entry is written `null`).
    pub unchecked: Vec<&'static str>,
}

/// A measure is judged while the perturbed reference stays within its tolerance over this:
/// beyond, chaos alone takes a deviation to within a factor of it of the tolerance.
pub const CHAOS_MARGIN: f64 = 10.0;

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

/// Runs `scene` on both backends for `steps` steps, sampling every `every` steps; every
/// measure judged at every sample.
pub fn compare(
    scene: &Scene,
    ctx: GpuContext,
    steps: u64,
    every: u64,
    tol: Tolerances,
) -> Result<Comparison, PowderError> {
    compare_perturbed(scene, ctx, steps, every, tol, None)
}

/// [`compare`], and with `perturbation` a third run, the CPU reference from positions each
/// moved by `perturbation` × its radius (in a direction of its own): how far a run that
/// differs from the reference at the start by about f32's rounding (1e-7) separates from
/// it in this scene, without the GPU. A measure is judged at a sample only while that run
/// stays within its tolerance over [`CHAOS_MARGIN`]: from then on (the measure's chaos
/// horizon, kept in [`Comparison::horizon`]) the scene's own chaos, not the engine,
/// decides its deviation, and the sample lists it as `chaotic`.
pub fn compare_perturbed(
    scene: &Scene,
    ctx: GpuContext,
    steps: u64,
    every: u64,
    tol: Tolerances,
    perturbation: Option<f64>,
) -> Result<Comparison, PowderError> {
    tol.validate()?;
    if steps == 0 {
        return Err(crate::ParamError::new(
            "steps",
            "a comparison needs at least one step (nothing would be compared)",
        )
        .into());
    }
    if let Some(p) = perturbation.filter(|p| !(p.is_finite() && *p > 0.0 && *p <= 1e-3)) {
        return Err(crate::ParamError::new(
            "perturbed",
            format!(
                "the perturbation must be a number in (0, 1e-3] of each radius, got {}",
                crate::error::num(p)
            ),
        )
        .into());
    }
    let mut cpu = CpuEngine::new(scene)?;
    if let Some(p) = perturbation {
        // (the perturbation alone must leave room under the position tolerance)
        let radii = cpu.radii();
        let r_min = radii.iter().copied().fold(f64::INFINITY, f64::min);
        let r_max = radii.iter().copied().fold(0.0, f64::max);
        let budget = tol.position / CHAOS_MARGIN;
        if p * r_max / r_min > budget {
            return Err(crate::ParamError::new(
                "perturbed",
                format!(
                    "a perturbation of {p:e} moves the largest particles by {:.3e} of the smallest radius, beyond a tenth of the position tolerance ({budget:e}): position could never be judged; choose a perturbation below {:.3e}",
                    p * r_max / r_min,
                    budget * r_min / r_max
                ),
            )
            .into());
        }
    }
    let mut perturbed = match perturbation {
        Some(p) => Some(CpuEngine::new(&perturbed_scene(scene, p))?),
        None => None,
    };
    let mut gpu = GpuEngine::new(scene, ctx)?;
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
    let mut horizon = BTreeMap::new();
    let mut perturbed_failed = false;
    let mut done = 0;
    while done < steps {
        let chunk = every.min(steps - done);
        cpu.run_steps(chunk)?;
        reference_holds(&mut cpu)?;
        // (a perturbed run that fails is past every horizon: its deviations are NaN)
        let mut failed = false;
        if let Some(p) = &mut perturbed {
            failed = p.run_steps(chunk).is_err();
        }
        if failed {
            perturbed = None;
            perturbed_failed = true;
        }
        gpu.run_steps(chunk)?;
        done += chunk;
        let g = gpu.state()?;
        let reference = Reference::of(&cpu);
        let (ec, eg) = (cpu.energies(), gpu.energies(&g)?);
        let sg = gpu.contact_stats()?;
        let on_gpu = Other {
            positions: &g.positions,
            velocities: &g.velocities,
            energies: [eg.kinetic, eg.elastic, eg.dissipated],
            stats: sg,
            histories: gpu.contact_histories()?,
        };
        let d = deviations(scene, &reference, &on_gpu, keeps_delta_max);
        let floor = match (&perturbed, perturbed_failed) {
            (Some(p), _) => {
                let f = deviations(scene, &reference, &Other::cpu(p), keeps_delta_max);
                Some(BTreeMap::from(f.named()))
            }
            (None, true) => Some(BTreeMap::from(
                tol.named().map(|(name, _)| (name, f64::NAN)),
            )),
            (None, false) => None,
        };
        let (exceeded, chaotic) = judge(&d.named(), &tol, floor.as_ref(), &mut horizon, cpu.steps);
        let sc = &reference.stats;
        samples.push(Sample {
            step: cpu.steps,
            time: cpu.time,
            position: d.position,
            velocity: d.velocity,
            kinetic_cpu: ec.kinetic,
            kinetic_gpu: eg.kinetic,
            kinetic: d.kinetic,
            contacts_cpu: sc.contacts + sc.wall_contacts,
            contacts_gpu: sg.contacts + sg.wall_contacts,
            contacts: d.contacts,
            max_overlap_cpu: sc.max_overlap,
            max_overlap_gpu: sg.max_overlap,
            elastic_cpu: ec.elastic,
            elastic_gpu: eg.elastic,
            dissipated_cpu: ec.dissipated,
            dissipated_gpu: eg.dissipated,
            energy: d.energy,
            history_pairs: d.history.compared,
            history_missing: d.history.missing,
            history: d.history.rms,
            history_max: d.history.max,
            exceeded,
            floor,
            chaotic,
        });
    }
    // (a measure past its horizon at the first sample was never judged: no verdict on it)
    let first = samples.first().map_or(0, |s| s.step);
    let never_judged: Vec<&'static str> = (horizon.iter())
        .filter(|&(_, &step)| step == first)
        .map(|(&name, _)| name)
        .collect();
    let passed = samples.iter().all(|s| s.exceeded.is_empty()) && never_judged.is_empty();
    Ok(Comparison {
        scene: scene.name.clone(),
        adapter: gpu.adapter().to_string(),
        particles: cpu.len(),
        dt: cpu.dt(),
        steps,
        tolerances: tol,
        samples,
        passed,
        perturbation,
        horizon,
        never_judged,
        unchecked: (tol.named().into_iter())
            .filter(|(_, t)| t.is_infinite())
            .map(|(name, _)| name)
            .collect(),
    })
}

/// Which measures of a sample at `step` exceed their tolerance, and which are past their
/// chaos horizon (not judged): a measure passes it at the first sample whose `floor` (the
/// perturbed reference's deviation; non-finite included) exceeds its tolerance over
/// [`CHAOS_MARGIN`], recorded in `horizon`, and stays past it.
fn judge(
    deviations: &[(&'static str, f64); 6],
    tol: &Tolerances,
    floor: Option<&BTreeMap<&'static str, f64>>,
    horizon: &mut BTreeMap<&'static str, u64>,
    step: u64,
) -> (Vec<&'static str>, Vec<&'static str>) {
    let (mut exceeded, mut chaotic) = (Vec::new(), Vec::new());
    for (&(name, deviation), (_, tolerance)) in deviations.iter().zip(tol.named()) {
        if floor.is_some_and(|f| over(f[name], tolerance / CHAOS_MARGIN)) {
            horizon.entry(name).or_insert(step);
        }
        if horizon.contains_key(name) {
            chaotic.push(name);
        } else if over(deviation, tolerance) {
            exceeded.push(name);
        }
    }
    (exceeded, chaotic)
}

/// `scene` with each particle moved by `size` × its radius, in a direction of its own (a
/// fixed hash of its index: the same perturbation on every run).
fn perturbed_scene(scene: &Scene, size: f64) -> Scene {
    let mut s = scene.clone();
    for (i, p) in s.particles.iter_mut().enumerate() {
        // (splitmix64 of the index, three 21-bit components in [-1, 1])
        let mut z = (i as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        let c = |k: u32| ((z >> (21 * k)) & 0x1f_ffff) as f64 / 1_048_575.5 - 1.0;
        let u = glam::DVec3::new(c(0), c(1), c(2))
            .try_normalize()
            .unwrap_or(glam::DVec3::X);
        for (a, x) in p.position.iter_mut().enumerate() {
            *x += size * p.radius * u[a];
            // (back into the box on a periodic axis, as the engines wrap)
            let (lo, hi) = (scene.domain.min[a], scene.domain.max[a]);
            if scene.domain.periodic[a] && !(lo..hi).contains(x) {
                *x = lo + (*x - lo).rem_euclid(hi - lo);
                if *x >= hi {
                    *x = lo;
                }
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A measure over its tolerance fails unless the perturbed reference has separated
    /// beyond a tenth of it, at this sample or any before; then it is not judged.
    #[test]
    fn measures_past_the_chaos_horizon_are_not_judged_and_stay_so() {
        let tol = Tolerances::default();
        let named = |position: f64, velocity: f64| {
            let mut d = tol.named().map(|(name, _)| (name, 0.0));
            (d[0].1, d[1].1) = (position, velocity);
            d
        };
        let floor = |position: f64, velocity: f64| BTreeMap::from(named(position, velocity));
        let mut horizon = BTreeMap::new();
        // no perturbed run: every measure judged
        let (ex, ch) = judge(&named(2e-3, 0.0), &tol, None, &mut horizon, 10);
        assert_eq!((ex, ch), (vec!["position"], vec![]));
        // the perturbed run close by: judged, and failing
        let f = floor(1e-4, 1e-3);
        let (ex, ch) = judge(&named(2e-3, 2e-2), &tol, Some(&f), &mut horizon, 10);
        assert_eq!((ex, ch), (vec!["position", "velocity"], vec![]));
        assert!(horizon.is_empty());
        // the perturbed run beyond a tenth of the position tolerance: not judged from here
        let f = floor(2e-4, 1e-3);
        let (ex, ch) = judge(&named(2e-3, 2e-2), &tol, Some(&f), &mut horizon, 20);
        assert_eq!((ex, ch), (vec!["velocity"], vec!["position"]));
        // ... nor later, even where the perturbed run comes back
        let f = floor(0.0, f64::NAN);
        let (ex, ch) = judge(&named(5.0, 5.0), &tol, Some(&f), &mut horizon, 30);
        assert_eq!((ex, ch), (vec![], vec!["position", "velocity"]));
        assert_eq!(
            horizon,
            BTreeMap::from([("position", 20), ("velocity", 30)])
        );
        // a deviation that is not a number fails where judged
        let (ex, _) = judge(&named(f64::NAN, 0.0), &tol, None, &mut BTreeMap::new(), 1);
        assert_eq!(ex, vec!["position"]);
    }

    /// Each particle moves by the perturbation times its radius, each its own way, the same
    /// on every call.
    #[test]
    fn the_perturbed_scene_moves_each_particle_by_its_share_of_its_radius() {
        let scene = crate::scene::Scene::from_toml_str(
            &std::fs::read_to_string("examples/cohesive_cluster.toml").unwrap(),
            "cluster",
        )
        .unwrap();
        let p = perturbed_scene(&scene, 1e-6);
        let moves: Vec<glam::DVec3> = (scene.particles.iter().zip(&p.particles))
            .map(|(a, b)| glam::DVec3::from_array(b.position) - glam::DVec3::from_array(a.position))
            .collect();
        for (m, q) in moves.iter().zip(&scene.particles) {
            assert!((m.length() / (1e-6 * q.radius) - 1.0).abs() < 1e-6, "{m}");
        }
        assert!(moves.windows(2).all(|w| w[0].angle_between(w[1]) > 1e-3));
        assert_eq!(perturbed_scene(&scene, 1e-6).particles, p.particles);
        // a particle on a periodic face stays inside the box, whichever way it moves
        let mut on_face = scene.clone();
        on_face.domain.periodic = [true, true, false];
        for q in &mut on_face.particles {
            (q.position[0], q.position[1]) = (on_face.domain.min[0], on_face.domain.min[1]);
        }
        let d = &on_face.domain;
        for q in perturbed_scene(&on_face, 1e-6).particles {
            for a in 0..2 {
                assert!(
                    (d.min[a]..d.max[a]).contains(&q.position[a]),
                    "{:?}",
                    q.position
                );
            }
        }
    }

    #[test]
    fn a_deviation_that_is_not_a_number_fails() {
        assert!(over(f64::NAN, 1e-3) && over(2e-3, 1e-3) && over(f64::INFINITY, 1e-3));
        assert!(!over(1e-3, 1e-3) && !over(0.0, 1e-3));
    }
}
