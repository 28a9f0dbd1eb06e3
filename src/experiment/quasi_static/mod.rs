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
//! A point's run leaves a typed measurement ([`QsMeasured`], `measure.rs`), its frames and points
//! rows; `columns.rs` declares every column with the accessor that reads it.
//!
//! `raycost render` and `raycost bench` use [`QuasiStaticConfig`] (a validated point), [`start`],
//! [`params`] and [`apply_ratio`]; the DETP settings inside come from the DETP module's interface
//! ([`super::detp`]).

pub mod columns;
pub mod measure;
pub mod spec;

use self::columns as col;
use self::measure::{FrameRow, QsMeasured, QsPointRow, ReplicaRun};
use self::spec::QuasiStaticSpec;
use super::detp::DynamicEngine;
use super::inputs::Inputs;
use super::kind::{Check, ConfigError, Context, Kind, Memory, Output, Rate, Table, Work};
use crate::detp::quasi_static::{mismatches, Engine, FrameStats, Params, QuasiStatic, Used};
use crate::error::Error;
use crate::stats::ClusteredMean;
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
pub(super) type Predictions = (f64, Vec<crate::detp::quasi_static::Prediction>, Vec<Used>);

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
    frames: &mut Vec<FrameRow>,
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
    let warm = if predictions.is_some() && !qs.scene.movers.is_empty() {
        qs.warm_timings(0, cfg.warm_repeats)
    } else {
        Vec::new()
    };
    let n_r = qs.live_segments() as f64;
    // One replica: batches of consecutive frames (correlated) are the clusters; several: each
    // replica is one cluster, so the standard error is across independent realisations.
    let b = if replicas > 1 {
        u32::MAX
    } else {
        batch(cfg.frames)
    };
    frames.push(FrameRow {
        replica,
        stats: f0.clone(),
        static_index_build_s: Some(qs.static_index_build_s),
        full: None,
    });
    let points_frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
    let write_points = cfg.detp.write_points && replica == 0;
    let mut points_at = (points_frame == 0 && write_points).then(|| (qs.sums(), qs.discs()));
    for f in 1..cfg.frames {
        let st = qs.step(f);
        progress(cfg.detp.photons);
        for (m, (_, value)) in means.iter_mut().zip(col::PER_FRAME_VALUES) {
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
        frames.push(FrameRow {
            replica,
            stats: st,
            static_index_build_s: None,
            full: checked,
        });
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
        warm,
        reference,
        points_at,
    }
}

/// One quasi-static point: `detp.replicas` independent runs of every frame (new photons each),
/// pooled (see [`measure::measure`]).
pub fn run_point(
    cfg: &QuasiStaticConfig,
    progress: &(dyn Fn(u64) + Sync),
) -> Output<QsMeasured, QuasiStaticTables> {
    let replicas = cfg.detp.replicas.max(1);
    let mut means = vec![ClusteredMean::default(); col::PER_FRAME_VALUES.len()];
    let mut full_s = ClusteredMean::default();
    let mut full = (0u64, 0u64);
    let mut frames = Vec::new();
    let runs: Vec<ReplicaRun> = (0..replicas)
        .map(|r| {
            run_replica(
                cfg,
                r,
                progress,
                &mut means,
                &mut full_s,
                &mut full,
                &mut frames,
            )
        })
        .collect();
    let m = measure::measure(cfg, &runs, &means, &full_s, full);
    let points = runs[0]
        .points_at
        .as_ref()
        .map_or_else(Vec::new, |(sums, discs)| {
            let frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
            measure::point_rows(&runs[0].qs, sums, discs, frame, m.points_static)
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
    const ABOUT: &'static str = "A scene whose dynamic objects move over F frames: frame 0 is a full DETP photon trace and gather; every later frame re-traces only the photons whose segments meet an object at its old or new pose (against f_R = n_R·Σ(r_D/r_0)²), updates the static points' sums and gathers the dynamic objects' points with the sphere cache or the disc index (Theorem 2's crossover r_D/r_0 ≈ 0.35, or a timed predictor). Frames are checked against a full recalculation, bit for bit.";
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
    fn photon_refusal(_: &QuasiStaticConfig) -> Option<String> {
        Some("kind quasi-static cannot split its photons: its per-frame counts do not add across photon shards (the segment index is sized by the frame's segments, the sphere cache subdivides by the rays a sphere holds); split its sweep points with --shard instead".into())
    }
    fn run(
        p: &QuasiStaticConfig,
        _: &(),
        ctx: &Context,
    ) -> Result<Output<QsMeasured, QuasiStaticTables>, Error> {
        Ok(run_point(p, ctx.progress))
    }
}
