//! A result CSV read as text cells by column name: all the report needs of a table (the point rows
//! of `NAME.csv`, the rows of `bench.csv`). Missing values may be `NaN` or empty (both conventions
//! occur in committed tables); [`Table::number`] reads either as NaN.

use std::collections::HashMap;
use std::path::Path;

use crate::error::InputError;
use crate::output::column::{Class, ColumnInfo};

/// A CSV table: its header and its rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names in file order.
    pub header: Vec<String>,
    /// Rows of cells, each as long as the header.
    pub rows: Vec<Vec<String>>,
    index: HashMap<String, usize>,
    /// The class the run's metadata declares for each column (empty: it declares none).
    classes: HashMap<String, Class>,
}

impl Table {
    /// Reads `path`; a file that is not a rectangular CSV with a header is an [`InputError`].
    pub fn read(path: &Path) -> Result<Table, InputError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| InputError::new(&file, format!("cannot read the table: {e}")))?;
        Self::parse(&text).map_err(|m| InputError::new(&file, m))
    }

    /// Parses CSV text (header line first).
    pub fn parse(text: &str) -> Result<Table, String> {
        let mut r = csv::ReaderBuilder::new().from_reader(text.as_bytes());
        let header: Vec<String> = r
            .headers()
            .map_err(|e| format!("no CSV header: {e}"))?
            .iter()
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        for rec in r.records() {
            let rec = rec.map_err(|e| format!("not a CSV table: {e}"))?;
            rows.push(rec.iter().map(str::to_string).collect());
        }
        let index = header
            .iter()
            .enumerate()
            .map(|(i, h)| (h.clone(), i))
            .collect();
        Ok(Table {
            header,
            rows,
            index,
            classes: HashMap::new(),
        })
    }

    /// The table checked against the columns its metadata declares (`declared`, in header order;
    /// empty for a run that declares none, whose header is taken as it stands): a header that
    /// differs (a table edited by hand, or paired with another run's metadata) is an
    /// [`InputError`] naming the file and the first column that differs. Each column then has the
    /// declared class ([`Table::class`]).
    pub fn declared(mut self, path: &Path, declared: &[ColumnInfo]) -> Result<Table, InputError> {
        if declared.is_empty() {
            return Ok(self);
        }
        let names: Vec<&str> = declared.iter().map(|c| c.name.as_str()).collect();
        if self.header != names {
            let at = (0..self.header.len().max(names.len()))
                .find(|&i| self.header.get(i).map(String::as_str) != names.get(i).copied())
                .unwrap_or(0);
            return Err(InputError::new(
                path.display().to_string(),
                format!(
                    "the header is not the columns its metadata declares: column {} is {} in the table, {} in the metadata",
                    at + 1,
                    self.header.get(at).map_or("missing".to_string(), |h| format!("'{h}'")),
                    names.get(at).map_or("missing".to_string(), |h| format!("'{h}'")),
                ),
            ));
        }
        self.classes = declared.iter().map(|c| (c.name.clone(), c.class)).collect();
        Ok(self)
    }

    /// The class the metadata declares for column `name` (None: undeclared).
    pub fn class(&self, name: &str) -> Option<Class> {
        self.classes.get(name).copied()
    }

    /// Whether column `name` exists.
    pub fn has(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// The cell of column `name` in row `row` (None if there is no such column).
    pub fn cell(&self, row: usize, name: &str) -> Option<&str> {
        let i = *self.index.get(name)?;
        self.rows.get(row)?.get(i).map(String::as_str)
    }

    /// The cell as a number: NaN when absent, empty, `NaN` or not a number.
    pub fn number(&self, row: usize, name: &str) -> f64 {
        self.cell(row, name)
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or(f64::NAN)
    }
}

/// A cell for display: integers as integers, other numbers with four significant digits (scientific
/// beyond 10⁶ or below 10⁻³), missing values as an empty string, text as it is.
pub fn display(cell: &str) -> String {
    let t = cell.trim();
    match t.parse::<f64>() {
        Ok(x) if x.is_nan() => String::new(),
        Ok(x) if x.is_infinite() => if x > 0.0 { "∞" } else { "−∞" }.into(),
        Ok(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{x:.0}"),
        Ok(x) if x != 0.0 && (x.abs() >= 1e6 || x.abs() < 1e-3) => format!("{x:.3e}"),
        Ok(x) => {
            let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
            format!("{x:.digits$}")
        }
        Err(_) => t.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_found_by_name_and_missing_values_read_as_nan() {
        let t = Table::parse("point,a_mean,b\n0,1.5,\n1,NaN,x\n").expect("csv");
        assert_eq!(t.number(0, "a_mean"), 1.5);
        assert!(t.number(1, "a_mean").is_nan());
        assert!(t.number(0, "b").is_nan());
        assert_eq!(t.cell(1, "b"), Some("x"));
        assert_eq!(t.cell(0, "zz"), None);
        assert!(Table::parse("a,b\n1\n").is_err(), "ragged rows are refused");
    }

    #[test]
    fn display_reads_like_the_summary() {
        assert_eq!(display("20000.0"), "20000");
        assert_eq!(display("NaN"), "");
        assert_eq!(display("4491480.55967441"), "4.491e6");
        assert_eq!(display("3.4230926610807496e-8"), "3.423e-8");
        assert_eq!(display("2.450148673299011"), "2.450");
        assert_eq!(display("0.066793"), "0.06679");
        assert_eq!(display("105.94112333333334"), "105.9");
        assert_eq!(display("grid"), "grid");
        assert_eq!(display("0"), "0");
    }
}
