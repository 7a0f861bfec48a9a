//! The warning a run gives where a friction dashpot overdamps its spring: Luding's slip
//! reset stores the dashpot's force in the spring, and the friction fades
//! (`docs/models.md`, *An overdamped tangential dashpot*).

use crate::model::{ContactModel, PairGeometry};
use crate::scene::{sphere_mass, Scene};

/// How many times the critical damping 2√(k·m) a friction dashpot may reach unwarned.
pub(super) const OVERDAMPED: f64 = 3.0;

/// One warning per friction law whose dashpot exceeds [`OVERDAMPED`] times the critical
/// damping of its lightest pair (two of a material's lightest spheres; the lightest of
/// each for an interaction), naming the law and the key.
pub(super) fn overdamped_friction(scene: &Scene) -> Vec<String> {
    let mut lightest: Vec<Option<(f64, f64)>> = vec![None; scene.materials.len()];
    for p in &scene.particles {
        let m = sphere_mass(scene.materials[p.material].density, p.radius);
        let slot = &mut lightest[p.material];
        if slot.is_none_or(|(lm, _)| m < lm) {
            *slot = Some((m, p.radius));
        }
    }
    let own = (scene.materials.iter().enumerate())
        .map(|(a, m)| ([a, a], &m.model, format!("material `{}`", m.name)));
    let between = scene.interactions.iter().map(|it| {
        let [a, b] = it.materials;
        let names = [a, b].map(|k| scene.materials[k].name.as_str());
        (
            it.materials,
            &it.model,
            format!("interaction `{}`-`{}`", names[0], names[1]),
        )
    });
    own.chain(between)
        .filter_map(|([a, b], model, who)| {
            let who = format!("{who} (its lightest pair)");
            let ((ma, ra), (mb, rb)) = (lightest[a]?, lightest[b]?);
            let geom = PairGeometry::spheres(ra, rb, ma, mb);
            Some(law_warnings(model, &geom, scene.impact_velocity, &who))
        })
        .flatten()
        .collect()
}

/// The warnings of one law on one pair (`who`: how the warning names it), at impact speed
/// `v` (the JKR twisting stiffness follows it).
pub(crate) fn law_warnings(
    model: &ContactModel,
    geom: &PairGeometry,
    v: f64,
    who: &str,
) -> Vec<String> {
    (model.friction_oscillators(geom, v).into_iter())
        .filter_map(|o| {
            let critical = 2.0 * (o.k * o.mass).sqrt();
            let key = match o.what {
                "tangential" => "gamma_t",
                "rolling" => "gamma_r",
                _ => "gamma_o",
            };
            (o.gamma > OVERDAMPED * critical).then(|| {
                format!(
                    "{who}: {key} = {:e} kg/s is {:.0} times the critical damping 2*sqrt(k*m) = {critical:.3e} kg/s of its {} spring: Luding's slip reset (eq. 20) stores the dashpot's force in the spring, and the friction the contact transmits fades (docs/models.md, *An overdamped tangential dashpot*); lower {key}",
                    o.gamma,
                    o.gamma / critical,
                    o.what
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(gamma_t: f64) -> Scene {
        let text = format!(
            "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 0.01]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\nfriction = 0.5\ngamma_t = {gamma_t:?}\n[[particles]]\nkind = \"list\"\npositions = [[0.002, 0.005, 0.005], [0.006, 0.005, 0.005]]\nradius = 1e-3\n"
        );
        Scene::from_toml_str(&text, "t").unwrap()
    }

    /// k_t = 2/7·100 N/m, m_t = 2/7·m/2 with m = 8.38e-6 kg: critical 2√(k_t·m_t) =
    /// 0.0117 kg/s; the warning names the material and the key above three times that.
    #[test]
    fn an_overdamped_friction_dashpot_is_named() {
        assert!(overdamped_friction(&scene(0.03)).is_empty());
        let w = overdamped_friction(&scene(0.1)).concat();
        assert!(
            w.contains("material `m` (its lightest pair): gamma_t = 1e-1 kg/s is 9 times")
                && w.contains("1.17"),
            "{w}"
        );
    }
}
