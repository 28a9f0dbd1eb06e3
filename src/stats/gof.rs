//! Goodness of fit: Pearson's χ² on binned counts and the one-sample Kolmogorov–Smirnov statistic.

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// A χ² test result: statistic, degrees of freedom and upper-tail p-value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChiSquare {
    /// Pearson's statistic Σ (O − E)² / E over the pooled bins.
    pub statistic: f64,
    /// Degrees of freedom: pooled bins − 1 − fitted parameters.
    pub dof: u32,
    /// P(χ²_dof ≥ statistic).
    pub p_value: f64,
}

/// Pearson's χ² of observed counts against expected counts (same total). Adjacent bins are pooled
/// from the left until each pooled expectation is at least 5 (the usual validity rule); the remainder
/// is pooled into the last group. `fitted` parameters estimated from the same data reduce the dof.
pub fn chi_square(observed: &[u64], expected: &[f64], fitted: u32) -> ChiSquare {
    assert_eq!(observed.len(), expected.len());
    let (mut stat, mut groups) = (0.0, 0u32);
    let (mut o_acc, mut e_acc) = (0.0, 0.0);
    let mut pending: Option<(f64, f64)> = None;
    for (&o, &e) in observed.iter().zip(expected) {
        o_acc += o as f64;
        e_acc += e;
        if e_acc >= 5.0 {
            if let Some((po, pe)) = pending.take() {
                stat += (po - pe) * (po - pe) / pe;
                groups += 1;
            }
            pending = Some((o_acc, e_acc));
            o_acc = 0.0;
            e_acc = 0.0;
        }
    }
    // The tail with expectation < 5 joins the last full group.
    if let Some((po, pe)) = pending {
        let (po, pe) = (po + o_acc, pe + e_acc);
        stat += (po - pe) * (po - pe) / pe;
        groups += 1;
    }
    // No degrees of freedom left (too few groups for the fitted parameters): no test.
    let dof = groups.saturating_sub(1 + fitted);
    let p_value = if dof == 0 {
        f64::NAN
    } else {
        ChiSquared::new(f64::from(dof))
            .map(|d| 1.0 - d.cdf(stat))
            .unwrap_or(f64::NAN)
    };
    ChiSquare {
        statistic: stat,
        dof,
        p_value,
    }
}

/// One-sample Kolmogorov–Smirnov statistic D = sup |F_n − F| of sorted samples against a CDF.
pub fn ks_statistic(sorted: &[f64], cdf: impl Fn(f64) -> f64) -> f64 {
    let n = sorted.len() as f64;
    sorted
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let f = cdf(x);
            (f - i as f64 / n).max((i + 1) as f64 / n - f)
        })
        .fold(0.0, f64::max)
}

/// Asymptotic p-value of the KS statistic D with n samples (Kolmogorov distribution with the
/// Stephens small-sample correction λ = (√n + 0.12 + 0.11/√n)·D).
pub fn ks_p_value(d: f64, n: usize) -> f64 {
    let sn = (n as f64).sqrt();
    let lambda = (sn + 0.12 + 0.11 / sn) * d;
    if lambda <= 0.0 {
        return 1.0;
    }
    if lambda < 1.18 {
        // Small λ: the alternating series converges too slowly; use the dual (Jacobi theta) form
        // K(λ) = √(2π)/λ · Σ exp(−(2k−1)²π²/(8λ²)), p = 1 − K(λ).
        let pi2 = std::f64::consts::PI * std::f64::consts::PI;
        let k: f64 = (1..=20)
            .map(|k| (-(((2 * k - 1) * (2 * k - 1)) as f64) * pi2 / (8.0 * lambda * lambda)).exp())
            .sum();
        return (1.0 - (2.0 * std::f64::consts::PI).sqrt() / lambda * k).clamp(0.0, 1.0);
    }
    let mut sum = 0.0;
    for k in 1..=100 {
        let k = k as f64;
        let term = 2.0 * (-1f64).powf(k - 1.0) * (-2.0 * k * k * lambda * lambda).exp();
        sum += term;
        if term.abs() < 1e-16 {
            break;
        }
    }
    sum.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::rng::stream;
    use rand::Rng;

    #[test]
    fn uniform_samples_pass_ks_and_shifted_ones_fail() {
        let mut rng = stream(&[9]);
        let mut xs: Vec<f64> = (0..5000).map(|_| rng.gen()).collect();
        xs.sort_by(f64::total_cmp);
        let d = ks_statistic(&xs, |x| x.clamp(0.0, 1.0));
        assert!(ks_p_value(d, xs.len()) > 0.001, "D = {d}");
        let d_bad = ks_statistic(&xs, |x| (x * 1.1).clamp(0.0, 1.0));
        assert!(ks_p_value(d_bad, xs.len()) < 1e-6);
    }

    #[test]
    fn chi_square_matches_a_hand_computed_case() {
        let r = chi_square(&[10, 20, 30], &[20.0, 20.0, 20.0], 0);
        assert!((r.statistic - 10.0).abs() < 1e-12);
        assert_eq!(r.dof, 2);
        assert!((r.p_value - (-5.0f64).exp()).abs() < 1e-9); // χ²₂ tail = e^(−x/2)
    }

    #[test]
    fn ks_p_value_is_continuous_and_right_for_small_and_large_lambda() {
        // Kolmogorov CDF K(λ): K(0.5) = 0.036055, K(1.0) = 0.730000, K(1.18) ≈ 0.876 (tables).
        let p = |lambda: f64| ks_p_value(lambda, 1_000_000_000_000); // √n large: λ ≈ √n·d
        let d = |lambda: f64| lambda / 1e6;
        assert!((p(d(0.5) * 1.0) - (1.0 - 0.036055)).abs() < 1e-4);
        assert!((p(d(1.0)) - (1.0 - 0.730000)).abs() < 1e-4);
        assert!((p(d(0.01)) - 1.0).abs() < 1e-12);
        assert!(
            (p(d(1.179_99)) - p(d(1.180_01))).abs() < 1e-4,
            "the two series meet"
        );
    }

    #[test]
    fn chi_square_without_degrees_of_freedom_is_not_a_test() {
        let r = chi_square(&[10, 10], &[10.0, 10.0], 1);
        assert_eq!(r.dof, 0);
        assert!(r.p_value.is_nan());
    }

    #[test]
    fn small_expectations_are_pooled() {
        let r = chi_square(&[5, 5, 1, 0], &[5.0, 5.0, 0.5, 0.5], 0);
        assert_eq!(r.dof, 1); // groups {5}, {5 + 1 + 0}
    }
}
