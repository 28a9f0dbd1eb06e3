//! Where the grid sits: origin, cell width, and (for finite grids) how many cells per axis.

use glam::DVec3;

use super::Cell;
use crate::geom::{float::MACHINE_EPSILON, Aabb};

/// Placement of a regular grid: cell `(i, j, k)` is `origin + a·[i, i+1] × [j, j+1] × [k, k+1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFrame {
    /// Corner of cell (0, 0, 0).
    pub origin: DVec3,
    /// Cell width a, > 0.
    pub width: f64,
    /// Cells per axis for a finite grid (cells `0..dims`), `None` for an unbounded one.
    pub dims: Option<[i64; 3]>,
}

impl GridFrame {
    /// The closed box of `cell`.
    #[inline]
    pub fn cell_box(&self, cell: Cell) -> Aabb {
        let lo =
            self.origin + DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) * self.width;
        Aabb::new(lo, lo + DVec3::splat(self.width))
    }

    /// The cell holding `p` (clamped into a finite grid).
    #[inline]
    pub fn cell_of(&self, p: DVec3) -> Cell {
        let q = ((p - self.origin) / self.width).floor();
        let mut c = [q.x as i64, q.y as i64, q.z as i64];
        if let Some(d) = self.dims {
            for i in 0..3 {
                c[i] = c[i].clamp(0, d[i] - 1);
            }
        }
        c
    }

    /// Is `cell` inside the grid?
    #[inline]
    pub fn contains(&self, cell: Cell) -> bool {
        match self.dims {
            None => true,
            Some(d) => (0..3).all(|i| cell[i] >= 0 && cell[i] < d[i]),
        }
    }

    /// Padding added to a sphere's radius when listing it in cells.
    ///
    /// Why: the tracer stops in the first cell whose exit distance is at least the best hit found.
    /// Both that exit distance and the hit distance carry rounding errors of a few ulps of the
    /// coordinates involved, so a sphere whose true first hit lies just beyond a cell face could be
    /// passed over if it were listed only in the next cell. Listing every sphere also in the cells
    /// within `pad` of it (pad = 64ε × the magnitude of the coordinates) makes the stop rule safe; it
    /// adds about ρ·area·pad ≈ 10⁻¹⁴ listings per cell, invisible in any count.
    #[inline]
    pub fn pad(&self, magnitude: f64, radius: f64) -> f64 {
        64.0 * MACHINE_EPSILON * (magnitude + radius + self.width)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_and_boxes_agree() {
        let f = GridFrame {
            origin: DVec3::new(-1.0, -1.0, -1.0),
            width: 0.5,
            dims: Some([4, 4, 4]),
        };
        let c = f.cell_of(DVec3::new(0.1, -0.6, 0.99));
        assert_eq!(c, [2, 0, 3]);
        let b = f.cell_box(c);
        assert_eq!(b.lo, DVec3::new(0.0, -1.0, 0.5));
        // Points on the max face clamp into the last cell.
        assert_eq!(f.cell_of(DVec3::splat(1.0)), [3, 3, 3]);
        assert!(!f.contains([4, 0, 0]) && f.contains([3, 3, 3]));
    }
}
