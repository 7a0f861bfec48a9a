//! Every scene key that is not a contact law's parameter, declared once: the keys each table
//! accepts (`keys.rs`), the scene reference (`powder params scene`, `docs/scene.md`) and the
//! test that the reader refuses each rule's edge follow from [`SCENE_KEYS`].

use crate::model::params::Rule;

/// A table of the scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    /// The top level: the tables themselves.
    Top,
    /// `[domain]`.
    Domain,
    /// `[simulation]`.
    Simulation,
    /// `[[material]]` (with its law's parameters: `powder params`).
    Material,
    /// `[[interaction]]` (with its law's parameters).
    Interaction,
    /// `[[wall]]`.
    Wall,
    /// One kind of motion, of a `[[wall]]` or of a `[[wall.phase]]`.
    Motion,
    /// `[[wall.phase]]`.
    Phase,
    /// `[[particles]]`.
    Particles,
    /// A random block's `size = { distribution = ..., ... }`.
    Size,
}

impl Section {
    /// Every section, in the reference's order.
    pub const ALL: [Section; 10] = [
        Section::Top,
        Section::Domain,
        Section::Simulation,
        Section::Material,
        Section::Interaction,
        Section::Wall,
        Section::Motion,
        Section::Phase,
        Section::Particles,
        Section::Size,
    ];

    /// The heading and a line on what the table is.
    pub fn title(self) -> (&'static str, &'static str) {
        match self {
            Section::Top => ("The tables", "the scene file's top level"),
            Section::Domain => ("`[domain]`", "the box the particles live in (required)"),
            Section::Simulation => ("`[simulation]`", "the run's settings (required)"),
            Section::Material => (
                "`[[material]]`",
                "at least one, referred to by name; its other keys are the parameters of its `model` (`powder params`, `docs/parameters.md`)",
            ),
            Section::Interaction => (
                "`[[interaction]]`",
                "the law between two materials (every pair of different materials that can meet needs one); its other keys are the parameters of its `model`",
            ),
            Section::Wall => (
                "`[[wall]]`",
                "an infinite plane, fixed unless given one kind of motion (below) or a program of `[[wall.phase]]`; a moving wall has an infinite mass",
            ),
            Section::Motion => (
                "A wall's motion",
                "in a `[[wall]]` or a `[[wall.phase]]`: a prescribed `velocity`, or the three `servo_*` keys (a wall moving along its normal to hold a force: speed = clamp(gain·(servo_force − F), ±servo_max_speed), stable while gain·k_bed·dt < 1); neither: at rest",
            ),
            Section::Phase => (
                "`[[wall.phase]]`",
                "a wall's program: phases from increasing times, each one kind of motion (above); the wall is at rest before the first, and a servo phase entered during the run starts at rest",
            ),
            Section::Particles => (
                "`[[particles]]`",
                "one or more blocks, expanded in file order (particle ids, from 0, follow it): `list` explicit particles; `lattice` a simple cubic lattice (x fastest, then y, then z) with every sphere inside the region; `random` random sequential placement without overlaps with the particles placed before that appear at the same time (up to 1000 attempts a particle; it jams near a solid fraction of 0.38)",
            ),
            Section::Size => (
                "A random block's `size`",
                "a size distribution, `size = { distribution = \"...\", ... }`, its keys by distribution (normal radii are truncated to (0, ∞) by redrawing)",
            ),
        }
    }
}

/// What a scene key is when the file leaves it out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Absent {
    /// It must be given.
    Required,
    /// This number: the reader takes it from here.
    Number(f64),
    /// As the words say (derived from other keys, or not a number).
    Words(&'static str),
}

impl Absent {
    /// In words, for the reference ("required", "1000", ...).
    pub fn text(self) -> String {
        match self {
            Absent::Required => "required".to_string(),
            Absent::Number(x) => format!("{x}"),
            Absent::Words(w) => w.to_string(),
        }
    }
}

/// One key of a scene table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneKey {
    /// The table it goes in.
    pub section: Section,
    /// The particle kinds (or size distributions) that take it; empty: every one.
    pub only: &'static [&'static str],
    /// The key.
    pub key: &'static str,
    /// What the value is ("number", "[x, y, z]", ...).
    pub value: &'static str,
    /// SI unit ("" for none).
    pub unit: &'static str,
    /// What it is when absent.
    pub default: Absent,
    /// The rule a number obeys ([`Rule::None`]: none, or one [`Self::valid`] states).
    pub rule: Rule,
    /// More of the rule in words, beyond [`Self::rule`] ("" for nothing more).
    pub valid: &'static str,
    /// What it is, in a line.
    pub doc: &'static str,
    /// A value of the right type that breaks the rule: the reader must refuse it, naming
    /// the key (a test sets each one). `None` where the rule has no such edge.
    pub refused: Option<&'static str>,
}

const ALL: &[&str] = &[];
const LIST: &[&str] = &["list"];
const LATTICE: &[&str] = &["lattice"];
const RANDOM: &[&str] = &["random"];
const LATTICE_RANDOM: &[&str] = &["lattice", "random"];
const LATTICE_RANDOM_LIST: &[&str] = &["list", "lattice", "random"];

/// A key (`only` the kinds that take it; [`ALL`]: every one).
#[allow(clippy::too_many_arguments)]
const fn key(
    section: Section,
    only: &'static [&'static str],
    key: &'static str,
    value: &'static str,
    unit: &'static str,
    default: Absent,
    rule: Rule,
    valid: &'static str,
    doc: &'static str,
    refused: Option<&'static str>,
) -> SceneKey {
    SceneKey {
        section,
        only,
        key,
        value,
        unit,
        default,
        rule,
        valid,
        doc,
        refused,
    }
}

use Section::*;

/// Every non-law scene key, in the reference's order.
pub const SCENE_KEYS: &[SceneKey] = &[
    key(Top, ALL, "domain", "table", "", Absent::Required, Rule::None, "", "the box the particles live in", None),
    key(Top, ALL, "simulation", "table", "", Absent::Required, Rule::None, "", "the run's settings", None),
    key(Top, ALL, "material", "array of tables", "", Absent::Required, Rule::None, "at least one", "the materials, each with its contact law", None),
    key(Top, ALL, "interaction", "array of tables", "", Absent::Words("none"), Rule::None, "", "the laws between pairs of materials", None),
    key(Top, ALL, "wall", "array of tables", "", Absent::Words("none"), Rule::None, "", "infinite planes", None),
    key(Top, ALL, "particles", "array of tables", "", Absent::Required, Rule::None, "at least one particle in all", "the particle blocks", None),
    // [domain]
    key(Domain, ALL, "min", "[x, y, z]", "m", Absent::Required, Rule::None, "", "the lower corner", None),
    key(Domain, ALL, "max", "[x, y, z]", "m", Absent::Required, Rule::None, "> min on every axis", "the upper corner", Some("[0.0, 0.0, 0.0]")),
    key(Domain, ALL, "periodic", "[x, y, z] of booleans", "", Absent::Words("[false, false, false]"), Rule::None, "no wall may face, and no gravity point along, a periodic axis", "the periodic axes (minimum image: pairs interact across the faces)", None),
    // [simulation]
    key(Simulation, ALL, "duration", "number", "s", Absent::Required, Rule::Positive, "", "the simulated time", Some("0.0")),
    key(Simulation, ALL, "dt", "\"auto\" or a number", "s", Absent::Words("\"auto\""), Rule::Positive, "", "the time step (\"auto\": from the stiffest contact, tc/50)", Some("0.0")),
    key(Simulation, ALL, "force_dt", "boolean", "", Absent::Words("false"), Rule::None, "", "accept a dt above the stability limit (and starting speeds at which a pair closes more than a radius in one step)", None),
    key(Simulation, ALL, "jump_impulses", "boolean", "", Absent::Words("true where some contact's force can jump"), Rule::None, "", "place the impulse of a contact force's jump (JKR touch and pull-off, jump-in adhesion, a viscous first touch) inside the step, second order in dt; false: plain velocity Verlet", None),
    key(Simulation, ALL, "output_every", "integer", "", Absent::Number(1000.0), Rule::Positive, "", "steps between outputs (`powder run`'s progress line, VTK snapshot, CSV row)", Some("0")),
    key(Simulation, ALL, "gravity", "[x, y, z]", "m/s²", Absent::Words("[0, 0, 0]"), Rule::None, "", "the gravitational acceleration", None),
    key(Simulation, ALL, "impact_velocity", "number", "m/s", Absent::Number(1.0), Rule::Positive, "", "the largest expected impact speed (it sets the Hertz/JKR contact time of the automatic dt; the starting velocities' fastest closing where that is faster)", Some("0.0")),
    key(Simulation, ALL, "checkpoint_every", "integer", "", Absent::Words("10·output_every"), Rule::Positive, "", "steps between checkpoints", Some("0")),
    key(Simulation, ALL, "contact_output", "boolean", "", Absent::Words("true under 100 000 particles"), Rule::None, "", "write the contact network with each VTK snapshot (`contacts/<name>_<step>.vtp`: a line a contact with its forces, overlap, history, sliding)", None),
    // [[material]]
    key(Material, ALL, "name", "string", "", Absent::Required, Rule::None, "unique", "the name blocks, walls and interactions refer to", None),
    key(Material, ALL, "density", "number", "kg/m³", Absent::Required, Rule::Positive, "", "the particles' density", Some("0.0")),
    key(Material, ALL, "model", "string", "", Absent::Required, Rule::None, "a law of `powder params`", "the contact law between two particles of the material (and with its walls)", Some("\"nope\"")),
    // [[interaction]]
    key(Interaction, ALL, "materials", "[string, string]", "", Absent::Required, Rule::None, "two different material names, a pair once", "the pair of materials (order does not matter)", Some("[\"powder\", \"nope\"]")),
    key(Interaction, ALL, "model", "string", "", Absent::Required, Rule::None, "a law of `powder params`", "the contact law between them", Some("\"nope\"")),
    // [[wall]]
    key(Wall, ALL, "point", "[x, y, z]", "m", Absent::Required, Rule::None, "", "a point on the plane", None),
    key(Wall, ALL, "normal", "[x, y, z]", "", Absent::Required, Rule::None, "non-zero", "points into the domain (need not be unit)", Some("[0.0, 0.0, 0.0]")),
    key(Wall, ALL, "material", "string", "", Absent::Words("the first [[material]]"), Rule::None, "a material's name", "the wall's material", Some("\"nope\"")),
    key(Wall, ALL, "velocities", "array of [x, y, z]", "m/s", Absent::Words("none"), Rule::None, "with `times`, as many", "a schedule: velocities[k] from times[k] (at rest before times[0]); instead of `velocity`, the servo and phases", None),
    key(Wall, ALL, "times", "array of numbers", "s", Absent::Words("none"), Rule::None, ">= 0, increasing", "when each of `velocities` starts", Some("[-1.0]")),
    key(Wall, ALL, "phase", "array of tables", "", Absent::Words("none"), Rule::None, "", "the wall's program (`[[wall.phase]]`, below)", None),
    // a wall's or a phase's motion
    key(Motion, ALL, "velocity", "[x, y, z]", "m/s", Absent::Words("at rest"), Rule::None, "", "a prescribed velocity (from t = 0 in a [[wall]], from `from` in a phase)", None),
    key(Motion, ALL, "servo_force", "number", "N", Absent::Words("none"), Rule::Positive, "with the other two servo keys", "the normal force the servo holds", Some("0.0")),
    key(Motion, ALL, "servo_gain", "number", "m/s per N", Absent::Words("none"), Rule::Positive, "", "speed per newton of force error", Some("0.0")),
    key(Motion, ALL, "servo_max_speed", "number", "m/s", Absent::Words("none"), Rule::Positive, "", "the servo's largest speed", Some("0.0")),
    // [[wall.phase]]
    key(Phase, ALL, "from", "number", "s", Absent::Required, Rule::NonNegative, "increasing from phase to phase", "when the phase starts", Some("-1.0")),
    // [[particles]]
    key(Particles, ALL, "kind", "string", "", Absent::Required, Rule::None, "\"list\", \"lattice\" or \"random\"", "how the block makes its particles", Some("\"nope\"")),
    key(Particles, ALL, "material", "string", "", Absent::Words("the first [[material]]"), Rule::None, "a material's name", "the particles' material", Some("\"nope\"")),
    key(Particles, ALL, "insert_at", "number", "s", Absent::Number(0.0), Rule::NonNegative, "", "when the block's particles appear (pouring; before that they neither move nor interact)", Some("-1.0")),
    key(Particles, ALL, "velocity", "[x, y, z]", "m/s", Absent::Words("[0, 0, 0]"), Rule::None, "", "every particle's starting velocity (a list: or `velocities`)", None),
    key(Particles, ALL, "angular_velocity", "[x, y, z]", "rad/s", Absent::Words("[0, 0, 0]"), Rule::None, "", "every particle's starting spin (only where a contact law turns particles)", None),
    key(Particles, LIST, "positions", "array of [x, y, z]", "m", Absent::Required, Rule::None, "", "the particles' centres", None),
    key(Particles, LATTICE_RANDOM_LIST, "radius", "number", "m", Absent::Words("required (list: or `radii`; random: or `size`)"), Rule::Positive, "", "every particle's radius", Some("0.0")),
    key(Particles, LIST, "radii", "array of numbers", "m", Absent::Words("none"), Rule::None, "> 0, one a position", "a radius a particle, instead of `radius`", Some("[0.0]")),
    key(Particles, LIST, "velocities", "array of [x, y, z]", "m/s", Absent::Words("none"), Rule::None, "one a position", "a starting velocity a particle, instead of `velocity`", Some("[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]")),
    key(Particles, LATTICE_RANDOM, "min", "[x, y, z]", "m", Absent::Required, Rule::None, "", "the region's lower corner (every sphere lies inside the region)", None),
    key(Particles, LATTICE_RANDOM, "max", "[x, y, z]", "m", Absent::Required, Rule::None, "> min on every axis", "the region's upper corner", Some("[0.0, 0.0, 0.0]")),
    key(Particles, LATTICE, "spacing", "number", "m", Absent::Words("2·radius·(1 + 10⁻⁹)"), Rule::None, ">= 2·radius", "the distance between lattice sites; a region a little short of its sites (by up to 10⁻⁶ of the spacing, as a region of exactly n diameters is for the default) holds them spread evenly, so neighbours touch exactly there: where a law's force jumps at the touch (JKR, jump-in adhesion), whether each such pair starts in contact is then decided by rounding, differently on the two engines; leave a clear gap where the network at the start matters", Some("1e-6")),
    key(Particles, LATTICE, "jitter", "number", "", Absent::Number(0.0), Rule::Closed(0.0, 1.0), "", "random shifts per axis of up to jitter·(spacing − 2·radius)/2, never causing overlaps", Some("2.0")),
    key(Particles, LATTICE_RANDOM, "seed", "integer", "", Absent::Number(1.0), Rule::NonNegative, "", "the seed of the jitter (lattice) or of the radii and positions (random, Pcg64)", Some("-1")),
    key(Particles, RANDOM, "count", "integer", "", Absent::Required, Rule::NonNegative, "", "how many particles", Some("-1")),
    key(Particles, RANDOM, "size", "table", "", Absent::Words("none"), Rule::None, "", "a size distribution instead of `radius` (below)", None),
    key(Particles, RANDOM, "batches", "integer", "", Absent::Number(1.0), Rule::Positive, "", "the number of batches `count` is poured in, each placed afresh in the region (seed + k)", Some("0")),
    key(Particles, RANDOM, "batch_interval", "number", "s", Absent::Number(0.0), Rule::NonNegative, "> 0 with batches > 1", "the time between batches (batch k appears at insert_at + k·batch_interval)", Some("0.0")),
    // a random block's size distribution
    key(Size, ALL, "distribution", "string", "", Absent::Required, Rule::None, "\"uniform\", \"normal\", \"lognormal\" or \"list\"", "the distribution of the radii", Some("\"nope\"")),
    key(Size, &["uniform"], "min", "number", "m", Absent::Required, Rule::Positive, "<= max", "the smallest radius", Some("0.0")),
    key(Size, &["uniform"], "max", "number", "m", Absent::Required, Rule::None, ">= min", "the largest radius", Some("1e-9")),
    key(Size, &["normal"], "mean", "number", "m", Absent::Required, Rule::Positive, "", "the mean radius", Some("0.0")),
    key(Size, &["normal"], "std", "number", "m", Absent::Required, Rule::NonNegative, "", "the standard deviation", Some("-1e-4")),
    key(Size, &["lognormal"], "median", "number", "m", Absent::Required, Rule::Positive, "", "the median radius", Some("0.0")),
    key(Size, &["lognormal"], "sigma", "number", "", Absent::Required, Rule::NonNegative, "", "the standard deviation of ln(radius)", Some("-0.1")),
    key(Size, &["list"], "radii", "array of numbers", "m", Absent::Required, Rule::None, "> 0", "the radii drawn from", Some("[0.0]")),
    key(Size, &["list"], "weights", "array of numbers", "", Absent::Words("all equal"), Rule::None, ">= 0, a positive sum, one a radius", "each radius's weight", Some("[-1.0]")),
];

impl SceneKey {
    /// Its whole rule in words: [`Self::rule`]'s and [`Self::valid`].
    pub fn valid_text(&self) -> String {
        let parts: Vec<String> = self
            .rule
            .text()
            .into_iter()
            .chain((!self.valid.is_empty()).then(|| self.valid.to_string()))
            .collect();
        parts.join(", ")
    }

    /// What it is, with its unit ("the simulated time, in s").
    pub fn what(&self) -> String {
        match self.unit.is_empty() {
            true => self.doc.to_string(),
            false => format!("{}, in {}", self.doc, self.unit),
        }
    }

    /// Why `value` breaks the rule, naming the key: "`key` (what) must be > 0, got 0"
    /// (`place`, e.g. `" in [simulation]"`, after the key).
    pub fn broken(&self, place: &str, value: f64) -> String {
        format!(
            "`{}`{place} ({}) must be {}, got {}",
            self.key,
            self.what(),
            self.rule.requirement(value),
            crate::error::num(value)
        )
    }
}

/// The declaration of `key` in `section`; panics where there is none (a reader's or a
/// check's key must be declared: the declarations' tests keep them so).
pub fn declared(section: Section, key: &str) -> &'static SceneKey {
    SCENE_KEYS
        .iter()
        .find(|k| k.section == section && k.key == key)
        .unwrap_or_else(|| panic!("`{key}` is not declared in {section:?}"))
}

/// The number `key` of `section` is when absent; panics where its declaration states none
/// (a reader asks only for keys declared with a number: the declarations' tests keep it so).
pub fn default_number(section: Section, key: &str) -> f64 {
    match declared(section, key).default {
        Absent::Number(x) => x,
        other => panic!("`{key}` in {section:?} has no number when absent: {other:?}"),
    }
}

/// Checks `value` of `key` in `section` against its declared rule: the error names the
/// key, what it is, its table and the rule (`what` says where, e.g. "particle 3").
pub fn check(section: Section, key: &str, value: f64, what: &str) -> Result<(), String> {
    let k = declared(section, key);
    match k.rule.holds(value) {
        true => Ok(()),
        false => Err(format!("{what}: {}", k.broken("", value))),
    }
}

/// The keys of `section` (of particle kind or size distribution `kind` where it has
/// them), in declaration order.
pub(super) fn keys_of(section: Section, kind: Option<&str>) -> Vec<&'static str> {
    SCENE_KEYS
        .iter()
        .filter(|k| k.section == section)
        .filter(|k| k.only.is_empty() || kind.is_some_and(|kind| k.only.contains(&kind)))
        .map(|k| k.key)
        .collect()
}

/// The keys of every kind or distribution of `section`, each once.
pub(super) fn any_keys_of(section: Section) -> Vec<&'static str> {
    let mut keys: Vec<&'static str> = Vec::new();
    for k in SCENE_KEYS.iter().filter(|k| k.section == section) {
        if !keys.contains(&k.key) {
            keys.push(k.key);
        }
    }
    keys
}
