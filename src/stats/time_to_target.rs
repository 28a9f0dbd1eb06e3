//! Which method when: the seconds each method needs to reach a target relative RMSE,
//! and the number of points N* beyond which DETP beats per-point path tracing, with a bootstrap CI
//! over replicas — or "never" with the reason. Pure functions of measured summaries.
//!
//! Errors are relative RMSEs over a point set: √(mean_i (Ê_i − E_i)²) / mean_i E_i, as the `detp`
//! kind reports them against the reference (its own variance subtracted).
//!
//! - **Path tracing** is unbiased and its points are independent: with n paths per point its
//!   relative RMSE is cv/√n, where cv = √(mean_i σ_i²)/mean_i E_i and σ_i² is the per-path variance
//!   at point i. A target ε needs n = ⌈(cv/ε)²⌉ paths per point, and n_P points cost n_P·n·t_path:
//!   linear in n_P, nothing paid once.
//! - **DETP** (and the photon map) has relative MSE B + c/N in its photon count N
//!   ([`ErrorFit`]), independent of n_P (a point's error depends on the photons and d, not on how many
//!   other points there are). A target ε needs N_ε = c/(ε² − B) photons, and none if √B ≥ ε (a
//!   bias floor). Its seconds are [`CostModel::seconds`](N_ε, n_P).
//! - **The crossover** N* solves T_DETP(n_P) = T_PT(n_P). With D(x) = T_DETP(x) − T_PT(x) =
//!   A + b·N_ε·x^γ + (c − p)·x (A = fixed + a·N_ε ≥ 0, p = n·t_path the path tracer's seconds per
//!   point, γ ∈ [0, 1]), D is concave and positive just above 0 (D(0) = A > 0, or for 0 < γ < 1 and
//!   b > 0 the x^γ term, whose slope at 0 is infinite, even when the fit leaves A = 0), so it has at
//!   most one positive root: DETP wins beyond it (0 only with A = 0 and no x^γ term). It exists
//!   iff DETP's seconds per added point eventually fall below the path tracer's: b·N_ε + c < p for
//!   γ = 1, c < p for γ < 1. Otherwise "never": DETP's cost per point (its tests per disc, i.e. its
//!   variance per disc) is not below the path tracer's.
//! - **Frames**: F frames of a quasi-static scene cost DETP T₁ + (F − 1)·t_f (the first frame in
//!   full, then incremental frames) against F·T_PT; DETP wins from F* = (T₁ − t_f)/(T_PT − t_f)
//!   frames on, if t_f < T_PT ([`frames_crossover`]).
//!
//! CIs come from a percentile bootstrap over replicas ([`bootstrap`]): replicas are the independent
//! units (a replica's points share its photons), so whole replicas are resampled, the summaries
//! recomputed and the statistic re-derived; "never" counts as +∞ (an upper bound of +∞ says the
//! data cannot exclude that DETP never wins). Seconds are taken as given (their spread across
//! replicas is small next to the errors'; the load at measurement time is reported beside them).

use super::fit::{log_curvature, CostModel, ErrorFit, ErrorModel};
use crate::sample::rng::{domain, stream};

/// Per-point path tracing's cost and noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTracingCost {
    /// cv: √(mean_i σ_i²) / mean_i E_i, the relative RMSE of one path per point.
    pub cv: f64,
    /// Seconds per path (wall clock on the threads used).
    pub seconds_per_path: f64,
}

impl PathTracingCost {
    /// cv from the per-path variances σ_i² at the points and their true irradiances E_i.
    pub fn cv_from(variances: &[f64], truth: &[f64]) -> f64 {
        let n = variances.len().min(truth.len()) as f64;
        let var = variances.iter().sum::<f64>() / n;
        let mean = truth.iter().sum::<f64>() / n;
        var.sqrt() / mean
    }

    /// cv² from the path tracer's own errors against the truth: `rel_mse[k]` is its relative MSE
    /// (the truth's variance subtracted) after `paths[k]` paths per point, e.g. at the prefix
    /// checkpoints of one run. Unbiased, mse(n) = cv²/n; least squares with relative weights
    /// 1/mse(n)² ∝ n² gives cv² = mean_k(n_k·mse_k). Where rare bright paths make the per-path
    /// sample variance unstable (heavy tails: a secondary vertex close to a point light), this reads
    /// the error as it is, not as the variance formula says it should be.
    pub fn cv2_from_prefix_errors(paths: &[f64], rel_mse: &[f64]) -> f64 {
        let n = paths.len().min(rel_mse.len()) as f64;
        paths.iter().zip(rel_mse).map(|(p, m)| p * m).sum::<f64>() / n
    }

    /// Paths per point for a relative RMSE of `target`: ⌈(cv/target)²⌉, at least 1.
    pub fn paths_for(&self, target: f64) -> u64 {
        // A hair below the integer it should be is that integer (rounding of cv and target).
        let n = (self.cv / target).powi(2) * (1.0 - 1e-12);
        (n.ceil() as u64).max(1)
    }

    /// Seconds per point at `target`.
    pub fn seconds_per_point(&self, target: f64) -> f64 {
        self.paths_for(target) as f64 * self.seconds_per_path
    }

    /// Seconds for `points` points at `target`.
    pub fn seconds(&self, points: f64, target: f64) -> f64 {
        points * self.seconds_per_point(target)
    }
}

/// Why DETP never beats path tracing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Never {
    /// DETP's error floor (√B, relative) is at or above the target: no photon count reaches it
    /// (a bias, or noise that does not fall with photons, such as NEE's direct part).
    ErrorFloor {
        /// √B.
        floor: f64,
        /// The target relative RMSE.
        target: f64,
    },
    /// DETP's seconds per added point are not below the path tracer's at the target.
    PerPointCost {
        /// DETP's seconds per added point, for many points (b·N_ε + c for γ = 1, c for γ < 1).
        detp: f64,
        /// The path tracer's seconds per point.
        path_tracing: f64,
    },
    /// A power law a·N^(−2γ) fitted to an error that does not fall (γ ≤ 0): no photon count
    /// reaches a target below the errors measured.
    NotFalling {
        /// The fitted γ.
        slope: f64,
    },
    /// The error curve of a radius schedule flattens in log–log (its curvature's interval lies
    /// above 0): a floor appears, so the power law a·N^(−2γ) that N_ε rests on does not hold.
    Flattens {
        /// The curvature of ln MSE in ln N ([`log_curvature`]).
        curvature: f64,
        /// The lower bound of its bootstrap interval (> 0).
        lo: f64,
    },
    /// DETP's seconds per further (incremental) frame are not below the path tracer's per frame.
    PerFrameCost {
        /// DETP's seconds per incremental frame.
        detp: f64,
        /// The path tracer's seconds per frame.
        path_tracing: f64,
    },
}

/// Where DETP starts to win.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossover {
    /// DETP is faster beyond this many points (or frames): a real number, round it up for a count.
    At(f64),
    /// It never is.
    Never(Never),
}

impl Crossover {
    /// The crossover as a number, +∞ for never.
    pub fn value(&self) -> f64 {
        match self {
            Crossover::At(x) => *x,
            Crossover::Never(_) => f64::INFINITY,
        }
    }
}

/// Why no photon count of `error` reaches `target` (where [`ErrorFit::photons_for`] is `None`): a
/// power law that does not fall, else the floor.
pub fn unreachable(error: &ErrorFit, target: f64) -> Never {
    if error.exponent != 1.0 && !error.falls() {
        return Never::NotFalling {
            slope: error.error_slope(),
        };
    }
    Never::ErrorFloor {
        floor: error.floor(),
        target,
    }
}

/// DETP's seconds for `points` points at relative RMSE `target`, or why it cannot reach it.
pub fn detp_seconds(
    error: &ErrorFit,
    cost: &CostModel,
    points: f64,
    target: f64,
) -> Result<f64, Never> {
    match error.photons_for(target) {
        Some(n) => Ok(cost.seconds(n, points)),
        None => Err(unreachable(error, target)),
    }
}

/// N*: the number of points beyond which DETP (error `error`, cost `cost`) reaches `target` faster
/// than path tracing (`pt`). See the module doc.
pub fn points_crossover(
    pt: &PathTracingCost,
    error: &ErrorFit,
    cost: &CostModel,
    target: f64,
) -> Crossover {
    let Some(n) = error.photons_for(target) else {
        return Crossover::Never(unreachable(error, target));
    };
    let p = pt.seconds_per_point(target);
    let d = |x: f64| cost.seconds(n, x) - p * x;
    let once = cost.seconds(n, 0.0);
    let per_point = if cost.gamma >= 1.0 {
        cost.per_photon_point * n + cost.per_point
    } else {
        cost.per_point
    };
    if per_point >= p {
        return Crossover::Never(Never::PerPointCost {
            detp: per_point,
            path_tracing: p,
        });
    }
    // 0 < γ < 1 with b > 0: b·N·x^γ outgrows p·x near 0 (its slope there is infinite), so D is
    // positive just above 0 even where the fit put nothing in A; γ = 0 puts b·N into A.
    let concave = cost.gamma > 0.0 && cost.gamma < 1.0 && cost.per_photon_point * n > 0.0;
    if !concave {
        if once <= 0.0 {
            return Crossover::At(0.0);
        }
        return Crossover::At(once / (p - per_point));
    }
    // D is concave, positive just above 0 and D → −∞: bracket the one root, then bisect.
    let mut hi = (once / (p - per_point)).max(1.0);
    while d(hi) > 0.0 && hi < f64::MAX / 4.0 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if d(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Crossover::At(hi)
}

/// F*: the frames beyond which DETP — `first_s` for the first frame, `frame_s` for each further
/// (incremental) frame — costs less in all than path tracing at `pt_frame_s` per frame.
pub fn frames_crossover(first_s: f64, frame_s: f64, pt_frame_s: f64) -> Crossover {
    if frame_s >= pt_frame_s {
        return Crossover::Never(Never::PerFrameCost {
            detp: frame_s,
            path_tracing: pt_frame_s,
        });
    }
    Crossover::At(((first_s - frame_s) / (pt_frame_s - frame_s)).max(1.0))
}

/// A statistic with its percentile bootstrap interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// The statistic on all replicas.
    pub estimate: f64,
    /// Lower bound (+∞ values sort last).
    pub lo: f64,
    /// Upper bound (+∞: not bounded).
    pub hi: f64,
    /// Fraction of resamples whose statistic was +∞ ("never").
    pub never_fraction: f64,
}

/// Percentile bootstrap over `replicas` independent replicas: `stat` receives the replica indices
/// of one resample (with repetition; all of them, in order, for the estimate) and returns the
/// statistic (+∞ for "never"). `draws` resamples from the stream `[BOOTSTRAP, seed]`, at two-sided
/// `level` (e.g. 0.95).
///
/// # Panics
/// With no replica, no draw, or a level outside (0, 1).
pub fn bootstrap(
    replicas: usize,
    draws: usize,
    level: f64,
    seed: u64,
    stat: impl Fn(&[usize]) -> f64,
) -> Interval {
    bootstrap_with(replicas, draws, level, seed, |pick, _| stat(pick))
}

/// [`bootstrap`] whose statistic may draw more randomness of its own for each resample (e.g. a
/// cost model's residuals, [`resample_cost`]) from the same stream, after the replicas' pick: the
/// estimate (all replicas, in order) gets `None`. With a statistic that draws nothing it is
/// [`bootstrap`] exactly.
///
/// # Panics
/// As [`bootstrap`].
pub fn bootstrap_with(
    replicas: usize,
    draws: usize,
    level: f64,
    seed: u64,
    stat: impl Fn(&[usize], Option<&mut crate::sample::rng::Stream>) -> f64,
) -> Interval {
    assert!(replicas >= 1 && draws >= 1 && level > 0.0 && level < 1.0);
    let all: Vec<usize> = (0..replicas).collect();
    let estimate = stat(&all, None);
    let mut rng = stream(&[domain::BOOTSTRAP, seed]);
    let mut values: Vec<f64> = (0..draws)
        .map(|_| {
            let pick: Vec<usize> = (0..replicas)
                .map(|_| rand::Rng::gen_range(&mut rng, 0..replicas))
                .collect();
            stat(&pick, Some(&mut rng))
        })
        .collect();
    values.sort_by(f64::total_cmp);
    let at = |q: f64| super::percentile(&values, q);
    Interval {
        estimate,
        lo: at(0.5 - 0.5 * level),
        hi: at(0.5 + 0.5 * level),
        never_fraction: values.iter().filter(|v| v.is_infinite()).count() as f64 / draws as f64,
    }
}

/// One bootstrap resample of a fitted cost model: a multiplicative residual bootstrap. Each sample
/// (N, n_P, seconds) keeps its N and n_P, its seconds become the model's × (1 + r), r drawn with
/// replacement from the samples' relative residuals (seconds/model − 1), and the model is refitted
/// at the same γ. So N*'s interval carries the cost model's misfit — the spread of the timings
/// between runs and the model's own lack of fit — not only the replicas' errors. With fewer than 2
/// samples, or none with a positive model value, the model comes back unchanged.
pub fn resample_cost(
    model: &CostModel,
    samples: &[(f64, f64, f64)],
    rng: &mut crate::sample::rng::Stream,
) -> CostModel {
    let fitted: Vec<f64> = samples.iter().map(|s| model.seconds(s.0, s.1)).collect();
    let residuals: Vec<f64> = samples
        .iter()
        .zip(&fitted)
        .filter(|(_, &f)| f > 0.0)
        .map(|(s, &f)| s.2 / f - 1.0)
        .collect();
    if samples.len() < 2 || residuals.is_empty() {
        return *model;
    }
    let drawn: Vec<(f64, f64, f64)> = samples
        .iter()
        .zip(&fitted)
        .map(|(s, &f)| {
            let r = residuals[rand::Rng::gen_range(rng, 0..residuals.len())];
            (s.0, s.1, f * (1.0 + r))
        })
        .collect();
    CostModel::fit(&drawn, model.gamma)
}

/// What one replica measured, for the crossover's bootstrap.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplicaErrors {
    /// DETP's relative MSE at each photon count of the analysis (this replica alone, the truth's
    /// variance subtracted).
    pub detp_mse: Vec<f64>,
    /// The path tracer's cv² in this replica: mean_i σ_i² / (mean_i E_i)².
    pub pt_cv2: f64,
}

/// The replicas `pick`'s mean relative MSE at each photon count (`mse[r][j]`: replica r at count j).
pub fn mean_mse(mse: &[Vec<f64>], photons: usize, pick: &[usize]) -> Vec<f64> {
    let k = pick.len() as f64;
    (0..photons)
        .map(|j| pick.iter().map(|&r| mse[r][j]).sum::<f64>() / k)
        .collect()
}

/// Whether a radius schedule's errors follow the power law a·N^(−2γ) its theory gives: γ and the
/// curvature of ln MSE in ln N ([`log_curvature`]), each with its bootstrap interval over the
/// replicas (the same resamples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLawCheck {
    /// γ of the fit on all replicas, and its interval.
    pub slope: Interval,
    /// The curvature, and its interval (NaN with fewer than three photon counts).
    pub curvature: Interval,
}

impl PowerLawCheck {
    /// Both statistics from `mse[r][j]` (replica r at `photons[j]`), `draws` resamples at `level`
    /// from the bootstrap stream of `seed`.
    pub fn run(photons: &[f64], mse: &[Vec<f64>], draws: usize, level: f64, seed: u64) -> Self {
        let at = |pick: &[usize]| mean_mse(mse, photons.len(), pick);
        let slope = bootstrap(mse.len(), draws, level, seed, |p| {
            ErrorFit::fit_power_law(photons, &at(p)).error_slope()
        });
        let curvature = bootstrap(mse.len(), draws, level, seed, |p| {
            log_curvature(photons, &at(p))
        });
        PowerLawCheck { slope, curvature }
    }

    /// Why the power law fails, if it does: the curvature's interval lies above 0 (the curve
    /// flattens: a floor appears), or γ ≤ 0 (the error does not fall). A NaN curvature (two photon
    /// counts) cannot fail.
    pub fn failure(&self) -> Option<Never> {
        if self.curvature.lo > 0.0 {
            return Some(Never::Flattens {
                curvature: self.curvature.estimate,
                lo: self.curvature.lo,
            });
        }
        let falls = self.slope.estimate > 0.0; // NaN (no fit) does not fall either
        (!falls).then_some(Never::NotFalling {
            slope: self.slope.estimate,
        })
    }
}

/// N* with its bootstrap interval: each resample averages the replicas' MSE curves and cv², refits
/// the error `model` (B + c/N, or a radius schedule's power law), redraws the cost model from `cost_samples` ([`resample_cost`]; empty: costs fixed) and
/// re-derives N*. The estimate is from all replicas and the fitted cost.
#[allow(clippy::too_many_arguments)] // the measured summaries, the target and the bootstrap's knobs
pub fn points_crossover_interval(
    model: ErrorModel,
    photons: &[f64],
    replicas: &[ReplicaErrors],
    seconds_per_path: f64,
    cost: &CostModel,
    cost_samples: &[(f64, f64, f64)],
    target: f64,
    draws: usize,
    level: f64,
    seed: u64,
) -> (Crossover, Interval) {
    let at = |pick: &[usize], cost: &CostModel| {
        let k = pick.len() as f64;
        let mse: Vec<f64> = (0..photons.len())
            .map(|j| pick.iter().map(|&r| replicas[r].detp_mse[j]).sum::<f64>() / k)
            .collect();
        let cv2 = pick.iter().map(|&r| replicas[r].pt_cv2).sum::<f64>() / k;
        let pt = PathTracingCost {
            cv: cv2.sqrt(),
            seconds_per_path,
        };
        points_crossover(&pt, &model.fit(photons, &mse), cost, target)
    };
    let all: Vec<usize> = (0..replicas.len()).collect();
    let estimate = at(&all, cost);
    let interval = bootstrap_with(replicas.len(), draws, level, seed, |p, rng| match rng {
        Some(rng) => at(p, &resample_cost(cost, cost_samples, rng)).value(),
        None => at(p, cost).value(),
    });
    (estimate, interval)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(per_photon_point: f64, per_point: f64, gamma: f64) -> CostModel {
        CostModel {
            fixed: 0.01,
            per_photon: 1e-6,
            per_photon_point,
            per_point,
            gamma,
        }
    }

    /// A path tracer with cv 1 at `seconds_per_path`.
    fn path_tracer(seconds_per_path: f64) -> PathTracingCost {
        PathTracingCost {
            cv: 1.0,
            seconds_per_path,
        }
    }

    /// An error MSE = floor² + c/N with no measured range.
    fn error(floor: f64, c: f64) -> ErrorFit {
        ErrorFit {
            floor2: floor * floor,
            c,
            measured_min: 0.0,
            exponent: 1.0,
        }
    }

    #[test]
    fn paths_per_point_follow_cv_over_target_squared() {
        let pt = path_tracer(2e-6);
        assert_eq!(pt.paths_for(0.1), 100);
        assert_eq!(pt.paths_for(0.05), 400);
        assert_eq!(pt.paths_for(0.03), 1112);
        assert_eq!(pt.paths_for(2.0), 1, "one path at least");
        assert!((pt.seconds(1000.0, 0.1) - 1000.0 * 100.0 * 2e-6).abs() < 1e-15);
        // cv: pooled variance over the mean truth.
        let cv = PathTracingCost::cv_from(&[4.0, 16.0], &[1.0, 3.0]);
        assert!((cv - 10f64.sqrt() / 2.0).abs() < 1e-15);
        // From prefix errors: mse = cv²/n exactly gives cv² back.
        let paths = [1.0, 2.0, 4.0, 8.0, 1024.0];
        let mse: Vec<f64> = paths.iter().map(|n| 2.25 / n).collect();
        assert!((PathTracingCost::cv2_from_prefix_errors(&paths, &mse) - 2.25).abs() < 1e-12);
    }

    /// γ = 1: the closed form A/(p − bN − c), at which both methods take the same seconds.
    #[test]
    fn the_points_crossover_equalises_the_seconds() {
        let pt = PathTracingCost {
            cv: 1.2,
            seconds_per_path: 2e-6,
        };
        let err = error(0.01, 50.0);
        let model = cost(1e-12, 2e-6, 1.0);
        for target in [0.1, 0.05, 0.02] {
            let Crossover::At(x) = points_crossover(&pt, &err, &model, target) else {
                panic!("a crossover at {target}");
            };
            let d = detp_seconds(&err, &model, x, target).expect("reachable");
            let p = pt.seconds(x, target);
            assert!((d / p - 1.0).abs() < 1e-9, "{target}: {d} vs {p} at {x}");
            // Beyond it DETP is faster, before it slower.
            assert!(
                detp_seconds(&err, &model, 2.0 * x, target).unwrap() < pt.seconds(2.0 * x, target)
            );
            assert!(
                detp_seconds(&err, &model, 0.5 * x, target).unwrap() > pt.seconds(0.5 * x, target)
            );
        }
    }

    /// γ < 1: the bisection finds the one root of the concave difference.
    #[test]
    fn a_sublinear_point_cost_crosses_once() {
        let pt = path_tracer(1e-6);
        let err = error(0.0, 10.0);
        let model = cost(1e-9, 1e-6, 0.5);
        let Crossover::At(x) = points_crossover(&pt, &err, &model, 0.05) else {
            panic!("a crossover");
        };
        let d = detp_seconds(&err, &model, x, 0.05).unwrap();
        assert!((d / pt.seconds(x, 0.05) - 1.0).abs() < 1e-9, "{x}");
    }

    /// The fit may leave nothing paid once (A = 0: no fixed cost, no cost per photon), as the
    /// Cornell box's refined sweep did for the sphere cache (γ = 0.2, seconds = b·N·n_P^0.2).
    /// DETP is still the dearer method at few points (b·N·x^γ ≫ p·x near 0): N* is the root
    /// (b·N/p)^(1/(1−γ)), not 0. With no x^γ term either, DETP costs nothing at 0 points: N* = 0.
    #[test]
    fn nothing_paid_once_still_crosses_at_the_root() {
        let pt = path_tracer(1e-6);
        let err = error(0.0, 10.0);
        let (b, gamma, target) = (1e-7, 0.2, 0.05);
        let model = CostModel {
            fixed: 0.0,
            per_photon: 0.0,
            per_photon_point: b,
            per_point: 0.0,
            gamma,
        };
        let n = err.photons_for(target).expect("reachable");
        let p = pt.seconds(1.0, target);
        let root = (b * n / p).powf(1.0 / (1.0 - gamma));
        let Crossover::At(x) = points_crossover(&pt, &err, &model, target) else {
            panic!("a crossover");
        };
        assert!((x / root - 1.0).abs() < 1e-9, "{x} against {root}");
        assert!(detp_seconds(&err, &model, 0.5 * x, target).unwrap() > pt.seconds(0.5 * x, target));
        assert!(detp_seconds(&err, &model, 2.0 * x, target).unwrap() < pt.seconds(2.0 * x, target));
        // A root below one point is found too (the bracket starts at 1).
        let tiny = CostModel {
            per_photon_point: 1e-12,
            ..model
        };
        let root = (1e-12 * n / p).powf(1.0 / (1.0 - gamma));
        assert!(root < 1.0);
        let Crossover::At(x) = points_crossover(&pt, &err, &tiny, target) else {
            panic!("a crossover");
        };
        assert!((x / root - 1.0).abs() < 1e-9, "{x} against {root}");
        // Nothing paid once and no x^γ term: DETP costs c·x < p·x from the first point on.
        let linear = CostModel {
            per_photon_point: 0.0,
            per_point: 1e-5,
            ..model
        };
        assert_eq!(
            points_crossover(&pt, &err, &linear, target),
            Crossover::At(0.0)
        );
    }

    #[test]
    fn never_says_why() {
        let pt = path_tracer(1e-6);
        let biased = error(0.08, 10.0);
        assert_eq!(
            points_crossover(&pt, &biased, &cost(0.0, 1e-6, 1.0), 0.05),
            Crossover::Never(Never::ErrorFloor {
                floor: 0.08,
                target: 0.05
            })
        );
        // Reachable (N_ε = 10/0.05² = 4000 photons), but each added point costs DETP
        // b·N_ε = 1 s against the path tracer's 400 paths × 1 µs.
        let unbiased = error(0.0, 10.0);
        match points_crossover(&pt, &unbiased, &cost(2.5e-4, 0.0, 1.0), 0.05) {
            Crossover::Never(Never::PerPointCost { detp, path_tracing }) => {
                assert!((detp - 1.0).abs() < 1e-12 && (path_tracing - 4e-4).abs() < 1e-15);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn frames_crossover_balances_the_totals() {
        let Crossover::At(f) = frames_crossover(10.0, 0.5, 2.5) else {
            panic!("a crossover");
        };
        assert!((10.0 + (f - 1.0) * 0.5 - f * 2.5).abs() < 1e-12);
        assert_eq!(
            frames_crossover(10.0, 3.0, 2.5),
            Crossover::Never(Never::PerFrameCost {
                detp: 3.0,
                path_tracing: 2.5
            })
        );
        // A first frame already cheaper than path tracing's: DETP wins from the first frame.
        assert_eq!(frames_crossover(1.0, 0.5, 2.5), Crossover::At(1.0));
    }

    /// The bootstrap's interval covers the spread of the replicas and is reproducible.
    #[test]
    fn the_bootstrap_interval_brackets_the_mean_of_replicas() {
        let values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let mean = |p: &[usize]| p.iter().map(|&i| values[i]).sum::<f64>() / p.len() as f64;
        let a = bootstrap(values.len(), 2000, 0.95, 7, mean);
        assert_eq!(a, bootstrap(values.len(), 2000, 0.95, 7, mean));
        assert!((a.estimate - 4.5).abs() < 1e-12);
        // SE of the mean: 2.29/√8 = 0.81; a 95 % interval about ±1.6.
        assert!(
            a.lo < 4.5 && a.hi > 4.5 && a.hi - a.lo > 2.0 && a.hi - a.lo < 4.5,
            "{a:?}"
        );
        assert_eq!(a.never_fraction, 0.0);
        // "Never" in some resamples: an unbounded upper end.
        let b = bootstrap(values.len(), 2000, 0.95, 7, |p| {
            if p.iter().filter(|&&i| i == 0).count() >= 2 {
                f64::INFINITY
            } else {
                1.0
            }
        });
        assert!(b.never_fraction > 0.05 && b.hi.is_infinite(), "{b:?}");
    }

    /// N* and its interval at target 5 % under the floor model, path tracing at 2 µs per path, 500
    /// resamples at 95 %, seed 1: the setting both interval tests share.
    fn floor_interval(
        photons: &[f64],
        replicas: &[ReplicaErrors],
        model: &CostModel,
        samples: &[(f64, f64, f64)],
    ) -> (Crossover, Interval) {
        points_crossover_interval(
            ErrorModel::Floor,
            photons,
            replicas,
            2e-6,
            model,
            samples,
            0.05,
            500,
            0.95,
            1,
        )
    }

    /// Replicas whose DETP error curve has a floor near the target: the interval of N* is wide, and
    /// "never" shows up in the resamples where the floor exceeds the target.
    #[test]
    fn the_crossover_interval_sees_a_floor_near_the_target() {
        let photons = [5e4, 2e5, 8e5];
        let make = |floor: f64, cv2: f64| ReplicaErrors {
            detp_mse: photons.iter().map(|&n| floor * floor + 100.0 / n).collect(),
            pt_cv2: cv2,
        };
        let clear: Vec<ReplicaErrors> =
            (0..6).map(|k| make(0.01 + 0.001 * k as f64, 1.0)).collect();
        let model = cost(1e-12, 1e-6, 1.0);
        let interval = |replicas: &[ReplicaErrors]| floor_interval(&photons, replicas, &model, &[]);
        let (est, ci) = interval(&clear);
        let Crossover::At(x) = est else {
            panic!("{est:?}")
        };
        assert!(ci.lo <= x && x <= ci.hi && ci.hi.is_finite(), "{x} {ci:?}");
        let near: Vec<ReplicaErrors> = [0.03, 0.04, 0.05, 0.06, 0.07]
            .iter()
            .map(|&f| make(f, 1.0))
            .collect();
        let (_, ci) = interval(&near);
        assert!(ci.never_fraction > 0.1 && ci.hi.is_infinite(), "{ci:?}");
    }

    /// Four replicas of a schedule's error a·N^(−2/3), each with its own ±8 % noise: γ's interval
    /// holds 1/3 and is narrow, the curvature's holds 0, the power law stands. Replicas that level
    /// off (B + c/N) are flagged as flattening; replicas that do not fall, as not falling.
    #[test]
    fn the_power_law_check_recovers_gamma_and_flags_a_floor() {
        let photons: Vec<f64> = (0..5).map(|k| 2.5e4 * 2f64.powi(k)).collect();
        let noise = |r: usize, j: usize| 1.0 + 0.08 * (((r * 7 + j * 3) % 5) as f64 - 2.0) / 2.0;
        let replicas = |f: &dyn Fn(f64) -> f64| -> Vec<Vec<f64>> {
            (0..4)
                .map(|r| {
                    photons
                        .iter()
                        .enumerate()
                        .map(|(j, &n)| f(n) * noise(r, j))
                        .collect()
                })
                .collect()
        };
        let power = replicas(&|n| 20.0 * n.powf(-2.0 / 3.0));
        let c = PowerLawCheck::run(&photons, &power, 2000, 0.95, 5);
        let third = 1.0 / 3.0;
        assert!(
            c.slope.lo < third && third < c.slope.hi && c.slope.hi - c.slope.lo < 0.05,
            "{c:?}"
        );
        assert!(c.curvature.lo < 0.0 && 0.0 < c.curvature.hi, "{c:?}");
        assert_eq!(c.failure(), None);
        let floor = replicas(&|n| 4e-4 + 40.0 / n);
        let f = PowerLawCheck::run(&photons, &floor, 2000, 0.95, 5);
        assert!(
            matches!(f.failure(), Some(Never::Flattens { lo, .. }) if lo > 0.0),
            "{f:?}"
        );
        let flat = replicas(&|_| 0.01);
        let g = PowerLawCheck::run(&photons, &flat, 2000, 0.95, 5);
        assert!(
            matches!(g.failure(), Some(Never::NotFalling { .. })),
            "{g:?}"
        );
        // An error model that does not fall says so, not "error floor".
        let fit = ErrorFit::fit_power_law(&photons, &mean_mse(&flat, photons.len(), &[0, 1, 2, 3]));
        assert!(!fit.falls(), "{fit:?}");
        assert!(matches!(unreachable(&fit, 0.005), Never::NotFalling { .. }));
    }

    /// The cost model's residual bootstrap: exact samples give the model back; noisy ones move
    /// it, and N*'s interval widens against fixed costs (the replicas' errors alone).
    #[test]
    fn the_cost_model_misfit_widens_the_crossover_interval() {
        let model = cost(1e-12, 1e-6, 1.0);
        let grid: Vec<(f64, f64)> = [5e4, 2e5, 8e5]
            .iter()
            .flat_map(|&n| [1e2, 1e3, 1e4, 1e5].map(|p| (n, p)))
            .collect();
        let exact: Vec<(f64, f64, f64)> = grid
            .iter()
            .map(|&(n, p)| (n, p, model.seconds(n, p)))
            .collect();
        let mut rng = stream(&[domain::BOOTSTRAP, 3]);
        let same = resample_cost(&model, &exact, &mut rng);
        for s in &exact {
            assert!((same.seconds(s.0, s.1) / s.2 - 1.0).abs() < 1e-9);
        }
        // ±30 % alternating misfit, as the committed sweeps show (worst misfit 0.13–0.36).
        let noisy: Vec<(f64, f64, f64)> = exact
            .iter()
            .enumerate()
            .map(|(k, s)| (s.0, s.1, s.2 * if k % 2 == 0 { 1.3 } else { 0.7 }))
            .collect();
        let photons = [5e4, 2e5, 8e5];
        let reps: Vec<ReplicaErrors> = (0..6)
            .map(|k| ReplicaErrors {
                detp_mse: photons
                    .iter()
                    .map(|&n| 1e-4 + (100.0 + k as f64) / n)
                    .collect(),
                pt_cv2: 1.0,
            })
            .collect();
        let fixed = floor_interval(&photons, &reps, &model, &[]);
        let moved = floor_interval(&photons, &reps, &model, &noisy);
        assert_eq!(
            fixed.0, moved.0,
            "the estimate uses the fitted cost either way"
        );
        let width = |i: &Interval| i.hi - i.lo;
        assert!(
            width(&moved.1) > 2.0 * width(&fixed.1),
            "{fixed:?} {moved:?}"
        );
    }
}
