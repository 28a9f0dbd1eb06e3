//! The infinite Poisson scene realised afresh for each ray, only in the region its walk can read.
//!
//! # Why
//! A grid query reads the spheres listed in the cells it visits, and a sphere is listed in a cell
//! only if its centre lies within `R` (the largest radius, plus a margin over the listing pad) of the
//! cell: in the cell's reach box `M(C) = [lo − R, hi + R]³`. So one ray needs the process only on
//! `U = ∪ M(C)` over the cells it visits. When every ray has its own realisation
//! (`grid.rays_per_scene = 1`), `U` is all that has to exist, and it can be drawn from one
//! sequential stream per ray, with no hashing of space at all.
//!
//! # How, and why it is exact
//! A 3D-DDA walk is monotone along every axis and steps one axis at a time. A step from `C` to
//! its neighbour along axis `i` adds to `U` the slab `M(C') \ M(C)`, of width `a` along `i` and
//! `a + 2R` across; it is disjoint from every earlier reach box, since those end where `M(C)` ends
//! along `i`. So `U` is the disjoint union of the first cell's reach box and one slab per step, and
//! a Poisson(ρ·volume) count of independent uniform centres in each piece, each with independent
//! marks (class i with probability α_i, then its radius), is exactly the marked Poisson process of
//! intensity ρ restricted to `U`. The walk may stop on a hit that depends on the spheres drawn so
//! far: the pieces not yet drawn are independent of them, so stopping early changes nothing.
//!
//! Spheres whose centre falls behind the current reach box along the step's axis can never be
//! listed again (monotone walk) and are dropped: the memory held is the ~ρ·(a + 2R)³ spheres of
//! one reach box, whatever the ray's length.
//!
//! The per-cell lists are built with exactly the test of [`super::lazy::LazyCells`]: every sphere
//! whose padded ball meets the cell. The shared-realisation engine ([`super::lazy`]) remains for
//! `rays_per_scene > 1`; the tests hold the two to the same distribution.

use glam::DVec3;
use rand::Rng;

use super::{ClassMarks, RadiusClass, RadiusDraw};
use crate::geom::Ray;
use crate::geom::Sphere;
use crate::grid::trace::WalkState;
use crate::grid::{Cell, CellLists, Dda, GridFrame, Hit, TraceCounts};
use crate::sample::{counter::SplitMix64, rng::hash_key, PoissonTable};

/// Margin of a reach box over the largest radius, as a fraction of the cell width: larger than
/// the listing pad `64ε·(magnitude + r + a)` for every cell within about 10⁹ cell widths of the
/// origin (a walk is cut off long before).
pub const REACH_MARGIN: f64 = 1.0 / 65536.0;

/// The process's constants for one radius draw (fixed per scene for per-sphere radii, drawn per
/// ray for per-scene radii).
#[derive(Clone, Debug, Default)]
struct Pieces {
    /// Reach `R` = largest radius + margin.
    reach: f64,
    /// Largest radius.
    r_max: f64,
    /// Poisson laws of the counts in the first cell's reach box and in a slab.
    cube: PoissonTable,
    slab: PoissonTable,
}

impl Pieces {
    fn new(intensity: f64, r_max: f64, a: f64) -> Self {
        let reach = r_max + a * REACH_MARGIN;
        let w = a + 2.0 * reach;
        Self {
            reach,
            r_max,
            cube: PoissonTable::new(intensity * w * w * w),
            slab: PoissonTable::new(intensity * a * w * w),
        }
    }
}

/// An infinite Poisson sphere scene of which each ray sees its own independent realisation.
#[derive(Clone, Debug)]
pub struct TubeScene {
    intensity: f64,
    classes: Vec<RadiusClass>,
    draw: RadiusDraw,
    /// The class mark's draw.
    marks: ClassMarks,
    width: f64,
    /// The pieces for per-sphere radii (known before any draw).
    fixed: Option<Pieces>,
}

impl TubeScene {
    /// The scene for a grid of cell width `cell_width`.
    pub fn new(intensity: f64, classes: &[RadiusClass], draw: RadiusDraw, cell_width: f64) -> Self {
        let marks = ClassMarks::new(classes);
        let fixed = match draw {
            RadiusDraw::PerSphere => {
                let r_max = classes.iter().map(|c| c.radius.max()).fold(0.0, f64::max);
                Some(Pieces::new(intensity, r_max, cell_width))
            }
            RadiusDraw::PerScene => None,
        };
        Self {
            intensity,
            classes: classes.to_vec(),
            draw,
            marks,
            width: cell_width,
            fixed,
        }
    }

    /// A cell-list source over this scene for a grid placed by `frame` (unbounded), using `cache`.
    /// Call [`TubeCells::start_ray`] before each ray's walk.
    pub fn cells<'a>(
        &'a self,
        frame: GridFrame,
        eye_magnitude: f64,
        cache: &'a mut TubeCache,
    ) -> TubeCells<'a> {
        debug_assert_eq!(frame.width, self.width);
        cache.generated = 0;
        TubeCells {
            scene: self,
            frame,
            eye_magnitude,
            cache,
            rng: SplitMix64::new(0),
            radii: Vec::new(),
            pieces: self.fixed.clone().unwrap_or_default(),
            last: None,
            next_id: 0,
        }
    }
}

/// A sphere of the current reach box, with what the fused tracer remembers of it.
#[derive(Clone, Copy, Debug)]
struct Active {
    s: Sphere,
    /// Where the traced ray meets it ([`Sphere::intersect`], ∞ for a miss), computed when it is
    /// drawn so that the walk's loop over the active set has no branch; ∞ on the generic path.
    t: f64,
    /// Listed in a visited cell already (the mailbox).
    seen: bool,
}

/// Buffers reused from ray to ray: the spheres of the current reach box and the list buffer.
#[derive(Debug, Default)]
pub struct TubeCache {
    active: Vec<Active>,
    scratch: Vec<Sphere>,
    generated: usize,
    /// Every sphere drawn for the current ray (tests check lists against it).
    #[cfg(test)]
    log: Vec<Sphere>,
}

/// Cell lists of one ray's realisation of a [`TubeScene`], drawn as its walk proceeds.
#[derive(Debug)]
pub struct TubeCells<'a> {
    scene: &'a TubeScene,
    frame: GridFrame,
    eye_magnitude: f64,
    cache: &'a mut TubeCache,
    rng: SplitMix64,
    /// Per-scene radius of each class for this ray's realisation.
    radii: Vec<f64>,
    pieces: Pieces,
    /// The cell listed last (the walk's position), or `None` before the first.
    last: Option<Cell>,
    next_id: u64,
}

impl TubeCells<'_> {
    /// Starts a new realisation for the ray keyed by `key` (its stream is `hash_key(key)`).
    pub fn start_ray(&mut self, key: &[u64]) {
        self.rng = SplitMix64::new(hash_key(key));
        if self.scene.draw == RadiusDraw::PerScene {
            self.radii.clear();
            for c in &self.scene.classes {
                let r = c.radius.sample(&mut self.rng);
                self.radii.push(r);
            }
            let r_max = self.radii.iter().copied().fold(0.0, f64::max);
            self.pieces = Pieces::new(self.scene.intensity, r_max, self.scene.width);
        }
        self.last = None;
        self.next_id = 0;
        self.cache.active.clear();
        #[cfg(test)]
        self.cache.log.clear();
    }

    /// Spheres drawn so far for the rays since [`TubeScene::cells`].
    pub fn generated(&self) -> usize {
        self.cache.generated
    }

    /// Draws a Poisson count (the slab's law, or the first reach box's) of marked centres uniform
    /// in the box `[lo, hi]` into the active set.
    /// With `ray`, each sphere also keeps where the ray meets it.
    #[inline(always)]
    fn draw_box(&mut self, slab: bool, lo: [f64; 3], hi: [f64; 3], ray: Option<&Ray>) {
        let law = if slab {
            &self.pieces.slab
        } else {
            &self.pieces.cube
        };
        let n = law.sample(&mut self.rng);
        if n == 0 {
            return;
        }
        let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        let scene = self.scene;
        let active = &mut self.cache.active;
        for _ in 0..n {
            // Three uniforms, then the class, then the radius: the stream's order is the model.
            let u: [f64; 3] = [self.rng.gen(), self.rng.gen(), self.rng.gen()];
            let class = scene.marks.draw(&mut self.rng);
            let r = match scene.draw {
                RadiusDraw::PerScene => self.radii[class],
                RadiusDraw::PerSphere => scene.classes[class].radius.sample(&mut self.rng),
            };
            let sphere = Sphere {
                c: DVec3::new(
                    lo[0] + u[0] * size[0],
                    lo[1] + u[1] * size[1],
                    lo[2] + u[2] * size[2],
                ),
                r,
                id: self.next_id,
            };
            let t = ray.and_then(|ray| sphere.intersect(ray));
            active.push(Active {
                s: sphere,
                t: t.unwrap_or(f64::INFINITY),
                seen: false,
            });
            #[cfg(test)]
            self.cache.log.push(sphere);
            self.next_id += 1;
        }
        self.cache.generated += n as usize;
    }

    /// Moves the realisation to `cell`: drops what fell behind, then draws the first cell's
    /// reach box or the slab a step adds (the fused tracer draws first and drops in its pass over
    /// the active set; the set and its order are the same).
    fn advance(&mut self, cell: Cell) {
        let (lo, hi, _) = cell_box(&self.frame, &cell);
        let entered = self.last.map(|last| {
            let axis = (0..3)
                .find(|&i| cell[i] != last[i])
                .expect("advance is called on a new cell");
            let step = cell[axis] - last[axis];
            assert!(
                step.abs() == 1 && (0..3).all(|i| i == axis || cell[i] == last[i]),
                "a tube realisation follows a DDA walk: {last:?} → {cell:?} is not one step"
            );
            (axis, step)
        });
        let piece = Piece::new(&lo, &hi, self.pieces.reach, self.frame.width, entered);
        // A stable compaction: the kept spheres keep their order.
        let active = &mut self.cache.active;
        let mut kept = 0;
        for i in 0..active.len() {
            let e = active[i];
            active[kept] = e;
            kept += usize::from(piece.keeps(&e.s));
        }
        active.truncate(kept);
        self.draw_box(piece.slab, piece.lo, piece.hi, None);
        self.last = Some(cell);
    }
}

/// What entering a cell changes in the realisation: the piece to draw (the first cell's reach box,
/// or the slab of width a a step adds on the far side of the reach box) and which spheres stay
/// (those not behind the reach box along the step's axis: the walk is monotone, so those can
/// never be listed again).
#[derive(Clone, Copy, Debug)]
struct Piece {
    /// A slab (else the first reach box): which Poisson law counts its spheres.
    slab: bool,
    lo: [f64; 3],
    hi: [f64; 3],
    /// The step's axis, its direction, and the reach box's face behind it.
    axis: usize,
    forward: bool,
    bound: f64,
}

impl Piece {
    /// For the cell `[lo, hi]`, reach `reach`, cell width `a`, entered by the step `(axis, sign)`
    /// (`None` for the walk's first cell).
    #[inline(always)]
    fn new(
        lo: &[f64; 3],
        hi: &[f64; 3],
        reach: f64,
        a: f64,
        entered: Option<(usize, i64)>,
    ) -> Self {
        let reach_lo = [lo[0] - reach, lo[1] - reach, lo[2] - reach];
        let reach_hi = [hi[0] + reach, hi[1] + reach, hi[2] + reach];
        let Some((axis, step)) = entered else {
            return Self {
                slab: false,
                lo: reach_lo,
                hi: reach_hi,
                axis: 0,
                forward: true,
                bound: f64::NEG_INFINITY,
            };
        };
        // The reach box cut to width a on the step's far side (selects, not a store into one
        // lane, which the next read of the box would wait for).
        let cut_lo = |j: usize| {
            if j == axis && step > 0 {
                reach_hi[j] - a
            } else {
                reach_lo[j]
            }
        };
        let cut_hi = |j: usize| {
            if j == axis && step < 0 {
                reach_lo[j] + a
            } else {
                reach_hi[j]
            }
        };
        Self {
            slab: true,
            lo: [cut_lo(0), cut_lo(1), cut_lo(2)],
            hi: [cut_hi(0), cut_hi(1), cut_hi(2)],
            axis,
            forward: step > 0,
            bound: if step > 0 {
                reach_lo[axis]
            } else {
                reach_hi[axis]
            },
        }
    }

    /// Does `s` stay in the active set?
    #[inline(always)]
    fn keeps(&self, s: &Sphere) -> bool {
        let c = s.c.to_array()[self.axis];
        if self.forward {
            c >= self.bound
        } else {
            c <= self.bound
        }
    }
}

/// The box of `cell` and its magnitude: [`GridFrame::cell_box`] and
/// [`crate::geom::Aabb::magnitude`], the same numbers, as plain arrays. Recomputed whole at every
/// step: updating only the axis that changed would write single lanes that the next vector read
/// of the box must wait for (a store-forwarding stall that cost 13 % of the walk).
#[inline(always)]
fn cell_box(frame: &GridFrame, cell: &Cell) -> ([f64; 3], [f64; 3], f64) {
    let (o, w) = (frame.origin, frame.width);
    let lo = [
        o.x + cell[0] as f64 * w,
        o.y + cell[1] as f64 * w,
        o.z + cell[2] as f64 * w,
    ];
    let hi = [lo[0] + w, lo[1] + w, lo[2] + w];
    let m = |i: usize| max(lo[i].abs(), hi[i].abs());
    (lo, hi, max(m(0), max(m(1), m(2))))
}

/// The nearest hit so far, from the fused tracer's (distance, id) pair (∞: none).
#[inline(always)]
fn nearest(t: f64, id: u64) -> Option<Hit> {
    (t < f64::INFINITY).then_some(Hit { id, t })
}

/// `f64::max` for values that are never NaN (one instruction instead of four).
#[inline(always)]
fn max(x: f64, y: f64) -> f64 {
    if x > y {
        x
    } else {
        y
    }
}

/// Signed distance from `p` to `[lo, hi]` along one axis, up to sign (0 inside): what
/// [`crate::geom::Aabb::distance_squared`] squares, without branches.
#[inline(always)]
fn gap(p: f64, lo: f64, hi: f64) -> f64 {
    let below = p - lo;
    let above = p - hi;
    (if below < 0.0 { below } else { 0.0 }) + (if above > 0.0 { above } else { 0.0 })
}

/// Is `s` listed in the cell of box `[lo, hi]`: does its padded ball meet the box? (The lazy
/// engine's test, operation for operation: the squared distance is the same number.)
#[inline(always)]
fn meets(s: &Sphere, lo: &[f64; 3], hi: &[f64; 3], frame: &GridFrame, magnitude: f64) -> bool {
    let (dx, dy, dz) = (
        gap(s.c.x, lo[0], hi[0]),
        gap(s.c.y, lo[1], hi[1]),
        gap(s.c.z, lo[2], hi[2]),
    );
    let rr = s.r + frame.pad(magnitude, s.r);
    dx * dx + dy * dy + dz * dz <= rr * rr
}

impl TubeCells<'_> {
    /// Traces `ray` in its own realisation keyed by `key`: [`crate::grid::trace`] over this
    /// source, fused. The walk, the lists, the counts and the hit are those of
    /// `start_ray(key)` then `trace(self, ray, …)`, bit for bit (tested), for either mailbox
    /// setting: a sphere's first listing is its distinct test, and its intersection is computed
    /// then, once (a repeat could not change the nearest hit). What it saves is the per-cell list
    /// buffer, the mailbox's hash set and the calls between them; the loop over the active set
    /// has no data-dependent branch (each sphere's distance along the ray is computed when it is
    /// drawn): with ~1 sphere per cell, the walk's time goes to per-step control flow more
    /// than to arithmetic (measured as time only: this VM exposes no branch-miss counters).
    pub fn trace_ray(&mut self, key: &[u64], ray: &Ray, max_steps: u32) -> TraceCounts {
        self.start_ray(key);
        let frame = self.frame;
        let reach = self.pieces.reach;
        let r_max = self.pieces.r_max;
        let mut counts = TraceCounts::default();
        let (mut best_t, mut best_id) = (f64::INFINITY, u64::MAX);
        let mut walk = WalkState::default();
        let mut dda = Dda::new(&frame, ray);
        let mut entered = None;
        while let Some((cell, _t_enter, t_exit)) = dda.next() {
            walk.enter(t_exit);
            let (lo, hi, magnitude) = cell_box(&frame, &cell);
            let piece = Piece::new(&lo, &hi, reach, frame.width, entered);
            self.draw_box(piece.slab, piece.lo, piece.hi, Some(ray));
            // One pass over the active set, without a branch: drop what fell behind the reach
            // box (a stable compaction; the piece's spheres, appended last, all stay), and count
            // and mailbox the listings of the others. The order and the set are those of
            // drop-then-draw, so this is the generic walk's list, bit for bit.
            let magnitude = magnitude + self.eye_magnitude;
            let active = &mut self.cache.active;
            let mut kept = 0;
            for i in 0..active.len() {
                let mut e = active[i];
                let keep = piece.keeps(&e.s);
                let listed = keep & meets(&e.s, &lo, &hi, &frame, magnitude);
                let first = listed & !e.seen;
                counts.n_i += u32::from(listed);
                counts.n_i_mb += u32::from(first);
                // `Hit::beats` on the precomputed distance. A miss (∞) can only displace
                // another ∞, which still reads as no hit; a real distance beats any ∞.
                let beats = first & ((e.t < best_t) | ((e.t == best_t) & (e.s.id < best_id)));
                best_t = if beats { e.t } else { best_t };
                best_id = if beats { e.s.id } else { best_id };
                e.seen |= listed;
                active[kept] = e;
                kept += usize::from(keep);
            }
            active.truncate(kept);
            if kept > 0 {
                assert!(
                    r_max + frame.pad(magnitude, r_max) <= reach,
                    "cell {cell:?} is too far from the origin for the reach margin"
                );
            }
            if walk.stops(&nearest(best_t, best_id), t_exit, max_steps, &mut counts) {
                break;
            }
            entered = Some(dda.last_step());
        }
        walk.finish(nearest(best_t, best_id), &mut counts);
        counts
    }
}

impl CellLists for TubeCells<'_> {
    fn frame(&self) -> &GridFrame {
        &self.frame
    }

    #[inline]
    fn pad_magnitude(&self, cell: Cell) -> f64 {
        self.frame.cell_box(cell).magnitude() + self.eye_magnitude
    }

    #[inline(always)]
    fn list(&mut self, cell: Cell) -> &[Sphere] {
        if self.last != Some(cell) {
            self.advance(cell);
        }
        let c = &mut *self.cache;
        c.scratch.clear();
        if c.active.is_empty() {
            return &c.scratch;
        }
        let (lo, hi, magnitude) = cell_box(&self.frame, &cell);
        let magnitude = magnitude + self.eye_magnitude;
        let r_max = self.pieces.r_max;
        assert!(
            r_max + self.frame.pad(magnitude, r_max) <= self.pieces.reach,
            "cell {cell:?} is too far from the origin for the reach margin"
        );
        for e in &c.active {
            if meets(&e.s, &lo, &hi, &self.frame, magnitude) {
                c.scratch.push(e.s);
            }
        }
        &c.scratch
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::{directions::uniform_direction, rng::stream};
    use crate::scene::RadiusDist;

    fn frame(a: f64) -> GridFrame {
        GridFrame {
            origin: DVec3::ZERO,
            width: a,
            dims: None,
        }
    }

    fn mixture() -> Vec<RadiusClass> {
        vec![
            RadiusClass {
                fraction: 0.6,
                radius: RadiusDist::Constant(0.1),
            },
            RadiusClass {
                fraction: 0.4,
                radius: RadiusDist::Uniform { lo: 0.05, hi: 0.45 },
            },
        ]
    }

    /// Along whole walks, every cell's list is exactly the drawn spheres whose padded ball meets
    /// the cell: no sphere is dropped from the active set while a later cell could still list it,
    /// and the slabs cover every reach box. Cells narrower and wider than the spheres, eyes near
    /// and far from the origin, both radius draws.
    #[test]
    fn lists_equal_the_definition_along_walks() {
        let mut rng = stream(&[0x7b]);
        let mut cache = TubeCache::default();
        let mut checked = 0usize;
        for (case, (a, rho, offset)) in [(0.5, 1.0, 0.0f64), (0.15, 3.0, 40.0), (2.0, 1.0, -1e3)]
            .into_iter()
            .enumerate()
        {
            for draw in [RadiusDraw::PerSphere, RadiusDraw::PerScene] {
                let scene = TubeScene::new(rho, &mixture(), draw, a);
                let f = frame(a);
                let mut lists = scene.cells(f, offset.abs() + 2.0 * a, &mut cache);
                for ray_no in 0..60u64 {
                    lists.start_ray(&[case as u64, ray_no]);
                    let eye = DVec3::splat(offset) + DVec3::new(rng.gen(), rng.gen(), rng.gen());
                    let ray = Ray::new(eye, uniform_direction(&mut rng));
                    for (cell, _, _) in Dda::new(&f, &ray).take(60) {
                        let mut got = lists.list(cell).to_vec();
                        let cb = f.cell_box(cell);
                        let m = lists.pad_magnitude(cell);
                        let mut want: Vec<Sphere> = lists
                            .cache
                            .log
                            .iter()
                            .copied()
                            .filter(|s| {
                                let p = s.r + f.pad(m, s.r);
                                cb.distance_squared(s.c) <= p * p
                            })
                            .collect();
                        got.sort_by_key(|s| s.id);
                        want.sort_by_key(|s| s.id);
                        assert_eq!(got, want, "case {case} {draw:?} cell {cell:?}");
                        checked += want.len();
                    }
                }
            }
        }
        assert!(checked > 3000, "checked {checked}");
    }

    /// The fused tracer is the generic tracer over the same realisation, bit for bit: counts,
    /// truncation and hit (id and distance), with and without mailboxing, for cells narrower and
    /// wider than the spheres, both radius draws, and walks cut off by `max_steps`.
    #[test]
    fn fused_trace_equals_the_generic_trace() {
        use crate::grid::{mailbox::Mailbox, trace};
        let mut rng = stream(&[0x7f]);
        let (mut cache_a, mut cache_b) = (TubeCache::default(), TubeCache::default());
        let mut mailbox = Mailbox::default();
        let mut hits = 0;
        for (case, (a, rho, max_steps)) in [
            (0.5, 1.0, 10_000_000u32),
            (0.1, 4.0, 10_000_000),
            (2.5, 0.5, 10_000_000),
            (0.3, 1.0, 7),
        ]
        .into_iter()
        .enumerate()
        {
            for draw in [RadiusDraw::PerSphere, RadiusDraw::PerScene] {
                let scene = TubeScene::new(rho, &mixture(), draw, a);
                let f = frame(a);
                let mut fused = scene.cells(f, 2.0 * a, &mut cache_a);
                let mut generic = scene.cells(f, 2.0 * a, &mut cache_b);
                for ray_no in 0..400u64 {
                    let key = [case as u64, ray_no];
                    let eye = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * a;
                    let ray = Ray::new(eye, uniform_direction(&mut rng));
                    let got = fused.trace_ray(&key, &ray, max_steps);
                    for skip in [true, false] {
                        generic.start_ray(&key);
                        let want = trace(&mut generic, &ray, &mut mailbox, skip, max_steps);
                        assert_eq!(got, want, "case {case} {draw:?} ray {ray_no} skip {skip}");
                    }
                    hits += usize::from(got.hit.is_some());
                }
            }
        }
        assert!(hits > 2000, "{hits}");
    }

    /// The realisation along a walk is the Poisson process: over independent rays, the centres in
    /// the reach box of the walk's 1st and 12th cells number Poisson(ρ·|M|) (mean and variance
    /// within 4 standard errors), the classes have their fractions, and centres in the 12th cell
    /// have no neighbour within s½ with probability ½ (P(D > s) = exp(−ρ·4πs³/3); the reach box
    /// holds every centre within R ≥ s½ of the cell). Tolerances are never tuned: 4 SE.
    #[test]
    fn walks_see_a_poisson_process() {
        let (a, rho) = (0.4, 2.0);
        let classes = vec![
            RadiusClass {
                fraction: 0.7,
                radius: RadiusDist::Constant(0.45),
            },
            RadiusClass {
                fraction: 0.3,
                radius: RadiusDist::Constant(0.2),
            },
        ];
        let scene = TubeScene::new(rho, &classes, RadiusDraw::PerSphere, a);
        let f = frame(a);
        let mut cache = TubeCache::default();
        let mut lists = scene.cells(f, 2.0 * a, &mut cache);
        let reach = 0.45 + a * REACH_MARGIN;
        let volume = (a + 2.0 * reach).powi(3);
        let s_half = (0.5f64.ln() / (-rho * 4.0 / 3.0 * std::f64::consts::PI)).cbrt();
        assert!(s_half < reach);
        let mut rng = stream(&[0x7c]);
        let reps = 20_000;
        let (mut first, mut twelfth) = (Vec::new(), Vec::new());
        let (mut small, mut all) = (0u64, 0u64);
        let (mut far, mut inner) = (0u64, 0u64);
        for rep in 0..reps {
            lists.start_ray(&[rep]);
            let eye = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * a;
            let ray = Ray::new(eye, uniform_direction(&mut rng));
            for (k, (cell, _, _)) in Dda::new(&f, &ray).take(12).enumerate() {
                lists.list(cell);
                let cb = f.cell_box(cell);
                let (lo, hi) = (cb.lo - DVec3::splat(reach), cb.hi + DVec3::splat(reach));
                let active: Vec<Sphere> = lists.cache.active.iter().map(|e| e.s).collect();
                let n = active
                    .iter()
                    .filter(|s| s.c.cmpge(lo).all() && s.c.cmple(hi).all())
                    .count();
                assert_eq!(n, active.len(), "the active set is the reach box");
                if k == 0 {
                    first.push(n as f64);
                }
                if k == 11 {
                    twelfth.push(n as f64);
                    for s in &active {
                        all += 1;
                        small += u64::from(s.r < 0.3);
                        if s.c.cmpge(cb.lo).all() && s.c.cmple(cb.hi).all() {
                            inner += 1;
                            let d = active
                                .iter()
                                .filter(|q| q.id != s.id)
                                .map(|q| q.c.distance(s.c))
                                .fold(f64::INFINITY, f64::min);
                            far += u64::from(d > s_half);
                        }
                    }
                }
            }
        }
        let lambda = rho * volume;
        for counts in [&first, &twelfth] {
            let n = counts.len() as f64;
            let mean = counts.iter().sum::<f64>() / n;
            let var = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0);
            assert!(
                (mean - lambda).abs() < 4.0 * (lambda / n).sqrt(),
                "mean {mean} vs {lambda}"
            );
            let se_var = ((2.0 * lambda * lambda + lambda) / n).sqrt();
            assert!((var - lambda).abs() < 4.0 * se_var, "var {var} vs {lambda}");
        }
        let f_small = small as f64 / all as f64;
        assert!(
            (f_small - 0.3).abs() < 4.0 * (0.21 / all as f64).sqrt(),
            "{f_small}"
        );
        // Centres of one ray's cell are few and nearly independent; binomial SE.
        let p = far as f64 / inner as f64;
        assert!(inner > 2000, "{inner}");
        assert!(
            (p - 0.5).abs() < 4.0 * (0.25 / inner as f64).sqrt(),
            "P(D > s½) = {p} over {inner}"
        );
    }

    /// The two engines realise the same process: over independent rays, the per-ray realisation
    /// (`rays_per_scene = 1`) and the shared block realisation (groups of 4, standard errors
    /// clustered by group) give the same mean N_I, mailboxed N_I, N_S and hit distance, each within
    /// 4 combined standard errors; for a mixture of radius laws drawn per sphere and per scene.
    #[test]
    fn tube_and_block_engines_agree() {
        use crate::scene::infinite::{InfiniteCaches, InfiniteScene, Walk};
        for (case, (a, draw)) in [(0.3, RadiusDraw::PerSphere), (0.8, RadiusDraw::PerScene)]
            .into_iter()
            .enumerate()
        {
            let classes = mixture();
            let scene = InfiniteScene {
                intensity: 1.5,
                classes: &classes,
                draw,
            };
            // Per engine: per-group sums of (n_i, n_i_mb, n_s, t) and their squares' cluster sums.
            let mut means = Vec::new();
            for rays_per_scene in [1usize, 4] {
                let walk = Walk {
                    cell_width: a,
                    eye_magnitude: 2.0 * a,
                    rays_per_scene,
                    mailbox: true,
                    max_steps: 10_000_000,
                };
                let mut caches = InfiniteCaches::default();
                let mut groups: Vec<[f64; 4]> = Vec::new();
                for b in 0..40u64 {
                    let mut rng = stream(&[0x7d, case as u64, rays_per_scene as u64, b]);
                    let rays: Vec<Ray> = (0..512)
                        .map(|_| {
                            let eye = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * a;
                            Ray::new(eye, uniform_direction(&mut rng))
                        })
                        .collect();
                    let mut out = Vec::new();
                    let key = [0x7e, case as u64, rays_per_scene as u64, b];
                    scene.trace_batch(&walk, &key, &rays, &mut caches, &mut out);
                    for g in out.chunks(rays_per_scene) {
                        let mut s = [0.0; 4];
                        for c in g {
                            let t = c.hit.map_or(0.0, |h| h.t);
                            s[0] += f64::from(c.n_i);
                            s[1] += f64::from(c.n_i_mb);
                            s[2] += f64::from(c.n_s);
                            s[3] += t;
                        }
                        groups.push(s);
                    }
                }
                let rays = (groups.len() * rays_per_scene) as f64;
                let mut m = [(0.0, 0.0); 4];
                for (i, mi) in m.iter_mut().enumerate() {
                    let mean = groups.iter().map(|g| g[i]).sum::<f64>() / rays;
                    // Cluster-robust variance of the ratio mean.
                    let var = groups
                        .iter()
                        .map(|g| (g[i] - mean * rays_per_scene as f64).powi(2))
                        .sum::<f64>()
                        / (rays * rays);
                    *mi = (mean, var.sqrt());
                }
                means.push(m);
            }
            for (i, (&(m1, s1), &(m2, s2))) in means[0].iter().zip(&means[1]).enumerate() {
                let se = (s1 * s1 + s2 * s2).sqrt();
                assert!(
                    (m1 - m2).abs() < 4.0 * se,
                    "case {case} quantity {i}: tube {m1} ± {s1}, blocks {m2} ± {s2}"
                );
            }
        }
    }
}
