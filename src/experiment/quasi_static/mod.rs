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
//! `dynamic.feed` choices in `docs/detp-costs.md`), each phase's seconds,
//! `frame_s` and `full_frame_s`; the theory of Theorem 2 for the same n: the static points' costs
//! (2 vs 8.08·t·f_R·∛n_S) and the dynamic points' (sphere cache vs disc index). Side tables: `frames`
//! (one row per frame) and, with `detp.write_points`, `points` (the irradiance at one frame).
//! Every column is declared in `columns.rs`.

pub mod columns;
pub mod spec;

use self::columns as col;
use self::spec::{QuasiStaticConfig, QuasiStaticSpec};
use super::detp::spec::DynamicEngine;
use super::inputs::Inputs;
use super::kind::{Check, ConfigError, Context, Kind, Memory, PointOutput, Rate, Work};
use super::metric::{Metric, Theory};
use crate::detp::fixed::Acc;
use crate::detp::quasi_static::{mismatches, Engine, FrameStats, Params, QuasiStatic, Used};
use crate::error::Error;
use crate::output::column::Column;
use crate::output::row::{Row, Value};
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

pub use self::spec::apply_ratio;

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
    QuasiStatic::start(cfg.scene.clone(), params(cfg, n_d, replica))
}

/// Frames per cluster of the per-frame estimates: 16 batches of consecutive frames (or one frame
/// each when there are fewer than 32).
fn batch(frames: u32) -> u32 {
    if frames <= 32 {
        1
    } else {
        (frames - 1).div_ceil(16)
    }
}

/// The predictor's run (engine "predicted" or `dynamic.predict`): its fraction, its predictions per
/// object, and the engine Theorem 2's rule would have picked per object.
type Predictions = (f64, Vec<crate::detp::quasi_static::Prediction>, Vec<Used>);

/// What one replica's run leaves for the point's row.
struct ReplicaRun {
    /// The run after its last frame (its scene, parameters and sums).
    qs: QuasiStatic,
    /// Frame 0.
    f0: FrameStats,
    /// Segments live after frame 0 (n_R).
    n_r: f64,
    /// The predictor's run, where asked.
    predictions: Option<Predictions>,
    /// The relative RMSE of the last frame against a high-photon reference and its seconds.
    reference: Option<(f64, f64)>,
    /// The points table's sums and discs, where asked.
    points_at: Option<(Vec<Acc>, crate::detp::disc::Discs)>,
}

/// Runs every frame of one replica, adding its per-frame values to `means` (one cluster per
/// replica when there are several, batches of consecutive frames otherwise), its checks to
/// `full_*`, and its frames to the frames table.
#[allow(clippy::too_many_arguments)]
fn run_replica(
    cfg: &QuasiStaticConfig,
    replica: u64,
    progress: &(dyn Fn(u64) + Sync),
    means: &mut [ClusteredMean],
    full_s: &mut ClusteredMean,
    full: &mut (u64, u64),
    tables: &mut QuasiStaticTables,
) -> ReplicaRun {
    let replicas = cfg.detp.replicas.max(1);
    let (mut qs, f0) = start(cfg, replica);
    progress(cfg.detp.photons);
    let predictions: Option<Predictions> = cfg.predict.map(|fraction| {
        let rule: Vec<Used> = (0..qs.scene.movers.len())
            .map(|m| qs.rule_engine(m))
            .collect();
        let p = qs.predict_and_pick(fraction, cfg.engine == DynamicEngine::Predicted);
        (fraction, p, rule)
    });
    let n_r = qs.live_segments() as f64;
    // One replica: batches of consecutive frames (correlated) are the clusters; several: each
    // replica is one cluster, so the standard error is across independent realisations.
    let b = if replicas > 1 {
        u32::MAX
    } else {
        batch(cfg.frames)
    };
    tables.frames.push(frame_row(replica, &f0, None));
    let points_frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
    let write_points = cfg.detp.write_points && replica == 0;
    let mut points_at = (points_frame == 0 && write_points).then(|| (qs.sums(), qs.discs()));
    for f in 1..cfg.frames {
        let st = qs.step(f);
        progress(cfg.detp.photons);
        for (m, (_, value)) in means.iter_mut().zip(col::PER_FRAME) {
            m.push(value(&st));
        }
        let check =
            cfg.check_every > 0 && (u64::from(f) % cfg.check_every == 0 || f == cfg.frames - 1);
        let checked = check.then(|| {
            let (sums, _, s) = qs.full_recalculation();
            let bad = mismatches(&qs.sums(), &sums);
            full.0 += bad;
            full.1 += 1;
            full_s.push(s);
            (s, bad)
        });
        if f % b == 0 || f == cfg.frames - 1 {
            means.iter_mut().for_each(ClusteredMean::end_batch);
            full_s.end_batch();
        }
        tables.frames.push(frame_row(replica, &st, checked));
        if f == points_frame && write_points {
            points_at = Some((qs.sums(), qs.discs()));
        }
    }
    // Error of the last frame against a high-photon reference (relative RMSE over the points; the
    // reference's own noise is part of it, a floor of about 1/√(crossings per disc) of the reference).
    let reference = cfg.reference_photons.map(|n| {
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
    });
    ReplicaRun {
        qs,
        f0,
        n_r,
        predictions,
        reference,
        points_at,
    }
}

/// One quasi-static point: `detp.replicas` independent runs of every frame (new photons each),
/// pooled. Geometry, point counts and the predictor's figures come from replica 0; times, the
/// reference error and n_R are means over replicas; checks are summed.
pub fn run_point(
    cfg: &QuasiStaticConfig,
    progress: &(dyn Fn(u64) + Sync),
) -> PointOutput<QuasiStaticTables> {
    let replicas = cfg.detp.replicas.max(1);
    let mut means = vec![ClusteredMean::default(); col::PER_FRAME.len()];
    let mut full_s = ClusteredMean::default();
    let mut full = (0u64, 0u64);
    let mut tables = QuasiStaticTables::default();
    let runs: Vec<ReplicaRun> = (0..replicas)
        .map(|r| {
            run_replica(
                cfg,
                r,
                progress,
                &mut means,
                &mut full_s,
                &mut full,
                &mut tables,
            )
        })
        .collect();
    let (full_mismatch, full_checked) = full;
    let mean_of =
        |f: &dyn Fn(&ReplicaRun) -> f64| runs.iter().map(f).sum::<f64>() / runs.len() as f64;
    let n_r = mean_of(&|r| r.n_r);
    let frame0_s = mean_of(&|r| r.f0.frame_s);
    let build_s = mean_of(&|r| r.qs.static_index_build_s);
    let reference = runs[0].reference.map(|_| {
        (
            mean_of(&|r| r.reference.map_or(f64::NAN, |x| x.0)),
            mean_of(&|r| r.reference.map_or(f64::NAN, |x| x.1)),
            cfg.reference_photons.unwrap_or(0),
        )
    });
    let first = &runs[0];
    let (qs, f0, predictions) = (&first.qs, &first.f0, &first.predictions);
    let r0 = qs.root().1;
    let ratios: Vec<f64> = qs.scene.movers.iter().map(|m| m.radius() / r0).collect();
    let f_r: f64 = ratios.iter().map(|&r| th::retraced_rays(n_r, r)).sum();
    let (n_s, n_dyn) = qs.point_counts();
    let n_d: usize = n_dyn.iter().sum();
    let est: Vec<Estimate> = means.iter().map(ClusteredMean::estimate).collect();
    let frame_s = est[col::PER_FRAME.len() - 1];

    let mut row = Row::default();
    let used: Vec<&str> = f0.used.iter().map(|u| u.as_str()).collect();
    row.put(&col::FRAMES, u64::from(cfg.frames))
        .put(&col::PHOTONS, cfg.detp.photons)
        .put(&col::SEGMENTS, first.n_r as u64)
        .put(&col::POINTS_STATIC, n_s)
        .put(&col::POINTS_DYNAMIC, n_d)
        .put(&col::OBJECTS, ratios.len())
        .put(&col::R0, r0)
        .put(&col::RATIO, ratios.iter().copied().fold(0.0, f64::max))
        .put(&col::CROSSOVER, qs.params().crossover)
        .put(&col::ENGINE_USED, used.join("+"))
        .put(&col::WARNINGS, cfg.warnings.len());
    let mut summary = Vec::new();
    for ((c, _), e) in col::PER_FRAME.iter().zip(&est) {
        if c.shape == crate::output::column::Shape::EstimateVsPrediction {
            // Both retrace counts are held against f_R.
            Metric::new(c, *e, Theory::Prediction(f_r)).write(&mut row, &mut summary);
        } else {
            row.put_estimate(c, e);
        }
    }
    let full = full_s.estimate();
    row.put_estimate(&col::FULL_FRAME_S, &full)
        .put(&col::FRAME0_S, frame0_s)
        .put(&col::STATIC_INDEX_BUILD_S, build_s)
        .put(&col::SPEEDUP, full.mean / frame_s.mean)
        .put(&col::FULL_MISMATCH, full_mismatch)
        .put(&col::FULL_CHECKED, full_checked);
    if let Some((fraction, preds, rule)) = predictions {
        // The first object's figures; picks are counted over all objects.
        let p = preds[0];
        let engines = ["sphere_cache", "disc_index"];
        row.put(&col::PREDICT_FRACTION, *fraction);
        for (i, e) in engines.iter().enumerate() {
            row.put_member(&col::PREDICTED_S, e, p.predicted[i]);
        }
        for (i, e) in engines.iter().enumerate() {
            row.put_member(&col::MEASURED_S, e, p.measured[i]);
        }
        for (i, e) in engines.iter().enumerate() {
            row.put_member(
                &col::PREDICTION_ERROR,
                e,
                p.predicted[i] / p.measured[i] - 1.0,
            );
        }
        row.put(&col::TIMED_PICK, p.pick.as_str())
            .put(&col::TIMED_BEST_ENGINE, p.best.as_str())
            .put(
                &col::TIMED_PICK_RIGHT,
                preds.iter().filter(|p| p.pick == p.best).count(),
            )
            .put(
                &col::TIMED_RULE_PICK_RIGHT,
                preds
                    .iter()
                    .zip(rule)
                    .filter(|(p, r)| p.best == **r)
                    .count(),
            );
    }
    if let Some((rmse, ref_s, n)) = reference {
        row.put(&col::IRRADIANCE_RMSE, rmse)
            .put(&col::REFERENCE_PHOTONS, n)
            .put(&col::REFERENCE_S, ref_s);
    }
    // Theorem 2 for this run's n (costs in ray tests, t = u).
    let q = cfg.detp.q();
    let (sc_static, di_static) = th::static_points_cost(f_r, n_s as f64, q);
    let (sc_dyn, di_dyn) =
        th::dynamic_points_cost(n_r, ratios.first().copied().unwrap_or(0.0), n_d as f64, q);
    row.put_member(&col::STATIC_TESTS_THEORY, "sphere_cache", sc_static)
        .put_member(&col::STATIC_TESTS_THEORY, "disc_index", di_static)
        .put_member(&col::DYNAMIC_TESTS_THEORY, "sphere_cache", sc_dyn)
        .put_member(&col::DYNAMIC_TESTS_THEORY, "disc_index", di_dyn)
        .put(
            &col::CROSSOVER_THEORY,
            th::crossover_ratio(q, n_d.max(1) as f64),
        );
    summary.push((
        "speedup".into(),
        Estimate {
            mean: full.mean / frame_s.mean,
            se: f64::NAN,
            n: full_checked,
            clusters: 1,
        },
        "full_frame_s / frame_s".into(),
        format!("{:.1}× faster", full.mean / frame_s.mean),
    ));
    if let Some((sums, discs)) = &first.points_at {
        let frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
        tables.points = points_table(qs, sums, discs, frame, n_s);
    }
    if cfg.engine == DynamicEngine::Predicted {
        row.decided_by_timing(col::decided_by_the_pick);
        for r in &mut tables.frames {
            r.decided_by_timing(col::decided_by_the_pick);
        }
    }
    PointOutput {
        row,
        tables,
        summary,
        checks: vec![Check {
            name: col::FULL_MISMATCH.name,
            what: "points where an incremental frame differs from its full recalculation",
            failures: full_mismatch,
            checked: full_checked,
        }],
        rate: Rate {
            per_s: est[3].mean / frame_s.mean.max(1e-12),
            unit: "segments",
        },
        // Its scene warnings are known before running (`Kind::warnings`).
        warnings: Vec::new(),
    }
}

/// One row of the frames table.
fn frame_row(replica: u64, st: &FrameStats, full: Option<(f64, u64)>) -> Row {
    use col::frame as c;
    let mut r = Row::default();
    let used: Vec<&str> = st.used.iter().map(|u| u.as_str()).collect();
    r.put(&col::REPLICA, replica)
        .put(&col::FRAME, st.frame)
        .put(&c::RETRACED_RAYS, st.affected_segments)
        .put(&c::RAYS_MEETING_OBJECT, st.meeting_new)
        .put(&c::PHOTONS_RETRACED, st.photons_retraced)
        .put(&col::SEGMENTS_REMOVED, st.segments_removed)
        .put(&col::SEGMENTS_ADDED, st.segments_added)
        .put(&c::SEGMENTS_RETRACED, st.segments_retraced)
        .put(&c::SEARCH_CELLS, st.search.cells)
        .put(&col::SEARCH_LISTINGS, st.search.listings)
        .put(&c::SEARCH_TESTS, st.search.tested)
        .put(&col::STATIC_DISC_TESTS, st.static_disc_tests)
        .put(&col::STATIC_SPHERE_TESTS, st.static_sphere_tests)
        .put(&col::DYNAMIC_DISC_TESTS, st.dynamic_disc_tests)
        .put(&c::DYNAMIC_SPHERE_TESTS, st.dynamic_sphere_tests)
        .put(&c::STATIC_TRAVERSAL, st.static_traversal)
        .put(&c::STATIC_RAYS_COPIED, st.static_rays_copied)
        .put(&c::STATIC_COUNTED_COST, st.static_counted_cost())
        .put(&c::DYNAMIC_TRAVERSAL, st.dynamic_traversal)
        .put(&c::DYNAMIC_RAYS_COPIED, st.dynamic_rays_copied)
        .put(&c::DYNAMIC_SPHERES_BUILT, st.dynamic_spheres_built)
        .put(&c::DYNAMIC_FEED, st.dynamic_feed)
        .put(&c::DYNAMIC_COUNTED_COST, st.dynamic_counted_cost())
        .put(&col::ENGINE_USED, used.join("+"))
        .put(&c::SEARCH_S, st.search_s)
        .put(&c::RETRACE_S, st.retrace_s)
        .put(&c::STATIC_S, st.static_s)
        .put(&c::DYNAMIC_S, st.dynamic_s)
        .put(&c::FRAME_S, st.frame_s)
        .put(&c::FULL_FRAME_S, full.map_or(f64::NAN, |f| f.0))
        .put(
            &c::FULL_MISMATCH,
            full.map_or(Value::missing(), |f| Value::U(f.1)),
        );
    r
}

/// The irradiance at every sample point at one frame, with its Poisson standard error
/// (√(E·w̄/πd²), w̄ the mean segment power).
fn points_table(
    qs: &QuasiStatic,
    sums: &[Acc],
    discs: &crate::detp::disc::Discs,
    frame: u32,
    n_static: usize,
) -> Vec<Row> {
    use crate::experiment::detp::columns as dc;
    let d = qs.params().disc_radius;
    let area = std::f64::consts::PI * d * d;
    let scale = qs.scale();
    let store = qs.live_store();
    let w = if store.is_empty() {
        0.0
    } else {
        store
            .segments
            .iter()
            .map(|s| scale.watts(Acc::from(s.power)))
            .sum::<f64>()
            / store.len() as f64
    };
    (0..discs.len())
        .map(|i| {
            let e = scale.watts(sums[i]) / area;
            let (c, n) = (discs.centers[i], discs.normals[i]);
            let mut r = Row::default();
            r.put(&dc::SAMPLE, i)
                .put(&col::FRAME, frame)
                .put(&col::DYNAMIC, u64::from(i >= n_static))
                .put(&dc::X, c.x)
                .put(&dc::Y, c.y)
                .put(&dc::Z, c.z)
                .put(&dc::NX, n.x)
                .put(&dc::NY, n.y)
                .put(&dc::NZ, n.z)
                .put(&col::POINT_IRRADIANCE, e)
                .put(&col::POINT_IRRADIANCE_SE, (e.max(0.0) * w / area).sqrt());
            r
        })
        .collect()
}

crate::side_tables!(
    /// `NAME.frames.csv` (one row per frame) and, with `detp.write_points`, `NAME.points.csv` (the
    /// irradiance at one frame).
    QuasiStaticTables { frames, points }
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
    const ABOUT: &'static str = "A scene whose dynamic objects move over F frames: frame 0 is a full DETP photon trace and gather; every later frame re-traces only the photons whose segments meet an object at its old or new pose (against f_R = n_R·Σ(r_D/r_0)²), updates the static points' sums and gathers the dynamic objects' points with the sphere cache or the disc index (Theorem 2's crossover r_D/r_0 ≈ 0.35, or a timed predictor). Frames are checked against a full recalculation, bit for bit.";
    type Raw = QuasiStaticSpec;
    type Point = QuasiStaticConfig;
    type Tables = QuasiStaticTables;
    type Shared = ();

    fn columns() -> Vec<(&'static str, &'static [Column])> {
        vec![
            ("main", col::MAIN),
            ("frames", col::FRAMES_TABLE),
            ("points", col::POINTS_TABLE),
        ]
    }
    fn configure(
        raw: QuasiStaticSpec,
        inputs: &mut Inputs,
    ) -> Result<QuasiStaticConfig, ConfigError> {
        QuasiStaticConfig::from_raw(&raw, inputs)
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
    fn memory(p: &QuasiStaticConfig) -> Memory {
        let mut m = super::detp::memory(&p.detp);
        let segs = m.needs.first().map_or(0.0, |n| n.bytes / 56.0);
        let cells = (segs / 64.0).clamp(64.0, f64::from(1u32 << 18));
        m.needs.push(super::kind::Need {
            bytes: segs * 4.0 * 1.5 * cells.cbrt() + cells * 24.0,
            key: "detp.photons",
            what: format!("segment index ({cells:.0} cells)"),
        });
        m
    }
    fn warnings(p: &QuasiStaticConfig) -> Vec<String> {
        p.warnings.clone()
    }
    fn shared(_: &[&QuasiStaticConfig]) -> Result<(), Error> {
        Ok(())
    }
    fn run(
        p: &QuasiStaticConfig,
        _: &(),
        ctx: &Context,
    ) -> Result<PointOutput<QuasiStaticTables>, Error> {
        Ok(run_point(p, ctx.progress))
    }
}
