//! A span-keeping TOML reader: the value tree with source positions, typed access to
//! one table, and the helpers that word its error messages.

use crate::error::PowderError;
use std::fmt::Display;
use std::ops::Range;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

pub(super) type Span = Range<usize>;
pub(super) type Res<T> = Result<T, PowderError>;

pub(super) struct Src<'a> {
    pub(super) name: &'a str,
    pub(super) text: &'a str,
    /// The `--set KEY=VALUE` overrides as given, which spans from [`SET_SPAN`] name.
    pub(super) sets: &'a [String],
}

/// Spans from here on are not in the text: `SET_SPAN + k` is a value of the `k`-th `--set`,
/// so an error in it names that override, not the line it replaced.
pub(super) const SET_SPAN: usize = usize::MAX / 2;

impl Src<'_> {
    /// 1-based line and column (in characters) of a byte offset.
    pub(super) fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut off = offset.min(self.text.len());
        while !self.text.is_char_boundary(off) {
            off -= 1;
        }
        let before = &self.text[..off];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
        (line, col)
    }

    pub(super) fn err(&self, span: Option<&Span>, msg: impl Display) -> PowderError {
        match span {
            Some(s) if s.start >= SET_SPAN => {
                let set = self.sets.get(s.start - SET_SPAN).map_or("", String::as_str);
                PowderError::Scene(format!("scene `{}`, --set {set}: {msg}", self.name))
            }
            Some(s) => {
                let (line, col) = self.line_col(s.start);
                PowderError::Scene(format!(
                    "scene `{}`, line {line}, column {col}: {msg}",
                    self.name
                ))
            }
            None => PowderError::Scene(format!("scene `{}`: {msg}", self.name)),
        }
    }
}

#[derive(Debug)]
pub(super) enum Val {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime,
    Array(Vec<Node>),
    Table(Vec<Entry>),
}

#[derive(Debug)]
pub(super) struct Node {
    pub(super) span: Span,
    pub(super) val: Val,
}

#[derive(Debug)]
pub(super) struct Entry {
    pub(super) key: String,
    key_span: Span,
    pub(super) node: Node,
}

impl Node {
    pub(super) fn new(span: Span, val: Val) -> Self {
        Self { span, val }
    }
}

impl Entry {
    /// An entry whose key and value are placed at `span`.
    pub(super) fn new(key: &str, span: &Span, node: Node) -> Self {
        Self {
            key: key.to_string(),
            key_span: span.clone(),
            node,
        }
    }
}

fn convert_value(src: &Src, v: &Spanned<DeValue>) -> Res<Node> {
    let span = v.span();
    let val = match v.get_ref() {
        DeValue::String(s) => Val::Str(s.to_string()),
        DeValue::Integer(i) => match i64::from_str_radix(i.as_str(), i.radix()) {
            Ok(x) => Val::Int(x),
            Err(_) => {
                return Err(src.err(
                    Some(&span),
                    format!("the integer {i} does not fit in 64 bits"),
                ))
            }
        },
        DeValue::Float(f) => match f.as_str().parse::<f64>() {
            Ok(x) => Val::Float(x),
            Err(_) => return Err(src.err(Some(&span), format!("cannot read the number {f}"))),
        },
        DeValue::Boolean(b) => Val::Bool(*b),
        DeValue::Datetime(_) => Val::Datetime,
        DeValue::Array(a) => Val::Array(
            a.iter()
                .map(|x| convert_value(src, x))
                .collect::<Res<Vec<_>>>()?,
        ),
        DeValue::Table(t) => Val::Table(convert_table(src, t)?),
    };
    Ok(Node { span, val })
}

pub(super) fn convert_table(src: &Src, t: &DeTable) -> Res<Vec<Entry>> {
    let mut entries = t
        .iter()
        .map(|(k, v)| {
            Ok(Entry {
                key: k.get_ref().to_string(),
                key_span: k.span(),
                node: convert_value(src, v)?,
            })
        })
        .collect::<Res<Vec<_>>>()?;
    entries.sort_by_key(|e| e.key_span.start);
    Ok(entries)
}

pub(super) fn describe(node: &Node) -> String {
    match &node.val {
        Val::Str(s) => {
            let hint = if s.trim().parse::<f64>().is_ok() {
                " (write numbers without quotes)"
            } else {
                ""
            };
            format!("the string {s:?}{hint}")
        }
        Val::Int(i) => format!("the integer {i}"),
        Val::Float(f) => format!("the number {f}"),
        Val::Bool(b) => format!("the boolean {b}"),
        Val::Datetime => "a date-time".to_string(),
        // (the elements named where few: a right length of the wrong kind says so)
        Val::Array(a) if a.is_empty() => "an empty array".to_string(),
        Val::Array(a) if a.len() <= 4 => format!(
            "an array of {} element(s): {}",
            a.len(),
            a.iter().map(describe).collect::<Vec<_>>().join(", ")
        ),
        Val::Array(a) => format!(
            "an array of {} element(s), the first {}",
            a.len(),
            describe(&a[0])
        ),
        Val::Table(_) => "a table".to_string(),
    }
}

pub(super) fn node_number(node: &Node) -> Option<f64> {
    match node.val {
        Val::Int(i) => Some(i as f64),
        Val::Float(f) => Some(f),
        _ => None,
    }
}

/// The candidate closest to `word`, if it is close enough to be a likely typo.
pub(super) fn suggest<'k>(word: &str, candidates: &[&'k str]) -> Option<&'k str> {
    let w = word.to_lowercase();
    candidates
        .iter()
        .map(|c| {
            let score =
                strsim::jaro_winkler(&w, c).max(strsim::normalized_damerau_levenshtein(&w, c));
            (score, *c)
        })
        .filter(|(s, _)| *s >= 0.7)
        .fold(None, |best: Option<(f64, &str)>, x| match best {
            Some(b) if b.0 >= x.0 => Some(b),
            _ => Some(x),
        })
        .map(|(_, c)| c)
}

pub(super) fn quoted_list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
pub(super) fn one_of_strings(options: &[&str]) -> String {
    let q: Vec<String> = options.iter().map(|o| format!("\"{o}\"")).collect();
    match q.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// `[x, y, z]`, each as [`crate::error::num`] writes it (no 300 zeros for 1e-300).
pub(super) fn fmt_vec(v: [f64; 3]) -> String {
    use crate::error::num;
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

pub(super) const AXES: [&str; 3] = ["x", "y", "z"];

pub(super) struct Tbl<'a> {
    pub(super) src: &'a Src<'a>,
    pub(super) entries: &'a [Entry],
    span: Option<Span>,
    pub(super) ctx: String,
}

impl<'a> Tbl<'a> {
    pub(super) fn new(
        src: &'a Src<'a>,
        entries: &'a [Entry],
        span: Option<Span>,
        ctx: String,
    ) -> Self {
        Self {
            src,
            entries,
            span,
            ctx,
        }
    }

    fn entry(&self, key: &str) -> Option<&'a Entry> {
        self.entries.iter().find(|e| e.key == key)
    }

    pub(super) fn get(&self, key: &str) -> Option<&'a Node> {
        self.entry(key).map(|e| &e.node)
    }

    pub(super) fn has(&self, key: &str) -> bool {
        self.entry(key).is_some()
    }

    /// An error located at the value of `key` (or at the table when the key is absent).
    pub(super) fn err_key(&self, key: &str, msg: impl Display) -> PowderError {
        let span = self.get(key).map(|n| &n.span).or(self.span.as_ref());
        self.src.err(span, msg)
    }

    pub(super) fn err_node(&self, node: &Node, msg: impl Display) -> PowderError {
        self.src.err(Some(&node.span), msg)
    }

    pub(super) fn err_table(&self, msg: impl Display) -> PowderError {
        self.src.err(self.span.as_ref(), msg)
    }

    pub(super) fn missing(&self, key: &str, what: &str) -> PowderError {
        self.err_table(format!(
            "missing required key `{key}` in {}: {what}",
            self.ctx
        ))
    }

    pub(super) fn type_err(&self, key: &str, node: &Node, expected: &str) -> PowderError {
        self.err_node(
            node,
            format!(
                "`{key}` in {} must be {expected}, got {}",
                self.ctx,
                describe(node)
            ),
        )
    }

    /// Rejects keys outside `allowed`; `hint` may explain a known-but-misplaced key.
    pub(super) fn check_keys(
        &self,
        allowed: &[&str],
        hint: impl Fn(&str) -> Option<String>,
    ) -> Res<()> {
        for e in self.entries {
            if allowed.contains(&e.key.as_str()) {
                continue;
            }
            let valid = quoted_list(allowed);
            let msg = if let Some(h) = hint(&e.key) {
                format!(
                    "unknown key `{}` in {}: {h} (valid keys: {valid})",
                    e.key, self.ctx
                )
            } else if let Some(s) = suggest(&e.key, allowed) {
                format!(
                    "unknown key `{}` in {}: did you mean `{s}`? (valid keys: {valid})",
                    e.key, self.ctx
                )
            } else {
                format!(
                    "unknown key `{}` in {}; valid keys are {valid}",
                    e.key, self.ctx
                )
            };
            return Err(self.src.err(Some(&e.key_span), msg));
        }
        Ok(())
    }

    pub(super) fn f64(&self, key: &str) -> Res<Option<f64>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let x = node_number(node).ok_or_else(|| self.type_err(key, node, "a number"))?;
        if !x.is_finite() {
            return Err(self.err_node(
                node,
                format!("`{key}` in {} must be a finite number, got {x}", self.ctx),
            ));
        }
        Ok(Some(x))
    }

    /// `key` > 0 if present.
    pub(super) fn positive(&self, key: &str, what: &str) -> Res<Option<f64>> {
        match self.f64(key)? {
            Some(x) if x <= 0.0 => Err(self.err_key(
                key,
                format!(
                    "`{key}` in {} ({what}) must be > 0, got {}",
                    self.ctx,
                    crate::error::num(x)
                ),
            )),
            other => Ok(other),
        }
    }

    pub(super) fn positive_req(&self, key: &str, what: &str) -> Res<f64> {
        self.positive(key, what)?
            .ok_or_else(|| self.missing(key, what))
    }

    pub(super) fn u64(&self, key: &str) -> Res<Option<u64>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match node.val {
            Val::Int(i) if i >= 0 => Ok(Some(i as u64)),
            _ => Err(self.type_err(key, node, "a non-negative integer")),
        }
    }

    pub(super) fn bool(&self, key: &str) -> Res<Option<bool>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match node.val {
            Val::Bool(b) => Ok(Some(b)),
            _ => Err(self.type_err(key, node, "true or false")),
        }
    }

    pub(super) fn str(&self, key: &str) -> Res<Option<&'a str>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        match &node.val {
            Val::Str(s) => Ok(Some(s.as_str())),
            _ => Err(self.type_err(key, node, "a string")),
        }
    }

    /// A string from a fixed set of options, with a suggestion for near misses.
    pub(super) fn choice(&self, key: &str, options: &[&'static str]) -> Res<Option<&'static str>> {
        let expected = one_of_strings(options);
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Str(s) = &node.val else {
            return Err(self.type_err(key, node, &expected));
        };
        if let Some(o) = options.iter().find(|o| **o == s.as_str()) {
            return Ok(Some(*o));
        }
        let mut msg = format!("`{key}` in {} must be {expected}, got \"{s}\"", self.ctx);
        if let Some(sug) = suggest(s, options) {
            msg.push_str(&format!(": did you mean \"{sug}\"?"));
        }
        Err(self.err_node(node, msg))
    }

    fn vec3_of(&self, key: &str, node: &Node) -> Res<[f64; 3]> {
        let expected = "an array of 3 numbers [x, y, z]";
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, expected));
        };
        if items.len() != 3 {
            return Err(self.type_err(key, node, expected));
        }
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            let x = node_number(item).ok_or_else(|| {
                self.err_node(
                    item,
                    format!(
                        "`{key}` in {} must be {expected}, but an element is {}",
                        self.ctx,
                        describe(item)
                    ),
                )
            })?;
            if !x.is_finite() {
                return Err(self.err_node(
                    item,
                    format!(
                        "`{key}` in {} must contain finite numbers, got {x}",
                        self.ctx
                    ),
                ));
            }
            *o = x;
        }
        Ok(out)
    }

    pub(super) fn vec3(&self, key: &str) -> Res<Option<[f64; 3]>> {
        match self.get(key) {
            None => Ok(None),
            Some(node) => self.vec3_of(key, node).map(Some),
        }
    }

    pub(super) fn vec3_req(&self, key: &str, what: &str) -> Res<[f64; 3]> {
        self.vec3(key)?.ok_or_else(|| self.missing(key, what))
    }

    pub(super) fn vec3_list(&self, key: &str) -> Res<Option<Vec<[f64; 3]>>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, "an array of [x, y, z] arrays"));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| self.vec3_of(&format!("{key}[{i}]"), item))
            .collect::<Res<Vec<_>>>()
            .map(Some)
    }

    pub(super) fn f64_list(&self, key: &str) -> Res<Option<Vec<f64>>> {
        let Some(node) = self.get(key) else {
            return Ok(None);
        };
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, "an array of numbers"));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                let x = node_number(item)
                    .ok_or_else(|| self.type_err(&format!("{key}[{i}]"), item, "a number"))?;
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(self.err_node(
                        item,
                        format!(
                            "`{key}[{i}]` in {} must be a finite number, got {x}",
                            self.ctx
                        ),
                    ))
                }
            })
            .collect::<Res<Vec<_>>>()
            .map(Some)
    }

    /// A sub-table `[key]` (or inline table).
    pub(super) fn table(&self, key: &str, ctx: String) -> Res<Option<Tbl<'a>>> {
        let Some(e) = self.entry(key) else {
            return Ok(None);
        };
        match &e.node.val {
            Val::Table(entries) => Ok(Some(Tbl::new(
                self.src,
                entries,
                Some(e.key_span.clone()),
                ctx,
            ))),
            _ => Err(self.type_err(key, &e.node, "a table")),
        }
    }

    /// An array of tables `[[key]]`, each with its span.
    pub(super) fn tables(&self, key: &str) -> Res<Vec<(Span, &'a [Entry])>> {
        let Some(node) = self.get(key) else {
            return Ok(Vec::new());
        };
        let expected = format!("an array of tables, written [[{key}]]");
        let Val::Array(items) = &node.val else {
            return Err(self.type_err(key, node, &expected));
        };
        items
            .iter()
            .map(|item| match &item.val {
                Val::Table(entries) => Ok((item.span.clone(), entries.as_slice())),
                _ => Err(self.type_err(key, item, &expected)),
            })
            .collect()
    }
}
