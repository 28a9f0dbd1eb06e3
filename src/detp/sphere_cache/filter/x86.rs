//! The x86_64 filter paths: 16 lanes with AVX-512 (F + VL) and 8 with AVX2 + FMA. Both compute the
//! portable lane's `q` (see the parent module for why any rounding of it is safe) and defer lanes
//! between the two thresholds to the exact rule.

use std::arch::x86_64::*;

use super::{portable, set_lanes, Probe, RayList};
use crate::detp::store::Segment;

/// 16 lanes at a time; the tail uses masked loads. Passing lanes are compress-stored into `out`.
///
/// # Safety
/// The CPU must have AVX-512 F and VL, and `out` must be empty with capacity for 16 lanes.
#[target_feature(enable = "avx512f,avx512vl")]
pub unsafe fn avx512(src: &RayList, probe: &Probe, segments: &[Segment], out: &mut RayList) {
    let n = src.len();
    debug_assert!(out.is_empty() && out.capacity() >= 16);
    let sx = _mm512_set1_ps(probe.s[0]);
    let sy = _mm512_set1_ps(probe.s[1]);
    let sz = _mm512_set1_ps(probe.s[2]);
    let sure2 = _mm512_set1_ps(probe.sure2);
    let maybe2 = _mm512_set1_ps(probe.maybe2);
    let zero = _mm512_setzero_ps();
    let (mut outs, mut oidx, mut cap) = pointers(out);
    let ins = [
        src.ox.as_ptr(),
        src.oy.as_ptr(),
        src.oz.as_ptr(),
        src.dx.as_ptr(),
        src.dy.as_ptr(),
        src.dz.as_ptr(),
        src.te.as_ptr(),
    ];
    let mut kept = 0usize;
    let mut i = 0usize;
    while i < n {
        let lanes: __mmask16 = if n - i >= 16 {
            0xffff
        } else {
            ((1u32 << (n - i)) - 1) as u16
        };
        let ld = |p: *const f32| _mm512_maskz_loadu_ps(lanes, p.add(i));
        let v = [
            ld(ins[0]),
            ld(ins[1]),
            ld(ins[2]),
            ld(ins[3]),
            ld(ins[4]),
            ld(ins[5]),
            ld(ins[6]),
        ];
        let wx = _mm512_sub_ps(sx, v[0]);
        let wy = _mm512_sub_ps(sy, v[1]);
        let wz = _mm512_sub_ps(sz, v[2]);
        let b = _mm512_fmadd_ps(wz, v[5], _mm512_fmadd_ps(wy, v[4], _mm512_mul_ps(wx, v[3])));
        let t = _mm512_min_ps(_mm512_max_ps(b, zero), v[6]);
        let px = _mm512_fmsub_ps(v[3], t, wx);
        let py = _mm512_fmsub_ps(v[4], t, wy);
        let pz = _mm512_fmsub_ps(v[5], t, wz);
        let q = _mm512_fmadd_ps(pz, pz, _mm512_fmadd_ps(py, py, _mm512_mul_ps(px, px)));
        let mut keep = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(lanes, q, sure2);
        let mut band = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(lanes, q, maybe2) & !keep;
        while band != 0 {
            let l = band.trailing_zeros() as usize;
            band &= band - 1;
            if probe.exact(&segments[src.idx[i + l] as usize]) {
                keep |= 1 << l;
            }
        }
        if kept + 16 > cap {
            // SAFETY: lanes 0..kept of every column were written by earlier stores.
            unsafe { out.room(kept) };
            (outs, oidx, cap) = pointers(out);
        }
        if keep != 0 {
            // Compress in registers, then a full 16-lane store: the memory form of vcompressps is
            // microcoded and ~10× slower on AMD Zen 4. The lanes past `kept` are scratch that the
            // next store or `set_len` disregards (hence 16 lanes of slack in the capacity).
            for (k, &o) in outs.iter().enumerate() {
                _mm512_storeu_ps(o.add(kept), _mm512_maskz_compress_ps(keep, v[k]));
            }
            let ix = _mm512_maskz_loadu_epi32(lanes, src.idx.as_ptr().add(i).cast());
            _mm512_storeu_si512(oidx.add(kept).cast(), _mm512_maskz_compress_epi32(keep, ix));
            kept += keep.count_ones() as usize;
        }
        i += 16;
    }
    set_lanes(out, kept);
}

/// For each 8-bit mask, the lane indices of its set bits first (AVX2 has no compress: a
/// `vpermps` by this table left-packs the kept lanes).
const PACK: [[u32; 8]; 256] = {
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let mut k = 0;
        let mut l = 0;
        while l < 8 {
            if m & (1 << l) != 0 {
                t[m][k] = l as u32;
                k += 1;
            }
            l += 1;
        }
        m += 1;
    }
    t
};

/// 8 lanes at a time, kept lanes left-packed by [`PACK`] and stored as whole vectors; the tail
/// goes through the portable lane.
///
/// # Safety
/// The CPU must have AVX2 and FMA, and `out` must be empty with capacity for 16 lanes.
#[target_feature(enable = "avx2,fma")]
pub unsafe fn avx2(src: &RayList, probe: &Probe, segments: &[Segment], out: &mut RayList) {
    let n = src.len();
    debug_assert!(out.is_empty() && out.capacity() >= 16);
    let sx = _mm256_set1_ps(probe.s[0]);
    let sy = _mm256_set1_ps(probe.s[1]);
    let sz = _mm256_set1_ps(probe.s[2]);
    let sure2 = _mm256_set1_ps(probe.sure2);
    let maybe2 = _mm256_set1_ps(probe.maybe2);
    let zero = _mm256_setzero_ps();
    let (mut outs, mut oidx, mut cap) = pointers(out);
    let ins = [
        src.ox.as_ptr(),
        src.oy.as_ptr(),
        src.oz.as_ptr(),
        src.dx.as_ptr(),
        src.dy.as_ptr(),
        src.dz.as_ptr(),
        src.te.as_ptr(),
    ];
    let mut kept = 0usize;
    let mut i = 0usize;
    while i + 8 <= n {
        let ld = |p: *const f32| _mm256_loadu_ps(p.add(i));
        let v = [
            ld(ins[0]),
            ld(ins[1]),
            ld(ins[2]),
            ld(ins[3]),
            ld(ins[4]),
            ld(ins[5]),
            ld(ins[6]),
        ];
        let wx = _mm256_sub_ps(sx, v[0]);
        let wy = _mm256_sub_ps(sy, v[1]);
        let wz = _mm256_sub_ps(sz, v[2]);
        let b = _mm256_fmadd_ps(wz, v[5], _mm256_fmadd_ps(wy, v[4], _mm256_mul_ps(wx, v[3])));
        let t = _mm256_min_ps(_mm256_max_ps(b, zero), v[6]);
        let px = _mm256_fmsub_ps(v[3], t, wx);
        let py = _mm256_fmsub_ps(v[4], t, wy);
        let pz = _mm256_fmsub_ps(v[5], t, wz);
        let q = _mm256_fmadd_ps(pz, pz, _mm256_fmadd_ps(py, py, _mm256_mul_ps(px, px)));
        let mut keep = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(q, sure2)) as u32;
        let maybe = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(q, maybe2)) as u32;
        let mut band = maybe & !keep;
        while band != 0 {
            let l = band.trailing_zeros() as usize;
            band &= band - 1;
            if probe.exact(&segments[src.idx[i + l] as usize]) {
                keep |= 1 << l;
            }
        }
        if kept + 16 > cap {
            // SAFETY: lanes 0..kept of every column were written by earlier stores.
            unsafe { out.room(kept) };
            (outs, oidx, cap) = pointers(out);
        }
        if keep != 0 {
            let perm = _mm256_loadu_si256(PACK[keep as usize].as_ptr().cast());
            for (k, &o) in outs.iter().enumerate() {
                _mm256_storeu_ps(o.add(kept), _mm256_permutevar8x32_ps(v[k], perm));
            }
            let ix = _mm256_loadu_si256(src.idx.as_ptr().add(i).cast());
            _mm256_storeu_si256(oidx.add(kept).cast(), _mm256_permutevar8x32_epi32(ix, perm));
            kept += keep.count_ones() as usize;
        }
        i += 8;
    }
    set_lanes(out, kept);
    portable(src, i, probe, segments, out);
}

/// The columns' write pointers and the lanes they have room for.
#[inline]
fn pointers(out: &mut RayList) -> ([*mut f32; 7], *mut u32, usize) {
    let cap = out.capacity();
    (
        [
            out.ox.as_mut_ptr(),
            out.oy.as_mut_ptr(),
            out.oz.as_mut_ptr(),
            out.dx.as_mut_ptr(),
            out.dy.as_mut_ptr(),
            out.dz.as_mut_ptr(),
            out.te.as_mut_ptr(),
        ],
        out.idx.as_mut_ptr(),
        cap,
    )
}
