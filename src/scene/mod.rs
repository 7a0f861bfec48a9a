//! The TOML scene description: domain, run settings, materials and their contact models,
//! walls and particles, with validation and errors a user can act on.
//!
//! Every error is a [`PowderError::Scene`] that starts with the scene's name and, where the
//! problem sits at a place in the file, its line and column
//! (``scene `cluster`, line 12, column 11: ...``). Unknown keys are rejected everywhere,
//! with the nearest valid key suggested.
//!
//! Every key is declared once in [`declared`], with its unit, default, rule and meaning:
//! the keys each table accepts follow from it, and so does the reference (`powder params
//! scene`, `docs/scene.md`, with the checks made at load time). The contact laws'
//! parameters are declared in `crate::model::params` (`powder params`).

mod checks;
pub mod declared;
#[cfg(test)]
mod declared_tests;
pub(crate) mod hash_grid;
mod keys;
mod parse;
mod particles;
mod read_declared;
pub mod reference;
mod set;
#[cfg(test)]
mod tests;
mod toml_reader;
mod validate;
pub(crate) use validate::can_name_files;

use crate::error::PowderError;
use crate::model::ContactModel;
use crate::overrides::Override;
pub use checks::MaterialUse;
use parse::parse_scene;
use std::path::Path;
use toml_reader::Src;

/// Largest accepted overlap at start, as a fraction of the (smaller) radius.
pub const OVERLAP_TOLERANCE: f64 = 0.01;
/// Attempts to find a free spot for one particle of a `random` block.
pub const MAX_PLACEMENT_ATTEMPTS: usize = 1000;
/// Largest number of particles one `lattice` or `random` block may create (guards typos).
pub const MAX_BLOCK_PARTICLES: u64 = 100_000_000;
/// Particles below which `contact_output` defaults to on (the contact network files of a
/// larger scene get large: a dense packing has about three contacts per particle).
pub const CONTACT_OUTPUT_BELOW: usize = 100_000;

/// The largest scene file read, bytes (a list of 10⁷ particles' positions is ~0.5 GB).
pub const MAX_SCENE_BYTES: u64 = 1 << 30;

/// The box the particles live in, m.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Domain {
    /// Lower corner (x, y, z), m.
    pub min: [f64; 3],
    /// Upper corner (x, y, z), m.
    pub max: [f64; 3],
    /// Periodic axes: a particle leaving through one face enters through the opposite one,
    /// and pairs interact across the faces (minimum image).
    pub periodic: [bool; 3],
}

impl Domain {
    /// Whether any axis is periodic.
    pub fn any_periodic(&self) -> bool {
        self.periodic.iter().any(|&p| p)
    }
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum DtSetting {
    /// From the stiffest contact of the scene.
    #[default]
    Auto,
    /// A fixed time step, s.
    Fixed(f64),
}

/// A named material: density and its own contact model.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name used in `[[interaction]]` and particle blocks.
    pub name: String,
    /// kg/m^3.
    pub density: f64,
    /// Contact model between two particles of this material (also between a wall of this
    /// material and such a particle), unless an [`Interaction`] overrides it.
    pub model: ContactModel,
}

/// A contact model for a pair of materials (indices into [`Scene::materials`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interaction {
    /// The two material indices (either order).
    pub materials: [usize; 2],
    /// Contact model of the pair, overriding the materials' own.
    pub model: ContactModel,
}

/// What a wall does during one phase of its motion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum WallPhase {
    /// At rest.
    #[default]
    Rest,
    /// A prescribed velocity, m/s.
    Velocity([f64; 3]),
    /// Servo control along the normal: each step the wall moves with speed
    /// clamp(gain·(force − F), ±max_speed) along its normal, F being the normal force the
    /// particles exerted on it the step before (at rest in the first step of a servo phase
    /// entered during the run); it holds `force` (N).
    Servo {
        /// Target normal force on the wall, N.
        force: f64,
        /// Gain, m/s per N of force error.
        gain: f64,
        /// Largest wall speed, m/s.
        max_speed: f64,
    },
}

/// How a wall moves (it is never pushed by the particles: an infinite mass): phases, each
/// from its start time on (s, strictly increasing), at rest before the first. A step
/// follows the phase its start time falls in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WallMotion {
    /// (from time s, what the wall does), by increasing time.
    pub phases: Vec<(f64, WallPhase)>,
}

impl WallMotion {
    /// At rest throughout.
    pub fn fixed() -> Self {
        Self::default()
    }

    /// One phase from t = 0 on.
    pub fn always(phase: WallPhase) -> Self {
        Self {
            phases: vec![(0.0, phase)],
        }
    }

    /// The index of the phase at time `t` (None: before the first).
    pub fn index_at(&self, t: f64) -> Option<usize> {
        self.phases.iter().rposition(|(from, _)| t >= *from)
    }

    /// The phase at time `t`.
    pub fn at(&self, t: f64) -> WallPhase {
        self.index_at(t)
            .map_or(WallPhase::Rest, |i| self.phases[i].1)
    }

    /// The prescribed velocity at time `t` (zero at rest and under servo control).
    pub fn prescribed_velocity(&self, t: f64) -> [f64; 3] {
        match self.at(t) {
            WallPhase::Velocity(v) => v,
            _ => [0.0; 3],
        }
    }

    /// The next time after `t` at which a phase starts.
    pub fn next_switch(&self, t: f64) -> Option<f64> {
        self.phases
            .iter()
            .map(|(from, _)| *from)
            .find(|&from| from > t)
    }

    /// Whether the wall ever moves.
    pub fn moves(&self) -> bool {
        self.phases.iter().any(|(_, p)| *p != WallPhase::Rest)
    }

    /// Whether some phase is under servo control.
    pub fn servo(&self) -> bool {
        self.phases
            .iter()
            .any(|(_, p)| matches!(p, WallPhase::Servo { .. }))
    }
}

/// An infinite plane wall.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// A point on the plane at time 0, m.
    pub point: [f64; 3],
    /// Normal pointing into the domain (the reader's is a unit vector; one of any
    /// non-zero length is normalised where used).
    pub normal: [f64; 3],
    /// How it moves (default: fixed).
    pub motion: WallMotion,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

/// One particle's initial state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleInit {
    /// m.
    pub position: [f64; 3],
    /// m/s.
    pub velocity: [f64; 3],
    /// rad/s: the spin it starts (or enters) with; only where a contact model makes
    /// particles rotate.
    pub angular_velocity: [f64; 3],
    /// m.
    pub radius: f64,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// When the particle appears, s (0: at the start). Before that it neither moves nor
    /// interacts; it enters with its position and velocity (pouring).
    pub insert_at: f64,
}

/// The volume of a sphere of `radius` (m), m³.
pub fn sphere_volume(radius: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * radius * radius * radius
}

/// The mass of a sphere of `radius` (m) and `density` (kg/m³), kg (ρ·4/3·π·r³ in this
/// order: the engines' masses, bitwise).
pub fn sphere_mass(density: f64, radius: f64) -> f64 {
    density * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
}

/// The moment of inertia of a solid sphere of `mass` (kg) and `radius` (m) about a
/// diameter, 2/5·m·r², kg·m².
pub fn sphere_inertia(mass: f64, radius: f64) -> f64 {
    0.4 * mass * radius * radius
}

/// Whether a particle inserted at `insert_at` (s) is due at the start of step `step` of
/// `dt`: both engines insert it at the first step k with insert_at ≤ k·dt (k·dt as f64, not
/// a summed time, which rounds low).
pub fn insert_due_at(insert_at: f64, step: u64, dt: f64) -> bool {
    insert_at <= step as f64 * dt
}

/// Whether a state saved after `steps` steps of `dt` may hold a particle inserted at
/// `insert_at` as `appeared` (a checkpoint's flag checked against the scene): it must have
/// appeared if due at step 0 or at the last step run, and must not have if not yet due at
/// step `steps` (a state taken between steps may hold one due then either way).
pub fn appearance_fits(insert_at: f64, steps: u64, dt: f64, appeared: bool) -> bool {
    let surely = insert_due_at(insert_at, steps.saturating_sub(1), dt);
    let maybe = insert_due_at(insert_at, steps, dt);
    (appeared || !surely) && (!appeared || maybe)
}

/// Where a saved state's appeared flags (`appeared[i]` after `steps` steps of `dt`) do not
/// fit the particles' `insert_at` ([`appearance_fits`]): a message naming the first one.
pub fn misfit_appearance(
    insert_at: &[f64],
    appeared: &[bool],
    steps: u64,
    dt: f64,
) -> Option<String> {
    if insert_at.len() != appeared.len() {
        return Some(format!(
            "it holds {} appeared flags for {} particles",
            appeared.len(),
            insert_at.len()
        ));
    }
    let i =
        (0..appeared.len()).find(|&i| !appearance_fits(insert_at[i], steps, dt, appeared[i]))?;
    Some(format!(
        "it has particle {i} {} after {steps} steps of dt = {dt:e} s, but the scene inserts it at t = {:e} s",
        if appeared[i] { "appeared" } else { "not yet appeared" },
        insert_at[i]
    ))
}

/// A scene: read from TOML (see the module documentation for the file format; checked as
/// it is read) or built in code (checked by [`Scene::validate`], which every engine calls).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The file stem, or "default".
    pub name: String,
    /// The domain box.
    pub domain: Domain,
    /// m/s^2.
    pub gravity: [f64; 3],
    /// How the time step is chosen.
    pub dt: DtSetting,
    /// Accept a dt above the stability limit.
    pub force_dt: bool,
    /// Place the impulse of a contact force's jump inside the step ([`crate::cpu::jump`],
    /// `shaders/jump.wgsl`); `None`: yes (the GPU engine: where some contact law's force
    /// can jump, [`crate::model::ContactModel::has_force_jumps`]).
    pub jump_impulses: Option<bool>,
    /// Simulated time, s.
    pub duration: f64,
    /// Steps between outputs: `powder run`'s progress line, VTK snapshot and CSV row.
    pub output_every: u64,
    /// Largest expected impact speed, m/s: sets the Hertz/JKR contact time
    /// for the automatic time step.
    pub impact_velocity: f64,
    /// Steps between checkpoints of `powder run` (default 10 × output_every).
    pub checkpoint_every: u64,
    /// Write the contact network with each snapshot of `powder run`; `None`: under
    /// [`CONTACT_OUTPUT_BELOW`] particles ([`Scene::writes_contacts`]).
    pub contact_output: Option<bool>,
    /// Materials, by index.
    pub materials: Vec<Material>,
    /// Pair models; they take precedence over the materials' own models.
    pub interactions: Vec<Interaction>,
    /// Plane walls.
    pub walls: Vec<Wall>,
    /// Fully expanded, in id order.
    pub particles: Vec<ParticleInit>,
}

impl Scene {
    /// Parses and validates a scene; `name` labels the errors (and becomes [`Scene::name`]).
    pub fn from_toml_str(text: &str, name: &str) -> Result<Scene, PowderError> {
        Self::from_toml_str_with(text, name, &[])
    }

    /// [`Scene::from_toml_str`] with `--set KEY=VALUE` overrides applied in order
    /// ([`crate::overrides`]); errors keep the file's line numbers.
    pub fn from_toml_str_with(
        text: &str,
        name: &str,
        sets: &[String],
    ) -> Result<Scene, PowderError> {
        let raw = sets;
        let sets = sets
            .iter()
            .map(|s| Override::parse(s))
            .collect::<Result<Vec<_>, _>>()?;
        let name = if name.is_empty() { "default" } else { name };
        let src = Src {
            name,
            text,
            sets: raw,
        };
        parse_scene(&src, &sets)
    }

    /// Reads and parses a scene file; the scene is named after the file stem.
    pub fn load(path: &Path) -> Result<Scene, PowderError> {
        Self::load_with(path, &[])
    }

    /// Loads a scene file with `--set KEY=VALUE` overrides applied ([`crate::overrides`]).
    pub fn load_with(path: &Path, sets: &[String]) -> Result<Scene, PowderError> {
        use std::io::Read;
        let cannot = |e| PowderError::io(format!("cannot read scene file `{}`", path.display()), e);
        // (read to a bound: a device such as /dev/zero would be read until memory runs out;
        // a pipe, `<(...)` or /dev/stdin, is read as a file)
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes))
            .map_err(cannot)?;
        if bytes.len() as u64 > MAX_SCENE_BYTES {
            return Err(PowderError::Scene(format!(
                "scene file `{}` is longer than {MAX_SCENE_BYTES} bytes (a device such as /dev/zero?): a scene is a TOML file of at most that size",
                path.display()
            )));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            PowderError::Scene(format!(
                "scene file `{}` is not UTF-8 text (byte {}): a scene is a TOML file",
                path.display(),
                e.utf8_error().valid_up_to()
            ))
        })?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Self::from_toml_str_with(&text, &name, sets)
    }

    /// Whether some particle appears only during the run (pouring).
    pub fn pours(&self) -> bool {
        self.particles.iter().any(|p| p.insert_at > 0.0)
    }

    /// Whether `powder run` writes the contact network with each snapshot.
    pub fn writes_contacts(&self) -> bool {
        self.contact_output
            .unwrap_or(self.particles.len() < CONTACT_OUTPUT_BELOW)
    }

    /// The contact model for a pair of material indices: an `[[interaction]]` for the pair
    /// (either order) if present, else the material's own model when both are the same.
    pub fn pair_model(&self, a: usize, b: usize) -> Result<ContactModel, PowderError> {
        let n = self.materials.len();
        if a >= n || b >= n {
            return Err(PowderError::Scene(format!(
                "material index {} is out of range: the scene has {n} material(s)",
                a.max(b)
            )));
        }
        if let Some(i) = self
            .interactions
            .iter()
            .find(|i| i.materials == [a, b] || i.materials == [b, a])
        {
            return Ok(i.model);
        }
        if a == b {
            return Ok(self.materials[a].model);
        }
        Err(PowderError::Scene(no_pair_model_message(
            &self.materials[a].name,
            &self.materials[b].name,
        )))
    }
}

fn no_pair_model_message(a: &str, b: &str) -> String {
    format!(
        "no contact model for materials `{a}` and `{b}`: add an [[interaction]] with materials = [\"{a}\", \"{b}\"]"
    )
}
