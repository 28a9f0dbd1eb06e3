//! Amanatides–Woo 3D DDA: the cells a ray pierces, in order, with the parameter interval of each.
//!
//! Robustness choices (after pbrt-v4's `DDAMajorantIterator`): the start cell is clamped into a finite
//! grid; −0.0 direction components were already turned into +0.0 by [`Ray::new`]; zero components
//! never step. The next boundary distance is recomputed from the absolute boundary coordinate
//! `origin + k·a` at every step instead of accumulating `t += Δt`, so the error stays a few ulps after
//! millions of steps. A cell may have zero length (a ray through an edge or a corner visits it for an
//! instant); `t_exit ≥ t_enter` always holds.

use super::{Cell, GridFrame};
use crate::geom::Ray;

/// Iterator over `(cell, t_enter, t_exit)` along a ray, starting at `t = 0`.
#[derive(Clone, Debug)]
pub struct Dda {
    cell: Cell,
    step: [i64; 3],
    inv_d: [f64; 3],
    o: [f64; 3],
    g0: [f64; 3],
    a: f64,
    t_next: [f64; 3],
    t_enter: f64,
    dims: Option<[i64; 3]>,
    done: bool,
    /// The axis of the latest step (towards the cell the next call returns).
    axis: usize,
}

impl Dda {
    /// Starts at the cell holding the ray origin. For a finite grid the origin must lie inside the
    /// grid's box (it is clamped to the nearest cell if it sits on the boundary).
    pub fn new(frame: &GridFrame, ray: &Ray) -> Self {
        let d = ray.d.to_array();
        let mut dda = Self {
            cell: start_cell(frame, ray),
            step: [0; 3],
            inv_d: [0.0; 3],
            o: ray.o.to_array(),
            g0: frame.origin.to_array(),
            a: frame.width,
            t_next: [f64::INFINITY; 3],
            t_enter: 0.0,
            dims: frame.dims,
            done: false,
            axis: 0,
        };
        for (i, &di) in d.iter().enumerate() {
            if di > 0.0 {
                dda.step[i] = 1;
            } else if di < 0.0 {
                dda.step[i] = -1;
            }
            if di != 0.0 {
                dda.inv_d[i] = 1.0 / di;
            }
            dda.t_next[i] = dda.boundary_t(i);
        }
        dda
    }

    /// The axis and sign of the step the latest [`Iterator::next`] took: how the walk enters the
    /// cell the next call returns (the infinite scene draws the slab that step adds).
    #[inline(always)]
    pub fn last_step(&self) -> (usize, i64) {
        (self.axis, self.step[self.axis])
    }

    /// Distance to the face through which the ray leaves the current cell along axis `i`.
    #[inline]
    fn boundary_t(&self, i: usize) -> f64 {
        match self.step[i] {
            0 => f64::INFINITY,
            s => {
                let k = if s > 0 {
                    self.cell[i] + 1
                } else {
                    self.cell[i]
                };
                let b = self.g0[i] + k as f64 * self.a;
                // Rounding can put the boundary a hair behind the origin: clamp to the entry.
                later((b - self.o[i]) * self.inv_d[i], self.t_enter)
            }
        }
    }
}

impl Dda {
    /// Calls `f` with every cell [`Iterator::next`] would return whose entry distance is at most
    /// `stop`, in order, and returns how many: the iterator's walk with `take_while(t_enter ≤
    /// stop)`, as one tight loop (no per-step `Option` of a tuple, no `done` flag; the disc index's
    /// walk spent 61 instructions a step in the iterator). The same comparisons and boundary
    /// formula, so the same cells (tested against the iterator).
    #[inline(always)]
    pub fn visit_until(mut self, stop: f64, mut f: impl FnMut(Cell)) -> u64 {
        let mut n = 0;
        loop {
            if self.t_enter > stop {
                return n;
            }
            f(self.cell);
            n += 1;
            let t = &self.t_next;
            let axis = if t[0] <= t[1] && t[0] <= t[2] {
                0
            } else if t[1] <= t[2] {
                1
            } else {
                2
            };
            let t_exit = later(t[axis], self.t_enter);
            if t_exit == f64::INFINITY {
                return n;
            }
            self.cell[axis] += self.step[axis];
            if let Some(d) = self.dims {
                if self.cell[axis] < 0 || self.cell[axis] >= d[axis] {
                    return n;
                }
            }
            self.axis = axis;
            self.t_enter = t_exit;
            self.t_next[axis] = self.boundary_t(axis);
        }
    }
}

/// The larger of two distances (never NaN here): `f64::max` without its NaN handling, which costs
/// three extra instructions on every step of every walk.
#[inline(always)]
fn later(t: f64, t_enter: f64) -> f64 {
    if t > t_enter {
        t
    } else {
        t_enter
    }
}

/// The cell a ray starts in: the one it enters. An origin exactly on a face, moving towards −axis,
/// starts in the lower cell; otherwise an eye at a cell corner would visit up to three cells for zero
/// length and count steps the geometry does not have (the floor effect of docs/theory.md's E[N_S] for a
/// corner eye assumes crossings at t = k·a/|d_x|, k ≥ 1). Clamped into a finite grid.
#[inline(always)]
pub fn start_cell(frame: &GridFrame, ray: &Ray) -> Cell {
    let d = ray.d.to_array();
    let q = ((ray.o - frame.origin) / frame.width).to_array();
    let mut cell = [0i64; 3];
    for i in 0..3 {
        let f = q[i].floor();
        cell[i] = f as i64 - i64::from(f == q[i] && d[i] < 0.0);
    }
    if let Some(dims) = frame.dims {
        for i in 0..3 {
            cell[i] = cell[i].clamp(0, dims[i] - 1);
        }
    }
    cell
}

impl Iterator for Dda {
    type Item = (Cell, f64, f64);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        // The axis whose face comes first (ties go to the lowest axis; the other axes follow with
        // zero-length cells).
        let t = &self.t_next;
        let axis = if t[0] <= t[1] && t[0] <= t[2] {
            0
        } else if t[1] <= t[2] {
            1
        } else {
            2
        };
        let t_exit = later(t[axis], self.t_enter);
        let out = (self.cell, self.t_enter, t_exit);
        if t_exit == f64::INFINITY {
            self.done = true;
            return Some(out);
        }
        self.cell[axis] += self.step[axis];
        self.axis = axis;
        self.t_enter = t_exit;
        if let Some(d) = self.dims {
            if self.cell[axis] < 0 || self.cell[axis] >= d[axis] {
                self.done = true;
                return Some(out);
            }
        }
        self.t_next[axis] = self.boundary_t(axis);
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn frame() -> GridFrame {
        GridFrame {
            origin: DVec3::ZERO,
            width: 1.0,
            dims: Some([4, 4, 4]),
        }
    }

    #[test]
    fn axis_parallel_ray_visits_a_row() {
        let ray = Ray::new(DVec3::new(0.5, 0.5, 0.5), DVec3::X);
        let cells: Vec<_> = Dda::new(&frame(), &ray).collect();
        assert_eq!(
            cells.iter().map(|c| c.0).collect::<Vec<_>>(),
            vec![[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]
        );
        assert_eq!(cells[1].1, 0.5);
        assert_eq!(cells[1].2, 1.5);
    }

    #[test]
    fn eye_on_a_corner_starts_in_the_cell_it_enters() {
        let f = GridFrame {
            origin: DVec3::ZERO,
            width: 1.0,
            dims: None,
        };
        let ray = Ray::new(DVec3::ZERO, DVec3::new(-1.0, -2.0, 3.0).normalize());
        let first = Dda::new(&f, &ray).next().expect("one cell");
        assert_eq!(first.0, [-1, -1, 0]);
        assert!(first.2 > 0.0, "the first cell has positive length");
    }

    #[test]
    fn negative_zero_direction_never_steps() {
        let ray = Ray::new(DVec3::new(0.5, 0.5, 0.5), DVec3::new(-0.0, 1.0, -0.0));
        let cells: Vec<_> = Dda::new(&frame(), &ray).map(|c| c.0).collect();
        assert_eq!(cells, vec![[0, 0, 0], [0, 1, 0], [0, 2, 0], [0, 3, 0]]);
    }

    #[test]
    fn diagonal_through_corners_visits_zero_length_cells_and_intervals_chain() {
        let ray = Ray::new(DVec3::ZERO, DVec3::ONE.normalize());
        let cells: Vec<_> = Dda::new(&frame(), &ray).collect();
        for w in cells.windows(2) {
            assert_eq!(w[0].2, w[1].1, "intervals must chain");
            let manhattan: i64 = (0..3).map(|i| (w[1].0[i] - w[0].0[i]).abs()).sum();
            assert_eq!(manhattan, 1, "face-adjacent steps only");
        }
        assert_eq!(cells.last().map(|c| c.0), Some([3, 3, 3]));
    }

    #[test]
    fn visit_until_visits_the_iterators_cells_up_to_the_stop() {
        use crate::sample::{directions::uniform_direction, rng::stream};
        let f = GridFrame {
            origin: DVec3::new(-1.0, -1.0, -1.0),
            width: 0.25,
            dims: Some([8, 8, 8]),
        };
        let mut rng = stream(&[2]);
        for k in 0..3000 {
            let o = DVec3::new(0.1, -0.3, 0.2) * (k % 4) as f64;
            let d = match k % 7 {
                0 => DVec3::new(0.0, 1.0, 0.0),
                1 => DVec3::new(1.0, 1.0, 0.0).normalize(),
                _ => uniform_direction(&mut rng),
            };
            let ray = Ray::new(o, d);
            let stop = [0.0, 0.3, 1.7, f64::INFINITY][k % 4];
            let want: Vec<Cell> = Dda::new(&f, &ray)
                .take_while(|c| c.1 <= stop)
                .map(|c| c.0)
                .collect();
            let mut got = Vec::new();
            let n = Dda::new(&f, &ray).visit_until(stop, |c| got.push(c));
            assert_eq!(got, want, "ray {k}");
            assert_eq!(n, want.len() as u64);
        }
    }

    #[test]
    fn visited_cells_cover_the_ray_in_an_unbounded_grid() {
        use crate::sample::{directions::uniform_direction, rng::stream};
        let f = GridFrame {
            origin: DVec3::new(0.3, -0.2, 0.1),
            width: 0.7,
            dims: None,
        };
        let mut rng = stream(&[1]);
        for _ in 0..2000 {
            let ray = Ray::new(DVec3::new(0.05, 0.2, -0.4), uniform_direction(&mut rng));
            for (cell, t0, t1) in Dda::new(&f, &ray).take(50) {
                assert!(t1 >= t0);
                let b = f.cell_box(cell);
                let mid = ray.at(0.5 * (t0 + t1));
                assert!(b.distance_squared(mid) < 1e-20, "midpoint outside its cell");
            }
        }
    }
}
