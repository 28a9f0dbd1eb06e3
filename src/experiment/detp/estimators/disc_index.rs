//! Estimator `disc-index`: the discs in an octree or a grid (`detp.index`) that every segment
//! traverses, against Theorem 1; its walk alone (no disc tests) is timed apart after its pass, for
//! eq. 8's traversal share. Its counts add across photon shards.

use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    self, gather, per_replica, timed, Engine, EngineMeasured, EnginePart, Output, Pooled, ReferenceCache, Sizes,
};
use crate::experiment::detp::{PointSet, RaySet};
use crate::output::table::{col, Table};
use crate::stats::Estimate;
use super::{Crossover, Estimator, Role, Shards};
use crate::output::column::{Class, Column};
use crate::detp::disc_index::{self, DiscIndex as Index, IndexKind, IndexStats};
use crate::experiment::kind::Need;
use crate::detp::fixed::Acc;
use crate::detp::nearest::{Kept, Nearest};
use crate::detp::store::SegmentStore;
use crate::theory::detp as th;

/// Estimator `disc-index`.
pub struct DiscIndex;

impl Estimator for DiscIndex {
    const NAME: &'static str = "disc-index";
    const COLUMN: &'static str = "disc_index";
    const ROLE: Role = Role::Detp;
    const CROSSOVER: Option<Crossover> = Some(Crossover::Detp);
    const SHARDS: Shards = Shards::Add;
    type Measured = IndexMeasured;
    const COLUMNS: Table<DetpConfig, IndexMeasured> = Table::of(&[
        col(&BOX_TESTS, |_, e| e.stats.box_tests.into()),
        col(&DDA_STEPS, |_, e| e.stats.dda_steps.into()),
        col(&COUNTED_COST, |_, e| e.stats.counted_cost().into()),
        col(&TESTS, |_, e| e.stats.ray_disc_tests.into()),
        col(&TESTS_THEORY, |_, e| {
            (e.sizes.reps * th::disc_index_cost(1.0, e.sizes.n_r, e.sizes.n_p)).into()
        }),
        col(&NODES, |_, e| e.stats.nodes_visited.into()),
        col(&COST_S, |_, e| e.seconds.into()),
        col(&BUILD_S, |_, e| e.build_s.into()),
        col(&BYTES, |_, e| e.bytes.into()),
        col(&TESTS_PER_REPLICA, |_, e| e.tests_per_replica.into()),
        col(&COST_PER_REPLICA_S, |_, e| e.seconds_per_replica.into()),
        col(&TRAVERSAL_PER_REPLICA_S, |_, e| {
            e.traversal_per_replica.into()
        }),
    ]);
    /// A disc grid's cells (an octree's nodes are few against the discs).
    fn memory(cfg: &DetpConfig, _segments: f64, _threads: f64) -> Vec<Need> {
        cfg.grid_cells()
            .map(|cells| Need {
                bytes: cells * 4.0,
                key: "detp.index_cell_width",
                what: format!("{cells:.3e} disc-grid cells"),
                per_photon: false,
            })
            .into_iter()
            .collect()
    }
    fn engine(_: &ReferenceCache) -> Box<dyn Engine> {
        Box::<Runs>::default()
    }
}

/// One replica's counts over a range of its photons: they add across photon shards (the seconds
/// add, the bytes take the larger).
#[derive(serde::Serialize, serde::Deserialize)]
struct Part {
    /// Nodes visited, box tests, DDA steps, disc tests.
    stats: [u64; 4],
    /// Build seconds.
    build_s: f64,
    /// Query seconds.
    query_s: f64,
    /// Seconds of the same walk without disc tests ([`Index::traversal_only`]).
    traversal_s: f64,
    /// Bytes of the index.
    bytes: usize,
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

/// The disc index's pass: every segment walks the index; its counts.
struct Pass<'a>(&'a dyn Index, &'a SegmentStore);

impl engines::Pass for Pass<'_> {
    type Stats = IndexStats;
    fn sums(&self, acc: &mut [Acc]) -> IndexStats {
        self.0.accumulate(self.1, None, 1, acc)
    }
    fn nearest(&self, tally: &Nearest, kept: &mut [Kept]) -> IndexStats {
        self.0.accumulate_nearest(self.1, None, tally, kept)
    }
}

/// The disc index (octree or grid).
#[derive(Default)]
struct Runs {
    runs: Vec<IndexRun>,
}

impl Engine for Runs {
    /// Builds the index and runs its pass; then, untimed by the pass and adding nothing, walks it
    /// again for the same segments without testing a disc (eq. 8 assumes that walk negligible
    /// against the tests): the same thread pool, so the two seconds compare like for like.
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let discs = &pts.discs;
        let (ix, build_s): (Box<dyn Index>, f64) = match cfg.index {
            IndexKind::Octree(leaf) => timed(|| {
                Box::new(disc_index::Octree::build(discs, leaf, cfg.disc_radius))
                    as Box<dyn Index>
            }),
            IndexKind::Grid(w) => {
                timed(|| Box::new(disc_index::GridIndex::build(discs, w)) as Box<dyn Index>)
            }
        };
        let (g, stats, query_s) = gather(cfg, discs, &Pass(ix.as_ref(), &rays.store));
        let (walked, traversal_s) = timed(|| ix.traversal_only(&rays.store, None));
        debug_assert_eq!(walked, stats, "the walk alone is the pass's walk");
        self.runs.push(IndexRun {
            stats,
            build_s,
            query_s,
            traversal_s,
            bytes: ix.bytes(),
        });
        Output::Sums(g)
    }
    fn seconds(&self) -> f64 {
        self.runs.iter().map(|r| r.query_s).sum()
    }
    fn part(&self) -> Option<EnginePart> {
        let r = self.runs.last()?;
        let st = r.stats;
        Some(EnginePart::new(
            "DiscIndex",
            &Part {
                stats: [st.nodes_visited, st.box_tests, st.dda_steps, st.ray_disc_tests],
                build_s: r.build_s,
                query_s: r.query_s,
                traversal_s: r.traversal_s,
                bytes: r.bytes,
            },
        ))
    }
    fn absorb(&mut self, _cfg: &DetpConfig, _pts: &PointSet, part: &EnginePart) {
        let Part {
            stats: [nodes_visited, box_tests, dda_steps, ray_disc_tests],
            build_s,
            query_s,
            traversal_s,
            bytes,
        } = part
            .read("DiscIndex")
            .expect("parts are matched to engines by the merge");
        let stats = IndexStats {
            nodes_visited,
            box_tests,
            dda_steps,
            ray_disc_tests,
            ..IndexStats::default()
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
        EngineMeasured::of::<DiscIndex>(IndexMeasured {
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

/// The disc index's walk alone, per replica.
pub const TRAVERSAL_PER_REPLICA_S: Column = Column::timed_estimate(
    "traversal_{}_per_replica_s",
    "s",
    "disc index: seconds of a second pass in one replica that walks the index for the same segments exactly as the engine's pass does (cells or nodes, box tests, DDA steps, candidate lists) but tests no disc, timed apart right after it on the same threads (not in cost_disc_index_s); over cost_disc_index_per_replica_s it is eq. 8's traversal share in seconds: mean, standard error across replicas, replicas",
);

/// Index nodes visited.
pub const NODES: Column = Column::value(
    "nodes_{}",
    "nodes",
    Class::Measured,
    "disc index: nodes (octree) or cells (grid) visited by the segments, summed over replicas",
);

/// Index box tests.
pub const BOX_TESTS: Column = Column::value(
    "box_tests_{}",
    "tests",
    Class::Measured,
    "disc index: segment–box slab tests (octree: every node tested; grid: each segment clipped to the grid's box), summed over replicas",
);

/// Index DDA steps.
pub const DDA_STEPS: Column = Column::value(
    "dda_steps_{}",
    "steps",
    Class::Measured,
    "disc index: 3D-DDA steps through grid cells (0 for an octree, whose steps are its box tests), summed over replicas",
);

/// Index size.
pub const BYTES: Column = Column::value(
    "bytes_{}",
    "bytes",
    Class::Measured,
    "disc index: bytes of the largest replica's index",
);
