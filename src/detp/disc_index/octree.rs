//! Discs in an octree: the hierarchy the paper's disc-indexing cost model assumes (each level cuts
//! the discs a segment meets by about 4, since a segment crossing a node crosses about half of its
//! 8 children's areas).
//!
//! A node splits at its centre into 8 children while it holds more than `max_leaf` discs and its
//! side exceeds `min_side`; a disc goes to every child whose closed box meets the disc's box
//! ([`Discs::bounds`]), so a disc on a split plane sits on both sides. Traversal tests the segment
//! against each node's box enlarged by the index pad (slab test over t ∈ [0, t_end]) and reports
//! the discs of the leaves it reaches, each once per segment (mailbox).
//!
//! # Layout and speed
//! The eight children of an inner node are one [`Boxes8`] block (448 bytes, structure of arrays),
//! tested together by one eight-lane slab test ([`SimdPath`]: AVX-512, AVX2 or scalar, all deciding
//! as [`super::clip`] does, bit for bit) with the segment's reciprocals computed once. The first
//! version popped each child from a stack and clipped it alone (three divisions and NaN-aware
//! min/max per box, ≈ 200 instructions; 78 % of a 10⁴-disc, leaf-8 run). The counters are those of
//! the algorithm and do not change: one box test per child of every inner node entered (all eight
//! are tested), one per root, a node *entered* when its box test passes.

use glam::DVec3;

use super::slab::{Boxes8, SlabRay};
use super::SimdPath;
use super::{DiscIndex, LocalDiscs, Mailbox, Reach, Walk};
use crate::detp::disc::Discs;
use crate::detp::store::Segment;
use crate::geom::Aabb;

/// Deepest level (a safety stop for discs that straddle every split).
const MAX_DEPTH: u32 = 24;

/// One node: its padded box, and either 8 children (`first..first + 8`, `count == u32::MAX`) or a
/// leaf's discs (`items[first..first + count]`).
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    first: u32,
    count: u32,
}

/// `count` of an inner node.
pub(super) const INNER: u32 = u32::MAX;

/// An octree of disc lists.
#[derive(Debug)]
pub struct Octree {
    discs: LocalDiscs,
    reach: Reach,
    /// The root (inner: `first` is its children's block).
    root: Node,
    /// The children of inner node blocks: block b holds nodes 1 + 8b … 8 + 8b of the build order,
    /// an inner child's `first` naming its own block.
    blocks: Vec<Boxes8>,
    items: Vec<u32>,
    path: SimdPath,
}

/// The octree as built: nodes in creation order (children of a node contiguous).
struct Built {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

impl Octree {
    /// Builds the octree over the discs' bounds (see the module doc for the split rule).
    ///
    /// # Panics
    /// On no discs, `max_leaf == 0` or `min_side ≤ 0` (overlapping discs are never separated, so
    /// without a smallest side their common region would be split down to [`MAX_DEPTH`]).
    pub fn build(discs: &Discs, max_leaf: usize, min_side: f64) -> Self {
        assert!(max_leaf > 0, "max_leaf must be positive");
        assert!(min_side > 0.0, "min_side must be positive");
        let local = LocalDiscs::new(discs);
        let discs = &local.discs;
        let reach = Reach::new(discs);
        let boxes: Vec<Aabb> = (0..discs.len()).map(|i| discs.bounds(i)).collect();
        let all: Vec<u32> = (0..discs.len() as u32).collect();
        let root = reach.bounds;
        let mut t = Built {
            nodes: vec![Node {
                lo: root.lo,
                hi: root.hi,
                first: 0,
                count: 0,
            }],
            items: Vec::new(),
        };
        t.split(0, root, all, &boxes, max_leaf, min_side, 0);
        for n in &mut t.nodes {
            let p = reach.padded(&Aabb::new(n.lo, n.hi));
            (n.lo, n.hi) = (p.lo, p.hi);
        }
        let block_of = |n: &Node| {
            if n.count == INNER {
                Node {
                    first: (n.first - 1) / 8,
                    ..*n
                }
            } else {
                *n
            }
        };
        let blocks = t.nodes[1..]
            .chunks_exact(8)
            .map(|kids| {
                let mut b = Boxes8 {
                    lo: [[0.0; 8]; 3],
                    hi: [[0.0; 8]; 3],
                    first: [0; 8],
                    count: [0; 8],
                };
                for (l, k) in kids.iter().map(block_of).enumerate() {
                    for a in 0..3 {
                        (b.lo[a][l], b.hi[a][l]) = (k.lo[a], k.hi[a]);
                    }
                    (b.first[l], b.count[l]) = (k.first, k.count);
                }
                b
            })
            .collect();
        Self {
            discs: local,
            reach,
            root: block_of(&t.nodes[0]),
            blocks,
            items: t.items,
            path: SimdPath::detect(),
        }
    }

    /// The same octree with its kernels on `path` (tests force every path this CPU has).
    ///
    /// # Panics
    /// If this CPU cannot run `path`.
    pub fn with_path(mut self, path: SimdPath) -> Self {
        assert!(path.is_available(), "slab path {path:?} not available");
        self.path = path;
        self
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        1 + 8 * self.blocks.len()
    }

    /// Reports leaf `first..first + count`'s discs not yet seen for this segment.
    #[inline]
    fn leaf(&self, first: u32, count: u32, mailbox: &mut Mailbox, out: &mut Vec<u32>) {
        mailbox.collect(&self.items[first as usize..(first + count) as usize], out);
    }
}

impl Built {
    #[allow(clippy::too_many_arguments)]
    fn split(
        &mut self,
        node: usize,
        b: Aabb,
        ids: Vec<u32>,
        boxes: &[Aabb],
        max_leaf: usize,
        min_side: f64,
        depth: u32,
    ) {
        let side = (b.hi - b.lo).max_element();
        if ids.len() <= max_leaf || side <= min_side || depth >= MAX_DEPTH {
            self.nodes[node].first = self.items.len() as u32;
            self.nodes[node].count = ids.len() as u32;
            self.items.extend_from_slice(&ids);
            return;
        }
        let mid = (b.lo + b.hi) * 0.5;
        let first = self.nodes.len();
        self.nodes[node].first = first as u32;
        self.nodes[node].count = INNER;
        let kids: Vec<Aabb> = (0..8)
            .map(|k| {
                let pick = |bit: usize, i: usize| {
                    if k >> bit & 1 == 0 {
                        (b.lo[i], mid[i])
                    } else {
                        (mid[i], b.hi[i])
                    }
                };
                let (x, y, z) = (pick(0, 0), pick(1, 1), pick(2, 2));
                Aabb::new(DVec3::new(x.0, y.0, z.0), DVec3::new(x.1, y.1, z.1))
            })
            .collect();
        for k in &kids {
            self.nodes.push(Node {
                lo: k.lo,
                hi: k.hi,
                first: 0,
                count: 0,
            });
        }
        for (k, kb) in kids.into_iter().enumerate() {
            let sub: Vec<u32> = ids
                .iter()
                .copied()
                .filter(|&i| {
                    let d = &boxes[i as usize];
                    d.lo.cmple(kb.hi).all() && kb.lo.cmple(d.hi).all()
                })
                .collect();
            self.split(first + k, kb, sub, boxes, max_leaf, min_side, depth + 1);
        }
    }
}

impl DiscIndex for Octree {
    fn discs(&self) -> &LocalDiscs {
        &self.discs
    }

    fn reach(&self) -> &Reach {
        &self.reach
    }

    fn candidates(&self, seg: &Segment, mailbox: &mut Mailbox, out: &mut Vec<u32>) -> Walk {
        mailbox.clear();
        let ray = SlabRay::new(seg);
        let mut walk = Walk {
            box_tests: 1,
            ..Walk::default()
        };
        if !ray.meets(&Aabb::new(self.root.lo, self.root.hi)) {
            return walk;
        }
        walk.entered = 1;
        if self.root.count != INNER {
            self.leaf(self.root.first, self.root.count, mailbox, out);
            return walk;
        }
        let mut stack = [0u32; 8 * MAX_DEPTH as usize + 8];
        stack[0] = self.root.first;
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let b = &self.blocks[stack[top] as usize];
            let mut hit = self.path.test8(&ray, b);
            walk.box_tests += 8;
            walk.entered += u64::from(hit.count_ones());
            while hit != 0 {
                let l = hit.trailing_zeros() as usize;
                hit &= hit - 1;
                if b.count[l] == INNER {
                    stack[top] = b.first[l];
                    top += 1;
                } else {
                    self.leaf(b.first[l], b.count[l], mailbox, out);
                }
            }
        }
        walk
    }

    fn path(&self) -> SimdPath {
        self.path
    }

    fn bytes(&self) -> usize {
        self.nodes() * std::mem::size_of::<Node>() + self.items.len() * 4 + self.discs.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::super::clip;
    use super::super::tests::{adversarial_segments, scene};
    use super::*;

    /// The first version's walk, kept as the oracle of the counters: every node popped from a
    /// stack and clipped alone (`clip` per box), children pushed in order.
    fn reference(t: &Octree, seg: &Segment, mailbox: &mut Mailbox) -> (Walk, Vec<u32>) {
        mailbox.clear();
        let (o, v, t_end) = (seg.o(), seg.d(), seg.t_end());
        let mut walk = Walk::default();
        let mut out = Vec::new();
        let mut stack = vec![t.root];
        while let Some(n) = stack.pop() {
            walk.box_tests += 1;
            if clip(o, v, &Aabb::new(n.lo, n.hi), 0.0, t_end).is_none() {
                continue;
            }
            walk.entered += 1;
            if n.count == INNER {
                let b = &t.blocks[n.first as usize];
                for l in 0..8 {
                    stack.push(Node {
                        lo: DVec3::new(b.lo[0][l], b.lo[1][l], b.lo[2][l]),
                        hi: DVec3::new(b.hi[0][l], b.hi[1][l], b.hi[2][l]),
                        first: b.first[l],
                        count: b.count[l],
                    });
                }
            } else {
                for &i in &t.items[n.first as usize..(n.first + n.count) as usize] {
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
        let (store, discs) = scene(3_000, 2_000, 0.03, 7);
        for (leaf, side) in [(8, 0.06), (32, 0.06), (1, 0.2), (4000, 0.06)] {
            let base = Octree::build(&discs, leaf, side);
            let segs: Vec<Segment> = store
                .segments
                .iter()
                .copied()
                .chain(adversarial_segments(&base.discs.discs, 11))
                .collect();
            let mut mb = Mailbox::new(discs.len());
            let want: Vec<(Walk, Vec<u32>)> =
                segs.iter().map(|s| reference(&base, s, &mut mb)).collect();
            let deep = want.iter().any(|w| w.0.entered > 3);
            assert_eq!(
                deep,
                leaf < 4000,
                "leaf {leaf}: walks go deep below the root"
            );
            for path in SimdPath::all_available() {
                let t = Octree::build(&discs, leaf, side).with_path(path);
                for (k, (s, w)) in segs.iter().zip(&want).enumerate() {
                    let mut got = Vec::new();
                    let walk = t.candidates(s, &mut mb, &mut got);
                    got.sort_unstable();
                    assert_eq!((walk, got), w.clone(), "{path:?}, leaf {leaf}, segment {k}");
                }
            }
        }
    }
}
