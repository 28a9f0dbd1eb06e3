//! Quasi-static DETP: a few dynamic objects move through a static scene, frame by frame, and the
//! irradiance at every sample point is kept up to date without tracing everything again (the DETP
//! paper's incremental recalculation, §3).
//!
//! Frame 0 traces every photon into the store and lists each segment in a [`SegmentIndex`]. At each
//! later frame:
//! 1. **search**: the index gives the segments that meet a mover's bounding sphere at its old or its
//!    new pose; their photons are the affected ones (counted: cells, listings, tests);
//! 2. **re-trace** those photons from their own streams at the new pose (the rest of each path may
//!    change too); their old segments are kept aside, the new ones take fresh slots;
//! 3. **static points**: subtract the old segments' power and add the new ones' (through the disc
//!    index built once, or through a sphere cache over just those segments);
//! 4. **dynamic points** (on a mover, posed with it): discarded and recomputed from all rays, by a
//!    sphere cache rooted at the mover's bounding sphere (fed by the index: only segments that meet it
//!    can cross its discs) or by a disc index built around the mover that every segment traverses.
//!    Theorem 2 picks per mover (`Engine::Hybrid`), or the spec forces one.
//!
//! # Why incremental equals full, bit for bit
//! A photon's path is a pure function of (seed, photon id, geometry at this frame): [`photon`]
//! draws from the photon's own stream, and [`Scene::first_two_hits`] offers static and dynamic hits in a
//! fixed order. A photon none of whose stored pieces `[0, t_end]` meets a mover at the old or the new
//! pose sees the same first and second hits at every bounce, so its path — and every draw after it —
//! is unchanged; the search finds every other photon (conservatively, see [`segment_index`]). So the
//! live segments are exactly the segments a full trace of the frame produces. Powers are integers,
//! so a static point's sum after "minus old, plus new" is the sum over those segments, whatever the
//! order; dynamic points are summed afresh. [`QuasiStatic::full_recalculation`] checks it.

pub mod lines;
pub mod predict;
pub mod segment_index;

use std::ops::Range;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::disc::Discs;
use super::disc_index::{DiscIndex, GridIndex, IndexStats, Octree};
use super::fixed::{Acc, PowerScale};
use super::order::{permutation, Order};
use super::photon::{retrace, trace_photon_range, trace_photons};
use super::sphere_cache::{self, CacheStats, SphereCacheParams};
use super::store::{Segment, SegmentStore};
use super::surface_points::points_on;
use crate::lt::motion::tau;
use crate::lt::Scene;
use segment_index::{SearchStats, SegmentIndex};

pub use predict::{Prediction, Predictor};

/// How a mover's dynamic points are recomputed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// Sphere cache below the crossover ratio r_D/r_0, disc index above (Theorem 2).
    Hybrid,
    /// Always the sphere cache (static points too).
    SphereCache,
    /// Always a disc index (static points too).
    DiscIndex,
}

/// What one mover's points were computed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Used {
    /// Sphere cache.
    SphereCache,
    /// Disc index.
    DiscIndex,
}

impl Used {
    /// The spelling in specs and tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Used::SphereCache => "sphere-cache",
            Used::DiscIndex => "disc-index",
        }
    }
}

/// Which segments a mover's dynamic points are gathered from (both engines give the same sums
/// whatever the feed: a segment crossing a dynamic disc meets the mover's sphere padded by d).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Feed {
    /// Theorem 2's model: the sphere cache gets the segment index's answer (the segments meeting
    /// the mover's bounding sphere padded by d, f_R of them), the disc index traverses every segment.
    #[default]
    Paper,
    /// Both engines get the segment index's answer.
    SegmentIndex,
    /// Both engines get every segment.
    All,
}

impl Feed {
    /// The spelling in specs.
    pub fn as_str(self) -> &'static str {
        match self {
            Feed::Paper => "paper",
            Feed::SegmentIndex => "segment-index",
            Feed::All => "all",
        }
    }
}

/// Settings of a quasi-static run.
#[derive(Clone, Debug)]
pub struct Params {
    /// Photons per frame.
    pub photons: u64,
    /// Seed of the photons' streams.
    pub seed: u64,
    /// Frames F (τ = f/(F − 1)).
    pub frames: u32,
    /// Disc radius d.
    pub disc_radius: f64,
    /// Spacing of the sample points on surfaces.
    pub spacing: f64,
    /// Engine choice.
    pub engine: Engine,
    /// Crossover r_D/r_0 of the hybrid choice.
    pub crossover: f64,
    /// Sphere-cache settings (Q, threshold, lists, chunks).
    pub cache: SphereCacheParams,
    /// Point order for the sphere cache.
    pub order: Order,
    /// The static points' disc index (and the dynamic points' when a disc index does them).
    pub index: IndexKind,
    /// Which segments the dynamic points' engines get.
    pub feed: Feed,
    /// Also time the disc index's traversal alone for the dynamic points
    /// ([`FrameStats::dynamic_traversal_s`]): a second walk of each mover's index after the frame's
    /// pass, kept out of every other seconds (eq. 8's assumption measured; the bench leaves it off).
    pub time_traversal: bool,
}

pub use super::disc_index::IndexKind;

impl IndexKind {
    fn build(self, discs: &Discs, d: f64) -> Box<dyn DiscIndex> {
        match self {
            IndexKind::Grid(w) => Box::new(GridIndex::build(discs, w)),
            IndexKind::Octree(leaf) => Box::new(Octree::build(discs, leaf, 2.0 * d)),
        }
    }
}

/// Counts and times of one frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameStats {
    /// Frame number.
    pub frame: u32,
    /// Segments that meet a mover's bounding sphere at the old or the new pose.
    pub affected_segments: u64,
    /// Of them, those meeting it at the new pose (the integral-geometry count n_R·(r_D/r_0)²).
    pub meeting_new: u64,
    /// Segments meeting a mover at its new pose after the frame's re-trace (eq. 11's one-pose
    /// count, per mover, summed): unlike `meeting_new`, counted on the re-traced paths, so a
    /// segment the old pose cut short before the new one is counted as its re-trace meets it, and
    /// with the bare radius (the search pads it); 0 at frame 0.
    pub meeting_pose: u64,
    /// Photons re-traced.
    pub photons_retraced: u64,
    /// Segments removed: each re-traced photon's old path from its first changed segment on.
    pub segments_removed: u64,
    /// Segments added (removed and added: the changed part of each re-traced path).
    pub segments_added: u64,
    /// Segments of the re-traced photons' new paths (changed or not).
    pub segments_retraced: u64,
    /// The search's counts.
    pub search: SearchStats,
    /// Static points: ray–disc tests of the update, and ray–sphere tests if a sphere cache did it.
    pub static_disc_tests: u64,
    /// Static points: ray–sphere tests (sphere cache only).
    pub static_sphere_tests: u64,
    /// Dynamic points: ray–disc tests.
    pub dynamic_disc_tests: u64,
    /// Dynamic points: ray–sphere tests (sphere cache only).
    pub dynamic_sphere_tests: u64,
    /// Dynamic points: the disc index's traversal (box tests + DDA steps).
    pub dynamic_traversal: u64,
    /// Dynamic points: segments copied into the sphere cache's lists.
    pub dynamic_rays_copied: u64,
    /// Dynamic points: spheres the sphere cache built.
    pub dynamic_spheres_built: u64,
    /// Dynamic points: the segment-index queries that fed them (cells read + segments tested).
    pub dynamic_feed: u64,
    /// Dynamic points: segments that reached their disc index (entered a cell or node of it; 0
    /// with the sphere cache). Theorem 2's proof charges every live segment as if it did.
    pub dynamic_rays_reaching: u64,
    /// Segments alive after the frame: n_R, the rays of the scene Theorem 2's proof charges.
    pub segments_live: u64,
    /// Sample points on the dynamic objects: n_D (not added over photon shards: the same points).
    pub dynamic_points: u64,
    /// Σ(r_D/r_0)² over the movers at this frame's pose (not added over photon shards: the same
    /// movers); f_R = `segments_live`·this ([`Self::f_r_theory`]).
    pub ratio_sq: f64,
    /// Σ over the movers of [`crate::theory::detp::union_lines_share`] (r_D/r_0, shift/r_0) from the
    /// old pose to this one (not added over photon shards); 0 at frame 0.
    pub union_share: f64,
    /// Static points: the disc index's traversal (box tests + DDA steps).
    pub static_traversal: u64,
    /// Static points: segments copied into the sphere cache's lists (sphere cache only).
    pub static_rays_copied: u64,
    /// Engine used per mover.
    pub used: Vec<Used>,
    /// Seconds: search, re-trace, static update, dynamic points, and the whole frame.
    pub search_s: f64,
    /// Re-trace seconds.
    pub retrace_s: f64,
    /// Static-update seconds.
    pub static_s: f64,
    /// Dynamic-points seconds.
    pub dynamic_s: f64,
    /// Seconds of the disc index's traversal alone for the dynamic points: every mover whose points
    /// used the disc index, its index walked again for the same segments without a disc test
    /// ([`DiscIndex::traversal_only`]), after the pass and outside `dynamic_s` and `frame_s`. 0 when
    /// no mover used the disc index (as `dynamic_traversal`), NaN when [`Params::time_traversal`]
    /// is off.
    pub dynamic_traversal_s: f64,
    /// Whole frame seconds.
    pub frame_s: f64,
}

/// A mover's sample points: at rest (per part, in the part's own coordinates), and posed at the
/// current frame.
struct DynamicPoints {
    mover: usize,
    /// (part, rest points, rest normals).
    rest: Vec<(usize, Vec<DVec3>, Vec<DVec3>)>,
    discs: Discs,
    acc: Vec<Acc>,
}

impl DynamicPoints {
    /// Points on every part of `mover`, at spacing ≈ `spacing` in the world (a part's own
    /// coordinates may be scaled: the spacing there is divided by its map's scale at τ = 0).
    fn new(scene: &Scene, mover: usize, spacing: f64, d: f64) -> Self {
        let m = &scene.movers[mover];
        let maps = m.part_maps(0.0);
        let rest: Vec<(usize, Vec<DVec3>, Vec<DVec3>)> = m
            .parts
            .iter()
            .zip(&maps)
            .enumerate()
            .map(|(k, (part, map))| {
                let s = map.matrix3.determinant().abs().cbrt().max(1e-300);
                let (p, n) = points_on(&part.triangles, &part.balls, &scene.surfaces, spacing / s);
                (k, p, n)
            })
            .collect();
        let mut dp = Self {
            mover,
            rest,
            discs: Discs::new(vec![], vec![], d).expect("d > 0"),
            acc: Vec::new(),
        };
        dp.discs = dp.posed(scene, 0.0, d);
        dp
    }

    /// The discs at τ: points mapped with their part, normals with its inverse transpose.
    fn posed(&self, scene: &Scene, tau: f64, d: f64) -> Discs {
        let maps = scene.movers[self.mover].part_maps(tau);
        let (mut c, mut n) = (Vec::new(), Vec::new());
        for (k, p, nn) in &self.rest {
            let m = maps[*k];
            let nm = m.matrix3.inverse().transpose();
            c.extend(p.iter().map(|&x| m.transform_point3(x)));
            n.extend(nn.iter().map(|&x| nm * x));
        }
        Discs::new(c, n, d).expect("posed points are finite")
    }
}

/// Where a run's rays come from.
#[derive(Clone, Debug)]
pub enum RaySource {
    /// Photons from the scene's lights; static points on its static surfaces.
    Photons,
    /// μ-random lines through the unit ball, stopped by the movers ([`lines`]); these static
    /// points (the scene has no static geometry), and r_0 = 1, the lines' ball.
    Lines(Discs),
}

/// The state of a quasi-static run at its current frame.
pub struct QuasiStatic {
    /// Photons or lines (the lines' static points moved out into `static_discs`).
    lines: bool,
    /// The scene, posed at the current frame.
    pub scene: Scene,
    params: Params,
    /// The photons traced: `0..photons`, or a `--photon-shard`'s range of them.
    ids: Range<u64>,
    /// Segments in slots; a dead slot has power 0 and t_end = −1 (it crosses nothing).
    store: SegmentStore,
    /// Per photon: its slots `start..start + len`.
    paths: Vec<(u32, u32)>,
    dead: usize,
    index: SegmentIndex,
    seen: Vec<bool>,
    /// Static sample points.
    pub static_discs: Discs,
    static_acc: Vec<Acc>,
    static_index: Box<dyn DiscIndex>,
    /// Root sphere of the static sphere cache (the scene's).
    root: (DVec3, f64),
    static_perm: Vec<u32>,
    dynamic: Vec<DynamicPoints>,
    /// Current frame.
    pub frame: u32,
    /// Bounding spheres of the movers at the current pose.
    spheres: Vec<(DVec3, f64)>,
    /// Seconds to build the static disc index (once, at frame 0).
    pub static_index_build_s: f64,
    /// Engines picked per mover by [`QuasiStatic::predict_and_pick`] (empty: the rule of
    /// `params.engine`).
    picked: Vec<Used>,
}

/// One mover's dynamic points recomputed: its posed discs, their sums, the engine used, its counts,
/// and (disc index) the walk to time alone afterwards.
type DynamicSums = (Discs, Vec<Acc>, Used, Counts, Option<IndexWalk>);

/// A mover's disc index and the segments its pass walked (all of the store's, or those listed),
/// kept so that `QuasiStatic::time_traversal` can walk them again without disc tests.
struct IndexWalk {
    index: Box<dyn DiscIndex>,
    ids: Option<Vec<u32>>,
}

/// Seconds spent in `f`, with its value.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let v = f();
    (v, t.elapsed().as_secs_f64())
}

impl QuasiStatic {
    /// Frame 0: poses the scene, traces every photon, builds the segment index, the static disc
    /// index and every sample point's sum. Returns the state and frame 0's stats (its `frame_s` is
    /// the full cost).
    pub fn start(scene: Scene, params: Params) -> (Self, FrameStats) {
        let ids = 0..params.photons;
        Self::start_photons(scene, params, ids)
    }

    /// [`Self::start`] with only the photons `ids` of the run's `params.photons` (`--photon-shard`):
    /// each is the photon the whole run traces, and every later frame re-traces only those of them
    /// that an object meets, so each frame's sums and counts are this range's share of the whole
    /// run's — they add across disjoint ranges, except the counts of the accelerators whose work
    /// depends on the other photons (the segment index, sized and compacted by this range's own
    /// segments; the sphere cache, which subdivides by the rays a sphere holds).
    pub fn start_photons(scene: Scene, params: Params, ids: Range<u64>) -> (Self, FrameStats) {
        Self::start_from(scene, params, ids, RaySource::Photons)
    }

    /// [`Self::start_photons`] with the rays of `source`: μ-random lines need no lights, and their
    /// scene holds only the movers.
    pub fn start_from(
        mut scene: Scene,
        params: Params,
        ids: Range<u64>,
        source: RaySource,
    ) -> (Self, FrameStats) {
        let t_all = Instant::now();
        scene.set_tau(tau(0, params.frames));
        let lines = matches!(source, RaySource::Lines(_));
        let static_discs = match source {
            RaySource::Lines(discs) => discs,
            RaySource::Photons => {
                let (st, sb) = scene.static_geometry();
                let (c, n) = points_on(st, sb, &scene.surfaces, params.spacing);
                Discs::new(c, n, params.disc_radius).expect("surface points are finite")
            }
        };
        let (store, trace_s) =
            timed(|| trace_range(lines, &scene, ids.clone(), params.photons, params.seed));
        let paths = (0..params.photons as usize)
            .map(|p| {
                let (a, b) = (store.photon_start[p], store.photon_start[p + 1]);
                (a, b - a)
            })
            .collect();
        // Lines: the unit ball and every disc reaching d beyond it, as kind detp roots them.
        let root = if lines {
            (DVec3::ZERO, 1.0 + params.disc_radius)
        } else {
            sphere_cache::root_sphere(&{
                let (b, d) = (scene.bounds(), static_discs.bounds_all());
                crate::geom::Aabb::new(b.lo.min(d.lo), b.hi.max(d.hi))
            })
        };
        let rays_box = if lines {
            lines::lines_bounds()
        } else {
            scene.bounds()
        };
        let index = SegmentIndex::new(rays_box, (store.len() / 64).clamp(64, 1 << 18));
        let (static_index, static_index_build_s) =
            timed(|| params.index.build(&static_discs, params.disc_radius));
        let static_perm = permutation(&static_discs.centers, params.order, 10);
        let dynamic = (0..scene.movers.len())
            .map(|k| DynamicPoints::new(&scene, k, params.spacing, params.disc_radius))
            .collect();
        let mut qs = Self {
            lines,
            spheres: scene
                .movers
                .iter()
                .map(|m| m.bounds_at(tau(0, params.frames)))
                .collect(),
            scene,
            params,
            ids,
            store,
            paths,
            dead: 0,
            index,
            seen: Vec::new(),
            static_acc: Vec::new(),
            static_discs,
            static_index,
            root,
            static_perm,
            dynamic,
            frame: 0,
            static_index_build_s,
            picked: Vec::new(),
        };
        qs.rebuild_index();
        let mut stats = FrameStats {
            retrace_s: trace_s,
            segments_added: qs.store.len() as u64,
            photons_retraced: qs.ids.end - qs.ids.start,
            ..Default::default()
        };
        let ((acc, t), s) = timed(|| qs.static_sums(&qs.store, None));
        qs.static_acc = acc;
        t.add_static(&mut stats);
        stats.static_s = s;
        let (mut dynamic, s) = timed(|| qs.dynamic_sums(&qs.store, true));
        stats.dynamic_s = s;
        let aside = qs.time_traversal(&mut dynamic, &mut stats);
        qs.apply_dynamic(dynamic, &mut stats);
        qs.proof_facts(None, &mut stats);
        stats.frame_s = t_all.elapsed().as_secs_f64() - aside;
        (qs, stats)
    }

    /// The frame's n_R, n_D and the μ-random-line expectations of the segments meeting the objects
    /// at one pose (f_R) and at the old or the new pose (`old`: the poses before the frame; none
    /// at frame 0), as Theorem 2's proof and eq. 11 state them.
    fn proof_facts(&self, old: Option<&[(DVec3, f64)]>, stats: &mut FrameStats) {
        let r0 = self.r0();
        stats.segments_live = self.live_segments() as u64;
        stats.dynamic_points = self.dynamic.iter().map(|dp| dp.discs.len() as u64).sum();
        stats.ratio_sq = self.spheres.iter().map(|&(_, r)| (r / r0).powi(2)).sum();
        stats.union_share = old.map_or(0.0, |old| {
            old.iter()
                .zip(&self.spheres)
                .map(|(&(a, _), &(b, r))| {
                    crate::theory::detp::union_lines_share(r / r0, (b - a).length() / r0)
                })
                .sum()
        });
    }

    /// Photon or line `p` at the current pose.
    fn retrace(&self, p: u32) -> Vec<Segment> {
        if self.lines {
            vec![lines::trace_line(&self.scene, self.params.seed, p)]
        } else {
            retrace(&self.scene, self.params.seed, self.params.photons, p)
        }
    }

    /// r_0 of eq. 11: the root sphere's radius, or 1 for lines (their ball; the root reaches d
    /// beyond it to hold every disc).
    pub fn r0(&self) -> f64 {
        if self.lines {
            1.0
        } else {
            self.root.1
        }
    }

    /// The run's settings.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Segments alive in the store.
    pub fn live_segments(&self) -> usize {
        self.store.len() - self.dead
    }

    /// Lists every live slot in the segment index afresh.
    fn rebuild_index(&mut self) {
        self.index.clear();
        for &(a, l) in &self.paths {
            for k in a..a + l {
                self.index.insert(k, &self.store.segments[k as usize]);
            }
        }
    }

    /// Moves the live segments to the front, photon by photon, and re-lists them (when more than
    /// half of the slots are dead). Slot numbers change; sums do not.
    fn compact(&mut self) {
        let mut segs = Vec::with_capacity(self.live_segments());
        for p in &mut self.paths {
            let (a, l) = *p;
            *p = (segs.len() as u32, l);
            segs.extend_from_slice(&self.store.segments[a as usize..(a + l) as usize]);
        }
        self.store.segments = segs;
        self.dead = 0;
        self.rebuild_index();
    }

    /// Static points' sums from `store` (all its segments, or the listed ones): by the disc index,
    /// or by a sphere cache over those segments when the spec forces it. Returns the sums and the
    /// engine's counts.
    fn static_sums(&self, store: &SegmentStore, only: Option<&[u32]>) -> (Vec<Acc>, Counts) {
        let mut acc = vec![0; self.static_discs.len()];
        if self.params.engine == Engine::SphereCache {
            let sub;
            let s = match only {
                Some(ids) => {
                    sub = subset(store, ids);
                    &sub
                }
                None => store,
            };
            let st = sphere_cache::run(
                s,
                &self.static_discs,
                &self.static_perm,
                self.root,
                &self.params.cache,
                &mut acc,
            );
            (acc, Counts::cache(&st))
        } else {
            let st: IndexStats = self.static_index.accumulate(store, only, 1, &mut acc);
            (acc, Counts::index(&st))
        }
    }

    /// Which engine a mover's points use by the run's rule (Theorem 2's ratio for the hybrid),
    /// unless the predictor picked.
    pub fn rule_engine(&self, mover: usize) -> Used {
        match self.params.engine {
            Engine::SphereCache => Used::SphereCache,
            Engine::DiscIndex => Used::DiscIndex,
            Engine::Hybrid => {
                if self.scene.movers[mover].radius() / self.r0() < self.params.crossover {
                    Used::SphereCache
                } else {
                    Used::DiscIndex
                }
            }
        }
    }

    /// Which engine a mover's points use.
    fn engine_for(&self, mover: usize) -> Used {
        self.picked
            .get(mover)
            .copied()
            .unwrap_or_else(|| self.rule_engine(mover))
    }

    /// The root of mover `m`'s sphere cache: its bounding sphere padded by d (and the segment
    /// index's pad), so every segment crossing one of its discs meets it.
    fn dynamic_root(&self, m: usize) -> (DVec3, f64) {
        let (c, r) = self.spheres[m];
        (
            c,
            (r + self.params.disc_radius) * (1.0 + 1e-9) + self.index.pad(),
        )
    }

    /// Every mover's points posed at the current frame and summed afresh from `store`. `indexed`:
    /// `store` is the state's own (the segment index may feed the sphere cache).
    fn dynamic_sums(&self, store: &SegmentStore, indexed: bool) -> Vec<DynamicSums> {
        self.dynamic_sums_with(store, indexed, None, None)
    }

    /// [`Self::dynamic_sums`] with every mover's engine forced to `force` (when given), for every
    /// mover or `only` one. With `indexed`, the engines get the segments [`Params::feed`] names;
    /// otherwise (a fresh store, or the predictor) every segment of `store`.
    fn dynamic_sums_with(
        &self,
        store: &SegmentStore,
        indexed: bool,
        force: Option<Used>,
        only: Option<usize>,
    ) -> Vec<DynamicSums> {
        let t = self.scene.tau();
        self.dynamic
            .iter()
            .filter(|dp| only.is_none_or(|m| m == dp.mover))
            .map(|dp| {
                let discs = dp.posed(&self.scene, t, self.params.disc_radius);
                let mut acc = vec![0; discs.len()];
                let used = force.unwrap_or_else(|| self.engine_for(dp.mover));
                let mut counts = Counts::default();
                if discs.is_empty() {
                    return (discs, acc, used, counts, None);
                }
                let root = self.dynamic_root(dp.mover);
                let fed = indexed
                    && match used {
                        Used::SphereCache => self.params.feed != Feed::All,
                        Used::DiscIndex => self.params.feed == Feed::SegmentIndex,
                    };
                let ids = if fed {
                    let live = |id: u32| !is_dead(&self.store.segments[id as usize]);
                    let mut seen = vec![false; store.len()];
                    let (ids, st) =
                        self.index
                            .query(&store.segments, root.0, root.1, &live, &mut seen);
                    counts.feed = st.cells + st.tested;
                    Some(ids)
                } else if indexed && self.dead > 0 {
                    // Every live segment: the slots emptied by re-traces (up to half the store
                    // before it is compacted, and all of them near the object) are no segments.
                    Some(
                        (0..store.len() as u32)
                            .filter(|&i| !is_dead(&store.segments[i as usize]))
                            .collect(),
                    )
                } else {
                    None
                };
                let walk = match used {
                    Used::SphereCache => {
                        let perm = permutation(&discs.centers, self.params.order, 10);
                        let sub;
                        let s = match &ids {
                            Some(ids) => {
                                sub = subset(store, ids);
                                &sub
                            }
                            None => store,
                        };
                        let cs =
                            sphere_cache::run(s, &discs, &perm, root, &self.params.cache, &mut acc);
                        counts.merge(&Counts::cache(&cs));
                        None
                    }
                    Used::DiscIndex => {
                        let index = self.params.index.build(&discs, self.params.disc_radius);
                        let is = index.accumulate(store, ids.as_deref(), 1, &mut acc);
                        counts.merge(&Counts::index(&is));
                        // Kept for the walk alone only when it is timed (otherwise released here).
                        self.params
                            .time_traversal
                            .then_some(IndexWalk { index, ids })
                    }
                };
                (discs, acc, used, counts, walk)
            })
            .collect()
    }

    /// Times the disc index's traversal alone for the movers of `out` whose points used it (see
    /// [`FrameStats::dynamic_traversal_s`]: their indexes walked again over the state's own store
    /// as their pass walked it; 0 when none did, NaN when [`Params::time_traversal`] is off), then
    /// releases those indexes, charging the release to `dynamic_s` as when the pass dropped them
    /// itself. Returns the seconds to keep out of `frame_s`.
    fn time_traversal(&self, out: &mut [DynamicSums], stats: &mut FrameStats) -> f64 {
        let walks: Vec<IndexWalk> = out.iter_mut().filter_map(|o| o.4.take()).collect();
        let (traversal_s, aside) = timed(|| {
            let each = walks
                .iter()
                .map(|w| timed(|| w.index.traversal_only(&self.store, w.ids.as_deref())).1);
            if self.params.time_traversal {
                each.sum()
            } else {
                f64::NAN
            }
        });
        stats.dynamic_traversal_s = traversal_s;
        let ((), release_s) = timed(|| drop(walks));
        stats.dynamic_s += release_s;
        aside
    }

    fn apply_dynamic(&mut self, out: Vec<DynamicSums>, stats: &mut FrameStats) {
        for (dp, (discs, acc, used, k, _)) in self.dynamic.iter_mut().zip(out) {
            dp.discs = discs;
            dp.acc = acc;
            stats.used.push(used);
            stats.dynamic_disc_tests += k.disc_tests;
            stats.dynamic_sphere_tests += k.sphere_tests;
            stats.dynamic_traversal += k.traversal;
            stats.dynamic_rays_copied += k.rays_copied;
            stats.dynamic_spheres_built += k.spheres_built;
            stats.dynamic_feed += k.feed;
            stats.dynamic_rays_reaching += k.reaching;
        }
    }

    /// Advances to frame `f` (any frame: poses are pure functions of τ).
    pub fn step(&mut self, f: u32) -> FrameStats {
        let t_all = Instant::now();
        let mut stats = FrameStats {
            frame: f,
            ..Default::default()
        };
        let t_new = tau(f, self.params.frames);
        let new_spheres: Vec<(DVec3, f64)> = self
            .scene
            .movers
            .iter()
            .map(|m| m.bounds_at(t_new))
            .collect();
        // 1. Search.
        let ((affected, photons), s) = timed(|| {
            let mut affected: Vec<u32> = Vec::new();
            let live = |id: u32| !is_dead(&self.store.segments[id as usize]);
            let mut seen = std::mem::take(&mut self.seen);
            let mut meeting_new = 0;
            for (old, new) in self.spheres.iter().zip(&new_spheres) {
                for (k, &(c, r)) in [old, new].into_iter().enumerate() {
                    let (ids, st) = self
                        .index
                        .query(&self.store.segments, c, r, &live, &mut seen);
                    stats.search.add(&st);
                    if k == 1 {
                        meeting_new += ids.len() as u64;
                    }
                    affected.extend(ids);
                }
            }
            self.seen = seen;
            stats.meeting_new = meeting_new;
            affected.sort_unstable();
            affected.dedup();
            let mut photons: Vec<u32> = affected
                .iter()
                .map(|&i| self.store.segments[i as usize].photon)
                .collect();
            photons.sort_unstable();
            photons.dedup();
            (affected, photons)
        });
        stats.search_s = s;
        stats.affected_segments = affected.len() as u64;
        stats.photons_retraced = photons.len() as u64;
        // 2. Re-trace at the new pose.
        self.scene.set_tau(t_new);
        let old_spheres = std::mem::replace(&mut self.spheres, new_spheres);
        let (new_paths, s) = timed(|| {
            photons
                .par_iter()
                .map(|&p| self.retrace(p))
                .collect::<Vec<Vec<Segment>>>()
        });
        stats.retrace_s = s;
        // The new path replaces the old one in fresh slots; only the segments from the first one
        // that differs on are changes for the sums (a path's prefix before it meets the object is
        // the same, bit for bit).
        let mut old = Vec::new();
        let mut added = Vec::new();
        let mut retraced = 0;
        for (&p, path) in photons.iter().zip(new_paths) {
            let (a, l) = self.paths[p as usize];
            let before = &self.store.segments[a as usize..(a + l) as usize];
            let same = before.iter().zip(&path).take_while(|(x, y)| x == y).count();
            old.extend_from_slice(&before[same..]);
            for seg in &mut self.store.segments[a as usize..(a + l) as usize] {
                seg.power = 0;
                seg.t_end = -1.0;
            }
            self.dead += l as usize;
            let start = self.store.segments.len() as u32;
            self.paths[p as usize] = (start, path.len() as u32);
            retraced += path.len();
            added.extend(start + same as u32..start + path.len() as u32);
            self.store.segments.extend(path);
        }
        let first_new = self.store.segments.len() - retraced;
        for id in first_new..self.store.segments.len() {
            self.index.insert(id as u32, &self.store.segments[id]);
        }
        stats.segments_retraced = retraced as u64;
        // Every segment meeting a new pose belongs to a re-traced photon (it met the old or the
        // new pose before, or its photon's path changed): count them on the new paths.
        stats.meeting_pose = self.spheres.iter().fold(0, |n, &(c, r)| {
            n + self.store.segments[first_new..]
                .iter()
                .filter(|s| segment_index::meets_ball(s, c, r, 0.0))
                .count() as u64
        });
        stats.segments_removed = old.len() as u64;
        stats.segments_added = added.len() as u64;
        // 3. Static points: minus old, plus new.
        let ((), s) = timed(|| {
            let old_store = SegmentStore::new(old, self.store.scale);
            let (minus, t1) = self.static_sums(&old_store, None);
            let (plus, t2) = self.static_sums(&self.store, Some(&added));
            for ((a, m), p) in self.static_acc.iter_mut().zip(minus).zip(plus) {
                *a += p - m;
            }
            t1.add_static(&mut stats);
            t2.add_static(&mut stats);
        });
        stats.static_s = s;
        // 4. Dynamic points, afresh.
        let (mut dynamic, s) = timed(|| self.dynamic_sums(&self.store, true));
        stats.dynamic_s = s;
        // Before compaction moves the slots the walks list.
        let aside = self.time_traversal(&mut dynamic, &mut stats);
        self.apply_dynamic(dynamic, &mut stats);
        self.proof_facts(Some(&old_spheres), &mut stats);
        if self.dead > self.live_segments() {
            self.compact();
        }
        self.frame = f;
        stats.frame_s = t_all.elapsed().as_secs_f64() - aside;
        stats
    }

    /// Irradiance sums: static points, then every mover's points (in mover order).
    pub fn sums(&self) -> Vec<Acc> {
        let mut v = self.static_acc.clone();
        for dp in &self.dynamic {
            v.extend_from_slice(&dp.acc);
        }
        v
    }

    /// All sample points in the order of [`Self::sums`] (static, then each mover's, posed).
    pub fn discs(&self) -> Discs {
        let mut c = self.static_discs.centers.clone();
        let mut n = self.static_discs.normals.clone();
        for dp in &self.dynamic {
            c.extend_from_slice(&dp.discs.centers);
            n.extend_from_slice(&dp.discs.normals);
        }
        Discs::new(c, n, self.params.disc_radius).expect("finite points")
    }

    /// Static points, and each mover's points.
    pub fn point_counts(&self) -> (usize, Vec<usize>) {
        (
            self.static_discs.len(),
            self.dynamic.iter().map(|d| d.discs.len()).collect(),
        )
    }

    /// Warm timings of both dynamic-point engines on every live segment, for mover `mover`:
    /// `repeats` rounds, each timing the sphere cache then the disc index (interleaved, so a slow
    /// spell of the machine falls on both). Each entry is one round's (sphere cache, disc index)
    /// seconds. Call after the engines ran once (the predictor's measured pass warms them).
    pub fn warm_timings(&self, mover: usize, repeats: u64) -> Vec<[f64; 2]> {
        let live = self.live_store();
        (0..repeats)
            .map(|_| {
                [Used::SphereCache, Used::DiscIndex].map(|u| {
                    let t = Instant::now();
                    let _ = self.dynamic_sums_with(&live, false, Some(u), Some(mover));
                    t.elapsed().as_secs_f64()
                })
            })
            .collect()
    }

    /// Irradiance at every sample point (order of [`Self::sums`]): power over πd².
    pub fn irradiance(&self) -> Vec<f64> {
        let area = std::f64::consts::PI * self.params.disc_radius.powi(2);
        self.sums()
            .iter()
            .map(|&a| self.store.scale.watts(a) / area)
            .collect()
    }

    /// A reference irradiance at the same points and frame from a fresh trace of `photons` photons
    /// with another `seed` (for the error of a run against a high-photon reference).
    pub fn reference_irradiance(&self, photons: u64, seed: u64) -> Vec<f64> {
        let store = trace_photons(&self.scene, photons, seed);
        let discs = self.discs();
        let d = self.params.disc_radius;
        let mut acc = vec![0; discs.len()];
        GridIndex::build(&discs, 2.0 * d).accumulate(&store, None, 1, &mut acc);
        let area = std::f64::consts::PI * d * d;
        acc.iter().map(|&a| store.scale.watts(a) / area).collect()
    }

    /// The power scale of the sums.
    pub fn scale(&self) -> PowerScale {
        self.store.scale
    }

    /// The scene's root sphere (centre, r_0).
    pub fn root(&self) -> (DVec3, f64) {
        self.root
    }

    /// The live segments, photon by photon (what a full trace of this frame gives).
    pub fn live_store(&self) -> SegmentStore {
        let mut segs = Vec::with_capacity(self.live_segments());
        for &(a, l) in &self.paths {
            segs.extend_from_slice(&self.store.segments[a as usize..(a + l) as usize]);
        }
        SegmentStore::new(segs, self.store.scale)
    }

    /// A full recalculation of the current frame: every photon (of the run's range) traced again,
    /// every sum afresh with the same engines. Returns the sums (in [`Self::sums`] order), the fresh
    /// store, and seconds.
    pub fn full_recalculation(&self) -> (Vec<Acc>, SegmentStore, f64) {
        let t = Instant::now();
        let store = trace_range(
            self.lines,
            &self.scene,
            self.ids.clone(),
            self.params.photons,
            self.params.seed,
        );
        let (mut sums, _) = self.static_sums(&store, None);
        for (_, acc, ..) in self.dynamic_sums(&store, false) {
            sums.extend(acc);
        }
        (sums, store, t.elapsed().as_secs_f64())
    }
}

/// The rays `ids` of a run: photons from the scene's lights, or μ-random lines.
fn trace_range(lines: bool, scene: &Scene, ids: Range<u64>, n: u64, seed: u64) -> SegmentStore {
    if lines {
        lines::trace_lines(scene, ids, n, seed)
    } else {
        trace_photon_range(scene, ids, n, seed)
    }
}

/// What one engine counted on one set of points (both engines' counters in one shape).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Ray–disc tests.
    pub disc_tests: u64,
    /// Ray–sphere tests (sphere cache).
    pub sphere_tests: u64,
    /// Box tests + DDA steps (disc index).
    pub traversal: u64,
    /// Segments copied into lists (sphere cache).
    pub rays_copied: u64,
    /// Spheres built (sphere cache).
    pub spheres_built: u64,
    /// Segment-index cells read + segments tested to feed the engine.
    pub feed: u64,
    /// Segments that reached the disc index (disc index only; [`IndexStats::segments_reaching`]).
    pub reaching: u64,
}

impl Counts {
    fn cache(s: &CacheStats) -> Self {
        Self {
            disc_tests: s.ray_disc_tests,
            sphere_tests: s.ray_sphere_tests,
            rays_copied: s.rays_copied(),
            spheres_built: s.builds(),
            ..Self::default()
        }
    }

    fn index(s: &IndexStats) -> Self {
        Self {
            disc_tests: s.ray_disc_tests,
            traversal: s.traversal(),
            reaching: s.segments_reaching,
            ..Self::default()
        }
    }

    fn merge(&mut self, o: &Self) {
        self.disc_tests += o.disc_tests;
        self.sphere_tests += o.sphere_tests;
        self.traversal += o.traversal;
        self.rays_copied += o.rays_copied;
        self.spheres_built += o.spheres_built;
        self.feed += o.feed;
        self.reaching += o.reaching;
    }

    fn add_static(&self, st: &mut FrameStats) {
        st.static_disc_tests += self.disc_tests;
        st.static_sphere_tests += self.sphere_tests;
        st.static_traversal += self.traversal;
        st.static_rays_copied += self.rays_copied;
    }
}

impl FrameStats {
    /// The stats of the same frame over the union of two disjoint photon ranges (`--photon-shard`):
    /// every count adds — the search's cells, listings and tests and the feed's as the work the
    /// ranges' own segment indexes did, not what one index over all segments would do — and seconds
    /// add; None where the frames or the engines used differ.
    pub fn add(&self, o: &Self) -> Option<Self> {
        if self.frame != o.frame || self.used != o.used {
            return None;
        }
        let mut search = self.search;
        search.add(&o.search);
        Some(Self {
            frame: self.frame,
            affected_segments: self.affected_segments + o.affected_segments,
            meeting_new: self.meeting_new + o.meeting_new,
            meeting_pose: self.meeting_pose + o.meeting_pose,
            photons_retraced: self.photons_retraced + o.photons_retraced,
            segments_removed: self.segments_removed + o.segments_removed,
            segments_added: self.segments_added + o.segments_added,
            segments_retraced: self.segments_retraced + o.segments_retraced,
            search,
            static_disc_tests: self.static_disc_tests + o.static_disc_tests,
            static_sphere_tests: self.static_sphere_tests + o.static_sphere_tests,
            dynamic_disc_tests: self.dynamic_disc_tests + o.dynamic_disc_tests,
            dynamic_sphere_tests: self.dynamic_sphere_tests + o.dynamic_sphere_tests,
            dynamic_traversal: self.dynamic_traversal + o.dynamic_traversal,
            dynamic_rays_copied: self.dynamic_rays_copied + o.dynamic_rays_copied,
            dynamic_spheres_built: self.dynamic_spheres_built + o.dynamic_spheres_built,
            dynamic_feed: self.dynamic_feed + o.dynamic_feed,
            dynamic_rays_reaching: self.dynamic_rays_reaching + o.dynamic_rays_reaching,
            segments_live: self.segments_live + o.segments_live,
            dynamic_points: self.dynamic_points,
            ratio_sq: self.ratio_sq,
            union_share: self.union_share,
            static_traversal: self.static_traversal + o.static_traversal,
            static_rays_copied: self.static_rays_copied + o.static_rays_copied,
            used: self.used.clone(),
            search_s: self.search_s + o.search_s,
            retrace_s: self.retrace_s + o.retrace_s,
            static_s: self.static_s + o.static_s,
            dynamic_s: self.dynamic_s + o.dynamic_s,
            dynamic_traversal_s: self.dynamic_traversal_s + o.dynamic_traversal_s,
            frame_s: self.frame_s + o.frame_s,
        })
    }

    /// The dynamic points' counted cost, weight 1 per ray–sphere test, ray–disc test, box test and
    /// DDA step (the feed's query and the copies are counted apart; `docs/detp-costs.md`).
    pub fn dynamic_counted_cost(&self) -> u64 {
        self.dynamic_disc_tests + self.dynamic_sphere_tests + self.dynamic_traversal
    }

    /// f_R = n_R·Σ(r_D/r_0)² (eq. 11) with this frame's n_R: the segments expected to meet the
    /// objects at one pose were the segments μ-random lines.
    pub fn f_r_theory(&self) -> f64 {
        self.segments_live as f64 * self.ratio_sq
    }

    /// The segments expected to meet an object at its old or its new pose were they μ-random
    /// lines: n_R·Σ union share; 0 at frame 0.
    pub fn union_theory(&self) -> f64 {
        self.segments_live as f64 * self.union_share
    }

    /// The static points' counted cost, same weights.
    pub fn static_counted_cost(&self) -> u64 {
        self.static_disc_tests + self.static_sphere_tests + self.static_traversal
    }
}

/// A slot emptied by a re-trace (power 0 and t_end = −1: it can cross nothing).
#[inline]
fn is_dead(s: &Segment) -> bool {
    s.power == 0 && s.t_end == -1.0
}

/// The listed segments as a store of their own.
fn subset(store: &SegmentStore, ids: &[u32]) -> SegmentStore {
    SegmentStore::new(
        ids.iter().map(|&i| store.segments[i as usize]).collect(),
        store.scale,
    )
}

/// Points whose sums differ.
pub fn mismatches(a: &[Acc], b: &[Acc]) -> u64 {
    assert_eq!(a.len(), b.len(), "the same points");
    a.iter().zip(b).filter(|(x, y)| x != y).count() as u64
}

#[cfg(test)]
mod tests;
