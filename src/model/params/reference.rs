//! The parameter reference, generated from the declarations: `powder params` prints it and
//! `docs/parameters.md` holds it (a test keeps the file current).

use super::{Fallback, Kind, Law, Param, Rule, DISSIPATIONS, LAWS};
use std::fmt::Write;

/// The reference in Markdown: every law's parameters, then the JKR family's dissipations.
pub fn markdown() -> String {
    let mut w = String::from(
        "# Contact-law parameters\n\n\
         Generated from the declarations (`src/model/params/declared.rs`) by `powder params`; \
         a test keeps this file equal to them, so edit the declarations, not this file \
         (`powder params > docs/parameters.md`).\n\n\
         A `[[material]]` or `[[interaction]]` names its law with `model = \"<law>\"`; its \
         other keys are that law's parameters, and no others. On the command line \
         (`powder collide`, `powder analytic`) each key is a flag, `--` and the key with `_` \
         as `-`. Units are SI. A friction sub-model's stiffness, damping or dynamic \
         coefficient given without its coefficient > 0 is refused: it would act on \
         nothing.\n",
    );
    for law in LAWS {
        section(&mut w, "##", law);
        if law.dissipation {
            let names: Vec<String> = DISSIPATIONS.iter().map(|d| quoted(d.name)).collect();
            let _ = writeln!(
                w,
                "\nWith `dissipation` one of {}, that dissipation's parameters too (below).",
                names.join(", ")
            );
        }
    }
    w.push_str("\n## The dissipations of the JKR family (`dissipation = \"...\"`)\n");
    for d in DISSIPATIONS {
        section(&mut w, "###", d);
    }
    w
}

/// One law's parameters (and the dissipations where it takes them), as [`markdown`]
/// writes them.
pub fn law_markdown(law: &Law) -> String {
    let mut w = String::new();
    section(&mut w, "#", law);
    if law.dissipation {
        for d in DISSIPATIONS {
            section(&mut w, "##", d);
        }
    }
    w.trim_start().to_string()
}

/// A law's heading and the table of its parameters.
fn section(w: &mut String, level: &str, law: &Law) {
    let _ = writeln!(w, "\n{level} `{}`: {}\n", law.name, law.doc);
    if law.params.is_empty() {
        w.push_str("No parameters.\n");
        return;
    }
    w.push_str("| key | unit | default | valid | what |\n| --- | --- | --- | --- | --- |\n");
    for p in law.params {
        let _ = writeln!(
            w,
            "| `{}` | {} | {} | {} | {} |",
            p.key,
            cell(p.unit),
            cell(&default(p)),
            cell(&valid(p)),
            cell(p.doc)
        );
    }
}

fn quoted(word: &str) -> String {
    format!("`\"{word}\"`")
}

/// The value a parameter takes when absent, in words.
fn default(p: &Param) -> String {
    match p.fallback {
        Fallback::Required => "required".into(),
        Fallback::Number(x) => format!("{x}"),
        Fallback::Word(word) => quoted(word),
        Fallback::Derived(text) => text.into(),
    }
}

/// The values a parameter accepts, in words.
fn valid(p: &Param) -> String {
    match (p.kind, p.rule_text()) {
        (Kind::Choice(words), _) => {
            let words: Vec<String> = words.iter().map(|w| quoted(w)).collect();
            format!("one of {}", words.join(", "))
        }
        (_, Some(rule)) => rule,
        (_, None) if p.rule == Rule::None => "checked with the others".into(),
        (_, None) => "finite".into(),
    }
}

/// Text safe in a table cell.
pub(crate) fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}
