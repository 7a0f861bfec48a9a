//! Every shipped scene loads and runs; JKR scenes parse with their options and errors.

use powder::cpu::CpuEngine;
use powder::model::{ContactModel, Dissipation, Pulloff, TsujiStiffness};
use powder::scene::Scene;

#[test]
fn every_example_scene_loads_and_steps() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut seen = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let mut engine = CpuEngine::new(&scene).unwrap();
            engine.run_steps(200).unwrap();
            let e = engine.energies();
            assert!(e.total().is_finite(), "{}", path.display());
            seen += 1;
        }
    }
    assert!(seen >= 3);
}

const JKR_SCENE: &str = r#"
[domain]
min = [0.0, 0.0, 0.0]
max = [1e-4, 1e-4, 1e-4]

[simulation]
duration = 1e-5
impact_velocity = 0.5

[[material]]
name = "m"
density = 2500.0
model = "jkr"
youngs = 1e8
poisson = 0.3
surface_energy = 0.01
dissipation = "powerlaw"
D = 1e-9
alpha = 1.0
beta = 1.0
friction = 0.2
rolling_hysteresis = 0.3
pulloff = "force"

[[particles]]
kind = "list"
positions = [[5e-5, 5e-5, 5e-5]]
radius = 5e-6
"#;

#[test]
fn jkr_material_parses_with_all_options() {
    let s = Scene::from_toml_str(JKR_SCENE, "jkr").unwrap();
    assert_eq!(s.impact_velocity, 0.5);
    let ContactModel::Jkr(p) = s.materials[0].model else {
        panic!("not jkr")
    };
    assert_eq!(
        p.dissipation,
        Dissipation::PowerLaw {
            d: 1e-9,
            alpha: 1.0,
            beta: 1.0
        }
    );
    assert_eq!(p.pulloff, Pulloff::Force);
    assert_eq!(
        (p.friction, p.rolling_hysteresis, p.stiffness_scale),
        (0.2, 0.3, 1.0)
    );
    // the reduced stiffness with the Tsuji dissipation it was derived for
    let tsuji = JKR_SCENE
        .replace(
            "dissipation = \"powerlaw\"\nD = 1e-9\nalpha = 1.0\nbeta = 1.0\n",
            "restitution = 0.5\n",
        )
        .replace(
            "pulloff = \"force\"",
            "pulloff = \"zero\"\nstiffness_scale = 0.5",
        );
    let s = Scene::from_toml_str(&tsuji, "jkr").unwrap();
    let ContactModel::Jkr(p) = s.materials[0].model else {
        panic!("not jkr")
    };
    assert_eq!(p.dissipation, Dissipation::tsuji(0.5));
    assert_eq!((p.pulloff, p.stiffness_scale), (Pulloff::Zero, 0.5));
    // paper 002's stiffness of the Tsuji dashpots
    let s = Scene::from_toml_str(
        &tsuji.replace(
            "restitution = 0.5\n",
            "restitution = 0.5\ntsuji_stiffness = \"hertz\"\n",
        ),
        "jkr",
    )
    .unwrap();
    let ContactModel::Jkr(p) = s.materials[0].model else {
        panic!("not jkr")
    };
    assert_eq!(
        p.dissipation,
        Dissipation::Tsuji {
            restitution: 0.5,
            stiffness: TsujiStiffness::Hertz
        }
    );
    let s = Scene::from_toml_str(
        &tsuji.replace(
            "restitution = 0.5\n",
            "dissipation = \"tsuji\"\nrestitution = 0.5\ntsuji_stiffness = \"contact-radius\"\n",
        ),
        "jkr",
    )
    .unwrap();
    let ContactModel::Jkr(p) = s.materials[0].model else {
        panic!("not jkr")
    };
    assert_eq!(p.dissipation, Dissipation::tsuji(0.5));
}

#[test]
fn jkr_scene_errors_name_the_key() {
    let err = |text: String| Scene::from_toml_str(&text, "jkr").unwrap_err().to_string();
    let e = err(JKR_SCENE.replace("friction = 0.2", "fricton = 0.2"));
    assert!(e.contains("did you mean `friction`"), "{e}");
    let e = err(JKR_SCENE.replace("friction = 0.2", "kp = 0.2"));
    assert!(
        e.contains("`kp` is a parameter of the `hysteretic` model"),
        "{e}"
    );
    let e = err(JKR_SCENE.replace("poisson = 0.3", "poisson = 0.7"));
    assert!(e.contains("poisson"), "{e}");
    let e = err(JKR_SCENE.replace("dissipation = \"powerlaw\"", "dissipation = \"tsuji\""));
    assert!(e.contains("restitution"), "{e}");
    // paper 002's reduced-stiffness rule is for Tsuji damping only
    let e = err(JKR_SCENE.replace("pulloff = \"force\"", "stiffness_scale = 0.5"));
    assert!(
        e.contains("stiffness_scale") && e.contains("Tsuji") && e.contains("line 23"),
        "{e}"
    );
    let e = err(JKR_SCENE.replace("D = 1e-9", "D = 1e-9\ntvis = 1.0"));
    assert!(
        e.contains("`tvis`") && e.contains("dissipation = \"krijt\" only"),
        "{e}"
    );
    // tsuji_stiffness belongs to the tsuji dissipation, with its two words
    let e = err(JKR_SCENE.replace("D = 1e-9", "D = 1e-9\ntsuji_stiffness = \"hertz\""));
    assert!(
        e.contains("`tsuji_stiffness`")
            && e.contains("dissipation = \"tsuji\" only")
            && e.contains("not dissipation = \"powerlaw\""),
        "{e}"
    );
    let e = err(JKR_SCENE.replace(
        "dissipation = \"powerlaw\"\nD = 1e-9\nalpha = 1.0\nbeta = 1.0\n",
        "restitution = 0.5\ntsuji_stiffness = \"sqrt\"\n",
    ));
    assert!(
        e.contains("`tsuji_stiffness`") && e.contains("\"contact-radius\" or \"hertz\""),
        "{e}"
    );
    let e = err(JKR_SCENE.replace("model = \"jkr\"", "model = \"hertz\""));
    assert!(
        e.contains("surface_energy") && e.contains("`jkr` model"),
        "{e}"
    );
}

/// Luding's friction keys in a scene: JKR takes the twisting trio (its own sliding and
/// rolling laws otherwise); a stiffness without its coefficient is refused at its line.
#[test]
fn luding_friction_keys_in_a_scene() {
    let s = Scene::from_toml_str(
        &JKR_SCENE.replace(
            "pulloff = \"force\"",
            "twisting_friction = 0.1\ngamma_o = 1e-9",
        ),
        "jkr",
    )
    .unwrap();
    let ContactModel::Jkr(p) = s.materials[0].model else {
        panic!("not jkr")
    };
    let o = p.luding.twisting;
    assert_eq!((o.mu_s, o.k, o.gamma), (0.1, 0.0, 1e-9));
    let err = |text: String| Scene::from_toml_str(&text, "jkr").unwrap_err().to_string();
    let e = err(JKR_SCENE.replace("pulloff = \"force\"", "ko = 5.0"));
    assert!(
        e.contains("ko is given but twisting_friction = 0") && e.contains("line 23"),
        "{e}"
    );
    let e = err(JKR_SCENE.replace("pulloff = \"force\"", "kt = 5.0"));
    assert!(
        e.contains("`kt` is a parameter of the `hysteretic` model"),
        "{e}"
    );
}

/// A particle block's `angular_velocity` starts the spin where particles rotate (the CPU
/// engine holds it from step 0; the GPU's is `tests/friction.rs`), and is refused with
/// the particle named where no contact model makes them rotate.
#[test]
fn angular_velocity_starts_the_spin_where_particles_rotate() {
    let spin = JKR_SCENE.replace(
        "radius = 5e-6",
        "radius = 5e-6\nangular_velocity = [1.0, 2.0, 3.0]",
    );
    let s = Scene::from_toml_str(&spin, "spin").unwrap();
    assert_eq!(s.particles[0].angular_velocity, [1.0, 2.0, 3.0]);
    let e = CpuEngine::new(&s).unwrap();
    assert_eq!(e.angular_velocities()[0].to_array(), [1.0, 2.0, 3.0]);
    let still = spin
        .replace("friction = 0.2", "friction = 0.0")
        .replace("rolling_hysteresis = 0.3", "rolling_hysteresis = 0.0");
    let s = Scene::from_toml_str(&still, "spin").unwrap();
    let e = CpuEngine::new(&s).err().unwrap().to_string();
    assert!(
        e.contains("particle 0 starts with angular_velocity") && e.contains("do not rotate"),
        "{e}"
    );
}

#[test]
fn more_particles_than_memory_holds_are_refused_with_what_fits() {
    if powder::memory::available().is_none() {
        return;
    }
    let text = JKR_SCENE.replace(
        "kind = \"list\"\npositions = [[5e-5, 5e-5, 5e-5]]",
        "kind = \"random\"\ncount = 90000000\nmin = [0.0, 0.0, 0.0]\nmax = [1e-4, 1e-4, 1e-4]",
    );
    let err = Scene::from_toml_str(&text, "huge").unwrap_err().to_string();
    assert!(
        err.contains("at most") && err.contains("particles fit") && err.contains("line"),
        "{err}"
    );
}
