//! Measuring the engines: against the papers' closed forms ([`collide`]), against each
//! other ([`compare`]), over the time step ([`accuracy`]) and for throughput ([`mod@bench`]).

pub mod accuracy;
pub mod bench;
pub mod collide;
pub mod compare;
pub mod packing;
pub mod provenance;
