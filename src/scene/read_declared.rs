//! Reading a number by its declaration (`declared.rs`): the rule it is checked against and
//! the words its errors use come from there.

use super::declared::{declared, default_number, SceneKey, Section};
use super::toml_reader::{Res, Tbl, Val};

impl Tbl<'_> {
    /// `key` of `section`, checked against its declared rule, if present.
    pub(super) fn number(&self, section: Section, key: &str) -> Res<Option<f64>> {
        let k = declared(section, key);
        let x = self.f64(key)?;
        match x {
            Some(x) if !k.rule.holds(x) => Err(self.broken(k, x)),
            other => Ok(other),
        }
    }

    /// [`Self::number`], required.
    pub(super) fn number_req(&self, section: Section, key: &str) -> Res<f64> {
        self.number(section, key)?
            .ok_or_else(|| self.missing(key, &declared(section, key).what()))
    }

    /// `key` of `section`, a non-negative integer checked against its declared rule, if
    /// present.
    pub(super) fn count(&self, section: Section, key: &str) -> Res<Option<u64>> {
        let k = declared(section, key);
        // (a negative integer breaks the rule, which says more than "non-negative integer")
        if let Some(Val::Int(i)) = self.get(key).map(|n| &n.val) {
            if *i < 0 && !k.rule.holds(*i as f64) {
                return Err(self.broken(k, *i as f64));
            }
        }
        match self.u64(key)? {
            Some(n) if !k.rule.holds(n as f64) => Err(self.broken(k, n as f64)),
            other => Ok(other),
        }
    }

    /// [`Self::number`], or its declared number when absent.
    pub(super) fn number_or_default(&self, section: Section, key: &str) -> Res<f64> {
        Ok(self
            .number(section, key)?
            .unwrap_or_else(|| default_number(section, key)))
    }

    /// [`Self::count`], or its declared number when absent.
    pub(super) fn count_or_default(&self, section: Section, key: &str) -> Res<u64> {
        Ok(self
            .count(section, key)?
            .unwrap_or_else(|| default_number(section, key) as u64))
    }

    /// The error for `x` breaking `k`'s rule, at the key.
    fn broken(&self, k: &SceneKey, x: f64) -> super::PowderError {
        self.err_key(k.key, k.broken(&format!(" in {}", self.ctx), x))
    }
}
