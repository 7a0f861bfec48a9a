//! Command-line flags for the contact laws, generated from the declarations of
//! [`super::params`]: `--model` and one flag per parameter, read by the same
//! [`params::read_model`] as scene tables.

use super::params::{self, Fallback, Kind, Law, Param, ParamSource, Raw};
use super::ContactModel;
use crate::error::{ParamError, PowderError};
use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::{Arg, ArgMatches, Args, Command, FromArgMatches};

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
        params::read_model(self, &self.model)
    }
}

/// The help line of one parameter: doc, unit, which laws take it, its default.
fn help(p: &Param) -> String {
    let laws: Vec<&str> = params::LAWS
        .iter()
        .filter(|l| params::keys_of(l).contains(&p.key))
        .map(|l| l.name)
        .collect();
    let mut s = format!("{} [{}]", capitalised(p.doc), laws.join(", "));
    if !p.unit.is_empty() {
        s.push_str(&format!(", {}", p.unit));
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
            let mut arg = Arg::new(p.key)
                .long(p.flag())
                .help(help(p))
                .allow_negative_numbers(true);
            arg = match p.kind {
                Kind::Choice(options) => arg.value_parser(PossibleValuesParser::new(options)),
                _ if p.unit.is_empty() => arg.value_name("X"),
                _ => arg.value_name(p.unit),
            };
            cmd = cmd.arg(arg);
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
        for p in params::all_params() {
            if let Ok(Some(v)) = m.try_get_one::<String>(p.key) {
                self.given.retain(|(k, _)| *k != p.key);
                self.given.push((p.key, v.clone()));
            }
        }
        Ok(())
    }
}

fn flag(key: &str) -> String {
    format!("--{}", key.replace('_', "-"))
}

fn static_key(key: &str) -> &'static str {
    params::param(key).map_or("model", |p| p.key)
}

impl ParamSource for LawArgs {
    type Error = PowderError;

    fn keys(&self) -> Vec<String> {
        self.given.iter().map(|(k, _)| k.to_string()).collect()
    }

    fn raw(&self, key: &str) -> Option<Raw> {
        let (_, v) = self.given.iter().find(|(k, _)| *k == key)?;
        Some(match v.trim().parse::<f64>() {
            Ok(x) => Raw::Number(x),
            Err(_) => Raw::Text(v.clone()),
        })
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
        ParamError::new(
            static_key(key),
            format!(
                "{} is required for --model {}: {what}",
                flag(key),
                self.model
            ),
        )
        .into()
    }

    fn unknown(&self, key: &str, law: &Law, owner: Option<&str>) -> PowderError {
        let hint = owner.map_or(String::new(), |m| {
            format!(" (it is a parameter of --model {m})")
        });
        ParamError::new(
            static_key(key),
            format!("{} does not apply to --model {}{hint}", flag(key), law.name),
        )
        .into()
    }

    fn invalid(&self, e: ParamError) -> PowderError {
        e.into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

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
        assert_eq!(
            j.dissipation,
            super::super::Dissipation::Tsuji { restitution: 0.5 }
        );
        assert_eq!(j.surface_energy, 0.0);
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
        let e = model(&["--model", "lsd", "--k", "stiff"]).unwrap_err();
        assert!(e.contains("--k must be a number"), "{e}");
        let e = model(&["--model", "lsd", "--k", "-1"]).unwrap_err();
        assert!(e.contains("must be > 0"), "{e}");
    }
}
