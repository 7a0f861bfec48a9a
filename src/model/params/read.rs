//! Reading a law from a front end (a scene table or the command line) through the
//! declarations: each value typed and checked, then the model built.

use super::*;
use Fallback::{Derived, Number, Required, Word};

/// A value as a front end holds it, before the declaration types it.
#[derive(Clone, Debug, PartialEq)]
pub enum Raw {
    /// A number.
    Number(f64),
    /// A word or string.
    Text(String),
    /// Anything else, described for a message ("the boolean true").
    Other(String),
}

/// Where parameter values come from (a scene table, command-line flags), and how that
/// front end words its errors.
pub trait ParamSource {
    /// The front end's error.
    type Error;
    /// The parameter keys given.
    fn keys(&self) -> Vec<String>;
    /// The value given for `key`.
    fn raw(&self, key: &str) -> Option<Raw>;
    /// How the front end names a key in a message ("`k1` in \[\[material\]\] #1", "--k1").
    fn name(&self, key: &str) -> String;
    /// How the front end writes a setting ("dissipation = \"tsuji\"", "--dissipation tsuji").
    fn setting(&self, key: &str, value: &str) -> String;
    /// An error about `key`, located where the front end can.
    fn error(&self, key: &str, message: String) -> Self::Error;
    /// A required key that is missing; `what` says what it is.
    fn missing(&self, key: &str, what: &str) -> Self::Error;
    /// A key that `law` does not take; `owner` is a law that does.
    fn unknown(&self, key: &str, law: &Law, owner: Option<&str>) -> Self::Error;
    /// A rule broken by the values together (or one value).
    fn invalid(&self, e: ParamError) -> Self::Error;
}

/// The typed values of one law, defaults applied on access.
struct Values {
    given: Vec<(&'static str, Typed)>,
}

#[derive(Clone, Copy)]
enum Typed {
    Number(f64),
    Word(&'static str),
}

impl Values {
    fn get(&self, key: &str) -> Option<Typed> {
        self.given.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }

    fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// The number given or the declared default (required numbers are present: read checks).
    fn num(&self, p: &Param) -> f64 {
        match (self.get(p.key), p.fallback) {
            (Some(Typed::Number(x)), _) => x,
            (_, Number(x)) => x,
            _ => f64::NAN,
        }
    }

    fn opt(&self, p: &Param) -> Option<f64> {
        match self.get(p.key) {
            Some(Typed::Number(x)) => Some(x),
            _ => None,
        }
    }

    fn word(&self, p: &Param) -> &'static str {
        match (self.get(p.key), p.fallback) {
            (Some(Typed::Word(w)), _) => w,
            (_, Word(w)) => w,
            _ => "",
        }
    }
    /// The variant the word given for `p` (or its default) names: the choice list is the
    /// enum's `WORDS` and the word was typed against it (`word_enum!`).
    fn choice<T>(&self, p: &Param, from_word: fn(&str) -> Option<T>) -> T {
        from_word(self.word(p)).expect("a word typed against the enum's own list")
    }
}

/// Types one given value against its declaration.
fn typed<S: ParamSource>(src: &S, p: &'static Param, raw: Raw) -> Result<Typed, S::Error> {
    let expected = match p.kind {
        Kind::Number => "a number".to_string(),
        Kind::NumberOrInf => format!("a number in {} or \"inf\"", p.unit),
        Kind::Choice(options) => one_of(options),
    };
    let got = match &raw {
        Raw::Number(x) => format!("the number {x}"),
        Raw::Text(s) => format!("the string {s:?}"),
        Raw::Other(d) => d.clone(),
    };
    let type_error = || {
        src.error(
            p.key,
            format!("{} must be {expected}, got {got}", src.name(p.key)),
        )
    };
    match (p.kind, raw) {
        (Kind::Number, Raw::Number(x)) if !x.is_finite() => Err(src.error(
            p.key,
            format!("{} must be a finite number, got {x}", src.name(p.key)),
        )),
        (Kind::Number | Kind::NumberOrInf, Raw::Number(x)) => Ok(Typed::Number(x)),
        (Kind::NumberOrInf, Raw::Text(s))
            if matches!(s.to_lowercase().as_str(), "inf" | "infinity") =>
        {
            Ok(Typed::Number(f64::INFINITY))
        }
        (Kind::Choice(options), Raw::Text(s)) => match options.iter().find(|o| **o == s) {
            Some(o) => Ok(Typed::Word(o)),
            None => Err(src.error(
                p.key,
                format!("{} must be {expected}, got \"{s}\"", src.name(p.key)),
            )),
        },
        _ => Err(type_error()),
    }
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
fn one_of(options: &[&str]) -> String {
    let q: Vec<String> = options.iter().map(|o| format!("\"{o}\"")).collect();
    match q.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// A typed value of one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A number (of [`Kind::Number`] or [`Kind::NumberOrInf`]).
    Number(f64),
    /// One of the words of a [`Kind::Choice`].
    Word(&'static str),
}

/// Reads one parameter from `src` outside a contact law (a command that takes a few
/// declared parameters, e.g. `powder analytic`): the value given, typed against the
/// declaration, a number checked against its rule; the declared default when absent;
/// `None` when neither (required or derived: the caller decides).
pub fn read_value<S: ParamSource>(src: &S, p: &'static Param) -> Result<Option<Value>, S::Error> {
    let value = match src.raw(p.key) {
        Some(raw) => match typed(src, p, raw)? {
            Typed::Number(x) => {
                p.check(x).map_err(|e| src.invalid(e))?;
                Value::Number(x)
            }
            Typed::Word(w) => Value::Word(w),
        },
        None => match p.fallback {
            Number(x) => Value::Number(x),
            Word(w) => Value::Word(w),
            Required | Derived(_) => return Ok(None),
        },
    };
    Ok(Some(value))
}

/// Reads the parameters of the law `name` from `src`: unknown keys, missing required keys,
/// wrong types and parameters of a dissipation not selected are errors of the front end;
/// the model is validated.
pub fn read_model<S: ParamSource>(src: &S, name: &str) -> Result<ContactModel, S::Error> {
    let law = law(name).unwrap_or(&LAWS[0]);
    let accepted = keys_of(law);
    for key in src.keys() {
        if !accepted.contains(&key.as_str()) {
            return Err(src.unknown(&key, law, owner_of(&key)));
        }
    }
    let mut values = Values { given: Vec::new() };
    for key in &accepted {
        let p = param(key).expect("declared");
        if let Some(raw) = src.raw(key) {
            let value = typed(src, p, raw)?;
            // every number given against its own rule, also where the model would not look
            // (a negative coefficient of a sub-model that is then off)
            if let Typed::Number(x) = value {
                p.check(x).map_err(|e| src.invalid(e))?;
            }
            values.given.push((p.key, value));
        }
    }
    let dissipation = if law.dissipation {
        let selected = if values.has(DISSIPATION.key) {
            values.word(&DISSIPATION)
        } else if values.has(RESTITUTION.key) {
            "tsuji"
        } else {
            "none"
        };
        let sub = DISSIPATIONS
            .iter()
            .find(|d| d.name == selected)
            .expect("a declared choice");
        Some(sub)
    } else {
        None
    };
    let required = law
        .params
        .iter()
        .chain(dissipation.iter().flat_map(|d| d.params));
    for p in required {
        if p.fallback == Required && !values.has(p.key) {
            let what = match dissipation {
                Some(d) if d.params.contains(p) => {
                    format!("{} ({})", p.what(), src.setting(DISSIPATION.key, d.name))
                }
                _ => p.what(),
            };
            return Err(src.missing(p.key, &what));
        }
    }
    if let Some(sub) = dissipation {
        // each dissipation's parameters only with that dissipation
        for p in DISSIPATIONS.iter().flat_map(|d| d.params) {
            if values.has(p.key) && !sub.params.iter().any(|q| q.key == p.key) {
                let owners: Vec<String> = DISSIPATIONS
                    .iter()
                    .filter(|d| d.params.iter().any(|q| q.key == p.key))
                    .map(|d| src.setting(DISSIPATION.key, d.name))
                    .collect();
                return Err(src.error(
                    p.key,
                    format!(
                        "{} applies to {} only, not {}",
                        src.name(p.key),
                        owners.join(" or "),
                        src.setting(DISSIPATION.key, sub.name)
                    ),
                ));
            }
        }
    }
    luding_given(law, &values).map_err(|e| src.invalid(e))?;
    let model = build(law, dissipation, &values);
    model.validate().map_err(|e| src.invalid(e))?;
    Ok(model)
}

/// Refuses a stiffness, damping or dynamic coefficient of a friction sub-model that is off:
/// it would have no effect, which is more likely a mistake than an intent.
fn luding_given(law: &Law, v: &Values) -> Result<(), ParamError> {
    // jkr/hertz: `friction` is the Mindlin law's, which takes none of these
    let groups: [(&Param, &[&Param]); 3] = [
        (&FRICTION, &[&FRICTION_DYNAMIC, &KT, &GAMMA_T]),
        (&ROLLING_FRICTION, &[&KR, &GAMMA_R]),
        (&TWISTING_FRICTION, &[&KO, &GAMMA_O]),
    ];
    for (mu, dependents) in groups {
        if !law.params.contains(&mu) || v.num(mu) > 0.0 {
            continue;
        }
        if let Some(p) = dependents
            .iter()
            .find(|p| law.params.contains(p) && v.has(p.key))
        {
            return Err(ParamError::new(
                p.key,
                format!(
                    "{} is given but {} = {}: {} acts only with {} > 0 (Luding 2008); set {} or drop {}",
                    p.key,
                    mu.key,
                    v.num(mu),
                    p.doc,
                    mu.key,
                    mu.key,
                    p.key
                ),
            ));
        }
    }
    Ok(())
}

/// Luding's friction of a hysteretic (`k` = k1) or LSD (`k` = k) pair with damping `gamma0`,
/// the defaults derived: μd = μs, k_t = 2/7·k, γ_t = 2/7·γ0 (the tangential period equals
/// the normal one), k_r = k_o = 2/5·k, γ_r = γ_o = 2/5·γ0 (equal periods for two equal
/// spheres with the lever a12). A sub-model that is off (μ = 0) is all zero.
fn luding(v: &Values, k: f64, gamma0: f64) -> LudingFriction {
    let spring = |mu: f64, mu_d: f64, kp: &Param, gp: &Param, share: f64| {
        if mu > 0.0 {
            CoulombSpring {
                mu_s: mu,
                mu_d,
                k: v.opt(kp).unwrap_or(share * k),
                gamma: v.opt(gp).unwrap_or(share * gamma0),
            }
        } else {
            CoulombSpring::default()
        }
    };
    let mu = v.num(&FRICTION);
    let mu_r = v.num(&ROLLING_FRICTION);
    let mu_o = v.num(&TWISTING_FRICTION);
    LudingFriction {
        sliding: spring(
            mu,
            v.opt(&FRICTION_DYNAMIC).unwrap_or(mu),
            &KT,
            &GAMMA_T,
            crate::model::friction::TANGENTIAL_SHARE,
        ),
        rolling: spring(
            mu_r,
            mu_r,
            &KR,
            &GAMMA_R,
            crate::model::friction::ROTATIONAL_SHARE,
        ),
        twisting: spring(
            mu_o,
            mu_o,
            &KO,
            &GAMMA_O,
            crate::model::friction::ROTATIONAL_SHARE,
        ),
    }
}

/// The model from typed values (required ones present, defaults from the declaration).
fn build(law: &Law, dissipation: Option<&Law>, v: &Values) -> ContactModel {
    match law.name {
        "hysteretic" => {
            let kc = v.num(&KC);
            ContactModel::Hysteretic(HystereticParams {
                k1: v.num(&K1),
                kp: v.num(&KP),
                kc,
                phi_f: v.num(&PHI_F),
                fa: v.num(&FA),
                kca: v
                    .opt(&KCA)
                    .unwrap_or(if kc > 0.0 { kc } else { f64::INFINITY }),
                adhesion: v.choice(&ADHESION, AdhesionMode::from_word),
                gamma0: v.num(&GAMMA0),
                k2_rule: v.choice(&K2_RULE, K2Rule::from_word),
                luding: luding(v, v.num(&K1), v.num(&GAMMA0)),
            })
        }
        "lsd" => ContactModel::Lsd(LsdParams {
            k: v.num(&K),
            gamma0: v.num(&GAMMA0),
            luding: luding(v, v.num(&K), v.num(&GAMMA0)),
        }),
        _ => {
            let dissipation = match dissipation.map_or("none", |d| d.name) {
                "tsuji" => Dissipation::Tsuji {
                    restitution: v.num(&RESTITUTION),
                    stiffness: v.choice(&TSUJI_STIFFNESS, TsujiStiffness::from_word),
                },
                "powerlaw" => Dissipation::PowerLaw {
                    d: v.num(&POWER_D),
                    alpha: v.num(&POWER_ALPHA),
                    beta: v.num(&POWER_BETA),
                },
                "krijt" => Dissipation::Krijt {
                    tvis: v.num(&TVIS),
                    sigma0: v.num(&SIGMA0),
                },
                "stress" => Dissipation::Stress {
                    tvis0_per_radius: v.num(&TVIS0_PER_RADIUS),
                    b: v.num(&STRESS_B),
                    zeta: v.num(&STRESS_ZETA),
                    sigma0: v.num(&SIGMA0),
                },
                "none" => Dissipation::None,
                // (the reader takes only the declared words, and a test builds each one)
                other => unreachable!("dissipation `{other}` is declared but not built"),
            };
            let adhesive = law.params.contains(&&SURFACE_ENERGY);
            ContactModel::Jkr(JkrParams {
                youngs: v.num(&YOUNGS),
                poisson: v.num(&POISSON),
                surface_energy: if adhesive {
                    v.num(&SURFACE_ENERGY)
                } else {
                    0.0
                },
                dissipation,
                friction: v.num(&FRICTION),
                rolling_hysteresis: v.num(&ROLLING_HYSTERESIS),
                pulloff: v.choice(&PULLOFF, Pulloff::from_word),
                stiffness_scale: v.num(&STIFFNESS_SCALE),
                luding: LudingFriction {
                    // k_o = 0: the Mindlin-derived stiffness of the current contact radius
                    twisting: if v.num(&TWISTING_FRICTION) > 0.0 {
                        CoulombSpring {
                            mu_s: v.num(&TWISTING_FRICTION),
                            mu_d: v.num(&TWISTING_FRICTION),
                            k: v.opt(&KO).unwrap_or(0.0),
                            gamma: v.opt(&GAMMA_O).unwrap_or(0.0),
                        }
                    } else {
                        CoulombSpring::default()
                    },
                    ..Default::default()
                },
            })
        }
    }
}
