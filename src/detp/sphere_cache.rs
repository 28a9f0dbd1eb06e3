//! The paper's sphere cache (§2.3), with the two repairs THEORY.md §2 calls for.
//!
//! Level i is a sphere of radius r_i = r_0·Q^i holding a list of segments. Points are visited in
//! the given order (a space-filling-curve permutation). For each point:
//! 1. **Keep only the chain of levels that all contain the disc** (`|c − s| + d ≤ r`, computed),
//!    dropping the first level that does not and everything below it. The paper's "pop until a
//!    sphere contains the disc" is wrong when a child sticks out of its parent: a disc inside a
//!    deep sphere can lie outside an ancestor whose dropped rays are then missing.
//! 2. While the deepest level holds at least `threshold` rays and r_{i+1} ≥ d, build level i+1
//!    centred on the point (it then contains the disc: `|c − c| + d = d ≤ r_{i+1}`). Its list is
//!    the segments of a source list that meet it ([`filter::meets`]): in [`ListMode::Exact`] the
//!    source is the deepest ancestor that encloses the child entirely (else the root), so every
//!    list is exactly the segments that meet its sphere (and the root) and the rays-per-level law
//!    n_R·(r_i/r_0)² applies; in [`ListMode::Inherited`] it is the parent (the paper's literal
//!    rule, cheaper, but a protruding child holds fewer rays than meet it).
//! 3. Test the deepest list against the disc with [`crate::detp::disc::crosses`].
//!
//! # Why no crossing is lost
//! A segment crossing the disc meets every sphere that contains the disc (filter module doc,
//! fact 1). Inherited: the deepest list is the segments that passed every sphere of the chain,
//! which all contain the disc. Exact: by induction each list is exactly {segments meeting the root
//! and the sphere}, because the source encloses the child (fact 2: meeting the child implies
//! meeting the source); the disc lies in the root and the deepest sphere. A disc outside the root
//! (a root that does not hold the scene) is tested against every segment.
//!
//! # Counters and threads
//! The ordered points are cut into chunks of `chunk_points` (a parameter, never the thread count),
//! each with its own cache, run in parallel; every counter is an integer sum over chunks, so it is
//! the same for any thread count. The root list (level 0) is built once and shared: level 0 counts
//! one build and one test per segment. A level's `misses` are its builds except those made for a
//! chunk's first point (cold starts). Level numbering starts at 0 with the root, r_i = r_0·Q^i.
//!
//! # The paper's §4.2 numbers, with this convention
//! 2²⁰ uniform lines, 10⁵ points uniform in the unit ball (d = 0.002, root radius 1 + d), Morton
//! order, Q = 0.6, threshold 100, exact lists: level 9 holds 106.7 rays on average (SE 0.03;
//! n_R·(r_9/1)² = 106.9), not the paper's 94.6; inherited lists hold 103.9. Misses rise with the
//! level up to level 9 (98 222 of 10⁵ points) and drop at level 10 (75 313), which is built only
//! when level 9 holds ≥ 100 rays. Spheres smaller than the point spacing (0.035 here) are rebuilt
//! for nearly every point, so m_i saturates at n_P instead of growing as Q^(−3i).

pub mod filter;

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use self::filter::{filter, kappa, FilterPath, Probe, RayList, MAX_LEVEL};
use super::disc::Discs;
use super::fixed::{add, Acc};
use super::store::SegmentStore;
use crate::geom::Aabb;

/// Where a new level takes its list from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListMode {
    /// The deepest ancestor that encloses the child (exact lists; the default).
    Exact,
    /// The parent (the paper's literal rule).
    Inherited,
}

/// Parameters of one sphere-cache run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereCacheParams {
    /// Ratio of consecutive radii, in (0, 1).
    pub q: f64,
    /// A level with at least this many rays gets a child (the paper's subdivision limit).
    pub threshold: usize,
    /// Where a new list comes from.
    pub list_mode: ListMode,
    /// Points per independent cache (the unit of parallel work).
    pub chunk_points: usize,
    /// The ball the rays are μ-random in, when they are (centre, radius): builds of spheres that lie
    /// inside it are counted apart (`inside_*`), since for them integral geometry gives the
    /// expected list length exactly, n_R·(r/R)², whatever their position.
    pub law_ball: Option<(DVec3, f64)>,
}

impl Default for SphereCacheParams {
    fn default() -> Self {
        Self {
            q: 2.0 / 3.0,
            threshold: 100,
            list_mode: ListMode::Exact,
            chunk_points: 4096,
            law_ball: None,
        }
    }
}

/// Exact counts for one level.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LevelStats {
    /// r_0·Q^i.
    pub radius: f64,
    /// Spheres built at this level.
    pub builds: u64,
    /// Builds except those for a chunk's first point.
    pub misses: u64,
    /// Σ list length over builds.
    pub rays_held: u64,
    /// Σ (list length)² over builds, for a standard error.
    pub rays_held_sq: u128,
    /// Builds of spheres inside the law ball (see [`SphereCacheParams::law_ball`]).
    pub inside_builds: u64,
    /// Σ list length over those builds.
    pub inside_rays_held: u64,
    /// Σ (list length)² over those builds.
    pub inside_rays_held_sq: u128,
    /// Builds holding fewer rays than the threshold: the spheres that are never subdivided (the
    /// paper's "94.6 rays at level 9" may be their mean; THEORY.md §2).
    pub leaf_builds: u64,
    /// Σ list length over those builds.
    pub leaf_rays_held: u64,
    /// Σ (list length)² over those builds.
    pub leaf_rays_held_sq: u128,
    /// Segments tested against spheres of this level while building them.
    pub ray_sphere_tests: u64,
}

impl LevelStats {
    /// Mean rays held per build and its standard error (None without builds; SE None below two).
    pub fn mean_rays(&self) -> Option<(f64, Option<f64>)> {
        if self.builds == 0 {
            return None;
        }
        let n = self.builds as f64;
        let mean = self.rays_held as f64 / n;
        let se = (self.builds > 1).then(|| {
            let var = (self.rays_held_sq as f64 - n * mean * mean) / (n - 1.0);
            (var.max(0.0) / n).sqrt()
        });
        Some((mean, se))
    }
}

/// Counters of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CacheStats {
    /// Per level, from the root (level 0).
    pub levels: Vec<LevelStats>,
    /// Segment–disc tests (deepest lists, plus every segment for a disc outside the root).
    pub ray_disc_tests: u64,
    /// Segment–sphere tests over all levels.
    pub ray_sphere_tests: u64,
}

impl CacheStats {
    /// Adds `other`'s counts to these (levels aligned by index; a level's radius is the same
    /// wherever it was built, and unset where it never was).
    pub fn merge(&mut self, other: &CacheStats) {
        if self.levels.len() < other.levels.len() {
            self.levels
                .resize(other.levels.len(), LevelStats::default());
        }
        for (a, b) in self.levels.iter_mut().zip(&other.levels) {
            if b.builds > 0 {
                a.radius = b.radius;
            }
            a.builds += b.builds;
            a.misses += b.misses;
            a.rays_held += b.rays_held;
            a.rays_held_sq += b.rays_held_sq;
            a.inside_builds += b.inside_builds;
            a.inside_rays_held += b.inside_rays_held;
            a.leaf_builds += b.leaf_builds;
            a.leaf_rays_held += b.leaf_rays_held;
            a.leaf_rays_held_sq += b.leaf_rays_held_sq;
            a.inside_rays_held_sq += b.inside_rays_held_sq;
            a.ray_sphere_tests += b.ray_sphere_tests;
        }
        self.ray_disc_tests += other.ray_disc_tests;
        self.ray_sphere_tests += other.ray_sphere_tests;
    }

    fn level(&mut self, i: usize, radius: f64) -> &mut LevelStats {
        if self.levels.len() <= i {
            self.levels.resize(i + 1, LevelStats::default());
        }
        let l = &mut self.levels[i];
        l.radius = radius;
        l
    }
}

/// The sphere circumscribing `bounds` (centre, half diagonal, enlarged by 2⁻⁴⁰ relative so that
/// the box's corners pass the containment test despite rounding).
pub fn root_sphere(bounds: &Aabb) -> (DVec3, f64) {
    let c = (bounds.lo + bounds.hi) * 0.5;
    let r = (bounds.hi - bounds.lo).length() * 0.5;
    (c, r * (1.0 + (-40f64).exp2()))
}

/// Runs the cache over the discs in the order `perm`, adding each disc's crossing power to
/// `acc[disc]`, with the fastest filter this CPU has.
pub fn run(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    acc: &mut [Acc],
) -> CacheStats {
    run_with(store, discs, perm, root, params, acc, FilterPath::detect())
}

/// [`run`] with a chosen filter path (every path gives the same lists; tests force each).
///
/// # Panics
/// On Q outside (0, 1), a zero chunk size, `acc` shorter than the discs, or an unavailable path.
pub fn run_with(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    acc: &mut [Acc],
    path: FilterPath,
) -> CacheStats {
    assert!(params.q > 0.0 && params.q < 1.0, "Q must lie in (0, 1)");
    assert!(params.chunk_points > 0, "chunk_points must be positive");
    assert!(acc.len() >= discs.len(), "one accumulator per disc");
    assert!(path.is_available(), "filter path {path:?} not available");
    let (center, r0) = root;
    let all = RayList::from_segments(&store.segments, center);
    let origin_bound = all.origin_bound();
    let probe = Probe::new(center, origin_bound, center, r0, kappa(0));
    let mut root_list = RayList::default();
    filter(path, &all, &probe, &store.segments, &mut root_list);
    drop(all);
    let mut stats = CacheStats::default();
    let l0 = stats.level(0, r0);
    l0.builds = 1;
    l0.rays_held = root_list.len() as u64;
    l0.rays_held_sq = (root_list.len() as u128).pow(2);
    l0.ray_sphere_tests = store.len() as u64;
    stats.ray_sphere_tests = store.len() as u64;
    let ctx = Ctx {
        store,
        discs,
        params,
        path,
        center,
        r0,
        origin_bound,
        root: &root_list,
    };
    let chunks: Vec<(Vec<Acc>, CacheStats)> = perm
        .par_chunks(params.chunk_points)
        .map(|points| ctx.chunk(points))
        .collect();
    for (points, (sums, s)) in perm.chunks(params.chunk_points).zip(chunks) {
        for (&p, v) in points.iter().zip(sums) {
            acc[p as usize] += v;
        }
        stats.merge(&s);
    }
    stats
}

/// What every chunk shares.
struct Ctx<'a> {
    store: &'a SegmentStore,
    discs: &'a Discs,
    params: &'a SphereCacheParams,
    path: FilterPath,
    center: DVec3,
    r0: f64,
    origin_bound: f64,
    root: &'a RayList,
}

/// One level of a chunk's cache.
struct Level<'a> {
    center: DVec3,
    radius: f64,
    list: Cow<'a, RayList>,
}

impl Level<'_> {
    #[inline]
    fn contains(&self, c: DVec3, d: f64) -> bool {
        (c - self.center).length() + d <= self.radius
    }
}

impl<'a> Ctx<'a> {
    /// One chunk: its own cache, its points' sums in chunk order, its counters.
    fn chunk(&self, points: &[u32]) -> (Vec<Acc>, CacheStats) {
        let d = self.discs.radius;
        let segs = &self.store.segments;
        let mut stats = CacheStats::default();
        let mut sums = vec![0; points.len()];
        let mut stack: Vec<Level<'a>> = vec![Level {
            center: self.center,
            radius: self.r0,
            list: Cow::Borrowed(self.root),
        }];
        let mut scratch = RayList::default();
        for (k, (&p, sum)) in points.iter().zip(&mut sums).enumerate() {
            let p = p as usize;
            let c = self.discs.centers[p];
            if !stack[0].contains(c, d) {
                for s in segs {
                    if self.discs.crossed_by(s, p) {
                        add(sum, s.power, 1);
                    }
                }
                stats.ray_disc_tests += segs.len() as u64;
                continue;
            }
            let keep = 1 + stack[1..]
                .iter()
                .position(|l| !l.contains(c, d))
                .unwrap_or(stack.len() - 1);
            stack.truncate(keep);
            while stack.last().map_or(0, |l| l.list.len()) >= self.params.threshold
                && stack.len() <= MAX_LEVEL
            {
                let i = stack.len();
                let r = self.r0 * self.params.q.powi(i as i32);
                if r < d {
                    break;
                }
                let src = match self.params.list_mode {
                    ListMode::Inherited => i - 1,
                    ListMode::Exact => (1..i)
                        .rev()
                        .find(|&j| (c - stack[j].center).length() + r <= stack[j].radius)
                        .unwrap_or(0),
                };
                let probe = Probe::new(self.center, self.origin_bound, c, r, kappa(i));
                // Filter into a warm scratch list with room for the whole source, then keep an
                // exact-size copy: reusing dropped lists instead kept every level at the root's
                // size (5× the memory at n_R = 2²⁰), and fresh source-size lists cost page faults.
                filter(self.path, &stack[src].list, &probe, segs, &mut scratch);
                let list = scratch.clone();
                let tested = stack[src].list.len() as u64;
                let held = list.len() as u64;
                let l = stats.level(i, r);
                l.builds += 1;
                l.misses += u64::from(k != 0);
                l.rays_held += held;
                l.rays_held_sq += u128::from(held) * u128::from(held);
                if list.len() < self.params.threshold {
                    l.leaf_builds += 1;
                    l.leaf_rays_held += held;
                    l.leaf_rays_held_sq += u128::from(held) * u128::from(held);
                }
                if let Some((lc, lr)) = self.params.law_ball {
                    if (c - lc).length() + r <= lr {
                        l.inside_builds += 1;
                        l.inside_rays_held += held;
                        l.inside_rays_held_sq += u128::from(held) * u128::from(held);
                    }
                }
                l.ray_sphere_tests += tested;
                stats.ray_sphere_tests += tested;
                stack.push(Level {
                    center: c,
                    radius: r,
                    list: Cow::Owned(list),
                });
            }
            let deepest = &stack[stack.len() - 1].list;
            for &s in deepest.indices() {
                let seg = &segs[s as usize];
                if self.discs.crossed_by(seg, p) {
                    add(sum, seg.power, 1);
                }
            }
            stats.ray_disc_tests += deepest.len() as u64;
        }
        (sums, stats)
    }
}

#[cfg(test)]
mod tests;
