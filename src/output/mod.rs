//! Outputs: SVG plots ([`plot`]), ParaView VTK snapshots of the particles ([`vtk`]) and of
//! the contact network ([`contacts`], binary through [`appended`]), the run's series written
//! row by row ([`series_csv`]), the atomic file replacement every writer uses
//! ([`atomic`]) and the output folder held by one run at a time ([`folder`]).

pub mod appended;
pub mod atomic;
pub mod contacts;
pub mod folder;
pub mod plot;
pub mod series_csv;
pub mod vtk;
