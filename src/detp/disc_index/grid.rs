//! Discs in a regular grid: the project's [`GridFrame`], cell-list builder and 3D-DDA, with each
//! disc listed as its bounding ball (radius d plus the index pad) in every cell the ball meets.
//!
//! A segment is clipped to the (padded) grid box over t ∈ [0, t_end], then walked cell by cell from
//! its entry point; a disc listed in several cells is tested once per segment (mailbox).

use glam::DVec3;

use super::{clip, DiscIndex, LocalDiscs, Mailbox, Reach, SimdPath, Walk};
use crate::detp::disc::Discs;
use crate::detp::store::Segment;
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::build::{cell_lists, frame_around, grid_magnitude};
use crate::grid::{Cell, Dda, GridFrame};

/// A regular grid of disc lists.
#[derive(Debug)]
pub struct GridIndex {
    discs: LocalDiscs,
    reach: Reach,
    frame: GridFrame,
    dims: [i64; 3],
    /// Discs of cell slot s are `items[offsets[s]..offsets[s + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    path: SimdPath,
}

impl GridIndex {
    /// Builds a grid of cell width `cell_width` over the discs' bounds.
    ///
    /// # Panics
    /// On no discs, a non-positive width, or 2³¹ cells or more.
    pub fn build(discs: &Discs, cell_width: f64) -> Self {
        assert!(cell_width > 0.0, "cell width must be positive");
        let local = LocalDiscs::new(discs);
        let discs = &local.discs;
        let reach = Reach::new(discs);
        let b = reach.padded(&reach.bounds);
        let frame = frame_around(b, cell_width, b.lo);
        let dims = frame.dims.expect("finite frame");
        let cells = dims.iter().product::<i64>();
        assert!(cells < 1 << 31, "grid of {cells} cells is too large");
        let balls: Vec<Sphere> = discs
            .centers
            .iter()
            .enumerate()
            .map(|(i, &c)| Sphere {
                c,
                r: discs.radius + reach.pad,
                id: i as u64,
            })
            .collect();
        let slot = |c: Cell| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as u32;
        let (offsets, items) = cell_lists(
            &frame,
            grid_magnitude(&frame),
            &balls,
            cells as usize,
            slot,
            |_, s| s,
        );
        Self {
            discs: local,
            reach,
            frame,
            dims,
            offsets,
            items,
            path: SimdPath::detect(),
        }
    }

    /// The same grid with its kernels on `path` (tests force every path this CPU has).
    ///
    /// # Panics
    /// If this CPU cannot run `path`.
    pub fn with_path(mut self, path: SimdPath) -> Self {
        assert!(path.is_available(), "SIMD path {path:?} not available");
        self.path = path;
        self
    }

    /// The grid's frame.
    pub fn frame(&self) -> &GridFrame {
        &self.frame
    }

    fn grid_box(&self) -> Aabb {
        let ext = DVec3::new(
            self.dims[0] as f64,
            self.dims[1] as f64,
            self.dims[2] as f64,
        ) * self.frame.width;
        self.reach
            .padded(&Aabb::new(self.frame.origin, self.frame.origin + ext))
    }
}

impl DiscIndex for GridIndex {
    fn discs(&self) -> &LocalDiscs {
        &self.discs
    }

    fn reach(&self) -> &Reach {
        &self.reach
    }

    fn candidates(&self, seg: &Segment, mailbox: &mut Mailbox, out: &mut Vec<u32>) -> Walk {
        mailbox.clear();
        let v = seg.d();
        let len = v.length();
        let dir = v / len;
        let o = seg.o();
        // In units of distance along `dir`.
        let mut walk = Walk {
            box_tests: 1,
            ..Walk::default()
        };
        let Some((t0, t1)) = clip(o, dir, &self.grid_box(), 0.0, seg.t_end() * len) else {
            return walk;
        };
        let ray = Ray::new(o + dir * t0, dir);
        let stop = t1 - t0 + self.reach.pad;
        let (items, offsets, dims) = (&self.items, &self.offsets, self.dims);
        walk.steps = Dda::new(&self.frame, &ray).visit_until(stop, |cell| {
            let s = ((cell[2] * dims[1] + cell[1]) * dims[0] + cell[0]) as usize;
            mailbox.collect(&items[offsets[s] as usize..offsets[s + 1] as usize], out);
        });
        walk.entered = walk.steps;
        walk
    }

    fn path(&self) -> SimdPath {
        self.path
    }

    fn bytes(&self) -> usize {
        self.offsets.len() * 4 + self.items.len() * 4 + self.discs.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{adversarial_segments, scene};
    use super::*;

    /// The first version's walk, kept as the oracle of the counters: the `Dda` iterator, one
    /// cell at a time, the mailbox's `insert` per listing.
    fn reference(g: &GridIndex, seg: &Segment, mailbox: &mut Mailbox) -> (Walk, Vec<u32>) {
        mailbox.clear();
        let v = seg.d();
        let len = v.length();
        let dir = v / len;
        let o = seg.o();
        let mut walk = Walk {
            box_tests: 1,
            ..Walk::default()
        };
        let mut out = Vec::new();
        if let Some((t0, t1)) = clip(o, dir, &g.grid_box(), 0.0, seg.t_end() * len) {
            let ray = Ray::new(o + dir * t0, dir);
            let stop = t1 - t0 + g.reach.pad;
            for (cell, t_enter, _) in Dda::new(&g.frame, &ray) {
                if t_enter > stop {
                    break;
                }
                walk.entered += 1;
                walk.steps += 1;
                let s = ((cell[2] * g.dims[1] + cell[1]) * g.dims[0] + cell[0]) as usize;
                for &i in &g.items[g.offsets[s] as usize..g.offsets[s + 1] as usize] {
                    if mailbox.insert(i) {
                        out.push(i);
                    }
                }
            }
        }
        out.sort_unstable();
        (walk, out)
    }

    #[test]
    fn every_path_walks_as_the_reference_walk_does() {
        let (store, discs) = scene(3_000, 2_000, 0.03, 8);
        for width in [0.03, 0.06, 0.5, 5.0] {
            let base = GridIndex::build(&discs, width);
            let segs: Vec<Segment> = store
                .segments
                .iter()
                .copied()
                .chain(adversarial_segments(&base.discs.discs, 12))
                .collect();
            let mut mb = Mailbox::new(discs.len());
            let want: Vec<(Walk, Vec<u32>)> =
                segs.iter().map(|s| reference(&base, s, &mut mb)).collect();
            for path in SimdPath::all_available() {
                let g = GridIndex::build(&discs, width).with_path(path);
                for (k, (s, w)) in segs.iter().zip(&want).enumerate() {
                    let mut got = Vec::new();
                    let walk = g.candidates(s, &mut mb, &mut got);
                    got.sort_unstable();
                    assert_eq!(
                        (walk, got),
                        w.clone(),
                        "{path:?}, width {width}, segment {k}"
                    );
                }
            }
        }
    }
}
