//! Every column kind `detp` writes, declared once, and the tables that read them from a point's
//! typed measurement: [`MAIN`] (the point's own columns around one group per engine, in the
//! point's engine order, each engine's group from its estimator's own table,
//! `estimators/NAME.rs`), [`LEVELS`], [`POINTS_TABLE`] and [`PATH_TRACING_TABLE`]. The engine
//! families (`tests_{}`, `cost_{}_s`, …) are declared here, once, for every estimator.
//! Engine columns are families, one member per engine (`tests_{}` → `tests_sphere_cache`).

use super::config::DetpConfig;
use super::estimators::path_tracing::PathRow;
use super::estimators::sphere_cache::LevelRow;
use super::estimators::ESTIMATORS;
use super::measure::{DetpMeasured, PointRow};
use crate::output::column::{Class, Column};
use crate::output::table::{cells, col, Against, Cell, Cells, Entry, Line, Table};
use crate::stats::{Estimate, Theory};
use crate::theory::detp as th;

/// Segments in the store.
pub const SEGMENTS: Column = Column::value(
    "segments",
    "segments",
    Class::Measured,
    "photon segments (or lines) traced, summed over replicas",
);
/// Segments the engines read with `direct = "nee"`.
pub const SEGMENTS_INDIRECT: Column = Column::value(
    "segments_indirect",
    "segments",
    Class::Measured,
    "the segments the engines read, summed over replicas: with detp.direct = \"nee\" those after the first bounce (indirect light), else every segment traced",
);
/// Seconds of the NEE direct part.
pub const DIRECT_S: Column = Column::value(
    "direct_s",
    "s",
    Class::Timing,
    "detp.direct = \"nee\": seconds of next-event estimation of the direct light at every point, summed over replicas (a per-point cost of every engine in that mode; computed once per point set and replica in a run); 0 otherwise",
);
/// Its shadow rays.
pub const DIRECT_RAYS_SHADOW: Column = Column::value(
    "direct_rays_shadow",
    "rays",
    Class::Measured,
    "detp.direct = \"nee\": shadow rays of the direct part, summed over replicas; 0 otherwise",
);
/// Sample points.
pub const POINTS: Column =
    Column::value("points", "points", Class::Measured, "sample points (discs)");
/// Tracing time.
pub const TRACE_S: Column = Column::value(
    "trace_s",
    "s",
    Class::Timing,
    "seconds to generate the lines or trace the photons, summed over replicas",
);
/// Seconds the edge remedy took.
pub const EDGE_S: Column = Column::value(
    "edge_s",
    "s",
    Class::Timing,
    "seconds spent on detp.edge's remedy, summed over replicas: the per-disc radii (clamp-radius, once per point) or cutting every segment at its first impact (first-hit); 0 for the paper's method",
);
/// Mean disc radius over d.
pub const EDGE_RADIUS: Column = Column::value(
    "edge_radius",
    "1",
    Class::Measured,
    "mean disc radius over d across the points (1 unless detp.edge = \"clamp-radius\" shrinks discs near other surfaces)",
);
/// An engine's counted tests.
pub const TESTS: Column = Column::value(
    "tests_{}",
    "tests",
    Class::Measured,
    "the engine's counted ray tests, summed over replicas (sphere cache: ray–sphere + ray–disc; disc index and brute force: ray–disc)",
);
/// The same per replica, with its spread across replicas.
pub const TESTS_PER_REPLICA: Column = Column::estimate(
    "tests_{}_per_replica",
    "tests",
    "the engine's counted ray tests in one replica: mean, standard error across replicas, replicas",
);
/// Seconds per replica, with their spread.
pub const COST_PER_REPLICA_S: Column = Column::timed_estimate(
    "cost_{}_per_replica_s",
    "s",
    "seconds the engine took in one replica: mean, standard error across replicas, replicas",
);
/// The disc index's walk alone, per replica.
pub const TRAVERSAL_PER_REPLICA_S: Column = Column::timed_estimate(
    "traversal_{}_per_replica_s",
    "s",
    "disc index: seconds of a second pass in one replica that walks the index for the same segments exactly as the engine's pass does (cells or nodes, box tests, DDA steps, candidate lists) but tests no disc, timed apart right after it on the same threads (not in cost_disc_index_s); over cost_disc_index_per_replica_s it is eq. 8's traversal share in seconds: mean, standard error across replicas, replicas",
);
/// Theorem 1 for them.
pub const TESTS_THEORY: Column = Column::value(
    "tests_{}_theory",
    "tests",
    Class::Theory,
    "Theorem 1's count for the engine (t = u = 1), times the replicas; brute force n_R·n_P",
);
/// Sphere cache: ray–sphere tests.
pub const RAY_SPHERE_TESTS: Column = Column::value(
    "ray_sphere_tests",
    "tests",
    Class::Measured,
    "sphere cache: ray–sphere tests building lists (T_R's work)",
);
/// Their theory.
pub const RAY_SPHERE_TESTS_THEORY: Column = Column::value(
    "ray_sphere_tests_theory",
    "tests",
    Class::Theory,
    "Theorem 1's T_R = t·n_R/Q²·(∛n_P − 1)/(1 − Q), times the replicas",
);
/// Sphere cache: ray–disc tests.
pub const RAY_DISC_TESTS: Column = Column::value(
    "ray_disc_tests",
    "tests",
    Class::Measured,
    "sphere cache: ray–disc tests against the deepest list (T_I's work)",
);
/// Their theory.
pub const RAY_DISC_TESTS_THEORY: Column = Column::value(
    "ray_disc_tests_theory",
    "tests",
    Class::Theory,
    "Theorem 1's T_I = (4/3)·u·n_R·∛n_P, times the replicas",
);
/// Sphere cache: segments copied into lists.
pub const RAYS_COPIED: Column = Column::value(
    "rays_copied",
    "segments",
    Class::Measured,
    "sphere cache: segments copied into lists while building them (the root's list once per replica, included), summed over replicas; weight 0 in counted_cost_sphere_cache (each copy follows a counted ray–sphere test)",
);
/// Sphere cache: spheres built.
pub const SPHERES_BUILT: Column = Column::value(
    "spheres_built",
    "spheres",
    Class::Measured,
    "sphere cache: spheres built over all levels (the root once per replica, included), summed over replicas",
);
/// Sphere cache: paper pop repairs.
pub const POP_REPAIRS: Column = Column::value(
    "pop_repairs",
    "points",
    Class::Measured,
    "sphere cache, detp.pop_rule = \"paper\": points whose kept chain held a level not containing the disc (inherited lists: cut back to the chain there to stay exact; exact lists: harmless); 0 for \"chain\"",
);
/// Engine's counted cost.
pub const COUNTED_COST: Column = Column::value(
    "counted_cost_{}",
    "tests",
    Class::Measured,
    "the engine's total counted cost, weight 1 per ray–sphere test, ray–disc test, segment–box slab test and DDA step, 0 per segment copied (sphere cache: ray_sphere_tests + ray_disc_tests; disc index: tests + box_tests + dda_steps; brute force: tests), summed over replicas",
);
/// An engine's seconds.
pub const COST_S: Column = Column::value(
    "cost_{}_s",
    "s",
    Class::Timing,
    "seconds of the engine's work on the points (after the rays exist and build_{}_s is paid), summed over replicas; path tracing: all detp.path_samples paths on its path_tracing_points points",
);
/// Ordering time.
pub const ORDER_S: Column = Column::value(
    "order_s",
    "s",
    Class::Timing,
    "sphere cache: seconds to sort the points along the space-filling curve",
);
/// Index nodes visited.
pub const NODES: Column = Column::value(
    "nodes_{}",
    "nodes",
    Class::Measured,
    "disc index: nodes (octree) or cells (grid) visited by the segments, summed over replicas",
);
/// Index box tests.
pub const BOX_TESTS: Column = Column::value(
    "box_tests_{}",
    "tests",
    Class::Measured,
    "disc index: segment–box slab tests (octree: every node tested; grid: each segment clipped to the grid's box), summed over replicas",
);
/// Index DDA steps.
pub const DDA_STEPS: Column = Column::value(
    "dda_steps_{}",
    "steps",
    Class::Measured,
    "disc index: 3D-DDA steps through grid cells (0 for an octree, whose steps are its box tests), summed over replicas",
);
/// What an engine pays once per photon set.
pub const BUILD_S: Column = Column::value(
    "build_{}_s",
    "s",
    Class::Timing,
    "seconds the engine pays once per photon set before any point's work, summed over replicas (disc index: building it; sphere cache: sorting the points, = order_s; photon maps: the kd-tree; path tracing: 0): with trace_s the part paid once, cost_{}_s/points the part per point",
);
/// Index size.
pub const BYTES: Column = Column::value(
    "bytes_{}",
    "bytes",
    Class::Measured,
    "disc index: bytes of the largest replica's index",
);
/// The growing photon map's k.
pub const PHOTON_MAP_GROWING_K: Column = Column::value(
    "photon_map_growing_k",
    "photons",
    Class::Measured,
    "photon-map-growing: the k it used at this photon count, photon_map_k·(photons/photon_map_k_photons)^photon_map_k_growth rounded (at least 1)",
);
/// Path tracing: points it ran on.
pub const PATH_TRACING_POINTS: Column = Column::value(
    "path_tracing_points",
    "points",
    Class::Measured,
    "path-tracing: the points it ran on (detp.path_points of them, or all); its cost for n points is cost_path_tracing_s·n/path_tracing_points",
);
/// Path tracing: per-path relative spread.
pub const PATH_TRACING_CV: Column = Column::value(
    "path_tracing_cv",
    "1",
    Class::Measured,
    "path-tracing: √(mean σ_i²)/mean E_i over its points and replicas, σ_i² the per-path variance at point i: the relative RMSE of one path per point",
);
/// Path tracing: cv from its prefix errors.
pub const PATH_TRACING_CV_PREFIX: Column = Column::value(
    "path_tracing_cv_prefix",
    "1",
    Class::Measured,
    "path-tracing: √(mean_k n_k·mse_k)/mean R over its checkpoints n_k, mse_k its mean squared error against engine reference (the reference's variance subtracted, mean over replicas), R the reference at its points: cv as its errors show it, robust to heavy tails; NaN without reference",
);
/// Path tracing: continuation rays.
pub const PATH_TRACING_RAYS_PATH: Column = Column::value(
    "path_tracing_rays_path",
    "rays",
    Class::Measured,
    "path-tracing: continuation rays of all its paths, summed over replicas",
);
/// Path tracing: shadow rays.
pub const PATH_TRACING_RAYS_SHADOW: Column = Column::value(
    "path_tracing_rays_shadow",
    "rays",
    Class::Measured,
    "path-tracing: shadow rays of all its paths, summed over replicas",
);
/// Path tracing: seconds per path.
pub const PATH_TRACING_S_PER_PATH: Column = Column::value(
    "path_tracing_s_per_path",
    "s",
    Class::Timing,
    "path-tracing: wall seconds per path (its seconds over path_tracing_points·detp.path_samples·replicas)",
);
/// Photon-map RMSE.
pub const PHOTON_MAP_RMSE: Column = Column::estimate(
    "photon_map_rmse",
    "W/m²",
    "photon map: root-mean-square error against the exact irradiance (where the scene has one), one sample per replica",
);
/// Photon-map bias.
pub const PHOTON_MAP_BIAS: Column = Column::estimate(
    "photon_map_bias",
    "W/m²",
    "photon map: mean error against the exact irradiance, one sample per replica",
);
/// Engine disagreements.
pub const MISMATCHES: Column = Column::value(
    "mismatches",
    "discs",
    Class::Check,
    "discs whose integer sum differs between DETP engines or from brute force (0 when correct; the run fails otherwise)",
);
/// Discs checked by brute force.
pub const BF_CHECKED: Column = Column::value(
    "bf_checked",
    "discs",
    Class::Check,
    "discs re-computed by brute force (a keyed subset of detp.brute_force_points, or all)",
);
/// Mean irradiance.
pub const IRRADIANCE: Column = Column::vs_prediction(
    "irradiance",
    "W/m²",
    "mean irradiance over the discs (over those with an exact value, where some have), one sample per replica; theory: the exact mean (NaN without a closed form)",
);
/// RMSE.
pub const IRRADIANCE_RMSE: Column = Column::estimate(
    "irradiance_rmse",
    "W/m²",
    "DETP's root-mean-square error against the exact irradiance, one sample per replica",
);
/// Bias.
pub const IRRADIANCE_BIAS: Column = Column::estimate(
    "irradiance_bias",
    "W/m²",
    "DETP's mean error against the exact irradiance, one sample per replica",
);
/// Reference: mean irradiance over the points.
pub const REFERENCE_IRRADIANCE: Column = Column::estimate(
    "reference_irradiance",
    "W/m²",
    "engine reference: its irradiance averaged over the sample points; SE from the points' own SEs (√Σse²/n), n = points",
);
/// Reference: mean SE.
pub const REFERENCE_MEAN_SE: Column = Column::value(
    "reference_mean_se",
    "W/m²",
    Class::Measured,
    "engine reference: the mean over the sample points of its standard error (detp.reference_samples paths each)",
);
/// DETP against the reference: mean error.
pub const IRRADIANCE_REF_BIAS: Column = Column::estimate(
    "irradiance_ref_bias",
    "W/m²",
    "DETP's mean error against engine reference over the points, Σ(E_i − R_i)/n; SE with ≥ 2 replicas across the replicas' mean errors (a replica's points share its photons) plus the reference's Σ se_R,i²/n², clusters its Welch–Satterthwaite degrees of freedom + 1; with one replica √Σ(se_E,i² + se_R,i²)/n (the point set is fixed)",
);
/// DETP against the reference: RMSE.
pub const IRRADIANCE_REF_RMSE: Column = Column::estimate(
    "irradiance_ref_rmse",
    "W/m²",
    "DETP's root-mean-square error against the true irradiance, estimated against engine reference with the reference's variance subtracted: √max(0, Σ((E_i − R_i)² − se_R,i²)/n); SE by the delta method from Var((E_i − R_i)²) ≈ 4b_i²s_i² + 2s_i⁴",
);
/// A baseline against the reference: mean error.
pub const BASELINE_REF_BIAS: Column = Column::estimate(
    "{}_ref_bias",
    "W/m²",
    "a baseline (photon_map, photon_map_growing, path_tracing): mean error against engine reference, as irradiance_ref_bias, over the points it ran on (photon maps: with one replica its per-point SE is E/√k; path tracing: at detp.path_samples paths, with one replica its per-point SE is σ_i/√K)",
);
/// A baseline against the reference: RMSE.
pub const BASELINE_REF_RMSE: Column = Column::estimate(
    "{}_ref_rmse",
    "W/m²",
    "a baseline: root-mean-square error against the true irradiance, estimated against engine reference as irradiance_ref_rmse, over the points it ran on",
);
/// Surface points skipped as covered.
pub const POINTS_COVERED: Column = Column::value(
    "points_covered",
    "points",
    Class::Measured,
    "point_source = \"surface\": lattice points skipped because other geometry covers them (a surface within 10⁻⁶ of the scene's size along the normal, or every probe over the hemisphere meets the back of a surface: inside a solid)",
);
/// Speed.
pub const RAYS_PER_S: Column = Column::value(
    "rays_per_s",
    "segments/s",
    Class::Timing,
    "segments handled per second of engine time",
);

/// A baseline's errors against the reference.
pub const BASELINE_REF: Table<DetpConfig, (Estimate, Estimate)> = Table::of(&[
    col(&BASELINE_REF_BIAS, |_, e| e.0.into()),
    col(&BASELINE_REF_RMSE, |_, e| e.1.into()),
]);

/// Each baseline's errors against the reference, in the point's engine order.
fn baseline_ref_cells(p: &DetpConfig, m: &DetpMeasured) -> Vec<(&'static str, Cells)> {
    m.reference.as_ref().map_or_else(Vec::new, |r| {
        r.baselines
            .iter()
            .map(|(stem, e)| (*stem, cells(BASELINE_REF.entries, p, e)))
            .collect()
    })
}

/// One group of cells per engine, in the point's engine order.
fn engine_cells(p: &DetpConfig, m: &DetpMeasured) -> Vec<(&'static str, Cells)> {
    m.engines.iter().map(|e| (e.column(), e.cells(p))).collect()
}

/// Every engine's columns, in registry order.
fn engine_columns() -> Vec<&'static Column> {
    ESTIMATORS.iter().flat_map(|e| e.columns()).collect()
}

/// The main table: the point's counts, one group per engine, the checks, the accuracy against the
/// reference and against the exact irradiance, the speed.
pub const MAIN: Table<DetpConfig, DetpMeasured> = Table::of(&[
    col(&SEGMENTS, |_, m| m.segments.into()),
    col(&SEGMENTS_INDIRECT, |_, m| m.segments_indirect.into()),
    col(&POINTS, |_, m| m.points.into()),
    col(&TRACE_S, |_, m| m.trace_s.into()),
    col(&EDGE_S, |_, m| m.edge_s.into()),
    col(&EDGE_RADIUS, |_, m| m.edge_radius.into()),
    col(&DIRECT_S, |_, m| m.direct_s.into()),
    col(&DIRECT_RAYS_SHADOW, |_, m| m.direct_rays_shadow.into()),
    Entry::Parts(engine_cells, engine_columns),
    col(&MISMATCHES, |_, m| m.mismatches.into()),
    col(&BF_CHECKED, |_, m| m.bf_checked.into()),
    col(&POINTS_COVERED, |_, m| m.points_covered.into()),
    col(&REFERENCE_IRRADIANCE, |_, m| {
        m.reference.as_ref().map(|r| r.irradiance).into()
    }),
    col(&REFERENCE_MEAN_SE, |_, m| {
        m.reference.as_ref().map(|r| r.mean_se).into()
    }),
    col(&IRRADIANCE_REF_BIAS, |_, m| {
        m.reference.as_ref().map(|r| r.detp.0).into()
    }),
    col(&IRRADIANCE_REF_RMSE, |_, m| {
        m.reference.as_ref().map(|r| r.detp.1).into()
    }),
    Entry::Parts(baseline_ref_cells, || BASELINE_REF.columns()),
    col(&IRRADIANCE, |_, m| {
        Cell::Judged(m.irradiance, Theory::Prediction(m.exact_mean))
    }),
    col(&IRRADIANCE_RMSE, |_, m| m.irradiance_rmse.into()),
    col(&IRRADIANCE_BIAS, |_, m| m.irradiance_bias.into()),
    col(&RAYS_PER_S, |_, m| m.rays_per_s.into()),
]);

/// Level number.
pub const LEVEL: Column = Column::value(
    "level",
    "1",
    Class::Measured,
    "sphere-cache level i (0: the root)",
);
/// Its radius.
pub const RADIUS: Column = Column::value("radius", "length", Class::Theory, "its radius r_0·Q^i");
/// Builds.
pub const BUILDS_LEVEL: Column = Column::value(
    "builds_level",
    "spheres",
    Class::Measured,
    "spheres built at this level, over replicas",
);
/// Rays held.
pub const RAYS_LEVEL: Column = Column::estimate(
    "rays_level",
    "rays",
    "mean rays held by the spheres built at this level (one cluster per replica)",
);
/// Its law.
pub const RAYS_LEVEL_THEORY: Column = Column::value(
    "rays_level_theory",
    "rays",
    Class::Theory,
    "the uniform-line law n_R·(r_i/r_law)²",
);
/// Lens-clipped law.
pub const RAYS_LEVEL_THEORY_CLIPPED: Column = Column::value(
    "rays_level_theory_clipped",
    "rays",
    Class::Theory,
    "lines: the law for sphere centres uniform in the ball, clipped where spheres stick out of it",
);
/// Spheres inside the law's ball.
pub const RAYS_LEVEL_INSIDE: Column = Column::estimate(
    "rays_level_inside",
    "rays",
    "lines: mean rays held by the spheres that lie inside the ball (where the law is exact)",
);
/// Misses.
pub const MISSES_LEVEL: Column = Column::value(
    "misses_level",
    "spheres",
    Class::Measured,
    "cache misses: builds of this level except a chunk's cold start",
);
/// Rays held by the spheres of this level that hold fewer than the threshold (never subdivided).
pub const RAYS_LEVEL_LEAF: Column = Column::vs_prediction(
    "rays_level_leaf",
    "segments",
    "rays held per sphere of this level that holds fewer than detp.threshold (a sphere never subdivided): mean over those builds, SE clustered by replica, builds; theory: E[X | X < threshold] for X ~ Poisson(rays_level_theory)",
);
/// Misses per replica.
pub const MISSES_LEVEL_PER_REPLICA: Column = Column::estimate(
    "misses_level_per_replica",
    "builds",
    "misses at this level in one replica: mean, standard error across replicas, replicas",
);
/// The paper's rebuild model.
pub const MISSES_LEVEL_THEORY: Column = Column::value(
    "misses_level_theory",
    "spheres",
    Class::Theory,
    "the paper's rebuild model m_i ≈ Q^(−3i) (one rebuild per region of S_i's size the sorted points visit; THEORY §2), times the replicas",
);
/// Rays copied per level.
pub const RAYS_COPIED_LEVEL: Column = Column::value(
    "rays_copied_level",
    "segments",
    Class::Measured,
    "segments copied into this level's lists (Σ list length over its builds), over replicas",
);
/// Tests.
pub const RAY_SPHERE_TESTS_LEVEL: Column = Column::value(
    "ray_sphere_tests_level",
    "tests",
    Class::Measured,
    "ray–sphere tests building this level's lists",
);

/// A level's summary line: rays held against the uniform-line law (photons of a scene are shown
/// against it, not judged: the README's real scenes hold 1.2–2.3× the law); none for a level no
/// replica built.
fn level_line(_: &DetpConfig, r: &LevelRow) -> Vec<Line> {
    if r.rays.n == 0 {
        return Vec::new();
    }
    vec![Line {
        metric: format!("rays L{}", r.level),
        estimate: r.rays,
        against: Against::Law {
            value: r.law,
            name: "n_R·(r_i/r_law)²",
            not_judged: (!r.lines).then_some("photons"),
        },
    }]
}

/// `NAME.levels.csv`: one row per sphere-cache level (the leaf mean is not summarised: one line
/// per level would drown the rays' lines).
pub const LEVELS: Table<DetpConfig, LevelRow> = Table {
    entries: &[
        col(&LEVEL, |_, r| r.level.into()),
        col(&RADIUS, |_, r| r.radius.into()),
        col(&BUILDS_LEVEL, |_, r| r.builds.into()),
        col(&RAYS_LEVEL, |_, r| r.rays.into()),
        col(&RAYS_LEVEL_THEORY, |_, r| r.law.into()),
        col(&RAYS_LEVEL_THEORY_CLIPPED, |_, r| r.clipped.into()),
        col(&RAYS_LEVEL_INSIDE, |_, r| r.inside.into()),
        col(&MISSES_LEVEL, |_, r| r.misses.into()),
        col(&MISSES_LEVEL_PER_REPLICA, |_, r| {
            r.misses_per_replica.into()
        }),
        col(&MISSES_LEVEL_THEORY, |p, r| {
            (p.replicas as f64 * p.q().powi(-3 * r.level as i32)).into()
        }),
        col(&RAYS_COPIED_LEVEL, |_, r| r.copied.into()),
        col(&RAY_SPHERE_TESTS_LEVEL, |_, r| r.sphere_tests.into()),
        col(&RAYS_LEVEL_LEAF, |p, r| {
            let law = th::poisson_mean_below(r.law, p.cache.threshold as u64);
            Cell::Judged(r.leaf, Theory::Prediction(law))
        }),
    ],
    lines: level_line,
};

/// Sample index.
pub const SAMPLE: Column =
    Column::value("sample", "1", Class::Measured, "the sample point's index");
/// Coordinates and normal.
pub const X: Column = Column::value("x", "length", Class::Measured, "the point");
/// y.
pub const Y: Column = Column::value("y", "length", Class::Measured, "the point");
/// z.
pub const Z: Column = Column::value("z", "length", Class::Measured, "the point");
/// Normal x.
pub const NX: Column = Column::value("nx", "1", Class::Measured, "its unit normal");
/// Normal y.
pub const NY: Column = Column::value("ny", "1", Class::Measured, "its unit normal");
/// Normal z.
pub const NZ: Column = Column::value("nz", "1", Class::Measured, "its unit normal");
/// Irradiance at the point.
pub const POINT_IRRADIANCE_MEAN: Column = Column::value(
    "irradiance_mean",
    "W/m²",
    Class::Measured,
    "DETP's irradiance at the point (mean over replicas)",
);
/// Its SE.
pub const POINT_IRRADIANCE_SE: Column = Column::value(
    "irradiance_se",
    "W/m²",
    Class::Measured,
    "its standard error: across replicas, or with one replica the Poisson SE √(E·w̄/πd²)",
);
/// Its value in each replica.
pub const POINT_IRRADIANCE_REPLICA: Column = Column::value(
    "irradiance_replica_{}",
    "W/m²",
    Class::Measured,
    "DETP's irradiance at the point in replica {} (with ≥ 2 replicas): a mean error over a group of points must take its SE across replicas, since a replica's points share its photons",
);
/// Exact value.
pub const POINT_IRRADIANCE_EXACT: Column = Column::value(
    "irradiance_exact",
    "W/m²",
    Class::Theory,
    "the scene's closed form at the point (NaN without one)",
);

/// The point's disc radius.
pub const POINT_DISC_RADIUS: Column = Column::value(
    "disc_radius",
    "length",
    Class::Measured,
    "the point's disc radius: d, or with detp.edge = \"clamp-radius\" its own radius (distance to the nearest other surface, clamped to [edge_min_radius·d, d]); its sum is divided by π·disc_radius²",
);
/// The point's distance to an edge.
pub const POINT_EDGE_DISTANCE: Column = Column::value(
    "edge_distance",
    "length",
    Class::Measured,
    "s: the distance from the point to the nearest edge or other surface (not its own plane), capped at detp.edge_distance_reach·d (the cap: none nearer); the paper's open-surface case is s ≥ d. NaN without a scene",
);
/// A baseline's estimate at the point.
pub const POINT_BASELINE_E: Column = Column::value(
    "{}_e",
    "W/m²",
    Class::Measured,
    "a baseline engine's irradiance at the point: reference_e (path-traced, unbiased) or photon_map_e (mean over replicas)",
);
/// Its SE.
pub const POINT_BASELINE_SE: Column = Column::value(
    "{}_se",
    "W/m²",
    Class::Measured,
    "its standard error: the reference's from its samples' variance; the photon map's across replicas, or with one replica E/√k",
);

/// A baseline's estimate and standard error at a point.
pub const BASELINE: Table<DetpConfig, (f64, f64)> = Table::of(&[
    col(&POINT_BASELINE_E, |_, b| b.0.into()),
    col(&POINT_BASELINE_SE, |_, b| b.1.into()),
]);

/// The baselines' columns at one point, one group per baseline in the point's engine order.
fn baseline_cells(p: &DetpConfig, r: &PointRow) -> Vec<(&'static str, Cells)> {
    r.baselines
        .iter()
        .map(|&(engine, e, se)| (engine, cells(BASELINE.entries, p, &(e, se))))
        .collect()
}

/// `NAME.points.csv`: one row per sample point.
pub const POINTS_TABLE: Table<DetpConfig, PointRow> = Table::of(&[
    col(&SAMPLE, |_, r| r.sample.into()),
    col(&X, |_, r| r.center.x.into()),
    col(&Y, |_, r| r.center.y.into()),
    col(&Z, |_, r| r.center.z.into()),
    col(&NX, |_, r| r.normal.x.into()),
    col(&NY, |_, r| r.normal.y.into()),
    col(&NZ, |_, r| r.normal.z.into()),
    col(&POINT_DISC_RADIUS, |_, r| r.disc_radius.into()),
    col(&POINT_EDGE_DISTANCE, |_, r| r.edge_distance.into()),
    col(&POINT_IRRADIANCE_MEAN, |_, r| r.mean.into()),
    col(&POINT_IRRADIANCE_SE, |_, r| r.se.into()),
    col(&POINT_IRRADIANCE_REPLICA, |_, r| {
        Cell::members(
            r.replicas
                .iter()
                .enumerate()
                .map(|(k, &e)| (k.to_string(), e)),
        )
    }),
    col(&POINT_IRRADIANCE_EXACT, |_, r| r.exact.into()),
    Entry::Parts(baseline_cells, || BASELINE.columns()),
    col(&POINT_PATH_TRACING_E, |_, r| {
        r.path_tracing
            .as_ref()
            .map(|(m, _)| Cell::members(m.iter().cloned()))
            .into()
    }),
    col(&POINT_PATH_TRACING_VAR, |_, r| {
        r.path_tracing.as_ref().map(|p| p.1).into()
    }),
    col(&POINT_DIRECT_E, |_, r| r.direct.0.into()),
    col(&POINT_DIRECT_SE, |_, r| r.direct.1.into()),
]);

/// Path tracing's running mean at a point.
pub const POINT_PATH_TRACING_E: Column = Column::value(
    "path_tracing_e_{}",
    "W/m²",
    Class::Measured,
    "path-tracing: its running mean at the point after {} paths (each checkpoint 1, 2, 4, …, detp.path_samples), mean over replicas; NaN at points outside path_tracing_points",
);
/// Path tracing's per-path variance at a point.
pub const POINT_PATH_TRACING_VAR: Column = Column::value(
    "path_tracing_var",
    "W²/m⁴",
    Class::Measured,
    "path-tracing: its per-path variance at the point (over detp.path_samples paths), mean over replicas; NaN outside path_tracing_points",
);
/// The NEE direct part at a point.
pub const POINT_DIRECT_E: Column = Column::value(
    "direct_e",
    "W/m²",
    Class::Measured,
    "detp.direct = \"nee\": the direct irradiance at the point by next-event estimation (included in irradiance_mean and every baseline but the reference and path tracing), mean over replicas; 0 otherwise",
);
/// Its SE.
pub const POINT_DIRECT_SE: Column = Column::value(
    "direct_se",
    "W/m²",
    Class::Measured,
    "its standard error (mean over replicas: √Σse_r²/R)",
);

/// Replica.
pub const PT_REPLICA: Column =
    Column::value("replica", "1", Class::Measured, "the replica");
/// Checkpoint.
pub const PT_PATHS: Column = Column::value(
    "paths",
    "paths",
    Class::Measured,
    "checkpoint: paths per point (1, 2, 4, …, detp.path_samples)",
);
/// Continuation rays.
pub const PT_RAYS_PATH: Column = Column::value(
    "rays_path",
    "rays",
    Class::Measured,
    "continuation rays of the first `paths` paths of every point",
);
/// Shadow rays.
pub const PT_RAYS_SHADOW: Column = Column::value(
    "rays_shadow",
    "rays",
    Class::Measured,
    "shadow rays of the first `paths` paths of every point",
);
/// Seconds to the checkpoint.
pub const PT_SECONDS: Column = Column::value(
    "seconds_s",
    "s",
    Class::Timing,
    "wall-clock seconds to this checkpoint: the points' thread seconds rescaled so that the last checkpoint's equal the run's wall time",
);
/// Thread seconds.
pub const PT_THREAD_S: Column = Column::value(
    "thread_s",
    "s",
    Class::Timing,
    "the points' thread seconds to this checkpoint, summed",
);
/// MSE against the reference.
pub const PT_REF_MSE: Column = Column::value(
    "ref_mse",
    "W²/m⁴",
    Class::Measured,
    "this replica's mean over its points of (E_i − R_i)² − se_R,i² against engine reference at this checkpoint (its own mean squared error, the reference's variance subtracted); NaN without reference",
);
/// Mean error against the reference.
pub const PT_REF_BIAS: Column = Column::value(
    "ref_bias",
    "W/m²",
    Class::Measured,
    "this replica's mean over its points of E_i − R_i at this checkpoint; NaN without reference",
);
/// Mean per-path variance.
pub const PT_VARIANCE_MEAN: Column = Column::value(
    "variance_mean",
    "W²/m⁴",
    Class::Measured,
    "this replica's per-path variance at K paths, mean over its points (the same on every row of the replica)",
);

/// `NAME.path_tracing.csv`: engine `path-tracing`, one row per replica and checkpoint (per replica,
/// so that an analysis can bootstrap over replicas).
pub const PATH_TRACING_TABLE: Table<DetpConfig, PathRow> = Table::of(&[
    col(&PT_REPLICA, |_, r| r.replica.into()),
    col(&PT_PATHS, |_, r| r.paths.into()),
    col(&PT_RAYS_PATH, |_, r| r.rays_path.into()),
    col(&PT_RAYS_SHADOW, |_, r| r.rays_shadow.into()),
    col(&PT_SECONDS, |_, r| r.seconds_s.into()),
    col(&PT_THREAD_S, |_, r| r.thread_s.into()),
    col(&PT_REF_MSE, |_, r| r.ref_mse.into()),
    col(&PT_REF_BIAS, |_, r| r.ref_bias.into()),
    col(&PT_VARIANCE_MEAN, |_, r| r.variance_mean.into()),
]);
