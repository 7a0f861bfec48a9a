//! Outputs: SVG plots ([`plot`]), ParaView VTK snapshots of the particles ([`vtk`]) and of
//! the contact network ([`contacts`], binary through [`appended`]), the run's series written
//! row by row ([`series_csv`]) and the atomic file replacement every writer uses
//! ([`atomic`]).

pub mod appended;
pub mod atomic;
pub mod contacts;
pub mod plot;
pub mod series_csv;
pub mod vtk;
