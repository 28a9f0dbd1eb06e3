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
//!
//! # Why the f32 triangle pre-test never drops a hit the f64 test would find
//! Before a leaf's packets get the exact f64 test, [`avx2::keep`] runs Möller–Trumbore without its
//! division in f32 on two packets at once (eight lanes) and clears the lanes it can *prove* the f64
//! test rejects; the f64 test then runs, unchanged, on every packet with a lane left, so answers
//! are bit for bit those of [`crate::lt::shapes::Triangle::intersect`]. With the f64 inputs o, d,
//! v₀, e₁, e₂ taken as exact reals, s = o − v₀, p = d × e₂, q = s × e₁, the exact values are
//! D = e₁·p, U = s·p, V = d·q, T = e₂·q, and the f64 test accepts iff D ≠ 0, u = U/D ∈ [τ, 1 − τ],
//! v = V/D ≥ τ, u + v ≤ 1 − τ and t = T/D > t_min (τ = −10⁻¹², each quotient with two f64
//! roundings). Write ε = 2⁻²⁴, R = max|oᵢ|, Vm = max|v₀ᵢ|, Dm = max|dᵢ|, E₁ = max|e₁ᵢ|,
//! E₂ = max|e₂ᵢ| (all rounded up to f32), S the largest |component| of the f32 s. Each input
//! rounded to f32 moves by ≤ ε of itself, each f32 operation by ≤ ε of its result, so
//! - s: |Δs| ≤ eS = 4ε(R + Vm) + κ (two roundings of the inputs, one of the difference), and
//!   every |sᵢ| ≤ Sb = S + eS;
//! - D: |ΔD| ≤ 48ε·E₁·Dm·E₂ ≤ eD = 128ε·E₁·Dm·E₂ + κ;
//! - U: |ΔU| ≤ 6·Dm·E₂·eS + 42ε·Sb·Dm·E₂ ≤ eU = 16·Dm·E₂·(eS + 8ε·Sb) + κ, and V, T alike
//!   (eV with Dm·E₁, eT with E₁·E₂: the same counts).
//!
//! κ = 2⁻¹⁰⁰ covers gradual underflow (≤ 2⁻¹⁵⁰ per operation, times factors ≤ 2³² that follow),
//! and the domain (every magnitude ≤ 2³⁰, else the bounds are +∞ and nothing is rejected) keeps
//! every product below f32's overflow. The f64 evaluation's own error (≤ 2⁻⁴⁸ of the same
//! magnitudes) and the f32 rounding of the comparisons below (≤ 2ε of each side, i.e. ≤ 12ε·E₁Dm·E₂
//! and ≤ 12ε·Sb·Dm·E) fit in the slack between the counts and the factors (80ε·E₁DmE₂ and
//! ≥ 86ε·Sb·Dm·E). With C = |D̄| > eD the sign σ of D is known (the lane is otherwise kept), and
//! with A = σŪ, B = σV̄, C′ = C + eD ≥ |D|, g = 2·10⁻¹²·C′, a lane is rejected when
//! A + eU + g < 0 (u < τ), A − eU − g > C′ (u > 1 − τ), B + eV + g < 0 (v < τ),
//! A + B − (eU + g) − (eV + g) > C′ (u + v > 1 − τ), or σT̄ + eT < t_min·(C − eD) with t_min ≥ 0
//! rounded down to f32 (t ≤ t_min; for t_min < 0 this test is off). Each comparison is false on
//! NaN, so a NaN anywhere keeps the lane. Tested on adversarial triangles and rays (every
//! rejected lane is an f64 miss) and through every traversal against the portable path, which has
//! no pre-test.

use std::mem::MaybeUninit;

use super::layout::{
    f32_down, f32_up, ChildRef, Node, Packet, PacketF32, F32_DOMAIN, LANES, WIDTH,
};

/// Barycentric tolerance of [`crate::lt::shapes::Triangle::intersect`].
const TOL: f64 = -1e-12;
const HI: f64 = 1.0 - TOL;
/// The f32 pre-test's absolute slack for gradual underflow, 2⁻¹⁰⁰ (module doc).
const KAPPA: f32 = f32::from_bits(27 << 23);

/// Subtrees a first pass keeps for the second to resume from ([`Culled`]), at most.
pub const CULLED: usize = 64;

/// Stack entries: the build bounds the binary depth by 40 + log₂ n ≤ 72, so a wide node path holds
/// at most 72 nodes, each leaving at most 7 siblings on the stack (504), plus a resumed pass's
/// starting subtrees.
const STACK: usize = 512 + CULLED;

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
    /// The triangle pre-test's ray: o and d rounded to the nearest f32.
    pub o32: [f32; 3],
    pub d32: [f32; 3],
    /// max |oᵢ| and max |dᵢ| rounded up; `dmag` is +∞ when either exceeds
    /// [`F32_DOMAIN`](super::layout::F32_DOMAIN) or is not finite, or until
    /// [`RayData::with_pretest`] sets them (the pre-test then keeps every lane).
    pub omag: f32,
    pub dmag: f32,
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
            o32: [0.0; 3],
            d32: [0.0; 3],
            omag: f32::INFINITY,
            dmag: f32::INFINITY,
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

    /// The same ray with the f32 triangle pre-test's fields set (without them `dmag` is +∞ and
    /// the pre-test keeps every lane): only the pre-test path pays for them.
    pub fn with_pretest(mut self) -> Self {
        let (o, d) = (self.o, self.d);
        let omax = o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let dmax = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        self.o32 = o.map(|x| x as f32);
        self.d32 = d.map(|x| x as f32);
        self.omag = f32_up(omax);
        if omax <= F32_DOMAIN && dmax <= F32_DOMAIN && o.iter().chain(&d).all(|x| x.is_finite()) {
            self.dmag = f32_up(dmax);
        }
        self
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

/// The portable path has no pre-test: every live lane of `a` and `b` goes to the f64 test.
#[inline(always)]
pub fn keep_all(a: &PacketF32, b: &PacketF32, _: &RayData, _: f32) -> u32 {
    a.live | b.live << LANES
}

/// t_min as the pre-test takes it: rounded down to f32 if t_min ≥ 0, else −∞ (its t test is off).
#[inline(always)]
pub fn pretest_t_min(t_min: f64) -> f32 {
    if t_min >= 0.0 {
        f32_down(t_min)
    } else {
        f32::NEG_INFINITY
    }
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

    use super::{RayData, HI, KAPPA, LANES, TOL, WIDTH};
    use crate::lt::bvh::layout::{Node, Packet, PacketF32};

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

    /// The f32 pre-test (module doc) of packets `a` and `b` (lanes 0–3 and 4–7): bit k set
    /// unless lane k is empty or provably missed at t > t_min, where `t_lo` is t_min rounded down
    /// to f32 if t_min ≥ 0, else −∞.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub unsafe fn keep(a: &PacketF32, b: &PacketF32, r: &RayData, t_lo: f32) -> u32 {
        let ld = |x: &[f32; LANES], y: &[f32; LANES]| {
            _mm256_set_m128(_mm_loadu_ps(y.as_ptr()), _mm_loadu_ps(x.as_ptr()))
        };
        let rows = |x: &[[f32; LANES]; 3], y: &[[f32; LANES]; 3]| {
            [ld(&x[0], &y[0]), ld(&x[1], &y[1]), ld(&x[2], &y[2])]
        };
        let s1 = |x: f32| _mm256_set1_ps(x);
        let (mul, sub, add) = (
            |x, y| _mm256_mul_ps(x, y),
            |x, y| _mm256_sub_ps(x, y),
            |x, y| _mm256_add_ps(x, y),
        );
        let cross = |u: [__m256; 3], v: [__m256; 3]| {
            [
                sub(mul(u[1], v[2]), mul(v[1], u[2])),
                sub(mul(u[2], v[0]), mul(v[2], u[0])),
                sub(mul(u[0], v[1]), mul(v[0], u[1])),
            ]
        };
        let dot = |u: [__m256; 3], v: [__m256; 3]| {
            add(add(mul(u[0], v[0]), mul(u[1], v[1])), mul(u[2], v[2]))
        };
        let (e1, e2, v0) = (rows(&a.e1, &b.e1), rows(&a.e2, &b.e2), rows(&a.v0, &b.v0));
        let d = r.d32.map(s1);
        let s = [
            sub(s1(r.o32[0]), v0[0]),
            sub(s1(r.o32[1]), v0[1]),
            sub(s1(r.o32[2]), v0[2]),
        ];
        let p = cross(d, e2);
        let det = dot(e1, p);
        let uu = dot(s, p);
        let q = cross(s, e1);
        let vv = dot(d, q);
        let tt = dot(e2, q);
        // The error bounds of the module doc.
        let sign_bit = s1(-0.0);
        let abs = |x| _mm256_andnot_ps(sign_bit, x);
        let (vm, e1m, e2m) = (
            ld(&a.mag[0], &b.mag[0]),
            ld(&a.mag[1], &b.mag[1]),
            ld(&a.mag[2], &b.mag[2]),
        );
        const EPS: f32 = f32::EPSILON / 2.0;
        let kappa = s1(KAPPA);
        let es = add(mul(s1(4.0 * EPS), add(s1(r.omag), vm)), kappa);
        let smax = _mm256_max_ps(_mm256_max_ps(abs(s[0]), abs(s[1])), abs(s[2]));
        let sb = add(smax, es);
        let dm = s1(r.dmag);
        let ed = add(mul(mul(s1(128.0 * EPS), e1m), mul(dm, e2m)), kappa);
        let w = mul(s1(16.0), add(es, mul(s1(8.0 * EPS), sb)));
        let eu = add(mul(mul(dm, e2m), w), kappa);
        let ev = add(mul(mul(dm, e1m), w), kappa);
        let et = add(mul(mul(e1m, e2m), w), kappa);
        // Sign-normalised: A = σU, B = σV, σT; C = |D|.
        let sign = _mm256_and_ps(det, sign_bit);
        let c = abs(det);
        let (au, bv, ts) = (
            _mm256_xor_ps(uu, sign),
            _mm256_xor_ps(vv, sign),
            _mm256_xor_ps(tt, sign),
        );
        let ce = add(c, ed);
        let g = mul(s1(2e-12), ce);
        let (mu, mv) = (add(eu, g), add(ev, g));
        let lt = |x, y| _mm256_cmp_ps::<_CMP_LT_OQ>(x, y);
        let gt = |x, y| _mm256_cmp_ps::<_CMP_GT_OQ>(x, y);
        let or = |x, y| _mm256_or_ps(x, y);
        let zero = _mm256_setzero_ps();
        let bary = or(
            or(lt(add(au, mu), zero), gt(sub(au, mu), ce)),
            or(lt(add(bv, mv), zero), gt(sub(add(au, bv), add(mu, mv)), ce)),
        );
        let behind = lt(add(ts, et), mul(s1(t_lo), sub(c, ed)));
        let reject = _mm256_and_ps(gt(c, ed), or(bary, behind));
        !(_mm256_movemask_ps(reject) as u32) & (a.live | b.live << LANES)
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

/// What a traversal walks: the nodes, the packets, their f32 copies, the root, and where it
/// starts (the root, or the subtrees an earlier pass culled).
#[derive(Clone, Copy)]
pub struct Tree<'a> {
    pub nodes: &'a [Node],
    pub packets: &'a [Packet],
    pub pretest: &'a [PacketF32],
    pub root: ChildRef,
    pub start: Option<&'a Culled>,
}

/// Where a traversal puts the subtrees it culls (a box that starts beyond the distance that still
/// matters): nowhere ([`Forget`]), or a list a later pass resumes from ([`Culled`]).
pub trait Deferred {
    /// Whether culled subtrees are kept: node tests then run to +∞ and cull by entry afterwards,
    /// which passes the same children as testing to the bound (tn ≤ min(exit, b) ⇔ tn ≤ exit and
    /// tn ≤ b).
    const KEEP: bool;
    /// A culled subtree and its entry distance.
    fn keep(&mut self, c: ChildRef, entry: f32);
}

/// Culled subtrees are dropped (every query but the first pass of the two-nearest query).
pub struct Forget;

impl Deferred for Forget {
    const KEEP: bool = false;
    #[inline(always)]
    fn keep(&mut self, _: ChildRef, _: f32) {}
}

/// Up to [`CULLED`] culled subtrees; past that `overflow` is set and the list is not complete.
pub struct Culled {
    list: [MaybeUninit<(ChildRef, f32)>; CULLED],
    len: usize,
    /// More were culled than the list holds.
    pub overflow: bool,
}

impl Culled {
    /// An empty list.
    pub fn new() -> Self {
        Self {
            list: [const { MaybeUninit::uninit() }; CULLED],
            len: 0,
            overflow: false,
        }
    }

    /// Orders the list so that a traversal starting from it pops the nearest subtree first.
    pub fn sort_far_first(&mut self) {
        // SAFETY: entries below `len` were written.
        let kept = &mut self.list[..self.len];
        kept.sort_unstable_by(|a, b| unsafe { b.assume_init().1.total_cmp(&a.assume_init().1) });
    }

    /// The subtrees kept, in their order (the last is popped first).
    pub fn entries(&self) -> impl Iterator<Item = (ChildRef, f32)> + '_ {
        // SAFETY: entries below `len` were written.
        self.list[..self.len]
            .iter()
            .map(|e| unsafe { e.assume_init() })
    }
}

impl Default for Culled {
    fn default() -> Self {
        Self::new()
    }
}

impl Deferred for Culled {
    const KEEP: bool = true;
    #[inline(always)]
    fn keep(&mut self, c: ChildRef, entry: f32) {
        if self.len < CULLED {
            self.list[self.len].write((c, entry));
            self.len += 1;
        } else {
            self.overflow = true;
        }
    }
}

/// The exact test of one packet inside a traversal: offers each hit (but triangle `skip`) to the
/// query, and returns from the traversal when the query says stop.
macro_rules! exact_test {
    ($packet:path, $p:expr, $ray:expr, $t_min:expr, $ts:ident, $skip:expr, $q:expr) => {
        let p = $p;
        // SAFETY: the traversal's caller checked the instruction set.
        let mut m = unsafe { $packet(p, $ray, $t_min, &mut $ts) };
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            if p.id[l] != $skip && $q.offer($ts[l], p.id[l]) {
                return;
            }
        }
    };
}

/// Defines a traversal over one instruction set's tests (a macro, not a generic function, so that
/// the tests inline into a function compiled with their instruction set).
macro_rules! traversal {
    ($(#[$m:meta])* fn $name:ident, $node:path, $keep:path, $packet:path, $pretest:expr) => {
        $(#[$m])*
        #[allow(clippy::missing_safety_doc, unused_unsafe)]
        pub unsafe fn $name<Q: Query, D: Deferred>(
            tree: &Tree<'_>,
            ray: &RayData,
            t_min: f64,
            skip: u32,
            q: &mut Q,
            culled: &mut D,
        ) {
            let Tree { nodes, packets, pretest, root, start } = *tree;
            let mut stack = [const { MaybeUninit::<(ChildRef, f32)>::uninit() }; STACK];
            // From the root, or from the subtrees an earlier pass culled.
            let mut top = 0;
            match start {
                None => {
                    stack[0].write((root, f32::NEG_INFINITY));
                    top = 1;
                }
                Some(list) => {
                    for e in list.entries() {
                        stack[top].write(e);
                        top += 1;
                    }
                }
            }
            let tmin = f32_down(t_min);
            let t_lo = pretest_t_min(t_min);
            let mut ts = [0.0f64; LANES];
            let mut near = [0.0f32; WIDTH];
            // The cull distance in f32 (rounded up), recomputed only after a leaf's offers.
            let mut bound = f32_up(q.bound());
            while top > 0 {
                top -= 1;
                // SAFETY: entries below `top` were written.
                let (r, entry) = unsafe { stack[top].assume_init() };
                if entry > bound {
                    culled.keep(r, entry);
                    continue;
                }
                if r.is_leaf() {
                    let range = r.packets();
                    if !$pretest {
                        for p in &packets[range] {
                            exact_test!($packet, p, ray, t_min, ts, skip, q);
                        }
                        bound = f32_up(q.bound());
                        continue;
                    }
                    // Packets in pairs through the pre-test (a last odd one goes straight to the
                    // exact test), then the exact test on each packet it left a lane in.
                    let mut i = range.start;
                    while i < range.end {
                        let j = (i + 1).min(range.end - 1);
                        let kept = if j > i {
                            // SAFETY: the caller checked the instruction set.
                            unsafe { $keep(&pretest[i], &pretest[j], ray, t_lo) }
                        } else {
                            0xF
                        };
                        let halves = [(i, kept & 0xF), (j, if j > i { kept >> LANES } else { 0 })];
                        for (k, half) in halves {
                            if half == 0 {
                                continue;
                            }
                            exact_test!($packet, &packets[k], ray, t_min, ts, skip, q);
                        }
                        i += 2;
                    }
                    bound = f32_up(q.bound());
                    continue;
                }
                let node = &nodes[r.index()];
                // SAFETY: as above.
                let t_max = if D::KEEP { f32::INFINITY } else { bound };
                let mut m = unsafe { $node(node, ray, tmin, t_max, &mut near) };
                assert!(top + WIDTH <= STACK, "BVH deeper than its traversal stack");
                // Push the hit children farthest first, so the nearest is traversed next.
                let first = top;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let e = (node.child[k], near[k]);
                    if D::KEEP && e.1 > bound {
                        culled.keep(e.0, e.1);
                        continue;
                    }
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
    fn traverse_scalar, node_scalar, keep_all, packet_scalar, false
);

#[cfg(target_arch = "x86_64")]
traversal!(
    /// Traversal with the AVX2 tests; the caller checks that the CPU has AVX2.
    #[target_feature(enable = "avx2")]
    fn traverse_avx2, avx2::node, keep_all, avx2::packet, false
);

#[cfg(target_arch = "x86_64")]
traversal!(
    /// Traversal with the AVX2 tests and the f32 triangle pre-test before the exact one (module
    /// doc); the caller checks that the CPU has AVX2. Same answers as [`traverse_avx2`], measured
    /// slower (docs/bench.md), so only chosen on request.
    #[target_feature(enable = "avx2")]
    fn traverse_avx2_pretest, avx2::node, avx2::keep, avx2::packet, true
);
