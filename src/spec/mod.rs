//! Experiment specs: TOML text → validated points.
//!
//! Two levels, as ripgrep's low/high args: [`raw::RawSpec`] mirrors the file and rejects unknown keys
//! and out-of-range values where they are read (with file, line, column and dotted key); then each
//! sweep point is expanded on the TOML tree, read again, and turned into a [`GridConfig`], the only
//! thing engines see. Checks that span several keys (one radius source, fractions summing to 1, the
//! memory a finite grid would need) come last and name the key they blame.

pub mod config;
pub mod detp;
pub mod quasi_static;
pub mod raw;
pub mod sweep;

pub use crate::error::InputError;
pub use config::{GridConfig, PointConfig, SceneModel};
pub use detp::DetpConfig;
pub use raw::{Kind, RawSpec, DEFAULT_RAYS_PER_SCENE};
pub use sweep::{Point, Spec};
