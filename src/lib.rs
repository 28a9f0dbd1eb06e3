//! raycost measures what ray-tracing acceleration structures really cost and holds every measurement
//! against closed-form theory.
//!
//! ```text
//! experiments/NAME.toml ─parse+validate─▶ Spec ─expand sweep─▶ [Point] ─run (rayon)─▶ [Row]
//!                                                  engines + theory (pure)     results/NAME/NAME.csv
//! ```
//! Layers, each depending only on those above it: `toml_text`, `geom`, `sample`, `stats`, `theory`,
//! `scene` (Poisson processes) and `lt` (light-transport scenes), `grid`, `detp` (ray store, discs,
//! sphere cache, disc index, photon tracing, photon map), `output`, `spec`, `experiment`, `bench`;
//! `render` (images of a quasi-static run) and `report` (an HTML page of a results folder); `cli`,
//! `app` and `main.rs` sit on top.
#![warn(missing_docs)]

pub mod app;
pub mod bench;
pub mod cli;
pub mod detp;
#[cfg(feature = "embree")]
pub mod embree;
pub mod error;
pub mod experiment;
pub mod geom;
pub mod grid;
pub mod lt;
pub mod output;
pub mod render;
pub mod report;
pub mod sample;
pub mod scene;
pub mod spec;
pub mod stats;
pub mod theory;
pub mod toml_text;
