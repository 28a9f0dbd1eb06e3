//! The two tests traversal repeats — a ray against a node's eight boxes (f32, conservative) and
//! against a packet's four triangles (f64, exact) — and the traversal loop itself, once per
//! instruction set: portable scalar code and AVX2 (+FMA for nothing: plain mul/add/sub, so the
//! packet test's rounding is the scalar test's, lane by lane).
//!
//! # Why the f32 box test never drops a hit the f64 test would find
//! Let the ray be o + t·d in f64 and a box [lo, hi] (f32, already containing the f64 box padded by
//! `pad`). The test uses o and 1/d rounded to f32, and computes (lo − o′)·(1/d) in f32, where the
//! origin o′ is shifted *away* from the plane by a margin m = 10⁻⁶·(B + max|oᵢ|), B the largest
//! box coordinate: o + m for lower planes, o − m for upper planes (whatever the sign of d). Every
//! rounding in that expression — o to f32 (≤ 2⁻²⁴|o|), o ± m (≤ 2⁻²⁴(|o| + m)), the subtraction
//! (≤ 2⁻²⁴(B + |o| + m)), 1/d to f32 and the product (relative 2⁻²⁴ each, i.e. a shift of the
//! plane by ≤ 2⁻²³(B + |o| + m) along the axis) — moves the computed plane distance by at most
//! 5·2⁻²⁴(B + |o| + m) ≈ 3·10⁻⁷(B + |o|), less than m ≈ 9.5·10⁻⁷ … 10⁻⁶·(B + |o|). So the computed
//! entry is never later, nor the computed exit earlier, than those of the exact ray through the
//! f64 box: the f32 test accepts a superset of what exact arithmetic on the padded f64 box accepts,
//! with a margin (≥ 6·10⁻⁷·B) far above the padding of the f3d7ed0 BVH (10⁻⁹ of the scene's size).
//! NaN (0·∞: a ray lying in a dilated box face with a zero direction component) is ignored by the
//! min/max (it constrains nothing), which again only widens the interval. The t bounds are
//! rounded outward to f32 too (t_min down, the cull distance up).

use std::mem::MaybeUninit;

use super::layout::{f32_down, f32_up, ChildRef, Node, Packet, LANES, WIDTH};

/// Barycentric tolerance of [`crate::lt::shapes::Triangle::intersect`].
const TOL: f64 = -1e-12;
const HI: f64 = 1.0 - TOL;

/// Stack entries: the build bounds the binary depth by 40 + log₂ n ≤ 72, so a wide node path holds
/// at most 72 nodes, each leaving at most 7 siblings on the stack.
const STACK: usize = 512;

/// A ray as the tests read it.
#[derive(Clone, Copy, Debug)]
pub struct RayData {
    pub o: [f64; 3],
    pub d: [f64; 3],
    /// Per axis: the shifted f32 origin for the near and the far plane, 1/d in f32.
    pub org_near: [f32; 3],
    pub org_far: [f32; 3],
    pub inv: [f32; 3],
    /// Per axis: index of the near plane's row in a node (`lo` rows 0..3, `hi` rows 3..6).
    pub near_row: [usize; 3],
}

impl RayData {
    /// `bound`: the largest |coordinate| of any box (B).
    pub fn new(o: [f64; 3], d: [f64; 3], bound: f64) -> Self {
        let omax = o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let m = f32_up((bound + omax) * 1e-6);
        let mut r = Self {
            o,
            d,
            org_near: [0.0; 3],
            org_far: [0.0; 3],
            inv: [0.0; 3],
            near_row: [0; 3],
        };
        for a in 0..3 {
            let inv = (1.0 / d[a]) as f32;
            let of = o[a] as f32;
            let neg = inv.is_sign_negative();
            r.inv[a] = inv;
            // Lower planes use o + m, upper planes o − m: both push the planes outward.
            r.org_near[a] = if neg { of - m } else { of + m };
            r.org_far[a] = if neg { of + m } else { of - m };
            r.near_row[a] = if neg { 3 + a } else { a };
        }
        r
    }

    /// The far plane's row for axis `a`.
    #[inline(always)]
    fn far_row(&self, a: usize) -> usize {
        (self.near_row[a] + 3) % 6
    }
}

/// What a traversal looks for: it offers every hit (t, triangle) and culls by `bound`.
pub trait Query {
    /// No hit beyond this matters any more.
    fn bound(&self) -> f64;
    /// A hit; true stops the traversal.
    fn offer(&mut self, t: f64, id: u32) -> bool;
}

/// `max` as `_mm256_max_ps` computes it: `a` if `a > b`, else `b` (so a NaN `a` is ignored).
#[inline(always)]
fn max_ps(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn min_ps(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// Portable node test: bit `k` of the result is set if child `k`'s box meets the ray within
/// [t_min, t_max]; `near[k]` is its entry distance.
#[inline(always)]
pub fn node_scalar(n: &Node, r: &RayData, t_min: f32, t_max: f32, near: &mut [f32; WIDTH]) -> u32 {
    let rows = [&n.lo[0], &n.lo[1], &n.lo[2], &n.hi[0], &n.hi[1], &n.hi[2]];
    let mut mask = 0;
    for k in 0..WIDTH {
        let (mut tn, mut tf) = (t_min, t_max);
        for a in 0..3 {
            let a_near = (rows[r.near_row[a]][k] - r.org_near[a]) * r.inv[a];
            let a_far = (rows[r.far_row(a)][k] - r.org_far[a]) * r.inv[a];
            tn = max_ps(a_near, tn);
            tf = min_ps(a_far, tf);
        }
        near[k] = tn;
        if tn <= tf {
            mask |= 1 << k;
        }
    }
    mask
}

/// The exact f64 test of lane `l`: [`crate::lt::shapes::Triangle::intersect`] operation for
/// operation.
#[inline(always)]
fn lane(p: &Packet, l: usize, o: &[f64; 3], d: &[f64; 3], t_min: f64) -> Option<f64> {
    let (e1, e2, v0) = (
        [p.e1[0][l], p.e1[1][l], p.e1[2][l]],
        [p.e2[0][l], p.e2[1][l], p.e2[2][l]],
        [p.v0[0][l], p.v0[1][l], p.v0[2][l]],
    );
    let pv = [
        d[1] * e2[2] - e2[1] * d[2],
        d[2] * e2[0] - e2[2] * d[0],
        d[0] * e2[1] - e2[0] * d[1],
    ];
    let det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = [o[0] - v0[0], o[1] - v0[1], o[2] - v0[2]];
    let u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) * inv;
    if !(TOL..=HI).contains(&u) {
        return None;
    }
    let q = [
        s[1] * e1[2] - e1[1] * s[2],
        s[2] * e1[0] - e1[2] * s[0],
        s[0] * e1[1] - e1[0] * s[1],
    ];
    let v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if v < TOL || u + v > HI {
        return None;
    }
    let t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    (t > t_min).then_some(t)
}

/// Portable packet test: bit `l` set if lane `l` is hit at `t[l]`.
#[inline(always)]
pub fn packet_scalar(p: &Packet, r: &RayData, t_min: f64, t: &mut [f64; LANES]) -> u32 {
    let mut mask = 0;
    for (l, tl) in t.iter_mut().enumerate() {
        if let Some(x) = lane(p, l, &r.o, &r.d, t_min) {
            *tl = x;
            mask |= 1 << l;
        }
    }
    mask
}

#[cfg(target_arch = "x86_64")]
pub mod avx2 {
    //! The same two tests in AVX2: eight boxes per f32 vector, four triangles per f64 vector,
    //! every f64 operation the scalar one (no FMA), so the packet test is bit-identical.
    use std::arch::x86_64::*;

    use super::{RayData, HI, LANES, TOL, WIDTH};
    use crate::lt::bvh::layout::{Node, Packet};

    /// [`super::node_scalar`] in AVX2.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub unsafe fn node(
        n: &Node,
        r: &RayData,
        t_min: f32,
        t_max: f32,
        near: &mut [f32; WIDTH],
    ) -> u32 {
        let base = n as *const Node as *const f32;
        let mut tn = _mm256_set1_ps(t_min);
        let mut tf = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let np = _mm256_load_ps(base.add(r.near_row[a] * WIDTH));
            let fp = _mm256_load_ps(base.add(r.far_row(a) * WIDTH));
            let inv = _mm256_set1_ps(r.inv[a]);
            let a_near = _mm256_mul_ps(_mm256_sub_ps(np, _mm256_set1_ps(r.org_near[a])), inv);
            let a_far = _mm256_mul_ps(_mm256_sub_ps(fp, _mm256_set1_ps(r.org_far[a])), inv);
            // max(x, acc) returns acc when x is NaN, as the scalar test does.
            tn = _mm256_max_ps(a_near, tn);
            tf = _mm256_min_ps(a_far, tf);
        }
        _mm256_storeu_ps(near.as_mut_ptr(), tn);
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32
    }

    /// [`super::packet_scalar`] in AVX2.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub unsafe fn packet(p: &Packet, r: &RayData, t_min: f64, t: &mut [f64; LANES]) -> u32 {
        let ld = |x: &[f64; LANES]| _mm256_load_pd(x.as_ptr());
        let (e1x, e1y, e1z) = (ld(&p.e1[0]), ld(&p.e1[1]), ld(&p.e1[2]));
        let (e2x, e2y, e2z) = (ld(&p.e2[0]), ld(&p.e2[1]), ld(&p.e2[2]));
        let (dx, dy, dz) = (
            _mm256_set1_pd(r.d[0]),
            _mm256_set1_pd(r.d[1]),
            _mm256_set1_pd(r.d[2]),
        );
        let (mul, sub, add) = (
            |a, b| _mm256_mul_pd(a, b),
            |a, b| _mm256_sub_pd(a, b),
            |a, b| _mm256_add_pd(a, b),
        );
        let px = sub(mul(dy, e2z), mul(e2y, dz));
        let py = sub(mul(dz, e2x), mul(e2z, dx));
        let pz = sub(mul(dx, e2y), mul(e2x, dy));
        let det = add(add(mul(e1x, px), mul(e1y, py)), mul(e1z, pz));
        let abs = _mm256_andnot_pd(_mm256_set1_pd(-0.0), det);
        let det_ok = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_NEQ_OQ>(det, _mm256_setzero_pd()),
            _mm256_cmp_pd::<_CMP_LT_OQ>(abs, _mm256_set1_pd(f64::INFINITY)),
        );
        let inv = _mm256_div_pd(_mm256_set1_pd(1.0), det);
        let sx = sub(_mm256_set1_pd(r.o[0]), ld(&p.v0[0]));
        let sy = sub(_mm256_set1_pd(r.o[1]), ld(&p.v0[1]));
        let sz = sub(_mm256_set1_pd(r.o[2]), ld(&p.v0[2]));
        let u = mul(add(add(mul(sx, px), mul(sy, py)), mul(sz, pz)), inv);
        let (tol, hi) = (_mm256_set1_pd(TOL), _mm256_set1_pd(HI));
        let u_ok = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GE_OQ>(u, tol),
            _mm256_cmp_pd::<_CMP_LE_OQ>(u, hi),
        );
        let qx = sub(mul(sy, e1z), mul(e1y, sz));
        let qy = sub(mul(sz, e1x), mul(e1z, sx));
        let qz = sub(mul(sx, e1y), mul(e1x, sy));
        let v = mul(add(add(mul(dx, qx), mul(dy, qy)), mul(dz, qz)), inv);
        let v_bad = _mm256_or_pd(
            _mm256_cmp_pd::<_CMP_LT_OQ>(v, tol),
            _mm256_cmp_pd::<_CMP_GT_OQ>(add(u, v), hi),
        );
        let tt = mul(add(add(mul(e2x, qx), mul(e2y, qy)), mul(e2z, qz)), inv);
        let t_ok = _mm256_cmp_pd::<_CMP_GT_OQ>(tt, _mm256_set1_pd(t_min));
        let ok = _mm256_andnot_pd(v_bad, _mm256_and_pd(_mm256_and_pd(det_ok, u_ok), t_ok));
        _mm256_storeu_pd(t.as_mut_ptr(), tt);
        _mm256_movemask_pd(ok) as u32
    }
}

/// Defines a traversal over one instruction set's tests (a macro, not a generic function, so that
/// the tests inline into a function compiled with their instruction set).
macro_rules! traversal {
    ($(#[$m:meta])* fn $name:ident, $node:path, $packet:path) => {
        $(#[$m])*
        #[allow(clippy::missing_safety_doc, unused_unsafe)]
        pub unsafe fn $name<Q: Query>(
            nodes: &[Node],
            packets: &[Packet],
            root: ChildRef,
            ray: &RayData,
            t_min: f64,
            skip: u32,
            q: &mut Q,
        ) {
            let mut stack = [const { MaybeUninit::<(ChildRef, f32)>::uninit() }; STACK];
            stack[0].write((root, f32::NEG_INFINITY));
            let mut top = 1;
            let tmin = f32_down(t_min);
            let mut ts = [0.0f64; LANES];
            let mut near = [0.0f32; WIDTH];
            // The cull distance in f32 (rounded up), recomputed only after a leaf's offers.
            let mut bound = f32_up(q.bound());
            while top > 0 {
                top -= 1;
                // SAFETY: entries below `top` were written.
                let (r, entry) = unsafe { stack[top].assume_init() };
                if entry > bound {
                    continue;
                }
                if r.is_leaf() {
                    for p in &packets[r.packets()] {
                        // SAFETY: the caller checked the instruction set.
                        let mut m = unsafe { $packet(p, ray, t_min, &mut ts) };
                        while m != 0 {
                            let l = m.trailing_zeros() as usize;
                            m &= m - 1;
                            if p.id[l] != skip && q.offer(ts[l], p.id[l]) {
                                return;
                            }
                        }
                    }
                    bound = f32_up(q.bound());
                    continue;
                }
                let node = &nodes[r.index()];
                // SAFETY: as above.
                let mut m = unsafe { $node(node, ray, tmin, bound, &mut near) };
                assert!(top + WIDTH <= STACK, "BVH deeper than its traversal stack");
                // Push the hit children farthest first, so the nearest is traversed next.
                let first = top;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let e = (node.child[k], near[k]);
                    let mut i = top;
                    // SAFETY: entries first..top were written in this loop.
                    while i > first && unsafe { stack[i - 1].assume_init() }.1 < e.1 {
                        stack[i] = stack[i - 1];
                        i -= 1;
                    }
                    stack[i].write(e);
                    top += 1;
                }
            }
        }
    };
}

traversal!(
    /// Traversal with the portable tests.
    fn traverse_scalar, node_scalar, packet_scalar
);

#[cfg(target_arch = "x86_64")]
traversal!(
    /// Traversal with the AVX2 tests; the caller checks that the CPU has AVX2.
    #[target_feature(enable = "avx2")]
    fn traverse_avx2, avx2::node, avx2::packet
);
