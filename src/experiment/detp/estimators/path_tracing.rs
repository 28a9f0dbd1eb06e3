//! Estimator `path-tracing`: per-point path tracing with next-event estimation as DETP's competitor
//! ("which method when"), [`crate::lt::pathtrace`] run on its own streams (`[PATH_TRACE, seed, replica, i]`,
//! i the point's place in the subset it runs on), so it shares no random number with the
//! reference it is judged against.
//!
//! One run of K = `detp.path_samples` paths per point gives the running mean at every checkpoint
//! 1, 2, 4, …, K: the whole error-against-seconds front of the competitor from one run. It runs on
//! `detp.path_points` of the points (the first of a keyed permutation of the point set, so a
//! larger subset holds a smaller one), since its cost and error are per point. Unlike the
//! reference it is not cached across sweep points: every sweep point with these points draws the
//! same samples (common random numbers, the same streams) but times them itself, so each row's
//! `path_tracing_s_per_path` is its own measurement.
//!
//! What it writes: the main table's group (seconds, rays, cv, the points it ran on), its errors
//! against the reference as every baseline's (`path_tracing_ref_*`), one row per replica and
//! checkpoint in `NAME.path_tracing.csv` ([`PathRow`], per replica so that an analysis can
//! bootstrap over replicas), and in the points table its running means and per-path variance.

use std::sync::Arc;

use glam::DVec3;
use rand::seq::SliceRandom;

use super::{Crossover, Estimator, Role, Shards};
use crate::output::column::{Class, Column};
use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    per_replica, Engine, EngineMeasured, EnginePart, Output, Pooled,
    ReferenceCache,
};
use crate::experiment::detp::spec::RawDetp;
use crate::experiment::detp::{PointSet, RaySet};
use crate::experiment::kind::{refuse, ConfigError};
use crate::output::table::{col, Table};
use crate::lt::pathtrace::{path_trace, powers_of_two, PathTraceRun};
use crate::sample::rng::{domain, stream};
use crate::stats::time_to_target::PathTracingCost;

/// Tag of the stream that permutes the points for `detp.path_points` (`[POINTS, seed, tag, n]`:
/// no sweep point has this index, so it draws no other stream's numbers).
const SUBSET_TAG: u64 = 0x7061_7468_5f70_7473;

/// The points the competitor runs on: all `n` (in order), or the first `m` of a keyed permutation
/// of `0..n`, sorted. The permutation does not depend on `m`, so the subsets are nested.
pub fn subset(seed: u64, n: usize, m: Option<u64>) -> Vec<usize> {
    let mut all: Vec<usize> = (0..n).collect();
    match m {
        Some(m) if (m as usize) < n => {
            all.shuffle(&mut stream(&[domain::POINTS, seed, SUBSET_TAG, n as u64]));
            let mut s = all[..m as usize].to_vec();
            s.sort_unstable();
            s
        }
        _ => all,
    }
}

/// One replica's competitor run.
pub struct PathTraced {
    /// The points (indices into the point set) it ran on, increasing.
    pub subset: Vec<usize>,
    /// What it measured on them, in subset order.
    pub run: PathTraceRun,
}

/// Estimator `path-tracing`.
pub struct PathTracing;

impl Estimator for PathTracing {
    const NAME: &'static str = "path-tracing";
    const COLUMN: &'static str = "path_tracing";
    const ROLE: Role = Role::Baseline;
    const CROSSOVER: Option<Crossover> = Some(Crossover::PathTracing);
    const SHARDS: Shards = Shards::Skip;
    type Measured = PathMeasured;
    const COLUMNS: Table<DetpConfig, PathMeasured> = Table::of(&[
        col(&COST_S, |_, e| e.seconds.into()),
        col(&BUILD_S, |_, _| 0.0.into()),
        col(&PATH_TRACING_POINTS, |_, e| e.points.into()),
        col(&PATH_TRACING_CV, |_, e| e.cv.into()),
        col(&PATH_TRACING_CV_PREFIX, |_, e| e.cv_prefix.into()),
        col(&PATH_TRACING_RAYS_PATH, |_, e| e.rays_path.into()),
        col(&PATH_TRACING_RAYS_SHADOW, |_, e| e.rays_shadow.into()),
        col(&PATH_TRACING_S_PER_PATH, |_, e| e.s_per_path.into()),
    ]);
    fn check(_d: &RawDetp, lines: bool) -> Result<(), ConfigError> {
        if lines {
            return refuse(
                "detp.engines",
                "\"path-tracing\" path-traces a scene's lights and surfaces: it needs detp.source = \"scene\"",
            );
        }
        Ok(())
    }
    fn engine(_: &ReferenceCache) -> Box<dyn Engine> {
        Box::new(Runs::new())
    }
}

/// The competitor over a point's replicas.
pub(crate) struct Runs {
    /// One run per replica, in replica order.
    runs: Vec<Arc<PathTraced>>,
}

impl Runs {
    /// A competitor with no replica run yet.
    fn new() -> Self {
        Self { runs: Vec::new() }
    }

    /// The next replica's run (replicas come in order), computed afresh at every sweep point:
    /// its values are a pure function of (scene, points, seed, K, replica) and repeat bit for bit
    /// wherever the point set repeats, but its seconds are this row's own, so an n_P sweep has
    /// one path-tracing timing per row and replica (a crossover resamples them), not one per
    /// point set copied to every row that shares it.
    fn compute(&mut self, cfg: &DetpConfig, pts: &PointSet) {
        let replica = self.runs.len() as u64;
        let Some(scene) = cfg.scene() else {
            unreachable!("configure refuses path-tracing without a scene")
        };
        let discs = &pts.discs;
        let subset = subset(cfg.seed, discs.len(), cfg.path_points);
        let at = |v: &[DVec3]| subset.iter().map(|&i| v[i]).collect::<Vec<_>>();
        let run = path_trace(
            &scene.scene,
            &at(&discs.centers),
            &at(&discs.normals),
            &powers_of_two(cfg.path_samples),
            cfg.seed,
            replica,
        );
        self.runs.push(Arc::new(PathTraced { subset, run }));
    }

    /// The runs, one per replica.
    pub(in crate::experiment::detp) fn runs(&self) -> &[Arc<PathTraced>] {
        &self.runs
    }

    /// Per point of the subset (in its order): the running mean at each checkpoint and the per-path
    /// variance, each the mean over replicas.
    pub(in crate::experiment::detp) fn point_means(&self) -> Vec<(Vec<f64>, f64)> {
        let Some(first) = self.runs.first() else {
            return Vec::new();
        };
        let reps = self.runs.len() as f64;
        let nc = first.run.checkpoints.len();
        (0..first.subset.len())
            .map(|j| {
                let means = (0..nc)
                    .map(|c| self.runs.iter().map(|r| r.run.mean(j, c)).sum::<f64>() / reps)
                    .collect();
                let var = self.runs.iter().map(|r| r.run.variance[j]).sum::<f64>() / reps;
                (means, var)
            })
            .collect()
    }

    /// The side table's rows: per replica and checkpoint, rays, seconds and errors against the
    /// reference (NaN without one).
    fn rows(&self, refr: Option<&[(f64, f64)]>) -> Vec<PathRow> {
        let mut rows = Vec::new();
        for (replica, r) in self.runs.iter().enumerate() {
            let run = &r.run;
            let m = r.subset.len().max(1) as f64;
            let variance_mean = run.variance.iter().sum::<f64>() / m;
            for (c, &paths) in run.checkpoints.iter().enumerate() {
                // The truth's mean over the replica's points, summed in point order as the
                // crossover sums it from a points table.
                let ref_mean = refr.map_or(f64::NAN, |refr| {
                    r.subset.iter().map(|&i| refr[i].0).sum::<f64>() / m
                });
                let (ref_mse, ref_bias) = refr.map_or((f64::NAN, f64::NAN), |refr| {
                    let (mut se, mut b) = (0.0, 0.0);
                    for (j, &i) in r.subset.iter().enumerate() {
                        let d = run.mean(j, c) - refr[i].0;
                        se += d * d - refr[i].1 * refr[i].1;
                        b += d;
                    }
                    (se / m, b / m)
                });
                rows.push(PathRow {
                    replica: replica as u64,
                    paths,
                    rays_path: run.rays[c].path,
                    rays_shadow: run.rays[c].shadow,
                    seconds_s: run.seconds[c],
                    thread_s: run.thread_s[c],
                    ref_mse,
                    ref_bias,
                    ref_mean,
                    variance_mean,
                });
            }
        }
        rows
    }
}

/// One row of `NAME.path_tracing.csv`: one replica at one checkpoint.
#[derive(Clone, Debug, PartialEq)]
pub struct PathRow {
    /// Replica.
    pub replica: u64,
    /// Paths per point.
    pub paths: u64,
    /// Continuation rays of the first `paths` paths of every point.
    pub rays_path: u64,
    /// Their shadow rays.
    pub rays_shadow: u64,
    /// Wall-rescaled seconds to this checkpoint.
    pub seconds_s: f64,
    /// Summed per-point thread seconds.
    pub thread_s: f64,
    /// Mean squared error against the reference, its variance subtracted.
    pub ref_mse: f64,
    /// Mean error against the reference.
    pub ref_bias: f64,
    /// The reference's mean over the replica's points (what its relative error is relative to).
    pub ref_mean: f64,
    /// Mean per-path variance over the points (at K).
    pub variance_mean: f64,
}

/// What the competitor measured over a point's replicas.
#[derive(Clone, Debug)]
pub struct PathMeasured {
    /// Points it ran on.
    pub points: u64,
    /// Wall seconds of all K paths on them, summed over replicas.
    pub seconds: f64,
    /// Continuation rays at K, summed over replicas.
    pub rays_path: u64,
    /// Shadow rays at K, summed over replicas.
    pub rays_shadow: u64,
    /// Wall seconds per path.
    pub s_per_path: f64,
    /// √(mean σ_i²) / mean E_i over its points and replicas.
    pub cv: f64,
    /// cv from its errors against the reference at the checkpoints (NaN without a reference).
    pub cv_prefix: f64,
    /// Its rows of `NAME.path_tracing.csv`.
    pub rows: Vec<PathRow>,
}

impl Engine for Runs {
    fn run(&mut self, cfg: &DetpConfig, _rays: &RaySet, pts: &PointSet) -> Output {
        self.compute(cfg, pts);
        Output::Baseline
    }
    fn part(&self) -> Option<EnginePart> {
        Some(EnginePart::unit("PathTracing"))
    }
    /// Photon shards skip the competitor (it needs no photons); the merge computes it, once.
    fn absorb(&mut self, cfg: &DetpConfig, pts: &PointSet, _part: &EnginePart) {
        self.compute(cfg, pts);
    }
    fn seconds(&self) -> f64 {
        // A baseline: not part of the DETP engines' speed.
        0.0
    }
    fn as_path_tracing(&self) -> Option<&Runs> {
        Some(self)
    }
    /// At K paths: the mean over replicas and its SE (across replicas, or with one replica
    /// √(σ²/K)); NaN at points outside the subset.
    fn per_point(&self, p: &Pooled) -> Option<Vec<(f64, f64)>> {
        let mut out = vec![(f64::NAN, f64::NAN); p.sizes.n_p as usize];
        let Some(first) = self.runs.first() else {
            return Some(out);
        };
        let k = *first.run.checkpoints.last().unwrap_or(&1) as f64;
        let last = first.run.checkpoints.len() - 1;
        for (j, &i) in first.subset.iter().enumerate() {
            let v: Vec<f64> = self.runs.iter().map(|r| r.run.mean(j, last)).collect();
            let e = per_replica(&v);
            let se = if v.len() == 1 {
                (first.run.variance[j] / k).sqrt()
            } else {
                e.se
            };
            out[i] = (e.mean, se);
        }
        Some(out)
    }
    fn replica_points(&self) -> Vec<Vec<f64>> {
        self.runs
            .iter()
            .map(|r| {
                let n = r.subset.last().map_or(0, |&i| i + 1);
                let last = r.run.checkpoints.len() - 1;
                let mut v = vec![f64::NAN; n];
                for (j, &i) in r.subset.iter().enumerate() {
                    v[i] = r.run.mean(j, last);
                }
                v
            })
            .collect()
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let rows = self.rows(p.reference);
        let points = self.runs.first().map_or(0, |r| r.subset.len()) as u64;
        let at_k = |f: fn(&crate::lt::reference::RayTally) -> u64| -> u64 {
            self.runs
                .iter()
                .map(|r| r.run.rays.last().map_or(0, f))
                .sum()
        };
        let seconds: f64 = self.runs.iter().map(|r| r.run.wall_s).sum();
        let paths: f64 = self
            .runs
            .iter()
            .map(|r| r.subset.len() as f64 * *r.run.checkpoints.last().unwrap_or(&0) as f64)
            .sum();
        let (mut var, mut mean, mut n) = (0.0, 0.0, 0.0);
        for r in &self.runs {
            let last = r.run.checkpoints.len() - 1;
            for j in 0..r.subset.len() {
                var += r.run.variance[j];
                mean += r.run.mean(j, last);
                n += 1.0;
            }
        }
        EngineMeasured::of::<PathTracing>(PathMeasured {
            points,
            seconds,
            rays_path: at_k(|t| t.path),
            rays_shadow: at_k(|t| t.shadow),
            s_per_path: seconds / paths,
            cv: (var / n).sqrt() / (mean / n),
            cv_prefix: self.cv_prefix(p.reference, &rows),
            rows,
        })
    }
}

impl Runs {
    /// cv from the prefix errors: the checkpoints' MSE (mean over replicas) relative to the
    /// reference's mean over the subset squared, through
    /// [`PathTracingCost::cv2_from_prefix_errors`] (NaN without a reference).
    fn cv_prefix(&self, refr: Option<&[(f64, f64)]>, rows: &[PathRow]) -> f64 {
        let (Some(refr), Some(first)) = (refr, self.runs.first()) else {
            return f64::NAN;
        };
        let m = first.subset.len().max(1) as f64;
        let truth = first.subset.iter().map(|&i| refr[i].0).sum::<f64>() / m;
        let cps = &first.run.checkpoints;
        let reps = self.runs.len() as f64;
        let rel_mse: Vec<f64> = (0..cps.len())
            .map(|c| {
                rows.iter()
                    .skip(c)
                    .step_by(cps.len())
                    .map(|r| r.ref_mse)
                    .sum::<f64>()
                    / reps
                    / (truth * truth)
            })
            .collect();
        let paths: Vec<f64> = cps.iter().map(|&c| c as f64).collect();
        PathTracingCost::cv2_from_prefix_errors(&paths, &rel_mse)
            .max(0.0)
            .sqrt()
    }
}

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

/// The truth's mean over the points.
pub const PT_REF_MEAN: Column = Column::value(
    "ref_mean",
    "W/m²",
    Class::Measured,
    "this replica's mean over its points of the reference R_i (the scale of a relative error: ref_mse / ref_mean² is the relative MSE `raycost crossover` takes path tracing's cv² from); NaN without reference",
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
    col(&PT_REF_MEAN, |_, r| r.ref_mean.into()),
    col(&PT_VARIANCE_MEAN, |_, r| r.variance_mean.into()),
]);
