//! What every engine of kind `detp` shares: the [`Engine`] a registered estimator
//! (`estimators/`, one file each) runs on a replica's rays and points, what it returns and keeps
//! for photon shards, what it knows when it pools its replicas, the run's cache of values computed
//! once per point set, the NEE direct part, and the statistics every estimator's columns use.
//!
//! DETP engines return their integer sum per disc, which the runner compares across engines and
//! against brute force; baselines (the photon map) return per-disc estimates instead.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::prelude::*;

use super::config::DetpConfig;
pub use super::estimators::EngineMeasured;
use super::estimators::path_tracing;
use super::estimators::sphere_cache::LevelRow;
use super::{PointSet, RaySet};
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::nearest::{Kept, Nearest};
use crate::detp::tally::Tally;
use crate::lt::reference::{self, Irradiance};
use crate::sample::rng::{domain, hash_key, mix64};
use crate::stats::{ClusteredMean, Estimate};

/// What one replica's engine returned.
pub(crate) enum Output {
    /// Integer sums per disc and, with the k-nearest-crossings radius, each disc's radius (a DETP
    /// engine: must equal every other DETP engine's, bit for bit).
    Sums(Gathered),
    /// A baseline's estimates (kept by the engine for its own columns; not compared).
    Baseline,
}

/// One replica's engine counts over a subset of its photons (`--photon-shard`): counts that add
/// across disjoint photon subsets, so the sum over a run's shards is what the engine counts on all
/// its photons. An engine whose counts do not add (the sphere cache's builds depend on how many
/// rays a sphere holds; the photon map's neighbours on every photon) has none.
///
/// Each engine writes its own counts under its tag (`{"DiscIndex": {…}}`, or the bare tag for an
/// engine that keeps none); two parts add field by field (numbers add, arrays element by element),
/// except a field named `bytes`, a size, which takes the larger.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, PartialEq)]
#[serde(transparent)]
pub struct EnginePart(serde_json::Value);

impl EnginePart {
    /// An engine's counts `counts` under its tag.
    pub fn new<T: serde::Serialize>(tag: &str, counts: &T) -> Self {
        let v = serde_json::to_value(counts).expect("counts are plain numbers");
        Self(serde_json::Value::Object([(tag.to_string(), v)].into_iter().collect()))
    }

    /// The part of an engine that keeps no counts (it reads no photons).
    pub fn unit(tag: &str) -> Self {
        Self(serde_json::Value::String(tag.to_string()))
    }

    /// The counts under `tag` (None for another engine's part).
    pub fn read<T: serde::de::DeserializeOwned>(&self, tag: &str) -> Option<T> {
        let v = self.0.as_object()?.get(tag)?;
        serde_json::from_value(v.clone()).ok()
    }

    /// The part of the union of two disjoint photon subsets (None if they are not the same
    /// engine's).
    pub fn add(&self, o: &Self) -> Option<Self> {
        add_values(&self.0, &o.0, false).map(Self)
    }
}

/// `a + b` field by field (`larger`: a size, which takes the larger).
fn add_values(a: &serde_json::Value, b: &serde_json::Value, larger: bool) -> Option<serde_json::Value> {
    use serde_json::Value as V;
    Some(match (a, b) {
        (V::Object(x), V::Object(y)) if x.len() == y.len() => V::Object(
            x.iter()
                .map(|(k, v)| Some((k.clone(), add_values(v, y.get(k)?, k == "bytes")?)))
                .collect::<Option<_>>()?,
        ),
        (V::Array(x), V::Array(y)) if x.len() == y.len() => V::Array(
            x.iter()
                .zip(y)
                .map(|(v, w)| add_values(v, w, larger))
                .collect::<Option<_>>()?,
        ),
        (V::Number(x), V::Number(y)) => match (x.as_u64(), y.as_u64()) {
            (Some(m), Some(n)) if larger => m.max(n).into(),
            (Some(m), Some(n)) => m.checked_add(n)?.into(),
            _ if larger => V::from(x.as_f64()?.max(y.as_f64()?)),
            _ => V::from(x.as_f64()? + y.as_f64()?),
        },
        (V::String(x), V::String(y)) if x == y => a.clone(),
        _ => return None,
    })
}


/// What the point knows when its engines pool their replicas.
pub(crate) struct Pooled<'a> {
    /// The point's config.
    pub cfg: &'a DetpConfig,
    /// The sizes Theorem 1 takes.
    pub sizes: Sizes,
    /// The exact irradiance per disc (NaN where unknown).
    pub exact: &'a [f64],
    /// Engine `reference`'s estimate and SE per disc, where it runs.
    pub reference: Option<&'a [(f64, f64)]>,
}

/// The sizes of a point that Theorem 1's counts take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sizes {
    /// Replicas.
    pub reps: f64,
    /// n_R: mean rays per replica meeting the law's ball.
    pub n_r: f64,
    /// n_P.
    pub n_p: f64,
}

/// What the rays-per-level law needs from the point's rays.
pub(crate) struct Law {
    /// Root radius r_0.
    pub root_radius: f64,
    /// Radius of the ball the rays are μ-random in.
    pub law_radius: f64,
    /// Lines (the lens-clipped law applies) or photons.
    pub lines: bool,
}

/// One engine (see the module doc).
pub(crate) trait Engine: Send {
    /// Runs on one replica.
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output;
    /// Engine seconds over all replicas so far (for `segments_per_s`).
    fn seconds(&self) -> f64;
    /// What it measured over all replicas.
    fn measured(&self, p: &Pooled) -> EngineMeasured;
    /// A baseline's estimate and standard error per disc, pooled over replicas (None for a DETP
    /// engine, whose per-disc values the runner pools itself).
    fn per_point(&self, _p: &Pooled) -> Option<Vec<(f64, f64)>> {
        None
    }
    /// A baseline's estimate per disc in each replica (empty where it keeps none).
    fn replica_points(&self) -> Vec<Vec<f64>> {
        Vec::new()
    }
    /// The path-tracing competitor, for its side table and points columns (None for the others).
    fn as_path_tracing(&self) -> Option<&path_tracing::Runs> {
        None
    }
    /// The levels table (the sphere cache only).
    fn levels(&self, _p: &Pooled, _law: &Law) -> Vec<LevelRow> {
        Vec::new()
    }
    /// The last replica's counts as an [`EnginePart`] (None where they do not add across photon
    /// subsets: such an engine refuses `--photon-shard`).
    fn part(&self) -> Option<EnginePart> {
        None
    }
    /// Records `part`, the counts of one replica summed over its photon shards, as if `run` had
    /// counted them (`raycost merge` of photon shards).
    fn absorb(&mut self, _cfg: &DetpConfig, _pts: &PointSet, _part: &EnginePart) {
        unreachable!("an engine without parts refuses --photon-shard before anything runs")
    }
}


/// What a DETP engine found on one replica's discs: the power units each disc counts and, with
/// `detp.radius_crossings`, the radius r_i its sum is divided by (as IEEE bits: compared bit for
/// bit across engines; empty: each disc's own radius, [`Discs::radius_of`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Gathered {
    /// Power units per disc (or per disc of a check subset).
    pub units: Vec<Acc>,
    /// r_i's bits per disc, with the k-nearest-crossings radius (else empty).
    pub radii: Vec<u64>,
}

/// A DETP engine's pass over a replica's segments, for the two tallies an engine runs: the
/// paper's power sums, or each disc's k nearest crossings ([`crate::detp::tally`]).
pub(crate) trait Pass {
    /// The engine's counts.
    type Stats;
    /// The power sums of every disc into `acc`.
    fn sums(&self, acc: &mut [Acc]) -> Self::Stats;
    /// Each disc's k nearest crossings into `kept`.
    fn nearest(&self, tally: &Nearest, kept: &mut [Kept]) -> Self::Stats;
}

/// The pass with the tally the point asks for, timed as one: with `detp.radius_crossings` finding
/// each disc's k nearest crossings and selecting its radius and counted power ([`select`]) is the
/// engine's cost, in its seconds.
pub(crate) fn gather<P: Pass>(cfg: &DetpConfig, discs: &Discs, pass: &P) -> (Gathered, P::Stats, f64) {
    let n = discs.len();
    let ((g, stats), s) = timed(|| match cfg.radius_crossings {
        None => {
            let mut acc = vec![0; n];
            let stats = pass.sums(&mut acc);
            (
                Gathered {
                    units: acc,
                    radii: Vec::new(),
                },
                stats,
            )
        }
        Some(rc) => {
            let tally = Nearest::new(rc.k);
            let mut kept = tally.empties(n);
            let stats = pass.nearest(&tally, &mut kept);
            let all: Vec<u32> = (0..n as u32).collect();
            (select(&kept, &all, rc.k, discs), stats)
        }
    });
    (g, stats, s)
}

/// The radius and counted power of the discs `which` (`kept` indexed by disc number), in that
/// order ([`Kept::select`], capped at each disc's own radius).
pub(crate) fn select(kept: &[Kept], which: &[u32], k: usize, discs: &Discs) -> Gathered {
    let (units, radii) = which
        .par_iter()
        .map(|&i| {
            let i = i as usize;
            let s = kept[i].select(k, discs.radius_of(i));
            (s.units, s.radius.to_bits())
        })
        .unzip();
    Gathered { units, radii }
}

pub(super) fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let s = Instant::now();
    let v = f();
    (v, s.elapsed().as_secs_f64())
}

/// One estimate from one value per replica (one cluster each).
pub(super) fn per_replica(values: &[f64]) -> Estimate {
    let mut m = ClusteredMean::default();
    for &v in values {
        m.push_cluster(1, v, v * v);
    }
    m.estimate()
}

/// Root-mean-square error and mean error of `est` against `exact` over the discs that have an exact
/// value (NaN, NaN if none has).
pub(super) fn errors(est: &[f64], exact: &[f64]) -> (f64, f64) {
    let (mut n, mut s, mut s2) = (0u64, 0.0, 0.0);
    for (e, x) in est.iter().zip(exact) {
        if x.is_finite() {
            let d = e - x;
            n += 1;
            s += d;
            s2 += d * d;
        }
    }
    if n == 0 {
        (f64::NAN, f64::NAN)
    } else {
        ((s2 / n as f64).sqrt(), s / n as f64)
    }
}


/// What a run computes once per point set and shares across its sweep points (other photon
/// counts, d, k, engines): the path-traced reference, keyed by (scene, points, samples, seed); the
/// NEE direct part, keyed by those and the replica. Values are a pure function of the key, so
/// sharing them changes no measured column. (The path-tracing competitor is not shared: each row
/// times its own, see `estimators/path_tracing.rs`.)
#[derive(Clone, Default)]
pub struct ReferenceCache {
    /// The reference per disc and its seconds.
    pub(super) reference: Memo<(Vec<Irradiance>, f64)>,
    /// The NEE direct part of one replica.
    pub(super) direct: Memo<DirectPart>,
}

/// Values by key, each computed once (outside the lock: two threads may both compute a missing
/// value, and then store the same).
pub(super) struct Memo<T>(Arc<Mutex<HashMap<u64, Arc<T>>>>);

impl<T> Default for Memo<T> {
    fn default() -> Self {
        Self(Arc::default())
    }
}

impl<T> Clone for Memo<T> {
    fn clone(&self) -> Self {
        Self(self.0.clone())
    }
}

impl<T> Memo<T> {
    /// The value at `key`, computed by `f` the first time.
    pub(super) fn get_or(&self, key: u64, f: impl FnOnce() -> T) -> Arc<T> {
        let cached = self.0.lock().expect("no panic holds it").get(&key).cloned();
        cached.unwrap_or_else(|| {
            let v = Arc::new(f());
            self.0
                .lock()
                .expect("no panic holds it")
                .insert(key, v.clone());
            v
        })
    }
}

/// A key for values computed on a point set: `parts` (a domain, the seed, sizes) with the scene's
/// path and every disc's centre and normal.
pub(super) fn point_set_key(cfg: &DetpConfig, pts: &PointSet, parts: &[u64]) -> u64 {
    let mut key = hash_key(parts);
    if let Some(scene) = cfg.scene() {
        for b in scene.path.to_string_lossy().bytes() {
            key = mix64(key ^ u64::from(b));
        }
    }
    let discs = &pts.discs;
    for (c, n) in discs.centers.iter().zip(&discs.normals) {
        for x in c.to_array().into_iter().chain(n.to_array()) {
            key = mix64(key ^ x.to_bits());
        }
    }
    key
}

/// `detp.direct = "nee"`: the direct irradiance of one replica at every disc, by next-event
/// estimation ([`crate::lt::direct`], streams `[DIRECT, seed, replica, disc]`), with its rays and
/// seconds. One number per disc added to every engine's indirect estimate, so the DETP engines
/// still agree bit for bit.
pub struct DirectPart {
    /// Per disc: the direct irradiance and its SE.
    pub values: Vec<Irradiance>,
    /// Rays cast (shadow rays).
    pub rays: reference::RayTally,
    /// Seconds.
    pub seconds: f64,
}

/// The direct part of replica `replica` at the point set's discs, through the run's cache (None
/// unless `detp.direct = "nee"`).
pub(super) fn direct_part(
    cfg: &DetpConfig,
    pts: &PointSet,
    replica: u64,
    cache: &ReferenceCache,
) -> Option<Arc<DirectPart>> {
    let super::config::Direct::Nee(samples) = cfg.direct else {
        return None;
    };
    let scene = cfg.scene()?;
    let key = point_set_key(cfg, pts, &[domain::DIRECT, cfg.seed, samples, replica]);
    Some(cache.direct.get_or(key, || {
        let discs = &pts.discs;
        let ((values, rays), seconds) = timed(|| {
            crate::lt::direct::direct_irradiance(
                &scene.scene,
                &discs.centers,
                &discs.normals,
                samples,
                cfg.seed,
                replica,
            )
        });
        DirectPart {
            values,
            rays,
            seconds,
        }
    }))
}


/// Σ_i ((E_i − R_i)² − se_R,i²) over the points of `est` and `refr` (R_i, se_R,i): n times the
/// engine's mean squared error against the true irradiance, the reference's variance subtracted
/// (see [`against_reference`]). Public so that `raycost crossover` judges one replica's values
/// exactly as the kind judges their mean.
pub fn squared_error_sum(est: impl IntoIterator<Item = f64>, refr: &[(f64, f64)]) -> f64 {
    est.into_iter()
        .zip(refr)
        .fold(0.0, |acc, (e, &(r, sr))| acc + ((e - r) * (e - r) - sr * sr))
}

/// Relative MSE of one replica's values `est` against the reference `refr` (R_i, se_R,i):
/// [mean_i (E_i − R_i)² − mean_i se_R,i²] / (mean_i R_i)², the truth's variance subtracted as in
/// [`squared_error_sum`]. What `raycost crossover` bootstraps over replicas: the kind writes it per
/// estimator and replica (`NAME.replica_errors.csv`), and the crossover computes it the same way
/// from a points table that has no such table beside it, so both give the same bits.
pub fn relative_mse(est: &[f64], refr: &[(f64, f64)]) -> f64 {
    let n = est.len().min(refr.len()) as f64;
    let truth = refr.iter().map(|r| r.0).sum::<f64>() / n;
    squared_error_sum(est.iter().copied(), refr) / n / (truth * truth)
}

/// An engine's estimates `est` against the reference `refr`, both (value, SE) per disc: the mean
/// error (bias) and the root-mean-square error against the *true* irradiance, each with a standard
/// error from the Monte Carlo noise of both (the point set is fixed).
///
/// E[(E_i − R_i)²] = b_i² + s_E,i² + s_R,i², so Σ((E_i − R_i)² − s_R,i²)/n estimates the engine's
/// mean square error (its bias² and its own variance), the reference's variance subtracted; its
/// variance is Σ Var((E_i − R_i)²)/n² with Var ≈ 4μ_i²s_i² + 2s_i⁴ (normal errors, mean μ_i,
/// variance s_i² = s_E,i² + s_R,i², μ_i² estimated by max(0, (E_i − R_i)² − s_i²)), carried to the
/// root by the delta method.
///
/// The bias's SE: one photon set feeds every point of a replica, so the points' errors are
/// correlated (overlapping discs share segments) and Σ s_i² would understate it. With two or more
/// replicas it is therefore taken across replicas: the replicas' mean errors b_r over the same
/// points, Var(b̄) = s_b²/R, plus the reference's own variance Σ s_R,i²/n² (its points are
/// independent streams); the degrees of freedom of that sum (Welch–Satterthwaite) are written as
/// its cluster count, so a CI uses Student-t. With one replica, the per-point sum as above.
/// `replicas` holds the engine's per-point values of each replica (empty if it has none).
pub(super) fn against_reference(
    est: &[(f64, f64)],
    replicas: &[Vec<f64>],
    refr: &[(f64, f64)],
) -> (Estimate, Estimate) {
    let n = est.len().min(refr.len());
    let (mut sum_d, mut var_d, mut var_mse) = (0.0, 0.0, 0.0);
    for (&(e, se), &(r, sr)) in est.iter().zip(refr) {
        let d = e - r;
        let s2 = se * se + sr * sr;
        sum_d += d;
        var_d += s2;
        let mu2 = (d * d - s2).max(0.0);
        var_mse += 4.0 * mu2 * s2 + 2.0 * s2 * s2;
    }
    let mse = squared_error_sum(est.iter().map(|e| e.0), refr);
    let nf = n as f64;
    let est_of = |mean: f64, se: f64| Estimate {
        mean: if n == 0 { f64::NAN } else { mean },
        se: if n == 0 { f64::NAN } else { se },
        n: n as u64,
        clusters: n as u64,
    };
    let bias = if replicas.len() >= 2 && n > 0 {
        let b: Vec<f64> = replicas
            .iter()
            .map(|e| e.iter().zip(refr).map(|(e, r)| e - r.0).sum::<f64>() / nf)
            .collect();
        let across = per_replica(&b);
        let a = across.se * across.se;
        let var_ref = refr[..n].iter().map(|r| r.1 * r.1).sum::<f64>() / (nf * nf);
        let reps = b.len() as f64;
        let dof = (a + var_ref).powi(2)
            / (a * a / (reps - 1.0) + var_ref * var_ref / (nf - 1.0).max(1.0));
        Estimate {
            mean: across.mean,
            se: (a + var_ref).sqrt(),
            n: n as u64,
            clusters: if dof.is_finite() {
                (dof.floor() as u64 + 1).clamp(2, n as u64)
            } else {
                n as u64
            },
        }
    } else {
        est_of(sum_d / nf, var_d.sqrt() / nf)
    };
    let mse = mse / nf;
    let se_mse = var_mse.sqrt() / nf;
    let rmse = mse.max(0.0).sqrt();
    let se_rmse = if rmse > 0.0 {
        se_mse / (2.0 * rmse)
    } else {
        se_mse.sqrt()
    };
    (bias, est_of(rmse, se_rmse))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts add field by field under their engine's tag, sizes take the larger, and parts of two
    /// different engines do not add.
    #[test]
    fn engine_parts_add_counts_and_keep_the_larger_size() {
        #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
        struct Counts {
            stats: [u64; 2],
            seconds: f64,
            bytes: usize,
        }
        let a = EnginePart::new("X", &Counts { stats: [1, 2], seconds: 0.5, bytes: 10 });
        let b = EnginePart::new("X", &Counts { stats: [3, 4], seconds: 0.25, bytes: 7 });
        let sum = a.add(&b).expect("the same engine's parts add");
        assert_eq!(
            sum.read::<Counts>("X"),
            Some(Counts { stats: [4, 6], seconds: 0.75, bytes: 10 })
        );
        assert_eq!(sum.read::<Counts>("Y"), None);
        let text = serde_json::to_string(&sum).expect("json");
        let back: EnginePart = serde_json::from_str(&text).expect("reads back");
        assert_eq!(back, sum);
        assert!(a.add(&EnginePart::unit("X")).is_none());
        assert!(EnginePart::unit("R").add(&EnginePart::unit("Q")).is_none());
        assert_eq!(EnginePart::unit("R").add(&EnginePart::unit("R")), Some(EnginePart::unit("R")));
        let other = EnginePart::new("Y", &Counts { stats: [1, 2], seconds: 0.5, bytes: 10 });
        assert!(a.add(&other).is_none());
    }

    /// Replicas whose errors are shared by every point (a replica-wide offset): the per-point sum
    /// of variances would call the mean error exact to within s/√n; across replicas it is the
    /// offsets' spread, as it must be.
    #[test]
    fn the_bias_se_sees_errors_shared_by_all_points() {
        let n = 400;
        let truth = vec![(10.0, 0.0); n];
        let offsets = [-0.3, 0.1, 0.4, -0.2];
        let replicas: Vec<Vec<f64>> = offsets
            .iter()
            .map(|o| {
                (0..n)
                    .map(|i| 10.0 + o + 0.01 * ((i % 7) as f64 - 3.0))
                    .collect()
            })
            .collect();
        let pooled: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let e = per_replica(&replicas.iter().map(|r| r[i]).collect::<Vec<_>>());
                (e.mean, e.se)
            })
            .collect();
        let (bias, _) = against_reference(&pooled, &replicas, &truth);
        let b = per_replica(&offsets);
        let pattern = (0..n).map(|i| 0.01 * ((i % 7) as f64 - 3.0)).sum::<f64>() / n as f64;
        assert!(
            (bias.mean - (b.mean + pattern)).abs() < 1e-12,
            "{}",
            bias.mean
        );
        assert!((bias.se - b.se).abs() < 1e-12, "{} vs {}", bias.se, b.se);
        // With an exact reference the degrees of freedom are the replicas' R − 1.
        assert_eq!(bias.clusters, offsets.len() as u64);
        let (naive, _) = against_reference(&pooled, &[], &truth);
        assert!(naive.se < bias.se / 10.0, "{} {}", naive.se, bias.se);
        // A noisy reference adds its variance and raises the degrees of freedom.
        let noisy: Vec<(f64, f64)> = truth.iter().map(|&(v, _)| (v, 4.0)).collect();
        let (both, _) = against_reference(&pooled, &replicas, &noisy);
        let var_ref = 16.0 / n as f64;
        assert!((both.se - (b.se * b.se + var_ref).sqrt()).abs() < 1e-12);
        assert!(both.clusters > offsets.len() as u64);
    }
}
