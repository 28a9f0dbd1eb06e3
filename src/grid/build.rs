//! A finite grid built once over a list of spheres: compressed cell lists (one offsets array, one
//! entries array holding copies of the sphere records in cell order, so a cell's spheres are
//! contiguous in memory).
//!
//! Build: every sphere enumerates the cells its padded bounding box covers and keeps those its ball
//! really overlaps (exact closed sphere–box test, see [`GridFrame::pad`]); pairs are produced in
//! parallel at per-sphere offsets and then placed by a counting sort, so the layout is identical for
//! every thread count.

use glam::DVec3;
use rayon::prelude::*;

use super::{Cell, CellLists, GridFrame};
use crate::geom::{Aabb, Sphere};

/// Bytes one listed sphere occupies in the entries array.
pub const ENTRY_BYTES: u64 = std::mem::size_of::<Sphere>() as u64;

/// A finite regular grid with its cell lists.
#[derive(Debug)]
pub struct FiniteGrid {
    frame: GridFrame,
    offsets: Vec<u32>,
    entries: Vec<Sphere>,
    pad_magnitude: f64,
}

/// Placement of a finite grid that covers `bounds` (spheres included) with cells of width `a`, with a
/// cell corner at `anchor` (the eye), so that "eye at a cell corner" holds exactly.
pub fn frame_around(bounds: Aabb, a: f64, anchor: DVec3) -> GridFrame {
    let lo_cells = ((anchor - bounds.lo) / a).ceil();
    let hi_cells = ((bounds.hi - anchor) / a).ceil();
    let origin = anchor - lo_cells * a;
    let dims = (lo_cells + hi_cells).max(DVec3::ONE);
    GridFrame {
        origin,
        width: a,
        dims: Some([dims.x as i64, dims.y as i64, dims.z as i64]),
    }
}

/// Memory in bytes a grid of `cells` cells listing `listings` sphere copies needs at peak during the
/// build (offsets + entries + the temporary pair array).
pub fn estimated_bytes(cells: u64, listings: u64) -> u64 {
    cells * 4 + listings * (ENTRY_BYTES + 16)
}

impl FiniteGrid {
    /// Builds the cell lists of `spheres` in `frame` (a finite frame covering every sphere).
    pub fn build(frame: GridFrame, spheres: &[Sphere]) -> Self {
        let dims = frame.dims.expect("a finite grid needs dims");
        let pad_magnitude = grid_magnitude(&frame);
        let n_cells = (dims[0] * dims[1] * dims[2]) as usize;
        let linear = |c: Cell| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as u32;
        let (offsets, order) =
            cell_lists(&frame, pad_magnitude, spheres, n_cells, linear, |_, s| s);
        let entries = order.iter().map(|&s| spheres[s as usize]).collect();
        Self {
            frame,
            offsets,
            entries,
            pad_magnitude,
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Total number of listings (Σ over cells of the list length).
    pub fn listings(&self) -> usize {
        self.entries.len()
    }

    /// Bytes held by the cell lists.
    pub fn bytes(&self) -> u64 {
        self.offsets.len() as u64 * 4 + self.entries.len() as u64 * ENTRY_BYTES
    }

    /// The coordinate magnitude used for list padding.
    pub fn pad_magnitude(&self) -> f64 {
        self.pad_magnitude
    }
}

/// The magnitude of a finite frame's coordinates, from which listing pads are computed.
pub fn grid_magnitude(frame: &GridFrame) -> f64 {
    let dims = frame.dims.expect("a finite grid needs dims");
    let extent = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * frame.width;
    Aabb::new(frame.origin, frame.origin + extent).magnitude()
}

/// Compressed cell lists shared by both finite grids: `(offsets, order)` where the listings of the
/// cell stored at `slot(cell)` are `order[offsets[slot]..offsets[slot + 1]]`, each the
/// `payload(cell, sphere index)` of one listed sphere (the index itself for [`FiniteGrid`]).
///
/// Every sphere enumerates the cells its padded bounding box covers and keeps those its ball really
/// overlaps (exact closed sphere–box test, see [`GridFrame::pad`]). Pairs are produced in parallel
/// at per-sphere positions and placed by a counting sort, so the layout is the same for every
/// thread count (within a cell, sphere order).
pub fn cell_lists<P: Copy + Default + Send>(
    frame: &GridFrame,
    pad_magnitude: f64,
    spheres: &[Sphere],
    n_slots: usize,
    slot: impl Fn(Cell) -> u32 + Sync,
    payload: impl Fn(Cell, u32) -> P + Sync,
) -> (Vec<u32>, Vec<P>) {
    const CHUNK: usize = 1 << 14;
    let pairs: Vec<Vec<(u32, P)>> = spheres
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut out = Vec::with_capacity(chunk.len() * 2);
            for (k, s) in chunk.iter().enumerate() {
                let reach = s.r + frame.pad(pad_magnitude, s.r);
                let lo = frame.cell_of(s.c - DVec3::splat(reach));
                let hi = frame.cell_of(s.c + DVec3::splat(reach));
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            let cell = [x, y, z];
                            if frame.cell_box(cell).distance_squared(s.c) <= reach * reach {
                                let s = (ci * CHUNK + k) as u32;
                                out.push((slot(cell), payload(cell, s)));
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    let mut offsets = vec![0u32; n_slots + 1];
    for &(c, _) in pairs.iter().flatten() {
        offsets[c as usize + 1] += 1;
    }
    for i in 0..n_slots {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut order = vec![P::default(); offsets[n_slots] as usize];
    for &(c, s) in pairs.iter().flatten() {
        order[cursor[c as usize] as usize] = s;
        cursor[c as usize] += 1;
    }
    (offsets, order)
}

/// A read-only finite grid can be shared by threads: wrap a reference.
impl CellLists for &FiniteGrid {
    #[inline]
    fn frame(&self) -> &GridFrame {
        &self.frame
    }

    #[inline]
    fn pad_magnitude(&self, _cell: Cell) -> f64 {
        self.pad_magnitude
    }

    #[inline]
    fn list(&mut self, cell: Cell) -> &[Sphere] {
        let d = self.frame.dims.expect("finite");
        let i = ((cell[2] * d[1] + cell[1]) * d[0] + cell[0]) as usize;
        &self.entries[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}
