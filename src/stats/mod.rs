//! Estimators that every engine's counters flow into: mergeable means with honest standard errors,
//! histograms, goodness-of-fit statistics, and the verdict of a measurement against theory
//! ([`verdict`]). All of them merge partial results in a fixed order, so a run's numbers do not
//! depend on how the work was split across threads. [`fit`] and [`time_to_target`] turn such summaries
//! into the speed-against-error answers (time to a target error, the crossover in points
//! or frames, bootstrap CIs over replicas).

pub mod fit;
pub mod gof;
pub mod histogram;
pub mod mean;
/// Seconds to a target error per method, and where one overtakes another (N*, F*): the cost
/// model behind `raycost crossover` (named apart from that command's layer, `crate::crossover`).
pub mod time_to_target;
pub mod verdict;

pub use histogram::Histogram;
pub use mean::{ClusteredMean, Estimate};
pub use verdict::{Theory, Tone, Verdict};

/// The q-quantile of `sorted` (ascending, not empty) as every bootstrap interval in raycost takes
/// it, in Rust and in `scripts/raycost_stats.py` alike: the value at 0-based rank ⌊q·(n − 1)⌋,
/// computed in double (numpy's "lower" percentile). At the draw counts used (2 000, 4 000) and
/// q = 0.025, 0.975 it is also the inverse of the empirical CDF. Both sides are held to the shared
/// cases of `scripts/tests/data/percentile_cases.txt`.
///
/// # Panics
/// If `sorted` is empty or q is outside [0, 1].
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    assert!(!sorted.is_empty() && (0.0..=1.0).contains(&q));
    sorted[((q * (sorted.len() - 1) as f64).floor() as usize).min(sorted.len() - 1)]
}

/// Two-sided Student-t quantile with `dof` degrees of freedom (normal beyond 10⁴; NaN for 0).
pub fn t_for_level(level: f64, dof: u64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    match dof {
        0 => f64::NAN,
        d if d > 10_000 => z_for_level(level),
        d => StudentsT::new(0.0, 1.0, d as f64)
            .expect("dof > 0")
            .inverse_cdf(0.5 + 0.5 * level),
    }
}

/// Two-sided standard-normal quantile for a confidence level (0.95 → 1.959964…).
pub fn z_for_level(level: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0)
        .expect("standard normal")
        .inverse_cdf(0.5 + 0.5 * level)
}

#[cfg(test)]
mod tests {
    /// The rows of a shared case file (`scripts/tests/data/`, read by the Python tests too): its
    /// non-comment lines, each as three fields.
    fn shared_rows(text: &str) -> Vec<[&str; 3]> {
        text.lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                [w[0], w[1], w[2]]
            })
            .collect()
    }

    /// The percentile convention Python's bootstrap uses too: the shared cases (written by
    /// `scripts/tests/data/make_percentile_cases.py`, checked by `scripts/tests/test_stats.py`).
    #[test]
    fn percentile_gives_the_ranks_python_gives() {
        let rows = shared_rows(include_str!(
            "../../scripts/tests/data/percentile_cases.txt"
        ));
        assert!(rows.len() > 100, "{} cases", rows.len());
        for [n, q, rank] in rows {
            let (n, q, rank): (usize, f64, f64) = (
                n.parse().expect("n"),
                q.parse().expect("q"),
                rank.parse().expect("rank"),
            );
            let values: Vec<f64> = (0..n).map(|i| i as f64).collect();
            assert_eq!(super::percentile(&values, q), rank, "n {n}, q {q}");
        }
    }

    /// The t quantiles Python's `raycost_stats.t_for_level` is held to (`statrs_t_quantiles.txt`,
    /// written from statrs) are this function's: the shared file is read by both test suites, so a
    /// change of statrs (or of the switch to the normal) fails here as it would in Python.
    #[test]
    fn t_quantiles_are_the_shared_ones_python_is_held_to() {
        let rows = shared_rows(include_str!(
            "../../scripts/tests/data/statrs_t_quantiles.txt"
        ));
        assert!(rows.len() > 50, "{} cases", rows.len());
        for [level, dof, t] in rows {
            let (level, dof, t): (f64, u64, f64) = (
                level.parse().expect("level"),
                dof.parse().expect("dof"),
                t.parse().expect("quantile"),
            );
            let got = super::t_for_level(level, dof);
            assert!(
                (got - t).abs() <= 1e-12 * t,
                "level {level}, dof {dof}: {got} against {t}"
            );
        }
    }

    #[test]
    fn t_quantiles_match_tables() {
        assert!((super::t_for_level(0.99, 3) - 5.8409).abs() < 1e-3);
        assert!((super::t_for_level(0.95, 10) - 2.2281).abs() < 1e-3);
        assert!((super::t_for_level(0.95, 1_000_000) - 1.95996).abs() < 1e-4);
        assert!(super::t_for_level(0.95, 0).is_nan());
    }
}
