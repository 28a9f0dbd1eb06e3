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

    /// One draw of the count given that it is at least 1 (the zero-truncated law), by the same
    /// inversion with the uniform drawn on (P(0), 1): P(k | k ≥ 1) = P(k)/(1 − P(0)) exactly. Above
    /// the table (μ ≥ 30, where P(0) < 10⁻¹³) it redraws [`poisson`] until the count is positive.
    #[inline(always)]
    pub fn sample_positive<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> u64 {
        if self.cdf.is_empty() {
            if self.mu <= 0.0 {
                return 0;
            }
            loop {
                let n = poisson(rng, self.mu);
                if n > 0 {
                    return n;
                }
            }
        }
        let v: f64 = rng.gen();
        let p0 = self.cdf[0];
        let u = p0 + (1.0 - p0) * v;
        let k = match self.cdf[1..].iter().position(|&c| u <= c) {
            Some(k) => k as u64 + 1,
            None => 1000,
        };
        // u = P(0) exactly (v = 0) belongs to k = 1's interval's closed end.
        k.max(1)
    }

    /// P(count = 0) = e^{−μ}.
    pub fn p_zero(&self) -> f64 {
        (-self.mu).exp()
    }
}

/// The number of failures before the first success of independent trials that each fail with
/// probability `p_fail`: P(K = k) = p_failᵏ(1 − p_fail), by inversion, K = ⌊ln U / ln p_fail⌋ with
/// U uniform on (0, 1]. `ln_fail` is ln p_fail (precomputed by the caller; 0 when every trial fails,
/// which gives `u64::MAX`, and −∞ when none does, which gives 0). The infinite scene uses it for the
/// run of empty slabs before the next occupied one.
#[inline(always)]
pub fn geometric_failures<R: rand::Rng + ?Sized>(rng: &mut R, ln_fail: f64) -> u64 {
    let v: f64 = rng.gen();
    if ln_fail == 0.0 {
        return u64::MAX;
    }
    // u ∈ (0, 1], so ln u is finite and ≤ 0, and ln_fail < 0: the quotient is ≥ 0 (0 when
    // ln_fail = −∞); the float-to-int cast saturates.
    let u = 1.0 - v;
    (u.ln() / ln_fail).floor() as u64
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

    /// The zero-truncated draw is the plain draw's inversion on a narrower interval: on the same
    /// stream, it equals the plain draw of the uniform mapped into (P(0), 1), and is never 0. (Its
    /// law is tested by χ² in `scene::tube`, which may use `stats`.)
    #[test]
    fn positive_poisson_is_the_inversion_above_zero() {
        for mu in [0.05, 0.245, 1.0, 3.7, 12.0] {
            let table = PoissonTable::new(mu);
            for seed in 0..20_000u64 {
                let mut a = counter::SplitMix64::new(seed);
                let k = table.sample_positive(&mut a);
                let mut b = counter::SplitMix64::new(seed);
                let v: f64 = rand::Rng::gen(&mut b);
                let u = table.p_zero() + (1.0 - table.p_zero()) * v;
                let mut c = 0usize;
                while c < table.cdf.len() && table.cdf[c] < u {
                    c += 1;
                }
                assert!(k >= 1);
                assert_eq!(k, (c as u64).max(1), "mu {mu} seed {seed}");
            }
        }
    }

    /// The geometric draw has P(K = k) = qᵏ(1 − q): mean q/(1 − q) and P(K = 0) = 1 − q within 4
    /// standard errors over 2·10⁵ draws; degenerate trials give 0 and u64::MAX.
    #[test]
    fn geometric_failures_have_the_geometric_law() {
        for q in [0.1f64, 0.5, 0.78, 0.97] {
            let mut rng = counter::SplitMix64::new(0x9e0 ^ q.to_bits());
            let n = 200_000;
            let draws: Vec<f64> = (0..n)
                .map(|_| geometric_failures(&mut rng, f64::ln(q)) as f64)
                .collect();
            let mean = draws.iter().sum::<f64>() / n as f64;
            let want = q / (1.0 - q);
            let se = (q / (1.0 - q).powi(2) / n as f64).sqrt();
            assert!(
                (mean - want).abs() < 4.0 * se,
                "q {q}: mean {mean} vs {want}"
            );
            let zeros = draws.iter().filter(|&&k| k == 0.0).count() as f64 / n as f64;
            let se0 = (q * (1.0 - q) / n as f64).sqrt();
            assert!((zeros - (1.0 - q)).abs() < 4.0 * se0, "q {q}: P(0) {zeros}");
        }
        let mut rng = counter::SplitMix64::new(1);
        assert_eq!(geometric_failures(&mut rng, f64::NEG_INFINITY), 0);
        assert_eq!(geometric_failures(&mut rng, 0.0), u64::MAX);
    }
}
