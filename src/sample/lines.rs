//! μ-random (isotropic uniform) lines through the unit sphere, the DETP paper's Alg. 4.1/4.2: a line
//! through two independent points uniform on the sphere's surface is uniformly distributed among the
//! lines that meet the ball.

use glam::DVec3;
use rand::Rng;

/// A point uniform on the unit sphere's surface by the paper's recipe: z ~ U[−1, 1], φ ~ U[0, 2π),
/// θ = asin z, point = (cos θ cos φ, cos θ sin φ, z).
pub fn uniform_on_sphere<R: Rng + ?Sized>(rng: &mut R) -> DVec3 {
    let z: f64 = rng.gen_range(-1.0..=1.0);
    let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
    let cos_theta = z.asin().cos();
    DVec3::new(cos_theta * phi.cos(), cos_theta * phi.sin(), z)
}

/// A μ-random line meeting the unit ball, as (point on the sphere, unit direction to a second point).
pub fn uniform_line<R: Rng + ?Sized>(rng: &mut R) -> (DVec3, DVec3) {
    loop {
        let p = uniform_on_sphere(rng);
        let q = uniform_on_sphere(rng);
        let d = q - p;
        if d.length_squared() > 1e-24 {
            return (p, d.normalize());
        }
    }
}

/// A point uniform in the unit ball (rejection from the cube [−1, 1]³: acceptance π/6).
pub fn uniform_in_ball<R: Rng + ?Sized>(rng: &mut R) -> DVec3 {
    loop {
        let p = DVec3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        if p.length_squared() <= 1.0 {
            return p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::rng::stream;

    /// Integral geometry: a μ-random line meeting the unit ball meets a concentric ball of radius q
    /// with probability q² (ratio of surface areas).
    #[test]
    fn inner_ball_hit_fraction_is_area_ratio() {
        let mut rng = stream(&[11]);
        let (q, n) = (0.5_f64, 200_000);
        let mut hits = 0u32;
        for _ in 0..n {
            let (p, d) = uniform_line(&mut rng);
            let foot = p - p.dot(d) * d;
            if foot.length() <= q {
                hits += 1;
            }
        }
        let f = f64::from(hits) / f64::from(n);
        let se = (q * q * (1.0 - q * q) / f64::from(n)).sqrt();
        assert!((f - q * q).abs() < 5.0 * se, "fraction {f} vs {}", q * q);
    }

    /// Uniform in the ball: P(|p| ≤ s) = s³, and the mean point is the centre.
    #[test]
    fn ball_points_fill_the_volume_uniformly() {
        let mut rng = stream(&[12]);
        let n = 200_000;
        let (mut inner, mut mean) = (0u32, DVec3::ZERO);
        for _ in 0..n {
            let p = uniform_in_ball(&mut rng);
            assert!(p.length() <= 1.0);
            inner += u32::from(p.length() <= 0.5);
            mean += p;
        }
        let f = f64::from(inner) / f64::from(n);
        let se = (0.125 * 0.875 / f64::from(n)).sqrt();
        assert!((f - 0.125).abs() < 5.0 * se, "{f}");
        assert!((mean / f64::from(n)).abs().max_element() < 5.0 * (0.2 / f64::from(n)).sqrt());
    }
}
