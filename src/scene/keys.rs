//! The keys each table of a scene file accepts, from their declarations (`declared.rs`).

use super::declared::{any_keys_of, keys_of, Section};
use std::sync::LazyLock;

/// The keys of a table, made once from the declarations.
type Keys = LazyLock<Vec<&'static str>>;

pub(super) static TOP_KEYS: Keys = LazyLock::new(|| keys_of(Section::Top, None));
pub(super) static DOMAIN_KEYS: Keys = LazyLock::new(|| keys_of(Section::Domain, None));
pub(super) static SIMULATION_KEYS: Keys = LazyLock::new(|| keys_of(Section::Simulation, None));
pub(super) static MATERIAL_KEYS: Keys = LazyLock::new(|| keys_of(Section::Material, None));
pub(super) static INTERACTION_KEYS: Keys = LazyLock::new(|| keys_of(Section::Interaction, None));
pub(super) static WALL_KEYS: Keys = LazyLock::new(|| keys_of(Section::Wall, None));
pub(super) static PHASE_KEYS: Keys = LazyLock::new(|| keys_of(Section::Phase, None));
/// The servo's keys (a servo is given by any of them).
pub(super) static SERVO_KEYS: Keys = LazyLock::new(|| {
    let servo = |k: &&str| k.starts_with("servo_");
    keys_of(Section::Motion, None)
        .into_iter()
        .filter(servo)
        .collect()
});

/// `keys` and those of one kind of motion (a wall's or a phase's).
pub(super) fn with_motion_keys(keys: &[&'static str]) -> Vec<&'static str> {
    let motion = keys_of(Section::Motion, None);
    keys.iter().copied().chain(motion).collect()
}

pub(super) const PARTICLE_KINDS: &[&str] = &["list", "lattice", "random"];

/// The keys of a `[[particles]]` block of `kind`.
pub(super) fn particle_keys(kind: &str) -> Vec<&'static str> {
    keys_of(Section::Particles, Some(kind))
}

pub(super) const DISTRIBUTIONS: &[&str] = &["uniform", "normal", "lognormal", "list"];

/// The keys of a size distribution (`None`: of any of them).
pub(super) fn size_keys(distribution: Option<&str>) -> Vec<&'static str> {
    match distribution {
        Some(d) => keys_of(Section::Size, Some(d)),
        None => any_keys_of(Section::Size),
    }
}
