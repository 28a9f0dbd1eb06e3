//! Kind `lines-in-sphere`: the smallest complete kind, and the template for a new one. μ-random lines
//! through the unit ball (DETP §4.2) meet a concentric sphere of radius r with probability r²
//! (Crofton: the measure of lines meeting a convex body is proportional to its surface area). The
//! sphere cache's rays-per-level law n_R·Q^(2i) is this fact once per level.
//!
//! A kind is this one module and one line in the registry ([`super::KINDS`]): its spec struct (serde
//! denies unknown keys, so a mistyped key is refused with its line), its validated point, what it
//! measures ([`Measured`]: typed values, no cells), its one table of columns with their accessors
//! ([`LinesInSphereKind::MAIN`]), and its runner.

use rayon::prelude::*;

use super::inputs::Inputs;
use super::kind::{col, Cell, ConfigError, Context, Kind, NoTables, Output, Rate, Table, Work};
use crate::error::Error;
use crate::output::column::{Class, Column};
use crate::sample::lines::uniform_line;
use crate::sample::rng::{domain, stream};
use crate::stats::{ClusteredMean, Estimate, Theory};
use crate::toml_text::de::{count, open_unit};

crate::spec_file! {
    /// The spec file: `[experiment]`, `[lines]` and `[sweep]`.
    pub struct LinesSpec {
        /// `[lines]`.
        lines: RawLines = {table};
    }
}

crate::spec_table! {
    /// `[lines]`.
    pub struct RawLines {
        /// Lines drawn per point.
        count: u64 = {required} read count, "integer", "lines", "≥ 1";
        /// r: radius of the inner sphere, relative to the unit sphere the lines are drawn through.
        inner_radius: f64 = {required} read open_unit, "number", "", "(0, 1)";
    }
}

/// A validated point.
#[derive(Clone, Debug, PartialEq)]
pub struct LinesPoint {
    seed: u64,
    count: u64,
    r: f64,
}

/// Fraction of lines meeting the inner sphere, against r².
pub const HIT_FRACTION: Column = Column::vs_prediction(
    "hit_fraction",
    "1",
    "fraction of μ-random lines through the unit ball that meet the concentric sphere of radius r; theory r²",
);
/// Lines drawn.
pub const LINES: Column = Column::value("lines", "lines", Class::Measured, "lines drawn");
/// Speed.
pub const LINES_PER_S: Column = Column::value(
    "lines_per_s",
    "lines/s",
    Class::Timing,
    "lines drawn and tested per second",
);

/// What one point measures.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The fraction of lines meeting the inner sphere (one cluster per batch).
    hit_fraction: Estimate,
    /// Lines per second.
    lines_per_s: f64,
}

/// Lines per keyed stream (so the result does not depend on the thread count).
const BATCH: u64 = 4096;

/// Kind `lines-in-sphere`.
pub struct LinesInSphereKind;

impl Kind for LinesInSphereKind {
    const NAME: &'static str = "lines-in-sphere";
    const ABOUT: &'static str = "μ-random lines through the unit ball meet a concentric sphere of radius r with probability r² (the law behind the sphere cache's rays per level); the smallest kind, a template for new ones.";
    type Raw = LinesSpec;
    type Point = LinesPoint;
    type Measured = Measured;
    type Tables = NoTables;
    type Shared = ();
    const MAIN: Table<LinesPoint, Measured> = Table::of(&[
        col(&LINES, |p, _| p.count.into()),
        col(&HIT_FRACTION, |p, m| {
            Cell::Judged(m.hit_fraction, Theory::Prediction(p.r * p.r))
        }),
        col(&LINES_PER_S, |_, m| m.lines_per_s.into()),
    ]);

    fn configure(raw: &LinesSpec, _: &mut Inputs) -> Result<LinesPoint, ConfigError> {
        Ok(LinesPoint {
            seed: raw.experiment.stream_seed(),
            count: raw.lines.count,
            r: raw.lines.inner_radius,
        })
    }
    fn describe(p: &LinesPoint) -> String {
        format!("{} lines, inner sphere r = {}", p.count, p.r)
    }
    fn work(p: &LinesPoint) -> Work {
        Work {
            units: p.count,
            unit: "lines",
            points: 1,
        }
    }
    fn shared(_: &[&LinesPoint]) -> Result<(), Error> {
        Ok(())
    }
    fn run(p: &LinesPoint, _: &(), ctx: &Context) -> Result<Output<Measured, NoTables>, Error> {
        let start = std::time::Instant::now();
        // One cluster per batch: hits and hits² of its lines (a hit is 0 or 1).
        let hits: Vec<(u64, u64)> = (0..p.count.div_ceil(BATCH))
            .into_par_iter()
            .map(|b| {
                let mut rng = stream(&[domain::LINES, p.seed, ctx.stream_point, b]);
                let n = BATCH.min(p.count - b * BATCH);
                let h = (0..n)
                    .filter(|_| {
                        let (o, d) = uniform_line(&mut rng);
                        // Distance of the line from the centre: |o − (o·d)d|.
                        (o - o.dot(d) * d).length() < p.r
                    })
                    .count() as u64;
                (ctx.progress)(n);
                (n, h)
            })
            .collect();
        let secs = start.elapsed().as_secs_f64();
        let mut m = ClusteredMean::default();
        for (n, h) in hits {
            m.push_cluster(n, h as f64, h as f64);
        }
        let rate = p.count as f64 / secs.max(1e-12);
        Ok(Output {
            measured: Measured {
                hit_fraction: m.estimate(),
                lines_per_s: rate,
            },
            tables: NoTables,
            checks: Vec::new(),
            rate: Rate {
                per_s: rate,
                unit: "lines",
            },
            warnings: Vec::new(),
        })
    }
}
