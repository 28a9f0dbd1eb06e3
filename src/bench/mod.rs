//! `raycost bench`: the speed of every engine on identical scenes, side by side in one run.
//!
//! Scene: n centres uniform in a cube at ρ = 1 (side n^⅓), r = 0.1; rays from the cube's centre in
//! uniform directions, first hit only (docs/bench.md's reference setting). Engines:
//! - `grid`: the query-optimised grid ([`FastGrid`]), cell width chosen by the cost model with T_I
//!   and T_S fitted on this machine ([`calibrate`]);
//! - `embree` (feature `embree`): Intel Embree 3's BVH over the same spheres;
//! - `brute-force`: every sphere, on a subset of the rays (the oracle);
//! - `grid-infinite`: the lazily generated infinite scene (no n), the study's counting tracer, at
//!   several cell widths, timed beside the finite grid in its own rounds ([`infinite`]).
//!
//! The grid and Embree are timed in alternating rounds on 1 thread and on all threads
//! ([`rounds`]): each round traces a fresh slice of the rays with every engine, so the per-round
//! ratio compares engines under the same machine conditions. Every ray's answer is checked: the
//! grid against brute force (exactly, on a subset), against itself across thread counts, and
//! Embree against the grid (by sphere, [`agreement`]).
//!
//! Output: `OUT/bench/bench.csv` (one row per engine, n and thread count, and cell width for
//! `grid-infinite`; `rays_per_s` is the median over rounds), `bench.rounds.csv` (every round's
//! seconds, from which the paired ratios are computed), `bench.infinite-rounds.csv` (the same for
//! the infinite scene and its finite reference) and `bench.meta.toml` (machine, calibration).

mod agreement;
mod calibrate;
pub mod columns;
pub mod detp;
mod infinite;
pub mod lt;
pub mod memory;
pub mod quasi_static;
mod rounds;
mod table;

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use glam::DVec3;
use rayon::prelude::*;

use self::agreement::Agreement;
use self::columns as bc;
use self::rounds::{alternate, median, paired_ratios, RoundTimes};
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::fast::{FastGrid, FastTrace};
use crate::grid::{build::frame_around, Hit};
use crate::output::meta::Meta;
use crate::output::row::Row;
use crate::output::sink::{Sink, SinkOptions};
use crate::sample::{directions::uniform_direction, rng::stream};
use crate::scene::finite::{FiniteScene, FiniteSize};
use crate::scene::{RadiusClass, RadiusDist, RadiusDraw};

const RHO: f64 = 1.0;
const R: f64 = 0.1;
/// Stream key of the bench's scenes and rays.
const KEY: u64 = 0x6265_6e63;

/// How much the bench measures.
struct Plan {
    sizes: &'static [u64],
    rounds: usize,
    rays_per_round: usize,
    /// Rays checked against brute force per n.
    brute_force_rays: usize,
    /// Spheres and rays of the calibration scene, and its rounds.
    calibration: (u64, usize, usize),
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                sizes: &[10_000, 100_000],
                rounds: 3,
                rays_per_round: 50_000,
                brute_force_rays: 2_000,
                calibration: (100_000, 20_000, 3),
            }
        } else {
            Self {
                sizes: &[10_000, 100_000, 1_000_000, 10_000_000],
                rounds: 7,
                rays_per_round: 300_000,
                brute_force_rays: 500,
                calibration: (1_000_000, 100_000, 5),
            }
        }
    }
}

/// One engine at one n and thread count: everything its row reports.
#[derive(Clone)]
struct Measured {
    engine: &'static str,
    n: u64,
    threads: usize,
    cell_width: f64,
    /// Seconds of each round, `rays_per_round` rays each.
    secs: Vec<f64>,
    rays_per_round: usize,
    build_s: f64,
    peak_mem_bytes: u64,
    structure_bytes: u64,
    agreement: Agreement,
    /// Mean N_I, N_S and cells visited (N_S + 1) per ray; NaN where the engine does not count.
    n_i: f64,
    n_s: f64,
}

impl Measured {
    fn rays_per_s(&self) -> f64 {
        self.rays_per_round as f64 / median(&self.secs)
    }

    /// Seconds per cell visited (median round), the grid's cost per unit of work.
    fn cell_s(&self) -> f64 {
        median(&self.secs) / (self.rays_per_round as f64 * (self.n_s + 1.0))
    }

    fn row(&self) -> Row {
        let mut row = Row::default();
        row.put(&bc::ENGINE, self.engine)
            .put(&bc::N, self.n)
            .put(&bc::THREADS, self.threads as u64)
            .put(&bc::CELL_WIDTH, self.cell_width)
            .put(&bc::RAYS, (self.rays_per_round * self.secs.len()) as u64)
            .put(&bc::ROUNDS, self.secs.len() as u64);
        row.put(&bc::RAYS_PER_S, self.rays_per_s())
            .put(
                &bc::ROUND_MIN_S,
                self.secs.iter().copied().fold(f64::INFINITY, f64::min),
            )
            .put(&bc::ROUND_MEDIAN_S, median(&self.secs))
            .put(
                &bc::ROUND_MAX_S,
                self.secs.iter().copied().fold(0.0, f64::max),
            )
            .put(&bc::CELL_S, self.cell_s())
            .put(&bc::BUILD_S, self.build_s)
            .put(&bc::PEAK_MEM_BYTES, self.peak_mem_bytes)
            .put(&bc::STRUCTURE_BYTES, self.structure_bytes);
        row.put(&bc::CHECKED, self.agreement.checked)
            .put(&bc::MISMATCHES, self.agreement.mismatches)
            .put(&bc::F32_TIES, self.agreement.f32_ties)
            .put(&bc::T_REL_DIFF_MAX, self.agreement.t_rel_diff_max)
            .put(&bc::N_I_MEAN, self.n_i)
            .put(&bc::N_S_MEAN, self.n_s);
        row
    }

    fn round_rows(&self) -> Vec<Row> {
        self.secs
            .iter()
            .enumerate()
            .map(|(r, &s)| {
                let mut row = Row::default();
                row.put(&bc::ENGINE, self.engine)
                    .put(&bc::N, self.n)
                    .put(&bc::THREADS, self.threads as u64)
                    .put(&bc::ROUND, r as u64)
                    .put(&bc::RAYS, self.rays_per_round as u64)
                    .put(&bc::ROUND_S, s);
                row
            })
            .collect()
    }
}

fn pool(threads: usize) -> anyhow::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("could not start a thread pool")
}

/// Traces `rays` through the query grid into `out` on the current pool.
fn trace_into(grid: &FastGrid, rays: &[Ray], out: &mut [FastTrace]) {
    out.par_chunks_mut(1024)
        .zip(rays.par_chunks(1024))
        .for_each(|(o, r)| o.iter_mut().zip(r).for_each(|(o, r)| *o = grid.trace(r)));
}

/// Runs the benchmark and writes `OUT/bench/bench.csv`, `bench.rounds.csv`, `bench.meta.toml`.
pub fn run(quick: bool, out: &Path, force: bool) -> anyhow::Result<()> {
    let plan = Plan::new(quick);
    let all = rayon::current_num_threads();
    // Open (and so refuse to overwrite) the results before spending minutes measuring.
    let mut meta = Meta::begin("bench", crate::experiment::runner::simd_paths());
    let t0 = std::time::Instant::now();
    let mut sink = Sink::open(
        &out.join("bench"),
        "bench",
        &meta,
        SinkOptions {
            force,
            resume: false,
            tables: &["rounds", infinite::ROUNDS_TABLE],
        },
    )?
    .expect("a sink opened without --resume always exists");
    let classes = [RadiusClass {
        fraction: 1.0,
        radius: RadiusDist::Constant(R),
    }];
    println!(
        "CPU: {}; ISA: {}; query-grid walk: {:?}; {all} thread(s)",
        meta.machine.cpu,
        meta.machine.isa.join(" "),
        crate::grid::fast::Walk::detect()
    );

    let cal = calibrate_here(&plan, &classes)?;
    let a = cal.cell_width;

    let total = plan.rounds * plan.rays_per_round;
    let rays: Vec<Ray> = directions(total, KEY)
        .into_iter()
        .map(|d| Ray::new(DVec3::ZERO, d))
        .collect();
    let mut measured: Vec<Measured> = Vec::new();
    for &n in plan.sizes {
        measured.extend(bench_size(n, a, &plan, &classes, &rays, all)?);
    }
    let inf = infinite::run(quick, a, &classes, all)?;

    print_summary(&measured, plan.sizes, all);
    inf.print();
    println!("\nDETP engines (uniform lines through the unit sphere, points in the ball):");
    let detp_rows = detp::run(quick);
    print_detp(&detp_rows);
    println!("\nQuasi-static DETP (one frame, incremental vs full):");
    let qs_rows = quasi_static::run(quick)?;
    println!("\nLight transport (one thread; rays cast by the exact core and by Embree):");
    let (lt_rows, lt_warnings) = lt::run(quick)?;
    meta.warnings.extend(lt_warnings);
    print_lt(&lt_rows);
    if quasi_static::find_kitchen().is_none() {
        meta.warnings.push(format!(
            "the BART kitchen ({}) was not found: the kitchen-* rows are missing",
            quasi_static::KITCHEN
        ));
    }
    let rows: Vec<Row> = measured
        .iter()
        .map(Measured::row)
        .chain(inf.rows.iter().map(infinite::InfiniteRow::row))
        .chain(detp_rows.iter().map(table::detp_row))
        .chain(qs_rows.iter().map(quasi_static::QsRow::row))
        .chain(lt_rows.iter().map(lt::LtRow::row))
        .collect();
    let sides = measured
        .iter()
        .map(|m| vec![("rounds", m.round_rows())])
        .chain(
            inf.round_rows()
                .into_iter()
                .map(|r| vec![(infinite::ROUNDS_TABLE, r)]),
        )
        .chain(detp_rows.iter().map(|_| Vec::new()))
        .chain(qs_rows.iter().map(|_| Vec::new()))
        .chain(lt_rows.iter().map(|_| Vec::new()));
    for (row, side) in table::union_columns(&rows).iter().zip(sides) {
        // Every table the bench writes is declared in its metadata, side tables included, so a
        // reader can check a header against what was written (the first row of each has every
        // column: all rows of a side table carry the same ones).
        for (name, side_rows) in &side {
            if let Some(first) = side_rows.first() {
                meta.columns
                    .entry((*name).to_string())
                    .or_insert_with(|| first.columns());
            }
        }
        sink.append(row, &side, &meta)
            .context("could not append to the bench table")?;
    }
    let bench = bench_meta(quick, &plan, &cal);
    meta.extra.insert("bench".into(), bench.into());
    if let Some(r) = table::union_columns(&rows).first() {
        meta.columns.insert("main".into(), r.columns());
    }
    meta.end(t0.elapsed().as_secs_f64());
    if meta.busy() {
        if let Some(w) = meta.warnings.last() {
            eprintln!("warning: {w}");
        }
    }
    for p in sink.finish(&meta)? {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// The query grid's cost model fitted on this machine, printed; its cell width is the bench's.
fn calibrate_here(plan: &Plan, classes: &[RadiusClass]) -> anyhow::Result<calibrate::Calibration> {
    let (cal_n, cal_rays, cal_rounds) = plan.calibration;
    let (cal_spheres, cal_bounds) = bench_scene(classes, cal_n, KEY ^ 1);
    let cal = calibrate::calibrate(
        &cal_spheres,
        cal_bounds,
        &directions(cal_rays, KEY ^ 2)
            .into_iter()
            .map(|d| Ray::new(DVec3::ZERO, d))
            .collect::<Vec<_>>(),
        cal_rounds,
        RHO,
        classes,
    )?;
    drop(cal_spheres);
    let a = cal.cell_width;
    println!(
        "cost model of the query grid, fitted on this machine (n = {cal_n}): T_I = {:.2} ns, T_S = {:.2} ns → cell width a = {a:.3}",
        cal.costs.t_i * 1e9,
        cal.costs.t_s * 1e9
    );
    for &(w, ni, ns, t) in &cal.points {
        println!(
            "  a = {w:.2}: N_I {ni:6.1}, N_S {ns:5.1}, measured {:6.0} ns/ray, model {:6.0} ns/ray",
            t * 1e9,
            (ni * cal.costs.t_i + ns * cal.costs.t_s) * 1e9
        );
    }

    Ok(cal)
}

/// The bench's own metadata: its plan and the calibration (`[cell width, N_I, N_S, median
/// seconds per ray]` per width timed).
fn bench_meta(quick: bool, plan: &Plan, cal: &calibrate::Calibration) -> toml::Table {
    let mut bench = toml::Table::new();
    bench.insert("quick".into(), quick.into());
    bench.insert("rounds".into(), (plan.rounds as i64).into());
    bench.insert("rays_per_round".into(), (plan.rays_per_round as i64).into());
    let mut calibration = toml::Table::new();
    calibration.insert("spheres".into(), (plan.calibration.0 as i64).into());
    calibration.insert("t_i_s".into(), cal.costs.t_i.into());
    calibration.insert("t_s_s".into(), cal.costs.t_s.into());
    calibration.insert("cell_width".into(), cal.cell_width.into());
    calibration.insert(
        "points".into(),
        toml::Value::Array(
            cal.points
                .iter()
                .map(|&(w, ni, ns, t)| {
                    toml::Value::Array(vec![w.into(), ni.into(), ns.into(), t.into()])
                })
                .collect(),
        ),
    );
    bench.insert("calibration".into(), calibration.into());
    bench
}

/// The grid, Embree and brute force on the n-sphere scene.
fn bench_size(
    n: u64,
    a: f64,
    plan: &Plan,
    classes: &[RadiusClass],
    rays: &[Ray],
    all: usize,
) -> anyhow::Result<Vec<Measured>> {
    let rss_before_scene = memory::rss_bytes();
    let (spheres, bounds) = bench_scene(classes, n, KEY ^ n);
    // What a process holding just the scene uses; each engine's peak adds its own increment.
    let scene_bytes = memory::rss_bytes().saturating_sub(rss_before_scene);
    let ((grid, grid_build), grid_peak) = memory::peak_increment(|| {
        timed(|| FastGrid::build(frame_around(bounds, a, DVec3::ZERO), &spheres))
    });
    #[cfg(feature = "embree")]
    let ((embree, embree_build), embree_peak) =
        memory::peak_increment(|| timed(|| crate::embree::EmbreeScene::build(&spheres)));
    #[cfg(feature = "embree")]
    let embree = embree?;
    let engines = Engines {
        grid: &grid,
        #[cfg(feature = "embree")]
        embree: &embree,
    };
    let race = race(&engines, rays, plan, all)?;
    let grid_row = Measured {
        engine: "grid",
        n,
        threads: 1,
        cell_width: a,
        secs: Vec::new(),
        rays_per_round: plan.rays_per_round,
        build_s: grid_build,
        peak_mem_bytes: scene_bytes + grid_peak,
        structure_bytes: grid.bytes(),
        agreement: Agreement::default(),
        n_i: f64::NAN,
        n_s: f64::NAN,
    };
    drop(grid);
    #[allow(unused_mut)]
    let mut out = grid_measured(&spheres, rays, &race, plan, all, grid_row, scene_bytes)?;
    #[cfg(feature = "embree")]
    {
        // Embree against the grid on every ray, on both thread counts.
        let hits: Vec<Option<Hit>> = race.grid.all.iter().map(|q| q.hit).collect();
        let mut check = agreement::embree_vs_grid(&spheres, rays, &race.embree.all, &hits);
        check.mismatches += differing(&race.embree, |h| h.map(|h| h.0));
        for (threads, secs) in [1, all].into_iter().zip(&race.embree_secs) {
            out.push(Measured {
                engine: "embree",
                n,
                threads,
                cell_width: f64::NAN,
                secs: secs.clone(),
                rays_per_round: plan.rays_per_round,
                build_s: embree_build,
                peak_mem_bytes: scene_bytes + embree_peak,
                structure_bytes: 0,
                agreement: check,
                n_i: f64::NAN,
                n_s: f64::NAN,
            });
        }
    }
    Ok(out)
}

/// `f()` and its seconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let value = f();
    (value, start.elapsed().as_secs_f64())
}

/// The structures racing at one size.
struct Engines<'a> {
    grid: &'a FastGrid,
    #[cfg(feature = "embree")]
    embree: &'a crate::embree::EmbreeScene,
}

/// What one engine answered on every ray, on one thread and on all.
struct Answers<T> {
    one: Vec<T>,
    all: Vec<T>,
}

impl<T: Clone> Answers<T> {
    fn new(len: usize, empty: T) -> Self {
        Answers {
            one: vec![empty.clone(); len],
            all: vec![empty; len],
        }
    }

    fn on(&mut self, all_threads: bool) -> &mut [T] {
        if all_threads {
            &mut self.all
        } else {
            &mut self.one
        }
    }
}

/// How many rays got a different answer (`key`) on one thread than on all.
fn differing<T, K: PartialEq>(a: &Answers<T>, key: impl Fn(&T) -> K) -> u64 {
    a.one
        .iter()
        .zip(&a.all)
        .filter(|(x, y)| key(x) != key(y))
        .count() as u64
}

/// Embree's first hit per ray: (sphere, t).
#[cfg(feature = "embree")]
type EmbreeHit = Option<(usize, f64)>;

/// Casts `rays` with Embree into `out` on the current pool.
#[cfg(feature = "embree")]
fn embree_into(e: &crate::embree::EmbreeScene, rays: &[Ray], out: &mut [EmbreeHit]) {
    out.par_chunks_mut(1024)
        .zip(rays.par_chunks(1024))
        .for_each(|(h, r)| e.first_hits(r, h));
}

/// The answers and the seconds of every round: `*_secs[0]` on one thread, `[1]` on all.
struct Race {
    grid: Answers<FastTrace>,
    grid_secs: [Vec<f64>; 2],
    #[cfg(feature = "embree")]
    embree: Answers<EmbreeHit>,
    #[cfg(feature = "embree")]
    embree_secs: [Vec<f64>; 2],
}

/// Every contestant in alternating rounds — grid on 1 thread, Embree on 1, grid on all, Embree on
/// all — after an untimed warm-up, so that the first timed contestant does not pay for faulting
/// in the freshly built structures.
fn race(engines: &Engines, rays: &[Ray], plan: &Plan, all: usize) -> anyhow::Result<Race> {
    let per = plan.rays_per_round;
    let mut grid = Answers::new(rays.len(), FastTrace::default());
    #[cfg(feature = "embree")]
    let mut embree: Answers<EmbreeHit> = Answers::new(rays.len(), None);
    let (one, many) = (pool(1)?, pool(all)?);
    let warm = &rays[..per.min(rays.len())];
    many.install(|| trace_into(engines.grid, warm, &mut grid.all[..warm.len()]));
    #[cfg(feature = "embree")]
    many.install(|| embree_into(engines.embree, warm, &mut embree.all[..warm.len()]));

    let embree_on = cfg!(feature = "embree");
    let contestants = if embree_on { 4 } else { 2 };
    // Contestant c: (is it the grid, does it use all threads)?
    let who = |c: usize| {
        if embree_on {
            (c.is_multiple_of(2), c >= 2)
        } else {
            (true, c == 1)
        }
    };
    let times = alternate(contestants, plan.rounds, |c, r| {
        let span = r * per..(r + 1) * per;
        let slice = &rays[span.clone()];
        let (is_grid, all_threads) = who(c);
        let p = if all_threads { &many } else { &one };
        if is_grid {
            let out = &mut grid.on(all_threads)[span];
            p.install(|| trace_into(engines.grid, slice, out));
        } else {
            #[cfg(feature = "embree")]
            {
                let out = &mut embree.on(all_threads)[span];
                p.install(|| embree_into(engines.embree, slice, out));
            }
        }
    });
    let secs = |is_grid: bool, all_threads: bool| -> Vec<f64> {
        let c = (0..contestants)
            .find(|&c| who(c) == (is_grid, all_threads))
            .expect("every engine and thread count is a contestant");
        times.secs[c].clone()
    };
    Ok(Race {
        grid_secs: [secs(true, false), secs(true, true)],
        grid,
        #[cfg(feature = "embree")]
        embree_secs: [secs(false, false), secs(false, true)],
        #[cfg(feature = "embree")]
        embree,
    })
}

/// The grid's rows (one thread, all threads) and brute force's: the grid's answers on every ray
/// checked against themselves across thread counts and against brute force on a subset.
fn grid_measured(
    spheres: &[Sphere],
    rays: &[Ray],
    race: &Race,
    plan: &Plan,
    all: usize,
    grid_row: Measured,
    scene_bytes: u64,
) -> anyhow::Result<Vec<Measured>> {
    let n = grid_row.n;
    let many = pool(all)?;
    let hits: Vec<Option<Hit>> = race.grid.all.iter().map(|q| q.hit).collect();
    let thread_diffs = differing(&race.grid, |q| *q);
    if thread_diffs > 0 {
        eprintln!("grid: {thread_diffs} rays answered differently on 1 and {all} threads");
    }
    let bf_n = plan.brute_force_rays.min(rays.len());
    let (mut grid_check, bf_s) = timed(|| {
        many.install(|| agreement::grid_vs_brute_force(spheres, &rays[..bf_n], &hits[..bf_n]))
    });
    grid_check.mismatches += thread_diffs;
    let mean = |f: fn(&FastTrace) -> u32| {
        let all = &race.grid.all;
        all.iter().map(|q| f64::from(f(q))).sum::<f64>() / all.len() as f64
    };
    let (n_i, n_s) = (mean(|q| q.n_i), mean(|q| q.n_s));
    let mut out: Vec<Measured> = [1, all]
        .into_iter()
        .zip(&race.grid_secs)
        .map(|(threads, secs)| Measured {
            threads,
            secs: secs.clone(),
            agreement: grid_check,
            n_i,
            n_s,
            ..grid_row.clone()
        })
        .collect();
    out.push(Measured {
        engine: "brute-force",
        n,
        threads: all,
        cell_width: f64::NAN,
        secs: vec![bf_s],
        rays_per_round: bf_n,
        build_s: 0.0,
        peak_mem_bytes: scene_bytes,
        structure_bytes: 0,
        agreement: Agreement {
            checked: bf_n as u64,
            ..Agreement::default()
        },
        n_i: n as f64,
        n_s: 0.0,
    });
    Ok(out)
}

/// The table, the ratios measured in this run, and the flatness and thread scaling of the grid.
/// The DETP rows, one line each.
fn print_detp(rows: &[detp::DetpBenchRow]) {
    println!(
        "{:<18} {:>7} {:>8} {:>4} {:>9} {:>8} {:>14} {:>14} {:>9} {:>5} {:>9}",
        "engine",
        "points",
        "rays",
        "thr",
        "wall s",
        "build s",
        "sphere tests/s",
        "disc tests/s",
        "peak MB",
        "mism",
        "filter"
    );
    for r in rows {
        println!(
            "{:<18} {:>7} {:>8} {:>4} {:>9.3} {:>8.3} {:>14.3e} {:>14.3e} {:>9.1} {:>5} {:>9}",
            r.engine,
            r.points,
            r.rays,
            r.threads,
            r.wall_s,
            r.build_s,
            r.ray_sphere_tests_per_s,
            r.ray_disc_tests_per_s,
            r.peak_mem_bytes as f64 / 1e6,
            r.mismatches,
            r.filter_path
        );
    }
}

/// The light-transport rows, one line each.
fn print_lt(rows: &[lt::LtRow]) {
    println!(
        "{:<8} {:<18} {:>7} {:>10} {:>11} {:>9} {:>8} {:>5} {:>9} {:>7}",
        "scene",
        "engine",
        "tris",
        "rays",
        "rays/s",
        "ns/ray",
        "/embree",
        "mism",
        "disagree",
        "path"
    );
    for r in rows {
        println!(
            "{:<8} {:<18} {:>7} {:>10} {:>11.4e} {:>9.1} {:>8.3} {:>5} {:>9} {:>7}",
            r.scene,
            r.engine,
            r.triangles,
            r.rays.iter().sum::<u64>(),
            r.rays_per_s(),
            1e9 / r.rays_per_s(),
            r.embree_ratio,
            r.mismatches,
            format!("{}/{}", r.embree_disagree, r.checked),
            r.bvh_path
        );
    }
}

fn print_summary(measured: &[Measured], sizes: &[u64], all: usize) {
    println!(
        "{:<14} {:>9} {:>4} {:>11} {:>19} {:>8} {:>8} {:>8} {:>6} {:>7} {:>7} {:>6}",
        "engine",
        "n",
        "thr",
        "rays/s",
        "round range",
        "build s",
        "peak MB",
        "mismatch",
        "ties",
        "N_I",
        "N_S",
        "ns/cell"
    );
    for m in measured {
        let (lo, hi) = rounds::rate_range(m.rays_per_round, &m.secs);
        println!(
            "{:<14} {:>9} {:>4} {:>11.4e} {:>9.3e}–{:<9.3e} {:>8.3} {:>8.0} {:>8} {:>6} {:>7.1} {:>7.1} {:>6.1}",
            m.engine,
            m.n,
            m.threads,
            m.rays_per_s(),
            lo,
            hi,
            m.build_s,
            m.peak_mem_bytes as f64 / 1e6,
            m.agreement.mismatches,
            m.agreement.f32_ties,
            m.n_i,
            m.n_s,
            m.cell_s() * 1e9
        );
    }
    let find = |engine: &str, n: u64, threads: usize| {
        measured
            .iter()
            .find(|m| m.engine == engine && m.n == n && m.threads == threads)
    };
    for &n in sizes {
        for threads in [1, all] {
            if let (Some(g), Some(e)) = (find("grid", n, threads), find("embree", n, threads)) {
                let (mid, lo, hi, k) = paired(g, e);
                println!(
                    "grid/embree at n = {n:.0e}, {threads} thread(s): {mid:.2} (median of {k} paired rounds, range {lo:.2}–{hi:.2}); build {:.2} s vs {:.2} s",
                    g.build_s, e.build_s
                );
            }
        }
        for engine in ["grid", "embree"] {
            if let (Some(one), Some(many)) = (find(engine, n, 1), find(engine, n, all)) {
                if all > 1 {
                    let (mid, lo, hi, _) = paired(many, one);
                    println!(
                        "{engine} 1 → {all} threads at n = {n:.0e}: {mid:.2}× (median of paired rounds, range {lo:.2}–{hi:.2})"
                    );
                }
            }
        }
    }
    if let (Some(&big), Some(&prev)) = (sizes.last(), sizes.iter().rev().nth(1)) {
        if let (Some(b), Some(p)) = (find("grid", big, all), find("grid", prev, all)) {
            println!(
                "grid flatness, n = {prev:.0e} → {big:.0e} ({all} threads): rays/s × {:.3}, ns per cell × {:.3}, cells per ray × {:.3}",
                b.rays_per_s() / p.rays_per_s(),
                b.cell_s() / p.cell_s(),
                (b.n_s + 1.0) / (p.n_s + 1.0)
            );
        }
    }
}

/// How many times faster `a` ran than `b`, round by round: (median, min, max, rounds).
fn paired(a: &Measured, b: &Measured) -> (f64, f64, f64, usize) {
    let ratios = paired_ratios(
        &RoundTimes {
            secs: vec![a.secs.clone(), b.secs.clone()],
        },
        0,
        1,
    );
    let (lo, hi) = ratios
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
    (median(&ratios), lo, hi, ratios.len())
}

/// `n` uniform directions from stream `key`.
fn directions(n: usize, key: u64) -> Vec<DVec3> {
    let mut rng = stream(&[key, 0]);
    (0..n).map(|_| uniform_direction(&mut rng)).collect()
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
