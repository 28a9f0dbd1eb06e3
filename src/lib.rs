//! raycost measures what ray-tracing acceleration structures really cost and holds every measurement
//! against closed-form theory.
//!
//! ```text
//! experiments/NAME.toml ─parse+validate─▶ Spec ─expand sweep─▶ [Point] ─run (rayon)─▶ [Row]
//!                                                  engines + theory (pure)     results/NAME/NAME.csv
//! ```
//! ## Layers
//!
//! Each module imports only modules of lower layers (`tests/layers.rs` reads this list and checks
//! every `crate::` path in `src/`, outside comments):
//!
//! 0. `error`: the error types (their variant decides the exit code)
//! 1. `toml_text`: TOML locations, located serde readers, key declarations
//! 2. `geom`: rays, spheres, boxes, robust intersection
//! 3. `sample`: keyed random streams, directions, lines, Poisson counts, radius laws
//! 4. `stats`: clustered means, histograms, goodness of fit, the verdict of a measurement against theory
//! 5. `theory`: closed forms (reads the radius laws of `sample`; imports no engine)
//! 6. `grid`: cells, the DDA walk, cell lists, the query grid
//! 7. `scene`: Poisson sphere processes. It sits above `grid` although the design card draws it
//!    beside it: the lazily generated infinite scene is drawn along the grid's own walk (cells,
//!    frames, the DDA), so that a ray and its scene meet the same cells with the same rounding
//! 8. `lt`: light-transport scenes (TOML and AFF scene files, the BVH, motion, the reference path tracer)
//! 9. `detp`, `embree`: the DETP engines (ray store, discs, sphere cache, disc index, photon tracing,
//!    photon map, incremental frames); the Embree baseline
//! 10. `output`: columns, rows, CSV, metadata, sinks, merge, progress, summary
//! 11. `spec`: a spec file read and expanded into points
//! 12. `experiment`: the kinds, their registry, plans and the one runner (its `reference` module
//!     writes the docs from the declarations; the runner does not import it)
//! 13. `bench`: `raycost bench`
//! 14. `render`, `report`, `crossover`: `raycost render` (images of a quasi-static run), `raycost
//!     report` (the HTML page of a results folder), `raycost crossover` (which method when, from the
//!     tables of three runs; it reads the `detp` kind's error sum)
//! 15. `reproduce`: `raycost reproduce` (reruns a result from its metadata through the runner or
//!     `crossover`, and compares its tables with `output::compare`)
//! 16. `cli`: clap definitions
//! 17. `app`: subcommand glue (`main.rs` sits on top)
#![warn(missing_docs)]

pub mod app;
pub mod bench;
pub mod cli;
pub mod crossover;
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
pub mod reproduce;
pub mod sample;
pub mod scene;
pub mod spec;
pub mod stats;
pub mod theory;
pub mod toml_text;
