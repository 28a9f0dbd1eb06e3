//! Rows: ordered (column, value) pairs, the unit every sink writes.

/// One CSV cell.
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

/// A table row: columns in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Row(pub Vec<(String, Value)>);

impl Row {
    /// Appends a column.
    pub fn push(&mut self, col: impl Into<String>, v: Value) -> &mut Self {
        self.0.push((col.into(), v));
        self
    }

    /// Appends a real.
    pub fn f(&mut self, col: impl Into<String>, x: f64) -> &mut Self {
        self.push(col, Value::F(x))
    }

    /// Appends an exact count.
    pub fn u(&mut self, col: impl Into<String>, x: u64) -> &mut Self {
        self.push(col, Value::U(x))
    }

    /// Appends text.
    pub fn s(&mut self, col: impl Into<String>, x: impl Into<String>) -> &mut Self {
        self.push(col, Value::S(x.into()))
    }

    /// Appends `M_mean, M_se, M_n` of an estimate.
    pub fn estimate(&mut self, m: &str, e: &crate::stats::Estimate) -> &mut Self {
        self.f(format!("{m}_mean"), e.mean)
            .f(format!("{m}_se"), e.se)
            .u(format!("{m}_n"), e.n)
    }

    /// The value of a column.
    pub fn get(&self, col: &str) -> Option<&Value> {
        self.0.iter().find(|(c, _)| c == col).map(|(_, v)| v)
    }
}

/// Is `col` a timing column (allowed to differ between runs of the same spec and seed)? Seconds
/// end in `_s`; an estimate of seconds is `X_s_mean`, `X_s_se`; `rays_per_s` and `speedup` are
/// rates; `timed_*` columns are decisions taken from measured times (the §4.1 predictor's pick).
pub fn is_timing_column(col: &str) -> bool {
    col.ends_with("_s")
        || col.ends_with("_s_mean")
        || col.ends_with("_s_se")
        || col == "rays_per_s"
        || col == "speedup"
        || col.starts_with("timed_")
}
