//! One segment against a list of candidate discs, four (AVX2) or eight (AVX-512) discs per
//! instruction: [`crate::detp::disc::crosses`] computed lane by lane.
//!
//! # Why every path decides exactly as `crosses` does
//! `crosses` evaluates `denom = v·n`, `w = c − o`, `num = w·n`, `t = num/denom`, `x = v·t − w` and
//! `|x|²`, each dot product as `(a_x b_x + a_y b_y) + a_z b_z` (glam's order), and accepts iff
//! `denom < 0`, `num < 0`, `t ≤ t_end` and `|x|² ≤ d·d`. The vector paths compute the same
//! products, sums and the quotient with the same IEEE operations in the same order — separate
//! multiplies and adds, never FMA (intrinsics are not contracted) — so every lane's values are
//! `crosses`' values bit for bit, and the four comparisons are ordered ones (false on NaN, as
//! `crosses`' negated comparisons reject NaN). Evaluating all four conditions where `crosses`
//! returns early changes nothing: a lane that fails one fails the conjunction. The disc records are
//! read from the index's packed `[centre, normal]` array by gathers, the radius from the per-disc
//! radii or the common one. Tests compare each path with `crosses` on random and degenerate
//! candidates.
//!
//! Branch-free lanes are the point: `denom < 0` is a coin flip for random segments, and the scalar
//! test's early returns cost a misprediction on about every other candidate.

use glam::DVec3;

use super::{LocalDiscs, SimdPath};
use crate::detp::disc::crosses;
use crate::detp::store::Segment;

/// Calls `hit(i)` for every disc `i` of `cands` that `seg` crosses ([`crosses`]' decision), in
/// the order of `cands`.
#[inline]
pub fn crossed(
    path: SimdPath,
    seg: &Segment,
    discs: &LocalDiscs,
    cands: &[u32],
    hit: &mut impl FnMut(u32),
) {
    let done = match path {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a non-scalar path is only chosen where `is_available` held (`SimdPath::detect`,
        // `all_available`; the indexes check a forced path).
        SimdPath::Avx512 => unsafe { x86::avx512(seg, discs, cands, hit) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        SimdPath::Avx2 => unsafe { x86::avx2(seg, discs, cands, hit) },
        _ => 0,
    };
    scalar(seg, discs, &cands[done..], hit);
}

/// Calls `hit(k)` for every segment `segs[k]` (k in `idx`) that crosses the disc (c, n, d)
/// ([`crosses`]' decision), in the order of `idx`: the sphere cache's test of a point against its
/// deepest list, the segments' fields gathered from the store, four or eight at a time.
#[inline]
pub fn crossing_segments(
    path: SimdPath,
    segs: &[Segment],
    idx: &[u32],
    disc: (DVec3, DVec3, f64),
    hit: &mut impl FnMut(u32),
) {
    let done = match path {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `crossed`.
        SimdPath::Avx512 => unsafe { x86::segments_avx512(segs, idx, disc, hit) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `crossed`.
        SimdPath::Avx2 => unsafe { x86::segments_avx2(segs, idx, disc, hit) },
        _ => 0,
    };
    let (c, n, d) = disc;
    for &k in &idx[done..] {
        let s = &segs[k as usize];
        if crosses(s.o(), s.d(), s.t_end(), c, n, d) {
            hit(k);
        }
    }
}

/// One candidate at a time (the portable path and the vector paths' tails).
#[inline]
fn scalar(seg: &Segment, discs: &LocalDiscs, cands: &[u32], hit: &mut impl FnMut(u32)) {
    let (o, v, t_end) = (seg.o(), seg.d(), seg.t_end());
    for &i in cands {
        let [c, n] = discs.packed[i as usize];
        if crosses(o, v, t_end, c, n, discs.discs.radius_of(i as usize)) {
            hit(i);
        }
    }
}

/// The segment's quantities, widened as `Segment::o`, `d` and `t_end` widen them.
#[inline]
fn parts(seg: &Segment) -> ([f64; 3], [f64; 3], f64) {
    let (o, v): (DVec3, DVec3) = (seg.o(), seg.d());
    (o.to_array(), v.to_array(), seg.t_end())
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use glam::DVec3;

    use super::{parts, LocalDiscs, Segment};

    /// Byte offsets of a segment's origin, direction and end in the store.
    const O: i64 = std::mem::offset_of!(Segment, origin) as i64;
    const D: i64 = std::mem::offset_of!(Segment, dir) as i64;
    const TE: i64 = std::mem::offset_of!(Segment, t_end) as i64;
    const SIZE: i64 = std::mem::size_of::<Segment>() as i64;

    /// `crosses`' arithmetic on a vector of lanes, once for both widths, in `crosses`' order (the
    /// module doc): for origins `o`, directions `v`, centres `c` and normals `n` it returns
    /// `[v·n, (c − o)·n, t, |v·t − (c − o)|²]`, each dot product `(a_x b_x + a_y b_y) + a_z b_z`.
    macro_rules! plane {
        ($name:ident, $feature:literal, $v:ty, $add:ident, $sub:ident, $mul:ident, $div:ident) => {
            #[inline]
            #[target_feature(enable = $feature)]
            unsafe fn $name(o: [$v; 3], v: [$v; 3], c: [$v; 3], n: [$v; 3]) -> [$v; 4] {
                let dot = |a: [$v; 3], b: [$v; 3]| {
                    $add($add($mul(a[0], b[0]), $mul(a[1], b[1])), $mul(a[2], b[2]))
                };
                let denom = dot(v, n);
                let w = [$sub(c[0], o[0]), $sub(c[1], o[1]), $sub(c[2], o[2])];
                let num = dot(w, n);
                let t = $div(num, denom);
                let x = [
                    $sub($mul(v[0], t), w[0]),
                    $sub($mul(v[1], t), w[1]),
                    $sub($mul(v[2], t), w[2]),
                ];
                [denom, num, t, dot(x, x)]
            }
        };
    }
    plane!(
        plane8,
        "avx512f",
        __m512d,
        _mm512_add_pd,
        _mm512_sub_pd,
        _mm512_mul_pd,
        _mm512_div_pd
    );
    plane!(
        plane4,
        "avx2",
        __m256d,
        _mm256_add_pd,
        _mm256_sub_pd,
        _mm256_mul_pd,
        _mm256_div_pd
    );

    /// The lanes `crosses` accepts, as bits: `denom < 0`, `num < 0`, `t ≤ t_end`, `|x|² ≤ r²`
    /// (ordered comparisons: false on NaN).
    #[inline]
    #[target_feature(enable = "avx512f")]
    unsafe fn accept8([denom, num, t, len2]: [__m512d; 4], te: __m512d, rr: __m512d) -> u32 {
        let zero = _mm512_setzero_pd();
        u32::from(
            _mm512_cmp_pd_mask::<_CMP_LT_OQ>(denom, zero)
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(num, zero)
                & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(t, te)
                & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(len2, rr),
        )
    }

    /// [`accept8`] on 4 lanes.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn accept4([denom, num, t, len2]: [__m256d; 4], te: __m256d, rr: __m256d) -> u32 {
        let zero = _mm256_setzero_pd();
        let ok = _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(denom, zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(num, zero),
            ),
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LE_OQ>(t, te),
                _mm256_cmp_pd::<_CMP_LE_OQ>(len2, rr),
            ),
        );
        _mm256_movemask_pd(ok) as u32
    }

    /// `hit(ids[lane])` for every set bit of `m`, in lane order.
    #[inline]
    fn report(mut m: u32, ids: &[u32], hit: &mut impl FnMut(u32)) {
        while m != 0 {
            hit(ids[m.trailing_zeros() as usize]);
            m &= m - 1;
        }
    }

    /// `crosses` for segments `idx` (gathered from `segs`, 8 at a time) against one disc; returns
    /// how many it decided.
    ///
    /// # Safety
    /// The CPU must have AVX-512 F; every index in `idx` must be below `segs.len()`.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn segments_avx512(
        segs: &[Segment],
        idx: &[u32],
        (c, n, d): (DVec3, DVec3, f64),
        hit: &mut impl FnMut(u32),
    ) -> usize {
        let base = segs.as_ptr().cast::<u8>();
        let c = c.to_array().map(|x| _mm512_set1_pd(x));
        let n = n.to_array().map(|x| _mm512_set1_pd(x));
        let dd = _mm512_set1_pd(d * d);
        let size = _mm512_set1_epi64(SIZE);
        debug_assert!(idx.iter().all(|&k| (k as usize) < segs.len()));
        let mut j = 0;
        while j + 8 <= idx.len() {
            let k = _mm512_cvtepu32_epi64(_mm256_loadu_si256(idx.as_ptr().add(j).cast()));
            // k·SIZE: `mul_epu32` multiplies the low 32 bits of each 64-bit lane (all of k) into
            // a 64-bit product (AVX-512 F; `mullo_epi64` would need DQ).
            let at = _mm512_mul_epu32(k, size);
            let g64 = |off: i64| {
                _mm512_i64gather_pd::<1>(_mm512_add_epi64(at, _mm512_set1_epi64(off)), base.cast())
            };
            let g32 = |off: i64| {
                _mm512_cvtps_pd(_mm512_i64gather_ps::<1>(
                    _mm512_add_epi64(at, _mm512_set1_epi64(off)),
                    base.cast(),
                ))
            };
            let o = [g64(O), g64(O + 8), g64(O + 16)];
            let v = [g32(D), g32(D + 4), g32(D + 8)];
            report(accept8(plane8(o, v, c, n), g32(TE), dd), &idx[j..], hit);
            j += 8;
        }
        j
    }

    /// [`segments_avx512`] 4 at a time.
    ///
    /// # Safety
    /// The CPU must have AVX2; every index in `idx` must be below `segs.len()`.
    #[target_feature(enable = "avx2")]
    pub unsafe fn segments_avx2(
        segs: &[Segment],
        idx: &[u32],
        (c, n, d): (DVec3, DVec3, f64),
        hit: &mut impl FnMut(u32),
    ) -> usize {
        let base = segs.as_ptr().cast::<u8>();
        let c = c.to_array().map(|x| _mm256_set1_pd(x));
        let n = n.to_array().map(|x| _mm256_set1_pd(x));
        let dd = _mm256_set1_pd(d * d);
        let size = _mm256_set1_epi64x(SIZE);
        debug_assert!(idx.iter().all(|&k| (k as usize) < segs.len()));
        let mut j = 0;
        while j + 4 <= idx.len() {
            let k = _mm256_cvtepu32_epi64(_mm_loadu_si128(idx.as_ptr().add(j).cast()));
            // k·SIZE without a 64-bit multiply: k < 2³², SIZE < 2³¹, `mul_epu32` takes the low
            // 32 bits of each 64-bit lane and forms the full 64-bit product.
            let at = _mm256_mul_epu32(k, size);
            let g64 = |off: i64| {
                _mm256_i64gather_pd::<1>(base.cast(), _mm256_add_epi64(at, _mm256_set1_epi64x(off)))
            };
            let g32 = |off: i64| {
                _mm256_cvtps_pd(_mm256_i64gather_ps::<1>(
                    base.cast(),
                    _mm256_add_epi64(at, _mm256_set1_epi64x(off)),
                ))
            };
            let o = [g64(O), g64(O + 8), g64(O + 16)];
            let v = [g32(D), g32(D + 4), g32(D + 8)];
            report(accept4(plane4(o, v, c, n), g32(TE), dd), &idx[j..], hit);
            j += 4;
        }
        j
    }

    /// Candidates in blocks of 8; returns how many it decided (the rest is the caller's tail).
    ///
    /// # Safety
    /// The CPU must have AVX-512 F.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn avx512(
        seg: &Segment,
        discs: &LocalDiscs,
        cands: &[u32],
        hit: &mut impl FnMut(u32),
    ) -> usize {
        let (o, v, t_end) = parts(seg);
        let o = o.map(|x| _mm512_set1_pd(x));
        let v = v.map(|x| _mm512_set1_pd(x));
        let te = _mm512_set1_pd(t_end);
        let base = discs.packed.as_ptr().cast::<f64>();
        let radii = discs.discs.radii.as_deref();
        let d = discs.discs.radius;
        let six = _mm256_set1_epi32(6);
        let mut j = 0;
        while j + 8 <= cands.len() {
            let ids = _mm256_loadu_si256(cands.as_ptr().add(j).cast());
            let at = _mm256_mullo_epi32(ids, six);
            let g = |f: usize| _mm512_i32gather_pd::<8>(at, base.add(f));
            let r = match radii {
                Some(r) => _mm512_i32gather_pd::<8>(ids, r.as_ptr()),
                None => _mm512_set1_pd(d),
            };
            let lanes = plane8(o, v, [g(0), g(1), g(2)], [g(3), g(4), g(5)]);
            report(accept8(lanes, te, _mm512_mul_pd(r, r)), &cands[j..], hit);
            j += 8;
        }
        j
    }

    /// Candidates in blocks of 4; returns how many it decided.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub unsafe fn avx2(
        seg: &Segment,
        discs: &LocalDiscs,
        cands: &[u32],
        hit: &mut impl FnMut(u32),
    ) -> usize {
        let (o, v, t_end) = parts(seg);
        let o = o.map(|x| _mm256_set1_pd(x));
        let v = v.map(|x| _mm256_set1_pd(x));
        let te = _mm256_set1_pd(t_end);
        let base = discs.packed.as_ptr().cast::<f64>();
        let radii = discs.discs.radii.as_deref();
        let d = discs.discs.radius;
        let six = _mm_set1_epi32(6);
        let mut j = 0;
        while j + 4 <= cands.len() {
            let ids = _mm_loadu_si128(cands.as_ptr().add(j).cast());
            let at = _mm_mullo_epi32(ids, six);
            let g = |f: usize| _mm256_i32gather_pd::<8>(base.add(f), at);
            let r = match radii {
                Some(r) => _mm256_i32gather_pd::<8>(r.as_ptr(), ids),
                None => _mm256_set1_pd(d),
            };
            let lanes = plane4(o, v, [g(0), g(1), g(2)], [g(3), g(4), g(5)]);
            report(accept4(lanes, te, _mm256_mul_pd(r, r)), &cands[j..], hit);
            j += 4;
        }
        j
    }
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;
    use crate::detp::disc::Discs;
    use crate::sample::lines::uniform_on_sphere;
    use crate::sample::rng::stream;

    /// Discs close to the segments (many crossings, rims within rounding, edge-on and back
    /// faces, a zero-length and an endless segment), with one radius and with radii per disc:
    /// every path reports exactly the discs `crosses` accepts.
    #[test]
    fn every_path_decides_as_crosses_does() {
        let mut rng = stream(&[0xc2055, 1]);
        let n = 300;
        let centers: Vec<DVec3> = (0..n).map(|_| uniform_on_sphere(&mut rng) * 0.3).collect();
        let mut normals: Vec<DVec3> = (0..n).map(|_| uniform_on_sphere(&mut rng)).collect();
        normals[0] = DVec3::X;
        normals[1] = DVec3::Y;
        let one = Discs::new(centers.clone(), normals.clone(), 0.2).unwrap();
        let radii: Vec<f64> = (0..n).map(|_| rng.gen_range(0.01..=0.2)).collect();
        let each = one.clone().with_radii(radii).unwrap();
        let (mut yes, mut no) = (0, 0);
        for discs in [one, each] {
            let local = LocalDiscs::new(&discs);
            for k in 0..400 {
                let o = uniform_on_sphere(&mut rng) * rng.gen_range(0.0..1.0);
                let d = match k % 5 {
                    0 => DVec3::X,
                    _ => uniform_on_sphere(&mut rng),
                };
                let t_end = match k % 4 {
                    0 => f64::INFINITY,
                    1 => 0.0,
                    _ => rng.gen_range(0.0..2.0),
                };
                let seg = Segment::new(o, d, 0.0, t_end, 1, k);
                let len = rng.gen_range(0..n);
                let cands: Vec<u32> = (0..len).map(|_| rng.gen_range(0..n as u32)).collect();
                let mut want = Vec::new();
                scalar(&seg, &local, &cands, &mut |i| want.push(i));
                let direct: Vec<u32> = cands
                    .iter()
                    .copied()
                    .filter(|&i| local.discs.crossed_by(&seg, i as usize))
                    .collect();
                assert_eq!(want, direct);
                yes += want.len();
                no += cands.len() - want.len();
                for path in SimdPath::all_available() {
                    let mut got = Vec::new();
                    crossed(path, &seg, &local, &cands, &mut |i| got.push(i));
                    assert_eq!(got, want, "{path:?}, segment {k}");
                }
            }
        }
        assert!(yes > 800 && no > 5_000, "{yes} crossings, {no} misses");
    }

    /// One disc against gathered segments (the sphere cache's deepest-list test): every path
    /// reports exactly the segments `crosses` accepts, in order, with segments aimed at the rim.
    #[test]
    fn every_path_finds_the_segments_crosses_accepts() {
        let mut rng = stream(&[0xc2055, 2]);
        let mut segs = Vec::new();
        for k in 0..3000u32 {
            let o = uniform_on_sphere(&mut rng) * rng.gen_range(0.0..1.0);
            let d = if k % 9 == 0 {
                -DVec3::Z
            } else {
                uniform_on_sphere(&mut rng)
            };
            let t_end = if k % 3 == 0 {
                f64::INFINITY
            } else {
                rng.gen_range(0.0..2.0)
            };
            segs.push(Segment::new(o, d, 0.0, t_end, 1, k));
        }
        let (mut yes, mut no) = (0, 0);
        for case in 0..200 {
            let c = uniform_on_sphere(&mut rng) * 0.2;
            let n = if case % 5 == 0 {
                DVec3::Z
            } else {
                uniform_on_sphere(&mut rng)
            };
            let d = rng.gen_range(0.05..0.6);
            let len = rng.gen_range(0..segs.len());
            let idx: Vec<u32> = (0..len)
                .map(|_| rng.gen_range(0..segs.len() as u32))
                .collect();
            let want: Vec<u32> = idx
                .iter()
                .copied()
                .filter(|&k| {
                    let s = &segs[k as usize];
                    crosses(s.o(), s.d(), s.t_end(), c, n, d)
                })
                .collect();
            yes += want.len();
            no += idx.len() - want.len();
            for path in SimdPath::all_available() {
                let mut got = Vec::new();
                crossing_segments(path, &segs, &idx, (c, n, d), &mut |k| got.push(k));
                assert_eq!(got, want, "{path:?}, case {case}");
            }
        }
        assert!(yes > 5_000 && no > 5_000, "{yes} crossings, {no} misses");
    }
}
