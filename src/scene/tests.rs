//! Unit tests of scene parsing and validation.

use super::hash_grid::dist2;
use super::particles::SizeDist;
use super::toml_reader::Src;
use super::*;
use crate::model::{AdhesionMode, K2Rule, LsdParams};
use rand::SeedableRng;
use rand_pcg::Pcg64;

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
    let off = minimal("", "").replace("duration = 0.1", "duration = 0.1\ncontact_output = false");
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
    assert_contains(&e, &["line 3", "`duration`", "duplicate key"]);
    let e = err("[simulation]\nduration = 0.1\n[simulation]\n");
    assert_contains(&e, &["line 3", "simulation", "duplicate"]);
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
    let e = err(&minimal("", "").replace("duration = 0.1", "duration = 0.1\ngravty = [0, 0, 0]"));
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
    let e = err(&minimal("", "").replace("radius = 1e-3", "radius = 1e-3\nvelocty = [0, 0, 0]"));
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
    let e = err(&minimal("", "").replace("duration = 0.1", "duration = 0.1\noutput_every = 1.5"));
    assert_contains(
        &e,
        &["`output_every` in [simulation] must be a non-negative integer"],
    );
    // a negative count is told its rule
    let e = err(&minimal("", "").replace("duration = 0.1", "duration = 0.1\noutput_every = -5"));
    assert_contains(&e, &["`output_every`", "must be > 0", "-5"]);
    let e = err(&minimal("", "").replace("min = [0.0, 0.0, 0.0]", "min = [0.0, 0.0]"));
    assert_contains(
        &e,
        &[
            "`min` in [domain] must be an array of 3 numbers",
            "2 element(s): the number 0, the number 0",
            "line 2",
        ],
    );
    // the right length of the wrong kind names the kind
    let e = err(&minimal("", "").replace(
        "min = [0.0, 0.0, 0.0]",
        "min = [0.0, 0.0, 0.0]\nperiodic = [1, 0, 0]",
    ));
    assert_contains(&e, &["`periodic`", "the integer 1, the integer 0"]);
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
            &["`max` in [domain] must be > `min`", "axis z"],
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
    // a material's law with itself is its own, not an interaction's (it used to override it)
    let e = err(&minimal(
        "",
        "[[interaction]]\nmaterials = [\"powder\", \"powder\"]\nmodel = \"lsd\"\nk = 1.0\n",
    ));
    assert_contains(
        &e,
        &[
            "`powder` with itself",
            "[[interaction]] #1",
            "two different materials",
        ],
    );
    let mut s = parse(FULL).unwrap();
    s.interactions[0].materials = [1, 1];
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("with itself"), "{e}");
    // a scene built in code is held to the reader's naming rules
    let mut s = parse(FULL).unwrap();
    s.materials[1].name = s.materials[0].name.clone();
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("materials 0 and 1 are both named"), "{e}");
    s.materials[1].name = " ".into();
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("material 1 has an empty name"), "{e}");
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
    // a lattice whose count is beyond u64 (it wrapped to none), a pour beyond the limit
    let e = err(&minimal(
        "",
        "[[particles]]\nkind = \"lattice\"\nmin = [0.001, 0.001, 0.0085]\nmax = [0.009, 0.009, 0.009]\nradius = 1e-22\nspacing = 2e-22\n",
    ));
    assert_contains(&e, &["would create", "e", "more than 100000000", "spacing"]);
    let e = err(&minimal(
        "",
        "[[particles]]\nkind = \"random\"\ncount = 1000000000\nbatches = 1000000000\nbatch_interval = 1e-3\nmin = [0, 0, 0]\nmax = [0.004, 0.004, 0.004]\nradius = 1e-4\n",
    ));
    assert_contains(&e, &["`count`", "1000000000", "more than the limit"]);
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
    // 5 x 10 x 15 diameters fit exactly, and no two spheres overlap beyond rounding (the
    // default spacing's last site lies 10⁻⁹ of the spacing beyond the region: clamped, it
    // overlapped its neighbour by 4·10⁻¹⁰ of the radius)
    let closest = |s: &Scene| {
        let p = &s.particles;
        let mut d: f64 = f64::INFINITY;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                d = d.min(dist2(p[i].position, p[j].position).sqrt());
            }
        }
        d
    };
    for extra in [
        "",
        "jitter = 1.0",
        "spacing = 0.0200000001",
        "spacing = 0.02",
    ] {
        let s = parse(&scene(extra)).unwrap();
        assert_eq!(s.particles.len(), 5 * 10 * 15, "{extra}");
        assert!(
            closest(&s) >= 0.02 * (1.0 - 1e-14),
            "{extra}: {:e}",
            closest(&s)
        );
        let last = s
            .particles
            .iter()
            .map(|p| p.position[2])
            .fold(0.0, f64::max);
        assert!(last <= 0.29 + 1e-15, "{extra}: {last}");
    }
    // a region whose last site would need neighbours closer than 2·radius drops it (the
    // default spacing's site lies 10⁻⁹ beyond; spread, they would overlap by 10⁻⁸)
    let block = |lo: &str, hi: &str| {
        scene("").replace(
            "min = [0.0, 0.0, 0.0]\nmax = [0.1, 0.2, 0.3]",
            &format!("min = {lo}\nmax = {hi}"),
        )
    };
    let s = parse(&block("[0.0, 0.0, 0.0]", "[0.0999999990, 0.2, 0.3]")).unwrap();
    assert_eq!(s.particles.len(), 4 * 10 * 15);
    assert!(closest(&s) >= 0.02 * (1.0 - 1e-14), "{:e}", closest(&s));
    // a region one diameter wide, whose site's bounds cross by rounding (0.04 + 0.01 >
    // 0.06 − 0.01), holds its site centred (the clamp to an empty interval panicked)
    let s = parse(&block("[0.04, 0.0, 0.0]", "[0.06, 0.2, 0.3]")).unwrap();
    assert_eq!(s.particles.len(), 10 * 15);
    assert!((s.particles[0].position[0] - 0.05).abs() < 1e-15);
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
    assert_contains(&e, &["`jitter`", "must be in [0, 1], got 2"]);
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
    // weights whose sum overflows f64 draw as their ratios do (equal: both radii)
    let s = parse(&random_scene(
        1,
        300,
        "size = { distribution = \"list\", radii = [0.8e-3, 1.2e-3], weights = [1e308, 1e308] }",
    ))
    .unwrap();
    let small = s.particles[1250..]
        .iter()
        .filter(|p| p.radius == 0.8e-3)
        .count();
    assert!((100..200).contains(&small), "{small} of 300 small");
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
        sets: &[],
    };
    assert_eq!(src.line_col(0), (1, 1));
    assert_eq!(src.line_col(3), (2, 1));
    assert_eq!(src.line_col(5), (2, 2));
    assert_eq!(src.line_col(100), (3, 1));
}

#[test]
fn overlaps_across_a_periodic_seam_are_refused() {
    let text = minimal("", "")
        .replace(
            "max = [0.01, 0.01, 0.01]",
            "max = [0.01, 0.01, 0.01]\nperiodic = [true, false, false]",
        )
        .replace(
            "[[0.005, 0.005, 0.005]]",
            "[[0.0009, 0.005, 0.005], [0.0091, 0.005, 0.005]]",
        );
    let e = err(&text);
    assert_contains(&e, &["particles 0", "and 1", "across the periodic seam"]);
    // apart by 2.2 mm across the seam: no overlap
    parse(&text.replace("0.0091", "0.0089")).unwrap();
    // across two seams at once (a corner): 1.4 mm apart only through the corner image
    let corner = minimal("", "")
        .replace(
            "max = [0.01, 0.01, 0.01]",
            "max = [0.01, 0.01, 0.01]\nperiodic = [true, true, false]",
        )
        .replace(
            "[[0.005, 0.005, 0.005]]",
            "[[0.0005, 0.0005, 0.005], [0.0095, 0.0095, 0.005]]",
        );
    assert_contains(&err(&corner), &["particles 0", "across the periodic seam"]);
}

#[test]
fn pouring_more_batches_than_particles_is_refused() {
    let block = "[[particles]]\nkind = \"random\"\ncount = 3\nbatches = 1000000000\nbatch_interval = 1e-6\nmin = [0, 0, 0]\nmax = [0.01, 0.01, 0.01]\nradius = 1e-4\n";
    let e = err(&minimal("", block));
    assert_contains(&e, &["`batches` = 1000000000", "more than `count` = 3"]);
    // a negative interval is refused even where one batch makes it unused
    let one = "[[particles]]\nkind = \"random\"\ncount = 3\nbatch_interval = -1e-3\nmin = [0, 0, 0]\nmax = [0.01, 0.01, 0.01]\nradius = 1e-4\n";
    assert_contains(
        &err(&minimal("", one)),
        &["`batch_interval`", "must be >= 0, got -0.001"],
    );
}

/// A pour whose next batch appears where the last one would still be in free flight is
/// warned of before the run; one whose batches have fallen out of the region is not.
#[test]
fn a_pour_onto_the_batch_before_is_warned_of() {
    let pour = |interval: &str| {
        format!(
            "[[particles]]\nkind = \"random\"\ncount = 40\nbatches = 2\nbatch_interval = {interval}\nmin = [0.0, 0.0, 0.02]\nmax = [0.01, 0.01, 0.03]\nradius = 1e-3\nseed = 3\nvelocity = [0.0, 0.0, -0.3]\n"
        )
    };
    let scene = |interval: &str| {
        let text = minimal("", &pour(interval))
            .replace(
                "duration = 0.1",
                "duration = 0.1\ngravity = [0.0, 0.0, -9.81]",
            )
            .replace("max = [0.01, 0.01, 0.01]", "max = [0.01, 0.01, 0.04]");
        parse(&text).unwrap()
    };
    let w = scene("1e-3").pour_onto_earlier().expect("a warning");
    assert_contains(
        &w,
        &[
            "appears at 1e-3 s where particle",
            "flown freely",
            "`batch_interval`",
        ],
    );
    // 0.1 s later the first batch has fallen 7.9 cm, out of the 1 cm region
    assert_eq!(scene("0.1").pour_onto_earlier(), None);
}

#[test]
fn insertions_after_the_end_are_named() {
    let block = |at: &str| {
        format!("[[particles]]\nkind = \"list\"\npositions = [[0.002, 0.002, 0.002]]\nradius = 1e-4\ninsert_at = {at}\n")
    };
    let late = parse(&minimal("", &block("2.0"))).unwrap();
    let w = late.late_insertions(0.1 - 1e-3).expect("a warning");
    assert_contains(
        &w,
        &["1 of the 2 particles", "particle 1", "insert_at = 2e0 s"],
    );
    // after the last step begins, before the duration: never inserted either
    let last = parse(&minimal("", &block("0.0995"))).unwrap();
    assert!(last.late_insertions(0.1 - 1e-3).is_some());
    let early = parse(&minimal("", &block("1e-9"))).unwrap();
    assert_eq!(early.late_insertions(0.1 - 1e-3), None);
}

fn parse_with(text: &str, sets: &[&str]) -> Result<Scene, String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str_with(text, "test", &sets).map_err(|e| e.to_string())
}

#[test]
fn overrides_reach_tables_blocks_and_elements() {
    let text = minimal(
        "",
        "[[particles]]\nkind = \"list\"\npositions = [[0.002, 0.002, 0.002]]\nradius = 1e-3\n",
    );
    let scene = parse_with(
        &text,
        &[
            "particles[1].radius = 5e-4",
            "domain.max=[0.02, 0.02, 0.01]",
            "domain.min[2] = -0.01",
            "simulation.duration = 0.5",
        ],
    )
    .unwrap();
    assert_eq!(scene.particles[1].radius, 5e-4);
    assert_eq!(scene.domain.max, [0.02, 0.02, 0.01]);
    assert_eq!(scene.domain.min[2], -0.01);
    assert_eq!(scene.duration, 0.5);
    let e = |sets: &[&str]| parse_with(&text, sets).unwrap_err();
    assert_contains(&e(&["particles[2].radius = 1"]), &["has 2 blocks"]);
    assert_contains(
        &e(&["particles.radius = 1"]),
        &["pick one with particles[INDEX]"],
    );
    assert_contains(&e(&["walls.x = 1"]), &["no `walls`"]);
    assert_contains(&e(&["domain.min.x = 1"]), &["`min` is not a table"]);
    assert_contains(&e(&["domain.min[3] = 1"]), &["`min` has no element [3]"]);
}

#[test]
fn errors_keep_the_files_line_numbers_with_overrides() {
    let text = minimal("", "");
    let line = |key: &str| 1 + text.lines().position(|l| l.starts_with(key)).unwrap();
    // a value set is named by its override, not the line it replaced
    let e = parse_with(&text, &["material[0].density = 0"]).unwrap_err();
    assert_contains(&e, &["--set material[0].density = 0: ", "density", "got 0"]);
    assert!(!e.contains("line "), "{e}");
    // an error elsewhere keeps its line, whatever was set before it
    let bad = text.replace("k = 100.0", "k = -1.0");
    let e = parse_with(
        &bad,
        &[
            "simulation.duration = 0.5",
            "domain.max = [0.02, 0.02, 0.02]",
        ],
    )
    .unwrap_err();
    assert_contains(&e, &[&format!("line {}, column", line("k = "))]);
    // so is a key added
    let e = parse_with(
        &text,
        &["simulation.duration = 0.5", "simulation.durration = 1"],
    )
    .unwrap_err();
    assert_contains(&e, &["--set simulation.durration = 1: ", "durration"]);
}

#[test]
fn negative_coefficients_of_a_sub_model_left_off_are_refused() {
    for key in ["friction", "rolling_friction", "twisting_friction"] {
        let e = err(&minimal(&format!("{key} = -0.3"), ""));
        assert_contains(
            &e,
            &[&format!("`{key}`"), "must be >= 0, got -0.3", "line 13"],
        );
    }
    let jkr = "model = \"jkr\"\nyoungs = 1e9\npoisson = 0.3\nsurface_energy = 0.05\ntwisting_friction = -1.0";
    let e = err(&minimal("", "").replace("model = \"lsd\"\nk = 100.0", jkr));
    assert_contains(&e, &["`twisting_friction`", "must be >= 0"]);
}

#[test]
fn a_wall_normal_too_long_to_square_is_normalised() {
    let wall = "[[wall]]\npoint = [0, 0, 0]\nnormal = [0, 1e300, 1e300]\n";
    let scene = parse(&minimal("", wall)).unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let n = scene.walls[0].normal;
    assert!(
        n[0] == 0.0 && (n[1] - h).abs() < 1e-15 && (n[2] - h).abs() < 1e-15,
        "{n:?}"
    );
    let tiny = parse(&minimal("", &wall.replace("1e300", "1e-200"))).unwrap();
    assert_eq!(tiny.walls[0].normal, n);
    let e = err(&minimal(
        "",
        &wall.replace("[0, 1e300, 1e300]", "[0, 0, 0]"),
    ));
    assert_contains(&e, &["must be a non-zero vector", "got [0, 0, 0]"]);
}

/// A saved state's appeared flag fits the pouring exactly outside the step its particle is
/// due at; a state taken as that step began may hold it either way.
#[test]
fn an_appeared_flag_fits_the_step_its_particle_is_due_at() {
    let dt = 1e-5;
    // due at step 10 (10·dt), and at the start (0)
    let at = 10.0 * dt;
    for (steps, must) in [(0, Some(false)), (9, Some(false)), (11, Some(true))] {
        for appeared in [false, true] {
            let fits = appearance_fits(at, steps, dt, appeared);
            assert_eq!(
                fits,
                must == Some(appeared),
                "after {steps} steps: {appeared}"
            );
        }
    }
    // (after 10 steps: step 10, which inserts it, may have begun)
    assert!(appearance_fits(at, 10, dt, true) && appearance_fits(at, 10, dt, false));
    assert!(appearance_fits(0.0, 0, dt, true) && !appearance_fits(0.0, 0, dt, false));
    let why = misfit_appearance(&[0.0, at], &[true, true], 5, dt).unwrap();
    assert!(why.contains("particle 1 appeared after 5 steps"), "{why}");
    assert!(misfit_appearance(&[0.0, at], &[true], 5, dt).is_some());
    assert!(misfit_appearance(&[0.0, at], &[true, false], 5, dt).is_none());
}

/// Neighbours touching to within rounding are warned of where the law's force jumps at
/// the touch (jump-in adhesion), not where it is continuous (a linear spring) nor where
/// a gap separates them; across a periodic seam too.
#[test]
fn pairs_touching_at_the_start_under_a_jumping_law_are_warned_of() {
    let scene = |law: &str, spacing: &str| {
        let text = format!(
            "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.012, 0.012, 0.006]\nperiodic = [true, true, false]\n[simulation]\nduration = 1.0\n[[material]]\nname = \"p\"\ndensity = 2000.0\n{law}\n[[particles]]\nkind = \"lattice\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.012, 0.012, 0.002]\nradius = 1e-3\n{spacing}"
        );
        Scene::from_toml_str(&text, "t").unwrap()
    };
    let sticky = "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 100.0\nphi_f = 0.05\nfa = 1e-5\nkca = 50.0";
    let w = scene(sticky, "").touching_at_start().expect("a warning");
    // 6 × 6 spheres, each touching its +x and +y neighbour (the seam's included)
    assert!(w.starts_with("72 pairs start touching"), "{w}");
    assert!(w.contains("(the first: particles 0 and 1, gap"), "{w}");
    assert!(w.contains("materials `p` and `p`"), "{w}");
    // a floor under the lattice's region: the 36 spheres resting on it exactly
    let floored = |law: &str| {
        let mut s = scene(law, "");
        s.walls.push(crate::scene::Wall {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            motion: Default::default(),
            material: 0,
        });
        s
    };
    let w = floored(sticky).touching_at_start().expect("a warning");
    assert!(w.starts_with("108 pairs start touching"), "{w}");
    assert!(w.contains("(the first: particle 0 and wall 0, gap"), "{w}");
    assert_eq!(scene(sticky, "spacing = 2.2e-3").touching_at_start(), None);
    assert_eq!(
        floored("model = \"lsd\"\nk = 100.0").touching_at_start(),
        None
    );
}
