//! Experiment kinds: each is one module implementing [`kind::Kind`] and one line in the registry
//! below ([`KINDS`]). A [`plan::Plan`] is a spec validated by its kind; the [`runner`] runs it and
//! knows kinds only through [`kind::DynKind`].

pub mod inputs;
pub mod kind;
pub mod machine;
pub mod photon_batches;
pub mod photon_shards;
pub mod plan;
pub mod reference;
pub mod registry;
pub mod runner;

// The registry: one line per kind module (the module and its kinds).
crate::kinds! {
    grid => [grid::Grid<grid::Study>, grid::Grid<grid::Scaling>, grid::Grid<grid::CostModel>],
    lines_in_sphere => [lines_in_sphere::LinesInSphereKind],
    detp => [detp::DetpKind],
    quasi_static => [quasi_static::QuasiStaticKind],
}

pub use crate::output::row::{Row, Value};
