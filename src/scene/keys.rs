//! The keys each table of a scene file accepts.

pub(super) const TOP_KEYS: &[&str] = &[
    "domain",
    "simulation",
    "material",
    "interaction",
    "wall",
    "particles",
];

pub(super) const DOMAIN_KEYS: &[&str] = &["min", "max", "periodic"];
pub(super) const SIMULATION_KEYS: &[&str] = &[
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
pub(super) const MATERIAL_KEYS: &[&str] = &["name", "density", "model"];
pub(super) const INTERACTION_KEYS: &[&str] = &["materials", "model"];
pub(super) const WALL_KEYS: &[&str] = &[
    "point",
    "normal",
    "material",
    "velocities",
    "times",
    "phase",
];
pub(super) const PHASE_KEYS: &[&str] = &["from"];
pub(super) const SERVO_KEYS: &[&str] = &["servo_force", "servo_gain", "servo_max_speed"];

/// `keys` and those of one kind of motion (a wall's or a phase's).
pub(super) fn with_motion_keys(keys: &[&'static str]) -> Vec<&'static str> {
    let motion = std::iter::once(&"velocity").chain(SERVO_KEYS);
    keys.iter().chain(motion).copied().collect()
}
pub(super) const PARTICLE_KINDS: &[&str] = &["list", "lattice", "random"];
pub(super) const LIST_KEYS: &[&str] = &[
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
pub(super) const LATTICE_KEYS: &[&str] = &[
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
pub(super) const RANDOM_KEYS: &[&str] = &[
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
pub(super) const DISTRIBUTIONS: &[&str] = &["uniform", "normal", "lognormal", "list"];
