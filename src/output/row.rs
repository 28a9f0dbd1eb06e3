//! Rows: ordered cells, each with its column's name, class and value — the unit every sink writes.
//! Cells come from [`Column`] declarations (see [`super::column`]), so a row knows which of its
//! columns are measured and which are timings. A kind's rows are built by [`super::table`] from its
//! declared tables; [`Row::put`] is for the few cells written by hand (the runner's `point`
//! column, `raycost bench`'s tables).

use super::column::{part, Class, Column, ColumnInfo, Shape};
use crate::stats::Estimate;

/// How every table writes a missing value.
pub const MISSING: &str = "NaN";

/// One CSV value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A real number (estimates, theory, timings).
    F(f64),
    /// An exact count.
    U(u64),
    /// Text (labels such as `inside`).
    S(String),
}

impl Value {
    /// CSV text: reals with full round-trip precision. A missing value, numeric (NaN) or text
    /// (empty), is written `NaN`: the one missing-value convention of every table (docs/columns.md),
    /// which every float parser reads back, where an empty field is refused by most.
    pub fn render(&self) -> String {
        match self {
            Value::F(x) => format!("{x:?}"),
            Value::U(u) => u.to_string(),
            Value::S(s) if s.is_empty() => MISSING.to_string(),
            Value::S(s) => s.clone(),
        }
    }

    /// A missing value.
    pub const fn missing() -> Self {
        Value::F(f64::NAN)
    }

    /// The value as a real, if it is a number.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::F(x) => Some(*x),
            Value::U(u) => Some(*u as f64),
            Value::S(_) => None,
        }
    }
}

impl From<f64> for Value {
    fn from(x: f64) -> Self {
        Value::F(x)
    }
}

impl From<u64> for Value {
    fn from(x: u64) -> Self {
        Value::U(x)
    }
}

impl From<usize> for Value {
    fn from(x: usize) -> Self {
        Value::U(x as u64)
    }
}

impl From<u32> for Value {
    fn from(x: u32) -> Self {
        Value::U(u64::from(x))
    }
}

impl From<&str> for Value {
    fn from(x: &str) -> Self {
        Value::S(x.to_string())
    }
}

impl From<String> for Value {
    fn from(x: String) -> Self {
        Value::S(x)
    }
}

/// One cell of a row.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// CSV column name.
    pub name: String,
    /// Its class.
    pub class: Class,
    /// Its unit: the declaration's, a parameter's spec key's (a length in the unit its table's
    /// `length_unit` names), as the run resolved it for this point.
    pub unit: &'static str,
    /// Its value.
    pub value: Value,
}

/// A table row: cells in column order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Row(pub Vec<Cell>);

impl Row {
    /// Appends one cell (the declared-table builder of `output::table`).
    pub(crate) fn push_cell(
        &mut self,
        name: String,
        class: Class,
        unit: &'static str,
        value: Value,
    ) -> &mut Self {
        self.push(name, class, unit, value)
    }

    fn push(&mut self, name: String, class: Class, unit: &'static str, value: Value) -> &mut Self {
        debug_assert!(
            self.0.iter().all(|c| c.name != name),
            "column {name} written twice"
        );
        self.0.push(Cell {
            name,
            class,
            unit,
            value,
        });
        self
    }

    /// Appends the single-valued column `c`.
    pub fn put(&mut self, c: &Column, v: impl Into<Value>) -> &mut Self {
        debug_assert!(c.shape == Shape::Value && !c.is_family(), "{}", c.name);
        self.push(c.name.to_string(), c.class, c.unit, v.into())
    }

    /// Appends the estimate cells of `c` under `stem` (`M_mean, M_se, M_n, M_clusters`).
    pub(crate) fn estimate_cells(&mut self, c: &Column, stem: &str, e: &Estimate) -> &mut Self {
        self.push(
            part::name(stem, part::MEAN),
            c.class,
            c.unit,
            Value::F(e.mean),
        )
        .push(part::name(stem, part::SE), c.class, c.unit, Value::F(e.se))
        .push(
            part::name(stem, part::N),
            Class::Measured,
            "1",
            Value::U(e.n),
        )
        .push(
            part::name(stem, part::CLUSTERS),
            Class::Measured,
            "1",
            Value::U(e.clusters),
        )
    }

    /// Appends a theory or check cell that belongs to the estimate `stem` (`_theory`, `_band`, …).
    pub(crate) fn derived_cell(
        &mut self,
        stem: &str,
        suffix: &str,
        class: Class,
        unit: &'static str,
        v: Value,
    ) -> &mut Self {
        self.push(format!("{stem}{suffix}"), class, unit, v)
    }

    /// Appends a parameter column (a spec key of the point, its value in `unit`).
    pub fn param(&mut self, name: &str, unit: &'static str, v: Value) -> &mut Self {
        self.push(name.to_string(), Class::Parameter, unit, v)
    }

    /// Puts `other`'s cells after this row's.
    pub fn extend(&mut self, other: &Row) -> &mut Self {
        for c in &other.0 {
            self.push(c.name.clone(), c.class, c.unit, c.value.clone());
        }
        self
    }

    /// The value of a column.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.iter().find(|c| c.name == name).map(|c| &c.value)
    }

    /// The columns of this row (what the metadata records of a table).
    pub fn columns(&self) -> Vec<ColumnInfo> {
        self.0
            .iter()
            .map(|c| ColumnInfo {
                name: c.name.clone(),
                class: c.class,
                unit: c.unit.to_string(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COUNT: Column = Column::value("count", "1", Class::Measured, "a count");
    const SECS: Column = Column::timed_estimate("frame_s", "s", "seconds");

    #[test]
    fn cells_carry_the_class_of_their_declaration() {
        let mut r = Row::default();
        r.put(&COUNT, 3u64).estimate_cells(
            &SECS,
            "frame_s",
            &Estimate {
                mean: 1.0,
                se: 0.1,
                n: 12,
                clusters: 4,
            },
        );
        let cols: Vec<(&str, Class)> = r.0.iter().map(|c| (c.name.as_str(), c.class)).collect();
        assert_eq!(
            cols,
            [
                ("count", Class::Measured),
                ("frame_s_mean", Class::Timing),
                ("frame_s_se", Class::Timing),
                ("frame_s_n", Class::Measured),
                ("frame_s_clusters", Class::Measured)
            ]
        );
        assert_eq!(r.get("count"), Some(&Value::U(3)));
        assert_eq!(r.get("frame_s_n"), Some(&Value::U(12)));
        assert_eq!(r.get("frame_s_clusters"), Some(&Value::U(4)));
    }
}
