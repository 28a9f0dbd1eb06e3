//! Experiment specs: TOML text → a tree per sweep point, with every error located.
//!
//! Two levels, as ripgrep's low/high args: this layer reads the file, checks the `[experiment]`
//! header, and expands `[sweep]` and `--set` into one tree per point ([`Spec`]); the experiment kind
//! named by `experiment.kind` then reads each tree into its own serde struct (unknown keys and tables
//! refused, every number range-checked where it is read, with the readers of
//! [`crate::toml_text::de`]) and translates it into the engines' own types. Errors found there come
//! back here to be located ([`Spec::locate`]): file, line, column and dotted key, or the `--set` flag
//! that set the value.

pub mod magnitude;
pub mod sweep;

pub use crate::error::InputError;
pub use crate::toml_text::de::KeyError;
pub use sweep::{PointSpec, RawExperiment, SetFlag, Spec, MAX_POINTS};
