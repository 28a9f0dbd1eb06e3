//! Every column kind `detp` writes, declared once, and the tables that read them from a point's
//! typed measurement: [`MAIN`] (the point's own columns around one group per engine, in the
//! point's engine order, each engine's group from its estimator's own table,
//! `estimators/NAME.rs`, which also declares the columns only it writes and its side table, if it
//! has one) and [`POINTS_TABLE`]. The engine families every estimator may write (`tests_{}`,
//! `cost_{}_s`, `build_{}_s`, …) are declared here, once.
//! Engine columns are families, one member per engine (`tests_{}` → `tests_sphere_cache`).

use super::config::DetpConfig;
use super::estimators::photon_map::{PhotonMap, PHOTON_MAP_REPLICA};
use super::estimators::photon_map_growing::{PhotonMapGrowing, PHOTON_MAP_GROWING_REPLICA};
use super::estimators::{Estimator as _, ESTIMATORS};
use super::measure::{DetpMeasured, PointRow};
use crate::output::column::{Class, Column};
use crate::output::table::{cells, col, Cell, Cells, Entry, Table};
use crate::stats::{Estimate, Theory};

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
/// The disc radius the engines used, as the spec writes lengths.
pub const DISC_RADIUS_USED: Column = Column::value(
    "disc_radius_used",
    crate::output::column::SPEC_LENGTH,
    Class::Measured,
    "d the engines used, in detp.length_unit: detp.disc_radius, or with detp.radius_schedule_photons the schedule's d(N) = d_ref·(N/N_ref)^(−β) at this point's photons (an edge remedy clamps each disc below it; with detp.radius_crossings it is the largest radius a disc's k-th crossing may have, see radius_crossings_ratio)",
);
/// The same over r_s.
pub const DISC_RADIUS_USED_ROOT: Column = Column::value(
    "disc_radius_used_root",
    "r_s",
    Class::Measured,
    "disc_radius_used over r_s, the radius of the sphere around the scene's bounds (1 for lines): the same d in root units whatever detp.length_unit",
);
/// k of the k-nearest-crossings radius at this point.
pub const RADIUS_CROSSINGS_K: Column = Column::value(
    "radius_crossings_k",
    "crossings",
    Class::Measured,
    "with detp.radius_crossings: k, the crossings each disc keeps at this point's photons, max(2, round(k_ref·(photons/N_ref)^(2/3))) (k_ref without radius_crossings_photons); NaN without the rule (and absent from a table none of whose points uses it)",
);
/// The mean k-nearest radius over the cap.
pub const RADIUS_CROSSINGS_RATIO: Column = Column::value(
    "radius_crossings_ratio",
    "1",
    Class::Measured,
    "with detp.radius_crossings: the mean over points and replicas of r_i (the k-th nearest crossing's distance, which the estimate's power is divided by π·r_i² of) over the disc's own radius (disc_radius_used, or an edge remedy's clamp below it); 1 where fewer than k crossings fell within the disc, which then counts them all as the paper does; NaN without the rule (and absent from a table none of whose points uses it)",
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
/// Theorem 1 for them.
pub const TESTS_THEORY: Column = Column::value(
    "tests_{}_theory",
    "tests",
    Class::Theory,
    "Theorem 1's count for the engine (t = u = 1), times the replicas; brute force n_R·n_P",
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
/// What an engine pays once per photon set.
pub const BUILD_S: Column = Column::value(
    "build_{}_s",
    "s",
    Class::Timing,
    "seconds the engine pays once per photon set before any point's work, summed over replicas (disc index: building it; sphere cache: sorting the points, = order_s; photon maps: the kd-tree; path tracing: 0): with trace_s the part paid once, cost_{}_s/points the part per point",
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
    "a baseline, by its column name (each estimator that is neither a DETP engine nor the reference): mean error against engine reference, as irradiance_ref_bias, over the points it ran on (photon maps: with one replica its per-point SE is E/√k; path tracing: at detp.path_samples paths, with one replica its per-point SE is σ_i/√K)",
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
/// Speed (segments, not rays: grid kinds' `rays_per_s` counts rays).
pub const SEGMENTS_PER_S: Column = Column::value(
    "segments_per_s",
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
    col(&DISC_RADIUS_USED, |p, _| (p.disc_radius / p.length_scale).into()),
    col(&DISC_RADIUS_USED_ROOT, |p, _| (p.disc_radius / p.root_radius).into()),
    col(&RADIUS_CROSSINGS_K, |p, _| {
        p.radius_crossings.map(|r| r.k as u64).into()
    }),
    col(&RADIUS_CROSSINGS_RATIO, |_, m| m.radius_crossings_ratio.into()),
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
    col(&SEGMENTS_PER_S, |_, m| m.segments_per_s.into()),
]);

/// Sample index.
pub const SAMPLE: Column =
    Column::value("sample", "1", Class::Measured, "the sample point's index (points drawn per replica, lines: replica k's point i is k·n_P + i)");
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
    "its standard error: across replicas, or with one replica the Poisson SE √(E·w̄/πd²) (d: the point's disc_radius; with detp.radius_crossings, a disc that found its k crossings: √(E·w̄/πr_i²·(k − 1)/(k − 2)), NaN at k = 2, whose variance is infinite)",
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
    "the point's disc radius: d (with a radius schedule d(N)), or with detp.edge = \"clamp-radius\" its own radius (edge_radius_factor κ times the distance to the nearest other surface, clamped to [edge_min_radius·d, d]); its sum is divided by π·disc_radius². With detp.radius_crossings: r_i, the distance of its k-th nearest crossing within that radius (the radius itself where fewer than k cross), mean over replicas (each replica divides by its own r_i²)",
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

/// A photon map's value per replica at a point (members named by the replica), absent where it did
/// not run or ran with one replica.
fn map_replicas(r: &PointRow, map: &str) -> Cell {
    r.map_replicas
        .iter()
        .find(|(c, _)| *c == map)
        .map(|(_, v)| Cell::members(v.iter().enumerate().map(|(k, &e)| (k.to_string(), e))))
        .into()
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
    col(&PHOTON_MAP_REPLICA, |_, r| map_replicas(r, PhotonMap::COLUMN)),
    col(&PHOTON_MAP_GROWING_REPLICA, |_, r| {
        map_replicas(r, PhotonMapGrowing::COLUMN)
    }),
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
