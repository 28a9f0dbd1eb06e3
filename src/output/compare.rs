//! Two runs' tables compared column class by column class: what `raycost reproduce` judges a rerun
//! by. One [`Side`] is a result as written (its tables, plain or gzip-compressed, and its metadata);
//! [`compare`] holds the second against the first, table by table.
//!
//! The rule, per table (the classes are the first side's `[[columns.TABLE]]`):
//! - the header must be the same (names and order) and every column's class the same; the number
//!   of rows the same;
//! - every column whose class is not `timing` (parameters, measured counts and estimates, theory,
//!   checks) is *counted*: equal byte for byte in every row;
//! - a timing `X_mean` whose table has `X_se` is held against its stated interval,
//!   |a − b| ≤ 3·√(se_a² + se_b²), and counted only when both runs' seconds are comparable: the same
//!   CPU model and neither run busy (other processes under [`super::meta::BUSY_CORES`] cores);
//!   otherwise, and for every other timing column, the cells are reported (ratios new/old), never
//!   counted. Seconds of one machine say nothing about another's. Where the result has committed
//!   separate runs (`runs/R`), a timing mean is held instead to the band those runs' spread gives
//!   one more run ([`RunSpread`]): the machine drifts between runs more than within one.
//!
//! A table declared in the first side's metadata but missing from either side is a counted
//! difference: a result that cannot be compared is not reproduced.

use std::path::{Path, PathBuf};

use super::column::{part, Class, ColumnInfo};
use super::header_changes;
use super::meta::Meta;
use super::readback::{finished_table_bytes, text_cells};
use super::run_spread::judge_offsets;
pub use super::run_spread::RunSpread;
use crate::error::OutputError;

/// Differences printed per table before the rest are only counted.
pub const SHOWN: usize = 5;

/// How many standard errors of the difference a timing mean may move (three: a 99.7 % band).
pub const TIMING_SIGMAS: f64 = 3.0;

/// One result as written: its tables (table name → file) and its metadata.
#[derive(Clone, Debug)]
pub struct Side {
    /// Table name (`main`, or a side table's name) → its file.
    pub tables: Vec<(String, PathBuf)>,
    /// The run's metadata (the classes of its columns, its machine).
    pub meta: Meta,
    /// The folder it was read from (for reports).
    pub folder: String,
}

impl Side {
    /// The tables of run `stem` in `dir`: `STEM.csv` is `main`, `STEM.TABLE.csv` (or
    /// `STEM.TABLE.csv.gz`, as large committed tables are kept) is `TABLE`.
    pub fn of_run(dir: &Path, stem: &str, meta: Meta) -> Result<Side, OutputError> {
        let entries = std::fs::read_dir(dir)
            .map_err(|e| OutputError::new(dir, format!("cannot read the results folder: {e}")))?;
        let mut tables = Vec::new();
        for e in entries.flatten() {
            let file = e.file_name().to_string_lossy().into_owned();
            let Some(rest) = file.strip_prefix(stem) else {
                continue;
            };
            let rest = rest
                .strip_suffix(".csv.gz")
                .or_else(|| rest.strip_suffix(".csv"));
            let table = match rest {
                Some("") => "main".to_string(),
                Some(t) if t.len() > 1 && t.starts_with('.') && !t[1..].contains('.') => {
                    t[1..].to_string()
                }
                _ => continue,
            };
            tables.push((table, e.path()));
        }
        // Only the tables the run declared (not the shards merged beside a merged table).
        tables.retain(|(t, _)| t == "main" || meta.columns.contains_key(t));
        tables.sort();
        // Both `T.csv` and `T.csv.gz`: the plain one is read (as `raycost crossover` does).
        tables.dedup_by(|b, a| a.0 == b.0);
        let folder = dir.display().to_string();
        Ok(Side {
            tables,
            meta,
            folder,
        })
    }

    /// The tables of a `raycost crossover` folder: `crossover.csv` (`main`), `best.csv`,
    /// `frames.csv`.
    pub fn of_crossover(dir: &Path, meta: Meta) -> Side {
        let tables = [
            ("main", "crossover.csv"),
            ("best", "best.csv"),
            ("frames", "frames.csv"),
        ]
        .iter()
        .map(|(t, f)| (t.to_string(), dir.join(f)))
        .filter(|(_, p)| p.is_file())
        .collect();
        Side {
            tables,
            meta,
            folder: dir.display().to_string(),
        }
    }

    pub(super) fn file(&self, table: &str) -> Option<&PathBuf> {
        self.tables.iter().find(|(t, _)| t == table).map(|(_, p)| p)
    }

    /// Whether this run's seconds were taken on a quiet machine.
    fn quiet(&self) -> bool {
        !self.meta.busy()
    }
}

/// One counted cell that differs.
#[derive(Clone, Debug, PartialEq)]
pub struct CellDiff {
    /// Data row, from 0.
    pub row: usize,
    /// The row's `point` cell, where the table has that column.
    pub point: Option<String>,
    /// The column.
    pub column: String,
    /// The first side's cell.
    pub old: String,
    /// The second side's cell.
    pub new: String,
}

impl std::fmt::Display for CellDiff {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.point {
            Some(p) => write!(f, "row {} (point {p})", self.row)?,
            None => write!(f, "row {}", self.row)?,
        }
        write!(f, " {}: {:?} → {:?}", self.column, self.old, self.new)
    }
}

/// The timing columns of one table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings {
    /// Timing columns.
    pub columns: usize,
    /// `X_mean` columns with an `X_se` beside them.
    pub with_interval: usize,
    /// Why their intervals do not count (another CPU, a busy machine); `None` when they do.
    pub not_counted: Option<String>,
    /// Cells judged against an interval: inside it.
    pub inside: usize,
    /// … outside it (the first few in `first_outside`).
    pub outside: usize,
    /// The first cells outside their interval.
    pub first_outside: Vec<CellDiff>,
    /// new/old over every timing cell where both are finite and > 0: (min, median, max).
    pub ratios: Option<(f64, f64, f64)>,
    /// Timing cells that differ as text (any timing column).
    pub differ: usize,
    /// Of the judged cells, those judged against the spread between the result's committed
    /// separate runs ([`RunSpread`]) rather than the two runs' own standard errors.
    pub between_runs: usize,
    /// How many committed runs that spread comes from (0: none).
    pub runs: usize,
    /// The rerun's seconds over the committed runs' (geometric means), the median over the cells
    /// judged against their spread: the machine's speed that session, reported, not judged.
    pub run_factor: Option<f64>,
}

/// One table compared.
#[derive(Clone, Debug, PartialEq)]
pub struct TableComparison {
    /// The table's name (`main`, `levels`, …).
    pub table: String,
    /// The first side's file name (or the table name when it has none).
    pub file: String,
    /// Columns in the header.
    pub columns: usize,
    /// Counted columns (every class but timing).
    pub compared: usize,
    /// Rows of the first side.
    pub rows: usize,
    /// Counted cells that differ.
    pub cells_differ: usize,
    /// Counted columns with at least one differing cell.
    pub columns_differ: Vec<String>,
    /// The first differing counted cells.
    pub first: Vec<CellDiff>,
    /// What else is wrong (a missing table, another header, other classes, another row count).
    pub problems: Vec<String>,
    /// Columns of the first side read under their current name or dropped as duplicates
    /// ([`super::header_changes`]): reported, not counted.
    pub mapped: Vec<String>,
    /// The timing columns.
    pub timings: Timings,
}

impl TableComparison {
    /// Whether everything counted is the same.
    pub fn same(&self) -> bool {
        self.cells_differ == 0
            && self.problems.is_empty()
            && (self.timings.not_counted.is_some() || self.timings.outside == 0)
    }

    /// One line: what was compared and what differs.
    pub fn line(&self) -> String {
        let mut s = format!(
            "{}{} ({}): {} of {} columns compared, {} rows, {} cell{} differ{}",
            if self.same() { "" } else { "DIFFERS " },
            self.file,
            self.table,
            self.compared,
            self.columns,
            self.rows,
            self.cells_differ,
            if self.cells_differ == 1 { "" } else { "s" },
            if self.cells_differ == 1 { "s" } else { "" },
        );
        if !self.columns_differ.is_empty() {
            s.push_str(&format!(
                " in {} column(s) [{}]",
                self.columns_differ.len(),
                self.columns_differ.join(", ")
            ));
        }
        if !self.first.is_empty() {
            let shown: Vec<String> = self.first.iter().map(ToString::to_string).collect();
            s.push_str(&format!(": {}", shown.join("; ")));
        }
        for p in &self.problems {
            s.push_str(&format!(" | {p}"));
        }
        for m in &self.mapped {
            s.push_str(&format!(" | mapped: {m}"));
        }
        let t = &self.timings;
        if t.columns > 0 {
            s.push_str(&format!("; {} timing column(s)", t.columns));
            if t.with_interval > 0 {
                s.push_str(&format!(
                    ", {} cell(s) inside their ±{TIMING_SIGMAS}σ interval, {} outside",
                    t.inside, t.outside
                ));
                if t.between_runs > 0 {
                    s.push_str(&format!(
                        " ({} of them judged against the spread between {} committed runs, after \
                         this run's machine factor {:.3})",
                        t.between_runs,
                        t.runs,
                        t.run_factor.unwrap_or(f64::NAN)
                    ));
                }
                if let Some(why) = &t.not_counted {
                    s.push_str(&format!(" (not counted: {why})"));
                }
                if !t.first_outside.is_empty() {
                    let shown: Vec<String> =
                        t.first_outside.iter().map(ToString::to_string).collect();
                    s.push_str(&format!(" [{}]", shown.join("; ")));
                }
            }
            if let Some((lo, med, hi)) = t.ratios {
                s.push_str(&format!(
                    ", seconds new/old {lo:.3}…{hi:.3} (median {med:.3})"
                ));
            }
        }
        s
    }

    /// The comparison as JSON.
    pub fn json(&self) -> serde_json::Value {
        let cells = |v: &[CellDiff]| -> Vec<serde_json::Value> {
            v.iter()
                .map(|d| {
                    serde_json::json!({
                        "row": d.row, "point": d.point, "column": d.column,
                        "old": d.old, "new": d.new,
                    })
                })
                .collect()
        };
        let t = &self.timings;
        serde_json::json!({
            "table": self.table,
            "file": self.file,
            "same": self.same(),
            "columns": self.columns,
            "compared": self.compared,
            "rows": self.rows,
            "cells_differ": self.cells_differ,
            "columns_differ": self.columns_differ,
            "differences": cells(&self.first),
            "problems": self.problems,
            "mapped": self.mapped,
            "timing": {
                "columns": t.columns,
                "with_interval": t.with_interval,
                "counted": t.not_counted.is_none(),
                "not_counted_because": t.not_counted,
                "inside": t.inside,
                "outside": t.outside,
                "first_outside": cells(&t.first_outside),
                "ratio_min": t.ratios.map(|r| r.0),
                "ratio_median": t.ratios.map(|r| r.1),
                "ratio_max": t.ratios.map(|r| r.2),
                "cells_differ": t.differ,
                "judged_between_runs": t.between_runs,
                "committed_runs": t.runs,
                "run_factor": t.run_factor,
            },
        })
    }
}

/// A table's header and rows as text.
pub(super) struct Cells {
    pub(super) header: Vec<String>,
    pub(super) rows: Vec<Vec<String>>,
}

/// Reads a table (gzip-decompressed if its name ends in `.gz`).
pub(super) fn read_cells(path: &Path) -> Result<Cells, OutputError> {
    let (header, rows) = text_cells(path, &finished_table_bytes(path)?)?;
    Ok(Cells { header, rows })
}

/// Compares every table of `old` (and any `new` has beyond them) with `new`'s. A table that cannot
/// be read is an error naming its file.
pub fn compare(
    old: &Side,
    new: &Side,
    judge_timings: bool,
    spread: Option<&RunSpread>,
) -> Result<Vec<TableComparison>, OutputError> {
    let mut names: Vec<String> = old.meta.columns.keys().cloned().collect();
    for (t, _) in old.tables.iter().chain(&new.tables) {
        if !names.contains(t) {
            names.push(t.clone());
        }
    }
    // `main` first, then the side tables by name.
    names.sort_by_key(|t| (t != "main", t.clone()));
    let not_counted = if judge_timings {
        timings_comparable(old, new).err()
    } else {
        Some("--timings report: timings reported, not judged".to_string())
    };
    let mut out = Vec::new();
    for table in names {
        let file = |s: &Side| {
            s.file(&table)
                .and_then(|p| p.file_name())
                .map(|f| f.to_string_lossy().into_owned())
        };
        let mut c = TableComparison {
            file: file(old)
                .or_else(|| file(new))
                .unwrap_or_else(|| table.clone()),
            table: table.clone(),
            columns: 0,
            compared: 0,
            rows: 0,
            cells_differ: 0,
            columns_differ: Vec::new(),
            first: Vec::new(),
            problems: Vec::new(),
            mapped: Vec::new(),
            timings: Timings {
                not_counted: not_counted.clone(),
                ..Timings::default()
            },
        };
        match (old.file(&table), new.file(&table)) {
            (Some(a), Some(b)) => {
                let mut classes = old.meta.columns.get(&table).cloned().unwrap_or_default();
                let new_classes = new.meta.columns.get(&table).map_or(&[][..], Vec::as_slice);
                let mut cells = read_cells(a)?;
                if let Some(kind) = old.meta.kind() {
                    let (mapped, differ) = header_changes::upgrade(
                        kind,
                        &table,
                        &mut cells.header,
                        &mut cells.rows,
                        &mut classes,
                    );
                    c.mapped = mapped;
                    c.problems.extend(differ);
                }
                compare_table(
                    &mut c,
                    &cells,
                    &read_cells(b)?,
                    &classes,
                    new_classes,
                    spread,
                );
            }
            (None, Some(_)) => c.problems.push(
                "missing in the result (declared in its metadata or written by the rerun)".into(),
            ),
            (Some(_), None) => c.problems.push("not written by the rerun".into()),
            (None, None) => c
                .problems
                .push("declared in the metadata, missing in both folders".into()),
        }
        out.push(c);
    }
    Ok(out)
}

/// Whether timing intervals count: both runs on the same CPU model, neither busy.
fn timings_comparable(old: &Side, new: &Side) -> Result<(), String> {
    if old.meta.machine.cpu != new.meta.machine.cpu {
        return Err(format!(
            "another CPU: {} then, {} now",
            old.meta.machine.cpu, new.meta.machine.cpu
        ));
    }
    for (side, which) in [(old, "the result"), (new, "the rerun")] {
        if !side.quiet() {
            return Err(format!("{which} ran on a busy machine"));
        }
    }
    Ok(())
}

/// One table against its rerun: the structure first, then every counted column cell by cell and
/// every timing column against the two runs' intervals.
fn compare_table(
    c: &mut TableComparison,
    a: &Cells,
    b: &Cells,
    classes: &[ColumnInfo],
    new_classes: &[ColumnInfo],
    spread: Option<&RunSpread>,
) {
    structure_problems(c, a, b, classes, new_classes);
    let class_of =
        |cols: &[ColumnInfo], name: &str| cols.iter().find(|c| c.name == name).map(|c| c.class);
    let timing = |h: &str| class_of(classes, h) == Some(Class::Timing);
    let at = |x: &Cells, name: &str| x.header.iter().position(|h| h == name);
    let point = at(a, "point");
    let diff = |r: usize, name: &str, x: &str, y: &str| CellDiff {
        row: r,
        point: point.map(|p| a.rows[r][p].clone()),
        column: name.to_string(),
        old: x.to_string(),
        new: y.to_string(),
    };
    let mut ratios = Vec::new();
    // Cells held to the committed runs' band: (offset, variance), the cell.
    let mut pending: Vec<((f64, f64), CellDiff)> = Vec::new();
    // Every column of the result that the rerun has, found by name.
    for (ca, name) in a.header.iter().enumerate() {
        let Some(cb) = at(b, name) else { continue };
        let pairs = a.rows.iter().zip(&b.rows).enumerate();
        if !timing(name) {
            c.compared += 1;
            let mut differs = false;
            for (r, (x, y)) in pairs {
                if x[ca] != y[cb] {
                    differs = true;
                    c.cells_differ += 1;
                    if c.first.len() < SHOWN {
                        c.first.push(diff(r, name, &x[ca], &y[cb]));
                    }
                }
            }
            if differs {
                c.columns_differ.push(name.clone());
            }
            continue;
        }
        c.timings.columns += 1;
        let se_name = part::stem(name, part::MEAN).map(|stem| part::name(stem, part::SE));
        let se = se_name
            .as_deref()
            .and_then(|n| Some((at(a, n)?, at(b, n)?)));
        if se.is_some() {
            c.timings.with_interval += 1;
        }
        let band = spread.and_then(|s| s.column(&c.table, name));
        for (r, (x, y)) in pairs {
            let (u, v) = (number(&x[ca]), number(&y[cb]));
            if x[ca] != y[cb] {
                c.timings.differ += 1;
                if let (Some(u), Some(v)) = (u, v) {
                    if u > 0.0 && v > 0.0 {
                        ratios.push(v / u);
                    }
                }
            }
            let Some((sa, sb)) = se else { continue };
            if x[ca] == y[cb] {
                c.timings.inside += 1;
                continue;
            }
            // Where the result has separate committed runs, their spread gives the band a new
            // run is held to, judged below once every cell's offset is known (`run_spread`).
            if let Some((band, v)) = band.zip(v) {
                if let Some(off) = band.offset(r, v, number(&y[sb]).unwrap_or(f64::NAN)) {
                    c.timings.runs = band.runs;
                    pending.push((off, diff(r, name, &x[ca], &y[cb])));
                    continue;
                }
            }
            // An interval that cannot be formed (one replica: SE NaN) judges nothing.
            if let (Some(u), Some(v), Some(su), Some(sv)) = (u, v, number(&x[sa]), number(&y[sb])) {
                if (u - v).abs() <= TIMING_SIGMAS * su.hypot(sv) {
                    c.timings.inside += 1;
                } else {
                    c.timings.outside += 1;
                    if c.timings.first_outside.len() < SHOWN {
                        c.timings.first_outside.push(diff(r, name, &x[ca], &y[cb]));
                    }
                }
            }
        }
    }
    c.timings.ratios = summary(&mut ratios);
    let offsets: Vec<(f64, f64)> = pending.iter().map(|p| p.0).collect();
    let (factor, inside) = judge_offsets(&offsets);
    if !pending.is_empty() {
        c.timings.run_factor = Some(factor.exp());
    }
    for ((_, cell), ok) in pending.into_iter().zip(inside) {
        c.timings.between_runs += 1;
        if ok {
            c.timings.inside += 1;
        } else {
            c.timings.outside += 1;
            if c.timings.first_outside.len() < SHOWN {
                c.timings.first_outside.push(cell);
            }
        }
    }
}

/// The table's shape against the rerun's: headers, columns without a class, classes that moved,
/// row counts (each a problem, none stopping the cell comparison).
fn structure_problems(
    c: &mut TableComparison,
    a: &Cells,
    b: &Cells,
    classes: &[ColumnInfo],
    new_classes: &[ColumnInfo],
) {
    c.columns = a.header.len();
    c.rows = a.rows.len();
    if a.header != b.header {
        let only = |x: &Cells, y: &Cells| -> Vec<String> {
            x.header
                .iter()
                .filter(|h| !y.header.contains(h))
                .cloned()
                .collect()
        };
        let (gone, added) = (only(a, b), only(b, a));
        c.problems.push(if gone.is_empty() && added.is_empty() {
            "headers differ: the same names in another order (cells compared by name)".into()
        } else {
            format!(
                "headers differ: only in the result [{}], only in the rerun [{}] (the other columns compared by name)",
                gone.join(", "),
                added.join(", ")
            )
        });
    }
    let class_of =
        |cols: &[ColumnInfo], name: &str| cols.iter().find(|c| c.name == name).map(|c| c.class);
    let undeclared: Vec<&str> = a
        .header
        .iter()
        .filter(|h| class_of(classes, h).is_none())
        .map(String::as_str)
        .collect();
    if !undeclared.is_empty() {
        c.problems.push(format!(
            "columns without a class in the metadata (compared as measured): [{}]",
            undeclared.join(", ")
        ));
    }
    let reclassed: Vec<String> = a
        .header
        .iter()
        .filter_map(|h| match (class_of(classes, h), class_of(new_classes, h)) {
            (Some(x), Some(y)) if x != y => Some(format!("{h} {} → {}", x.as_str(), y.as_str())),
            _ => None,
        })
        .collect();
    if !reclassed.is_empty() {
        c.problems
            .push(format!("classes differ: {}", reclassed.join(", ")));
    }
    if a.rows.len() != b.rows.len() {
        c.problems.push(format!(
            "{} rows in the result, {} in the rerun",
            a.rows.len(),
            b.rows.len()
        ));
    }
}

/// A finite number, or `None`.
fn number(s: &str) -> Option<f64> {
    s.parse::<f64>().ok().filter(|x| x.is_finite())
}

/// (min, median, max) of `v`, or `None` when it is empty.
fn summary(v: &mut [f64]) -> Option<(f64, f64, f64)> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some((v[0], v[v.len() / 2], v[v.len() - 1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::column::ColumnInfo;

    fn info(name: &str, class: Class) -> ColumnInfo {
        ColumnInfo {
            name: name.into(),
            class,
            unit: String::new(),
        }
    }

    fn cells(text: &str) -> Cells {
        let mut lines = text
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect());
        Cells {
            header: lines.next().expect("a header"),
            rows: lines.collect(),
        }
    }

    /// `new` compared with `OLD`, both under [`classes`], no committed runs.
    fn against_old(c: &mut TableComparison, new: &str) {
        compare_table(c, &cells(OLD), &cells(new), &classes(), &classes(), None);
    }

    fn fresh(table: &str) -> TableComparison {
        TableComparison {
            table: table.into(),
            file: format!("x.{table}.csv"),
            columns: 0,
            compared: 0,
            rows: 0,
            cells_differ: 0,
            columns_differ: Vec::new(),
            first: Vec::new(),
            problems: Vec::new(),
            mapped: Vec::new(),
            timings: Timings::default(),
        }
    }

    fn classes() -> Vec<ColumnInfo> {
        vec![
            info("point", Class::Parameter),
            info("n_mean", Class::Measured),
            info("t_mean", Class::Timing),
            info("t_se", Class::Timing),
            info("wall_s", Class::Timing),
        ]
    }

    const OLD: &str = "point,n_mean,t_mean,t_se,wall_s\n0,1.5,10,1,2\n1,2.5,20,1,4\n";

    /// Counted cells must match byte for byte (`1.50` is not `1.5`); the row, its point and the
    /// column are named.
    #[test]
    fn a_counted_cell_that_differs_is_named() {
        let mut c = fresh("main");
        let new = "point,n_mean,t_mean,t_se,wall_s\n0,1.5,10,1,2\n1,2.50,20,1,4\n";
        against_old(&mut c, new);
        assert_eq!((c.compared, c.cells_differ), (2, 1));
        assert_eq!(c.columns_differ, ["n_mean"]);
        assert_eq!(
            c.first[0].to_string(),
            "row 1 (point 1) n_mean: \"2.5\" → \"2.50\""
        );
        assert!(!c.same());
        assert!(
            c.line()
                .starts_with("DIFFERS x.main.csv (main): 2 of 5 columns"),
            "{}",
            c.line()
        );
    }

    /// A timing mean inside 3·√(se_a² + se_b²) passes, outside fails when counted and only
    /// reports when not; timing columns without an interval never fail.
    #[test]
    fn timings_are_held_to_their_interval_only_when_comparable() {
        // |20 − 24| = 4 ≤ 3·√2 ≈ 4.24: inside; wall_s doubles: a ratio only.
        let inside = "point,n_mean,t_mean,t_se,wall_s\n0,1.5,10,1,4\n1,2.5,24,1,8\n";
        let mut c = fresh("main");
        c.timings.not_counted = None;
        against_old(&mut c, inside);
        assert_eq!((c.timings.inside, c.timings.outside), (2, 0));
        assert_eq!(c.timings.ratios, Some((1.2, 2.0, 2.0)));
        assert!(c.same(), "{}", c.line());
        // |20 − 25| = 5 > 4.24: outside.
        let outside = "point,n_mean,t_mean,t_se,wall_s\n0,1.5,10,1,4\n1,2.5,25,1,8\n";
        let mut c = fresh("main");
        c.timings.not_counted = None;
        against_old(&mut c, outside);
        assert_eq!((c.timings.inside, c.timings.outside), (1, 1));
        assert!(!c.same());
        assert!(c.line().contains("row 1 (point 1) t_mean"), "{}", c.line());
        let mut c = fresh("main");
        c.timings.not_counted = Some("another CPU".into());
        against_old(&mut c, outside);
        assert!(c.same(), "{}", c.line());
        assert!(
            c.line().contains("not counted: another CPU"),
            "{}",
            c.line()
        );
    }

    #[test]
    fn another_header_or_row_count_or_class_is_a_difference() {
        let mut c = fresh("main");
        let renamed = "point,n_mean,t_mean,t_se,wall\n0,1.5,10,1,2\n1,2.5,20,1,4\n";
        against_old(&mut c, renamed);
        assert!(c.problems[0].contains("only in the result [wall_s], only in the rerun [wall]"));
        assert_eq!(c.compared, 2, "the other columns are still compared");
        let mut c = fresh("main");
        let reordered = "point,t_mean,n_mean,t_se,wall_s\n0,10,1.5,1,2\n1,20,2.6,1,4\n";
        against_old(&mut c, reordered);
        assert!(c.problems[0].contains("another order"), "{:?}", c.problems);
        assert_eq!((c.compared, c.cells_differ), (2, 1), "compared by name");
        assert_eq!(c.first[0].new, "2.6");
        let mut c = fresh("main");
        let short = "point,n_mean,t_mean,t_se,wall_s\n0,1.5,10,1,2\n";
        against_old(&mut c, short);
        assert!(c.problems[0].contains("2 rows in the result, 1 in the rerun"));
        let mut other = classes();
        other[1].class = Class::Timing;
        let mut c = fresh("main");
        compare_table(&mut c, &cells(OLD), &cells(OLD), &classes(), &other, None);
        assert!(
            c.problems[0].contains("n_mean measured → timing"),
            "{:?}",
            c.problems
        );
        assert!(!c.same());
    }
}
