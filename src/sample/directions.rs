//! Uniform directions on the unit sphere (the paper's image sphere as resolution → ∞).

use glam::DVec3;
use rand::Rng;

/// A direction uniform on the unit sphere: z uniform in [−1, 1], azimuth uniform (Archimedes).
#[inline]
pub fn uniform_direction<R: Rng + ?Sized>(rng: &mut R) -> DVec3 {
    let z: f64 = rng.gen_range(-1.0..=1.0);
    let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// A direction cosine-distributed about the unit normal `n` (density cos θ / π): how a diffuse
/// surface emits and reflects, shared by the photon tracer and the reference path tracer.
#[inline]
pub fn cosine_about<R: Rng + ?Sized>(rng: &mut R, n: DVec3) -> DVec3 {
    let (u1, u2): (f64, f64) = (rng.gen(), rng.gen());
    let r = u1.sqrt();
    let phi = std::f64::consts::TAU * u2;
    let (a, b) = n.any_orthonormal_pair();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// A point uniform in the unit cube `[0, 1)³`.
#[inline]
pub fn uniform_unit_cube<R: Rng + ?Sized>(rng: &mut R) -> DVec3 {
    DVec3::new(rng.gen(), rng.gen(), rng.gen())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::rng::stream;

    #[test]
    fn directions_are_unit_and_isotropic() {
        let mut rng = stream(&[7]);
        let n = 200_000;
        let (mut mean, mut abs_x) = (DVec3::ZERO, 0.0);
        for _ in 0..n {
            let d = uniform_direction(&mut rng);
            assert!((d.length() - 1.0).abs() < 1e-12);
            mean += d;
            abs_x += d.x.abs();
        }
        mean /= n as f64;
        // Each component has variance 1/3: SE of the mean = sqrt(1/(3n)); allow 5 SE.
        let se = (1.0 / (3.0 * n as f64)).sqrt();
        assert!(mean.abs().max_element() < 5.0 * se, "mean {mean}");
        // E|d_x| = 1/2 with variance 1/3 − 1/4 = 1/12.
        let se_abs = (1.0 / (12.0 * n as f64)).sqrt();
        assert!((abs_x / n as f64 - 0.5).abs() < 5.0 * se_abs);
    }
}
