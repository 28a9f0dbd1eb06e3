//! Spheres and the cancellation-free ray–sphere test both tracers share.
//!
//! # Why this test is robust
//! The textbook discriminant `b² − 4ac` subtracts two nearly equal numbers whenever the sphere is small
//! or far compared with the distance to its centre (`c = |f|² − r²` with `|f| ≫ r`): the difference is
//! lost to cancellation and grazing rays flip between hit and miss. Following pbrt-v4
//! (`shapes.h`, after Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing
//! Gems ch. 7), we compute the discriminant from the perpendicular foot of the centre on the ray:
//! `v = f − (f·d)d` is the offset of the centre from the ray, and `Δ/4 = (r − |v|)(r + |v|)` is a
//! product of two well-conditioned factors, accurate to a few ulps even when `|f| ≫ r`. The roots are
//! then taken as `q` and `c/q` with `q = −(b' + sign(b')√Δ')`, so neither root is a difference of
//! nearly equal numbers either. The near root is `c/q` when the origin is outside the sphere.

use glam::DVec3;

use super::Ray;

/// A sphere with a stable identity (`id`): two engines agree on a hit iff they report the same `id`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub c: DVec3,
    /// Radius, > 0.
    pub r: f64,
    /// Identity, unique within a scene.
    pub id: u64,
}

impl Sphere {
    /// Does the closed ball contain `p`? Spheres that contain (or touch) the eye are ignored by the
    /// tracers: the paper's "first intersected" means the first sphere not containing the ray origin.
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        (p - self.c).length_squared() <= self.r * self.r
    }

    /// Distance along `ray` (unit direction) to where it enters this sphere, or `None` if it misses
    /// or the sphere contains the origin. Tangent rays (`Δ = 0`) count as hits: balls are closed.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<f64> {
        let f = ray.o - self.c;
        // b' = f·d (half of pbrt's b with a = 1). A hit needs the centre ahead of the origin.
        let b = f.dot(ray.d);
        if b >= 0.0 {
            return None;
        }
        // Perpendicular offset v of the centre from the ray line.
        let v = f - b * ray.d;
        let vl2 = v.length_squared();
        // Cheap, exact rejection of most misses without a square root: if |v|² > r²(1+8ε), the
        // correctly rounded √|v|² exceeds r, so the discriminant below would be negative anyway.
        // The function therefore returns exactly what it would without this test.
        if vl2 > self.r * self.r * (1.0 + 8.0 * f64::EPSILON) {
            return None;
        }
        let fl = f.length();
        if fl <= self.r {
            return None;
        }
        // c = |f|² − r² as a product, free of cancellation when the origin is near the surface.
        let c = (fl - self.r) * (fl + self.r);
        // Discriminant Δ/4 = (r − |v|)(r + |v|): two well-conditioned factors.
        let vl = vl2.sqrt();
        let disc = (self.r - vl) * (self.r + vl);
        if disc < 0.0 {
            return None;
        }
        // q = −(b' − √Δ') > 0 since b' < 0; the near root is c/q (origin outside ⇒ c > 0).
        let q = -b + disc.sqrt();
        Some(c / q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
        Ray::new(DVec3::from(o), DVec3::from(d).normalize())
    }

    #[test]
    fn head_on_hit_is_at_distance_minus_radius() {
        let s = Sphere {
            c: DVec3::new(10.0, 0.0, 0.0),
            r: 1.0,
            id: 0,
        };
        assert_eq!(s.intersect(&ray([0.0; 3], [1.0, 0.0, 0.0])), Some(9.0));
        assert_eq!(s.intersect(&ray([0.0; 3], [-1.0, 0.0, 0.0])), None);
    }

    #[test]
    fn sphere_containing_or_touching_the_origin_is_ignored() {
        let s = Sphere {
            c: DVec3::new(0.5, 0.0, 0.0),
            r: 1.0,
            id: 0,
        };
        assert_eq!(s.intersect(&ray([0.0; 3], [1.0, 0.0, 0.0])), None);
        let touching = Sphere {
            c: DVec3::new(1.0, 0.0, 0.0),
            r: 1.0,
            id: 0,
        };
        assert_eq!(touching.intersect(&ray([0.0; 3], [1.0, 0.0, 0.0])), None);
    }

    #[test]
    fn tangent_ray_hits_at_the_foot_point() {
        let s = Sphere {
            c: DVec3::new(5.0, 1.0, 0.0),
            r: 1.0,
            id: 0,
        };
        let t = s
            .intersect(&ray([0.0; 3], [1.0, 0.0, 0.0]))
            .expect("tangent ray hits");
        // A few ulps, the accuracy the module documents (c = (|f|−r)(|f|+r) rounds |f| = √26).
        assert!((t - 5.0).abs() <= 4.0 * f64::EPSILON * 5.0, "t = {t}");
        let missed = Sphere {
            c: DVec3::new(5.0, 1.0 + 1e-12, 0.0),
            r: 1.0,
            id: 0,
        };
        assert_eq!(missed.intersect(&ray([0.0; 3], [1.0, 0.0, 0.0])), None);
    }

    #[test]
    fn tiny_far_sphere_keeps_full_relative_accuracy() {
        // |f| / r = 1e12: the textbook discriminant b² − c cancels completely here.
        let r = 1e-6;
        let s = Sphere {
            c: DVec3::new(1e6, 0.5 * r, 0.0),
            r,
            id: 0,
        };
        let t = s
            .intersect(&ray([0.0; 3], [1.0, 0.0, 0.0]))
            .expect("grazing hit");
        let exact = 1e6 - (r * r - 0.25 * r * r).sqrt();
        assert!(
            ((t - exact) / exact).abs() < 1e-15,
            "t = {t}, exact = {exact}"
        );
    }
}
