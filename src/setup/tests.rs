//! The set-up's refusals and time-step rules, each at its edge.

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
    // a spread beyond f64 is said so, not printed as inf; one whose squares overflow but
    // whose length f64 holds is given
    let e = refused(&scene([1e308, -1e308]));
    assert!(
        e.contains("more than f64 holds") && !e.contains("inf"),
        "{e}"
    );
    let e = refused(&scene([1e200, -1e200]));
    assert!(e.contains("differ by up to 2e200 m/s"), "{e}");
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
    // moving away from the particles' side it passes none (it used to be refused)
    assert!(Resolved::new(&scene(-1e5, false)).is_ok());
}

/// The dt a refusal advises, typed back, is accepted (rounded to 4 digits it could lie
/// just above the limit and be refused in turn).
#[test]
fn the_advised_time_step_is_accepted() {
    for k in 0..40 {
        let radius = 1.0e-3 * (1.0 + 0.00731 * f64::from(k));
        let mut s = scene("model = \"lsd\"\nk = 100.0", &radius.to_string());
        s.dt = DtSetting::Fixed(1.0);
        let e = refused(&s);
        let advised: f64 = e
            .split("use dt <= ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("{e}"));
        s.dt = DtSetting::Fixed(advised);
        assert!(Resolved::new(&s).is_ok(), "radius {radius}: {e}");
    }
}

/// A wall moving at the start away from the particles' side closes on none: accepted,
/// with the dt of the particles (it used to be refused as a closing of 6.6e-3 m a step);
/// moving toward them as fast, refused.
#[test]
fn a_wall_receding_at_the_start_closes_on_no_particle() {
    let scene = |speed: f64| {
        let text = format!(
            "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.01, 0.01]\n[simulation]\nduration = 0.1\n[[material]]\nname = \"m\"\ndensity = 2000.0\nmodel = \"lsd\"\nk = 100.0\n[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\nvelocity = [{speed:?}, 0.0, 0.0]\n[[particles]]\nkind = \"list\"\npositions = [[0.45, 0.005, 0.005]]\nradius = 1e-3\n"
        );
        Scene::from_toml_str(&text, "t").unwrap()
    };
    let at_rest = Resolved::new(&scene(0.0)).unwrap();
    let receding = Resolved::new(&scene(-1e3)).unwrap();
    assert_eq!(receding.dt, at_rest.dt);
    let e = refused(&scene(1e3));
    assert!(e.contains("pass through each other"), "{e}");
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
        r.time_step.reason.contains("gamma0") && r.time_step.reason.contains("another contact's"),
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
