//! The infinite Poisson scene, generated lazily where rays go: the paper's n → ∞ limit with no
//! boundary at all.
//!
//! # The process
//! Space is cut into cubic generation blocks of width `g` on a lattice offset by `−R` (R a little
//! over the largest radius). Block `b` holds a Poisson(ρ·g³) count of centres, uniform in the block,
//! each with an independent mark: its radius class (probability α_i) and its radius. The stream of
//! a block is keyed by (realisation seed, block) only, so any block can be produced on demand, in
//! any order, by any thread, and always comes out the same. Disjoint blocks with independent
//! Poisson counts of uniform points make a homogeneous Poisson process of intensity ρ, and
//! independent marks make the class-i spheres independent Poisson processes of intensity α_i·ρ
//! (the marking theorem), which is the paper's mixture.
//!
//! # Why this layout
//! A ray walks ~1.5·L/a cells (L ≈ 1/(ρπr²) its free path) and needs only the spheres within reach
//! of them. The block width is the cell width divided by a whole number (about one or two centres
//! per block), and the lattice is shifted by −R: a cell's reach box `[ka − R, (k+1)a + R]` then
//! spans exactly two blocks per axis when `g = a`, and a step of the walk brings in one new layer of
//! four blocks. Blocks live in a small direct-mapped window ([`LazyCache`]) indexed by the block
//! coordinates modulo its width: the blocks one cell needs never collide, a walk reuses the blocks
//! of the previous cell, and the memory held is a few kilobytes whatever the ray's length — the
//! scene is modelled only where rays go, and nothing is kept that no ray will read again.
//!
//! The first version used blocks of about eight centres fixed at width 2 with no offset, memoised
//! per batch in a hash map: at a = 0.5 each cell gathered ~27 candidates from up to eight blocks
//! and a batch's spheres overflowed the L2 cache (docs/bench.md, the infinite scene).
//!
//! # What is exact
//! A cell's list is every sphere whose padded ball meets the cell: the blocks scanned cover the
//! cell's reach box widened past any rounding, and each candidate is tested exactly. The tests
//! check every list against a brute-force enumeration of the centres near the cell.

use glam::DVec3;
use rand::Rng;

use super::{ClassMarks, RadiusClass, RadiusDraw};
use crate::geom::Sphere;
use crate::grid::{Cell, CellLists, GridFrame};
use crate::sample::{counter::SplitMix64, rng::mix64, rng::stream, PoissonTable};

/// Odd multipliers that spread block coordinates before mixing (one per axis).
const AXIS_MUL: [u64; 3] = [
    0x9e37_79b9_7f4a_7c15,
    0xc2b2_ae3d_27d4_eb4f,
    0x1656_67b1_9e37_79f9,
];
/// Multiplier of a sphere's index inside its block, for its id.
const ID_MUL: u64 = 0xd6e8_feb8_6659_fd93;
/// Target mean centres per block: few candidates per cell, few empty blocks.
const CENTRES_PER_BLOCK: f64 = 1.5;
/// Most blocks per axis a cell may span; wider reach boxes get wider (unaligned) blocks.
const MAX_SPAN: usize = 16;

/// One realisation of an infinite Poisson sphere scene.
#[derive(Clone, Debug)]
pub struct LazyScene {
    seed: u64,
    classes: Vec<RadiusClass>,
    draw: RadiusDraw,
    /// Radius of each class when drawn per scene.
    per_scene: Vec<f64>,
    /// The class mark's draw.
    marks: ClassMarks,
    /// Largest radius over the classes in this realisation.
    r_max: f64,
    /// Block width g and the lattice offset: block `b` spans `off + g·[b, b + 1)` per axis.
    g: f64,
    off: f64,
    /// The Poisson law of a block's count, mean ρ·g³.
    count: PoissonTable,
    /// Width of the block window (a power of two ≥ the blocks a cell spans per axis).
    window: usize,
}

impl LazyScene {
    /// The realisation keyed by `key`; `cell_width` sets the block lattice (blocks are aligned with
    /// the cells of a grid of that width placed at the origin, which is what makes walks cheap).
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
        let marks = ClassMarks::new(classes);
        let reach = |i: usize| match draw {
            RadiusDraw::PerScene => per_scene[i],
            RadiusDraw::PerSphere => classes[i].radius.max(),
        };
        let r_max = (0..classes.len()).map(reach).fold(0.0, f64::max);
        // Cell-aligned blocks of about CENTRES_PER_BLOCK centres (a whole number per cell width).
        let by_count = (CENTRES_PER_BLOCK / intensity).cbrt();
        let per_cell = (cell_width / by_count).round().max(1.0);
        let mut g = cell_width / per_cell;
        // The offset exceeds any listing pad near the origin, so a cell's reach box starts exactly
        // on a block face; farther out it may start one block early, which costs time, not truth.
        let big_r = r_max + cell_width * super::tube::REACH_MARGIN;
        let spanned = |g: f64| ((cell_width + 2.0 * big_r) / g).floor() as usize + 2;
        if spanned(g) > MAX_SPAN {
            g = (cell_width + 2.0 * big_r) / (MAX_SPAN - 2) as f64;
        }
        let window = spanned(g).min(MAX_SPAN).next_power_of_two();
        let mu = intensity * g * g * g;
        Self {
            seed,
            classes: classes.to_vec(),
            draw,
            per_scene,
            marks,
            r_max,
            g,
            off: -big_r,
            count: PoissonTable::new(mu),
            window,
        }
    }

    /// Largest radius of class `i` in this realisation.
    #[cfg(test)]
    fn reach(&self, i: usize) -> f64 {
        match self.draw {
            RadiusDraw::PerScene => self.per_scene[i],
            RadiusDraw::PerSphere => self.classes[i].radius.max(),
        }
    }

    /// The block width (for tests and the bench's report).
    pub fn block_width(&self) -> f64 {
        self.g
    }

    /// The hashed key of block `b`: three chained bijective mixes, so distinct blocks get
    /// independent-looking streams (collisions about 2⁻⁶⁴ per pair).
    #[inline(always)]
    fn block_key(&self, b: Cell) -> u64 {
        let h = mix64(self.seed ^ (b[0] as u64).wrapping_mul(AXIS_MUL[0]));
        let h = mix64(h ^ (b[1] as u64).wrapping_mul(AXIS_MUL[1]));
        mix64(h ^ (b[2] as u64).wrapping_mul(AXIS_MUL[2]))
    }

    /// Generates block `b` into `out` (appended): count, then per centre its position, class and
    /// radius, all from the block's own stream.
    #[inline]
    pub fn generate_block(&self, b: Cell, out: &mut Vec<Sphere>) {
        let key = self.block_key(b);
        let mut rng = SplitMix64::new(key);
        let n = self.count.sample(&mut rng);
        let g = self.g;
        let lo = DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64) * g + DVec3::splat(self.off);
        for k in 0..n {
            let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
            let class = self.marks.draw(&mut rng);
            let r = match self.draw {
                RadiusDraw::PerScene => self.per_scene[class],
                RadiusDraw::PerSphere => self.classes[class].radius.sample(&mut rng),
            };
            out.push(Sphere {
                c: lo + u * g,
                r,
                id: mix64(key ^ (k + 1).wrapping_mul(ID_MUL)),
            });
        }
    }

    /// The blocks whose centres may lie in `[lo, hi]` (widened past rounding), per axis.
    fn block_range(&self, lo: DVec3, hi: DVec3) -> (Cell, Cell) {
        let delta = 1e-9 * (lo.abs().max(hi.abs()).max_element() + self.g);
        let bl = ((lo - DVec3::splat(delta + self.off)) / self.g).floor();
        let bh = ((hi + DVec3::splat(delta - self.off)) / self.g).floor();
        (
            [bl.x as i64, bl.y as i64, bl.z as i64],
            [bh.x as i64, bh.y as i64, bh.z as i64],
        )
    }

    /// Every sphere whose centre lies in the axis box `[lo, hi]` (for oracles and tests).
    pub fn spheres_in(&self, lo: DVec3, hi: DVec3) -> Vec<Sphere> {
        let mut out = Vec::new();
        let (bl, bh) = self.block_range(lo, hi);
        for z in bl[2]..=bh[2] {
            for y in bl[1]..=bh[1] {
                for x in bl[0]..=bh[0] {
                    self.generate_block([x, y, z], &mut out);
                }
            }
        }
        out.retain(|s| s.c.cmpge(lo).all() && s.c.cmple(hi).all());
        out
    }

    /// A cell-list source over this realisation for a grid placed by `frame` (unbounded), using
    /// (and first clearing) `cache`: one cache per thread, reused realisation after realisation.
    pub fn cells<'a>(
        &'a self,
        frame: GridFrame,
        eye_magnitude: f64,
        cache: &'a mut LazyCache,
    ) -> LazyCells<'a> {
        cache.reset(self.window);
        LazyCells {
            scene: self,
            frame,
            eye_magnitude,
            cache,
        }
    }
}

/// One slot of the block window: which block it holds (if its stamp is current) and its spheres.
#[derive(Clone, Debug, Default)]
struct Slot {
    key: Cell,
    stamp: u32,
    spheres: Vec<Sphere>,
}

/// The buffers behind [`LazyCells`]: a direct-mapped window of generated blocks (slot = block
/// coordinates modulo the window width, per axis) and the list buffer. Reused across
/// realisations; clearing is one stamp increment.
#[derive(Debug, Default)]
pub struct LazyCache {
    slots: Vec<Slot>,
    /// log2 of the window width.
    bits: u32,
    stamp: u32,
    generated: usize,
    scratch: Vec<Sphere>,
}

impl LazyCache {
    /// Forgets every block (a new realisation) and sizes the window.
    fn reset(&mut self, window: usize) {
        let bits = window.trailing_zeros();
        if self.slots.len() != window * window * window {
            self.slots = vec![Slot::default(); window * window * window];
            self.stamp = 0;
        }
        self.bits = bits;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.slots.iter_mut().for_each(|s| s.stamp = 0);
            self.stamp = 1;
        }
        self.generated = 0;
        self.scratch.clear();
    }

    /// The slot of block `b`.
    #[inline(always)]
    fn slot_of(&self, b: Cell) -> usize {
        let m = (1i64 << self.bits) - 1;
        ((b[0] & m) | (b[1] & m) << self.bits | (b[2] & m) << (2 * self.bits)) as usize
    }
}

/// Cell lists of a [`LazyScene`], built on request from the blocks within reach.
#[derive(Debug)]
pub struct LazyCells<'a> {
    scene: &'a LazyScene,
    frame: GridFrame,
    eye_magnitude: f64,
    cache: &'a mut LazyCache,
}

impl LazyCells<'_> {
    /// Spheres generated so far for this realisation (blocks generated again after leaving the
    /// window count again: this is the generation work, not the scene's size).
    pub fn generated(&self) -> usize {
        self.cache.generated
    }

    /// Builds the list of `cell` into the scratch buffer: every sphere of the blocks covering the
    /// cell's reach box whose padded ball meets the cell.
    #[inline]
    fn build_list(&mut self, cell: Cell) {
        let scene = self.scene;
        let cb = self.frame.cell_box(cell);
        let magnitude = self.pad_magnitude(cell);
        let reach = scene.r_max + self.frame.pad(magnitude, scene.r_max);
        let (bl, bh) = scene.block_range(cb.lo - DVec3::splat(reach), cb.hi + DVec3::splat(reach));
        let (lo, hi) = (cb.lo, cb.hi);
        let c = &mut *self.cache;
        c.scratch.clear();
        for z in bl[2]..=bh[2] {
            for y in bl[1]..=bh[1] {
                for x in bl[0]..=bh[0] {
                    let b = [x, y, z];
                    let i = c.slot_of(b);
                    let slot = &mut c.slots[i];
                    if slot.stamp != c.stamp || slot.key != b {
                        slot.spheres.clear();
                        scene.generate_block(b, &mut slot.spheres);
                        slot.key = b;
                        slot.stamp = c.stamp;
                        c.generated += slot.spheres.len();
                    }
                    for s in &slot.spheres {
                        let q = s.c.clamp(lo, hi);
                        let rr = s.r + self.frame.pad(magnitude, s.r);
                        if (s.c - q).length_squared() <= rr * rr {
                            c.scratch.push(*s);
                        }
                    }
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
        self.build_list(cell);
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
        s.generate_block([3, -4, 5], &mut a);
        s.generate_block([3, -4, 5], &mut b);
        assert_eq!(a, b);
        let spheres = s.spheres_in(DVec3::splat(-10.0), DVec3::splat(10.0));
        let mu = 8000.0;
        assert!(
            (spheres.len() as f64 - mu).abs() < 5.0 * mu.sqrt(),
            "{}",
            spheres.len()
        );
        // Every centre lies in its own block, and ids are distinct.
        let mut ids: Vec<u64> = spheres.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), spheres.len());
    }

    /// Blocks are aligned with the cells: at g = a a cell's reach box spans two blocks per axis.
    #[test]
    fn blocks_align_with_cells() {
        let classes = [RadiusClass {
            fraction: 1.0,
            radius: RadiusDist::Constant(0.1),
        }];
        for (a, per_cell) in [(0.5, 1.0), (1.0, 1.0), (2.36, 2.0), (3.0, 3.0)] {
            let s = LazyScene::new(1.0, &classes, RadiusDraw::PerSphere, a, &[2]);
            assert_eq!(s.block_width(), a / per_cell, "a = {a}");
            let frame = GridFrame {
                origin: DVec3::ZERO,
                width: a,
                dims: None,
            };
            let cb = frame.cell_box([7, -3, 2]);
            let reach = 0.1 + frame.pad(cb.magnitude(), 0.1);
            let (bl, bh) = s.block_range(cb.lo - DVec3::splat(reach), cb.hi + DVec3::splat(reach));
            for i in 0..3 {
                assert_eq!(bh[i] - bl[i] + 1, per_cell as i64 + 1, "a = {a}");
            }
        }
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

    /// Every cell list equals the definition: among all centres within the largest padded reach
    /// of the cell (enumerated from scratch), those whose padded ball meets the cell, with the same
    /// ids and values. Walks start near and far from the origin, with cells narrower and wider
    /// than the spheres, and realisations change under one cache (so stale slots would show).
    #[test]
    fn cell_lists_equal_the_definition() {
        use crate::grid::Dda;
        let classes = classes();
        let mut rng = stream(&[0x1a2b]);
        let mut checked = 0;
        let mut cache = LazyCache::default();
        for (case, (a, offset, rho)) in [
            (0.5, 0.0, 1.0),
            (0.37, 3.3, 2.0),
            (1.3, -1e4, 1.0),
            (0.2, 1e6, 1.0),
            (3.0, -7.0, 4.0),
            (0.1, 0.5, 8.0),
        ]
        .into_iter()
        .enumerate()
        {
            for draw in [RadiusDraw::PerSphere, RadiusDraw::PerScene] {
                let scene = LazyScene::new(rho, &classes, draw, a, &[5, case as u64]);
                let frame = GridFrame {
                    origin: DVec3::ZERO,
                    width: a,
                    dims: None,
                };
                let eye = DVec3::splat(offset) + DVec3::new(rng.gen(), rng.gen(), rng.gen()) * a;
                let eye_mag = eye.abs().max_element() + a;
                let mut lists = scene.cells(frame, eye_mag, &mut cache);
                for _ in 0..20 {
                    let d = crate::sample::directions::uniform_direction(&mut rng);
                    let ray = crate::geom::Ray::new(eye, d);
                    for (cell, _, _) in Dda::new(&frame, &ray).take(40) {
                        let mut got = lists.list(cell).to_vec();
                        let cb = frame.cell_box(cell);
                        let m = lists.pad_magnitude(cell);
                        let r_max = (0..classes.len())
                            .map(|i| scene.reach(i))
                            .fold(0.0, f64::max);
                        let w = DVec3::splat(r_max + frame.pad(m, r_max) + 1e-6);
                        let mut want: Vec<Sphere> = scene
                            .spheres_in(cb.lo - w, cb.hi + w)
                            .into_iter()
                            .filter(|s| {
                                let p = s.r + frame.pad(m, s.r);
                                cb.distance_squared(s.c) <= p * p
                            })
                            .collect();
                        let key = |s: &Sphere| (s.id, s.c.x.to_bits(), s.r.to_bits());
                        got.sort_by_key(key);
                        want.sort_by_key(key);
                        assert_eq!(got, want, "case {case} {draw:?} cell {cell:?}");
                        checked += want.len();
                    }
                }
            }
        }
        assert!(checked > 5000, "checked {checked}");
    }

    /// A realisation is a pure function of its key: the same lists whatever the cache saw before.
    #[test]
    fn lists_do_not_depend_on_the_cache_history() {
        let classes = classes();
        let frame = GridFrame {
            origin: DVec3::ZERO,
            width: 0.5,
            dims: None,
        };
        let scene = LazyScene::new(1.0, &classes, RadiusDraw::PerSphere, 0.5, &[9]);
        let other = LazyScene::new(1.0, &classes, RadiusDraw::PerSphere, 0.5, &[10]);
        let cells: Vec<Cell> = (0..200).map(|i| [i % 7, (i * 3) % 11 - 5, i / 9]).collect();
        let mut fresh = LazyCache::default();
        let mut lists = scene.cells(frame, 1.0, &mut fresh);
        let want: Vec<Vec<Sphere>> = cells.iter().map(|&c| lists.list(c).to_vec()).collect();
        let mut used = LazyCache::default();
        {
            let mut l = other.cells(frame, 1.0, &mut used);
            for &c in &cells {
                l.list(c);
            }
        }
        let mut lists = scene.cells(frame, 1.0, &mut used);
        for (c, w) in cells.iter().zip(&want) {
            assert_eq!(lists.list(*c), &w[..]);
        }
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
