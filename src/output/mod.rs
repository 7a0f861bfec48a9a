pub mod atomic;
pub mod plot;
pub mod vtk;
