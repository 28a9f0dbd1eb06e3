//! Least-squares fits for the speed-against-error analysis: how an estimator's error
//! falls with its photons, and how its seconds grow with photons and points. Pure functions.
//!
//! Both fits are linear in non-negative coefficients (a variance and a squared bias cannot be
//! negative, nor can a cost), so they are non-negative least squares: with at most four
//! coefficients every subset of them is tried (the unconstrained fit over the subset, the others
//! 0) and the best feasible one kept. That is the exact NNLS solution (its optimum is the
//! unconstrained optimum over its support), with no iteration to tune.

/// The relative mean square error of a consistent-but-biased estimator with N photons:
/// MSE(N) = B + c/N, i.e. error(N) = √(bias² + c/N) in units of the mean irradiance.
///
/// `floor2` is what does not fall with N: the squared bias of every point, averaged over the points
/// (not the squared mean bias: opposite biases at different points do not cancel in an RMSE).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorFit {
    /// B: the part of the relative MSE that stays at any N (relative bias², ≥ 0).
    pub floor2: f64,
    /// c: the part that falls as 1/N (relative variance × photons, ≥ 0).
    pub c: f64,
    /// The smallest photon count the fit was made on (0 for a fit written by hand):
    /// [`ErrorFit::photons_for`] never answers fewer, since below it the fit is an extrapolation and
    /// the measured count already reaches the target.
    pub measured_min: f64,
}

impl ErrorFit {
    /// Weighted NNLS fit of `mse[k] ≈ B + c/photons[k]` with weights `weights[k]` (1/Var of each
    /// value). NaN values are skipped.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn fit(photons: &[f64], mse: &[f64], weights: &[f64]) -> Self {
        assert!(photons.len() == mse.len() && mse.len() == weights.len());
        let kept: Vec<(f64, f64, f64)> = photons
            .iter()
            .zip(mse)
            .zip(weights)
            .filter(|((n, y), w)| n.is_finite() && y.is_finite() && w.is_finite())
            .map(|((&n, &y), &w)| (n, y, w))
            .collect();
        let rows: Vec<([f64; 2], f64, f64)> = kept
            .iter()
            .map(|&(n, y, w)| ([1.0, 1.0 / n], y, w))
            .collect();
        let x = nnls(&rows);
        let measured_min = kept.iter().map(|k| k.0).fold(f64::INFINITY, f64::min);
        Self {
            floor2: x[0],
            c: x[1],
            measured_min: if measured_min.is_finite() {
                measured_min
            } else {
                0.0
            },
        }
    }

    /// Relative least squares: the noise of an MSE estimate is proportional to its size
    /// (Var ≈ 2·MSE²/dof for normal errors), so the weights are 1/MSE², with MSE the fitted value
    /// (iterated from the measured one; three rounds settle it). Fits a curve spanning decades.
    pub fn fit_relative(photons: &[f64], mse: &[f64]) -> Self {
        // A value at or below 0 (the reference's variance subtracted from a tiny MSE) gets the
        // weight of the smallest positive one, not an infinite one.
        let smallest = mse
            .iter()
            .copied()
            .filter(|&y| y > 0.0)
            .fold(f64::INFINITY, f64::min);
        let weight = |y: f64| 1.0 / y.max(smallest).powi(2);
        let mut w: Vec<f64> = mse.iter().map(|&y| weight(y)).collect();
        let mut fit = Self::fit(photons, mse, &w);
        for _ in 0..3 {
            w = photons.iter().map(|&n| weight(fit.mse(n))).collect();
            fit = Self::fit(photons, mse, &w);
        }
        fit
    }

    /// Relative MSE at `photons`.
    pub fn mse(&self, photons: f64) -> f64 {
        self.floor2 + self.c / photons
    }

    /// Relative RMSE at `photons`.
    pub fn error(&self, photons: f64) -> f64 {
        self.mse(photons).sqrt()
    }

    /// The error no photon count goes below: √B. It is a bias where the estimator is biased, and
    /// also any noise that more photons do not reduce (with `detp.direct = "nee"`, the direct part's
    /// next-event estimate at a fixed `detp.direct_samples`).
    pub fn floor(&self) -> f64 {
        self.floor2.sqrt()
    }

    /// Photons for a relative RMSE of `target`: c/(target² − B), but not fewer than
    /// `measured_min` (conservative: the fit is not trusted below the counts it was made on); `None`
    /// if the floor is at or above the target.
    pub fn photons_for(&self, target: f64) -> Option<f64> {
        let room = target * target - self.floor2;
        (room > 0.0).then(|| (self.c / room).max(self.measured_min))
    }
}

/// What DETP's seconds are made of, for N photons and n_P points:
/// `seconds(N, n_P) = fixed + per_photon·N + per_photon_point·N·n_P^γ + per_point·n_P`.
///
/// Why this form: tracing costs per photon (a·N); each segment's walk through the disc index costs
/// a part independent of the points (cells visited at a fixed cell width 2d, absorbed in a) and a
/// part proportional to the discs it is tested against, whose number along a segment grows with the
/// disc density, ∝ n_P at fixed d (b·N·n_P, γ = 1); building the index, the per-disc accumulators
/// and the output cost per point (c·n_P). γ < 1 describes a disc radius that shrinks as points are
/// added (d ∝ spacing: tests per segment ∝ n_P·d² … n_P·d, γ between 0 and ½). γ is chosen from the
/// measured scaling, not fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    /// Seconds independent of both sizes.
    pub fixed: f64,
    /// Seconds per photon (a).
    pub per_photon: f64,
    /// Seconds per photon per n_P^γ (b).
    pub per_photon_point: f64,
    /// Seconds per point (c).
    pub per_point: f64,
    /// γ, in [0, 1].
    pub gamma: f64,
}

impl CostModel {
    /// Seconds for `photons` photons and `points` points.
    pub fn seconds(&self, photons: f64, points: f64) -> f64 {
        self.fixed
            + self.per_photon * photons
            + self.per_photon_point * photons * points.powf(self.gamma)
            + self.per_point * points
    }

    /// NNLS fit to measured `(photons, points, seconds)` with exponent `gamma`, in relative terms
    /// (weights 1/seconds²: runs from milliseconds to minutes count alike).
    ///
    /// # Panics
    /// If γ is outside [0, 1].
    pub fn fit(samples: &[(f64, f64, f64)], gamma: f64) -> Self {
        assert!((0.0..=1.0).contains(&gamma), "γ must lie in [0, 1]");
        let rows: Vec<([f64; 4], f64, f64)> = samples
            .iter()
            .filter(|s| s.2 > 0.0 && s.2.is_finite())
            .map(|&(n, p, s)| ([1.0, n, n * p.powf(gamma), p], s, 1.0 / (s * s)))
            .collect();
        let x = nnls(&rows);
        Self {
            fixed: x[0],
            per_photon: x[1],
            per_photon_point: x[2],
            per_point: x[3],
            gamma,
        }
    }

    /// [`CostModel::fit`] at each γ of `gammas`, keeping the one with the least relative squared
    /// misfit Σ (model/measured − 1)²: γ chosen by the measured scaling in n_P.
    ///
    /// # Panics
    /// If `gammas` is empty or holds a value outside [0, 1].
    pub fn fit_best_gamma(samples: &[(f64, f64, f64)], gammas: &[f64]) -> Self {
        let misfit = |m: &Self| -> f64 {
            samples
                .iter()
                .map(|&(n, p, s)| (m.seconds(n, p) / s - 1.0).powi(2))
                .sum()
        };
        gammas
            .iter()
            .map(|&g| Self::fit(samples, g))
            .min_by(|a, b| misfit(a).total_cmp(&misfit(b)))
            .expect("at least one γ")
    }

    /// The largest relative misfit |model/measured − 1| over `samples` (how well the form holds).
    pub fn worst_relative_misfit(&self, samples: &[(f64, f64, f64)]) -> f64 {
        samples
            .iter()
            .map(|&(n, p, s)| (self.seconds(n, p) / s - 1.0).abs())
            .fold(0.0, f64::max)
    }
}

/// Non-negative weighted least squares over `rows` = (x, y, weight) with K ≤ 4 coefficients, by
/// trying every support (see the module doc). Coefficients not determined by the data are 0.
fn nnls<const K: usize>(rows: &[([f64; K], f64, f64)]) -> [f64; K] {
    let mut best = ([0.0; K], weighted_ssr(rows, &[0.0; K]));
    for mask in 1u32..(1 << K) {
        let cols: Vec<usize> = (0..K).filter(|j| mask & (1 << j) != 0).collect();
        let Some(sol) = solve_support(rows, &cols) else {
            continue;
        };
        if sol.iter().any(|&v| v < 0.0) {
            continue;
        }
        let mut x = [0.0; K];
        for (&j, &v) in cols.iter().zip(&sol) {
            x[j] = v;
        }
        let ssr = weighted_ssr(rows, &x);
        if ssr < best.1 {
            best = (x, ssr);
        }
    }
    best.0
}

/// Σ w (y − x·β)².
fn weighted_ssr<const K: usize>(rows: &[([f64; K], f64, f64)], beta: &[f64; K]) -> f64 {
    rows.iter()
        .map(|(x, y, w)| {
            let f: f64 = x.iter().zip(beta).map(|(a, b)| a * b).sum();
            w * (y - f).powi(2)
        })
        .sum()
}

/// The weighted least-squares coefficients over the columns `cols` (normal equations, Gaussian
/// elimination with partial pivoting), or `None` if they are not determined.
fn solve_support<const K: usize>(
    rows: &[([f64; K], f64, f64)],
    cols: &[usize],
) -> Option<Vec<f64>> {
    let m = cols.len();
    if rows.len() < m {
        return None;
    }
    // Columns scaled to unit weighted norm, so that photons (~10⁶) and constants (1) pivot alike.
    let scale: Vec<f64> = cols
        .iter()
        .map(|&j| {
            rows.iter()
                .map(|(x, _, w)| w * x[j] * x[j])
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    if scale.iter().any(|&s| s <= 0.0 || !s.is_finite()) {
        return None;
    }
    let mut a = vec![vec![0.0; m + 1]; m];
    for (x, y, w) in rows {
        for r in 0..m {
            let xr = x[cols[r]] / scale[r];
            for c in 0..m {
                a[r][c] += w * xr * x[cols[c]] / scale[c];
            }
            a[r][m] += w * xr * y;
        }
    }
    for col in 0..m {
        let piv = (col..m).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                for (v, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                    *v -= f * p;
                }
            }
        }
    }
    Some((0..m).map(|r| a[r][m] / a[r][r] / scale[r]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Below the smallest measured photon count the fit is not trusted: a target the measured
    /// count already reaches needs that count, not the extrapolated fewer.
    #[test]
    fn photons_for_never_goes_below_the_measured_range() {
        let photons = [1e4, 1e5, 1e6];
        let mse: Vec<f64> = photons.iter().map(|n| 1e-4 + 10.0 / n).collect();
        let fit = ErrorFit::fit_relative(&photons, &mse);
        assert_eq!(fit.measured_min, 1e4);
        // error(1e4) = √(1e-4 + 1e-3) ≈ 0.033: a 10 % target is met at the smallest count.
        assert_eq!(fit.photons_for(0.1), Some(1e4));
        // 2 % needs c/(ε² − B) = 10/(4e-4 − 1e-4) ≈ 3.3e4, inside the range: unchanged.
        let n = fit.photons_for(0.02).unwrap();
        assert!((n / (10.0 / 3e-4) - 1.0).abs() < 1e-6, "{n}");
        assert_eq!(fit.photons_for(0.009), None, "below the floor (1 %)");
    }

    #[test]
    fn an_exact_bias_variance_curve_is_recovered() {
        let truth = ErrorFit {
            floor2: 0.08f64.powi(2),
            c: 40.0,
            measured_min: 0.0,
        };
        let n = [2.5e4, 1e5, 4e5, 1.6e6];
        let mse: Vec<f64> = n.iter().map(|&x| truth.mse(x)).collect();
        let fit = ErrorFit::fit_relative(&n, &mse);
        assert!((fit.floor2 / truth.floor2 - 1.0).abs() < 1e-9, "{fit:?}");
        assert!((fit.c / truth.c - 1.0).abs() < 1e-9, "{fit:?}");
        assert!((fit.floor() - 0.08).abs() < 1e-9);
        assert_eq!(fit.photons_for(0.05), None, "the floor is above 5 %");
        // 10 % needs 40/(0.01 − 0.0064) ≈ 1.1·10⁴ photons, below the smallest measured 2.5·10⁴:
        // the measured count is the answer. 8.5 % needs ≈ 4.8·10⁴, inside the range.
        assert_eq!(fit.photons_for(0.10), Some(2.5e4));
        let n = fit.photons_for(0.085).expect("above the floor");
        assert!((fit.error(n) - 0.085).abs() < 1e-9);
    }

    /// Unbiased data (B = 0) whose noise makes the unconstrained intercept negative: the fit holds
    /// the floor at 0 and refits c alone, never a negative squared bias.
    #[test]
    fn a_negative_intercept_is_held_at_zero() {
        let n = [1e4, 1e5, 1e6];
        let mse = [1.0e-2, 0.9e-3, 0.5e-4];
        let fit = ErrorFit::fit(&n, &mse, &[1e4, 1e6, 1e8]);
        assert_eq!(fit.floor2, 0.0);
        assert!(fit.c > 0.0);
        // The constrained optimum over c alone: Σ w x y / Σ w x².
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for ((n, y), w) in n.iter().zip(mse).zip([1e4, 1e6, 1e8]) {
            sxy += w * y / n;
            sxx += w / (n * n);
        }
        assert!((fit.c / (sxy / sxx) - 1.0).abs() < 1e-12, "{fit:?}");
    }

    /// Noisy points around a known curve: the fitted curve is within the noise.
    #[test]
    fn a_noisy_curve_is_fitted_within_its_noise() {
        let truth = ErrorFit {
            floor2: 1e-3,
            c: 100.0,
            measured_min: 0.0,
        };
        let n: Vec<f64> = (0..8).map(|k| 1e4 * 2f64.powi(k)).collect();
        // ±5 % alternating noise.
        let mse: Vec<f64> = n
            .iter()
            .enumerate()
            .map(|(k, &x)| truth.mse(x) * if k % 2 == 0 { 1.05 } else { 0.95 })
            .collect();
        let fit = ErrorFit::fit_relative(&n, &mse);
        for &x in &n {
            assert!((fit.mse(x) / truth.mse(x) - 1.0).abs() < 0.06, "{fit:?}");
        }
    }

    #[test]
    fn a_cost_model_is_recovered_from_its_own_values() {
        let truth = CostModel {
            fixed: 0.02,
            per_photon: 1e-6,
            per_photon_point: 2e-11,
            per_point: 3e-6,
            gamma: 1.0,
        };
        let mut samples = Vec::new();
        for n in [5e4, 2e5, 8e5] {
            for p in [1e2, 1e3, 1e4, 1e5] {
                samples.push((n, p, truth.seconds(n, p)));
            }
        }
        let fit = CostModel::fit(&samples, 1.0);
        for (a, b) in [
            (fit.fixed, truth.fixed),
            (fit.per_photon, truth.per_photon),
            (fit.per_photon_point, truth.per_photon_point),
            (fit.per_point, truth.per_point),
        ] {
            assert!((a / b - 1.0).abs() < 1e-6, "{fit:?}");
        }
        assert!(fit.worst_relative_misfit(&samples) < 1e-9);
    }

    /// Seconds that grow as √n_P per photon: the γ grid finds ½, and the fit is exact there.
    #[test]
    fn the_best_gamma_is_the_measured_scaling() {
        let truth = CostModel {
            fixed: 0.0,
            per_photon: 1e-6,
            per_photon_point: 3e-8,
            per_point: 1e-6,
            gamma: 0.5,
        };
        let mut samples = Vec::new();
        for n in [5e4, 2e5] {
            for p in [1e3, 1e4, 1e5, 1e6] {
                samples.push((n, p, truth.seconds(n, p)));
            }
        }
        let grid: Vec<f64> = (0..=10).map(|k| f64::from(k) / 10.0).collect();
        let fit = CostModel::fit_best_gamma(&samples, &grid);
        assert_eq!(fit.gamma, 0.5);
        assert!(fit.worst_relative_misfit(&samples) < 1e-9, "{fit:?}");
        assert!(CostModel::fit(&samples, 1.0).worst_relative_misfit(&samples) > 0.1);
    }

    /// A cost with no per-point part: the fit sets it to 0 rather than a negative value.
    #[test]
    fn a_cost_term_that_is_absent_is_zero() {
        let samples: Vec<(f64, f64, f64)> = [(1e5, 1e3), (1e6, 1e3), (1e5, 1e5), (1e6, 1e5)]
            .iter()
            .enumerate()
            .map(|(k, &(n, p))| (n, p, 1e-6 * n * if k % 2 == 0 { 1.01 } else { 0.99 }))
            .collect();
        let fit = CostModel::fit(&samples, 1.0);
        assert!(fit.per_photon > 0.0);
        for v in [fit.fixed, fit.per_photon_point, fit.per_point] {
            assert!(v >= 0.0);
        }
        assert!(fit.worst_relative_misfit(&samples) < 0.03, "{fit:?}");
    }
}
