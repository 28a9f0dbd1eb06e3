//! Reproducible randomness: streams keyed by logical work items, and the samplers built on them.

pub mod counter;
pub mod directions;
pub mod lines;
pub mod rng;

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
