//! One DETP point, from its replicas to its typed measurement: every replica's rays through every
//! engine ([`replicate`]), then the point's pooled values ([`measure`]): the counts, each engine's
//! measurement, the engines' agreement, DETP's irradiance per disc and its accuracy against the exact
//! value and the path-traced reference, the levels table and (if asked) the points table.
//! `columns.rs` declares how each value becomes a column.

use std::ops::Range;
use std::sync::Arc;

use glam::DVec3;

use super::config::DetpConfig;
use super::engines::{
    self, DirectPart, EngineMeasured, Law, Output, Pooled, ReferenceCache, Sizes,
};
use super::estimators::photon_map::PhotonMap;
use super::estimators::photon_map_growing::PhotonMapGrowing;
use super::estimators::sphere_cache::LevelRow;
use super::estimators::Role;
use super::replica_errors::ReplicaErrorRow;
use super::spec::EngineChoice;
use super::shards::ReplicaPart;
use super::{agree, check_sums, points, rays, PointSet};
use crate::detp::disc::disc_area;
use crate::error::Error;
use crate::stats::Estimate;

/// What one DETP point measured.
#[derive(Clone, Debug)]
pub struct DetpMeasured {
    /// Segments traced, summed over replicas.
    pub segments: u64,
    /// The segments the engines read (`detp.direct = "nee"`: those after the first bounce).
    pub segments_indirect: u64,
    /// `detp.direct = "nee"`: the direct part's seconds, summed over replicas (else 0).
    pub direct_s: f64,
    /// `detp.direct = "nee"`: its shadow rays, summed over replicas (else 0).
    pub direct_rays_shadow: u64,
    /// Sample points.
    pub points: usize,
    /// Seconds making the rays, summed over replicas.
    pub trace_s: f64,
    /// Seconds on `detp.edge`'s remedy.
    pub edge_s: f64,
    /// Mean disc radius over d.
    pub edge_radius: f64,
    /// With `detp.radius_crossings`: the mean over discs and replicas of r_i over the disc's own
    /// radius (1 where fewer than k crossings fell within it).
    pub radius_crossings_ratio: Option<f64>,
    /// Each engine's measurement, in the point's engine order.
    pub engines: Vec<EngineMeasured>,
    /// Discs where the DETP engines or brute force disagree.
    pub mismatches: u64,
    /// Discs re-computed by brute force.
    pub bf_checked: u64,
    /// Surface points skipped as covered.
    pub points_covered: Option<u64>,
    /// Accuracy against engine `reference`, where it ran.
    pub reference: Option<AgainstReference>,
    /// DETP's mean irradiance over the judged discs.
    pub irradiance: Estimate,
    /// The exact mean over them (NaN without a closed form).
    pub exact_mean: f64,
    /// DETP's RMSE against the exact irradiance.
    pub irradiance_rmse: Estimate,
    /// DETP's mean error against it.
    pub irradiance_bias: Estimate,
    /// Segments per second of engine time.
    pub segments_per_s: f64,
}

/// The engines against the path-traced reference.
#[derive(Clone, Debug)]
pub struct AgainstReference {
    /// The reference's irradiance averaged over the points.
    pub irradiance: Estimate,
    /// Its mean standard error.
    pub mean_se: f64,
    /// DETP's bias and RMSE against it.
    pub detp: (Estimate, Estimate),
    /// Each other baseline's (column stem, bias, RMSE), in engine order: the photon maps' and
    /// path tracing's (over the points it ran on).
    pub baselines: Vec<(&'static str, (Estimate, Estimate))>,
}

/// One row of `NAME.points.csv`.
#[derive(Clone, Debug)]
pub struct PointRow {
    /// The sample's index.
    pub sample: usize,
    /// Its position.
    pub center: DVec3,
    /// Its normal.
    pub normal: DVec3,
    /// Its disc radius.
    pub disc_radius: f64,
    /// Distance to the nearest edge or other surface, capped at `detp.edge_distance_reach`·d (NaN
    /// without a scene).
    pub edge_distance: f64,
    /// DETP's irradiance (mean over replicas).
    pub mean: f64,
    /// Its standard error.
    pub se: f64,
    /// Its value in each replica (with ≥ 2 replicas).
    pub replicas: Vec<f64>,
    /// The exact value (NaN without one).
    pub exact: f64,
    /// Each baseline's (column stem, estimate, SE).
    pub baselines: Vec<(&'static str, f64, f64)>,
    /// The photon maps' value in each replica (column stem, values; with ≥ 2 replicas): one
    /// replica is one map of N photons, so an analysis judges a map by its replicas' own errors,
    /// not by their mean's (a fixed-k map's variance goes as 1/k whatever N).
    pub map_replicas: Vec<(&'static str, Vec<f64>)>,
    /// Engine `path-tracing` at this point (None where it did not run).
    pub path_tracing: Option<PathAtPoint>,
    /// `detp.direct = "nee"`: the direct part and its SE, mean over replicas (else 0, 0: the
    /// columns stay when a sweep varies `detp.direct`).
    pub direct: (f64, f64),
}

/// Engine `path-tracing` at a point: its running mean at each checkpoint (member name: the
/// paths) and its per-path variance, means over replicas.
pub type PathAtPoint = (Vec<(String, f64)>, f64);

/// What the replicas of one point leave.
pub(super) struct Replicated {
    /// The point set every replica shares or, where each replica draws its own
    /// ([`DetpConfig::points_per_replica`]), the replica's being traced or last absorbed.
    pts: PointSet,
    /// Each absorbed replica's exact irradiance per disc (of its own points where they vary).
    exact: Vec<Vec<f64>>,
    /// Points drawn per replica with `detp.write_points`: the earlier replicas' sets (the last one
    /// is `pts`), for their rows in the points table.
    earlier: Vec<PointSet>,
    refs: ReferenceCache,
    /// `detp.direct = "nee"`: the direct part per replica.
    direct: Vec<Arc<DirectPart>>,
    segments_direct: u64,
    engines: Vec<Box<dyn engines::Engine>>,
    /// DETP's irradiance per disc, per replica.
    irr: Vec<Vec<f64>>,
    /// With `detp.radius_crossings`: each disc's radius r_i per replica (else empty: each disc
    /// keeps its own, [`crate::detp::disc::Discs::radius_of`]).
    radii: Vec<Vec<f64>>,
    law_radius: f64,
    root_radius: f64,
    mean_segment_watts: f64,
    segments: u64,
    rays_in_root: u64,
    trace_s: f64,
    edge_s: f64,
    mismatches: u64,
    bf_checked: u64,
}

impl Replicated {
    /// A point's replicas before any has run: its sample points and fresh engines.
    fn new(cfg: &DetpConfig, point: u64, refs: &ReferenceCache) -> Result<Self, Error> {
        Ok(Self {
            engines: cfg
                .engines
                .iter()
                .map(|&e| e.estimator().engine(refs))
                .collect(),
            irr: Vec::with_capacity(cfg.replicas as usize),
            radii: Vec::new(),
            law_radius: 1.0,
            root_radius: 1.0,
            mean_segment_watts: 0.0,
            segments: 0,
            rays_in_root: 0,
            trace_s: 0.0,
            edge_s: 0.0,
            mismatches: 0,
            bf_checked: 0,
            pts: points(cfg, point, 0)?,
            exact: Vec::with_capacity(cfg.replicas as usize),
            earlier: Vec::new(),
            refs: refs.clone(),
            direct: Vec::new(),
            segments_direct: 0,
        })
        .map(|mut r| {
            r.edge_s = r.pts.edge_s;
            r
        })
    }

    /// Makes `pts` replica `replica`'s point set: drawn anew where points vary per replica (replica
    /// 0's is drawn by [`Replicated::new`]), kept for the points table if it is written.
    fn enter(&mut self, cfg: &DetpConfig, point: u64, replica: u64) -> Result<(), Error> {
        if replica == 0 || !cfg.points_per_replica() {
            return Ok(());
        }
        let next = points(cfg, point, replica)?;
        self.edge_s += next.edge_s;
        let prev = std::mem::replace(&mut self.pts, next);
        if cfg.write_points {
            self.earlier.push(prev);
        }
        Ok(())
    }

    /// The point sets of the replicas in replica order (one where they share it).
    fn sets(&self) -> impl Iterator<Item = &PointSet> {
        self.earlier.iter().chain(std::iter::once(&self.pts))
    }

    /// Adds one replica's sums and counts (traced here, or summed over its photon shards): the
    /// engines' agreement, DETP's irradiance per disc, the segment counts. The one place a
    /// replica's integer sums become values, so a merged run equals an unsplit one bit for bit.
    fn absorb(&mut self, cfg: &DetpConfig, point: u64, replica: u64, part: &ReplicaPart) {
        let scale = part.scale();
        self.law_radius = f64::from_bits(part.law_radius);
        self.root_radius = f64::from_bits(part.root_radius);
        self.segments += part.segments;
        self.segments_direct += part.segments_direct;
        self.rays_in_root += part.rays_in_root;
        self.trace_s += part.trace_s;
        self.edge_s += part.edge_s;
        if part.segments > 0 {
            // Σ power is an integer: the same bits whichever photons were traced where.
            self.mean_segment_watts =
                part.power_units() as f64 * scale.watts_per_unit / part.segments as f64;
        }
        let n = self.pts.discs.len();
        let a = agree(cfg, point, replica, n, part);
        self.mismatches += a.mismatches;
        self.bf_checked += a.bf_checked;
        let discs = &self.pts.discs;
        let direct = engines::direct_part(cfg, &self.pts, replica, &self.refs);
        // The k-nearest rule's r_i, or each disc's own radius: the one area its sum is divided by.
        let radii: Vec<f64> = if a.radii.is_empty() {
            (0..n).map(|i| discs.radius_of(i)).collect()
        } else {
            a.radii.iter().map(|&b| f64::from_bits(b)).collect()
        };
        self.irr.push(
            a.sums
                .iter()
                .zip(&radii)
                .enumerate()
                .map(|(i, (&s, &r))| {
                    let e = scale.watts(s) / disc_area(r);
                    direct.as_ref().map_or(e, |d| e + d.values[i].mean)
                })
                .collect(),
        );
        if !a.radii.is_empty() {
            self.radii.push(radii);
        }
        self.direct.extend(direct);
        self.exact.push(self.pts.exact.clone());
    }

    /// Disc `i`'s radius in replica `replica` (the k-nearest rule's r_i, else its own).
    fn radius(&self, replica: usize, i: usize) -> f64 {
        self.radii
            .get(replica)
            .map_or_else(|| self.pts.discs.radius_of(i), |r| r[i])
    }

    /// The Poisson variance of DETP's estimate `e` (its part without the direct light) at disc `i`
    /// in replica `replica`: e·w̄/(π r²) for a sum over a disc of radius r. With the k-nearest rule
    /// a disc that found its k crossings counts k − 1 of them over a random area, whose variance
    /// is (k − 1)/(k − 2) times that (λ²/(k − 2) for a Poisson field; infinite at k = 2, written
    /// NaN); a disc that did not (r_i = its own radius) is a plain sum.
    fn poisson_var(&self, cfg: &DetpConfig, replica: usize, i: usize, e: f64) -> f64 {
        let r = self.radius(replica, i);
        let var = e * self.mean_segment_watts / disc_area(r);
        match cfg.radius_crossings {
            Some(rc) if r < self.pts.discs.radius_of(i) => {
                let k = rc.k as f64;
                if rc.k > 2 {
                    var * (k - 1.0) / (k - 2.0)
                } else {
                    f64::NAN
                }
            }
            _ => var,
        }
    }

    /// The mean over replicas of the direct part at disc `i` and its variance (0, 0 without one).
    fn direct_at(&self, i: usize) -> (f64, f64) {
        if self.direct.is_empty() {
            return (0.0, 0.0);
        }
        let r = self.direct.len() as f64;
        let mean = self.direct.iter().map(|d| d.values[i].mean).sum::<f64>() / r;
        let var = self
            .direct
            .iter()
            .map(|d| d.values[i].se * d.values[i].se)
            .sum::<f64>()
            / (r * r);
        (mean, var)
    }
}

/// How a replica's photons are traced.
pub(super) enum Tracing {
    /// A photon shard: the reference and path tracing are skipped (they need no photons and are
    /// computed once by the merge).
    Shard,
    /// All of them, with the NEE direct part the photon maps add (`detp.direct = "nee"`).
    Whole(Option<Arc<DirectPart>>),
}

/// The photons `ids` of one replica through every engine (see [`Tracing`]): their sums, the check
/// subset's brute-force sums and the counts, as a [`ReplicaPart`].
pub(super) fn trace_replica(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    ids: Range<u64>,
    engines: &mut [Box<dyn engines::Engine>],
    pts: &PointSet,
    tracing: Tracing,
) -> ReplicaPart {
    let span = (ids.start, ids.end);
    let mut rays = rays(cfg, point, replica, pts, ids);
    let shard = matches!(tracing, Tracing::Shard);
    if let Tracing::Whole(direct) = tracing {
        rays.direct = direct;
    }
    let sums: Vec<_> = engines
        .iter_mut()
        .zip(&cfg.engines)
        .filter(|(_, &c)| !shard || c.reads_photons())
        .filter_map(|(e, _)| match e.run(cfg, &rays, pts) {
            Output::Sums(s) => Some(s),
            Output::Baseline => None,
        })
        .collect();
    ReplicaPart::new(
        span,
        &rays,
        sums,
        check_sums(cfg, point, replica, &rays, pts),
    )
}

/// Every replica through every engine.
pub(super) fn replicate(
    cfg: &DetpConfig,
    point: u64,
    progress: &(dyn Fn(u64) + Sync),
    refs: &ReferenceCache,
) -> Result<Replicated, Error> {
    let mut r = Replicated::new(cfg, point, refs)?;
    for replica in 0..cfg.replicas {
        r.enter(cfg, point, replica)?;
        let direct = engines::direct_part(cfg, &r.pts, replica, refs);
        let part = trace_replica(
            cfg,
            point,
            replica,
            0..cfg.photons,
            &mut r.engines,
            &r.pts,
            Tracing::Whole(direct),
        );
        r.absorb(cfg, point, replica, &part);
        progress(cfg.photons);
    }
    Ok(r)
}

/// A point's photons `ids` of every replica (`--photon-shard`): the parts a merge adds.
pub(super) fn replicate_part(
    cfg: &DetpConfig,
    point: u64,
    ids: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
    refs: &ReferenceCache,
) -> Result<Vec<ReplicaPart>, Error> {
    let mut engines: Vec<Box<dyn engines::Engine>> = cfg
        .engines
        .iter()
        .map(|&e| e.estimator().engine(refs))
        .collect();
    let mut pts = points(cfg, point, 0)?;
    let mut parts = Vec::with_capacity(cfg.replicas as usize);
    for replica in 0..cfg.replicas {
        if replica > 0 && cfg.points_per_replica() {
            pts = points(cfg, point, replica)?;
        }
        let mut part = trace_replica(
            cfg,
            point,
            replica,
            ids.clone(),
            &mut engines,
            &pts,
            Tracing::Shard,
        );
        part.engines = engines
            .iter()
            .map(|e| e.part().ok_or_else(|| Error::internal("an engine without parts")))
            .collect::<Result<_, _>>()?;
        parts.push(part);
        progress(ids.end - ids.start);
    }
    Ok(parts)
}

/// A point's replicas from their parts summed over every photon shard (`raycost merge`): each
/// engine records its summed counts, then every replica is absorbed as [`replicate`] absorbs it.
pub(super) fn replicate_merged(
    cfg: &DetpConfig,
    point: u64,
    parts: &[ReplicaPart],
    progress: &(dyn Fn(u64) + Sync),
    refs: &ReferenceCache,
) -> Result<Replicated, Error> {
    let mut r = Replicated::new(cfg, point, refs)?;
    for (replica, part) in (0..cfg.replicas).zip(parts) {
        r.enter(cfg, point, replica)?;
        for (e, p) in r.engines.iter_mut().zip(&part.engines) {
            e.absorb(cfg, &r.pts, p);
        }
        r.absorb(cfg, point, replica, part);
        progress(cfg.photons);
    }
    Ok(r)
}

/// Is it the reference the others are judged against?
fn is_reference(c: EngineChoice) -> bool {
    c.estimator().role() == Role::Reference
}

/// The mean of `values` over the indices `judged`.
fn mean_over(values: &[f64], judged: &[usize]) -> f64 {
    judged.iter().map(|&i| values[i]).sum::<f64>() / judged.len().max(1) as f64
}

/// What the point measured, its levels, points and replica-errors rows, and its warnings.
pub(super) fn measure(
    cfg: &DetpConfig,
    r: &Replicated,
) -> (
    DetpMeasured,
    Vec<LevelRow>,
    Vec<PointRow>,
    Vec<ReplicaErrorRow>,
    Vec<String>,
) {
    let discs = &r.pts.discs;
    let reps = cfg.replicas as f64;
    let mut pooled = Pooled {
        cfg,
        sizes: Sizes {
            reps,
            n_r: r.rays_in_root as f64 / reps,
            n_p: discs.len() as f64,
        },
        exact: &r.pts.exact,
        reference: None,
    };
    // Points drawn per replica have no per-disc mean across replicas (disc i is another point in
    // each): their rows are per replica (`point_rows`), and no engine that needs one (the
    // reference, scenes only) runs on them.
    let detp_points = if cfg.points_per_replica() {
        Vec::new()
    } else {
        per_disc(cfg, r)
    };
    // Baselines' estimates per disc, and every engine against the reference where it runs.
    let baselines: Vec<(EngineChoice, Vec<(f64, f64)>)> = cfg
        .engines
        .iter()
        .zip(&r.engines)
        .filter_map(|(&c, e)| e.per_point(&pooled).map(|v| (c, v)))
        .collect();
    pooled.reference = baselines
        .iter()
        .find(|(c, _)| is_reference(*c))
        .map(|(_, v)| v.as_slice());
    let reference = against_reference(cfg, r, &detp_points, &baselines);
    let (irradiance, exact_mean) = mean_irradiance(cfg, r);
    let errs: Vec<(f64, f64)> = r
        .irr
        .iter()
        .zip(&r.exact)
        .map(|(e, x)| engines::errors(e, x))
        .collect();
    let engine_s: f64 = r.engines.iter().map(|e| e.seconds()).sum();
    let law = Law {
        root_radius: r.root_radius,
        law_radius: r.law_radius,
        lines: cfg.scene().is_none(),
    };
    let levels = r
        .engines
        .iter()
        .flat_map(|e| e.levels(&pooled, &law))
        .collect();
    let rows = if cfg.write_points {
        point_rows(cfg, r, &detp_points, &baselines)
    } else {
        Vec::new()
    };
    let replica_errors = match pooled.reference {
        Some(refr) => super::replica_errors::rows(&r.irr, &map_replica_points(cfg, r), refr),
        None => Vec::new(),
    };
    let mut warnings = Vec::new();
    if !discs.is_empty() && r.irr.iter().all(|e| e.iter().all(|&x| x == 0.0)) {
        warnings.push(format!(
            "no photon crossed any of the {} discs: the irradiance is 0 everywhere (do the lights face the points? is d too small for {} photons?)",
            discs.len(),
            cfg.photons
        ));
    }
    let measured = DetpMeasured {
        segments: r.segments + r.segments_direct,
        segments_indirect: r.segments,
        // A fold from +0: an empty f64 sum is −0, which would be written as such.
        direct_s: r.direct.iter().fold(0.0, |a, d| a + d.seconds),
        direct_rays_shadow: r.direct.iter().map(|d| d.rays.shadow).sum(),
        points: discs.len(),
        trace_s: r.trace_s,
        edge_s: r.edge_s,
        edge_radius: (0..discs.len())
            .map(|i| discs.radius_of(i) / discs.radius)
            .sum::<f64>()
            / discs.len().max(1) as f64,
        radius_crossings_ratio: (!r.radii.is_empty()).then(|| {
            let ratios = r
                .radii
                .iter()
                .flat_map(|v| v.iter().enumerate().map(|(i, &x)| x / discs.radius_of(i)));
            ratios.sum::<f64>() / (r.radii.len() * discs.len()).max(1) as f64
        }),
        engines: r.engines.iter().map(|e| e.measured(&pooled)).collect(),
        mismatches: r.mismatches,
        bf_checked: r.bf_checked,
        points_covered: r.pts.covered,
        reference,
        irradiance,
        exact_mean,
        irradiance_rmse: engines::per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
        irradiance_bias: engines::per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>()),
        segments_per_s: r.segments as f64 / engine_s.max(1e-12),
    };
    (measured, levels, rows, replica_errors, warnings)
}

/// DETP's estimate per disc: mean over replicas, SE across them (or, with one replica, the Poisson
/// SE of a sum of segments of the mean segment power: √(E·w̄/πd²)).
fn per_disc(cfg: &DetpConfig, r: &Replicated) -> Vec<(f64, f64)> {
    let discs = &r.pts.discs;
    (0..discs.len())
        .map(|i| {
            let v: Vec<f64> = r.irr.iter().map(|e| e[i]).collect();
            let mut est = engines::per_replica(&v);
            if r.irr.len() == 1 {
                // The Poisson SE of DETP's part; with `nee` plus the direct part's own variance.
                let (direct, var) = r.direct_at(i);
                let detp = (est.mean - direct).max(0.0);
                est.se = (r.poisson_var(cfg, 0, i, detp) + var).sqrt();
            }
            (est.mean, est.se)
        })
        .collect()
}

/// DETP and the photon map against engine `reference`, where it ran.
fn against_reference(
    cfg: &DetpConfig,
    r: &Replicated,
    detp_points: &[(f64, f64)],
    baselines: &[(EngineChoice, Vec<(f64, f64)>)],
) -> Option<AgainstReference> {
    let (_, refr) = baselines
        .iter()
        .find(|(c, _)| is_reference(*c))?;
    let n = refr.len().max(1) as f64;
    let se2: f64 = refr.iter().map(|r| r.1 * r.1).sum();
    // Every other baseline over the points where it has an estimate (path tracing may run on a
    // subset of them).
    let others = baselines
        .iter()
        .filter(|(c, _)| !is_reference(*c))
        .map(|(c, est)| {
            let replicas = cfg
                .engines
                .iter()
                .zip(&r.engines)
                .find(|(&e, _)| e == *c)
                .map_or_else(Vec::new, |(_, e)| e.replica_points());
            let on: Vec<usize> = (0..est.len()).filter(|&i| est[i].0.is_finite()).collect();
            let pick = |v: &[(f64, f64)]| on.iter().map(|&i| v[i]).collect::<Vec<_>>();
            let replicas: Vec<Vec<f64>> = replicas
                .iter()
                .map(|v| on.iter().map(|&i| v[i]).collect())
                .collect();
            let errs = engines::against_reference(&pick(est), &replicas, &pick(refr));
            (c.column(), errs)
        })
        .collect();
    Some(AgainstReference {
        irradiance: Estimate {
            mean: refr.iter().map(|r| r.0).sum::<f64>() / n,
            se: se2.sqrt() / n,
            n: refr.len() as u64,
            clusters: refr.len() as u64,
        },
        mean_se: refr.iter().map(|r| r.1).sum::<f64>() / n,
        detp: engines::against_reference(detp_points, &r.irr, refr),
        baselines: others,
    })
}

/// The discs judged against an exact value: those with one (all of them where none has one, so the
/// mean irradiance is still reported).
fn judged_discs(exact: &[f64]) -> Vec<usize> {
    let with_exact: Vec<usize> = (0..exact.len()).filter(|&i| exact[i].is_finite()).collect();
    if with_exact.is_empty() {
        (0..exact.len()).collect()
    } else {
        with_exact
    }
}

/// DETP's mean irradiance and the exact mean, over the discs with an exact value (see
/// [`judged_discs`]), each replica over its own points' (they differ where points vary per replica;
/// the exact mean is then the mean over replicas of theirs).
fn mean_irradiance(cfg: &DetpConfig, r: &Replicated) -> (Estimate, f64) {
    let judged_of: Vec<Vec<usize>> = r.exact.iter().map(|x| judged_discs(x)).collect();
    let with_exact: Vec<f64> = r
        .exact
        .iter()
        .zip(&judged_of)
        .filter(|(x, _)| x.iter().any(|v| v.is_finite()))
        .map(|(x, j)| mean_over(x, j))
        .collect();
    let exact_mean = match with_exact.first() {
        None => f64::NAN,
        // A shared point set: its own mean, bit for bit.
        Some(&first) if with_exact.iter().all(|&x| x == first) => first,
        Some(_) => with_exact.iter().sum::<f64>() / with_exact.len() as f64,
    };
    let mut mean_irr = engines::per_replica(
        &r.irr
            .iter()
            .zip(&judged_of)
            .map(|(e, j)| mean_over(e, j))
            .collect::<Vec<_>>(),
    );
    let judged = judged_discs(&r.pts.exact);
    if r.irr.len() == 1 && !judged.is_empty() {
        // One replica: the Poisson SE of the mean over the n judged points, each point's sum
        // counted as independent (as the points table does per point): √(Σ Ē·w̄/(π·d_i²))/n, which
        // is √(Ē·w̄/(πd²·n)) when every disc has radius d. With it the mean is judged against an
        // exact value instead of "n/a".
        // With `nee` DETP's part is the mean less the direct part's, whose variance adds.
        let n = judged.len() as f64;
        let direct: Vec<(f64, f64)> = judged.iter().map(|&i| r.direct_at(i)).collect();
        let detp = (mean_irr.mean - direct.iter().map(|d| d.0).sum::<f64>() / n).max(0.0);
        let var: f64 = judged
            .iter()
            .zip(&direct)
            .map(|(&i, d)| r.poisson_var(cfg, 0, i, detp) + d.1)
            .sum();
        mean_irr.se = var.sqrt() / n;
        mean_irr.clusters = judged.len() as u64;
    }
    (mean_irr, exact_mean)
}

/// Points drawn per replica: one row per replica and disc (replica k's disc i is sample k·n_P + i),
/// its value in that replica with the Poisson SE of one replica's sum (as [`per_disc`] gives with
/// one replica). Only lines draw points per replica: no direct part, edge distance, baseline or
/// path tracing.
fn replica_point_rows(cfg: &DetpConfig, r: &Replicated) -> Vec<PointRow> {
    let mut rows = Vec::new();
    for (k, (set, irr)) in r.sets().zip(&r.irr).enumerate() {
        let discs = &set.discs;
        rows.extend((0..discs.len()).map(|i| PointRow {
            sample: k * discs.len() + i,
            center: discs.centers[i],
            normal: discs.normals[i],
            disc_radius: r.radius(k, i),
            edge_distance: f64::NAN,
            mean: irr[i],
            se: r.poisson_var(cfg, k, i, irr[i].max(0.0)).sqrt(),
            replicas: Vec::new(),
            exact: set.exact[i],
            baselines: Vec::new(),
            map_replicas: Vec::new(),
            path_tracing: None,
            direct: (0.0, 0.0),
        }));
    }
    rows
}

/// The points table: DETP's estimate and SE per disc, its value in each replica, then each
/// baseline's (per replica and disc where points vary per replica: [`replica_point_rows`]).
fn point_rows(
    cfg: &DetpConfig,
    r: &Replicated,
    detp_points: &[(f64, f64)],
    baselines: &[(EngineChoice, Vec<(f64, f64)>)],
) -> Vec<PointRow> {
    if cfg.points_per_replica() {
        return replica_point_rows(cfg, r);
    }
    let discs = &r.pts.discs;
    let path = path_tracing_points(r, discs.len());
    let maps = map_replica_points(cfg, r);
    let edge = cfg.scene().map_or_else(
        || vec![f64::NAN; discs.len()],
        |s| {
            let reach = cfg.edge_distance_reach * cfg.disc_radius;
            crate::detp::edge::edge_distances(&s.scene, &discs.centers, &discs.normals, reach)
        },
    );
    detp_points
        .iter()
        .enumerate()
        .map(|(i, &(mean, se))| PointRow {
            sample: i,
            center: discs.centers[i],
            normal: discs.normals[i],
            disc_radius: mean_radius(r, i),
            edge_distance: edge[i],
            mean,
            se,
            replicas: if r.irr.len() >= 2 {
                r.irr.iter().map(|e| e[i]).collect()
            } else {
                Vec::new()
            },
            exact: r.pts.exact[i],
            baselines: baselines
                .iter()
                .map(|(c, v)| (c.column(), v[i].0, v[i].1))
                .collect(),
            map_replicas: maps
                .iter()
                .map(|(c, v)| (*c, v.iter().map(|e| e[i]).collect()))
                .collect(),
            path_tracing: path.as_ref().map(|p| p[i].clone()),
            direct: {
                let (mean, var) = r.direct_at(i);
                (mean, var.sqrt())
            },
        })
        .collect()
}

/// Disc `i`'s radius: its own, or with the k-nearest rule r_i's mean over the replicas.
fn mean_radius(r: &Replicated, i: usize) -> f64 {
    if r.radii.is_empty() {
        r.pts.discs.radius_of(i)
    } else {
        r.radii.iter().map(|v| v[i]).sum::<f64>() / r.radii.len() as f64
    }
}

/// The photon maps' estimates per replica and disc (column stem, `[replica][disc]`), with ≥ 2
/// replicas (one replica's value is the mean's, already in `{map}_e`).
fn map_replica_points(cfg: &DetpConfig, r: &Replicated) -> Vec<(&'static str, Vec<Vec<f64>>)> {
    if r.irr.len() < 2 {
        return Vec::new();
    }
    cfg.engines
        .iter()
        .zip(&r.engines)
        .filter(|(c, _)| c.is::<PhotonMap>() || c.is::<PhotonMapGrowing>())
        .map(|(c, e)| (c.column(), e.replica_points()))
        .collect()
}

/// Engine `path-tracing`'s running means (members named by their paths) and per-path variance at
/// every disc, NaN outside the points it ran on (None where it did not run).
fn path_tracing_points(r: &Replicated, n: usize) -> Option<Vec<PathAtPoint>> {
    let pt = r.engines.iter().find_map(|e| e.as_path_tracing())?;
    let first = pt.runs().first()?;
    let cps = &first.run.checkpoints;
    let mut out = vec![
        (
            cps.iter().map(|c| (c.to_string(), f64::NAN)).collect(),
            f64::NAN
        );
        n
    ];
    for (&i, (means, var)) in first.subset.iter().zip(pt.point_means()) {
        out[i] = (
            cps.iter().map(|c| c.to_string()).zip(means).collect(),
            var,
        );
    }
    Some(out)
}
