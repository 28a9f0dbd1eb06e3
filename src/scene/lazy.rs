//! The infinite Poisson scene, generated lazily where rays go: the paper's n → ∞ limit with no
//! boundary at all.
//!
//! Space is cut into generation blocks (per class, of width `G_i`). The centres in a block are a
//! Poisson(α_i·ρ·G_i³) count of uniform points drawn from a stream keyed by (scene seed, class,
//! block), so any block can be produced on demand, in any order, and always comes out the same.
//! A grid cell's list gathers the spheres of the blocks within reach (cell ± largest radius) that
//! really overlap the cell. Both blocks and cell lists are cached for one batch of rays, which shares
//! one scene realisation; the caches are dropped with the batch, so memory grows with what one batch
//! traces, never with the universe.

use crate::sample::directions::uniform_unit_cube;
use glam::DVec3;
use rand::Rng;
use rustc_hash::FxHashMap;

use super::{RadiusClass, RadiusDraw};
use crate::geom::Sphere;
use crate::grid::{Cell, CellLists, GridFrame};
use crate::sample::{counter::SplitMix64, rng::domain, rng::hash_key, rng::stream};

/// One realisation of an infinite Poisson sphere scene.
#[derive(Clone, Debug)]
pub struct LazyScene {
    seed: u64,
    intensity: f64,
    classes: Vec<RadiusClass>,
    draw: RadiusDraw,
    /// Radius of each class when drawn per scene.
    per_scene: Vec<f64>,
    /// Generation block width per class.
    block: Vec<f64>,
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
        let block = classes
            .iter()
            .map(|c| {
                // About 8 centres per block, but never narrower than a cell or a sphere diameter:
                // a cell then gathers from few blocks, and blocks are not mostly empty.
                let by_count = (8.0 / (intensity * c.fraction)).cbrt();
                by_count.max(cell_width).max(2.0 * c.radius.max())
            })
            .collect();
        Self {
            seed: rng.gen(),
            intensity,
            classes: classes.to_vec(),
            draw,
            per_scene,
            block,
        }
    }

    /// Largest radius of class `i` in this realisation.
    fn reach(&self, i: usize) -> f64 {
        match self.draw {
            RadiusDraw::PerScene => self.per_scene[i],
            RadiusDraw::PerSphere => self.classes[i].radius.max(),
        }
    }

    /// The spheres of block `b` of class `class`, appended to `out`.
    pub fn generate_block(&self, class: usize, b: Cell, out: &mut Vec<Sphere>) {
        let key = hash_key(&[
            domain::BLOCK,
            self.seed,
            class as u64,
            b[0] as u64,
            b[1] as u64,
            b[2] as u64,
        ]);
        let mut rng = SplitMix64::new(key);
        let g = self.block[class];
        let mu = self.intensity * self.classes[class].fraction * g * g * g;
        let n = crate::sample::poisson(&mut rng, mu);
        let lo = DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64) * g;
        for k in 0..n {
            let u = uniform_unit_cube(&mut rng);
            let r = match self.draw {
                RadiusDraw::PerScene => self.per_scene[class],
                RadiusDraw::PerSphere => self.classes[class].radius.sample(&mut rng),
            };
            out.push(Sphere {
                c: lo + u * g,
                r,
                id: hash_key(&[key, k]),
            });
        }
    }

    /// Every sphere whose centre lies in the axis box `[lo, hi]` (for oracles and tests).
    pub fn spheres_in(&self, lo: DVec3, hi: DVec3) -> Vec<Sphere> {
        let mut out = Vec::new();
        for class in 0..self.classes.len() {
            let g = self.block[class];
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
        cache.clear();
        LazyCells {
            scene: self,
            frame,
            eye_magnitude,
            cache,
        }
    }
}

/// The buffers behind [`LazyCells`]: generated blocks and built cell lists of one batch.
#[derive(Debug, Default)]
pub struct LazyCache {
    blocks: FxHashMap<(usize, Cell), (u32, u32)>,
    block_arena: Vec<Sphere>,
    cells: FxHashMap<Cell, (u32, u32)>,
    cell_arena: Vec<Sphere>,
    scratch: Vec<Sphere>,
}

impl LazyCache {
    /// Forgets everything, keeping the allocations.
    pub fn clear(&mut self) {
        self.blocks.clear();
        self.block_arena.clear();
        self.cells.clear();
        self.cell_arena.clear();
        self.scratch.clear();
    }
}

/// Cell lists of a [`LazyScene`], generated on first visit and cached for the batch.
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
        self.cache.block_arena.len()
    }

    fn block(&mut self, class: usize, b: Cell) -> (u32, u32) {
        if let Some(&r) = self.cache.blocks.get(&(class, b)) {
            return r;
        }
        let start = self.cache.block_arena.len() as u32;
        self.scene
            .generate_block(class, b, &mut self.cache.block_arena);
        let r = (start, self.cache.block_arena.len() as u32);
        self.cache.blocks.insert((class, b), r);
        r
    }

    fn build_list(&mut self, cell: Cell) -> (u32, u32) {
        let cb = self.frame.cell_box(cell);
        let magnitude = self.pad_magnitude(cell);
        self.cache.scratch.clear();
        for class in 0..self.scene.classes.len() {
            let reach_r = self.scene.reach(class);
            let reach = reach_r + self.frame.pad(magnitude, reach_r);
            let g = self.scene.block[class];
            let bl = ((cb.lo - DVec3::splat(reach)) / g).floor();
            let bh = ((cb.hi + DVec3::splat(reach)) / g).floor();
            for z in bl.z as i64..=bh.z as i64 {
                for y in bl.y as i64..=bh.y as i64 {
                    for x in bl.x as i64..=bh.x as i64 {
                        let (s, e) = self.block(class, [x, y, z]);
                        for sp in &self.cache.block_arena[s as usize..e as usize] {
                            let rr = sp.r + self.frame.pad(magnitude, sp.r);
                            if cb.distance_squared(sp.c) <= rr * rr {
                                self.cache.scratch.push(*sp);
                            }
                        }
                    }
                }
            }
        }
        let c = &mut *self.cache;
        let start = c.cell_arena.len() as u32;
        c.cell_arena.extend_from_slice(&c.scratch);
        (start, c.cell_arena.len() as u32)
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
        let (s, e) = match self.cache.cells.get(&cell) {
            Some(&r) => r,
            None => {
                let r = self.build_list(cell);
                self.cache.cells.insert(cell, r);
                r
            }
        };
        &self.cache.cell_arena[s as usize..e as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RadiusDist;

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
}
