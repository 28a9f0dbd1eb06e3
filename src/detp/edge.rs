//! What DETP does where a disc reaches past an edge (`detp.edge`).
//!
//! The paper counts a segment's crossings of a disc up to the *second* intersection of its line with
//! the scene, so that a disc on a concave surface (whose tangent plane lies behind the surface) is
//! not shadowed by the surface it approximates. Where the disc of a point at distance s < d from an
//! edge reaches into an adjacent solid — the floor beside a box standing on it — that rule lets light
//! through the solid: a photon that hits the box's top, or its lit face near the floor, still
//! crosses the part of the disc under the box before it leaves the box's far side. Beside a shadowed
//! face the estimate is far too high, beside a lit face too low (the part under the box sees less
//! than the floor beside it), and floor under the box reads light where the truth is 0.
//!
//! Modes (every engine reads the mode through the same two places — the per-disc radius of
//! [`crate::detp::disc::Discs`] and the segments' stored `t_end` — so brute force, the sphere cache
//! and both disc indexes still decide every (segment, disc) pair with the one exact
//! [`crate::detp::disc::crosses`], and their integer sums stay equal bit for bit):
//! - [`EdgeMode::Paper`]: the paper's method, unchanged (the default);
//! - [`EdgeMode::ClampRadius`]: each disc's radius is κ times the distance s from its point to the
//!   nearest *other* surface (any triangle or sphere that is not coplanar with the disc and facing
//!   the same way: the floor's own triangles do not count, a box's bottom face does), clamped to
//!   [r_min·d, d], and its power is divided by π r_i². With κ ≤ 1 a disc reaches into no solid
//!   (unless κ·s < r_min·d): nothing is counted that did not arrive in free space; κ < 1 keeps a
//!   margin from the edge (the irradiance bends before the edge, not only past it), κ > 1 trades
//!   some reach into the solid for less noise. Culling bounds every disc by d, which holds the
//!   smaller disc, so it stays conservative. Its price is noise: a disc of radius r gathers (r/d)²
//!   of the photons, so the standard error grows as d/r;
//! - [`EdgeMode::FirstHit`]: a crossing counts only up to `gap·d` beyond the segment's first impact
//!   (t_end := min(t_end, t_hit + gap·d) for every segment, before any engine runs). A photon that
//!   enters a solid dies at its surface; the gap keeps the paper's concave-surface allowance for
//!   surfaces that sag at most gap·d below their tangent plane over the disc. The disc keeps radius
//!   d and area πd², so the part of it inside a solid now gathers nothing: beside a lit face the
//!   estimate is low by the fraction of the disc that is covered;
//! - [`EdgeMode::ClampFirstHit`]: both. The clamped disc lies in free space, so cutting at the first
//!   impact removes only light that passed through something above it (an open sheet, a box a point
//!   lies under), which no clamp can see when it is farther than d.

use glam::DVec3;
use rayon::prelude::*;

use super::store::SegmentStore;
use crate::lt::shapes::Triangle;
use crate::lt::Scene;

/// `detp.edge`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeMode {
    /// The paper's method.
    Paper,
    /// Per-disc radius = κ × the distance to the nearest other surface, clamped to [min·d, d]
    /// (`min`: the fraction `detp.edge_min_radius`; κ: `detp.edge_radius_factor`).
    ClampRadius {
        /// r_min / d.
        min: f64,
        /// κ.
        factor: f64,
    },
    /// Crossings counted up to `gap·d` beyond the first impact (`gap`: `detp.edge_gap`).
    FirstHit {
        /// The allowance beyond the first impact, over d.
        gap: f64,
    },
    /// Both: clamped radii and crossings cut at the first impact.
    ClampFirstHit {
        /// r_min / d.
        min: f64,
        /// κ.
        factor: f64,
        /// The allowance beyond the first impact, over d.
        gap: f64,
    },
}

impl EdgeMode {
    /// r_min / d when discs get their own radius.
    pub fn clamp_min(self) -> Option<f64> {
        match self {
            EdgeMode::ClampRadius { min, .. } | EdgeMode::ClampFirstHit { min, .. } => Some(min),
            _ => None,
        }
    }

    /// κ, the factor on the edge distance, when discs get their own radius.
    pub fn clamp_factor(self) -> Option<f64> {
        match self {
            EdgeMode::ClampRadius { factor, .. } | EdgeMode::ClampFirstHit { factor, .. } => {
                Some(factor)
            }
            _ => None,
        }
    }

    /// The first-hit allowance over d when segments are cut.
    pub fn first_hit_gap(self) -> Option<f64> {
        match self {
            EdgeMode::FirstHit { gap } | EdgeMode::ClampFirstHit { gap, .. } => Some(gap),
            _ => None,
        }
    }
}

/// The radius of each disc under [`EdgeMode::ClampRadius`]: `factor` (κ > 0) times the distance s
/// from centre `c[i]` to the nearest surface of `scene` that is not the disc's own plane (see the
/// module doc), clamped to [min·d, d]. The search reaches d/κ, the farthest s that can still bind
/// (κ·s ≥ d beyond it), so κ·min(s, d/κ) clamped is κ·s clamped. With κ = 1 this is the distance
/// itself, bit for bit (d/1 = d, 1·s = s). Parallel over discs; each radius depends only on its own
/// disc.
pub fn clamped_radii(
    scene: &Scene,
    c: &[DVec3],
    n: &[DVec3],
    d: f64,
    min: f64,
    factor: f64,
) -> Vec<f64> {
    assert!(
        factor > 0.0 && factor.is_finite(),
        "κ = {factor} must be > 0"
    );
    let lo = (min * d).min(d);
    let mut r = edge_distances(scene, c, n, d / factor);
    r.iter_mut().for_each(|s| *s = (factor * *s).clamp(lo, d));
    r
}

/// s for every point, whatever the edge mode: the distance from centre `c[i]` (normal `n[i]`) to the
/// nearest surface of `scene` that is not the point's own plane ([`nearest_other_surface`]), capped
/// at `reach` (`reach` itself means "none nearer"). The hard cases are read against s/d; the points
/// table carries it (`edge_distance`). The boundary of the point's own plane is not an edge here: a
/// disc that hangs over an open rim reaches into free space, not into a solid. Parallel over
/// points; each value depends only on its own point.
pub fn edge_distances(scene: &Scene, c: &[DVec3], n: &[DVec3], reach: f64) -> Vec<f64> {
    assert_eq!(c.len(), n.len(), "one normal per point");
    c.par_iter()
        .zip(n)
        .map(|(&p, &nn)| nearest_other_surface(scene, p, nn, reach))
        .collect()
}

/// Distance from `p` to the nearest surface of `scene` other than the plane through `p` with normal
/// `n` (triangles lying in that plane and facing the same way, and a sphere `p` lies on, are the
/// point's own surface), or `reach` if none is nearer.
pub fn nearest_other_surface(scene: &Scene, p: DVec3, n: DVec3, reach: f64) -> f64 {
    // Tolerance for "lies in the plane": rounding of the points and vertices, far below any d.
    let tol = scene.precision().offset() + 1e-9 * reach;
    let mut best = reach;
    scene.triangles_near(p, reach, &mut |i| {
        let t = &scene.triangles[i as usize];
        if own_plane(t, p, n, tol) {
            return;
        }
        best = best.min(distance_to_triangle(p, t));
    });
    for b in &scene.balls {
        let g = ((p - b.center).length() - b.radius).abs();
        if g > tol {
            best = best.min(g);
        }
    }
    best
}

/// Does triangle `t` lie in the plane (p, n) and face the same way?
fn own_plane(t: &Triangle, p: DVec3, n: DVec3, tol: f64) -> bool {
    t.v.iter().all(|v| (*v - p).dot(n).abs() <= tol) && t.cross().dot(n) > 0.0
}

/// Euclidean distance from `p` to the closed triangle `t` (Ericson, Real-Time Collision Detection
/// §5.1.5: the closest point by Voronoi regions).
pub fn distance_to_triangle(p: DVec3, t: &Triangle) -> f64 {
    let [a, b, c] = t.v;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    let q = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        let vc = d1 * d4 - d3 * d2;
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            a + ab * (d1 / (d1 - d3))
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            a + ac * (d2 / (d2 - d6))
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let den = 1.0 / (va + vb + vc);
            a + ab * (vb * den) + ac * (vc * den)
        }
    };
    (p - q).length()
}

/// [`EdgeMode::FirstHit`] on a store: every segment's counted end moves to at most `gap` beyond its
/// first impact. Done once, before the engines run, so they all read the same stored segments.
pub fn clip_to_first_hit(store: &mut SegmentStore, gap: f64) {
    let g = gap as f32;
    store.segments.par_iter_mut().for_each(|s| {
        s.t_end = s.t_end.min(s.t_hit + g);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Triangle {
        Triangle {
            v: [DVec3::from(a), DVec3::from(b), DVec3::from(c)],
            surface: 0,
        }
    }

    #[test]
    fn distance_to_triangle_matches_a_dense_sampling() {
        let t = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.2, 0.9, 0.1]);
        let probes = [
            DVec3::new(0.3, 0.3, 0.5),
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(2.0, 0.1, -0.3),
            DVec3::new(0.5, -0.4, 0.2),
            DVec3::new(0.2, 2.0, 0.0),
            DVec3::new(0.9, 0.8, 0.0),
        ];
        for p in probes {
            // Minimum over a fine barycentric grid: ≥ the exact distance, within the grid's step.
            let k = 400;
            let mut m = f64::INFINITY;
            for i in 0..=k {
                for j in 0..=(k - i) {
                    let (u, v) = (f64::from(i) / f64::from(k), f64::from(j) / f64::from(k));
                    let q = t.v[0] + (t.v[1] - t.v[0]) * u + (t.v[2] - t.v[0]) * v;
                    m = m.min((p - q).length());
                }
            }
            let d = distance_to_triangle(p, &t);
            assert!(
                d <= m + 1e-12 && m - d < 3e-3,
                "{p}: exact {d}, sampled {m}"
            );
        }
    }

    /// A unit box standing on a floor: s per point equals the exhaustive minimum over the triangles
    /// that are not the point's own plane, capped at the reach, and the clamped radii are s clamped.
    #[test]
    fn edge_distances_match_an_exhaustive_search_and_give_the_clamped_radii() {
        let text = "[[surface]]\nkind = \"quad\"\nvertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]\nalbedo = 0.5\n\
            [[surface]]\nkind = \"quad\"\nvertices = [[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]]\nalbedo = 0.5\n\
            [[surface]]\nkind = \"quad\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]]\nalbedo = 0.5\n\
            [[surface]]\nkind = \"quad\"\nvertices = [[0, 0, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]]\nalbedo = 0.5\n\
            [[surface]]\nkind = \"quad\"\nvertices = [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]]\nalbedo = 0.5\n\
            [[light]]\nkind = \"point\"\nposition = [0, 3, 0]\npower = 1.0\n";
        let s = Scene::parse(text, std::path::Path::new("box.toml")).expect("scene");
        let mut c = vec![
            DVec3::new(-0.3, 0.0, 0.5), // beside the face x = 0 (and the bottom's edge)
            DVec3::new(2.0, 0.0, 2.0),  // √2 from the box's corner edge, beyond the reach
            DVec3::new(0.5, 1.0, 0.5),  // the top: its side faces meet it 0.5 away
        ];
        let mut n = vec![DVec3::Y; 3];
        let mut rng = crate::sample::rng::stream(&[42]);
        for _ in 0..40 {
            let (x, z): (f64, f64) = (
                rand::Rng::gen_range(&mut rng, -2.0..3.0),
                rand::Rng::gen_range(&mut rng, -2.0..3.0),
            );
            let on_top = (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&z);
            c.push(DVec3::new(x, if on_top { 1.0 } else { 0.0 }, z));
            n.push(DVec3::Y);
        }
        let reach = 1.0;
        let got = edge_distances(&s, &c, &n, reach);
        assert!(
            (got[0] - 0.3).abs() < 1e-12 && got[1] == reach && (got[2] - 0.5).abs() < 1e-12,
            "{got:?}"
        );
        let tol = 1e-9 * s.magnitude() + 1e-9 * reach;
        for ((p, nn), g) in c.iter().zip(&n).zip(&got) {
            let want = s
                .triangles
                .iter()
                .filter(|t| !own_plane(t, *p, *nn, tol))
                .map(|t| distance_to_triangle(*p, t))
                .fold(reach, f64::min);
            assert_eq!(*g, want, "{p}");
        }
        let radii = clamped_radii(&s, &c, &n, reach, 0.25, 1.0);
        for (r, g) in radii.iter().zip(&got) {
            assert_eq!(*r, g.clamp(0.25, reach));
        }
        // κ ≠ 1: κ·s clamped, s from the exhaustive search with no cap (a cap at d would be wrong
        // for κ < 1, where s up to d/κ still binds).
        for factor in [0.5, 0.8, 2.0] {
            let radii = clamped_radii(&s, &c, &n, reach, 0.25, factor);
            for ((p, nn), r) in c.iter().zip(&n).zip(&radii) {
                let s_all = s
                    .triangles
                    .iter()
                    .filter(|t| !own_plane(t, *p, *nn, tol))
                    .map(|t| distance_to_triangle(*p, t))
                    .fold(f64::INFINITY, f64::min);
                let want = (factor * s_all).clamp(0.25, reach);
                assert!(
                    (r - want).abs() <= 1e-12,
                    "κ = {factor}, {p}: {r} vs {want}"
                );
            }
        }
    }

    #[test]
    fn own_plane_needs_the_plane_and_the_same_facing() {
        let floor = tri([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]); // normal +y
        let p = DVec3::new(0.2, 0.0, 0.2);
        assert!(floor.cross().dot(DVec3::Y) > 0.0);
        assert!(own_plane(&floor, p, DVec3::Y, 1e-12));
        // The same triangle facing down (a box's bottom on the floor) is another surface.
        let bottom = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        assert!(!own_plane(&bottom, p, DVec3::Y, 1e-12));
        // Parallel but raised: another surface.
        let raised = tri([0.0, 0.1, 0.0], [0.0, 0.1, 1.0], [1.0, 0.1, 0.0]);
        assert!(!own_plane(&raised, p, DVec3::Y, 1e-12));
    }
}
