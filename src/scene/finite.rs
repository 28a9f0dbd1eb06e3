//! Finite Poisson scenes: sphere centres uniform in a cube, at intensity ρ, built into a real grid.
//!
//! Two ways to fix the size: a side length (the count is Poisson(ρ·L³), split into classes as
//! independent Poisson processes of intensity α_i·ρ) or an exact count n (side (n/ρ)^⅓, each sphere's
//! class drawn with probability α_i): the n of the paper's E[t(n)].

use crate::sample::directions::uniform_unit_cube;
use glam::DVec3;
use rand::Rng;
use rayon::prelude::*;

use super::{RadiusClass, RadiusDraw};
use crate::geom::{Aabb, Sphere};
use crate::sample::rng::stream;

/// How large a finite scene is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FiniteSize {
    /// Cube side L; the number of spheres is Poisson(ρL³).
    Side(f64),
    /// Exactly n spheres; the side is (n/ρ)^⅓.
    Count(u64),
}

/// Everything that defines one finite scene realisation.
#[derive(Clone, Debug, PartialEq)]
pub struct FiniteScene {
    /// ρ, centres per unit volume.
    pub intensity: f64,
    /// Radius classes (fractions sum to 1).
    pub classes: Vec<RadiusClass>,
    /// When radii are drawn.
    pub draw: RadiusDraw,
    /// Side or count.
    pub size: FiniteSize,
    /// Centre of the cube (the eye sits here); non-zero to test large coordinates.
    pub center: DVec3,
}

impl FiniteScene {
    /// The cube side L.
    pub fn side(&self) -> f64 {
        match self.size {
            FiniteSize::Side(l) => l,
            FiniteSize::Count(n) => (n as f64 / self.intensity).cbrt(),
        }
    }

    /// Expected number of spheres.
    pub fn expected_count(&self) -> f64 {
        match self.size {
            FiniteSize::Side(l) => self.intensity * l * l * l,
            FiniteSize::Count(n) => n as f64,
        }
    }

    /// The cube holding the centres.
    pub fn centre_box(&self) -> Aabb {
        let h = DVec3::splat(0.5 * self.side());
        Aabb::new(self.center - h, self.center + h)
    }

    /// Largest radius any sphere can have.
    pub fn max_radius(&self) -> f64 {
        self.classes
            .iter()
            .map(|c| c.radius.max())
            .fold(0.0, f64::max)
    }

    /// Generates the spheres of the realisation keyed by `key` (ids are indices). Chunks of spheres
    /// draw from their own streams, so the result does not depend on the thread count.
    pub fn generate(&self, key: &[u64]) -> Vec<Sphere> {
        let mut master = stream(key);
        let per_scene: Vec<f64> = self
            .classes
            .iter()
            .map(|c| c.radius.sample(&mut master))
            .collect();
        // Class of every sphere, as counts per class in a fixed order.
        let counts: Vec<u64> = match self.size {
            FiniteSize::Side(l) => self
                .classes
                .iter()
                .map(|c| {
                    crate::sample::poisson(&mut master, c.fraction * self.intensity * l * l * l)
                })
                .collect(),
            FiniteSize::Count(n) => {
                let mut counts = vec![0u64; self.classes.len()];
                let mut left = n;
                let mut mass = 1.0;
                for (i, c) in self.classes.iter().enumerate() {
                    let k = if i + 1 == self.classes.len() || mass <= 0.0 {
                        left
                    } else {
                        binomial(&mut master, left, (c.fraction / mass).min(1.0))
                    };
                    counts[i] = k;
                    left -= k;
                    mass -= c.fraction;
                }
                counts
            }
        };
        let total: u64 = counts.iter().sum();
        let class_of = |idx: u64| {
            let mut acc = 0;
            for (i, &k) in counts.iter().enumerate() {
                acc += k;
                if idx < acc {
                    return i;
                }
            }
            counts.len() - 1
        };
        const CHUNK: u64 = 1 << 16;
        let b = self.centre_box();
        let chunks = total.div_ceil(CHUNK);
        (0..chunks)
            .into_par_iter()
            .flat_map_iter(|ci| {
                let mut rng = stream(&[key, &[0x6368_756e, ci]].concat());
                let lo = ci * CHUNK;
                let hi = (lo + CHUNK).min(total);
                let per_scene = &per_scene;
                (lo..hi)
                    .map(move |idx| {
                        let class = class_of(idx);
                        let u = uniform_unit_cube(&mut rng);
                        let r = match self.draw {
                            RadiusDraw::PerScene => per_scene[class],
                            RadiusDraw::PerSphere => self.classes[class].radius.sample(&mut rng),
                        };
                        Sphere {
                            c: b.lo + u * (b.hi - b.lo),
                            r,
                            id: idx,
                        }
                    })
                    .collect::<Vec<_>>()
            })
            .collect()
    }
}

/// Binomial(n, p) by rand_distr.
fn binomial<R: Rng + ?Sized>(rng: &mut R, n: u64, p: f64) -> u64 {
    use rand_distr::Distribution;
    rand_distr::Binomial::new(n, p.clamp(0.0, 1.0))
        .expect("valid binomial")
        .sample(rng)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RadiusDist;

    fn scene(size: FiniteSize) -> FiniteScene {
        FiniteScene {
            intensity: 2.0,
            classes: vec![
                RadiusClass {
                    fraction: 0.25,
                    radius: RadiusDist::Constant(0.3),
                },
                RadiusClass {
                    fraction: 0.75,
                    radius: RadiusDist::Uniform { lo: 0.05, hi: 0.1 },
                },
            ],
            draw: RadiusDraw::PerSphere,
            size,
            center: DVec3::new(1e3, 0.0, 0.0),
        }
    }

    #[test]
    fn exact_count_scene_has_n_spheres_inside_the_cube_with_class_fractions() {
        let s = scene(FiniteSize::Count(100_000));
        let spheres = s.generate(&[1, 2]);
        assert_eq!(spheres.len(), 100_000);
        let b = s.centre_box();
        assert!(spheres.iter().all(|x| b.distance_squared(x.c) == 0.0));
        let big = spheres.iter().filter(|x| x.r == 0.3).count() as f64 / 1e5;
        assert!((big - 0.25).abs() < 5.0 * (0.25f64 * 0.75 / 1e5).sqrt());
        assert_eq!(spheres, s.generate(&[1, 2]), "same key, same scene");
    }

    #[test]
    fn side_scene_count_is_poisson() {
        let s = scene(FiniteSize::Side(20.0));
        let n = s.generate(&[3]).len() as f64;
        let mu = 2.0 * 8000.0;
        assert!((n - mu).abs() < 5.0 * mu.sqrt());
    }
}
