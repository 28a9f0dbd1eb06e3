//! The DETP engines' speed on one scene, side by side: sphere cache, grid index, octree and brute
//! force, each on 1 and 2 threads (each run in its own rayon pool), every answer checked against
//! brute force on a subset of points.
//!
//! Scene (the paper's §4.2 validation): n_R μ-random lines through the unit sphere (segments from
//! their first point on the sphere, t_end = +∞), n_P points uniform in the unit ball with uniform
//! normals, Hilbert order at 10 bits per axis. The disc radius is half the mean point spacing:
//! d = r_0·(4π/3 / n_P)^(1/3) / 2 with r_0 = 1 (0.0172 for n_P = 10⁵), so neighbouring discs
//! about touch (the paper's cost model spaces points by ≈ d; this is that within a factor 2).
//! Sphere cache: root sphere of radius 1 + d about the origin (the smallest that holds every disc),
//! Q = 2/3, threshold 100, exact lists, chunks of 4096 points. Grid index: cells of width 2d;
//! octree: leaves of at most 32 discs, no side below 2d. Both were the fastest or within 15 % of
//! it among widths d–6d and leaves of 8–128 discs, timed single-threaded at 10⁴ and 10⁵ discs (2d
//! beat d by 1.5× at 10⁵: the walk is bound by loads of cell offsets and disc records, so fewer,
//! fuller cells pay).
//!
//! Full run: n_R = 1024·1024, n_P = 10⁵, brute force on 256 points; quick: 2¹⁶ lines, 10⁴ points.

use std::time::Instant;

use glam::DVec3;
use rand::Rng;

use super::memory::peak_increment;
use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::disc_index::{DiscIndex, GridIndex, Octree};
use crate::detp::fixed::{Acc, PowerScale};
use crate::detp::order::{permutation, Order};
use crate::detp::sphere_cache::filter::{filter, kappa, FilterPath, Probe, RayList};
use crate::detp::sphere_cache::{self, SphereCacheParams};
use crate::detp::store::{Segment, SegmentStore};
use crate::sample::lines::{uniform_line, uniform_on_sphere};
use crate::sample::rng::stream;

/// Stream key of the DETP bench scene.
const KEY: u64 = 0x6465_7470;

/// One engine on one thread count.
#[derive(Clone, Debug, PartialEq)]
pub struct DetpBenchRow {
    /// `sphere-cache`, `disc-index-grid`, `disc-index-octree` or `brute-force`.
    pub engine: &'static str,
    /// Points (discs) the engine computed.
    pub points: u64,
    /// Segments in the store.
    pub rays: u64,
    /// Threads of the pool it ran in.
    pub threads: usize,
    /// Seconds of the accumulation (excluding the build).
    pub wall_s: f64,
    /// Seconds of the build (index build; for the sphere cache, the point sort).
    pub build_s: f64,
    /// Segment–sphere tests (sphere cache only).
    pub ray_sphere_tests: u64,
    /// Segment–disc tests.
    pub ray_disc_tests: u64,
    /// `ray_sphere_tests / wall_s`.
    pub ray_sphere_tests_per_s: f64,
    /// `ray_disc_tests / wall_s`.
    pub ray_disc_tests_per_s: f64,
    /// Peak resident bytes added while the engine built and ran.
    pub peak_mem_bytes: u64,
    /// Points of the brute-force subset whose sum differs from brute force (0 when correct).
    pub mismatches: u64,
    /// The sphere cache's filter path (`avx512`, `avx2`, `portable`); `-` for other engines.
    pub filter_path: &'static str,
}

/// Sizes of one bench run.
#[derive(Clone, Copy, Debug)]
struct Plan {
    rays: u32,
    points: usize,
    brute_points: usize,
}

/// Runs the bench (see the module doc) and returns one row per engine and thread count.
pub fn run(quick: bool) -> Vec<DetpBenchRow> {
    let plan = if quick {
        Plan {
            rays: 1 << 16,
            points: 10_000,
            brute_points: 256,
        }
    } else {
        Plan {
            rays: 1 << 20,
            points: 100_000,
            brute_points: 256,
        }
    };
    run_plan(plan)
}

/// The scene: uniform lines and points (see the module doc).
fn scene(plan: Plan) -> (SegmentStore, Discs) {
    let mut rng = stream(&[KEY, 0]);
    let segs = (0..plan.rays)
        .map(|k| {
            let (p, d) = uniform_line(&mut rng);
            Segment::new(p, d, 0.0, f64::INFINITY, rng.gen_range(1..1 << 20), k)
        })
        .collect();
    let d = (4.0 * std::f64::consts::PI / 3.0 / plan.points as f64).cbrt() / 2.0;
    (
        SegmentStore::new(segs, PowerScale::for_max_power(1.0)),
        Discs::in_ball(&mut rng, plan.points, DVec3::ZERO, 1.0, d),
    )
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
}

/// What one engine run measured.
struct Measured {
    acc: Vec<Acc>,
    wall_s: f64,
    build_s: f64,
    sphere: u64,
    disc: u64,
}

fn run_plan(plan: Plan) -> Vec<DetpBenchRow> {
    let (store, discs) = scene(plan);
    let n = discs.len();
    let step = (n / plan.brute_points).max(1);
    let subset: Vec<u32> = (0..n).step_by(step).map(|i| i as u32).collect();
    let mut rows = Vec::new();
    let mut oracle: Option<Vec<Acc>> = None;
    let params = SphereCacheParams::default();
    let d = discs.radius;
    // The unit sphere grown by d (and a hair for rounding) holds every disc; with r_0 = 1 a disc
    // near the rim would stick out of the root and be tested against every segment.
    let root = (DVec3::ZERO, 1.0 + d * (1.0 + 1e-9));
    for threads in [1, 2] {
        let p = pool(threads);
        // Brute force first: its sums are the reference for every other engine.
        let (m, brute_mem) = p.install(|| {
            peak_increment(|| {
                let mut acc = vec![0; n];
                let t = Instant::now();
                let tests = brute::accumulate(&store, &discs, Some(&subset), 1, &mut acc);
                Measured {
                    wall_s: t.elapsed().as_secs_f64(),
                    acc,
                    build_s: 0.0,
                    sphere: 0,
                    disc: tests,
                }
            })
        });
        let reference = oracle.get_or_insert_with(|| m.acc.clone()).clone();
        let mismatches = |acc: &[Acc]| {
            subset
                .iter()
                .filter(|&&i| acc[i as usize] != reference[i as usize])
                .count() as u64
        };
        let engines: [(&'static str, &(dyn Fn() -> Measured + Sync)); 3] = [
            ("sphere-cache", &|| {
                let t = Instant::now();
                let perm = permutation(&discs.centers, Order::Hilbert, 10);
                let build_s = t.elapsed().as_secs_f64();
                let mut acc = vec![0; n];
                let t = Instant::now();
                let s = sphere_cache::run(&store, &discs, &perm, root, &params, &mut acc);
                Measured {
                    wall_s: t.elapsed().as_secs_f64(),
                    acc,
                    build_s,
                    sphere: s.ray_sphere_tests,
                    disc: s.ray_disc_tests,
                }
            }),
            ("disc-index-grid", &|| {
                let t = Instant::now();
                let g = GridIndex::build(&discs, 2.0 * d);
                indexed(&g, &store, n, t.elapsed().as_secs_f64())
            }),
            ("disc-index-octree", &|| {
                let t = Instant::now();
                let o = Octree::build(&discs, 32, 2.0 * d);
                indexed(&o, &store, n, t.elapsed().as_secs_f64())
            }),
        ];
        let mut push = |engine: &'static str, m: Measured, mem: u64, points: usize| {
            rows.push(DetpBenchRow {
                engine,
                points: points as u64,
                rays: store.len() as u64,
                threads,
                wall_s: m.wall_s,
                build_s: m.build_s,
                ray_sphere_tests: m.sphere,
                ray_disc_tests: m.disc,
                ray_sphere_tests_per_s: m.sphere as f64 / m.wall_s,
                ray_disc_tests_per_s: m.disc as f64 / m.wall_s,
                peak_mem_bytes: mem,
                mismatches: mismatches(&m.acc),
                filter_path: if engine == "sphere-cache" {
                    FilterPath::detect().name()
                } else {
                    "-"
                },
            });
        };
        for (engine, f) in engines {
            let (m, mem) = p.install(|| peak_increment(f));
            push(engine, m, mem, n);
        }
        push("brute-force", m, brute_mem, subset.len());
    }
    rows
}

fn indexed<I: DiscIndex>(ix: &I, store: &SegmentStore, n: usize, build_s: f64) -> Measured {
    let mut acc = vec![0; n];
    let t = Instant::now();
    let s = ix.accumulate(store, None, 1, &mut acc);
    Measured {
        wall_s: t.elapsed().as_secs_f64(),
        acc,
        build_s,
        sphere: 0,
        disc: s.ray_disc_tests,
    }
}

/// Single-thread speed of the ray–sphere filter on one path: tests per second over lists that fit
/// in L2 (4096 lanes of uniform lines, spheres of radius 0.3 at random centres in the ball, about
/// a third of the lanes kept), the setting of a cache's deep levels.
pub fn filter_speed(path: FilterPath, tests: u64) -> f64 {
    let mut rng = stream(&[KEY, 1]);
    let segs: Vec<Segment> = (0..4096)
        .map(|k| {
            let (p, d) = uniform_line(&mut rng);
            Segment::new(p, d, 0.0, f64::INFINITY, 1, k)
        })
        .collect();
    let list = RayList::from_segments(&segs, DVec3::ZERO);
    let bound = list.origin_bound();
    let probes: Vec<Probe> = (0..64)
        .map(|_| {
            let c = uniform_on_sphere(&mut rng) * rng.gen_range(0.0..0.5);
            Probe::new(DVec3::ZERO, bound, c, 0.3, kappa(3))
        })
        .collect();
    let mut out = RayList::default();
    let mut kept = 0;
    let rounds = tests.div_ceil(list.len() as u64);
    let t = Instant::now();
    for r in 0..rounds {
        filter(
            path,
            &list,
            &probes[r as usize % probes.len()],
            &segs,
            &mut out,
        );
        kept += out.len();
    }
    let s = t.elapsed().as_secs_f64();
    std::hint::black_box(kept);
    (rounds * list.len() as u64) as f64 / s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_engine_matches_brute_force_on_a_small_plan() {
        let rows = run_plan(Plan {
            rays: 1 << 12,
            points: 2_000,
            brute_points: 100,
        });
        assert_eq!(rows.len(), 8);
        for r in &rows {
            assert_eq!(r.mismatches, 0, "{r:?}");
            assert!(r.ray_disc_tests > 0 && r.wall_s > 0.0, "{r:?}");
        }
        let count = |e: &str, t: usize| {
            rows.iter()
                .find(|r| r.engine == e && r.threads == t)
                .map(|r| (r.ray_sphere_tests, r.ray_disc_tests))
                .unwrap()
        };
        for e in ["sphere-cache", "disc-index-grid", "disc-index-octree"] {
            assert_eq!(count(e, 1), count(e, 2), "{e}: counters across threads");
        }
    }

    /// `cargo test --release --lib bench::detp::tests::print_quick -- --ignored --nocapture`
    #[test]
    #[ignore = "prints the quick bench and the filter speed per path (a few seconds)"]
    fn print_quick() {
        for path in FilterPath::all_available() {
            let r = filter_speed(path, 2_000_000_000);
            println!(
                "filter {}: {:.0} M tests/s per thread",
                path.name(),
                r / 1e6
            );
        }
        for r in run(true) {
            println!("{r:?}");
        }
        let plan = Plan {
            rays: 1 << 16,
            points: 10_000,
            brute_points: 1,
        };
        let (store, discs) = scene(plan);
        let perm = permutation(&discs.centers, Order::Hilbert, 10);
        let root = (DVec3::ZERO, 1.0 + discs.radius * (1.0 + 1e-9));
        for mode in [
            sphere_cache::ListMode::Exact,
            sphere_cache::ListMode::Inherited,
        ] {
            let params = SphereCacheParams {
                list_mode: mode,
                ..Default::default()
            };
            let mut acc = vec![0; discs.len()];
            let s = sphere_cache::run(&store, &discs, &perm, root, &params, &mut acc);
            println!(
                "{mode:?}: sphere tests {} disc tests {}",
                s.ray_sphere_tests, s.ray_disc_tests
            );
            for (i, l) in s.levels.iter().enumerate() {
                let theory = f64::from(plan.rays) * l.radius * l.radius;
                println!(
                    "  level {i} r {:.4} builds {} misses {} mean rays {:.1} (n_R r² {theory:.1}) tests {}",
                    l.radius,
                    l.builds,
                    l.misses,
                    l.mean_rays().map_or(0.0, |m| m.0),
                    l.ray_sphere_tests
                );
            }
        }
    }
}
