//! Outputs: SVG plots ([`plot`]), ParaView VTK snapshots ([`vtk`]), the run's series
//! written row by row ([`series_csv`]) and the atomic file replacement every writer uses
//! ([`atomic`]).

pub mod atomic;
pub mod plot;
pub mod series_csv;
pub mod vtk;
