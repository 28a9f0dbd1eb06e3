//! Kind `detp`: one point builds a ray store (μ-random lines through the unit ball, or photons traced
//! from a scene), discs on sample points, and runs the engines the spec names on it, once per replica
//! (the engines themselves live in `engines.rs`, one [`engines::Engine`] each):
//!
//! - `sphere-cache`: the hierarchy of spheres (points visited in Morton/Hilbert/no order), with its
//!   counters per level — rays held, rebuilds (cache misses), ray–sphere tests — against
//!   n_R·Q^(2i) and Theorem 1;
//! - `disc-index`: the discs in an octree or a grid that every segment traverses, against Theorem 1;
//! - `brute-force`: every segment against every disc;
//! - `photon-map`: Jensen's k-nearest-neighbour estimate over the same photons (scenes only);
//! - `reference`: the path-traced irradiance at every point ([`crate::lt::reference`]), the ground
//!   truth DETP and the photon map are measured against (scenes only; computed once per point set
//!   in a run, not per replica).
//!
//! The DETP engines must give the same integer sum on every disc, bit for bit; on top of that a keyed
//! random subset of `brute_force_points` discs is re-computed by brute force. Any difference is the
//! `mismatches` [`Check`]: the runner writes the row and fails the run (exit 1).
//!
//! Columns are declared in `columns.rs` (counts are totals over the point's replicas; estimates have
//! one cluster per replica, so their standard errors cover independent ray sets).

use glam::DVec3;
use rand::seq::index::sample as sample_indices;
use rayon::prelude::*;

pub mod columns;
pub mod engines;
mod lines;
mod scene;
pub mod spec;

use self::columns as col;
use self::engines::{Law, Output, Pooled, ReferenceCache};
pub use self::spec::DetpConfig;
use self::spec::{DetpSpec, EngineChoice, Points};
use super::inputs::Inputs;
use super::kind::{
    refuse, Check, ConfigError, Context, Kind, Memory, Need, PointOutput, Rate, Work,
};
use super::metric::{Metric, Theory};
use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::store::SegmentStore;
use crate::error::Error;
use crate::output::column::Column;
use crate::output::row::Row;
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
}

/// The sample points of a point (shared by its replicas) with their exact irradiance where known.
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

/// Sample points: uniform in the ball (drawn once per point: all replicas share them, only the rays
/// change), on a scene's surfaces, or from a user's CSV.
pub(crate) fn points(cfg: &DetpConfig, point: u64) -> Result<PointSet, Error> {
    if let Some(s) = cfg.scene() {
        return scene::points(cfg, &s.scene);
    }
    let (centers, normals) = match &cfg.points {
        Points::Ball(n) => {
            let n = *n;
            let pairs: Vec<(DVec3, DVec3)> = (0..n.div_ceil(BATCH))
                .into_par_iter()
                .flat_map_iter(|b| {
                    let mut rng = stream(&[domain::POINTS, cfg.seed, point, b]);
                    let count = BATCH.min(n - b * BATCH);
                    (0..count).map(move |_| {
                        let c = uniform_in_ball(&mut rng);
                        (c, crate::sample::directions::uniform_direction(&mut rng))
                    })
                })
                .collect();
            pairs.into_iter().unzip()
        }
        Points::Grid(k) => lattice(cfg.seed, point, *k),
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
/// from the same keyed streams as points in the ball.
fn lattice(seed: u64, point: u64, k: u64) -> (Vec<DVec3>, Vec<DVec3>) {
    let s = spec::lattice_spacing(k);
    let a = 1.0 / 3f64.sqrt();
    let n = k.pow(3);
    let at = move |i: u64| -a + s * (i as f64 + 0.5);
    let pairs: Vec<(DVec3, DVec3)> = (0..n.div_ceil(BATCH))
        .into_par_iter()
        .flat_map_iter(|b| {
            let mut rng = stream(&[domain::POINTS, seed, point, b]);
            let lo = b * BATCH;
            (lo..(lo + BATCH).min(n)).map(move |i| {
                let c = DVec3::new(at(i % k), at(i / k % k), at(i / (k * k)));
                (c, crate::sample::directions::uniform_direction(&mut rng))
            })
        })
        .collect();
    pairs.into_iter().unzip()
}

/// The rays of one replica.
pub(crate) fn rays(cfg: &DetpConfig, point: u64, replica: u64, pts: &PointSet) -> RaySet {
    match cfg.scene() {
        None => lines::lines(cfg, point, replica),
        Some(s) => scene::photons(cfg, point, replica, &s.scene, &pts.discs),
    }
}

/// What the engines of one replica agreed on, and how far that was checked.
struct Agreement {
    /// The first DETP engine's sums.
    sums: Vec<Acc>,
    /// Discs where another engine or brute force differs.
    mismatches: u64,
    /// Discs re-computed by brute force.
    bf_checked: u64,
}

/// Every DETP engine against the first, disc by disc, and a keyed subset of discs against brute
/// force (unless brute force ran on all of them already).
fn agree(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    rays: &RaySet,
    pts: &PointSet,
    sums: &[Vec<Acc>],
) -> Agreement {
    let n = pts.discs.len();
    let (first, rest) = sums
        .split_first()
        .expect("configure refuses a spec without a DETP engine");
    let mut mismatches = (0..n)
        .filter(|&i| rest.iter().any(|o| o[i] != first[i]))
        .count() as u64;
    let bf_checked = if cfg.engines.contains(&EngineChoice::BruteForce) {
        n as u64
    } else if cfg.brute_force_points > 0 && n > 0 {
        let k = (cfg.brute_force_points as usize).min(n);
        let mut rng = stream(&[domain::CHECK, cfg.seed, point, replica]);
        let mut subset: Vec<u32> = sample_indices(&mut rng, n, k)
            .into_iter()
            .map(|i| i as u32)
            .collect();
        subset.sort_unstable();
        let mut bf = vec![0; n];
        brute::accumulate(&rays.store, &pts.discs, Some(&subset), 1, &mut bf);
        mismatches += subset
            .iter()
            .filter(|&&i| bf[i as usize] != first[i as usize])
            .count() as u64;
        k as u64
    } else {
        0
    };
    Agreement {
        sums: first.clone(),
        mismatches,
        bf_checked,
    }
}

/// The mean of `values` over the indices `judged`.
fn mean_over(values: &[f64], judged: &[usize]) -> f64 {
    judged.iter().map(|&i| values[i]).sum::<f64>() / judged.len().max(1) as f64
}

/// One DETP point: every replica through every engine, then the row, the levels table and (if
/// asked) the points table.
pub fn run_point(
    cfg: &DetpConfig,
    point: u64,
    progress: &(dyn Fn(u64) + Sync),
    refs: &ReferenceCache,
) -> Result<PointOutput<DetpTables>, Error> {
    let pts = points(cfg, point)?;
    let discs = &pts.discs;
    let mut engines: Vec<Box<dyn engines::Engine>> = cfg
        .engines
        .iter()
        .map(|&e| engines::engine(e, refs))
        .collect();
    let (mut law_radius, mut root_radius, mut mean_segment_watts) = (1.0, 1.0, 0.0);
    let (mut segments, mut rays_in_root, mut trace_s) = (0u64, 0u64, 0.0);
    let mut edge_s = pts.edge_s;
    let (mut mismatches, mut bf_checked) = (0u64, 0u64);
    let mut irr: Vec<Vec<f64>> = Vec::with_capacity(cfg.replicas as usize);
    for replica in 0..cfg.replicas {
        let rays = rays(cfg, point, replica, &pts);
        let scale = rays.store.scale;
        law_radius = rays.law_radius;
        root_radius = rays.root.1;
        segments += rays.store.len() as u64;
        rays_in_root += rays.rays_in_root;
        trace_s += rays.trace_s;
        edge_s += rays.edge_s;
        if !rays.store.is_empty() {
            mean_segment_watts = rays
                .store
                .segments
                .iter()
                .map(|s| scale.watts(i64::from(s.power)))
                .sum::<f64>()
                / rays.store.len() as f64;
        }
        let sums: Vec<Vec<Acc>> = engines
            .iter_mut()
            .filter_map(|e| match e.run(cfg, &rays, &pts) {
                Output::Sums(s) => Some(s),
                Output::Baseline => None,
            })
            .collect();
        let a = agree(cfg, point, replica, &rays, &pts, &sums);
        mismatches += a.mismatches;
        bf_checked += a.bf_checked;
        irr.push(
            a.sums
                .iter()
                .enumerate()
                .map(|(i, &s)| discs.irradiance(i, scale.watts(s)))
                .collect(),
        );
        progress(cfg.photons);
    }

    let reps = cfg.replicas as f64;
    let pooled = Pooled {
        cfg,
        reps,
        n_r: rays_in_root as f64 / reps,
        n_p: discs.len() as f64,
        exact: &pts.exact,
    };
    let mut row = Row::default();
    row.put(&col::SEGMENTS, segments)
        .put(&col::POINTS, discs.len())
        .put(&col::TRACE_S, trace_s)
        .put(&col::EDGE_S, edge_s)
        .put(
            &col::EDGE_RADIUS,
            (0..discs.len())
                .map(|i| discs.radius_of(i) / discs.radius)
                .sum::<f64>()
                / discs.len().max(1) as f64,
        );
    for e in &engines {
        e.write(&pooled, &mut row);
    }
    row.put(&col::MISMATCHES, mismatches)
        .put(&col::BF_CHECKED, bf_checked);
    if let Some(c) = pts.covered {
        row.put(&col::POINTS_COVERED, c);
    }

    // DETP's estimate per disc: mean over replicas, SE across them (or, with one replica, the
    // Poisson SE of a sum of segments of the mean segment power: √(E·w̄/πd²)).
    let detp_points: Vec<(f64, f64)> = (0..discs.len())
        .map(|i| {
            let v: Vec<f64> = irr.iter().map(|e| e[i]).collect();
            let mut est = engines::per_replica(&v);
            if irr.len() == 1 {
                est.se = (est.mean.max(0.0) * mean_segment_watts / discs.area(i)).sqrt();
            }
            (est.mean, est.se)
        })
        .collect();
    // Baselines' estimates per disc, and every engine against the reference where it runs.
    let baselines: Vec<(EngineChoice, Vec<(f64, f64)>)> = cfg
        .engines
        .iter()
        .zip(&engines)
        .filter_map(|(&c, e)| e.per_point(&pooled).map(|v| (c, v)))
        .collect();
    if let Some((_, refr)) = baselines
        .iter()
        .find(|(c, _)| *c == EngineChoice::Reference)
    {
        let n = refr.len().max(1) as f64;
        let se2: f64 = refr.iter().map(|r| r.1 * r.1).sum();
        row.put_estimate(
            &col::REFERENCE_IRRADIANCE,
            &crate::stats::Estimate {
                mean: refr.iter().map(|r| r.0).sum::<f64>() / n,
                se: se2.sqrt() / n,
                n: refr.len() as u64,
                clusters: refr.len() as u64,
            },
        )
        .put(
            &col::REFERENCE_MEAN_SE,
            refr.iter().map(|r| r.1).sum::<f64>() / n,
        );
        let (bias, rmse) = engines::against_reference(&detp_points, &irr, refr);
        row.put_estimate(&col::IRRADIANCE_REF_BIAS, &bias)
            .put_estimate(&col::IRRADIANCE_REF_RMSE, &rmse);
        if let Some((_, pm)) = baselines
            .iter()
            .find(|(c, _)| *c == EngineChoice::PhotonMap)
        {
            let pm_replicas = cfg
                .engines
                .iter()
                .zip(&engines)
                .find(|(&c, _)| c == EngineChoice::PhotonMap)
                .map_or_else(Vec::new, |(_, e)| e.replica_points());
            let (bias, rmse) = engines::against_reference(pm, &pm_replicas, refr);
            row.put_estimate(&col::PHOTON_MAP_REF_BIAS, &bias)
                .put_estimate(&col::PHOTON_MAP_REF_RMSE, &rmse);
        }
    }

    // Accuracy against ground truth: the discs with an exact value (all of them where none has one,
    // so the mean irradiance is still reported).
    let with_exact: Vec<usize> = (0..discs.len())
        .filter(|&i| pts.exact[i].is_finite())
        .collect();
    let judged: Vec<usize> = if with_exact.is_empty() {
        (0..discs.len()).collect()
    } else {
        with_exact
    };
    let exact_mean = if pts.exact.iter().any(|x| x.is_finite()) {
        mean_over(&pts.exact, &judged)
    } else {
        f64::NAN
    };
    let errs: Vec<(f64, f64)> = irr.iter().map(|e| engines::errors(e, &pts.exact)).collect();
    let mut mean_irr = engines::per_replica(
        &irr.iter()
            .map(|e| mean_over(e, &judged))
            .collect::<Vec<_>>(),
    );
    if irr.len() == 1 && !judged.is_empty() {
        // One replica: the Poisson SE of the mean over the n judged points, each point's sum
        // counted as independent (as the points table does per point): √(Σ Ē·w̄/(π·d_i²))/n, which
        // is √(Ē·w̄/(πd²·n)) when every disc has radius d. With it the mean is judged against an
        // exact value instead of "n/a".
        let n = judged.len() as f64;
        let var: f64 = judged
            .iter()
            .map(|&i| mean_irr.mean.max(0.0) * mean_segment_watts / discs.area(i))
            .sum();
        mean_irr.se = var.sqrt() / n;
        mean_irr.clusters = judged.len() as u64;
    }
    let engine_s: f64 = engines.iter().map(|e| e.seconds()).sum();
    let rays_per_s = segments as f64 / engine_s.max(1e-12);
    let mut summary = Vec::new();
    Metric::new(&col::IRRADIANCE, mean_irr, Theory::Prediction(exact_mean))
        .write(&mut row, &mut summary);
    row.put_estimate(
        &col::IRRADIANCE_RMSE,
        &engines::per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
    )
    .put_estimate(
        &col::IRRADIANCE_BIAS,
        &engines::per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>()),
    )
    .put(&col::RAYS_PER_S, rays_per_s);

    let law = Law {
        root_radius,
        law_radius,
        lines: cfg.scene().is_none(),
    };
    let mut tables = DetpTables::default();
    let mut lines = Vec::new();
    for e in &engines {
        let (rows, mut l) = e.levels(&pooled, &law);
        tables.levels.extend(rows);
        lines.append(&mut l);
    }
    // Levels first, then the point's own metrics.
    lines.append(&mut summary);

    // Points table: DETP's estimate and SE per disc, then each baseline's.
    if cfg.write_points {
        for (i, &(mean, se)) in detp_points.iter().enumerate() {
            let (c, nn) = (discs.centers[i], discs.normals[i]);
            let mut r = Row::default();
            r.put(&col::SAMPLE, i)
                .put(&col::X, c.x)
                .put(&col::Y, c.y)
                .put(&col::Z, c.z)
                .put(&col::NX, nn.x)
                .put(&col::NY, nn.y)
                .put(&col::NZ, nn.z)
                .put(&col::POINT_DISC_RADIUS, discs.radius_of(i))
                .put(&col::POINT_IRRADIANCE_MEAN, mean)
                .put(&col::POINT_IRRADIANCE_SE, se);
            if irr.len() >= 2 {
                for (k, e) in irr.iter().enumerate() {
                    r.put_member(&col::POINT_IRRADIANCE_REPLICA, &k.to_string(), e[i]);
                }
            }
            r.put(&col::POINT_IRRADIANCE_EXACT, pts.exact[i]);
            for (c, v) in &baselines {
                r.put_member(&col::POINT_BASELINE_E, c.column(), v[i].0)
                    .put_member(&col::POINT_BASELINE_SE, c.column(), v[i].1);
            }
            tables.points.push(r);
        }
    }
    let mut warnings = Vec::new();
    if !discs.is_empty() && irr.iter().all(|e| e.iter().all(|&x| x == 0.0)) {
        warnings.push(format!(
            "no photon crossed any of the {} discs: the irradiance is 0 everywhere (do the lights face the points? is d too small for {} photons?)",
            discs.len(),
            cfg.photons
        ));
    }
    Ok(PointOutput {
        row,
        tables,
        summary: lines,
        checks: vec![Check {
            name: col::MISMATCHES.name,
            what: "discs where the DETP engines or brute force disagree",
            failures: mismatches,
            checked: bf_checked.max(discs.len() as u64 * cfg.replicas),
        }],
        rate: Rate {
            per_s: rays_per_s,
            unit: "segments",
        },
        warnings,
    })
}

crate::side_tables!(
    /// `NAME.levels.csv` (one row per sphere-cache level) and, with `detp.write_points`,
    /// `NAME.points.csv` (one row per sample point).
    DetpTables { levels, points }
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
            spec::lattice_spacing(*k)
        ),
        Points::Surface(s) => format!("surface points at spacing {s}"),
        Points::File(p) => format!("{} points from {}", p.centers.len(), p.path.display()),
    };
    let engines: Vec<&str> = cfg.engines.iter().map(|e| e.as_str()).collect();
    format!(
        "{rays}, {pts}, d = {}, Q = {}, {:?} lists, {:?} pop, order {:?}, engines {}, {} replica(s)",
        cfg.disc_radius,
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
/// path per thread (n_R·Σ Q^{2i} = n_R/(1 − Q²) indices), the discs, and a disc grid's cells.
pub fn memory(cfg: &DetpConfig) -> Memory {
    let segs = cfg.photons as f64 * segments_per_photon(cfg);
    let threads = rayon::current_num_threads() as f64;
    let n_p = cfg.point_count() as f64;
    let mut needs = vec![
        Need {
            bytes: segs * std::mem::size_of::<crate::detp::store::Segment>() as f64,
            key: "detp.photons",
            what: format!("segment store of ~{segs:.3e} segments"),
        },
        Need {
            bytes: n_p * 128.0,
            key: match cfg.points {
                Points::Ball(_) | Points::Grid(_) => "detp.points",
                Points::File(_) => "detp.points_file",
                // Surface points: one per spacing² (the spacing defaults to 2d).
                Points::Surface(_) if cfg.spacing_given => "detp.point_spacing",
                Points::Surface(_) => "detp.disc_radius",
            },
            what: format!("{n_p:.3e} discs and their sums"),
        },
    ];
    if cfg.engines.contains(&EngineChoice::SphereCache) {
        needs.push(Need {
            bytes: segs * 4.0 * threads / (1.0 - cfg.q() * cfg.q()),
            key: "detp.q",
            what: "sphere-cache ray lists (n_R/(1 − Q²) per thread)".into(),
        });
    }
    if cfg.engines.contains(&EngineChoice::PhotonMap) {
        needs.push(Need {
            bytes: segs * 48.0,
            key: "detp.photons",
            what: "photon-map k-d tree of the impacts".into(),
        });
    }
    if let (true, Some(cells)) = (
        cfg.engines.contains(&EngineChoice::DiscIndex),
        cfg.grid_cells(),
    ) {
        needs.push(Need {
            bytes: cells * 4.0,
            key: "detp.index_cell_width",
            what: format!("{cells:.3e} disc-grid cells"),
        });
    }
    Memory {
        needs,
        budget: Some(("detp.memory_budget_gib", cfg.memory_budget_gib)),
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
    const ABOUT: &'static str = "Density estimation on the tangent plane: photon segments (μ-random lines through the unit ball, or photons traced from a scene) crossing discs of radius d on sample points, gathered by the sphere cache (radius ratio Q, threshold, Morton/Hilbert order), a disc index (octree or grid), brute force and, as baselines, Jensen's photon map and a path-traced reference (engine reference: unbiased irradiance per point with its SE, and every engine's bias and RMSE against it). Engines agree bit for bit (integer fixed point) and with brute force on a keyed subset; tests per engine against Theorem 1, rays per level against n_R·Q^(2i), irradiance against the exact value where the source has one.";
    type Raw = DetpSpec;
    type Point = DetpConfig;
    type Tables = DetpTables;
    type Shared = ReferenceCache;

    fn columns() -> Vec<(&'static str, &'static [Column])> {
        vec![
            ("main", col::MAIN),
            ("levels", col::LEVELS),
            ("points", col::POINTS_TABLE),
        ]
    }
    fn configure(raw: DetpSpec, inputs: &mut Inputs) -> Result<DetpConfig, ConfigError> {
        if raw.detp.engine.is_some() {
            return refuse(
                "detp.engine",
                "belongs to kind quasi-static (it chooses the engine of moving frames); kind \"detp\" runs the engines listed in detp.engines",
            );
        }
        DetpConfig::from_raw(raw.experiment.seed, &raw.detp, inputs)
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
    fn memory(p: &DetpConfig) -> Memory {
        memory(p)
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
    ) -> Result<PointOutput<DetpTables>, Error> {
        run_point(p, ctx.index, ctx.progress, refs)
    }
}
