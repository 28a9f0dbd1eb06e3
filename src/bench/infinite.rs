//! The lazily generated infinite scene in `raycost bench`: the grid experiments' throughput as a
//! tracked figure, so that a slower scene generator shows up in the bench.
//!
//! Set-up, as the grid experiments run it (`experiments/quickstart.toml`): an infinite Poisson scene
//! at ρ = 1, r = 0.1 ([`InfiniteScene`], which picks the engine as experiments do), the eye uniform
//! in its cell (cell [0, a)³), uniform directions, the counting tracer ([`crate::grid::trace`]) with
//! mailboxing, and every group of [`RAYS_PER_SCENE`] rays (the experiments' default
//! `grid.rays_per_scene`: 1, each ray its own realisation) sharing one realisation.
//! Rays are handed to the thread pool in batches of [`BATCH`]; each thread keeps one [`InfiniteCaches`]
//! from batch to batch, as an experiment's worker does.
//!
//! Several cell widths are timed, each on 1 thread and on all threads, beside the finite query grid
//! ([`FastGrid`]) on the bench's n-sphere scene (n = 10⁶; 10⁵ with `--quick`) at the bench's cell
//! width. All of them run in alternating rounds ([`super::rounds`]): each round traces a fresh slice
//! of rays with every contestant, so the ratio infinite / finite is a median of per-round paired
//! ratios, like the bench's other ratios. The goal is that the best width reaches
//! [`TARGET_RATIO`] of the finite grid on 1 and on 2 threads.
//!
//! Rows (`bench.csv`): `engine = grid-infinite`, `n = 0`, one per cell width and thread count, with
//! the bench's columns (`rays_per_s`, `round_*_s`, `cell_s` = seconds per visited cell, visited
//! cells being Σ (N_S + 1), `peak_mem_bytes`, `checked`/`mismatches`: the rays' counts and hits on
//! 1 thread against all threads, `n_i_mean`, `n_s_mean`) and `n_i_mb_mean`, `hit_mean`,
//! `generated_mean` (spheres generated per ray), `rays_per_scene`, `eye`, `timed_best` (1 on
//! the fastest width of its thread count), `finite_n`, `finite_cell_width`, `finite_rays_per_s`,
//! `timed_finite_ratio` (median of the per-round ratios of this row's rays/s to the finite grid's
//! on as many threads) with `timed_finite_ratio_min`/`_max`. Every round's seconds and visited
//! cells, the finite grid's included (`engine = grid`), go to `bench.infinite-rounds.csv`.

use std::sync::Mutex;

use glam::DVec3;
use rayon::prelude::*;

use super::columns as bc;
use super::rounds::{self, alternate, median};
use super::{bench_scene, directions, memory, pool, trace_into, KEY, RHO};
use crate::experiment::grid::BATCH;
use crate::geom::Ray;
use crate::grid::fast::{FastGrid, FastTrace};
use crate::grid::{build::frame_around, TraceCounts};
use crate::output::row::Row;
use crate::sample::directions::{uniform_direction, uniform_unit_cube};
use crate::sample::rng::stream;
use crate::scene::infinite::{InfiniteCaches, InfiniteScene, Walk};
use crate::scene::{RadiusClass, RadiusDraw};

/// The engine name of the rows.
pub const ENGINE: &str = "grid-infinite";
/// The side table of every round's seconds (`bench.infinite-rounds.csv`).
pub const ROUNDS_TABLE: &str = "infinite-rounds";
/// Cell widths timed by the full bench.
pub const WIDTHS: &[f64] = &[0.2, 0.35, 0.5, 0.7, 1.0, 1.5, 2.0];
/// Cell widths timed by `bench --quick`.
pub const QUICK_WIDTHS: &[f64] = &[0.35, 0.7, 1.5];
/// Rays sharing one scene realisation: the experiments' default (`grid.rays_per_scene`).
pub const RAYS_PER_SCENE: usize = crate::experiment::grid::DEFAULT_RAYS_PER_SCENE as usize;
/// The goal for the best width: at least this fraction of the finite grid's rays/s.
pub const TARGET_RATIO: f64 = 1.0 / 3.0;
/// The experiments' default walk bound (`grid.max_steps`).
const MAX_STEPS: u32 = 10_000_000;

/// How much this part of the bench measures.
#[derive(Clone, Debug)]
struct Plan {
    widths: &'static [f64],
    rounds: usize,
    /// Infinite-scene rays per round and contestant (a multiple of [`BATCH`]).
    rays_per_round: usize,
    /// Spheres of the finite reference scene, and its rays per round.
    finite_n: u64,
    finite_rays_per_round: usize,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                widths: QUICK_WIDTHS,
                rounds: 3,
                rays_per_round: 2048,
                finite_n: 100_000,
                finite_rays_per_round: 50_000,
            }
        } else {
            Self {
                widths: WIDTHS,
                rounds: 5,
                rays_per_round: 16_384,
                finite_n: 1_000_000,
                finite_rays_per_round: 300_000,
            }
        }
    }
}

/// The finite query grid timed in the same rounds.
#[derive(Clone, Debug)]
pub struct FiniteRef {
    pub n: u64,
    pub cell_width: f64,
    pub rays_per_round: usize,
    pub secs: Vec<f64>,
    /// Cells visited per round, Σ (N_S + 1).
    pub cells: Vec<u64>,
}

impl FiniteRef {
    pub fn rays_per_s(&self) -> f64 {
        self.rays_per_round as f64 / median(&self.secs)
    }
}

/// One cell width on one thread count.
#[derive(Clone, Debug)]
pub struct InfiniteRow {
    pub cell_width: f64,
    pub threads: usize,
    pub rays_per_round: usize,
    /// Seconds of each round.
    pub secs: Vec<f64>,
    /// Cells visited per round, Σ (N_S + 1).
    pub cells: Vec<u64>,
    pub n_i: f64,
    pub n_i_mb: f64,
    pub n_s: f64,
    pub hit: f64,
    /// Rays cut off by the walk bound (0 expected).
    pub truncated: u64,
    /// Mean spheres generated per scene realisation.
    pub generated: f64,
    /// Resident memory the per-thread caches grew by on a first pass with fresh caches.
    pub peak_mem_bytes: u64,
    /// Rays compared between 1 thread and all threads, and how many differed.
    pub checked: u64,
    pub mismatches: u64,
    /// The fastest width of its thread count (median rays/s).
    pub best: bool,
    /// The finite grid on as many threads, and this row's per-round ratios to it.
    pub finite: FiniteRef,
    pub ratios: Vec<f64>,
}

impl InfiniteRow {
    pub fn rays_per_s(&self) -> f64 {
        self.rays_per_round as f64 / median(&self.secs)
    }

    /// Seconds per visited cell: the median over rounds of the round's seconds per cell.
    pub fn cell_s(&self) -> f64 {
        let per: Vec<f64> = self
            .secs
            .iter()
            .zip(&self.cells)
            .map(|(&s, &c)| s / c as f64)
            .collect();
        median(&per)
    }

    /// Median, min and max of the per-round ratios to the finite grid.
    pub fn ratio(&self) -> (f64, f64, f64) {
        let (lo, hi) = self
            .ratios
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
        (median(&self.ratios), lo, hi)
    }

    /// The bench table's row (the bench's columns first, in its order).
    pub fn row(&self) -> Row {
        let fold = |f: fn(f64, f64) -> f64, init| self.secs.iter().copied().fold(init, f);
        let (ratio, lo, hi) = self.ratio();
        let mut row = Row::default();
        row.put(&bc::ENGINE, ENGINE)
            .put(&bc::N, 0u64)
            .put(&bc::THREADS, self.threads as u64)
            .put(&bc::CELL_WIDTH, self.cell_width)
            .put(&bc::RAYS, (self.rays_per_round * self.secs.len()) as u64)
            .put(&bc::ROUNDS, self.secs.len() as u64);
        row.put(&bc::RAYS_PER_S, self.rays_per_s())
            .put(&bc::ROUND_MIN_S, fold(f64::min, f64::INFINITY))
            .put(&bc::ROUND_MEDIAN_S, median(&self.secs))
            .put(&bc::ROUND_MAX_S, fold(f64::max, 0.0))
            .put(&bc::CELL_S, self.cell_s())
            .put(&bc::BUILD_S, 0.0)
            .put(&bc::PEAK_MEM_BYTES, self.peak_mem_bytes)
            .put(&bc::STRUCTURE_BYTES, 0u64);
        row.put(&bc::CHECKED, self.checked)
            .put(&bc::MISMATCHES, self.mismatches)
            .put(&bc::F32_TIES, 0u64)
            .put(&bc::T_REL_DIFF_MAX, 0.0)
            .put(&bc::N_I_MEAN, self.n_i)
            .put(&bc::N_S_MEAN, self.n_s);
        row.put(&bc::N_I_MB_MEAN, self.n_i_mb)
            .put(&bc::HIT_MEAN, self.hit)
            .put(&bc::TRUNCATED, self.truncated)
            .put(&bc::GENERATED_MEAN, self.generated)
            .put(&bc::RAYS_PER_SCENE, RAYS_PER_SCENE as u64)
            .put(&bc::EYE, "uniform")
            .put(&bc::TIMED_BEST, u64::from(self.best))
            .put(&bc::FINITE_N, self.finite.n)
            .put(&bc::FINITE_CELL_WIDTH, self.finite.cell_width)
            .put(&bc::FINITE_RAYS_PER_S, self.finite.rays_per_s())
            .put(&bc::TIMED_FINITE_RATIO, ratio)
            .put(&bc::TIMED_FINITE_RATIO_MIN, lo)
            .put(&bc::TIMED_FINITE_RATIO_MAX, hi);
        row
    }

    /// This row's rounds for `bench.infinite-rounds.csv`; `with_finite` adds the finite grid's.
    pub fn round_rows(&self, with_finite: bool) -> Vec<Row> {
        let one = |engine: &str, n: u64, a: f64, rays: usize, r: usize, cells: u64, s: f64| {
            let mut row = Row::default();
            row.put(&bc::ENGINE, engine)
                .put(&bc::N, n)
                .put(&bc::THREADS, self.threads as u64)
                .put(&bc::CELL_WIDTH, a)
                .put(&bc::ROUND, r as u64)
                .put(&bc::RAYS, rays as u64)
                .put(&bc::CELLS, cells)
                .put(&bc::ROUND_S, s);
            row
        };
        let f = &self.finite;
        let finite = f
            .secs
            .iter()
            .zip(&f.cells)
            .enumerate()
            .map(|(r, (&s, &c))| one("grid", f.n, f.cell_width, f.rays_per_round, r, c, s));
        let own = self
            .secs
            .iter()
            .zip(&self.cells)
            .enumerate()
            .map(|(r, (&s, &c))| one(ENGINE, 0, self.cell_width, self.rays_per_round, r, c, s));
        if with_finite {
            finite.chain(own).collect()
        } else {
            own.collect()
        }
    }
}

/// What this part of the bench measured: one row per width and thread count (widths fastest).
#[derive(Clone, Debug, Default)]
pub struct Infinite {
    pub rows: Vec<InfiniteRow>,
}

impl Infinite {
    /// The side-table rows of each row, in row order (the finite grid's rounds with the first row
    /// of each thread count).
    pub fn round_rows(&self) -> Vec<Vec<Row>> {
        self.rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let first = i == 0 || self.rows[i - 1].threads != r.threads;
                r.round_rows(first)
            })
            .collect()
    }

    /// The best row of each thread count.
    pub fn best(&self) -> impl Iterator<Item = &InfiniteRow> {
        self.rows.iter().filter(|r| r.best)
    }

    /// A readable table on stdout, and the best width of each thread count against the target.
    pub fn print(&self) {
        let Some(first) = self.rows.first() else {
            return;
        };
        println!(
            "\nInfinite Poisson scene (lazily generated; ρ = {RHO}, r = {}, eye uniform in its cell, {RAYS_PER_SCENE} rays per realisation), beside the finite query grid at n = {:.0e} (a = {:.3}), paired rounds:",
            super::R,
            first.finite.n as f64,
            first.finite.cell_width
        );
        println!(
            "{:>6} {:>4} {:>11} {:>19} {:>8} {:>7} {:>7} {:>6} {:>8} {:>8} {:>5} {:>11} {:>19}",
            "a",
            "thr",
            "rays/s",
            "round range",
            "ns/cell",
            "N_I",
            "N_S",
            "hit",
            "spheres",
            "peak MB",
            "mism",
            "inf/finite",
            "round range"
        );
        for r in &self.rows {
            let (ratio, lo, hi) = r.ratio();
            let (slow, fast) = rounds::rate_range(r.rays_per_round, &r.secs);
            println!(
                "{:>6.2} {:>4} {:>11.4e} {:>9.3e}–{:<9.3e} {:>8.1} {:>7.1} {:>7.2} {:>6.3} {:>8.0} {:>8.1} {:>5} {:>11.4} {:>9.4}–{:<9.4}{}",
                r.cell_width,
                r.threads,
                r.rays_per_s(),
                slow,
                fast,
                r.cell_s() * 1e9,
                r.n_i,
                r.n_s,
                r.hit,
                r.generated,
                r.peak_mem_bytes as f64 / 1e6,
                r.mismatches,
                ratio,
                lo,
                hi,
                if r.best { "  ← best" } else { "" }
            );
        }
        for r in self.best() {
            let (ratio, lo, hi) = r.ratio();
            println!(
                "infinite best, {} thread(s): a = {:.2}, {:.4e} rays/s; finite grid (n = {:.0e}) {:.4e} rays/s; infinite / finite {ratio:.4} (paired rounds {lo:.4}–{hi:.4}); target ≥ {TARGET_RATIO:.3}: {}",
                r.threads,
                r.cell_width,
                r.rays_per_s(),
                r.finite.n as f64,
                r.finite.rays_per_s(),
                if ratio >= TARGET_RATIO { "met" } else { "not met" }
            );
        }
    }
}

/// One contestant of the rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Who {
    /// The finite query grid on (threads).
    Finite(usize),
    /// Width index, threads.
    Infinite(usize, usize),
}

/// Runs this part of the bench: the finite grid at the bench's cell width `finite_a`, the infinite
/// scene at every width of the plan, each on 1 and on `all` threads.
pub fn run(
    quick: bool,
    finite_a: f64,
    classes: &[RadiusClass],
    all: usize,
) -> anyhow::Result<Infinite> {
    let field = Field::new(quick, finite_a, classes, all)?;
    let peak = field.warm_up();
    let raced = field.race();
    let finite = field.finite_refs(&raced);
    Ok(Infinite {
        rows: field.rows(&raced, &finite, &peak),
    })
}

/// What every round shares: the pools and per-worker caches of each thread count, the finite
/// grid, and both ray sets.
struct Field<'a> {
    plan: Plan,
    classes: &'a [RadiusClass],
    finite_a: f64,
    thread_counts: Vec<usize>,
    pools: Vec<rayon::ThreadPool>,
    /// One cache per worker of each pool, kept from batch to batch and round to round.
    caches: Vec<Vec<Mutex<InfiniteCaches>>>,
    grid: FastGrid,
    fin_rays: Vec<Ray>,
    /// The infinite scene's rays, per width: one warm-up slice, then one slice per round.
    inf_rays: Vec<Vec<Ray>>,
    warm: usize,
}

/// The rounds' seconds and every contestant's answers.
struct Raced {
    times: rounds::RoundTimes,
    who: Vec<Who>,
    /// Per thread count, the finite grid's answer per ray.
    fin_out: Vec<Vec<FastTrace>>,
    /// Per width and thread count, the infinite scene's counts per ray.
    inf_out: Vec<Vec<Vec<TraceCounts>>>,
    /// Per width, spheres generated in the rounds (on one thread).
    generated: Vec<u64>,
}

impl<'a> Field<'a> {
    fn new(
        quick: bool,
        finite_a: f64,
        classes: &'a [RadiusClass],
        all: usize,
    ) -> anyhow::Result<Self> {
        let plan = Plan::new(quick);
        let thread_counts: Vec<usize> = if all > 1 { vec![1, all] } else { vec![1] };
        let pools = thread_counts
            .iter()
            .map(|&t| pool(t))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let caches = thread_counts.iter().map(|&t| fresh_caches(t)).collect();
        // The finite reference: the bench's n-sphere scene (the same realisation as its grid rows).
        let (spheres, bounds) = bench_scene(classes, plan.finite_n, KEY ^ plan.finite_n);
        let grid = FastGrid::build(frame_around(bounds, finite_a, DVec3::ZERO), &spheres);
        drop(spheres);
        let fin_rays: Vec<Ray> = directions(plan.rounds * plan.finite_rays_per_round, KEY)
            .into_iter()
            .map(|d| Ray::new(DVec3::ZERO, d))
            .collect();
        let warm = 2 * BATCH as usize * all;
        let inf_rays = plan
            .widths
            .iter()
            .enumerate()
            .map(|(i, &a)| {
                eye_rays(
                    a,
                    warm + plan.rounds * plan.rays_per_round,
                    &[KEY, 3, i as u64],
                )
            })
            .collect();
        Ok(Field {
            plan,
            classes,
            finite_a,
            thread_counts,
            pools,
            caches,
            grid,
            fin_rays,
            inf_rays,
            warm,
        })
    }

    /// Untimed warm-up: fault in the finite grid; grow each width's caches from fresh ones (their
    /// growth is the row's memory), then leave every cache grown. Returns the growth per width and
    /// thread count.
    fn warm_up(&self) -> Vec<Vec<u64>> {
        let (plan, warm) = (&self.plan, self.warm);
        let fin_per = plan.finite_rays_per_round;
        let mut peak = vec![vec![0u64; self.thread_counts.len()]; plan.widths.len()];
        for (t, p) in self.pools.iter().enumerate() {
            let mut scratch = vec![FastTrace::default(); fin_per];
            p.install(|| trace_into(&self.grid, &self.fin_rays[..fin_per], &mut scratch));
            for (i, &a) in plan.widths.iter().enumerate() {
                let fresh = fresh_caches(self.thread_counts[t]);
                let rays = &self.inf_rays[i][..warm];
                let mut out = vec![TraceCounts::default(); warm];
                let (_, grew) = memory::peak_increment(|| {
                    p.install(|| trace_lazy(self.classes, a, rays, 0, &mut out, &fresh))
                });
                peak[i][t] = grew;
                drop(fresh);
                p.install(|| trace_lazy(self.classes, a, rays, 0, &mut out, &self.caches[t]));
            }
        }
        peak
    }

    /// Every contestant (the finite grid, then each width, per thread count) in alternating rounds.
    fn race(&self) -> Raced {
        let (plan, warm) = (&self.plan, self.warm);
        let (per, fin_per) = (plan.rays_per_round, plan.finite_rays_per_round);
        let threads = self.thread_counts.len();
        let mut fin_out = vec![vec![FastTrace::default(); self.fin_rays.len()]; threads];
        let mut inf_out: Vec<Vec<Vec<TraceCounts>>> = plan
            .widths
            .iter()
            .map(|_| vec![vec![TraceCounts::default(); plan.rounds * per]; threads])
            .collect();
        let mut who = Vec::new();
        for t in 0..threads {
            who.push(Who::Finite(t));
            who.extend((0..plan.widths.len()).map(|i| Who::Infinite(i, t)));
        }
        let mut generated = vec![0u64; plan.widths.len()];
        let times = alternate(who.len(), plan.rounds, |c, r| match who[c] {
            Who::Finite(t) => {
                let span = r * fin_per..(r + 1) * fin_per;
                let out = &mut fin_out[t][span.clone()];
                self.pools[t].install(|| trace_into(&self.grid, &self.fin_rays[span], out));
            }
            Who::Infinite(i, t) => {
                let span = r * per..(r + 1) * per;
                let rays = &self.inf_rays[i][warm + span.start..warm + span.end];
                let out = &mut inf_out[i][t][span];
                // Batch keys continue the warm-up's, so every round traces fresh realisations.
                let first_batch = (warm + r * per) / BATCH as usize;
                let (a, caches) = (plan.widths[i], &self.caches[t]);
                let g = self.pools[t]
                    .install(|| trace_lazy(self.classes, a, rays, first_batch, out, caches));
                if t == 0 {
                    generated[i] += g;
                }
            }
        });
        Raced {
            times,
            who,
            fin_out,
            inf_out,
            generated,
        }
    }

    /// The finite grid's reference per thread count.
    fn finite_refs(&self, raced: &Raced) -> Vec<FiniteRef> {
        let fin_per = self.plan.finite_rays_per_round;
        (0..self.thread_counts.len())
            .map(|t| FiniteRef {
                n: self.plan.finite_n,
                cell_width: self.finite_a,
                rays_per_round: fin_per,
                secs: raced.secs_of(Who::Finite(t)),
                cells: raced.fin_out[t]
                    .chunks(fin_per)
                    .map(|ch| cells_of(ch.iter().map(|q| q.n_s)))
                    .collect(),
            })
            .collect()
    }

    /// One row per thread count and width, the fastest width of each thread count marked.
    fn rows(&self, raced: &Raced, finite: &[FiniteRef], peak: &[Vec<u64>]) -> Vec<InfiniteRow> {
        let plan = &self.plan;
        let mut rows = Vec::new();
        for (t, &threads) in self.thread_counts.iter().enumerate() {
            for (i, &a) in plan.widths.iter().enumerate() {
                let mut row = raced.row(plan, i, t, &finite[t]);
                row.cell_width = a;
                row.threads = threads;
                row.peak_mem_bytes = peak[i][t];
                rows.push(row);
            }
            let group = rows.len() - plan.widths.len()..rows.len();
            if let Some(b) = rows[group.clone()]
                .iter()
                .enumerate()
                .max_by(|x, y| x.1.rays_per_s().total_cmp(&y.1.rays_per_s()))
                .map(|(k, _)| group.start + k)
            {
                rows[b].best = true;
            }
        }
        rows
    }
}

impl Raced {
    /// The seconds of each round of contestant `w`.
    fn secs_of(&self, w: Who) -> Vec<f64> {
        let c = self
            .who
            .iter()
            .position(|&x| x == w)
            .expect("every contestant raced");
        self.times.secs[c].clone()
    }

    /// Width `i` on thread count `t` (cell width, threads and memory left for the caller).
    fn row(&self, plan: &Plan, i: usize, t: usize, fin: &FiniteRef) -> InfiniteRow {
        let per = plan.rays_per_round;
        let counts = &self.inf_out[i][t];
        let rays = counts.len() as f64;
        let mean = |f: fn(&TraceCounts) -> f64| counts.iter().map(f).sum::<f64>() / rays;
        // Against the first thread count (1): the same rays and realisations, so the same
        // counts and hits, to the bit.
        let mismatches = counts
            .iter()
            .zip(&self.inf_out[i][0])
            .filter(|(x, y)| x != y)
            .count() as u64;
        let secs = self.secs_of(Who::Infinite(i, t));
        let ratios = secs
            .iter()
            .zip(&fin.secs)
            .map(|(&s, &fs)| (per as f64 / s) / (fin.rays_per_round as f64 / fs))
            .collect();
        let scenes = (plan.rounds * per).div_ceil(RAYS_PER_SCENE) as f64;
        InfiniteRow {
            cell_width: f64::NAN,
            threads: 0,
            rays_per_round: per,
            secs,
            cells: counts
                .chunks(per)
                .map(|ch| cells_of(ch.iter().map(|q| q.n_s)))
                .collect(),
            n_i: mean(|q| f64::from(q.n_i)),
            n_i_mb: mean(|q| f64::from(q.n_i_mb)),
            n_s: mean(|q| f64::from(q.n_s)),
            hit: mean(|q| f64::from(u8::from(q.hit.is_some()))),
            truncated: counts.iter().filter(|q| q.truncated).count() as u64,
            generated: self.generated[i] as f64 / scenes,
            peak_mem_bytes: 0,
            checked: if t == 0 { 0 } else { counts.len() as u64 },
            mismatches,
            best: false,
            finite: fin.clone(),
            ratios,
        }
    }
}

/// Cells visited by a round's rays: N_S + 1 each.
fn cells_of(steps: impl Iterator<Item = u32>) -> u64 {
    steps.map(|s| u64::from(s) + 1).sum()
}

/// One empty cache per worker of a pool of `threads`.
fn fresh_caches(threads: usize) -> Vec<Mutex<InfiniteCaches>> {
    (0..threads)
        .map(|_| Mutex::new(InfiniteCaches::default()))
        .collect()
}

/// `n` rays with the eye uniform in the cell [0, a)³ and uniform directions, from stream `key`.
fn eye_rays(a: f64, n: usize, key: &[u64]) -> Vec<Ray> {
    let mut rng = stream(key);
    (0..n)
        .map(|_| {
            let d = uniform_direction(&mut rng);
            Ray::new(uniform_unit_cube(&mut rng) * a, d)
        })
        .collect()
}

/// Traces `rays` through the infinite scene at cell width `a` into `out`, on the current pool, as
/// the grid experiments do: batches of [`BATCH`] rays in parallel (batch `first_batch + k` for the
/// k-th), each group of [`RAYS_PER_SCENE`] rays in its own realisation, keyed by batch and group;
/// each worker uses its own cache of `caches`. Returns the spheres generated, summed over groups.
fn trace_lazy(
    classes: &[RadiusClass],
    a: f64,
    rays: &[Ray],
    first_batch: usize,
    out: &mut [TraceCounts],
    caches: &[Mutex<InfiniteCaches>],
) -> u64 {
    let scene = InfiniteScene {
        intensity: RHO,
        classes,
        draw: RadiusDraw::PerSphere,
    };
    let walk = Walk {
        cell_width: a,
        eye_magnitude: 2.0 * a,
        rays_per_scene: RAYS_PER_SCENE,
        mailbox: true,
        max_steps: MAX_STEPS,
        slabs: crate::scene::tube::SlabDraw::Gaps,
    };
    out.par_chunks_mut(BATCH as usize)
        .zip(rays.par_chunks(BATCH as usize))
        .enumerate()
        .map(|(k, (out, rays))| {
            let worker = rayon::current_thread_index().unwrap_or(0) % caches.len();
            let mut cache = caches[worker]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let b = (first_batch + k) as u64;
            let mut counts = Vec::with_capacity(rays.len());
            let generated = scene.trace_batch(&walk, &[KEY, 4, b], rays, &mut cache, &mut counts);
            out.copy_from_slice(&counts);
            generated
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quick_plan_is_a_subset_and_rounds_are_whole_batches() {
        for quick in [false, true] {
            let p = Plan::new(quick);
            assert_eq!(p.rays_per_round % BATCH as usize, 0);
            assert!(p.widths.iter().all(|w| WIDTHS.contains(w)));
        }
        assert!(
            RAYS_PER_SCENE as u64 <= BATCH,
            "a realisation fits in a batch"
        );
    }

    #[test]
    fn lazy_trace_is_independent_of_the_thread_count_and_counts_cells() {
        let classes = [RadiusClass {
            fraction: 1.0,
            radius: crate::scene::RadiusDist::Constant(super::super::R),
        }];
        let rays = eye_rays(0.5, 2 * BATCH as usize, &[KEY, 99]);
        let mut one = vec![TraceCounts::default(); rays.len()];
        let mut two = one.clone();
        let c1 = [Mutex::new(InfiniteCaches::default())];
        let c2 = [
            Mutex::new(InfiniteCaches::default()),
            Mutex::new(InfiniteCaches::default()),
        ];
        let g1 = pool(1)
            .expect("pool")
            .install(|| trace_lazy(&classes, 0.5, &rays, 7, &mut one, &c1));
        let g2 = pool(2)
            .expect("pool")
            .install(|| trace_lazy(&classes, 0.5, &rays, 7, &mut two, &c2));
        assert_eq!(one, two);
        assert_eq!(g1, g2);
        assert!(g1 > 0);
        // At ρ = 1, r = 0.1 almost every ray hits within the walk bound.
        assert!(one.iter().filter(|q| q.hit.is_some()).count() > rays.len() * 9 / 10);
        assert!(one.iter().all(|q| !q.truncated));
    }
}
