//! Discs in an octree: the hierarchy the paper's disc-indexing cost model assumes (each level cuts
//! the discs a segment meets by about 4, since a segment crossing a node crosses about half of its
//! 8 children's areas).
//!
//! A node splits at its centre into 8 children while it holds more than `max_leaf` discs and its
//! side exceeds `min_side`; a disc goes to every child whose closed box meets the disc's box
//! ([`Discs::bounds`]), so a disc on a split plane sits on both sides. Traversal tests the segment
//! against each node's box enlarged by the index pad (slab test over t ∈ [0, t_end]) and reports
//! the discs of the leaves it reaches, each once per segment (mailbox).

use glam::DVec3;

use super::{clip, DiscIndex, LocalDiscs, Mailbox, Reach, Walk};
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

const INNER: u32 = u32::MAX;

/// An octree of disc lists.
#[derive(Debug)]
pub struct Octree {
    discs: LocalDiscs,
    reach: Reach,
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
        let mut t = Self {
            discs: local,
            reach,
            nodes: Vec::new(),
            items: Vec::new(),
        };
        let root = reach.bounds;
        t.nodes.push(Node {
            lo: root.lo,
            hi: root.hi,
            first: 0,
            count: 0,
        });
        t.split(0, root, all, &boxes, max_leaf, min_side, 0);
        for n in &mut t.nodes {
            let p = reach.padded(&Aabb::new(n.lo, n.hi));
            (n.lo, n.hi) = (p.lo, p.hi);
        }
        t
    }

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

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }
}

impl DiscIndex for Octree {
    fn discs(&self) -> &LocalDiscs {
        &self.discs
    }

    fn reach(&self) -> &Reach {
        &self.reach
    }

    fn candidates(&self, seg: &Segment, mailbox: &mut Mailbox, f: &mut dyn FnMut(u32)) -> Walk {
        mailbox.clear();
        let (o, v, t_end) = (seg.o(), seg.d(), seg.t_end());
        let mut walk = Walk::default();
        let mut stack = [0u32; 8 * MAX_DEPTH as usize + 8];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            walk.box_tests += 1;
            if clip(o, v, &Aabb::new(n.lo, n.hi), 0.0, t_end).is_none() {
                continue;
            }
            walk.entered += 1;
            if n.count == INNER {
                for k in 0..8 {
                    stack[top] = n.first + k;
                    top += 1;
                }
            } else {
                for &i in &self.items[n.first as usize..(n.first + n.count) as usize] {
                    if mailbox.insert(i) {
                        f(i);
                    }
                }
            }
        }
        walk
    }

    fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.items.len() * 4 + self.discs.bytes()
    }
}
