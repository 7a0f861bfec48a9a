//! `--set KEY=VALUE` applied to the parsed scene, not to its text: the file's values keep
//! their lines, and a value set is located at its `--set`, so an error in it names the
//! override, not the line it replaced.

use super::toml_reader::{Entry, Node, Res, Span, Val, SET_SPAN};
use crate::error::PowderError;
use crate::overrides::Override;
use toml::Value;

/// Applies `set`, the `k`-th override, to the top-level table `root`.
pub(super) fn apply(root: &mut Vec<Entry>, set: &Override, k: usize) -> Res<()> {
    // (what the override places is located at it, not at the text it replaces)
    let here = SET_SPAN + k..SET_SPAN + k;
    let key = set.key();
    let (last, parents) = set.path.split_last().expect("a path has a component");
    let mut table = root;
    for (name, index) in parents {
        let entry = table
            .iter_mut()
            .find(|e| &e.key == name)
            .ok_or_else(|| PowderError::Scene(format!("--set {key}: the scene has no `{name}`")))?;
        let node = if index.is_none() && matches!(entry.node.val, Val::Table(_)) {
            &mut entry.node
        } else {
            match (&mut entry.node.val, index) {
                (Val::Array(blocks), Some(i)) => {
                    let n = blocks.len();
                    match blocks.get_mut(*i) {
                    Some(block @ Node { val: Val::Table(_), .. }) => block,
                    _ => {
                        return Err(PowderError::Scene(format!(
                            "--set {key}: `{name}` has {n} blocks, no block [{i}] (indices start at 0)"
                        )))
                    }
                }
                }
                (Val::Array(items), None)
                    if items.iter().all(|i| matches!(i.val, Val::Table(_))) =>
                {
                    return Err(PowderError::Scene(format!(
                        "--set {key}: `{name}` is a list of blocks: pick one with {name}[INDEX]"
                    )))
                }
                _ => {
                    return Err(PowderError::Scene(format!(
                        "--set {key}: `{name}` is not a table"
                    )))
                }
            }
        };
        let Val::Table(entries) = &mut node.val else {
            unreachable!("matched a table above")
        };
        table = entries;
    }
    let (name, index) = last;
    let found = table.iter_mut().find(|e| &e.key == name);
    match (found, index) {
        (Some(entry), None) => entry.node = node_of(&set.value, &here),
        (None, None) => table.push(Entry::new(name, &here, node_of(&set.value, &here))),
        (
            Some(Entry {
                node:
                    Node {
                        val: Val::Array(items),
                        ..
                    },
                ..
            }),
            Some(i),
        ) if *i < items.len() => items[*i] = node_of(&set.value, &here),
        _ => {
            return Err(PowderError::Scene(format!(
                "--set {key}: `{name}` has no element [{}]",
                index.unwrap_or(0)
            )))
        }
    }
    Ok(())
}

/// The parsed form of a value given on the command line, placed at `span`.
fn node_of(value: &Value, span: &Span) -> Node {
    let val = match value {
        Value::String(s) => Val::Str(s.clone()),
        Value::Integer(i) => Val::Int(*i),
        Value::Float(f) => Val::Float(*f),
        Value::Boolean(b) => Val::Bool(*b),
        Value::Datetime(_) => Val::Datetime,
        Value::Array(items) => Val::Array(items.iter().map(|v| node_of(v, span)).collect()),
        Value::Table(t) => Val::Table(
            t.iter()
                .map(|(k, v)| Entry::new(k, span, node_of(v, span)))
                .collect(),
        ),
    };
    Node::new(span.clone(), val)
}
