//! The query-optimised finite grid that `raycost bench` races against Embree.
//!
//! It answers exactly what the counting tracer ([`super::FiniteGrid`] + [`super::trace`]) answers
//! (the same first sphere at the same f64 distance as brute force, the same N_I and N_S; the oracle
//! tests check all three on adversarial rays), but is laid out and walked for speed. What the
//! profile taught (numbers from this 2-core EPYC VM, n = 10⁶ and 10⁷, ρ = 1, r = 0.1):
//!
//! - **Memory, not arithmetic, was the wall.** The first query grid spent ~1 DRAM miss per cell
//!   step: 16-byte f32 records plus 4-byte ids is ~30 bytes of cell data per unit volume, so the
//!   10⁶ scene (71 MB) did not fit the 32 MiB L3 (of which this VM effectively gets less than
//!   24 MiB: a pointer chase over 24 MiB already runs at DRAM latency). Here a listing is one
//!   `u32`: the centre quantised to 10 bits per axis inside its cell's padded box (the box the
//!   centres of listed spheres can lie in). The hot data (offsets + records) is ~5 B per unit
//!   volume at the bench's cell width: 5 MB for n = 10⁶, and the cells within two mean free paths
//!   of the eye, where 87 % of cell visits fall, take about as much at n = 10⁷.
//! - **TLB misses were half of what remained**: a walk touches a fresh 4 KiB page per step. The
//!   arrays live on 2 MiB pages ([`super::huge`]; 1.4× more rays/s).
//! - **The walk runs ahead of the tests.** The 3D-DDA does not depend on what the cells hold, so
//!   the AVX2 walk ([`avx2`]) computes cells a few steps before it tests them and prefetches each
//!   cell's offsets, then its records ([`FastGrid::lookahead`]), so that the misses of several cells
//!   are in flight together instead of one after another.
//! - **Tests are 8 at a time** (AVX2; 16 with AVX-512, [`Walk::Avx512`], opt-in: see
//!   [`Walk::PREFERRED`]), in f32, in the quantised units of the cell, and only a listing that
//!   passes is re-tested exactly ([`Sphere::intersect`], f64) on its full-precision copy, stored in
//!   listing order so that a candidate costs one miss, not two (index, then sphere).
//! - **The cell width follows the costs**: with a test costing ~1/30 of a step, wider cells (~17
//!   listings) beat the paper-style optimum of a few listings per cell; `raycost bench` fits T_I and
//!   T_S on this grid and lets the cost model choose (a ≈ 2.2–2.4 at ρ = 1, r = 0.1).
//!
//! # Why the f32 filter never loses a hit
//! Let `L = origin + cell·a − R` be the low corner of the quantisation box of a cell (R bounds the
//! radius of every quantised sphere plus the listing pad, so a listed centre lies in
//! `[L, L + a + 2R]` on each axis) and `s = (a + 2R)/1023` the quantisation step. A listing stores
//! `u = round((c − L)/s)`, so the dequantised centre `c' = L + s·u` is within `√3·s/2` of the true
//! centre `c` (Euclidean). In units of `s`, with the ray origin at `o' = (o − L)/s` (computed in f64),
//! the filter evaluates in f32
//! `b' = u·d − o'·d` (distance of the centre along the ray) and
//! `v' = u − (u·d)d − w`, `w = o' − (o'·d)d` (its offset from the ray line),
//! and passes the listing if `b' > −m_b` and `|v'|² ≤ (r_max/s + m_v)²`. Both `b'` and `|v'|` are
//! 1-Lipschitz in the centre, so replacing `c` by `c'` moves them by at most `√3/2`; the f32
//! evaluation moves them by at most a few ulps of the magnitudes involved: `|u| ≤ 1023·√3`,
//! `|w| ≤ |v'| + |u|`, and `|o'·d|`, which is bounded by the grid's diagonal over `s` and enters
//! only `b'`. The margins `m_v = √3/2 + 1/64` and `m_b = m_v + 2⁻²⁰·(diagonal/s)` exceed these
//! bounds by orders of magnitude, and do not grow with the scene's distance from the coordinate
//! origin (the old f32 records relative to the grid origin needed a margin of 64·ε₃₂ times the
//! coordinate magnitude, which at an offset of 10⁸ admitted every listing). So every sphere the
//! exact test accepts (`(c − o)·d > 0`, `|v| ≤ r(1 + 4ε)`) passes the filter; the filter only
//! admits a few extra candidates (`n_c`, ~1 per ray), which the exact test then decides.
//!
//! Spheres larger than a cell (`r > a`) are not quantised: their record carries a flag bit that
//! makes them a candidate in every cell they are listed in (rare in the scenes studied; correct for
//! any).

#[cfg(target_arch = "x86_64")]
mod avx2;

use glam::DVec3;
use rayon::prelude::*;

use super::build::{cell_lists, grid_magnitude};
use super::huge::HugeSlice;
use super::{Dda, GridFrame, Hit};
use crate::geom::{Ray, Sphere};

/// Bits per axis of a quantised centre.
const QBITS: u32 = 10;
/// Largest quantised coordinate.
const QMAX: u32 = (1 << QBITS) - 1;
/// Record flag: a sphere larger than a cell, a candidate wherever it is listed.
const LARGE: u32 = 1 << 31;
/// Records past the end, so that an 8-wide load at any listing stays inside the array.
const TAIL: usize = 8;

/// A finite grid laid out for fast queries (see the module docs).
#[derive(Debug)]
pub struct FastGrid {
    frame: GridFrame,
    dims: [i64; 3],
    /// Listings of cell (x, y, z) are `offsets[s]..offsets[s + 1]`, `s = x + nx·(y + ny·z)`.
    offsets: HugeSlice<u32>,
    /// Quantised centres (or [`LARGE`]), in listing order, plus [`TAIL`] zeros.
    recs: HugeSlice<u32>,
    /// Exact centre and radius of each listing's sphere, in listing order.
    exact: HugeSlice<[f64; 4]>,
    /// Id of each listing's sphere, in listing order.
    ids: HugeSlice<u64>,
    /// Half-width R of the quantisation box beyond the cell (largest quantised radius + pad).
    reach: f64,
    /// Quantisation step s = (a + 2R)/QMAX.
    qstep: f64,
    /// Squared filter radius (r_max/s + m_v)², quantisation units.
    filter_r2: f32,
    /// Margin m_b of the along-ray test, quantisation units.
    margin_b: f32,
    /// The walk [`trace`](Self::trace) takes (one this CPU can run).
    walk: Walk,
    /// Cells ahead of the one tested at which the AVX2 walk computes a cell (and prefetches its
    /// offsets), and at which it prefetches the cell's records.
    pub lookahead: (usize, usize),
}

/// Counts and hit of one query.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FastTrace {
    /// The first hit (`id` is the sphere's id).
    pub hit: Option<Hit>,
    /// Listings filtered (N_I without mailbox).
    pub n_i: u32,
    /// Cell steps.
    pub n_s: u32,
    /// Listings that passed the f32 filter and were tested exactly (diagnostic).
    pub n_c: u32,
}

/// Which walk [`FastGrid::trace`] uses. All return the same hits and counts, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// The pipelined walk with a 16-wide filter (x86_64 CPUs with AVX-512 F and VL besides AVX2,
    /// FMA and BMI2).
    Avx512,
    /// The pipelined AVX2 walk (x86_64 CPUs with AVX2, FMA and BMI2).
    Avx2,
    /// The plain walk: [`Dda`] cell by cell, scalar filter. Any CPU.
    Portable,
}

impl Walk {
    /// Every walk, widest filter first.
    pub const ALL: [Walk; 3] = [Walk::Avx512, Walk::Avx2, Walk::Portable];

    /// The walk a new grid uses on this CPU: the one named by the environment variable
    /// `RAYCOST_WALK` (`avx512`, `avx2` or `portable`) if set and this CPU can run it, else the
    /// first of [`Walk::PREFERRED`] it can run. `raycost bench` records the result (`walk = ...`
    /// in `bench.meta.toml`).
    pub fn detect() -> Self {
        let forced = match std::env::var("RAYCOST_WALK").as_deref() {
            Ok("avx512") => Some(Walk::Avx512),
            Ok("avx2") => Some(Walk::Avx2),
            Ok("portable") => Some(Walk::Portable),
            _ => None,
        };
        forced
            .into_iter()
            .chain(Self::PREFERRED)
            .find(|w| w.available())
            .unwrap_or(Walk::Portable)
    }

    /// Order of preference of [`detect`](Self::detect): AVX2 first, so that a CPU with AVX-512
    /// still takes the AVX2 walk unless `RAYCOST_WALK=avx512` asks for the other one.
    ///
    /// Why: the 16-wide filter is no faster at the cell widths the cost model picks. Measured with
    /// `examples/walk_speed.rs` (n = 10⁶, ρ = 1, r = 0.1, 200 000 rays from the centre per round, 9
    /// interleaved rounds, medians; 2-vCPU KVM guest "Intel(R) Xeon(R) Processor", family 6
    /// model 167, AVX-512 F/VL/BW/DQ/FP16), AVX-512 / AVX2 rays/s, median of paired rounds:
    /// - a = 2.36 (the width `raycost bench` picks, 16.4 listings per cell): 1.004 and 1.004 on 1
    ///   thread (1.53–1.56 M rays/s each), 0.990 and 0.985 on 2 threads (3.0–3.2 M each);
    /// - a = 2.0: 0.99 (1 thread); a = 2.8: 1.10 / 1.08 (1 / 2 threads); a = 3.2: 1.16; a = 4
    ///   (73 listings per cell): 1.20 / 1.28.
    ///
    /// The walk waits on memory (a DRAM miss per few cells), not on the filter, once a cell holds
    /// about one AVX2 vector's worth of listings; AVX-512 only wins where cells are wide, and at
    /// its own best width (a = 2.8: 1.56 M rays/s on 1 thread) it ties AVX2 at its best (a = 2.36:
    /// 1.52–1.56 M). On 2 threads at a = 2.36 it is 1–1.5 % slower, and older AVX-512 CPUs lower
    /// their clock under 512-bit instructions, so AVX2 stays the default.
    pub const PREFERRED: [Walk; 3] = [Walk::Avx2, Walk::Avx512, Walk::Portable];

    /// Whether this CPU can run the walk.
    pub fn available(self) -> bool {
        match self {
            Walk::Avx512 => avx2_available() && avx512_available(),
            Walk::Avx2 => avx2_available(),
            Walk::Portable => true,
        }
    }

    /// The walks this CPU can run (tests run every one of them).
    pub fn all_available() -> Vec<Walk> {
        Self::ALL.into_iter().filter(|w| w.available()).collect()
    }
}

impl FastGrid {
    /// Builds over `spheres` in the finite `frame` (as [`super::FiniteGrid::build`]); ids are the
    /// spheres' `id` fields.
    ///
    /// # Panics
    /// If the grid has 2³¹ cells or more, or lists 2³² spheres or more.
    pub fn build(frame: GridFrame, spheres: &[Sphere]) -> Self {
        let dims = frame.dims.expect("a finite grid needs dims");
        let a = frame.width;
        let n_cells = dims.iter().product::<i64>() as usize;
        assert!(n_cells < 1 << 31, "{n_cells} cells: too many for u32 slots");
        assert!(spheres.len() < 1 << 32, "too many spheres for u32 indices");
        let pad_magnitude = grid_magnitude(&frame);
        // Spheres up to one cell wide are quantised; R bounds their reach beyond the cell.
        let r_max = spheres
            .par_iter()
            .map(|s| s.r)
            .filter(|&r| r <= a)
            .reduce(|| 0.0, f64::max);
        let reach = r_max + frame.pad(pad_magnitude, r_max);
        let qstep = (a + 2.0 * reach) / f64::from(QMAX);
        let quantise = |cell: [i64; 3], s: u32| -> u64 {
            let sp = &spheres[s as usize];
            let rec = if sp.r > a {
                LARGE
            } else {
                let corner = frame.origin
                    + DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) * a
                    - DVec3::splat(reach);
                let u = ((sp.c - corner) / qstep)
                    .round()
                    .clamp(DVec3::ZERO, DVec3::splat(f64::from(QMAX)));
                (u.x as u32) | (u.y as u32) << QBITS | (u.z as u32) << (2 * QBITS)
            };
            u64::from(rec) | u64::from(s) << 32
        };
        let slot = |c: [i64; 3]| (c[0] + dims[0] * (c[1] + dims[1] * c[2])) as u32;
        let (offsets_v, listed) =
            cell_lists(&frame, pad_magnitude, spheres, n_cells, slot, quantise);
        let mut offsets = HugeSlice::<u32>::zeroed(offsets_v.len());
        offsets.copy_from_slice(&offsets_v);
        drop(offsets_v);
        let mut recs = HugeSlice::<u32>::zeroed(listed.len() + TAIL);
        let mut exact = HugeSlice::<[f64; 4]>::zeroed(listed.len());
        let mut ids = HugeSlice::<u64>::zeroed(listed.len());
        recs[..listed.len()]
            .par_iter_mut()
            .zip(exact.par_iter_mut())
            .zip(ids.par_iter_mut())
            .zip(listed.par_iter())
            .for_each(|(((rec, x), id), &p)| {
                *rec = p as u32;
                let sp = &spheres[(p >> 32) as usize];
                *x = [sp.c.x, sp.c.y, sp.c.z, sp.r];
                *id = sp.id;
            });
        // Filter margins (module docs): √3/2 of quantisation plus generous f32 rounding slack.
        let extent = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * a;
        let diagonal = (extent + DVec3::splat(2.0 * reach)).length() / qstep;
        let margin_v = 3f64.sqrt() / 2.0 + 1.0 / 64.0;
        let margin_b = margin_v + diagonal * 2f64.powi(-20);
        let filter_r = r_max * (1.0 + 1e-6) / qstep + margin_v;
        Self {
            frame,
            dims,
            offsets,
            recs,
            exact,
            ids,
            reach,
            qstep,
            filter_r2: (filter_r * filter_r) as f32,
            margin_b: margin_b as f32,
            walk: Walk::detect(),
            lookahead: (6, 3),
        }
    }

    /// Bytes held by the grid's arrays (as allocated).
    pub fn bytes(&self) -> u64 {
        (self.offsets.allocated_bytes()
            + self.recs.allocated_bytes()
            + self.exact.allocated_bytes()
            + self.ids.allocated_bytes()) as u64
    }

    /// The walk [`trace`](Self::trace) uses on this machine.
    pub fn walk(&self) -> Walk {
        self.walk
    }

    /// Forces a walk (for tests and comparisons); a walk the CPU cannot run falls back to the
    /// next one it can ([`Walk::Avx512`] → [`Walk::Avx2`] → [`Walk::Portable`]).
    pub fn set_walk(&mut self, walk: Walk) {
        self.walk = Walk::ALL
            .into_iter()
            .skip_while(|&w| w != walk)
            .find(|w| w.available())
            .unwrap_or(Walk::Portable);
    }

    /// The first sphere `ray` enters inside the grid, with N_I and N_S. `ray` must start inside
    /// the grid's box.
    pub fn trace(&self, ray: &Ray) -> FastTrace {
        debug_assert!(
            {
                let hi = self.frame.origin
                    + DVec3::new(
                        self.dims[0] as f64,
                        self.dims[1] as f64,
                        self.dims[2] as f64,
                    ) * self.frame.width;
                ray.o.cmpge(self.frame.origin).all() && ray.o.cmple(hi).all()
            },
            "the query grid traces rays that start inside it"
        );
        match self.walk {
            // SAFETY: `walk` is Avx512 only when the CPU reports AVX-512 F and VL, AVX2, FMA and
            // BMI2 (`Walk::available`).
            #[cfg(target_arch = "x86_64")]
            Walk::Avx512 => unsafe { avx2::trace_avx512(self, ray) },
            // SAFETY: `walk` is Avx2 only when the CPU reports AVX2, FMA and BMI2.
            #[cfg(target_arch = "x86_64")]
            Walk::Avx2 => unsafe { avx2::trace(self, ray) },
            _ => self.trace_portable(ray),
        }
    }

    /// The plain walk: [`Dda`] cell by cell, the filter one listing at a time.
    fn trace_portable(&self, ray: &Ray) -> FastTrace {
        let mut out = FastTrace::default();
        let d32 = ray.d.as_vec3().to_array();
        let mut best: Option<Hit> = None;
        let mut visited = 0u32;
        let mut last_exit = 0.0;
        for (cell, _, t_exit) in Dda::new(&self.frame, ray) {
            visited += 1;
            last_exit = t_exit;
            let (lo, hi) = self.listings_of(cell);
            out.n_i += (hi - lo) as u32;
            let w = self.cell_frame(ray, cell);
            for k in lo..hi {
                if passes(self.recs[k], w, d32, self.margin_b, self.filter_r2) {
                    out.n_c += 1;
                    self.test_exact(k, ray, &mut best);
                }
            }
            if matches!(best, Some(h) if h.t <= t_exit) {
                out.hit = best;
                out.n_s = visited - 1;
                return out;
            }
        }
        // The walk left the grid: a sphere entered beyond the last cell is not this grid's hit.
        out.hit = best.filter(|h| h.t <= last_exit);
        out.n_s = visited - 1;
        out
    }

    /// Listing range of `cell`.
    #[inline(always)]
    fn listings_of(&self, cell: [i64; 3]) -> (usize, usize) {
        let s = (cell[0] + self.dims[0] * (cell[1] + self.dims[1] * cell[2])) as usize;
        (self.offsets[s] as usize, self.offsets[s + 1] as usize)
    }

    /// The filter's per-cell constants `[w_x, w_y, w_z, o'·d]` (module docs), from f64.
    #[inline(always)]
    fn cell_frame(&self, ray: &Ray, cell: [i64; 3]) -> [f32; 4] {
        let corner = DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64);
        let o = ((ray.o - self.frame.origin + DVec3::splat(self.reach))
            - corner * self.frame.width)
            / self.qstep;
        let od = o.dot(ray.d);
        let w = o - od * ray.d;
        [w.x as f32, w.y as f32, w.z as f32, od as f32]
    }

    /// Exact test of listing `k`; keeps the nearer of it and `best` (ties to the smaller id). The id
    /// is read only for a hit: it lives in another array, and most candidates are the final hit.
    #[inline(always)]
    fn test_exact(&self, k: usize, ray: &Ray, best: &mut Option<Hit>) {
        let x = self.exact[k];
        let sphere = Sphere {
            c: DVec3::new(x[0], x[1], x[2]),
            r: x[3],
            id: 0,
        };
        if let Some(t) = sphere.intersect(ray) {
            let id = self.ids[k];
            if best.is_none_or(|h| t < h.t || (t == h.t && id < h.id)) {
                *best = Some(Hit { id, t });
            }
        }
    }
}

/// The f32 filter of one record (module docs): could this listing's sphere be hit?
#[inline(always)]
fn passes(rec: u32, w: [f32; 4], d: [f32; 3], margin_b: f32, filter_r2: f32) -> bool {
    if rec & LARGE != 0 {
        return true;
    }
    let u = [0, QBITS, 2 * QBITS].map(|shift| ((rec >> shift) & QMAX) as f32);
    let ud = u[2].mul_add(d[2], u[1].mul_add(d[1], u[0] * d[0]));
    let v = [0, 1, 2].map(|i| (-ud).mul_add(d[i], u[i] - w[i]));
    let v2 = v[2].mul_add(v[2], v[1].mul_add(v[1], v[0] * v[0]));
    ud > w[3] - margin_b && v2 <= filter_r2
}

fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

fn avx512_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;
    use crate::sample::{directions::uniform_direction, rng::stream};

    /// The filter must pass every listing whose sphere the exact test hits, including spheres the
    /// ray grazes within a few ulps, in cells far from the coordinate origin.
    #[test]
    fn filter_passes_every_exact_hit_even_grazing_and_far_away() {
        let mut rng = stream(&[0xF117E4]);
        let mut grazes = 0;
        for case in 0..20_000 {
            let scale = 10f64.powi(rng.gen_range(-3..9));
            let a = rng.gen_range(0.2..3.0) * scale.min(1e3);
            let r = a * rng.gen_range(0.01..1.0);
            let origin = DVec3::splat(scale);
            let frame = GridFrame {
                origin,
                width: a,
                dims: Some([16, 16, 16]),
            };
            // A ray from the middle of the grid (so the hit, at most 7 cells on, is inside it), and a
            // sphere centred near the ray whose offset from the line is r·(1 − δ) with δ down to
            // 1e-12: grazing hits.
            let o = origin
                + (DVec3::splat(6.0) + DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 4.0) * a;
            let d = uniform_direction(&mut rng);
            let ray = Ray::new(o, d);
            let along = rng.gen_range(0.5..6.0) * a;
            let perp = d.any_orthonormal_vector();
            let delta = 10f64.powf(rng.gen_range(-12.0..-1.0));
            let c = o + d * along + perp * r * (1.0 - delta);
            let sphere = Sphere { c, r, id: case };
            let Some(t) = sphere.intersect(&ray) else {
                continue;
            };
            grazes += usize::from(delta < 1e-6);
            let grid = FastGrid::build(frame, &[sphere]);
            // The cell holding the hit point lists the sphere; its record must pass.
            let cell = frame.cell_of(ray.at(t));
            let (lo, hi) = grid.listings_of(cell);
            assert_eq!(hi - lo, 1, "case {case}: the hit cell lists the sphere");
            let w = grid.cell_frame(&ray, cell);
            let d32 = ray.d.as_vec3().to_array();
            assert!(
                passes(grid.recs[lo], w, d32, grid.margin_b, grid.filter_r2),
                "case {case}: filter rejects an exact hit (scale {scale:e}, a {a}, r {r}, δ {delta:e})"
            );
        }
        assert!(grazes > 1000, "too few grazing cases: {grazes}");
    }

    /// Every walk this CPU has returns the same hit and counts on random rays through random
    /// scenes: a sparse one (~5 listings per cell, large spheres in many cells) and a dense one
    /// (~45 per cell), so that every tail length of the 8- and 16-wide filters occurs.
    #[test]
    fn avx512_avx2_and_portable_walks_agree() {
        let mut rng = stream(&[0xA7A7]);
        let frame = GridFrame {
            origin: DVec3::splat(-10.0),
            width: 1.3,
            dims: Some([16, 15, 17]),
        };
        let walks = Walk::all_available();
        eprintln!("walks on this CPU: {walks:?}");
        for (n, n_rays) in [(6000, 20_000), (60_000, 5_000)] {
            let spheres: Vec<Sphere> = (0..n)
                .map(|id| Sphere {
                    c: DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 21.0 - DVec3::splat(10.0),
                    r: if id % 97 == 0 {
                        2.0
                    } else {
                        rng.gen_range(0.02..0.3)
                    },
                    id,
                })
                .collect();
            let mut grid = FastGrid::build(frame, &spheres);
            for _ in 0..n_rays {
                let o = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 19.0 - DVec3::splat(9.5);
                let ray = Ray::new(o, uniform_direction(&mut rng));
                grid.set_walk(Walk::Portable);
                let plain = grid.trace(&ray);
                for &w in &walks {
                    grid.set_walk(w);
                    assert_eq!(grid.walk(), w);
                    assert_eq!(grid.trace(&ray), plain, "n = {n}, {w:?} walk, ray {ray:?}");
                }
            }
        }
    }
}
