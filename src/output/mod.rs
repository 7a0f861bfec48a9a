//! Outputs: SVG plots ([`plot`]), ParaView VTK snapshots ([`vtk`]) and the atomic file
//! replacement every writer uses ([`atomic`]).

pub mod atomic;
pub mod plot;
pub mod vtk;
