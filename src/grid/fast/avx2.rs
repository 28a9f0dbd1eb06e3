//! The pipelined AVX2 walk of [`FastGrid`]: the same cells, listings, filter and stopping rule as
//! the portable walk (and so as the counting tracer), arranged so that memory latency overlaps.
//!
//! - **Pipeline.** The 3D-DDA runs `lookahead.0` cells (default 6) ahead of the cell being tested
//!   and prefetches each new cell's offsets; `lookahead.1` cells (default 3) ahead it reads the
//!   offsets (now cached) and prefetches the cell's records. On this machine DRAM answers in
//!   125–170 ns and a cell takes ~40–60 ns, so three cells of lead cover a record miss.
//! - **Exact walk.** Four f64 lanes (x, y, z, unused), branch-free: the axis of the nearest face is
//!   found with vector min/compare, ties go to the lowest axis exactly as in [`Dda`], and every
//!   boundary distance is [`Dda`]'s formula `((origin + k·a) − o)·(1/d)` (no FMA), so the cells and
//!   their exit distances are bit for bit those of [`Dda`]. (The first scalar version selected the
//!   axis with `if`s that compiled to branches and mispredicted about every other step.)
//! - **Filter.** Eight listings per instruction, with the same f32 operations in the same order as
//!   [`super::passes`], so both walks count the same candidates.
//!
//! Cost (callgrind, n = 10⁶, a = 2.36): ~4 400 instructions per ray for 17.3 cells: the filter ~32
//! per 8 listings (30 %), the walk ~55 per cell (28 %), per-ray set-up ~420 (10 %). Tried and
//! measured no better, so not kept: filtering two cells ahead and prefetching the candidates' exact
//! data (the records had not arrived yet; with a deeper pipeline, the bookkeeping cost what the
//! prefetch saved), prefetching every listing's exact data (1.4× slower: bandwidth), deeper
//! lookahead (flat from 4 to 12 cells), batching the walk four cells at a time (more spills, not
//! fewer), non-temporal record prefetches, and 4×4×4-brick or Morton cell orders instead of the
//! linear one (equal once the arrays sit on huge pages).

use std::arch::x86_64::*;

use super::{FastGrid, FastTrace, Hit, QBITS, QMAX};
use crate::geom::Ray;
use crate::grid::dda::start_cell;

/// Ring of cells computed ahead; a power of two above the lookahead.
const RING: usize = 16;

/// One cell of the walk, computed ahead of its test.
#[derive(Clone, Copy, Default)]
struct Ahead {
    /// The filter's per-cell constants `[w_x, w_y, w_z, o'·d]`.
    w: [f32; 4],
    t_exit: f64,
    slot: u32,
    /// The walk leaves the grid after this cell.
    last: bool,
    lo: u32,
    hi: u32,
}

/// Lane masks selecting axis x, y or z (index = the axis).
static ONE_HOT: [[i64; 4]; 3] = [[-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0]];

/// Defines an entry point of the walk, filtering 16 listings per step (`WIDE`, AVX-512) or 8
/// (AVX2). A macro rather than a generic function: the closures of the walk must be compiled
/// with the entry point's instruction sets (closures inherit `#[target_feature]`), or LLVM leaves
/// them and the intrinsics in them out of line (measured: a generic `#[inline(always)]` walk
/// called from two `#[target_feature]` functions kept `advance` as a call with every intrinsic
/// inside it a call).
macro_rules! walk {
    ($(#[$m:meta])* fn $name:ident, WIDE = $wide:literal) => {
        $(#[$m])*
        pub(super) unsafe fn $name(g: &FastGrid, ray: &Ray) -> FastTrace {
            const WIDE: bool = $wide;
            let frame = &g.frame;
            let a = frame.width;
            let (o, d, g0) = (ray.o, ray.d, frame.origin);
            let k0 = start_cell(frame, ray);
            let set = |x: f64, y: f64, z: f64, w: f64| _mm256_set_pd(w, z, y, x);
            // Walk constants per axis (lane 3 is unused). An axis the ray does not move along gets
            // 1/d = +∞ and a boundary two cells up, so its distance is +∞ (as in Dda) without a separate
            // case; the index at which an axis leaves the grid is NaN (never equal) for such an axis.
            let (mut inv, mut kofs, mut step, mut exit) =
                ([f64::INFINITY; 4], [2.0; 4], [0.0; 4], [f64::NAN; 4]);
            for (i, di) in d.to_array().into_iter().enumerate() {
                if di > 0.0 {
                    (inv[i], kofs[i], step[i], exit[i]) = (1.0 / di, 1.0, 1.0, g.dims[i] as f64);
                } else if di < 0.0 {
                    (inv[i], kofs[i], step[i], exit[i]) = (1.0 / di, 0.0, -1.0, -1.0);
                }
            }
            let (v_inv, v_kofs) = (
                _mm256_loadu_pd(inv.as_ptr()),
                _mm256_loadu_pd(kofs.as_ptr()),
            );
            let (v_step, v_exit) = (
                _mm256_loadu_pd(step.as_ptr()),
                _mm256_loadu_pd(exit.as_ptr()),
            );
            let v_g = set(g0.x, g0.y, g0.z, 0.0);
            let v_o = set(o.x, o.y, o.z, 0.0);
            let v_a = _mm256_set1_pd(a);
            // Slot of the current cell (x + nx·(y + ny·z)), and its change per step along each axis.
            let stride = [1, g.dims[0], g.dims[0] * g.dims[1]];
            let mut slot = k0[0] + g.dims[0] * (k0[1] + g.dims[1] * k0[2]);
            let dslot = [0, 1, 2].map(|i| stride[i] * step[i] as i64);
            // Filter constants: the ray origin relative to cell 0's quantisation corner, in steps.
            let v_d = set(d.x, d.y, d.z, 0.0);
            let rel = |o: f64, g0: f64| (o - g0 + g.reach) / g.qstep;
            let v_cq = set(rel(o.x, g0.x), rel(o.y, g0.y), rel(o.z, g0.z), 0.0);
            let v_aq = _mm256_set1_pd(a / g.qstep);
            // Boundary distance before the lower bound by the entry distance (Dda::boundary_t).
            let raw = |k: __m256d| {
                let b = _mm256_add_pd(v_g, _mm256_mul_pd(_mm256_add_pd(k, v_kofs), v_a));
                _mm256_mul_pd(_mm256_sub_pd(b, v_o), v_inv)
            };
            let mut v_k = set(k0[0] as f64, k0[1] as f64, k0[2] as f64, 0.0);
            let mut v_t = _mm256_max_pd(raw(v_k), _mm256_setzero_pd());
            let mut v_tn = raw(_mm256_add_pd(v_k, v_step));
            let mut v_enter = _mm256_setzero_pd();

            let offsets = g.offsets.as_ptr();
            let recs = g.recs.as_ptr();
            // Computes the current cell into `e`, steps to the next, and says whether `e` is the last.
            let mut advance = |e: &mut Ahead| -> bool {
                // Nearest face: lanes 0..2 of `v_min` all hold min(t_x, t_y, t_z).
                let m1 = _mm256_permute4x64_pd(v_t, 0b11_00_10_01);
                let m2 = _mm256_permute4x64_pd(v_t, 0b11_01_00_10);
                let v_min = _mm256_min_pd(v_t, _mm256_min_pd(m1, m2));
                let eq = _mm256_movemask_pd(_mm256_cmp_pd(v_t, v_min, _CMP_EQ_OQ)) as u32;
                let axis = (eq & 7).trailing_zeros() as usize;
                let v_exit_t = _mm256_max_pd(v_min, v_enter);
                e.t_exit = _mm256_cvtsd_f64(v_exit_t);
                // Storage slot and its prefetch.
                e.slot = slot as u32;
                prefetch(offsets.add(slot as usize));
                // Filter constants w = o' − (o'·d)d and o'·d for this cell.
                let oq = _mm256_fnmadd_pd(v_k, v_aq, v_cq);
                let p = _mm256_mul_pd(oq, v_d);
                let ph = _mm256_hadd_pd(p, p);
                let od = _mm256_add_pd(ph, _mm256_permute2f128_pd(ph, ph, 1));
                let w = _mm256_blend_pd(_mm256_fnmadd_pd(od, v_d, oq), od, 0b1000);
                _mm_storeu_ps(e.w.as_mut_ptr(), _mm256_cvtpd_ps(w));
                // Step along `axis`.
                let one = _mm256_castsi256_pd(_mm256_loadu_si256(
                    ONE_HOT.get_unchecked(axis).as_ptr() as *const __m256i
                ));
                v_k = _mm256_add_pd(v_k, _mm256_and_pd(v_step, one));
                slot += *dslot.get_unchecked(axis);
                e.last = _mm256_movemask_pd(_mm256_cmp_pd(v_k, v_exit, _CMP_EQ_OQ)) != 0;
                v_t = _mm256_blendv_pd(v_t, _mm256_max_pd(v_tn, v_exit_t), one);
                v_tn = raw(_mm256_add_pd(v_k, v_step));
                v_enter = v_exit_t;
                e.last
            };
            let fetch_records = |e: &mut Ahead| {
                let s = e.slot as usize;
                e.lo = *offsets.add(s);
                e.hi = *offsets.add(s + 1);
                prefetch(recs.add(e.lo as usize));
                prefetch(recs.add(e.hi.saturating_sub(1) as usize));
            };

            let mut ring = [Ahead::default(); RING];
            let (k_ahead, k_records) = (g.lookahead.0.clamp(1, RING - 1), g.lookahead.1);
            let (mut made, mut fetched, mut ended) = (0usize, 0usize, false);
            while made < k_ahead && !ended {
                ended = advance(&mut ring[made % RING]);
                made += 1;
            }
            while fetched < k_records.min(made) {
                fetch_records(&mut ring[fetched % RING]);
                fetched += 1;
            }

            let v_dx = _mm256_set1_ps(d.x as f32);
            let v_dy = _mm256_set1_ps(d.y as f32);
            let v_dz = _mm256_set1_ps(d.z as f32);
            let v_r2 = _mm256_set1_ps(g.filter_r2);
            let v_q = _mm256_set1_epi32(QMAX as i32);
            // Candidate bits of listings k..k+8 of a cell whose filter constants are `w` (super::passes,
            // eight lanes at once); listings at or past `hi` are never candidates.
            let filter8 = |w: &[f32; 4], k: usize, hi: usize| -> u32 {
                let q = _mm256_loadu_si256(recs.add(k) as *const __m256i);
                let ux = _mm256_cvtepi32_ps(_mm256_and_si256(q, v_q));
                let uy = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(q, QBITS as i32), v_q));
                let uz = _mm256_cvtepi32_ps(_mm256_and_si256(
                    _mm256_srli_epi32(q, 2 * QBITS as i32),
                    v_q,
                ));
                let ud = _mm256_fmadd_ps(uz, v_dz, _mm256_fmadd_ps(uy, v_dy, _mm256_mul_ps(ux, v_dx)));
                let vx = _mm256_fnmadd_ps(ud, v_dx, _mm256_sub_ps(ux, _mm256_set1_ps(w[0])));
                let vy = _mm256_fnmadd_ps(ud, v_dy, _mm256_sub_ps(uy, _mm256_set1_ps(w[1])));
                let vz = _mm256_fnmadd_ps(ud, v_dz, _mm256_sub_ps(uz, _mm256_set1_ps(w[2])));
                let v2 = _mm256_fmadd_ps(vz, vz, _mm256_fmadd_ps(vy, vy, _mm256_mul_ps(vx, vx)));
                let pass = _mm256_and_ps(
                    _mm256_cmp_ps(ud, _mm256_set1_ps(w[3] - g.margin_b), _CMP_GT_OQ),
                    _mm256_cmp_ps(v2, v_r2, _CMP_LE_OQ),
                );
                // Large spheres (sign bit set) always pass; lanes at or past `hi` never do.
                let bits = _mm256_movemask_ps(_mm256_or_ps(pass, _mm256_castsi256_ps(q))) as u32;
                _bzhi_u32(bits, (hi - k).min(8) as u32)
            };
            // The same filter on 16 lanes (AVX-512 F): a masked load stops at `hi`, so no lane past it is
            // read or passes; the operations and their order are those of `filter8`. (Its broadcasts are
            // inside, so that the AVX2 instantiation executes no AVX-512 instruction; they are
            // loop-invariant and hoisted.)
            let filter16 = |w: &[f32; 4], k: usize, hi: usize| -> u32 {
                let (w_dx, w_dy, w_dz) = (
                    _mm512_set1_ps(d.x as f32),
                    _mm512_set1_ps(d.y as f32),
                    _mm512_set1_ps(d.z as f32),
                );
                let w_q = _mm512_set1_epi32(QMAX as i32);
                let lanes = _bzhi_u32(0xffff, (hi - k).min(16) as u32) as __mmask16;
                let q = _mm512_maskz_loadu_epi32(lanes, recs.add(k) as *const i32);
                let ux = _mm512_cvtepi32_ps(_mm512_and_si512(q, w_q));
                let uy = _mm512_cvtepi32_ps(_mm512_and_si512(_mm512_srli_epi32::<QBITS>(q), w_q));
                let uz = _mm512_cvtepi32_ps(_mm512_and_si512(_mm512_srli_epi32::<{ 2 * QBITS }>(q), w_q));
                let ud = _mm512_fmadd_ps(uz, w_dz, _mm512_fmadd_ps(uy, w_dy, _mm512_mul_ps(ux, w_dx)));
                let vx = _mm512_fnmadd_ps(ud, w_dx, _mm512_sub_ps(ux, _mm512_set1_ps(w[0])));
                let vy = _mm512_fnmadd_ps(ud, w_dy, _mm512_sub_ps(uy, _mm512_set1_ps(w[1])));
                let vz = _mm512_fnmadd_ps(ud, w_dz, _mm512_sub_ps(uz, _mm512_set1_ps(w[2])));
                let v2 = _mm512_fmadd_ps(vz, vz, _mm512_fmadd_ps(vy, vy, _mm512_mul_ps(vx, vx)));
                let along =
                    _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(lanes, ud, _mm512_set1_ps(w[3] - g.margin_b));
                let pass = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(along, v2, _mm512_set1_ps(g.filter_r2));
                // Large spheres (sign bit set) always pass.
                let large = _mm512_mask_cmplt_epi32_mask(lanes, q, _mm512_setzero_si512());
                u32::from(pass | large)
            };
            let width = if WIDE { 16 } else { 8 };
            let mut out = FastTrace::default();
            let mut best: Option<Hit> = None;
            let mut i = 0usize;
            loop {
                if !ended {
                    ended = advance(&mut ring[made % RING]);
                    made += 1;
                }
                if fetched < made {
                    fetch_records(&mut ring[fetched % RING]);
                    fetched += 1;
                }
                let e = ring[i % RING];
                let (lo, hi) = (e.lo as usize, e.hi as usize);
                out.n_i += (hi - lo) as u32;
                let mut k = lo;
                while k < hi {
                    let mut bits = if WIDE {
                        filter16(&e.w, k, hi)
                    } else {
                        filter8(&e.w, k, hi)
                    };
                    while bits != 0 {
                        let l = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        out.n_c += 1;
                        g.test_exact(k + l, ray, &mut best);
                    }
                    k += width;
                }
                if matches!(best, Some(h) if h.t <= e.t_exit) {
                    break;
                }
                if e.last {
                    // Left the grid: a sphere entered beyond the last cell is not this grid's hit.
                    best = best.filter(|h| h.t <= e.t_exit);
                    break;
                }
                i += 1;
            }
            out.n_s = i as u32;
            out.hit = best;
            out
        }
    };
}
walk! {
    /// [`FastGrid::trace`] on the AVX2 walk.
    ///
    /// # Safety
    /// The CPU must support AVX2, FMA and BMI2 (every AVX2 CPU has BMI2; the dispatch in
    /// [`FastGrid::trace`] checks all three).
    #[target_feature(enable = "avx2,fma,bmi2")]
    fn trace, WIDE = false
}

walk! {
    /// [`FastGrid::trace`] on the AVX-512 walk: the same pipelined walk, the filter 16 listings per
    /// step (masked loads, mask-register compares) instead of 8.
    ///
    /// # Safety
    /// The CPU must support AVX-512 F and VL besides AVX2, FMA and BMI2 (the dispatch in
    /// [`FastGrid::trace`] checks all five).
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma,bmi2")]
    fn trace_avx512, WIDE = true
}

#[inline(always)]
fn prefetch<T>(p: *const T) {
    // SAFETY: a prefetch is a hint; it never faults, whatever the address.
    unsafe { _mm_prefetch(p as *const i8, _MM_HINT_T0) };
}
