//! Experiment kinds: each is one module implementing [`kind::Kind`] and one line in
//! [`registry::KINDS`]. A [`plan::Plan`] is a spec validated by its kind; the [`runner`] runs it and
//! knows kinds only through [`kind::DynKind`].

pub mod detp;
pub mod grid;
pub mod inputs;
pub mod kind;
pub mod lines_in_sphere;
pub mod machine;
pub mod plan;
pub mod quasi_static;
pub mod reference;
pub mod registry;
pub mod runner;

pub use crate::output::row::{Row, Value};
