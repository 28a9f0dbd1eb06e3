//! Direct light at a point by next-event estimation alone (`detp.direct = "nee"`): the
//! first term of [`crate::lt::reference`]'s sum, with the same physics and the same functions
//! ([`add_delta_lights`], [`add_area_samples`]). Point and spot lights are exact (one shadow ray
//! each, no random draw); area lights are the mean of S samples (a point uniform over each light's
//! area and a shadow ray), with its standard error.
//!
//! DETP then estimates only the rest, the indirect light, from the segments after the first bounce
//! ([`crate::detp::indirect`]): E = E_direct(NEE) + E_indirect(DETP). The direct part is one number
//! per point, the same for every DETP engine, so adding it keeps the engines' bit-for-bit agreement.
//!
//! Point i of replica r draws from `[DIRECT, seed, r, i]`: independent of the reference and of
//! the path-tracing competitor, and new in every replica (so a spread across replicas includes
//! the direct part's own noise).

use glam::DVec3;
use rayon::prelude::*;

use super::reference::{add_area_samples, add_delta_lights, Irradiance, Lights, RayTally};
use super::Scene;
use crate::sample::rng::{domain, stream};

/// The direct irradiance at every (point, normal) of replica `replica` (normals need not be unit
/// length), with `area_samples` samples per area light, and the rays it cast. Without area lights
/// the value is exact (SE 0) and `area_samples` is not used; with them and one sample, the SE is NaN.
///
/// # Panics
/// If the points and normals differ in number, or `area_samples` is 0.
pub fn direct_irradiance(
    scene: &Scene,
    points: &[DVec3],
    normals: &[DVec3],
    area_samples: u64,
    seed: u64,
    replica: u64,
) -> (Vec<Irradiance>, RayTally) {
    assert_eq!(points.len(), normals.len(), "one normal per point");
    assert!(area_samples >= 1, "at least one area-light sample");
    let lights = Lights::new(scene);
    let per_point: Vec<(Irradiance, RayTally)> = points
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (&p, &n))| {
            let n = n.normalize();
            let mut tally = RayTally::default();
            let mut delta = 0.0;
            add_delta_lights(scene, scene, p, n, None, &mut tally, &mut delta);
            if !lights.any_area() {
                return (
                    Irradiance {
                        mean: delta,
                        se: 0.0,
                    },
                    tally,
                );
            }
            let mut rng = stream(&[domain::DIRECT, seed, replica, i as u64]);
            let (mut mean, mut m2) = (0.0, 0.0);
            for k in 1..=area_samples {
                let mut x = 0.0;
                add_area_samples(
                    scene, scene, &lights, &mut rng, p, n, None, &mut tally, &mut x,
                );
                let d = x - mean;
                mean += d / k as f64;
                m2 += d * (x - mean);
            }
            let se = if area_samples >= 2 {
                (m2 / (area_samples - 1) as f64 / area_samples as f64).sqrt()
            } else {
                f64::NAN
            };
            let mean = delta + mean;
            (Irradiance { mean, se }, tally)
        })
        .collect();
    let mut rays = RayTally::default();
    let values = per_point
        .into_iter()
        .map(|(e, t)| {
            rays.path += t.path;
            rays.shadow += t.shadow;
            e
        })
        .collect();
    (values, rays)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::lt::reference::tests::{
        point_light_over_plane, polygon_irradiance, rectangle, rectangle_probes, scene, LAMP,
    };

    /// A point light over a *reflecting* plane: the direct part is still Φ·h/(4π(h² + x²)^{3/2})
    /// exactly (SE 0, one shadow ray, no continuation ray), whatever the indirect light.
    #[test]
    fn a_point_light_is_exact_whatever_the_albedo() {
        let s = point_light_over_plane(0.7);
        let pts = [
            DVec3::ZERO,
            DVec3::new(1.5, 0.0, 0.0),
            DVec3::new(-2.0, 0.0, 2.0),
        ];
        let (got, rays) = direct_irradiance(&s, &pts, &[DVec3::Y; 3], 1, 1, 0);
        for (p, g) in pts.iter().zip(&got) {
            let x2 = p.x * p.x + p.z * p.z;
            let want = 100.0 * 1.0 / (4.0 * PI * (1.0 + x2).powf(1.5));
            assert!((g.mean - want).abs() < 1e-12 * want, "{p}: {g:?} vs {want}");
            assert_eq!(g.se, 0.0);
        }
        assert_eq!(rays, RayTally { path: 0, shadow: 3 });
    }

    /// A Lambertian rectangle over a reflecting floor (albedo 0.5): the direct part is Lambert's polygon
    /// formula, within its SE, at upright and tilted normals.
    #[test]
    fn a_lambertian_rectangle_is_lamberts_polygon_formula() {
        let s = rectangle(0.5);
        let (pts, normals) = rectangle_probes();
        let (got, rays) = direct_irradiance(&s, &pts, &normals, 20_000, 7, 0);
        for ((p, n), g) in pts.iter().zip(&normals).zip(&got) {
            let want = polygon_irradiance(2.0, &LAMP, *p, *n);
            let z = (g.mean - want) / g.se;
            assert!(g.se > 0.0 && g.se < 0.02 * want, "{p}: {g:?}");
            assert!(z.abs() < 4.0, "{p}: {g:?} vs {want} (z = {z})");
        }
        assert_eq!(rays.path, 0);
        assert!(rays.shadow <= 4 * 20_000);
        // Replicas are new samples; the same replica is the same sample.
        let again = direct_irradiance(&s, &pts, &normals, 20_000, 7, 0).0;
        assert_eq!(again, got);
        assert_ne!(direct_irradiance(&s, &pts, &normals, 20_000, 7, 1).0, got);
    }

    /// Inside an emitting sphere cos θ_x cos θ_y / r² = 1/(4R²) for any two points of it, so every
    /// area sample is π·L_e: the direct part is exact though it is sampled.
    #[test]
    fn the_furnace_direct_light_is_pi_le_in_every_sample() {
        let s = scene(FURNACE);
        let pts = [DVec3::X, -DVec3::Y, DVec3::new(0.0, 0.6, 0.8)];
        let normals: Vec<DVec3> = pts.iter().map(|p| -*p).collect();
        let (got, _) = direct_irradiance(&s, &pts, &normals, 64, 3, 0);
        for g in &got {
            assert!((g.mean - PI).abs() < 1e-9, "{g:?}");
            assert!(g.se < 1e-9, "{g:?}");
        }
    }

    pub(crate) const FURNACE: &str = "[[surface]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\ninside = true\nalbedo = 0.5\nemission = 1.0\n";
}
