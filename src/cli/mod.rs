//! The commands of the `powder` binary, one file each, and the choices they share.

use clap::{Args, ValueEnum};
use powder::measure::collide::{self, CollideResult, CollideSpec};
use powder::model::flags::LawArgs;
use powder::model::ContactModel;
use powder::scene::Scene;
use powder::{ParamError, PowderError};
use std::path::PathBuf;

mod accuracy;
pub(crate) mod analytic;
mod bench;
mod choices;
mod collisions;
mod compare;
mod info;
mod params;
mod run;
mod stop_signals;

pub(crate) use accuracy::*;
pub(crate) use bench::*;
pub(crate) use choices::*;
pub(crate) use collisions::*;
pub(crate) use compare::*;
pub(crate) use info::*;
pub(crate) use params::*;
pub(crate) use run::*;
pub(crate) use stop_signals::exit_status;

/// A default list as its flag's comma-separated text.
pub(crate) fn list_text<T: std::fmt::Display>(items: &[T]) -> String {
    let words: Vec<String> = items.iter().map(|x| x.to_string()).collect();
    words.join(",")
}
