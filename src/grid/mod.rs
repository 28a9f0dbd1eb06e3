//! One regular grid of cubic cells and one 3D-DDA walker, reused by every engine that indexes space.
//!
//! The grid does not know what it indexes: a [`CellLists`] source hands out the spheres listed in a
//! cell (a finite CSR grid built once, or an infinite scene generated lazily per cell), and
//! [`trace::trace`] walks the cells a ray pierces, in order, counting what the paper counts.

pub mod build;
pub mod dda;
pub mod fast;
pub mod frame;
pub mod huge;
pub mod mailbox;
pub mod trace;

pub use build::FiniteGrid;
pub use dda::Dda;
pub use frame::GridFrame;
pub use trace::{brute_force, exit_distance, trace, Hit, TraceCounts};

use crate::geom::Sphere;

/// Integer cell coordinates (unbounded for infinite grids).
pub type Cell = [i64; 3];

/// A source of cell lists: the spheres whose closed ball overlaps each cell.
pub trait CellLists {
    /// The grid's placement and extent.
    fn frame(&self) -> &GridFrame;
    /// Spheres listed in `cell` (which lies inside the frame).
    fn list(&mut self, cell: Cell) -> &[Sphere];
    /// The coordinate magnitude from which the listing pad of `cell` was computed
    /// (`GridFrame::pad(magnitude, r)`): lets the tracer tell, exactly as the lists were built,
    /// that a sphere lies in this cell only.
    fn pad_magnitude(&self, cell: Cell) -> f64;
}
