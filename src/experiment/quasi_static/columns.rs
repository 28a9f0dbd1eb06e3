//! Every column kind `quasi-static` writes, declared once, and the per-frame metrics as one list
//! ([`PER_FRAME`]: the column and how to read it from a frame's stats), so the accumulators, the
//! row and the summary cannot fall out of step.

use crate::detp::quasi_static::FrameStats;
use crate::experiment::detp::columns as detp;
use crate::output::column::{Class, Column};

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
/// Photons.
pub const PHOTONS: Column = parameter("photons", "photons", "photons traced per frame");
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
);

/// The measured columns whose values follow the engine picked for the dynamic points: with
/// `detp.engine = "predicted"` the §4.1 predictor picks on seconds, so these may differ between
/// runs of one spec and seed and are written as timings (`Row::decided_by_timing`).
pub fn decided_by_the_pick(name: &str) -> bool {
    name == ENGINE_USED.name || name.starts_with("dynamic_")
}
/// Warnings.
pub const WARNINGS: Column = measured(
    "warnings",
    "warnings",
    "counted warnings about the scene (see meta.toml)",
);

/// Segments a frame re-traces or removes.
pub const RETRACED_RAYS: Column = Column::vs_prediction(
    "retraced_rays",
    "segments",
    "segments meeting an object at its old or new pose, per frame; theory f_R = n_R·Σ(r_D/r_0)²",
);
/// Segments meeting the new pose.
pub const RAYS_MEETING_OBJECT: Column = Column::vs_prediction(
    "rays_meeting_object",
    "segments",
    "segments meeting an object at its new pose, per frame; theory f_R",
);
/// Photons re-traced.
pub const PHOTONS_RETRACED: Column =
    Column::estimate("photons_retraced", "photons", "photons re-traced per frame");
/// Segments re-traced.
pub const SEGMENTS_RETRACED: Column = Column::estimate(
    "segments_retraced",
    "segments",
    "segments re-traced per frame",
);
/// Segments changed.
pub const SEGMENTS_CHANGED: Column =
    Column::estimate("segments_changed", "segments", "segments added per frame");
/// Search tests.
pub const SEARCH_TESTS: Column = Column::estimate(
    "search_tests",
    "tests",
    "segment–object tests finding the affected segments, per frame",
);
/// Search cells.
pub const SEARCH_CELLS: Column = Column::estimate(
    "search_cells",
    "cells",
    "segment-index cells visited by the search, per frame",
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
);
/// Dynamic points' sphere tests.
pub const DYNAMIC_SPHERE_TESTS: Column = Column::estimate(
    "dynamic_sphere_tests",
    "tests",
    "ray–sphere tests of the dynamic points' sphere cache, per frame",
);
/// disc-index traversal updating the static points, per frame.
pub const STATIC_TRAVERSAL: Column = Column::estimate(
    "static_traversal",
    "steps",
    "disc-index traversal updating the static points: segment–box slab tests + DDA steps (0 when a sphere cache does them), per frame",
);
/// segments copied into sphere-cache lists updating the static points (0 with the disc index), per frame.
pub const STATIC_RAYS_COPIED: Column = Column::estimate(
    "static_rays_copied",
    "segments",
    "segments copied into sphere-cache lists updating the static points (0 with the disc index), per frame",
);
/// the static points' counted cost, per frame.
pub const STATIC_COUNTED_COST: Column = Column::estimate(
    "static_counted_cost",
    "tests",
    "the static points' counted cost: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each, per frame",
);
/// disc-index traversal of the dynamic points, per frame.
pub const DYNAMIC_TRAVERSAL: Column = Column::estimate(
    "dynamic_traversal",
    "steps",
    "disc-index traversal of the dynamic points: segment–box slab tests + DDA steps (0 with the sphere cache), per frame",
);
/// segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index), per frame.
pub const DYNAMIC_RAYS_COPIED: Column = Column::estimate(
    "dynamic_rays_copied",
    "segments",
    "segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index), per frame",
);
/// spheres the dynamic points' sphere cache built, root included (0 with the disc index), per frame.
pub const DYNAMIC_SPHERES_BUILT: Column = Column::estimate(
    "dynamic_spheres_built",
    "spheres",
    "spheres the dynamic points' sphere cache built, root included (0 with the disc index), per frame",
);
/// segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost, per frame.
pub const DYNAMIC_FEED: Column = Column::estimate(
    "dynamic_feed",
    "steps",
    "segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost, per frame",
);
/// the dynamic points' counted cost with the engine used, per frame.
pub const DYNAMIC_COUNTED_COST: Column = Column::estimate(
    "dynamic_counted_cost",
    "tests",
    "the dynamic points' counted cost with the engine used: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each (copies and the feed apart), per frame",
);
/// Search seconds.
pub const SEARCH_S: Column = Column::timed_estimate(
    "search_s",
    "s",
    "seconds finding the affected segments, per frame",
);
/// Re-trace seconds.
pub const RETRACE_S: Column =
    Column::timed_estimate("retrace_s", "s", "seconds re-tracing photons, per frame");
/// Static update seconds.
pub const STATIC_S: Column = Column::timed_estimate(
    "static_s",
    "s",
    "seconds updating the static points, per frame",
);
/// Dynamic seconds.
pub const DYNAMIC_S: Column = Column::timed_estimate(
    "dynamic_s",
    "s",
    "seconds gathering the dynamic points, per frame",
);
/// Frame seconds.
pub const FRAME_S: Column =
    Column::timed_estimate("frame_s", "s", "seconds of an incremental frame");

/// How a per-frame metric reads one frame's stats.
pub type FrameValue = fn(&FrameStats) -> f64;

/// The per-frame metrics, estimated over frames 1…F−1 (batches of consecutive frames as clusters),
/// in column order: the column and its value in one frame's stats.
pub const PER_FRAME: &[(Column, FrameValue)] = &[
    (RETRACED_RAYS, |s| s.affected_segments as f64),
    (RAYS_MEETING_OBJECT, |s| s.meeting_new as f64),
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
    (FRAME_S, |s| s.frame_s),
];

/// Full recalculation seconds.
pub const FULL_FRAME_S: Column = Column::timed_estimate(
    "full_frame_s",
    "s",
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
/// Error against a reference.
pub const IRRADIANCE_RMSE: Column = measured(
    "irradiance_rmse",
    "1",
    "relative RMSE of the last frame against a run of dynamic.reference_photons photons (includes the reference's own noise)",
);
/// Reference photons.
pub const REFERENCE_PHOTONS: Column = parameter(
    "reference_photons",
    "photons",
    "photons of the reference run",
);
/// Reference seconds.
pub const REFERENCE_S: Column = timing("reference_s", "s", "seconds of the reference run");
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
);
/// Crossover of Theorem 2.
pub const CROSSOVER_THEORY: Column = theory(
    "crossover_theory",
    "1",
    "Theorem 2's crossover r_D/r_0 for this n_D (≈ 0.35 as n_D → ∞)",
);

/// The main table, in column order.
pub const MAIN: &[Column] = &[
    FRAMES,
    PHOTONS,
    SEGMENTS,
    POINTS_STATIC,
    POINTS_DYNAMIC,
    OBJECTS,
    R0,
    RATIO,
    CROSSOVER,
    ENGINE_USED,
    WARNINGS,
    RETRACED_RAYS,
    RAYS_MEETING_OBJECT,
    PHOTONS_RETRACED,
    SEGMENTS_RETRACED,
    SEGMENTS_CHANGED,
    SEARCH_TESTS,
    SEARCH_CELLS,
    STATIC_TESTS,
    DYNAMIC_TESTS,
    DYNAMIC_SPHERE_TESTS,
    STATIC_TRAVERSAL,
    STATIC_RAYS_COPIED,
    STATIC_COUNTED_COST,
    DYNAMIC_TRAVERSAL,
    DYNAMIC_RAYS_COPIED,
    DYNAMIC_SPHERES_BUILT,
    DYNAMIC_FEED,
    DYNAMIC_COUNTED_COST,
    SEARCH_S,
    RETRACE_S,
    STATIC_S,
    DYNAMIC_S,
    FRAME_S,
    FULL_FRAME_S,
    FRAME0_S,
    STATIC_INDEX_BUILD_S,
    SPEEDUP,
    FULL_MISMATCH,
    FULL_CHECKED,
    PREDICT_FRACTION,
    PREDICTED_S,
    MEASURED_S,
    PREDICTION_ERROR,
    TIMED_PICK,
    TIMED_BEST_ENGINE,
    TIMED_PICK_RIGHT,
    TIMED_RULE_PICK_RIGHT,
    IRRADIANCE_RMSE,
    REFERENCE_PHOTONS,
    REFERENCE_S,
    STATIC_TESTS_THEORY,
    DYNAMIC_TESTS_THEORY,
    CROSSOVER_THEORY,
];

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
    "segment-index listings the search read",
);
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
);
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
        "segment-index cells the search visited",
    );
    /// Search tests.
    pub const SEARCH_TESTS: Column = measured(
        "search_tests",
        "tests",
        "segment–object tests of the search",
    );
    /// Dynamic sphere tests.
    pub const DYNAMIC_SPHERE_TESTS: Column = measured(
        "dynamic_sphere_tests",
        "tests",
        "ray–sphere tests of the dynamic points",
    );
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
    );
    /// segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index).
    pub const DYNAMIC_RAYS_COPIED: Column = measured(
        "dynamic_rays_copied",
        "segments",
        "segments copied into the dynamic points' sphere-cache lists, root list included (0 with the disc index)",
    );
    /// spheres the dynamic points' sphere cache built, root included (0 with the disc index).
    pub const DYNAMIC_SPHERES_BUILT: Column = measured(
        "dynamic_spheres_built",
        "spheres",
        "spheres the dynamic points' sphere cache built, root included (0 with the disc index)",
    );
    /// segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost.
    pub const DYNAMIC_FEED: Column = measured(
        "dynamic_feed",
        "steps",
        "segment-index cells read + segments tested to feed the dynamic points' engine (dynamic.feed; 0 when it gets every segment); not in dynamic_counted_cost",
    );
    /// the dynamic points' counted cost with the engine used.
    pub const DYNAMIC_COUNTED_COST: Column = measured(
        "dynamic_counted_cost",
        "tests",
        "the dynamic points' counted cost with the engine used: ray–disc + ray–sphere tests + box tests + DDA steps, weight 1 each (copies and the feed apart)",
    );
    /// Search seconds.
    pub const SEARCH_S: Column = timing("search_s", "s", "seconds finding the affected segments");
    /// Re-trace seconds.
    pub const RETRACE_S: Column = timing("retrace_s", "s", "seconds re-tracing photons");
    /// Static seconds.
    pub const STATIC_S: Column = timing("static_s", "s", "seconds updating the static points");
    /// Dynamic seconds.
    pub const DYNAMIC_S: Column = timing("dynamic_s", "s", "seconds gathering the dynamic points");
    /// Frame seconds.
    pub const FRAME_S: Column = timing("frame_s", "s", "seconds of the frame");
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
}

/// `NAME.frames.csv`.
pub const FRAMES_TABLE: &[Column] = &[
    REPLICA,
    FRAME,
    frame::RETRACED_RAYS,
    frame::RAYS_MEETING_OBJECT,
    frame::PHOTONS_RETRACED,
    SEGMENTS_REMOVED,
    SEGMENTS_ADDED,
    frame::SEGMENTS_RETRACED,
    frame::SEARCH_CELLS,
    SEARCH_LISTINGS,
    frame::SEARCH_TESTS,
    STATIC_DISC_TESTS,
    STATIC_SPHERE_TESTS,
    DYNAMIC_DISC_TESTS,
    frame::DYNAMIC_SPHERE_TESTS,
    frame::STATIC_TRAVERSAL,
    frame::STATIC_RAYS_COPIED,
    frame::STATIC_COUNTED_COST,
    frame::DYNAMIC_TRAVERSAL,
    frame::DYNAMIC_RAYS_COPIED,
    frame::DYNAMIC_SPHERES_BUILT,
    frame::DYNAMIC_FEED,
    frame::DYNAMIC_COUNTED_COST,
    ENGINE_USED,
    frame::SEARCH_S,
    frame::RETRACE_S,
    frame::STATIC_S,
    frame::DYNAMIC_S,
    frame::FRAME_S,
    frame::FULL_FRAME_S,
    frame::FULL_MISMATCH,
];

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

/// `NAME.points.csv`.
pub const POINTS_TABLE: &[Column] = &[
    detp::SAMPLE,
    FRAME,
    DYNAMIC,
    detp::X,
    detp::Y,
    detp::Z,
    detp::NX,
    detp::NY,
    detp::NZ,
    POINT_IRRADIANCE,
    POINT_IRRADIANCE_SE,
];
