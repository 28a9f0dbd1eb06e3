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
        let n_cells = (dims[0] * dims[1] * dims[2]) as usize;
        let grid_box = Aabb::new(
            frame.origin,
            frame.origin + DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * frame.width,
        );
        let pad_magnitude = grid_box.magnitude();
        let linear = |c: Cell| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize;

        // Overlapped cells of one sphere, in a fixed order.
        let overlaps = |s: &Sphere, out: &mut Vec<u32>| {
            let reach = s.r + frame.pad(pad_magnitude, s.r);
            let lo = frame.cell_of(s.c - DVec3::splat(reach));
            let hi = frame.cell_of(s.c + DVec3::splat(reach));
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        let cell = [i, j, k];
                        if frame.cell_box(cell).distance_squared(s.c) <= reach * reach {
                            out.push(linear(cell) as u32);
                        }
                    }
                }
            }
        };

        // Pairs (cell, sphere) in sphere order, produced in parallel chunks.
        const CHUNK: usize = 1 << 14;
        let pairs: Vec<Vec<(u32, u32)>> = spheres
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(ci, chunk)| {
                let mut out = Vec::with_capacity(chunk.len() * 2);
                let mut cells = Vec::with_capacity(27);
                for (k, s) in chunk.iter().enumerate() {
                    cells.clear();
                    overlaps(s, &mut cells);
                    let idx = (ci * CHUNK + k) as u32;
                    out.extend(cells.iter().map(|&c| (c, idx)));
                }
                out
            })
            .collect();

        // Counting sort by cell; within a cell, sphere order.
        let mut offsets = vec![0u32; n_cells + 1];
        for &(c, _) in pairs.iter().flatten() {
            offsets[c as usize + 1] += 1;
        }
        for i in 0..n_cells {
            offsets[i + 1] += offsets[i];
        }
        let total = offsets[n_cells] as usize;
        let mut cursor = offsets.clone();
        let placeholder = Sphere {
            c: DVec3::ZERO,
            r: 0.0,
            id: u64::MAX,
        };
        let mut entries = vec![placeholder; total];
        for &(c, s) in pairs.iter().flatten() {
            let slot = &mut cursor[c as usize];
            entries[*slot as usize] = spheres[s as usize];
            *slot += 1;
        }
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

impl CellLists for FiniteGrid {
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
