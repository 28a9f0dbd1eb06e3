//! Rays with unit direction, as the eye rays of the paper ("image sphere" directions).

use glam::DVec3;

/// A half-line `o + t·d`, `t ≥ 0`. `d` is unit length for every ray the tracers create, so `t` is a
/// distance (the paper's first-hit distance t*).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin (the eye).
    pub o: DVec3,
    /// Direction, unit length.
    pub d: DVec3,
}

impl Ray {
    /// A ray from `o` along `d`; −0.0 components of `d` become +0.0.
    pub fn new(o: DVec3, d: DVec3) -> Self {
        use super::float::positive_zero as pz;
        debug_assert!(
            (d.length_squared() - 1.0).abs() < 1e-9,
            "direction must be unit: {d}"
        );
        Self {
            o,
            d: DVec3::new(pz(d.x), pz(d.y), pz(d.z)),
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.o + self.d * t
    }
}
