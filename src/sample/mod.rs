//! Reproducible randomness: streams keyed by logical work items, and the samplers built on them.

pub mod directions;
pub mod lines;
pub mod rng;

pub use rng::Stream;
