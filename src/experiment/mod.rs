//! One module per experiment kind: each maps a point's parameters to a row of measurements and the
//! theory for the same parameters. Rows are plain data; `output` writes them.

pub mod detp;
pub mod grid;
pub mod machine;
pub mod metric;
pub mod quasi_static;
pub mod runner;

pub use crate::output::row::{Row, Value};

/// One point's results: the main row, its rows of each side table (`NAME.TABLE.csv`, e.g. `hist`,
/// `levels`, `points`), and what the terminal summary shows.
#[derive(Clone, Debug, Default)]
pub struct PointResult {
    /// The point's row (without the `point` and parameter columns, which the runner prepends).
    pub row: Row,
    /// Side tables: (table name, rows), names from [`side_tables`] of the point's kind.
    pub tables: Vec<(&'static str, Vec<Row>)>,
    /// Human summary: (metric, measured, theory text, verdict).
    pub summary: Vec<metric::SummaryLine>,
    /// Rays per second while tracing.
    pub rays_per_s: f64,
}

/// The side tables a kind writes, declared up front so the sink can open (and resume, and merge)
/// them before the first point runs.
pub fn side_tables(kind: crate::spec::Kind) -> &'static [&'static str] {
    use crate::spec::Kind;
    match kind {
        Kind::Grid | Kind::GridScaling | Kind::GridCostModel => &["hist"],
        Kind::Detp => &["levels", "points"],
        Kind::QuasiStatic => &["frames", "points"],
    }
}

/// Runs one point of any kind.
pub fn run_point(
    config: &crate::spec::PointConfig,
    point: u64,
    machine: Option<machine::MachineCosts>,
    progress: &(dyn Fn(u64) + Sync),
) -> anyhow::Result<PointResult> {
    use crate::spec::PointConfig;
    match config {
        PointConfig::Grid(g) => Ok(grid::run_point(g, point, machine, progress)),
        PointConfig::Detp(d) => detp::run_point(d, point, progress),
        PointConfig::QuasiStatic(q) => quasi_static::run_point(q, point, progress),
    }
}
