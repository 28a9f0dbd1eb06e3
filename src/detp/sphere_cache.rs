//! The paper's sphere cache (§2.3), with the two repairs docs/theory.md §2 calls for.
//!
//! Level i is a sphere of radius r_i = r_0·Q^i holding a list of segments. Points are visited in
//! the given order (a space-filling-curve permutation). For each point:
//! 1. **Pop** ([`PopRule`]). [`PopRule::Chain`] (the default) keeps only the chain of levels
//!    that all contain the disc (`|c − s| + d ≤ r`, computed), dropping the first level that does
//!    not and everything below it. [`PopRule::Paper`] pops the deepest level while it does not
//!    contain the disc, as the paper does; with inherited lists that is wrong when a child sticks
//!    out of its parent (a disc inside a deep sphere can lie outside an ancestor whose dropped rays
//!    are then missing), so there the chain is cut back as the chain rule cuts it (counted as a
//!    repair); with exact lists every list is exact whatever its ancestors, and the paper's rule
//!    stands as it is.
//! 2. While the deepest level holds at least `threshold` rays and r_{i+1} ≥ d, build level i+1
//!    centred on the point (it then contains the disc: `|c − c| + d = d ≤ r_{i+1}`). Its list is
//!    the segments of a source list that meet it ([`filter::meets`]): in [`ListMode::Exact`] the
//!    source is the deepest ancestor that encloses the child entirely (else the root), so every
//!    list is exactly the segments that meet its sphere (and the root) and the rays-per-level law
//!    n_R·(r_i/r_0)² applies; in [`ListMode::Inherited`] it is the parent (the paper's literal
//!    rule, cheaper, but a protruding child holds fewer rays than meet it).
//! 3. Test the deepest list against the disc with [`crate::detp::disc::crosses`].
//!
//! Defaults: inherited lists and the chain rule — the paper's cache with the one repair that keeps
//! every disc's answer exact (docs/theory.md §2: test the paper's claims with the paper's cache).
//!
//! # Why no crossing is lost
//! A segment crossing the disc meets every sphere that contains the disc (filter module doc,
//! fact 1). Inherited (always with the chain, see 1.): the deepest list is the segments that passed
//! every sphere of the chain, which all contain the disc. Exact: by induction each list is exactly {segments meeting the root
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
//! order, Q = 0.6, threshold 100, seed 1, one replica (`raycost run` on a `kind = "detp"` spec with
//! exactly these keys, `brute_force_points = 64`, swept over `detp.list_mode`; 0 mismatches):
//! exact lists hold 106.92 rays on average at level 9 (n_R·(r_9/1)² = 106.92), not the paper's
//! 94.6; inherited lists hold 104.05. Misses rise with the level up to level 9 (exact 98 292,
//! inherited 98 272 of 10⁵ points) and drop at level 10 (exact 75 963, inherited 66 167), which is
//! built only when level 9 holds ≥ 100 rays. Spheres smaller than the point spacing (0.035 here)
//! are rebuilt for nearly every point, so m_i saturates at n_P instead of growing as Q^(−3i).

pub mod filter;

use glam::DVec3;
use rayon::prelude::*;

use self::filter::{filter, kappa, FilterPath, Probe, RayList, MAX_LEVEL};
use super::disc::Discs;
use super::disc_index::cross::crossing_segments;
use super::disc_index::SimdPath;
use super::fixed::Acc;
use super::store::SegmentStore;
use super::tally::{Power, Tally};
use crate::geom::Aabb;

/// Where a new level takes its list from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListMode {
    /// The deepest ancestor that encloses the child (exact lists: raycost's variant).
    Exact,
    /// The parent (the paper's rule, §3; the default).
    Inherited,
}

/// Which levels a new point keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PopRule {
    /// Keep the chain of levels that all contain the disc: drop the first level (from the root)
    /// that does not, and everything below it (the default; exact with either list mode).
    Chain,
    /// The paper's rule: pop the deepest level while it does not contain the disc, keep everything
    /// above the first that does. Exact lists make it exact as it stands (every list holds exactly
    /// the segments meeting its sphere, whatever its ancestors); with inherited lists a kept level
    /// that does not contain the disc may have dropped crossing segments, so there the chain is cut
    /// as [`PopRule::Chain`] cuts it (a *repair*, counted in [`CacheStats::pop_repairs`]).
    Paper,
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
    /// Which levels a new point keeps.
    pub pop_rule: PopRule,
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
            list_mode: ListMode::Inherited,
            pop_rule: PopRule::Chain,
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
    /// Σ list length over builds: the segments copied into this level's lists.
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
    /// paper's "94.6 rays at level 9" may be their mean; docs/theory.md §2).
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
    /// [`PopRule::Paper`]: points whose kept chain held a level not containing the disc (with
    /// inherited lists the chain was then cut there; with exact lists nothing needed doing).
    pub pop_repairs: u64,
}

impl CacheStats {
    /// Spheres built over all levels (the root's one build included).
    pub fn builds(&self) -> u64 {
        self.levels.iter().map(|l| l.builds).sum()
    }

    /// Segments copied into lists over all levels (the root's list included).
    pub fn rays_copied(&self) -> u64 {
        self.levels.iter().map(|l| l.rays_held).sum()
    }

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
        self.pop_repairs += other.pop_repairs;
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

/// [`run`] with no level deeper than `max_level` built (the deepest list then serves the disc
/// tests): the §4.1 predictor simulates the upper levels this way and takes the lower ones from
/// theory. `max_level` ≥ the deepest level the run reaches gives exactly [`run`]'s counts.
pub fn run_to_level(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    acc: &mut [Acc],
    max_level: usize,
) -> CacheStats {
    run_capped(
        store,
        discs,
        perm,
        root,
        params,
        acc,
        FilterPath::detect(),
        max_level,
    )
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
    run_capped(store, discs, perm, root, params, acc, path, MAX_LEVEL)
}

/// [`run_with`] for any [`Tally`]: offers each disc's crossings to `acc[disc]` (the power sums
/// are [`run_with`]; the k-nearest crossings are [`crate::detp::nearest::Nearest`]).
#[allow(clippy::too_many_arguments)]
pub fn run_tally<T: Tally>(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    tally: &T,
    acc: &mut [T::State],
    path: FilterPath,
) -> CacheStats {
    run_generic(
        store, discs, perm, root, params, tally, acc, path, MAX_LEVEL,
    )
}

/// [`run_with`] building no level deeper than `max_level` (at most [`MAX_LEVEL`]).
#[allow(clippy::too_many_arguments)]
fn run_capped(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    acc: &mut [Acc],
    path: FilterPath,
    max_level: usize,
) -> CacheStats {
    let tally = Power { sign: 1 };
    run_generic(
        store, discs, perm, root, params, &tally, acc, path, max_level,
    )
}

/// The cache's one driver, for any [`Tally`].
#[allow(clippy::too_many_arguments)]
fn run_generic<T: Tally>(
    store: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (DVec3, f64),
    params: &SphereCacheParams,
    tally: &T,
    acc: &mut [T::State],
    path: FilterPath,
    max_level: usize,
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
        simd: simd_for(path),
        max_level: max_level.min(MAX_LEVEL),
    };
    // One set of level lists per worker, reused by every chunk it runs (the lists' contents never
    // carry over: each build rewrites its level's list), so a steady-state run allocates nothing.
    let chunks: Vec<(Vec<T::State>, CacheStats)> = perm
        .par_chunks(params.chunk_points)
        .map_init(Vec::new, |lists, points| ctx.chunk(tally, points, lists))
        .collect();
    for (points, (sums, s)) in perm.chunks(params.chunk_points).zip(chunks) {
        for (&p, v) in points.iter().zip(sums) {
            tally.merge(&mut acc[p as usize], v);
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
    /// The disc tests' path, matching the filter's (see [`simd_for`]).
    simd: SimdPath,
    /// The deepest level built.
    max_level: usize,
}

/// The disc tests' SIMD path for a filter path: the same instruction set (every path decides as
/// `crosses` does).
fn simd_for(path: FilterPath) -> SimdPath {
    match path {
        FilterPath::Avx512 => SimdPath::Avx512,
        FilterPath::Avx2 => SimdPath::Avx2,
        FilterPath::Portable => SimdPath::Scalar,
    }
}

/// One level of a chunk's cache; its list is the root's (level 0) or `lists[level]`.
struct Level {
    center: DVec3,
    radius: f64,
    /// Segments in the level's list.
    len: usize,
}

impl Level {
    #[inline]
    fn contains(&self, c: DVec3, d: f64) -> bool {
        (c - self.center).length() + d <= self.radius
    }
}

impl<'a> Ctx<'a> {
    /// The list of level `i` of a chunk's cache.
    fn list<'l>(&'l self, lists: &'l [RayList], i: usize) -> &'l RayList {
        if i == 0 {
            self.root
        } else {
            &lists[i]
        }
    }

    /// One chunk: its own cache, its points' sums in chunk order, its counters. `lists[i]` holds
    /// level i's list (i ≥ 1); the buffers are the caller's, reused from chunk to chunk.
    fn chunk<T: Tally>(
        &self,
        tally: &T,
        points: &[u32],
        lists: &mut Vec<RayList>,
    ) -> (Vec<T::State>, CacheStats) {
        let d = self.discs.radius;
        let segs = &self.store.segments;
        let mut stats = CacheStats::default();
        let mut sums = tally.empties(points.len());
        let mut stack: Vec<Level> = vec![Level {
            center: self.center,
            radius: self.r0,
            len: self.root.len(),
        }];
        for (k, (&p, sum)) in points.iter().zip(&mut sums).enumerate() {
            let p = p as usize;
            let c = self.discs.centers[p];
            let n = self.discs.normals[p];
            if !stack[0].contains(c, d) {
                for (k, s) in segs.iter().enumerate() {
                    if self.discs.crossed_by(s, p) {
                        tally.offer(sum, s, k as u32, || (c, n));
                    }
                }
                stats.ray_disc_tests += segs.len() as u64;
                continue;
            }
            // The chain: up to the first level (below the root) not containing the disc.
            let chain = 1 + stack[1..]
                .iter()
                .position(|l| !l.contains(c, d))
                .unwrap_or(stack.len() - 1);
            let keep = match self.params.pop_rule {
                PopRule::Chain => chain,
                PopRule::Paper => {
                    // Up to the deepest level containing the disc (the root always does).
                    let paper = (1..stack.len())
                        .rev()
                        .find(|&j| stack[j].contains(c, d))
                        .map_or(1, |j| j + 1);
                    if paper > chain {
                        stats.pop_repairs += 1;
                    }
                    match self.params.list_mode {
                        ListMode::Exact => paper,
                        ListMode::Inherited => chain,
                    }
                }
            };
            stack.truncate(keep);
            while stack.last().map_or(0, |l| l.len) >= self.params.threshold
                && stack.len() <= self.max_level
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
                // Straight into level i's own list, reused from point to point: it grows only
                // past its longest list so far (the filter makes room as lanes are kept), so in a
                // steady state nothing is allocated, copied or faulted in. (The first version
                // filtered into a scratch list of the source's size and kept an exact-size copy:
                // 13 % of the run in `memmove`, 3.6 M page faults at Q = 0.9.)
                if lists.len() <= i {
                    lists.resize_with(i + 1, RayList::default);
                }
                let (head, tail) = lists.split_at_mut(i);
                filter(self.path, self.list(head, src), &probe, segs, &mut tail[0]);
                let tested = stack[src].len as u64;
                let held = tail[0].len() as u64;
                let l = stats.level(i, r);
                l.builds += 1;
                l.misses += u64::from(k != 0);
                l.rays_held += held;
                l.rays_held_sq += u128::from(held) * u128::from(held);
                if tail[0].len() < self.params.threshold {
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
                    len: held as usize,
                });
            }
            let deepest = self.list(lists, stack.len() - 1);
            // `Discs::crossed_by`'s decisions, four or eight segments at a time.
            let disc = (c, n, self.discs.radius_of(p));
            crossing_segments(self.simd, segs, deepest.indices(), disc, &mut |s| {
                tally.offer(sum, &segs[s as usize], s, || (c, n));
            });
            stats.ray_disc_tests += deepest.len() as u64;
        }
        (sums, stats)
    }
}

#[cfg(test)]
mod tests;
