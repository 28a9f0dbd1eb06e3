//! The engines of kind `detp`, one [`Engine`] each: what it runs on a replica's rays and points, and
//! what it measured over all replicas, typed ([`EngineMeasured`]; `columns.rs` declares each
//! engine's columns). A new engine is one struct here, one line in [`engine`] and its table in
//! `columns.rs`; the point runner (`mod.rs`) treats them all alike.
//!
//! DETP engines return their integer sum per disc, which the runner compares across engines and
//! against brute force; baselines (the photon map) return per-disc estimates instead.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::config::DetpConfig;
use super::spec::{EngineChoice, FilterChoice};
use super::{PointSet, RaySet};
use crate::detp::disc_index::{DiscIndex, IndexKind, IndexStats};
use crate::detp::fixed::Acc;
use crate::detp::photon_map::{self, Filter};
use crate::detp::{brute, disc_index, order, sphere_cache};
use super::path_tracing::{PathMeasured, PathTracing};
use crate::lt::reference::{self, Irradiance};
use crate::sample::rng::{domain, hash_key, mix64};
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

/// What one replica's engine returned.
pub(super) enum Output {
    /// Integer sums per disc (a DETP engine: must equal every other DETP engine's, bit for bit).
    Sums(Vec<Acc>),
    /// A baseline's estimates (kept by the engine for its own columns; not compared).
    Baseline,
}

/// One replica's engine counts over a subset of its photons (`--photon-shard`): counts that add
/// across disjoint photon subsets, so the sum over a run's shards is what the engine counts on all
/// its photons. An engine whose counts do not add (the sphere cache's builds depend on how many
/// rays a sphere holds; the photon map's neighbours on every photon) has none.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, PartialEq)]
pub enum EnginePart {
    /// The disc index: its [`IndexStats`] (nodes, box tests, DDA steps, disc tests), build,
    /// query and traversal-alone seconds, bytes.
    DiscIndex {
        /// Nodes visited, box tests, DDA steps, disc tests.
        stats: [u64; 4],
        /// Build seconds.
        build_s: f64,
        /// Query seconds.
        query_s: f64,
        /// Seconds of the same walk without disc tests ([`DiscIndex::traversal_only`]).
        traversal_s: f64,
        /// Bytes of the index.
        bytes: usize,
    },
    /// Brute force: its tests and seconds.
    BruteForce {
        /// Segment–disc tests.
        tests: u64,
        /// Seconds.
        seconds: f64,
    },
    /// The reference: photon-independent, computed where the shards are merged.
    Reference,
    /// The path-tracing competitor: photon-independent, computed where the shards are merged.
    PathTracing,
}

impl EnginePart {
    /// The part of the union of two disjoint photon subsets (seconds add; bytes are the larger).
    pub fn add(&self, o: &Self) -> Option<Self> {
        Some(match (self, o) {
            (
                Self::DiscIndex {
                    stats: a,
                    build_s,
                    query_s,
                    traversal_s,
                    bytes,
                },
                Self::DiscIndex {
                    stats: b,
                    build_s: b_build,
                    query_s: b_query,
                    traversal_s: b_traversal,
                    bytes: b_bytes,
                },
            ) => Self::DiscIndex {
                stats: std::array::from_fn(|i| a[i] + b[i]),
                build_s: build_s + b_build,
                query_s: query_s + b_query,
                traversal_s: traversal_s + b_traversal,
                bytes: (*bytes).max(*b_bytes),
            },
            (
                Self::BruteForce { tests, seconds },
                Self::BruteForce {
                    tests: t,
                    seconds: s,
                },
            ) => Self::BruteForce {
                tests: tests + t,
                seconds: seconds + s,
            },
            (Self::Reference, Self::Reference) => Self::Reference,
            (Self::PathTracing, Self::PathTracing) => Self::PathTracing,
            _ => return None,
        })
    }
}

/// What the point knows when its engines pool their replicas.
pub(super) struct Pooled<'a> {
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
pub(super) struct Law {
    /// Root radius r_0.
    pub root_radius: f64,
    /// Radius of the ball the rays are μ-random in.
    pub law_radius: f64,
    /// Lines (the lens-clipped law applies) or photons.
    pub lines: bool,
}

/// One engine (see the module doc).
pub(super) trait Engine: Send {
    /// Runs on one replica.
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output;
    /// Engine seconds over all replicas so far (for `rays_per_s`).
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
    fn as_path_tracing(&self) -> Option<&PathTracing> {
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

/// What an engine measured over a point's replicas.
#[derive(Clone, Debug)]
pub enum EngineMeasured {
    /// The sphere cache.
    SphereCache(CacheMeasured),
    /// The disc index.
    DiscIndex(IndexMeasured),
    /// Brute force.
    BruteForce(BruteMeasured),
    /// The photon map (a baseline).
    PhotonMap(MapMeasured),
    /// The photon map with a k growing with the photons (a baseline).
    PhotonMapGrowing(MapMeasured),
    /// Per-point path tracing (the competitor, a baseline).
    PathTracing(PathMeasured),
    /// The path-traced reference (a baseline): its seconds.
    Reference(f64),
}

/// The sphere cache's counts, summed over replicas.
#[derive(Clone, Debug)]
pub struct CacheMeasured {
    /// The point's sizes (Theorem 1's input).
    pub sizes: Sizes,
    /// Ray–sphere tests.
    pub sphere_tests: u64,
    /// Ray–disc tests.
    pub disc_tests: u64,
    /// Segments copied into lists.
    pub rays_copied: u64,
    /// Spheres built.
    pub spheres_built: u64,
    /// Pop repairs (`detp.pop_rule = "paper"`).
    pub pop_repairs: u64,
    /// Engine seconds.
    pub seconds: f64,
    /// Seconds sorting the points (what it pays before any point's work).
    pub order_s: f64,
    /// Tests per replica, with their spread.
    pub tests_per_replica: Estimate,
    /// Seconds per replica, with their spread.
    pub seconds_per_replica: Estimate,
}

/// The disc index's counts, summed over replicas.
#[derive(Clone, Debug)]
pub struct IndexMeasured {
    /// The point's sizes.
    pub sizes: Sizes,
    /// Traversal and tests.
    pub stats: IndexStats,
    /// Engine seconds.
    pub seconds: f64,
    /// Build seconds.
    pub build_s: f64,
    /// Bytes of the largest replica's index.
    pub bytes: usize,
    /// Tests per replica, with their spread.
    pub tests_per_replica: Estimate,
    /// Seconds per replica, with their spread.
    pub seconds_per_replica: Estimate,
    /// Seconds per replica of the same walk without disc tests (eq. 8's traversal), with their
    /// spread.
    pub traversal_per_replica: Estimate,
}

/// Brute force's tests, summed over replicas.
#[derive(Clone, Debug)]
pub struct BruteMeasured {
    /// The point's sizes.
    pub sizes: Sizes,
    /// Ray–disc tests.
    pub tests: u64,
    /// Engine seconds.
    pub seconds: f64,
    /// Tests per replica, with their spread.
    pub tests_per_replica: Estimate,
    /// Seconds per replica, with their spread.
    pub seconds_per_replica: Estimate,
}

/// The photon map against the exact irradiance, one sample per replica.
#[derive(Clone, Debug)]
pub struct MapMeasured {
    /// Root-mean-square error.
    pub rmse: Estimate,
    /// Mean error.
    pub bias: Estimate,
    /// Seconds of the queries (per point), summed over replicas.
    pub seconds: f64,
    /// Seconds building the kd-tree (once per photon set), summed over replicas.
    pub build_s: f64,
    /// The k it used.
    pub k: u64,
}

/// One row of `NAME.levels.csv`: one sphere-cache level over the point's replicas.
#[derive(Clone, Debug)]
pub struct LevelRow {
    /// Level i.
    pub level: u64,
    /// Its radius (as built, else r_0·Q^i).
    pub radius: f64,
    /// Spheres built.
    pub builds: u64,
    /// Rays held per sphere built.
    pub rays: Estimate,
    /// The uniform-line law n_R·(r_i/r_law)².
    pub law: f64,
    /// Lines: the law for centres uniform in the ball, clipped (NaN for photons).
    pub clipped: f64,
    /// Rays held by spheres inside the law's ball.
    pub inside: Estimate,
    /// Rays held by the spheres never subdivided.
    pub leaf: Estimate,
    /// Cache misses.
    pub misses: u64,
    /// Misses per replica, with their spread.
    pub misses_per_replica: Estimate,
    /// Segments copied into this level's lists.
    pub copied: u64,
    /// Ray–sphere tests building them.
    pub sphere_tests: u64,
    /// Whether the rays are μ-random lines (the law applies) or photons (shown, not judged).
    pub lines: bool,
}
/// The engine for a choice of `detp.engines` (the reference reads and fills the run's `cache`).
pub(super) fn engine(e: EngineChoice, cache: &ReferenceCache) -> Box<dyn Engine> {
    match e {
        EngineChoice::SphereCache => Box::new(SphereCache::default()),
        EngineChoice::DiscIndex => Box::new(Index::default()),
        EngineChoice::BruteForce => Box::new(BruteForce::default()),
        EngineChoice::PhotonMap => Box::new(PhotonMap::default()),
        EngineChoice::PhotonMapGrowing => Box::new(PhotonMap {
            growing: true,
            ..PhotonMap::default()
        }),
        EngineChoice::PathTracing => Box::new(PathTracing::new(cache.clone())),
        EngineChoice::Reference => Box::new(Reference {
            cache: cache.clone(),
            result: None,
        }),
    }
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

/// The sphere cache.
#[derive(Default)]
struct SphereCache {
    runs: Vec<(sphere_cache::CacheStats, f64, f64)>,
}

impl Engine for SphereCache {
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let discs = &pts.discs;
        let (perm, order_s) =
            timed(|| order::permutation(&discs.centers, cfg.order, cfg.order_bits));
        let params = sphere_cache::SphereCacheParams {
            law_ball: rays.law_ball,
            ..cfg.cache
        };
        let mut acc = vec![0; discs.len()];
        let (stats, s) =
            timed(|| sphere_cache::run(&rays.store, discs, &perm, rays.root, &params, &mut acc));
        self.runs.push((stats, s, order_s));
        Output::Sums(acc)
    }
    fn seconds(&self) -> f64 {
        self.runs.iter().map(|r| r.1).sum()
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let tests: Vec<f64> = self
            .runs
            .iter()
            .map(|r| (r.0.ray_sphere_tests + r.0.ray_disc_tests) as f64)
            .collect();
        let secs: Vec<f64> = self.runs.iter().map(|r| r.1).collect();
        EngineMeasured::SphereCache(CacheMeasured {
            sizes: p.sizes,
            sphere_tests: self.runs.iter().map(|r| r.0.ray_sphere_tests).sum(),
            disc_tests: self.runs.iter().map(|r| r.0.ray_disc_tests).sum(),
            rays_copied: self.runs.iter().map(|r| r.0.rays_copied()).sum(),
            spheres_built: self.runs.iter().map(|r| r.0.builds()).sum(),
            pop_repairs: self.runs.iter().map(|r| r.0.pop_repairs).sum(),
            seconds: self.seconds(),
            order_s: self.runs.iter().map(|r| r.2).sum(),
            tests_per_replica: per_replica(&tests),
            seconds_per_replica: per_replica(&secs),
        })
    }
    fn levels(&self, p: &Pooled, law: &Law) -> Vec<LevelRow> {
        let depth = self
            .runs
            .iter()
            .map(|r| r.0.levels.len())
            .max()
            .unwrap_or(0);
        (0..depth).map(|i| self.level(p, law, i)).collect()
    }
}

impl SphereCache {
    /// Level `i` over the replicas.
    fn level(&self, p: &Pooled, law: &Law, i: usize) -> LevelRow {
        let mut m = ClusteredMean::default();
        let mut inside = ClusteredMean::default();
        let mut leaf = ClusteredMean::default();
        let (mut builds, mut misses, mut tests, mut copied) = (0u64, 0u64, 0u64, 0u64);
        let mut misses_per_replica = Vec::with_capacity(self.runs.len());
        let mut radius = f64::NAN;
        for (stats, ..) in &self.runs {
            let l = stats.levels.get(i).cloned().unwrap_or_default();
            m.push_cluster(l.builds, l.rays_held as f64, l.rays_held_sq as f64);
            inside.push_cluster(
                l.inside_builds,
                l.inside_rays_held as f64,
                l.inside_rays_held_sq as f64,
            );
            leaf.push_cluster(
                l.leaf_builds,
                l.leaf_rays_held as f64,
                l.leaf_rays_held_sq as f64,
            );
            builds += l.builds;
            misses += l.misses;
            misses_per_replica.push(l.misses as f64);
            tests += l.ray_sphere_tests;
            copied += l.rays_held;
            if l.builds > 0 {
                radius = l.radius;
            }
        }
        let n_r = p.sizes.n_r;
        let ri = law.root_radius * p.cfg.q().powi(i as i32);
        let clipped = match (law.lines, i) {
            // The root is concentric with the ball and holds it: every line.
            (true, 0) => n_r,
            (true, _) => {
                th::rays_per_level_uniform_centres(n_r, law.law_radius, ri.min(law.law_radius))
            }
            (false, _) => f64::NAN,
        };
        LevelRow {
            level: i as u64,
            radius: if radius.is_finite() { radius } else { ri },
            builds,
            rays: m.estimate(),
            law: n_r * (ri / law.law_radius).min(1.0).powi(2),
            clipped,
            inside: inside.estimate(),
            leaf: leaf.estimate(),
            misses,
            misses_per_replica: per_replica(&misses_per_replica),
            copied,
            sphere_tests: tests,
            lines: law.lines,
        }
    }
}

/// One replica of the disc index.
#[derive(Clone, Copy)]
struct IndexRun {
    stats: IndexStats,
    build_s: f64,
    /// Seconds of the engine's pass (`accumulate`).
    query_s: f64,
    /// Seconds of the walk alone (`traversal_only`), timed after the pass.
    traversal_s: f64,
    bytes: usize,
}

/// The disc index (octree or grid).
#[derive(Default)]
struct Index {
    runs: Vec<IndexRun>,
}

impl Engine for Index {
    /// Builds the index and runs its pass; then, untimed by the pass and adding nothing, walks it
    /// again for the same segments without testing a disc (eq. 8 assumes that walk negligible
    /// against the tests): the same thread pool, so the two seconds compare like for like.
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let discs = &pts.discs;
        let mut acc = vec![0; discs.len()];
        let (ix, build_s): (Box<dyn DiscIndex>, f64) = match cfg.index {
            IndexKind::Octree(leaf) => timed(|| {
                Box::new(disc_index::Octree::build(discs, leaf, cfg.disc_radius))
                    as Box<dyn DiscIndex>
            }),
            IndexKind::Grid(w) => {
                timed(|| Box::new(disc_index::GridIndex::build(discs, w)) as Box<dyn DiscIndex>)
            }
        };
        let (stats, query_s) = timed(|| ix.accumulate(&rays.store, None, 1, &mut acc));
        let (walked, traversal_s) = timed(|| ix.traversal_only(&rays.store, None));
        debug_assert_eq!(walked, stats, "the walk alone is the pass's walk");
        self.runs.push(IndexRun {
            stats,
            build_s,
            query_s,
            traversal_s,
            bytes: ix.bytes(),
        });
        Output::Sums(acc)
    }
    fn seconds(&self) -> f64 {
        self.runs.iter().map(|r| r.query_s).sum()
    }
    fn part(&self) -> Option<EnginePart> {
        let r = self.runs.last()?;
        let st = r.stats;
        Some(EnginePart::DiscIndex {
            stats: [st.nodes_visited, st.box_tests, st.dda_steps, st.ray_disc_tests],
            build_s: r.build_s,
            query_s: r.query_s,
            traversal_s: r.traversal_s,
            bytes: r.bytes,
        })
    }
    fn absorb(&mut self, _cfg: &DetpConfig, _pts: &PointSet, part: &EnginePart) {
        let EnginePart::DiscIndex {
            stats: [nodes_visited, box_tests, dda_steps, ray_disc_tests],
            build_s,
            query_s,
            traversal_s,
            bytes,
        } = *part
        else {
            unreachable!("parts are matched to engines by the merge")
        };
        let stats = IndexStats {
            nodes_visited,
            box_tests,
            dda_steps,
            ray_disc_tests,
        };
        self.runs.push(IndexRun {
            stats,
            build_s,
            query_s,
            traversal_s,
            bytes,
        });
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let per = |f: fn(&IndexRun) -> f64| per_replica(&self.runs.iter().map(f).collect::<Vec<_>>());
        EngineMeasured::DiscIndex(IndexMeasured {
            sizes: p.sizes,
            stats: self
                .runs
                .iter()
                .fold(IndexStats::default(), |a, r| a.merge(r.stats)),
            seconds: self.seconds(),
            build_s: self.runs.iter().map(|r| r.build_s).sum(),
            bytes: self.runs.iter().map(|r| r.bytes).max().unwrap_or(0),
            tests_per_replica: per(|r| r.stats.ray_disc_tests as f64),
            seconds_per_replica: per(|r| r.query_s),
            traversal_per_replica: per(|r| r.traversal_s),
        })
    }
}

/// Brute force: every segment against every disc.
#[derive(Default)]
struct BruteForce {
    runs: Vec<(u64, f64)>,
}

impl Engine for BruteForce {
    fn run(&mut self, _cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let mut acc = vec![0; pts.discs.len()];
        let (tests, s) = timed(|| brute::accumulate(&rays.store, &pts.discs, None, 1, &mut acc));
        self.runs.push((tests, s));
        Output::Sums(acc)
    }
    fn seconds(&self) -> f64 {
        self.runs.iter().map(|r| r.1).sum()
    }
    fn part(&self) -> Option<EnginePart> {
        let &(tests, seconds) = self.runs.last()?;
        Some(EnginePart::BruteForce { tests, seconds })
    }
    fn absorb(&mut self, _cfg: &DetpConfig, _pts: &PointSet, part: &EnginePart) {
        let EnginePart::BruteForce { tests, seconds } = *part else {
            unreachable!("parts are matched to engines by the merge")
        };
        self.runs.push((tests, seconds));
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let tests: Vec<f64> = self.runs.iter().map(|r| r.0 as f64).collect();
        let secs: Vec<f64> = self.runs.iter().map(|r| r.1).collect();
        EngineMeasured::BruteForce(BruteMeasured {
            sizes: p.sizes,
            tests: self.runs.iter().map(|r| r.0).sum(),
            seconds: self.seconds(),
            tests_per_replica: per_replica(&tests),
            seconds_per_replica: per_replica(&secs),
        })
    }
}

/// Jensen's photon map over the same photons' impacts (a baseline): with a fixed k
/// (`photon-map`), or k(N) = k₀·(N/N₀)^β growing with the photons so that its error keeps falling
/// (`photon-map-growing`). With `detp.direct = "nee"` the store holds the indirect segments only
/// and the NEE direct part is added at each point, as for DETP.
#[derive(Default)]
struct PhotonMap {
    /// k grows with the photons.
    growing: bool,
    /// Per replica: estimates, query seconds, build seconds.
    runs: Vec<(Vec<f64>, f64, f64)>,
}

impl PhotonMap {
    /// The k at this point's photon count.
    fn k(&self, cfg: &DetpConfig) -> usize {
        if self.growing {
            cfg.k_growth.k(cfg.photons)
        } else {
            cfg.photon_map_k as usize
        }
    }
}

impl Engine for PhotonMap {
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let filter = match cfg.photon_map_filter {
            FilterChoice::Cone => Filter::Cone,
            FilterChoice::Disc => Filter::Disc,
        };
        let (map, build_s) = timed(|| photon_map::PhotonMap::build(&rays.store));
        let (mut e, s) = timed(|| {
            map.estimate(&pts.discs.centers, &pts.discs.normals, self.k(cfg), filter)
        });
        if let Some(direct) = &rays.direct {
            for (e, d) in e.iter_mut().zip(&direct.values) {
                *e += d.mean;
            }
        }
        self.runs.push((e, s, build_s));
        Output::Baseline
    }
    fn seconds(&self) -> f64 {
        // A baseline: not part of the DETP engines' speed.
        0.0
    }
    fn replica_points(&self) -> Vec<Vec<f64>> {
        self.runs.iter().map(|r| r.0.clone()).collect()
    }
    fn per_point(&self, p: &Pooled) -> Option<Vec<(f64, f64)>> {
        let n = self.runs.first().map_or(0, |r| r.0.len());
        let k = self.k(p.cfg) as f64;
        Some(
            (0..n)
                .map(|i| {
                    let v: Vec<f64> = self.runs.iter().map(|r| r.0[i]).collect();
                    let e = per_replica(&v);
                    // One replica: a k-nearest-neighbour estimate has relative SE ≈ 1/√k.
                    let se = if v.len() == 1 {
                        e.mean.abs() / k.sqrt()
                    } else {
                        e.se
                    };
                    (e.mean, se)
                })
                .collect(),
        )
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let errs: Vec<(f64, f64)> = self.runs.iter().map(|r| errors(&r.0, p.exact)).collect();
        let m = MapMeasured {
            rmse: per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
            bias: per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>()),
            seconds: self.runs.iter().map(|r| r.1).sum(),
            build_s: self.runs.iter().map(|r| r.2).sum(),
            k: self.k(p.cfg) as u64,
        };
        if self.growing {
            EngineMeasured::PhotonMapGrowing(m)
        } else {
            EngineMeasured::PhotonMap(m)
        }
    }
}

/// What a run computes once per point set and shares across its sweep points (other photon
/// counts, d, k, engines): the path-traced reference, keyed by (scene, points, samples, seed); the
/// path-tracing competitor and the NEE direct part, keyed by those and the replica. Values are a
/// pure function of the key, so sharing them changes no measured column.
#[derive(Clone, Default)]
pub struct ReferenceCache {
    /// The reference per disc and its seconds.
    reference: Memo<(Vec<Irradiance>, f64)>,
    /// The competitor of one replica.
    pub(super) path_tracing: Memo<super::path_tracing::PathTraced>,
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

/// The path-traced reference irradiance per disc (a baseline: never part of DETP's sums or speed).
struct Reference {
    cache: ReferenceCache,
    /// Estimates per disc and the seconds they took to compute.
    result: Option<Arc<(Vec<Irradiance>, f64)>>,
}

impl Reference {
    /// The reference at the point's discs, once per point (it does not depend on the replica's
    /// photons), shared through the run's cache.
    fn compute(&mut self, cfg: &DetpConfig, pts: &PointSet) {
        if self.result.is_some() {
            return;
        }
        let Some(scene) = cfg.scene() else {
            unreachable!("configure refuses the reference without a scene")
        };
        let discs = &pts.discs;
        let key = point_set_key(cfg, pts, &[domain::REFERENCE, cfg.seed, cfg.reference_samples]);
        let r = self.cache.reference.get_or(key, || {
            timed(|| {
                reference::irradiance(
                    &scene.scene,
                    &discs.centers,
                    &discs.normals,
                    cfg.reference_samples,
                    hash_key(&[cfg.seed]),
                )
            })
        });
        self.result = Some(r);
    }
}

impl Engine for Reference {
    fn run(&mut self, cfg: &DetpConfig, _rays: &RaySet, pts: &PointSet) -> Output {
        self.compute(cfg, pts);
        Output::Baseline
    }
    fn part(&self) -> Option<EnginePart> {
        Some(EnginePart::Reference)
    }
    /// Photon shards skip the reference (it needs no photons); the merge computes it, once.
    fn absorb(&mut self, cfg: &DetpConfig, pts: &PointSet, _part: &EnginePart) {
        self.compute(cfg, pts);
    }
    fn seconds(&self) -> f64 {
        0.0
    }
    fn per_point(&self, _p: &Pooled) -> Option<Vec<(f64, f64)>> {
        self.result
            .as_ref()
            .map(|r| r.0.iter().map(|e| (e.mean, e.se)).collect())
    }
    fn measured(&self, _p: &Pooled) -> EngineMeasured {
        EngineMeasured::Reference(self.result.as_ref().map_or(0.0, |r| r.1))
    }
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
