//! The analysis (docs/plans/crossover-wiring.md §4), pure: per target and method configuration the
//! photons (or paths) it needs, its seconds once and per point, and N* — the points beyond which
//! it beats per-point path tracing — from the measured seconds of the n_P sweep
//! ([`measured_star`]: interpolated between measured n_P, marked where extrapolated, a bootstrap
//! over the fronts' replicas, the sweep's runs and path tracing's timings, widened to hold the
//! other interpolation form and the global model), the global cost model's N* beside it with its
//! own interval ([`points_crossover_interval`]); and per target and n_P the fastest configuration.

use super::costs::{points_range, CostSamples, FittedCost, PathTiming};
use super::fronts::{DetpErrors, MapErrors};
use super::measured::{measured_star, MeasuredInputs, MeasuredStar, RunTimings};
use super::method::{Config, Method};
use crate::stats::fit::{ErrorFit, ErrorModel};
use crate::stats::time_to_target::{
    mean_mse, points_crossover, points_crossover_interval, unreachable, Crossover, Never,
    PathTracingCost, PowerLawCheck, ReplicaErrors,
};

/// Bootstrap resamples.
pub const DRAWS: usize = 2000;
/// Two-sided level of the interval.
pub const LEVEL: f64 = 0.95;
/// `seconds_per_point` is the seconds per added point at this many points.
pub const POINTS_PER_POINT: f64 = 1e4;
/// The n_P of `best.csv`.
pub const BEST_POINTS: [f64; 5] = [1e2, 1e3, 1e4, 1e5, 1e6];

/// Everything the analysis reads, already extracted from the tables.
#[derive(Clone, Debug)]
pub struct Inputs {
    /// The scene's name.
    pub scene: String,
    /// The fronts' experiment.seed (the bootstrap's stream).
    pub seed: u64,
    /// DETP's errors per configuration.
    pub detp: Vec<DetpErrors>,
    /// The photon maps' errors.
    pub maps: Vec<MapErrors>,
    /// Path tracing's cv² per replica, and the fronts' sweep point it was read at.
    pub pt_cv2: Vec<f64>,
    /// That sweep point.
    pub pt_point: u64,
    /// Path tracing's seconds per path (n_P sweep).
    pub timing: PathTiming,
    /// Seconds per configuration (n_P sweep, every run pooled: the global model's samples).
    pub costs: Vec<CostSamples>,
    /// The n_P sweep's runs, each with its own seconds (the measured N*'s curves).
    pub runs: Vec<RunTimings>,
}

/// One row of `crossover.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct CrossRow {
    /// Scene.
    pub scene: String,
    /// Target relative RMSE.
    pub target: f64,
    /// Method configuration.
    pub config: Config,
    /// N_ε (photons of one estimate), or paths per point for path tracing; NaN if unreachable.
    pub photons: f64,
    /// The largest photon count the fronts measured for this configuration (NaN for path
    /// tracing): an N_ε beyond it is the error fit's extrapolation, not a measured error.
    pub photons_measured_max: f64,
    /// √B (NaN under a radius schedule: its error model has no floor).
    pub error_floor: f64,
    /// c of B + c/N (path tracing: cv²; NaN under a radius schedule).
    pub error_fit_c: f64,
    /// a of a·N^(−2γ) under a radius schedule (NaN otherwise).
    pub error_fit_a: f64,
    /// Under a radius schedule: the fitted γ and the log–log curvature with their intervals.
    pub power_law: Option<PowerLawCheck>,
    /// Seconds paid once at N_ε.
    pub seconds_once: f64,
    /// Seconds per added point at [`POINTS_PER_POINT`] points.
    pub seconds_per_point: f64,
    /// The cost model, if the n_P sweep timed this configuration.
    pub cost: Option<FittedCost>,
    /// N*, or NaN ("never": see `reason`): from the measured seconds (log–log between measured
    /// n_P), else (no per-run timings) the global model's.
    pub n_star: f64,
    /// Bounds (+∞: unbounded; NaN: no bootstrap): the measured N*'s bootstrap widened to hold the
    /// linear form's and the model's N*.
    pub n_star_lo: f64,
    /// Upper bound.
    pub n_star_hi: f64,
    /// Fraction of resamples that said "never".
    pub never_fraction: f64,
    /// N* from the measured seconds interpolated linearly (NaN: not measured).
    pub n_star_linear: f64,
    /// The global cost model's N* and its bootstrap bounds (NaN: no model).
    pub n_star_model: f64,
    /// Lower bound.
    pub n_star_model_lo: f64,
    /// Upper bound.
    pub n_star_model_hi: f64,
    /// N* lies outside the n_P the sweep measured.
    pub extrapolated: bool,
    /// The n_P the sweep measured for this configuration (smallest, largest; NaN: none).
    pub measured_points: (f64, f64),
    /// N* measured head to head (DETP at N_ε and path tracing at its paths on the same points,
    /// [`super::confirm`]); NaN without such a run.
    pub n_star_head_to_head: f64,
    /// Empty, or why something is missing or never.
    pub reason: String,
}

impl CrossRow {
    /// Seconds for `points` points at the target, if known.
    pub fn seconds(&self, points: f64) -> Option<f64> {
        if !self.photons.is_finite() {
            return None;
        }
        if self.config.method.is_path_tracing() {
            return Some(points * self.seconds_per_point);
        }
        self.cost.map(|c| c.model.seconds(self.photons, points))
    }
}

/// Why "never", in words.
fn never_reason(n: &Never) -> String {
    match n {
        Never::ErrorFloor { floor, target } => {
            format!("error floor √B = {floor:.4} ≥ target {target}")
        }
        Never::PerPointCost { detp, path_tracing } => format!(
            "per-point cost {detp:.3e} s ≥ path tracing's {path_tracing:.3e} s at this target"
        ),
        Never::PerFrameCost { detp, path_tracing } => {
            format!("per-frame cost {detp:.3e} s ≥ path tracing's {path_tracing:.3e} s per frame")
        }
        Never::NotFalling { slope } => {
            format!("the error does not fall with photons (fitted γ = {slope:.3} ≤ 0)")
        }
        Never::Flattens { curvature, lo } => format!(
            "the error curve flattens (log–log curvature {curvature:.3}, 95 % lower bound {lo:.3} > 0): a floor appears, so the power law a·N^(−2γ) does not hold"
        ),
    }
}

/// The path tracer over all replicas.
pub fn path_tracer(cv2: &[f64], seconds_per_path: f64) -> PathTracingCost {
    let mean = cv2.iter().sum::<f64>() / cv2.len().max(1) as f64;
    PathTracingCost {
        cv: mean.max(0.0).sqrt(),
        seconds_per_path,
    }
}

/// A row's fields that follow from the error fit and (if any) the cost model alone.
fn base_row(inp: &Inputs, target: f64, config: Config, fit: &ErrorFit) -> CrossRow {
    let rule = config.radius_rule.unwrap_or_default();
    let power = rule.error_model() == ErrorModel::PowerLaw;
    let cost = inp
        .costs
        .iter()
        .find(|c| config.matches(&c.config))
        .map(CostSamples::fit);
    let photons = fit.photons_for(target).unwrap_or(f64::NAN);
    let (once, per_point) = match (cost, photons.is_finite()) {
        (Some(c), true) => {
            let once = c.model.seconds(photons, 0.0);
            let at = c.model.seconds(photons, POINTS_PER_POINT);
            (once, (at - once) / POINTS_PER_POINT)
        }
        _ => (f64::NAN, f64::NAN),
    };
    let mut reason = Vec::new();
    if cost.is_none() {
        reason.push(match rule == Default::default() {
            true => "no cost sweep at this d/edge/direct".to_string(),
            false => format!(
                "no cost sweep at this d/edge/direct and radius rule{}",
                rule.describe()
            ),
        });
    }
    if !photons.is_finite() {
        reason.push(never_reason(&unreachable(fit, target)));
    }
    let (floor, c, a) = match power {
        true => (f64::NAN, f64::NAN, fit.c),
        false => (fit.floor(), fit.c, f64::NAN),
    };
    CrossRow {
        scene: inp.scene.clone(),
        target,
        config,
        photons,
        photons_measured_max: f64::NAN,
        error_floor: floor,
        error_fit_c: c,
        error_fit_a: a,
        power_law: None,
        seconds_once: once,
        seconds_per_point: per_point,
        cost,
        n_star: f64::NAN,
        n_star_lo: f64::NAN,
        n_star_hi: f64::NAN,
        never_fraction: f64::NAN,
        n_star_linear: f64::NAN,
        n_star_model: f64::NAN,
        n_star_model_lo: f64::NAN,
        n_star_model_hi: f64::NAN,
        extrapolated: false,
        measured_points: (f64::NAN, f64::NAN),
        n_star_head_to_head: f64::NAN,
        reason: reason.join("; "),
    }
}

/// Adds a "never" reason (once) to a row.
fn add_reason(row: &mut CrossRow, why: String) {
    if !row.reason.contains(&why) {
        if !row.reason.is_empty() {
            row.reason.push_str("; ");
        }
        row.reason.push_str(&why);
    }
}

/// The rows of one configuration (one per method of `methods`) at `target` from each replica's
/// relative MSE at each photon count (`mse[r][j]`, N photons of one replica): the error fit on the
/// replicas' mean, N* and its bootstrap CI with the replicas as the units (paired with path
/// tracing's). DETP and the photon maps alike.
fn replica_rows(
    inp: &Inputs,
    config: &Config,
    methods: &[Method],
    photons: &[f64],
    mse: &[Vec<f64>],
    target: f64,
) -> Vec<CrossRow> {
    let reps = mse.len().min(inp.pt_cv2.len());
    let all: Vec<usize> = (0..reps).collect();
    let mean = mean_mse(mse, photons.len(), &all);
    let model = config
        .radius_rule
        .map_or(ErrorModel::Floor, |r| r.error_model());
    let fit = model.fit(photons, &mean);
    let power_law = (model == ErrorModel::PowerLaw)
        .then(|| PowerLawCheck::run(photons, &mse[..reps], DRAWS, LEVEL, inp.seed));
    let failure = power_law.as_ref().and_then(PowerLawCheck::failure);
    let replicas: Vec<ReplicaErrors> = (0..reps)
        .map(|r| ReplicaErrors {
            detp_mse: mse[r].clone(),
            pt_cv2: inp.pt_cv2[r],
        })
        .collect();
    methods
        .iter()
        .map(|&method| {
            let config = Config {
                method,
                ..config.clone()
            };
            let mut row = base_row(inp, target, config, &fit);
            row.photons_measured_max = photons.iter().copied().fold(f64::NAN, f64::max);
            row.power_law = power_law;
            if let Some(never) = failure {
                // The fit N_ε rests on does not hold: no N_ε, no N*, and why.
                (row.photons, row.seconds_once, row.seconds_per_point) =
                    (f64::NAN, f64::NAN, f64::NAN);
                add_reason(&mut row, never_reason(&never));
                return row;
            }
            if let Some(c) = row.cost {
                let samples = inp
                    .costs
                    .iter()
                    .find(|s| row.config.matches(&s.config))
                    .map_or(&[][..], |s| &s.samples[..]);
                let (est, ci) = points_crossover_interval(
                    model,
                    photons,
                    &replicas,
                    inp.timing.median,
                    &c.model,
                    samples,
                    target,
                    DRAWS,
                    LEVEL,
                    inp.seed,
                );
                (row.n_star_model_lo, row.n_star_model_hi) = (ci.lo, ci.hi);
                row.n_star_model = est.value();
                let m = MeasuredInputs {
                    config: &row.config,
                    model,
                    photons,
                    replicas: &replicas,
                    runs: &inp.runs,
                    target,
                };
                let measured = row
                    .photons
                    .is_finite()
                    .then(|| measured_star(&m, DRAWS, LEVEL, inp.seed))
                    .flatten();
                match measured {
                    Some(s) => put_measured(&mut row, &s),
                    None if !row.photons.is_finite() => row.n_star = est.value(),
                    None => {
                        // No per-run timings: the model's N* and interval.
                        (row.n_star_lo, row.n_star_hi) = (ci.lo, ci.hi);
                        row.never_fraction = ci.never_fraction;
                        row.n_star = est.value();
                        add_reason(
                            &mut row,
                            "no per-run seconds at ≥ 2 n_P: N* from the global cost model".into(),
                        );
                        mark_model_range(&mut row, samples);
                    }
                }
                if let Crossover::Never(n) = est {
                    add_reason(&mut row, format!("model: {}", never_reason(&n)));
                }
                if row.n_star.is_infinite() {
                    row.n_star = f64::NAN;
                }
                if row.n_star_model.is_infinite() {
                    row.n_star_model = f64::NAN;
                }
            }
            row
        })
        .collect()
}

/// A row's N* from the measured seconds: the log–log estimate, its interval widened to hold the
/// linear form's interval and the model's N* (their spread is the form error), extrapolated where
/// it lies outside the measured n_P.
fn put_measured(row: &mut CrossRow, s: &MeasuredStar) {
    let (lo, hi) = s.range;
    row.measured_points = s.range;
    row.n_star = s.loglog.n_star;
    row.n_star_linear = s.linear.n_star;
    row.never_fraction = s.loglog_ci.never_fraction;
    let forms = [s.loglog_ci.lo, s.linear_ci.lo, row.n_star_model];
    let tops = [s.loglog_ci.hi, s.linear_ci.hi, row.n_star_model];
    let finite_min = |v: &[f64]| {
        v.iter()
            .copied()
            .filter(|x| !x.is_nan())
            .fold(f64::INFINITY, f64::min)
    };
    let finite_max = |v: &[f64]| {
        v.iter()
            .copied()
            .filter(|x| !x.is_nan())
            .fold(f64::NEG_INFINITY, f64::max)
    };
    row.n_star_lo = finite_min(&forms);
    row.n_star_hi = finite_max(&tops);
    row.extrapolated = s.loglog.extrapolated || !(lo..=hi).contains(&s.loglog.n_star);
    if s.loglog.n_star.is_infinite() {
        row.extrapolated = false;
        add_reason(
            row,
            format!(
                "never in the measured seconds over n_P {lo:.0}–{hi:.0} (the gap does not close)"
            ),
        );
    } else if row.extrapolated {
        add_reason(
            row,
            format!("N* extrapolated: outside the measured n_P {lo:.0}–{hi:.0}"),
        );
    }
}

/// A DETP configuration's rows (one per engine) at `target`, with the bootstrap CI of N*.
fn detp_rows(inp: &Inputs, e: &DetpErrors, target: f64) -> Vec<CrossRow> {
    replica_rows(inp, &e.config, &Method::detp(), &e.photons, &e.mse, target)
}

/// A photon map's row at `target`, judged as DETP is: each replica's error at its own N photons
/// (a fixed-k map's variance goes as 1/k, whatever N or the replicas), the replicas the
/// bootstrap's units. Without per-replica values in the points table: N* from the fit on the
/// replicas' mean MSE, no CI.
fn map_row(inp: &Inputs, e: &MapErrors, target: f64) -> CrossRow {
    if e.per_replica {
        let method = [e.config.method];
        return replica_rows(inp, &e.config, &method, &e.photons, &e.mse, target).remove(0);
    }
    let mean = e.mse.first().map_or(&[][..], |m| &m[..]);
    let fit = ErrorFit::fit_relative(&e.photons, mean);
    let mut row = base_row(inp, target, e.config.clone(), &fit);
    row.photons_measured_max = e.photons.iter().copied().fold(f64::NAN, f64::max);
    add_reason(
        &mut row,
        "no per-replica values in the points table: the replicas' mean MSE at N photons from the mean and its SE, no bootstrap CI"
            .into(),
    );
    if let Some(c) = row.cost {
        let pt = path_tracer(&inp.pt_cv2, inp.timing.median);
        match points_crossover(&pt, &fit, &c.model, target) {
            Crossover::At(x) => (row.n_star, row.n_star_model) = (x, x),
            Crossover::Never(n) => add_reason(&mut row, never_reason(&n)),
        }
        let samples = inp
            .costs
            .iter()
            .find(|s| row.config.matches(&s.config))
            .map_or(&[][..], |s| &s.samples[..]);
        mark_model_range(&mut row, samples);
    }
    row
}

/// A row whose N* comes from the global cost model alone: the n_P its configuration was timed at
/// (`samples`, the sweep's), and the N* marked extrapolated where it lies outside them — the model
/// is a fit over those n_P, so beyond them it is a trend, not a measurement.
fn mark_model_range(row: &mut CrossRow, samples: &[(f64, f64, f64)]) {
    let (lo, hi) = points_range(samples);
    row.measured_points = (lo, hi);
    if row.n_star.is_finite() && !(lo..=hi).contains(&row.n_star) {
        row.extrapolated = true;
        add_reason(
            row,
            format!("N* extrapolated: the model's, outside the timed n_P {lo:.0}–{hi:.0}"),
        );
    }
}

/// Path tracing's row at `target`.
fn path_row(inp: &Inputs, target: f64) -> CrossRow {
    let pt = path_tracer(&inp.pt_cv2, inp.timing.median);
    let t = &inp.timing;
    CrossRow {
        scene: inp.scene.clone(),
        target,
        config: Config {
            method: Method::path_tracing(),
            direct: None,
            edge: None,
            disc_radius: None,
            radius_rule: None,
        },
        photons: pt.paths_for(target) as f64,
        photons_measured_max: f64::NAN,
        error_floor: 0.0,
        error_fit_c: pt.cv * pt.cv,
        error_fit_a: f64::NAN,
        power_law: None,
        seconds_once: 0.0,
        seconds_per_point: pt.seconds_per_point(target),
        cost: None,
        n_star: f64::NAN,
        n_star_lo: f64::NAN,
        n_star_hi: f64::NAN,
        never_fraction: f64::NAN,
        n_star_linear: f64::NAN,
        n_star_model: f64::NAN,
        n_star_model_lo: f64::NAN,
        n_star_model_hi: f64::NAN,
        extrapolated: false,
        measured_points: (f64::NAN, f64::NAN),
        n_star_head_to_head: f64::NAN,
        reason: format!(
            "cv² from its prefix errors at fronts sweep point {} ({} replicas); s per path: median {:.3e} of {} rows (min {:.3e}, max {:.3e})",
            inp.pt_point,
            inp.pt_cv2.len(),
            t.median,
            t.rows,
            t.min,
            t.max
        ),
    }
}

/// Every row of `crossover.csv`: per target, DETP's configurations (both engines), the photon
/// maps, path tracing. The DETP configurations run in parallel (each one's bootstrap draws from
/// its own stream of the fronts' seed, so the rows do not depend on the thread count) and are
/// collected in order.
pub fn crossover_rows(inp: &Inputs, targets: &[f64]) -> Vec<CrossRow> {
    use rayon::prelude::*;
    let mut rows = Vec::new();
    for &target in targets {
        let detp: Vec<Vec<CrossRow>> = inp
            .detp
            .par_iter()
            .map(|e| detp_rows(inp, e, target))
            .collect();
        rows.extend(detp.into_iter().flatten());
        rows.extend(inp.maps.iter().map(|e| map_row(inp, e, target)));
        rows.push(path_row(inp, target));
    }
    rows
}

/// One row of `best.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct BestRow {
    /// Scene.
    pub scene: String,
    /// Target.
    pub target: f64,
    /// n_P.
    pub points: f64,
    /// The fastest configuration and its seconds.
    pub best: Option<(String, f64)>,
    /// The runner-up and its seconds.
    pub runner_up: Option<(String, f64)>,
    /// n_P lies outside the n_P the sweep measured: the seconds are the model's beyond its data.
    pub extrapolated: bool,
}

/// Per target and n_P of [`BEST_POINTS`] and `more_points` (e.g. the fronts' own point count; in
/// increasing order with them), the two fastest configurations that reach the target, marked
/// extrapolated where n_P lies outside `measured` (the sweep's smallest and largest n_P).
pub fn best_rows(
    rows: &[CrossRow],
    targets: &[f64],
    more_points: &[f64],
    measured: (f64, f64),
) -> Vec<BestRow> {
    let mut grid: Vec<f64> = BEST_POINTS.iter().chain(more_points).copied().collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let mut out = Vec::new();
    for &target in targets {
        for &points in &grid {
            let mut c: Vec<(String, f64)> = rows
                .iter()
                .filter(|r| r.target == target)
                .filter_map(|r| Some((r.config.describe(), r.seconds(points)?)))
                .filter(|c| c.1.is_finite())
                .collect();
            c.sort_by(|a, b| a.1.total_cmp(&b.1));
            let mut it = c.into_iter();
            out.push(BestRow {
                scene: rows.first().map_or_else(String::new, |r| r.scene.clone()),
                target,
                points,
                best: it.next(),
                runner_up: it.next(),
                extrapolated: !(measured.0..=measured.1).contains(&points),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crossover::method::RadiusRule;
    use crate::stats::fit::CostModel;

    const MODEL: CostModel = CostModel {
        fixed: 0.5,
        per_photon: 1e-6,
        per_photon_point: 1e-12,
        per_point: 1e-6,
        gamma: 1.0,
    };

    /// Errors exactly B + c/N in every replica, seconds exactly the cost model, cv² = 1 in every
    /// replica: N* is the closed form A/(p − b·N_ε − c), the CI collapses on it, and a target below
    /// the floor says so.
    fn inputs() -> Inputs {
        let photons = vec![1e4, 4e4, 1.6e5];
        let truth = ErrorFit {
            floor2: 0.01f64.powi(2),
            c: 50.0,
            measured_min: 0.0,
            exponent: 1.0,
        };
        let mse: Vec<Vec<f64>> = (0..3)
            .map(|_| photons.iter().map(|&n| truth.mse(n)).collect())
            .collect();
        let config = Config {
            method: Method::named("sphere-cache").unwrap(),
            direct: Some("photons".into()),
            edge: Some("paper".into()),
            disc_radius: Some(5.0),
            radius_rule: Some(RadiusRule::default()),
        };
        let mut samples = Vec::new();
        for n in [1e4, 1e5] {
            for p in [1e2, 1e3, 1e4, 1e5] {
                samples.push((n, p, MODEL.seconds(n, p)));
            }
        }
        let other = Config {
            disc_radius: Some(15.0),
            ..config.clone()
        };
        Inputs {
            scene: "synthetic".into(),
            seed: 1,
            detp: vec![
                DetpErrors {
                    config: config.clone(),
                    photons: photons.clone(),
                    mse: mse.clone(),
                },
                DetpErrors {
                    config: other,
                    photons,
                    mse,
                },
            ],
            maps: Vec::new(),
            pt_cv2: vec![1.0; 3],
            pt_point: 0,
            timing: PathTiming {
                median: 2e-6,
                min: 2e-6,
                max: 2e-6,
                rows: 1,
            },
            costs: vec![CostSamples { config, samples }],
            runs: Vec::new(),
        }
    }

    /// A radius schedule beside the fixed d at the same d: its N_ε comes from a·N^(−2γ), not
    /// B + c/N, with γ beside the derived 1/3; the fixed rule's seconds are not its seconds (no
    /// N* until the sweep timed its own rule); a schedule whose errors level off is never, and
    /// says why.
    #[test]
    fn a_schedule_is_fitted_as_a_power_law_and_timed_by_its_own_rule() {
        let mut inp = inputs();
        let rule = RadiusRule::read(f64::NAN, 1e4, f64::NAN);
        let config = Config {
            radius_rule: Some(rule),
            ..inp.detp[0].config.clone()
        };
        let photons: Vec<f64> = (0..5).map(|k| 1e4 * 2f64.powi(k)).collect();
        let replicas = |f: &dyn Fn(f64) -> f64| -> Vec<Vec<f64>> {
            (0..3)
                .map(|r| {
                    photons
                        .iter()
                        .enumerate()
                        .map(|(j, &n)| f(n) * (1.0 + 0.02 * (((r + j) % 3) as f64 - 1.0)))
                        .collect()
                })
                .collect()
        };
        let a = 20.0;
        inp.detp = vec![DetpErrors {
            config: config.clone(),
            photons: photons.clone(),
            mse: replicas(&|n| a * n.powf(-2.0 / 3.0)),
        }];
        let rows = crossover_rows(&inp, &[0.05]);
        let sc = &rows[0];
        assert_eq!(sc.config, config);
        let want = (a / 0.05f64.powi(2)).powf(1.5);
        assert!(
            (sc.photons / want - 1.0).abs() < 0.05,
            "{} vs {want}",
            sc.photons
        );
        assert!(sc.error_floor.is_nan() && sc.error_fit_c.is_nan(), "{sc:?}");
        assert!((sc.error_fit_a / a - 1.0).abs() < 0.1, "{sc:?}");
        let check = sc.power_law.expect("a schedule is checked");
        assert!((check.slope.estimate - 1.0 / 3.0).abs() < 0.01, "{check:?}");
        assert!(
            sc.reason
                .contains("no cost sweep at this d/edge/direct and radius rule")
                && sc.n_star.is_nan(),
            "{sc:?}"
        );
        // Timed under its own rule: an N*.
        let own = CostSamples {
            config: Config {
                radius_rule: Some(rule),
                ..inp.costs[0].config.clone()
            },
            samples: inp.costs[0].samples.clone(),
        };
        inp.costs.push(own);
        let rows = crossover_rows(&inp, &[0.05]);
        assert!(
            rows[0].n_star.is_finite() && rows[0].n_star > 0.0,
            "{:?}",
            rows[0]
        );
        // Errors that level off: the power law does not hold, never.
        inp.detp[0].mse = replicas(&|n| 4e-4 + 40.0 / n);
        let rows = crossover_rows(&inp, &[0.05]);
        assert!(
            rows[0].photons.is_nan() && rows[0].n_star.is_nan(),
            "{:?}",
            rows[0]
        );
        assert!(rows[0].reason.contains("flattens"), "{}", rows[0].reason);
    }

    /// A photon map with photons-only direct light (no d, edge or radius rule).
    fn photon_map() -> Config {
        Config {
            method: Method::named("photon-map").unwrap(),
            direct: Some("photons".into()),
            edge: None,
            disc_radius: None,
            radius_rule: None,
        }
    }

    /// A fixed-k photon map whose every replica's error levels off at 20 % (B = 0.04): the mean of
    /// four replicas would be at 10 %, but one estimate never is, so a 10 % target is out of
    /// reach (per-replica values, or only their mean MSE, alike).
    #[test]
    fn a_photon_map_does_not_reach_what_one_replica_does_not() {
        let mut inp = inputs();
        let config = photon_map();
        let photons = vec![1e4, 1e5, 1e6];
        for per_replica in [true, false] {
            let series = if per_replica { 4 } else { 1 };
            inp.maps = vec![MapErrors {
                config: config.clone(),
                photons: photons.clone(),
                mse: vec![photons.iter().map(|n| 0.04 + 100.0 / n).collect(); series],
                per_replica,
            }];
            inp.pt_cv2 = vec![1.0; 4];
            let rows = crossover_rows(&inp, &[0.1, 0.25]);
            let map: Vec<&CrossRow> = rows
                .iter()
                .filter(|r| r.config.method.label() == "photon-map")
                .collect();
            assert_eq!(map.len(), 2);
            assert!(
                map[0].photons.is_nan() && map[0].n_star.is_nan(),
                "{:?}",
                map[0]
            );
            assert!(map[0].reason.contains("error floor"), "{}", map[0].reason);
            assert!(
                (map[0].error_floor - 0.2).abs() < 1e-6,
                "{}",
                map[0].error_floor
            );
            // 25 % is within one replica's reach.
            assert!(map[1].photons.is_finite(), "{:?}", map[1]);
        }
    }

    /// One run of the n_P sweep timed exactly as the model, path tracing at 2·10⁻⁶ s per path on
    /// every row.
    fn run_at(n_p: &[f64]) -> RunTimings {
        let inp = inputs();
        let mut samples = Vec::new();
        let mut path = Vec::new();
        for &p in n_p {
            for n in [1e4, 1e5] {
                samples.push((n, p, MODEL.seconds(n, p)));
            }
            path.extend([(p, 2e-6), (p, 2e-6)]);
        }
        RunTimings {
            costs: vec![CostSamples {
                config: inp.costs[0].config.clone(),
                samples,
            }],
            path,
        }
    }

    /// With per-run seconds N* comes from them: between the measured n_P that bracket the
    /// model's closed form (≈ 651), the linear form on it (seconds affine in N and in n_P: the
    /// interpolation is exact), the model's N* beside it, the interval holding all three; a sweep that stops below N* marks the row and the best.csv rows beyond.
    #[test]
    fn n_star_comes_from_the_measured_seconds_and_says_when_it_is_extrapolated() {
        let mut inp = inputs();
        inp.runs = vec![run_at(&[1e2, 3e2, 1e3, 3e3, 1e4])];
        let rows = crossover_rows(&inp, &[0.05]);
        let sc = &rows[0];
        let closed = sc.n_star_model;
        assert!(closed > 600.0 && closed < 700.0, "{sc:?}");
        assert!(sc.n_star > 3e2 && sc.n_star < 1e3, "{sc:?}");
        assert!((sc.n_star_linear / closed - 1.0).abs() < 1e-9, "{sc:?}");
        let all = [sc.n_star, sc.n_star_linear, sc.n_star_model];
        assert!(
            all.iter().all(|&x| sc.n_star_lo <= x && x <= sc.n_star_hi),
            "{sc:?}"
        );
        assert!(
            !sc.extrapolated && !sc.reason.contains("extrapolated"),
            "{sc:?}"
        );
        assert_eq!(sc.measured_points, (1e2, 1e4));
        inp.runs = vec![run_at(&[1e2, 2e2, 3e2])];
        let rows = crossover_rows(&inp, &[0.05]);
        let sc = &rows[0];
        assert!(sc.n_star > 3e2, "{sc:?}");
        assert!(
            sc.extrapolated && sc.reason.contains("extrapolated"),
            "{sc:?}"
        );
        let best = best_rows(&rows, &[0.05], &[], (1e2, 3e2));
        assert!(best[0].points == 1e2 && !best[0].extrapolated);
        assert!(best[1..].iter().all(|b| b.extrapolated), "{best:?}");
    }

    /// A row whose N* comes from the global cost model alone (no per-run seconds; a photon map
    /// with only its replicas' mean MSE) records the n_P its configuration was timed at and is
    /// marked extrapolated when its N* (≈ 651 here) lies outside them.
    #[test]
    fn a_model_only_n_star_outside_the_timed_points_is_marked_extrapolated() {
        let mut inp = inputs();
        let rows = crossover_rows(&inp, &[0.05]);
        let sc = &rows[0];
        assert!(sc.n_star > 600.0 && sc.n_star < 700.0, "{sc:?}");
        assert!(
            !sc.extrapolated && sc.measured_points == (1e2, 1e5),
            "{sc:?}"
        );
        inp.costs[0].samples.retain(|s| s.1 >= 1e4);
        let map = photon_map();
        let photons = vec![1e4, 1e5, 1e6];
        inp.maps = vec![MapErrors {
            config: map.clone(),
            photons: photons.clone(),
            mse: vec![photons.iter().map(|n| 50.0 / n).collect()],
            per_replica: false,
        }];
        inp.costs.push(CostSamples {
            config: map,
            samples: inp.costs[0].samples.clone(),
        });
        let rows = crossover_rows(&inp, &[0.05]);
        let model_only: Vec<&CrossRow> = rows
            .iter()
            .filter(|r| {
                ["sphere-cache", "photon-map"].contains(&r.config.method.label())
                    && r.n_star.is_finite()
            })
            .collect();
        assert_eq!(model_only.len(), 2, "{rows:?}");
        for r in model_only {
            assert!(r.n_star < 1e4, "{r:?}");
            assert_eq!(r.measured_points, (1e4, 1e5));
            assert!(
                r.extrapolated && r.reason.contains("N* extrapolated"),
                "{r:?}"
            );
        }
    }

    #[test]
    fn n_star_is_the_closed_form_and_unmatched_configurations_say_why() {
        let inp = inputs();
        let rows = crossover_rows(&inp, &[0.05, 0.005]);
        // Per target: 2 configurations × 2 engines + path tracing.
        assert_eq!(rows.len(), 10);
        let sc = &rows[0];
        assert_eq!(sc.config.method.label(), "sphere-cache");
        let n_eps = 50.0 / (0.05f64.powi(2) - 1e-4);
        assert!((sc.photons / n_eps - 1.0).abs() < 1e-6, "{}", sc.photons);
        let p = 400.0 * 2e-6; // (1/0.05)² paths per point
        let once = MODEL.fixed + MODEL.per_photon * n_eps;
        let closed = once / (p - MODEL.per_photon_point * n_eps - MODEL.per_point);
        assert!(
            (sc.n_star / closed - 1.0).abs() < 1e-5,
            "{} vs {closed}",
            sc.n_star
        );
        assert!(
            (sc.n_star_lo / closed - 1.0).abs() < 1e-5
                && (sc.n_star_hi / closed - 1.0).abs() < 1e-5
        );
        assert_eq!(sc.never_fraction, 0.0);
        assert!(sc.reason.contains("global cost model"), "{}", sc.reason);
        assert_eq!(sc.n_star_model, sc.n_star);
        assert!((sc.seconds_once - once).abs() < 1e-9);
        // The disc index has no cost sweep here; neither has d = 15.
        assert!(rows[1].reason.contains("no cost sweep") && rows[1].n_star.is_nan());
        assert!(rows[2].reason.contains("no cost sweep"));
        let pt = &rows[4];
        assert_eq!(
            (pt.config.method, pt.photons),
            (Method::path_tracing(), 400.0)
        );
        // Below the floor: never, and why.
        assert!(
            rows[5].photons.is_nan() && rows[5].reason.contains("error floor"),
            "{:?}",
            rows[5]
        );
        // best.csv: path tracing at few points, DETP beyond N*.
        let best = best_rows(&rows, &[0.05], &[], (1e2, 1e5));
        assert_eq!(best.len(), 5);
        let marked: Vec<bool> = best.iter().map(|b| b.extrapolated).collect();
        assert_eq!(
            marked,
            [false, false, false, false, true],
            "10⁶ is beyond the sweep"
        );
        assert!(best[0].best.as_ref().is_some_and(|b| b.0 == "path-tracing"));
        assert!(best[4]
            .best
            .as_ref()
            .is_some_and(|b| b.0.starts_with("sphere-cache")));
        let (b, r) = (
            best[4].best.clone().unwrap(),
            best[4].runner_up.clone().unwrap(),
        );
        assert!(b.1 <= r.1 && (b.1 - MODEL.seconds(n_eps, 1e6)).abs() < 1e-6 * b.1);
    }
}
