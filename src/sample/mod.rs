//! Reproducible randomness: streams keyed by logical work items, and the samplers built on them
//! (directions, lines, Poisson counts, keyed nested subsamples, and the radius laws of [`radius`], which `theory` integrates
//! and `scene` draws from).

pub mod counter;
pub mod directions;
pub mod lines;
pub mod philox;
pub mod radius;
pub mod rng;
pub mod subset;

pub use rng::Stream;

/// A Poisson(μ) count: inversion for small means (exact and cheap for the near-empty blocks of a
/// lazy scene), rand_distr's sampler above.
pub fn poisson<R: rand::Rng + ?Sized>(rng: &mut R, mu: f64) -> u64 {
    if mu <= 0.0 {
        return 0;
    }
    if mu < 30.0 {
        let u: f64 = rng.gen();
        let (mut k, mut p) = (0u64, (-mu).exp());
        let mut cdf = p;
        while u > cdf && k < 1000 {
            k += 1;
            p *= mu / k as f64;
            cdf += p;
        }
        return k;
    }
    use rand_distr::Distribution;
    rand_distr::Poisson::new(mu)
        .expect("mu is finite and positive")
        .sample(rng) as u64
}

/// [`poisson`] for one fixed mean, with its CDF precomputed: the same draw from the same stream, the
/// same result, without an `exp` and a loop per draw (the lazy scenes draw a count per block or
/// slab, most of them zero).
#[derive(Clone, Debug, Default)]
pub struct PoissonTable {
    mu: f64,
    /// `cdf[k]`: the running sum of [`poisson`]'s loop after `k` steps, computed with the same
    /// operations in the same order, up to where it stops growing (empty from 30 on, where
    /// [`poisson`] uses another sampler).
    cdf: Vec<f64>,
}

impl PoissonTable {
    /// The table for mean `mu`.
    pub fn new(mu: f64) -> Self {
        let mut cdf = Vec::new();
        if mu > 0.0 && mu < 30.0 {
            let (mut k, mut p) = (0u64, (-mu).exp());
            let mut c = p;
            cdf.push(c);
            while k < 1000 {
                k += 1;
                p *= mu / k as f64;
                let next = c + p;
                if next == c {
                    break;
                }
                c = next;
                cdf.push(c);
            }
        }
        Self { mu, cdf }
    }

    /// The mean.
    pub fn mean(&self) -> f64 {
        self.mu
    }

    /// One draw, equal to `poisson(rng, mu)` on the same stream.
    #[inline(always)]
    pub fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> u64 {
        if self.cdf.is_empty() {
            return poisson(rng, self.mu);
        }
        let u: f64 = rng.gen();
        // The loop stops at the first k with u ≤ cdf[k] (or at k = 1000): the number of leading
        // entries below u. The first four are counted without branches (small means end there).
        let head = self.cdf.len().min(4);
        let below = self.cdf[..head]
            .iter()
            .map(|&c| usize::from(c < u))
            .sum::<usize>();
        if below < head {
            return below as u64;
        }
        match self.cdf[head..]
            .iter()
            .position(|&c| u <= c)
            .map(|k| k + head)
        {
            Some(k) => k as u64,
            // Beyond the table the running sum no longer grows: the loop runs on to its cap.
            None => 1000,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tabled Poisson draw equals `sample::poisson` on the same stream, for many seeds and
    /// means (including the tail beyond the table and the other sampler from 30 on).
    #[test]
    fn tabled_poisson_equals_the_sampler() {
        for mu in [0.01, 0.125, 1.0, 8.0, 17.3, 29.9, 30.0, 108.0] {
            let table = PoissonTable::new(mu);
            for seed in 0..20_000u64 {
                let (mut a, mut b) = (
                    counter::SplitMix64::new(seed),
                    counter::SplitMix64::new(seed),
                );
                assert_eq!(
                    table.sample(&mut a),
                    poisson(&mut b, mu),
                    "mu {mu} seed {seed}"
                );
            }
        }
    }
}
