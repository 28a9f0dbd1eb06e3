//! What is traced: Poisson sphere processes, finite (built into a real grid) or infinite (generated
//! lazily where rays go: per ray in the reach boxes of its walk, or block by block for rays that
//! share a realisation), with one or several radius classes.

pub mod finite;
pub mod infinite;
pub mod lazy;
pub mod radius;
pub mod tube;

pub use radius::{RadiusClass, RadiusDist, RadiusDraw};
