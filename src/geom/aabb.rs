//! Axis-aligned boxes: grid cells and scene bounds.

use glam::DVec3;

/// A closed axis-aligned box `[lo, hi]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub lo: DVec3,
    /// Maximum corner.
    pub hi: DVec3,
}

impl Aabb {
    /// The box between two corners (`lo ≤ hi` componentwise).
    pub fn new(lo: DVec3, hi: DVec3) -> Self {
        debug_assert!(lo.cmple(hi).all());
        Self { lo, hi }
    }

    /// Squared Euclidean distance from `p` to the closed box (0 inside). Exact up to one rounding
    /// per operation: clamping is exact, so only the final subtraction and sum round.
    #[inline]
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let q = p.clamp(self.lo, self.hi);
        (p - q).length_squared()
    }

    /// Largest absolute coordinate of either corner: the magnitude that sets rounding errors here.
    pub fn magnitude(&self) -> f64 {
        self.lo.abs().max(self.hi.abs()).max_element()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_is_zero_inside_and_euclidean_outside() {
        let b = Aabb::new(DVec3::ZERO, DVec3::ONE);
        assert_eq!(b.distance_squared(DVec3::splat(0.5)), 0.0);
        assert_eq!(b.distance_squared(DVec3::new(2.0, 0.5, 0.5)), 1.0);
        assert_eq!(b.distance_squared(DVec3::new(2.0, 2.0, 0.5)), 2.0);
        assert_eq!(b.distance_squared(DVec3::new(-1.0, -1.0, -1.0)), 3.0);
    }
}
