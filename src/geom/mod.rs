//! Geometric primitives and their robust intersection tests (f64 throughout).
//!
//! Everything the tracers compare lives here so that the grid and the brute-force oracle call the
//! very same arithmetic: two engines that agree on which sphere is first must compute the same `t`
//! for the same (ray, sphere) pair, bit for bit.

pub mod aabb;
pub mod float;
pub mod ray;
pub mod sphere;

pub use aabb::Aabb;
pub use ray::Ray;
pub use sphere::Sphere;
