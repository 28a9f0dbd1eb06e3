//! Estimators that every engine's counters flow into: mergeable means with honest standard errors,
//! histograms, and goodness-of-fit statistics. All of them merge partial results in a fixed order,
//! so a run's numbers do not depend on how the work was split across threads.

pub mod gof;
pub mod histogram;
pub mod mean;

pub use histogram::Histogram;
pub use mean::{ClusteredMean, Estimate};

/// Two-sided standard-normal quantile for a confidence level (0.95 → 1.959964…).
pub fn z_for_level(level: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0)
        .expect("standard normal")
        .inverse_cdf(0.5 + 0.5 * level)
}
