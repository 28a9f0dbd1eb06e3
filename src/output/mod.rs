//! Where results go: CSV tables and metadata written so that nothing a user has is ever lost.
//!
//! Rows are appended and flushed point by point to `.partial` files beside the final ones; only a
//! finished run renames them into place (an atomic rename on one file system). An existing result
//! is never replaced without `--force`, and every check that could refuse a run happens before the
//! first point is traced.

pub mod column;
pub mod csv;
pub mod merge;
pub mod meta;
pub mod progress;
pub mod row;
pub mod sink;
pub mod summary;
pub mod table;
pub mod time;

pub use crate::error::OutputError;
