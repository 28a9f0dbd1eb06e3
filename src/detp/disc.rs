//! Sample points with normals, the tangent discs around them, and the one exact test that decides
//! whether a segment crosses a disc.
//!
//! Every engine decides a (segment, disc) pair with [`crosses`] and nothing else, so engines can only
//! differ in which pairs they test. The test counts a crossing once and only once:
//! - only **front** crossings count: the segment travels against the normal (v·n < 0). A segment in
//!   the disc's plane (v·n = 0, the disc seen edge-on) never crosses it, and one from behind does not
//!   count;
//! - the crossing parameter must lie in the half-open range t ∈ (0, t_end]: a segment that *starts* on
//!   the plane (a photon leaving the surface the disc lies on) does not count there, one that *ends*
//!   on it does. Consecutive segments of a path therefore never both count the same junction;
//! - the rim is closed: |x − c| ≤ d.
//!
//! The comparisons avoid dividing where they can (t > 0 is num < 0 with num = (c − o)·n), and the
//! arithmetic is fixed, so the decision is a deterministic function of the stored numbers.

use glam::DVec3;

use crate::geom::Aabb;

use super::store::Segment;

/// Sample points, their unit normals and the disc radius d (with `detp.edge = "clamp-radius"`, a
/// radius per disc, each at most d).
#[derive(Clone, Debug, PartialEq)]
pub struct Discs {
    /// Disc centres (the sample points).
    pub centers: Vec<DVec3>,
    /// Unit normals: a segment counts when it arrives against the normal.
    pub normals: Vec<DVec3>,
    /// Disc radius d: every disc's radius, or the largest when discs have their own
    /// ([`Discs::with_radii`]). Every engine bounds a disc by d, so culling stays conservative
    /// whatever the per-disc radii are.
    pub radius: f64,
    /// Per-disc radii (each in (0, d]), or `None`: every disc has radius d (the paper's method).
    pub radii: Option<Vec<f64>>,
}

impl Discs {
    /// Discs from points and normals; normals are normalised here. Fails on a zero or non-finite
    /// normal, a non-finite point, or d ≤ 0.
    pub fn new(
        centers: Vec<DVec3>,
        normals: Vec<DVec3>,
        radius: f64,
    ) -> Result<Self, crate::error::Invalid> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("disc radius must be finite and > 0, got {radius}").into());
        }
        if centers.len() != normals.len() {
            return Err(format!("{} points but {} normals", centers.len(), normals.len()).into());
        }
        let mut unit = Vec::with_capacity(normals.len());
        for (i, (c, n)) in centers.iter().zip(&normals).enumerate() {
            if !c.is_finite() {
                return Err(format!("point {i} is not finite: {c}").into());
            }
            let l = n.length();
            if !(l.is_finite() && l > 0.0) {
                return Err(format!("point {i} has a zero or non-finite normal: {n}").into());
            }
            unit.push(*n / l);
        }
        Ok(Self {
            centers,
            normals: unit,
            radius,
            radii: None,
        })
    }

    /// The same discs with a radius each (`radii[i]` ∈ (0, d]). Fails on a wrong count or a radius
    /// outside (0, d].
    pub fn with_radii(mut self, radii: Vec<f64>) -> Result<Self, crate::error::Invalid> {
        if radii.len() != self.len() {
            return Err(format!("{} radii for {} discs", radii.len(), self.len()).into());
        }
        if let Some((i, r)) = radii
            .iter()
            .enumerate()
            .find(|(_, &r)| !(r > 0.0 && r <= self.radius))
        {
            return Err(format!("disc {i}: radius {r} outside (0, {}]", self.radius).into());
        }
        self.radii = Some(radii);
        Ok(self)
    }

    /// The radius of disc `i`.
    #[inline]
    pub fn radius_of(&self, i: usize) -> f64 {
        match &self.radii {
            None => self.radius,
            Some(r) => r[i],
        }
    }

    /// The area π r_i² that disc `i`'s power sum is divided by.
    pub fn area(&self, i: usize) -> f64 {
        disc_area(self.radius_of(i))
    }

    /// `n` discs of radius `d` centred uniformly in the ball (`center`, `rad`) with uniform normals:
    /// the DETP paper's validation points (§4.2), drawn from `rng` (centre, then normal, per disc).
    pub fn in_ball<R: rand::Rng + ?Sized>(
        rng: &mut R,
        n: usize,
        center: DVec3,
        rad: f64,
        d: f64,
    ) -> Self {
        let (mut c, mut nn) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for _ in 0..n {
            c.push(center + crate::sample::lines::uniform_in_ball(rng) * rad);
            nn.push(crate::sample::lines::uniform_on_sphere(rng));
        }
        Self::new(c, nn, d).expect("finite centres, unit normals and d > 0")
    }

    /// Number of discs.
    pub fn len(&self) -> usize {
        self.centers.len()
    }

    /// No discs?
    pub fn is_empty(&self) -> bool {
        self.centers.is_empty()
    }

    /// Does segment `s` cross disc `i`? (See the module doc.)
    #[inline]
    pub fn crossed_by(&self, s: &Segment, i: usize) -> bool {
        crosses(
            s.o(),
            s.d(),
            s.t_end(),
            self.centers[i],
            self.normals[i],
            self.radius_of(i),
        )
    }

    /// A box that holds disc `i` (conservative by a relative pad of 10⁻⁹ of the coordinates'
    /// magnitude plus d, so culling by it can never drop a crossing [`crosses`] accepts). It is the
    /// box of the radius-d disc even when disc `i` is smaller: larger, hence still conservative.
    pub fn bounds(&self, i: usize) -> Aabb {
        disc_bounds(self.centers[i], self.normals[i], self.radius)
    }

    /// The box around all discs.
    pub fn bounds_all(&self) -> Aabb {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for i in 0..self.len() {
            let b = self.bounds(i);
            lo = lo.min(b.lo);
            hi = hi.max(b.hi);
        }
        Aabb::new(lo, hi)
    }

    /// Irradiance of disc `i` for its accumulated power sum: watts / (π r_i²).
    pub fn irradiance(&self, i: usize, watts: f64) -> f64 {
        watts / self.area(i)
    }
}

/// π r²: the area a disc of radius r divides its power sum by.
#[inline]
pub fn disc_area(r: f64) -> f64 {
    std::f64::consts::PI * r * r
}

/// The exact crossing test of a segment (o, v, t ∈ (0, t_end]) with the disc (c, n, d).
// The negated comparisons are deliberate: they reject NaN along with the failing values.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[inline]
pub fn crosses(o: DVec3, v: DVec3, t_end: f64, c: DVec3, n: DVec3, d: f64) -> bool {
    let denom = v.dot(n);
    // Front crossings only; parallel (0), back (> 0) and NaN all fail here.
    if !(denom < 0.0) {
        return false;
    }
    let w = c - o;
    let num = w.dot(n);
    // t = num / denom > 0 ⇔ num < 0, decided without a division.
    if !(num < 0.0) {
        return false;
    }
    let t = num / denom;
    if !(t <= t_end) {
        return false;
    }
    let x = v * t - w;
    x.length_squared() <= d * d
}

/// A box holding the disc (c, n, d): along axis k the disc reaches d·√(1 − n_k²), padded.
pub fn disc_bounds(c: DVec3, n: DVec3, d: f64) -> Aabb {
    let ext = DVec3::new(
        (1.0 - n.x * n.x).max(0.0).sqrt(),
        (1.0 - n.y * n.y).max(0.0).sqrt(),
        (1.0 - n.z * n.z).max(0.0).sqrt(),
    ) * d;
    let pad = 1e-9 * (c.abs().max_element() + d);
    Aabb::new(c - ext - DVec3::splat(pad), c + ext + DVec3::splat(pad))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(o: DVec3, v: DVec3, t_end: f64) -> (DVec3, DVec3, f64) {
        (o, v, t_end)
    }

    #[test]
    fn front_crossings_count_back_and_edge_on_do_not() {
        let (c, n, d) = (DVec3::ZERO, DVec3::Z, 1.0);
        let (o, v, t) = seg(DVec3::new(0.2, 0.1, 1.0), -DVec3::Z, 5.0);
        assert!(crosses(o, v, t, c, n, d));
        assert!(!crosses(-o, DVec3::Z, t, c, n, d), "from behind");
        assert!(
            !crosses(DVec3::new(-2.0, 0.0, 0.0), DVec3::X, 5.0, c, n, d),
            "in plane"
        );
    }

    #[test]
    fn starting_on_the_plane_does_not_count_ending_on_it_does() {
        let (c, n, d) = (DVec3::ZERO, DVec3::Z, 1.0);
        // Starts on the plane, leaves downward (front direction): t = 0 is excluded.
        assert!(!crosses(DVec3::new(0.1, 0.0, 0.0), -DVec3::Z, 3.0, c, n, d));
        // Ends exactly on the plane: t = t_end is included.
        assert!(crosses(DVec3::new(0.1, 0.0, 2.0), -DVec3::Z, 2.0, c, n, d));
        // Ends just short of it.
        assert!(!crosses(
            DVec3::new(0.1, 0.0, 2.0),
            -DVec3::Z,
            1.999_999,
            c,
            n,
            d
        ));
    }

    #[test]
    fn the_rim_is_closed() {
        let (c, n, d) = (DVec3::ZERO, DVec3::Z, 0.5);
        assert!(crosses(DVec3::new(0.5, 0.0, 1.0), -DVec3::Z, 2.0, c, n, d));
        assert!(!crosses(
            DVec3::new(0.5 + 1e-12, 0.0, 1.0),
            -DVec3::Z,
            2.0,
            c,
            n,
            d
        ));
    }

    #[test]
    fn bounds_hold_every_rim_point() {
        let n = DVec3::new(0.3, -0.5, 0.81).normalize();
        let c = DVec3::new(1e6, -3.0, 2.5);
        let b = disc_bounds(c, n, 0.25);
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        for k in 0..360 {
            let a = f64::from(k).to_radians();
            let p = c + 0.25 * (a.cos() * u + a.sin() * w);
            assert!(b.distance_squared(p) == 0.0, "rim point {p} outside {b:?}");
        }
    }

    #[test]
    fn discs_reject_zero_normals_and_bad_radius() {
        assert!(Discs::new(vec![DVec3::ZERO], vec![DVec3::ZERO], 1.0).is_err());
        assert!(Discs::new(vec![DVec3::ZERO], vec![DVec3::Z], 0.0).is_err());
        assert!(Discs::new(vec![DVec3::ZERO], vec![DVec3::Z], f64::NAN).is_err());
        let d = Discs::new(vec![DVec3::ZERO], vec![DVec3::new(0.0, 0.0, 3.0)], 1.0).unwrap();
        assert_eq!(d.normals[0], DVec3::Z);
    }
}
