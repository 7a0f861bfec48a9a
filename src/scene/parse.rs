//! Parsing a scene file: the top-level table and the domain, simulation, material,
//! interaction and wall sections.

use super::checks::{check_pair_models, check_particles, check_periodic};
use super::declared::Section;
use super::keys::{
    with_motion_keys, DOMAIN_KEYS, INTERACTION_KEYS, MATERIAL_KEYS, PHASE_KEYS, SERVO_KEYS,
    SIMULATION_KEYS, TOP_KEYS, WALL_KEYS,
};
use super::particles::parse_particles;
use super::toml_reader::{
    convert_table, describe, fmt_vec, node_number, one_of_strings, quoted_list, suggest, Node, Res,
    Src, Tbl, Val, AXES,
};
use super::{Domain, DtSetting, Interaction, Material, Scene, Wall, WallMotion, WallPhase};
use crate::error::{ParamError, PowderError};
use crate::model::{params, ContactModel};
use crate::overrides::Override;
use toml::de::DeTable;

/// Parses `src` with the `--set` overrides `sets` applied in order.
pub(super) fn parse_scene(src: &Src, sets: &[Override]) -> Res<Scene> {
    let doc = DeTable::parse(src.text).map_err(|e| {
        // (the text at the error where it is short, e.g. the key a duplicate repeats)
        let at = (e.span().and_then(|r| src.text.get(r)).map(str::trim))
            .filter(|t| !t.is_empty() && t.len() <= 60 && !t.contains('\n'))
            .map(|t| format!(" at `{t}`"))
            .unwrap_or_default();
        let msg = format!("TOML syntax error{at}: {}", e.message().trim_end());
        src.err(e.span().as_ref(), msg)
    })?;
    let mut root_entries = convert_table(src, doc.get_ref())?;
    for (k, set) in sets.iter().enumerate() {
        super::set::apply(&mut root_entries, set, k)?;
    }
    let root = Tbl::new(src, &root_entries, None, "the top-level table".to_string());
    root.check_keys(&TOP_KEYS, |k| {
        let sections: [(&str, &[&str]); 2] = [
            ("simulation", &SIMULATION_KEYS[..]),
            ("domain", &DOMAIN_KEYS[..]),
        ];
        sections
            .iter()
            .find(|(_, keys)| keys.contains(&k))
            .map(|(s, _)| format!("`{k}` belongs in the [{s}] table"))
    })?;

    let domain = parse_domain(&root)?;
    let sim = parse_simulation(&root)?;
    let materials = parse_materials(&root)?;
    let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
    let interactions = parse_interactions(&root, &names)?;
    let walls = parse_walls(&root, &names)?;
    let (particles, origin) = parse_particles(&root, &names)?;

    let scene = Scene {
        name: src.name.to_string(),
        domain,
        gravity: sim.gravity,
        dt: sim.dt,
        force_dt: sim.force_dt,
        jump_impulses: sim.jump_impulses,
        impact_velocity: sim.impact_velocity,
        checkpoint_every: sim.checkpoint_every,
        contact_output: sim.contact_output,
        duration: sim.duration,
        output_every: sim.output_every,
        materials,
        interactions,
        walls,
        particles,
    };
    check_periodic(src, &scene)?;
    check_particles(src, &scene, &origin)?;
    check_pair_models(src, &scene)?;
    Ok(scene)
}

fn parse_domain(root: &Tbl) -> Res<Domain> {
    let t = root
        .table("domain", "[domain]".to_string())?
        .ok_or_else(|| {
            root.src.err(
                None,
                "missing required table [domain]: add [domain] with min = [x, y, z] and max = [x, y, z] in m",
            )
        })?;
    t.check_keys(&DOMAIN_KEYS, |_| None)?;
    let min = t.vec3_req("min", "the lower corner [x, y, z] of the domain in m")?;
    let max = t.vec3_req("max", "the upper corner [x, y, z] of the domain in m")?;
    for a in 0..3 {
        if max[a] <= min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "`max` in [domain] must be > `min` on every axis, but on axis {} max = {} <= min = {}",
                    AXES[a], max[a], min[a]
                ),
            ));
        }
    }
    let mut periodic = [false; 3];
    if let Some(node) = t.get("periodic") {
        let expected = "an array of 3 booleans [x, y, z], e.g. [true, true, false]";
        let Val::Array(items) = &node.val else {
            return Err(t.type_err("periodic", node, expected));
        };
        if items.len() != 3 {
            return Err(t.type_err("periodic", node, expected));
        }
        for (a, item) in items.iter().enumerate() {
            match item.val {
                Val::Bool(b) => periodic[a] = b,
                _ => return Err(t.type_err("periodic", node, expected)),
            }
        }
    }
    Ok(Domain { min, max, periodic })
}

struct SimSettings {
    duration: f64,
    dt: DtSetting,
    force_dt: bool,
    jump_impulses: Option<bool>,
    output_every: u64,
    impact_velocity: f64,
    checkpoint_every: u64,
    contact_output: Option<bool>,
    gravity: [f64; 3],
}

fn parse_simulation(root: &Tbl) -> Res<SimSettings> {
    let t = root
        .table("simulation", "[simulation]".to_string())?
        .ok_or_else(|| {
            root.src.err(
                None,
                "missing required table [simulation]: add [simulation] with at least duration = <s>",
            )
        })?;
    t.check_keys(&SIMULATION_KEYS, |_| None)?;
    let duration = t.number_req(Section::Simulation, "duration")?;
    let dt = match t.get("dt") {
        None => DtSetting::Auto,
        Some(node) => match &node.val {
            Val::Str(s) if s == "auto" => DtSetting::Auto,
            _ => match node_number(node) {
                Some(x) if x.is_finite() && x > 0.0 => DtSetting::Fixed(x),
                Some(x) => {
                    return Err(t.err_node(
                        node,
                        format!(
                        "`dt` in [simulation] must be \"auto\" or a time step > 0 in s, got {x}"
                    ),
                    ))
                }
                None => return Err(t.type_err("dt", node, "\"auto\" or a time step > 0 in s")),
            },
        },
    };
    let force_dt = t.bool("force_dt")?.unwrap_or(false);
    let jump_impulses = t.bool("jump_impulses")?;
    let output_every = t.count_or_default(Section::Simulation, "output_every")?;
    let gravity = t.vec3("gravity")?.unwrap_or([0.0; 3]);
    let impact_velocity = t.number_or_default(Section::Simulation, "impact_velocity")?;
    let checkpoint_every = t
        .count(Section::Simulation, "checkpoint_every")?
        .unwrap_or(10 * output_every);
    Ok(SimSettings {
        checkpoint_every,
        contact_output: t.bool("contact_output")?,
        impact_velocity,
        duration,
        dt,
        force_dt,
        jump_impulses,
        output_every,
        gravity,
    })
}

fn parse_materials(root: &Tbl) -> Res<Vec<Material>> {
    let tables = root.tables("material")?;
    if tables.is_empty() {
        return Err(root.src.err(
            None,
            "no [[material]]: add at least one, e.g. [[material]] name = \"powder\", density = 2000.0, model = \"lsd\", k = 100.0",
        ));
    }
    let mut out: Vec<Material> = Vec::with_capacity(tables.len());
    for (i, (span, entries)) in tables.into_iter().enumerate() {
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[material]] #{}", i + 1),
        );
        if let Some(Val::Str(name)) = t.get("name").map(|n| &n.val) {
            t.ctx = format!("[[material]] #{} (`{name}`)", i + 1);
        }
        let kind = model_kind(&t, &MATERIAL_KEYS)?;
        let name = t.str("name")?.ok_or_else(|| {
            t.missing(
                "name",
                "the material's name, used by particles, walls and interactions",
            )
        })?;
        if name.trim().is_empty() {
            return Err(t.err_key("name", format!("`name` in {} must not be empty", t.ctx)));
        }
        if let Some(j) = out.iter().position(|m| m.name == name) {
            return Err(t.err_key(
                "name",
                format!(
                    "duplicate material name `{name}` in {} (also [[material]] #{}): names must be unique",
                    t.ctx,
                    j + 1
                ),
            ));
        }
        let model = build_model(&t, kind, &MATERIAL_KEYS, &format!("material `{name}`"))?;
        let density = t.number_req(Section::Material, "density")?;
        out.push(Material {
            name: name.to_string(),
            density,
            model,
        });
    }
    Ok(out)
}

/// Reads `model` and checks that the table's keys are `common` or some law's parameters
/// (each law's own keys are checked by [`params::read_model`]).
fn model_kind(t: &Tbl, common: &[&str]) -> Res<&'static str> {
    let names = params::law_names();
    let Some(kind) = t.choice("model", &names)? else {
        let mut all: Vec<&str> = common.to_vec();
        all.extend(params::all_params().iter().map(|p| p.key));
        t.check_keys(&all, |_| None)?;
        return Err(t.missing(
            "model",
            &format!("the contact model, {}", one_of_strings(&names)),
        ));
    };
    Ok(kind)
}

/// A scene table as a source of contact-law parameters.
struct TableParams<'t, 'a> {
    t: &'t Tbl<'a>,
    /// The table's own keys (name, density, materials, model).
    common: &'t [&'t str],
    /// "material `glass`", "interaction `a`-`b`".
    owner: &'t str,
}

impl params::ParamSource for TableParams<'_, '_> {
    type Error = PowderError;

    fn keys(&self) -> Vec<String> {
        self.t
            .entries
            .iter()
            .map(|e| e.key.clone())
            .filter(|k| !self.common.contains(&k.as_str()))
            .collect()
    }

    fn raw(&self, key: &str) -> Option<params::Raw> {
        let node = self.t.get(key)?;
        Some(match &node.val {
            Val::Int(i) => params::Raw::Number(*i as f64),
            Val::Float(x) => params::Raw::Number(*x),
            Val::Str(s) => params::Raw::Text(s.clone()),
            _ => params::Raw::Other(describe(node)),
        })
    }

    fn name(&self, key: &str) -> String {
        format!("`{key}` in {}", self.t.ctx)
    }

    fn setting(&self, key: &str, value: &str) -> String {
        format!("{key} = \"{value}\"")
    }

    fn error(&self, key: &str, message: String) -> PowderError {
        self.t.err_key(key, message)
    }

    fn missing(&self, key: &str, what: &str) -> PowderError {
        self.t.missing(key, what)
    }

    fn unknown(&self, key: &str, law: &params::Law, owner: Option<&str>) -> PowderError {
        let mut allowed: Vec<&str> = self.common.to_vec();
        allowed.extend(params::keys_of(law));
        let hint = |k: &str| {
            owner.filter(|_| k == key).map(|m| {
                format!(
                    "`{k}` is a parameter of the `{m}` model, but {} uses model = \"{}\"",
                    self.owner, law.name
                )
            })
        };
        match self.t.check_keys(&allowed, hint) {
            Err(e) => e,
            Ok(()) => self
                .t
                .err_key(key, format!("unknown key `{key}` in {}", self.t.ctx)),
        }
    }

    fn invalid(&self, e: ParamError) -> PowderError {
        self.t.err_key(e.param, format!("{}: {e}", self.owner))
    }
}

fn build_model(t: &Tbl, kind: &str, common: &[&str], owner: &str) -> Res<ContactModel> {
    params::read_model(&TableParams { t, common, owner }, kind)
}

/// Resolves a material name; errors list the known names.
fn material_index(t: &Tbl, node: &Node, key: &str, name: &str, names: &[&str]) -> Res<usize> {
    if let Some(i) = names.iter().position(|n| *n == name) {
        return Ok(i);
    }
    let mut msg = format!(
        "unknown material `{name}` in `{key}` of {}; known materials are {}",
        t.ctx,
        quoted_list(names)
    );
    if let Some(s) = suggest(name, names) {
        msg.push_str(&format!(": did you mean `{s}`?"));
    }
    Err(t.err_node(node, msg))
}

/// The optional `material` key of a wall or particle block; default the first material.
pub(super) fn material_ref(t: &Tbl, names: &[&str]) -> Res<usize> {
    match t.str("material")? {
        None => Ok(0),
        Some(name) => {
            let node = t.get("material").expect("present");
            material_index(t, node, "material", name, names)
        }
    }
}

fn parse_interactions(root: &Tbl, names: &[&str]) -> Res<Vec<Interaction>> {
    let mut out: Vec<Interaction> = Vec::new();
    for (i, (span, entries)) in root.tables("interaction")?.into_iter().enumerate() {
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[interaction]] #{}", i + 1),
        );
        let kind = model_kind(&t, &INTERACTION_KEYS)?;
        let expected = "an array of two material names, e.g. [\"powder\", \"glass\"]";
        let node = t
            .get("materials")
            .ok_or_else(|| t.missing("materials", expected))?;
        let pair: Vec<&str> = match &node.val {
            Val::Array(items) if items.len() == 2 => items
                .iter()
                .map(|it| match &it.val {
                    Val::Str(s) => Ok(s.as_str()),
                    _ => Err(t.type_err("materials", node, expected)),
                })
                .collect::<Res<Vec<_>>>()?,
            _ => return Err(t.type_err("materials", node, expected)),
        };
        let a = material_index(&t, node, "materials", pair[0], names)?;
        let b = material_index(&t, node, "materials", pair[1], names)?;
        t.ctx = format!("[[interaction]] #{} (`{}`-`{}`)", i + 1, names[a], names[b]);
        if a == b {
            return Err(t.err_key(
                "materials",
                format!(
                    "{} pairs `{}` with itself: a material's law with itself is its [[material]]'s `model`; an interaction is between two different materials",
                    t.ctx, names[a]
                ),
            ));
        }
        if let Some(j) = out
            .iter()
            .position(|x| x.materials == [a, b] || x.materials == [b, a])
        {
            return Err(t.err_key(
                "materials",
                format!(
                    "duplicate interaction for materials `{}` and `{}` in {} (also [[interaction]] #{})",
                    names[a],
                    names[b],
                    t.ctx,
                    j + 1
                ),
            ));
        }
        let owner = format!("interaction `{}`-`{}`", names[a], names[b]);
        let model = build_model(&t, kind, &INTERACTION_KEYS, &owner)?;
        out.push(Interaction {
            materials: [a, b],
            model,
        });
    }
    Ok(out)
}

/// `velocity`, or `velocities` with `times`, or `servo_*`, or `[[wall.phase]]`: at most
/// one kind of motion.
fn parse_wall_motion(t: &Tbl) -> Res<WallMotion> {
    let kinds = [
        t.has("velocity"),
        t.has("velocities") || t.has("times"),
        SERVO_KEYS.iter().any(|k| t.has(k)),
        t.has("phase"),
    ];
    if kinds.iter().filter(|&&k| k).count() > 1 {
        return Err(t.err_table(format!(
            "{} mixes kinds of motion: give `velocity` (constant), or `velocities` with `times` (a schedule), or `servo_force`, `servo_gain` and `servo_max_speed` (force control), or `[[wall.phase]]` tables (a program)",
            t.ctx
        )));
    }
    if kinds[1] {
        let velocities = t.vec3_list("velocities")?.ok_or_else(|| {
            t.missing(
                "velocities",
                "the wall velocities [[vx, vy, vz], ...] in m/s, one per entry of `times`",
            )
        })?;
        let times = t.f64_list("times")?.ok_or_else(|| {
            t.missing(
                "times",
                "the times in s from which each of `velocities` applies, increasing",
            )
        })?;
        if velocities.len() != times.len() || times.is_empty() {
            return Err(t.err_key(
                "times",
                format!(
                    "`times` in {} has {} entries and `velocities` {}: give one start time per velocity",
                    t.ctx,
                    times.len(),
                    velocities.len()
                ),
            ));
        }
        check_increasing(t, "times", "`times`", &times)?;
        let phases = times.into_iter().zip(velocities);
        return Ok(WallMotion {
            phases: phases.map(|(t, v)| (t, WallPhase::Velocity(v))).collect(),
        });
    }
    if kinds[3] {
        let mut phases = Vec::new();
        for (i, (span, entries)) in t.tables("phase")?.into_iter().enumerate() {
            let p = Tbl::new(
                t.src,
                entries,
                Some(span),
                format!("{} phase #{}", t.ctx, i + 1),
            );
            p.check_keys(&with_motion_keys(&PHASE_KEYS), |_| None)?;
            let from = p.number_req(Section::Phase, "from")?;
            phases.push((from, parse_wall_phase(&p)?));
        }
        let times: Vec<f64> = phases.iter().map(|(from, _)| *from).collect();
        check_increasing(t, "phase", "the phases' `from`", &times)?;
        return Ok(WallMotion { phases });
    }
    Ok(match parse_wall_phase(t)? {
        WallPhase::Rest => WallMotion::fixed(),
        phase => WallMotion::always(phase),
    })
}

/// Phase start times (`what`, at `key`): at least one, from >= 0 s, strictly increasing.
fn check_increasing(t: &Tbl, key: &str, what: &str, times: &[f64]) -> Res<()> {
    if times.is_empty() || times[0] < 0.0 || times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(t.err_key(
            key,
            format!(
                "the start times in {} ({what}) must start at >= 0 s and increase strictly, got {times:?}",
                t.ctx
            ),
        ));
    }
    Ok(())
}

/// One phase's motion: `velocity`, or `servo_*`, or neither (at rest).
fn parse_wall_phase(t: &Tbl) -> Res<WallPhase> {
    let servo = SERVO_KEYS.iter().any(|k| t.has(k));
    if t.has("velocity") && servo {
        return Err(t.err_table(format!(
            "{} mixes kinds of motion: give `velocity` or `servo_force`, `servo_gain` and `servo_max_speed`",
            t.ctx
        )));
    }
    if let Some(v) = t.vec3("velocity")? {
        return Ok(WallPhase::Velocity(v));
    }
    if servo {
        let force = t.number_req(Section::Motion, "servo_force")?;
        let gain = t.number_req(Section::Motion, "servo_gain")?;
        let max_speed = t.number_req(Section::Motion, "servo_max_speed")?;
        return Ok(WallPhase::Servo {
            force,
            gain,
            max_speed,
        });
    }
    Ok(WallPhase::Rest)
}

fn parse_walls(root: &Tbl, names: &[&str]) -> Res<Vec<Wall>> {
    let mut out = Vec::new();
    for (i, (span, entries)) in root.tables("wall")?.into_iter().enumerate() {
        let t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[wall]] #{}", i + 1),
        );
        t.check_keys(&with_motion_keys(&WALL_KEYS), |_| None)?;
        let point = t.vec3_req("point", "a point [x, y, z] on the wall plane in m")?;
        let n = t.vec3_req(
            "normal",
            "the wall normal [x, y, z], pointing into the domain",
        )?;
        let given = n;
        let mut n = n;
        let mut len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        // (a long or tiny normal's squares overflow or underflow: scaled by its largest
        // component first)
        let scale = n.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        if (len == f64::INFINITY || len == 0.0) && scale > 0.0 && scale.is_finite() {
            n = n.map(|c| c / scale);
            len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        }
        if !(len > 0.0 && len.is_finite()) {
            return Err(t.err_key(
                "normal",
                format!(
                    "`normal` in {} must be a non-zero vector pointing into the domain, got {}",
                    t.ctx,
                    fmt_vec(given)
                ),
            ));
        }
        let material = material_ref(&t, names)?;
        let motion = parse_wall_motion(&t)?;
        out.push(Wall {
            point,
            normal: [n[0] / len, n[1] / len, n[2] / len],
            motion,
            material,
        });
    }
    Ok(out)
}
