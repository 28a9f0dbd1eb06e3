//! A query-optimised finite grid for speed measurements (`raycost bench`, issue: grid vs Embree).
//!
//! Same cells, same lists, same stopping rule and the same exact f64 ray–sphere test as
//! [`super::FiniteGrid`] + [`super::trace`], so it returns the same first sphere at the same distance
//! as brute force (the oracle tests check it). What changes is the layout and the work per listing:
//! - cells are stored in 4×4×4 bricks (cell data of a ray's consecutive cells shares cache lines);
//! - an occupancy bitmap skips empty cells without touching the offsets;
//! - each listing is a 16-byte f32 record (centre relative to the grid origin, radius), four to a
//!   cache line (lists are short, ~1–3 per cell at the best cell width, so records beat
//!   structure-of-arrays, which would touch four lines per cell); only listings that pass the
//!   filter read the sphere index and get the exact f64 test on the original sphere;
//! - no mailbox: a repeated listing costs one filter evaluation, cheaper than a mailbox probe.
//!
//! # Why the f32 filter never loses a hit
//! A listing passes if its centre lies within `r + m` of the ray line and not more than `m` behind
//! the origin, computed in f32 from coordinates relative to the grid origin. Rounding the centre,
//! origin and direction to f32 and the f32 arithmetic move the computed perpendicular distance and
//! the along-ray offset by at most about 10·ε₃₂·(|c| + |o| + |c − o|) ≤ 10·ε₃₂·(2M + 2|o|) with
//! Euclidean norms bounded by √3 times the largest coordinate. With M bounding the listed centres'
//! coordinates and |o| the ray origin's (both relative to the grid origin), the per-ray margin
//! m = 64·ε₃₂·(M + |o|) covers it (plus the f64 test's own few-ulp slack, far smaller), so every
//! sphere the exact test accepts passes the filter; the filter only admits a few extra candidates,
//! which the exact test then rejects.

use glam::{DVec3, Vec3};

use super::build::{cell_lists, grid_magnitude};
use super::{GridFrame, Hit};
use crate::geom::{Ray, Sphere};

/// Brick edge in cells.
const B: i64 = 4;

/// A finite grid laid out for fast queries.
#[derive(Debug)]
pub struct FastGrid {
    frame: GridFrame,
    dims: [i64; 3],
    bricks: [i64; 3],
    offsets: Vec<u32>,
    occupied: Vec<u64>,
    /// Listing records (centre relative to the grid origin, radius), 16 bytes: four per cache line.
    rec: Vec<[f32; 4]>,
    idx: Vec<u32>,
    spheres: Vec<Sphere>,
    /// Bound M on the listed centres' relative coordinates (grid extent + largest radius).
    m_bound: f32,
    pad_magnitude: f64,
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
}

impl FastGrid {
    /// Builds over `spheres` in the finite `frame` (as [`super::FiniteGrid::build`]).
    pub fn build(frame: GridFrame, spheres: &[Sphere]) -> Self {
        let dims = frame.dims.expect("a finite grid needs dims");
        let bricks = [0, 1, 2].map(|i| (dims[i] + B - 1) / B);
        let n_slots = (bricks[0] * bricks[1] * bricks[2] * B * B * B) as usize;
        let extent = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * frame.width;
        let pad_magnitude = grid_magnitude(&frame);
        let (offsets, order) = cell_lists(&frame, pad_magnitude, spheres, n_slots, |c| {
            slot_of(c, bricks) as u32
        });
        let total = order.len();
        let mut occupied = vec![0u64; n_slots.div_ceil(64)];
        for c in 0..n_slots {
            if offsets[c + 1] > offsets[c] {
                occupied[c / 64] |= 1 << (c % 64);
            }
        }
        let mut rec = vec![[0f32; 4]; total];
        for (k, &s) in order.iter().enumerate() {
            let sp = &spheres[s as usize];
            let rel = (sp.c - frame.origin).as_vec3();
            rec[k] = [rel.x, rel.y, rel.z, sp.r as f32];
        }
        let idx = order;
        let r_max = spheres.iter().map(|s| s.r).fold(0.0, f64::max);
        let m_bound = extent.max_element() + r_max;
        let m_bound = m_bound as f32;
        Self {
            frame,
            dims,
            bricks,
            offsets,
            occupied,
            rec,
            idx,
            spheres: spheres.to_vec(),
            m_bound,
            pad_magnitude,
        }
    }

    /// Bytes held (cell data, listings and the f64 spheres).
    pub fn bytes(&self) -> u64 {
        (self.offsets.len() * 4
            + self.occupied.len() * 8
            + self.rec.len() * 20
            + self.spheres.len() * std::mem::size_of::<Sphere>()) as u64
    }

    /// The first sphere `ray` enters inside the grid, with N_I and N_S.
    pub fn trace(&self, ray: &Ray) -> FastTrace {
        let frame = &self.frame;
        let a = frame.width;
        let mut out = FastTrace::default();
        let o_rel = (ray.o - frame.origin).as_vec3();
        let d32 = ray.d.as_vec3();
        debug_assert!(
            (0..3).all(|i| ray.o[i] >= frame.origin[i]
                && ray.o[i] <= frame.origin[i] + self.dims[i] as f64 * a),
            "the query grid traces rays that start inside it"
        );
        let m = 64.0 * f32::EPSILON * (self.m_bound + o_rel.abs().max_element());

        // DDA state (as grid::Dda: start cell entered by the ray, boundaries from absolute
        // coordinates, ties to the lowest axis).
        let o = ray.o.to_array();
        let d = ray.d.to_array();
        let g0 = frame.origin.to_array();
        let q = ((ray.o - frame.origin) / a).to_array();
        let mut cell = [0i64; 3];
        let mut step = [0i64; 3];
        let mut inv = [0.0f64; 3];
        for i in 0..3 {
            let f = q[i].floor();
            cell[i] = (f as i64 - i64::from(f == q[i] && d[i] < 0.0)).clamp(0, self.dims[i] - 1);
            step[i] = if d[i] > 0.0 {
                1
            } else if d[i] < 0.0 {
                -1
            } else {
                0
            };
            if d[i] != 0.0 {
                inv[i] = 1.0 / d[i];
            }
        }
        let boundary = |i: usize, c: i64, t_enter: f64| -> f64 {
            match step[i] {
                0 => f64::INFINITY,
                s => {
                    let k = if s > 0 { c + 1 } else { c };
                    ((g0[i] + k as f64 * a - o[i]) * inv[i]).max(t_enter)
                }
            }
        };
        let mut t_enter = 0.0;
        let mut t_next = [0, 1, 2].map(|i| boundary(i, cell[i], 0.0));
        let mut best: Option<Hit> = None;
        let mut visited = 0u32;
        loop {
            visited += 1;
            // Branchless choice of the first face (ties to the lowest axis, as grid::Dda): the axis
            // is random for random rays, so a branch here mispredicts about half the time.
            let i01 = usize::from(t_next[1] < t_next[0]);
            let t01 = t_next[0].min(t_next[1]);
            let axis = if t_next[2] < t01 { 2 } else { i01 };
            let t_exit = t_next[axis].max(t_enter);
            let s = slot_of(cell, self.bricks);
            if self.occupied[s / 64] >> (s % 64) & 1 == 1 {
                let (lo, hi) = (self.offsets[s] as usize, self.offsets[s + 1] as usize);
                out.n_i += (hi - lo) as u32;
                for (k, rc) in self.rec[lo..hi].iter().enumerate() {
                    let k = lo + k;
                    // Conservative f32 filter (see the module doc), then the exact test.
                    let f = Vec3::new(rc[0], rc[1], rc[2]) - o_rel;
                    let b = f.dot(d32);
                    let v = f - b * d32;
                    let rr = rc[3] + m;
                    if b > -m && v.length_squared() <= rr * rr {
                        let sp = &self.spheres[self.idx[k] as usize];
                        if let Some(t) = sp.intersect(ray) {
                            if best.is_none_or(|h| t < h.t || (t == h.t && sp.id < h.id)) {
                                best = Some(Hit { id: sp.id, t });
                            }
                        }
                    }
                }
            }
            if matches!(best, Some(h) if h.t <= t_exit) {
                break;
            }
            cell[axis] += step[axis];
            if t_exit == f64::INFINITY || cell[axis] < 0 || cell[axis] >= self.dims[axis] {
                // Left the grid: a sphere entered beyond the last cell is not this grid's hit.
                best = best.filter(|h| h.t <= t_exit);
                break;
            }
            t_enter = t_exit;
            t_next[axis] = boundary(axis, cell[axis], t_enter);
        }
        out.n_s = visited - 1;
        out.hit = best;
        out
    }

    /// The padding magnitude used for listing (same rule as `FiniteGrid`).
    pub fn pad_magnitude(&self) -> f64 {
        self.pad_magnitude
    }
}

/// Storage slot of a cell: bricks in x-fastest order, cells x-fastest within a brick.
#[inline]
fn slot_of(c: [i64; 3], bricks: [i64; 3]) -> usize {
    // Cells are non-negative here: shifts and masks instead of signed division.
    debug_assert!(c.iter().all(|&x| x >= 0) && B == 4);
    let [x, y, z] = c.map(|v| v as usize);
    let brick = ((z >> 2) * bricks[1] as usize + (y >> 2)) * bricks[0] as usize + (x >> 2);
    let local = ((z & 3) << 4) | ((y & 3) << 2) | (x & 3);
    (brick << 6) | local
}
