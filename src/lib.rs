//! `powder`: a discrete element method (DEM) engine for cohesive powders.
//!
//! * [`model`] — contact models in f64, one module each, plus the papers' closed forms;
//! * [`cpu`] — the f64 CPU reference backend (linked cells, per-contact history, Verlet),
//!   spread over every core with the same bits on any thread count;
//! * [`backend`] — which engine a command runs on (`auto`: a hardware GPU, else the CPU);
//! * [`scene`] — the TOML scene description and its validation;
//! * [`gpu`] — the GPU engine (wgpu + WGSL), compared against the CPU engine in the tests;
//! * [`setup`], [`checkpoint`], [`output`] — what both engines derive from a scene, bitwise
//!   checkpoints, and the outputs (VTK, CSV, SVG plots, atomically written files);
//! * [`run`] — `powder run` on either backend over one `Simulation` trait, with the
//!   energies a run observes;
//! * [`measure`] — the engines measured: the two-sphere collision against the papers'
//!   closed forms, CPU against GPU, error against run time, throughput against N.

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
