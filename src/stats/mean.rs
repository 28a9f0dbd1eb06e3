//! Means with standard errors that stay honest when samples are correlated within batches.
//!
//! Rays of one batch share one scene realisation, so two rays of a batch that leave the eye in nearby
//! directions often hit the same sphere: their counts are correlated and the naive `s/√n` would
//! understate the error. Batches, on the other hand, are independent (each has its own scene stream).
//! [`ClusteredMean`] therefore treats each batch as a cluster and uses the cluster-robust (ratio)
//! variance estimator: with batch sums `S_b`, counts `n_b`, `N = Σ n_b`, `ȳ = ΣS_b/N` and `B` batches,
//! `SE² = B/(B−1) · Σ_b (S_b − ȳ n_b)² / N²`. It also covers ratio means such as the first-hit distance
//! over hitting rays only, whose count per batch varies. Expanding the square keeps it mergeable:
//! only `Σ S_b`, `Σ n_b`, `Σ S_b²`, `Σ S_b n_b`, `Σ n_b²` and `B` are stored.

/// A mean with its standard error and sample count: the `M_mean, M_se, M_n` columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Sample mean (NaN when there are no samples).
    pub mean: f64,
    /// Standard error of the mean (NaN with fewer than two clusters).
    pub se: f64,
    /// Number of samples.
    pub n: u64,
    /// Number of independent clusters behind `se` (batches or replicas).
    pub clusters: u64,
}

impl Estimate {
    /// Half-width of the two-sided confidence interval at `level` (e.g. 0.95): Student-t with
    /// clusters − 1 degrees of freedom, since the clustered variance is estimated from that many
    /// independent cluster totals (with 4 replicas the 99 % factor is 5.84, not 2.58). NaN when
    /// there is no standard error.
    pub fn half_width(&self, level: f64) -> f64 {
        super::t_for_level(level, self.clusters.saturating_sub(1)) * self.se
    }
}

/// Accumulates samples batch by batch; see the module doc for the estimator.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusteredMean {
    n: u64,
    sum: f64,
    sum_sq_samples: f64,
    clusters: u64,
    s2: f64,
    sn: f64,
    n2: f64,
    cur_n: u64,
    cur_s: f64,
    cur_sq: f64,
}

impl ClusteredMean {
    /// Adds one sample to the current batch.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.cur_n += 1;
        self.cur_s += x;
        self.cur_sq += x * x;
    }

    /// Closes the current batch (a cluster). A batch with no samples still counts as a cluster:
    /// for ratio means it is an independent draw that contributed nothing.
    pub fn end_batch(&mut self) {
        let (nb, sb) = (self.cur_n as f64, self.cur_s);
        self.n += self.cur_n;
        self.sum += sb;
        self.s2 += sb * sb;
        self.sn += sb * nb;
        self.n2 += nb * nb;
        self.sum_sq_samples += self.cur_sq;
        self.clusters += 1;
        self.cur_n = 0;
        self.cur_s = 0.0;
        self.cur_sq = 0.0;
    }

    /// Adds one whole cluster from its aggregates: `n` samples summing to `sum`, whose squares sum to
    /// `sum_sq` (for engines that count per level and report only totals, one cluster per replica).
    pub fn push_cluster(&mut self, n: u64, sum: f64, sum_sq: f64) {
        debug_assert!(self.cur_n == 0, "push_cluster between batches only");
        self.cur_n = n;
        self.cur_s = sum;
        self.cur_sq = sum_sq;
        self.end_batch();
    }

    /// Merges closed batches of `other` after those of `self` (call in batch order for bit-identical
    /// sums whatever the thread count).
    pub fn merge(&mut self, other: &Self) {
        debug_assert!(
            self.cur_n == 0 && other.cur_n == 0,
            "merge closed batches only"
        );
        self.n += other.n;
        self.sum += other.sum;
        self.sum_sq_samples += other.sum_sq_samples;
        self.clusters += other.clusters;
        self.s2 += other.s2;
        self.sn += other.sn;
        self.n2 += other.n2;
    }

    /// Pools everything `other` holds (closed batches only) into this accumulator's open batch, so
    /// that many batches become one cluster (a replica of a finite scene).
    pub fn absorb(&mut self, other: &Self) {
        debug_assert!(other.cur_n == 0, "absorb closed batches only");
        self.cur_n += other.n;
        self.cur_s += other.sum;
        self.cur_sq += other.sum_sq_samples;
    }

    /// Number of samples in closed batches.
    pub fn n(&self) -> u64 {
        self.n
    }

    /// Sample variance of the individual samples (not of the mean).
    pub fn sample_variance(&self) -> f64 {
        if self.n < 2 {
            return f64::NAN;
        }
        let m = self.sum / self.n as f64;
        ((self.sum_sq_samples - self.n as f64 * m * m) / (self.n - 1) as f64).max(0.0)
    }

    /// The mean, its cluster-robust standard error and the sample count.
    pub fn estimate(&self) -> Estimate {
        if self.n == 0 {
            return Estimate {
                mean: f64::NAN,
                se: f64::NAN,
                n: 0,
                clusters: self.clusters,
            };
        }
        let nn = self.n as f64;
        let m = self.sum / nn;
        let se = if self.clusters < 2 {
            f64::NAN
        } else {
            let b = self.clusters as f64;
            let ss = (self.s2 - 2.0 * m * self.sn + m * m * self.n2).max(0.0);
            (b / (b - 1.0) * ss).sqrt() / nn
        };
        Estimate {
            mean: m,
            se,
            n: self.n,
            clusters: self.clusters,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::rng::stream;
    use rand::Rng;

    #[test]
    fn independent_samples_give_the_textbook_standard_error() {
        let mut rng = stream(&[5]);
        let mut m = ClusteredMean::default();
        for _ in 0..2000 {
            for _ in 0..50 {
                m.push(rng.gen::<f64>());
            }
            m.end_batch();
        }
        let e = m.estimate();
        let textbook = (m.sample_variance() / e.n as f64).sqrt();
        assert_eq!(e.n, 100_000);
        // Both estimate √(1/12/n) = 9.13e-4; they agree to within their own sampling error (~2 %).
        assert!(
            (e.se / textbook - 1.0).abs() < 0.08,
            "{} vs {}",
            e.se,
            textbook
        );
        assert!((e.mean - 0.5).abs() < 5.0 * e.se);
    }

    #[test]
    fn correlated_batches_widen_the_error() {
        // Each batch shares one offset: samples within a batch are strongly correlated.
        let mut rng = stream(&[6]);
        let mut m = ClusteredMean::default();
        for _ in 0..400 {
            let shared: f64 = rng.gen();
            for _ in 0..100 {
                m.push(shared + 0.01 * rng.gen::<f64>());
            }
            m.end_batch();
        }
        let e = m.estimate();
        let naive = (m.sample_variance() / e.n as f64).sqrt();
        // The true SE is ≈ √(1/12/400) = 0.0144, ten times the naive one.
        assert!(e.se > 5.0 * naive, "clustered {} vs naive {}", e.se, naive);
        assert!((e.se - (1.0f64 / 12.0 / 400.0).sqrt()).abs() < 0.3 * e.se);
    }

    /// What the runner relies on: per-batch accumulators merged one by one in batch order give
    /// bit-identical results to one pass, however the batches were spread over threads. (Merging
    /// two halves regroups the float sums and may differ in the last bits: the runner never does.)
    #[test]
    fn merging_batches_in_order_equals_one_pass() {
        let mut rng = stream(&[8]);
        let xs: Vec<f64> = (0..1000).map(|_| rng.gen()).collect();
        let mut one = ClusteredMean::default();
        let mut merged = ClusteredMean::default();
        for chunk in xs.chunks(10) {
            let mut batch = ClusteredMean::default();
            for &x in chunk {
                one.push(x);
                batch.push(x);
            }
            one.end_batch();
            batch.end_batch();
            merged.merge(&batch);
        }
        assert_eq!(merged.estimate(), one.estimate());
        assert_eq!(
            merged.sample_variance().to_bits(),
            one.sample_variance().to_bits()
        );
    }
}
