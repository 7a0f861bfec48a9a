pub mod atomic;
pub mod plot;
