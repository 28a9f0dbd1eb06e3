//! The primitives light transport needs, with their f64 intersection tests: triangles (quads are
//! two) and spheres. Every test returns all ray parameters t > t_min at which the ray's line meets
//! the surface, so a caller can take the first and the second intersection.

use glam::DVec3;

/// A triangle with its surface index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices, wound so that (v1 − v0) × (v2 − v0) is the side that receives light.
    pub v: [DVec3; 3],
    /// Index of the surface (material, emission) it belongs to.
    pub surface: u32,
}

/// `triangles` without the duplicates: a triangle with the same surface and the same three vertices
/// (bit for bit, −0 = +0) as an earlier one, wound the same way, is dropped, and the number dropped
/// comes back. Two copies wound opposite ways (a double-sided sheet) are both kept.
///
/// O(n log n): a sort of canonical keys. Why it matters: n copies of one face give a bounding-volume
/// hierarchy no split can separate, so every query tests all of them and placing surface points
/// became quadratic (10⁵ copies: over a minute; 10⁵ distinct faces: 0.2 s).
pub fn without_duplicates(triangles: Vec<Triangle>) -> (Vec<Triangle>, usize) {
    let bits = |v: DVec3| {
        let b = |x: f64| (x + 0.0).to_bits();
        [b(v.x), b(v.y), b(v.z)]
    };
    // The key: surface, winding class, and the vertices in sorted order.
    let key = |t: &Triangle| {
        let mut v = t.v.map(bits);
        // The winding of the given order relative to the sorted order: an even permutation keeps it.
        let mut parity = false;
        for i in 0..3 {
            for j in 0..2 - i {
                if v[j] > v[j + 1] {
                    v.swap(j, j + 1);
                    parity = !parity;
                }
            }
        }
        (t.surface, parity, v)
    };
    let mut order: Vec<(u32, bool, [[u64; 3]; 3], usize)> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (s, p, v) = key(t);
            (s, p, v, i)
        })
        .collect();
    order.sort_unstable();
    let mut keep = vec![true; triangles.len()];
    for w in order.windows(2) {
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 && w[0].2 == w[1].2 {
            // Keep the earliest of each run (the sort puts it first: index is the last key).
            keep[w[1].3] = false;
        }
    }
    let dropped = keep.iter().filter(|&&k| !k).count();
    if dropped == 0 {
        return (triangles, 0);
    }
    let kept = triangles
        .into_iter()
        .zip(keep)
        .filter_map(|(t, k)| k.then_some(t))
        .collect();
    (kept, dropped)
}

impl Triangle {
    /// Unnormalised normal (its length is twice the area).
    pub fn cross(&self) -> DVec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    /// Unit normal.
    pub fn normal(&self) -> DVec3 {
        self.cross().normalize()
    }

    /// Area.
    pub fn area(&self) -> f64 {
        0.5 * self.cross().length()
    }

    /// Is it degenerate (zero or non-finite area)?
    pub fn degenerate(&self) -> bool {
        let a = self.area();
        !(a.is_finite() && a > 0.0)
    }

    /// Möller–Trumbore in f64: the t of the crossing, if it lies in (t_min, ∞). Edges are closed
    /// (barycentrics ≥ 0 with a relative tolerance of 10⁻¹²), so a ray through a shared edge meets at
    /// least one of the two triangles; the caller's t ordering makes a double hit harmless.
    #[inline]
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<f64> {
        let e1 = self.v[1] - self.v[0];
        let e2 = self.v[2] - self.v[0];
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - self.v[0];
        let u = s.dot(p) * inv;
        const TOL: f64 = -1e-12;
        if !(TOL..=1.0 - TOL).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        if v < TOL || u + v > 1.0 - TOL {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t > t_min).then_some(t)
    }

    /// Bounding box corners.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (
            self.v[0].min(self.v[1]).min(self.v[2]),
            self.v[0].max(self.v[1]).max(self.v[2]),
        )
    }

    /// Centroid.
    pub fn centroid(&self) -> DVec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }
}

/// A sphere seen from outside (normals outward) or from inside (normals inward).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
    /// Seen from inside: the normal that receives light points to the centre.
    pub inside: bool,
    /// Surface index.
    pub surface: u32,
}

impl Ball {
    /// Both roots of |o + t d − c| = R (t0 ≤ t1), cancellation-free (the discriminant from the
    /// perpendicular offset, the second root as c/q), or None if the line misses.
    #[inline]
    pub fn roots(&self, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
        let a = d.length_squared();
        let f = o - self.center;
        let b = f.dot(d);
        let perp = f - d * (b / a);
        let r = self.radius;
        let disc = a * (r - perp.length()) * (r + perp.length());
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r * r;
        // Roots of a t² + 2b t + c = 0: q = −(b + sign(b)·√disc), t = q/a and c/q (no cancellation).
        let sq = disc.sqrt();
        let q = if b >= 0.0 { -(b + sq) } else { -b + sq };
        if q == 0.0 {
            return Some((0.0, 0.0));
        }
        let (t0, t1) = (q / a, c / q);
        Some((t0.min(t1), t0.max(t1)))
    }

    /// The normal that receives light at surface point p.
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        let n = (p - self.center).normalize();
        if self.inside {
            -n
        } else {
            n
        }
    }

    /// Area.
    pub fn area(&self) -> f64 {
        4.0 * std::f64::consts::PI * self.radius * self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hits_inside_and_misses_outside() {
        let t = Triangle {
            v: [DVec3::ZERO, DVec3::X, DVec3::Y],
            surface: 0,
        };
        assert_eq!(
            t.intersect(DVec3::new(0.2, 0.2, 1.0), -DVec3::Z, 0.0),
            Some(1.0)
        );
        assert_eq!(t.intersect(DVec3::new(0.8, 0.8, 1.0), -DVec3::Z, 0.0), None);
        assert_eq!(t.intersect(DVec3::new(0.2, 0.2, 1.0), DVec3::Z, 0.0), None);
        assert_eq!(t.normal(), DVec3::Z);
        assert!((t.area() - 0.5).abs() < 1e-15);
    }

    #[test]
    fn ball_roots_are_ordered_and_accurate() {
        let b = Ball {
            center: DVec3::new(0.0, 0.0, 5.0),
            radius: 1.0,
            inside: false,
            surface: 0,
        };
        let (t0, t1) = b.roots(DVec3::ZERO, DVec3::Z).unwrap();
        assert!((t0 - 4.0).abs() < 1e-12 && (t1 - 6.0).abs() < 1e-12);
        let (t0, t1) = b.roots(DVec3::new(0.0, 0.0, 5.0), DVec3::X).unwrap();
        assert!((t0 + 1.0).abs() < 1e-12 && (t1 - 1.0).abs() < 1e-12);
        assert!(b.roots(DVec3::new(2.0, 0.0, 0.0), DVec3::Z).is_none());
        // Far away and tiny: each root within a few ulps of t ≈ 10⁸ (no cancellation, which would
        // lose the 2·10⁻³ chord entirely).
        let far = Ball {
            center: DVec3::new(0.0, 0.0, 1e8),
            radius: 1e-3,
            inside: false,
            surface: 0,
        };
        let (t0, t1) = far.roots(DVec3::ZERO, DVec3::Z).unwrap();
        let ulps = 4.0 * f64::EPSILON * 1e8;
        assert!((t0 - (1e8 - 1e-3)).abs() <= ulps, "{t0}");
        assert!((t1 - (1e8 + 1e-3)).abs() <= ulps, "{t1}");
    }
}
