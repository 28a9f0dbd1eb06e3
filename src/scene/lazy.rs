//! The infinite Poisson scene, generated lazily where rays go: the paper's n → ∞ limit with no
//! boundary at all.
//!
//! Space is cut into generation blocks (per class, of width `G_i`). The centres in a block are a
//! Poisson(α_i·ρ·G_i³) count of uniform points drawn from a stream keyed by (scene seed, class,
//! block), so any block can be produced on demand, in any order, and always comes out the same.
//! A grid cell's list gathers the spheres of the blocks within reach (cell ± largest radius) that
//! really overlap the cell. Blocks are memoised for one batch of rays, which shares one scene
//! realisation; the memo is dropped with the batch, so memory grows with what one batch traces,
//! never with the universe.
//!
//! # Speed (issue 10)
//! The profile of the first version (quickstart, a = 0.5, one thread, 38 µs per ray): 56 % building
//! cell lists (every sphere of every block within reach tested against every visited cell, then
//! copied into a per-batch cell cache), 14 % generating blocks, 9 % hash-map inserts, 8 % the walk.
//! What a ray needs is small (~95 cells, ~30 listings, ~300 generated spheres at a = 0.5), so:
//! - blocks are memoised in a flat open-addressing table ([`LazyCache`]) cleared by a stamp, and
//!   held structure-of-arrays;
//! - a cell's list is built on the fly into one reused buffer (no cell cache: most cells are visited
//!   by one ray of the batch, and rebuilding costs less than caching);
//! - the blocks within reach of a cell are looked up once per change of the block range, which
//!   consecutive cells of a walk mostly share;
//! - the overlap test runs over the gathered candidates in SIMD-friendly form (the same f64
//!   operations as before, so the lists are identical);
//! - a block's Poisson count reads a per-class CDF table computed with exactly the operations of
//!   [`crate::sample::poisson`], and a sphere's id (`hash_key([block key, k])`) is hashed only
//!   when the sphere is listed.
//!
//! The draws are unchanged: the same keyed stream per block, consumed in the same order, so every
//! sphere (centre, radius, id) and so every count is bit for bit what the first version produced.

use glam::DVec3;
use rand::Rng;

use super::{RadiusClass, RadiusDraw};
use crate::geom::Sphere;
use crate::grid::{Cell, CellLists, GridFrame};
use crate::sample::{counter::SplitMix64, rng::domain, rng::hash_key, rng::mix64, rng::stream};

/// Additive constant of [`hash_key`]'s word mixing.
const HASH_ADD: u64 = 0x632b_e59b_d9b4_e019;
/// Initial state of [`hash_key`] (before xoring the key length).
const HASH_INIT: u64 = 0x9e37_79b9_7f4a_7c15;

/// One step of [`hash_key`]: folds `word` into state `h`.
#[inline(always)]
fn hash_step(h: u64, word: u64) -> u64 {
    mix64(h ^ mix64(word.wrapping_add(HASH_ADD)))
}

/// `hash_key(&[key, k])`, from `h1 = hash_step(HASH_INIT ^ 2, key)` (precomputed per block).
#[inline(always)]
fn sphere_id(h1: u64, k: u32) -> u64 {
    hash_step(h1, u64::from(k))
}

/// Per-class constants of block generation.
#[derive(Clone, Debug)]
struct ClassGen {
    /// Block width G.
    g: f64,
    /// Poisson mean of a block's count, ρ·α·G³.
    mu: f64,
    /// `hash_key` state after `[BLOCK, seed, class]` (length 6 keys).
    prefix: u64,
    /// The CDF of Poisson(mu) as [`crate::sample::poisson`] accumulates it, up to where it stops
    /// growing (empty when mu ≥ 30, where that function uses another sampler).
    cdf: Vec<f64>,
}

/// One realisation of an infinite Poisson sphere scene.
#[derive(Clone, Debug)]
pub struct LazyScene {
    seed: u64,
    classes: Vec<RadiusClass>,
    draw: RadiusDraw,
    /// Radius of each class when drawn per scene.
    per_scene: Vec<f64>,
    /// Generation constants per class.
    gen: Vec<ClassGen>,
}

/// The Poisson CDF table of [`crate::sample::poisson`] for mean `mu` (< 30): `cdf[k]` is the
/// running sum after `k` steps, computed with the same operations in the same order, until it stops
/// changing.
fn poisson_cdf(mu: f64) -> Vec<f64> {
    if !(mu > 0.0 && mu < 30.0) {
        return Vec::new();
    }
    let (mut k, mut p) = (0u64, (-mu).exp());
    let mut cdf = vec![p];
    let mut c = p;
    while k < 1000 {
        k += 1;
        p *= mu / k as f64;
        let next = c + p;
        if next == c {
            break;
        }
        c = next;
        cdf.push(c);
    }
    cdf
}

impl LazyScene {
    /// The realisation keyed by `key`; `cell_width` guides the block size.
    pub fn new(
        intensity: f64,
        classes: &[RadiusClass],
        draw: RadiusDraw,
        cell_width: f64,
        key: &[u64],
    ) -> Self {
        let mut rng = stream(key);
        let per_scene: Vec<f64> = classes.iter().map(|c| c.radius.sample(&mut rng)).collect();
        let seed: u64 = rng.gen();
        let gen = classes
            .iter()
            .enumerate()
            .map(|(i, c)| {
                // About 8 centres per block, but never narrower than a cell or a sphere diameter:
                // a cell then gathers from few blocks, and blocks are not mostly empty.
                let by_count = (8.0 / (intensity * c.fraction)).cbrt();
                let g = by_count.max(cell_width).max(2.0 * c.radius.max());
                let mu = intensity * c.fraction * g * g * g;
                let prefix = [domain::BLOCK, seed, i as u64]
                    .into_iter()
                    .fold(HASH_INIT ^ 6, hash_step);
                ClassGen {
                    g,
                    mu,
                    prefix,
                    cdf: poisson_cdf(mu),
                }
            })
            .collect();
        Self {
            seed,
            classes: classes.to_vec(),
            draw,
            per_scene,
            gen,
        }
    }

    /// Largest radius of class `i` in this realisation.
    fn reach(&self, i: usize) -> f64 {
        match self.draw {
            RadiusDraw::PerScene => self.per_scene[i],
            RadiusDraw::PerSphere => self.classes[i].radius.max(),
        }
    }

    /// Generates block `b` of class `class`: calls `emit(centre, radius, h1, k)` for its `k`-th
    /// sphere, whose id is `sphere_id(h1, k)`.
    #[inline(always)]
    fn generate_with(&self, class: usize, b: Cell, mut emit: impl FnMut(DVec3, f64, u64, u32)) {
        let cg = &self.gen[class];
        let key = [b[0] as u64, b[1] as u64, b[2] as u64]
            .into_iter()
            .fold(cg.prefix, hash_step);
        debug_assert_eq!(
            key,
            hash_key(&[
                domain::BLOCK,
                self.seed,
                class as u64,
                b[0] as u64,
                b[1] as u64,
                b[2] as u64
            ])
        );
        let mut rng = SplitMix64::new(key);
        let n = poisson_from_table(&mut rng, cg.mu, &cg.cdf);
        let g = cg.g;
        let lo = DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64) * g;
        let h1 = hash_step(HASH_INIT ^ 2, key);
        for k in 0..n {
            let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
            let r = match self.draw {
                RadiusDraw::PerScene => self.per_scene[class],
                RadiusDraw::PerSphere => self.classes[class].radius.sample(&mut rng),
            };
            emit(lo + u * g, r, h1, k as u32);
        }
    }

    /// The spheres of block `b` of class `class`, appended to `out`.
    pub fn generate_block(&self, class: usize, b: Cell, out: &mut Vec<Sphere>) {
        self.generate_with(class, b, |c, r, h1, k| {
            out.push(Sphere {
                c,
                r,
                id: sphere_id(h1, k),
            })
        });
    }

    /// Every sphere whose centre lies in the axis box `[lo, hi]` (for oracles and tests).
    pub fn spheres_in(&self, lo: DVec3, hi: DVec3) -> Vec<Sphere> {
        let mut out = Vec::new();
        for class in 0..self.classes.len() {
            let g = self.gen[class].g;
            let (bl, bh) = ((lo / g).floor(), (hi / g).floor());
            for z in bl.z as i64..=bh.z as i64 {
                for y in bl.y as i64..=bh.y as i64 {
                    for x in bl.x as i64..=bh.x as i64 {
                        self.generate_block(class, [x, y, z], &mut out);
                    }
                }
            }
        }
        out.retain(|s| s.c.cmpge(lo).all() && s.c.cmple(hi).all());
        out
    }

    /// A cell-list source over this realisation for a grid placed by `frame` (unbounded), using
    /// (and first clearing) `cache`: one cache per thread, reused batch after batch, so the memory
    /// of one batch is allocated once and not faulted in again for every batch.
    pub fn cells<'a>(
        &'a self,
        frame: GridFrame,
        eye_magnitude: f64,
        cache: &'a mut LazyCache,
    ) -> LazyCells<'a> {
        cache.clear(self.classes.len());
        LazyCells {
            scene: self,
            frame,
            eye_magnitude,
            cache,
        }
    }
}

/// [`crate::sample::poisson`] with the small-mean CDF precomputed: the same draw, the same result.
#[inline]
fn poisson_from_table(rng: &mut SplitMix64, mu: f64, cdf: &[f64]) -> u64 {
    if cdf.is_empty() {
        return crate::sample::poisson(rng, mu);
    }
    let u: f64 = rng.gen();
    // The original loop stops at the first k with u ≤ cdf[k] (or at k = 1000).
    match cdf.iter().position(|&c| u <= c) {
        Some(k) => k as u64,
        // Beyond the table the running sum no longer grows: the loop runs on to its cap.
        None => 1000,
    }
}

/// The instruction set the list builder was compiled for, picked at run time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Isa {
    /// Baseline x86-64 (or another architecture).
    #[default]
    Portable,
    /// AVX2.
    Avx2,
    /// AVX-512 F and VL.
    Avx512,
}

impl Isa {
    /// The best this CPU offers.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") {
                return Isa::Avx512;
            }
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("bmi2") {
                return Isa::Avx2;
            }
        }
        Isa::Portable
    }
}

/// Centres tested per step of the box filter; the centre arrays keep this many NaNs past the last
/// sphere, so that a full step can be read at any sphere.
const PAD: usize = 8;

/// One memoised block: where its spheres sit in the arena.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    key: [i64; 3],
    start: u32,
    count: u32,
    class: u8,
    stamp: u8,
}

/// The buffers behind [`LazyCells`]: the blocks generated for one batch (a flat open-addressing
/// table into a structure-of-arrays arena) and the list buffer.
#[derive(Debug)]
pub struct LazyCache {
    isa: Isa,
    table: Vec<Slot>,
    stamp: u8,
    used: usize,
    /// Generated spheres, structure of arrays: centre, radius, and what their id is hashed from.
    cx: Vec<f64>,
    cy: Vec<f64>,
    cz: Vec<f64>,
    r: Vec<f64>,
    h1: Vec<u64>,
    k: Vec<u32>,
    /// Per class: the block range last looked up and the arena ranges of its blocks (x fastest).
    last: Vec<Option<(Cell, Cell)>>,
    handles: Vec<Vec<(u32, u32)>>,
    spare: Vec<(u32, u32)>,
    /// The list of the cell asked for last.
    scratch: Vec<Sphere>,
}

impl Default for LazyCache {
    fn default() -> Self {
        Self::with_isa(Isa::detect())
    }
}

impl LazyCache {
    /// An empty cache whose list builder uses `isa` (downgraded to what this CPU has).
    pub fn with_isa(isa: Isa) -> Self {
        let best = Isa::detect();
        let isa = match (isa, best) {
            (Isa::Avx512, Isa::Avx512) => Isa::Avx512,
            (Isa::Avx512 | Isa::Avx2, Isa::Avx512 | Isa::Avx2) => Isa::Avx2,
            _ => Isa::Portable,
        };
        Self {
            isa,
            table: Vec::new(),
            stamp: 0,
            used: 0,
            cx: Vec::new(),
            cy: Vec::new(),
            cz: Vec::new(),
            r: Vec::new(),
            h1: Vec::new(),
            k: Vec::new(),
            last: Vec::new(),
            handles: Vec::new(),
            spare: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The instruction set its list builder uses.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Spheres in the arena (the centre arrays hold [`PAD`] more).
    #[inline(always)]
    fn generated(&self) -> usize {
        self.r.len()
    }

    /// Forgets everything, keeping the allocations.
    fn clear(&mut self, classes: usize) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.table.iter_mut().for_each(|s| s.stamp = 0);
            self.stamp = 1;
        }
        self.used = 0;
        for v in [&mut self.cx, &mut self.cy, &mut self.cz] {
            v.clear();
            v.extend_from_slice(&[f64::NAN; PAD]);
        }
        self.r.clear();
        self.h1.clear();
        self.k.clear();
        self.last.clear();
        self.last.resize(classes, None);
        self.handles.resize_with(classes, Vec::new);
        self.scratch.clear();
        if self.table.is_empty() {
            self.table = vec![Slot::default(); 1 << 12];
        }
    }

    #[inline(always)]
    fn hash(class: usize, b: Cell) -> u64 {
        // Neighbouring blocks must not cluster in the table: mix every bit into the low ones.
        mix64(
            (b[0] as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ (b[1] as u64)
                    .wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
                    .rotate_left(21)
                ^ (b[2] as u64)
                    .wrapping_mul(0x1656_67b1_9e37_79f9)
                    .rotate_left(42)
                ^ class as u64,
        )
    }

    /// The table slot of (class, b): the live entry if there is one, else the empty slot to fill.
    #[inline(always)]
    fn find(&self, class: usize, b: Cell) -> (usize, bool) {
        let mask = self.table.len() - 1;
        let mut i = Self::hash(class, b) as usize & mask;
        loop {
            let s = &self.table[i];
            if s.stamp != self.stamp {
                return (i, false);
            }
            if s.key == b && s.class == class as u8 {
                return (i, true);
            }
            i = (i + 1) & mask;
        }
    }

    fn grow(&mut self) {
        let live: Vec<Slot> = self
            .table
            .iter()
            .filter(|s| s.stamp == self.stamp)
            .copied()
            .collect();
        self.table = vec![Slot::default(); self.table.len() * 2];
        self.stamp = 1;
        for s in live {
            let (i, _) = self.find(s.class as usize, s.key);
            self.table[i] = Slot { stamp: 1, ..s };
        }
    }
}

/// Cell lists of a [`LazyScene`], built on request from the blocks within reach (generated on
/// first use and memoised for the batch).
#[derive(Debug)]
pub struct LazyCells<'a> {
    scene: &'a LazyScene,
    frame: GridFrame,
    eye_magnitude: f64,
    cache: &'a mut LazyCache,
}

impl LazyCells<'_> {
    /// Number of spheres generated so far (the memory this batch holds).
    pub fn generated(&self) -> usize {
        self.cache.generated()
    }

    /// The arena range of block `b` of `class`, generating it on first use.
    #[inline(always)]
    fn block(&mut self, class: usize, b: Cell) -> (u32, u32) {
        let (i, found) = self.cache.find(class, b);
        if found {
            let s = &self.cache.table[i];
            return (s.start, s.start + s.count);
        }
        let c = &mut *self.cache;
        let start = c.generated() as u32;
        for v in [&mut c.cx, &mut c.cy, &mut c.cz] {
            v.truncate(start as usize);
        }
        self.scene.generate_with(class, b, |p, r, h1, k| {
            c.cx.push(p.x);
            c.cy.push(p.y);
            c.cz.push(p.z);
            c.r.push(r);
            c.h1.push(h1);
            c.k.push(k);
        });
        let end = c.cx.len() as u32;
        for v in [&mut c.cx, &mut c.cy, &mut c.cz] {
            v.extend_from_slice(&[f64::NAN; PAD]);
        }
        c.table[i] = Slot {
            key: b,
            start,
            count: end - start,
            class: u8::try_from(class).expect("fewer than 256 radius classes"),
            stamp: c.stamp,
        };
        c.used += 1;
        if 2 * c.used > c.table.len() {
            c.grow();
        }
        (start, end)
    }

    /// [`Self::build_list`] compiled for AVX-512 (the same operations, so the same lists).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx2,bmi2")]
    unsafe fn build_list_avx512(&mut self, cell: Cell) {
        self.build_list(cell);
    }

    /// [`Self::build_list`] compiled for AVX2 (the same operations, so the same lists).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi2")]
    unsafe fn build_list_avx2(&mut self, cell: Cell) {
        self.build_list(cell);
    }

    /// Builds the list of `cell` into the scratch buffer: every sphere of the blocks within reach
    /// (the first version's block range) whose padded ball overlaps the cell. A box test against
    /// the cell's reach box, widened far beyond any rounding of the exact test, skips the exact
    /// test for most of them.
    #[inline(always)]
    fn build_list(&mut self, cell: Cell) {
        let cb = self.frame.cell_box(cell);
        let magnitude = self.pad_magnitude(cell);
        self.cache.scratch.clear();
        let (lo, hi) = (cb.lo.to_array(), cb.hi.to_array());
        for class in 0..self.scene.classes.len() {
            let reach_r = self.scene.reach(class);
            let reach = reach_r + self.frame.pad(magnitude, reach_r);
            let g = self.scene.gen[class].g;
            let elo = cb.lo - DVec3::splat(reach);
            let ehi = cb.hi + DVec3::splat(reach);
            let (bl, bh) = ((elo / g).floor(), (ehi / g).floor());
            let bl = [bl.x as i64, bl.y as i64, bl.z as i64];
            let bh = [bh.x as i64, bh.y as i64, bh.z as i64];
            if self.cache.last[class] != Some((bl, bh)) {
                // Blocks of the previous range are reused from its handles (consecutive cells of a
                // walk share most of them); only the new ones are looked up in the table.
                let prev = self.cache.last[class];
                let mut handles = std::mem::take(&mut self.cache.spare);
                handles.clear();
                for z in bl[2]..=bh[2] {
                    for y in bl[1]..=bh[1] {
                        for x in bl[0]..=bh[0] {
                            let old = prev.and_then(|(pl, ph)| {
                                let inside = (0..3).all(|i| {
                                    let v = [x, y, z][i];
                                    v >= pl[i] && v <= ph[i]
                                });
                                inside.then(|| {
                                    let (nx, ny) = (ph[0] - pl[0] + 1, ph[1] - pl[1] + 1);
                                    let at = (x - pl[0]) + nx * ((y - pl[1]) + ny * (z - pl[2]));
                                    self.cache.handles[class][at as usize]
                                })
                            });
                            handles.push(match old {
                                Some(h) => h,
                                None => self.block(class, [x, y, z]),
                            });
                        }
                    }
                }
                self.cache.spare = std::mem::replace(&mut self.cache.handles[class], handles);
                self.cache.last[class] = Some((bl, bh));
            }
            // Every sphere the exact test accepts has its centre within `reach` of the cell, up to
            // rounding; `delta` exceeds that rounding by orders of magnitude.
            let delta = 1e-9 * (elo.abs().max(ehi.abs()).max_element() + g);
            let (qlo, qhi) = (
                (elo - DVec3::splat(delta)).to_array(),
                (ehi + DVec3::splat(delta)).to_array(),
            );
            let c = &mut *self.cache;
            for &(s, e) in &c.handles[class] {
                let (s, e) = (s as usize, e as usize);
                let mut i = s;
                if s == e {
                    continue;
                }
                while i < e {
                    // Eight at a time, branch-free (the arena has PAD readable slots past its end).
                    let lane =
                        |v: &[f64]| -> [f64; PAD] { v[i..i + PAD].try_into().expect("PAD lanes") };
                    let (xs, ys, zs) = (lane(&c.cx), lane(&c.cy), lane(&c.cz));
                    let mut mask = 0u32;
                    for j in 0..PAD {
                        let near = (xs[j] >= qlo[0])
                            & (xs[j] <= qhi[0])
                            & (ys[j] >= qlo[1])
                            & (ys[j] <= qhi[1])
                            & (zs[j] >= qlo[2])
                            & (zs[j] <= qhi[2]);
                        mask |= u32::from(near) << j;
                    }
                    if e - i < PAD {
                        mask &= (1u32 << (e - i)) - 1;
                    }
                    while mask != 0 {
                        let j = i + mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let (x, y, z) = (c.cx[j], c.cy[j], c.cz[j]);
                        let d = |p: f64, l: f64, h: f64| {
                            let q = if p < l {
                                l
                            } else if p > h {
                                h
                            } else {
                                p
                            };
                            p - q
                        };
                        let (dx, dy, dz) =
                            (d(x, lo[0], hi[0]), d(y, lo[1], hi[1]), d(z, lo[2], hi[2]));
                        let r = c.r[j];
                        let rr = r + self.frame.pad(magnitude, r);
                        if dx * dx + dy * dy + dz * dz <= rr * rr {
                            c.scratch.push(Sphere {
                                c: DVec3::new(x, y, z),
                                r,
                                id: sphere_id(c.h1[j], c.k[j]),
                            });
                        }
                    }
                    i += PAD;
                }
            }
        }
    }
}

impl CellLists for LazyCells<'_> {
    fn frame(&self) -> &GridFrame {
        &self.frame
    }

    #[inline]
    fn pad_magnitude(&self, cell: Cell) -> f64 {
        self.frame.cell_box(cell).magnitude() + self.eye_magnitude
    }

    #[inline]
    fn list(&mut self, cell: Cell) -> &[Sphere] {
        match self.cache.isa {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Isa::Avx512` is detected only where the CPU has AVX-512 F and VL.
            Isa::Avx512 => unsafe { self.build_list_avx512(cell) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Isa::Avx2` is detected only where the CPU has AVX2.
            Isa::Avx2 => unsafe { self.build_list_avx2(cell) },
            _ => self.build_list(cell),
        }
        &self.cache.scratch
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RadiusDist;
    use rand::Rng;

    #[test]
    fn blocks_are_reproducible_and_have_poisson_counts() {
        let classes = [RadiusClass {
            fraction: 1.0,
            radius: RadiusDist::Constant(0.1),
        }];
        let s = LazyScene::new(1.0, &classes, RadiusDraw::PerSphere, 0.5, &[1]);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        s.generate_block(0, [3, -4, 5], &mut a);
        s.generate_block(0, [3, -4, 5], &mut b);
        assert_eq!(a, b);
        let spheres = s.spheres_in(DVec3::splat(-10.0), DVec3::splat(10.0));
        let mu = 8000.0;
        assert!(
            (spheres.len() as f64 - mu).abs() < 5.0 * mu.sqrt(),
            "{}",
            spheres.len()
        );
    }

    fn classes() -> Vec<RadiusClass> {
        vec![
            RadiusClass {
                fraction: 0.7,
                radius: RadiusDist::Constant(0.1),
            },
            RadiusClass {
                fraction: 0.3,
                radius: RadiusDist::Uniform { lo: 0.2, hi: 0.6 },
            },
        ]
    }

    /// `hash_step` chains reproduce `hash_key`, so ids and block keys are the first version's.
    #[test]
    fn incremental_hashes_equal_hash_key() {
        for (key, k) in [
            (0u64, 0u32),
            (u64::MAX, 7),
            (0x1234_5678_9abc_def0, 123_456),
        ] {
            let h1 = hash_step(HASH_INIT ^ 2, key);
            assert_eq!(sphere_id(h1, k), hash_key(&[key, u64::from(k)]));
        }
    }

    /// The tabled Poisson draw equals `sample::poisson` on the same stream, for many seeds and
    /// means (including the tail beyond the table and the other sampler from 30 on).
    #[test]
    fn tabled_poisson_equals_the_sampler() {
        for mu in [0.01, 0.125, 1.0, 8.0, 17.3, 29.9, 30.0, 108.0] {
            let cdf = poisson_cdf(mu);
            for seed in 0..20_000u64 {
                let (mut a, mut b) = (SplitMix64::new(seed), SplitMix64::new(seed));
                assert_eq!(
                    poisson_from_table(&mut a, mu, &cdf),
                    crate::sample::poisson(&mut b, mu),
                    "mu {mu} seed {seed}"
                );
            }
        }
    }

    /// Every cell list, on every instruction-set path this CPU has, equals the definition: the
    /// spheres of the blocks within reach whose padded ball meets the cell (as a multiset, with
    /// the same ids and values), on walks through cells near and far from the origin.
    #[test]
    fn cell_lists_equal_the_definition_on_every_path() {
        use crate::grid::Dda;
        let classes = classes();
        let mut paths = vec![Isa::Portable];
        if Isa::detect() != Isa::Portable {
            paths.push(Isa::Avx2);
        }
        if Isa::detect() == Isa::Avx512 {
            paths.push(Isa::Avx512);
        }
        let mut rng = stream(&[0x1a2b]);
        let mut checked = 0;
        for &isa in &paths {
            let mut cache = LazyCache::with_isa(isa);
            assert_eq!(cache.isa(), isa);
            for (case, (a, offset)) in [(0.5, 0.0), (0.37, 3.3), (1.3, -1e4), (0.2, 1e6)]
                .into_iter()
                .enumerate()
            {
                let scene =
                    LazyScene::new(1.0, &classes, RadiusDraw::PerSphere, a, &[5, case as u64]);
                let frame = GridFrame {
                    origin: DVec3::ZERO,
                    width: a,
                    dims: None,
                };
                let eye = DVec3::splat(offset) + DVec3::new(rng.gen(), rng.gen(), rng.gen()) * a;
                let eye_mag = eye.abs().max_element() + a;
                let mut lists = scene.cells(frame, eye_mag, &mut cache);
                for _ in 0..30 {
                    let d = crate::sample::directions::uniform_direction(&mut rng);
                    let ray = crate::geom::Ray::new(eye, d);
                    for (cell, _, _) in Dda::new(&frame, &ray).take(40) {
                        let mut got = lists.list(cell).to_vec();
                        // The definition, from scratch.
                        let cb = frame.cell_box(cell);
                        let m = lists.pad_magnitude(cell);
                        let mut want = Vec::new();
                        for class in 0..classes.len() {
                            let rr = scene.reach(class) + frame.pad(m, scene.reach(class));
                            let g = scene.gen[class].g;
                            let bl = ((cb.lo - DVec3::splat(rr)) / g).floor();
                            let bh = ((cb.hi + DVec3::splat(rr)) / g).floor();
                            for z in bl.z as i64..=bh.z as i64 {
                                for y in bl.y as i64..=bh.y as i64 {
                                    for x in bl.x as i64..=bh.x as i64 {
                                        let mut blk = Vec::new();
                                        scene.generate_block(class, [x, y, z], &mut blk);
                                        want.extend(blk.into_iter().filter(|s| {
                                            let p = s.r + frame.pad(m, s.r);
                                            cb.distance_squared(s.c) <= p * p
                                        }));
                                    }
                                }
                            }
                        }
                        let key = |s: &Sphere| (s.id, s.c.x.to_bits(), s.r.to_bits());
                        got.sort_by_key(key);
                        want.sort_by_key(key);
                        assert_eq!(got, want, "{isa:?} case {case} cell {cell:?}");
                        checked += want.len();
                    }
                }
            }
        }
        assert!(checked > 2000 * paths.len(), "checked {checked}");
    }

    /// The lazy scene is a homogeneous marked Poisson process: over independent realisations, the
    /// count in a unit cube has mean = variance = ρV (each within 4 standard errors), the
    /// nearest-neighbour distance follows P(D > s) = exp(−ρ·4πs³/3), and the class fractions are
    /// α_i. Tolerances are 4 standard errors of each estimate (so a correct process fails about
    /// once in 10⁴ runs), never tuned.
    #[test]
    fn lazy_scene_is_a_poisson_process() {
        let rho = 2.0;
        let classes = classes();
        let reps = 4000;
        let mut counts = Vec::with_capacity(reps);
        let mut class_n = [0u64; 2];
        // Per realisation: (centres in the cube whose nearest neighbour is beyond s_half, centres).
        let mut nn: Vec<(f64, f64)> = Vec::with_capacity(reps);
        // P(D > s) at the distance where it is 1/2.
        let s_half = (0.5f64.ln() / (-rho * 4.0 / 3.0 * std::f64::consts::PI)).cbrt();
        for rep in 0..reps {
            let scene = LazyScene::new(
                rho,
                &classes,
                RadiusDraw::PerSphere,
                0.5,
                &[0x9015, rep as u64],
            );
            // Cube placement varies with the realisation, straddling block faces.
            let lo = DVec3::splat(rep as f64 * 0.37 - 700.0);
            let inner = scene.spheres_in(lo, lo + DVec3::ONE);
            counts.push(inner.len() as f64);
            for s in &inner {
                class_n[usize::from(s.r > 0.15)] += 1;
            }
            // Nearest-neighbour distances of every centre in the cube, among all centres within
            // reach (a box wide enough that P(D > half-width) is negligible). Summed over the
            // cube's centres, this estimates the Palm probability without selection bias (Campbell).
            let w = 3.0 * s_half;
            let around = scene.spheres_in(lo - DVec3::splat(w), lo + DVec3::splat(1.0 + w));
            let mut far = 0u64;
            for p in &inner {
                let d = around
                    .iter()
                    .filter(|q| q.id != p.id)
                    .map(|q| q.c.distance(p.c))
                    .fold(f64::INFINITY, f64::min);
                far += u64::from(d > s_half);
            }
            nn.push((far as f64, inner.len() as f64));
        }
        let n = reps as f64;
        let mean = counts.iter().sum::<f64>() / n;
        let var = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // Poisson(λ): SE of the mean √(λ/n); SE of the sample variance √((2λ² + λ)/n).
        let lambda = rho;
        let se_mean = (lambda / n).sqrt();
        let se_var = ((2.0 * lambda * lambda + lambda) / n).sqrt();
        assert!(
            (mean - lambda).abs() < 4.0 * se_mean,
            "mean {mean} vs {lambda}"
        );
        assert!(
            (var - lambda).abs() < 4.0 * se_var,
            "variance {var} vs {lambda}"
        );
        // Class fractions: binomial SE.
        let total = (class_n[0] + class_n[1]) as f64;
        let f0 = class_n[0] as f64 / total;
        let se_f = (0.7 * 0.3 / total).sqrt();
        assert!((f0 - 0.7).abs() < 4.0 * se_f, "class fraction {f0}");
        // Nearest neighbour: a ratio estimator over realisations, its standard error clustered by
        // realisation (the centres of one realisation share neighbours).
        let (far, all): (f64, f64) = nn.iter().fold((0.0, 0.0), |a, x| (a.0 + x.0, a.1 + x.1));
        let p = far / all;
        let se_p = nn
            .iter()
            .map(|x| (x.0 - p * x.1).powi(2))
            .sum::<f64>()
            .sqrt()
            / all;
        assert!(all > 5000.0, "{all}");
        assert!((p - 0.5).abs() < 4.0 * se_p, "P(D > s_half) = {p} ± {se_p}");
    }
}
