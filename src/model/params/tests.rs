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
    assert!(POWER_BETA.check(-3.0).is_ok() && POWER_BETA.check(f64::NAN).is_err());
}
