//! Kind `detp`: one point builds a ray store (μ-random lines through the unit ball, or photons traced
//! from a scene), discs on sample points, and runs the engines the spec names on it, once per replica
//! (each an estimator of the registry, one file each in `estimators/`, see [`estimators`]):
//!
//! - `sphere-cache`: the hierarchy of spheres (points visited in Morton/Hilbert/no order), with its
//!   counters per level — rays held, rebuilds (cache misses), ray–sphere tests — against
//!   n_R·Q^(2i) and Theorem 1;
//! - `disc-index`: the discs in an octree or a grid that every segment traverses, against Theorem 1;
//!   its walk alone (no disc tests) is timed apart after its pass, for eq. 8's traversal share;
//! - `brute-force`: every segment against every disc;
//! - `photon-map`: Jensen's k-nearest-neighbour estimate over the same photons (scenes only), and
//!   `photon-map-growing` with k(N) = k₀·(N/N₀)^β so that its error keeps falling;
//! - `path-tracing`: per-point path tracing with next-event estimation, DETP's competitor at a
//!   target error (scenes only, once per point set and replica in a run);
//! - `reference`: the path-traced irradiance at every point ([`crate::lt::reference`]), the ground
//!   truth DETP and the photon map are measured against (scenes only; computed once per point set
//!   in a run, not per replica).
//!
//! The DETP engines must give the same integer sum on every disc, bit for bit; on top of that a keyed
//! random subset of `brute_force_points` discs is re-computed by brute force. Any difference is the
//! `mismatches` [`Check`]: the runner writes the row and fails the run (exit 1).
//!
//! The spec's `[detp]` table is declared in `spec.rs` and validated in `config.rs`; a point's run and
//! its typed measurement are in `measure.rs`; columns are declared with their accessors in
//! `columns.rs` and each estimator's file (counts are totals over the point's replicas; estimates
//! have one cluster per replica, so their standard errors cover independent ray sets).
//!
//! # Interface for other kinds and commands
//!
//! Kind `quasi-static` reads the same `[detp]` table and `raycost render` draws a DETP point; both
//! use only what is re-exported here: [`RawDetp`] (the table as written), [`DetpConfig`] (it
//! validated: [`Rays`], [`Points`], d, the sphere cache's parameters, the index), [`memory`],
//! [`describe`], [`DynamicEngine`] (quasi-static's engine choice), [`EngineChoice`] (a name of the
//! estimator registry; `EngineChoice::is::<E>()` tells an estimator of [`estimators`]), the edge
//! remedies' defaults [`EDGE_MIN_RADIUS`] and [`EDGE_GAP`], and [`lattice_spacing`].

use std::ops::Range;

use glam::DVec3;
use rand::seq::index::sample as sample_indices;
use rayon::prelude::*;

pub mod columns;
pub mod config;
pub mod engines;
pub mod estimators;
mod lines;
pub mod measure;
pub mod replica_errors;
mod scene;
pub mod shards;
pub mod spec;

// The DETP module's interface for kind `quasi-static` and `raycost render`: the validated `[detp]`
// table and its parts, what a point needs in memory, the one-line description, and the defaults of
// the edge remedies.
pub use self::config::{lattice_spacing, DetpConfig, Points, Rays, SurfacePoints};
pub use self::estimators::path_tracing;
pub use self::spec::{
    DynamicEngine, EngineChoice, RawDetp, EDGE_GAP, EDGE_MIN_RADIUS, EDGE_RADIUS_FACTOR,
    RADIUS_SCHEDULE_EXPONENT,
};

use self::columns as col;
use self::engines::{Gathered, ReferenceCache};
use self::shards::ReplicaPart;
use self::estimators::sphere_cache::LevelRow;
use self::measure::{DetpMeasured, PointRow};
use self::path_tracing::{PathMeasured, PathRow};
use self::replica_errors::ReplicaErrorRow;
use self::spec::DetpSpec;
use super::inputs::Inputs;
use super::kind::{
    refuse, Batching, Check, ConfigError, Context, Kind, Memory, Need, Output, Rate, Table, Work,
};
use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::nearest::Nearest;
use crate::detp::tally::Tally;
use crate::detp::store::SegmentStore;
use crate::error::Error;
use crate::sample::lines::uniform_in_ball;
use crate::sample::rng::{domain, stream};

/// Lines or points drawn from one keyed stream: a batch (so generation parallelises and stays
/// independent of the thread count).
pub(crate) const BATCH: u64 = 4096;

/// The rays of one replica and what the theory needs to know about them.
pub(crate) struct RaySet {
    pub(crate) store: SegmentStore,
    /// The root sphere (centre, radius) that every segment meets.
    pub(crate) root: (DVec3, f64),
    /// Radius of the ball the rays are μ-random in (n_R of them meet it): a sphere of radius r
    /// inside it holds n_R·(r / law_radius)² of them. The unit ball for lines; the root for scenes.
    pub(crate) law_radius: f64,
    /// The ball the rays are μ-random in, if they are (lines: the unit ball).
    pub(crate) law_ball: Option<(DVec3, f64)>,
    /// Segments meeting the law's ball: the n_R of the rays-per-level law.
    pub(crate) rays_in_root: u64,
    /// Seconds to generate or trace them.
    pub(crate) trace_s: f64,
    /// Seconds spent applying `detp.edge` to them (first-hit).
    pub(crate) edge_s: f64,
    /// `detp.direct = "nee"`: the direct (bounce-0) segments traced and left out of `store`.
    pub(crate) segments_direct: u64,
    /// `detp.direct = "nee"`: the NEE direct part the photon maps add to their indirect estimate.
    pub(crate) direct: Option<std::sync::Arc<engines::DirectPart>>,
}

/// The sample points of one replica (or, for the fixed sources, of every replica: see [`points`])
/// with their exact irradiance where known.
pub(crate) struct PointSet {
    pub(crate) discs: Discs,
    /// Exact irradiance per disc, NaN where the source has none.
    pub(crate) exact: Vec<f64>,
    /// Seconds spent applying `detp.edge` to the discs (clamp-radius).
    pub(crate) edge_s: f64,
    /// Surface points: lattice points skipped because other geometry covers them (None for other
    /// point sources).
    pub(crate) covered: Option<u64>,
}

/// The sample points of replica `replica` at stream point `point`.
///
/// Which sources vary per replica ([`DetpConfig::points_per_replica`]):
/// - uniform in the ball (`Points::Ball`): positions and normals are random, so each replica draws
///   its own (`[POINTS, seed, point, replica, batch]`): a replica is a new sample of lines *and*
///   points, and an SE across replicas covers both (the sphere cache's misses depend on the points);
/// - eq. 4's lattice (`Points::Grid`): its centres are fixed by the layout, its normals random, so
///   each replica draws its own normals on the same centres;
/// - a scene's surface lattice and a user's points file: fixed by design (the places the reference
///   is computed once and the same at every sweep point, or the points the user chose), shared by
///   every replica; `replica` is not read.
///
/// `point` is the stream point: with `experiment.common_random_numbers` every sweep point reads the
/// same streams, so replica r has the same points at every sweep point (a choice between sweep
/// points, never between replicas).
pub(crate) fn points(cfg: &DetpConfig, point: u64, replica: u64) -> Result<PointSet, Error> {
    if let Some(s) = cfg.scene() {
        return scene::points(cfg, &s.scene);
    }
    let (centers, normals) = match &cfg.points {
        Points::Ball(n) => {
            let n = *n;
            let pairs: Vec<(DVec3, DVec3)> = (0..n.div_ceil(BATCH))
                .into_par_iter()
                .flat_map_iter(|b| {
                    let mut rng = stream(&[domain::POINTS, cfg.seed, point, replica, b]);
                    let count = BATCH.min(n - b * BATCH);
                    (0..count).map(move |_| {
                        let c = uniform_in_ball(&mut rng);
                        (c, crate::sample::directions::uniform_direction(&mut rng))
                    })
                })
                .collect();
            pairs.into_iter().unzip()
        }
        Points::Grid(k) => lattice(cfg.seed, point, replica, *k),
        Points::File(p) => (p.centers.clone(), p.normals.clone()),
        Points::Surface(_) => {
            return Err(Error::internal(
                "surface points need a scene (the spec check refuses this)",
            ))
        }
    };
    let discs = Discs::new(centers, normals, cfg.disc_radius).map_err(Error::internal)?;
    let exact = discs
        .centers
        .iter()
        .map(|&c| lines::exact(cfg.photons, c, cfg.disc_radius))
        .collect();
    Ok(PointSet {
        discs,
        exact,
        edge_s: 0.0,
        covered: None,
    })
}

/// Eq. 4's layout: k³ points at the cell centres of a k-per-side lattice filling the cube inscribed
/// in the unit ball (spacing 2/(√3·k), so r_0 = √3·spacing·k/2 = 1), with uniform normals drawn
/// from the same keyed streams as points in the ball (the replica's own).
fn lattice(seed: u64, point: u64, replica: u64, k: u64) -> (Vec<DVec3>, Vec<DVec3>) {
    let s = config::lattice_spacing(k);
    let a = 1.0 / 3f64.sqrt();
    let n = k.pow(3);
    let at = move |i: u64| -a + s * (i as f64 + 0.5);
    let pairs: Vec<(DVec3, DVec3)> = (0..n.div_ceil(BATCH))
        .into_par_iter()
        .flat_map_iter(|b| {
            let mut rng = stream(&[domain::POINTS, seed, point, replica, b]);
            let lo = b * BATCH;
            (lo..(lo + BATCH).min(n)).map(move |i| {
                let c = DVec3::new(at(i % k), at(i / k % k), at(i / (k * k)));
                (c, crate::sample::directions::uniform_direction(&mut rng))
            })
        })
        .collect();
    pairs.into_iter().unzip()
}

/// The rays `ids` of one replica (`0..cfg.photons` unless `--photon-shard` splits them).
pub(crate) fn rays(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    pts: &PointSet,
    ids: Range<u64>,
) -> RaySet {
    match cfg.scene() {
        None => lines::lines(cfg, point, replica, ids),
        Some(s) => scene::photons(cfg, point, replica, ids, &s.scene, &pts.discs),
    }
}

/// What the engines of one replica agreed on, and how far that was checked.
struct Agreement {
    /// The first DETP engine's sums.
    sums: Vec<Acc>,
    /// Its radii with `detp.radius_crossings` (IEEE bits; else empty).
    radii: Vec<u64>,
    /// Discs where another engine or brute force differs.
    mismatches: u64,
    /// Discs re-computed by brute force.
    bf_checked: u64,
}

/// The keyed subset of discs that brute force re-computes (None where brute force runs on every
/// disc anyway, or is not asked for): it depends on the seed, the point and the replica only, so
/// photon shards and their merge draw the same subset.
fn check_subset(cfg: &DetpConfig, point: u64, replica: u64, n: usize) -> Option<Vec<u32>> {
    if oracle_runs(cfg) || cfg.brute_force_points == 0 || n == 0 {
        return None;
    }
    let k = (cfg.brute_force_points as usize).min(n);
    let mut rng = stream(&[domain::CHECK, cfg.seed, point, replica]);
    let mut subset: Vec<u32> = sample_indices(&mut rng, n, k)
        .into_iter()
        .map(|i| i as u32)
        .collect();
    subset.sort_unstable();
    Some(subset)
}

/// Does brute force (an estimator whose sums are the oracle) run on every disc?
fn oracle_runs(cfg: &DetpConfig) -> bool {
    cfg.engines.iter().any(|e| e.estimator().oracle())
}

/// Brute force's sums (and, with `detp.radius_crossings`, radii) on the check subset of discs (in
/// subset order; empty without a subset).
fn check_sums(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    rays: &RaySet,
    pts: &PointSet,
) -> Gathered {
    let Some(subset) = check_subset(cfg, point, replica, pts.discs.len()) else {
        return Gathered::default();
    };
    let discs = &pts.discs;
    match cfg.radius_crossings {
        None => {
            let mut bf = vec![0; discs.len()];
            brute::accumulate(&rays.store, discs, Some(&subset), 1, &mut bf);
            Gathered {
                units: subset.iter().map(|&i| bf[i as usize]).collect(),
                radii: Vec::new(),
            }
        }
        Some(rc) => {
            let tally = Nearest::new(rc.k);
            let mut kept = tally.empties(discs.len());
            brute::accumulate_with(&rays.store, discs, Some(&subset), &tally, &mut kept);
            engines::select(&kept, &subset, rc.k, discs)
        }
    }
}

/// Every DETP engine against the first, disc by disc, and the check subset's brute-force sums
/// against it (brute force ran on every disc already where there is no subset): the sums and, with
/// `detp.radius_crossings`, the radii (`part.radii`, `part.bf_radii`; empty otherwise).
fn agree(cfg: &DetpConfig, point: u64, replica: u64, n: usize, part: &ReplicaPart) -> Agreement {
    let (sums, bf) = (&part.sums, &part.bf);
    let (first, rest) = sums
        .split_first()
        .expect("configure refuses a spec without a DETP engine");
    let no_radii = Vec::new();
    let radius = |e: usize| part.radii.get(e).unwrap_or(&no_radii);
    let differs =
        |e: usize, i: usize, o: &[Acc]| o[i] != first[i] || radius(e).get(i) != radius(0).get(i);
    let mut mismatches = (0..n)
        .filter(|&i| rest.iter().enumerate().any(|(e, o)| differs(e + 1, i, o)))
        .count() as u64;
    let bf_checked = match check_subset(cfg, point, replica, n) {
        _ if oracle_runs(cfg) => n as u64,
        Some(subset) => {
            mismatches += subset
                .iter()
                .enumerate()
                .filter(|&(j, &i)| {
                    bf[j] != first[i as usize]
                        || part.bf_radii.get(j) != radius(0).get(i as usize)
                })
                .count() as u64;
            subset.len() as u64
        }
        None => 0,
    };
    Agreement {
        sums: first.clone(),
        radii: radius(0).clone(),
        mismatches,
        bf_checked,
    }
}

crate::side_tables!(
    /// `NAME.levels.csv` (one row per sphere-cache level), with `detp.write_points`
    /// `NAME.points.csv` (one row per sample point), with engine `path-tracing`
    /// `NAME.path_tracing.csv`, and with engine `reference` and ≥ 2 replicas
    /// `NAME.replica_errors.csv` (one row per estimator and replica).
    DetpTables for DetpConfig {
        levels: LevelRow = estimators::sphere_cache::LEVELS,
        points: PointRow = col::POINTS_TABLE,
        path_tracing: PathRow = path_tracing::PATH_TRACING_TABLE,
        replica_errors: ReplicaErrorRow = replica_errors::REPLICA_ERRORS_TABLE,
    }
);

/// One line describing a DETP point for `raycost check`.
pub fn describe(cfg: &DetpConfig) -> String {
    let rays = match cfg.scene() {
        None => format!("{} μ-random lines", cfg.photons),
        Some(s) => format!("{} photons from {}", cfg.photons, s.path.display()),
    };
    let pts = match &cfg.points {
        Points::Ball(n) => format!("{n} points in the unit ball"),
        Points::Grid(k) => format!(
            "{} points on a {k}³ lattice of spacing {:.6} in the unit ball",
            k.pow(3),
            config::lattice_spacing(*k)
        ),
        Points::Surface(s) => match s.keep {
            Some(n) => format!("{n} surface points keyed from the lattice of spacing {}", s.spacing),
            None => format!("surface points at spacing {}", s.spacing),
        },
        Points::File(p) => format!("{} points from {}", p.centers.len(), p.path.display()),
    };
    let engines: Vec<&str> = cfg.engines.iter().map(|e| e.as_str()).collect();
    let radius = match cfg.radius_crossings {
        None => format!("d = {}", cfg.disc_radius),
        Some(rc) => format!("radius of the {} nearest crossings within d = {}", rc.k, cfg.disc_radius),
    };
    format!(
        "{rays}, {pts}, {radius}, Q = {}, {:?} lists, {:?} pop, order {:?}, engines {}, {} replica(s)",
        cfg.q(),
        cfg.cache.list_mode,
        cfg.cache.pop_rule,
        cfg.order,
        engines.join("+"),
        cfg.replicas
    )
}

/// Segments per photon, at most: a lines point has one per line; a scene's photon bounces until
/// absorbed, 1/(1 − albedo) on average for the brightest surface (capped at the tracer's limit).
fn segments_per_photon(cfg: &DetpConfig) -> f64 {
    match cfg.scene() {
        None => 1.0,
        Some(s) => {
            let a = s
                .scene
                .surfaces
                .iter()
                .map(|x| x.albedo)
                .fold(0.0, f64::max);
            (1.0 / (1.0 - a).max(1e-9)).min(f64::from(crate::detp::photon::MAX_BOUNCES) + 1.0)
        }
    }
}

/// The large structures of a DETP point: the segment store, the sphere cache's lists along one
/// path per thread (n_R·Σ Q^{2i} = n_R/(1 − Q²) indices), the photon map's tree, the discs, and a
/// disc grid's cells. The first three grow with the photons traced at once (what photon batches
/// divide); the discs with their sums and the disc grid do not.
pub fn memory(cfg: &DetpConfig, threads: usize) -> Memory {
    let segs = cfg.photons as f64 * segments_per_photon(cfg);
    let threads = threads as f64;
    let n_p = cfg.point_count() as f64;
    let mut needs = vec![
        Need {
            bytes: segs * std::mem::size_of::<crate::detp::store::Segment>() as f64,
            key: "detp.photons",
            what: format!("segment store of ~{segs:.3e} segments"),
            per_photon: true,
        },
        Need {
            // Points drawn per replica are all kept for the points table when it is written.
            bytes: n_p
                * 128.0
                * if cfg.points_per_replica() && cfg.write_points {
                    cfg.replicas as f64
                } else {
                    1.0
                },
            key: match cfg.points {
                Points::Ball(_) | Points::Grid(_) => "detp.points",
                Points::File(_) => "detp.points_file",
                // Surface points: one per spacing² (the spacing defaults to 2d).
                Points::Surface(s) if s.keep.is_some() => "detp.points",
                Points::Surface(_) if cfg.spacing_given => "detp.point_spacing",
                Points::Surface(_) => "detp.disc_radius",
            },
            what: format!("{n_p:.3e} discs and their sums"),
            per_photon: false,
        },
    ];
    // Each estimator's own, once (the two photon maps share their k-d tree's line).
    for e in estimators::ESTIMATORS {
        if cfg.engines.iter().any(|c| c.as_str() == e.name()) {
            for need in e.memory(cfg, segs, threads) {
                if !needs.contains(&need) {
                    needs.push(need);
                }
            }
        }
    }
    if let Some(rc) = cfg.radius_crossings {
        needs.push(nearest_need(rc.k, n_p, threads));
    }
    Memory {
        needs,
        budget: Some(("detp.memory_budget_gib", cfg.memory_budget_gib)),
        batching: Some(Batching {
            key: "detp.photon_batches",
            forced: cfg.photon_batches,
            photons: cfg.photons,
        }),
    }
}

/// The k-nearest-crossings heaps of `detp.radius_crossings`: a DETP engine's pass keeps one heap
/// per disc in every worker (the disc index folds per worker thread; the sphere cache per chunk)
/// and the merged set, so at most (threads + 1)·n_P heaps, each of at most 2k slots (a growing
/// vector's capacity) of [`CROSSING_BYTES`](crate::detp::nearest::CROSSING_BYTES). The engines
/// run one after another, so one engine's at a time.
fn nearest_need(k: usize, n_p: f64, threads: f64) -> Need {
    let heap = std::mem::size_of::<crate::detp::nearest::Kept>() as f64
        + 2.0 * k as f64 * crate::detp::nearest::CROSSING_BYTES as f64;
    Need {
        bytes: (threads + 1.0) * n_p * heap,
        key: "detp.radius_crossings",
        what: format!("k-nearest heaps of k = {k} crossings for {n_p:.3e} discs, per thread"),
        per_photon: false,
    }
}

/// Kind `detp`.
pub struct DetpKind;

impl Kind for DetpKind {
    const NAME: &'static str = "detp";
    const FIXED: &'static [(&'static str, &'static str)] = &[(
        "detp.engines",
        "the engines decide the table's columns, which must be the same for every point",
    )];
    const ABOUT: &'static str = "Density estimation on the tangent plane: photon segments (μ-random lines through the unit ball, or photons traced from a scene) crossing discs of radius d on sample points, gathered by the sphere cache (radius ratio Q, threshold, Morton/Hilbert order), a disc index (octree or grid), brute force and, as baselines, Jensen's photon map (fixed k, or k growing with the photons: photon-map-growing), per-point path tracing as the competitor at a target error (path-tracing: its own streams, running means at 1, 2, 4, … paths, NAME.path_tracing.csv) and a path-traced reference (engine reference: unbiased irradiance per point with its SE, and every engine's bias and RMSE against it; with ≥ 2 replicas each estimator's relative MSE per replica, NAME.replica_errors.csv, what raycost crossover reads). With detp.direct = \"nee\" direct light is next-event estimation at each point and DETP (and the photon maps) estimate the indirect light from the segments after the first bounce. Engines agree bit for bit (integer fixed point) and with brute force on a keyed subset; tests per engine against Theorem 1, rays per level against n_R·Q^(2i), irradiance against the exact value where the source has one.";
    type Raw = DetpSpec;
    type Point = DetpConfig;
    type Measured = DetpMeasured;
    type Tables = DetpTables;
    type Shared = ReferenceCache;
    const MAIN: Table<DetpConfig, DetpMeasured> = col::MAIN;

    fn configure(raw: &DetpSpec, inputs: &mut Inputs) -> Result<DetpConfig, ConfigError> {
        if raw.detp.engine.is_some() {
            return refuse(
                "detp.engine",
                "belongs to kind quasi-static (it chooses the engine of moving frames); kind \"detp\" runs the engines listed in detp.engines",
            );
        }
        DetpConfig::from_raw(raw.experiment.stream_seed(), &raw.detp, inputs)
    }
    fn describe(p: &DetpConfig) -> String {
        describe(p)
    }
    fn work(p: &DetpConfig) -> Work {
        Work {
            units: p.photons * p.replicas,
            unit: if p.scene().is_some() {
                "photons"
            } else {
                "lines"
            },
            points: p.point_count(),
        }
    }
    fn memory(p: &DetpConfig, threads: usize) -> Memory {
        memory(p, threads)
    }
    fn warnings(p: &DetpConfig) -> Vec<String> {
        p.warnings()
    }
    fn shared(_: &[&DetpConfig]) -> Result<ReferenceCache, Error> {
        Ok(ReferenceCache::default())
    }
    fn run(
        p: &DetpConfig,
        refs: &ReferenceCache,
        ctx: &Context,
    ) -> Result<Output<DetpMeasured, DetpTables>, Error> {
        let replicated = match ctx.merged {
            None => measure::replicate(p, ctx.stream_point, ctx.progress, refs)?,
            Some(parts) => {
                let shards = parts
                    .iter()
                    .map(|v| serde_json::from_value(v.clone()))
                    .collect::<Result<Vec<Vec<shards::ReplicaPart>>, _>>()
                    .map_err(|e| Error::usage(format!("a photon shard's part does not read: {e}")))?;
                let total = shards::add_parts(p, &shards).map_err(Error::usage)?;
                measure::replicate_merged(p, ctx.stream_point, &total, ctx.progress, refs)?
            }
        };
        let (measured, levels, points, replica_errors, warnings) = measure::measure(p, &replicated);
        let path_tracing = measured
            .engines
            .iter()
            .find_map(|e| e.get::<PathMeasured>().map(|m| m.rows.clone()))
            .unwrap_or_default();
        let checks = vec![Check {
            name: col::MISMATCHES.name,
            what: "discs where the DETP engines or brute force disagree",
            failures: measured.mismatches,
            checked: measured.bf_checked.max(measured.points as u64 * p.replicas),
        }];
        let rate = Rate {
            per_s: measured.segments_per_s,
            unit: "segments",
        };
        Ok(Output {
            measured,
            tables: DetpTables {
                levels,
                points,
                path_tracing,
                replica_errors,
            },
            checks,
            rate,
            warnings,
        })
    }
    fn photon_refusal(p: &DetpConfig) -> Option<String> {
        shards::refusal(p)
    }
    fn trace_part(
        p: &DetpConfig,
        refs: &ReferenceCache,
        ctx: &Context,
        (k, n): (u64, u64),
    ) -> Result<serde_json::Value, Error> {
        let ids = shards::photon_range(p.photons, k, n);
        let parts = measure::replicate_part(p, ctx.stream_point, ids, ctx.progress, refs)?;
        serde_json::to_value(parts).map_err(Error::internal)
    }
    fn add_parts(
        _: &DetpConfig,
        a: serde_json::Value,
        b: serde_json::Value,
    ) -> Result<serde_json::Value, Error> {
        crate::experiment::photon_shards::add_following::<shards::ReplicaPart>(a, b)
    }
}
