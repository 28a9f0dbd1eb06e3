//! Disc indexing (the paper's alternative to the sphere cache): the discs go into a spatial index
//! once, and every segment traverses it, adding (`sign = 1`) or removing (`sign = −1`) its power to
//! the discs it crosses. Removing old segments and adding new ones is how quasi-static frames are
//! updated; sums are integers, so the result equals accumulating the surviving segments directly.
//!
//! Two indexes share the traversal driver here: a regular grid ([`grid::GridIndex`], reusing the
//! project's frame, cell-list builder and 3D-DDA) and an octree ([`octree::Octree`], the hierarchy
//! the paper's cost model assumes). Each hands the driver the candidate discs of a segment, each
//! disc once (mailboxed); the driver decides every pair with [`Discs::crossed_by`].
//!
//! # Why the culling is conservative
//! Let `B` be the box around all discs ([`Discs::bounds_all`], which holds every disc with a pad),
//! `M = min(|B|_∞, 4·diag(B)) + diag(B)` its scale (`|B|_∞ + diag(B)` whenever B holds the origin)
//! and `P = max(2⁻³⁰·M, 2⁻⁴⁰·|B|_∞)` the *index pad*: every box the indexes test (cells, octree
//! nodes, the clip box) is enlarged by at least `P`. For a segment whose origin lies within
//! `R = 2¹⁰·M` of B's centre, every quantity a traversal computes (a slab parameter, a clipped
//! entry point, a DDA boundary) is a handful of f64 operations on magnitudes ≤ |B|_∞ + 4R, so it is
//! off by at most ~100ε·(|B|_∞ + 4R) < 2⁻⁴⁶·|B|_∞ + 2⁻³³·M, four times below P. (With
//! `M = |B|_∞ + diag`, as before, a scene translated far from the origin got pads proportional to
//! its translation — 93 mm for a Cornell box at 10¹¹ mm — and every cell listed every disc.) A
//! crossing that [`crate::detp::disc::crosses`] accepts happens at a point x of the segment inside
//! the disc, hence inside B and inside the box of every cell or node that lists the disc and
//! contains x; the computed traversal passes within 2⁻³³·M of x, so it tests that box, enlarged by
//! P, and reaches the disc. Segments starting farther than R (none in the scenes studied: photons
//! start on the scene's surfaces) are tested against every disc, which is trivially conservative.

pub mod cross;
pub mod grid;
pub mod octree;
pub mod path;
pub mod slab;

use glam::DVec3;
use rayon::prelude::*;

use super::disc::Discs;
use super::fixed::Acc;
use super::nearest::{Kept, Nearest};
use super::order::{permutation, Order};
use super::store::{Segment, SegmentStore};
use super::tally::{Power, Tally};
use crate::geom::Aabb;

pub use grid::GridIndex;
pub use octree::Octree;
pub use path::SimdPath;

/// What one segment's walk through an index cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Walk {
    /// Grid cells or octree nodes entered.
    pub entered: u64,
    /// Segment–box slab tests ([`clip`]): one per octree node tested, one per segment clipped to
    /// the grid's box.
    pub box_tests: u64,
    /// 3D-DDA steps (grid cells stepped through; 0 in an octree, whose steps are its box tests).
    pub steps: u64,
}

/// Counters of one traversal run, exact integers (the same for any thread count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IndexStats {
    /// Grid cells or octree nodes the segments entered (far-origin segments enter none).
    pub nodes_visited: u64,
    /// Segment–box slab tests (octree nodes tested, or segments clipped to the grid's box).
    pub box_tests: u64,
    /// 3D-DDA steps through grid cells (0 for an octree).
    pub dda_steps: u64,
    /// Segment–disc tests, each distinct (segment, disc) pair once.
    pub ray_disc_tests: u64,
    /// Segments that reached the index: entered one of its cells or nodes, or (an origin beyond
    /// its reach) were tested against every disc. Theorem 2's proof charges every ray of the
    /// scene as if it reached the index; this is the share that does.
    pub segments_reaching: u64,
}

impl IndexStats {
    /// Adds `o`'s counts.
    pub fn merge(mut self, o: Self) -> Self {
        self.nodes_visited += o.nodes_visited;
        self.box_tests += o.box_tests;
        self.dda_steps += o.dda_steps;
        self.ray_disc_tests += o.ray_disc_tests;
        self.segments_reaching += o.segments_reaching;
        self
    }

    /// The traversal's counted steps, weight 1 each: box tests plus DDA steps (what Theorem 1
    /// charges beside the ray–disc tests; `docs/detp-costs.md`).
    pub fn traversal(&self) -> u64 {
        self.box_tests + self.dda_steps
    }

    /// Counted cost, weight 1 per box test, DDA step and ray–disc test.
    pub fn counted_cost(&self) -> u64 {
        self.traversal() + self.ray_disc_tests
    }
}

/// Which disc index a spec chose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IndexKind {
    /// A regular grid of this cell width.
    Grid(f64),
    /// An octree with leaves of at most this many discs (and sides ≥ 2d).
    Octree(usize),
}

/// A spatial index over discs that segments traverse.
pub trait DiscIndex: Sync {
    /// The indexed discs, in the index's own order.
    fn discs(&self) -> &LocalDiscs;

    /// The index's reach (see the module doc): pad, centre and the origin radius R.
    fn reach(&self) -> &Reach;

    /// Appends to `out` every candidate disc of `seg` (each once, thanks to `mailbox`, which is
    /// started afresh here) and returns what the walk cost. Only for segments within the reach.
    fn candidates(&self, seg: &Segment, mailbox: &mut Mailbox, out: &mut Vec<u32>) -> Walk;

    /// Bytes held by the index (discs included).
    fn bytes(&self) -> usize;

    /// The SIMD path of the index's kernels (all paths give the same answers and counts).
    fn path(&self) -> SimdPath;

    /// Adds `sign ×` the power of each segment (all, or those listed in `segments`) to every disc
    /// it crosses. Parallel over segments; integer sums make the result order-free.
    fn accumulate(
        &self,
        store: &SegmentStore,
        segments: Option<&[u32]>,
        sign: i8,
        acc: &mut [Acc],
    ) -> IndexStats {
        accumulate_with(self, store, segments, &Power { sign }, acc)
    }

    /// Offers each segment (all, or those listed in `segments`) to the k-nearest-crossings state
    /// of every disc it crosses: [`accumulate_with`] for [`Nearest`], compiled per index (a
    /// boxed index pays one dynamic call, not one per candidate).
    fn accumulate_nearest(
        &self,
        store: &SegmentStore,
        segments: Option<&[u32]>,
        tally: &Nearest,
        acc: &mut [Kept],
    ) -> IndexStats {
        accumulate_with(self, store, segments, tally, acc)
    }

    /// **Traversal alone**, for timing it (eq. 8 assumes it negligible): walks the index for every
    /// segment exactly as [`DiscIndex::accumulate`] does — the same cells or nodes, box tests, DDA
    /// steps, mailbox and candidate lists — but tests no disc and adds nothing. Returns the
    /// counters `accumulate` would return, `ray_disc_tests` included (the candidates it would have
    /// tested), so that seconds(accumulate) − seconds(traversal_only) is the disc tests' share.
    fn traversal_only(&self, store: &SegmentStore, segments: Option<&[u32]>) -> IndexStats {
        walk_segments(
            self,
            store,
            segments,
            || 0u64,
            |n, _, _, c| *n += c.len() as u64,
            |a, b| *a += b,
        )
        .1
    }
}

/// [`DiscIndex::accumulate`] for any [`Tally`]: offers each segment (all, or those listed in
/// `segments`) to every disc it crosses, `acc` indexed by the caller's disc numbers. Parallel over
/// segments; each worker's states are merged by the tally, so the result is order-free.
pub fn accumulate_with<I, T>(
    ix: &I,
    store: &SegmentStore,
    segments: Option<&[u32]>,
    tally: &T,
    acc: &mut [T::State],
) -> IndexStats
where
    I: DiscIndex + ?Sized,
    T: Tally,
{
    let discs = ix.discs();
    assert!(acc.len() >= discs.len(), "one accumulator per disc");
    let local = &discs.discs;
    let (states, stats) = walk_segments(
        ix,
        store,
        segments,
        || tally.empties(discs.len()),
        // `crosses` on exact copies of the discs' values: `Discs::crossed_by`'s decisions.
        |states, k, s, cands| {
            cross::crossed(ix.path(), s, discs, cands, &mut |i| {
                let i = i as usize;
                tally.offer(&mut states[i], s, k, || {
                    (local.centers[i], local.normals[i])
                });
            });
        },
        |a, b| a.iter_mut().zip(b).for_each(|(x, y)| tally.merge(x, y)),
    );
    for (&i, s) in discs.original.iter().zip(states) {
        tally.merge(&mut acc[i as usize], s);
    }
    stats
}

/// The per-segment driver shared by [`DiscIndex::accumulate`] and [`DiscIndex::traversal_only`]:
/// walks each segment (all, or those in `segments`) in parallel and hands its candidates to
/// `test`, with one state `T` per worker, merged by `merge`. A segment starting outside the reach
/// gets every disc as a candidate.
fn walk_segments<I, T, N, F, M>(
    ix: &I,
    store: &SegmentStore,
    segments: Option<&[u32]>,
    init: N,
    test: F,
    merge: M,
) -> (T, IndexStats)
where
    I: DiscIndex + ?Sized,
    T: Send,
    N: Fn() -> T + Sync + Send,
    F: Fn(&mut T, u32, &Segment, &[u32]) + Sync + Send,
    M: Fn(&mut T, T) + Sync + Send,
{
    let nd = ix.discs().len();
    let n = segments.map_or(store.len(), <[u32]>::len);
    let seg_no = |k: usize| segments.map_or(k, |s| s[k] as usize);
    let (state, stats, _, _) = (0..n)
        .into_par_iter()
        .with_min_len(1 << 12)
        .fold(
            || (init(), IndexStats::default(), Mailbox::new(nd), Vec::new()),
            |(mut t, mut st, mut mb, mut cands), k| {
                let no = seg_no(k);
                let s = &store.segments[no];
                cands.clear();
                if ix.reach().holds(s.o()) {
                    let w = ix.candidates(s, &mut mb, &mut cands);
                    st.nodes_visited += w.entered;
                    st.box_tests += w.box_tests;
                    st.dda_steps += w.steps;
                    st.segments_reaching += u64::from(w.entered > 0);
                } else {
                    cands.extend(0..nd as u32);
                    st.segments_reaching += u64::from(nd > 0);
                }
                st.ray_disc_tests += cands.len() as u64;
                test(&mut t, no as u32, s, &cands);
                (t, st, mb, cands)
            },
        )
        .reduce(
            || (init(), IndexStats::default(), Mailbox::new(0), Vec::new()),
            |(mut a, sa, mb, c), (b, sb, _, _)| {
                merge(&mut a, b);
                (a, sa.merge(sb), mb, c)
            },
        );
    (state, stats)
}

/// The discs of an index, renumbered along a Hilbert curve through their centres and packed
/// centre-with-normal: a segment's candidates in neighbouring cells or leaves then sit in
/// neighbouring memory, and a test reads one record instead of two arrays (the walks were bound by
/// these loads; 1.3–1.4× faster at 10⁵ discs). The values are exact copies, so every decision is
/// the one [`Discs::crossed_by`] makes on the caller's discs.
#[derive(Clone, Debug)]
pub struct LocalDiscs {
    /// The discs in index order.
    pub discs: Discs,
    packed: Vec<[DVec3; 2]>,
    /// `original[k]`: the caller's index of local disc k.
    original: Vec<u32>,
}

impl LocalDiscs {
    /// The discs of `discs`, in Hilbert order.
    pub fn new(discs: &Discs) -> Self {
        let original = permutation(&discs.centers, Order::Hilbert, 10);
        let pick = |v: &[DVec3]| original.iter().map(|&i| v[i as usize]).collect::<Vec<_>>();
        let (centers, normals) = (pick(&discs.centers), pick(&discs.normals));
        let packed = centers
            .iter()
            .zip(&normals)
            .map(|(&c, &n)| [c, n])
            .collect();
        Self {
            // Not `Discs::new`: it would re-normalise the normals and could change their bits.
            discs: Discs {
                centers,
                normals,
                radius: discs.radius,
                radii: discs
                    .radii
                    .as_ref()
                    .map(|r| original.iter().map(|&i| r[i as usize]).collect()),
            },
            packed,
            original,
        }
    }

    /// Number of discs.
    pub fn len(&self) -> usize {
        self.original.len()
    }

    /// No discs?
    pub fn is_empty(&self) -> bool {
        self.original.is_empty()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.len() * (48 + 48 + 4) + self.discs.radii.as_ref().map_or(0, |r| r.len() * 8)
    }
}

/// The discs already tested for the current segment: one stamp per disc, direct-mapped (a disc
/// index knows its discs, so this beats the grid's hashed [`crate::grid::mailbox::Mailbox`], which
/// serves unbounded lazily generated scenes: 10–20 % faster walks at 10⁴ discs).
#[derive(Clone, Debug)]
pub struct Mailbox {
    seen: Vec<u32>,
    stamp: u32,
}

impl Mailbox {
    /// A mailbox for discs `0..n`.
    pub fn new(n: usize) -> Self {
        Self {
            seen: vec![0; n],
            stamp: 0,
        }
    }

    /// Starts a new segment: every disc is untested again.
    #[inline]
    pub fn clear(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
    }

    /// Appends to `out` the discs of `items` not yet seen for this segment, and marks them. Without
    /// a branch per disc: whether a disc is new is a coin flip along a walk (the branchy loop
    /// mispredicted on about every other listing), so each disc is written and `out` grows by one
    /// only if it was new.
    #[inline]
    pub fn collect(&mut self, items: &[u32], out: &mut Vec<u32>) {
        out.reserve(items.len());
        let mut len = out.len();
        let spare = out.spare_capacity_mut().as_mut_ptr();
        let base = len;
        for &i in items {
            let s = &mut self.seen[i as usize];
            let new = *s != self.stamp;
            *s = self.stamp;
            // SAFETY: `len − base < items.len()` ≤ the spare capacity reserved above.
            unsafe { (*spare.add(len - base)).write(i) };
            len += usize::from(new);
        }
        // SAFETY: the first `len` elements are initialised (those before `base` were; every
        // element in `base..len` was written above).
        unsafe { out.set_len(len) };
    }

    /// Marks disc `i`; true if it was not yet tested for this segment.
    #[inline]
    pub fn insert(&mut self, i: u32) -> bool {
        let s = &mut self.seen[i as usize];
        let new = *s != self.stamp;
        *s = self.stamp;
        new
    }
}

/// Where an index's traversal is provably conservative (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Box around all discs.
    pub bounds: Aabb,
    /// The pad P every tested box is enlarged by.
    pub pad: f64,
    center: DVec3,
    radius: f64,
}

impl Reach {
    /// The reach of an index over `discs` (which must not be empty).
    pub fn new(discs: &Discs) -> Self {
        assert!(!discs.is_empty(), "an index needs at least one disc");
        let bounds = discs.bounds_all();
        let p = crate::lt::precision::Precision::of(&bounds);
        let m = p.scale() + p.size;
        Self {
            bounds,
            pad: (m * (-30f64).exp2()).max(p.rounding()),
            center: (bounds.lo + bounds.hi) * 0.5,
            radius: m * 1024.0,
        }
    }

    /// Is a segment starting at `o` within the reach?
    #[inline]
    pub fn holds(&self, o: DVec3) -> bool {
        (o - self.center).length() <= self.radius
    }

    /// The box `b` enlarged by the pad.
    #[inline]
    pub fn padded(&self, b: &Aabb) -> Aabb {
        Aabb::new(b.lo - DVec3::splat(self.pad), b.hi + DVec3::splat(self.pad))
    }
}

/// The parameter range in which the line o + v·t, t ∈ [t0, t1], lies in the closed box `b`
/// (slab test; a zero direction component keeps the range iff o lies in that slab).
#[inline]
pub fn clip(o: DVec3, v: DVec3, b: &Aabb, mut t0: f64, mut t1: f64) -> Option<(f64, f64)> {
    for k in 0..3 {
        let (ok, vk, lo, hi) = (o[k], v[k], b.lo[k], b.hi[k]);
        if vk == 0.0 {
            if ok < lo || ok > hi {
                return None;
            }
            continue;
        }
        let inv = 1.0 / vk;
        let (a, c) = ((lo - ok) * inv, (hi - ok) * inv);
        t0 = t0.max(a.min(c));
        t1 = t1.min(a.max(c));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests;
