//! `powder params`: every contact law's parameters (key, unit, default, valid values, what),
//! from their declarations (`powder::model::params::reference`).

use super::*;
use powder::model::params::{self, reference};

#[derive(Args)]
pub(crate) struct ParamsArgs {
    /// Only this law's parameters (with the dissipations, for jkr and hertz).
    #[arg(value_parser = clap::builder::PossibleValuesParser::new(params::law_names()))]
    law: Option<String>,
}

pub(crate) fn params_cmd(a: &ParamsArgs) -> Result<(), PowderError> {
    let text = match a.law.as_deref().and_then(params::law) {
        Some(law) => reference::law_markdown(law),
        None => reference::markdown(),
    };
    print!("{text}");
    Ok(())
}
