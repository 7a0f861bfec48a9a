//! `powder`: a discrete element method (DEM) engine for cohesive powders.
//!
//! * [`model`] — contact models in f64, one module each, plus the papers' closed forms;
//! * [`cpu`] — the f64 CPU reference backend (linked cells, per-contact history, Verlet),
//!   spread over every core with the same bits on any thread count;
//! * [`backend`] — which engine a command runs on (`auto`: a hardware GPU, else the CPU);
//! * [`scene`] — the TOML scene description and its validation;
//! * [`collide`] — the head-on two-sphere collision used to check models against theory;
//! * [`output`] — plots and atomically written files;
//! * [`run`] over [`simulation`] — `powder run` on either backend, with [`observed`]
//!   energies (the parts a GPU run without the energy ledger cannot know left out);
//! * [`mod@bench`] and [`accuracy`] — throughput against N, and error against run time.

#![warn(missing_docs)]

pub mod accuracy;
pub mod backend;
pub mod bench;
pub mod checkpoint;
pub mod collide;
pub mod compare;
pub mod cpu;
pub mod error;
pub mod gpu;
pub mod memory;
pub mod model;
pub mod observed;
pub mod output;
pub mod overrides;
pub mod run;
pub mod scene;
pub mod setup;
pub mod simulation;

pub use error::{ParamError, PowderError};
