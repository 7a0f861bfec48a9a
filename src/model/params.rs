//! Contact-law parameters, declared once: every key with its unit, default, validity rule
//! and one line of doc. Scene tables and command-line flags are read through
//! [`read_model`], the flags are generated from the same table ([`super::flags`]), and the
//! models' `validate` apply the per-parameter rules declared here.

use super::{
    AdhesionMode, ContactModel, CoulombSpring, Dissipation, HystereticParams, JkrParams, K2Rule,
    LsdParams, LudingFriction, Pulloff, TsujiStiffness,
};
use crate::error::ParamError;

/// What values a parameter takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A finite number.
    Number,
    /// A number or "inf".
    NumberOrInf,
    /// One of a fixed set of words.
    Choice(&'static [&'static str]),
}

/// What a parameter is when it is not given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fallback {
    /// It must be given.
    Required,
    /// This number.
    Number(f64),
    /// This word (a [`Kind::Choice`]).
    Word(&'static str),
    /// Derived from other parameters, as the text says.
    Derived(&'static str),
}

/// The validity rule of one numeric parameter (finite in every case).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    /// Any finite value.
    Finite,
    /// > 0.
    Positive,
    /// ≥ 0.
    NonNegative,
    /// lo < x ≤ hi.
    LeftOpen(f64, f64),
    /// lo < x < hi.
    Open(f64, f64),
    /// > 0, or infinite.
    PositiveOrInf,
    /// Checked with the other parameters by the model.
    None,
}

/// One parameter of a contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Param {
    /// The scene key; the command-line flag is `--` + the key with `_` → `-`.
    pub key: &'static str,
    /// What the values are.
    pub kind: Kind,
    /// SI unit ("" for dimensionless or words).
    pub unit: &'static str,
    /// Value when absent.
    pub fallback: Fallback,
    /// Validity rule of a numeric value.
    pub rule: Rule,
    /// One line: what it is, with the paper's equation where there is one.
    pub doc: &'static str,
}

impl Param {
    /// The command-line flag without the dashes.
    pub fn flag(&self) -> String {
        self.key.replace('_', "-")
    }

    /// `doc, unit`: what a message about a missing value says.
    pub fn what(&self) -> String {
        if self.unit.is_empty() {
            self.doc.to_string()
        } else {
            format!("{} in {}", self.doc, self.unit)
        }
    }

    /// The rule in words ("> 0", "in (0, 1]"); `None` for [`Rule::None`] and [`Rule::Finite`].
    pub fn rule_text(&self) -> Option<String> {
        match self.rule {
            Rule::None | Rule::Finite => None,
            Rule::PositiveOrInf => Some("> 0 (inf for none)".to_string()),
            Rule::Positive => Some("> 0".to_string()),
            Rule::NonNegative => Some(">= 0".to_string()),
            Rule::LeftOpen(lo, hi) => Some(format!("in ({lo}, {hi}]")),
            Rule::Open(lo, hi) => Some(format!("in ({lo}, {hi})")),
        }
    }

    /// Checks `value` against the rule; the error names the key and the rule.
    pub fn check(&self, value: f64) -> Result<(), ParamError> {
        let ok = match self.rule {
            Rule::None => return Ok(()),
            Rule::PositiveOrInf => value > 0.0,
            _ if !value.is_finite() => false,
            Rule::Finite => true,
            Rule::Positive => value > 0.0,
            Rule::NonNegative => value >= 0.0,
            Rule::LeftOpen(lo, hi) => value > lo && value <= hi,
            Rule::Open(lo, hi) => value > lo && value < hi,
        };
        let rule = match self.rule {
            Rule::PositiveOrInf => self.rule_text().unwrap_or_default(),
            _ if !value.is_finite() => "a finite number".to_string(),
            _ => self.rule_text().unwrap_or_default(),
        };
        if ok {
            Ok(())
        } else {
            Err(ParamError::new(
                self.key,
                format!("{} ({}) must be {rule}, got {value}", self.key, self.doc),
            ))
        }
    }
}

/// A contact law, or a sub-model along one of its axes: a name and its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Law {
    /// The name in scenes (`model = "..."`) and on the command line.
    pub name: &'static str,
    /// One line: what it is and where from.
    pub doc: &'static str,
    /// Its own parameters.
    pub params: &'static [&'static Param],
    /// Whether the normal dissipation of [`DISSIPATIONS`] applies (selected by
    /// [`DISSIPATION`]).
    pub dissipation: bool,
}

macro_rules! param {
    ($name:ident, $key:literal, $kind:expr, $unit:literal, $fallback:expr, $rule:expr, $doc:literal) => {
        #[doc = $doc]
        pub const $name: Param = Param {
            key: $key,
            kind: $kind,
            unit: $unit,
            fallback: $fallback,
            rule: $rule,
            doc: $doc,
        };
    };
}

use Fallback::{Derived, Number, Required, Word};
use Kind::{Choice, NumberOrInf};
const NUM: Kind = Kind::Number;

// The hysteretic adhesive elasto-plastic law (paper 000 eqs. 5-15).
param!(
    K1,
    "k1",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the hysteretic loading stiffness k1"
);
param!(
    KP,
    "kp",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the hysteretic limit stiffness kp (>= k1)"
);
param!(
    KC,
    "kc",
    NUM,
    "N/m",
    Required,
    Rule::NonNegative,
    "the hysteretic tensile-branch slope kc"
);
param!(
    PHI_F,
    "phi_f",
    NUM,
    "",
    Required,
    Rule::LeftOpen(0.0, 1.0),
    "the hysteretic plasticity depth phi_f (paper 000 eq. 10)"
);
param!(
    FA,
    "fa",
    NUM,
    "N",
    Number(0.0),
    Rule::NonNegative,
    "the non-contact adhesive force fa (paper 000 eq. 14)"
);
param!(
    KCA,
    "kca",
    NumberOrInf,
    "N/m",
    Derived("kc, or inf when kc = 0"),
    Rule::PositiveOrInf,
    "the non-contact adhesive stiffness kc_a, inf = zero range (paper 000 eq. 14)"
);
param!(
    ADHESION,
    "adhesion",
    Choice(&["jump-in", "reversible"]),
    "",
    Word("jump-in"),
    Rule::None,
    "the non-contact adhesion on first approach (paper 000 eqs. 14-15)"
);
param!(
    K2_RULE,
    "k2_rule",
    Choice(&["linear", "sqrt"]),
    "",
    Word("linear"),
    Rule::None,
    "the k2(delta_max) interpolation (paper 000 eq. 9 or D.1)"
);
param!(
    GAMMA0,
    "gamma0",
    NUM,
    "kg/s",
    Number(0.0),
    Rule::NonNegative,
    "the viscous damping gamma0 (paper 000 eq. 2)"
);
// The linear spring-dashpot (paper 000 eq. 2).
param!(
    K,
    "k",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the LSD spring stiffness k"
);
// The JKR family (papers 001, 002).
param!(
    YOUNGS,
    "youngs",
    NUM,
    "Pa",
    Required,
    Rule::Positive,
    "Young's modulus E of the material"
);
param!(
    POISSON,
    "poisson",
    NUM,
    "",
    Required,
    Rule::Open(-1.0, 0.5),
    "the Poisson ratio"
);
param!(
    SURFACE_ENERGY,
    "surface_energy",
    NUM,
    "J/m^2",
    Required,
    Rule::NonNegative,
    "the surface energy gamma per surface (Fc = 3 pi gamma R*)"
);
param!(PULLOFF, "pulloff", Choice(&["displacement", "force", "zero"]), "", Word("displacement"), Rule::None, "where a stretched JKR contact breaks: at the turning point, at -Fc, or at zero overlap (paper 002)");
param!(
    STIFFNESS_SCALE,
    "stiffness_scale",
    NUM,
    "",
    Number(1.0),
    Rule::Positive,
    "the reduced stiffness S: E -> S E, gamma -> gamma S^(2/5) (paper 002 eq. 24)"
);
param!(
    FRICTION,
    "friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the (static) sliding friction coefficient mu_s, 0 = frictionless (jkr, hertz: paper 002 eqs. 14-17; hysteretic, lsd: Luding 2008)"
);
param!(ROLLING_HYSTERESIS, "rolling_hysteresis", NUM, "", Number(0.0), Rule::NonNegative, "the rolling resistance as adhesion hysteresis delta gamma / gamma, 0 = none (paper 002 eq. 18)");
// Luding's sliding, rolling and twisting friction (Luding 2008, docs/luding2008_laws.md;
// `model::friction`): hysteretic and lsd take all of them, jkr and hertz the twisting trio.
// Rolling and twisting act through the lever a12 = 2R* (2r against a wall).
param!(
    FRICTION_DYNAMIC,
    "friction_dynamic",
    NUM,
    "",
    Derived("friction (mu_d = mu_s)"),
    Rule::NonNegative,
    "the dynamic sliding friction coefficient mu_d <= mu_s, the force while slipping (Luding 2008)"
);
param!(
    KT,
    "kt",
    NUM,
    "N/m",
    Derived("2/7 k1 (hysteretic) or 2/7 k (lsd): the normal period"),
    Rule::Positive,
    "the tangential spring stiffness k_t (Luding 2008)"
);
param!(
    GAMMA_T,
    "gamma_t",
    NUM,
    "kg/s",
    Derived("2/7 gamma0"),
    Rule::NonNegative,
    "the tangential damping gamma_t (Luding 2008)"
);
param!(
    ROLLING_FRICTION,
    "rolling_friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the rolling friction coefficient mu_r, torque <= mu_r a12 f_N*; 0 = none (Luding 2008)"
);
param!(
    KR,
    "kr",
    NUM,
    "N/m",
    Derived("2/5 k1 (hysteretic) or 2/5 k (lsd)"),
    Rule::Positive,
    "the rolling spring stiffness k_r, torque stiffness k_r a12^2 per rad (Luding 2008)"
);
param!(
    GAMMA_R,
    "gamma_r",
    NUM,
    "kg/s",
    Derived("2/5 gamma0"),
    Rule::NonNegative,
    "the rolling damping gamma_r (Luding 2008)"
);
param!(
    TWISTING_FRICTION,
    "twisting_friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the twisting friction coefficient mu_o, torque <= mu_o a12 f_N*; 0 = none (Luding 2008)"
);
param!(
    KO,
    "ko",
    NUM,
    "N/m",
    Derived("2/5 k1 (hysteretic), 2/5 k (lsd), 2/5 * 8 G* a at the current contact radius a (jkr, hertz)"),
    Rule::Positive,
    "the twisting spring stiffness k_o, torque stiffness k_o a12^2 per rad (Luding 2008)"
);
param!(
    GAMMA_O,
    "gamma_o",
    NUM,
    "kg/s",
    Derived("2/5 gamma0 (hysteretic, lsd), 0 (jkr, hertz)"),
    Rule::NonNegative,
    "the twisting damping gamma_o (Luding 2008)"
);
// Normal dissipation of the JKR family, one sub-model at a time.
param!(
    DISSIPATION,
    "dissipation",
    Choice(&["none", "tsuji", "powerlaw", "krijt", "stress"]),
    "",
    Derived("tsuji when restitution is given, otherwise none"),
    Rule::None,
    "the normal dissipation model"
);
param!(
    RESTITUTION,
    "restitution",
    NUM,
    "",
    Required,
    Rule::LeftOpen(0.0, 1.0),
    "the target restitution e of dissipation = \"tsuji\" (paper 002 eq. 12)"
);
param!(TSUJI_STIFFNESS, "tsuji_stiffness", Choice(&["contact-radius", "hertz"]), "", Word("contact-radius"), Rule::None, "the stiffness of the Tsuji dashpots: \"contact-radius\" Sn = 2E* a, St = 8G* a (a the JKR contact radius, also at negative overlap) or \"hertz\" Sn = 2E* sqrt(R* delta), St = 8G* sqrt(R* delta), 0 at delta <= 0 (paper 002 eqs. 13-16)");
param!(
    POWER_D,
    "D",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the power-law dissipation coefficient D (paper 001 eq. 19)"
);
param!(
    POWER_ALPHA,
    "alpha",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the power-law velocity exponent alpha (paper 001 eq. 19)"
);
param!(
    POWER_BETA,
    "beta",
    NUM,
    "",
    Required,
    Rule::Finite,
    "the power-law contact-radius exponent beta (paper 001 eq. 19)"
);
param!(
    TVIS,
    "tvis",
    NUM,
    "s",
    Required,
    Rule::NonNegative,
    "the relaxation time T_vis of dissipation = \"krijt\" (paper 001 eq. 12)"
);
param!(SIGMA0, "sigma0", NUM, "Pa", Number(0.0), Rule::NonNegative, "the crack stress sigma0 ~ gamma / atomic spacing, 0 = a follows the JKR curve (paper 001 eq. B2)");
param!(
    TVIS0_PER_RADIUS,
    "tvis0_per_radius",
    NUM,
    "s/m",
    Required,
    Rule::NonNegative,
    "C of T_vis,0 = C*R of dissipation = \"stress\" (paper 001 eq. 18)"
);
param!(
    STRESS_B,
    "B",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the pressure coefficient B of dissipation = \"stress\" (paper 001 eq. 17)"
);
param!(
    STRESS_ZETA,
    "zeta",
    NUM,
    "",
    Required,
    Rule::Positive,
    "the pressure exponent zeta of dissipation = \"stress\" (paper 001 eq. 17)"
);

/// The normal contact laws, with the parameters each takes.
pub const LAWS: &[Law] = &[
    Law {
        name: "hysteretic",
        doc: "the hysteretic adhesive elasto-plastic model (paper 000 eqs. 5-15)",
        params: &[
            &K1,
            &KP,
            &KC,
            &PHI_F,
            &FA,
            &KCA,
            &ADHESION,
            &GAMMA0,
            &K2_RULE,
            &FRICTION,
            &FRICTION_DYNAMIC,
            &KT,
            &GAMMA_T,
            &ROLLING_FRICTION,
            &KR,
            &GAMMA_R,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: false,
    },
    Law {
        name: "lsd",
        doc: "the linear spring-dashpot (paper 000 eq. 2)",
        params: &[
            &K,
            &GAMMA0,
            &FRICTION,
            &FRICTION_DYNAMIC,
            &KT,
            &GAMMA_T,
            &ROLLING_FRICTION,
            &KR,
            &GAMMA_R,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: false,
    },
    Law {
        name: "jkr",
        doc: "JKR with damping, friction and rolling resistance (papers 001, 002)",
        params: &[
            &YOUNGS,
            &POISSON,
            &SURFACE_ENERGY,
            &DISSIPATION,
            &FRICTION,
            &ROLLING_HYSTERESIS,
            &PULLOFF,
            &STIFFNESS_SCALE,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: true,
    },
    Law {
        name: "hertz",
        doc: "Hertz (JKR without adhesion) with damping and friction",
        params: &[
            &YOUNGS,
            &POISSON,
            &DISSIPATION,
            &FRICTION,
            &STIFFNESS_SCALE,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: true,
    },
];

/// The normal dissipations of the JKR family, selected by `dissipation`.
pub const DISSIPATIONS: &[Law] = &[
    Law {
        name: "none",
        doc: "no dissipation beyond the JKR hysteresis",
        params: &[],
        dissipation: false,
    },
    Law {
        name: "tsuji",
        doc: "Tsuji damping calibrated by the restitution (paper 002 eqs. 11-13, 16)",
        params: &[&RESTITUTION, &TSUJI_STIFFNESS],
        dissipation: false,
    },
    Law {
        name: "powerlaw",
        doc: "power-law dissipation D E* |v|^alpha a^beta (paper 001 eq. 19)",
        params: &[&POWER_D, &POWER_ALPHA, &POWER_BETA],
        dissipation: false,
    },
    Law {
        name: "krijt",
        doc: "the Krijt viscoelastic contact radius (paper 001 eqs. 10-12, B1-B2)",
        params: &[&TVIS, &SIGMA0],
        dissipation: false,
    },
    Law {
        name: "stress",
        doc: "the stress-dependent Krijt model (paper 001 eqs. 17-18)",
        params: &[&TVIS0_PER_RADIUS, &STRESS_B, &STRESS_ZETA, &SIGMA0],
        dissipation: false,
    },
];

/// The law called `name`.
pub fn law(name: &str) -> Option<&'static Law> {
    LAWS.iter().find(|l| l.name == name)
}

/// The names of the normal laws.
pub fn law_names() -> Vec<&'static str> {
    LAWS.iter().map(|l| l.name).collect()
}

/// Every parameter of every law and sub-model, each once, in declaration order.
pub fn all_params() -> Vec<&'static Param> {
    let mut out: Vec<&'static Param> = Vec::new();
    for p in LAWS.iter().chain(DISSIPATIONS).flat_map(|l| l.params) {
        if !out.iter().any(|q| q.key == p.key) {
            out.push(p);
        }
    }
    out
}

/// The parameter called `key`.
pub fn param(key: &str) -> Option<&'static Param> {
    all_params().into_iter().find(|p| p.key == key)
}

/// The keys `law` accepts: its own and, where the dissipation axis applies, every
/// dissipation's.
pub fn keys_of(law: &Law) -> Vec<&'static str> {
    let mut keys: Vec<&'static str> = law.params.iter().map(|p| p.key).collect();
    if law.dissipation {
        for p in DISSIPATIONS.iter().flat_map(|d| d.params) {
            if !keys.contains(&p.key) {
                keys.push(p.key);
            }
        }
    }
    keys
}

/// The first law that takes `key`, for "is a parameter of the X model" hints.
pub fn owner_of(key: &str) -> Option<&'static str> {
    LAWS.iter()
        .find(|l| keys_of(l).contains(&key))
        .map(|l| l.name)
}

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
            values.given.push((p.key, typed(src, p, raw)?));
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
    // a sub-model that is off stays all zero: a frictionless model is the one of before
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
            2.0 / 7.0,
        ),
        rolling: spring(mu_r, mu_r, &KR, &GAMMA_R, 0.4),
        twisting: spring(mu_o, mu_o, &KO, &GAMMA_O, 0.4),
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
                adhesion: match v.word(&ADHESION) {
                    "reversible" => AdhesionMode::Reversible,
                    _ => AdhesionMode::JumpIn,
                },
                gamma0: v.num(&GAMMA0),
                k2_rule: match v.word(&K2_RULE) {
                    "sqrt" => K2Rule::Sqrt,
                    _ => K2Rule::Linear,
                },
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
                    stiffness: match v.word(&TSUJI_STIFFNESS) {
                        "hertz" => TsujiStiffness::Hertz,
                        _ => TsujiStiffness::ContactRadius,
                    },
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
                _ => Dissipation::None,
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
                pulloff: match v.word(&PULLOFF) {
                    "force" => Pulloff::Force,
                    "zero" => Pulloff::Zero,
                    _ => Pulloff::Displacement,
                },
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_every_key_is_declared_once_and_flags_are_unique() {
        let all = all_params();
        for (i, p) in all.iter().enumerate() {
            assert!(
                all[i + 1..].iter().all(|q| q.flag() != p.flag()),
                "{} twice",
                p.key
            );
            // the same key means the same declaration wherever it is used
            for l in LAWS.iter().chain(DISSIPATIONS) {
                for q in l.params.iter().filter(|q| q.key == p.key) {
                    assert_eq!(*q, *p, "{} declared twice differently", p.key);
                }
            }
            if let Word(w) = p.fallback {
                assert!(
                    matches!(p.kind, Kind::Choice(o) if o.contains(&w)),
                    "{}",
                    p.key
                );
            }
        }
        // the dissipation choice lists exactly the declared dissipations
        let Kind::Choice(names) = DISSIPATION.kind else {
            panic!()
        };
        let declared: Vec<&str> = DISSIPATIONS.iter().map(|d| d.name).collect();
        assert_eq!(names, declared.as_slice());
    }

    #[test]
    fn params_rules_name_the_key_and_the_rule() {
        assert!(PHI_F.check(1.0).is_ok());
        let e = PHI_F.check(0.0).unwrap_err();
        assert_eq!(e.param, "phi_f");
        assert!(e.message.contains("(0, 1]"), "{e}");
        assert!(POISSON.check(0.5).is_err() && POISSON.check(-0.99).is_ok());
        assert!(K1.check(f64::INFINITY).is_err() && K1.check(f64::NAN).is_err());
        assert!(KCA.check(f64::INFINITY).is_ok() && KCA.check(0.0).is_err());
        assert!(KCA.check(f64::NAN).is_err());
        assert!(POWER_BETA.check(-3.0).is_ok() && POWER_BETA.check(f64::NAN).is_err());
    }
}
