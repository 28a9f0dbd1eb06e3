//! Where results go: CSV tables and metadata written so that nothing a user has is ever lost.
//!
//! Every file a user keeps is written through one result-folder protocol ([`folder`]: a lock per
//! result, files created new and never through a symlink, fsync, rename). Rows are appended and
//! flushed point by point to `.partial` files beside the final ones; only a finished run publishes
//! them, the main table last. Resume and merge read every row back and check it ([`readback`]). An
//! existing result is never replaced without `--force`, and every check that could refuse a run
//! happens before the first point is traced.

pub mod column;
pub mod compare;
pub mod csv;
pub mod folder;
pub mod header_changes;
pub mod location;
pub mod merge;
pub mod meta;
pub mod progress;
pub mod readback;
pub mod row;
pub mod run_spread;
pub mod sink;
pub mod summary;
pub mod table;
pub mod time;
pub mod work;

pub use crate::error::OutputError;
