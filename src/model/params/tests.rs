//! The declarations' own tests: keys unique, rules and defaults as declared.

use super::*;
use Fallback::Word;

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
    assert!(POWER_BETA.check(-3.0).is_err() && POWER_BETA.check(f64::NAN).is_err());
}

/// Values given as a front end would, for reading laws in tests.
struct Given(Vec<(&'static str, Raw)>);

impl ParamSource for Given {
    type Error = String;
    fn keys(&self) -> Vec<String> {
        self.0.iter().map(|(k, _)| k.to_string()).collect()
    }
    fn raw(&self, key: &str) -> Option<Raw> {
        self.0
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.clone())
    }
    fn name(&self, key: &str) -> String {
        key.to_string()
    }
    fn setting(&self, key: &str, value: &str) -> String {
        format!("{key} = {value}")
    }
    fn error(&self, key: &str, message: String) -> String {
        format!("{key}: {message}")
    }
    fn missing(&self, key: &str, what: &str) -> String {
        format!("{key} missing ({what})")
    }
    fn unknown(&self, key: &str, law: &Law, _: Option<&str>) -> String {
        format!("{key} unknown to {}", law.name)
    }
    fn invalid(&self, e: ParamError) -> String {
        e.to_string()
    }
}

/// A value that `p`'s rule accepts.
fn sample(p: &Param) -> Raw {
    match (p.kind, p.rule) {
        (Kind::Choice(words), _) => Raw::Text(words[0].to_string()),
        (_, Rule::LeftOpen(lo, hi) | Rule::Open(lo, hi) | Rule::Closed(lo, hi)) => {
            Raw::Number(0.5 * (lo + hi))
        }
        _ => Raw::Number(0.5),
    }
}

/// The required parameters of `law`, sampled.
fn required(law: &Law) -> Vec<(&'static str, Raw)> {
    (law.params.iter())
        .filter(|p| p.fallback == Fallback::Required)
        .map(|p| (p.key, sample(p)))
        .collect()
}

/// Every declared law and every declared dissipation reads into the model it names, and
/// every word of every choice reads (each choice's words name its enum's variants).
#[test]
fn params_every_law_dissipation_and_word_reads_into_what_it_names() {
    for law in LAWS {
        let mut given = required(law);
        if law.params.contains(&&SURFACE_ENERGY) {
            given.push((SURFACE_ENERGY.key, Raw::Number(0.1)));
        }
        let model = read_model(&Given(given.clone()), law.name).unwrap();
        assert_eq!(model.law_name(), law.name);
        for p in law.params {
            let Kind::Choice(words) = p.kind else {
                continue;
            };
            for w in words {
                let mut with = given.clone();
                with.push((p.key, Raw::Text(w.to_string())));
                // a dissipation's own parameters come with it
                if let Some(d) = DISSIPATIONS
                    .iter()
                    .find(|d| p.key == DISSIPATION.key && d.name == *w)
                {
                    with.extend(required(d));
                }
                // the crack pull-off comes with a Krijt dissipation
                if p.key == PULLOFF.key && *w == Pulloff::Crack.word() {
                    let krijt = DISSIPATIONS.iter().find(|d| d.name == "krijt").unwrap();
                    with.push((DISSIPATION.key, Raw::Text(krijt.name.to_string())));
                    with.extend(required(krijt));
                }
                let read = read_model(&Given(with), law.name);
                // the Krijt laws' crack speed needs adhesion
                if law.name == "hertz" && ["krijt", "stress", "crack"].contains(w) {
                    assert!(read.unwrap_err().contains("surface_energy > 0"));
                    continue;
                }
                let m = read.unwrap_or_else(|e| panic!("{} {} = {w}: {e}", law.name, p.key));
                if let (ContactModel::Jkr(j), true) = (&m, p.key == DISSIPATION.key) {
                    assert_eq!(j.dissipation.name(), *w);
                }
            }
        }
    }
}

/// The word enums read and write their words, as serde and clap do.
#[test]
fn params_word_enums_agree_with_serde_and_clap() {
    fn check<T>(words: &[&str], from: fn(&str) -> Option<T>, word: fn(T) -> &'static str)
    where
        T: Copy + PartialEq + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned,
    {
        for w in words {
            let v = from(w).unwrap_or_else(|| panic!("{w}"));
            assert_eq!(word(v), *w);
            assert_eq!(serde_json::to_string(&v).unwrap(), format!("\"{w}\""));
            assert_eq!(serde_json::from_str::<T>(&format!("\"{w}\"")).unwrap(), v);
        }
        assert!(from("no-such-word").is_none());
    }
    check(K2Rule::WORDS, K2Rule::from_word, K2Rule::word);
    check(
        AdhesionMode::WORDS,
        AdhesionMode::from_word,
        AdhesionMode::word,
    );
    check(Pulloff::WORDS, Pulloff::from_word, Pulloff::word);
    check(
        TsujiStiffness::WORDS,
        TsujiStiffness::from_word,
        TsujiStiffness::word,
    );
    fn clap_words<T: clap::ValueEnum>() -> Vec<String> {
        (T::value_variants().iter())
            .map(|v| v.to_possible_value().unwrap().get_name().to_string())
            .collect()
    }
    assert_eq!(clap_words::<K2Rule>(), K2Rule::WORDS);
    assert_eq!(clap_words::<AdhesionMode>(), AdhesionMode::WORDS);
    assert_eq!(clap_words::<Pulloff>(), Pulloff::WORDS);
}

/// docs/parameters.md is the reference the declarations generate.
#[test]
fn the_parameter_reference_is_current() {
    let file = include_str!("../../../docs/parameters.md");
    assert!(
        file == super::reference::markdown(),
        "docs/parameters.md is out of date: `cargo run --release -- params > docs/parameters.md`"
    );
    for p in super::all_params() {
        assert!(file.contains(&format!("| `{}` |", p.key)), "{}", p.key);
    }
}
