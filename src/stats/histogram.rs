//! Fixed-bin histograms that merge exactly (integer counts), with an overflow bin.

/// Counts of samples in `bins` equal bins on `[lo, hi)`, plus under- and overflow.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Left edge of the first bin.
    pub lo: f64,
    /// Right edge of the last bin.
    pub hi: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
    /// Samples below `lo`.
    pub underflow: u64,
    /// Samples at or above `hi`.
    pub overflow: u64,
}

impl Histogram {
    /// An empty histogram of `bins` equal bins on `[lo, hi)`.
    pub fn new(lo: f64, hi: f64, bins: usize) -> Self {
        assert!(
            hi > lo && bins > 0,
            "histogram needs lo < hi and at least one bin"
        );
        Self {
            lo,
            hi,
            counts: vec![0; bins],
            underflow: 0,
            overflow: 0,
        }
    }

    /// Adds one sample.
    #[inline]
    pub fn push(&mut self, x: f64) {
        if x < self.lo {
            self.underflow += 1;
        } else if x >= self.hi {
            self.overflow += 1;
        } else {
            let k = ((x - self.lo) / (self.hi - self.lo) * self.counts.len() as f64) as usize;
            let last = self.counts.len() - 1;
            self.counts[k.min(last)] += 1;
        }
    }

    /// Adds the counts of a histogram with the same bins.
    pub fn merge(&mut self, other: &Self) {
        assert_eq!(
            (self.lo, self.hi, self.counts.len()),
            (other.lo, other.hi, other.counts.len())
        );
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        self.underflow += other.underflow;
        self.overflow += other.overflow;
    }

    /// Total number of samples, under- and overflow included.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum::<u64>() + self.underflow + self.overflow
    }

    /// `(left edge, right edge)` of bin `k`.
    pub fn edges(&self, k: usize) -> (f64, f64) {
        let w = (self.hi - self.lo) / self.counts.len() as f64;
        (self.lo + w * k as f64, self.lo + w * (k + 1) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_land_in_their_bins() {
        let mut h = Histogram::new(0.0, 1.0, 4);
        for x in [-0.1, 0.0, 0.3, 0.26, 0.99, 1.0, 7.0] {
            h.push(x);
        }
        assert_eq!(h.counts, vec![1, 2, 0, 1]);
        assert_eq!((h.underflow, h.overflow, h.total()), (1, 2, 7));
        assert_eq!(h.edges(1), (0.25, 0.5));
    }
}
