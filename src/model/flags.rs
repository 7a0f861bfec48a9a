//! Command-line flags for the contact laws, generated from the declarations of
//! [`super::params`]: `--model` and one flag per parameter ([`LawArgs`]), read by the same
//! [`params::read_model`] as scene tables; and the flags of a fixed list of declared
//! parameters outside a contact law ([`ParamArgs`], e.g. `powder analytic`).

use super::params::{self, Fallback, Kind, Law, Param, ParamSource, Raw};
use super::ContactModel;
use crate::error::{ParamError, PowderError};
use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::{Arg, ArgMatches, Args, Command, FromArgMatches};
use std::marker::PhantomData;

/// `--model` and the parameter flags as given on the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LawArgs {
    /// The normal law (`--model`).
    pub model: String,
    /// The parameter flags given, by key, as typed.
    pub given: Vec<(&'static str, String)>,
}

impl LawArgs {
    /// The contact model these flags describe, validated; errors name the flag.
    pub fn contact_model(&self) -> Result<ContactModel, PowderError> {
        let flags = Flags {
            given: &self.given,
            model: Some(&self.model),
        };
        params::read_model(&flags, &self.model)
    }
}

/// The help line of one parameter: doc, unit, which laws take it, its default.
fn help(p: &Param) -> String {
    let laws: Vec<&str> = params::LAWS
        .iter()
        .filter(|l| params::keys_of(l).contains(&p.key))
        .map(|l| l.name)
        .collect();
    help_line(p, Some(&laws))
}

/// The help line of one parameter: doc, `[laws]` when given, unit, default.
fn help_line(p: &Param, laws: Option<&[&str]>) -> String {
    let mut s = capitalised(p.doc);
    if let Some(laws) = laws {
        s.push_str(&format!(" [{}]", laws.join(", ")));
    }
    if !p.unit.is_empty() {
        s.push_str(&format!(", {}", p.unit));
    }
    if let Some(rule) = p.rule_text() {
        s.push_str(&format!(", {rule}"));
    }
    match p.fallback {
        Fallback::Required => {}
        Fallback::Number(x) => s.push_str(&format!("; default {x}")),
        Fallback::Word(w) => s.push_str(&format!("; default {w}")),
        Fallback::Derived(text) => s.push_str(&format!("; default {text}")),
    }
    s
}

fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

impl Args for LawArgs {
    fn augment_args(cmd: Command) -> Command {
        let models = params::LAWS
            .iter()
            .map(|l| PossibleValue::new(l.name).help(l.doc));
        let mut cmd = cmd.arg(
            Arg::new("model")
                .long("model")
                .required(true)
                .help("The normal contact law")
                .value_parser(PossibleValuesParser::new(models)),
        );
        for p in params::all_params() {
            cmd = cmd.arg(flag_arg(p).help(help(p)));
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for LawArgs {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut out = Self::default();
        out.update_from_arg_matches(m)?;
        Ok(out)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        if let Ok(Some(model)) = m.try_get_one::<String>("model") {
            self.model = model.clone();
        }
        update_given(&mut self.given, &params::all_params(), m);
        Ok(())
    }
}

/// The flag of one declared parameter (`--` + key with `_` → `-`, id = the key): a value
/// name from the unit, the choices of a [`Kind::Choice`]; the value is kept as typed and
/// typed against the declaration later (so its errors name the flag and the rule).
fn flag_arg(p: &'static Param) -> Arg {
    let arg = Arg::new(p.key).long(p.flag()).allow_negative_numbers(true);
    match p.kind {
        Kind::Choice(options) => arg.value_parser(PossibleValuesParser::new(options)),
        _ if p.unit.is_empty() => arg.value_name("X"),
        _ => arg.value_name(p.unit),
    }
}

/// Records the flags of `list` given in `m`, as typed, by key.
fn update_given(given: &mut Vec<(&'static str, String)>, list: &[&'static Param], m: &ArgMatches) {
    for p in list {
        if let Ok(Some(v)) = m.try_get_one::<String>(p.key) {
            given.retain(|(k, _)| *k != p.key);
            given.push((p.key, v.clone()));
        }
    }
}

/// A flag's text as a declaration's raw value: a number where it parses as one.
fn raw_of(given: &[(&'static str, String)], key: &str) -> Option<Raw> {
    let (_, v) = given.iter().find(|(k, _)| *k == key)?;
    Some(match v.trim().parse::<f64>() {
        Ok(x) => Raw::Number(x),
        Err(_) => Raw::Text(v.clone()),
    })
}

fn flag(key: &str) -> String {
    format!("--{}", key.replace('_', "-"))
}

fn static_key(key: &str) -> &'static str {
    params::param(key).map_or("model", |p| p.key)
}

/// Flags given on the command line as a source of declared parameters: for a contact
/// law (`--model`, [`LawArgs`]) or a command's own list ([`ParamArgs`]); errors name the
/// flag.
struct Flags<'a> {
    given: &'a [(&'static str, String)],
    /// The `--model` the flags are read for, if any.
    model: Option<&'a str>,
}

impl ParamSource for Flags<'_> {
    type Error = PowderError;

    fn keys(&self) -> Vec<String> {
        self.given.iter().map(|(k, _)| k.to_string()).collect()
    }

    fn raw(&self, key: &str) -> Option<Raw> {
        raw_of(self.given, key)
    }

    fn name(&self, key: &str) -> String {
        flag(key)
    }

    fn setting(&self, key: &str, value: &str) -> String {
        format!("{} {value}", flag(key))
    }

    fn error(&self, key: &str, message: String) -> PowderError {
        ParamError::new(static_key(key), message).into()
    }

    fn missing(&self, key: &str, what: &str) -> PowderError {
        let place = match self.model {
            Some(m) => format!("for --model {m}"),
            None => "here".to_string(),
        };
        ParamError::new(
            static_key(key),
            format!("{} is required {place}: {what}", flag(key)),
        )
        .into()
    }

    fn unknown(&self, key: &str, law: &Law, owner: Option<&str>) -> PowderError {
        let message = match self.model {
            Some(_) => {
                let hint = owner.map_or(String::new(), |m| {
                    format!(" (it is a parameter of --model {m})")
                });
                format!("{} does not apply to --model {}{hint}", flag(key), law.name)
            }
            None => format!("{} does not apply here", flag(key)),
        };
        ParamError::new(static_key(key), message).into()
    }

    fn invalid(&self, e: ParamError) -> PowderError {
        e.into()
    }
}

/// A fixed list of declared parameters that a command takes as flags outside a contact
/// law (see [`ParamArgs`]).
pub trait ParamSet {
    /// The parameters, in the order of the help.
    const PARAMS: &'static [&'static Param];

    /// Adjusts the generated flag of `p` (e.g. `requires` another flag). The default: a
    /// parameter without a fallback is a required flag.
    fn adjust(arg: Arg, p: &'static Param) -> Arg {
        arg.required(p.fallback == Fallback::Required)
    }
}

/// The flags of the parameters `S::PARAMS`, generated from their declarations in
/// [`params`] (flag, help, unit, choices, default), as [`LawArgs`] does for the contact
/// laws; the values are typed and checked against the declared rules when read
/// ([`Self::number`], [`Self::word`]), so the errors name the flag and the rule.
/// `#[command(flatten)]` it into a clap command.
pub struct ParamArgs<S> {
    given: Vec<(&'static str, String)>,
    set: PhantomData<fn() -> S>,
}

impl<S> Default for ParamArgs<S> {
    fn default() -> Self {
        Self {
            given: Vec::new(),
            set: PhantomData,
        }
    }
}

impl<S> Clone for ParamArgs<S> {
    fn clone(&self) -> Self {
        Self {
            given: self.given.clone(),
            set: PhantomData,
        }
    }
}

impl<S> std::fmt::Debug for ParamArgs<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParamArgs")
            .field("given", &self.given)
            .finish()
    }
}

impl<S: ParamSet> ParamArgs<S> {
    /// The typed value of `p` (one of `S::PARAMS`): the one given or the declared default,
    /// `None` when neither.
    fn value(&self, p: &'static Param) -> Result<Option<params::Value>, PowderError> {
        debug_assert!(S::PARAMS.iter().any(|q| q.key == p.key), "{}", p.key);
        params::read_value(&self.flags(), p)
    }

    fn flags(&self) -> Flags<'_> {
        Flags {
            given: &self.given,
            model: None,
        }
    }

    /// The number given for `p` or its declared default, checked against its rule; `None`
    /// when neither (an optional flag not given).
    pub fn get(&self, p: &'static Param) -> Result<Option<f64>, PowderError> {
        match self.value(p)? {
            Some(params::Value::Number(x)) => Ok(Some(x)),
            Some(params::Value::Word(w)) => Err(self.flags().error(
                p.key,
                format!("{} must be a number, got \"{w}\"", flag(p.key)),
            )),
            None => Ok(None),
        }
    }

    /// The number given for `p` or its declared default, checked against its rule; an
    /// error naming the flag when neither.
    pub fn number(&self, p: &'static Param) -> Result<f64, PowderError> {
        self.get(p)?
            .ok_or_else(|| self.flags().missing(p.key, &p.what()))
    }

    /// The word given for `p` (a [`Kind::Choice`]) or its declared default.
    pub fn word(&self, p: &'static Param) -> Result<&'static str, PowderError> {
        match self.value(p)? {
            Some(params::Value::Word(w)) => Ok(w),
            _ => Err(self.flags().missing(p.key, &p.what())),
        }
    }
}

impl<S: ParamSet> Args for ParamArgs<S> {
    fn augment_args(mut cmd: Command) -> Command {
        for p in S::PARAMS {
            cmd = cmd.arg(S::adjust(flag_arg(p).help(help_line(p, None)), p));
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl<S: ParamSet> FromArgMatches for ParamArgs<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut out = Self::default();
        out.update_from_arg_matches(m)?;
        Ok(out)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        update_given(&mut self.given, S::PARAMS, m);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    #[command(allow_negative_numbers = true)]
    struct Cli {
        #[command(flatten)]
        law: LawArgs,
    }

    fn model(args: &[&str]) -> Result<ContactModel, String> {
        let cli = Cli::try_parse_from(std::iter::once("t").chain(args.iter().copied()))
            .map_err(|e| e.to_string())?;
        cli.law.contact_model().map_err(|e| e.to_string())
    }

    #[test]
    fn flags_build_the_same_model_as_a_scene_table() {
        let m = model(&[
            "--model",
            "hysteretic",
            "--k1",
            "100",
            "--kp",
            "500",
            "--kc",
            "100",
            "--phi-f",
            "0.05",
            "--fa",
            "1e-3",
        ])
        .unwrap();
        let ContactModel::Hysteretic(h) = m else {
            panic!("{m:?}")
        };
        assert_eq!(
            (h.k1, h.kp, h.kc, h.phi_f, h.fa),
            (100.0, 500.0, 100.0, 0.05, 1e-3)
        );
        // kca defaults to kc (the declaration's derived default)
        assert_eq!(h.kca, 100.0);
        let m = model(&[
            "--model",
            "jkr",
            "--youngs",
            "1e9",
            "--poisson",
            "0.3",
            "--surface-energy",
            "0.1",
            "--dissipation",
            "powerlaw",
            "--D",
            "0.5",
            "--alpha",
            "1",
            "--beta",
            "2",
        ])
        .unwrap();
        let ContactModel::Jkr(j) = m else {
            panic!("{m:?}")
        };
        assert_eq!(
            j.dissipation,
            super::super::Dissipation::PowerLaw {
                d: 0.5,
                alpha: 1.0,
                beta: 2.0
            }
        );
        assert_eq!((j.youngs, j.stiffness_scale, j.friction), (1e9, 1.0, 0.0));
        // --restitution alone selects the Tsuji dissipation
        let m = model(&[
            "--model",
            "hertz",
            "--youngs",
            "1e9",
            "--poisson",
            "0.3",
            "--restitution",
            "0.5",
        ])
        .unwrap();
        let ContactModel::Jkr(j) = m else {
            panic!("{m:?}")
        };
        assert_eq!(j.dissipation, super::super::Dissipation::tsuji(0.5));
        assert_eq!(j.surface_energy, 0.0);
        // paper 002's stiffness of the Tsuji dashpots
        let m = model(&[
            "--model",
            "jkr",
            "--youngs",
            "1e9",
            "--poisson",
            "0.3",
            "--surface-energy",
            "0.1",
            "--restitution",
            "0.5",
            "--tsuji-stiffness",
            "hertz",
        ])
        .unwrap();
        let ContactModel::Jkr(j) = m else {
            panic!("{m:?}")
        };
        assert_eq!(
            j.dissipation,
            super::super::Dissipation::Tsuji {
                restitution: 0.5,
                stiffness: super::super::TsujiStiffness::Hertz
            }
        );
    }

    struct Pair;

    impl ParamSet for Pair {
        const PARAMS: &'static [&'static Param] =
            &[&params::K1, &params::PHI_F, &params::KCA, &params::PULLOFF];
    }

    #[derive(Parser)]
    struct Analytic {
        #[command(flatten)]
        law: ParamArgs<Pair>,
    }

    fn analytic(args: &[&str]) -> Result<ParamArgs<Pair>, String> {
        Analytic::try_parse_from(std::iter::once("t").chain(args.iter().copied()))
            .map(|a| a.law)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn declared_flags_outside_a_law_come_from_the_declarations() {
        // flag, unit, rule and default in the help, from the declaration
        let mut cmd = Analytic::command();
        let help = cmd.render_long_help().to_string();
        for text in [
            "--k1 <N/m>",
            "The hysteretic loading stiffness k1, N/m, > 0",
            "--phi-f <X>",
            "in (0, 1]",
            "--kca <N/m>",
            "default kc, or inf when kc = 0",
            "default displacement",
        ] {
            assert!(help.contains(text), "`{text}` missing in {help}");
        }
        // required where the declaration has no fallback
        let e = analytic(&["--phi-f", "0.5"]).unwrap_err();
        assert!(e.contains("--k1"), "{e}");
        let a = analytic(&["--k1", "100", "--phi-f", "0.5", "--kca", "inf"]).unwrap();
        assert_eq!(a.number(&params::K1).unwrap(), 100.0);
        assert_eq!(a.number(&params::KCA).unwrap(), f64::INFINITY);
        assert_eq!(a.word(&params::PULLOFF).unwrap(), "displacement");
        // typed and checked against the declared rule when read, naming the flag or key
        let a = analytic(&["--k1", "stiff", "--phi-f", "1.5"]).unwrap();
        let e = a.number(&params::K1).unwrap_err().to_string();
        assert!(e.contains("--k1 must be a number"), "{e}");
        let e = a.number(&params::PHI_F).unwrap_err().to_string();
        assert!(e.contains("`phi_f`") && e.contains("(0, 1]"), "{e}");
        let a = analytic(&["--k1", "-1", "--phi-f", "1", "--pulloff", "zero"]).unwrap();
        assert!(a
            .number(&params::K1)
            .unwrap_err()
            .to_string()
            .contains("> 0"));
        assert_eq!(a.word(&params::PULLOFF).unwrap(), "zero");
        // a derived default is the caller's: absent
        assert_eq!(
            analytic(&["--k1", "1", "--phi-f", "1"])
                .unwrap()
                .get(&params::KCA)
                .unwrap(),
            None
        );
        assert!(analytic(&["--k1", "1", "--phi-f", "1", "--pulloff", "sideways"]).is_err());
    }

    /// Luding's friction: `--friction μ` alone sets μs = μd, the stiffnesses and dampings
    /// follow k1 (k) and γ0; a sub-model that is off stays all zero; JKR takes twisting only.
    #[test]
    fn luding_friction_flags_and_their_derived_defaults() {
        use crate::model::CoulombSpring;
        let hyst = |extra: &[&str]| {
            let mut args = vec![
                "--model",
                "hysteretic",
                "--k1",
                "100",
                "--kp",
                "500",
                "--kc",
                "10",
                "--phi-f",
                "0.05",
                "--gamma0",
                "1e-3",
            ];
            args.extend_from_slice(extra);
            model(&args)
        };
        let ContactModel::Hysteretic(h) = hyst(&["--friction", "0.4"]).unwrap() else {
            panic!()
        };
        let s = h.luding.sliding;
        assert_eq!((s.mu_s, s.mu_d), (0.4, 0.4));
        assert!((s.k - 200.0 / 7.0).abs() < 1e-12 && (s.gamma - 2e-3 / 7.0).abs() < 1e-18);
        assert_eq!(h.luding.rolling, CoulombSpring::default());
        assert_eq!(h.luding.twisting, CoulombSpring::default());
        let m = hyst(&[
            "--friction",
            "0.4",
            "--friction-dynamic",
            "0.3",
            "--rolling-friction",
            "0.1",
            "--twisting-friction",
            "0.05",
            "--ko",
            "7",
        ])
        .unwrap();
        let ContactModel::Hysteretic(h) = m else {
            panic!()
        };
        assert_eq!((h.luding.sliding.mu_s, h.luding.sliding.mu_d), (0.4, 0.3));
        let r = h.luding.rolling;
        assert_eq!((r.mu_s, r.mu_d, r.k), (0.1, 0.1, 40.0));
        assert!((r.gamma - 4e-4).abs() < 1e-18);
        let o = h.luding.twisting;
        assert_eq!((o.mu_s, o.k), (0.05, 7.0));
        assert!(m.needs_rotation());
        // LSD: from k
        let ContactModel::Lsd(l) =
            model(&["--model", "lsd", "--k", "350", "--rolling-friction", "0.2"]).unwrap()
        else {
            panic!()
        };
        assert_eq!(l.luding.rolling.k, 140.0);
        assert!(!l.luding.sliding.is_on());
        // JKR/Hertz: twisting only, the Mindlin-derived stiffness (0) and no damping by default
        let jkr = |extra: &[&str]| {
            let mut args = vec!["--model", "hertz", "--youngs", "1e9", "--poisson", "0.3"];
            args.extend_from_slice(extra);
            model(&args)
        };
        let ContactModel::Jkr(j) = jkr(&["--twisting-friction", "0.1"]).unwrap() else {
            panic!()
        };
        let o = j.luding.twisting;
        assert_eq!((o.mu_s, o.mu_d, o.k, o.gamma), (0.1, 0.1, 0.0, 0.0));
        assert!((j.twisting_stiffness(1e-6) - 3.2 * j.g_star() * 1e-6).abs() < 1e-9);
        // refused: a sub-model's parameters without its coefficient, mu_d > mu_s, and the
        // Luding sliding/rolling keys for the JKR family
        let e = hyst(&["--kt", "10"]).unwrap_err();
        assert!(e.contains("kt is given but friction = 0"), "{e}");
        let e = hyst(&["--friction", "0.3", "--gamma-r", "1e-3"]).unwrap_err();
        assert!(
            e.contains("gamma_r is given but rolling_friction = 0"),
            "{e}"
        );
        let e = jkr(&["--ko", "1e3"]).unwrap_err();
        assert!(e.contains("ko is given but twisting_friction = 0"), "{e}");
        let e = hyst(&["--friction", "0.3", "--friction-dynamic", "0.4"]).unwrap_err();
        assert!(e.contains("must be <= friction"), "{e}");
        let e = jkr(&["--friction", "0.3", "--kt", "5"]).unwrap_err();
        assert!(e.contains("--kt does not apply to --model hertz"), "{e}");
        let e = jkr(&["--rolling-friction", "0.1"]).unwrap_err();
        assert!(e.contains("does not apply to --model hertz"), "{e}");
        let e = hyst(&["--twisting-friction", "0.1", "--ko", "0"]).unwrap_err();
        assert!(e.contains("ko") && e.contains("> 0"), "{e}");
    }

    #[test]
    fn flags_errors_name_the_flag_and_the_rule() {
        let e = model(&[
            "--model",
            "hysteretic",
            "--kp",
            "500",
            "--kc",
            "1",
            "--phi-f",
            "0.1",
        ])
        .unwrap_err();
        assert!(e.contains("--k1 is required for --model hysteretic"), "{e}");
        let e = model(&["--model", "lsd", "--k", "1", "--kp", "5"]).unwrap_err();
        assert!(e.contains("--kp does not apply to --model lsd"), "{e}");
        assert!(e.contains("hysteretic"), "{e}");
        let e = model(&[
            "--model",
            "jkr",
            "--youngs",
            "1e9",
            "--poisson",
            "0.3",
            "--surface-energy",
            "0.1",
            "--tvis",
            "1e-9",
        ])
        .unwrap_err();
        assert!(
            e.contains("--tvis applies to --dissipation krijt only"),
            "{e}"
        );
        // a parameter of the tsuji dissipation only
        let e = model(&[
            "--model",
            "hertz",
            "--youngs",
            "1e9",
            "--poisson",
            "0.3",
            "--tsuji-stiffness",
            "hertz",
        ])
        .unwrap_err();
        assert!(
            e.contains("--tsuji-stiffness applies to --dissipation tsuji only"),
            "{e}"
        );
        let e = model(&["--model", "lsd", "--k", "stiff"]).unwrap_err();
        assert!(e.contains("--k must be a number"), "{e}");
        let e = model(&["--model", "lsd", "--k", "-1"]).unwrap_err();
        assert!(e.contains("must be > 0"), "{e}");
    }
}
