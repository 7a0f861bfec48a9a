//! What every backend derives from a scene before stepping: the pair-model tables, the
//! particle masses, the time step and the largest interaction reach. One place, so the
//! CPU and GPU engines run exactly the same physics set-up.

use crate::error::{num, PowderError};
use crate::model::{ContactModel, PairGeometry, TimeStep};
use crate::scene::{DtSetting, MaterialUse, Scene};

/// The most steps a run counts: steps and times (step·dt) are exact to here.
pub const MAX_STEPS: u64 = 1 << 53;

/// The coarsest f64 position spacing in the domain accepted, over the smallest radius.
pub const POSITION_RESOLUTION: f64 = 1e-6;

/// A scene resolved for stepping.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// Number of materials.
    pub n_materials: usize,
    /// Pair models, n_materials × n_materials (row = first particle's material).
    pub models: Vec<ContactModel>,
    /// Wall models, walls × n_materials.
    pub wall_models: Vec<ContactModel>,
    /// Particle masses, kg, in scene order.
    pub mass: Vec<f64>,
    /// The time step used and the rule it was checked against.
    pub dt: f64,
    /// The most restrictive time-step rule over all material pairs, walls and the Rayleigh
    /// guard (default, largest accepted dt, reason).
    pub time_step: TimeStep,
    /// Largest radius, m.
    pub r_max: f64,
    /// Largest distance beyond touching at which any pair interacts (the non-contact
    /// range, or how far a JKR neck stretches), at the largest radius, m.
    pub max_reach: f64,
    /// Whether some contact model needs angular velocities.
    pub rotation: bool,
}

impl Resolved {
    /// Resolves `scene`: pair and wall models, masses, the time step (checked against its
    /// rule unless `force_dt`), the largest radius and reach.
    pub fn new(scene: &Scene) -> Result<Self, PowderError> {
        // (a scene built in code has not met the reader's checks)
        scene.validate()?;
        let n_materials = scene.materials.len();
        // a pair of materials that never meets (no particle of one of them) needs no model:
        // the first material's own stands in, never evaluated
        let uses = MaterialUse::of(scene);
        let model = |a: usize, b: usize| match scene.pair_model(a, b) {
            Err(_) if !uses.meet(a, b) => Ok(scene.materials[a].model),
            found => found,
        };
        let mut models = Vec::with_capacity(n_materials * n_materials);
        for a in 0..n_materials {
            for b in 0..n_materials {
                models.push(model(a, b)?);
            }
        }
        let mut wall_models = Vec::with_capacity(scene.walls.len() * n_materials);
        for w in &scene.walls {
            for b in 0..n_materials {
                wall_models.push(model(w.material, b)?);
            }
        }
        let mass: Vec<f64> = scene
            .particles
            .iter()
            .map(|p| crate::scene::sphere_mass(scene.materials[p.material].density, p.radius))
            .collect();
        // (a radius and density each in range can still give a mass of 0 or ∞ in f64)
        if let Some((i, m)) = mass
            .iter()
            .enumerate()
            .find(|(_, m)| !(m.is_finite() && **m > 0.0))
        {
            let p = &scene.particles[i];
            let material = &scene.materials[p.material];
            return Err(PowderError::Scene(format!(
                "particle {i}: its mass comes out as {m:e} kg (radius {:e} m, density {:e} kg/m^3 of material `{}`): choose a radius and density whose mass 4/3·π·r³·ρ is a finite number above 0",
                p.radius, material.density, material.name
            )));
        }
        // Time step: the most demanding pair of materials, with the lightest particles of
        // each, and each against the other's heaviest (a rolling or twisting oscillator is
        // stiffest for a small sphere on a large one); walls count as infinite mass.
        let mut lightest: Vec<Option<(f64, f64)>> = vec![None; n_materials];
        let mut heaviest: Vec<Option<(f64, f64)>> = vec![None; n_materials];
        for (p, &m) in scene.particles.iter().zip(&mass) {
            let slot = &mut lightest[p.material];
            if slot.is_none_or(|(lm, _)| m < lm) {
                *slot = Some((m, p.radius));
            }
            let slot = &mut heaviest[p.material];
            if slot.is_none_or(|(hm, _)| m > hm) {
                *slot = Some((m, p.radius));
            }
        }
        // the rule with the smallest limit, and the one with the smallest default step: a
        // contact's default (a fraction of its contact time) may be shorter than that of the
        // contact whose viscous limit binds
        let mut time_step: Option<TimeStep> = None;
        let mut shortest: Option<TimeStep> = None;
        // (the first rule whose step is not a finite number above 0: it would stop time)
        let mut unusable: Option<TimeStep> = None;
        // (each rule names its contact: in a scene of several materials, which to change)
        let mut consider = |mut ts: TimeStep, contact: String| {
            ts.reason = format!("{} [{contact}]", ts.reason);
            let usable = |t: f64| t.is_finite() && t > 0.0;
            if !(usable(ts.max) && usable(ts.default)) {
                unusable.get_or_insert(ts);
                return;
            }
            if shortest.as_ref().is_none_or(|t| ts.default < t.default) {
                shortest = Some(ts.clone());
            }
            if time_step.as_ref().is_none_or(|t| ts.max < t.max) {
                time_step = Some(ts);
            }
        };
        // the Hertz/JKR contact time follows the impact speed: the larger of the expected
        // one and the fastest closing the starting velocities allow
        let starting = starting_closing_speed(scene);
        let v_imp = if starting > scene.impact_velocity * (1.0 + 1e-9) {
            starting
        } else {
            scene.impact_velocity
        };
        for a in 0..n_materials {
            let Some((ma, ra)) = lightest[a] else {
                continue;
            };
            for b in 0..n_materials {
                let (Some(light), Some(heavy)) = (lightest[b], heaviest[b]) else {
                    continue;
                };
                let contact = match a == b {
                    true => format!("material `{}`", scene.materials[a].name),
                    false => format!(
                        "materials `{}` and `{}`",
                        scene.materials[a].name, scene.materials[b].name
                    ),
                };
                for (mb, rb) in [light, heavy] {
                    let geom = PairGeometry::spheres(ra, rb, ma, mb);
                    consider(
                        models[a * n_materials + b].time_step(&geom, v_imp),
                        contact.clone(),
                    );
                }
            }
            for w in 0..scene.walls.len() {
                let geom = PairGeometry::wall(ra, ma);
                consider(
                    wall_models[w * n_materials + a].time_step(&geom, v_imp),
                    format!("wall {w} and material `{}`", scene.materials[a].name),
                );
            }
        }
        // the Rayleigh time of each JKR/Hertz material's smallest sphere
        for (a, material) in scene.materials.iter().enumerate() {
            if let (ContactModel::Jkr(p), Some((_, r))) = (&material.model, lightest[a]) {
                let t_r = p.rayleigh_time(r, material.density);
                consider(
                    TimeStep::rayleigh(t_r, &material.name, r),
                    format!("material `{}`", material.name),
                );
            }
        }
        if let Some(ts) = unusable {
            return Err(PowderError::Scene(format!(
                "the time step comes out as {:e} s (largest stable {:e} s; {}): the parameters of that contact are beyond what a time step can resolve (a stiffness, damping or velocity, or a density or radius that sets the mass, out of range)",
                ts.default, ts.max, ts.reason
            )));
        }
        let mut time_step =
            time_step.ok_or_else(|| PowderError::Scene("the scene has no particles".into()))?;
        if let Some(other) = shortest.filter(|o| o.default < time_step.default) {
            time_step.default = other.default;
            time_step.contact_time = time_step.contact_time.min(other.contact_time);
            time_step.reason += &format!(
                "; the default step {:.4e} s is another contact's ({})",
                other.default, other.reason
            );
        }
        if v_imp > scene.impact_velocity && time_step.reason.contains("impact velocity") {
            time_step.reason += &format!(
                " (the starting velocities close a pair at up to {v_imp:e} m/s, above simulation.impact_velocity = {:e} m/s)",
                scene.impact_velocity
            );
        }
        // a JKR adhesion too weak for f64 at the largest radius of the pair (the weakest)
        let mut largest = vec![0f64; n_materials];
        for p in &scene.particles {
            largest[p.material] = largest[p.material].max(p.radius);
        }
        let pairs = (0..n_materials).flat_map(|a| (0..n_materials).map(move |b| (a, b)));
        for (a, b) in pairs.filter(|&(a, b)| uses.particles[a] && uses.particles[b]) {
            if let ContactModel::Jkr(p) = &models[a * n_materials + b] {
                let r_eff = largest[a] * largest[b] / (largest[a] + largest[b]);
                p.check_adhesion_scale(r_eff).map_err(|e| {
                    let names = [a, b].map(|m| scene.materials[m].name.as_str());
                    PowderError::Scene(format!("materials `{}` and `{}`: {e}", names[0], names[1]))
                })?;
            }
        }
        for (w, wall) in scene.walls.iter().enumerate() {
            for b in (0..n_materials).filter(|&b| uses.particles[b]) {
                if let ContactModel::Jkr(p) = &wall_models[w * n_materials + b] {
                    p.check_adhesion_scale(largest[b]).map_err(|e| {
                        let m = &scene.materials[b].name;
                        PowderError::Scene(format!(
                            "wall {w} (material `{}`) and material `{m}`: {e}",
                            scene.materials[wall.material].name
                        ))
                    })?;
                }
            }
        }
        let dt = match scene.dt {
            DtSetting::Auto => time_step.default,
            DtSetting::Fixed(dt) => {
                if dt > time_step.max && !scene.force_dt {
                    return Err(PowderError::Scene(format!(
                        "dt = {dt:e} s is above the stable limit {:.4e} s ({}); use dt <= {:.4e} s or set force_dt = true",
                        time_step.max, time_step.reason, time_step.max
                    )));
                }
                dt
            }
        };
        // positions are f64 coordinates: they must resolve far below a radius anywhere in
        // the domain (a domain of ±1e20 m rounded every position to 0)
        let r_min = (scene.particles.iter())
            .map(|p| p.radius)
            .fold(f64::INFINITY, f64::min);
        for a in 0..3 {
            let far = scene.domain.min[a].abs().max(scene.domain.max[a].abs());
            let ulp = f64::from_bits(far.to_bits() + 1) - far;
            if ulp > POSITION_RESOLUTION * r_min {
                return Err(PowderError::Scene(format!(
                    "the domain reaches {far:e} m on axis {}, where f64 positions resolve only {ulp:e} m, more than {POSITION_RESOLUTION:e} of the smallest radius {r_min:e} m: shrink the domain or move it nearer the origin",
                    ["x", "y", "z"][a]
                )));
            }
        }
        // steps are counted in u64 and times are step·dt in f64: both exact up to 2^53
        // steps; a run or an event beyond that would never end or never come
        let rule = match scene.dt {
            DtSetting::Auto => format!("the automatic dt, {}", time_step.reason),
            DtSetting::Fixed(_) => "simulation.dt".to_string(),
        };
        let beyond = |t: f64| t.is_nan() || t / dt > MAX_STEPS as f64;
        // (an infinite duration runs until its caller stops it: `collide`)
        if scene.duration.is_finite() && beyond(scene.duration) {
            return Err(PowderError::Scene(format!(
                "simulation.duration = {:e} s is {:.3e} steps of dt = {dt:e} s ({rule}), beyond the {MAX_STEPS} steps a run can count: shorten the run or check the parameter that sets dt",
                scene.duration,
                scene.duration / dt
            )));
        }
        let events = (scene.particles.iter().enumerate())
            .map(|(i, p)| (format!("particle {i}'s insert_at"), p.insert_at))
            .chain(scene.walls.iter().enumerate().flat_map(|(w, wall)| {
                (wall.motion.phases.iter())
                    .map(move |(t, _)| (format!("wall {w}'s phase time"), *t))
            }));
        for (what, t) in events {
            if beyond(t) {
                return Err(PowderError::Scene(format!(
                    "{what} {t:e} s is {:.3e} steps of dt = {dt:e} s ({rule}), beyond the {MAX_STEPS} steps a run can count: an event that late never comes; remove it or bring it within the run",
                    t / dt
                )));
            }
        }
        // (a pair closing more than a radius in one step can pass through each other
        // unseen: the monitor only sees overlaps at the ends of steps; a forced dt accepts it)
        let closing = velocity_spread(scene);
        if let Some((i, p)) = scene
            .particles
            .iter()
            .enumerate()
            .find(|(_, p)| !scene.force_dt && closing * dt > p.radius)
        {
            // (velocities of opposite signs near f64's limit differ by more than it holds)
            let spread = if (closing * dt).is_finite() {
                format!("by up to {closing:e} m/s: a pair (or a particle and a wall) closes {:e} m in a step of {dt:e} s", closing * dt)
            } else {
                format!("by more than f64 holds: a pair (or a particle and a wall) closes more than {:e} m in a step of {dt:e} s", f64::MAX)
            };
            return Err(PowderError::Scene(format!(
                "the starting velocities differ {spread}, more than the radius {:e} m of particle {i}, and can pass through each other between two steps; lower the velocities or set a smaller simulation.dt (the automatic one follows simulation.impact_velocity for Hertz and JKR contacts), or force_dt = true to run it anyway",
                p.radius
            )));
        }
        // a wall's later phases, which the starting spread does not see
        let r_min = (scene.particles.iter().map(|p| p.radius)).fold(f64::INFINITY, f64::min);
        for (w, wall) in scene.walls.iter().enumerate() {
            for (k, (from, phase)) in wall.motion.phases.iter().enumerate() {
                let speed = wall_normal_velocity(wall, phase).length();
                let during = *from > 0.0 && *from < scene.duration;
                if !scene.force_dt && during && speed * dt > r_min {
                    return Err(PowderError::Scene(format!(
                        "wall {w}'s motion from t = {} s (its phase or schedule entry {k}) moves it at up to {speed:.4e} m/s along its normal: it closes {:.4e} m in a step of {dt:.4e} s, more than the smallest particle radius {} m, and particles can pass through it between two steps; slow that motion or set a smaller simulation.dt, or force_dt = true to run it anyway",
                        num(*from),
                        speed * dt,
                        num(r_min)
                    )));
                }
            }
        }
        let r_max = scene.particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        let max_reach = models
            .iter()
            .map(|m| m.reach(0.5 * r_max))
            .chain(wall_models.iter().map(|m| m.reach(r_max)))
            .fold(0.0, f64::max);
        let rotation = models
            .iter()
            .chain(&wall_models)
            .any(ContactModel::needs_rotation);
        if !rotation {
            if let Some((i, p)) = scene
                .particles
                .iter()
                .enumerate()
                .find(|(_, p)| p.angular_velocity != [0.0; 3])
            {
                return Err(PowderError::Scene(format!(
                    "particle {i} starts with angular_velocity = {:?} rad/s, but no contact model of the scene has friction, rolling or twisting resistance, so particles do not rotate: remove angular_velocity or give the model friction",
                    p.angular_velocity
                )));
            }
        }
        Ok(Self {
            n_materials,
            models,
            wall_models,
            mass,
            dt,
            time_step,
            r_max,
            max_reach,
            rotation,
        })
    }
}

/// The fastest a pair (or a particle and a wall) can close at the start, m/s: with two
/// particles moving on straight lines (no walls, periodic axes or pours) their approach
/// along the line of centres (0 when they part), otherwise [`velocity_spread`].
fn starting_closing_speed(scene: &Scene) -> f64 {
    use glam::DVec3;
    let v = |i: usize| DVec3::from_array(scene.particles[i].velocity);
    let alone = scene.walls.is_empty() && !scene.domain.any_periodic() && !scene.pours();
    if scene.particles.len() == 2 && alone {
        let x = |i: usize| DVec3::from_array(scene.particles[i].position);
        let n = (x(1) - x(0)).normalize_or_zero();
        return (v(0) - v(1)).dot(n).max(0.0);
    }
    velocity_spread(scene)
}

/// The velocity along its normal a wall moves with in `phase` (under servo control the
/// largest it starts with), m/s.
fn wall_normal_velocity(w: &crate::scene::Wall, phase: &crate::scene::WallPhase) -> glam::DVec3 {
    use crate::scene::WallPhase;
    use glam::DVec3;
    let n = DVec3::from_array(w.normal).normalize_or_zero();
    match *phase {
        WallPhase::Rest => DVec3::ZERO,
        WallPhase::Velocity(v) => n * DVec3::from_array(v).dot(n),
        WallPhase::Servo {
            force,
            gain,
            max_speed,
        } => n * (gain * force).min(max_speed),
    }
}

/// A bound on every relative speed at the start: the diagonal of the bounding box of the
/// particles' starting velocities and the walls' along their normals (a prescribed one, or
/// a servo's first step, min(gain·force, max_speed)); particles moving together close
/// nothing.
fn velocity_spread(scene: &Scene) -> f64 {
    use glam::DVec3;
    let velocities = (scene.particles.iter())
        .map(|p| DVec3::from_array(p.velocity))
        .chain((scene.walls.iter()).map(|w| wall_normal_velocity(w, &w.motion.at(0.0))));
    let (lo, hi) = velocities.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    (hi - lo).max(DVec3::ZERO).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(material: &str, radius: &str) -> Scene {
        let text = format!(
            "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 0.01]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\n{material}\n[[particles]]\nkind = \"list\"\npositions = [[0.005, 0.005, 0.005]]\nradius = {radius}\n"
        );
        Scene::from_toml_str(&text, "t").unwrap()
    }

    fn refused(s: &Scene) -> String {
        match Resolved::new(s) {
            Ok(r) => panic!("accepted with dt = {:e} s", r.dt),
            Err(e) => e.to_string(),
        }
    }

    /// Two spheres at 1000 m/s head-on close 0.13 m a step of the LSD dt (6.4e-5 s): they
    /// would pass through each other unseen, so the scene is refused, naming the particle;
    /// at 1 m/s, or both at 1000 m/s the same way (closing nothing), it runs.
    #[test]
    fn a_pair_that_can_pass_through_in_one_step_is_refused() {
        let scene = |v: [f64; 2]| {
            let text = format!(
                "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.01, 0.01]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\n[[particles]]\nkind = \"list\"\npositions = [[0.45, 0.005, 0.005], [0.55, 0.005, 0.005]]\nradius = 1e-3\nvelocities = [[{:?}, 0.0, 0.0], [{:?}, 0.0, 0.0]]\n",
                v[0], v[1]
            );
            Scene::from_toml_str(&text, "t").unwrap()
        };
        let e = refused(&scene([1000.0, -1000.0]));
        assert!(
            e.contains("differ by up to 2e3 m/s") && e.contains("pass through each other"),
            "{e}"
        );
        assert!(Resolved::new(&scene([1.0, -1.0])).is_ok());
        assert!(Resolved::new(&scene([1000.0, 1000.0])).is_ok());
        // a spread beyond f64 is said so, not printed as inf
        let e = refused(&scene([1e308, -1e308]));
        assert!(
            e.contains("more than f64 holds") && !e.contains("inf"),
            "{e}"
        );
    }

    /// A wall whose later phase moves it a radius in a step is refused before the run,
    /// naming the phase (at t = 0 the starting spread sees it); force_dt accepts it.
    #[test]
    fn a_wall_phase_that_can_pass_particles_in_one_step_is_refused() {
        let scene = |speed: f64, force: bool| {
            let text = format!(
                "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.01, 0.01]\n[simulation]\nduration = 0.1\nforce_dt = {force}\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\n[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n[[wall.phase]]\nfrom = 1e-3\nvelocity = [{speed:?}, 0.0, 0.0]\n[[particles]]\nkind = \"list\"\npositions = [[0.45, 0.005, 0.005]]\nradius = 1e-3\n"
            );
            Scene::from_toml_str(&text, "t").unwrap()
        };
        let e = refused(&scene(1e5, false));
        assert!(
            e.contains("wall 0's motion from t = 0.001 s (its phase or schedule entry 0)")
                && e.contains("1.0000e5 m/s")
                && e.contains("force_dt"),
            "{e}"
        );
        assert!(Resolved::new(&scene(1.0, false)).is_ok());
        assert!(Resolved::new(&scene(1e5, true)).is_ok());
    }

    /// Hertz spheres starting at ±50 m/s (impact_velocity left at 1 m/s): the automatic dt
    /// follows their 100 m/s approach, saying so; two spheres parting, or moving side by
    /// side, keep impact_velocity's.
    #[test]
    fn the_automatic_dt_follows_faster_starting_velocities() {
        let scene = |v: [[f64; 3]; 2]| {
            let text = format!(
                "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.02, 0.01, 0.01]\n[simulation]\nduration = 2e-4\n[[material]]\nname = \"g\"\ndensity = 2650.0\nmodel = \"hertz\"\nyoungs = 7e10\npoisson = 0.17\nrestitution = 0.5\n[[particles]]\nkind = \"list\"\npositions = [[0.0085, 0.005, 0.005], [0.0115, 0.005, 0.005]]\nradius = 1e-3\nvelocities = [{:?}, {:?}]\n",
                v[0], v[1]
            );
            Scene::from_toml_str(&text, "t").unwrap()
        };
        let slow = Resolved::new(&scene([[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]])).unwrap();
        let fast = Resolved::new(&scene([[50.0, 0.0, 0.0], [-50.0, 0.0, 0.0]])).unwrap();
        // Hertz: tc ∝ v^(−1/5); at 1 m/s the Rayleigh rule binds (its limit is the lower)
        let hertz = |v: f64| {
            let Ok(ContactModel::Jkr(p)) = scene([[0.0; 3]; 2]).pair_model(0, 0) else {
                panic!()
            };
            let m = 2650.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-9;
            p.hertz_contact_time(0.5e-3, 0.5 * m, v) / crate::model::DEFAULT_DT_FRACTION
        };
        assert!(
            slow.time_step.reason.contains("Rayleigh"),
            "{}",
            slow.time_step.reason
        );
        assert!(fast.dt < 0.5 * slow.dt, "{} {}", fast.dt, slow.dt);
        assert!(
            (fast.dt - hertz(100.0)).abs() < 1e-12 * fast.dt,
            "{}",
            fast.dt
        );
        assert!(
            fast.time_step
                .reason
                .contains("close a pair at up to 1e2 m/s"),
            "{}",
            fast.time_step.reason
        );
        for v in [[-50.0, 50.0], [50.0, 50.0]] {
            let r = Resolved::new(&scene([[v[0], 0.0, 0.0], [v[1], 0.0, 0.0]])).unwrap();
            assert_eq!(r.dt, slow.dt, "{v:?}");
        }
    }

    /// One material at r = 1 mm and 10 µm with Luding's rolling and twisting springs: the
    /// stiffest oscillator is a small sphere rolling on a large one (m = 1/[ℓ²(1/I_s +
    /// 1/I_b)] ≈ m_s/10, where two small ones give m_s/5), and the automatic dt resolves it.
    #[test]
    fn the_time_step_resolves_a_small_sphere_rolling_on_a_large_one() {
        let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 0.01]\n[simulation]\nduration = 1e-3\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 0.0\nphi_f = 0.05\nfriction = 0.3\nrolling_friction = 0.1\nkr = 1000.0\ntwisting_friction = 0.1\nko = 1000.0\n[[particles]]\nkind = \"list\"\npositions = [[0.003, 0.005, 0.005], [0.006, 0.005, 0.005], [0.008, 0.005, 0.005]]\nradii = [1e-3, 1e-5, 1e-5]\n";
        let r = Resolved::new(&Scene::from_toml_str(text, "t").unwrap()).unwrap();
        let (rs, rb) = (1e-5f64, 1e-3f64);
        let mass = |r: f64| 2000.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        let inertia = |r: f64| 0.4 * mass(r) * r * r;
        let lever = 2.0 * rs * rb / (rs + rb);
        let m = 1.0 / (lever * lever * (1.0 / inertia(rs) + 1.0 / inertia(rb)));
        let tc = std::f64::consts::PI * (m / 1000.0).sqrt();
        assert!(
            r.dt <= tc / crate::model::DEFAULT_DT_FRACTION * (1.0 + 1e-12),
            "{:e} vs {:e}",
            r.dt,
            tc / 50.0
        );
        assert!(
            r.time_step.reason.contains("oscillator"),
            "{}",
            r.time_step.reason
        );
    }

    /// The default step is the shortest contact's default, where the smallest limit is a
    /// viscous one of another contact: a stiff undamped material `a` (default tc/50 =
    /// 1.29e-6 s) beside a soft, damped one `b` (limit 0.2·m_r/γ0 = 4.19e-6 s, its default
    /// too), not the binding limit's contact's default.
    #[test]
    fn the_default_step_is_the_shortest_contacts_default() {
        let text = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.01, 0.01, 0.01]\n[simulation]\nduration = 1e-3\n[[material]]\nname = \"a\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 1e4\n[[material]]\nname = \"b\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 1.0\ngamma0 = 0.2\n[[interaction]]\nmaterials = [\"a\", \"b\"]\nmodel = \"lsd\"\nk = 1.0\n[[particles]]\nkind = \"list\"\nmaterial = \"a\"\npositions = [[0.003, 0.005, 0.005]]\nradius = 1e-3\n[[particles]]\nkind = \"list\"\nmaterial = \"b\"\npositions = [[0.007, 0.005, 0.005]]\nradius = 1e-3\n";
        let r = Resolved::new(&Scene::from_toml_str(text, "t").unwrap()).unwrap();
        let m_r = 0.5 * 2000.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-9;
        let tc_a = std::f64::consts::PI * (m_r / 1e4f64).sqrt();
        let limit_b = crate::model::MAX_VISCOUS_STEP * m_r / 0.2;
        assert!(
            (r.time_step.max / limit_b - 1.0).abs() < 1e-12,
            "{:?}",
            r.time_step
        );
        assert!(
            (r.dt / (tc_a / crate::model::DEFAULT_DT_FRACTION) - 1.0).abs() < 1e-12,
            "{:e}: {:?}",
            r.dt,
            r.time_step
        );
        assert!(
            r.time_step.reason.contains("gamma0")
                && r.time_step.reason.contains("another contact's"),
            "{}",
            r.time_step.reason
        );
    }

    /// A run or an event beyond the steps a run can count, and a domain too far out for
    /// f64 positions to resolve its particles, are refused, naming what.
    #[test]
    fn runs_events_and_domains_beyond_f64_are_refused() {
        let lsd = "model = \"lsd\"\nk = 100.0";
        let mut s = scene(lsd, "1e-3");
        s.dt = DtSetting::Fixed(1e-320);
        let e = refused(&s);
        assert!(
            e.contains("simulation.duration") && e.contains("steps a run can count"),
            "{e}"
        );
        let mut s = scene(lsd, "1e-3");
        s.particles[0].insert_at = 1e15;
        let e = refused(&s);
        assert!(e.contains("particle 0's insert_at 1e15 s"), "{e}");
        let mut s = scene(lsd, "1e-3");
        s.domain.min[0] = -1e20;
        let e = refused(&s);
        assert!(e.contains("reaches 1e20 m on axis x"), "{e}");
        assert!(Resolved::new(&scene(lsd, "1e-3")).is_ok());
    }

    /// A JKR adhesion too weak for f64 (it gave NaN energies) is refused; a weak one that
    /// f64 carries runs.
    #[test]
    fn a_jkr_adhesion_below_f64_is_refused() {
        let jkr =
            |g: &str| format!("model = \"jkr\"\nyoungs = 1e8\npoisson = 0.3\nsurface_energy = {g}");
        let e = refused(&scene(&jkr("1e-200"), "1e-3"));
        assert!(
            e.contains("materials `m` and `m`: surface_energy = 1e-200"),
            "{e}"
        );
        assert!(e.contains("set surface_energy = 0"), "{e}");
        assert!(Resolved::new(&scene(&jkr("1e-60"), "1e-3")).is_ok());
    }

    /// A material no particle uses needs no model with the others (the scene reader asks
    /// for none; the engines did).
    #[test]
    fn a_material_no_particle_uses_needs_no_interaction() {
        let lsd = "model = \"lsd\"\nk = 100.0\n[[material]]\nname = \"unused\"\ndensity = 1.0\nmodel = \"lsd\"\nk = 1.0";
        let r = Resolved::new(&scene(lsd, "1e-3")).unwrap();
        assert_eq!(r.models.len(), 4);
    }

    #[test]
    fn a_mass_or_time_step_that_overflows_is_refused() {
        let e = refused(&scene("model = \"lsd\"\nk = 100.0", "1e-300"));
        assert!(
            e.contains("particle 0: its mass comes out as 0e0 kg"),
            "{e}"
        );
        let jkr = "model = \"jkr\"\nyoungs = 1e300\npoisson = 0.3\nsurface_energy = 0.05";
        let e = refused(&scene(jkr, "1e-3"));
        assert!(e.contains("the time step comes out as 0e0 s"), "{e}");
        // the same law in range runs
        let jkr = "model = \"jkr\"\nyoungs = 1e9\npoisson = 0.3\nsurface_energy = 0.05";
        assert!(Resolved::new(&scene(jkr, "1e-3")).unwrap().dt > 0.0);
    }
}
