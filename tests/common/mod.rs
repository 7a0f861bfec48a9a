//! Helpers shared by the integration tests.

pub mod backends;
pub mod builder;
pub mod model_scene;
pub use builder::SceneBuilder;

use powder::gpu::{GpuContext, GpuState};
use powder::scene::Scene;
use std::path::Path;

/// The GPU context, or `None` (with a notice) when no adapter exists outside CI; in CI
/// (where lavapipe is installed) a missing adapter fails the test.
#[allow(dead_code)]
pub fn gpu() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("CI").is_none() => {
            eprintln!("skipping GPU test: {e}");
            None
        }
        Err(e) => panic!("CI needs a GPU adapter (lavapipe): {e}"),
    }
}

/// A context on the OpenGL backend (llvmpipe in CI), or `None` (with a notice) when there
/// is none outside CI; in CI a missing GL adapter fails the test.
#[allow(dead_code)]
pub fn gl() -> Option<GpuContext> {
    let gl = powder::gpu::AdapterPreference::Name("gl".into());
    match GpuContext::with_preference(&gl) {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("CI").is_none() => {
            eprintln!("skipping GL test: {e}");
            None
        }
        Err(e) => panic!("CI needs the GL adapter (llvmpipe): {e}"),
    }
}

/// An example scene from `examples/`, loaded.
#[allow(dead_code)]
pub fn example(name: &str) -> Scene {
    Scene::load(&example_path(name)).unwrap()
}

/// The path of a file in `examples/`.
#[allow(dead_code)]
pub fn example_path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

/// The cohesive cluster example writing outputs every 500 steps and checkpoints every 1000
/// (the run-output tests' scene).
#[allow(dead_code)] // each test binary compiles this module; not all use every helper
pub fn cluster_with_outputs() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/cohesive_cluster.toml"
    );
    let mut s = Scene::load(Path::new(path)).unwrap();
    s.output_every = 500;
    s.checkpoint_every = 1000;
    s
}

/// The largest distance between corresponding points of `a` and `b` (0 when empty).
#[allow(dead_code)]
pub fn max_distance(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.distance(*y))
        .fold(0.0, f64::max)
}

/// Asserts that two GPU states hold bitwise the same positions and velocities.
#[allow(dead_code)]
pub fn assert_same_bits(a: &GpuState, b: &GpuState) {
    let bits = |v: &[glam::DVec3]| {
        v.iter()
            .flat_map(|p| p.to_array().map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a.positions), bits(&b.positions));
    assert_eq!(bits(&a.velocities), bits(&b.velocities));
}

/// Asserts that two GPU runs of one scene are bitwise the same run: positions, velocities,
/// spins, the ledger's dissipation and wall work, rebuilds, every contact's history, the
/// wall forces and sampled wall contacts' histories (`what` names the case).
#[allow(dead_code)]
pub fn assert_same_run(a: &powder::gpu::GpuEngine, b: &powder::gpu::GpuEngine, what: &str) {
    let bits = |v: &[glam::DVec3]| {
        v.iter()
            .map(|p| p.to_array().map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    let (sa, sb) = (a.state().unwrap(), b.state().unwrap());
    assert_same_bits(&sa, &sb);
    let spins = (bits(&sa.angular_velocities), bits(&sb.angular_velocities));
    assert_eq!(spins.0, spins.1, "{what}");
    let (ea, eb) = (a.energies(&sa).unwrap(), b.energies(&sb).unwrap());
    assert_eq!(ea.dissipated.to_bits(), eb.dissipated.to_bits(), "{what}");
    assert_eq!(ea.wall_work.to_bits(), eb.wall_work.to_bits(), "{what}");
    assert_eq!(a.rebuilds().unwrap(), b.rebuilds().unwrap(), "{what}");
    let histories = (
        a.contact_histories().unwrap(),
        b.contact_histories().unwrap(),
    );
    assert_eq!(histories.0, histories.1, "{what}");
    let walls = (a.wall_forces().unwrap(), b.wall_forces().unwrap());
    assert_eq!(bits(&walls.0), bits(&walls.1), "{what}");
    let n = sa.positions.len();
    for w in 0..walls.0.len() {
        for i in [0, n / 2, n - 1] {
            assert_eq!(
                a.wall_contact_history(w, i).unwrap(),
                b.wall_contact_history(w, i).unwrap(),
                "{what}: wall {w}, particle {i}"
            );
        }
    }
}

/// A contact model from its parameters as the command line gives them (the declared
/// defaults apply).
#[allow(dead_code)]
pub fn law(name: &str, params: &[(&'static str, f64)]) -> powder::model::ContactModel {
    powder::model::flags::LawArgs {
        model: name.into(),
        given: params.iter().map(|(k, v)| (*k, v.to_string())).collect(),
    }
    .contact_model()
    .unwrap()
}

/// One sphere of `radius` and `density` over a floor z = 0 in a 1 m × 10 cm box: `keys`
/// are the material's model lines; it starts at height `z` with velocity `v` and spin `w`.
#[allow(dead_code)]
pub fn floor_scene(
    keys: &str,
    [radius, density]: [f64; 2],
    gravity: [f64; 3],
    z: f64,
    v: [f64; 3],
    w: [f64; 3],
) -> Scene {
    use builder::vec3;
    SceneBuilder::new("floor", [-0.5, -0.05, -0.01], [0.5, 0.05, 0.05], 1.0)
        .simulation("gravity", &vec3(gravity))
        .simulation("impact_velocity", "0.1")
        .material("m", density, keys)
        .floor()
        .particles(
            "list",
            &format!(
                "radius = {radius:e}\npositions = [{}]\nvelocity = {}\nangular_velocity = {}",
                vec3([0.0, 0.0, z]),
                vec3(v),
                vec3(w)
            ),
        )
        .build()
}

/// Head-on collisions of 1 µm spheres of 2000 kg/m³ with JKR law `p`, one per (partner
/// radius, wall) of `pairs`, at 1.05, 1.3, 2 and 5 times the sticking speed: each spec with
/// the closed-form e (paper 002's loss W of `p`'s pull-off rule).
#[allow(dead_code)]
pub fn jkr_collisions(
    p: powder::model::JkrParams,
    pairs: &[(f64, bool)],
    jump_impulses: Option<bool>,
) -> Vec<(powder::measure::collide::CollideSpec, f64)> {
    use powder::measure::collide::CollideSpec;
    use powder::model::{analytic, ContactModel};
    let mut out = Vec::new();
    for &(radius2, wall) in pairs {
        let base = CollideSpec {
            radius2,
            wall,
            jump_impulses,
            ..CollideSpec::head_on(ContactModel::Jkr(p), 1e-6, 2000.0, 1.0)
        };
        let g = base.geometry();
        let r = g.r_eff();
        let w = analytic::jkr_loss(p.pulloff) * p.fc(r) * p.delta0(r);
        let v_stick = analytic::jkr_sticking_velocity(w, g.reduced_mass);
        for f in [1.05, 1.3, 2.0, 5.0] {
            let v = f * v_stick;
            let e = analytic::jkr_restitution(w, g.reduced_mass, v).unwrap();
            let spec = CollideSpec {
                velocity: v,
                ..base.clone()
            };
            out.push((spec, e));
        }
    }
    out
}

/// Two jittered lattices of 1 mm spheres in a box over a floor: `lower` below, `upper`
/// above thrown at `velocity`, with the materials (and interactions) `materials` adds and
/// the floor of material `wall`; `spacing` sets the gaps between lattice neighbours.
#[allow(dead_code)]
pub fn two_lattices(
    materials: impl FnOnce(SceneBuilder) -> SceneBuilder,
    [lower, upper, wall]: [&str; 3],
    spacing: f64,
    velocity: [f64; 3],
) -> Scene {
    let lattice = |material: &str, z: [f64; 2], seed: u32, velocity: String| {
        format!(
            "material = \"{material}\"\nmin = [0.0011, 0.0011, {:?}]\nmax = [0.0109, 0.0109, {:?}]\n\
             radius = 1.0e-3\nspacing = {spacing:e}\njitter = 0.5\n{velocity}seed = {seed}",
            z[0], z[1]
        )
    };
    let thrown = format!("velocity = {}\n", builder::vec3(velocity));
    let box_ = SceneBuilder::new("packing", [0.0; 3], [0.012, 0.012, 0.02], 0.05)
        .gravity()
        .simulation("impact_velocity", "0.5");
    materials(box_)
        .floor_of(wall)
        .particles(
            "lattice",
            &lattice(lower, [0.0011, 0.0062], 7, String::new()),
        )
        .particles("lattice", &lattice(upper, [0.0066, 0.0118], 8, thrown))
        .build()
}

/// A box of jittered 1 mm spheres thrown onto a floor: the materials `materials` adds,
/// every sphere of `rough` ([`rough`]), the upper half of `upper`.
#[allow(dead_code)]
pub fn packing(materials: impl FnOnce(SceneBuilder) -> SceneBuilder, upper: &str) -> Scene {
    two_lattices(
        materials,
        ["rough", upper, "rough"],
        2.1e-3,
        [0.1, 0.05, -0.3],
    )
}

/// The material `rough`: [`builder::ROUGH`] at 2000 kg/m³.
#[allow(dead_code)]
pub fn rough(b: SceneBuilder) -> SceneBuilder {
    b.material("rough", 2000.0, builder::ROUGH)
}

/// Prints a GPU-against-CPU comparison's samples (to read a failure's trace).
#[allow(dead_code)]
pub fn report(c: &powder::measure::compare::Comparison) {
    for s in &c.samples {
        eprintln!(
            "step {}: pos {:.2e} vel {:.2e} energy {:.2e} contacts {}/{} history {:.2e} over {}",
            s.step,
            s.position,
            s.velocity,
            s.energy,
            s.contacts_cpu,
            s.contacts_gpu,
            s.history,
            s.history_pairs
        );
    }
}

/// The number that follows `phrase` in a message (up to the next space), or a panic that
/// shows the message.
#[allow(dead_code)]
pub fn number_after<T: std::str::FromStr>(text: &str, phrase: &str) -> T {
    text.split(phrase)
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number after {phrase:?} in {text}"))
}
