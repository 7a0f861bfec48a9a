//! What the GPU holds in f32, checked before a run starts: a mass, radius or moment of
//! inertia that rounds to 0 or ∞, or a pair parameter beyond f32's range, would turn the
//! first forces into NaN.

use super::*;

/// The energies the GPU's ledger sums in f32 per particle, J: a step's increments reach
/// some 10⁻⁸ of them and the sums grow with the run, so 10⁸ of room on either side.
const LEDGER_ENERGIES: (f64, f64) = (1e-30, 1e30);

/// Refuses a scene value the GPU's f32 cannot hold, naming the particle, pair or setting.
/// `rows`: the pair table of composition `kind` (`pair_table`), the pairs of materials
/// first and then each wall's with every material; `ledger`: the run keeps the energy
/// ledger, whose energies must fit too.
pub(super) fn check_f32_range(
    scene: &Scene,
    r: &Resolved,
    (rows, kind): (&[u8], &Composition),
    ledger: bool,
) -> Result<(), PowderError> {
    let row_bytes = kind.row_bytes();
    // (f32's normal numbers: a subnormal loses its digits, 0 divides)
    let normal = |x: f64| {
        let y = x as f32;
        y.is_finite() && y.abs() >= f32::MIN_POSITIVE
    };
    let finite = |v: &[f64; 3]| v.iter().all(|&x| (x as f32).is_finite());
    let refuse = |what: String| {
        Err(PowderError::Scene(format!(
            "{what}, which the GPU engine holds in f32 (magnitudes from 1.2e-38 to 3.4e38): run the scene on the CPU (--backend cpu) or choose other units"
        )))
    };
    if !normal(r.dt) {
        return refuse(format!("the time step is {:e} s", r.dt));
    }
    let d = &scene.domain;
    let extent = [0, 1, 2].map(|a| d.max[a] - d.min[a]);
    if !(finite(&d.min) && finite(&d.max) && finite(&extent)) {
        return refuse(format!("the [domain] spans {:?} to {:?} m", d.min, d.max));
    }
    // (points are held as cells and f32 offsets from the domain's corner)
    let from_corner = |x: &[f64; 3]| [0, 1, 2].map(|a| x[a] - d.min[a]);
    for (w, wall) in scene.walls.iter().enumerate() {
        let phases_fit = wall.motion.phases.iter().all(|(from, phase)| {
            (*from as f32).is_finite()
                && match *phase {
                    WallPhase::Rest => true,
                    WallPhase::Velocity(v) => finite(&v),
                    WallPhase::Servo {
                        force,
                        gain,
                        max_speed,
                    } => finite(&[force, gain, max_speed]),
                }
        });
        if !finite(&from_corner(&wall.point)) || !phases_fit {
            return refuse(format!(
                "wall {w}'s point {:?} m or motion {:?}",
                wall.point, wall.motion.phases
            ));
        }
    }
    if !finite(&scene.gravity) {
        return refuse(format!("gravity is {:?} m/s^2", scene.gravity));
    }
    for (i, (p, &m)) in scene.particles.iter().zip(&r.mass).enumerate() {
        if !normal(m) {
            return refuse(format!("particle {i}'s mass is {m:e} kg"));
        }
        if !normal(p.radius) {
            return refuse(format!("particle {i}'s radius is {:e} m", p.radius));
        }
        let inertia = crate::scene::sphere_inertia(m, p.radius);
        if r.rotation && !normal(inertia) {
            return refuse(format!(
                "particle {i}'s moment of inertia is {inertia:e} kg m^2"
            ));
        }
        if !finite(&from_corner(&p.position)) {
            return refuse(format!("particle {i}'s position is {:?} m", p.position));
        }
        if !finite(&p.velocity) || !finite(&p.angular_velocity) {
            return refuse(format!(
                "particle {i}'s velocity is {:?} m/s (angular {:?} rad/s)",
                p.velocity, p.angular_velocity
            ));
        }
    }
    if ledger {
        // a particle's energy scale: ½·m·v² at the larger of its speed and the expected
        // impact speed, or its weight over its radius where that is more
        let g = DVec3::from_array(scene.gravity).length();
        for (i, (p, &m)) in scene.particles.iter().zip(&r.mass).enumerate() {
            let v = DVec3::from_array(p.velocity)
                .length()
                .max(scene.impact_velocity);
            let (kinetic, weight) = (0.5 * m * v * v, m * g * p.radius);
            let e = kinetic.max(weight);
            if !(LEDGER_ENERGIES.0..=LEDGER_ENERGIES.1).contains(&e) {
                let term = if kinetic >= weight {
                    format!("½·m·v² at {v:e} m/s, the larger of its speed and simulation.impact_velocity")
                } else {
                    "m·g·r, its weight over its radius".into()
                };
                return Err(PowderError::Scene(format!(
                    "particle {i}'s energy scale is {e:.3e} J ({term}), which the GPU engine holds in f32 in its energy ledger: it takes {:e} to {:e} J a particle (f32's 1.2e-38 to 3.4e38 with room for a step's increments and a run's sums); run on the CPU (--backend cpu), without the ledger (--no-ledger), or in other units",
                    LEDGER_ENERGIES.0, LEDGER_ENERGIES.1
                )));
            }
        }
    }
    let n = scene.materials.len();
    let name = |m: usize| &scene.materials[m].name;
    for (k, row) in rows.chunks(row_bytes.max(1)).enumerate() {
        // (the rows hold no infinity by design: `kca` = ∞ is encoded as 0)
        let beyond = (row.chunks_exact(4))
            .map(|w| f32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .position(|x| !x.is_finite());
        if let Some(word) = beyond {
            let pair = if k < n * n {
                format!("materials `{}` and `{}`", name(k / n), name(k % n))
            } else {
                format!("wall {} and material `{}`", (k - n * n) / n, name(k % n))
            };
            let member = kind
                .row_member_at(4 * word)
                .unwrap_or_else(|| "a word".into());
            return refuse(format!(
                "the contact law of {pair} has a parameter (or one derived from them) beyond f32's range: `{member}` of its GPU pair row (`gpu::layout::pair_rows`)"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const LSD: &str = "density = 2000.0\nmodel = \"lsd\"\nk = 100.0";

    fn check(material: &str, gravity: &str, domain_max: &str) -> Result<(), String> {
        let text = format!(
            "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = {domain_max}\n[simulation]\nduration = 1e-20\ngravity = {gravity}\n[[material]]\nname = \"m\"\n{material}\n[[particles]]\nkind = \"list\"\npositions = [[0.005, 0.005, 0.005]]\nradius = 1e-3\n"
        );
        let scene = Scene::from_toml_str(&text, "t").unwrap();
        let r = Resolved::new(&scene).unwrap();
        let models: Vec<ContactModel> = r.models.iter().chain(&r.wall_models).copied().collect();
        let (kind, rows) = pair_table(&models);
        check_f32_range(&scene, &r, (&rows, &kind), true).map_err(|e| e.to_string())
    }

    fn refused(material: &str, gravity: &str, domain_max: &str, part: &str) {
        let e = check(material, gravity, domain_max).unwrap_err();
        assert!(e.contains(part), "{e}");
        assert!(e.contains("which the GPU engine holds in f32") && e.contains("--backend cpu"));
    }

    #[test]
    fn values_beyond_f32_are_refused_before_the_run() {
        let (g, max) = ("[0.0, 0.0, -9.81]", "[0.01, 0.01, 0.01]");
        check(LSD, g, max).unwrap();
        // the mass underflows f32
        refused(
            &LSD.replace("2000.0", "1e-40"),
            g,
            max,
            "particle 0's mass is",
        );
        refused(
            LSD,
            "[0.0, 0.0, -1e39]",
            max,
            "gravity is [0.0, 0.0, -1e39]",
        );
        // (a domain beyond f32 is beyond what f64 positions resolve for any particle that
        // f32 holds: the scene is refused before, `setup::Resolved`)
        let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 1e200]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\n[[particles]]\nkind = \"list\"\npositions = [[0.005, 0.005, 0.005]]\nradius = 1e-3\n";
        let e = Resolved::new(&Scene::from_toml_str(text, "t").unwrap()).unwrap_err();
        assert!(e.to_string().contains("the domain reaches 1e200 m"), "{e}");
        // (with friction the particles rotate: I = 2/5·m·r² underflows first)
        let rough = format!("{}\nfriction = 0.3", LSD.replace("2000.0", "1e-26"));
        refused(&rough, g, max, "particle 0's moment of inertia");
        let stiff = "density = 2000.0\nmodel = \"hysteretic\"\nk1 = 1e40\nkp = 5e40\nkc = 1e40\nphi_f = 0.05";
        refused(stiff, g, max, "the contact law of materials `m` and `m`");
        refused(stiff, g, max, "`hysteretic.k1` of its GPU pair row");
        let soft =
            "density = 2000.0\nmodel = \"jkr\"\nyoungs = 1e8\npoisson = 0.3\nsurface_energy = 1e40";
        refused(soft, g, max, "`jkr.gamma` of its GPU pair row");
        // a parameter below f32's normal numbers (it flushed to 0: particles passed through)
        let limp = "density = 2000.0\nmodel = \"lsd\"\nk = 1e-46";
        refused(limp, g, max, "`hysteretic.k1` of its GPU pair row");
        // energies the ledger cannot sum in f32, though the mass fits
        for (density, scale) in [("1e-22", "2.094e-31 J"), ("1e40", "2.094e31 J")] {
            refused(&LSD.replace("2000.0", density), g, max, scale);
        }
    }
}
