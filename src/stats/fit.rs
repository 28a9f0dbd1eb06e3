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
    /// The power of N in the falling part: MSE(N) = B + c·N^(−exponent). 1 for a fixed radius per
    /// point (variance ∝ 1/N, [`ErrorFit::fit_relative`]); 2γ for a radius that shrinks with N
    /// (no floor, B = 0: [`ErrorFit::fit_power_law`]).
    pub exponent: f64,
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
            measured_min: finite_or_zero(measured_min),
            exponent: 1.0,
        }
    }

    /// The power law of a radius schedule (`docs/theory.md`, "A disc radius per point and per
    /// photon count"): with d ∝ N^(−β) the bias² falls as N^(−4β) and the variance as
    /// N^(−(1−2β)), so the MSE has no floor and falls as a·N^(−2γ). Least squares of ln MSE on
    /// ln N over the positive values (an MSE estimate's noise is proportional to its size, so equal
    /// weights in the log): c = a, exponent = 2γ, B = 0. Fewer than two distinct N: NaN.
    pub fn fit_power_law(photons: &[f64], mse: &[f64]) -> Self {
        let logs = log_points(photons, mse);
        let measured_min = logs.iter().map(|p| p.0.exp()).fold(f64::INFINITY, f64::min);
        let centre = mean(logs.iter().map(|p| p.0));
        let rows: Vec<([f64; 2], f64, f64)> = logs
            .iter()
            .map(|&(x, y)| ([1.0, x - centre], y, 1.0))
            .collect();
        let (c, exponent) = match solve_support(&rows, &[0, 1]) {
            Some(b) => ((b[0] - b[1] * centre).exp(), -b[1]),
            None => (f64::NAN, f64::NAN),
        };
        Self {
            floor2: 0.0,
            c,
            measured_min: finite_or_zero(measured_min),
            exponent,
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
        if self.exponent == 1.0 {
            self.floor2 + self.c / photons
        } else {
            self.floor2 + self.c * photons.powf(-self.exponent)
        }
    }

    /// γ: the relative RMSE's fall in N where it has no floor (error ∝ N^(−γ)), exponent/2.
    pub fn error_slope(&self) -> f64 {
        0.5 * self.exponent
    }

    /// Whether the error falls with N at all (a positive c and exponent): a power law fitted to a
    /// flat or rising curve reaches no target below it.
    pub fn falls(&self) -> bool {
        self.c > 0.0 && self.exponent > 0.0
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

    /// Photons for a relative RMSE of `target`: c/(target² − B) (with a power law
    /// (c/(target² − B))^(1/exponent)), but not fewer than `measured_min` (conservative: the fit is
    /// not trusted below the counts it was made on); `None` if the floor is at or above the target
    /// or the error does not fall ([`ErrorFit::falls`]).
    pub fn photons_for(&self, target: f64) -> Option<f64> {
        let room = target * target - self.floor2;
        if self.exponent == 1.0 {
            return (room > 0.0).then(|| (self.c / room).max(self.measured_min));
        }
        (room > 0.0 && self.falls()).then(|| {
            (self.c / room)
                .powf(1.0 / self.exponent)
                .max(self.measured_min)
        })
    }
}

/// Which form a DETP configuration's error takes in its photon count N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorModel {
    /// MSE = B + c/N: a radius fixed per point (fixed d, or the edge-aware κ·s_i): the variance
    /// falls as 1/N, the bias stays ([`ErrorFit::fit_relative`]).
    Floor,
    /// MSE = a·N^(−2γ): a radius shrinking with N (the schedule): bias and variance both fall
    /// ([`ErrorFit::fit_power_law`]).
    PowerLaw,
}

impl ErrorModel {
    /// This model fitted to the relative MSE `mse` at `photons`.
    pub fn fit(self, photons: &[f64], mse: &[f64]) -> ErrorFit {
        match self {
            ErrorModel::Floor => ErrorFit::fit_relative(photons, mse),
            ErrorModel::PowerLaw => ErrorFit::fit_power_law(photons, mse),
        }
    }
}

/// The curvature of ln MSE against ln N: the x² coefficient of the least-squares quadratic in
/// x = ln N (centred), over the positive values. 0 for a power law; positive where the curve
/// flattens (a floor appears: B + c/N has curvature B·c/N/(B + c/N)² > 0); NaN with fewer than three
/// distinct N.
pub fn log_curvature(photons: &[f64], mse: &[f64]) -> f64 {
    let logs = log_points(photons, mse);
    let centre = mean(logs.iter().map(|p| p.0));
    let rows: Vec<([f64; 3], f64, f64)> = logs
        .iter()
        .map(|&(x, y)| {
            let x = x - centre;
            ([1.0, x, x * x], y, 1.0)
        })
        .collect();
    solve_support(&rows, &[0, 1, 2]).map_or(f64::NAN, |b| b[2])
}

/// (ln N, ln MSE) of the finite pairs with N > 0 and MSE > 0.
fn log_points(photons: &[f64], mse: &[f64]) -> Vec<(f64, f64)> {
    photons
        .iter()
        .zip(mse)
        .filter(|(n, y)| n.is_finite() && **n > 0.0 && y.is_finite() && **y > 0.0)
        .map(|(n, y)| (n.ln(), y.ln()))
        .collect()
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, k) = v.fold((0.0, 0usize), |(s, k), x| (s + x, k + 1));
    s / k as f64
}

fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
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

    /// The error fit's second copy, in Python (`scripts/raycost_stats.py`,
    /// `fit_relative_iterated`, which the radius-schedule numbers use), is held to the same shared
    /// cases (`scripts/tests/data/error_fit_cases.txt`, Python's answers, with a value below 0 and
    /// a NaN among them): the same zeros and the fitted MSE within 1e-9 relative at every sample.
    #[test]
    fn the_error_fit_equals_the_python_copy() {
        let text = include_str!("../../scripts/tests/data/error_fit_cases.txt");
        let mut cases: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = Vec::new();
        for line in text.lines().filter(|l| !l.starts_with('#')) {
            let mut words = line.split_whitespace();
            let word = words.next();
            let values: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
            match word {
                Some("case") => cases.push((Vec::new(), Vec::new(), Vec::new())),
                Some("sample") => {
                    let c = cases.last_mut().unwrap();
                    c.0.push(values[0]);
                    c.1.push(values[1]);
                }
                Some("expect") => cases.last_mut().unwrap().2 = values,
                _ => {}
            }
        }
        assert_eq!(cases.len(), 6);
        for (photons, mse, expect) in &cases {
            let fit = ErrorFit::fit_relative(photons, mse);
            assert_eq!(
                [fit.floor2 == 0.0, fit.c == 0.0],
                [expect[0] == 0.0, expect[1] == 0.0],
                "{fit:?} against {expect:?}"
            );
            for &n in photons {
                let (a, b) = (fit.mse(n), expect[0] + expect[1] / n);
                assert!((a - b).abs() <= 1e-9 * b, "at {n}: {a} against {b}");
            }
        }
    }

    /// The cost fit's second copy, in Python (`scripts/raycost_stats.py`, `fit_costs`), is held to
    /// the same shared cases (`scripts/tests/data/cost_fit_cases.txt`, Python's answers): the same
    /// columns kept and fitted seconds within 1e-9 relative at every sample. Both solve the same
    /// normal equations on rows normalised by their seconds, so only rounding may differ.
    #[test]
    fn the_cost_fit_equals_the_python_copy() {
        let text = include_str!("../../scripts/tests/data/cost_fit_cases.txt");
        /// γ, the samples (photons, points, seconds), Python's [fixed, a, b, c].
        type Case = (f64, Vec<(f64, f64, f64)>, Vec<f64>);
        let mut cases: Vec<Case> = Vec::new();
        for line in text.lines().filter(|l| !l.starts_with('#')) {
            let mut words = line.split_whitespace();
            let word = words.next();
            let values: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
            match word {
                Some("case") => cases.push((values[0], Vec::new(), Vec::new())),
                Some("sample") => cases
                    .last_mut()
                    .unwrap()
                    .1
                    .push((values[0], values[1], values[2])),
                Some("expect") => cases.last_mut().unwrap().2 = values,
                _ => {}
            }
        }
        assert_eq!(cases.len(), 5);
        for (gamma, samples, expect) in &cases {
            let fit = CostModel::fit(samples, *gamma);
            let got = [
                fit.fixed,
                fit.per_photon,
                fit.per_photon_point,
                fit.per_point,
            ];
            let zeros = |c: &[f64]| c.iter().map(|&v| v == 0.0).collect::<Vec<_>>();
            assert_eq!(
                zeros(&got),
                zeros(expect),
                "γ {gamma}: {got:?} against {expect:?}"
            );
            let python = CostModel {
                fixed: expect[0],
                per_photon: expect[1],
                per_photon_point: expect[2],
                per_point: expect[3],
                gamma: *gamma,
            };
            for &(n, p, s) in samples {
                let (a, b) = (fit.seconds(n, p), python.seconds(n, p));
                assert!(
                    (a - b).abs() < 1e-9 * s,
                    "γ {gamma} at ({n}, {p}): {a} against {b}"
                );
            }
        }
    }

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
            exponent: 1.0,
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
            exponent: 1.0,
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

    /// A radius schedule's error a·N^(−2γ), γ = 1/3, with ±5 % alternating noise over six octaves:
    /// γ and N_ε come back within what the noise allows, the exact curve exactly; below the
    /// smallest measured count the measured count is the answer.
    #[test]
    fn a_power_law_is_recovered_from_noisy_errors() {
        let (a, gamma) = (20.0, 1.0 / 3.0);
        let n: Vec<f64> = (0..7).map(|k| 2.5e4 * 2f64.powi(k)).collect();
        let truth = |x: f64| a * x.powf(-2.0 * gamma);
        let exact: Vec<f64> = n.iter().map(|&x| truth(x)).collect();
        let fit = ErrorFit::fit_power_law(&n, &exact);
        assert!((fit.error_slope() - gamma).abs() < 1e-12, "{fit:?}");
        assert!((fit.c / a - 1.0).abs() < 1e-9, "{fit:?}");
        assert_eq!((fit.floor2, fit.measured_min), (0.0, 2.5e4));
        // ε = 1 %: N_ε = (a/ε²)^(3/2).
        let want = (a / 1e-4f64).powf(1.5);
        let got = fit.photons_for(0.01).expect("no floor");
        assert!((got / want - 1.0).abs() < 1e-9, "{got} vs {want}");
        assert!((fit.error(got) - 0.01).abs() < 1e-12);
        assert_eq!(
            fit.photons_for(0.5),
            Some(2.5e4),
            "already met at the smallest count"
        );
        let noisy: Vec<f64> = exact
            .iter()
            .enumerate()
            .map(|(k, &y)| y * if k % 2 == 0 { 1.05 } else { 0.95 })
            .collect();
        let fit = ErrorModel::PowerLaw.fit(&n, &noisy);
        assert!((fit.error_slope() - gamma).abs() < 0.01, "{fit:?}");
        let got = fit.photons_for(0.01).expect("no floor");
        assert!((got / want - 1.0).abs() < 0.1, "{got} vs {want}");
        // The floor model on the same data is the other fit.
        assert_eq!(ErrorModel::Floor.fit(&n, &noisy).exponent, 1.0);
    }

    /// A flat error does not fall: no target below it is reached.
    #[test]
    fn a_power_law_that_does_not_fall_reaches_nothing() {
        let n = [1e4, 2e4, 4e4, 8e4];
        let fit = ErrorFit::fit_power_law(&n, &[0.01, 0.011, 0.0105, 0.0112]);
        assert!(!fit.falls() && fit.error_slope() <= 0.0, "{fit:?}");
        assert_eq!(fit.photons_for(0.05), None);
        let two = ErrorFit::fit_power_law(&[1e4, 1e4], &[0.01, 0.02]);
        assert!(two.exponent.is_nan() && two.photons_for(0.05).is_none());
    }

    /// The log–log curvature: 0 for a power law; for B + c/N (second derivative B·c/N/(B + c/N)²
    /// in ln N, ¼ at the knee N = c/B) a quadratic coefficient of about half the mean second
    /// derivative over the counts; NaN with two counts.
    #[test]
    fn the_log_curvature_sees_a_floor() {
        let n: Vec<f64> = (0..5).map(|k| 1e4 * 4f64.powi(k)).collect();
        let power: Vec<f64> = n.iter().map(|x| 3.0 * x.powf(-0.6)).collect();
        assert!(log_curvature(&n, &power).abs() < 1e-9);
        // The knee at 10⁵ photons, inside the counts: 0.0930 by an independent quadratic fit.
        let floor: Vec<f64> = n.iter().map(|x| 1e-4 + 10.0 / x).collect();
        let q = log_curvature(&n, &floor);
        assert!((q - 0.0930).abs() < 0.001, "{q}");
        assert!(log_curvature(&n[..2], &floor[..2]).is_nan());
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
