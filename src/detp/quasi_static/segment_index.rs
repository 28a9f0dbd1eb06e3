//! An index over stored segments: which segments pass near a ball? A quasi-static frame asks it for
//! the segments that meet a dynamic object's bounding sphere at its old and at its new pose, so that
//! only those photons are re-traced — a search, never a re-trace of everything.
//!
//! A regular grid over the scene's box (the project's [`GridFrame`] and [`Dda`]): each segment is
//! listed in every cell its stored line piece `[0, t_end]` pierces (clipped to the box). A query
//! gathers the cells that overlap the ball's box, and tests each listed, live segment once against
//! the ball (segment–sphere distance).
//!
//! # Why the search is conservative
//! The query ball is padded by `pad` (see [`SegmentIndex::pad`]): 10⁻⁶ of the box's coordinate
//! scale. It covers (a) the difference between the photon's f64 path and its stored f32 direction
//! and length (relative error ≤ 2⁻²³ over lengths ≤ the box diagonal), and (b) the few-ulp error of
//! the DDA's cell boundaries. So a segment whose true path touches the ball pierces a cell that
//! overlaps the padded ball's box, and passes the padded distance test.

use glam::DVec3;

use crate::detp::store::Segment;
use crate::geom::{Aabb, Ray};
use crate::grid::{Dda, GridFrame};

/// What a search cost: exact counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SearchStats {
    /// Cells whose lists were read.
    pub cells: u64,
    /// Listings read (a segment listed in several of the cells counts each time).
    pub listings: u64,
    /// Distinct live segments tested against the ball.
    pub tested: u64,
}

impl SearchStats {
    /// Adds `o`'s counts.
    pub fn add(&mut self, o: &SearchStats) {
        self.cells += o.cells;
        self.listings += o.listings;
        self.tested += o.tested;
    }
}

/// Segments listed per grid cell.
#[derive(Clone, Debug)]
pub struct SegmentIndex {
    frame: GridFrame,
    dims: [i64; 3],
    bounds: Aabb,
    cells: Vec<Vec<u32>>,
    /// Segments whose piece is not wholly inside the box (an origin outside it, or a piece running
    /// past it): a query whose ball reaches outside the box tests all of them, so an object that
    /// pokes out of the scene's box is still searched exactly.
    outer: Vec<u32>,
    pad: f64,
}

impl SegmentIndex {
    /// An empty index over `bounds` with about `cells` cells (cubic cells, at least 1 per axis).
    pub fn new(bounds: Aabb, cells: usize) -> Self {
        // Relative to the box's own scale, not to its distance from the origin (a box translated
        // far away got a pad as large as the translation allowed, and every cell every segment).
        let p = crate::lt::precision::Precision::of(&bounds);
        let pad = (1e-6 * (p.scale() + p.size)).max(p.rounding());
        let lo = bounds.lo - DVec3::splat(pad);
        let hi = bounds.hi + DVec3::splat(pad);
        let ext = hi - lo;
        let width = (ext.x * ext.y * ext.z / cells.max(1) as f64)
            .cbrt()
            .max(ext.max_element() / 1024.0);
        let dims = [
            (ext.x / width).ceil().max(1.0) as i64,
            (ext.y / width).ceil().max(1.0) as i64,
            (ext.z / width).ceil().max(1.0) as i64,
        ];
        let frame = GridFrame {
            origin: lo,
            width,
            dims: Some(dims),
        };
        let hi = lo + DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * width;
        Self {
            frame,
            dims,
            bounds: Aabb::new(lo, hi),
            cells: vec![Vec::new(); (dims[0] * dims[1] * dims[2]) as usize],
            outer: Vec::new(),
            pad,
        }
    }

    /// The padding of every query ball.
    pub fn pad(&self) -> f64 {
        self.pad
    }

    fn slot(&self, c: [i64; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// Lists segment `id` in the cells its piece `[0, t_end]` pierces inside the box.
    pub fn insert(&mut self, id: u32, s: &Segment) {
        let (o, d) = (s.o(), s.d());
        let t_end = s.t_end() * (1.0 + 1e-6);
        let Some((t0, t1)) = crate::detp::disc_index::clip(o, d, &self.bounds, 0.0, t_end) else {
            self.outer.push(id);
            return;
        };
        if t0 > 0.0 || t1 < t_end {
            self.outer.push(id);
        }
        let start = o + d * t0;
        let ray = Ray::new(start, d);
        let len = t1 - t0;
        for (cell, t_in, _) in Dda::new(&self.frame, &ray) {
            if t_in > len + self.pad {
                break;
            }
            if self.frame.contains(cell) {
                let k = self.slot(cell);
                self.cells[k].push(id);
            }
        }
    }

    /// Removes every listing (keeps the cells' capacity).
    pub fn clear(&mut self) {
        self.cells.iter_mut().for_each(Vec::clear);
        self.outer.clear();
    }

    /// Listings held.
    pub fn listings(&self) -> usize {
        self.cells.iter().map(Vec::len).sum()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.cells.iter().map(|c| c.capacity() * 4 + 24).sum()
    }

    /// The live segments (`live(id)`) whose piece meets the ball (c, r) padded by [`Self::pad`],
    /// sorted, each once; `seen` is scratch of at least the largest id + 1 entries, all false, and
    /// is left all false.
    pub fn query(
        &self,
        segments: &[Segment],
        c: DVec3,
        r: f64,
        live: &dyn Fn(u32) -> bool,
        seen: &mut Vec<bool>,
    ) -> (Vec<u32>, SearchStats) {
        if seen.len() < segments.len() {
            seen.resize(segments.len(), false);
        }
        let r = r + self.pad;
        let lo = self.frame.cell_of(c - DVec3::splat(r));
        let hi = self.frame.cell_of(c + DVec3::splat(r));
        let mut st = SearchStats::default();
        let mut hits = Vec::new();
        let mut touched = Vec::new();
        // Tests each live listing once (the `seen` mark), whichever list it comes from.
        let mut visit = |list: &[u32], st: &mut SearchStats| {
            for &id in list {
                st.listings += 1;
                let i = id as usize;
                if seen[i] || !live(id) {
                    continue;
                }
                seen[i] = true;
                touched.push(id);
                st.tested += 1;
                if meets_ball(&segments[i], c, r, self.pad) {
                    hits.push(id);
                }
            }
        };
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    st.cells += 1;
                    visit(&self.cells[self.slot([x, y, z])], &mut st);
                }
            }
        }
        let inside = (c - DVec3::splat(r)).cmpge(self.bounds.lo).all()
            && (c + DVec3::splat(r)).cmple(self.bounds.hi).all();
        if !inside {
            visit(&self.outer, &mut st);
        }
        for id in touched {
            seen[id as usize] = false;
        }
        hits.sort_unstable();
        (hits, st)
    }
}

/// Does the stored piece `[0, t_end]` of `s` (lengthened by `pad`) come within `r` of `c`?
pub fn meets_ball(s: &Segment, c: DVec3, r: f64, pad: f64) -> bool {
    let (o, d) = (s.o(), s.d());
    let t_end = if s.t_end.is_finite() {
        s.t_end() * (1.0 + 1e-6) + pad
    } else {
        f64::INFINITY
    };
    let t = (c - o).dot(d).clamp(0.0, t_end);
    (o + d * t).distance_squared(c) <= r * r
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;
    use crate::detp::store::SegmentStore;
    use crate::sample::rng::stream;

    #[test]
    fn finds_exactly_what_a_scan_finds() {
        let mut rng = stream(&[77]);
        let store = SegmentStore::test_lines(&mut rng, 4000);
        // A box smaller than the lines' ball, so pieces run out of it.
        let b = Aabb::new(DVec3::splat(-0.7), DVec3::splat(0.7));
        let mut idx = SegmentIndex::new(b, 512);
        for (i, s) in store.segments.iter().enumerate() {
            idx.insert(i as u32, s);
        }
        let mut seen = Vec::new();
        for k in 0..80 {
            // The last 30 balls reach out of the index's box (an object poking out of the scene).
            let span = if k < 50 { 0.8 } else { 1.4 };
            let c = DVec3::new(
                rng.gen_range(-span..span),
                rng.gen_range(-span..span),
                rng.gen_range(-span..span),
            );
            let r = rng.gen_range(0.01..0.3);
            let live = |id: u32| id % 7 != 3;
            let (got, st) = idx.query(&store.segments, c, r, &live, &mut seen);
            let want: Vec<u32> = (0..store.len() as u32)
                .filter(|&i| {
                    live(i) && meets_ball(&store.segments[i as usize], c, r + idx.pad(), idx.pad())
                })
                .collect();
            assert_eq!(got, want);
            assert!(st.tested >= got.len() as u64 && st.cells > 0);
            assert!(seen.iter().all(|&s| !s));
        }
    }
}
