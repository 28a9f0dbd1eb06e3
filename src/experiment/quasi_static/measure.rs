//! One quasi-static point's replicas pooled into its typed measurement: geometry, point counts and
//! the predictor's figures come from replica 0; times, the reference error and n_R are means over
//! replicas; checks are summed; the per-frame estimates were accumulated frame by frame (batches of
//! consecutive frames, or one cluster per replica, as clusters). `columns.rs` declares how each
//! value becomes a column, with the theory of Theorem 2 for the same n.

use super::spec::QuasiStaticConfig;
use super::Predictions;
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::quasi_static::{FrameStats, Prediction, QuasiStatic, Used};
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

/// What one replica's run leaves for the point's row.
pub(super) struct ReplicaRun {
    /// The run after its last frame (its scene, parameters and sums).
    pub(super) qs: QuasiStatic,
    /// Frame 0.
    pub(super) f0: FrameStats,
    /// Segments live after frame 0 (n_R).
    pub(super) n_r: f64,
    /// The predictor's run, where asked.
    pub(super) predictions: Option<Predictions>,
    /// Warm timings of both engines on every segment for the first object, round by round
    /// (`dynamic.warm_repeats`).
    pub(super) warm: Vec<[f64; 2]>,
    /// The relative RMSE of the last frame against a high-photon reference and its seconds.
    pub(super) reference: Option<(f64, f64)>,
    /// The points table's sums and discs, where asked.
    pub(super) points_at: Option<(Vec<Acc>, Discs)>,
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
    /// Against a reference run: (relative RMSE, seconds, photons), means over replicas.
    pub reference: Option<(f64, f64, u64)>,
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

/// The point's measurement from its replicas' runs and the per-frame accumulators.
pub(super) fn measure(
    cfg: &QuasiStaticConfig,
    runs: &[ReplicaRun],
    means: &[ClusteredMean],
    full_s: &ClusteredMean,
    (full_mismatch, full_checked): (u64, u64),
) -> QsMeasured {
    let mean_of =
        |f: &dyn Fn(&ReplicaRun) -> f64| runs.iter().map(f).sum::<f64>() / runs.len() as f64;
    let first = &runs[0];
    let qs = &first.qs;
    let r0 = qs.root().1;
    let (n_s, n_dyn) = qs.point_counts();
    let used: Vec<&str> = first.f0.used.iter().map(|u| u.as_str()).collect();
    QsMeasured {
        segments: first.n_r as u64,
        n_r: mean_of(&|r| r.n_r),
        points_static: n_s,
        points_dynamic: n_dyn.iter().sum(),
        ratios: qs.scene.movers.iter().map(|m| m.radius() / r0).collect(),
        r0,
        crossover: qs.params().crossover,
        engine_used: used.join("+"),
        per_frame: means.iter().map(ClusteredMean::estimate).collect(),
        full_frame_s: full_s.estimate(),
        frame0_s: mean_of(&|r| r.f0.frame_s),
        static_index_build_s: mean_of(&|r| r.qs.static_index_build_s),
        full_mismatch,
        full_checked,
        predictor: first
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
        picks: runs
            .iter()
            .filter_map(|r| r.predictions.as_ref().map(|p| p.1[0].pick))
            .collect(),
        warm: warm_seconds(runs),
        reference: first.reference.map(|_| {
            (
                mean_of(&|r| r.reference.map_or(f64::NAN, |x| x.0)),
                mean_of(&|r| r.reference.map_or(f64::NAN, |x| x.1)),
                cfg.reference_photons.unwrap_or(0),
            )
        }),
    }
}

/// Each engine's warm seconds, one cluster per replica (its rounds pooled), where any were timed.
fn warm_seconds(runs: &[ReplicaRun]) -> Option<[Estimate; 2]> {
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
/// (√(E·w̄/πd²), w̄ the mean segment power).
pub(super) fn point_rows(
    qs: &QuasiStatic,
    sums: &[Acc],
    discs: &Discs,
    frame: u32,
    n_static: usize,
) -> Vec<QsPointRow> {
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
            QsPointRow {
                sample: i,
                frame,
                dynamic: u64::from(i >= n_static),
                center: discs.centers[i],
                normal: discs.normals[i],
                irradiance: e,
                se: (e.max(0.0) * w / area).sqrt(),
            }
        })
        .collect()
}
