//! One quasi-static point's replicas pooled into its typed measurement: geometry, point counts and
//! the predictor's figures come from replica 0; times, the reference error and n_R are means over
//! replicas; checks are summed; the per-frame estimates were accumulated frame by frame (batches of
//! consecutive frames, or one cluster per replica, as clusters). `columns.rs` declares how each
//! value becomes a column, with the theory of Theorem 2 for the same n.

use super::columns as col;
use super::shards::{Facts, PointsAt, ReplicaPart};
use super::path_tracing::{self as pt, PathTracingMeasured, TracedFrame};
use super::spec::QuasiStaticConfig;
use super::Predictions;
use crate::detp::fixed::PowerScale;
use crate::detp::quasi_static::{FrameStats, Prediction, Used};
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

/// What an unsplit replica's run leaves beside its part (refused with `--photon-shard`).
#[derive(Default)]
pub(super) struct Extras {
    /// The predictor's run, where asked.
    pub(super) predictions: Option<Predictions>,
    /// Warm timings of both engines on every segment for the first object, round by round
    /// (`dynamic.warm_repeats`).
    pub(super) warm: Vec<[f64; 2]>,
    /// The relative RMSE of the last frame against a high-photon reference and its seconds.
    pub(super) reference: Option<(f64, f64)>,
    /// Path tracing at frame 0 and the checked frames, in frame order (empty when off).
    pub(super) path_tracing: Vec<TracedFrame>,
}

/// IEEE bits of three numbers (exact through JSON).
pub(super) fn f64_bits(v: [f64; 3]) -> [u64; 3] {
    v.map(f64::to_bits)
}

/// The numbers of [`f64_bits`].
pub(super) fn from_bits(b: [u64; 3]) -> [f64; 3] {
    b.map(f64::from_bits)
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

/// The per-frame accumulators over every replica's frames 1 … F − 1, in replica then frame order.
struct PerFrame {
    means: Vec<ClusteredMean>,
    full_s: ClusteredMean,
    /// (points differing, frames checked).
    full: (u64, u64),
    rows: Vec<FrameRow>,
}

/// Adds each replica's frames to the per-frame estimates (one cluster per replica when there are
/// several, batches of consecutive frames otherwise), its checks and its frames table rows.
fn per_frame(cfg: &QuasiStaticConfig, parts: &[ReplicaPart]) -> PerFrame {
    let mut acc = PerFrame {
        means: vec![ClusteredMean::default(); col::PER_FRAME_VALUES.len()],
        full_s: ClusteredMean::default(),
        full: (0, 0),
        rows: Vec::new(),
    };
    // One replica: batches of consecutive frames (correlated) are the clusters; several: each
    // replica is one cluster, so the standard error is across independent realisations.
    let b = if parts.len() > 1 {
        u32::MAX
    } else {
        batch(cfg.frames)
    };
    for (replica, part) in (0u64..).zip(parts) {
        for (f, fp) in (0u32..).zip(&part.frames) {
            let full = fp.full.as_ref().map(|c| (c.seconds, c.diffs.len() as u64));
            if f > 0 {
                for (m, (_, value)) in acc.means.iter_mut().zip(col::PER_FRAME_VALUES) {
                    m.push(value(&fp.stats));
                }
                if let Some((s, bad)) = full {
                    acc.full.0 += bad;
                    acc.full.1 += 1;
                    acc.full_s.push(s);
                }
                if f % b == 0 || f == cfg.frames - 1 {
                    acc.means.iter_mut().for_each(ClusteredMean::end_batch);
                    acc.full_s.end_batch();
                }
            }
            acc.rows.push(FrameRow {
                replica,
                stats: fp.stats.clone(),
                static_index_build_s: (f == 0).then_some(part.static_index_build_s),
                full,
                path_tracing: None,
            });
        }
    }
    acc
}

/// What one quasi-static point measured.
#[derive(Clone, Debug)]
pub struct QsMeasured {
    /// Segments after frame 0 of replica 0.
    pub segments: u64,
    /// n_R: segments after frame 0, mean over replicas.
    pub n_r: f64,
    /// Static points (n_S).
    pub points_static: usize,
    /// Dynamic points (n_D).
    pub points_dynamic: usize,
    /// Each object's r_D/r_0.
    pub ratios: Vec<f64>,
    /// r_0.
    pub r0: f64,
    /// The crossover the hybrid engine used.
    pub crossover: f64,
    /// The engine each object's points used at frame 0, joined by `+`.
    pub engine_used: String,
    /// Per-frame estimates, in [`super::columns::PER_FRAME_VALUES`] order.
    pub per_frame: Vec<Estimate>,
    /// Seconds of a full recalculation of a checked frame.
    pub full_frame_s: Estimate,
    /// Seconds of frame 0 (mean over replicas).
    pub frame0_s: f64,
    /// Seconds building the static points' index (mean over replicas).
    pub static_index_build_s: f64,
    /// Points differing from a full recalculation, over the checked frames.
    pub full_mismatch: u64,
    /// Frames checked.
    pub full_checked: u64,
    /// The predictor's figures (replica 0), where asked.
    pub predictor: Option<Predictor>,
    /// The engine the predictor picked for the first object, replica by replica.
    pub picks: Vec<Used>,
    /// Warm seconds of each engine (sphere cache, disc index) on every segment for the first
    /// object: one cluster per replica (the mean of its rounds), where timed.
    pub warm: Option<[Estimate; 2]>,
    /// Against a reference run (of `dynamic.reference_photons` photons, a parameter column
    /// already): (relative RMSE, seconds), means over replicas.
    pub reference: Option<(f64, f64)>,
    /// Per-point path tracing over the traced frames, where it ran.
    pub path_tracing: Option<PathTracingMeasured>,
}

/// The §4.1 predictor's figures for the first object, its picks counted over all objects.
#[derive(Clone, Copy, Debug)]
pub struct Predictor {
    /// The fraction of the photons it timed.
    pub fraction: f64,
    /// The first object's prediction.
    pub first: Prediction,
    /// Objects whose predicted pick was the faster engine.
    pub pick_right: usize,
    /// Objects whose Theorem 2 rule pick was the faster engine.
    pub rule_pick_right: usize,
}

impl QsMeasured {
    /// Seconds of an incremental frame (the last per-frame estimate).
    pub fn frame_s(&self) -> Estimate {
        *self
            .per_frame
            .last()
            .expect("frame_s is a per-frame metric")
    }

    /// f_R = n_R·Σ(r_D/r_0)² (eq. 11).
    pub fn f_r(&self) -> f64 {
        self.ratios
            .iter()
            .map(|&r| th::retraced_rays(self.n_r, r))
            .sum()
    }

    /// full_frame_s / frame_s.
    pub fn speedup(&self) -> f64 {
        self.full_frame_s.mean / self.frame_s().mean
    }
}

/// One row of `NAME.frames.csv`.
#[derive(Clone, Debug)]
pub struct FrameRow {
    /// The replica.
    pub replica: u64,
    /// The frame's counts and seconds.
    pub stats: FrameStats,
    /// Frame 0's row: the seconds this replica spent building the static points' index (an
    /// amortisation needs each replica's build, not only their mean).
    pub static_index_build_s: Option<f64>,
    /// A checked frame: (seconds of the full recalculation, points differing).
    pub full: Option<(f64, u64)>,
    /// Path tracing at this frame, where it ran.
    pub path_tracing: Option<TracedFrame>,
}

/// One row of the quasi-static `NAME.points.csv`: the irradiance at one point at one frame.
#[derive(Clone, Debug)]
pub struct QsPointRow {
    /// The sample's index.
    pub sample: usize,
    /// The frame.
    pub frame: u32,
    /// 1 on a dynamic object.
    pub dynamic: u64,
    /// Position.
    pub center: glam::DVec3,
    /// Normal.
    pub normal: glam::DVec3,
    /// Irradiance.
    pub irradiance: f64,
    /// Its Poisson standard error.
    pub se: f64,
}

/// The point's measurement and its frames table from its replicas' parts.
pub(super) fn measure(
    cfg: &QuasiStaticConfig,
    parts: &[ReplicaPart],
    extras: &[Extras],
) -> (QsMeasured, Vec<FrameRow>) {
    let mut acc = per_frame(cfg, parts);
    for row in &mut acc.rows {
        row.path_tracing = extras
            .get(row.replica as usize)
            .and_then(|e| e.path_tracing.iter().find(|t| t.frame == row.stats.frame))
            .copied();
    }
    let mean_of =
        |f: &dyn Fn(&ReplicaPart) -> f64| parts.iter().map(f).sum::<f64>() / parts.len() as f64;
    let first = &parts[0];
    let facts = &first.facts;
    let used: Vec<&str> = first.frames[0].stats.used.iter().map(|u| u.as_str()).collect();
    let reference = |r: &Extras| r.reference;
    let m = QsMeasured {
        segments: first.n_r,
        n_r: mean_of(&|r| r.n_r as f64),
        points_static: facts.points_static as usize,
        points_dynamic: facts.points_dynamic.iter().sum::<u64>() as usize,
        ratios: facts.ratios.iter().map(|&b| f64::from_bits(b)).collect(),
        r0: f64::from_bits(facts.r0),
        crossover: f64::from_bits(facts.crossover),
        engine_used: used.join("+"),
        per_frame: acc.means.iter().map(ClusteredMean::estimate).collect(),
        full_frame_s: acc.full_s.estimate(),
        frame0_s: mean_of(&|r| r.frames[0].stats.frame_s),
        static_index_build_s: mean_of(&|r| r.static_index_build_s),
        full_mismatch: acc.full.0,
        full_checked: acc.full.1,
        predictor: extras[0]
            .predictions
            .as_ref()
            .map(|(fraction, preds, rule)| Predictor {
                fraction: *fraction,
                first: preds[0],
                pick_right: preds.iter().filter(|p| p.pick == p.best).count(),
                rule_pick_right: preds
                    .iter()
                    .zip(rule)
                    .filter(|(p, r)| p.best == **r)
                    .count(),
            }),
        picks: extras
            .iter()
            .filter_map(|r| r.predictions.as_ref().map(|p| p.1[0].pick))
            .collect(),
        warm: warm_seconds(extras),
        reference: reference(&extras[0]).map(|_| {
            let of = |i: usize| {
                extras.iter().map(|e| reference(e).map_or(f64::NAN, |x| [x.0, x.1][i]))
                    .sum::<f64>()
                    / extras.len() as f64
            };
            (of(0), of(1))
        }),
        path_tracing: pt::pool(extras),
    };
    (m, acc.rows)
}

/// Each engine's warm seconds, one cluster per replica (its rounds pooled), where any were timed.
fn warm_seconds(runs: &[Extras]) -> Option<[Estimate; 2]> {
    if runs.iter().all(|r| r.warm.is_empty()) {
        return None;
    }
    Some([0, 1].map(|e| {
        let mut m = ClusteredMean::default();
        for r in runs {
            r.warm.iter().for_each(|w| m.push(w[e]));
            m.end_batch();
        }
        m.estimate()
    }))
}

/// The irradiance at every sample point at one frame, with its Poisson standard error
/// (√(E·w̄/πd²), w̄ the mean power of the frame's live segments, from their exact integer sum).
pub(super) fn point_rows(
    cfg: &QuasiStaticConfig,
    facts: &Facts,
    at: &PointsAt,
    n_static: usize,
) -> Vec<QsPointRow> {
    let d = cfg.detp.disc_radius;
    let area = std::f64::consts::PI * d * d;
    let scale = PowerScale {
        watts_per_unit: f64::from_bits(facts.scale),
    };
    let w = if at.live_segments == 0 {
        0.0
    } else {
        let units = at.power_units().expect("parts are checked when they are added");
        units as f64 * scale.watts_per_unit / at.live_segments as f64
    };
    let (centers, normals) = at.discs();
    (0..at.sums.len())
        .map(|i| {
            let e = scale.watts(at.sums[i]) / area;
            QsPointRow {
                sample: i,
                frame: at.frame,
                dynamic: u64::from(i >= n_static),
                center: centers[i],
                normal: normals[i],
                irradiance: e,
                se: (e.max(0.0) * w / area).sqrt(),
            }
        })
        .collect()
}
