//! Closed-form theory: pure functions (no I/O, no randomness, no `Result`) that give the value each
//! measurement is held against.
//!
//! - [`grid`]: the regular grid over Poisson spheres, Márton & Szirmay-Kalos, "average-case
//!   complexity of the regular grid" (restated in `docs/theory.md` §1): eqs. (3)–(9),
//!   Results 3.1 and 3.2, plus the cell-step counts and sharper test-count predictors that the paper
//!   does not state (derived in that module's doc comments).
//!
//! Note on layering: the theory reads the radius laws of [`crate::sample::radius`] (a plain data type
//! with its own quadrature and sampler, below both), so that theory and scene integrate exactly the
//! same truncated law; the theory imports no engine.

pub mod detp;
pub mod grid;
