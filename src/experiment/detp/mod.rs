//! Kind `detp`: one point builds a ray store (μ-random lines through the unit ball, or photons traced
//! from a scene), discs on sample points, and runs the engines the spec names on it, once per replica:
//!
//! - `sphere-cache`: the hierarchy of spheres (points visited in Morton/Hilbert/no order), with its
//!   counters per level — rays held, rebuilds (cache misses), ray–sphere tests — against
//!   n_R·Q^(2i) and Theorem 1;
//! - `disc-index`: the discs in an octree or a grid that every segment traverses, against Theorem 1;
//! - `brute-force`: every segment against every disc;
//! - `photon-map`: Jensen's k-nearest-neighbour estimate over the same photons (scenes only).
//!
//! The DETP engines must give the same integer sum on every disc, bit for bit; on top of that a keyed
//! random subset of `brute_force_points` discs is re-computed by brute force. Any difference is a
//! `mismatches` count, and the runner fails the run on a non-zero one (keeping the table as evidence).
//!
//! Columns (counts are totals over the point's replicas; estimates are `_mean/_se/_n` with one
//! cluster per replica, so their standard errors cover independent ray sets):
//! `segments`, `points`, per engine `tests_E`, `cost_E_s` (E = sphere_cache, disc_index,
//! brute_force, photon_map) and, where Theorem 1 has one, `tests_E_theory`; the sphere cache's
//! `ray_sphere_tests` and `ray_disc_tests`; the index's `nodes_disc_index`; `mismatches`,
//! `bf_checked`; accuracy against the exact irradiance where the source has one
//! (`irradiance_rmse`, `irradiance_bias`, `photon_map_rmse`, `photon_map_bias`). Side tables:
//! `levels` (one row per sphere-cache level) and, with `detp.write_points`, `points`.

use std::time::Instant;

use glam::DVec3;
use rand::seq::index::sample as sample_indices;
use rayon::prelude::*;

mod lines;
mod scene;

use super::metric::{Metric, Theory};
use super::{PointResult, Row};
use crate::detp::disc::Discs;
use crate::detp::disc_index::DiscIndex;
use crate::detp::fixed::{Acc, PowerScale};
use crate::detp::store::SegmentStore;
use crate::detp::{brute, disc_index, order, sphere_cache};
use crate::sample::lines::uniform_in_ball;
use crate::sample::rng::{domain, stream};
use crate::spec::detp::{EngineChoice, IndexChoice, ListModeChoice, OrderChoice, Points, Rays};
use crate::spec::DetpConfig;
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

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
}

/// The sample points of a point (shared by its replicas) with their exact irradiance where known.
pub(crate) struct PointSet {
    pub(crate) discs: Discs,
    /// Exact irradiance per disc, NaN where the source has none.
    pub(crate) exact: Vec<f64>,
}

/// Sample points of a lines point (uniform in the ball, or a user's CSV): drawn once per point (all
/// replicas share them, only the rays change).
fn points(cfg: &DetpConfig, point: u64) -> anyhow::Result<PointSet> {
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
        Points::File(p) => {
            crate::detp::surface_points::read_points_csv(p).map_err(anyhow::Error::msg)?
        }
        Points::Surface(_) => {
            anyhow::bail!("surface points need a scene (the spec check refuses this)")
        }
    };
    let discs = Discs::new(centers, normals, cfg.disc_radius).map_err(anyhow::Error::msg)?;
    let exact = match cfg.rays {
        Rays::Lines => discs
            .centers
            .iter()
            .map(|&c| lines::exact(cfg.photons, c, cfg.disc_radius))
            .collect(),
        Rays::Scene(_) => vec![f64::NAN; discs.len()],
    };
    Ok(PointSet { discs, exact })
}

/// What the engines of one replica produced.
#[derive(Default)]
struct ReplicaOut {
    /// The agreed sums (the first DETP engine's), per disc.
    acc: Vec<Acc>,
    mismatches: u64,
    bf_checked: u64,
    cache: Option<sphere_cache::CacheStats>,
    cache_s: f64,
    order_s: f64,
    index: Option<disc_index::IndexStats>,
    index_s: f64,
    index_build_s: f64,
    index_bytes: u64,
    brute_tests: u64,
    brute_s: f64,
    photon_map: Option<Vec<f64>>,
    photon_map_s: f64,
    segments: u64,
    rays_in_root: u64,
    trace_s: f64,
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let s = Instant::now();
    let v = f();
    (v, s.elapsed().as_secs_f64())
}

/// Runs every engine of the spec on one replica's rays.
fn run_engines(
    cfg: &DetpConfig,
    point: u64,
    rays: &RaySet,
    pts: &PointSet,
) -> anyhow::Result<ReplicaOut> {
    let discs = &pts.discs;
    let n = discs.len();
    let mut out = ReplicaOut {
        segments: rays.store.len() as u64,
        rays_in_root: rays.rays_in_root,
        trace_s: rays.trace_s,
        ..ReplicaOut::default()
    };
    let mut sums: Vec<Vec<Acc>> = Vec::new();
    for engine in &cfg.engines {
        match engine {
            EngineChoice::SphereCache => {
                let ord = match cfg.order {
                    OrderChoice::None => order::Order::None,
                    OrderChoice::Morton => order::Order::Morton,
                    OrderChoice::Hilbert => order::Order::Hilbert,
                };
                let (perm, order_s) =
                    timed(|| order::permutation(&discs.centers, ord, cfg.order_bits));
                let params = sphere_cache::SphereCacheParams {
                    q: cfg.q,
                    threshold: cfg.threshold as usize,
                    list_mode: match cfg.list_mode {
                        ListModeChoice::Exact => sphere_cache::ListMode::Exact,
                        ListModeChoice::Inherited => sphere_cache::ListMode::Inherited,
                    },
                    chunk_points: cfg.chunk_points as usize,
                    law_ball: rays.law_ball,
                };
                let mut acc = vec![0; n];
                let (stats, s) = timed(|| {
                    sphere_cache::run(&rays.store, discs, &perm, rays.root, &params, &mut acc)
                });
                out.cache = Some(stats);
                out.cache_s = s;
                out.order_s = order_s;
                sums.push(acc);
            }
            EngineChoice::DiscIndex => {
                let mut acc = vec![0; n];
                let (stats, build_s, s, bytes) = match cfg.index {
                    IndexChoice::Octree => {
                        let (ix, b) = timed(|| {
                            disc_index::Octree::build(
                                discs,
                                cfg.octree_leaf as usize,
                                cfg.disc_radius,
                            )
                        });
                        let (st, s) = timed(|| ix.accumulate(&rays.store, None, 1, &mut acc));
                        (st, b, s, ix.bytes())
                    }
                    IndexChoice::Grid => {
                        let (ix, b) =
                            timed(|| disc_index::GridIndex::build(discs, cfg.index_cell_width));
                        let (st, s) = timed(|| ix.accumulate(&rays.store, None, 1, &mut acc));
                        (st, b, s, ix.bytes())
                    }
                };
                out.index = Some(stats);
                out.index_s = s;
                out.index_build_s = build_s;
                out.index_bytes = bytes as u64;
                sums.push(acc);
            }
            EngineChoice::BruteForce => {
                let mut acc = vec![0; n];
                let (tests, s) = timed(|| brute::accumulate(&rays.store, discs, None, 1, &mut acc));
                out.brute_tests = tests;
                out.brute_s = s;
                sums.push(acc);
            }
            EngineChoice::PhotonMap => {
                let (e, s) = timed(|| scene::photon_map(cfg, &rays.store, discs));
                out.photon_map = Some(e);
                out.photon_map_s = s;
            }
        }
    }
    // Every DETP engine against the first, disc by disc.
    if let Some((first, rest)) = sums.split_first() {
        let differ = |i: usize| rest.iter().any(|o| o[i] != first[i]);
        out.mismatches = (0..n).filter(|&i| differ(i)).count() as u64;
        // A keyed subset against brute force (unless brute force ran on everything already).
        if !cfg.engines.contains(&EngineChoice::BruteForce) && cfg.brute_force_points > 0 {
            let k = (cfg.brute_force_points as usize).min(n);
            let mut rng = stream(&[domain::CHECK, cfg.seed, point]);
            let mut subset: Vec<u32> = sample_indices(&mut rng, n, k)
                .into_iter()
                .map(|i| i as u32)
                .collect();
            subset.sort_unstable();
            let mut bf = vec![0; n];
            brute::accumulate(&rays.store, discs, Some(&subset), 1, &mut bf);
            out.mismatches += subset
                .iter()
                .filter(|&&i| bf[i as usize] != first[i as usize])
                .count() as u64;
            out.bf_checked = k as u64;
        } else if cfg.engines.contains(&EngineChoice::BruteForce) {
            out.bf_checked = n as u64;
        }
        out.acc = first.clone();
    }
    Ok(out)
}

/// Root-mean-square error and mean error of `est` against `exact` over the discs that have an exact
/// value (NaN, NaN if none has).
fn errors(est: &[f64], exact: &[f64]) -> (f64, f64) {
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

/// One estimate from one value per replica (one cluster each).
fn per_replica(values: &[f64]) -> Estimate {
    let mut m = ClusteredMean::default();
    for &v in values {
        m.push_cluster(1, v, v * v);
    }
    m.estimate()
}

/// One DETP point: every replica, then the row, the levels table and (if asked) the points table.
pub fn run_point(
    cfg: &DetpConfig,
    point: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> anyhow::Result<PointResult> {
    let scene = scene::load(cfg)?;
    let pts = match &scene {
        None => points(cfg, point)?,
        Some(s) => scene::points(cfg, point, s)?,
    };
    let discs = &pts.discs;
    let d = cfg.disc_radius;
    let area = std::f64::consts::PI * d * d;
    let mut outs = Vec::with_capacity(cfg.replicas as usize);
    let mut scale = PowerScale::for_max_power(1.0);
    let mut law_radius = 1.0;
    let mut root_radius = 1.0;
    let mut mean_segment_watts = 0.0;
    for replica in 0..cfg.replicas {
        let rays = match &scene {
            None => lines::lines(cfg, point, replica),
            Some(s) => scene::photons(cfg, point, replica, s, &pts.discs),
        };
        scale = rays.store.scale;
        law_radius = rays.law_radius;
        root_radius = rays.root.1;
        mean_segment_watts = if rays.store.is_empty() {
            0.0
        } else {
            rays.store
                .segments
                .iter()
                .map(|s| scale.watts(i64::from(s.power)))
                .sum::<f64>()
                / rays.store.len() as f64
        };
        outs.push(run_engines(cfg, point, &rays, &pts)?);
        progress(cfg.photons);
    }
    let irr: Vec<Vec<f64>> = outs
        .iter()
        .map(|o| o.acc.iter().map(|&a| scale.watts(a) / area).collect())
        .collect();

    let mut row = Row::default();
    let total = |f: &dyn Fn(&ReplicaOut) -> u64| outs.iter().map(f).sum::<u64>();
    let secs = |f: &dyn Fn(&ReplicaOut) -> f64| outs.iter().map(f).sum::<f64>();
    let reps = cfg.replicas as f64;
    let n_p = discs.len() as f64;
    let n_r = outs.iter().map(|o| o.rays_in_root).sum::<u64>() as f64 / reps;
    row.u("segments", total(&|o| o.segments))
        .u("points", discs.len() as u64)
        .f("trace_s", secs(&|o| o.trace_s));
    let (t_r, t_i) = th::sphere_cache_cost(1.0, 1.0, n_r, n_p, cfg.q);
    let mut engine_s = 0.0;
    for engine in &cfg.engines {
        let c = engine.column();
        match engine {
            EngineChoice::SphereCache => {
                let st = |o: &ReplicaOut| o.cache.clone().unwrap_or_default();
                let sphere = total(&|o| st(o).ray_sphere_tests);
                let disc = total(&|o| st(o).ray_disc_tests);
                row.u(format!("tests_{c}"), sphere + disc)
                    .f(format!("tests_{c}_theory"), reps * (t_r + t_i))
                    .u("ray_sphere_tests", sphere)
                    .f("ray_sphere_tests_theory", reps * t_r)
                    .u("ray_disc_tests", disc)
                    .f("ray_disc_tests_theory", reps * t_i)
                    .f(format!("cost_{c}_s"), secs(&|o| o.cache_s))
                    .f("order_s", secs(&|o| o.order_s));
                engine_s += secs(&|o| o.cache_s);
            }
            EngineChoice::DiscIndex => {
                let st = |o: &ReplicaOut| o.index.unwrap_or_default();
                row.u(format!("tests_{c}"), total(&|o| st(o).ray_disc_tests))
                    .f(
                        format!("tests_{c}_theory"),
                        reps * th::disc_index_cost(1.0, n_r, n_p),
                    )
                    .u(format!("nodes_{c}"), total(&|o| st(o).nodes_visited))
                    .f(format!("cost_{c}_s"), secs(&|o| o.index_s))
                    .f(format!("build_{c}_s"), secs(&|o| o.index_build_s))
                    .u(
                        format!("bytes_{c}"),
                        outs.iter().map(|o| o.index_bytes).max().unwrap_or(0),
                    );
                engine_s += secs(&|o| o.index_s);
            }
            EngineChoice::BruteForce => {
                row.u(format!("tests_{c}"), total(&|o| o.brute_tests))
                    .f(format!("tests_{c}_theory"), reps * n_r * n_p)
                    .f(format!("cost_{c}_s"), secs(&|o| o.brute_s));
                engine_s += secs(&|o| o.brute_s);
            }
            EngineChoice::PhotonMap => {
                let errs: Vec<(f64, f64)> = outs
                    .iter()
                    .map(|o| errors(o.photon_map.as_deref().unwrap_or(&[]), &pts.exact))
                    .collect();
                row.estimate(
                    "photon_map_rmse",
                    &per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
                )
                .estimate(
                    "photon_map_bias",
                    &per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>()),
                )
                .f(format!("cost_{c}_s"), secs(&|o| o.photon_map_s));
            }
        }
    }
    row.u("mismatches", total(&|o| o.mismatches))
        .u("bf_checked", total(&|o| o.bf_checked));
    let errs: Vec<(f64, f64)> = irr.iter().map(|e| errors(e, &pts.exact)).collect();
    let exact_mean = {
        let v: Vec<f64> = pts
            .exact
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let rmse = per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>());
    let bias = per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>());
    // The mean over the discs that have an exact value (all of them where none has).
    let judged: Vec<usize> = match (0..discs.len())
        .filter(|&i| pts.exact[i].is_finite())
        .collect::<Vec<_>>()
    {
        v if v.is_empty() => (0..discs.len()).collect(),
        v => v,
    };
    let mean_irr = per_replica(
        &irr.iter()
            .map(|e| judged.iter().map(|&i| e[i]).sum::<f64>() / judged.len().max(1) as f64)
            .collect::<Vec<_>>(),
    );
    let mut summary = Vec::new();
    Metric::new("irradiance", mean_irr, Theory::Prediction(exact_mean))
        .write(&mut row, &mut summary);
    row.estimate("irradiance_rmse", &rmse)
        .estimate("irradiance_bias", &bias)
        .f(
            "rays_per_s",
            total(&|o| o.segments) as f64 / engine_s.max(1e-12),
        );

    // Levels table.
    let mut levels = Vec::new();
    let mut level_lines = Vec::new();
    let depth = outs
        .iter()
        .filter_map(|o| o.cache.as_ref().map(|c| c.levels.len()))
        .max()
        .unwrap_or(0);
    for i in 0..depth {
        let level = |o: &ReplicaOut| o.cache.as_ref().and_then(|c| c.levels.get(i).cloned());
        let mut m = ClusteredMean::default();
        let mut inside = ClusteredMean::default();
        let (mut builds, mut misses, mut tests) = (0u64, 0u64, 0u64);
        let mut radius = f64::NAN;
        for o in &outs {
            let l = level(o).unwrap_or_default();
            m.push_cluster(l.builds, l.rays_held as f64, l.rays_held_sq as f64);
            inside.push_cluster(
                l.inside_builds,
                l.inside_rays_held as f64,
                l.inside_rays_held_sq as f64,
            );
            builds += l.builds;
            misses += l.misses;
            tests += l.ray_sphere_tests;
            if l.builds > 0 {
                radius = l.radius;
            }
        }
        let e = m.estimate();
        let r0 = root_radius;
        let ri = r0 * cfg.q.powi(i as i32);
        let theory = n_r * (ri / law_radius).min(1.0).powi(2);
        let clipped = match cfg.rays {
            // The root is concentric with the ball and holds it: every line.
            Rays::Lines if i == 0 => n_r,
            Rays::Lines => th::rays_per_level_uniform_centres(n_r, law_radius, ri.min(law_radius)),
            Rays::Scene(_) => f64::NAN,
        };
        let mut r = Row::default();
        r.u("level", i as u64)
            .f("radius", if radius.is_finite() { radius } else { ri })
            .u("builds_level", builds)
            .estimate("rays_level", &e)
            .f("rays_level_theory", theory)
            .f("rays_level_theory_clipped", clipped)
            .estimate("rays_level_inside", &inside.estimate())
            .u("misses_level", misses)
            .u("ray_sphere_tests_level", tests);
        levels.push(r);
        if e.n > 0 {
            level_lines.push((
                format!("rays L{i}"),
                e,
                format!("{theory:.4} (n_R·(r_i/r_law)²)"),
                super::metric::z_verdict(&e, theory),
            ));
        }
    }
    // Levels first, then the point's own metrics.
    level_lines.append(&mut summary);
    let mut summary = level_lines;
    let mismatches = total(&|o| o.mismatches);
    summary.push((
        "mismatch".into(),
        Estimate {
            mean: mismatches as f64,
            se: 0.0,
            n: total(&|o| o.bf_checked),
            clusters: outs.len() as u64,
        },
        "0 (engines = brute force)".into(),
        if mismatches == 0 {
            "ok (exact)"
        } else {
            "FAIL"
        }
        .into(),
    ));

    // Points table: mean over replicas, SE across them (or, with one replica, the Poisson SE of a sum
    // of segments of the mean segment power: √(E·w̄/πd²)).
    let mut point_rows = Vec::new();
    if cfg.write_points {
        for i in 0..discs.len() {
            let v: Vec<f64> = irr.iter().map(|e| e[i]).collect();
            let mut est = per_replica(&v);
            if outs.len() == 1 {
                est.se = (est.mean.max(0.0) * mean_segment_watts / area).sqrt();
            }
            let (c, nn) = (discs.centers[i], discs.normals[i]);
            let mut r = Row::default();
            r.u("sample", i as u64)
                .f("x", c.x)
                .f("y", c.y)
                .f("z", c.z)
                .f("nx", nn.x)
                .f("ny", nn.y)
                .f("nz", nn.z)
                .f("irradiance_mean", est.mean)
                .f("irradiance_se", est.se)
                .f("irradiance_exact", pts.exact[i]);
            point_rows.push(r);
        }
    }
    Ok(PointResult {
        row,
        tables: vec![("levels", levels), ("points", point_rows)],
        summary,
        rays_per_s: total(&|o| o.segments) as f64 / engine_s.max(1e-12),
    })
}

/// One line describing a DETP point for `raycost check`.
pub fn describe(cfg: &DetpConfig) -> String {
    let rays = match &cfg.rays {
        Rays::Lines => format!("{} μ-random lines", cfg.photons),
        Rays::Scene(p) => format!("{} photons from {}", cfg.photons, p.display()),
    };
    let pts = match &cfg.points {
        Points::Ball(n) => format!("{n} points in the unit ball"),
        Points::Surface(s) => format!("surface points at spacing {s}"),
        Points::File(p) => format!("points from {}", p.display()),
    };
    let engines: Vec<&str> = cfg.engines.iter().map(|e| e.as_str()).collect();
    format!(
        "{rays}, {pts}, d = {}, Q = {}, order {}, engines {}, {} replica(s)",
        cfg.disc_radius,
        cfg.q,
        cfg.order.as_str(),
        engines.join("+"),
        cfg.replicas
    )
}
