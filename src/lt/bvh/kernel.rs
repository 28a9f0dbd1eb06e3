//! The tests traversal repeats — a ray against a node's eight boxes (f32, conservative), against
//! a block's eight triangles (an f32 filter), and against one triangle (f64, exact) — and the
//! traversal loop itself, once per instruction set: portable scalar code and AVX2 (+FMA for
//! nothing: plain mul/add/sub, so the f64 test's rounding is the scalar test's, and the AVX2
//! filter's the scalar filter's, lane by lane).
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
//!
//! # The f32 filter: why it never drops a hit that matters
//! A leaf's triangles are first tested eight at a time in f32 ([`block_scalar`], [`avx2::block`]);
//! only the lanes it cannot rule out go to the exact f64 test ([`lane`], which is
//! [`crate::lt::shapes::Triangle::intersect`] operation for operation), so every answer, and every
//! t bit, is still the f64 test's. The filter rules a lane out only where it *proves* that the f64
//! test rejects it, or returns a t beyond the cull distance (where no query's answer can change:
//! traversal already skips boxes that start there).
//!
//! The f64 test computes, from its f64 inputs d, e₁, e₂ and s = fl(o − v₀), the triple products
//! det = e₁·(d×e₂), U = s·(d×e₂), V = d·(s×e₁), T = e₂·(s×e₁), then u = U·fl(1/det), v, t
//! likewise, and hits iff det ≠ 0, u ≥ −10⁻¹², v ≥ −10⁻¹², u + v ≤ 1 + 10⁻¹², t > t_min. The
//! filter computes the same four polynomials in f32 (the same operations in the same order, no
//! division) from d, e₁, e₂, o and v₀ rounded to nearest f32, s̃ = fl₃₂(õ − ṽ₀). Write X* for the
//! exact value of X on the f64 inputs, u = 2⁻²⁴, D = max|dᵢ|, E₁, E₂ = max|e₁ᵢ|, max|e₂ᵢ|,
//! S = max|oᵢ| + max|v₀ᵢ| (≥ |sᵢ|), all rounded up. Each polynomial is a sum of six monomials
//! (±e₁ᵢdⱼe₂ₖ for det), and a chain of +, −, × evaluates to Σ monomial·Π(1 + εⱼ) over the roundings
//! on the monomial's path. For det that path has 3 input roundings, the cross product's product
//! and difference, the dot product's product and two sums: 8 roundings, so
//! |det₃₂ − det*| ≤ γ₈·6DE₁E₂ (γₖ = ku/(1 − ku)). For U, V, T one factor is s̃, whose error is
//! absolute: |s̃ᵢ − sᵢ| ≤ (2u + 2u²)(|oᵢ| + |v₀ᵢ|) + 2⁻⁵³(…) ≤ 2.01u·S; the other two factors take
//! 2 input roundings and 5 operation roundings, so |U₃₂ − U*| ≤ 6DE₂S(γ₇(1 + 2.01u) + 2.01u(1 + γ₇))
//! ≤ 9.1u·6DE₂S, and likewise V (6DE₁S) and T (6E₁E₂S). The f64 test's own values differ from X*
//! by ≤ γ₅ in 2⁻⁵³ times the same magnitudes (< 0.01u·M). With M_det = 6DE₁E₂, M_U = 6DE₂S,
//! M_V = 6DE₁S, M_T = 6E₁E₂S, the filter takes ΔX = 16u·M_X + 2⁻⁹⁰ (κ = 96u), which covers both
//! errors (≤ 9.2u·M_X) with 6.8u·M_X to spare for the roundings of the comparisons below and of ΔX
//! itself (each a few u times the same magnitudes); 2⁻⁹⁰ covers underflow: inputs are at most
//! 2²⁴ ([`F32_RANGE`](super::layout::F32_RANGE); beyond it, or not finite, a ray or a triangle gets
//! NaN magnitudes and every lane goes to f64), so each of the ≤ 64 absolute underflow errors
//! (≤ 2⁻¹⁵⁰) is multiplied by at most two factors ≤ 2²⁵: < 2⁻⁹⁵ in all.
//!
//! Let A = |det₃₂| and U′, V′, T′ the f32 values times sign(det₃₂). A lane is *decided* if
//! A > Δdet: then det* and the f64 det are non-zero with det₃₂'s sign and |det₆₄| ≤ G = A + Δdet
//! (≥ A − Δdet). A decided lane is ruled out if (K = 1.01·10⁻¹², the f64 test's 10⁻¹² with room
//! for its 2·2⁻⁵³ rounding of u = U·fl(1/det))
//! - U′ < −(ΔU + K·G): then U′₆₄ < −10⁻¹²·|det₆₄|(1 + 2⁻⁵⁰), so u < −10⁻¹²;
//! - U′ − ΔU > G + K·G: u > 1 + 10⁻¹²; and V′ < −(ΔV + K·G): v < −10⁻¹²;
//! - (U′ + V′) − 2(ΔU + ΔV) > G + K·G: the f64 fl(u + v) errs by ≤ 2⁻⁵¹(|U′| + |V′|)/|det|, far
//!   below the second ΔU + ΔV, so u + v > 1 + 10⁻¹²;
//! - T′ − ΔT > b·G·(1 + 2⁻²⁰), b ≥ 0 the cull distance rounded up to f32: t > b;
//! - T′ + ΔT < t_min·(A − Δdet)·(1 − 2⁻²⁰), t_min ≥ 0 rounded down (−∞ otherwise): t ≤ t_min.
//!
//! (the factors 1 ± 2⁻²⁰ absorb the f32 products' roundings and the f64 division's). Every
//! comparison is false on NaN, so a lane the filter must not judge is never ruled out. Tested:
//! lane by lane against the f64 test on adversarial rays (grazing edges and vertices, in and near
//! the triangle's plane, 10⁻⁷ and 10⁷ scales, origins on the surface), and whole answers against the
//! f64-only kernel.

use std::mem::MaybeUninit;

use super::layout::{
    f32_down, f32_up, Block, ChildRef, Node, Packet, BLOCK, F32_RANGE, LANES, WIDTH,
};

/// Barycentric tolerance of [`crate::lt::shapes::Triangle::intersect`].
const TOL: f64 = -1e-12;
const HI: f64 = 1.0 - TOL;

/// Stack entries: the build bounds the binary depth by 40 + log₂ n ≤ 72, so a wide node path holds
/// at most 72 nodes, each leaving at most 7 siblings on the stack.
const STACK: usize = 512;

/// The filter's κ = 96u = 6·2⁻²⁰: ΔX = κ·(product of magnitudes) + [`EPS_ABS`].
pub const KAPPA: f32 = 6.0 / (1u32 << 20) as f32;
/// The filter's absolute error term (underflow), 2⁻⁹⁰.
pub const EPS_ABS: f32 = 1.0 / (1u128 << 90) as f32;
/// The filter's barycentric tolerance, 1.01·10⁻¹² (the f64 test's 10⁻¹² and its rounding).
pub const K_TOL: f32 = 1.01e-12;
/// 1 + 2⁻²⁰ and 1 − 2⁻²⁰ (exact in f32).
const UP: f32 = 1.0 + 1.0 / (1u32 << 20) as f32;
const DOWN: f32 = 1.0 - 1.0 / (1u32 << 20) as f32;

/// Subtrees a two-nearest traversal sets aside for its second crossing (more: the second crossing
/// is found by a second traversal from the root).
pub const DEFER: usize = 128;

/// Subtrees met beyond the first crossing, kept for the second crossing (see
/// `Bvh::two_nearest`).
pub struct Deferred {
    entries: [MaybeUninit<(ChildRef, f32)>; DEFER],
    len: usize,
    /// More than [`DEFER`] were met: some were dropped.
    pub overflow: bool,
}

impl Default for Deferred {
    fn default() -> Self {
        Self::new()
    }
}

impl Deferred {
    /// None yet.
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            entries: [const { MaybeUninit::uninit() }; DEFER],
            len: 0,
            overflow: false,
        }
    }

    #[inline(always)]
    fn push(&mut self, e: (ChildRef, f32)) {
        if self.len < DEFER {
            self.entries[self.len].write(e);
            self.len += 1;
        } else {
            self.overflow = true;
        }
    }

    /// The subtrees, with their entry distances, in the order met.
    #[inline(always)]
    pub fn entries(&self) -> &[(ChildRef, f32)] {
        // SAFETY: the first `len` entries were written; MaybeUninit<T> has T's layout.
        unsafe { std::slice::from_raw_parts(self.entries.as_ptr().cast(), self.len) }
    }
}
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
    /// The filter's inputs: o and d rounded to nearest f32, κ·max|dᵢ| and max|oᵢ| rounded up (NaN
    /// when the ray is beyond [`F32_RANGE`] or not finite: every lane then goes to f64).
    pub o32: [f32; 3],
    pub d32: [f32; 3],
    pub kd: f32,
    pub o_max: f32,
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
            o32: o.map(|x| x as f32),
            d32: d.map(|x| x as f32),
            kd: f32::NAN,
            o_max: f32::NAN,
        };
        let dmax = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        // `x <= R` is false for NaN; an infinite component makes the max infinite.
        if dmax <= F32_RANGE && omax <= F32_RANGE && o.iter().chain(&d).all(|x| x.is_finite()) {
            r.kd = KAPPA * f32_up(dmax);
            r.o_max = f32_up(omax);
        }
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
    /// Subtrees entered beyond this are set aside ([`Deferred`]) rather than traversed now.
    #[inline(always)]
    fn near_bound(&self) -> f64 {
        self.bound()
    }
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

/// The t_min and the cull distance as the filter reads them: t_min ≥ 0 rounded down (else −∞),
/// the distance clamped to ≥ 0 and rounded up.
#[inline(always)]
pub fn filter_limits(t_min: f64, bound: f64) -> (f32, f32) {
    let lo = if t_min >= 0.0 {
        f32_down(t_min)
    } else {
        f32::NEG_INFINITY
    };
    (lo, f32_up(bound.max(0.0)))
}

/// Portable f32 filter (module doc, "The f32 filter"): bit `k` clear only if lane `k` of the
/// block is certainly missed by the f64 test, or hit beyond `bound`; bits of unused lanes clear.
#[inline(always)]
pub fn block_scalar(b: &Block, r: &RayData, t_min: f32, bound: f32) -> u32 {
    let d = r.d32;
    let mut miss = 0;
    for k in 0..BLOCK {
        let (e1, e2) = (
            [b.e1[0][k], b.e1[1][k], b.e1[2][k]],
            [b.e2[0][k], b.e2[1][k], b.e2[2][k]],
        );
        let p = [
            d[1] * e2[2] - e2[1] * d[2],
            d[2] * e2[0] - e2[2] * d[0],
            d[0] * e2[1] - e2[0] * d[1],
        ];
        let det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        let s = [
            r.o32[0] - b.v0[0][k],
            r.o32[1] - b.v0[1][k],
            r.o32[2] - b.v0[2][k],
        ];
        let uu = s[0] * p[0] + s[1] * p[1] + s[2] * p[2];
        let q = [
            s[1] * e1[2] - e1[1] * s[2],
            s[2] * e1[0] - e1[2] * s[0],
            s[0] * e1[1] - e1[0] * s[1],
        ];
        let vv = d[0] * q[0] + d[1] * q[1] + d[2] * q[2];
        let tt = e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2];
        let sign = det.to_bits() & 0x8000_0000;
        let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
        let (a, uu, vv, tt) = (det.abs(), flip(uu), flip(vv), flip(tt));
        let sm = r.o_max + b.v0_max[k];
        let ddet = r.kd * b.e12_max[k] + EPS_ABS;
        let du = r.kd * b.e2_max[k] * sm + EPS_ABS;
        let dv = r.kd * b.e1_max[k] * sm + EPS_ABS;
        let dt = KAPPA * b.e12_max[k] * sm + EPS_ABS;
        let g = a + ddet;
        let kg = K_TOL * g;
        let hi = g + kg;
        let out = uu < -(du + kg)
            || uu - du > hi
            || vv < -(dv + kg)
            || (uu + vv) - 2.0 * (du + dv) > hi
            || tt - dt > bound * g * UP
            || tt + dt < t_min * (a - ddet) * DOWN;
        if a > ddet && out {
            miss |= 1 << k;
        }
    }
    b.live & !miss
}

/// The exact f64 test of lane `l`: [`crate::lt::shapes::Triangle::intersect`] operation for
/// operation.
#[inline(always)]
pub fn lane(p: &Packet, l: usize, o: &[f64; 3], d: &[f64; 3], t_min: f64) -> Option<f64> {
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

    use super::{RayData, DOWN, EPS_ABS, HI, KAPPA, K_TOL, LANES, TOL, UP, WIDTH};
    use crate::lt::bvh::layout::{Block, Node, Packet, BLOCK};

    /// [`super::block_scalar`] in AVX2: the same f32 operations on eight lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub unsafe fn block(b: &Block, r: &RayData, t_min: f32, bound: f32) -> u32 {
        let ld = |x: &[f32; BLOCK]| _mm256_load_ps(x.as_ptr());
        let set = |x: f32| _mm256_set1_ps(x);
        let (mul, sub, add) = (
            |a, b| _mm256_mul_ps(a, b),
            |a, b| _mm256_sub_ps(a, b),
            |a, b| _mm256_add_ps(a, b),
        );
        let (lt, gt) = (
            |a, b| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b),
            |a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b),
        );
        let or = |a, b| _mm256_or_ps(a, b);
        let (e1x, e1y, e1z) = (ld(&b.e1[0]), ld(&b.e1[1]), ld(&b.e1[2]));
        let (e2x, e2y, e2z) = (ld(&b.e2[0]), ld(&b.e2[1]), ld(&b.e2[2]));
        let (dx, dy, dz) = (set(r.d32[0]), set(r.d32[1]), set(r.d32[2]));
        let px = sub(mul(dy, e2z), mul(e2y, dz));
        let py = sub(mul(dz, e2x), mul(e2z, dx));
        let pz = sub(mul(dx, e2y), mul(e2x, dy));
        let det = add(add(mul(e1x, px), mul(e1y, py)), mul(e1z, pz));
        let sx = sub(set(r.o32[0]), ld(&b.v0[0]));
        let sy = sub(set(r.o32[1]), ld(&b.v0[1]));
        let sz = sub(set(r.o32[2]), ld(&b.v0[2]));
        let uu = add(add(mul(sx, px), mul(sy, py)), mul(sz, pz));
        let qx = sub(mul(sy, e1z), mul(e1y, sz));
        let qy = sub(mul(sz, e1x), mul(e1z, sx));
        let qz = sub(mul(sx, e1y), mul(e1x, sy));
        let vv = add(add(mul(dx, qx), mul(dy, qy)), mul(dz, qz));
        let tt = add(add(mul(e2x, qx), mul(e2y, qy)), mul(e2z, qz));
        let signbit = set(-0.0);
        let sign = _mm256_and_ps(det, signbit);
        let a = _mm256_andnot_ps(signbit, det);
        let (uu, vv, tt) = (
            _mm256_xor_ps(uu, sign),
            _mm256_xor_ps(vv, sign),
            _mm256_xor_ps(tt, sign),
        );
        let neg = |x| _mm256_xor_ps(x, signbit);
        let sm = add(set(r.o_max), ld(&b.v0_max));
        let (kd, eps) = (set(r.kd), set(EPS_ABS));
        let e12 = ld(&b.e12_max);
        let ddet = add(mul(kd, e12), eps);
        let du = add(mul(mul(kd, ld(&b.e2_max)), sm), eps);
        let dv = add(mul(mul(kd, ld(&b.e1_max)), sm), eps);
        let dt = add(mul(mul(set(KAPPA), e12), sm), eps);
        let g = add(a, ddet);
        let kg = mul(set(K_TOL), g);
        let hi = add(g, kg);
        let out = or(
            or(
                or(lt(uu, neg(add(du, kg))), gt(sub(uu, du), hi)),
                or(
                    lt(vv, neg(add(dv, kg))),
                    gt(sub(add(uu, vv), mul(set(2.0), add(du, dv))), hi),
                ),
            ),
            or(
                gt(sub(tt, dt), mul(mul(set(bound), g), set(UP))),
                lt(add(tt, dt), mul(mul(set(t_min), sub(a, ddet)), set(DOWN))),
            ),
        );
        let miss = _mm256_and_ps(gt(a, ddet), out);
        b.live & !(_mm256_movemask_ps(miss) as u32)
    }

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
/// the tests inline into a function compiled with their instruction set). `FILTER` false tests
/// leaves with the f64 packet test alone (the kernel before the f32 filter, kept for comparison).
macro_rules! traversal {
    ($(#[$m:meta])* fn $name:ident, $node:path, $packet:path, $block:path) => {
        $(#[$m])*
        #[allow(clippy::missing_safety_doc, unused_unsafe, clippy::too_many_arguments)]
        pub unsafe fn $name<Q: Query, const FILTER: bool>(
            nodes: &[Node],
            packets: &[Packet],
            blocks: &[Block],
            start: (ChildRef, f32),
            ray: &RayData,
            t_min: f64,
            skip: u32,
            q: &mut Q,
            deferred: &mut Deferred,
        ) {
            let mut stack = [const { MaybeUninit::<(ChildRef, f32)>::uninit() }; STACK];
            stack[0].write(start);
            let mut top = 1;
            let tmin = f32_down(t_min);
            let fmin = filter_limits(t_min, 0.0).0;
            let mut ts = [0.0f64; LANES];
            let mut near = [0.0f32; WIDTH];
            // The cull distance in f32 (rounded up), recomputed only after a leaf's offers, and
            // the distance beyond which subtrees are set aside.
            let mut bound = f32_up(q.bound());
            let mut later = f32_up(q.near_bound());
            while top > 0 {
                top -= 1;
                // SAFETY: entries below `top` were written.
                let (r, entry) = unsafe { stack[top].assume_init() };
                if entry > bound {
                    continue;
                }
                if entry > later {
                    deferred.push((r, entry));
                    continue;
                }
                if r.is_leaf() {
                    let range = r.packets();
                    if FILTER {
                        let hi = bound.max(0.0);
                        for b in range.start / 2..range.end.div_ceil(2) {
                            // SAFETY: the caller checked the instruction set.
                            let mut m = unsafe { $block(&blocks[b], ray, fmin, hi) };
                            if 2 * b + 1 >= range.end {
                                m &= (1 << LANES) - 1;
                            }
                            while m != 0 {
                                let k = m.trailing_zeros() as usize;
                                m &= m - 1;
                                let (p, l) = (&packets[2 * b + k / LANES], k % LANES);
                                if p.id[l] == skip {
                                    continue;
                                }
                                if let Some(t) = lane(p, l, &ray.o, &ray.d, t_min) {
                                    if q.offer(t, p.id[l]) {
                                        return;
                                    }
                                }
                            }
                        }
                    } else {
                        for p in &packets[range] {
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
                    }
                    bound = f32_up(q.bound());
                    later = f32_up(q.near_bound());
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
    fn traverse_scalar, node_scalar, packet_scalar, block_scalar
);

#[cfg(target_arch = "x86_64")]
traversal!(
    /// Traversal with the AVX2 tests; the caller checks that the CPU has AVX2.
    #[target_feature(enable = "avx2")]
    fn traverse_avx2, avx2::node, avx2::packet, avx2::block
);
