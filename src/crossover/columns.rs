//! Every column `raycost crossover` writes, declared once ([`crate::output::column`]), and the rows
//! of its three tables built from them. Seconds and what is derived from them (N*, F*, the best
//! method) are timings; the error fits are measured.

use super::analysis::{BestRow, CrossRow};
use super::frames::FramesRow;
use crate::output::column::{Class, Column};
use crate::output::row::Row;

const fn value(name: &'static str, unit: &'static str, class: Class, doc: &'static str) -> Column {
    Column::value(name, unit, class, doc)
}

/// A column whose +∞ is meaningful (an unbounded interval).
const fn unbounded(name: &'static str, unit: &'static str, doc: &'static str) -> Column {
    Column {
        infinite_ok: true,
        ..Column::value(name, unit, Class::Timing, doc)
    }
}

/// Scene.
pub const SCENE: Column = value(
    "scene",
    "",
    Class::Parameter,
    "the scene (the fronts' detp.scene file stem, else the run's name)",
);
/// Target.
pub const TARGET: Column = value(
    "target",
    "1",
    Class::Parameter,
    "the target relative RMSE ε (RMSE over the points / mean irradiance)",
);
/// Method.
pub const METHOD: Column = value(
    "method",
    "",
    Class::Parameter,
    "the method, by its name in detp.engines: each estimator of kind detp that declares how the crossover compares it (the DETP engines, the photon maps, path tracing)",
);
/// detp.direct.
pub const DIRECT: Column = value(
    "direct",
    "",
    Class::Parameter,
    "detp.direct of the configuration (NaN for path tracing)",
);
/// detp.edge.
pub const EDGE: Column = value(
    "edge",
    "",
    Class::Parameter,
    "detp.edge (NaN where the method does not depend on it: photon maps, path tracing)",
);
/// detp.disc_radius.
pub const DISC_RADIUS: Column = value(
    "disc_radius",
    "length",
    Class::Parameter,
    "detp.disc_radius d (NaN where the method does not depend on it)",
);
/// κ.
pub const EDGE_RADIUS_FACTOR: Column = value(
    "edge_radius_factor",
    "1",
    Class::Parameter,
    "radius rule: κ of an edge-clamping remedy, d_i = clamp(κ·s_i, r_min·d, d) (detp.edge_radius_factor), where it is not the default 1 (NaN: κ = 1, no clamping remedy, or a method without discs)",
);
/// N_ref.
pub const RADIUS_SCHEDULE_PHOTONS: Column = value(
    "radius_schedule_photons",
    "photons",
    Class::Parameter,
    "radius rule: N_ref of the schedule d(N) = d·(N/N_ref)^(−β) (detp.radius_schedule_photons; NaN: d fixed, or β = 0)",
);
/// β.
pub const RADIUS_SCHEDULE_EXPONENT: Column = value(
    "radius_schedule_exponent",
    "1",
    Class::Parameter,
    "radius rule: β of the schedule d(N) = d·(N/N_ref)^(−β) (NaN: d fixed)",
);
/// N_ε or paths.
pub const PHOTONS: Column = value("photons", "photons", Class::Measured, "N_ε = c/(ε² − B): photons of one estimate (one replica, DETP and the photon maps alike) that reach the target (under a radius schedule N_ε = (a/ε²)^(1/(2γ)) from a·N^(−2γ)); path tracing: paths per point ⌈(cv/ε)²⌉; NaN if unreachable");
/// The fronts' largest photon count.
pub const PHOTONS_MEASURED_MAX: Column = value("photons_measured_max", "photons", Class::Measured, "the largest photon count of one estimate the fronts measured for this configuration (NaN for path tracing): where photons exceeds it, N_ε (and the N* resting on it) is the error fit's extrapolation past the measured errors, by the factor photons / photons_measured_max");
/// √B.
pub const ERROR_FLOOR: Column = value(
    "error_floor",
    "1",
    Class::Measured,
    "√B of the fit relative MSE = B + c/N (error floor: bias, or noise more photons do not reduce, e.g. NEE direct at fixed detp.direct_samples); 0 for path tracing; NaN under a radius schedule (no floor in its model: see error_curvature)",
);
/// c.
pub const ERROR_FIT_C: Column = value(
    "error_fit_c",
    "photons",
    Class::Measured,
    "c of relative MSE = B + c/N (path tracing: cv², its relative MSE × paths; NaN under a radius schedule: see error_fit_a)",
);
/// a.
pub const ERROR_FIT_A: Column = value(
    "error_fit_a",
    "photons^(2γ)",
    Class::Measured,
    "a of relative MSE = a·N^(−2γ), the error model of a radius schedule (least squares of ln MSE on ln N; no floor); NaN for other rules",
);
/// γ fitted.
pub const ERROR_SLOPE: Column = value(
    "error_slope",
    "1",
    Class::Measured,
    "γ of relative RMSE ∝ N^(−γ) fitted under a radius schedule (NaN for other rules)",
);
/// Its bounds.
pub const ERROR_SLOPE_LO: Column = value(
    "error_slope_lo",
    "1",
    Class::Measured,
    "2.5 % percentile of γ over 2000 bootstrap resamples of the fronts' replicas",
);
/// Upper.
pub const ERROR_SLOPE_HI: Column = value(
    "error_slope_hi",
    "1",
    Class::Measured,
    "97.5 % percentile of γ",
);
/// γ derived.
pub const ERROR_SLOPE_THEORY: Column = value(
    "error_slope_theory",
    "1",
    Class::Theory,
    "γ the theory derives for the schedule: min(2β, (1 − 2β)/2), 1/3 at β = 1/6 (docs/theory.md; NaN for other rules)",
);
/// Curvature.
pub const ERROR_CURVATURE: Column = value(
    "error_curvature",
    "1",
    Class::Measured,
    "under a radius schedule, the x² coefficient of ln MSE fitted as a quadratic in x = ln N: 0 for a power law, > 0 where a floor appears (its interval above 0: never, see reason); NaN for other rules or < 3 photon counts",
);
/// Its bounds.
pub const ERROR_CURVATURE_LO: Column = value(
    "error_curvature_lo",
    "1",
    Class::Measured,
    "2.5 % percentile of the curvature over the same resamples",
);
/// Upper.
pub const ERROR_CURVATURE_HI: Column = value(
    "error_curvature_hi",
    "1",
    Class::Measured,
    "97.5 % percentile of the curvature",
);
/// Seconds once.
pub const SECONDS_ONCE: Column = value("seconds_once", "s", Class::Timing, "the cost model's seconds at N_ε and no point: fixed + a·N_ε (trace, build); 0 for path tracing");
/// Seconds per point.
pub const SECONDS_PER_POINT: Column = value("seconds_per_point", "s", Class::Timing, "seconds per added point at N_ε, averaged over the first 10⁴ points: (T(N_ε, 10⁴) − T(N_ε, 0))/10⁴; path tracing: paths × seconds per path");
/// γ.
pub const COST_GAMMA: Column = value(
    "cost_gamma",
    "1",
    Class::Timing,
    "γ of seconds = fixed + a·N + b·N·n_P^γ + c·n_P, best on a 0.05 grid over the n_P sweep",
);
/// The fitted cost model's coefficients, so that a plot or a spreadsheet can draw T(N_ε, n_P).
pub const COST_FIXED: Column = value(
    "cost_fixed",
    "s",
    Class::Timing,
    "fixed of the cost model seconds = fixed + a·N + b·N·n_P^γ + c·n_P (one estimate: per replica)",
);
/// a.
pub const COST_PER_PHOTON: Column = value(
    "cost_per_photon",
    "s",
    Class::Timing,
    "a: seconds per photon",
);
/// b.
pub const COST_PER_PHOTON_POINT: Column = value(
    "cost_per_photon_point",
    "s",
    Class::Timing,
    "b: seconds per photon × n_P^γ",
);
/// c.
pub const COST_PER_POINT: Column =
    value("cost_per_point", "s", Class::Timing, "c: seconds per point");
/// Worst misfit.
pub const COST_WORST_MISFIT: Column = value(
    "cost_worst_misfit",
    "1",
    Class::Timing,
    "largest |model/measured − 1| of the cost model over the n_P sweep's samples",
);
/// N*.
pub const N_STAR: Column = value("n_star", "points", Class::Timing, "N*: beyond this many points the configuration reaches the target faster than path tracing, from the n_P sweep's measured seconds at N_ε (linear in photons between the two measured counts, then log–log between the neighbouring measured n_P where the curves cross); without per-run seconds, the global model's (see reason). NaN: never");
/// Lower bound.
pub const N_STAR_LO: Column = unbounded("n_star_lo", "points", "lower bound of N*: the least of the 2.5 % percentiles of the log–log and linear forms over 2000 bootstrap resamples (the fronts' replicas, the sweep's runs when ≥ 2, path tracing's per-row timings) and the global model's N* (form error) (+inf: never in that many; NaN: no bootstrap)");
/// Upper bound.
pub const N_STAR_HI: Column = unbounded(
    "n_star_hi",
    "points",
    "upper bound of N*: the largest of the forms' 97.5 % percentiles and the model's N* (+inf: the data cannot exclude that it never wins)",
);
/// Linear form.
pub const N_STAR_LINEAR: Column = unbounded(
    "n_star_linear",
    "points",
    "N* from the measured seconds interpolated linearly in n_P (T_DETP − T_PT linear between neighbouring n_P); NaN: not measured; +inf: never",
);
/// The model's N*.
pub const N_STAR_MODEL: Column = value("n_star_model", "points", Class::Timing, "N* of the global cost model seconds = fixed + a·N + b·N·n_P^γ + c·n_P fitted over every run of the sweep, with path tracing's median seconds per path (NaN: never or no model)");
/// Its bounds.
pub const N_STAR_MODEL_LO: Column = unbounded("n_star_model_lo", "points", "2.5 % percentile of the model's N* over 2000 resamples of the fronts' replicas and the model's residuals");
/// Upper.
pub const N_STAR_MODEL_HI: Column = unbounded(
    "n_star_model_hi",
    "points",
    "97.5 % percentile of the model's N*",
);
/// Extrapolated.
pub const EXTRAPOLATED: Column = value("extrapolated", "", Class::Timing, "true where the value lies outside the n_P the sweep measured (crossover.csv: N*; best.csv: n_P), so it rests on a trend beyond the data, not on measured seconds");
/// Head to head.
pub const N_STAR_HEAD_TO_HEAD: Column = unbounded("n_star_head_to_head", "points", "N* measured head to head (with a confirmation run: DETP at N_ε and path tracing at its paths per point on the same points at a few n_P, log–log between them; their seconds are in reason); NaN without one, +inf: never there");
/// Measured n_P.
pub const SWEEP_POINTS_MIN: Column = value(
    "sweep_points_min",
    "points",
    Class::Parameter,
    "the smallest n_P the sweep timed this configuration at (NaN: none)",
);
/// Measured n_P.
pub const SWEEP_POINTS_MAX: Column = value(
    "sweep_points_max",
    "points",
    Class::Parameter,
    "the largest n_P the sweep timed this configuration at (NaN: none)",
);
/// Never fraction.
pub const NEVER_FRACTION: Column = value(
    "never_fraction",
    "1",
    Class::Timing,
    "fraction of bootstrap resamples in which it never beats path tracing (NaN: no bootstrap)",
);
/// Reason.
pub const REASON: Column = value("reason", "", Class::Timing, "why a value is NaN or never (error floor, a schedule's error curve that flattens, per-point cost, no cost sweep at this d/edge/direct and radius rule), or a note on how it was computed; NaN when there is nothing to say");

/// n_P.
pub const POINTS: Column = value(
    "points",
    "points",
    Class::Parameter,
    "n_P: points to compute",
);
/// Best.
pub const BEST: Column = value("best", "", Class::Timing, "the fastest configuration reaching the target at n_P (its seconds from the fitted model; extrapolated = true where n_P lies outside the sweep's measured n_P)");
/// Its seconds.
pub const BEST_S: Column = value("best_s", "s", Class::Timing, "its seconds");
/// Runner-up.
pub const RUNNER_UP: Column = value(
    "runner_up",
    "",
    Class::Timing,
    "the second fastest configuration",
);
/// Its seconds.
pub const RUNNER_UP_S: Column = value("runner_up_s", "s", Class::Timing, "its seconds");

/// The frames table's sweep point.
pub const FRAMES_POINT: Column = value(
    "frames_point",
    "1",
    Class::Parameter,
    "the frames table's sweep point (its `point`)",
);
/// The fronts' d used.
pub const FRONTS_DISC_RADIUS: Column = value("fronts_disc_radius", "length", Class::Parameter, "the fronts' d whose error fit (direct photons, edge paper) gave N_ε: the frames' d, or the nearest");
/// First frame.
pub const FIRST_S: Column = value(
    "first_s",
    "s",
    Class::Timing,
    "DETP's frame 0 at N_ε (frame0_s scaled to N_ε)",
);
/// Incremental frame.
pub const FRAME_S: Column = value(
    "frame_s",
    "s",
    Class::Timing,
    "DETP's incremental frame at N_ε (frame_s_mean scaled)",
);
/// Full frame.
pub const FULL_S: Column = value(
    "full_s",
    "s",
    Class::Timing,
    "DETP's full recalculation at N_ε (full_frame_s_mean scaled)",
);
/// Paths.
pub const PT_PATHS: Column = value(
    "path_tracing_paths",
    "paths",
    Class::Measured,
    "path tracing's paths per point ⌈(cv/ε)²⌉ with the frames run's cv",
);
/// Path tracing per frame.
pub const PT_FRAME_S: Column = value(
    "path_tracing_frame_s",
    "s",
    Class::Timing,
    "path tracing's seconds per frame: n_P × paths × seconds per path",
);
/// F*.
pub const FRAMES_STAR: Column = value("frames_star", "frames", Class::Timing, "F*: from this many frames on, DETP (first frame, then incremental) costs less in all than path tracing (NaN: never)");
/// F* full.
pub const FRAMES_STAR_FULL: Column = value("frames_star_full", "frames", Class::Timing, "F* of DETP recalculating every frame in full: 1 if a full frame is cheaper than path tracing's, else NaN (never)");

fn text(x: &Option<String>) -> String {
    x.clone().unwrap_or_default()
}

/// A row of `crossover.csv`.
pub fn crossover_row(r: &CrossRow) -> Row {
    let mut row = Row::default();
    let (gamma, misfit) = r
        .cost
        .map_or((f64::NAN, f64::NAN), |c| (c.model.gamma, c.worst_misfit));
    let coef =
        |f: fn(&crate::stats::fit::CostModel) -> f64| r.cost.map_or(f64::NAN, |c| f(&c.model));
    let rule = r.config.radius_rule.unwrap_or_default();
    let schedule =
        |f: fn(&super::method::Schedule) -> f64| rule.schedule.as_ref().map_or(f64::NAN, f);
    let power = |f: fn(&crate::stats::time_to_target::PowerLawCheck) -> f64| {
        r.power_law.as_ref().map_or(f64::NAN, f)
    };
    row.put(&SCENE, r.scene.as_str())
        .put(&TARGET, r.target)
        .put(&METHOD, r.config.method.label())
        .put(&DIRECT, text(&r.config.direct))
        .put(&EDGE, text(&r.config.edge))
        .put(&DISC_RADIUS, r.config.disc_radius.unwrap_or(f64::NAN))
        .put(&EDGE_RADIUS_FACTOR, rule.edge_factor.unwrap_or(f64::NAN))
        .put(&RADIUS_SCHEDULE_PHOTONS, schedule(|s| s.photons))
        .put(&RADIUS_SCHEDULE_EXPONENT, schedule(|s| s.exponent))
        .put(&PHOTONS, r.photons)
        .put(&PHOTONS_MEASURED_MAX, r.photons_measured_max)
        .put(&ERROR_FLOOR, r.error_floor)
        .put(&ERROR_FIT_C, r.error_fit_c)
        .put(&ERROR_FIT_A, r.error_fit_a)
        .put(&ERROR_SLOPE, power(|p| p.slope.estimate))
        .put(&ERROR_SLOPE_LO, power(|p| p.slope.lo))
        .put(&ERROR_SLOPE_HI, power(|p| p.slope.hi))
        .put(&ERROR_SLOPE_THEORY, rule.derived_error_slope())
        .put(&ERROR_CURVATURE, power(|p| p.curvature.estimate))
        .put(&ERROR_CURVATURE_LO, power(|p| p.curvature.lo))
        .put(&ERROR_CURVATURE_HI, power(|p| p.curvature.hi))
        .put(&SECONDS_ONCE, r.seconds_once)
        .put(&SECONDS_PER_POINT, r.seconds_per_point)
        .put(&COST_GAMMA, gamma)
        .put(&COST_FIXED, coef(|m| m.fixed))
        .put(&COST_PER_PHOTON, coef(|m| m.per_photon))
        .put(&COST_PER_PHOTON_POINT, coef(|m| m.per_photon_point))
        .put(&COST_PER_POINT, coef(|m| m.per_point))
        .put(&COST_WORST_MISFIT, misfit)
        .put(&N_STAR, r.n_star)
        .put(&N_STAR_LO, r.n_star_lo)
        .put(&N_STAR_HI, r.n_star_hi)
        .put(&NEVER_FRACTION, r.never_fraction)
        .put(&N_STAR_LINEAR, r.n_star_linear)
        .put(&N_STAR_MODEL, r.n_star_model)
        .put(&N_STAR_MODEL_LO, r.n_star_model_lo)
        .put(&N_STAR_MODEL_HI, r.n_star_model_hi)
        .put(&EXTRAPOLATED, flag(r.extrapolated))
        .put(&SWEEP_POINTS_MIN, r.measured_points.0)
        .put(&SWEEP_POINTS_MAX, r.measured_points.1)
        .put(&N_STAR_HEAD_TO_HEAD, r.n_star_head_to_head)
        .put(&REASON, r.reason.as_str());
    row
}

/// A row of `best.csv`.
pub fn best_row(r: &BestRow) -> Row {
    let split = |x: &Option<(String, f64)>| {
        x.clone()
            .map_or((String::new(), f64::NAN), |(label, s)| (label, s))
    };
    let (best, best_s) = split(&r.best);
    let (runner, runner_s) = split(&r.runner_up);
    let mut row = Row::default();
    row.put(&SCENE, r.scene.as_str())
        .put(&TARGET, r.target)
        .put(&POINTS, r.points)
        .put(&BEST, best)
        .put(&BEST_S, best_s)
        .put(&RUNNER_UP, runner)
        .put(&RUNNER_UP_S, runner_s)
        .put(&EXTRAPOLATED, flag(r.extrapolated));
    row
}

fn flag(x: bool) -> &'static str {
    if x {
        "true"
    } else {
        "false"
    }
}

/// A row of `frames.csv`.
pub fn frames_row(r: &FramesRow) -> Row {
    let mut row = Row::default();
    row.put(&SCENE, r.scene.as_str())
        .put(&TARGET, r.target)
        .put(&FRAMES_POINT, r.frames_point)
        .put(&POINTS, r.points)
        .put(&DISC_RADIUS, r.disc_radius)
        .put(&FRONTS_DISC_RADIUS, r.fronts_disc_radius)
        .put(&PHOTONS, r.photons)
        .put(&FIRST_S, r.first_s)
        .put(&FRAME_S, r.frame_s)
        .put(&FULL_S, r.full_s)
        .put(&PT_PATHS, r.path_tracing_paths)
        .put(&PT_FRAME_S, r.path_tracing_frame_s)
        .put(&FRAMES_STAR, r.frames_star)
        .put(&FRAMES_STAR_FULL, r.frames_star_full)
        .put(&REASON, r.reason.as_str());
    row
}
