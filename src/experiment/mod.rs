//! One module per experiment kind: each maps a point's parameters to a row of measurements and the
//! theory for the same parameters. Rows are plain data; `output` writes them.

pub mod grid;
pub mod machine;
pub mod row;
pub mod runner;

pub use row::{Row, Value};
