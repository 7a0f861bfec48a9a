//! The scene reference, generated from the declarations (`declared.rs`): `powder params
//! scene` prints it and `docs/scene.md` holds it (a test keeps the file current).

use super::declared::{Section, SCENE_KEYS};
use super::OVERLAP_TOLERANCE;
use crate::model::params::reference::cell;
use std::fmt::Write;

/// The reference in Markdown: every table's keys, then the checks made at load time.
pub fn markdown() -> String {
    let mut w = String::from(
        "# Scene keys\n\n\
         Generated from the declarations (`src/scene/declared.rs`) by `powder params scene`; \
         a test keeps this file equal to them, so edit the declarations, not this file \
         (`powder params scene > docs/scene.md`). The contact laws' parameters, which \
         `[[material]]` and `[[interaction]]` take beside the keys here, are in \
         `docs/parameters.md` (`powder params`). An annotated scene is in the README; every \
         example in `examples/` is annotated too.\n\n\
         A scene is a TOML file. Units are SI. Unknown keys are refused everywhere, with the \
         nearest valid key suggested; every error names the scene and, where the problem sits \
         at a place in the file, its line and column. `--set KEY=VALUE` changes any value from \
         the command line (`simulation.dt=1e-6`, `particles[0].count=500`, \
         `wall[1].phase[0].from=0.1`).\n",
    );
    for section in Section::ALL {
        let (title, what) = section.title();
        let _ = writeln!(w, "\n## {title}\n\n{}.\n", capitalised(what));
        let kinds = SCENE_KEYS
            .iter()
            .any(|k| k.section == section && !k.only.is_empty());
        w.push_str(match kinds {
            true => "| key | for | value | unit | default | valid | what |\n| --- | --- | --- | --- | --- | --- | --- |\n",
            false => "| key | value | unit | default | valid | what |\n| --- | --- | --- | --- | --- | --- |\n",
        });
        for k in SCENE_KEYS.iter().filter(|k| k.section == section) {
            let _ = write!(w, "| `{}` |", k.key);
            if kinds {
                let only = match k.only.is_empty() {
                    true => "all".to_string(),
                    false => k.only.join(", "),
                };
                let _ = write!(w, " {only} |");
            }
            let _ = writeln!(
                w,
                " {} | {} | {} | {} | {} |",
                cell(k.value),
                cell(k.unit),
                cell(&k.default.text()),
                cell(&k.valid_text()),
                cell(k.doc)
            );
        }
    }
    let tol = 100.0 * OVERLAP_TOLERANCE;
    let _ = writeln!(
        w,
        "\n## Checks at load time\n\n\
         Besides each key's type and rule above: material names are unique and every name \
         referred to exists; a wall has at most one kind of motion (`velocity`, \
         `velocities` with `times`, the servo, or phases); there is at least one particle; \
         every sphere lies inside the domain (within {tol} % of its radius; on a periodic \
         axis its centre in [min, max)); no two particles appearing at the same time overlap \
         by more than {tol} % of the smaller radius, and no particle overlaps a wall by more \
         than {tol} % of its radius; every pair of different materials that can meet \
         (particle–particle, particle–wall) has an `[[interaction]]`."
    );
    w
}

fn capitalised(text: &str) -> String {
    let mut chars = text.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}
