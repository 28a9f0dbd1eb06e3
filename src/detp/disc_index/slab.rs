//! The segment–box slab test of [`super::clip`], prepared once per segment and run on eight boxes
//! at a time: an octree node's eight children ([`Boxes8`]).
//!
//! # Why every path decides exactly as `clip` does
//! `clip(o, v, b, 0, t_end)` computes, per axis k with `v_k ≠ 0`, `inv = 1/v_k`,
//! `a = (lo_k − o_k)·inv`, `c = (hi_k − o_k)·inv`, `t0 = max(t0, min(a, c))`,
//! `t1 = min(t1, max(a, c))`, and with `v_k = 0` rejects iff `o_k < lo_k` or `o_k > hi_k`; it
//! accepts iff `t0 ≤ t1` at the end. [`SlabRay`] computes `inv` by the same division once per
//! segment instead of once per box; every path then runs the same IEEE operations (subtract,
//! multiply, min, max, compare; no FMA) per lane, so each lane's values are those of `clip`,
//! bit for bit. NaN cannot arise: the origin and the boxes are finite (the driver only walks
//! segments whose origin lies within the index's reach), and `inv` is finite because a non-zero
//! direction component is a widened f32, at least 2⁻¹⁴⁹ in magnitude. Without NaN, Rust's
//! `f64::min`/`max` and the vector `min`/`max` return the same number (at most the sign of a zero
//! differs, which no later comparison sees). The tests compare every path with `clip` on random
//! and adversarial boxes.

use glam::DVec3;

use super::{clip, SimdPath};
use crate::detp::store::Segment;
use crate::geom::Aabb;

/// A segment prepared for slab tests over t ∈ [0, t_end] (the octree's parameterisation).
#[derive(Clone, Copy, Debug)]
pub struct SlabRay {
    o: [f64; 3],
    inv: [f64; 3],
    /// Axes with a zero direction component (tested by position, not by slab).
    flat: [bool; 3],
    t_end: f64,
    v: DVec3,
}

impl SlabRay {
    /// The segment's origin, direction and end, with the reciprocals `clip` would compute.
    #[inline]
    pub fn new(seg: &Segment) -> Self {
        let (o, v) = (seg.o(), seg.d());
        let va = v.to_array();
        let mut inv = [0.0; 3];
        let mut flat = [false; 3];
        for k in 0..3 {
            flat[k] = va[k] == 0.0;
            if !flat[k] {
                inv[k] = 1.0 / va[k];
            }
        }
        Self {
            o: o.to_array(),
            inv,
            flat,
            t_end: seg.t_end(),
            v,
        }
    }

    /// `clip(o, v, b, 0, t_end).is_some()`, through `clip` itself (one box: the root).
    #[inline]
    pub fn meets(&self, b: &Aabb) -> bool {
        clip(DVec3::from_array(self.o), self.v, b, 0.0, self.t_end).is_some()
    }

    /// One lane of [`Boxes8`], scalar (the portable path).
    #[inline]
    fn lane(&self, b: &Boxes8, l: usize) -> bool {
        let (mut t0, mut t1) = (0.0f64, self.t_end);
        for k in 0..3 {
            let (lo, hi, o) = (b.lo[k][l], b.hi[k][l], self.o[k]);
            if self.flat[k] {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let a = (lo - o) * self.inv[k];
            let c = (hi - o) * self.inv[k];
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
        t0 <= t1
    }
}

/// Eight boxes in structure-of-arrays form (one cache-line row per coordinate): 448 bytes, the
/// size of eight [`super::octree`] nodes of 56 bytes.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Boxes8 {
    /// Low corners: `lo[axis][lane]`.
    pub lo: [[f64; 8]; 3],
    /// High corners.
    pub hi: [[f64; 8]; 3],
    /// Per lane: an inner child's block, or a leaf's first item.
    pub first: [u32; 8],
    /// Per lane: a leaf's disc count, or [`super::octree::INNER`].
    pub count: [u32; 8],
}

const _: () = assert!(std::mem::size_of::<Boxes8>() == 448);

impl SimdPath {
    /// Bit l set iff the segment meets box l (as `clip` decides it).
    #[inline]
    pub fn test8(self, r: &SlabRay, b: &Boxes8) -> u8 {
        match self {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: a `SimdPath` other than `Scalar` is only used where `is_available` held
            // (`detect`, `all_available`; the octree checks a forced path).
            Self::Avx512 => unsafe { x86::test8_avx512(r, b) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Self::Avx2 => unsafe { x86::test8_avx2(r, b) },
            _ => (0..8).fold(0u8, |m, l| m | (u8::from(r.lane(b, l)) << l)),
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::{Boxes8, SlabRay};

    /// # Safety
    /// The CPU must have AVX-512 F.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn test8_avx512(r: &SlabRay, b: &Boxes8) -> u8 {
        let mut t0 = _mm512_setzero_pd();
        let mut t1 = _mm512_set1_pd(r.t_end);
        let mut inside: __mmask8 = 0xff;
        for k in 0..3 {
            let lo = _mm512_load_pd(b.lo[k].as_ptr());
            let hi = _mm512_load_pd(b.hi[k].as_ptr());
            let o = _mm512_set1_pd(r.o[k]);
            if r.flat[k] {
                inside &= _mm512_cmp_pd_mask::<_CMP_GE_OQ>(o, lo)
                    & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(o, hi);
                continue;
            }
            let inv = _mm512_set1_pd(r.inv[k]);
            let a = _mm512_mul_pd(_mm512_sub_pd(lo, o), inv);
            let c = _mm512_mul_pd(_mm512_sub_pd(hi, o), inv);
            t0 = _mm512_max_pd(t0, _mm512_min_pd(a, c));
            t1 = _mm512_min_pd(t1, _mm512_max_pd(a, c));
        }
        inside & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(t0, t1)
    }

    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub unsafe fn test8_avx2(r: &SlabRay, b: &Boxes8) -> u8 {
        let mut t0 = [_mm256_setzero_pd(); 2];
        let mut t1 = [_mm256_set1_pd(r.t_end); 2];
        let mut inside = [_mm256_castsi256_pd(_mm256_set1_epi64x(-1)); 2];
        for k in 0..3 {
            let o = _mm256_set1_pd(r.o[k]);
            let inv = _mm256_set1_pd(r.inv[k]);
            for h in 0..2 {
                let lo = _mm256_load_pd(b.lo[k].as_ptr().add(4 * h));
                let hi = _mm256_load_pd(b.hi[k].as_ptr().add(4 * h));
                if r.flat[k] {
                    let ok = _mm256_and_pd(
                        _mm256_cmp_pd::<_CMP_GE_OQ>(o, lo),
                        _mm256_cmp_pd::<_CMP_LE_OQ>(o, hi),
                    );
                    inside[h] = _mm256_and_pd(inside[h], ok);
                    continue;
                }
                let a = _mm256_mul_pd(_mm256_sub_pd(lo, o), inv);
                let c = _mm256_mul_pd(_mm256_sub_pd(hi, o), inv);
                t0[h] = _mm256_max_pd(t0[h], _mm256_min_pd(a, c));
                t1[h] = _mm256_min_pd(t1[h], _mm256_max_pd(a, c));
            }
        }
        let pass = |h: usize| _mm256_and_pd(inside[h], _mm256_cmp_pd::<_CMP_LE_OQ>(t0[h], t1[h]));
        (_mm256_movemask_pd(pass(0)) | _mm256_movemask_pd(pass(1)) << 4) as u8
    }
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;
    use crate::sample::rng::stream;

    /// Segments and boxes that share coordinates, touch, contain the origin, and lie behind it,
    /// with zero, tiny and −0 direction components: every path must give `clip`'s answer.
    #[test]
    fn every_path_decides_as_clip_does() {
        let mut rng = stream(&[0x51ab, 1]);
        let grid = [-1.0, -0.5, 0.0, 0.25, 0.5, 1.0];
        let pick = |rng: &mut crate::sample::rng::Stream| -> f64 {
            if rng.gen_bool(0.5) {
                grid[rng.gen_range(0..grid.len())]
            } else {
                rng.gen_range(-1.2..1.2)
            }
        };
        let (mut met, mut missed) = (0, 0);
        for case in 0..20_000 {
            let o = DVec3::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
            let mut d = [0.0f32; 3];
            for dk in &mut d {
                *dk = match rng.gen_range(0..6) {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 1e-30 * if rng.gen_bool(0.5) { 1.0 } else { -1.0 },
                    3 => f32::from_bits(1),
                    _ => rng.gen_range(-1.0f32..1.0),
                };
            }
            if d.iter().all(|&x| x == 0.0) {
                d[case % 3] = 1.0;
            }
            let t_end = match case % 4 {
                0 => f32::INFINITY,
                1 => 0.0,
                _ => rng.gen_range(0.0f32..3.0),
            };
            let seg = Segment {
                origin: o.to_array(),
                dir: d,
                t_hit: t_end,
                t_end,
                power: 1,
                photon: 0,
                bounce: 0,
                flags: 0,
            };
            let ray = SlabRay::new(&seg);
            let mut b = Boxes8 {
                lo: [[0.0; 8]; 3],
                hi: [[0.0; 8]; 3],
                first: [0; 8],
                count: [0; 8],
            };
            let mut want = 0u8;
            for l in 0..8 {
                for k in 0..3 {
                    let (p, q) = (pick(&mut rng), pick(&mut rng));
                    (b.lo[k][l], b.hi[k][l]) = (p.min(q), p.max(q));
                }
                let bx = Aabb::new(
                    DVec3::new(b.lo[0][l], b.lo[1][l], b.lo[2][l]),
                    DVec3::new(b.hi[0][l], b.hi[1][l], b.hi[2][l]),
                );
                let hit = clip(seg.o(), seg.d(), &bx, 0.0, seg.t_end()).is_some();
                assert_eq!(ray.meets(&bx), hit);
                want |= u8::from(hit) << l;
            }
            met += want.count_ones();
            missed += 8 - want.count_ones();
            for path in SimdPath::all_available() {
                assert_eq!(path.test8(&ray, &b), want, "{path:?}, case {case}");
            }
        }
        assert!(
            met > 10_000 && missed > 10_000,
            "{met} met, {missed} missed"
        );
    }
}
