//! What `powder run` needs of a backend, so one run loop (outputs, checkpoints, the run
//! monitor) drives both the f64 CPU reference ([`CpuEngine`]) and the GPU engine
//! ([`GpuEngine`]).

use crate::checkpoint;
use crate::checkpoint::RunMarks;
use crate::cpu::{ContactStats, CpuEngine, CpuState, Partner};
use crate::error::PowderError;
use crate::gpu::{GpuEngine, GpuSavedState};
use crate::output::contacts::ContactNetwork;
use crate::run::observed::ObservedEnergies;
use crate::scene::Scene;
use glam::DVec3;
use std::path::Path;

/// The state of a simulation at one instant, read back in the scene's particle order.
#[derive(Clone, Debug)]
pub struct Observation {
    /// Particle centres, m.
    pub positions: Vec<DVec3>,
    /// Particle velocities, m/s.
    pub velocities: Vec<DVec3>,
    /// Empty when the particles do not rotate.
    pub angular_velocities: Vec<DVec3>,
    /// Energies, J: the ledger's parts are `None` when the run keeps no ledger.
    pub energies: ObservedEnergies,
    /// Contact statistics; `None` when the run keeps no ledger (they are counted there).
    pub contacts: Option<ContactStats>,
    /// Force of the particles on each wall, N (normal and tangential parts); `None` when the
    /// run keeps no ledger (the device keeps the wall contacts' forces there).
    pub wall_forces: Option<Vec<DVec3>>,
    /// Where each wall's plane passes now (its scene point, moved with the wall), m.
    pub wall_points: Vec<DVec3>,
    /// Each wall's velocity over the last step, m/s.
    pub wall_velocities: Vec<DVec3>,
}

/// A deepest overlap the run monitor found: the ratio over a12 and who it involves.
#[derive(Clone, Debug)]
pub struct PeakOverlap {
    /// Largest overlap δ over the pair's a12.
    pub ratio: f64,
    /// "particle 3 overlaps particle 7", or what the backend knows.
    pub who: String,
    /// The particle whose partner the backend does not know (the GPU's monitor keeps the
    /// particle only): the run's monitor finds it from the positions.
    pub unnamed: Option<usize>,
}

/// A backend as `powder run` drives it.
pub trait Simulation {
    /// A saved state ([`Self::save`]), restored when the run monitor stops a run.
    type Saved;
    /// "cpu" or "gpu".
    fn backend(&self) -> &'static str;
    /// The GPU adapter, if any.
    fn adapter(&self) -> Option<String>;
    /// The CPU threads the step is spread over (the CPU engine).
    fn threads(&self) -> Option<usize> {
        None
    }
    /// Steps taken.
    fn steps(&self) -> u64;
    /// Simulated time, s.
    fn time(&self) -> f64;
    /// Time step, s.
    fn dt(&self) -> f64;
    /// Number of particles.
    fn len(&self) -> usize;
    /// Whether there are no particles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Particle radii in scene order, m.
    fn radii(&self) -> &[f64];
    /// Number of walls.
    fn wall_count(&self) -> usize;
    /// The digests of the parts of the scene the engine was built from
    /// (`checkpoint::run_digests` with all wall phases): a run refuses another scene's.
    fn scene_parts(&self) -> &[(String, u64)];
    /// Whether the run keeps the energy ledger (stored and dissipated energy, contact
    /// statistics, wall forces): always on the CPU, optional on the GPU.
    fn has_ledger(&self) -> bool;
    /// Whether particle `i` has appeared (pouring; every particle of a scene that does not
    /// pour).
    fn has_appeared(&self, i: usize) -> bool;
    /// Advances `n` steps.
    fn run_steps(&mut self, n: u64) -> Result<(), PowderError>;
    /// Reads the state, energies, contact statistics and wall forces (without the ledger:
    /// the state, the kinetic and gravitational energy and the walls' points).
    fn observe(&self) -> Result<Observation, PowderError>;
    /// What the run monitor needs between outputs: [`Self::observe`], where it costs more
    /// without the wall forces (the GPU reads its lists back for them) those left out.
    fn observe_for_checks(&self) -> Result<Observation, PowderError> {
        self.observe()
    }
    /// Copies the evolving state (for the run monitor to go back to).
    fn save(&self) -> Result<Self::Saved, PowderError>;
    /// Returns to a state from [`Self::save`].
    fn restore(&mut self, saved: Self::Saved) -> Result<(), PowderError>;
    /// Writes a checkpoint that resumes bitwise on this backend.
    fn write_checkpoint(
        &self,
        path: &Path,
        scene: &Scene,
        run: &RunMarks,
    ) -> Result<(), PowderError>;
    /// Continues from a checkpoint of `scene` written by this backend; returns what its
    /// run kept beside the state.
    fn read_checkpoint(&mut self, path: &Path, scene: &Scene) -> Result<RunMarks, PowderError>;
    /// A particle with a non-finite position or velocity (the GPU engine reports
    /// non-finite accelerations from `run_steps` already).
    fn non_finite(&self) -> Option<usize>;
    /// The deepest overlap over a12 since the last call (every step is watched).
    fn take_peak_overlap(&mut self) -> Option<PeakOverlap>;
    /// Up to `limit` particles whose centre has left the domain box.
    fn escaped(&self, limit: usize) -> Vec<usize>;
    /// Extra lines for the summary (e.g. neighbour-list rebuilds).
    fn notes(&self) -> Result<Vec<String>, PowderError>;
    /// Neighbour-list rebuilds so far, as the engine counts them (the GPU's initial build
    /// included; the CPU's since the engine was built).
    fn rebuilds(&self) -> Result<u64, PowderError>;
    /// Quiet batches kept and rolled back (GPU, `gpu::quiet`); `None` on the CPU.
    fn quiet_batches(&self) -> Option<(u64, u64)>;
    /// The engaged contacts now, for the contact network output.
    fn contact_network(&self) -> Result<ContactNetwork, PowderError>;
}

impl Simulation for CpuEngine {
    type Saved = CpuState;
    fn backend(&self) -> &'static str {
        "cpu"
    }
    fn threads(&self) -> Option<usize> {
        Some(CpuEngine::threads(self))
    }
    fn adapter(&self) -> Option<String> {
        None
    }
    fn steps(&self) -> u64 {
        self.steps
    }
    fn time(&self) -> f64 {
        self.time
    }
    fn dt(&self) -> f64 {
        CpuEngine::dt(self)
    }
    fn len(&self) -> usize {
        CpuEngine::len(self)
    }
    fn radii(&self) -> &[f64] {
        CpuEngine::radii(self)
    }
    fn wall_count(&self) -> usize {
        CpuEngine::wall_count(self)
    }
    fn scene_parts(&self) -> &[(String, u64)] {
        CpuEngine::scene_parts(self)
    }
    fn has_ledger(&self) -> bool {
        true
    }
    fn has_appeared(&self, i: usize) -> bool {
        i < self.len() && self.is_active(i)
    }
    fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        CpuEngine::run_steps(self, n)
    }
    fn observe(&self) -> Result<Observation, PowderError> {
        Ok(Observation {
            positions: self.positions().to_vec(),
            velocities: self.velocities().to_vec(),
            angular_velocities: self.angular_velocities().to_vec(),
            energies: self.energies().into(),
            contacts: Some(self.contact_stats()),
            wall_forces: Some(self.wall_forces()),
            wall_points: self.walls_now().iter().map(|w| w.0).collect(),
            wall_velocities: self.walls_now().iter().map(|w| w.1).collect(),
        })
    }
    fn save(&self) -> Result<CpuState, PowderError> {
        Ok(self.state())
    }
    fn restore(&mut self, saved: CpuState) -> Result<(), PowderError> {
        CpuEngine::restore(self, saved)
    }
    fn write_checkpoint(
        &self,
        path: &Path,
        scene: &Scene,
        run: &RunMarks,
    ) -> Result<(), PowderError> {
        checkpoint::save(path, scene, self, run)
    }
    fn read_checkpoint(&mut self, path: &Path, scene: &Scene) -> Result<RunMarks, PowderError> {
        let (state, marks) = checkpoint::load(path, scene)?;
        CpuEngine::restore(self, state)?;
        Ok(marks)
    }
    fn non_finite(&self) -> Option<usize> {
        CpuEngine::non_finite(self)
    }
    fn take_peak_overlap(&mut self) -> Option<PeakOverlap> {
        CpuEngine::take_peak_overlap(self).map(|(ratio, i, partner)| PeakOverlap {
            ratio,
            who: match partner {
                Partner::Particle(j) => format!("particle {i} overlaps particle {j}"),
                Partner::Wall(w) => format!("particle {i} overlaps wall {w}"),
            },
            unnamed: None,
        })
    }
    fn escaped(&self, limit: usize) -> Vec<usize> {
        CpuEngine::escaped(self, limit)
    }
    fn notes(&self) -> Result<Vec<String>, PowderError> {
        Ok(Vec::new())
    }
    fn rebuilds(&self) -> Result<u64, PowderError> {
        Ok(CpuEngine::rebuilds(self))
    }
    fn quiet_batches(&self) -> Option<(u64, u64)> {
        None
    }
    fn contact_network(&self) -> Result<ContactNetwork, PowderError> {
        Ok(CpuEngine::contact_network(self))
    }
}

impl Simulation for GpuEngine {
    type Saved = GpuSavedState;
    fn backend(&self) -> &'static str {
        "gpu"
    }
    fn adapter(&self) -> Option<String> {
        Some(GpuEngine::adapter(self).to_string())
    }
    fn steps(&self) -> u64 {
        self.steps
    }
    fn time(&self) -> f64 {
        self.time
    }
    fn dt(&self) -> f64 {
        GpuEngine::dt(self)
    }
    fn len(&self) -> usize {
        GpuEngine::len(self)
    }
    fn radii(&self) -> &[f64] {
        GpuEngine::radii(self)
    }
    fn wall_count(&self) -> usize {
        GpuEngine::wall_count(self)
    }
    fn scene_parts(&self) -> &[(String, u64)] {
        GpuEngine::scene_parts(self)
    }
    fn has_ledger(&self) -> bool {
        GpuEngine::has_ledger(self)
    }
    fn has_appeared(&self, i: usize) -> bool {
        GpuEngine::has_appeared(self, i)
    }
    fn run_steps(&mut self, n: u64) -> Result<(), PowderError> {
        GpuEngine::run_steps(self, n)
    }
    fn observe(&self) -> Result<Observation, PowderError> {
        let mut obs = self.observe_for_checks()?;
        if self.has_ledger() {
            obs.wall_forces = Some(self.wall_forces()?);
        }
        Ok(obs)
    }
    fn observe_for_checks(&self) -> Result<Observation, PowderError> {
        let (s, energies, contacts) = if self.has_ledger() {
            let (s, energies, contacts) = self.state_energies_and_contact_stats()?;
            (s, energies.into(), Some(contacts))
        } else {
            // what the read-back state tells on the host, in f64
            let s = self.state()?;
            let known = ObservedEnergies {
                kinetic: self.kinetic_energy(&s),
                gravitational: self.gravitational_energy(&s),
                inserted: self.inserted_energy(),
                ..Default::default()
            };
            (s, known, None)
        };
        let walls = self.walls_now()?;
        Ok(Observation {
            energies,
            contacts,
            wall_forces: None,
            wall_points: walls.iter().map(|w| w.0).collect(),
            wall_velocities: walls.iter().map(|w| w.1).collect(),
            positions: s.positions,
            velocities: s.velocities,
            angular_velocities: s.angular_velocities,
        })
    }
    fn save(&self) -> Result<GpuSavedState, PowderError> {
        self.save_state()
    }
    fn restore(&mut self, saved: GpuSavedState) -> Result<(), PowderError> {
        self.restore_state(saved)
    }
    fn write_checkpoint(
        &self,
        path: &Path,
        scene: &Scene,
        run: &RunMarks,
    ) -> Result<(), PowderError> {
        checkpoint::save_gpu(path, scene, &self.save_state()?, run)
    }
    fn read_checkpoint(&mut self, path: &Path, scene: &Scene) -> Result<RunMarks, PowderError> {
        let (saved, marks) = checkpoint::load_gpu(path, scene)?;
        let adapter = saved.adapter.clone();
        // a state that does not fit (e.g. the other ledger option) names the file
        self.restore_state(saved).map_err(|e| match e {
            PowderError::Run(m) => PowderError::Run(format!(
                "cannot resume from checkpoint `{}`: {m}",
                path.display()
            )),
            e => e,
        })?;
        if adapter != GpuEngine::adapter(self) {
            eprintln!(
                "notice: checkpoint `{}` was written on {}; continuing on {} (not bitwise identical to an uninterrupted run)",
                path.display(),
                adapter,
                GpuEngine::adapter(self)
            );
        }
        Ok(marks)
    }
    fn non_finite(&self) -> Option<usize> {
        None
    }
    fn take_peak_overlap(&mut self) -> Option<PeakOverlap> {
        GpuEngine::take_peak_overlap(self).map(|(ratio, beyond)| PeakOverlap {
            ratio,
            who: match beyond {
                Some(i) => format!("particle {i} overlaps a neighbour or wall"),
                None => "a contact overlaps".into(),
            },
            unnamed: beyond,
        })
    }
    fn escaped(&self, _limit: usize) -> Vec<usize> {
        GpuEngine::escaped(self).into_iter().collect()
    }
    fn notes(&self) -> Result<Vec<String>, PowderError> {
        let mut notes = vec![format!(
            "neighbour lists rebuilt {} times (Verlet skin; the initial build included)",
            self.rebuilds()?
        )];
        let (kept, rolled_back) = self.quiet_batches();
        if kept + rolled_back > 0 {
            notes.push(format!(
                "{kept} quiet batches (no per-step rebuild check; bitwise the same), {rolled_back} rolled back and rerun with the check"
            ));
        }
        if !self.has_ledger() {
            notes.push(
                "no energy ledger (--no-ledger): stored and dissipated energy, wall work, the energy balance, contact statistics, wall forces and contacts that left the neighbour lists are not tracked, and the run monitor has no energy-growth check".into(),
            );
        }
        if self.dropped_contacts() > 0 {
            notes.push(format!(
                "{} engaged contacts left the neighbour lists within one step (moved more than the skin in one step): the time step is too large for these speeds",
                self.dropped_contacts()
            ));
        }
        Ok(notes)
    }
    fn rebuilds(&self) -> Result<u64, PowderError> {
        GpuEngine::rebuilds(self)
    }
    fn quiet_batches(&self) -> Option<(u64, u64)> {
        Some(GpuEngine::quiet_batches(self))
    }
    fn contact_network(&self) -> Result<ContactNetwork, PowderError> {
        GpuEngine::contact_network(self)
    }
}
