//! `powder params`: every contact law's parameters (key, unit, default, valid values, what),
//! from their declarations (`powder::model::params::reference`); `powder params scene`: the
//! scene's other keys (`powder::scene::reference`).

use super::*;
use powder::model::params::{self, reference};

#[derive(Args)]
pub(crate) struct ParamsArgs {
    /// Only this law's parameters (with the dissipations, for jkr and hertz), or `scene`:
    /// every other key of a scene file.
    #[arg(value_parser = clap::builder::PossibleValuesParser::new(
        params::law_names().into_iter().chain(["scene"])
    ))]
    law: Option<String>,
}

pub(crate) fn params_cmd(a: &ParamsArgs) -> Result<(), PowderError> {
    let text = match a.law.as_deref() {
        Some("scene") => powder::scene::reference::markdown(),
        Some(name) => match params::law(name) {
            Some(law) => reference::law_markdown(law),
            None => reference::markdown(),
        },
        None => reference::markdown(),
    };
    print!("{text}");
    Ok(())
}
