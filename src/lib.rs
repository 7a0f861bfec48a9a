//! `powder`: a discrete element method (DEM) engine for cohesive powders.
//!
//! The engine, what a library user builds from a scene and steps:
//! * [`scene`] — the TOML scene description and its validation;
//! * [`model`] — contact models in f64, one module each, plus the papers' closed forms;
//! * [`setup`] — what both engines derive from a scene (pair tables, time step, reach);
//! * [`cpu`] — the f64 CPU reference engine, spread over every core with the same bits on
//!   any thread count;
//! * [`gpu`] — the GPU engine (wgpu + WGSL), compared against the CPU engine in the tests.
//!
//! The application, what the `powder` commands add around it:
//! * [`run`] — `powder run` on either engine over one `Simulation` trait (outputs,
//!   checkpoints, the monitor); [`backend`] — which engine `auto` picks;
//! * [`checkpoint`], [`output`] — bitwise checkpoints, and the outputs (VTK, CSV, SVG plots,
//!   atomically written files); [`overrides`] — `--set KEY=VALUE`;
//! * [`measure`] — the engines measured: the two-sphere collision against the papers'
//!   closed forms, CPU against GPU, error against run time, throughput against N.
//!
//! The crate map: `docs/architecture.md`.

#![warn(missing_docs)]

pub mod backend;
pub mod checkpoint;
pub mod cpu;
pub mod error;
pub mod gpu;
pub mod measure;
pub mod memory;
pub mod model;
pub mod output;
pub mod overrides;
pub mod run;
pub mod scene;
pub mod setup;

pub use error::{ParamError, PowderError};
