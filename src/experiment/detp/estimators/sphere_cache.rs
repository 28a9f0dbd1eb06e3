//! Estimator `sphere-cache`: the hierarchy of spheres (points visited in Morton/Hilbert/no order),
//! with its counters per level — rays held, rebuilds (cache misses), ray–sphere tests — against
//! n_R·Q^(2i) and Theorem 1 (`NAME.levels.csv`, one row per level).

use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    self, gather, per_replica, timed, Engine, EngineMeasured, Output, Pooled, ReferenceCache, Sizes,
};
use crate::experiment::detp::{PointSet, RaySet};
use crate::output::table::{col, Table};
use crate::stats::Estimate;
use super::{Crossover, Estimator, Role, Shards};
use crate::output::column::{Class, Column};
use crate::output::table::{Against, Cell, Line};
use crate::stats::Theory;
use crate::detp::{order, sphere_cache};
use crate::experiment::detp::engines::Law;
use crate::experiment::kind::Need;
use crate::stats::ClusteredMean;
use crate::theory::detp as th;
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::nearest::{Kept, Nearest};
use crate::detp::sphere_cache::filter::FilterPath;
use crate::detp::store::SegmentStore;
use glam::DVec3;

/// Estimator `sphere-cache`.
pub struct SphereCache;

impl Estimator for SphereCache {
    const NAME: &'static str = "sphere-cache";
    const COLUMN: &'static str = "sphere_cache";
    const ROLE: Role = Role::Detp;
    const CROSSOVER: Option<Crossover> = Some(Crossover::Detp);
    const SHARDS: Shards =
        Shards::Refuse("the sphere cache subdivides a sphere by how many rays it holds");
    type Measured = CacheMeasured;
    const COLUMNS: Table<DetpConfig, CacheMeasured> = Table::of(&[
        col(&TESTS, |_, e| (e.sphere_tests + e.disc_tests).into()),
        col(&TESTS_THEORY, |p, e| {
            let (t_r, t_i) = cache_cost(p, &e.sizes);
            (e.sizes.reps * (t_r + t_i)).into()
        }),
        col(&RAY_SPHERE_TESTS, |_, e| e.sphere_tests.into()),
        col(&RAY_SPHERE_TESTS_THEORY, |p, e| {
            (e.sizes.reps * cache_cost(p, &e.sizes).0).into()
        }),
        col(&RAY_DISC_TESTS, |_, e| e.disc_tests.into()),
        col(&RAY_DISC_TESTS_THEORY, |p, e| {
            (e.sizes.reps * cache_cost(p, &e.sizes).1).into()
        }),
        col(&RAYS_COPIED, |_, e| e.rays_copied.into()),
        col(&SPHERES_BUILT, |_, e| e.spheres_built.into()),
        col(&POP_REPAIRS, |_, e| e.pop_repairs.into()),
        col(&COUNTED_COST, |_, e| (e.sphere_tests + e.disc_tests).into()),
        col(&COST_S, |_, e| e.seconds.into()),
        col(&BUILD_S, |_, e| e.order_s.into()),
        col(&ORDER_S, |_, e| e.order_s.into()),
        col(&TESTS_PER_REPLICA, |_, e| e.tests_per_replica.into()),
        col(&COST_PER_REPLICA_S, |_, e| e.seconds_per_replica.into()),
    ]);
    /// Its ray lists along one path per thread: n_R·Σ Q^{2i} = n_R/(1 − Q²) indices.
    fn memory(cfg: &DetpConfig, segments: f64, threads: f64) -> Vec<Need> {
        vec![Need {
            bytes: segments * 4.0 * threads / (1.0 - cfg.q() * cfg.q()),
            key: "detp.q",
            what: "sphere-cache ray lists (n_R/(1 − Q²) per thread)".into(),
            per_photon: true,
        }]
    }
    fn engine(_: &ReferenceCache) -> Box<dyn Engine> {
        Box::<Runs>::default()
    }
}

/// Theorem 1's (T_R, T_I) for the sphere cache at these sizes (t = u = 1).
fn cache_cost(p: &DetpConfig, z: &Sizes) -> (f64, f64) {
    th::sphere_cache_cost(1.0, 1.0, z.n_r, z.n_p, p.q())
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

/// The sphere cache's pass over the points in their order; its counts.
struct Pass<'a> {
    store: &'a SegmentStore,
    discs: &'a Discs,
    perm: &'a [u32],
    root: (DVec3, f64),
    params: &'a sphere_cache::SphereCacheParams,
}

impl engines::Pass for Pass<'_> {
    type Stats = sphere_cache::CacheStats;
    fn sums(&self, acc: &mut [Acc]) -> Self::Stats {
        sphere_cache::run(self.store, self.discs, self.perm, self.root, self.params, acc)
    }
    fn nearest(&self, tally: &Nearest, kept: &mut [Kept]) -> Self::Stats {
        sphere_cache::run_tally(
            self.store,
            self.discs,
            self.perm,
            self.root,
            self.params,
            tally,
            kept,
            FilterPath::detect(),
        )
    }
}

/// The sphere cache.
#[derive(Default)]
struct Runs {
    runs: Vec<(sphere_cache::CacheStats, f64, f64)>,
}

impl Engine for Runs {
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let discs = &pts.discs;
        let (perm, order_s) =
            timed(|| order::permutation(&discs.centers, cfg.order, cfg.order_bits));
        let params = sphere_cache::SphereCacheParams {
            law_ball: rays.law_ball,
            ..cfg.cache
        };
        let pass = Pass {
            store: &rays.store,
            discs,
            perm: &perm,
            root: rays.root,
            params: &params,
        };
        let (g, stats, s) = gather(cfg, discs, &pass);
        self.runs.push((stats, s, order_s));
        Output::Sums(g)
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
        EngineMeasured::of::<SphereCache>(CacheMeasured {
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

impl Runs {
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

/// Sphere cache: ray–sphere tests.
pub const RAY_SPHERE_TESTS: Column = Column::value(
    "ray_sphere_tests",
    "tests",
    Class::Measured,
    "sphere cache: ray–sphere tests building lists (T_R's work)",
);

/// Their theory.
pub const RAY_SPHERE_TESTS_THEORY: Column = Column::value(
    "ray_sphere_tests_theory",
    "tests",
    Class::Theory,
    "Theorem 1's T_R = t·n_R/Q²·(∛n_P − 1)/(1 − Q), times the replicas",
);

/// Sphere cache: ray–disc tests.
pub const RAY_DISC_TESTS: Column = Column::value(
    "ray_disc_tests",
    "tests",
    Class::Measured,
    "sphere cache: ray–disc tests against the deepest list (T_I's work)",
);

/// Their theory.
pub const RAY_DISC_TESTS_THEORY: Column = Column::value(
    "ray_disc_tests_theory",
    "tests",
    Class::Theory,
    "Theorem 1's T_I = (4/3)·u·n_R·∛n_P, times the replicas",
);

/// Sphere cache: segments copied into lists.
pub const RAYS_COPIED: Column = Column::value(
    "rays_copied",
    "segments",
    Class::Measured,
    "sphere cache: segments copied into lists while building them (the root's list once per replica, included), summed over replicas; weight 0 in counted_cost_sphere_cache (each copy follows a counted ray–sphere test)",
);

/// Sphere cache: spheres built.
pub const SPHERES_BUILT: Column = Column::value(
    "spheres_built",
    "spheres",
    Class::Measured,
    "sphere cache: spheres built over all levels (the root once per replica, included), summed over replicas",
);

/// Sphere cache: paper pop repairs.
pub const POP_REPAIRS: Column = Column::value(
    "pop_repairs",
    "points",
    Class::Measured,
    "sphere cache, detp.pop_rule = \"paper\": points whose kept chain held a level not containing the disc (inherited lists: cut back to the chain there to stay exact; exact lists: harmless); 0 for \"chain\"",
);

/// Ordering time.
pub const ORDER_S: Column = Column::value(
    "order_s",
    "s",
    Class::Timing,
    "sphere cache: seconds to sort the points along the space-filling curve",
);

/// Level number.
pub const LEVEL: Column = Column::value(
    "level",
    "1",
    Class::Measured,
    "sphere-cache level i (0: the root)",
);

/// Its radius.
pub const RADIUS: Column = Column::value("radius", "length", Class::Theory, "its radius r_0·Q^i");

/// Builds.
pub const BUILDS_LEVEL: Column = Column::value(
    "builds_level",
    "spheres",
    Class::Measured,
    "spheres built at this level, over replicas",
);

/// Rays held.
pub const RAYS_LEVEL: Column = Column::estimate(
    "rays_level",
    "rays",
    "mean rays held by the spheres built at this level (one cluster per replica)",
);

/// Its law.
pub const RAYS_LEVEL_THEORY: Column = Column::value(
    "rays_level_theory",
    "rays",
    Class::Theory,
    "the uniform-line law n_R·(r_i/r_law)²",
);

/// Lens-clipped law.
pub const RAYS_LEVEL_THEORY_CLIPPED: Column = Column::value(
    "rays_level_theory_clipped",
    "rays",
    Class::Theory,
    "lines: the law for sphere centres uniform in the ball, clipped where spheres stick out of it",
);

/// Spheres inside the law's ball.
pub const RAYS_LEVEL_INSIDE: Column = Column::estimate(
    "rays_level_inside",
    "rays",
    "lines: mean rays held by the spheres that lie inside the ball (where the law is exact)",
);

/// Misses.
pub const MISSES_LEVEL: Column = Column::value(
    "misses_level",
    "spheres",
    Class::Measured,
    "cache misses: builds of this level except a chunk's cold start",
);

/// Rays held by the spheres of this level that hold fewer than the threshold (never subdivided).
pub const RAYS_LEVEL_LEAF: Column = Column::vs_prediction(
    "rays_level_leaf",
    "segments",
    "rays held per sphere of this level that holds fewer than detp.threshold (a sphere never subdivided): mean over those builds, SE clustered by replica, builds; theory: E[X | X < threshold] for X ~ Poisson(rays_level_theory)",
);

/// Misses per replica.
pub const MISSES_LEVEL_PER_REPLICA: Column = Column::estimate(
    "misses_level_per_replica",
    "builds",
    "misses at this level in one replica: mean, standard error across replicas, replicas",
);

/// The paper's rebuild model.
pub const MISSES_LEVEL_THEORY: Column = Column::value(
    "misses_level_theory",
    "spheres",
    Class::Theory,
    "the paper's rebuild model m_i ≈ Q^(−3i) (one rebuild per region of S_i's size the sorted points visit; THEORY §2), times the replicas",
);

/// Rays copied per level.
pub const RAYS_COPIED_LEVEL: Column = Column::value(
    "rays_copied_level",
    "segments",
    Class::Measured,
    "segments copied into this level's lists (Σ list length over its builds), over replicas",
);

/// Tests.
pub const RAY_SPHERE_TESTS_LEVEL: Column = Column::value(
    "ray_sphere_tests_level",
    "tests",
    Class::Measured,
    "ray–sphere tests building this level's lists",
);

/// A level's summary line: rays held against the uniform-line law (photons of a scene are shown
/// against it, not judged: the README's real scenes hold 1.2–2.3× the law); none for a level no
/// replica built.
fn level_line(_: &DetpConfig, r: &LevelRow) -> Vec<Line> {
    if r.rays.n == 0 {
        return Vec::new();
    }
    vec![Line {
        metric: format!("rays L{}", r.level),
        estimate: r.rays,
        against: Against::Law {
            value: r.law,
            name: "n_R·(r_i/r_law)²",
            not_judged: (!r.lines).then_some("photons"),
        },
    }]
}

/// `NAME.levels.csv`: one row per sphere-cache level (the leaf mean is not summarised: one line
/// per level would drown the rays' lines).
pub const LEVELS: Table<DetpConfig, LevelRow> = Table {
    entries: &[
        col(&LEVEL, |_, r| r.level.into()),
        col(&RADIUS, |_, r| r.radius.into()),
        col(&BUILDS_LEVEL, |_, r| r.builds.into()),
        col(&RAYS_LEVEL, |_, r| r.rays.into()),
        col(&RAYS_LEVEL_THEORY, |_, r| r.law.into()),
        col(&RAYS_LEVEL_THEORY_CLIPPED, |_, r| r.clipped.into()),
        col(&RAYS_LEVEL_INSIDE, |_, r| r.inside.into()),
        col(&MISSES_LEVEL, |_, r| r.misses.into()),
        col(&MISSES_LEVEL_PER_REPLICA, |_, r| {
            r.misses_per_replica.into()
        }),
        col(&MISSES_LEVEL_THEORY, |p, r| {
            (p.replicas as f64 * p.q().powi(-3 * r.level as i32)).into()
        }),
        col(&RAYS_COPIED_LEVEL, |_, r| r.copied.into()),
        col(&RAY_SPHERE_TESTS_LEVEL, |_, r| r.sphere_tests.into()),
        col(&RAYS_LEVEL_LEAF, |p, r| {
            let law = th::poisson_mean_below(r.law, p.cache.threshold as u64);
            Cell::Judged(r.leaf, Theory::Prediction(law))
        }),
    ],
    lines: level_line,
};
