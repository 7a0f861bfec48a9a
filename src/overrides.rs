//! `--set KEY=VALUE`: change values of a scene file from the command line (scale an example
//! up, sweep a parameter) without editing it. Parsed here; applied to the parsed scene by
//! [`crate::scene::Scene::from_toml_str_with`], so errors keep the file's line numbers and
//! an error in a value set names its override.
//!
//! KEY is a dotted path into the TOML document; `name[i]` picks the i-th (0-based) block of
//! an array of tables such as `[[particles]]`: `simulation.duration`, `particles[0].count`,
//! `wall[5].velocities`, `domain.max`. VALUE is a TOML value: `1e5`, `[0.1, 0.1, 0.05]`,
//! `"jkr"`, `true`. A key that does not exist yet is added to an existing table (the scene
//! validation then says whether it is a valid key); a missing table or block is an error.

use crate::error::PowderError;
use toml::{Table, Value};

/// One parsed `KEY=VALUE`.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// Path components: (table key, optional block index).
    pub path: Vec<(String, Option<usize>)>,
    /// The new value.
    pub value: Value,
}

fn bad(set: &str, why: impl std::fmt::Display) -> PowderError {
    PowderError::Scene(format!(
        "--set `{set}`: {why}; write KEY=VALUE with KEY a dotted path such as particles[0].count or domain.max and VALUE a TOML value such as 1e5, [0.1, 0.1, 0.05] or \"jkr\""
    ))
}

impl Override {
    /// Parses `KEY=VALUE`.
    pub fn parse(set: &str) -> Result<Self, PowderError> {
        let (key, value) = set.split_once('=').ok_or_else(|| bad(set, "no `=`"))?;
        let mut path = Vec::new();
        for part in key.trim().split('.') {
            let part = part.trim();
            let (name, index) = match part.split_once('[') {
                Some((name, rest)) => {
                    let i = rest
                        .strip_suffix(']')
                        .and_then(|i| i.trim().parse::<usize>().ok())
                        .ok_or_else(|| bad(set, format!("`{part}` is not NAME[INDEX]")))?;
                    (name.trim(), Some(i))
                }
                None => (part, None),
            };
            if name.is_empty() {
                return Err(bad(set, "an empty key"));
            }
            path.push((name.to_string(), index));
        }
        let doc: Table = format!("v = {}", value.trim())
            .parse()
            .map_err(|e| bad(set, format!("`{}` is not a TOML value ({e})", value.trim())))?;
        let value = doc.get("v").cloned().ok_or_else(|| bad(set, "no value"))?;
        Ok(Self { path, value })
    }

    /// The path as written.
    pub fn key(&self) -> String {
        self.path
            .iter()
            .map(|(n, i)| match i {
                Some(i) => format!("{n}[{i}]"),
                None => n.clone(),
            })
            .collect::<Vec<_>>()
            .join(".")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_parse_paths_and_values() {
        let o = Override::parse("particles[0].count = 1e5").unwrap();
        assert_eq!(
            o.path,
            vec![
                ("particles".to_string(), Some(0)),
                ("count".to_string(), None)
            ]
        );
        assert_eq!(o.value.as_float(), Some(1e5));
        assert_eq!(o.key(), "particles[0].count");
        let o = Override::parse("domain.max=[2.0, 2.0, 1.0]").unwrap();
        assert_eq!(o.value.as_array().map(Vec::len), Some(3));
    }

    #[test]
    fn bad_overrides_say_what_is_wrong() {
        let e = |s: &str| Override::parse(s).unwrap_err().to_string();
        assert!(e("count").contains("no `=`"));
        assert!(e("domain.max = [1.0, ").contains("not a TOML value"));
        assert!(e("particles[x].count = 1").contains("NAME[INDEX]"));
        assert!(e(".count = 1").contains("an empty key"));
    }
}
