//! Tables declared as data: a kind lists, once, each column it writes with the accessor that reads
//! the column's value out of its typed measurement (and the point's parameters, for theory), and
//! the code here alone turns a measurement into a [`Row`] and summary [`Line`]s. No kind writes a
//! cell by name: the column's name, unit, class and shape come from its [`Column`], the cells'
//! suffixes (`_mean`, `_se`, `_theory`, `_band`, …) from its shape, the verdict from
//! [`crate::stats::verdict`].
//!
//! An [`Entry`] is a column and its accessor, `fn(&P, &M) -> Cell` (P: the point's validated
//! parameters, M: what one row measures). A [`Cell`] says what the column holds in that row: a value,
//! an estimate, an estimate held against [`Theory`], a family's members, or nothing (a column only
//! some points have). [`Entry::Parts`] places other tables' cells in the row, one group per part
//! (the DETP engines, each with its own columns, in the point's engine order); a family column in a
//! part's table is written as that part's member (`tests_{}` in the sphere cache's part:
//! `tests_sphere_cache`).
//!
//! Cells of a column declared [`Column::decided_by_timing`] are written as timings in a row whose
//! values a clock decided (the quasi-static predictor's engine pick), and cells of a column declared
//! [`Column::accelerator_work`] in a row merged from photon shards (the work summed across the
//! shards' own accelerators), so the reproducibility checks do not compare them there ([`Demote`]).

use super::column::{part, Class, Column, Shape};
use super::row::{Row, Value};
use super::summary::SummaryLine;
use crate::stats::verdict::{not_judged, z_verdict, Theory, Verdict};
use crate::stats::Estimate;

/// What one declared column holds in one row.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Not written in this row (a column that only some points have).
    Absent,
    /// One value.
    Value(Value),
    /// An estimate: `M_mean, M_se, M_n, M_clusters`.
    Estimate(Estimate),
    /// An estimate held against theory: its cells, `M_theory`, for a band `M_lower, M_upper, M_band`;
    /// in the main table also a summary line.
    Judged(Estimate, Theory),
    /// The members of a family (`tests_{}` → `tests_PART`), in order.
    Members(Vec<(String, Cell)>),
}

impl Cell {
    /// The members of a family from `(part, value)` pairs.
    pub fn members<T: Into<Cell>>(parts: impl IntoIterator<Item = (String, T)>) -> Cell {
        Cell::Members(parts.into_iter().map(|(k, v)| (k, v.into())).collect())
    }
}

macro_rules! value_cells {
    ($($t:ty),*) => {$(
        impl From<$t> for Cell {
            fn from(x: $t) -> Cell {
                Cell::Value(x.into())
            }
        }
    )*};
}
value_cells!(f64, u64, usize, u32, &str, String, Value);

impl From<Estimate> for Cell {
    fn from(e: Estimate) -> Cell {
        Cell::Estimate(e)
    }
}

impl<T: Into<Cell>> From<Option<T>> for Cell {
    /// `None`: the column is not written in this row.
    fn from(x: Option<T>) -> Cell {
        x.map_or(Cell::Absent, Into::into)
    }
}

/// One entry of a declared table.
pub enum Entry<P: 'static, M: 'static> {
    /// A column and the accessor that reads its cell.
    Column(&'static Column, fn(&P, &M) -> Cell),
    /// Other tables' cells, one group per part: `(part, cells)`, the cells built with [`cells`];
    /// and those tables' columns (for the docs and the declaration checks).
    Parts(
        fn(&P, &M) -> Vec<(&'static str, Cells)>,
        fn() -> Vec<&'static Column>,
    ),
}

/// A column and its accessor (shorter to read in a table).
pub const fn col<P, M>(column: &'static Column, cell: fn(&P, &M) -> Cell) -> Entry<P, M> {
    Entry::Column(column, cell)
}

/// A table's declared columns and the summary lines its rows add beyond their judged cells.
pub struct Table<P: 'static, M: 'static> {
    /// The columns, in row order.
    pub entries: &'static [Entry<P, M>],
    /// Summary lines of one row (the main table: beside its judged cells, which are lines by
    /// themselves; a side table: its only lines, since its rows are many).
    pub lines: fn(&P, &M) -> Vec<Line>,
}

impl<P: 'static, M: 'static> Table<P, M> {
    /// A table whose rows add no summary lines of their own.
    pub const fn of(entries: &'static [Entry<P, M>]) -> Self {
        Self {
            entries,
            lines: no_lines,
        }
    }

    /// Its columns, in row order (a column that several parts write, once).
    pub fn columns(&self) -> Vec<&'static Column> {
        let mut out: Vec<&'static Column> = Vec::new();
        for e in self.entries {
            let cols = match e {
                Entry::Column(c, _) => vec![*c],
                Entry::Parts(_, cols) => cols(),
            };
            for c in cols {
                if !out.iter().any(|o| o.name == c.name) {
                    out.push(c);
                }
            }
        }
        out
    }
}

fn no_lines<P, M>(_: &P, _: &M) -> Vec<Line> {
    Vec::new()
}

/// The cells of one row (or one part of a row), with their columns, in order.
pub type Cells = Vec<(&'static Column, Cell)>;

/// The cells `entries` read from `(p, m)`.
pub fn cells<P, M>(entries: &[Entry<P, M>], p: &P, m: &M) -> Cells {
    let mut out = Vec::with_capacity(entries.len());
    for e in entries {
        match e {
            Entry::Column(c, get) => out.push((*c, get(p, m))),
            Entry::Parts(parts, _) => {
                for (part, cells) in parts(p, m) {
                    out.extend(cells.into_iter().map(|(c, cell)| match cell {
                        Cell::Absent | Cell::Members(_) => (c, cell),
                        _ if c.is_family() => (c, Cell::Members(vec![(part.to_string(), cell)])),
                        _ => (c, cell),
                    }));
                }
            }
        }
    }
    out
}

/// What a summary line holds a measurement against.
#[derive(Clone, Debug, PartialEq)]
pub enum Against {
    /// A theory: judged by its rule, shown as [`Theory::describe`].
    Theory(Theory),
    /// A law named `name` (shown `value (name)`): judged like a prediction, or, where the law does
    /// not apply (`not_judged`: why), shown as a ratio and not judged.
    Law {
        /// Its value.
        value: f64,
        /// How it is written (`n_R·(r_i/r_law)²`).
        name: &'static str,
        /// Why it does not apply here, if it does not.
        not_judged: Option<&'static str>,
    },
    /// A ratio shown as a speed-up (`full_frame_s / frame_s`), not judged.
    Speedup(&'static str),
}

/// A summary line before it is judged: a metric, its estimate, and what it is held against.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// The metric's name.
    pub metric: String,
    /// Its estimate.
    pub estimate: Estimate,
    /// Against what.
    pub against: Against,
}

impl Line {
    /// The line as the summary prints it, with its verdict.
    pub fn judge(&self) -> SummaryLine {
        let e = &self.estimate;
        let (theory, verdict) = match &self.against {
            Against::Theory(t) => (t.describe(), t.verdict(e)),
            Against::Law {
                value,
                name,
                not_judged: why,
            } => (
                format!("{value:.4} ({name})"),
                match why {
                    None => z_verdict(e, *value),
                    Some(why) => not_judged(e, *value, why),
                },
            ),
            Against::Speedup(what) => (what.to_string(), Verdict::Faster(e.mean)),
        };
        SummaryLine {
            metric: self.metric.clone(),
            measured: *e,
            theory,
            verdict,
        }
    }
}

/// Which of a row's measured cells are written as timings (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Demote {
    /// A clock decided this row's values: the columns declared `decided_by_timing`.
    pub timed: bool,
    /// The row was merged from photon shards: the columns declared `accelerator_work`.
    pub photon_merged: bool,
}

impl Demote {
    /// Whether `c`'s measured cells are written as timings in this row.
    fn demotes(self, c: &Column) -> bool {
        (self.timed && c.decided_by_timing) || (self.photon_merged && c.accelerator_work)
    }
}

/// Turns `cells` into a row: every column's cells with their declared names, classes and units, and
/// the summary lines of its judged cells (when `judged_lines`). `demote`: which measured cells are
/// written as timings (see the module doc). A cell whose kind does not fit its column's shape is a
/// bug in the kind's table (an error naming the column).
pub fn row(
    cells: &Cells,
    demote: Demote,
    judged_lines: bool,
) -> Result<(Row, Vec<SummaryLine>), String> {
    let mut row = Row::default();
    let mut lines = Vec::new();
    for (c, cell) in cells {
        let start = row.0.len();
        write(&mut row, &mut lines, c, c.name, cell, judged_lines)?;
        if demote.demotes(c) {
            for cell in &mut row.0[start..] {
                if cell.class == Class::Measured {
                    cell.class = Class::Timing;
                }
            }
        }
    }
    Ok((row, lines))
}

/// Appends the cells of `cell` (column `c`, named `stem`).
fn write(
    row: &mut Row,
    lines: &mut Vec<SummaryLine>,
    c: &Column,
    stem: &str,
    cell: &Cell,
    judged_lines: bool,
) -> Result<(), String> {
    let mismatch = || {
        format!(
            "column {} is declared {:?}{} but its accessor gave {cell:?}",
            c.name,
            c.shape,
            if c.is_family() { " (a family)" } else { "" }
        )
    };
    match cell {
        Cell::Absent => {}
        Cell::Members(parts) if c.is_family() && stem.contains("{}") => {
            for (part, v) in parts {
                write(row, lines, c, &c.member(part), v, judged_lines)?;
            }
        }
        _ if stem.contains("{}") => return Err(mismatch()),
        Cell::Value(v) if c.shape == Shape::Value => {
            row.push_cell(stem.to_string(), c.class, c.unit, v.clone());
        }
        Cell::Estimate(e) if c.shape == Shape::Estimate => {
            row.estimate_cells(c, stem, e);
        }
        Cell::Judged(e, t) => {
            match (c.shape, t) {
                (Shape::EstimateVsPrediction, Theory::Prediction(p)) => {
                    row.estimate_cells(c, stem, e).derived_cell(
                        stem,
                        part::THEORY,
                        Class::Theory,
                        c.unit,
                        Value::F(*p),
                    );
                }
                (
                    Shape::EstimateVsBand,
                    Theory::Band {
                        prediction,
                        lower,
                        upper,
                    },
                ) => {
                    let verdict = t.verdict(e).to_string();
                    row.estimate_cells(c, stem, e)
                        .derived_cell(
                            stem,
                            part::THEORY,
                            Class::Theory,
                            c.unit,
                            Value::F(*prediction),
                        )
                        .derived_cell(stem, part::LOWER, Class::Theory, c.unit, Value::F(*lower))
                        .derived_cell(stem, part::UPPER, Class::Theory, c.unit, Value::F(*upper))
                        .derived_cell(stem, part::BAND, Class::Check, "1", Value::S(verdict));
                }
                _ => return Err(mismatch()),
            }
            if judged_lines {
                lines.push(
                    Line {
                        metric: stem.to_string(),
                        estimate: *e,
                        against: Against::Theory(*t),
                    }
                    .judge(),
                );
            }
        }
        _ => return Err(mismatch()),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    struct M {
        count: u64,
        tests: Vec<(String, u64)>,
        n_i: Estimate,
        finite: Option<f64>,
    }

    static COUNT: Column =
        Column::value("count", "1", Class::Measured, "a count").decided_by_timing();
    static TESTS: Column =
        Column::value("tests_{}", "tests", Class::Measured, "per engine").accelerator_work();
    static N_I: Column = Column::vs_band("n_i", "tests", "ray-sphere tests");
    static FINITE: Column = Column::value("finite", "1", Class::Measured, "finite scenes only");

    static ENTRIES: &[Entry<f64, M>] = &[
        col(&COUNT, |_, m| m.count.into()),
        col(&TESTS, |_, m| Cell::members(m.tests.clone())),
        col(&N_I, |p, m| {
            Cell::Judged(
                m.n_i,
                Theory::Band {
                    prediction: *p,
                    lower: 1.0,
                    upper: 10.0,
                },
            )
        }),
        col(&FINITE, |_, m| m.finite.into()),
    ];

    fn measured() -> M {
        M {
            count: 3,
            tests: vec![("grid".into(), 5), ("octree".into(), 7)],
            n_i: Estimate {
                mean: 5.0,
                se: 0.1,
                n: 1000,
                clusters: 100,
            },
            finite: None,
        }
    }

    /// A declared table gives the cells, classes and summary lines `Metric::write` and `Row::put`
    /// gave by hand before, and a column absent from a row is not written.
    #[test]
    fn a_declared_table_builds_its_row_and_lines() {
        let (row, lines) =
            row(&cells(ENTRIES, &5.1, &measured()), Demote::default(), true).expect("fits");
        let names: Vec<&str> = row.0.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "count",
                "tests_grid",
                "tests_octree",
                "n_i_mean",
                "n_i_se",
                "n_i_n",
                "n_i_clusters",
                "n_i_theory",
                "n_i_lower",
                "n_i_upper",
                "n_i_band"
            ]
        );
        assert_eq!(row.get("n_i_band"), Some(&Value::S("inside".into())));
        assert_eq!(row.get("tests_octree"), Some(&Value::U(7)));
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].verdict, Verdict::Inside);
        assert_eq!(lines[0].theory, "5.100 [1.000, 10.000]");
        let (_, none) =
            super::row(&cells(ENTRIES, &5.1, &measured()), Demote::default(), false).expect("fits");
        assert!(none.is_empty());
    }

    #[test]
    fn a_timed_decision_demotes_only_its_columns_measured_cells() {
        let timed = Demote {
            timed: true,
            ..Demote::default()
        };
        let (row, _) = row(&cells(ENTRIES, &5.1, &measured()), timed, false).expect("fits");
        let class = |n: &str| row.0.iter().find(|c| c.name == n).map(|c| c.class);
        assert_eq!(class("count"), Some(Class::Timing));
        assert_eq!(class("tests_grid"), Some(Class::Measured));
        assert_eq!(class("n_i_mean"), Some(Class::Measured));
    }

    #[test]
    fn a_photon_merge_demotes_only_accelerator_work() {
        let merged = Demote {
            photon_merged: true,
            ..Demote::default()
        };
        let (row, _) = row(&cells(ENTRIES, &5.1, &measured()), merged, false).expect("fits");
        let class = |n: &str| row.0.iter().find(|c| c.name == n).map(|c| c.class);
        assert_eq!(class("tests_grid"), Some(Class::Timing));
        assert_eq!(class("count"), Some(Class::Measured));
        assert_eq!(class("n_i_mean"), Some(Class::Measured));
    }

    #[test]
    fn a_cell_that_does_not_fit_its_column_is_refused() {
        static BAD: &[Entry<f64, M>] = &[col(&COUNT, |_, m| Cell::Estimate(m.n_i))];
        let e = row(&cells(BAD, &0.0, &measured()), Demote::default(), true).expect_err("shape");
        assert!(e.contains("column count"), "{e}");
    }
}
