//! The reference: irradiance at given points and normals by Monte Carlo path tracing with next-event
//! estimation, an unbiased estimate with its own standard error, independent of DETP's discs and
//! photons. It models exactly the physics the photon tracer ([`crate::detp::photon`])
//! models, so the two estimate the same quantity:
//!
//! - **irradiance** E(x, n) = ∫ L_in(x, ω) (n·ω)⁺ dω: the power per area arriving from the
//!   hemisphere around n (DETP counts segments travelling against the normal);
//! - **area lights** emit radiance L_e on their light-receiving side only (the triangle's winding
//!   normal, a sphere's [`crate::lt::shapes::Ball::normal_at`]: inward for a sphere seen from
//!   inside), Lambertian: power π·L_e·area, as photons leave cosine-distributed about that normal;
//! - **point lights** have intensity Φ/4π; **spot lights** Φ / (2π(1 − cos θ_c)) inside their cone
//!   (photons are uniform in its solid angle) and 0 outside; neither can be hit;
//! - **reflection** is diffuse and two-sided with the surface's albedo α, emitting surfaces
//!   included: light arriving on either side leaves on that side, radiance α·E/π;
//! - paths stop after [`MAX_BOUNCES`] reflections, as photon paths do.
//!
//! One sample of E at x: at each path vertex the direct light (every point and spot light, one
//! area sample on every area light, each with a shadow ray), then a cosine-distributed direction to
//! the next surface, which the path reaches and continues from with probability α (Russian roulette
//! with the albedo: with cosine sampling the weight π·(α/π)/α is 1, so a sample is the plain sum of
//! the direct terms along its path). Emission met by a path ray is not added (the direct term
//! already counts it). Samples at point i draw from the stream `[REFERENCE, key, i]` one after
//! another, so a point's estimate depends on neither the thread count nor the other points.
//!
//! The pieces are public so that other estimators reuse this very physics rather than a copy
//! (per-point path tracing): [`Lights`] (the area lights' sampling tables), [`add_delta_lights`] and
//! [`add_area_samples`] (next-event estimation at one vertex: [`crate::lt::direct`] averages them
//! for the direct light alone) and [`sample`] (one path: [`crate::lt::pathtrace`] runs it on its own
//! streams as a competitor). Each counts the rays it casts in a [`RayTally`].

use std::f64::consts::PI;

use glam::DVec3;
use rand::Rng;
use rayon::prelude::*;

use super::cast::Caster;
use super::{Light, Prim, Scene};
use crate::sample::directions::{cosine_about, uniform_direction};
use crate::sample::rng::{domain, stream};

use super::MAX_BOUNCES;

/// The estimate at one point: mean over its samples and the standard error of that mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Irradiance {
    /// Mean of the samples (W/m² in the scene's units).
    pub mean: f64,
    /// Standard error of the mean, from the samples' variance.
    pub se: f64,
}

/// The irradiance at every (point, normal) from `samples` paths each; point i draws from the
/// stream `[REFERENCE, key, i]`. Normals need not be unit length.
pub fn irradiance(
    scene: &Scene,
    points: &[DVec3],
    normals: &[DVec3],
    samples: u64,
    key: u64,
) -> Vec<Irradiance> {
    irradiance_with(scene, scene, points, normals, samples, key).0
}

/// [`irradiance`] with the rays cast by `caster` (the scene's own core, or Embree in
/// `raycost bench`), and the number of rays cast (path and shadow rays).
pub fn irradiance_with<C: Caster>(
    scene: &Scene,
    caster: &C,
    points: &[DVec3],
    normals: &[DVec3],
    samples: u64,
    key: u64,
) -> (Vec<Irradiance>, u64) {
    assert_eq!(points.len(), normals.len(), "one normal per point");
    assert!(samples >= 2, "a standard error needs two samples");
    let lights = Lights::new(scene);
    let (est, rays): (Vec<Irradiance>, Vec<u64>) = points
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (&p, &n))| {
            let mut rng = stream(&[domain::REFERENCE, key, i as u64]);
            let n = n.normalize();
            // Welford: stable for the long tails of rare bright paths.
            let (mut mean, mut m2) = (0.0, 0.0);
            let mut tally = RayTally::default();
            for k in 0..samples {
                let x = sample(scene, caster, &lights, &mut rng, p, n, &mut tally);
                let delta = x - mean;
                mean += delta / (k + 1) as f64;
                m2 += delta * (x - mean);
            }
            let var = m2 / (samples - 1) as f64;
            let est = Irradiance {
                mean,
                se: (var / samples as f64).sqrt(),
            };
            (est, tally.total())
        })
        .unzip();
    (est, rays.iter().sum())
}

/// Rays cast by an estimator, by purpose: continuation rays (a path's next surface) and shadow
/// rays (next-event estimation's visibility tests). Counts are exact, so they do not depend on the
/// thread count; a renderer would add one camera ray per point, as DETP needs the same points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayTally {
    /// Continuation rays: the path's next surface (nearest hit).
    pub path: u64,
    /// Shadow rays: visibility between a vertex and a light sample.
    pub shadow: u64,
}

impl RayTally {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.path + self.shadow
    }
}

/// The area lights' sampling tables, built once per scene.
pub struct Lights {
    /// Per area light: (light index, radiance, total area, cumulative triangle areas).
    area: Vec<(usize, f64, f64, Vec<f64>)>,
}

impl Lights {
    /// The tables of `scene`'s area lights.
    pub fn new(scene: &Scene) -> Self {
        let mut area = Vec::new();
        for (li, l) in scene.lights.iter().enumerate() {
            if let Light::Area {
                surface,
                triangles,
                ball,
                ..
            } = l
            {
                let le = scene.surfaces[*surface as usize].emission;
                let mut acc = 0.0;
                let cum: Vec<f64> = triangles
                    .iter()
                    .map(|&t| {
                        acc += scene.triangles[t as usize].area();
                        acc
                    })
                    .collect();
                let total = acc + ball.map_or(0.0, |b| scene.balls[b as usize].area());
                area.push((li, le, total, cum));
            }
        }
        Self { area }
    }

    /// Does the scene have an area light (whose direct light is a random sample)?
    pub fn any_area(&self) -> bool {
        !self.area.is_empty()
    }
}

/// Self-intersection epsilon, the photon tracer's ([`crate::lt::precision::Precision::offset`]).
fn eps(scene: &Scene) -> f64 {
    scene.precision().offset()
}

/// Is the straight path from `x` (leaving primitive `from`) to `y` (on primitive `to`, if any)
/// free? Hits within ε of either end do not block (the surfaces the path starts and ends on).
///
/// The rule is on the nearest hit h: blocked iff h.t < r − ε and not (h is `to` and
/// h.t ≥ r·(1 − 10⁻⁹)). It is decided by a shadow ray (any hit before min(r − ε, r·(1 − 10⁻⁹))
/// blocks) and, only if r·(1 − 10⁻⁹) < r − ε, the nearest hit in between: the same answer as
/// finding the nearest hit, without ordering the hits before the first blocker.
fn visible<C: Caster>(
    scene: &Scene,
    caster: &C,
    x: DVec3,
    from: Option<Prim>,
    y: DVec3,
    to: Option<Prim>,
    tally: &mut RayTally,
) -> bool {
    let v = y - x;
    let r = v.length();
    let e = eps(scene);
    if r <= e {
        return false;
    }
    let d = v / r;
    let (end, on_target) = (r - e, r * (1.0 - 1e-9));
    tally.shadow += 1;
    if caster.occluded(x, d, e, end.min(on_target), from) {
        return false;
    }
    if on_target >= end {
        return true;
    }
    caster
        .first_hit_before(x, d, e, end, from)
        .is_none_or(|h| Some(h.prim) == to)
}

/// The direct irradiance at `x` with unit normal `n` (leaving primitive `from`): every point and
/// spot light exactly, one area sample per area light.
#[allow(clippy::too_many_arguments)] // the vertex (x, n, from), the caster and the sinks are distinct
fn direct<R: Rng + ?Sized, C: Caster>(
    scene: &Scene,
    caster: &C,
    lights: &Lights,
    rng: &mut R,
    x: DVec3,
    n: DVec3,
    from: Option<Prim>,
    tally: &mut RayTally,
) -> f64 {
    // One accumulator through both parts, in this order: the sum is the same float as before the
    // parts were split out.
    let mut e = 0.0;
    add_delta_lights(scene, caster, x, n, from, tally, &mut e);
    add_area_samples(scene, caster, lights, rng, x, n, from, tally, &mut e);
    e
}

/// Adds to `e` the irradiance at `x` (unit normal `n`, leaving primitive `from`) from every point
/// and spot light, exactly (one shadow ray each that faces `x`): no random draw.
pub fn add_delta_lights<C: Caster>(
    scene: &Scene,
    caster: &C,
    x: DVec3,
    n: DVec3,
    from: Option<Prim>,
    tally: &mut RayTally,
    e: &mut f64,
) {
    for l in &scene.lights {
        let (position, intensity) = match l {
            Light::Point { position, power } => (*position, power / (4.0 * PI)),
            Light::Spot {
                position,
                axis,
                cos_cone,
                power,
            } => {
                // Outside the cone nothing; inside, the power spread uniformly over its solid angle.
                let out = (x - *position).normalize_or_zero();
                if out.dot(*axis) < *cos_cone {
                    continue;
                }
                (*position, power / (2.0 * PI * (1.0 - cos_cone)))
            }
            Light::Area { .. } => continue,
        };
        let v = position - x;
        let r2 = v.length_squared();
        let cos = n.dot(v) / r2.sqrt();
        if cos > 0.0 && visible(scene, caster, x, from, position, None, tally) {
            *e += intensity * cos / r2;
        }
    }
}

/// Adds to `e` one unbiased sample of the irradiance at `x` (unit normal `n`, leaving primitive
/// `from`) from every area light: a point uniform over each light's area, one shadow ray each.
#[allow(clippy::too_many_arguments)] // the vertex (x, n, from) and the sinks (tally, e) are distinct
pub fn add_area_samples<R: Rng + ?Sized, C: Caster>(
    scene: &Scene,
    caster: &C,
    lights: &Lights,
    rng: &mut R,
    x: DVec3,
    n: DVec3,
    from: Option<Prim>,
    tally: &mut RayTally,
    e: &mut f64,
) {
    for (li, le, total, cum) in &lights.area {
        let Light::Area {
            triangles, ball, ..
        } = &scene.lights[*li]
        else {
            unreachable!("built from area lights")
        };
        // A point uniform over the light's area (a triangle in proportion to its area).
        let u = rng.gen::<f64>() * total;
        let tri_area = cum.last().copied().unwrap_or(0.0);
        let (y, ny, prim) = if u < tri_area || ball.is_none() {
            let k = cum.partition_point(|&c| c <= u).min(triangles.len() - 1);
            let t = scene.triangles[triangles[k] as usize];
            let (mut a, mut b): (f64, f64) = (rng.gen(), rng.gen());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let y = t.v[0] + (t.v[1] - t.v[0]) * a + (t.v[2] - t.v[0]) * b;
            (y, t.normal(), Prim::Triangle(triangles[k]))
        } else {
            let bi = ball.expect("checked above");
            let s = scene.balls[bi as usize];
            let y = s.center + uniform_direction(rng) * s.radius;
            (y, s.normal_at(y), Prim::Ball(bi))
        };
        let v = y - x;
        let r2 = v.length_squared();
        let r = r2.sqrt();
        let cos_x = n.dot(v) / r;
        // One-sided: x must lie on the emitting side of the light.
        let cos_y = -ny.dot(v) / r;
        if cos_x > 0.0 && cos_y > 0.0 && visible(scene, caster, x, from, y, Some(prim), tally) {
            *e += le * cos_x * cos_y / r2 * total;
        }
    }
}

/// One sample of the irradiance at `p` with unit normal `n` (see the module doc), counting the
/// rays it casts in `tally`.
pub fn sample<R: Rng + ?Sized, C: Caster>(
    scene: &Scene,
    caster: &C,
    lights: &Lights,
    rng: &mut R,
    p: DVec3,
    n: DVec3,
    tally: &mut RayTally,
) -> f64 {
    let e = eps(scene);
    let (mut x, mut nx, mut from) = (p, n, None);
    let mut total = 0.0;
    for bounce in 0..=MAX_BOUNCES {
        total += direct(scene, caster, lights, rng, x, nx, from, tally);
        if bounce == MAX_BOUNCES {
            break;
        }
        let d = cosine_about(rng, nx);
        tally.path += 1;
        let Some(h) = caster.first_hit(x, d, e, from) else {
            break;
        };
        if rng.gen::<f64>() >= scene.surfaces[h.surface as usize].albedo {
            break;
        }
        let y = x + d * h.t;
        let mut ny = scene.normal(h.prim, y);
        if ny.dot(d) > 0.0 {
            ny = -ny; // reflect on the side the path arrived from
        }
        (x, nx, from) = (y, ny, Some(h.prim));
    }
    total
}

#[cfg(test)]
pub(crate) mod tests {
    use std::path::Path;

    use super::*;

    /// A scene from its TOML text.
    pub(crate) fn scene(text: &str) -> Scene {
        Scene::parse(text, Path::new("test.toml")).expect("scene")
    }

    /// A 100 W point light at height 1 over an 8 × 8 plane of albedo `albedo`.
    pub(crate) fn point_light_over_plane(albedo: f64) -> Scene {
        scene(&format!(
            "[[surface]]\nkind = \"quad\"\nvertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]\nalbedo = {albedo:?}\n[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\npower = 100.0\n"
        ))
    }

    /// |z| of `got` against `want` in units of its SE.
    fn z(got: &Irradiance, want: f64) -> f64 {
        (got.mean - want) / got.se
    }

    #[test]
    fn a_point_light_over_a_black_plane_is_phi_cos_over_4_pi_r2() {
        let s = point_light_over_plane(0.0);
        let pts = [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.5),
            DVec3::new(-2.0, 0.0, 1.0),
        ];
        let got = irradiance(&s, &pts, &[DVec3::Y; 3], 16, 1);
        for (p, g) in pts.iter().zip(&got) {
            let r = (DVec3::Y - *p).length();
            let want = 100.0 / (4.0 * PI) / (r * r * r);
            // Deterministic on a black plane: every sample is the closed form.
            assert!((g.mean - want).abs() < 1e-12 * want, "{p}: {g:?} vs {want}");
        }
        // From below, nothing (one-sided incidence).
        let below = irradiance(&s, &[DVec3::ZERO], &[-DVec3::Y], 4, 1);
        assert_eq!(below[0].mean, 0.0);
    }

    /// Lambert's formula for a polygon of uniform radiance `le` seen from `x` with normal `n`
    /// (wholly in front of both): E = (L_e/2)·|Σ γ_i n·(R_i × R_(i+1))/|R_i × R_(i+1)||.
    pub(crate) fn polygon_irradiance(le: f64, poly: &[DVec3], x: DVec3, n: DVec3) -> f64 {
        let mut s = 0.0;
        for i in 0..poly.len() {
            let (a, b) = (poly[i] - x, poly[(i + 1) % poly.len()] - x);
            let c = a.cross(b);
            s += a.angle_between(b) * n.dot(c / c.length());
        }
        0.5 * le * s.abs()
    }

    /// A 1 × 0.5 lamp (L_e = 2, facing down) at height 1 over an 8 × 8 floor, both of albedo
    /// `albedo` (0: direct light only; above 0, some indirect light: floor → lamp → floor).
    pub(crate) fn rectangle(albedo: f64) -> Scene {
        scene(&format!(
            "[[surface]]\nname = \"floor\"\nkind = \"quad\"\nvertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]\nalbedo = {albedo:?}\n[[surface]]\nname = \"lamp\"\nkind = \"quad\"\nvertices = [[-0.5, 1, -0.25], [0.5, 1, -0.25], [0.5, 1, 0.25], [-0.5, 1, 0.25]]\nalbedo = {albedo:?}\nemission = 2.0\n"
        ))
    }

    /// The lamp's corners.
    pub(crate) const LAMP: [DVec3; 4] = [
        DVec3::new(-0.5, 1.0, -0.25),
        DVec3::new(0.5, 1.0, -0.25),
        DVec3::new(0.5, 1.0, 0.25),
        DVec3::new(-0.5, 1.0, 0.25),
    ];

    /// Floor points under and beside the lamp, with their normals (the last one tilted).
    pub(crate) fn rectangle_probes() -> ([DVec3; 4], [DVec3; 4]) {
        let tilted = DVec3::new(0.3, 1.0, -0.2).normalize();
        (
            [
                DVec3::ZERO,
                DVec3::new(0.3, 0.0, 0.1),
                DVec3::new(1.5, 0.0, -0.7),
                DVec3::new(-2.5, 0.0, 2.0),
            ],
            [DVec3::Y, DVec3::Y, DVec3::Y, tilted],
        )
    }

    #[test]
    fn a_lambertian_rectangle_over_a_black_plane_is_lamberts_polygon_formula() {
        let s = rectangle(0.0);
        // The lamp faces down: (v1 − v0) × (v2 − v0) = x × z = −y.
        assert!(s.triangles[2].normal().y < -0.99);
        let (pts, normals) = rectangle_probes();
        let got = irradiance(&s, &pts, &normals, 20_000, 7);
        for ((p, n), g) in pts.iter().zip(&normals).zip(&got) {
            let want = polygon_irradiance(2.0, &LAMP, *p, *n);
            println!(
                "rectangle at {p}: {:.5} ± {:.5} vs {want:.5} (z = {:.2})",
                g.mean,
                g.se,
                z(g, want)
            );
            assert!(g.se > 0.0 && g.se < 0.02 * want, "{p}: {g:?}");
            assert!(z(g, want).abs() < 4.0, "{p}: {g:?} vs {want}");
        }
        // One-sided emission: above the lamp, facing it, nothing arrives.
        let above = irradiance(&s, &[DVec3::new(0.0, 2.0, 0.0)], &[-DVec3::Y], 100, 7);
        assert_eq!(above[0].mean, 0.0);
    }

    #[test]
    fn the_closed_furnace_sphere_is_pi_le_over_one_minus_albedo() {
        let s = scene("[[surface]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\ninside = true\nalbedo = 0.5\nemission = 1.0\n");
        let pts = [DVec3::X, -DVec3::Y, DVec3::new(0.0, 0.6, 0.8)];
        let normals: Vec<DVec3> = pts.iter().map(|p| -*p).collect();
        let got = irradiance(&s, &pts, &normals, 20_000, 3);
        let want = PI / (1.0 - 0.5);
        for (p, g) in pts.iter().zip(&got) {
            println!(
                "sphere at {p}: {:.5} ± {:.5} vs {want:.5} (z = {:.2})",
                g.mean,
                g.se,
                z(g, want)
            );
            assert!(g.se > 0.0, "{p}: {g:?}");
            assert!(z(g, want).abs() < 4.0, "{p}: {g:?} vs {want}");
        }
    }

    #[test]
    fn a_point_depends_on_its_index_and_key_only() {
        let s = rectangle(0.0);
        let pts = [DVec3::ZERO, DVec3::new(0.5, 0.0, 0.5)];
        let both = irradiance(&s, &pts, &[DVec3::Y; 2], 50, 9);
        let first = irradiance(&s, &pts[..1], &[DVec3::Y], 50, 9);
        assert_eq!(both[0], first[0]);
        assert_ne!(irradiance(&s, &pts[..1], &[DVec3::Y], 50, 10)[0], first[0]);
    }

    #[test]
    fn a_spot_light_is_its_power_over_the_cone_inside_and_dark_outside() {
        let s = scene(
            "[[surface]]\nkind = \"quad\"\nvertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]\nalbedo = 0.0\n[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncone_deg = 30\npower = 10.0\n",
        );
        let got = irradiance(
            &s,
            &[DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0)],
            &[DVec3::Y; 2],
            4,
            1,
        );
        let want = 10.0 / (2.0 * PI * (1.0 - 30f64.to_radians().cos()));
        assert!((got[0].mean - want).abs() < 1e-12 * want, "{got:?}");
        assert_eq!(got[1].mean, 0.0, "45° is outside a 30° cone");
    }
}
