//! Rows: ordered cells, each with its column's name, class and value — the unit every sink writes.
//! Cells come from [`Column`] declarations (see [`super::column`]), so a row knows which of its
//! columns are measured and which are timings.

use super::column::{Class, Column, ColumnInfo, Shape};
use crate::stats::Estimate;

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
    /// CSV text: reals with full round-trip precision, NaN as `NaN`.
    pub fn render(&self) -> String {
        match self {
            Value::F(x) => format!("{x:?}"),
            Value::U(u) => u.to_string(),
            Value::S(s) => s.clone(),
        }
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
    /// Its unit (from the declaration; empty for parameters, whose units the spec reference gives).
    pub unit: &'static str,
    /// Its value.
    pub value: Value,
}

/// A table row: cells in column order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Row(pub Vec<Cell>);

impl Row {
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

    /// Appends member `part` of the single-valued family `c` (`tests_{}` → `tests_PART`).
    pub fn put_member(&mut self, c: &Column, part: &str, v: impl Into<Value>) -> &mut Self {
        debug_assert!(c.shape == Shape::Value && c.is_family(), "{}", c.name);
        self.push(c.member(part), c.class, c.unit, v.into())
    }

    /// Appends `M_mean, M_se, M_n` of the estimate column `c`.
    pub fn put_estimate(&mut self, c: &Column, e: &Estimate) -> &mut Self {
        debug_assert!(c.shape == Shape::Estimate && !c.is_family(), "{}", c.name);
        self.estimate_cells(c, c.name, e)
    }

    /// Appends `M_mean, M_se, M_n` of member `part` of the estimate family `c`
    /// (`tests_{}_per_replica` → `tests_PART_per_replica_mean`, …).
    pub fn put_member_estimate(&mut self, c: &Column, part: &str, e: &Estimate) -> &mut Self {
        debug_assert!(c.shape == Shape::Estimate && c.is_family(), "{}", c.name);
        let stem = c.member(part);
        self.estimate_cells(c, &stem, e)
    }

    /// Appends the estimate cells of `c` under `stem` (a metric writes its theory columns after).
    pub(crate) fn estimate_cells(&mut self, c: &Column, stem: &str, e: &Estimate) -> &mut Self {
        self.push(format!("{stem}_mean"), c.class, c.unit, Value::F(e.mean))
            .push(format!("{stem}_se"), c.class, c.unit, Value::F(e.se))
            .push(format!("{stem}_n"), Class::Measured, "1", Value::U(e.n))
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

    /// Appends a parameter column (a spec key of the point).
    pub fn param(&mut self, name: &str, v: Value) -> &mut Self {
        self.push(name.to_string(), Class::Parameter, "", v)
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
        r.put(&COUNT, 3u64).put_estimate(
            &SECS,
            &Estimate {
                mean: 1.0,
                se: 0.1,
                n: 4,
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
                ("frame_s_n", Class::Measured)
            ]
        );
        assert_eq!(r.get("count"), Some(&Value::U(3)));
    }
}
