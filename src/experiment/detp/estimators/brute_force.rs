//! Estimator `brute-force`: every segment against every disc. Its sums are the oracle: where it
//! runs, every disc is checked against it (else a keyed subset is re-computed by brute force).

use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    self, gather, per_replica, Engine, EngineMeasured, EnginePart, Output, Pooled, ReferenceCache, Sizes,
};
use crate::experiment::detp::{PointSet, RaySet};
use crate::output::table::{col, Table};
use crate::stats::Estimate;
use super::{Estimator, Role, Shards};
use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::fixed::Acc;
use crate::detp::nearest::{Kept, Nearest};
use crate::detp::store::SegmentStore;

/// Estimator `brute-force`.
pub struct BruteForce;

impl Estimator for BruteForce {
    const NAME: &'static str = "brute-force";
    const COLUMN: &'static str = "brute_force";
    const ROLE: Role = Role::Detp;
    const SHARDS: Shards = Shards::Add;
    const ORACLE: bool = true;
    type Measured = BruteMeasured;
    const COLUMNS: Table<DetpConfig, BruteMeasured> = Table::of(&[
        col(&TESTS, |_, e| e.tests.into()),
        col(&COUNTED_COST, |_, e| e.tests.into()),
        col(&TESTS_THEORY, |_, e| {
            (e.sizes.reps * e.sizes.n_r * e.sizes.n_p).into()
        }),
        col(&COST_S, |_, e| e.seconds.into()),
        col(&TESTS_PER_REPLICA, |_, e| e.tests_per_replica.into()),
        col(&COST_PER_REPLICA_S, |_, e| e.seconds_per_replica.into()),
    ]);
    fn engine(_: &ReferenceCache) -> Box<dyn Engine> {
        Box::<Runs>::default()
    }
}

/// One replica's counts over a range of its photons (they add across photon shards).
#[derive(serde::Serialize, serde::Deserialize)]
struct Part {
    /// Segment–disc tests.
    tests: u64,
    /// Seconds.
    seconds: f64,
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

/// Brute force's pass: every segment against every disc; its tests.
struct Pass<'a>(&'a SegmentStore, &'a Discs);

impl engines::Pass for Pass<'_> {
    type Stats = u64;
    fn sums(&self, acc: &mut [Acc]) -> u64 {
        brute::accumulate(self.0, self.1, None, 1, acc)
    }
    fn nearest(&self, tally: &Nearest, kept: &mut [Kept]) -> u64 {
        brute::accumulate_with(self.0, self.1, None, tally, kept)
    }
}

/// Brute force: every segment against every disc.
#[derive(Default)]
struct Runs {
    runs: Vec<(u64, f64)>,
}

impl Engine for Runs {
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let (g, tests, s) = gather(cfg, &pts.discs, &Pass(&rays.store, &pts.discs));
        self.runs.push((tests, s));
        Output::Sums(g)
    }
    fn seconds(&self) -> f64 {
        self.runs.iter().map(|r| r.1).sum()
    }
    fn part(&self) -> Option<EnginePart> {
        let &(tests, seconds) = self.runs.last()?;
        Some(EnginePart::new("BruteForce", &Part { tests, seconds }))
    }
    fn absorb(&mut self, _cfg: &DetpConfig, _pts: &PointSet, part: &EnginePart) {
        let Part { tests, seconds } = part
            .read("BruteForce")
            .expect("parts are matched to engines by the merge");
        self.runs.push((tests, seconds));
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let tests: Vec<f64> = self.runs.iter().map(|r| r.0 as f64).collect();
        let secs: Vec<f64> = self.runs.iter().map(|r| r.1).collect();
        EngineMeasured::of::<BruteForce>(BruteMeasured {
            sizes: p.sizes,
            tests: self.runs.iter().map(|r| r.0).sum(),
            seconds: self.seconds(),
            tests_per_replica: per_replica(&tests),
            seconds_per_replica: per_replica(&secs),
        })
    }
}
