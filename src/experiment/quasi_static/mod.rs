//! Kind `quasi-static`: one point runs F frames of a scene whose dynamic objects move. Frame 0 is a
//! full photon trace; every later frame is recalculated incrementally
//! ([`crate::detp::quasi_static`]) and, every `dynamic.check_every` frames, against a full
//! recalculation of the same frame: `full_mismatch` counts the points whose sums differ (0 when
//! correct) and `full_frame_s` times it.
//!
//! Columns: the counts of frame 0 (`segments`, `points_static`, `points_dynamic`), the objects'
//! `ratio` r_D/r_0 and the engine each used; per-frame estimates over frames 1…F−1 (`_mean/_se/_n`;
//! consecutive frames are correlated, so the standard error is over batches of consecutive frames):
//! `retraced_rays` (segments meeting an object at its old or new pose) and `rays_meeting_object` (at
//! the new pose) beside f_R = n_R·Σ(r_D/r_0)² (`retraced_rays_theory`), photons and segments
//! re-traced, the search's tests, the static and dynamic points' tests, the disc index's traversal,
//! the sphere cache's list building, the feed's query and each side's counted cost (weights and the
//! `dynamic.feed` choices in `docs/detp-costs.md`), each phase's seconds, the disc index's
//! traversal alone for the dynamic points (`dynamic_traversal_s`: a second walk without disc tests,
//! timed apart), `frame_s` and `full_frame_s`; the theory of Theorem 2 for the same n: the static points' costs
//! (2 vs 8.08·t·f_R·∛n_S) and the dynamic points' (sphere cache vs disc index). Side tables: `frames`
//! (one row per frame) and, with `detp.write_points`, `points` (the irradiance at one frame).
//! With `"path-tracing"` in `detp.engines`, per-point path tracing runs in the posed scene at
//! frame 0 and at every checked frame (`path_tracing_*` in both tables, `path_tracing.rs`): the
//! third cost of F frames beside the incremental and the full recalculation.
//! A point's run leaves a typed measurement ([`QsMeasured`], `measure.rs`), its frames and points
//! rows; `columns.rs` declares every column with the accessor that reads it.
//!
//! With `detp.source = "lines"` (the control of eq. 11, [`crate::detp::quasi_static::lines`]) the
//! rays are μ-random lines through the unit ball (r_0 = 1), the one object an absorbing sphere of
//! radius `dynamic.ratio` on a circle of radius (1 − ratio)/2 about the centre, and the static
//! points uniform in the ball (`detp.points`, kind detp's draw). `retraced_rays` then counts the
//! lines meeting the sphere at its old or new pose, and `retraced_rays_theory` stays f_R as eq. 11
//! writes it, the count at one pose (the paper's eq. 14 charges 2·f_R for the old and new lists):
//! the union is expected at up to 2·f_R, less the lines meeting both poses.
//!
//! `raycost render` and `raycost bench` use [`QuasiStaticConfig`] (a validated point), [`start`],
//! [`params`] and [`apply_ratio`]; the DETP settings inside come from the DETP module's interface
//! ([`super::detp`]).

pub mod columns;
pub mod measure;
pub mod path_tracing;
pub mod shards;
pub mod spec;
pub mod theorem2;

use std::ops::Range;

use self::columns as col;
use self::measure::{Extras, FrameRow, QsMeasured, QsPointRow};
use self::shards::{Facts, FullCheck, FramePart, PointsAt, ReplicaPart};
use self::spec::QuasiStaticSpec;
use super::detp::DynamicEngine;
use super::inputs::Inputs;
use super::kind::{Check, ConfigError, Context, Kind, Memory, Output, Rate, Table, Work};
use crate::detp::quasi_static::{Engine, FrameStats, Params, QuasiStatic, RaySource, Used};
use crate::error::Error;
use crate::theory::detp as th;

pub use self::spec::{apply_ratio, QuasiStaticConfig};

/// The engines' settings for a validated point and one of its replicas.
pub fn params(cfg: &QuasiStaticConfig, n_dynamic_points: f64, replica: u64) -> Params {
    let d = &cfg.detp;
    Params {
        photons: d.photons,
        seed: replica_seed(d.seed, replica),
        frames: cfg.frames,
        disc_radius: d.disc_radius,
        spacing: cfg.spacing,
        engine: match cfg.engine {
            DynamicEngine::Hybrid => Engine::Hybrid,
            DynamicEngine::SphereCache => Engine::SphereCache,
            DynamicEngine::DiscIndex => Engine::DiscIndex,
            // Frame 0 runs by Theorem 2's rule; the predictor then picks (see `run_point`).
            DynamicEngine::Predicted => Engine::Hybrid,
        },
        crossover: cfg
            .crossover
            .unwrap_or_else(|| th::crossover_ratio(d.q(), n_dynamic_points.max(1.0))),
        cache: d.cache,
        order: d.order,
        index: d.index,
        feed: cfg.feed,
        // dynamic_traversal_s (eq. 8 in seconds).
        time_traversal: true,
    }
}

/// The photon streams' key of a replica. Common random numbers: every point of a sweep traces the
/// same photon streams (keyed by the seed and the replica alone), so engines and ratios are compared
/// on identical photons; a point's results still depend only on its own parameters, never on threads
/// or shards. Replica 0 keeps the key of the runs before replicas existed, so their tables reproduce.
fn replica_seed(seed: u64, replica: u64) -> u64 {
    if replica == 0 {
        crate::sample::rng::hash_key(&[seed, 0x7173])
    } else {
        crate::sample::rng::hash_key(&[seed, 0x7173, replica])
    }
}

/// Starts a run of one replica: frame 0 and its stats.
pub fn start(cfg: &QuasiStaticConfig, replica: u64) -> (QuasiStatic, FrameStats) {
    start_photons(cfg, replica, 0..cfg.detp.photons)
}

/// [`start`] with the photons `ids` only (`--photon-shard`).
fn start_photons(
    cfg: &QuasiStaticConfig,
    replica: u64,
    ids: Range<u64>,
) -> (QuasiStatic, FrameStats) {
    // n_D for Theorem 2's finite-n crossover: the dynamic points of the first object, estimated
    // from its area (the run counts them exactly afterwards).
    let n_d = cfg
        .scene
        .movers
        .first()
        .map(|m| {
            let posed = m.posed(0.0);
            let area: f64 = posed.triangles.iter().map(|t| t.area()).sum::<f64>()
                + posed.balls.iter().map(|b| b.area()).sum::<f64>();
            area / (cfg.spacing * cfg.spacing)
        })
        .unwrap_or(1.0);
    let source = if cfg.lines {
        // The replica's own static points (see `detp::points`): a replica is new lines and points.
        let set = super::detp::points(&cfg.detp, 0, replica)
            .expect("points uniform in the ball are finite");
        RaySource::Lines(set.discs)
    } else {
        RaySource::Photons
    };
    QuasiStatic::start_from(cfg.scene.clone(), params(cfg, n_d, replica), ids, source)
}

/// The predictor's run (engine "predicted" or `dynamic.predict`): its fraction, its predictions per
/// object, and the engine Theorem 2's rule would have picked per object.
pub(super) type Predictions = (f64, Vec<crate::detp::quasi_static::Prediction>, Vec<Used>);

/// Runs every frame of one replica over the photons `ids`: its part (what adds across photon
/// shards), and the predictor's and the reference run's figures (unsplit runs only: they are
/// refused with `--photon-shard`).
fn trace_replica(
    cfg: &QuasiStaticConfig,
    replica: u64,
    ids: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> (ReplicaPart, Extras) {
    let photons = ids.end - ids.start;
    let (mut qs, f0) = start_photons(cfg, replica, ids.clone());
    progress(photons);
    let predictions: Option<Predictions> = cfg.predict.map(|fraction| {
        let rule: Vec<Used> = (0..qs.scene.movers.len())
            .map(|m| qs.rule_engine(m))
            .collect();
        let p = qs.predict_and_pick(
            fraction,
            cfg.predictor,
            cfg.engine == DynamicEngine::Predicted,
        );
        (fraction, p, rule)
    });
    let warm = if predictions.is_some() && !qs.scene.movers.is_empty() {
        qs.warm_timings(0, cfg.warm_repeats)
    } else {
        Vec::new()
    };
    let n_r = qs.live_segments() as u64;
    let points_frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
    let write_points = cfg.detp.write_points && replica == 0;
    let mut points_at = (points_frame == 0 && write_points).then(|| PointsAt::of(&qs));
    let mut frames = vec![FramePart {
        stats: f0,
        full: None,
    }];
    // After frame 0's own timings, and the predictor's: it reads the run's state only.
    let mut traced: Vec<path_tracing::TracedFrame> = path_tracing::traces(cfg, 0)
        .then(|| path_tracing::trace_frame(cfg, &qs, replica))
        .into_iter()
        .collect();
    for f in 1..cfg.frames {
        let stats = qs.step(f);
        progress(photons);
        let full = checked(cfg, f).then(|| {
            let (sums, _, seconds) = qs.full_recalculation();
            let diffs = qs
                .sums()
                .iter()
                .zip(&sums)
                .enumerate()
                .filter(|(_, (a, b))| a != b)
                .map(|(i, (a, b))| (i as u32, a - b))
                .collect();
            FullCheck { seconds, diffs }
        });
        frames.push(FramePart { stats, full });
        if path_tracing::traces(cfg, f) {
            traced.push(path_tracing::trace_frame(cfg, &qs, replica));
        }
        if f == points_frame && write_points {
            points_at = Some(PointsAt::of(&qs));
        }
    }
    let reference = cfg.reference_photons.map(|n| reference_error(&qs, cfg, n, replica));
    let part = ReplicaPart {
        ids: (ids.start, ids.end),
        facts: Facts::of(&qs),
        n_r,
        static_index_build_s: qs.static_index_build_s,
        frames,
        points_at,
    };
    (
        part,
        Extras {
            predictions,
            warm,
            reference,
            path_tracing: traced,
        },
    )
}

/// Is frame `f` (≥ 1) checked against a full recalculation: every `dynamic.check_every`-th frame
/// and the last (none with 0)?
fn checked(cfg: &QuasiStaticConfig, f: u32) -> bool {
    cfg.check_every > 0 && (u64::from(f) % cfg.check_every == 0 || f == cfg.frames - 1)
}

/// Error of the last frame against a high-photon reference (relative RMSE over the points; the
/// reference's own noise is part of it, a floor of about 1/√(crossings per disc) of the
/// reference), and the reference's seconds.
fn reference_error(qs: &QuasiStatic, cfg: &QuasiStaticConfig, n: u64, replica: u64) -> (f64, f64) {
    let mine = qs.irradiance();
    let t = std::time::Instant::now();
    let refr = qs.reference_irradiance(
        n,
        crate::sample::rng::hash_key(&[cfg.detp.seed, 0x7265_6665, replica]),
    );
    let ref_s = t.elapsed().as_secs_f64();
    let mean_ref = refr.iter().sum::<f64>() / refr.len().max(1) as f64;
    let mse = mine
        .iter()
        .zip(&refr)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / mine.len().max(1) as f64;
    (mse.sqrt() / mean_ref, ref_s)
}

/// One quasi-static point: `detp.replicas` independent runs of every frame (new photons each),
/// pooled (see [`measure::measure`]).
pub fn run_point(
    cfg: &QuasiStaticConfig,
    progress: &(dyn Fn(u64) + Sync),
) -> Output<QsMeasured, QuasiStaticTables> {
    let (parts, extras): (Vec<ReplicaPart>, Vec<Extras>) = (0..cfg.detp.replicas.max(1))
        .map(|r| trace_replica(cfg, r, 0..cfg.detp.photons, progress))
        .unzip();
    output(cfg, &parts, &extras)
}

/// The point's output from its replicas' parts (a whole run's, or the sum of its photon shards').
fn output(
    cfg: &QuasiStaticConfig,
    parts: &[ReplicaPart],
    extras: &[Extras],
) -> Output<QsMeasured, QuasiStaticTables> {
    let (m, frames) = measure::measure(cfg, parts, extras);
    let points = parts[0].points_at.as_ref().map_or_else(Vec::new, |at| {
        measure::point_rows(cfg, &parts[0].facts, at, m.points_static)
    });
    let rate = Rate {
        per_s: m.per_frame[3].mean / m.frame_s().mean.max(1e-12),
        unit: "segments",
    };
    Output {
        checks: vec![Check {
            name: col::FULL_MISMATCH.name,
            what: "points where an incremental frame differs from its full recalculation",
            failures: m.full_mismatch,
            checked: m.full_checked,
        }],
        measured: m,
        tables: QuasiStaticTables { frames, points },
        rate,
        // Its scene warnings are known before running (`Kind::warnings`).
        warnings: Vec::new(),
    }
}

/// `raycost merge` of photon shards: the point's parts, one list of replicas per shard, added and
/// measured as a whole run.
fn merged_point(
    cfg: &QuasiStaticConfig,
    parts: &[serde_json::Value],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Output<QsMeasured, QuasiStaticTables>, Error> {
    let shards = parts
        .iter()
        .map(|v| serde_json::from_value(v.clone()))
        .collect::<Result<Vec<Vec<ReplicaPart>>, _>>()
        .map_err(|e| Error::usage(format!("a photon shard's part does not read: {e}")))?;
    let total = shards::add_parts(cfg, &shards).map_err(Error::usage)?;
    let extras: Vec<Extras> = total.iter().map(|_| Extras::default()).collect();
    progress(<QuasiStaticKind as Kind>::work(cfg).units);
    Ok(output(cfg, &total, &extras))
}

crate::side_tables!(
    /// `NAME.frames.csv` (one row per frame) and, with `detp.write_points`, `NAME.points.csv` (the
    /// irradiance at one frame).
    QuasiStaticTables for QuasiStaticConfig {
        frames: FrameRow = col::FRAMES_TABLE,
        points: QsPointRow = col::POINTS_TABLE,
    }
);

/// One line for `raycost check`.
pub fn describe(cfg: &QuasiStaticConfig) -> String {
    let warnings: String = cfg
        .warnings
        .iter()
        .map(|w| format!("\n      warning: {w}"))
        .collect();
    format!(
        "{}; {} frames, r_D/r_0 {}, engine {}, feed {}, full check every {} frame(s){warnings}",
        super::detp::describe(&cfg.detp),
        cfg.frames,
        cfg.ratio
            .map_or("as in the scene".to_string(), |r| format!("{r}")),
        cfg.engine.as_str(),
        cfg.feed.as_str(),
        cfg.check_every
    )
}

/// Kind `quasi-static`.
pub struct QuasiStaticKind;

impl Kind for QuasiStaticKind {
    const NAME: &'static str = "quasi-static";
    const FIXED: &'static [(&'static str, &'static str)] = &[(
        "detp.engines",
        "quasi-static frames choose their engine with detp.engine",
    )];
    const ABOUT: &'static str = "A scene whose dynamic objects move over F frames: frame 0 is a full DETP photon trace and gather; every later frame re-traces only the photons whose segments meet an object at its old or new pose (against f_R = n_R·Σ(r_D/r_0)²), updates the static points' sums and gathers the dynamic objects' points with the sphere cache or the disc index (Theorem 2's crossover r_D/r_0 ≈ 0.35, or a timed predictor). Frames are checked against a full recalculation, bit for bit. With detp.source = \"lines\" the rays are μ-random lines through the unit ball (eq. 11's own assumption, r_0 = 1) and the object an absorbing sphere of radius dynamic.ratio circling inside it, static points uniform in the ball.";
    type Raw = QuasiStaticSpec;
    type Point = QuasiStaticConfig;
    type Measured = QsMeasured;
    type Tables = QuasiStaticTables;
    type Shared = ();
    const MAIN: Table<QuasiStaticConfig, QsMeasured> = col::MAIN;

    fn configure(
        raw: &QuasiStaticSpec,
        inputs: &mut Inputs,
    ) -> Result<QuasiStaticConfig, ConfigError> {
        QuasiStaticConfig::from_raw(raw, inputs)
    }
    fn describe(p: &QuasiStaticConfig) -> String {
        describe(p)
    }
    fn work(p: &QuasiStaticConfig) -> Work {
        Work {
            units: p.detp.photons * u64::from(p.frames) * p.detp.replicas.max(1),
            unit: "photon-frames",
            points: p.detp.point_count(),
        }
    }
    /// DETP's needs, and the segment index of the incremental frames: about segments/64 cubic cells
    /// (64 to 2¹⁸), each segment listed in the cells its piece pierces (≈ 1.5·∛cells).
    fn memory(p: &QuasiStaticConfig, threads: usize) -> Memory {
        let mut m = super::detp::memory(&p.detp, threads);
        let segs = m.needs.first().map_or(0.0, |n| n.bytes / 56.0);
        let cells = (segs / 64.0).clamp(64.0, f64::from(1u32 << 18));
        m.needs.push(super::kind::Need {
            bytes: segs * 4.0 * 1.5 * cells.cbrt() + cells * 24.0,
            key: "detp.photons",
            what: format!("segment index ({cells:.0} cells)"),
            // Its listings grow with the segments; its cells are capped (a batch's index is
            // sized by the batch's segments, so dividing the whole by B over-counts a batch).
            per_photon: true,
        });
        m
    }
    fn warnings(p: &QuasiStaticConfig) -> Vec<String> {
        p.warnings.clone()
    }
    /// With engine "predicted" the §4.1 predictor picks the dynamic points' engine on seconds.
    fn timed_decision(p: &QuasiStaticConfig) -> bool {
        p.engine == DynamicEngine::Predicted
    }
    fn shared(_: &[&QuasiStaticConfig]) -> Result<(), Error> {
        Ok(())
    }
    fn photon_refusal(p: &QuasiStaticConfig) -> Option<String> {
        shards::refusal(p)
    }
    fn run(
        p: &QuasiStaticConfig,
        _: &(),
        ctx: &Context,
    ) -> Result<Output<QsMeasured, QuasiStaticTables>, Error> {
        match ctx.merged {
            None => Ok(run_point(p, ctx.progress)),
            Some(parts) => merged_point(p, parts, ctx.progress),
        }
    }
    fn trace_part(
        p: &QuasiStaticConfig,
        _: &(),
        ctx: &Context,
        (k, n): (u64, u64),
    ) -> Result<serde_json::Value, Error> {
        let ids = super::detp::shards::photon_range(p.detp.photons, k, n);
        let parts: Vec<ReplicaPart> = (0..p.detp.replicas.max(1))
            .map(|r| trace_replica(p, r, ids.clone(), ctx.progress).0)
            .collect();
        serde_json::to_value(parts).map_err(Error::internal)
    }
    fn add_parts(
        _: &QuasiStaticConfig,
        a: serde_json::Value,
        b: serde_json::Value,
    ) -> Result<serde_json::Value, Error> {
        crate::experiment::photon_shards::add_following::<ReplicaPart>(a, b)
    }
}
