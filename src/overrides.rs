//! `--set KEY=VALUE`: change values of a scene file from the command line (scale an example
//! up, sweep a parameter) without editing it.
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
    fn key(&self) -> String {
        self.path
            .iter()
            .map(|(n, i)| match i {
                Some(i) => format!("{n}[{i}]"),
                None => n.clone(),
            })
            .collect::<Vec<_>>()
            .join(".")
    }

    /// Applies the override to a parsed document.
    fn apply(&self, doc: &mut Table) -> Result<(), PowderError> {
        let key = self.key();
        let mut table = doc;
        let (last, parents) = self.path.split_last().expect("a path has a component");
        for (name, index) in parents {
            let entry = table.get_mut(name).ok_or_else(|| {
                PowderError::Scene(format!("--set {key}: the scene has no `{name}`"))
            })?;
            table = match (entry, index) {
                (Value::Table(t), None) => t,
                (Value::Array(blocks), Some(i)) => {
                    let n = blocks.len();
                    match blocks.get_mut(*i) {
                        Some(Value::Table(t)) => t,
                        _ => {
                            return Err(PowderError::Scene(format!(
                                "--set {key}: `{name}` has {n} blocks, no block [{i}] (indices start at 0)"
                            )))
                        }
                    }
                }
                (Value::Array(_), None) => {
                    return Err(PowderError::Scene(format!(
                        "--set {key}: `{name}` is a list of blocks: pick one with {name}[INDEX]"
                    )))
                }
                _ => {
                    return Err(PowderError::Scene(format!(
                        "--set {key}: `{name}` is not a table"
                    )))
                }
            };
        }
        let (name, index) = last;
        match index {
            None => {
                table.insert(name.clone(), self.value.clone());
            }
            Some(i) => match table.get_mut(name) {
                Some(Value::Array(items)) if *i < items.len() => items[*i] = self.value.clone(),
                _ => {
                    return Err(PowderError::Scene(format!(
                        "--set {key}: `{name}` has no element [{i}]"
                    )))
                }
            },
        }
        Ok(())
    }
}

/// The scene text with every `KEY=VALUE` of `sets` applied, in order (comments are not
/// kept; line numbers in later error messages refer to the rewritten text).
pub fn apply(text: &str, sets: &[String]) -> Result<String, PowderError> {
    if sets.is_empty() {
        return Ok(text.to_string());
    }
    let mut doc: Table = text.parse().map_err(|e| {
        PowderError::Scene(format!(
            "cannot apply --set: the scene is not valid TOML: {e}"
        ))
    })?;
    for set in sets {
        Override::parse(set)?.apply(&mut doc)?;
    }
    Ok(doc.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\n[[particles]]\nkind = \"random\"\ncount = 10\n\n[[particles]]\nkind = \"list\"\n";

    #[test]
    fn overrides_reach_tables_blocks_and_elements() {
        let out = apply(
            TEXT,
            &[
                "particles[0].count = 1e5".into(),
                "domain.max=[2.0, 2.0, 1.0]".into(),
                "particles[1].radius = 0.5".into(),
                "domain.min[2] = -1.0".into(),
            ],
        )
        .unwrap();
        let doc: Table = out.parse().unwrap();
        assert_eq!(doc["particles"][0]["count"].as_float(), Some(1e5));
        assert_eq!(doc["particles"][1]["radius"].as_float(), Some(0.5));
        assert_eq!(doc["domain"]["max"][0].as_float(), Some(2.0));
        assert_eq!(doc["domain"]["min"][2].as_float(), Some(-1.0));
        assert_eq!(apply(TEXT, &[]).unwrap(), TEXT);
    }

    #[test]
    fn bad_overrides_say_what_is_wrong() {
        let e = |s: &str| apply(TEXT, &[s.to_string()]).unwrap_err().to_string();
        assert!(e("count").contains("no `=`"));
        assert!(e("particles[2].count = 1").contains("has 2 blocks"));
        assert!(e("particles.count = 1").contains("pick one with particles[INDEX]"));
        assert!(e("simulation.duration = 1").contains("no `simulation`"));
        assert!(e("domain.max = [1.0, ").contains("not a TOML value"));
        assert!(e("particles[x].count = 1").contains("NAME[INDEX]"));
    }
}
