//! Every column kind `quasi-static` writes, declared once, the per-frame metrics as one list
//! ([`PER_FRAME_VALUES`]: the column and how to read it from a frame's stats, so the accumulators
//! and the row cannot fall out of step), and the tables that read the columns from a point's
//! measurement ([`MAIN`], [`FRAMES_TABLE`], [`POINTS_TABLE`]).
//!
//! The columns whose values follow the engine picked for the dynamic points (`engine_used` and the
//! `dynamic_*` counts and seconds) are declared [`Column::decided_by_timing`]: with `detp.engine =
//! "predicted"` the §4.1 predictor picks on seconds, so those may differ between runs of one spec
//! and seed and are written as timings.

use super::measure::{FrameRow, QsMeasured, QsPointRow};
use super::spec::QuasiStaticConfig;
use super::theorem2::{self, Assumption};
use crate::detp::quasi_static::FrameStats;
use crate::experiment::detp::columns as detp;
use crate::experiment::detp::estimators::path_tracing;
use crate::output::column::{Class, Column, Shape};
use crate::output::row::Value;
use crate::output::table::{col, Against, Cell, Cells, Entry, Line, Table};
use crate::stats::{Estimate, Theory};
use crate::theory::detp as th;

const fn measured(name: &'static str, unit: &'static str, doc: &'static str) -> Column {
    Column::value(name, unit, Class::Measured, doc)
}
const fn parameter(name: &'static str, unit: &'static str, doc: &'static str) -> Column {
    Column::value(name, unit, Class::Parameter, doc)
}
const fn timing(name: &'static str, unit: &'static str, doc: &'static str) -> Column {
    Column::value(name, unit, Class::Timing, doc)
}
const fn theory(name: &'static str, unit: &'static str, doc: &'static str) -> Column {
    Column::value(name, unit, Class::Theory, doc)
}

/// Frames.
pub const FRAMES: Column = parameter("frames", "frames", "frames run (frame 0 is a full trace)");
/// Segments.
pub const SEGMENTS: Column = measured(
    "segments",
    "segments",
    "segments stored after frame 0 (n_R) of replica 0",
);
/// Static points.
pub const POINTS_STATIC: Column = measured(
    "points_static",
    "points",
    "sample points on static surfaces (n_S)",
);
/// Dynamic points.
pub const POINTS_DYNAMIC: Column = measured(
    "points_dynamic",
    "points",
    "sample points on the dynamic objects (n_D)",
);
/// Objects.
pub const OBJECTS: Column = measured("objects", "objects", "dynamic objects");
/// Root radius.
pub const R0: Column = measured(
    "r0",
    "length",
    "radius r_0 of the root sphere around the scene",
);
/// Largest ratio.
pub const RATIO: Column = measured("ratio", "1", "the largest object's r_D/r_0");
/// Crossover used.
pub const CROSSOVER: Column = parameter(
    "crossover",
    "1",
    "r_D/r_0 above which an object's points use the disc index (dynamic.crossover, or Theorem 2's for this n_D)",
);
/// Engines used at frame 0.
pub const ENGINE_USED: Column = measured(
    "engine_used",
    "",
    "the engine each object's points used at frame 0, joined by + (with engine \"predicted\" the pick is taken on seconds: this and the dynamic_* counts are then classed timing)",
)
.decided_by_timing();

/// Warnings.
pub const WARNINGS: Column = measured(
    "warnings",
    "warnings",
    "counted warnings about the scene (see meta.toml)",
);

/// Segments a frame re-traces or removes.
pub const RETRACED_RAYS: Column = frame::RETRACED_RAYS.mean_over(
    "segments meeting an object at its old or new pose, per frame; theory f_R = n_R·Σ(r_D/r_0)²",
)
    .against_prediction();
/// Segments meeting the new pose.
pub const RAYS_MEETING_OBJECT: Column = frame::RAYS_MEETING_OBJECT.mean_over(
    "segments meeting an object at its new pose, per frame; theory f_R",
)
    .against_prediction();
/// Segments meeting the pose after the re-trace: eq. 11's one-pose count.
pub const RAYS_AT_POSE: Column = frame::RAYS_AT_POSE.mean_over(
    "segments meeting an object at its new pose after the frame's re-trace (eq. 11's one-pose count: unlike rays_meeting_object, a segment the old pose cut short is counted as re-traced, and the radius is not padded), per frame; theory f_R",
)
    .against_prediction();
/// The union's expectation for μ-random lines.
pub const RETRACED_RAYS_UNION_THEORY: Column = Column::estimate(
    "retraced_rays_union_theory",
    "segments",
    "segments expected to meet an object at its old or new pose were they μ-random lines: n_R·Σ(2ρ² − (1/π)∫₀¹ L(δ√(1−c²)) dc), ρ = r_D/r_0, δ the pose's shift/r_0, L the lens of two discs of radius ρ (docs/theory.md), per frame; retraced_rays's own expectation",
);
/// A1 of Theorem 2's proof.
pub const RAYS_AT_POSE_PER_F_R: Column = Column::estimate(
    "rays_at_pose_per_f_r",
    "1",
    "Theorem 2's proof, A1: rays_at_pose ÷ f_R = n_R·Σ(r_D/r_0)² with the frame's n_R (the proof: 1), per frame",
);
/// A2 of Theorem 2's proof.
pub const DYNAMIC_CACHE_WORK_PER_RAY: Column = Column::estimate(
    "dynamic_cache_work_per_ray",
    "1",
    "Theorem 2's proof, A2: the dynamic points' sphere-cache ray–disc + ray–sphere tests ÷ (rays_at_pose·∛n_D) (the proof: 8.08; NaN with the disc index), per frame",
)
.decided_by_timing();
/// Rays reaching the dynamic points' disc index.
pub const DYNAMIC_RAYS_REACHING: Column = frame::DYNAMIC_RAYS_REACHING.mean_over(
    "segments that reach the dynamic points' disc index: enter one of its cells or nodes, or start beyond its reach and test every disc (0 with the sphere cache), per frame",
);
/// A3 of Theorem 2's proof.
pub const DYNAMIC_REACH_SHARE: Column = Column::estimate(
    "dynamic_reach_share",
    "1",
    "Theorem 2's proof, A3: dynamic_rays_reaching ÷ the frame's live segments n_R (the proof charges every ray: 1; NaN with the sphere cache), per frame",
)
.decided_by_timing();
/// A4 of Theorem 2's proof.
pub const DYNAMIC_INDEX_TESTS_PER_RAY: Column = Column::estimate(
    "dynamic_index_tests_per_ray",
    "1",
    "Theorem 2's proof, A4: the dynamic points' disc-index ray–disc tests ÷ (dynamic_rays_reaching·∛n_D) (the proof: 1; NaN with the sphere cache), per frame",
)
.decided_by_timing();
/// Photons re-traced.
pub const PHOTONS_RETRACED: Column = frame::PHOTONS_RETRACED.mean_over(
    "photons re-traced per frame",
);
/// Segments re-traced.
pub const SEGMENTS_RETRACED: Column = frame::SEGMENTS_RETRACED.mean_over(
    "segments re-traced per frame",
);
/// Segments changed.
pub const SEGMENTS_CHANGED: Column =
    Column::estimate("segments_changed", "segments", "segments added per frame");
/// Search tests.
pub const SEARCH_TESTS: Column = frame::SEARCH_TESTS.mean_over(
    "segment–object tests finding the affected segments, per frame (with --photon-shard: summed over the shards' own indexes, and classed timing)",
);
/// Search cells.
pub const SEARCH_CELLS: Column = frame::SEARCH_CELLS.mean_over(
    "segment-index cells visited by the search, per frame (with --photon-shard: summed over the shards' own indexes, and classed timing)",
);
/// Static points' tests.
pub const STATIC_TESTS: Column = Column::estimate(
    "static_tests",
    "tests",
    "ray–disc and ray–sphere tests updating the static points, per frame",
);
/// Dynamic points' tests.
pub const DYNAMIC_TESTS: Column = Column::estimate(
    "dynamic_tests",
    "tests",
    "ray–disc tests of the dynamic points, per frame",
)
.decided_by_timing();
/// Dynamic points' sphere tests.
pub const DYNAMIC_SPHERE_TESTS: Column = frame::DYNAMIC_SPHERE_TESTS.mean_over(
    "ray–sphere tests of the dynamic points' sphere cache, per frame",
);
/// disc-index traversal updating the static points, per frame.
pub const STATIC_TRAVERSAL: Column = frame::STATIC_TRAVERSAL.mean_over(
    "disc-index traversal updating the static points: segment–box slab tests + DDA steps (0 when a sphere cache does them), per frame",
);
/// segments copied into sphere-cache lists updating the static points (0 with the disc index), per frame.
pub const STATIC_RAYS_COPIED: Column = frame::STATIC_RAYS_COPIED.mean_over(
    "segments copied into sphere-cache lists updating the static points (0 with the disc index), per frame",
);
/// the static points' counted cost, per frame.
pub const STATIC_COUNTED_COST: Column = frame::STATIC_COUNTED_COST.mean_over(
    "the static points' counted cost: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each, per frame",
);
/// disc-index traversal of the dynamic points, per frame.
pub const DYNAMIC_TRAVERSAL: Column = frame::DYNAMIC_TRAVERSAL.mean_over(
    "disc-index traversal of the dynamic points: segment–box slab tests + DDA steps (0 with the sphere cache), per frame",
);
/// segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index), per frame.
pub const DYNAMIC_RAYS_COPIED: Column = frame::DYNAMIC_RAYS_COPIED.mean_over(
    "segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index), per frame",
);
/// spheres the dynamic points' sphere cache built, root included (0 with the disc index), per frame.
pub const DYNAMIC_SPHERES_BUILT: Column = frame::DYNAMIC_SPHERES_BUILT.mean_over(
    "spheres the dynamic points' sphere cache built, root included (0 with the disc index), per frame",
);
/// segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost, per frame.
pub const DYNAMIC_FEED: Column = frame::DYNAMIC_FEED.mean_over(
    "segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost, per frame (with --photon-shard: summed over the shards' own indexes, and classed timing)",
);
/// the dynamic points' counted cost with the engine used, per frame.
pub const DYNAMIC_COUNTED_COST: Column = frame::DYNAMIC_COUNTED_COST.mean_over(
    "the dynamic points' counted cost with the engine used: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each (copies and the feed apart), per frame",
);
/// Search seconds.
pub const SEARCH_S: Column = frame::SEARCH_S.mean_over(
    "seconds finding the affected segments, per frame",
);
/// Re-trace seconds.
pub const RETRACE_S: Column = frame::RETRACE_S.mean_over(
    "seconds re-tracing photons, per frame",
);
/// Static update seconds.
pub const STATIC_S: Column = frame::STATIC_S.mean_over(
    "seconds updating the static points, per frame",
);
/// Dynamic seconds.
pub const DYNAMIC_S: Column = frame::DYNAMIC_S.mean_over(
    "seconds gathering the dynamic points, per frame",
);
/// The dynamic points' disc-index traversal alone, seconds.
pub const DYNAMIC_TRAVERSAL_S: Column = frame::DYNAMIC_TRAVERSAL_S.mean_over(
    "seconds of the disc index's traversal alone for the dynamic points: each object's index walked again for the same segments as its pass (cells or nodes, box tests, DDA steps, candidate lists) but testing no disc, timed apart after the pass (in neither dynamic_s nor frame_s); over dynamic_s it is eq. 8's traversal share in seconds. Objects on the sphere cache add nothing (0 with the sphere cache, as dynamic_traversal). Per frame",
);
/// Frame seconds.
pub const FRAME_S: Column = frame::FRAME_S.mean_over(
    "seconds of an incremental frame",
);

/// How a per-frame metric reads one frame's stats.
pub type FrameValue = fn(&FrameStats) -> f64;

/// The per-frame metrics, estimated over frames 1…F−1 (batches of consecutive frames as clusters),
/// in column order: the column and its value in one frame's stats.
pub const PER_FRAME_VALUES: &[(Column, FrameValue)] = &[
    (RETRACED_RAYS, |s| s.affected_segments as f64),
    (RAYS_MEETING_OBJECT, |s| s.meeting_new as f64),
    (RAYS_AT_POSE, |s| s.meeting_pose as f64),
    (RETRACED_RAYS_UNION_THEORY, FrameStats::union_theory),
    (RAYS_AT_POSE_PER_F_R, theorem2::rays_per_pose_share),
    (DYNAMIC_CACHE_WORK_PER_RAY, theorem2::cache_work_per_ray),
    (DYNAMIC_RAYS_REACHING, |s| s.dynamic_rays_reaching as f64),
    (DYNAMIC_REACH_SHARE, theorem2::reach_share),
    (DYNAMIC_INDEX_TESTS_PER_RAY, theorem2::index_tests_per_ray),
    (PHOTONS_RETRACED, |s| s.photons_retraced as f64),
    (SEGMENTS_RETRACED, |s| s.segments_retraced as f64),
    (SEGMENTS_CHANGED, |s| s.segments_added as f64),
    (SEARCH_TESTS, |s| s.search.tested as f64),
    (SEARCH_CELLS, |s| s.search.cells as f64),
    (STATIC_TESTS, |s| {
        (s.static_disc_tests + s.static_sphere_tests) as f64
    }),
    (DYNAMIC_TESTS, |s| s.dynamic_disc_tests as f64),
    (DYNAMIC_SPHERE_TESTS, |s| s.dynamic_sphere_tests as f64),
    (STATIC_TRAVERSAL, |s| s.static_traversal as f64),
    (STATIC_RAYS_COPIED, |s| s.static_rays_copied as f64),
    (STATIC_COUNTED_COST, |s| s.static_counted_cost() as f64),
    (DYNAMIC_TRAVERSAL, |s| s.dynamic_traversal as f64),
    (DYNAMIC_RAYS_COPIED, |s| s.dynamic_rays_copied as f64),
    (DYNAMIC_SPHERES_BUILT, |s| s.dynamic_spheres_built as f64),
    (DYNAMIC_FEED, |s| s.dynamic_feed as f64),
    (DYNAMIC_COUNTED_COST, |s| s.dynamic_counted_cost() as f64),
    (SEARCH_S, |s| s.search_s),
    (RETRACE_S, |s| s.retrace_s),
    (STATIC_S, |s| s.static_s),
    (DYNAMIC_S, |s| s.dynamic_s),
    (DYNAMIC_TRAVERSAL_S, |s| s.dynamic_traversal_s),
    (FRAME_S, |s| s.frame_s),
];

/// Full recalculation seconds.
pub const FULL_FRAME_S: Column = frame::FULL_FRAME_S.mean_over(
    "seconds of a full recalculation of a checked frame",
);
/// Frame 0.
pub const FRAME0_S: Column = timing(
    "frame0_s",
    "s",
    "seconds of frame 0 (the full trace and gather), mean over replicas",
);
/// Static index build.
pub const STATIC_INDEX_BUILD_S: Column = timing(
    "static_index_build_s",
    "s",
    "seconds building the static points' index",
);
/// Speed-up.
pub const SPEEDUP: Column = timing("speedup", "1", "full_frame_s / frame_s");
/// Incremental vs full.
pub const FULL_MISMATCH: Column = Column::value(
    "full_mismatch",
    "points",
    Class::Check,
    "points whose integer sum differs between the incremental frame and a full recalculation, over the checked frames (0 when correct; the run fails otherwise)",
);
/// Frames checked.
pub const FULL_CHECKED: Column = Column::value(
    "full_checked",
    "frames",
    Class::Check,
    "frames checked against a full recalculation",
);
/// Predictor's sample.
pub const PREDICT_FRACTION: Column = parameter(
    "predict_fraction",
    "1",
    "fraction of the photons the predictor times each engine on",
);
/// Predicted seconds.
pub const PREDICTED_S: Column = timing(
    "predicted_{}_s",
    "s",
    "the first object's predicted seconds per frame for the engine",
);
/// The paper predictor's level split.
pub const PAPER_SPLIT_LEVEL: Column = Column::value(
    "paper_split_level",
    "level",
    Class::Measured,
    "dynamic.predictor = \"paper\": the first object's level split s (its sphere cache's levels 0 … s simulated on the fraction, the deeper ones from theory); NaN for the subsample predictor",
);
/// The paper predictor's predicted tests.
pub const PAPER_PREDICTED_TESTS: Column = Column::value(
    "paper_predicted_sphere_cache_tests",
    "tests",
    Class::Measured,
    "dynamic.predictor = \"paper\": the first object's predicted sphere-cache tests (ray–sphere + ray–disc) on all photons, the seconds' scale; NaN for the subsample predictor",
);
/// Measured seconds.
pub const MEASURED_S: Column = timing(
    "measured_{}_s",
    "s",
    "its measured seconds per frame for the engine",
);
/// Prediction error.
pub const PREDICTION_ERROR: Column =
    timing("timed_prediction_error_{}", "1", "predicted / measured − 1");
/// The predictor's pick.
pub const TIMED_PICK: Column = timing(
    "timed_pick",
    "",
    "the engine the predictor picked for the first object",
);
/// The faster engine.
pub const TIMED_BEST_ENGINE: Column = timing(
    "timed_best_engine",
    "",
    "the engine that measured faster for it",
);
/// Right picks.
pub const TIMED_PICK_RIGHT: Column = timing(
    "timed_pick_right",
    "objects",
    "objects whose predicted pick was the faster engine",
);
/// Right rule picks.
pub const TIMED_RULE_PICK_RIGHT: Column = timing(
    "timed_rule_pick_right",
    "objects",
    "objects whose Theorem 2 rule pick was the faster engine",
);
/// The predictor's pick in each replica.
pub const PICK_REPLICA: Column = timing(
    "pick_replica_{}",
    "",
    "the engine the predictor picked for the first object in replica {} (\"sphere-cache\" or \"disc-index\")",
);
/// Warm seconds of each engine.
pub const WARM_S: Column = Column::timed_estimate(
    "warm_{}_s",
    "s",
    "the engine's seconds on every segment for the first object's points, timed warm dynamic.warm_repeats times per replica, the engines interleaved (one cluster per replica)",
);
/// Error against a reference, relative (detp's `irradiance_rmse` is in W/m²).
pub const IRRADIANCE_REL_RMSE: Column = measured(
    "irradiance_rel_rmse",
    "1",
    "relative RMSE of the last frame against a run of dynamic.reference_photons photons (includes the reference's own noise)",
);
/// Reference seconds.
pub const REFERENCE_S: Column = timing("reference_s", "s", "seconds of the reference run");
/// Path tracing's points.
pub const PATH_TRACING_POINTS: Column = measured(
    "path_tracing_points",
    "points",
    "\"path-tracing\" in detp.engines: the points path-traced at frame 0 and at each checked frame (detp.path_points of the frame's points, a keyed subset, or all)",
);
/// Path tracing's seconds per path.
pub const PATH_TRACING_S_PER_PATH: Column = frame::PATH_TRACING_S_PER_PATH.mean_over(
    "path tracing in the scene posed at frame 0 and each checked frame: wall seconds per path (detp.path_samples paths at each of path_tracing_points points), over those frames of every replica (one cluster per replica); in no other timing",
);
/// Path tracing's cv.
pub const PATH_TRACING_CV: Column = frame::PATH_TRACING_CV.mean_over(
    "path tracing at frame 0 and each checked frame: √(mean_i σ_i²)/mean_i Ê_i over its points (σ_i² the per-path variance, Ê_i the mean of the detp.path_samples paths), the relative RMSE of one path per point; over those frames of every replica (one cluster per replica)",
);
/// Path tracing's continuation rays.
pub const PATH_TRACING_RAYS_PATH: Column = measured(
    "path_tracing_rays_path",
    "rays",
    "path tracing: continuation rays per path, mean over frame 0 and the checked frames of every replica",
);
/// Path tracing's shadow rays.
pub const PATH_TRACING_RAYS_SHADOW: Column = measured(
    "path_tracing_rays_shadow",
    "rays",
    "path tracing: shadow rays per path, mean over frame 0 and the checked frames of every replica",
);
/// Theorem 2, static points.
pub const STATIC_TESTS_THEORY: Column = theory(
    "static_tests_theory_{}",
    "tests",
    "Theorem 2: the static points' update cost per frame with the engine",
);
/// Theorem 2, dynamic points.
pub const DYNAMIC_TESTS_THEORY: Column = theory(
    "dynamic_tests_theory_{}",
    "tests",
    "Theorem 2: the dynamic points' gather cost per frame with the engine",
)
.decided_by_timing();
/// Crossover of Theorem 2.
pub const CROSSOVER_THEORY: Column = theory(
    "crossover_theory",
    "1",
    "Theorem 2's crossover r_D/r_0 for this n_D (≈ 0.35 as n_D → ∞)",
);

/// The per-frame estimates, in [`PER_FRAME_VALUES`] order; both retrace counts (the columns held
/// against a prediction) are held against f_R.
fn per_frame_cells(_: &QuasiStaticConfig, m: &QsMeasured) -> Vec<(&'static str, Cells)> {
    let f_r = m.f_r();
    let cells = PER_FRAME_VALUES
        .iter()
        .zip(&m.per_frame)
        .map(|((c, _), &e)| {
            let cell = if c.shape == Shape::EstimateVsPrediction {
                Cell::Judged(e, Theory::Prediction(f_r))
            } else {
                Cell::Estimate(e)
            };
            (c, cell)
        })
        .collect();
    vec![("", cells)]
}

/// The predictor's per-engine seconds, `sphere_cache` and `disc_index`.
fn per_engine(m: &QsMeasured, f: fn(&super::measure::Predictor, usize) -> f64) -> Cell {
    match &m.predictor {
        Some(p) => Cell::members(
            ["sphere_cache", "disc_index"]
                .iter()
                .enumerate()
                .map(|(i, e)| (e.to_string(), f(p, i))),
        ),
        None => Cell::Absent,
    }
}

/// Theorem 2's costs for this run's n (in ray tests, t = u): `sphere_cache` and `disc_index`.
fn engines(costs: (f64, f64)) -> Cell {
    Cell::members([
        ("sphere_cache".to_string(), costs.0),
        ("disc_index".to_string(), costs.1),
    ])
}

/// The main table, in column order.
pub const MAIN: Table<QuasiStaticConfig, QsMeasured> = Table {
    entries: &[
        col(&FRAMES, |p, _| u64::from(p.frames).into()),
        col(&SEGMENTS, |_, m| m.segments.into()),
        col(&POINTS_STATIC, |_, m| m.points_static.into()),
        col(&POINTS_DYNAMIC, |_, m| m.points_dynamic.into()),
        col(&OBJECTS, |_, m| m.ratios.len().into()),
        col(&R0, |_, m| m.r0.into()),
        col(&RATIO, |_, m| {
            m.ratios.iter().copied().fold(0.0, f64::max).into()
        }),
        col(&CROSSOVER, |_, m| m.crossover.into()),
        col(&ENGINE_USED, |_, m| m.engine_used.as_str().into()),
        col(&WARNINGS, |p, _| p.warnings.len().into()),
        Entry::Parts(per_frame_cells, || {
            PER_FRAME_VALUES.iter().map(|(c, _)| c).collect()
        }),
        col(&FULL_FRAME_S, |_, m| m.full_frame_s.into()),
        col(&FRAME0_S, |_, m| m.frame0_s.into()),
        col(&STATIC_INDEX_BUILD_S, |_, m| m.static_index_build_s.into()),
        col(&SPEEDUP, |_, m| m.speedup().into()),
        col(&FULL_MISMATCH, |_, m| m.full_mismatch.into()),
        col(&FULL_CHECKED, |_, m| m.full_checked.into()),
        col(&PREDICT_FRACTION, |_, m| {
            m.predictor.map(|p| p.fraction).into()
        }),
        col(&PREDICTED_S, |_, m| {
            per_engine(m, |p, i| p.first.predicted[i])
        }),
        // Written wherever a predictor ran (NaN for the subsample's), so a sweep over
        // dynamic.predictor keeps one header.
        col(&PAPER_SPLIT_LEVEL, |_, m| {
            m.predictor
                .map(|p| p.first.paper.map_or(Cell::from(f64::NAN), |(s, _)| Cell::from(s)))
                .into()
        }),
        col(&PAPER_PREDICTED_TESTS, |_, m| {
            m.predictor
                .map(|p| p.first.paper.map_or(f64::NAN, |(_, t)| t))
                .into()
        }),
        col(&MEASURED_S, |_, m| {
            per_engine(m, |p, i| p.first.measured[i])
        }),
        col(&PREDICTION_ERROR, |_, m| {
            per_engine(m, |p, i| p.first.predicted[i] / p.first.measured[i] - 1.0)
        }),
        col(&TIMED_PICK, |_, m| {
            m.predictor.map(|p| p.first.pick.as_str()).into()
        }),
        col(&TIMED_BEST_ENGINE, |_, m| {
            m.predictor.map(|p| p.first.best.as_str()).into()
        }),
        col(&TIMED_PICK_RIGHT, |_, m| {
            m.predictor.map(|p| p.pick_right).into()
        }),
        col(&TIMED_RULE_PICK_RIGHT, |_, m| {
            m.predictor.map(|p| p.rule_pick_right).into()
        }),
        col(&PICK_REPLICA, |_, m| {
            Cell::members(
                m.picks
                    .iter()
                    .enumerate()
                    .map(|(k, u)| (k.to_string(), u.as_str())),
            )
        }),
        col(&WARM_S, |_, m| match m.warm {
            Some([sc, di]) => Cell::members([
                ("sphere_cache".to_string(), sc),
                ("disc_index".to_string(), di),
            ]),
            None => Cell::Absent,
        }),
        col(&IRRADIANCE_REL_RMSE, |_, m| m.reference.map(|r| r.0).into()),
        col(&REFERENCE_S, |_, m| m.reference.map(|r| r.1).into()),
        col(&PATH_TRACING_POINTS, |_, m| {
            m.path_tracing.map(|t| t.points).into()
        }),
        col(&PATH_TRACING_S_PER_PATH, |_, m| {
            m.path_tracing.map(|t| t.s_per_path).into()
        }),
        col(&PATH_TRACING_CV, |_, m| m.path_tracing.map(|t| t.cv).into()),
        col(&PATH_TRACING_RAYS_PATH, |_, m| {
            m.path_tracing.map(|t| t.rays_path).into()
        }),
        col(&PATH_TRACING_RAYS_SHADOW, |_, m| {
            m.path_tracing.map(|t| t.rays_shadow).into()
        }),
        col(&STATIC_TESTS_THEORY, |p, m| {
            engines(th::static_points_cost(
                m.f_r(),
                m.points_static as f64,
                p.detp.q(),
            ))
        }),
        col(&DYNAMIC_TESTS_THEORY, |p, m| {
            let ratio = m.ratios.first().copied().unwrap_or(0.0);
            engines(th::dynamic_points_cost(
                m.n_r,
                ratio,
                m.points_dynamic as f64,
                p.detp.q(),
            ))
        }),
        col(&CROSSOVER_THEORY, |p, m| {
            th::crossover_ratio(p.detp.q(), m.points_dynamic.max(1) as f64).into()
        }),
    ],
    lines: speedup_line,
};

/// The speed-up of an incremental frame over a full recalculation, shown, not judged.
fn speedup_line(_: &QuasiStaticConfig, m: &QsMeasured) -> Vec<Line> {
    vec![Line {
        metric: "speedup".into(),
        estimate: Estimate {
            mean: m.speedup(),
            se: f64::NAN,
            n: m.full_checked,
            clusters: 1,
        },
        against: Against::Speedup("full_frame_s / frame_s"),
    }]
}

/// Frame number.
pub const FRAME: Column = measured("frame", "1", "the frame");
/// The replica a frame belongs to.
pub const REPLICA: Column = measured(
    "replica",
    "1",
    "the replica (an independent run of every frame with new photons), from 0",
);
/// Segments removed in a frame.
pub const SEGMENTS_REMOVED: Column = measured("segments_removed", "segments", "segments removed");
/// Segments added.
pub const SEGMENTS_ADDED: Column = measured("segments_added", "segments", "segments added");
/// Search listings.
pub const SEARCH_LISTINGS: Column = measured(
    "search_listings",
    "listings",
    "segment-index listings the search read (with --photon-shard: summed over the shards' own indexes, and classed timing)",
).accelerator_work();
/// Static disc tests.
pub const STATIC_DISC_TESTS: Column = measured(
    "static_disc_tests",
    "tests",
    "ray–disc tests updating the static points",
);
/// Static sphere tests.
pub const STATIC_SPHERE_TESTS: Column = measured(
    "static_sphere_tests",
    "tests",
    "ray–sphere tests updating the static points",
);
/// Dynamic disc tests.
pub const DYNAMIC_DISC_TESTS: Column = measured(
    "dynamic_disc_tests",
    "tests",
    "ray–disc tests of the dynamic points",
)
.decided_by_timing();
/// One frame's counts and seconds (per-frame values, no estimate).
pub mod frame {
    use super::*;
    /// Retraced rays.
    pub const RETRACED_RAYS: Column = measured(
        "retraced_rays",
        "segments",
        "segments meeting an object at its old or new pose",
    );
    /// Meeting the new pose.
    pub const RAYS_MEETING_OBJECT: Column = measured(
        "rays_meeting_object",
        "segments",
        "segments meeting an object at its new pose",
    );
    /// Meeting the pose after the re-trace.
    pub const RAYS_AT_POSE: Column = measured(
        "rays_at_pose",
        "segments",
        "segments meeting an object at its new pose after the frame's re-trace (eq. 11's one-pose count; 0 at frame 0)",
    );
    /// The frame's n_R.
    pub const SEGMENTS_LIVE: Column = measured(
        "segments_live",
        "segments",
        "segments alive after the frame: n_R, the rays of the scene Theorem 2's proof charges",
    );
    /// Rays reaching the dynamic points' disc index.
    pub const DYNAMIC_RAYS_REACHING: Column = measured(
        "dynamic_rays_reaching",
        "segments",
        "segments that reach the dynamic points' disc index (0 with the sphere cache)",
    )
    .decided_by_timing();
    /// Theorem 2's proof's accounting.
    pub const DYNAMIC_PROOF_COST: Column = measured(
        "dynamic_proof_cost",
        "tests",
        "Theorem 2's proof's charge for the dynamic points: the sphere cache its ray–disc + ray–sphere tests, the disc index ∛n_D for every live segment (n_R·∛n_D)",
    )
    .decided_by_timing();
    /// The counted cost with one assumption of the proof in place of its measured factor.
    pub const DYNAMIC_COST_ASSUMING: Column = measured(
        "dynamic_cost_assuming_{}",
        "tests",
        "the dynamic points' ray–disc + ray–sphere tests with one of Theorem 2's proof's assumptions in place of the measured factor, the others measured (src/experiment/quasi_static/theorem2.rs): rays_per_pose (A1 = 1, the cache's work scaled to f_R rays), cache_constant (A2: 8.08·∛n_D per ray at the pose), every_ray (A3 = 1, the index's tests scaled to every live segment), cbrt_tests (A4 = 1: ∛n_D tests per reaching ray); the other engine's cost as counted",
    )
    .decided_by_timing();
    /// Photons re-traced.
    pub const PHOTONS_RETRACED: Column =
        measured("photons_retraced", "photons", "photons re-traced");
    /// Segments re-traced.
    pub const SEGMENTS_RETRACED: Column =
        measured("segments_retraced", "segments", "segments re-traced");
    /// Search cells.
    pub const SEARCH_CELLS: Column = measured(
        "search_cells",
        "cells",
        "segment-index cells the search visited (with --photon-shard: summed over the shards' own indexes, and classed timing)",
    ).accelerator_work();
    /// Search tests.
    pub const SEARCH_TESTS: Column = measured(
        "search_tests",
        "tests",
        "segment–object tests of the search (with --photon-shard: summed over the shards' own indexes, and classed timing)",
    ).accelerator_work();
    /// Dynamic sphere tests.
    pub const DYNAMIC_SPHERE_TESTS: Column = measured(
        "dynamic_sphere_tests",
        "tests",
        "ray–sphere tests of the dynamic points",
    )
    .decided_by_timing();
    /// disc-index traversal updating the static points.
    pub const STATIC_TRAVERSAL: Column = measured(
        "static_traversal",
        "steps",
        "disc-index traversal updating the static points: segment–box slab tests + DDA steps (0 when a sphere cache does them)",
    );
    /// segments copied into sphere-cache lists updating the static points (0 with the disc index).
    pub const STATIC_RAYS_COPIED: Column = measured(
        "static_rays_copied",
        "segments",
        "segments copied into sphere-cache lists updating the static points (0 with the disc index)",
    );
    /// the static points' counted cost.
    pub const STATIC_COUNTED_COST: Column = measured(
        "static_counted_cost",
        "tests",
        "the static points' counted cost: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each",
    );
    /// disc-index traversal of the dynamic points.
    pub const DYNAMIC_TRAVERSAL: Column = measured(
        "dynamic_traversal",
        "steps",
        "disc-index traversal of the dynamic points: segment–box slab tests + DDA steps (0 with the sphere cache)",
    )
.decided_by_timing();
    /// segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index).
    pub const DYNAMIC_RAYS_COPIED: Column = measured(
        "dynamic_rays_copied",
        "segments",
        "segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index)",
    )
.decided_by_timing();
    /// spheres the dynamic points' sphere cache built, root included (0 with the disc index).
    pub const DYNAMIC_SPHERES_BUILT: Column = measured(
        "dynamic_spheres_built",
        "spheres",
        "spheres the dynamic points' sphere cache built, root included (0 with the disc index)",
    )
    .decided_by_timing();
    /// segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost.
    pub const DYNAMIC_FEED: Column = measured(
        "dynamic_feed",
        "steps",
        "segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost (with --photon-shard: summed over the shards' own indexes, and classed timing)",
    )
    .decided_by_timing()
    .accelerator_work();
    /// the dynamic points' counted cost with the engine used.
    pub const DYNAMIC_COUNTED_COST: Column = measured(
        "dynamic_counted_cost",
        "tests",
        "the dynamic points' counted cost with the engine used: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each (copies and the feed apart)",
    )
.decided_by_timing();
    /// Search seconds.
    pub const SEARCH_S: Column = timing("search_s", "s", "seconds finding the affected segments");
    /// Re-trace seconds.
    pub const RETRACE_S: Column = timing("retrace_s", "s", "seconds re-tracing photons");
    /// Static seconds.
    pub const STATIC_S: Column = timing("static_s", "s", "seconds updating the static points");
    /// Dynamic seconds.
    pub const DYNAMIC_S: Column =
        timing("dynamic_s", "s", "seconds gathering the dynamic points").decided_by_timing();
    /// The dynamic points' disc-index traversal alone.
    pub const DYNAMIC_TRAVERSAL_S: Column = timing(
        "dynamic_traversal_s",
        "s",
        "seconds of the disc index's traversal alone for the dynamic points (walked again without disc tests after the pass; in neither dynamic_s nor frame_s); 0 with the sphere cache",
    )
    .decided_by_timing();
    /// Frame seconds.
    pub const FRAME_S: Column = timing("frame_s", "s", "seconds of the frame");
    /// The static index's build in one replica.
    pub const STATIC_INDEX_BUILD_S: Column = timing(
        "static_index_build_s",
        "s",
        "seconds this replica spent building the static points' index (frame 0's row; NaN on the others)",
    );
    /// Full recalculation seconds.
    pub const FULL_FRAME_S: Column = timing(
        "full_frame_s",
        "s",
        "seconds of the full recalculation (NaN if not checked)",
    );
    /// Mismatch.
    pub const FULL_MISMATCH: Column = Column::value(
        "full_mismatch",
        "points",
        Class::Check,
        "points differing from the full recalculation (empty if not checked)",
    );
    /// Path tracing's seconds per path at this frame.
    pub const PATH_TRACING_S_PER_PATH: Column = path_tracing::PATH_TRACING_S_PER_PATH.described(
        "\"path-tracing\" in detp.engines: wall seconds per path in the scene posed at this frame (frame 0 and the checked frames; NaN on the others)",
    );
    /// Path tracing's cv at this frame.
    pub const PATH_TRACING_CV: Column = path_tracing::PATH_TRACING_CV.described(
        "path tracing at this frame: √(mean_i σ_i²)/mean_i Ê_i over its points (frame 0 and the checked frames; NaN on the others)",
    );
}

/// `NAME.frames.csv`: one row per frame of every replica.
pub const FRAMES_TABLE: Table<QuasiStaticConfig, FrameRow> = Table::of(&[
    col(&REPLICA, |_, r| r.replica.into()),
    col(&FRAME, |_, r| r.stats.frame.into()),
    col(&frame::RETRACED_RAYS, |_, r| {
        r.stats.affected_segments.into()
    }),
    col(&frame::RAYS_MEETING_OBJECT, |_, r| {
        r.stats.meeting_new.into()
    }),
    col(&frame::RAYS_AT_POSE, |_, r| r.stats.meeting_pose.into()),
    col(&frame::PHOTONS_RETRACED, |_, r| {
        r.stats.photons_retraced.into()
    }),
    col(&SEGMENTS_REMOVED, |_, r| r.stats.segments_removed.into()),
    col(&SEGMENTS_ADDED, |_, r| r.stats.segments_added.into()),
    col(&frame::SEGMENTS_RETRACED, |_, r| {
        r.stats.segments_retraced.into()
    }),
    col(&frame::SEARCH_CELLS, |_, r| r.stats.search.cells.into()),
    col(&SEARCH_LISTINGS, |_, r| r.stats.search.listings.into()),
    col(&frame::SEARCH_TESTS, |_, r| r.stats.search.tested.into()),
    col(&STATIC_DISC_TESTS, |_, r| r.stats.static_disc_tests.into()),
    col(&STATIC_SPHERE_TESTS, |_, r| {
        r.stats.static_sphere_tests.into()
    }),
    col(&DYNAMIC_DISC_TESTS, |_, r| {
        r.stats.dynamic_disc_tests.into()
    }),
    col(&frame::DYNAMIC_SPHERE_TESTS, |_, r| {
        r.stats.dynamic_sphere_tests.into()
    }),
    col(&frame::STATIC_TRAVERSAL, |_, r| {
        r.stats.static_traversal.into()
    }),
    col(&frame::STATIC_RAYS_COPIED, |_, r| {
        r.stats.static_rays_copied.into()
    }),
    col(&frame::STATIC_COUNTED_COST, |_, r| {
        r.stats.static_counted_cost().into()
    }),
    col(&frame::DYNAMIC_TRAVERSAL, |_, r| {
        r.stats.dynamic_traversal.into()
    }),
    col(&frame::DYNAMIC_RAYS_COPIED, |_, r| {
        r.stats.dynamic_rays_copied.into()
    }),
    col(&frame::DYNAMIC_SPHERES_BUILT, |_, r| {
        r.stats.dynamic_spheres_built.into()
    }),
    col(&frame::DYNAMIC_FEED, |_, r| r.stats.dynamic_feed.into()),
    col(&frame::DYNAMIC_COUNTED_COST, |_, r| {
        r.stats.dynamic_counted_cost().into()
    }),
    col(&frame::SEGMENTS_LIVE, |_, r| r.stats.segments_live.into()),
    col(&frame::DYNAMIC_RAYS_REACHING, |_, r| {
        r.stats.dynamic_rays_reaching.into()
    }),
    col(&frame::DYNAMIC_PROOF_COST, |_, r| {
        theorem2::proof_cost(&r.stats).into()
    }),
    col(&frame::DYNAMIC_COST_ASSUMING, |_, r| {
        Cell::members(
            Assumption::ALL
                .iter()
                .map(|&a| (a.name().to_string(), theorem2::cost_assuming(&r.stats, a))),
        )
    }),
    col(&ENGINE_USED, |_, r| {
        let used: Vec<&str> = r.stats.used.iter().map(|u| u.as_str()).collect();
        used.join("+").into()
    }),
    col(&frame::SEARCH_S, |_, r| r.stats.search_s.into()),
    col(&frame::RETRACE_S, |_, r| r.stats.retrace_s.into()),
    col(&frame::STATIC_S, |_, r| r.stats.static_s.into()),
    col(&frame::DYNAMIC_S, |_, r| r.stats.dynamic_s.into()),
    col(&frame::DYNAMIC_TRAVERSAL_S, |_, r| {
        r.stats.dynamic_traversal_s.into()
    }),
    col(&frame::FRAME_S, |_, r| r.stats.frame_s.into()),
    col(&frame::STATIC_INDEX_BUILD_S, |_, r| {
        r.static_index_build_s.unwrap_or(f64::NAN).into()
    }),
    col(&frame::FULL_FRAME_S, |_, r| {
        r.full.map_or(f64::NAN, |f| f.0).into()
    }),
    col(&frame::FULL_MISMATCH, |_, r| {
        r.full.map_or(Value::missing(), |f| Value::U(f.1)).into()
    }),
    // Written only where path tracing runs (the header is unchanged without it), NaN on the
    // frames it skips.
    col(&frame::PATH_TRACING_S_PER_PATH, |p, r| {
        p.path_tracing()
            .then(|| r.path_tracing.map_or(f64::NAN, |t| t.s_per_path))
            .into()
    }),
    col(&frame::PATH_TRACING_CV, |p, r| {
        p.path_tracing()
            .then(|| r.path_tracing.map_or(f64::NAN, |t| t.cv))
            .into()
    }),
]);

/// Whether a point is on a dynamic object.
pub const DYNAMIC: Column = measured("dynamic", "1", "1 if the point is on a dynamic object");
/// Points table irradiance.
pub const POINT_IRRADIANCE: Column = measured(
    "irradiance_mean",
    "W/m²",
    "DETP's irradiance at the point at that frame",
);
/// Its SE.
pub const POINT_IRRADIANCE_SE: Column = measured(
    "irradiance_se",
    "W/m²",
    "its Poisson standard error √(E·w̄/πd²)",
);

/// `NAME.points.csv`: the irradiance at one frame.
pub const POINTS_TABLE: Table<QuasiStaticConfig, QsPointRow> = Table::of(&[
    col(&detp::SAMPLE, |_, r| r.sample.into()),
    col(&FRAME, |_, r| r.frame.into()),
    col(&DYNAMIC, |_, r| r.dynamic.into()),
    col(&detp::X, |_, r| r.center.x.into()),
    col(&detp::Y, |_, r| r.center.y.into()),
    col(&detp::Z, |_, r| r.center.z.into()),
    col(&detp::NX, |_, r| r.normal.x.into()),
    col(&detp::NY, |_, r| r.normal.y.into()),
    col(&detp::NZ, |_, r| r.normal.z.into()),
    col(&POINT_IRRADIANCE, |_, r| r.irradiance.into()),
    col(&POINT_IRRADIANCE_SE, |_, r| r.se.into()),
]);
