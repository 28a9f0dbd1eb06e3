//! Per-point path tracing in the moving scene (DETP's competitor over frames): with
//! `"path-tracing"` in `detp.engines`, each replica runs [`crate::lt::pathtrace::path_trace`] at
//! frame 0 and at every frame checked against a full recalculation (`dynamic.check_every`), on the
//! scene posed at that frame and at that frame's sample points (static points, and the dynamic
//! objects' points at their current pose), so that a frame's path-tracing cost and noise are those
//! of its own geometry. Beside DETP's incremental and full frames this gives the third cost of a
//! run of F frames at a target error: path tracing every frame from scratch.
//!
//! It runs on `detp.path_points` of the points: kind detp's keyed, nested subset
//! ([`crate::experiment::detp::path_tracing::subset`]; the point count does not change between
//! frames, so every frame traces the same points), with K = `detp.path_samples` paths per point.
//! Its streams are `[PATH_TRACE, frame_seed(seed, frame), replica, i]` ([`frame_seed`]): frames
//! and replicas draw independent numbers, none of DETP's photons', and a point's values depend on
//! neither the thread count nor the other points.
//!
//! It only reads the run's state (the posed scene and the points), after the frame's own timings
//! were taken: no DETP count, sum or second changes with it on.

use super::measure::Extras;
use super::spec::QuasiStaticConfig;
use crate::detp::quasi_static::QuasiStatic;
use crate::experiment::detp::path_tracing::subset;
use crate::lt::pathtrace::{path_trace, powers_of_two, PathTraceRun};
use crate::sample::rng::hash_key;
use crate::stats::time_to_target::PathTracingCost;
use crate::stats::{ClusteredMean, Estimate};

/// Tag of the per-frame path-tracing seed (`[seed, tag, frame]`).
const FRAME_TAG: u64 = 0x0071_745f_7061_7468; // "qt_path"

/// The seed path tracing passes to [`path_trace`] at `frame`: its streams are
/// `[PATH_TRACE, frame_seed(seed, frame), replica, i]`.
pub fn frame_seed(seed: u64, frame: u32) -> u64 {
    hash_key(&[seed, FRAME_TAG, u64::from(frame)])
}

/// What path tracing measured at one frame of one replica.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedFrame {
    /// The frame.
    pub frame: u32,
    /// Points traced.
    pub points: usize,
    /// Wall seconds per path (a timing).
    pub s_per_path: f64,
    /// √(mean_i σ_i²) / mean_i Ê_i over the points (σ_i² the per-path variance, Ê_i the K-path
    /// mean): the relative RMSE of one path per point.
    pub cv: f64,
    /// Continuation rays per path.
    pub rays_path: f64,
    /// Shadow rays per path.
    pub rays_shadow: f64,
}

impl TracedFrame {
    /// The figures of one run at `frame`.
    pub fn of(frame: u32, run: &PathTraceRun) -> Self {
        let last = run.checkpoints.len() - 1;
        let paths = run.len() as f64 * run.checkpoints[last] as f64;
        let rays = run.rays[last];
        Self {
            frame,
            points: run.len(),
            s_per_path: run.seconds_per_path(),
            cv: PathTracingCost::cv_from(&run.variance, &run.means_at(last)),
            rays_path: rays.path as f64 / paths,
            rays_shadow: rays.shadow as f64 / paths,
        }
    }
}

/// Does path tracing run at frame `f` (frame 0 and the checked frames)?
pub(super) fn traces(cfg: &QuasiStaticConfig, f: u32) -> bool {
    cfg.path_tracing() && (f == 0 || super::checked(cfg, f))
}

/// Path tracing at the run's current frame, replica `replica`.
pub fn trace_frame(cfg: &QuasiStaticConfig, qs: &QuasiStatic, replica: u64) -> TracedFrame {
    let d = &cfg.detp;
    let discs = qs.discs();
    let points = subset(d.seed, discs.len(), d.path_points);
    let at = |v: &[glam::DVec3]| points.iter().map(|&i| v[i]).collect::<Vec<_>>();
    let run = path_trace(
        &qs.scene,
        &at(&discs.centers),
        &at(&discs.normals),
        &powers_of_two(d.path_samples),
        frame_seed(d.seed, qs.frame),
        replica,
    );
    TracedFrame::of(qs.frame, &run)
}

/// Path tracing over a point's traced frames and replicas (one cluster per replica).
#[derive(Clone, Copy, Debug)]
pub struct PathTracingMeasured {
    /// Points traced per frame.
    pub points: usize,
    /// Wall seconds per path.
    pub s_per_path: Estimate,
    /// cv.
    pub cv: Estimate,
    /// Continuation rays per path, mean over the traced frames.
    pub rays_path: f64,
    /// Shadow rays per path, mean over the traced frames.
    pub rays_shadow: f64,
}

/// The replicas' traced frames pooled (`None` when path tracing is off).
pub(super) fn pool(extras: &[Extras]) -> Option<PathTracingMeasured> {
    let first = extras.iter().find_map(|e| e.path_tracing.first())?;
    let (mut s, mut cv) = (ClusteredMean::default(), ClusteredMean::default());
    let (mut rays_path, mut rays_shadow, mut n) = (0.0, 0.0, 0.0);
    for e in extras {
        for t in &e.path_tracing {
            s.push(t.s_per_path);
            cv.push(t.cv);
            rays_path += t.rays_path;
            rays_shadow += t.rays_shadow;
            n += 1.0;
        }
        s.end_batch();
        cv.end_batch();
    }
    Some(PathTracingMeasured {
        points: first.points,
        s_per_path: s.estimate(),
        cv: cv.estimate(),
        rays_path: rays_path / n,
        rays_shadow: rays_shadow / n,
    })
}
