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
    /// lo ≤ x ≤ hi.
    Closed(f64, f64),
    /// > 0, or infinite.
    PositiveOrInf,
    /// Checked with the other parameters by the model.
    None,
}

impl Rule {
    /// The rule in words ("> 0", "in (0, 1]"); `None` for [`Rule::None`] and [`Rule::Finite`].
    pub fn text(&self) -> Option<String> {
        match self {
            Rule::None | Rule::Finite => None,
            Rule::PositiveOrInf => Some("> 0 (inf for none)".to_string()),
            Rule::Positive => Some("> 0".to_string()),
            Rule::NonNegative => Some(">= 0".to_string()),
            Rule::LeftOpen(lo, hi) => Some(format!("in ({lo}, {hi}]")),
            Rule::Open(lo, hi) => Some(format!("in ({lo}, {hi})")),
            Rule::Closed(lo, hi) => Some(format!("in [{lo}, {hi}]")),
        }
    }

    /// Whether `value` obeys the rule ([`Rule::None`]: always).
    pub fn holds(&self, value: f64) -> bool {
        match self {
            Rule::None => true,
            Rule::PositiveOrInf => value > 0.0,
            _ if !value.is_finite() => false,
            Rule::Finite => true,
            Rule::Positive => value > 0.0,
            Rule::NonNegative => value >= 0.0,
            Rule::LeftOpen(lo, hi) => value > *lo && value <= *hi,
            Rule::Open(lo, hi) => value > *lo && value < *hi,
            Rule::Closed(lo, hi) => value >= *lo && value <= *hi,
        }
    }

    /// What a value that breaks the rule must be instead, in words ("> 0", "a finite
    /// number").
    pub fn requirement(&self, value: f64) -> String {
        match self {
            Rule::PositiveOrInf => self.text().unwrap_or_default(),
            _ if !value.is_finite() => "a finite number".to_string(),
            _ => self.text().unwrap_or_default(),
        }
    }
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
        self.rule.text()
    }

    /// Checks `value` against the rule; the error names the key and the rule.
    pub fn check(&self, value: f64) -> Result<(), ParamError> {
        let ok = self.rule.holds(value);
        let rule = self.rule.requirement(value);
        if ok {
            Ok(())
        } else {
            Err(ParamError::new(
                self.key,
                format!(
                    "{} ({}) must be {rule}, got {}",
                    self.key,
                    self.doc,
                    crate::error::num(value)
                ),
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

mod declared;
mod read;
pub mod reference;
#[cfg(test)]
mod tests;
mod words;

pub(crate) use words::word_enum;

pub use declared::*;
pub use read::{read_model, read_value, ParamSource, Raw, Value};

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
