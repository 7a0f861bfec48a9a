//! The scene-key declarations tied to the reader and to `docs/scene.md`.

use super::declared::{SceneKey, Section, SCENE_KEYS};
use super::Scene;
use crate::model::params::Rule;

/// A scene with every table the declarations name: a servo wall (0), a plain wall (1), a
/// wall with a phase (2); a list block with `radius` (0), a lattice (1), random blocks of a
/// fixed radius (2) and of each size distribution (3–6), a list block with `radii` (7).
const TEMPLATE: &str = r#"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.04, 0.04, 0.04]

[simulation]
duration = 0.01

[[material]]
name = "powder"
density = 2000.0
model = "lsd"
k = 100.0

[[material]]
name = "glass"
density = 2500.0
model = "lsd"
k = 100.0

[[interaction]]
materials = ["powder", "glass"]
model = "lsd"
k = 100.0

[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
servo_force = 1.0
servo_gain = 1e-3
servo_max_speed = 0.01

[[wall]]
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]

[[wall]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[wall.phase]]
from = 0.0

[[particles]]
kind = "list"
positions = [[0.035, 0.035, 0.035]]
radius = 1e-3

[[particles]]
kind = "lattice"
min = [0.002, 0.002, 0.002]
max = [0.01, 0.01, 0.01]
radius = 1e-3

[[particles]]
kind = "random"
count = 2
min = [0.002, 0.002, 0.015]
max = [0.03, 0.03, 0.03]
radius = 1e-3

[[particles]]
kind = "random"
count = 2
min = [0.002, 0.002, 0.015]
max = [0.03, 0.03, 0.03]
size = { distribution = "uniform", min = 1e-3, max = 1e-3 }

[[particles]]
kind = "random"
count = 2
min = [0.002, 0.002, 0.015]
max = [0.03, 0.03, 0.03]
size = { distribution = "normal", mean = 1e-3, std = 1e-5 }

[[particles]]
kind = "random"
count = 2
min = [0.002, 0.002, 0.015]
max = [0.03, 0.03, 0.03]
size = { distribution = "lognormal", median = 1e-3, sigma = 0.01 }

[[particles]]
kind = "random"
count = 2
min = [0.002, 0.002, 0.015]
max = [0.03, 0.03, 0.03]
size = { distribution = "list", radii = [1e-3], weights = [1.0] }

[[particles]]
kind = "list"
positions = [[0.035, 0.035, 0.005]]
radii = [1e-3]
"#;

/// Where `key` goes in [`TEMPLATE`] for kind (or distribution) `kind`, and the settings it
/// needs beside it.
fn place(key: &SceneKey, kind: &str) -> (String, Vec<String>) {
    let block = |b: usize| format!("particles[{b}].{}", key.key);
    let path = match key.section {
        Section::Top => unreachable!("no top-level key has a refused value"),
        Section::Domain => format!("domain.{}", key.key),
        Section::Simulation => format!("simulation.{}", key.key),
        Section::Material => format!("material[0].{}", key.key),
        Section::Interaction => format!("interaction[0].{}", key.key),
        Section::Wall => format!("wall[1].{}", key.key),
        Section::Motion => format!("wall[0].{}", key.key),
        Section::Phase => format!("wall[2].phase[0].{}", key.key),
        Section::Particles => match (kind, key.key) {
            ("list", "radii" | "velocities") => block(7),
            ("list", _) => block(0),
            ("lattice", _) => block(1),
            _ => block(2),
        },
        Section::Size => {
            let b = match kind {
                "uniform" => 3,
                "normal" => 4,
                "lognormal" => 5,
                _ => 6,
            };
            format!("particles[{b}].size.{}", key.key)
        }
    };
    let beside = match key.key {
        "times" => vec!["wall[1].velocities=[[0.0, 0.0, 0.0]]".to_string()],
        "batch_interval" => vec!["particles[2].batches=2".to_string()],
        _ => vec![],
    };
    (path, beside)
}

#[test]
fn the_template_scene_reads() {
    let scene = Scene::from_toml_str(TEMPLATE, "template").unwrap();
    assert_eq!(scene.walls.len(), 3);
}

/// Each declared rule's edge is refused by the reader, in an error that names the key
/// (each kind that takes the key, the key set through `--set`).
#[test]
fn the_reader_refuses_each_declared_rule_edge() {
    let (mut checked, mut wrong) = (0, Vec::new());
    for key in SCENE_KEYS {
        let Some(refused) = key.refused else {
            continue;
        };
        let kinds: &[&str] = match (key.section, key.only.is_empty()) {
            (Section::Particles, true) => &["list", "lattice", "random"],
            (_, true) => &[""],
            (_, false) => key.only,
        };
        for kind in kinds {
            let (path, mut sets) = place(key, kind);
            sets.push(format!("{path}={refused}"));
            match Scene::from_toml_str_with(TEMPLATE, "template", &sets) {
                Ok(_) => wrong.push(format!(
                    "{path} = {refused} was accepted (valid: {})",
                    key.valid
                )),
                Err(e) => {
                    let err = e.to_string();
                    let named = [format!("`{}`", key.key), format!("`{}[", key.key)];
                    if !named.iter().any(|n| err.contains(n)) || err.contains("unknown key") {
                        wrong.push(format!(
                            "{path} = {refused}: the error does not name `{}`: {err}",
                            key.key
                        ));
                    }
                }
            }
            checked += 1;
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert!(checked >= 40, "{checked} edges checked");
}

/// The settings beside a refused value are valid on their own (the refusal is the value's).
#[test]
fn the_settings_beside_a_refused_value_read() {
    for key in SCENE_KEYS.iter().filter(|k| k.refused.is_some()) {
        let (_, mut sets) = place(key, key.only.first().copied().unwrap_or("random"));
        match key.key {
            "times" => sets.push("wall[1].times=[0.0]".into()),
            "batch_interval" => sets.push("particles[2].batch_interval=0.001".into()),
            _ => {}
        }
        Scene::from_toml_str_with(TEMPLATE, "template", &sets)
            .unwrap_or_else(|e| panic!("{sets:?}: {e}"));
    }
}

/// A number a key takes when absent obeys the key's own rule, and a scene that leaves the
/// key out reads it.
#[test]
fn a_declared_default_number_obeys_its_rule_and_is_read() {
    for k in SCENE_KEYS {
        if let super::declared::Absent::Number(x) = k.default {
            assert!(k.rule.holds(x), "{}: {x} breaks {:?}", k.key, k.rule);
        }
    }
    let scene = Scene::from_toml_str_with(TEMPLATE, "template", &[]).unwrap();
    let n = |s, k| super::declared::default_number(s, k);
    assert_eq!(
        scene.output_every as f64,
        n(Section::Simulation, "output_every")
    );
    assert_eq!(
        scene.impact_velocity,
        n(Section::Simulation, "impact_velocity")
    );
}

/// Every key has a doc, a value and a default in words, and each (section, kind) holds a
/// key once.
#[test]
fn every_declaration_is_complete_and_once() {
    for (i, k) in SCENE_KEYS.iter().enumerate() {
        assert!(
            !k.doc.is_empty() && !k.value.is_empty() && !k.default.text().is_empty(),
            "{k:?}"
        );
        let clash = SCENE_KEYS[..i].iter().any(|o| {
            o.section == k.section
                && o.key == k.key
                && (o.only.is_empty()
                    || k.only.is_empty()
                    || o.only.iter().any(|x| k.only.contains(x)))
        });
        assert!(!clash, "{} declared twice in {:?}", k.key, k.section);
        // a numeric refused value breaks the typed rule where that is the whole rule
        if let Some(x) = k.refused.and_then(|r| r.parse::<f64>().ok()) {
            if k.rule != Rule::None && k.valid.is_empty() {
                assert!(!k.rule.holds(x), "{}: {x} obeys {:?}", k.key, k.rule);
            }
        }
    }
}

/// The numbers the declarations state in words are the reader's constants.
#[test]
fn the_declared_numbers_are_the_readers() {
    let text = |s: Section| s.title().1.to_string();
    let attempts = format!("up to {} attempts", super::MAX_PLACEMENT_ATTEMPTS);
    assert!(text(Section::Particles).contains(&attempts));
    let output = SCENE_KEYS
        .iter()
        .find(|k| k.key == "contact_output")
        .unwrap();
    let below = super::CONTACT_OUTPUT_BELOW.to_string();
    let below = format!(
        "{} {}",
        &below[..below.len() - 3],
        &below[below.len() - 3..]
    );
    assert_eq!(
        output.default.text(),
        format!("true under {below} particles")
    );
}

/// docs/scene.md is the reference the declarations generate.
#[test]
fn the_scene_reference_is_current() {
    let file = include_str!("../../docs/scene.md");
    assert!(
        file == super::reference::markdown(),
        "docs/scene.md is out of date: `cargo run --release -- params scene > docs/scene.md`"
    );
}
