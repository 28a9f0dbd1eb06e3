//! `raycost bench`: speed of every engine on identical scenes, side by side in one run.
//!
//! Scene: n centres uniform in a cube at ρ = 1 (side n^⅓), r = 0.1; rays from the cube's centre in
//! uniform directions, first hit only (PERFORMANCE.md's setting). The finite grid runs with the cell
//! width the cost model picks from T_I and T_S measured on this machine, on one thread and on all;
//! the lazily generated infinite scene and brute force (a subset of rays) run beside it. Every grid
//! answer is checked against brute force on the rays brute force traces (`mismatches` must be 0).

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use glam::DVec3;
use rayon::prelude::*;

use crate::experiment::grid::BATCH;
use crate::experiment::machine;
use crate::experiment::Row;
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::fast::{FastGrid, FastTrace};
use crate::grid::{brute_force, build::frame_around, mailbox::Mailbox, trace, GridFrame};
use crate::output::sink::{Sink, SinkOptions};
use crate::sample::{directions::uniform_direction, rng::stream};
use crate::scene::finite::{FiniteScene, FiniteSize};
use crate::scene::lazy::LazyScene;
use crate::scene::{RadiusClass, RadiusDist, RadiusDraw};
use crate::theory::grid::{self as th, Eye, GridTheoryInput, QueryCost};

const RHO: f64 = 1.0;
const R: f64 = 0.1;

/// Peak resident memory of this process so far (VmHWM), bytes; 0 where /proc is unavailable.
pub fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

fn pool(threads: usize) -> anyhow::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("could not start a thread pool")
}

/// Traces `rays` through the query-optimised grid on the current pool; returns results and seconds.
pub fn trace_finite(grid: &FastGrid, rays: &[Ray]) -> (Vec<FastTrace>, f64) {
    let start = Instant::now();
    let counts: Vec<FastTrace> = rays
        .par_chunks(1024)
        .flat_map_iter(|chunk| chunk.iter().map(|r| grid.trace(r)))
        .collect();
    (counts, start.elapsed().as_secs_f64())
}

/// Runs the benchmark and writes `OUT/bench/bench.csv`.
pub fn run(quick: bool, out: &Path, force: bool) -> anyhow::Result<()> {
    let sizes: &[u64] = if quick {
        &[10_000, 100_000]
    } else {
        &[10_000, 100_000, 1_000_000, 10_000_000]
    };
    let n_rays: usize = if quick { 200_000 } else { 2_000_000 };
    let bf_rays: usize = if quick { 2_000 } else { 500 };
    let all = rayon::current_num_threads();
    let dir = out.join("bench");
    let mut sink = Sink::open(
        &dir,
        "bench",
        "bench",
        SinkOptions {
            force,
            resume: false,
        },
    )?
    .expect("a sink opened without --resume always exists");

    let classes = [RadiusClass {
        fraction: 1.0,
        radius: RadiusDist::Constant(R),
    }];
    let probe = GridTheoryInput {
        intensity: RHO,
        classes: &classes,
        draw: RadiusDraw::PerSphere,
        cell_width: 1.0,
    };
    let costs = calibrate(&classes, if quick { 100_000 } else { 1_000_000 })?;
    // The query grid tests every listing (no mailbox), so the model's N_I is the plain one.
    let a = th::best_cell_width(
        &probe,
        &QueryCost {
            t_i: costs.t_i,
            t_s: costs.t_s,
            eye: Eye::Uniform,
            mailbox: false,
        },
        0.1,
        5.0,
    );
    println!(
        "cost model of the query grid, fitted on this machine: T_I = {:.2} ns, T_S = {:.2} ns → cell width a = {a:.3}",
        costs.t_i * 1e9,
        costs.t_s * 1e9
    );
    println!(
        "{:<14} {:>9} {:>7} {:>12} {:>9} {:>12} {:>9} {:>8} {:>8} {:>8}",
        "engine",
        "n",
        "threads",
        "rays/s",
        "build s",
        "peak MB",
        "mismatch",
        "f32 ties",
        "N_I",
        "N_S"
    );
    let mut speeds: Vec<(String, u64, u64, f64)> = Vec::new();
    let mut emit = |sink: &mut Sink, mut row: Row| -> anyhow::Result<()> {
        // Columns only Embree fills (f32 near-ties and t differences), kept in every row.
        if row.get("f32_ties").is_none() {
            row.u("f32_ties", 0).f("t_rel_diff_max", f64::NAN);
        }
        let g = |c: &str| row.get(c).and_then(|v| v.as_f64()).unwrap_or(f64::NAN);
        println!(
            "{:<14} {:>9} {:>7} {:>12.4e} {:>9.3} {:>12.1} {:>9} {:>8} {:>8.2} {:>8.2}",
            row.get("engine").map_or(String::new(), |v| v.render()),
            g("n"),
            g("threads"),
            g("rays_per_s"),
            g("build_s"),
            g("peak_mem_bytes") / 1e6,
            g("mismatches"),
            g("f32_ties"),
            g("n_i_mean"),
            g("n_s_mean")
        );
        speeds.push((
            row.get("engine").map_or(String::new(), |v| v.render()),
            g("n") as u64,
            g("threads") as u64,
            g("rays_per_s"),
        ));
        sink.append(&row, &[])
            .context("could not append to the bench table")?;
        Ok(())
    };

    let mut rng = stream(&[0x6265_6e63, 0]);
    let dirs: Vec<DVec3> = (0..n_rays).map(|_| uniform_direction(&mut rng)).collect();
    for &n in sizes {
        let (spheres, bounds) = bench_scene(&classes, n, 0x6265_6e63);
        let start = Instant::now();
        let grid = FastGrid::build(frame_around(bounds, a, DVec3::ZERO), &spheres);
        let build_s = start.elapsed().as_secs_f64();
        let peak = peak_rss_bytes();
        let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(DVec3::ZERO, d)).collect();

        // Brute force on a subset: the oracle for mismatches, and its own speed.
        let bf_n = bf_rays.min(rays.len());
        let bf_start = Instant::now();
        let oracle: Vec<Option<u64>> = pool(all)?.install(|| {
            rays[..bf_n]
                .par_iter()
                .map(|r| brute_force(&spheres, r).map(|h| h.id))
                .collect()
        });
        let bf_s = bf_start.elapsed().as_secs_f64();

        // Untimed warm-up: fault in the freshly built arrays so the first timed run (1 thread) does
        // not pay for it and inflate the 1 → 2 thread speed-up.
        let _ = trace_finite(&grid, &rays[..rays.len().min(200_000)]);
        let mut grid_hits: Vec<Option<crate::grid::Hit>> = Vec::new();
        for threads in [1, all] {
            let (counts, secs) = pool(threads)?.install(|| trace_finite(&grid, &rays));
            let mismatches = counts[..bf_n]
                .iter()
                .zip(&oracle)
                .filter(|(c, o)| c.hit.map(|h| h.id) != **o)
                .count();
            let mut row = Row::default();
            row.s("engine", "grid")
                .u("n", n)
                .u("threads", threads as u64)
                .f("cell_width", a)
                .u("rays", rays.len() as u64);
            row.f("rays_per_s", rays.len() as f64 / secs)
                .f("build_s", build_s)
                .u("peak_mem_bytes", peak)
                .u("grid_bytes", grid.bytes());
            row.u("checked", bf_n as u64)
                .u("mismatches", mismatches as u64);
            row.f("n_i_mean", mean(counts.iter().map(|c| f64::from(c.n_i))))
                .f("n_s_mean", mean(counts.iter().map(|c| f64::from(c.n_s))));
            emit(&mut sink, row)?;
            grid_hits = counts.iter().map(|c| c.hit).collect();
        }
        let mut row = Row::default();
        row.s("engine", "brute-force")
            .u("n", n)
            .u("threads", all as u64)
            .f("cell_width", f64::NAN)
            .u("rays", bf_n as u64);
        row.f("rays_per_s", bf_n as f64 / bf_s)
            .f("build_s", 0.0)
            .u("peak_mem_bytes", peak)
            .u("grid_bytes", 0);
        row.u("checked", bf_n as u64)
            .u("mismatches", 0)
            .f("n_i_mean", n as f64)
            .f("n_s_mean", 0.0);
        emit(&mut sink, row)?;
        drop(grid);
        // Embree on the same spheres and rays; checked against the grid on every ray (Embree works
        // in f32, so only sphere ids are compared).
        #[cfg(feature = "embree")]
        {
            let start = Instant::now();
            let scene = crate::embree::EmbreeScene::build(&spheres)?;
            let e_build = start.elapsed().as_secs_f64();
            let e_peak = peak_rss_bytes();
            let mut warm = vec![None; rays.len().min(200_000)];
            scene.first_hits(&rays[..warm.len()], &mut warm);
            for threads in [1, all] {
                let mut hits = vec![None; rays.len()];
                let start = Instant::now();
                pool(threads)?.install(|| {
                    hits.par_chunks_mut(4096)
                        .zip(rays.par_chunks(4096))
                        .for_each(|(h, r)| scene.first_hits(r, h))
                });
                let secs = start.elapsed().as_secs_f64();
                // Embree intersects in f32: classify each disagreement by the exact f64 geometry.
                let (mut mismatches, mut ties, mut t_rel_max) = (0u64, 0u64, 0.0f64);
                for (k, (e, g)) in hits.iter().zip(&grid_hits).enumerate() {
                    let ray = &rays[k];
                    match (e, g) {
                        (Some((ei, te)), Some(gh)) if spheres[*ei].id == gh.id => {
                            t_rel_max = t_rel_max.max((te - gh.t).abs() / gh.t)
                        }
                        (None, None) => {}
                        (e, g) => {
                            let near_tie = |s: &Sphere, t_ref: f64| {
                                s.intersect(ray)
                                    .is_some_and(|t| (t - t_ref).abs() <= 1e-5 * t_ref)
                            };
                            // A graze f32 cannot resolve: Embree's quadratic forms |f|² − b² in f32, so
                            // its discriminant carries an absolute error of a few ε₃₂·|f|².
                            let grazed = |s: &Sphere| {
                                let f = s.c - ray.o;
                                let v = f - f.dot(ray.d) * ray.d;
                                (v.length_squared() - s.r * s.r).abs()
                                    <= 8.0 * f64::from(f32::EPSILON) * f.length_squared()
                            };
                            let explained = match (e, g) {
                                (Some((ei, _)), Some(gh)) => {
                                    near_tie(&spheres[*ei], gh.t)
                                        || grazed(&spheres[*ei])
                                        || grazed(&spheres[gh.id as usize])
                                }
                                (Some((ei, _)), None) => grazed(&spheres[*ei]),
                                (None, Some(gh)) => grazed(&spheres[gh.id as usize]),
                                (None, None) => true,
                            };
                            if explained {
                                ties += 1;
                            } else {
                                mismatches += 1;
                                let t64 = |i: usize| spheres[i].intersect(ray);
                                eprintln!(
                                    "embree mismatch: n = {n}, ray {k} o = {:?} d = {:?}: embree {:?} (f64 t {:?}), grid {:?}",
                                    ray.o,
                                    ray.d,
                                    e,
                                    e.and_then(|(i, _)| t64(i)),
                                    g
                                );
                            }
                        }
                    }
                }
                let mut row = Row::default();
                row.s("engine", "embree")
                    .u("n", n)
                    .u("threads", threads as u64)
                    .f("cell_width", f64::NAN)
                    .u("rays", rays.len() as u64);
                row.f("rays_per_s", rays.len() as f64 / secs)
                    .f("build_s", e_build)
                    .u("peak_mem_bytes", e_peak)
                    .u("grid_bytes", 0);
                row.u("checked", rays.len() as u64)
                    .u("mismatches", mismatches)
                    .f("n_i_mean", f64::NAN)
                    .f("n_s_mean", f64::NAN);
                row.u("f32_ties", ties).f("t_rel_diff_max", t_rel_max);
                emit(&mut sink, row)?;
            }
        }
        #[cfg(not(feature = "embree"))]
        let _ = &grid_hits;
    }

    // The lazily generated infinite scene (no n: it has no boundary), same a, same directions.
    for threads in [1, all] {
        let start = Instant::now();
        let (n_i, n_s) = pool(threads)?.install(|| {
            let parts: Vec<(f64, f64)> = dirs
                .par_chunks(BATCH as usize)
                .enumerate()
                .map_init(
                    crate::scene::lazy::LazyCache::default,
                    |cache, (b, chunk)| {
                        let scene = LazyScene::new(
                            RHO,
                            &classes,
                            RadiusDraw::PerSphere,
                            a,
                            &[0x6265_6e63, 1, b as u64],
                        );
                        let mut lists = scene.cells(
                            GridFrame {
                                origin: DVec3::ZERO,
                                width: a,
                                dims: None,
                            },
                            2.0 * a,
                            cache,
                        );
                        let mut mb = Mailbox::default();
                        let eye = DVec3::splat(0.5 * a);
                        chunk.iter().fold((0.0, 0.0), |acc, &d| {
                            let c = trace(&mut lists, &Ray::new(eye, d), &mut mb, true, 10_000_000);
                            (acc.0 + f64::from(c.n_i), acc.1 + f64::from(c.n_s))
                        })
                    },
                )
                .collect();
            parts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1))
        });
        let secs = start.elapsed().as_secs_f64();
        let mut row = Row::default();
        row.s("engine", "grid-infinite")
            .u("n", 0)
            .u("threads", threads as u64)
            .f("cell_width", a)
            .u("rays", dirs.len() as u64);
        row.f("rays_per_s", dirs.len() as f64 / secs)
            .f("build_s", 0.0)
            .u("peak_mem_bytes", peak_rss_bytes())
            .u("grid_bytes", 0);
        row.u("checked", 0)
            .u("mismatches", 0)
            .f("n_i_mean", n_i / dirs.len() as f64)
            .f("n_s_mean", n_s / dirs.len() as f64);
        emit(&mut sink, row)?;
    }
    // Ratios measured in this run, side by side.
    for &n in sizes {
        for threads in [1, all as u64] {
            let rate = |e: &str| {
                speeds
                    .iter()
                    .find(|s| s.0 == e && s.1 == n && s.2 == threads)
                    .map(|s| s.3)
            };
            if let (Some(g), Some(e)) = (rate("grid"), rate("embree")) {
                println!(
                    "ratio grid/embree at n = {n:.0e}, {threads} thread(s): {:.2}",
                    g / e
                );
            }
        }
    }
    let rate = |e: &str, n: u64| {
        speeds
            .iter()
            .find(|s| s.0 == e && s.1 == n && s.2 == all as u64)
            .map(|s| s.3)
    };
    if let (Some(g), Some(i)) = (
        rate("grid", *sizes.last().expect("sizes")),
        rate("grid-infinite", 0),
    ) {
        println!(
            "ratio grid (n = {:.0e}) / grid-infinite, {all} threads: {:.2}",
            *sizes.last().expect("sizes") as f64,
            g / i
        );
    }
    let meta = format!(
        "[bench]\nquick = {quick}\nthreads = {all}\nhost = \"{}\"\nt_i_s = {:e}\nt_s_s = {:e}\ncell_width = {a}\nfinished = \"{}\"\n",
        crate::output::meta::host_name(),
        costs.t_i,
        costs.t_s,
        crate::output::time::now_rfc3339()
    );
    for p in sink.finish(&meta)? {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// T_I and T_S of the query grid on this machine: the grid is timed (one thread) at three cell
/// widths on a calibration scene of `n` spheres, and t = N_I·T_I + N_S·T_S is fitted to the three
/// (N_I, N_S, time per ray) triples by least squares. Unlike the microbenchmarks of
/// `experiment::machine`, this includes the memory traffic of the real lists.
fn calibrate(classes: &[RadiusClass], n: u64) -> anyhow::Result<machine::MachineCosts> {
    let (spheres, bounds) = bench_scene(classes, n, 0x6361_6c69);
    let mut rng = stream(&[0x6361_6c69, 1]);
    let rays: Vec<Ray> = (0..100_000)
        .map(|_| Ray::new(DVec3::ZERO, uniform_direction(&mut rng)))
        .collect();
    let (mut sii, mut sis, mut sss, mut sit, mut sst) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for a in [0.6, 1.2, 2.4] {
        let grid = FastGrid::build(frame_around(bounds, a, DVec3::ZERO), &spheres);
        let (counts, secs) = pool(1)?.install(|| trace_finite(&grid, &rays));
        let t = secs / rays.len() as f64;
        let ni = mean(counts.iter().map(|c| f64::from(c.n_i)));
        let ns = mean(counts.iter().map(|c| f64::from(c.n_s)));
        (sii, sis, sss, sit, sst) = (
            sii + ni * ni,
            sis + ni * ns,
            sss + ns * ns,
            sit + ni * t,
            sst + ns * t,
        );
    }
    // Normal equations of the two-parameter fit without intercept.
    let det = sii * sss - sis * sis;
    let t_i = ((sit * sss - sst * sis) / det).max(1e-12);
    let t_s = ((sst * sii - sit * sis) / det).max(1e-12);
    Ok(machine::MachineCosts { t_i, t_s })
}

/// The bench scene: `n` centres uniform in a cube at ρ = 1 around the origin, and the box a grid
/// over them must cover.
fn bench_scene(classes: &[RadiusClass], n: u64, key: u64) -> (Vec<Sphere>, Aabb) {
    let scene = FiniteScene {
        intensity: RHO,
        classes: classes.to_vec(),
        draw: RadiusDraw::PerSphere,
        size: FiniteSize::Count(n),
        center: DVec3::ZERO,
    };
    let b = scene.centre_box();
    (
        scene.generate(&[key, n]),
        Aabb::new(b.lo - DVec3::splat(R), b.hi + DVec3::splat(R)),
    )
}

fn mean(it: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = it.fold((0.0, 0u64), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}
