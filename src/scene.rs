//! The TOML scene description: domain, run settings, materials and their contact models,
//! walls and particles, with validation and errors a user can act on.
//!
//! Every error is a [`PowderError::Scene`] that starts with the scene's name and, where the
//! problem sits at a place in the file, its line and column
//! (``scene `cluster`, line 12, column 11: ...``). Unknown keys are rejected everywhere,
//! with the nearest valid key suggested.
//!
//! # Schema
//!
//! Units are SI throughout. "required" keys have no default.
//!
//! ```toml
//! [domain]                      # required: the box the particles live in, m
//! # periodic = [true, true, false] # optional, default none: periodic axes (minimum image;
//! #                              #   no wall may face, and no gravity point along, one)
//! min = [0.0, 0.0, 0.0]         # required, m
//! max = [0.01, 0.01, 0.02]      # required, m; max > min on every axis
//!
//! [simulation]                  # required
//! duration = 0.05               # required, s, > 0: simulated time
//! dt = "auto"                   # "auto" (default: from the stiffest contact) or a time step in s, > 0
//! force_dt = false              # default false; true accepts a dt above the stability limit
//! jump_impulses = true          # default true (the GPU: where some contact's force can jump):
//!                               # place the impulse of a contact force's jump (JKR touch and
//!                               # pull-off, jump-in adhesion, a viscous first touch) inside the
//!                               # step, second order in dt; false: plain velocity Verlet
//! output_every = 1000           # default 1000, >= 1: steps between outputs (progress line,
//!                               # VTK snapshot, CSV row of `powder run`)
//! gravity = [0.0, 0.0, -9.81]   # m/s^2, default [0, 0, 0]
//! impact_velocity = 1.0         # m/s, > 0, default 1: largest expected impact speed; sets the
//!                               # Hertz/JKR contact time of the automatic time step
//! checkpoint_every = 10000      # default 10 * output_every, >= 1: steps between checkpoints
//! contact_output = true         # default: true under 100000 particles; with each VTK snapshot,
//!                               # the contact network (`contacts/<name>_<step>.vtp`: one line
//!                               # per contact with its forces, overlap, history, sliding)
//!
//! [[material]]                  # at least one; referred to by name
//! name = "powder"               # required, unique
//! density = 2000.0              # required, kg/m^3, > 0
//! model = "hysteretic"          # required: "hysteretic", "lsd", "jkr" or "hertz"; the other keys are the
//!                               # model's parameters (below); no other keys are allowed
//!
//! # model = "hysteretic" (piece-wise linear adhesive elasto-plastic model):
//! k1 = 100.0                    # required, N/m, > 0: plastic loading stiffness
//! kp = 500.0                    # required, N/m, >= k1: elastic limit (un-/re-loading) stiffness
//! kc = 100.0                    # required, N/m, >= 0: slope of the tensile (adhesive) branch
//! phi_f = 0.05                  # required, dimensionless, 0 < phi_f <= 1: plasticity depth
//! fa = 0.0                      # N, >= 0, default 0: non-contact adhesive force
//! kca = "inf"                   # N/m, > 0, default kc if kc > 0 else "inf" (zero range):
//!                               # non-contact adhesive stiffness; a number, inf or "inf"
//! adhesion = "jump-in"          # "jump-in" (default) or "reversible"
//! gamma0 = 0.0                  # kg/s, >= 0, default 0: viscous damping in contact
//! k2_rule = "linear"            # "linear" (default) or "sqrt": how k2 grows with delta_max
//! # Luding's friction (hysteretic and lsd; docs/models.md "Luding's sliding, rolling and twisting
//! # friction"); > 0 makes particles rotate (both backends). Lever a12 = 2R* (2r at a wall),
//! # Coulomb load max(0, f_n + kc delta + fa) (lsd: max(0, f_n)):
//! friction = 0.0                # >= 0, default 0 (off): static sliding coefficient mu_s
//! friction_dynamic = 0.0        # 0 <= mu_d <= mu_s, default friction
//! kt = 28.6                     # N/m, > 0, default 2/7 k1 (lsd: 2/7 k)
//! gamma_t = 0.0                 # kg/s, >= 0, default 2/7 gamma0
//! rolling_friction = 0.0        # >= 0, default 0 (off): mu_r, torque <= mu_r a12 f_N*
//! kr = 40.0                     # N/m, > 0, default 2/5 k1 (lsd: 2/5 k)
//! gamma_r = 0.0                 # kg/s, >= 0, default 2/5 gamma0
//! twisting_friction = 0.0       # >= 0, default 0 (off): mu_o, torque <= mu_o a12 f_N*
//! ko = 40.0                     # N/m, > 0, default 2/5 k1 (lsd: 2/5 k)
//! gamma_o = 0.0                 # kg/s, >= 0, default 2/5 gamma0
//! # (a stiffness, damping or friction_dynamic without its coefficient > 0 is refused)
//!
//! # model = "lsd" (linear spring-dashpot):
//! k = 300.0                     # required, N/m, > 0: spring stiffness
//! gamma0 = 0.0                  # kg/s, >= 0, default 0: viscous damping
//! # and Luding's friction keys as for "hysteretic"
//!
//! # model = "jkr" (JKR adhesive elastic spheres) or "hertz" (the same without adhesion):
//! youngs = 1e8                  # required, Pa, > 0: Young's modulus E of the material
//! poisson = 0.3                 # required, -1 < poisson < 0.5
//! surface_energy = 0.05         # jkr only, required, J/m^2, >= 0: gamma per surface, Fc = 3 pi gamma R*
//! dissipation = "none"          # "none" (default), "tsuji" (paper 002 eqs. 11-16, needs
//!                               # restitution; the default when restitution is given) or
//!                               # "powerlaw" (paper 001 eq. 19, needs D, alpha, beta),
//!                               # "krijt" (jkr only, paper 001 eqs. 10-12, B1-B2, needs tvis)
//!                               # or "stress" (jkr only, paper 001 eqs. 17-18, needs
//!                               # tvis0_per_radius, B, zeta); krijt/stress: both backends
//! restitution = 0.9             # target restitution e in (0, 1] of "tsuji"
//! tsuji_stiffness = "contact-radius" # "tsuji" only: the stiffness of its dashpots,
//!                               # "contact-radius" (default: Sn = 2E* a, St = 8G* a) or
//!                               # "hertz" (paper 002 eq. 13: 2E* sqrt(R* delta),
//!                               # 8G* sqrt(R* delta), zero at delta <= 0)
//! D = 118.0                     # "powerlaw": F = sgn(v) D E* |v|^alpha a^beta
//! alpha = 3.0
//! beta = 1.5
//! tvis = 0.075                  # "krijt": relaxation time T_vis, s, >= 0
//! tvis0_per_radius = 2.1e-4     # "stress": C, s/m, >= 0: T_vis = C R exp[(B p_c/E*)^zeta]
//! B = 6.2                       # "stress": >= 0
//! zeta = 4.0                    # "stress": > 0
//! sigma0 = 2.9                  # "krijt"/"stress": Pa, >= 0, default 0: crack stress
//!                               # ~ gamma/(atomic spacing) of the contact-radius dynamics
//!                               # (eq. B2); 0 = a follows the JKR curve instantly
//! friction = 0.0                # >= 0, default 0: sliding friction mu_s (adhesive Coulomb
//!                               # limit |Ft| <= mu_s |F_N + 2 Fc|); > 0 makes particles rotate
//! rolling_hysteresis = 0.0      # jkr only, >= 0, default 0: Delta gamma / gamma of the
//!                               # rolling resistance (xi_crit = a0/12 * Delta gamma / gamma)
//! pulloff = "displacement"      # jkr only: "displacement" (default, breaks at
//!                               # -(3/4)^(2/3) delta0) or "force" (breaks at F = -Fc)
//! stiffness_scale = 1.0         # > 0, default 1: E -> S E and gamma -> gamma S^(2/5)
//! twisting_friction = 0.0       # >= 0, default 0 (off): Luding's twisting, mu_o
//! ko = 1e3                      # N/m, > 0, default 2/5 * 8 G* a at the current contact radius
//! gamma_o = 0.0                 # kg/s, >= 0, default 0
//!
//! [[interaction]]               # optional: the model for a pair of materials
//! materials = ["powder", "glass"]  # required: two material names (order does not matter)
//! model = "lsd"                 # required, with that model's parameters as in [[material]]
//! k = 300.0
//!
//! [[wall]]                      # optional: an infinite plane
//! point = [0.0, 0.0, 0.0]       # required, m: a point on the plane
//! normal = [0.0, 0.0, 1.0]      # required: points into the domain; need not be unit, non-zero
//! material = "powder"           # default: the first [[material]]
//! # at most one kind of motion (default: fixed); a moving wall has an infinite mass:
//! # velocity = [0.0, 0.0, -0.01] # m/s, prescribed from t = 0; or a schedule:
//! # velocities = [[0.0, 0.0, -0.01], [0.0, 0.0, 0.01]]  # m/s, piecewise constant,
//! # times = [0.0, 0.05]          #   velocities[k] from times[k] s (at rest before times[0]); or
//! # servo_force = 0.5            # N > 0: move along the normal to hold this normal force,
//! # servo_gain = 1e-3            #   m/s per N > 0: speed = clamp(gain·(servo_force − F), ±max)
//! # servo_max_speed = 0.01       #   m/s > 0 (stable while gain·k_bed·dt < 1)
//! # [[wall.phase]]              # or a program: phases, each one kind of motion as above
//! # from = 0.0                   #   (`velocity` or `servo_*`; neither: at rest) from `from`
//! # servo_force = 0.5            #   s on (>= 0, increasing; at rest before the first); a
//! # servo_gain = 1e-3            #   servo phase entered during the run starts at rest
//! # servo_max_speed = 0.01
//! # [[wall.phase]]
//! # from = 0.02
//! # velocity = [0.0, 0.0, 0.01]
//!
//! [[particles]]                 # one or more blocks, expanded in file order; particle ids
//!                               # (0-based) follow the order of expansion
//! kind = "list"                 # required: "list", "lattice" or "random"
//! material = "powder"           # default: the first [[material]]
//! insert_at = 0.0               # s, >= 0, default 0: when the block's particles appear
//!                               # (pouring; before that they neither move nor interact)
//!
//! # kind = "list": explicit particles
//! positions = [[0.005, 0.005, 0.005], [0.005, 0.005, 0.008]]   # required, m
//! radius = 1.1e-3               # m, > 0, for all; or
//! # radii = [1.1e-3, 1.0e-3]    # m, > 0, one per position (exactly one of radius / radii)
//! velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, -0.1]]  # m/s, optional, one per position; or
//! # velocity = [0.0, 0.0, 0.0] # m/s for all; default zero
//! # angular_velocity = [0.0, 0.0, 100.0]  # rad/s for all, any kind, default zero: only
//! #                             # where a contact model makes particles rotate
//!
//! # kind = "lattice": simple cubic lattice, x fastest, then y, then z
//! min = [0.0, 0.0, 0.0]         # required, m: region corner; spheres lie fully inside the region
//! max = [0.01, 0.01, 0.01]      # required, m
//! radius = 1e-3                 # required, m, > 0: all particles
//! spacing = 2.1e-3              # m, >= 2*radius, default 2*radius*(1 + 1e-9)
//! velocity = [0.0, 0.0, 0.0]    # m/s, default zero
//! jitter = 0.0                  # default 0, 0..=1: random displacement per axis of up to
//!                               # jitter*(spacing - 2*radius)/2, never causing overlaps
//! seed = 1                      # default 1: seed of the jitter
//!
//! # kind = "random": random sequential placement without overlaps (with every particle
//! # placed before, of all blocks, that appears at the same time), spheres fully inside the
//! # region; up to 1000 attempts per particle. Random sequential addition jams near a solid
//! # fraction of ~0.38.
//! # batches = 1                 # default 1: pour `count` in this many batches, each placed
//! # batch_interval = 0.01       #   afresh in the region (seed + k), batch k appearing at
//! #                             #   insert_at + k·batch_interval s (> 0 with batches > 1)
//! count = 500                   # required, >= 0
//! min = [0.0, 0.0, 0.0]         # required, m
//! max = [0.01, 0.01, 0.01]      # required, m
//! seed = 1                      # default 1: seed of radii and positions (Pcg64)
//! radius = 1e-3                 # m, > 0: a fixed radius; or a size distribution (exactly one):
//! # size = { distribution = "uniform", min = 0.8e-3, max = 1.2e-3 }   # m, 0 < min <= max
//! # size = { distribution = "normal", mean = 1e-3, std = 1e-4 }       # m, mean > 0, std >= 0
//! # size = { distribution = "lognormal", median = 1e-3, sigma = 0.2 } # median m > 0, sigma >= 0
//! # size = { distribution = "list", radii = [1e-3, 2e-3], weights = [3.0, 1.0] }
//! #        radii m > 0; weights >= 0 with a positive sum, default all equal
//! # (normal radii are truncated to (0, inf) by redrawing)
//! velocity = [0.0, 0.0, 0.0]    # m/s, default zero
//! ```
//!
//! # Checks at load time
//!
//! Besides the types and ranges above: material names are unique and every referenced
//! name exists; there is at least one particle; every sphere lies inside the domain
//! (within 1% of its radius); no two particles overlap by more than 1% of the smaller
//! radius, and no particle overlaps a wall by more than 1% of its radius; every pair of
//! different materials that can meet (particle–particle, particle–wall) has an
//! `[[interaction]]`.

use crate::error::{ParamError, PowderError};
use crate::model::{params, ContactModel};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, LogNormal, Normal};
use rand_pcg::Pcg64;
use std::collections::HashMap;
use std::fmt::Display;
use std::hash::{BuildHasherDefault, Hasher};
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Largest accepted overlap at start, as a fraction of the (smaller) radius.
pub const OVERLAP_TOLERANCE: f64 = 0.01;
/// Attempts to find a free spot for one particle of a `random` block.
pub const MAX_PLACEMENT_ATTEMPTS: usize = 1000;
/// Largest number of particles one `lattice` or `random` block may create (guards typos).
pub const MAX_BLOCK_PARTICLES: u64 = 100_000_000;

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
    /// Unit normal pointing into the domain.
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

/// A validated scene (see the module documentation for the file format).
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
    /// Steps between progress/summary lines.
    pub output_every: u64,
    /// Largest expected impact speed, m/s (default 1): sets the Hertz/JKR contact time
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
        let name = if name.is_empty() { "default" } else { name };
        let src = Src { name, text };
        parse_scene(&src)
    }

    /// Reads and parses a scene file; the scene is named after the file stem.
    pub fn load(path: &Path) -> Result<Scene, PowderError> {
        Self::load_with(path, &[])
    }

    /// Loads a scene file with `--set KEY=VALUE` overrides applied ([`crate::overrides`]).
    pub fn load_with(path: &Path, sets: &[String]) -> Result<Scene, PowderError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            PowderError::io(format!("cannot read scene file `{}`", path.display()), e)
        })?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let text = crate::overrides::apply(&text, sets)?;
        Self::from_toml_str(&text, &name)
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

// ---------------------------------------------------------------------------------------
// Key lists
// ---------------------------------------------------------------------------------------

const TOP_KEYS: &[&str] = &[
    "domain",
    "simulation",
    "material",
    "interaction",
    "wall",
    "particles",
];
/// Particles below which `contact_output` defaults to on (the contact network files of a
/// larger scene get large: a dense packing has about three contacts per particle).
pub const CONTACT_OUTPUT_BELOW: usize = 100_000;

const DOMAIN_KEYS: &[&str] = &["min", "max", "periodic"];
const SIMULATION_KEYS: &[&str] = &[
    "duration",
    "dt",
    "force_dt",
    "jump_impulses",
    "output_every",
    "gravity",
    "impact_velocity",
    "checkpoint_every",
    "contact_output",
];
const MATERIAL_KEYS: &[&str] = &["name", "density", "model"];
const INTERACTION_KEYS: &[&str] = &["materials", "model"];
const WALL_KEYS: &[&str] = &[
    "point",
    "normal",
    "material",
    "velocities",
    "times",
    "phase",
];
const PHASE_KEYS: &[&str] = &["from"];
const SERVO_KEYS: &[&str] = &["servo_force", "servo_gain", "servo_max_speed"];

/// `keys` and those of one kind of motion (a wall's or a phase's).
fn with_motion_keys(keys: &[&'static str]) -> Vec<&'static str> {
    let motion = std::iter::once(&"velocity").chain(SERVO_KEYS);
    keys.iter().chain(motion).copied().collect()
}
const PARTICLE_KINDS: &[&str] = &["list", "lattice", "random"];
const LIST_KEYS: &[&str] = &[
    "kind",
    "material",
    "positions",
    "radius",
    "radii",
    "velocities",
    "velocity",
    "angular_velocity",
    "insert_at",
];
const LATTICE_KEYS: &[&str] = &[
    "kind",
    "material",
    "min",
    "max",
    "radius",
    "spacing",
    "velocity",
    "angular_velocity",
    "jitter",
    "seed",
    "insert_at",
];
const RANDOM_KEYS: &[&str] = &[
    "kind",
    "material",
    "count",
    "min",
    "max",
    "seed",
    "radius",
    "size",
    "velocity",
    "angular_velocity",
    "insert_at",
    "batches",
    "batch_interval",
];
const DISTRIBUTIONS: &[&str] = &["uniform", "normal", "lognormal", "list"];

// ---------------------------------------------------------------------------------------
// Source positions and a span-carrying value tree
// ---------------------------------------------------------------------------------------

type Span = Range<usize>;
type Res<T> = Result<T, PowderError>;

struct Src<'a> {
    name: &'a str,
    text: &'a str,
}

impl Src<'_> {
    /// 1-based line and column (in characters) of a byte offset.
    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut off = offset.min(self.text.len());
        while !self.text.is_char_boundary(off) {
            off -= 1;
        }
        let before = &self.text[..off];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
        (line, col)
    }

    fn err(&self, span: Option<&Span>, msg: impl Display) -> PowderError {
        match span {
            Some(s) => {
                let (line, col) = self.line_col(s.start);
                PowderError::Scene(format!(
                    "scene `{}`, line {line}, column {col}: {msg}",
                    self.name
                ))
            }
            None => PowderError::Scene(format!("scene `{}`: {msg}", self.name)),
        }
    }
}

#[derive(Debug)]
enum Val {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime,
    Array(Vec<Node>),
    Table(Vec<Entry>),
}

#[derive(Debug)]
struct Node {
    span: Span,
    val: Val,
}

#[derive(Debug)]
struct Entry {
    key: String,
    key_span: Span,
    node: Node,
}

fn convert_value(src: &Src, v: &Spanned<DeValue>) -> Res<Node> {
    let span = v.span();
    let val = match v.get_ref() {
        DeValue::String(s) => Val::Str(s.to_string()),
        DeValue::Integer(i) => match i64::from_str_radix(i.as_str(), i.radix()) {
            Ok(x) => Val::Int(x),
            Err(_) => {
                return Err(src.err(
                    Some(&span),
                    format!("the integer {i} does not fit in 64 bits"),
                ))
            }
        },
        DeValue::Float(f) => match f.as_str().parse::<f64>() {
            Ok(x) => Val::Float(x),
            Err(_) => return Err(src.err(Some(&span), format!("cannot read the number {f}"))),
        },
        DeValue::Boolean(b) => Val::Bool(*b),
        DeValue::Datetime(_) => Val::Datetime,
        DeValue::Array(a) => Val::Array(
            a.iter()
                .map(|x| convert_value(src, x))
                .collect::<Res<Vec<_>>>()?,
        ),
        DeValue::Table(t) => Val::Table(convert_table(src, t)?),
    };
    Ok(Node { span, val })
}

fn convert_table(src: &Src, t: &DeTable) -> Res<Vec<Entry>> {
    let mut entries = t
        .iter()
        .map(|(k, v)| {
            Ok(Entry {
                key: k.get_ref().to_string(),
                key_span: k.span(),
                node: convert_value(src, v)?,
            })
        })
        .collect::<Res<Vec<_>>>()?;
    entries.sort_by_key(|e| e.key_span.start);
    Ok(entries)
}

fn describe(node: &Node) -> String {
    match &node.val {
        Val::Str(s) => {
            let hint = if s.trim().parse::<f64>().is_ok() {
                " (write numbers without quotes)"
            } else {
                ""
            };
            format!("the string {s:?}{hint}")
        }
        Val::Int(i) => format!("the integer {i}"),
        Val::Float(f) => format!("the number {f}"),
        Val::Bool(b) => format!("the boolean {b}"),
        Val::Datetime => "a date-time".to_string(),
        Val::Array(a) => format!("an array of {} element(s)", a.len()),
        Val::Table(_) => "a table".to_string(),
    }
}

fn node_number(node: &Node) -> Option<f64> {
    match node.val {
        Val::Int(i) => Some(i as f64),
        Val::Float(f) => Some(f),
        _ => None,
    }
}

/// The candidate closest to `word`, if it is close enough to be a likely typo.
fn suggest<'k>(word: &str, candidates: &[&'k str]) -> Option<&'k str> {
    let w = word.to_lowercase();
    candidates
        .iter()
        .map(|c| {
            let score =
                strsim::jaro_winkler(&w, c).max(strsim::normalized_damerau_levenshtein(&w, c));
            (score, *c)
        })
        .filter(|(s, _)| *s >= 0.7)
        .fold(None, |best: Option<(f64, &str)>, x| match best {
            Some(b) if b.0 >= x.0 => Some(b),
            _ => Some(x),
        })
        .map(|(_, c)| c)
}

fn quoted_list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
fn one_of_strings(options: &[&str]) -> String {
    let q: Vec<String> = options.iter().map(|o| format!("\"{o}\"")).collect();
    match q.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

fn fmt_vec(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

const AXES: [&str; 3] = ["x", "y", "z"];

// ---------------------------------------------------------------------------------------
// Typed access to one table
// ---------------------------------------------------------------------------------------

struct Tbl<'a> {
    src: &'a Src<'a>,
    entries: &'a [Entry],
    span: Option<Span>,
    ctx: String,
}

impl<'a> Tbl<'a> {
    fn new(src: &'a Src<'a>, entries: &'a [Entry], span: Option<Span>, ctx: String) -> Self {
        Self {
            src,
            entries,
            span,
            ctx,
        }
    }

    fn entry(&self, key: &str) -> Option<&'a Entry> {
        self.entries.iter().find(|e| e.key == key)
    }

    fn get(&self, key: &str) -> Option<&'a Node> {
        self.entry(key).map(|e| &e.node)
    }

    fn has(&self, key: &str) -> bool {
        self.entry(key).is_some()
    }

    /// An error located at the value of `key` (or at the table when the key is absent).
    fn err_key(&self, key: &str, msg: impl Display) -> PowderError {
        let span = self.get(key).map(|n| &n.span).or(self.span.as_ref());
        self.src.err(span, msg)
    }

    fn err_node(&self, node: &Node, msg: impl Display) -> PowderError {
        self.src.err(Some(&node.span), msg)
    }

    fn err_table(&self, msg: impl Display) -> PowderError {
        self.src.err(self.span.as_ref(), msg)
    }

    fn missing(&self, key: &str, what: &str) -> PowderError {
        self.err_table(format!(
            "missing required key `{key}` in {}: {what}",
            self.ctx
        ))
    }

    fn type_err(&self, key: &str, node: &Node, expected: &str) -> PowderError {
        self.err_node(
            node,
            format!(
                "`{key}` in {} must be {expected}, got {}",
                self.ctx,
                describe(node)
            ),
        )
    }

    /// Rejects keys outside `allowed`; `hint` may explain a known-but-misplaced key.
    fn check_keys(&self, allowed: &[&str], hint: impl Fn(&str) -> Option<String>) -> Res<()> {
        for e in self.entries {
            if allowed.contains(&e.key.as_str()) {
                continue;
            }
            let valid = quoted_list(allowed);
            let msg = if let Some(h) = hint(&e.key) {
                format!(
                    "unknown key `{}` in {}: {h} (valid keys: {valid})",
                    e.key, self.ctx
                )
            } else if let Some(s) = suggest(&e.key, allowed) {
                format!(
                    "unknown key `{}` in {}: did you mean `{s}`? (valid keys: {valid})",
                    e.key, self.ctx
                )
            } else {
                format!(
                    "unknown key `{}` in {}; valid keys are {valid}",
                    e.key, self.ctx
                )
            };
            return Err(self.src.err(Some(&e.key_span), msg));
        }
        Ok(())
    }

    fn f64(&self, key: &str) -> Res<Option<f64>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let x = node_number(node).ok_or_else(|| self.type_err(key, node, "a number"))?;
        if !x.is_finite() {
            return Err(self.err_node(
                node,
                format!("`{key}` in {} must be a finite number, got {x}", self.ctx),
            ));
        }
        Ok(Some(x))
    }

    fn f64_req(&self, key: &str, what: &str) -> Res<f64> {
        self.f64(key)?.ok_or_else(|| self.missing(key, what))
    }

    /// `key` > 0 if present.
    fn positive(&self, key: &str, what: &str) -> Res<Option<f64>> {
        match self.f64(key)? {
            Some(x) if x <= 0.0 => Err(self.err_key(
                key,
                format!("`{key}` in {} ({what}) must be > 0, got {x}", self.ctx),
            )),
            other => Ok(other),
        }
    }

    fn positive_req(&self, key: &str, what: &str) -> Res<f64> {
        self.positive(key, what)?
            .ok_or_else(|| self.missing(key, what))
    }

    fn u64(&self, key: &str) -> Res<Option<u64>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match node.val {
            Val::Int(i) if i >= 0 => Ok(Some(i as u64)),
            _ => Err(self.type_err(key, node, "a non-negative integer")),
        }
    }

    fn bool(&self, key: &str) -> Res<Option<bool>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match node.val {
            Val::Bool(b) => Ok(Some(b)),
            _ => Err(self.type_err(key, node, "true or false")),
        }
    }

    fn str(&self, key: &str) -> Res<Option<&'a str>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match &node.val {
            Val::Str(s) => Ok(Some(s.as_str())),
            _ => Err(self.type_err(key, node, "a string")),
        }
    }

    /// A string from a fixed set of options, with a suggestion for near misses.
    fn choice(&self, key: &str, options: &[&'static str]) -> Res<Option<&'static str>> {
        let expected = one_of_strings(options);
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Str(s) = &node.val else {
            return Err(self.type_err(key, node, &expected));
        };
        if let Some(o) = options.iter().find(|o| **o == s.as_str()) {
            return Ok(Some(*o));
        }
        let mut msg = format!("`{key}` in {} must be {expected}, got \"{s}\"", self.ctx);
        if let Some(sug) = suggest(s, options) {
            msg.push_str(&format!(": did you mean \"{sug}\"?"));
        }
        Err(self.err_node(node, msg))
    }

    fn vec3_of(&self, key: &str, node: &Node) -> Res<[f64; 3]> {
        let expected = "an array of 3 numbers [x, y, z]";
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, expected));
        };
        if items.len() != 3 {
            return Err(self.type_err(key, node, expected));
        }
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            let x = node_number(item).ok_or_else(|| {
                self.err_node(
                    item,
                    format!(
                        "`{key}` in {} must be {expected}, but an element is {}",
                        self.ctx,
                        describe(item)
                    ),
                )
            })?;
            if !x.is_finite() {
                return Err(self.err_node(
                    item,
                    format!(
                        "`{key}` in {} must contain finite numbers, got {x}",
                        self.ctx
                    ),
                ));
            }
            *o = x;
        }
        Ok(out)
    }

    fn vec3(&self, key: &str) -> Res<Option<[f64; 3]>> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => self.vec3_of(key, node).map(Some),
        }
    }

    fn vec3_req(&self, key: &str, what: &str) -> Res<[f64; 3]> {
        self.vec3(key)?.ok_or_else(|| self.missing(key, what))
    }

    fn vec3_list(&self, key: &str) -> Res<Option<Vec<[f64; 3]>>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, "an array of [x, y, z] arrays"));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| self.vec3_of(&format!("{key}[{i}]"), item))
            .collect::<Res<Vec<_>>>()
            .map(Some)
    }

    fn f64_list(&self, key: &str) -> Res<Option<Vec<f64>>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, "an array of numbers"));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                let x = node_number(item)
                    .ok_or_else(|| self.type_err(&format!("{key}[{i}]"), item, "a number"))?;
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(self.err_node(
                        item,
                        format!(
                            "`{key}[{i}]` in {} must be a finite number, got {x}",
                            self.ctx
                        ),
                    ))
                }
            })
            .collect::<Res<Vec<_>>>()
            .map(Some)
    }

    /// A sub-table `[key]` (or inline table).
    fn table(&self, key: &str, ctx: String) -> Res<Option<Tbl<'a>>> {
        let Some(e) = self.entry(key) else {
            return Ok(None);
        };
        match &e.node.val {
            Val::Table(entries) => Ok(Some(Tbl::new(
                self.src,
                entries,
                Some(e.key_span.clone()),
                ctx,
            ))),
            _ => Err(self.type_err(key, &e.node, "a table")),
        }
    }

    /// An array of tables `[[key]]`, each with its span.
    fn tables(&self, key: &str) -> Res<Vec<(Span, &'a [Entry])>> {
        let Some(node) = self.get(key) else {
            return Ok(Vec::new());
        };
        let expected = format!("an array of tables, written [[{key}]]");
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, &expected));
        };
        items
            .iter()
            .map(|item| match &item.val {
                Val::Table(entries) => Ok((item.span.clone(), entries.as_slice())),
                _ => Err(self.type_err(key, item, &expected)),
            })
            .collect()
    }
}

// ---------------------------------------------------------------------------------------
// Scene parsing
// ---------------------------------------------------------------------------------------

fn parse_scene(src: &Src) -> Res<Scene> {
    let doc = DeTable::parse(src.text).map_err(|e| {
        let msg = format!("TOML syntax error: {}", e.message().trim_end());
        src.err(e.span().as_ref(), msg)
    })?;
    let root_entries = convert_table(src, doc.get_ref())?;
    let root = Tbl::new(src, &root_entries, None, "the top-level table".to_string());
    root.check_keys(TOP_KEYS, |k| {
        let sections: [(&str, &[&str]); 2] =
            [("simulation", SIMULATION_KEYS), ("domain", DOMAIN_KEYS)];
        sections
            .iter()
            .find(|(_, keys)| keys.contains(&k))
            .map(|(s, _)| format!("`{k}` belongs in the [{s}] table"))
    })?;

    let domain = parse_domain(&root)?;
    let sim = parse_simulation(&root)?;
    let materials = parse_materials(&root)?;
    let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
    let interactions = parse_interactions(&root, &names)?;
    let walls = parse_walls(&root, &names)?;
    let (particles, origin) = parse_particles(&root, &names)?;

    let scene = Scene {
        name: src.name.to_string(),
        domain,
        gravity: sim.gravity,
        dt: sim.dt,
        force_dt: sim.force_dt,
        jump_impulses: sim.jump_impulses,
        impact_velocity: sim.impact_velocity,
        checkpoint_every: sim.checkpoint_every,
        contact_output: sim.contact_output,
        duration: sim.duration,
        output_every: sim.output_every,
        materials,
        interactions,
        walls,
        particles,
    };
    check_periodic(src, &scene)?;
    check_particles(src, &scene, &origin)?;
    check_pair_models(src, &scene)?;
    Ok(scene)
}

fn parse_domain(root: &Tbl) -> Res<Domain> {
    let t = root
        .table("domain", "[domain]".to_string())?
        .ok_or_else(|| {
            root.src.err(
                None,
                "missing required table [domain]: add [domain] with min = [x, y, z] and max = [x, y, z] in m",
            )
        })?;
    t.check_keys(DOMAIN_KEYS, |_| None)?;
    let min = t.vec3_req("min", "the lower corner [x, y, z] of the domain in m")?;
    let max = t.vec3_req("max", "the upper corner [x, y, z] of the domain in m")?;
    for a in 0..3 {
        if max[a] <= min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "[domain] max must be > min on every axis, but on axis {} max = {} <= min = {}",
                    AXES[a], max[a], min[a]
                ),
            ));
        }
    }
    let mut periodic = [false; 3];
    if let Some(node) = t.get("periodic") {
        let expected = "an array of 3 booleans [x, y, z], e.g. [true, true, false]";
        let Val::Array(items) = &node.val else {
            return Err(t.type_err("periodic", node, expected));
        };
        if items.len() != 3 {
            return Err(t.type_err("periodic", node, expected));
        }
        for (a, item) in items.iter().enumerate() {
            match item.val {
                Val::Bool(b) => periodic[a] = b,
                _ => return Err(t.type_err("periodic", node, expected)),
            }
        }
    }
    Ok(Domain { min, max, periodic })
}

struct SimSettings {
    duration: f64,
    dt: DtSetting,
    force_dt: bool,
    jump_impulses: Option<bool>,
    output_every: u64,
    impact_velocity: f64,
    checkpoint_every: u64,
    contact_output: Option<bool>,
    gravity: [f64; 3],
}

fn parse_simulation(root: &Tbl) -> Res<SimSettings> {
    let t = root
        .table("simulation", "[simulation]".to_string())?
        .ok_or_else(|| {
            root.src.err(
                None,
                "missing required table [simulation]: add [simulation] with at least duration = <s>",
            )
        })?;
    t.check_keys(SIMULATION_KEYS, |_| None)?;
    let duration = t.positive_req("duration", "the simulated time in s")?;
    let dt = match t.get("dt") {
        None => DtSetting::Auto,
        Some(node) => match &node.val {
            Val::Str(s) if s == "auto" => DtSetting::Auto,
            _ => match node_number(node) {
                Some(x) if x.is_finite() && x > 0.0 => DtSetting::Fixed(x),
                Some(x) => {
                    return Err(t.err_node(
                        node,
                        format!(
                        "`dt` in [simulation] must be \"auto\" or a time step > 0 in s, got {x}"
                    ),
                    ))
                }
                None => return Err(t.type_err("dt", node, "\"auto\" or a time step > 0 in s")),
            },
        },
    };
    let force_dt = t.bool("force_dt")?.unwrap_or(false);
    let jump_impulses = t.bool("jump_impulses")?;
    let output_every = t.u64("output_every")?.unwrap_or(1000);
    if output_every == 0 {
        return Err(t.err_key(
            "output_every",
            "`output_every` in [simulation] must be >= 1 (steps between progress lines), got 0",
        ));
    }
    let gravity = t.vec3("gravity")?.unwrap_or([0.0; 3]);
    let impact_velocity = t
        .positive(
            "impact_velocity",
            "the largest expected impact speed in m/s",
        )?
        .unwrap_or(1.0);
    let checkpoint_every = t.u64("checkpoint_every")?.unwrap_or(10 * output_every);
    if checkpoint_every == 0 {
        return Err(t.err_key(
            "checkpoint_every",
            "`checkpoint_every` in [simulation] must be >= 1 (steps between checkpoints), got 0",
        ));
    }
    Ok(SimSettings {
        checkpoint_every,
        contact_output: t.bool("contact_output")?,
        impact_velocity,
        duration,
        dt,
        force_dt,
        jump_impulses,
        output_every,
        gravity,
    })
}

fn parse_materials(root: &Tbl) -> Res<Vec<Material>> {
    let tables = root.tables("material")?;
    if tables.is_empty() {
        return Err(root.src.err(
            None,
            "no [[material]]: add at least one, e.g. [[material]] name = \"powder\", density = 2000.0, model = \"lsd\", k = 100.0",
        ));
    }
    let mut out: Vec<Material> = Vec::with_capacity(tables.len());
    for (i, (span, entries)) in tables.into_iter().enumerate() {
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[material]] #{}", i + 1),
        );
        if let Some(Val::Str(name)) = t.get("name").map(|n| &n.val) {
            t.ctx = format!("[[material]] #{} (`{name}`)", i + 1);
        }
        let kind = model_kind(&t, MATERIAL_KEYS)?;
        let name = t.str("name")?.ok_or_else(|| {
            t.missing(
                "name",
                "the material's name, used by particles, walls and interactions",
            )
        })?;
        if name.trim().is_empty() {
            return Err(t.err_key("name", format!("`name` in {} must not be empty", t.ctx)));
        }
        if let Some(j) = out.iter().position(|m| m.name == name) {
            return Err(t.err_key(
                "name",
                format!(
                    "duplicate material name `{name}` in {} (also [[material]] #{}): names must be unique",
                    t.ctx,
                    j + 1
                ),
            ));
        }
        let model = build_model(&t, kind, MATERIAL_KEYS, &format!("material `{name}`"))?;
        let density = t.positive_req("density", "the material density in kg/m^3")?;
        out.push(Material {
            name: name.to_string(),
            density,
            model,
        });
    }
    Ok(out)
}

/// Reads `model` and checks that the table's keys are `common` or some law's parameters
/// (each law's own keys are checked by [`params::read_model`]).
fn model_kind(t: &Tbl, common: &[&str]) -> Res<&'static str> {
    let names = params::law_names();
    let Some(kind) = t.choice("model", &names)? else {
        let mut all: Vec<&str> = common.to_vec();
        all.extend(params::all_params().iter().map(|p| p.key));
        t.check_keys(&all, |_| None)?;
        return Err(t.missing(
            "model",
            &format!("the contact model, {}", one_of_strings(&names)),
        ));
    };
    Ok(kind)
}

/// A scene table as a source of contact-law parameters.
struct TableParams<'t, 'a> {
    t: &'t Tbl<'a>,
    /// The table's own keys (name, density, materials, model).
    common: &'t [&'t str],
    /// "material `glass`", "interaction `a`-`b`".
    owner: &'t str,
}

impl params::ParamSource for TableParams<'_, '_> {
    type Error = PowderError;

    fn keys(&self) -> Vec<String> {
        self.t
            .entries
            .iter()
            .map(|e| e.key.clone())
            .filter(|k| !self.common.contains(&k.as_str()))
            .collect()
    }

    fn raw(&self, key: &str) -> Option<params::Raw> {
        let node = self.t.get(key)?;
        Some(match &node.val {
            Val::Int(i) => params::Raw::Number(*i as f64),
            Val::Float(x) => params::Raw::Number(*x),
            Val::Str(s) => params::Raw::Text(s.clone()),
            _ => params::Raw::Other(describe(node)),
        })
    }

    fn name(&self, key: &str) -> String {
        format!("`{key}` in {}", self.t.ctx)
    }

    fn setting(&self, key: &str, value: &str) -> String {
        format!("{key} = \"{value}\"")
    }

    fn error(&self, key: &str, message: String) -> PowderError {
        self.t.err_key(key, message)
    }

    fn missing(&self, key: &str, what: &str) -> PowderError {
        self.t.missing(key, what)
    }

    fn unknown(&self, key: &str, law: &params::Law, owner: Option<&str>) -> PowderError {
        let mut allowed: Vec<&str> = self.common.to_vec();
        allowed.extend(params::keys_of(law));
        let hint = |k: &str| {
            owner.filter(|_| k == key).map(|m| {
                format!(
                    "`{k}` is a parameter of the `{m}` model, but {} uses model = \"{}\"",
                    self.owner, law.name
                )
            })
        };
        match self.t.check_keys(&allowed, hint) {
            Err(e) => e,
            Ok(()) => self
                .t
                .err_key(key, format!("unknown key `{key}` in {}", self.t.ctx)),
        }
    }

    fn invalid(&self, e: ParamError) -> PowderError {
        self.t.err_key(e.param, format!("{}: {e}", self.owner))
    }
}

fn build_model(t: &Tbl, kind: &str, common: &[&str], owner: &str) -> Res<ContactModel> {
    params::read_model(&TableParams { t, common, owner }, kind)
}

/// Resolves a material name; errors list the known names.
fn material_index(t: &Tbl, node: &Node, key: &str, name: &str, names: &[&str]) -> Res<usize> {
    if let Some(i) = names.iter().position(|n| *n == name) {
        return Ok(i);
    }
    let mut msg = format!(
        "unknown material `{name}` in `{key}` of {}; known materials are {}",
        t.ctx,
        quoted_list(names)
    );
    if let Some(s) = suggest(name, names) {
        msg.push_str(&format!(": did you mean `{s}`?"));
    }
    Err(t.err_node(node, msg))
}

/// The optional `material` key of a wall or particle block; default the first material.
fn material_ref(t: &Tbl, names: &[&str]) -> Res<usize> {
    match t.str("material")? {
        None => Ok(0),
        Some(name) => {
            let node = t.get("material").expect("present");
            material_index(t, node, "material", name, names)
        }
    }
}

fn parse_interactions(root: &Tbl, names: &[&str]) -> Res<Vec<Interaction>> {
    let mut out: Vec<Interaction> = Vec::new();
    for (i, (span, entries)) in root.tables("interaction")?.into_iter().enumerate() {
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[interaction]] #{}", i + 1),
        );
        let kind = model_kind(&t, INTERACTION_KEYS)?;
        let expected = "an array of two material names, e.g. [\"powder\", \"glass\"]";
        let node = t
            .get("materials")
            .ok_or_else(|| t.missing("materials", expected))?;
        let pair: Vec<&str> = match &node.val {
            Val::Array(items) if items.len() == 2 => items
                .iter()
                .map(|it| match &it.val {
                    Val::Str(s) => Ok(s.as_str()),
                    _ => Err(t.type_err("materials", node, expected)),
                })
                .collect::<Res<Vec<_>>>()?,
            _ => return Err(t.type_err("materials", node, expected)),
        };
        let a = material_index(&t, node, "materials", pair[0], names)?;
        let b = material_index(&t, node, "materials", pair[1], names)?;
        t.ctx = format!("[[interaction]] #{} (`{}`-`{}`)", i + 1, names[a], names[b]);
        if let Some(j) = out
            .iter()
            .position(|x| x.materials == [a, b] || x.materials == [b, a])
        {
            return Err(t.err_key(
                "materials",
                format!(
                    "duplicate interaction for materials `{}` and `{}` in {} (also [[interaction]] #{})",
                    names[a],
                    names[b],
                    t.ctx,
                    j + 1
                ),
            ));
        }
        let owner = format!("interaction `{}`-`{}`", names[a], names[b]);
        let model = build_model(&t, kind, INTERACTION_KEYS, &owner)?;
        out.push(Interaction {
            materials: [a, b],
            model,
        });
    }
    Ok(out)
}

/// `velocity`, or `velocities` with `times`, or `servo_*`, or `[[wall.phase]]`: at most
/// one kind of motion.
fn parse_wall_motion(t: &Tbl) -> Res<WallMotion> {
    let kinds = [
        t.has("velocity"),
        t.has("velocities") || t.has("times"),
        SERVO_KEYS.iter().any(|k| t.has(k)),
        t.has("phase"),
    ];
    if kinds.iter().filter(|&&k| k).count() > 1 {
        return Err(t.err_table(format!(
            "{} mixes kinds of motion: give `velocity` (constant), or `velocities` with `times` (a schedule), or `servo_force`, `servo_gain` and `servo_max_speed` (force control), or `[[wall.phase]]` tables (a program)",
            t.ctx
        )));
    }
    if kinds[1] {
        let velocities = t.vec3_list("velocities")?.ok_or_else(|| {
            t.missing(
                "velocities",
                "the wall velocities [[vx, vy, vz], ...] in m/s, one per entry of `times`",
            )
        })?;
        let times = t.f64_list("times")?.ok_or_else(|| {
            t.missing(
                "times",
                "the times in s from which each of `velocities` applies, increasing",
            )
        })?;
        if velocities.len() != times.len() || times.is_empty() {
            return Err(t.err_key(
                "times",
                format!(
                    "`times` in {} has {} entries and `velocities` {}: give one start time per velocity",
                    t.ctx,
                    times.len(),
                    velocities.len()
                ),
            ));
        }
        check_increasing(t, "times", &times)?;
        let phases = times.into_iter().zip(velocities);
        return Ok(WallMotion {
            phases: phases.map(|(t, v)| (t, WallPhase::Velocity(v))).collect(),
        });
    }
    if kinds[3] {
        let mut phases = Vec::new();
        for (i, (span, entries)) in t.tables("phase")?.into_iter().enumerate() {
            let p = Tbl::new(
                t.src,
                entries,
                Some(span),
                format!("{} phase #{}", t.ctx, i + 1),
            );
            p.check_keys(&with_motion_keys(PHASE_KEYS), |_| None)?;
            let from = p.f64_req("from", "the time in s from which the phase applies")?;
            phases.push((from, parse_wall_phase(&p)?));
        }
        let times: Vec<f64> = phases.iter().map(|(from, _)| *from).collect();
        check_increasing(t, "phase", &times)?;
        return Ok(WallMotion { phases });
    }
    Ok(match parse_wall_phase(t)? {
        WallPhase::Rest => WallMotion::fixed(),
        phase => WallMotion::always(phase),
    })
}

/// Phase start times: at least one, from >= 0 s, strictly increasing.
fn check_increasing(t: &Tbl, key: &str, times: &[f64]) -> Res<()> {
    if times.is_empty() || times[0] < 0.0 || times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(t.err_key(
            key,
            format!(
                "the start times in {} (`{key}`) must start at >= 0 s and increase strictly, got {times:?}",
                t.ctx
            ),
        ));
    }
    Ok(())
}

/// One phase's motion: `velocity`, or `servo_*`, or neither (at rest).
fn parse_wall_phase(t: &Tbl) -> Res<WallPhase> {
    let servo = SERVO_KEYS.iter().any(|k| t.has(k));
    if t.has("velocity") && servo {
        return Err(t.err_table(format!(
            "{} mixes kinds of motion: give `velocity` or `servo_force`, `servo_gain` and `servo_max_speed`",
            t.ctx
        )));
    }
    if let Some(v) = t.vec3("velocity")? {
        return Ok(WallPhase::Velocity(v));
    }
    if servo {
        let force = t.positive_req(
            "servo_force",
            "the normal force in N the servo-controlled wall holds",
        )?;
        let gain = t.positive_req(
            "servo_gain",
            "the servo gain in m/s per N of force error (stable while gain·k_bed·dt < 1)",
        )?;
        let max_speed = t.positive_req(
            "servo_max_speed",
            "the largest speed in m/s of the servo-controlled wall",
        )?;
        return Ok(WallPhase::Servo {
            force,
            gain,
            max_speed,
        });
    }
    Ok(WallPhase::Rest)
}

fn parse_walls(root: &Tbl, names: &[&str]) -> Res<Vec<Wall>> {
    let mut out = Vec::new();
    for (i, (span, entries)) in root.tables("wall")?.into_iter().enumerate() {
        let t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[wall]] #{}", i + 1),
        );
        t.check_keys(&with_motion_keys(WALL_KEYS), |_| None)?;
        let point = t.vec3_req("point", "a point [x, y, z] on the wall plane in m")?;
        let n = t.vec3_req(
            "normal",
            "the wall normal [x, y, z], pointing into the domain",
        )?;
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if !(len > 0.0 && len.is_finite()) {
            return Err(t.err_key(
                "normal",
                format!(
                    "`normal` in {} must be a non-zero vector pointing into the domain, got {}",
                    t.ctx,
                    fmt_vec(n)
                ),
            ));
        }
        let material = material_ref(&t, names)?;
        let motion = parse_wall_motion(&t)?;
        out.push(Wall {
            point,
            normal: [n[0] / len, n[1] / len, n[2] / len],
            motion,
            material,
        });
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// Particle blocks
// ---------------------------------------------------------------------------------------

/// Where each particle came from, for messages: the 1-based `[[particles]]` block.
type Origin = Vec<usize>;

fn parse_particles(root: &Tbl, names: &[&str]) -> Res<(Vec<ParticleInit>, Origin)> {
    let blocks = root.tables("particles")?;
    if blocks.is_empty() {
        return Err(root.src.err(
            None,
            "the scene has no particles: add a [[particles]] block (kind = \"list\", \"lattice\" or \"random\")",
        ));
    }
    let mut particles: Vec<ParticleInit> = Vec::new();
    let mut origin: Origin = Vec::new();
    for (i, (span, entries)) in blocks.into_iter().enumerate() {
        let block = i + 1;
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[particles]] #{block}"),
        );
        let kind = t.choice("kind", PARTICLE_KINDS)?.ok_or_else(|| {
            t.missing(
                "kind",
                "how to create the particles: \"list\", \"lattice\" or \"random\"",
            )
        })?;
        t.ctx = format!("[[particles]] #{block} (kind = \"{kind}\")");
        let before = particles.len();
        let insert_at = t.f64("insert_at")?.unwrap_or(0.0);
        if insert_at < 0.0 {
            return Err(t.err_key(
                "insert_at",
                format!(
                    "`insert_at` in {} is {insert_at} s: the time the block's particles appear must be >= 0",
                    t.ctx
                ),
            ));
        }
        match kind {
            "list" => {
                t.check_keys(LIST_KEYS, |_| None)?;
                expand_list(&t, names, &mut particles)?;
            }
            "lattice" => {
                t.check_keys(LATTICE_KEYS, |_| None)?;
                expand_lattice(&t, names, &mut particles)?;
            }
            _ => {
                t.check_keys(RANDOM_KEYS, |_| None)?;
                // pouring: `batches` batches of count/batches, `batch_interval` s apart,
                // each placed afresh in the region
                let batches = t.u64("batches")?.unwrap_or(1);
                let interval = t.f64("batch_interval")?.unwrap_or(0.0);
                if batches == 0 || (batches > 1 && (interval.is_nan() || interval <= 0.0)) {
                    return Err(t.err_key(
                        "batches",
                        format!(
                            "{}: `batches` must be >= 1, and a pour of several batches needs `batch_interval` > 0 s (the time between them)",
                            t.ctx
                        ),
                    ));
                }
                for k in 0..batches {
                    expand_random(
                        &t,
                        names,
                        &mut particles,
                        insert_at + k as f64 * interval,
                        (k, batches),
                    )?;
                }
            }
        }
        if kind != "random" {
            for p in &mut particles[before..] {
                p.insert_at = insert_at;
            }
        }
        origin.resize(origin.len() + particles.len() - before, block);
    }
    Ok((particles, origin))
}

/// Reads an optional `velocity` (for all particles of a block).
fn block_velocity(t: &Tbl) -> Res<[f64; 3]> {
    Ok(t.vec3("velocity")?.unwrap_or([0.0; 3]))
}

fn block_angular_velocity(t: &Tbl) -> Res<[f64; 3]> {
    Ok(t.vec3("angular_velocity")?.unwrap_or([0.0; 3]))
}

fn region(t: &Tbl) -> Res<([f64; 3], [f64; 3])> {
    let min = t.vec3_req("min", "the lower corner [x, y, z] of the region in m")?;
    let max = t.vec3_req("max", "the upper corner [x, y, z] of the region in m")?;
    for a in 0..3 {
        if max[a] <= min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "the region of {} must have max > min on every axis, but on axis {} max = {} <= min = {}",
                    t.ctx, AXES[a], max[a], min[a]
                ),
            ));
        }
    }
    Ok((min, max))
}

fn one_of(t: &Tbl, a: &str, b: &str, what: &str) -> Res<()> {
    match (t.has(a), t.has(b)) {
        (true, true) => Err(t.err_key(
            b,
            format!("{} has both `{a}` and `{b}`: give only one ({what})", t.ctx),
        )),
        (false, false) => Err(t.err_table(format!(
            "missing required key in {}: give `{a}` or `{b}` ({what})",
            t.ctx
        ))),
        _ => Ok(()),
    }
}

fn expand_list(t: &Tbl, names: &[&str], out: &mut Vec<ParticleInit>) -> Res<()> {
    let material = material_ref(t, names)?;
    let positions = t
        .vec3_list("positions")?
        .ok_or_else(|| t.missing("positions", "the particle centres [[x, y, z], ...] in m"))?;
    let n = positions.len();
    one_of(
        t,
        "radius",
        "radii",
        "one radius for all particles in m, or one per position",
    )?;
    let radii = match t.positive("radius", "the particle radius in m")? {
        Some(r) => vec![r; n],
        None => {
            let radii = t.f64_list("radii")?.unwrap_or_default();
            if radii.len() != n {
                return Err(t.err_key(
                    "radii",
                    format!(
                        "`radii` in {} has {} entries but `positions` has {n}: give one radius per position",
                        t.ctx,
                        radii.len()
                    ),
                ));
            }
            if let Some((i, r)) = radii.iter().enumerate().find(|(_, r)| **r <= 0.0) {
                return Err(t.err_key(
                    "radii",
                    format!(
                        "`radii[{i}]` in {} must be > 0 (a radius in m), got {r}",
                        t.ctx
                    ),
                ));
            }
            radii
        }
    };
    if t.has("velocity") && t.has("velocities") {
        return Err(t.err_key(
            "velocities",
            format!(
                "{} has both `velocity` and `velocities`: give only one (one velocity for all, or one per position)",
                t.ctx
            ),
        ));
    }
    let velocities = match t.vec3_list("velocities")? {
        Some(v) => {
            if v.len() != n {
                return Err(t.err_key(
                    "velocities",
                    format!(
                        "`velocities` in {} has {} entries but `positions` has {n}: give one velocity per position",
                        t.ctx,
                        v.len()
                    ),
                ));
            }
            v
        }
        None => vec![block_velocity(t)?; n],
    };
    let angular_velocity = block_angular_velocity(t)?;
    for i in 0..n {
        out.push(ParticleInit {
            position: positions[i],
            velocity: velocities[i],
            angular_velocity,
            radius: radii[i],
            material,
            insert_at: 0.0,
        });
    }
    Ok(())
}

fn expand_lattice(t: &Tbl, names: &[&str], out: &mut Vec<ParticleInit>) -> Res<()> {
    let material = material_ref(t, names)?;
    let (min, max) = region(t)?;
    let radius = t.positive_req("radius", "the particle radius in m")?;
    let spacing = t
        .positive("spacing", "the lattice spacing in m")?
        .unwrap_or(2.0 * radius * (1.0 + 1e-9));
    if spacing < 2.0 * radius {
        return Err(t.err_key(
            "spacing",
            format!(
                "`spacing` in {} ({spacing}) must be >= 2*radius ({}), or neighbours overlap",
                t.ctx,
                2.0 * radius
            ),
        ));
    }
    let jitter = t.f64("jitter")?.unwrap_or(0.0);
    if !(0.0..=1.0).contains(&jitter) {
        return Err(t.err_key(
            "jitter",
            format!(
                "`jitter` in {} must be between 0 and 1 (a fraction of the gap between neighbours), got {jitter}",
                t.ctx
            ),
        ));
    }
    let seed = t.u64("seed")?.unwrap_or(1);
    let velocity = block_velocity(t)?;
    let angular_velocity = block_angular_velocity(t)?;
    let mut counts = [0u64; 3];
    for a in 0..3 {
        let free = max[a] - min[a] - 2.0 * radius;
        if free < -1e-9 * radius {
            return Err(t.err_key(
                "radius",
                format!(
                    "the region of {} is narrower than one particle diameter ({}) on axis {}: enlarge the region or reduce `radius`",
                    t.ctx,
                    2.0 * radius,
                    AXES[a]
                ),
            ));
        }
        // the tolerance keeps a region of exactly n diameters at n particles
        counts[a] = (free.max(0.0) / spacing + 1e-6).floor() as u64 + 1;
    }
    let total = counts[0] as u128 * counts[1] as u128 * counts[2] as u128;
    if total > MAX_BLOCK_PARTICLES as u128 {
        return Err(t.err_key(
            "spacing",
            format!(
                "{} would create {total} particles (more than {MAX_BLOCK_PARTICLES}): check `spacing`, `radius` and the region",
                t.ctx
            ),
        ));
    }
    crate::memory::check_particles(
        total as u64 + out.len() as u64,
        crate::memory::CPU_BYTES_PER_PARTICLE,
        "this scene",
    )
    .map_err(|m| t.err_key("spacing", format!("{}: {m}", t.ctx)))?;
    let gap = spacing - 2.0 * radius;
    let amp = 0.5 * jitter * gap;
    let mut rng = Pcg64::seed_from_u64(seed);
    out.reserve(total as usize);
    for iz in 0..counts[2] {
        for iy in 0..counts[1] {
            for ix in 0..counts[0] {
                let idx = [ix, iy, iz];
                let mut p = [0.0; 3];
                for a in 0..3 {
                    let mut x = min[a] + radius + idx[a] as f64 * spacing;
                    if amp > 0.0 {
                        x += amp * (2.0 * rng.random::<f64>() - 1.0);
                    }
                    // clamping only shortens a displacement, so it cannot create overlaps
                    p[a] = x.clamp(min[a] + radius, max[a] - radius);
                }
                out.push(ParticleInit {
                    position: p,
                    velocity,
                    angular_velocity,
                    radius,
                    material,
                    insert_at: 0.0,
                });
            }
        }
    }
    Ok(())
}

/// A radius distribution of a `random` block.
#[derive(Clone, Debug, PartialEq)]
enum SizeDist {
    Fixed(f64),
    Uniform {
        min: f64,
        max: f64,
    },
    Normal {
        mean: f64,
        std: f64,
    },
    LogNormal {
        median: f64,
        sigma: f64,
    },
    /// Radii with cumulative normalised weights.
    List {
        radii: Vec<f64>,
        cumulative: Vec<f64>,
    },
}

impl SizeDist {
    /// A radius > 0. Normal radii are redrawn until positive (mean > 0 makes this quick).
    fn sample(&self, rng: &mut Pcg64) -> f64 {
        match self {
            Self::Fixed(r) => *r,
            Self::Uniform { min, max } => min + (max - min) * rng.random::<f64>(),
            Self::Normal { mean, std } => {
                let d = Normal::new(*mean, *std).expect("validated normal parameters");
                loop {
                    let r = d.sample(rng);
                    if r > 0.0 {
                        return r;
                    }
                }
            }
            Self::LogNormal { median, sigma } => LogNormal::new(median.ln(), *sigma)
                .expect("validated lognormal parameters")
                .sample(rng),
            Self::List { radii, cumulative } => {
                let u = rng.random::<f64>();
                let i = cumulative.partition_point(|c| *c <= u).min(radii.len() - 1);
                radii[i]
            }
        }
    }
}

fn parse_size(t: &Tbl) -> Res<SizeDist> {
    if let Some(r) = t.positive("radius", "the particle radius in m")? {
        return Ok(SizeDist::Fixed(r));
    }
    let s = t
        .table("size", format!("`size` of {}", t.ctx))?
        .expect("one_of checked radius or size");
    if !s.has("distribution") {
        s.check_keys(
            &[
                "distribution",
                "min",
                "max",
                "mean",
                "std",
                "median",
                "sigma",
                "radii",
                "weights",
            ],
            |_| None,
        )?;
    }
    let dist = s.choice("distribution", DISTRIBUTIONS)?.ok_or_else(|| {
        s.missing(
            "distribution",
            "\"uniform\", \"normal\", \"lognormal\" or \"list\"",
        )
    })?;
    let keys: &[&str] = match dist {
        "uniform" => &["distribution", "min", "max"],
        "normal" => &["distribution", "mean", "std"],
        "lognormal" => &["distribution", "median", "sigma"],
        _ => &["distribution", "radii", "weights"],
    };
    s.check_keys(keys, |_| None)?;
    let non_negative = |key: &str, what: &str| -> Res<f64> {
        let x = s.f64_req(key, what)?;
        if x < 0.0 {
            return Err(s.err_key(
                key,
                format!("`{key}` in {} ({what}) must be >= 0, got {x}", s.ctx),
            ));
        }
        Ok(x)
    };
    Ok(match dist {
        "uniform" => {
            let min = s.positive_req("min", "the smallest radius in m")?;
            let max = s.positive_req("max", "the largest radius in m")?;
            if max < min {
                return Err(s.err_key(
                    "max",
                    format!("`max` ({max}) in {} must be >= `min` ({min})", s.ctx),
                ));
            }
            SizeDist::Uniform { min, max }
        }
        "normal" => SizeDist::Normal {
            mean: s.positive_req("mean", "the mean radius in m")?,
            std: non_negative("std", "the standard deviation of the radius in m")?,
        },
        "lognormal" => SizeDist::LogNormal {
            median: s.positive_req("median", "the median radius in m")?,
            sigma: non_negative("sigma", "the standard deviation of ln(radius)")?,
        },
        _ => {
            let radii = s
                .f64_list("radii")?
                .ok_or_else(|| s.missing("radii", "the possible radii in m"))?;
            if radii.is_empty() {
                return Err(s.err_key("radii", format!("`radii` in {} must not be empty", s.ctx)));
            }
            if let Some((i, r)) = radii.iter().enumerate().find(|(_, r)| **r <= 0.0) {
                return Err(s.err_key(
                    "radii",
                    format!(
                        "`radii[{i}]` in {} must be > 0 (a radius in m), got {r}",
                        s.ctx
                    ),
                ));
            }
            let weights = s.f64_list("weights")?.unwrap_or(vec![1.0; radii.len()]);
            if weights.len() != radii.len() {
                return Err(s.err_key(
                    "weights",
                    format!(
                        "`weights` in {} has {} entries but `radii` has {}: give one weight per radius",
                        s.ctx,
                        weights.len(),
                        radii.len()
                    ),
                ));
            }
            let sum: f64 = weights.iter().sum();
            if weights.iter().any(|w| *w < 0.0) || sum <= 0.0 {
                return Err(s.err_key(
                    "weights",
                    format!("`weights` in {} must be >= 0 with a positive sum", s.ctx),
                ));
            }
            let mut acc = 0.0;
            let cumulative = weights
                .iter()
                .map(|w| {
                    acc += w / sum;
                    acc
                })
                .collect();
            SizeDist::List { radii, cumulative }
        }
    })
}

/// Places batch `batch.0` of `batch.1` of a random block (count/batches particles, the
/// first batches taking the remainder) at time `insert_at`, clear of the particles that
/// appear at the same time.
fn expand_random(
    t: &Tbl,
    names: &[&str],
    out: &mut Vec<ParticleInit>,
    insert_at: f64,
    batch: (u64, u64),
) -> Res<()> {
    let material = material_ref(t, names)?;
    let total = t
        .u64("count")?
        .ok_or_else(|| t.missing("count", "the number of particles to place"))?;
    let count = total / batch.1 + u64::from(batch.0 < total % batch.1);
    if count > MAX_BLOCK_PARTICLES {
        return Err(t.err_key(
            "count",
            format!(
                "`count` in {} is {count}, more than the limit {MAX_BLOCK_PARTICLES}",
                t.ctx
            ),
        ));
    }
    crate::memory::check_particles(
        count + out.len() as u64,
        crate::memory::CPU_BYTES_PER_PARTICLE,
        "this scene",
    )
    .map_err(|m| t.err_key("count", format!("{}: {m}", t.ctx)))?;
    let (min, max) = region(t)?;
    let seed = t.u64("seed")?.unwrap_or(1).wrapping_add(batch.0);
    one_of(
        t,
        "radius",
        "size",
        "a fixed radius in m, or a size distribution",
    )?;
    let size = parse_size(t)?;
    let velocity = block_velocity(t)?;
    let angular_velocity = block_angular_velocity(t)?;

    let mut rng = Pcg64::seed_from_u64(seed);
    let radii: Vec<f64> = (0..count).map(|_| size.sample(&mut rng)).collect();
    let block_rmax = radii.iter().copied().fold(0.0, f64::max);
    for a in 0..3 {
        if 2.0 * block_rmax > max[a] - min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "the region of {} is narrower on axis {} ({}) than the largest particle diameter drawn ({}): enlarge the region or use smaller particles",
                    t.ctx,
                    AXES[a],
                    max[a] - min[a],
                    2.0 * block_rmax
                ),
            ));
        }
    }
    let rmax = out.iter().map(|p| p.radius).fold(block_rmax, f64::max);
    let mut grid = Grid::new(2.0 * rmax);
    for (i, p) in out.iter().enumerate() {
        // particles that appear at another time may occupy the same place
        if p.insert_at == insert_at {
            grid.insert(i, p.position);
        }
    }
    let before = out.len();
    for (k, &r) in radii.iter().enumerate() {
        let mut placed = false;
        for _ in 0..MAX_PLACEMENT_ATTEMPTS {
            let mut p = [0.0; 3];
            for a in 0..3 {
                p[a] = min[a] + r + (max[a] - min[a] - 2.0 * r) * rng.random::<f64>();
            }
            let free = grid
                .neighbours(p, r + rmax)
                .all(|j| dist2(p, out[j].position) >= sq(r + out[j].radius));
            if free {
                grid.insert(out.len(), p);
                out.push(ParticleInit {
                    position: p,
                    velocity,
                    angular_velocity,
                    radius: r,
                    material,
                    insert_at,
                });
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(t.err_key(
                "count",
                format!(
                    "{} could place only {k} of {count} particles in the region {} to {} ({MAX_PLACEMENT_ATTEMPTS} attempts found no free spot for the next one, avoiding the {before} particle(s) of earlier blocks): use a larger region, fewer or smaller particles (random placement jams near a solid fraction of 0.38), or a lattice",
                    t.ctx,
                    fmt_vec(min),
                    fmt_vec(max)
                ),
            ));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Uniform hash grid for O(N) neighbour checks
// ---------------------------------------------------------------------------------------

fn sq(x: f64) -> f64 {
    x * x
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    sq(a[0] - b[0]) + sq(a[1] - b[1]) + sq(a[2] - b[2])
}

/// FxHash-style hasher for integer cell keys.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
}

type Cell = (i64, i64, i64);

struct Grid {
    cell: f64,
    map: HashMap<Cell, Vec<usize>, BuildHasherDefault<CellHasher>>,
}

impl Grid {
    fn new(cell: f64) -> Self {
        Self {
            cell: if cell > 0.0 { cell } else { 1.0 },
            map: HashMap::default(),
        }
    }

    fn cell_of(&self, p: [f64; 3]) -> Cell {
        let c = |x: f64| (x / self.cell).floor() as i64;
        (c(p[0]), c(p[1]), c(p[2]))
    }

    fn insert(&mut self, i: usize, p: [f64; 3]) {
        let c = self.cell_of(p);
        self.map.entry(c).or_default().push(i);
    }

    /// Indices of all points in cells that may hold a point within `reach` of `p`.
    fn neighbours(&self, p: [f64; 3], reach: f64) -> impl Iterator<Item = usize> + '_ {
        let lo = self.cell_of([p[0] - reach, p[1] - reach, p[2] - reach]);
        let hi = self.cell_of([p[0] + reach, p[1] + reach, p[2] + reach]);
        (lo.0..=hi.0).flat_map(move |x| {
            (lo.1..=hi.1).flat_map(move |y| {
                (lo.2..=hi.2).flat_map(move |z| {
                    self.map
                        .get(&(x, y, z))
                        .map(|v| v.as_slice())
                        .unwrap_or(&[])
                        .iter()
                        .copied()
                })
            })
        })
    }
}

// ---------------------------------------------------------------------------------------
// Whole-scene checks
// ---------------------------------------------------------------------------------------

/// Periodic axes: no wall may face one (its normal would have a component along it) and
/// gravity may not point along one (the potential energy would be unbounded).
fn check_periodic(src: &Src, scene: &Scene) -> Res<()> {
    let d = &scene.domain;
    for (a, axis) in AXES.iter().enumerate() {
        if !d.periodic[a] {
            continue;
        }
        if scene.gravity[a] != 0.0 {
            return Err(src.err(
                None,
                format!(
                    "gravity {} has a component along the periodic axis {axis}: particles would fall forever and the gravitational energy is unbounded; make the axis non-periodic (with walls) or gravity perpendicular to it",
                    fmt_vec(scene.gravity)
                ),
            ));
        }
        for (w, wall) in scene.walls.iter().enumerate() {
            if wall.normal[a].abs() > 1e-12 {
                return Err(src.err(
                    None,
                    format!(
                        "[[wall]] #{} (normal {}) faces the periodic axis {axis}: a wall across a periodic axis would cut the periodic images; make the axis non-periodic or remove the wall",
                        w + 1,
                        fmt_vec(wall.normal)
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn check_particles(src: &Src, scene: &Scene, origin: &Origin) -> Res<()> {
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
        let first = grid
            .neighbours(p.position, p.radius + rmax)
            .filter(|&j| {
                let q = &ps[j];
                let overlap = p.radius + q.radius - dist2(p.position, q.position).sqrt();
                // particles that appear at different times may share a place (pouring)
                q.insert_at == p.insert_at && overlap > OVERLAP_TOLERANCE * p.radius.min(q.radius)
            })
            .min();
        if let Some(j) = first {
            let q = &ps[j];
            let overlap = p.radius + q.radius - dist2(p.position, q.position).sqrt();
            return Err(src.err(
                None,
                format!(
                    "particles {j} (from [[particles]] #{}, at {}) and {i} (from [[particles]] #{}, at {}) overlap by {overlap:.3e} m at the start, more than {}% of the smaller radius: move them apart",
                    origin[j],
                    fmt_vec(q.position),
                    origin[i],
                    fmt_vec(p.position),
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

/// Every pair of materials that can meet needs a contact model.
fn check_pair_models(src: &Src, scene: &Scene) -> Res<()> {
    let n = scene.materials.len();
    let mut used = vec![false; n];
    for p in &scene.particles {
        used[p.material] = true;
    }
    let mut wall_used = vec![false; n];
    for w in &scene.walls {
        wall_used[w.material] = true;
    }
    for a in 0..n {
        for b in a..n {
            let meets = (used[a] && (used[b] || wall_used[b])) || (wall_used[a] && used[b]);
            if meets {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AdhesionMode, K2Rule, LsdParams};

    const FULL: &str = r#"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.01, 0.01, 0.02]

[simulation]
duration = 0.05
gravity = [0.0, 0.0, -9.81]

[[material]]
name = "powder"
density = 2000.0
model = "hysteretic"
k1 = 100.0
kp = 500.0
kc = 100.0
phi_f = 0.05

[[material]]
name = "glass"
density = 2500
model = "lsd"
k = 300.0
gamma0 = 1e-3

[[interaction]]
materials = ["glass", "powder"]
model = "lsd"
k = 200.0

[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 2.0]

[[particles]]
kind = "list"
material = "glass"
positions = [[0.002, 0.002, 0.002], [0.005, 0.005, 0.005]]
radii = [1e-3, 1.5e-3]
velocities = [[0.0, 0.0, -0.1], [0.1, 0.0, 0.0]]

[[particles]]
kind = "lattice"
min = [0.0, 0.0, 0.01]
max = [0.01, 0.01, 0.014]
radius = 1e-3
"#;

    fn parse(text: &str) -> Result<Scene, String> {
        Scene::from_toml_str(text, "test").map_err(|e| e.to_string())
    }

    fn err(text: &str) -> String {
        match parse(text) {
            Ok(_) => panic!("expected an error for:\n{text}"),
            Err(e) => e,
        }
    }

    fn assert_contains(msg: &str, parts: &[&str]) {
        for p in parts {
            assert!(msg.contains(p), "message {msg:?} lacks {p:?}");
        }
    }

    /// A minimal valid scene with `extra` appended after one list particle.
    fn minimal(material_extra: &str, extra: &str) -> String {
        format!(
            r#"[domain]
min = [0.0, 0.0, 0.0]
max = [0.01, 0.01, 0.01]

[simulation]
duration = 0.1

[[material]]
name = "powder"
density = 2000.0
model = "lsd"
k = 100.0
{material_extra}
[[particles]]
kind = "list"
positions = [[0.005, 0.005, 0.005]]
radius = 1e-3
{extra}"#
        )
    }

    #[test]
    fn contact_output_is_on_below_the_size_limit_unless_set() {
        let small = parse(&minimal("", "")).unwrap();
        assert_eq!(small.contact_output, None);
        assert!(small.writes_contacts());
        let off =
            minimal("", "").replace("duration = 0.1", "duration = 0.1\ncontact_output = false");
        assert!(!parse(&off).unwrap().writes_contacts());
        let mut large = small.clone();
        large.particles = vec![small.particles[0]; CONTACT_OUTPUT_BELOW];
        assert!(!large.writes_contacts());
        large.contact_output = Some(true);
        assert!(large.writes_contacts());
        let bad = minimal("", "").replace("duration = 0.1", "duration = 0.1\ncontact_output = 1");
        let err = parse(&bad).unwrap_err().to_string();
        assert!(err.contains("contact_output"), "{err}");
    }

    #[test]
    fn full_scene_values_and_defaults() {
        let s = parse(FULL).unwrap();
        assert_eq!(s.name, "test");
        assert_eq!(s.domain.max, [0.01, 0.01, 0.02]);
        assert_eq!(s.gravity, [0.0, 0.0, -9.81]);
        assert_eq!(s.dt, DtSetting::Auto);
        assert!(!s.force_dt);
        assert_eq!(s.jump_impulses, None);
        assert_eq!(s.duration, 0.05);
        assert_eq!(s.output_every, 1000);
        assert_eq!(s.materials.len(), 2);
        assert_eq!(s.materials[1].density, 2500.0);
        match s.materials[0].model {
            ContactModel::Hysteretic(p) => {
                assert_eq!((p.k1, p.kp, p.kc, p.phi_f), (100.0, 500.0, 100.0, 0.05));
                assert_eq!(p.fa, 0.0);
                assert_eq!(p.kca, 100.0, "kca defaults to kc");
                assert_eq!(p.adhesion, AdhesionMode::JumpIn);
                assert_eq!(p.gamma0, 0.0);
                assert_eq!(p.k2_rule, K2Rule::Linear);
            }
            other => panic!("wrong model {other:?}"),
        }
        assert_eq!(
            s.materials[1].model,
            ContactModel::Lsd(LsdParams::new(300.0, 1e-3))
        );
        assert_eq!(s.interactions.len(), 1);
        assert_eq!(s.interactions[0].materials, [1, 0]);
        assert_eq!(s.walls.len(), 1);
        assert_eq!(s.walls[0].normal, [0.0, 0.0, 1.0]);
        assert_eq!(s.walls[0].material, 0);
        // 2 listed + 5 x 5 x 2 lattice
        assert_eq!(s.particles.len(), 2 + 50);
        assert_eq!(s.particles[1].radius, 1.5e-3);
        assert_eq!(s.particles[1].velocity, [0.1, 0.0, 0.0]);
        assert_eq!(s.particles[1].material, 1);
        assert_eq!(s.particles[2].material, 0);
        assert_eq!(s.particles[2].velocity, [0.0; 3]);
        assert!((s.particles[2].position[0] - 1e-3).abs() < 1e-15);
        assert!((s.particles[2].position[2] - 0.011).abs() < 1e-15);
        // pair models: override in either order, own model, missing pair
        let lsd200 = ContactModel::Lsd(LsdParams::new(200.0, 0.0));
        assert_eq!(s.pair_model(0, 1).unwrap(), lsd200);
        assert_eq!(s.pair_model(1, 0).unwrap(), lsd200);
        assert_eq!(s.pair_model(1, 1).unwrap(), s.materials[1].model);
        assert!(s.pair_model(0, 2).is_err());
    }

    #[test]
    fn simulation_settings_and_hysteretic_options() {
        let text = minimal(
            "",
            r#"
[[material]]
name = "h"
density = 1000
model = "hysteretic"
k1 = 1.0
kp = 2.0
kc = 0.0
phi_f = 0.1
fa = 1e-6
adhesion = "reversible"
k2_rule = "sqrt"
gamma0 = 1e-4

[[material]]
name = "h2"
density = 1000
model = "hysteretic"
k1 = 1.0
kp = 2.0
kc = 1.0
phi_f = 0.1
kca = "inf"
"#,
        )
        .replace(
            "duration = 0.1",
            "duration = 0.1\ndt = 1e-6\nforce_dt = true\njump_impulses = false\noutput_every = 7",
        );
        let s = parse(&text).unwrap();
        assert_eq!(s.dt, DtSetting::Fixed(1e-6));
        assert!(s.force_dt);
        assert_eq!(s.jump_impulses, Some(false));
        let bad = text.replace("jump_impulses = false", "jump_impulses = 1");
        let e = parse(&bad).unwrap_err().to_string();
        assert!(e.contains("jump_impulses"), "{e}");
        assert_eq!(s.output_every, 7);
        let ContactModel::Hysteretic(h) = s.materials[1].model else {
            panic!()
        };
        assert_eq!(h.kca, f64::INFINITY, "kc = 0 gives zero range");
        assert_eq!(h.adhesion, AdhesionMode::Reversible);
        assert_eq!(h.k2_rule, K2Rule::Sqrt);
        assert_eq!((h.fa, h.gamma0), (1e-6, 1e-4));
        let ContactModel::Hysteretic(h2) = s.materials[2].model else {
            panic!()
        };
        assert_eq!(h2.kca, f64::INFINITY);
    }

    #[test]
    fn malformed_toml_has_line_and_column() {
        let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01 0.01]\n";
        let e = err(text);
        assert_contains(
            &e,
            &["scene `test`", "line 3", "column", "TOML syntax error"],
        );
        let e = err("[simulation]\nduration = 0.1\nduration = 0.2\n");
        assert_contains(&e, &["line 3"]);
    }

    #[test]
    fn unknown_keys_are_rejected_with_suggestions() {
        let e = err(&minimal("dencity = 3.0", ""));
        assert_contains(
            &e,
            &[
                "line 13",
                "unknown key `dencity` in [[material]] #1 (`powder`): did you mean `density`?",
            ],
        );
        // a parameter of the other model
        let e = err(&minimal("kp = 500.0", ""));
        assert_contains(
            &e,
            &[
                "unknown key `kp`",
                "parameter of the `hysteretic` model",
                "line 13",
            ],
        );
        // in a fixed table
        let e =
            err(&minimal("", "").replace("duration = 0.1", "duration = 0.1\ngravty = [0, 0, 0]"));
        assert_contains(
            &e,
            &[
                "unknown key `gravty` in [simulation]",
                "did you mean `gravity`?",
                "line 7",
            ],
        );
        // at the top level
        let e = err(&minimal("", "[[materials]]\nname = \"x\"\n"));
        assert_contains(
            &e,
            &[
                "unknown key `materials` in the top-level table",
                "did you mean `material`?",
            ],
        );
        let e = err(&format!("duration = 1.0\n{}", minimal("", "")));
        assert_contains(
            &e,
            &["`duration` belongs in the [simulation] table", "line 1"],
        );
        // in particle blocks and size tables
        let e =
            err(&minimal("", "").replace("radius = 1e-3", "radius = 1e-3\nvelocty = [0, 0, 0]"));
        assert_contains(
            &e,
            &[
                "unknown key `velocty` in [[particles]] #1 (kind = \"list\")",
                "`velocity`",
            ],
        );
        let e = err(&minimal(
            "",
            "[[particles]]\nkind = \"random\"\ncount = 1\nmin = [0, 0, 0]\nmax = [0.003, 0.003, 0.003]\nsize = { distribution = \"uniform\", min = 1e-4, maxx = 2e-4 }\n",
        ));
        assert_contains(&e, &["unknown key `maxx`", "did you mean `max`?"]);
        let e = err(&minimal(
            "",
            "[[particles]]\nkind = \"random\"\ncount = 1\nmin = [0, 0, 0]\nmax = [0.003, 0.003, 0.003]\nsize = { distrbution = \"uniform\", min = 1e-4, max = 2e-4 }\n",
        ));
        assert_contains(
            &e,
            &["unknown key `distrbution`", "did you mean `distribution`?"],
        );
        // in a wall, an interaction
        let e = err(&minimal(
            "",
            "[[wall]]\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = \"powder\"\ncolour = 1\n",
        ));
        assert_contains(&e, &["unknown key `colour` in [[wall]] #1"]);
        // unknown values of string options are suggested too
        let e = err(&minimal("", "").replace("model = \"lsd\"", "model = \"hysteresis\""));
        assert_contains(
            &e,
            &[
                "`model` in [[material]] #1 (`powder`) must be",
                "did you mean \"hysteretic\"?",
            ],
        );
    }

    #[test]
    fn missing_keys_and_wrong_types() {
        let e = err(&minimal("", "").replace("duration = 0.1", ""));
        assert_contains(
            &e,
            &["missing required key `duration` in [simulation]", "line 5"],
        );
        let e = err(&minimal("", "").replace("k = 100.0", ""));
        assert_contains(
            &e,
            &["missing required key `k` in [[material]] #1 (`powder`)"],
        );
        let e = err("[simulation]\nduration = 1.0\n");
        assert_contains(&e, &["missing required table [domain]"]);
        let e = err(&minimal("", "").replace("density = 2000.0", "density = \"2000\""));
        assert_contains(
            &e,
            &[
                "`density` in [[material]] #1 (`powder`) must be a number",
                "\"2000\"",
                "line 10",
            ],
        );
        let e =
            err(&minimal("", "").replace("duration = 0.1", "duration = 0.1\noutput_every = 1.5"));
        assert_contains(
            &e,
            &["`output_every` in [simulation] must be a non-negative integer"],
        );
        let e = err(&minimal("", "").replace("min = [0.0, 0.0, 0.0]", "min = [0.0, 0.0]"));
        assert_contains(
            &e,
            &[
                "`min` in [domain] must be an array of 3 numbers",
                "2 element(s)",
                "line 2",
            ],
        );
        let e = err(&minimal("", "").replace("[domain]", "[[domain]]"));
        assert_contains(&e, &["`domain` in the top-level table must be a table"]);
        let e = err(&minimal("", "").replace("kind = \"list\"", ""));
        assert_contains(&e, &["missing required key `kind` in [[particles]] #1"]);
    }

    #[test]
    fn out_of_range_values() {
        let cases: &[(&str, &str, &[&str])] = &[
            (
                "density = 2000.0",
                "density = 0.0",
                &["`density`", "must be > 0", "line 10"],
            ),
            (
                "radius = 1e-3",
                "radius = -1e-3",
                &["`radius`", "must be > 0"],
            ),
            (
                "duration = 0.1",
                "duration = 0",
                &["`duration`", "must be > 0"],
            ),
            (
                "duration = 0.1",
                "duration = 0.1\ndt = -1e-6",
                &["`dt`", "\"auto\" or a time step > 0"],
            ),
            (
                "duration = 0.1",
                "duration = 0.1\ndt = \"fast\"",
                &["`dt`", "\"auto\""],
            ),
            (
                "max = [0.01, 0.01, 0.01]",
                "max = [0.01, 0.01, 0.0]",
                &["max must be > min", "axis z"],
            ),
            (
                "k = 100.0",
                "k = -1.0",
                &["material `powder`: invalid parameter `k`", "line 12"],
            ),
            (
                "density = 2000.0",
                "density = nan",
                &["`density`", "finite"],
            ),
        ];
        for (from, to, parts) in cases {
            let e = err(&minimal("", "").replace(from, to));
            assert_contains(&e, parts);
        }
        let hyst = minimal("", "").replace(
            "model = \"lsd\"\nk = 100.0",
            "model = \"hysteretic\"\nk1 = 100.0\nkp = 50.0\nkc = 1.0\nphi_f = 0.05",
        );
        let e = err(&hyst);
        assert_contains(
            &e,
            &["material `powder`: invalid parameter `kp`", "line 13"],
        );
        let e = err(&minimal(
            "",
            "[[wall]]\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n",
        ));
        assert_contains(&e, &["`normal` in [[wall]] #1 must be a non-zero vector"]);
        let e = err(&minimal(
            "",
            "[[wall]]\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = \"powdr\"\n",
        ));
        assert_contains(
            &e,
            &[
                "unknown material `powdr`",
                "known materials are `powder`",
                "did you mean `powder`?",
            ],
        );
        let e = err(&minimal("", "").replace("radius = 1e-3", "radii = [1e-3, 1e-3]"));
        assert_contains(&e, &["`radii`", "has 2 entries but `positions` has 1"]);
        let e = err(&minimal(
            "",
            "[[material]]\nname = \"powder\"\ndensity = 1.0\nmodel = \"lsd\"\nk = 1.0\n",
        ));
        assert_contains(
            &e,
            &[
                "duplicate material name `powder`",
                "[[material]] #2",
                "also [[material]] #1",
            ],
        );
        let e = err(&minimal("", "").replace("radius = 1e-3", "radius = 1e-3\nradii = [1e-3]"));
        assert_contains(&e, &["has both `radius` and `radii`"]);
    }

    #[test]
    fn particle_placement_errors() {
        // outside the domain
        let e = err(&minimal("", "").replace(
            "[[0.005, 0.005, 0.005]]",
            "[[0.005, 0.005, 0.005], [0.0095, 0.005, 0.005]]",
        ));
        assert_contains(
            &e,
            &[
                "particle 1",
                "[0.0095, 0.005, 0.005]",
                "not inside the domain",
                "axis x",
            ],
        );
        // overlapping
        let e = err(&minimal("", "").replace(
            "[[0.005, 0.005, 0.005]]",
            "[[0.005, 0.005, 0.005], [0.002, 0.002, 0.002], [0.0065, 0.005, 0.005]]",
        ));
        assert_contains(&e, &["particles 0", "and 2", "overlap"]);
        // touching within 1% is fine
        parse(&minimal("", "").replace(
            "[[0.005, 0.005, 0.005]]",
            "[[0.005, 0.005, 0.005], [0.006995, 0.005, 0.005]]",
        ))
        .unwrap();
        // overlapping a wall
        let e = err(&minimal(
            "",
            "[[wall]]\npoint = [0, 0, 0.0045]\nnormal = [0, 0, 1]\n",
        ));
        assert_contains(&e, &["particle 0", "overlaps [[wall]] #1"]);
        // empty scenes
        let e = err(&minimal("", "").replace("[[0.005, 0.005, 0.005]]", "[]"));
        assert_contains(&e, &["no particles"]);
        let text = minimal("", "");
        let cut = text.find("[[particles]]").unwrap();
        let e = err(&text[..cut]);
        assert_contains(&e, &["no particles", "[[particles]]"]);
        // different materials without an interaction
        let e = err(&minimal(
            "",
            "[[material]]\nname = \"glass\"\ndensity = 1.0\nmodel = \"lsd\"\nk = 1.0\n[[particles]]\nkind = \"list\"\nmaterial = \"glass\"\npositions = [[0.002, 0.002, 0.002]]\nradius = 1e-3\n",
        ));
        assert_contains(
            &e,
            &[
                "no contact model for materials `powder` and `glass`",
                "materials = [\"powder\", \"glass\"]",
            ],
        );
        // a random block that cannot fit
        let e = err(&minimal(
            "",
            "[[particles]]\nkind = \"random\"\ncount = 100\nmin = [0, 0, 0]\nmax = [0.004, 0.004, 0.004]\nradius = 1e-3\n",
        ));
        assert_contains(
            &e,
            &[
                "[[particles]] #2 (kind = \"random\") could place only",
                "of 100",
                "larger region",
            ],
        );
    }

    fn random_scene(seed: u64, count: usize, size: &str) -> String {
        format!(
            r#"[domain]
min = [0.0, 0.0, 0.0]
max = [0.05, 0.05, 0.05]
[simulation]
duration = 1.0
[[material]]
name = "p"
density = 1000.0
model = "lsd"
k = 1.0
[[particles]]
kind = "lattice"
min = [0.0, 0.0, 0.0]
max = [0.05, 0.05, 0.004]
radius = 1e-3
[[particles]]
kind = "random"
count = {count}
min = [0.0, 0.0, 0.0]
max = [0.05, 0.05, 0.05]
seed = {seed}
{size}
"#
        )
    }

    #[test]
    fn random_placement_is_reproducible_and_non_overlapping() {
        let a = parse(&random_scene(7, 2000, "radius = 1e-3")).unwrap();
        let b = parse(&random_scene(7, 2000, "radius = 1e-3")).unwrap();
        let c = parse(&random_scene(8, 2000, "radius = 1e-3")).unwrap();
        let lattice = 25 * 25 * 2;
        assert_eq!(a.particles.len(), lattice + 2000);
        assert_eq!(a, b);
        assert_ne!(a.particles, c.particles);
        // brute-force overlap check, including against the lattice block
        let ps = &a.particles;
        for i in 0..ps.len() {
            for j in (i + 1).max(lattice)..ps.len() {
                let d = dist2(ps[i].position, ps[j].position).sqrt();
                assert!(
                    d >= ps[i].radius + ps[j].radius - 1e-15,
                    "{i} and {j} overlap"
                );
            }
            for k in 0..3 {
                assert!(ps[i].position[k] - ps[i].radius >= -1e-15);
                assert!(ps[i].position[k] + ps[i].radius <= 0.05 + 1e-15);
            }
        }
    }

    #[test]
    fn lattice_counts_and_jitter() {
        let scene = |extra: &str| {
            format!(
                "[domain]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[simulation]\nduration = 1.0\n[[material]]\nname = \"p\"\ndensity = 1.0\nmodel = \"lsd\"\nk = 1.0\n[[particles]]\nkind = \"lattice\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.1, 0.2, 0.3]\nradius = 0.01\n{extra}"
            )
        };
        // 5 x 10 x 15 diameters fit exactly
        let s = parse(&scene("")).unwrap();
        assert_eq!(s.particles.len(), 5 * 10 * 15);
        assert!(s.particles[1].position[0] - s.particles[0].position[0] > 0.02 - 1e-12);
        let s = parse(&scene("spacing = 0.03")).unwrap();
        // floor((0.1-0.02)/0.03)+1 = 3, floor(0.18/0.03)+1 = 7, floor(0.28/0.03)+1 = 10
        assert_eq!(s.particles.len(), 3 * 7 * 10);
        let j = parse(&scene("spacing = 0.03\njitter = 1.0\nseed = 3")).unwrap();
        assert_eq!(j.particles.len(), 3 * 7 * 10);
        let moved = j
            .particles
            .iter()
            .zip(&s.particles)
            .filter(|(a, b)| a.position != b.position)
            .count();
        assert!(moved > 100);
        for (a, b) in j.particles.iter().zip(&s.particles) {
            for k in 0..3 {
                assert!((a.position[k] - b.position[k]).abs() <= 0.005 + 1e-12);
            }
        }
        let e = err(&scene("spacing = 0.015"));
        assert_contains(&e, &["`spacing`", "must be >= 2*radius"]);
        let e = err(&scene("jitter = 2.0"));
        assert_contains(&e, &["`jitter`", "between 0 and 1"]);
    }

    #[test]
    fn size_distributions_stay_in_bounds() {
        let mut rng = Pcg64::seed_from_u64(5);
        let u = SizeDist::Uniform {
            min: 0.8e-3,
            max: 1.2e-3,
        };
        let n = SizeDist::Normal {
            mean: 1e-3,
            std: 1e-3,
        };
        let l = SizeDist::LogNormal {
            median: 1e-3,
            sigma: 0.5,
        };
        let list = SizeDist::List {
            radii: vec![1e-3, 2e-3],
            cumulative: vec![0.75, 1.0],
        };
        let mut small = 0;
        for _ in 0..20000 {
            let r = u.sample(&mut rng);
            assert!((0.8e-3..=1.2e-3).contains(&r));
            assert!(n.sample(&mut rng) > 0.0);
            assert!(l.sample(&mut rng) > 0.0);
            let r = list.sample(&mut rng);
            assert!(r == 1e-3 || r == 2e-3);
            if r == 1e-3 {
                small += 1;
            }
        }
        assert!((small as f64 / 20000.0 - 0.75).abs() < 0.02);
        // through the scene file
        for size in [
            "size = { distribution = \"uniform\", min = 0.8e-3, max = 1.2e-3 }",
            "size = { distribution = \"normal\", mean = 1e-3, std = 2e-4 }",
            "size = { distribution = \"lognormal\", median = 1e-3, sigma = 0.1 }",
            "size = { distribution = \"list\", radii = [0.8e-3, 1.2e-3], weights = [1, 3] }",
        ] {
            let s = parse(&random_scene(1, 300, size)).unwrap();
            assert_eq!(s.particles.len(), 625 * 2 + 300);
            assert!(s
                .particles
                .iter()
                .all(|p| p.radius > 0.0 && p.radius < 3e-3));
        }
        let s = parse(&random_scene(
            1,
            300,
            "size = { distribution = \"uniform\", min = 0.8e-3, max = 1.2e-3 }",
        ))
        .unwrap();
        assert!(s.particles[1250..]
            .iter()
            .all(|p| (0.8e-3..=1.2e-3).contains(&p.radius)));
        let e = err(&random_scene(
            1,
            3,
            "size = { distribution = \"uniform\", min = 2e-3, max = 1e-3 }",
        ));
        assert_contains(&e, &["`max`", "must be >= `min`"]);
        let e = err(&random_scene(
            1,
            3,
            "size = { distribution = \"gauss\", mean = 1e-3, std = 1e-4 }",
        ));
        assert_contains(&e, &["`distribution`", "\"uniform\""]);
        let e = err(&random_scene(
            1,
            3,
            "size = { distribution = \"list\", radii = [1e-3], weights = [1, 2] }",
        ));
        assert_contains(&e, &["`weights`", "has 2 entries"]);
    }

    #[test]
    fn example_files_parse() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
        let cluster = Scene::load(&dir.join("cohesive_cluster.toml")).unwrap();
        assert_eq!(cluster.name, "cohesive_cluster");
        assert_eq!(cluster.particles.len(), 200);
        assert!(matches!(
            cluster.materials[0].model,
            ContactModel::Hysteretic(_)
        ));
        assert_eq!(cluster.gravity, [0.0, 0.0, -9.81]);
        let pair = Scene::load(&dir.join("lsd_pair.toml")).unwrap();
        assert_eq!(pair.particles.len(), 2);
        assert!(matches!(pair.materials[0].model, ContactModel::Lsd(_)));
        assert_eq!(pair.gravity, [0.0; 3]);
    }

    #[test]
    fn load_error_names_the_path() {
        let e = Scene::load(Path::new("/no/such/dir/scene.toml"))
            .unwrap_err()
            .to_string();
        assert_contains(&e, &["/no/such/dir/scene.toml"]);
    }

    #[test]
    fn line_col_counts_characters() {
        let src = Src {
            name: "x",
            text: "ab\nçd\n",
        };
        assert_eq!(src.line_col(0), (1, 1));
        assert_eq!(src.line_col(3), (2, 1));
        assert_eq!(src.line_col(5), (2, 2));
        assert_eq!(src.line_col(100), (3, 1));
    }
}
