//! Building: a binary tree by binned SAH over triangle centroids, collapsed into 8-wide nodes
//! whose leaves are packets of four triangles.
//!
//! The binary build bins centroids into 16 bins per axis and takes the cheapest split by the
//! surface-area heuristic, counting a leaf's cost in packets (four triangles cost one packet test)
//! and a node's box test at half a packet. A range of at most four triangles is a leaf; so is any
//! range whose SAH split costs more than testing it whole, up to 16 triangles. When the centroids
//! coincide (no split separates them) the range is halved in index order. Past depth 40 the split is
//! the median, so the depth and the traversal stack stay bounded. Collapsing replaces, in each node,
//! the child of largest surface area by its two children until eight children fill it.
//!
//! Every box is the union of its triangles' f64 bounds padded by `pad`, then rounded outward to f32
//! ([`Node::set`]); the build is deterministic (a pure function of the triangles and their order).

use glam::DVec3;

use super::layout::{ChildRef, Node, Packet, LANES, MAX_LEAF_PACKETS, WIDTH};
use crate::lt::shapes::Triangle;

const BINS: usize = 16;
/// A node's box test, in packet tests.
const NODE_COST: f64 = 0.5;
/// Triangles a SAH leaf may hold (a single-leaf scene may hold more).
const MAX_LEAF: usize = 16;
/// Binary depth past which ranges are split at the median.
const SAH_DEPTH: usize = 40;

/// A binary node during the build.
struct Bin {
    lo: DVec3,
    hi: DVec3,
    /// Inner: the two children; leaf: `None`.
    kids: Option<(usize, usize)>,
    /// Leaf: its range of `order`.
    range: (usize, usize),
}

impl Bin {
    fn area(&self) -> f64 {
        half_area(self.lo, self.hi)
    }
}

fn half_area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// What the build produces.
pub struct Built {
    pub nodes: Vec<Node>,
    pub packets: Vec<Packet>,
    pub root: ChildRef,
    /// The root's f64 box (padded).
    pub lo: DVec3,
    pub hi: DVec3,
}

/// Builds over `tris`; a scene of at most `single_leaf` triangles is one leaf.
pub fn build(tris: &[Triangle], key_of: &[u32], pad: f64, single_leaf: usize) -> Built {
    let mut b = Builder {
        tris,
        key_of,
        pad,
        centroid: tris.iter().map(Triangle::centroid).collect(),
        bounds: tris.iter().map(Triangle::bounds).collect(),
        bins: Vec::new(),
    };
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let root = if tris.len() <= single_leaf.min(MAX_LEAF_PACKETS as usize * LANES) {
        let (lo, hi) = b.bounds(&order);
        b.bins.push(Bin {
            lo,
            hi,
            kids: None,
            range: (0, order.len()),
        });
        0
    } else {
        b.split(&mut order, 0, 0)
    };
    b.collapse(root, &order)
}

struct Builder<'a> {
    tris: &'a [Triangle],
    /// The key a packet stores for each triangle.
    key_of: &'a [u32],
    pad: f64,
    centroid: Vec<DVec3>,
    /// Each triangle's (lo, hi).
    bounds: Vec<(DVec3, DVec3)>,
    bins: Vec<Bin>,
}

/// Component-wise min and max by plain comparisons (the inputs are finite: glam's NaN-aware
/// `min`/`max` cost twice the build time).
#[inline(always)]
fn vmin(a: DVec3, b: DVec3) -> DVec3 {
    let m = |x: f64, y: f64| if y < x { y } else { x };
    DVec3::new(m(a.x, b.x), m(a.y, b.y), m(a.z, b.z))
}

#[inline(always)]
fn vmax(a: DVec3, b: DVec3) -> DVec3 {
    let m = |x: f64, y: f64| if y > x { y } else { x };
    DVec3::new(m(a.x, b.x), m(a.y, b.y), m(a.z, b.z))
}

impl Builder<'_> {
    /// The padded f64 box of the triangles `ids`.
    fn bounds(&self, ids: &[u32]) -> (DVec3, DVec3) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in ids {
            let (a, b) = self.bounds[i as usize];
            lo = vmin(lo, a);
            hi = vmax(hi, b);
        }
        (lo - DVec3::splat(self.pad), hi + DVec3::splat(self.pad))
    }

    /// Builds the binary subtree over `order[..]` (which starts at `start` in the full order) and
    /// returns its index.
    fn split(&mut self, order: &mut [u32], start: usize, depth: usize) -> usize {
        let (lo, hi) = self.bounds(order);
        let id = self.bins.len();
        self.bins.push(Bin {
            lo,
            hi,
            kids: None,
            range: (start, start + order.len()),
        });
        let n = order.len();
        if n <= LANES {
            return id;
        }
        let mid = match self.sah_split(order, lo, hi, depth) {
            Some(mid) => mid,
            None if n <= MAX_LEAF => return id,
            None => n / 2,
        };
        let (a, b) = order.split_at_mut(mid);
        let left = self.split(a, start, depth + 1);
        let right = self.split(b, start + mid, depth + 1);
        self.bins[id].kids = Some((left, right));
        id
    }

    /// Partitions `order` at the cheapest binned-SAH plane and returns the split index, or `None`
    /// if a leaf is cheaper (or no plane separates the centroids). Past `SAH_DEPTH`, the median of
    /// the widest centroid axis.
    fn sah_split(&self, order: &mut [u32], lo: DVec3, hi: DVec3, depth: usize) -> Option<usize> {
        let (mut clo, mut chi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in order.iter() {
            clo = vmin(clo, self.centroid[i as usize]);
            chi = vmax(chi, self.centroid[i as usize]);
        }
        let ext = chi - clo;
        let n = order.len();
        if ext.max_element() <= 0.0 {
            return None;
        }
        if depth >= SAH_DEPTH {
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let c = &self.centroid;
            order.select_nth_unstable_by(n / 2, |&a, &b| {
                c[a as usize][axis]
                    .total_cmp(&c[b as usize][axis])
                    .then(a.cmp(&b))
            });
            return Some(n / 2);
        }
        let mut best = (f64::INFINITY, 0usize, 0usize); // (cost, axis, bins left of the plane)
        for axis in 0..3 {
            if ext[axis] <= 0.0 {
                continue;
            }
            let scale = BINS as f64 / ext[axis];
            let bin_of = |i: u32| {
                (((self.centroid[i as usize][axis] - clo[axis]) * scale) as usize).min(BINS - 1)
            };
            let mut count = [0usize; BINS];
            let mut blo = [DVec3::splat(f64::INFINITY); BINS];
            let mut bhi = [DVec3::splat(f64::NEG_INFINITY); BINS];
            for &i in order.iter() {
                let k = bin_of(i);
                let (a, b) = self.bounds[i as usize];
                count[k] += 1;
                blo[k] = vmin(blo[k], a);
                bhi[k] = vmax(bhi[k], b);
            }
            // Right-to-left sweep: area·packets of the right side for each plane.
            let mut right = [0.0; BINS];
            let (mut rlo, mut rhi, mut rn) = (
                DVec3::splat(f64::INFINITY),
                DVec3::splat(f64::NEG_INFINITY),
                0,
            );
            for k in (1..BINS).rev() {
                rlo = vmin(rlo, blo[k]);
                rhi = vmax(rhi, bhi[k]);
                rn += count[k];
                right[k] = half_area(rlo, rhi) * rn.div_ceil(LANES) as f64;
            }
            let (mut llo, mut lhi, mut ln) = (
                DVec3::splat(f64::INFINITY),
                DVec3::splat(f64::NEG_INFINITY),
                0,
            );
            for k in 1..BINS {
                llo = vmin(llo, blo[k - 1]);
                lhi = vmax(lhi, bhi[k - 1]);
                ln += count[k - 1];
                if ln == 0 || ln == n {
                    continue;
                }
                let cost = half_area(llo, lhi) * ln.div_ceil(LANES) as f64 + right[k];
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        if !best.0.is_finite() {
            return None;
        }
        let area = half_area(lo, hi);
        let split_cost = NODE_COST + best.0 / area;
        let leaf_cost = n.div_ceil(LANES) as f64;
        if n <= MAX_LEAF && leaf_cost <= split_cost {
            return None;
        }
        let (axis, k) = (best.1, best.2);
        let scale = BINS as f64 / ext[axis];
        let left_of = |i: u32| {
            ((((self.centroid[i as usize][axis] - clo[axis]) * scale) as usize).min(BINS - 1)) < k
        };
        // Stable partition: keeps the build a pure function of the input order.
        let (l, r): (Vec<u32>, Vec<u32>) = order.iter().partition(|&&i| left_of(i));
        let mid = l.len();
        order[..mid].copy_from_slice(&l);
        order[mid..].copy_from_slice(&r);
        Some(mid)
    }

    /// Collapses the binary tree under `root` into 8-wide nodes and packets.
    fn collapse(self, root: usize, order: &[u32]) -> Built {
        let mut out = Built {
            nodes: Vec::new(),
            packets: Vec::new(),
            root: ChildRef::EMPTY,
            lo: self.bins.first().map_or(DVec3::ZERO, |b| b.lo),
            hi: self.bins.first().map_or(DVec3::ZERO, |b| b.hi),
        };
        if self.tris.is_empty() {
            return out;
        }
        out.root = self.emit(root, order, &mut out);
        out
    }

    /// Emits binary node `b` (a leaf's packets, or a wide node over its collapsed children).
    fn emit(&self, b: usize, order: &[u32], out: &mut Built) -> ChildRef {
        let bin = &self.bins[b];
        let Some(_) = bin.kids else {
            let (s, e) = bin.range;
            let start = out.packets.len();
            for chunk in order[s..e].chunks(LANES) {
                let tris: Vec<(u32, Triangle)> = chunk
                    .iter()
                    .map(|&i| (self.key_of[i as usize], self.tris[i as usize]))
                    .collect();
                out.packets.push(Packet::new(&tris));
            }
            return ChildRef::leaf(start, out.packets.len() - start);
        };
        // Open the largest inner child until eight children (or only leaves) remain.
        let mut kids = vec![b];
        loop {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| self.bins[k].kids.is_some())
                .max_by(|(_, &x), (_, &y)| self.bins[x].area().total_cmp(&self.bins[y].area()))
                .map(|(pos, _)| pos);
            match open {
                Some(pos) if kids.len() < WIDTH || (kids.len() == 1) => {
                    let (l, r) = self.bins[kids[pos]].kids.expect("an inner node");
                    kids[pos] = l;
                    kids.insert(pos + 1, r);
                }
                _ => break,
            }
            if kids.len() >= WIDTH {
                break;
            }
        }
        let index = out.nodes.len();
        out.nodes.push(Node::empty());
        let mut node = Node::empty();
        for (k, &c) in kids.iter().enumerate() {
            let r = self.emit(c, order, out);
            node.set(k, r, self.bins[c].lo, self.bins[c].hi);
        }
        out.nodes[index] = node;
        ChildRef::node(index)
    }
}

/// The order in which the BVH of f3d7ed0 met the triangles: its tree (median split of the
/// longest centroid axis, leaves of at most 4 triangles, a scene of at most 64 one leaf) visited
/// depth first, right child first, every ray in the same order. That BVH kept, among hits at equal
/// t, the one it met first; ranking triangles by this order keeps its answers bit for bit
/// (coincident triangles of opposite orientation, common in BART meshes, tie exactly).
pub fn legacy_order(tris: &[Triangle]) -> Vec<u32> {
    fn visit(tris: &[Triangle], order: &mut [u32], root: bool, out: &mut Vec<u32>) {
        let (mut clo, mut chi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in order.iter() {
            let c = tris[i as usize].centroid();
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let ext = chi - clo;
        if order.len() <= 4 || (root && order.len() <= 64) || ext.max_element() <= 0.0 {
            out.extend_from_slice(order);
            return;
        }
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&a, &b| {
            tris[a as usize].centroid()[axis].total_cmp(&tris[b as usize].centroid()[axis])
        });
        let (left, right) = order.split_at_mut(mid);
        visit(tris, right, false, out);
        visit(tris, left, false, out);
    }
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let mut out = Vec::with_capacity(tris.len());
    visit(tris, &mut order, true, &mut out);
    out
}
