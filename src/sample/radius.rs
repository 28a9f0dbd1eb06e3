//! Radius classes of Result 3.2: class i holds a fraction α_i of the spheres (its centres form an
//! independent Poisson process of intensity α_i·ρ) and draws radii from its own distribution.

use rand::Rng;
use statrs::distribution::{ContinuousCDF, Normal};

/// A radius distribution. Lognormal is truncated at `max` so that every sphere has a known bound
/// (the lazy scene must know how far a sphere can reach); theory integrates the same truncated law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadiusDist {
    /// Every radius equals this value.
    Constant(f64),
    /// Uniform on `[lo, hi]`, `0 < lo ≤ hi`.
    Uniform {
        /// Smallest radius.
        lo: f64,
        /// Largest radius.
        hi: f64,
    },
    /// `exp(N(ln median, sigma²))` conditioned on `≤ max`: a heavy-ish right tail.
    LogNormal {
        /// Median of the untruncated law.
        median: f64,
        /// Standard deviation of ln R.
        sigma: f64,
        /// Truncation point, > 0.
        max: f64,
    },
}

/// When a class's random radius is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadiusDraw {
    /// Each sphere draws its own radius (a marked Poisson process; the usual meaning).
    PerSphere,
    /// The whole class shares one radius R_i, drawn once per scene realisation: the paper's literal
    /// setting for Result 3.2, where E[N_I] integrates E[N_I | R_1..R_n] over the radius densities.
    PerScene,
}

/// One class: a fraction of the spheres and their radius law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusClass {
    /// α_i ∈ (0, 1]; the fractions of a scene sum to 1.
    pub fraction: f64,
    /// The class's radius law.
    pub radius: RadiusDist,
}

fn std_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("the standard normal has valid parameters")
}

impl RadiusDist {
    /// Largest radius this law can produce.
    pub fn max(&self) -> f64 {
        match *self {
            Self::Constant(r) => r,
            Self::Uniform { hi, .. } => hi,
            Self::LogNormal { max, .. } => max,
        }
    }

    /// Draws one radius.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Self::Constant(r) => r,
            Self::Uniform { lo, hi } => {
                if lo == hi {
                    lo
                } else {
                    rng.gen_range(lo..=hi)
                }
            }
            Self::LogNormal { median, sigma, max } => {
                // Inverse CDF restricted to [0, F(max)]: exact truncation, one uniform per radius.
                let n = std_normal();
                let f_max = n.cdf((max / median).ln() / sigma);
                let u: f64 = rng.gen::<f64>() * f_max;
                let z = n.inverse_cdf(u.max(f64::MIN_POSITIVE));
                (median * (sigma * z).exp()).min(max)
            }
        }
    }

    /// Gauss–Legendre nodes `(r, weight)` whose weights sum to 1, for E[g(R)] = Σ w·g(r). Exact for
    /// constants; `n` nodes per panel on the support (for lognormal, on ln r from the 1e-12 quantile
    /// to `max`, where the density is smooth).
    pub fn quadrature(&self, n: usize) -> Vec<(f64, f64)> {
        match *self {
            Self::Constant(r) => vec![(r, 1.0)],
            Self::Uniform { lo, hi } => {
                if lo == hi {
                    return vec![(lo, 1.0)];
                }
                gauss_legendre_panels(lo, hi, n, 8)
                    .into_iter()
                    .map(|(x, w)| (x, w / (hi - lo)))
                    .collect()
            }
            Self::LogNormal { median, sigma, max } => {
                let nrm = std_normal();
                let z_hi = (max / median).ln() / sigma;
                let z_lo = (-7.0_f64).min(z_hi - 1.0);
                let mass = nrm.cdf(z_hi) - nrm.cdf(z_lo);
                let pdf = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
                gauss_legendre_panels(z_lo, z_hi, n, 16)
                    .into_iter()
                    .map(|(z, w)| (median * (sigma * z).exp(), w * pdf(z) / mass))
                    .collect()
            }
        }
    }

    /// E[g(R)] by [`Self::quadrature`] with 16 nodes per panel.
    pub fn expect(&self, g: impl Fn(f64) -> f64) -> f64 {
        self.quadrature(16).into_iter().map(|(r, w)| w * g(r)).sum()
    }
}

/// Gauss–Legendre nodes and weights on `[a, b]`, split into `panels` equal panels of `n` nodes.
pub fn gauss_legendre_panels(a: f64, b: f64, n: usize, panels: usize) -> Vec<(f64, f64)> {
    let (x, w) = gauss_legendre(n);
    let h = (b - a) / panels as f64;
    let mut out = Vec::with_capacity(n * panels);
    for p in 0..panels {
        let (lo, hi) = (a + h * p as f64, a + h * (p + 1) as f64);
        for (xi, wi) in x.iter().zip(&w) {
            out.push((0.5 * (hi - lo) * xi + 0.5 * (hi + lo), 0.5 * (hi - lo) * wi));
        }
    }
    out
}

/// Gauss–Legendre nodes and weights on [−1, 1] by Newton iteration on P_n (Golub–Welsch is overkill
/// for the n ≤ 64 used here).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pn1) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::rng::stream;

    #[test]
    fn quadrature_integrates_polynomials_exactly() {
        let u = RadiusDist::Uniform { lo: 1.0, hi: 3.0 };
        assert!((u.expect(|_| 1.0) - 1.0).abs() < 1e-14);
        assert!((u.expect(|r| r) - 2.0).abs() < 1e-14);
        assert!((u.expect(|r| r * r) - 13.0 / 3.0).abs() < 1e-13);
    }

    #[test]
    fn truncated_lognormal_moments_match_sampling() {
        let d = RadiusDist::LogNormal {
            median: 0.1,
            sigma: 0.5,
            max: 0.4,
        };
        assert!((d.expect(|_| 1.0) - 1.0).abs() < 1e-12);
        let mut rng = stream(&[3]);
        let n = 400_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let r = d.sample(&mut rng);
            assert!(r > 0.0 && r <= 0.4);
            s1 += r;
            s2 += r * r;
        }
        let (m1, m2) = (s1 / n as f64, s2 / n as f64);
        let se = ((m2 - m1 * m1) / n as f64).sqrt();
        assert!(
            (m1 - d.expect(|r| r)).abs() < 5.0 * se,
            "{m1} vs {}",
            d.expect(|r| r)
        );
    }
}
