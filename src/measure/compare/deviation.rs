//! The deviations of one engine's state from the CPU reference's at a sample, each as the
//! tolerance of the same name measures it ([`super::Tolerances`]).

use crate::cpu::engine::minimum_image;
use crate::cpu::{ContactStats, CpuEngine};
use crate::model::ContactHistory;
use crate::scene::Scene;
use glam::DVec3;
use std::collections::HashMap;

/// What the reference (the f64 CPU engine) shows at a sample.
pub(super) struct Reference<'a> {
    pub cpu: &'a CpuEngine,
    pub contacts: Vec<((u32, u32), f64, ContactHistory)>,
    pub stats: ContactStats,
}

impl<'a> Reference<'a> {
    pub fn of(cpu: &'a CpuEngine) -> Self {
        Self {
            cpu,
            contacts: cpu.contacts(),
            stats: cpu.contact_stats(),
        }
    }
}

/// What the engine compared with the reference shows at the same sample.
pub(super) struct Other<'a> {
    pub positions: &'a [DVec3],
    pub velocities: &'a [DVec3],
    /// Kinetic, stored and dissipated energy, J.
    pub energies: [f64; 3],
    pub stats: ContactStats,
    pub histories: Vec<((u32, u32), ContactHistory)>,
}

impl<'a> Other<'a> {
    /// Another CPU engine (the perturbed reference).
    pub fn cpu(cpu: &'a CpuEngine) -> Self {
        let e = cpu.energies();
        Self {
            positions: cpu.positions(),
            velocities: cpu.velocities(),
            energies: [e.kinetic, e.elastic, e.dissipated],
            stats: cpu.contact_stats(),
            histories: (cpu.contacts().into_iter())
                .map(|(key, _, h)| (key, h))
                .collect(),
        }
    }
}

/// One engine's deviations from the reference at a sample.
pub(super) struct Deviations {
    pub position: f64,
    pub velocity: f64,
    pub kinetic: f64,
    pub contacts: f64,
    pub energy: f64,
    pub history: HistoryDeviation,
}

impl Deviations {
    /// The six measures by name, in [`super::MEASURES`]' order.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        let d = [
            self.position,
            self.velocity,
            self.kinetic,
            self.contacts,
            self.energy,
            self.history.rms,
        ];
        std::array::from_fn(|k| (super::MEASURES[k], d[k]))
    }
}

/// How far `other` is from `reference` (positions to the nearest periodic image: a
/// particle at a periodic face may have wrapped in one engine and not yet in the other).
/// `keeps_delta_max`: the pairs whose δmax both engines keep.
pub(super) fn deviations(
    scene: &Scene,
    reference: &Reference,
    other: &Other,
    keeps_delta_max: impl Fn(u32, u32) -> bool,
) -> Deviations {
    let cpu = reference.cpu;
    let r_min = cpu.radii().iter().copied().fold(f64::INFINITY, f64::min);
    let d = &scene.domain;
    let box_ = (DVec3::from_array(d.min), DVec3::from_array(d.max));
    let position = (cpu.positions().iter().zip(other.positions))
        .map(|(a, b)| minimum_image(*a - *b, d.periodic, box_).length())
        .fold(0.0, f64::max)
        / r_min;
    // (the floors, for a scene at rest, scale with the scene: 10⁻¹² of its expected impact
    // speed and the square of that of its particles' energy at that speed)
    let v_ref = scene.impact_velocity;
    let e_floor = 1e-24 * 0.5 * v_ref * v_ref * cpu.masses().iter().sum::<f64>();
    let v_scale = (cpu.velocities().iter())
        .map(|v| v.length())
        .fold(0.0, f64::max)
        + 1e-12 * v_ref;
    let velocity = (cpu.velocities().iter().zip(other.velocities))
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max)
        / v_scale;
    let ec = cpu.energies();
    let [kinetic_o, elastic_o, dissipated_o] = other.energies;
    let kinetic =
        (ec.kinetic - kinetic_o).abs() / ec.kinetic.abs().max(kinetic_o.abs()).max(e_floor);
    let in_play = (ec.kinetic + ec.elastic.abs() + ec.dissipated).max(e_floor);
    let energy = (ec.elastic - elastic_o)
        .abs()
        .max((ec.dissipated - dissipated_o).abs())
        / in_play;
    let count = |s: &ContactStats| s.contacts + s.wall_contacts;
    let (c, o) = (count(&reference.stats), count(&other.stats));
    let contacts = c.abs_diff(o) as f64 / c.max(1) as f64;
    let history = history_deviation(&reference.contacts, &other.histories, keeps_delta_max);
    Deviations {
        position,
        velocity,
        kinetic,
        contacts,
        energy,
        history,
    }
}

/// History deviations of the contacts with overlap that the CPU holds.
#[derive(Clone, Copy, Debug)]
pub(super) struct HistoryDeviation {
    pub compared: usize,
    pub missing: usize,
    pub rms: f64,
    pub max: f64,
}

/// Compares δmax (pairs of the hysteretic model: `keeps_delta_max`), the tangential
/// spring, ξ, the twisting spring and the Krijt contact radius of every CPU contact with
/// overlap against the other engine's copy of the same side.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// In a scene of tiny units, an engine whose particles move the other way, with half
    /// the kinetic energy, deviates by order one: the floors of a scene at rest scale with
    /// the scene (they were 1e-12 m/s and 1e-30 J, and passed such an engine).
    #[test]
    fn the_floors_scale_with_the_scene() {
        let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1e-10, 1e-10, 1e-10]\n[simulation]\nduration = 1e-3\nimpact_velocity = 6e-19\n[[material]]\nname = \"m\"\ndensity = 1.0\nmodel = \"lsd\"\nk = 1e-46\n[[particles]]\nkind = \"list\"\npositions = [[3e-11, 5e-11, 5e-11], [7e-11, 5e-11, 5e-11]]\nradius = 1e-11\nvelocities = [[3e-19, 0.0, 0.0], [-3e-19, 0.0, 0.0]]\n";
        let scene = Scene::from_toml_str(text, "tiny").unwrap();
        let cpu = CpuEngine::new(&scene).unwrap();
        let reference = Reference::of(&cpu);
        let back: Vec<DVec3> = cpu.velocities().iter().map(|v| -*v).collect();
        let mut other = Other::cpu(&cpu);
        other.velocities = &back;
        other.energies[0] *= 0.5;
        let d = deviations(&scene, &reference, &other, |_, _| false);
        assert!((d.velocity - 2.0).abs() < 1e-9, "{}", d.velocity);
        assert!((d.kinetic - 0.5).abs() < 1e-9, "{}", d.kinetic);
    }
}
