//! Keyed nested subsamples: the first n items of a permutation keyed by a seed alone.
//!
//! Each item `i` gets the key `hash_key([domain::SUBSET, seed, i])`; the items sorted by key (ties,
//! about 2⁻⁶⁴ apart, by index) form the permutation. The first n of it therefore depend only on the
//! seed and the item count — never on a sweep point, a thread or n — so the same n gives the same
//! items everywhere and n₁ < n₂ keeps a prefix: the smaller subsample is nested in the larger.

use super::rng::{domain, hash_key};

/// The indices of the first `n` of `total` items in the permutation keyed by `seed`, in that
/// permutation's order (so a smaller `n` gives a prefix of a larger one). `None` when `n > total`.
pub fn keyed_prefix(total: usize, n: usize, seed: u64) -> Option<Vec<usize>> {
    if n > total {
        return None;
    }
    let mut keyed: Vec<(u64, usize)> = (0..total)
        .map(|i| (hash_key(&[domain::SUBSET, seed, i as u64]), i))
        .collect();
    if n < total {
        keyed.select_nth_unstable(n);
        keyed.truncate(n);
    }
    keyed.sort_unstable();
    Some(keyed.into_iter().map(|(_, i)| i).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// n₁ < n₂ ⇒ the first n₁ are a prefix of the first n₂; every index is distinct and in range.
    #[test]
    fn smaller_subsamples_are_prefixes_of_larger_ones() {
        let total = 5000;
        let all = keyed_prefix(total, total, 7).unwrap();
        let mut seen = all.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..total).collect::<Vec<_>>(), "a permutation");
        for n in [0, 1, 17, 1500, 4999] {
            let p = keyed_prefix(total, n, 7).unwrap();
            assert_eq!(p[..], all[..n], "n = {n}");
        }
        assert_ne!(all[..100], (0..100).collect::<Vec<_>>()[..], "shuffled");
    }

    /// The seed keys the permutation; more items than exist are refused.
    #[test]
    fn seeded_and_bounded() {
        assert_eq!(keyed_prefix(100, 10, 1), keyed_prefix(100, 10, 1));
        assert_ne!(keyed_prefix(100, 10, 1), keyed_prefix(100, 10, 2));
        assert_eq!(keyed_prefix(10, 11, 1), None);
    }
}
