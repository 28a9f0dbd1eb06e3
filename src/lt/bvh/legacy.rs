//! The BVH of f3d7ed0 (binary, median split, f64 boxes padded by 10⁻⁹ of the scene's size,
//! unordered traversal), kept for the tests only: the new core must answer as it did.
#![allow(dead_code)]

use glam::DVec3;

use super::TwoNearest;
use crate::lt::shapes::Triangle;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Triangles in a leaf; 0 for an inner node.
    count: u32,
}

/// The hierarchy (triangle indices in leaf order).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    pad: f64,
}

impl Bvh {
    /// Builds over `tris`.
    pub fn build(tris: &[Triangle]) -> Self {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let magnitude = tris
            .iter()
            .flat_map(|t| t.v)
            .map(|v| v.abs().max_element())
            .fold(1.0, f64::max);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * tris.len() / 4 + 1),
            order: Vec::new(),
            pad: 1e-9 * magnitude,
        };
        if !tris.is_empty() {
            bvh.nodes.push(Node {
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
                start: 0,
                count: 0,
            });
            bvh.split(tris, &mut order, 0, 0);
        }
        bvh.order = order;
        bvh
    }

    fn split(&mut self, tris: &[Triangle], order: &mut [u32], node: usize, start: usize) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let (mut clo, mut chi) = (lo, hi);
        for &i in order.iter() {
            let (a, b) = tris[i as usize].bounds();
            lo = lo.min(a);
            hi = hi.max(b);
            let c = tris[i as usize].centroid();
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let pad = DVec3::splat(self.pad);
        self.nodes[node].lo = lo - pad;
        self.nodes[node].hi = hi + pad;
        let ext = chi - clo;
        // A scene of at most 64 triangles is one leaf: testing them all beats any tree (Cornell
        // box, 32 triangles: 3.4 M rays/s as one leaf against 2.2 M through a tree of leaves of 4).
        if order.len() <= 4 || (node == 0 && order.len() <= 64) || ext.max_element() <= 0.0 {
            self.nodes[node].start = start as u32;
            self.nodes[node].count = order.len() as u32;
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
        let left = self.nodes.len();
        self.nodes[node].start = left as u32;
        let blank = self.nodes[node];
        self.nodes.push(blank);
        self.nodes.push(blank);
        let (a, b) = order.split_at_mut(mid);
        self.split(tris, a, left, start);
        self.split(tris, b, left + 1, start + mid);
    }

    /// Over no triangles?
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.order.len() * 4
    }

    /// The two nearest triangle crossings with t > t_min, skipping triangle `skip` (the surface a
    /// photon leaves).
    pub fn two_nearest(
        &self,
        tris: &[Triangle],
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: u32,
        best: &mut TwoNearest,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            let t0 = (n.lo - o) * inv;
            let t1 = (n.hi - o) * inv;
            let near = t0.min(t1).max_element();
            let far = t0.max(t1).min_element();
            // NaN (0 · ∞: the ray lies in a slab's plane) is treated as a hit: conservative.
            if near > far || far < t_min || near > best.second.0 {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.start as usize..(n.start + n.count) as usize] {
                    if i == skip {
                        continue;
                    }
                    if let Some(t) = tris[i as usize].intersect(o, d, t_min) {
                        best.offer(t, i);
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = n.start;
                stack[top + 1] = n.start + 1;
                top += 2;
            } else {
                // Deeper than 64 levels cannot happen with median splits of < 2⁶⁰ triangles.
                unreachable!("BVH deeper than its traversal stack");
            }
        }
    }
}

impl Bvh {
    /// The nearest triangle crossing with t > t_min, skipping triangle `skip`: (t, triangle), or
    /// (+∞, `u32::MAX`). The same traversal as [`Bvh::two_nearest`], culling boxes beyond the
    /// nearest hit so far (a path tracer needs only the first hit).
    pub fn nearest(
        &self,
        tris: &[Triangle],
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: u32,
    ) -> (f64, u32) {
        let mut best = (f64::INFINITY, u32::MAX);
        if self.nodes.is_empty() {
            return best;
        }
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            let t0 = (n.lo - o) * inv;
            let t1 = (n.hi - o) * inv;
            let near = t0.min(t1).max_element();
            let far = t0.max(t1).min_element();
            if near > far || far < t_min || near > best.0 {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.start as usize..(n.start + n.count) as usize] {
                    if i == skip {
                        continue;
                    }
                    if let Some(t) = tris[i as usize].intersect(o, d, t_min) {
                        if t < best.0 {
                            best = (t, i);
                        }
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = n.start;
                stack[top + 1] = n.start + 1;
                top += 2;
            } else {
                unreachable!("BVH deeper than its traversal stack");
            }
        }
        best
    }
}
