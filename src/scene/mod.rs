//! What is traced: Poisson sphere processes, finite (built into a real grid) or infinite (generated
//! lazily, block by block, where rays go), with one or several radius classes.

pub mod finite;
pub mod lazy;
pub mod radius;

pub use radius::{RadiusClass, RadiusDist, RadiusDraw};
