//! The scenes of `examples/compare/`, written to reach combinations the feature tests do
//! not (laws, sub-models, interactions, tilted and moving walls, periodic axes together),
//! run on both engines as `powder compare` runs them.

mod common;

use common::{gpu, report};
use powder::measure::compare::{compare_perturbed, Tolerances};
use powder::scene::Scene;

/// `examples/compare/<name>` on both engines for `steps` steps, sampled every `every`,
/// judged up to its chaos horizon where `perturbation` is given: it passes, with at least
/// `contacts` pair contacts at the end, and every measure is judged at a sample with
/// contacts before its horizon (a comparison whose contacts all come after it would pass
/// on the free flight alone).
fn passes(name: &str, steps: u64, every: u64, perturbation: Option<f64>, contacts: usize) {
    let path = format!("{}/examples/compare/{name}", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(std::path::Path::new(&path)).unwrap();
    let Some(ctx) = gpu() else { return };
    let c = compare_perturbed(
        &scene,
        ctx,
        steps,
        every,
        Tolerances::default(),
        perturbation,
    )
    .unwrap();
    report(&c);
    let last = c.samples.last().unwrap();
    assert!(c.passed, "{name}: {last:?}");
    assert!(last.contacts_cpu >= contacts, "{name}: {last:?}");
    let touched = c.samples.iter().find(|s| s.contacts_cpu > 0).unwrap().step;
    for (measure, horizon) in &c.horizon {
        assert!(
            *horizon > touched,
            "{name}: {measure} past its horizon at step {horizon}, before the first contacts at {touched}"
        );
    }
}

/// Polydisperse LSD grains with Luding's friction (μs > μd), rolling and twisting in a
/// hopper of tilted steel walls, with an interaction of their own (measured: passes, the
/// position horizon at step 10 500, contacts from 7 500).
#[test]
fn the_hopper_of_two_materials_follows_the_cpu() {
    passes("hopper.toml", 12_000, 1_500, Some(1e-6), 4);
}

/// A cohesive bed with non-contact adhesion and Luding's friction sheared between a moving
/// floor and a pressing lid, periodic in x and y (measured: passes, 50 contacts at the end,
/// horizons at steps 6000–7000).
#[test]
fn the_sheared_cohesive_bed_follows_the_cpu() {
    passes("sheared_bed.toml", 8_000, 1_000, Some(1e-6), 40);
}

/// JKR micro-spheres with the Krijt radius, the crack pull-off, friction, rolling and
/// twisting, thrown together onto a plate, every measure judged at every sample
/// (measured: 28 contacts at the end, positions within 1.4e-7 of the radius).
#[test]
fn the_jkr_cloud_with_the_crack_pulloff_follows_the_cpu() {
    passes("jkr_cloud.toml", 10_000, 1_000, None, 20);
}

/// A cohesive cluster pulled onto a floor in a domain 600 km wide, where the GPU's cells
/// are 1.1e5 m wide and an f32 offset resolves 8 mm of a 1.1 mm radius: the compensated
/// separations and the neighbour search's slack keep it on the CPU's track (measured:
/// positions within 1e-4 of the radius at step 2500; before, invented overlaps stopped it
/// at step 1 and missed pairs threw it off by a radius at step 1900).
#[test]
fn a_cluster_in_a_sparse_domain_follows_the_cpu() {
    passes("sparse_cluster.toml", 2_500, 250, None, 2);
}

/// Two micro-spheres meeting obliquely in a 1 m box (0.25 m cells, an f32 offset 30 times
/// the collision's overlap): the contact normal from the compensated separation (measured:
/// velocities within 5e-6 of the largest; 1.2e-2 from the uncompensated one).
#[test]
fn an_oblique_pair_in_a_sparse_box_follows_the_cpu() {
    let path = format!(
        "{}/examples/compare/sparse_pair.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = Scene::load(std::path::Path::new(&path)).unwrap();
    let Some(ctx) = gpu() else { return };
    let c = compare_perturbed(&scene, ctx, 5_000, 250, Tolerances::default(), None).unwrap();
    report(&c);
    assert!(c.samples.iter().any(|s| s.contacts_cpu > 0));
    for s in &c.samples {
        assert!(s.velocity < 1e-4, "{s:?}");
    }
}
