//! The ray-casting core of light transport: the nearest hit, the nearest *and* the next crossing
//! beyond it (DETP counts crossings up to the second intersection), and any hit before a distance
//! (shadow rays), over triangles, each answer exactly what testing every triangle with
//! [`Triangle::intersect`] gives (see "Exactness").
//!
//! # Structure
//! A binned-SAH binary tree collapsed into 8-wide nodes ([`build`]); each node holds its children's
//! boxes in f32, rounded outward, tested eight at a time; leaves are packets of four triangles as
//! structure-of-arrays f64, tested four at a time with the f64 Möller–Trumbore test
//! ([`kernel`]). Traversal is ordered (nearest child first) and culls every box that starts beyond
//! the distance that still matters. A scene of at most [`SINGLE_LEAF`] triangles is one leaf: for
//! so few (the Cornell box's 32), testing them all in packets beats any tree.
//!
//! # Instruction sets
//! AVX2 where the CPU has it, else portable scalar code ([`Path::detect`]; `RAYCOST_BVH=scalar`
//! forces the portable path). Both run the same f64 operations on every triangle, so they give
//! identical answers (tested by forcing each path). A third path, [`Path::Avx2Pretest`]
//! (`RAYCOST_BVH=avx2-pretest`), puts a conservative f32 test in front of the f64 one that skips
//! only lanes it proves missed — the same answers, but measured 3–5 % slower on the bench scenes
//! (docs/bench.md), so it is not the default.
//!
//! # Exactness
//! Which triangles a ray hits, and at which t, is decided only by the f64 test, never by a box: the
//! f32 box test is conservative (proof in [`kernel`]), so traversal tests every triangle whose
//! padded box the exact ray meets within the distances that matter. The answer is then a function
//! of the set of hits alone, not of the order traversal meets them. Triangles are ranked by the
//! order in which the BVH of f3d7ed0 met them ([`build::legacy_order`]: its tree, depth first,
//! right child first — the same order for every ray; the index order for a scene of at most 64
//! triangles), and
//! - nearest: the hit with the smallest (t, rank);
//! - two nearest: that, and the smallest (t, rank) among the hits with
//!   t − t₁ > 10⁻¹²·max(|t|, 1) (a crossing within 10⁻¹² of the first, such as the other triangle
//!   of a shared edge, is the same crossing);
//! - any hit: whether some hit has t < t_max.
//!
//! That BVH kept, among hits at equal t, the one it met first, and folded hits with
//! [`TwoNearest::offer`] in that order: its answers are the ones above — the first always, the
//! second unless three crossings lie within 2·10⁻¹² of each other without two being equal (the
//! fold can then lose the second; tested). Exact ties are common: the BART kitchen has coincident
//! triangles of opposite orientation, and ranking by index instead changed 228 of 413 352 random
//! rays' nearest triangle there. Testing every triangle agrees with any BVH except where the f64
//! test accepts a point outside the triangle's padded box, which needs a ray within ~10⁻⁹ rad of a
//! triangle's plane; the margin here (≥ 6·10⁻⁷ of the scene's size) makes that rarer than the old
//! padding (10⁻⁹) did.

mod build;
mod kernel;
pub mod layout;
#[cfg(test)]
mod tests;

use glam::DVec3;

use self::kernel::{Culled, Deferred, Forget, Query, RayData};
use self::layout::{ChildRef, Node, Packet, PacketF32};
use super::shapes::Triangle;

/// Scenes of at most this many triangles are one leaf (measured: the Cornell box's 32 triangles
/// in 8 packets beat a tree).
pub const SINGLE_LEAF: usize = 0;

/// Two crossings closer than this (relative, at least 10⁻¹² absolute) are one crossing.
#[inline]
fn same_crossing(t: f64, first: f64) -> bool {
    t - first <= 1e-12 * t.abs().max(1.0)
}

/// The two nearest (t, triangle) along a ray; t = +∞ where there is none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoNearest {
    /// Nearest.
    pub first: (f64, u32),
    /// Next beyond it.
    pub second: (f64, u32),
}

impl TwoNearest {
    const EMPTY: Self = Self {
        first: (f64::INFINITY, u32::MAX),
        second: (f64::INFINITY, u32::MAX),
    };

    /// Offers a candidate. Equal t from a different triangle (a ray through a shared edge) is the
    /// same crossing, not a second one. (The fold the scene uses to merge static, dynamic and sphere
    /// hits; the BVH itself answers by [`TwoNearest`]'s order-free rule, see the module doc.)
    #[inline]
    pub fn offer(&mut self, t: f64, id: u32) {
        if t < self.first.0 {
            if self.first.0 - t > 1e-12 * t.abs().max(1.0) {
                self.second = self.first;
            }
            self.first = (t, id);
        } else if t < self.second.0 && t - self.first.0 > 1e-12 * t.abs().max(1.0) {
            self.second = (t, id);
        }
    }
}

impl Default for TwoNearest {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Is (t, id) before (u, jd) in the order (t, then index)?
#[inline(always)]
fn before(t: f64, id: u32, u: f64, jd: u32) -> bool {
    t < u || (t == u && id < jd)
}

/// The nearest hit before `limit`.
struct Nearest {
    best: (f64, u32),
    limit: f64,
}

impl Query for Nearest {
    #[inline(always)]
    fn bound(&self) -> f64 {
        self.best.0.min(self.limit)
    }
    #[inline(always)]
    fn offer(&mut self, t: f64, id: u32) -> bool {
        if t < self.limit && before(t, id, self.best.0, self.best.1) {
            self.best = (t, id);
        }
        false
    }
}

/// The two nearest crossings. A hit within 10⁻¹² of the current first that is not itself the
/// first is dropped; if the first later moves nearer, such a hit could become the second, so
/// `dropped` sends the ray through a second pass ([`SecondOnly`]).
struct Two {
    best: TwoNearest,
    dropped: bool,
}

impl Query for Two {
    #[inline(always)]
    fn bound(&self) -> f64 {
        self.best.second.0
    }
    #[inline(always)]
    fn offer(&mut self, t: f64, id: u32) -> bool {
        let b = &mut self.best;
        if before(t, id, b.first.0, b.first.1) {
            let old = b.first;
            b.first = (t, id);
            if old.0.is_finite() {
                if !same_crossing(old.0, t) {
                    if before(old.0, old.1, b.second.0, b.second.1) {
                        b.second = old;
                    }
                } else if old.0 != t {
                    self.dropped = true;
                }
            }
        } else if !same_crossing(t, b.first.0) {
            if before(t, id, b.second.0, b.second.1) {
                b.second = (t, id);
            }
        } else if t != b.first.0 {
            self.dropped = true;
        }
        false
    }
}

/// [`Two`] culling beyond the first crossing only: the first pass of a tree's two-nearest query,
/// whose second crossing (an upper bound of the true one) lets the second pass cull early.
struct TwoFirstPass(Two);

impl Query for TwoFirstPass {
    #[inline(always)]
    fn bound(&self) -> f64 {
        self.0.best.first.0
    }
    #[inline(always)]
    fn offer(&mut self, t: f64, id: u32) -> bool {
        self.0.offer(t, id)
    }
}

/// The second crossing given the final first one.
struct SecondOnly {
    first: f64,
    second: (f64, u32),
}

impl Query for SecondOnly {
    #[inline(always)]
    fn bound(&self) -> f64 {
        self.second.0
    }
    #[inline(always)]
    fn offer(&mut self, t: f64, id: u32) -> bool {
        if !same_crossing(t, self.first) && before(t, id, self.second.0, self.second.1) {
            self.second = (t, id);
        }
        false
    }
}

/// Any hit before `limit`.
struct Any {
    limit: f64,
    hit: bool,
}

impl Query for Any {
    #[inline(always)]
    fn bound(&self) -> f64 {
        self.limit
    }
    #[inline(always)]
    fn offer(&mut self, t: f64, _: u32) -> bool {
        self.hit = t < self.limit;
        self.hit
    }
}

/// Which tests traversal runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// Portable scalar code.
    Scalar,
    /// AVX2.
    Avx2,
    /// AVX2 with the f32 triangle pre-test in front of the exact test: the same answers, measured
    /// slower than [`Path::Avx2`] (docs/bench.md), so chosen only by `RAYCOST_BVH=avx2-pretest` or
    /// [`Bvh::with_path`] (the bench times it beside the default).
    Avx2Pretest,
}

impl Path {
    /// AVX2 if this CPU has it, unless `RAYCOST_BVH=scalar` asks for the portable path
    /// (`RAYCOST_BVH=avx2-pretest`: AVX2 with the f32 pre-test, where the CPU has AVX2).
    pub fn detect() -> Self {
        let asked = std::env::var("RAYCOST_BVH").unwrap_or_default();
        if asked == "avx2-pretest" && Self::Avx2Pretest.available() {
            Self::Avx2Pretest
        } else if asked != "scalar" && Self::Avx2.available() {
            Self::Avx2
        } else {
            Self::Scalar
        }
    }

    /// Can this CPU run it?
    pub fn available(self) -> bool {
        match self {
            Self::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 | Self::Avx2Pretest => is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            Self::Avx2 | Self::Avx2Pretest => false,
        }
    }

    /// Its name (`avx2`, `scalar`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Scalar => "scalar",
            Self::Avx2 => "avx2",
            Self::Avx2Pretest => "avx2-pretest",
        }
    }
}

/// The hierarchy, with its own copy of the triangles (as packets).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles by rank (packets hold ranks, answers map them back to indices).
    packets: Vec<Packet>,
    /// The same packets in f32 for the pre-test (one per packet, same index).
    pretest: Vec<PacketF32>,
    /// Rank → triangle index.
    id_of: Vec<u32>,
    /// Triangle index → rank.
    key_of: Vec<u32>,
    root: ChildRef,
    /// The largest |coordinate| of any box (sets the f32 test's margin).
    bound: f64,
    path: Path,
}

impl Default for Bvh {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            packets: Vec::new(),
            pretest: Vec::new(),
            id_of: Vec::new(),
            key_of: Vec::new(),
            root: ChildRef::EMPTY,
            bound: 0.0,
            path: Path::Scalar,
        }
    }
}

impl Bvh {
    /// Builds over `tris` (triangle i keeps index i in every answer).
    pub fn build(tris: &[Triangle]) -> Self {
        Self::build_with(tris, SINGLE_LEAF)
    }

    /// Builds over `tris`, one leaf if there are at most `single_leaf` of them.
    pub fn build_with(tris: &[Triangle], single_leaf: usize) -> Self {
        let magnitude = tris
            .iter()
            .flat_map(|t| t.v)
            .map(|v| v.abs().max_element())
            .fold(1.0, f64::max);
        let id_of = build::legacy_order(tris);
        let mut key_of = vec![0; tris.len()];
        for (rank, &i) in id_of.iter().enumerate() {
            key_of[i as usize] = rank as u32;
        }
        let built = build::build(tris, &key_of, 1e-9 * magnitude, single_leaf);
        let bound = built.lo.abs().max(built.hi.abs()).max_element();
        Self {
            nodes: built.nodes,
            pretest: built.packets.iter().map(PacketF32::new).collect(),
            packets: built.packets,
            id_of,
            key_of,
            root: built.root,
            bound: f64::from(layout::f32_up(bound)),
            path: Path::detect(),
        }
    }

    /// The same hierarchy traversed with `path` (which this CPU must be able to run).
    pub fn with_path(mut self, path: Path) -> Self {
        assert!(path.available(), "this CPU cannot run the {path:?} path");
        self.path = path;
        self
    }

    /// The tests it runs.
    pub fn path(&self) -> Path {
        self.path
    }

    /// Over no triangles?
    pub fn is_empty(&self) -> bool {
        self.packets.is_empty()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.packets.len() * std::mem::size_of::<Packet>()
            + self.pretest.len() * std::mem::size_of::<PacketF32>()
            + 8 * self.id_of.len()
    }

    /// Each triangle's rank (the tie order, see the module doc), by index.
    pub fn ranks(&self) -> &[u32] {
        &self.key_of
    }

    /// A triangle's rank (`u32::MAX` for none).
    #[inline]
    fn key(&self, id: u32) -> u32 {
        self.key_of.get(id as usize).copied().unwrap_or(u32::MAX)
    }

    /// A (t, rank) answer as (t, triangle index).
    #[inline]
    fn id(&self, (t, key): (f64, u32)) -> (f64, u32) {
        (t, self.id_of.get(key as usize).copied().unwrap_or(u32::MAX))
    }

    /// Runs `q` over every hit with t > t_min, skipping triangle `skip`, culled by `q`'s bound
    /// (`q` sees ranks, not indices).
    #[inline]
    fn run<Q: Query>(&self, o: DVec3, d: DVec3, t_min: f64, skip: u32, q: &mut Q) {
        self.walk(None, o, d, t_min, skip, q, &mut Forget);
    }

    /// [`Bvh::run`] from `start` (the root if `None`), keeping what it culls in `culled`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn walk<Q: Query, D: Deferred>(
        &self,
        start: Option<&Culled>,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: u32,
        q: &mut Q,
        culled: &mut D,
    ) {
        if self.packets.is_empty() {
            return;
        }
        let skip = self.key(skip);
        let mut ray = RayData::new(o.to_array(), d.to_array(), self.bound);
        if self.path == Path::Avx2Pretest {
            ray = ray.with_pretest();
        }
        let tree = kernel::Tree {
            nodes: &self.nodes,
            packets: &self.packets,
            pretest: &self.pretest,
            root: self.root,
            start,
        };
        let (r, c) = (&ray, culled);
        match self.path {
            // SAFETY: the portable tests need nothing.
            Path::Scalar => unsafe { kernel::traverse_scalar(&tree, r, t_min, skip, q, c) },
            // SAFETY: `with_path` and `detect` only choose AVX2 where the CPU has it.
            #[cfg(target_arch = "x86_64")]
            Path::Avx2 => unsafe { kernel::traverse_avx2(&tree, r, t_min, skip, q, c) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Path::Avx2Pretest => unsafe {
                kernel::traverse_avx2_pretest(&tree, r, t_min, skip, q, c)
            },
            #[cfg(not(target_arch = "x86_64"))]
            Path::Avx2 | Path::Avx2Pretest => unreachable!("AVX2 is never chosen off x86-64"),
        }
    }

    /// The two nearest crossings with t > t_min, skipping triangle `skip` (the surface a photon
    /// leaves), by the rule of the module doc.
    ///
    /// A single-node tree tests its packets once, keeping both crossings ([`Two`]); a deeper tree
    /// is traversed twice: for the nearest (culling beyond it, keeping any farther crossing its
    /// leaves hold and the subtrees it culled) and then for the next crossing beyond it, from the
    /// subtrees the first pass culled rather than from the root, culling beyond the best found so
    /// far (two passes measured 2–5× faster on the BART kitchen than one traversal that can cull
    /// only beyond the second crossing).
    pub fn two_nearest(&self, o: DVec3, d: DVec3, t_min: f64, skip: u32) -> TwoNearest {
        if self.nodes.len() <= 1 {
            let mut q = Two {
                best: TwoNearest::EMPTY,
                dropped: false,
            };
            self.run(o, d, t_min, skip, &mut q);
            if q.dropped {
                q.best.second = self.second(o, d, t_min, skip, q.best.first.0, q.best.second);
            }
            return TwoNearest {
                first: self.id(q.best.first),
                second: self.id(q.best.second),
            };
        }
        let mut q = TwoFirstPass(Two {
            best: TwoNearest::EMPTY,
            dropped: false,
        });
        let mut culled = Culled::new();
        self.walk(None, o, d, t_min, skip, &mut q, &mut culled);
        let best = q.0.best;
        if !best.first.0.is_finite() {
            return TwoNearest::EMPTY;
        }
        // Any second crossing the first pass met bounds the second pass. Every leaf the first
        // pass tested offered all its hits to `Two`, whose second is exact over them unless it
        // dropped one ([`Two`]), so the second pass needs only the subtrees the first culled —
        // unless it dropped a hit or culled more than it could keep: then it starts at the root.
        let second = if q.0.dropped || culled.overflow {
            self.second(o, d, t_min, skip, best.first.0, best.second)
        } else {
            culled.sort_far_first();
            let mut s = SecondOnly {
                first: best.first.0,
                second: best.second,
            };
            let t_from = t_min.max(best.first.0);
            self.walk(Some(&culled), o, d, t_from, skip, &mut s, &mut Forget);
            s.second
        };
        TwoNearest {
            first: self.id(best.first),
            second: self.id(second),
        }
    }

    /// The nearest crossing that is not the same crossing as `first`, given one such, `bound`.
    /// Every such crossing lies beyond `first`, so hits at or before it are not even tested.
    fn second(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: u32,
        first: f64,
        bound: (f64, u32),
    ) -> (f64, u32) {
        let mut s = SecondOnly {
            first,
            second: bound,
        };
        self.run(o, d, t_min.max(first), skip, &mut s);
        s.second
    }

    /// The nearest crossing with t_min < t < limit, skipping triangle `skip`: (t, triangle), or
    /// (+∞, `u32::MAX`).
    pub fn nearest_before(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        limit: f64,
        skip: u32,
    ) -> (f64, u32) {
        let mut q = Nearest {
            best: (f64::INFINITY, u32::MAX),
            limit,
        };
        self.run(o, d, t_min, skip, &mut q);
        self.id(q.best)
    }

    /// The nearest crossing with t > t_min, skipping triangle `skip`: (t, triangle), or
    /// (+∞, `u32::MAX`). The first of [`Bvh::two_nearest`], found without the second.
    pub fn nearest(&self, o: DVec3, d: DVec3, t_min: f64, skip: u32) -> (f64, u32) {
        self.nearest_before(o, d, t_min, f64::INFINITY, skip)
    }

    /// Is there a crossing with t_min < t < limit (skipping triangle `skip`)? Stops at the first
    /// one found.
    pub fn any_before(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64, skip: u32) -> bool {
        let mut q = Any { limit, hit: false };
        self.run(o, d, t_min, skip, &mut q);
        q.hit
    }

    /// Calls `f` with every triangle whose leaf box comes within `r` of `p` (a superset of the
    /// triangles within `r`: the caller measures each).
    pub fn near(&self, p: DVec3, r: f64, f: &mut dyn FnMut(u32)) {
        if self.packets.is_empty() {
            return;
        }
        let mut stack = vec![self.root];
        while let Some(c) = stack.pop() {
            if c.is_leaf() {
                for pk in &self.packets[c.packets()] {
                    pk.id
                        .iter()
                        .filter(|&&k| k != u32::MAX)
                        .for_each(|&k| f(self.id_of[k as usize]));
                }
                continue;
            }
            let n = &self.nodes[c.index()];
            for k in 0..layout::WIDTH {
                let lo = DVec3::new(n.lo[0][k].into(), n.lo[1][k].into(), n.lo[2][k].into());
                let hi = DVec3::new(n.hi[0][k].into(), n.hi[1][k].into(), n.hi[2][k].into());
                if n.child[k] != ChildRef::EMPTY && (p.clamp(lo, hi) - p).length_squared() <= r * r
                {
                    stack.push(n.child[k]);
                }
            }
        }
    }
}

/// The answer of [`Bvh::two_nearest`] by testing every triangle (the oracle), by the same rule;
/// `rank` is [`Bvh::ranks`].
pub fn two_nearest_brute(
    tris: &[Triangle],
    rank: &[u32],
    o: DVec3,
    d: DVec3,
    t_min: f64,
    skip: u32,
) -> TwoNearest {
    let hits: Vec<(f64, u32)> = tris
        .iter()
        .enumerate()
        .filter(|&(i, _)| i as u32 != skip)
        .filter_map(|(i, t)| t.intersect(o, d, t_min).map(|t| (t, i as u32)))
        .collect();
    let lexmin = |a: (f64, u32), b: (f64, u32)| {
        let r = |x: (f64, u32)| rank.get(x.1 as usize).copied().unwrap_or(u32::MAX);
        if before(b.0, r(b), a.0, r(a)) {
            b
        } else {
            a
        }
    };
    let first = hits.iter().copied().fold(TwoNearest::EMPTY.first, lexmin);
    let second = hits
        .iter()
        .copied()
        .filter(|&(t, _)| !same_crossing(t, first.0))
        .fold(TwoNearest::EMPTY.second, lexmin);
    TwoNearest { first, second }
}
