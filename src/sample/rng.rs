//! Random streams keyed by what they are for, never by which thread runs them.
//!
//! Every random draw in raycost comes from a [`Stream`] created from a key such as
//! `[PHOTON, seed, photon]` or `[RAYS, seed, point, batch]`: the same spec and seed give the same
//! numbers on every machine, thread count, shard and batch, and any one photon, path, line batch
//! or point can be drawn again alone (quasi-static frames re-trace only the photons that met a
//! mover; shards trace disjoint ranges of photons).
//!
//! **The generator: Philox2x64-10, counter-based** ([`super::philox`]). A key `[w₀, …, wₙ₋₁]`
//! becomes the Philox key `hash(w₀ … wₙ₋₂; n)` (pbrt-v4's `MixBits` chain, a SplitMix64 finaliser
//! per word) and the counter's high word `wₙ₋₁`; the stream is the blocks at counters
//! `(0, wₙ₋₁), (1, wₙ₋₁), …`. Why:
//! - *Cost.* Making a stream is hashing n − 1 words (≈ 20 instructions a word) and storing two;
//!   a draw is half a block, ≈ 40 instructions with rand's float conversion. ChaCha8, used before,
//!   needed a 256-bit seed expanded from the hash and a first block of 4 × 64 bytes before the
//!   first draw: ≈ 670 instructions per photon for a photon's ≈ 10 draws (callgrind, docs/bench.md:
//!   a photon segment went from 2 170 to 2 035 instructions on the Cornell box).
//! - *Streams that differ in the last word* — consecutive photons, points, batches, samples, the
//!   common case and the hard one for a counter generator — share the Philox key and use disjoint
//!   counters of one keyed bijection: they can never overlap or coincide. This is the layout the
//!   generator's authors designed it for (key = seed, counter = (position, object id)), and the one
//!   their statistical tests cover: they report Philox2x64 "Crush-resistant" (passing TestU01's
//!   SmallCrush, Crush and BigCrush over many keys and counter sequences) from 6 rounds on; 10
//!   rounds is their recommended default, a safety margin (Salmon et al. 2011). A counter-incremented SplitMix64 (state = hash(key), output i =
//!   mix(state + i·γ)) would be cheaper per draw, but all its streams are windows on one sequence:
//!   among 10⁹ photons of 100 draws each, some two would share draws with probability ≈ 1.
//! - *Streams that differ in an earlier word* get unrelated 64-bit Philox keys; two distinct
//!   prefixes share one with probability 2⁻⁶⁴ (before, with ChaCha, every key went through one
//!   64-bit hash, so 10⁹ photons shared a stream somewhere with probability ≈ 3 %; now photons of one
//!   seed never do).
//! - *Period:* 2⁶⁴ blocks of two words per stream — more than any stream here draws.
//!
//! What we rely on and what we checked: the authors' BigCrush results for the block function, our
//! implementation pinned to their known-answer vectors, and our own battery on the streams exactly
//! as the engines key them (first words of consecutive photon ids interleaved, and one long
//! stream): `scripts/rng_quality.sh`, results in `results/rng-quality/`. The tests below are the
//! quick version (correlation of adjacent keys, χ² uniformity), run with every `cargo test`.
//!
//! The lazily generated infinite scene draws its spheres from [`super::counter::SplitMix64`] per ray
//! or block, not from [`stream`]: one or two draws per cell step, where even a Philox block would be
//! a tenth of the step's cost.
//!
//! Feature `chacha-streams` builds the previous streams (ChaCha8 seeded from the hashed key)
//! instead, for one purpose: parity runs (`scripts/parity_runs.sh`) of a binary with this feature
//! against one built before the switch show that nothing but the stream changed.

/// SplitMix64 / MurmurHash3 finaliser: a bijective 64-bit mix (pbrt `MixBits`).
#[inline]
pub fn mix64(mut v: u64) -> u64 {
    v ^= v >> 31;
    v = v.wrapping_mul(0x7fb5_d329_728e_a185);
    v ^= v >> 27;
    v = v.wrapping_mul(0x81da_def4_bc2d_d44d);
    v ^= v >> 33;
    v
}

/// Hashes a key of words into one 64-bit value; order matters, and distinct keys of the same length
/// collide with probability about 2⁻⁶⁴.
#[inline]
pub fn hash_key(key: &[u64]) -> u64 {
    hash_words(key, key.len())
}

/// The chain of [`hash_key`] over `words`, started from a value that depends on `len` (the length of
/// the whole key, of which `words` may be a prefix).
#[inline]
fn hash_words(words: &[u64], len: usize) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15_u64 ^ len as u64;
    for &k in words {
        h = mix64(h ^ mix64(k.wrapping_add(0x632b_e59b_d9b4_e019)));
    }
    h
}

/// A random stream: Philox2x64-10 keyed as the module doc says.
#[cfg(not(feature = "chacha-streams"))]
pub type Stream = super::philox::Philox2x64;

/// A random stream: ChaCha8 seeded from the hashed key (feature `chacha-streams`, parity only).
#[cfg(feature = "chacha-streams")]
pub type Stream = rand_chacha::ChaCha8Rng;

/// The stream for `key` (for example `[seed, point, batch]`).
#[cfg(not(feature = "chacha-streams"))]
#[inline]
pub fn stream(key: &[u64]) -> Stream {
    match key.split_last() {
        Some((&last, prefix)) => Stream::new(hash_words(prefix, key.len()), last),
        None => Stream::new(hash_words(&[], 0), 0),
    }
}

/// The stream for `key`, as before the switch to Philox (feature `chacha-streams`).
#[cfg(feature = "chacha-streams")]
pub fn stream(key: &[u64]) -> Stream {
    use rand::SeedableRng;
    let mut seed = [0u8; 32];
    let mut h = hash_key(key);
    for chunk in seed.chunks_mut(8) {
        h = mix64(h.wrapping_add(0x9e37_79b9_7f4a_7c15));
        chunk.copy_from_slice(&h.to_le_bytes());
    }
    Stream::from_seed(seed)
}

/// Domain tags keep streams for different purposes apart even when their numeric keys coincide.
pub mod domain {
    /// Rays of one batch: `[RAYS, seed, point, batch]`.
    pub const RAYS: u64 = 0x7261_7973;
    /// One scene realisation: `[SCENE, seed, point, replica]`.
    pub const SCENE: u64 = 0x7363_656e;
    /// One block of a lazily generated Poisson scene: `[BLOCK, scene seed, class, x, y, z]`.
    pub const BLOCK: u64 = 0x626c_6f63;
    /// A batch of μ-random lines of a DETP point: `[LINES, seed, point, replica, batch]`.
    pub const LINES: u64 = 0x6c69_6e65;
    /// A batch of DETP sample points of one replica: `[POINTS, seed, point, replica, batch]`.
    pub const POINTS: u64 = 0x706f_696e;
    /// One photon's path: `[PHOTON, seed, photon id]` (re-traceable alone).
    pub const PHOTON: u64 = 0x7068_6f74;
    /// The subset of points checked by brute force: `[CHECK, seed, point]`.
    pub const CHECK: u64 = 0x6368_6563;
    /// The reference path tracer's samples at one sample point: `[REFERENCE, seed, point, sample]`.
    pub const REFERENCE: u64 = 0x7265_6665;
    /// Per-point path tracing as a competitor, independent of the reference it is
    /// judged against: `[PATH_TRACE, seed, replica, point]`.
    pub const PATH_TRACE: u64 = 0x7061_7468;
    /// Direct light by next-event estimation alone: `[DIRECT, seed, replica, point]`.
    pub const DIRECT: u64 = 0x6469_7265;
    /// Bootstrap resamples of an analysis: `[BOOTSTRAP, seed]`.
    pub const BOOTSTRAP: u64 = 0x626f_6f74;
    /// The seed of a separate run of a spec (`experiment.run` ≥ 1): `[RUN, seed, run]`.
    pub const RUN: u64 = 0x7275_6e73;
    /// The keyed order of a nested subsample (surface points with `detp.points`):
    /// `[SUBSET, seed, item]`, no sweep point, so every point of a sweep keeps the same items.
    pub const SUBSET: u64 = 0x7375_6273;
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn same_key_same_numbers_different_key_different_numbers() {
        let draw = |key: &[u64]| -> Vec<u64> {
            let mut s = stream(key);
            (0..4).map(|_| s.gen()).collect()
        };
        assert_eq!(draw(&[1, 2, 3]), draw(&[1, 2, 3]));
        assert_ne!(draw(&[1, 2, 3]), draw(&[1, 2, 4]));
        assert_ne!(draw(&[1, 2, 3]), draw(&[1, 3, 3]));
        assert_ne!(draw(&[1, 2, 3]), draw(&[2, 3]));
        assert_ne!(draw(&[]), draw(&[0]));
        assert_ne!(draw(&[0]), draw(&[0, 0]));
    }

    #[test]
    fn domains_are_distinct() {
        let all = [
            domain::RAYS,
            domain::SCENE,
            domain::BLOCK,
            domain::LINES,
            domain::POINTS,
            domain::PHOTON,
            domain::CHECK,
            domain::REFERENCE,
            domain::PATH_TRACE,
            domain::DIRECT,
            domain::RUN,
            domain::BOOTSTRAP,
            domain::SUBSET,
        ];
        for (i, a) in all.iter().enumerate() {
            assert!(all[i + 1..].iter().all(|b| b != a), "{a:#x} appears twice");
        }
    }

    #[test]
    fn key_order_and_length_matter() {
        assert_ne!(hash_key(&[1, 2]), hash_key(&[2, 1]));
        assert_ne!(hash_key(&[0]), hash_key(&[0, 0]));
    }

    /// The layout the module doc promises: key = the hash of every word but the last (and of the
    /// key's length), counter = (block, last word). The block function itself is pinned to the
    /// reference's known answers in `philox`.
    #[cfg(not(feature = "chacha-streams"))]
    #[test]
    fn stream_is_philox_keyed_by_the_prefix_and_counted_by_the_last_word() {
        use crate::sample::philox::block;
        let key = [domain::PHOTON, 5, 1234];
        let mut s = stream(&key);
        let k = hash_words(&key[..2], 3);
        assert_eq!(k, {
            let mut h = 0x9e37_79b9_7f4a_7c15_u64 ^ 3;
            for w in &key[..2] {
                h = mix64(h ^ mix64(w.wrapping_add(0x632b_e59b_d9b4_e019)));
            }
            h
        });
        let words: Vec<u64> = (0..4).map(|_| s.gen()).collect();
        let want: Vec<u64> = (0..2).flat_map(|i| block([i, 1234], k)).collect();
        assert_eq!(words, want);
    }

    /// The first `n` draws in [0, 1) of the streams `key(i)`, i = 0, 1, …: the engines' usage
    /// (one stream per photon, point or batch, a handful of draws each).
    fn first_draws(n: usize, key: impl Fn(u64) -> Vec<u64>) -> Vec<f64> {
        (0..n as u64).map(|i| stream(&key(i)).gen()).collect()
    }

    /// χ² p-value of `x` in [0, 1) against uniform, over `bins` equal bins.
    fn uniform_p(x: &[f64], bins: usize) -> f64 {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let mut counts = vec![0u64; bins];
        for &v in x {
            counts[((v * bins as f64) as usize).min(bins - 1)] += 1;
        }
        let e = x.len() as f64 / bins as f64;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        ChiSquared::new((bins - 1) as f64).unwrap().sf(chi2)
    }

    /// Pearson correlation of `a` and `b` times √n: standard normal under independence.
    fn correlation_z(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len() as f64;
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            sab += (x - ma) * (y - mb);
            saa += (x - ma) * (x - ma);
            sbb += (y - mb) * (y - mb);
        }
        sab / (saa * sbb).sqrt() * n.sqrt()
    }

    // Thresholds fixed before looking at any result: a χ² p-value below 10⁻⁴ or a correlation of
    // |z| > 4.5 (two-sided p = 6.8·10⁻⁶) fails. The seeds are fixed, so a test fails only by a
    // defect or, for a sound generator, with probability ≈ 10⁻⁴ per check when seeds change.
    const P_MIN: f64 = 1e-4;
    const Z_MAX: f64 = 4.5;
    const N: usize = 1 << 16;

    /// First draws of streams keyed by consecutive photon ids (same prefix, the last word counting)
    /// and by consecutive seeds (a different Philox key each) are uniform, and so is one long stream.
    #[test]
    fn first_draws_of_adjacent_keys_are_uniform() {
        let by_photon = first_draws(N, |i| vec![domain::PHOTON, 17, i]);
        let by_seed = first_draws(N, |i| vec![domain::PHOTON, i, 17]);
        let mut one = stream(&[domain::RAYS, 17, 0, 0]);
        let long: Vec<f64> = (0..N).map(|_| one.gen()).collect();
        for (what, x) in [("photon", by_photon), ("seed", by_seed), ("long", long)] {
            for bins in [16, 256] {
                let p = uniform_p(&x, bins);
                assert!(p > P_MIN, "{what}: chi-square over {bins} bins p = {p:.2e}");
            }
        }
    }

    /// Adjacent keys give uncorrelated draws: the first draw of key i against the first of key i + 1
    /// (lag 1 over consecutive photons) and against the second draw of key i + 1, for keys differing
    /// in the last word and in an earlier one; and each bit of the first 64-bit words is fair.
    #[test]
    fn adjacent_keys_give_uncorrelated_first_draws() {
        let pairs = |key: &dyn Fn(u64) -> Vec<u64>| -> (Vec<f64>, Vec<f64>, Vec<f64>) {
            let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
            for i in 0..N as u64 {
                let (mut s, mut t) = (stream(&key(i)), stream(&key(i + 1)));
                a.push(s.gen());
                b.push(t.gen());
                let _: f64 = t.gen();
                c.push(t.gen());
            }
            (a, b, c)
        };
        let last = |i| vec![domain::PHOTON, 3, i];
        let earlier = |i| vec![domain::LINES, 3, i, 0, 7];
        for (what, key) in [
            ("last word", &last as &dyn Fn(u64) -> Vec<u64>),
            ("earlier word", &earlier),
        ] {
            let (a, b, c) = pairs(key);
            for (lag, other) in [("first", &b), ("third", &c)] {
                let z = correlation_z(&a, other);
                assert!(
                    z.abs() < Z_MAX,
                    "{what}: corr(first, {lag} of next) z = {z:.2}"
                );
            }
        }
        let words: Vec<u64> = (0..N as u64)
            .map(|i| stream(&[domain::PHOTON, 3, i]).gen())
            .collect();
        for bit in 0..64 {
            let ones = words.iter().filter(|w| (*w >> bit) & 1 == 1).count() as f64;
            let z = (ones - N as f64 / 2.0) / (N as f64 / 4.0).sqrt();
            assert!(z.abs() < Z_MAX, "bit {bit}: z = {z:.2}");
        }
    }
}
