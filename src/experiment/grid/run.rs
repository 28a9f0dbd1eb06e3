//! The regular-grid study (kinds `grid`, `grid-scaling`, `grid-cost-model`): trace rays from the eye
//! through a grid over Poisson spheres, count N_I, N_S, t* and hits, and set each measurement beside
//! the theory of `theory::grid` for the same parameters.
//!
//! Rays are processed in batches of [`BATCH`]. Each batch has its own random stream keyed by
//! (seed, point, batch); in an infinite scene it also has its own scene realisation, so batches are
//! independent and the standard errors (clustered by batch, see `stats::mean`) are honest. Batch
//! results are merged in batch order, so every measured column is identical for any thread count.

use std::time::Instant;

use crate::sample::directions::uniform_unit_cube;
use glam::DVec3;
use rayon::prelude::*;

use super::columns as col;
use super::config::{GridConfig, SceneModel, Variant};
use super::GridTables;
use crate::experiment::kind::{Check, PointOutput, Rate};
use crate::experiment::machine::MachineCosts;
use crate::experiment::metric::{Metric, Theory};
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::{
    brute_force, build::frame_around, mailbox::Mailbox, trace, FiniteGrid, TraceCounts,
};
use crate::output::row::Row;
use crate::sample::{directions::uniform_direction, rng::domain, rng::stream};
use crate::scene::finite::FiniteScene;
use crate::scene::infinite::{InfiniteCaches, InfiniteScene, Walk};
use crate::stats::{gof, ClusteredMean, Histogram};
use crate::theory::grid::{self as th, Eye, GridTheoryInput};

/// Rays per batch (fixed: it must not depend on the thread count).
pub const BATCH: u64 = 256;
/// Batches handed to the thread pool at a time (bounds memory; progress advances per chunk).
const CHUNK_BATCHES: u64 = 64;
/// First-hit distances kept for the Kolmogorov–Smirnov test.
const KS_CAP: usize = 1_000_000;
/// N_I values histogrammed exactly (1..NI_BINS); larger ones pool into an overflow bin.
const NI_BINS: usize = 4000;

/// The per-ray means of a point, in one array so that batches and replicas merge in one loop.
#[derive(Clone, Copy, Debug)]
enum M {
    NI,
    NIMb,
    NS,
    THit,
    Hit,
    PLog,
    PSqrt,
}

/// Number of [`M`] means.
const MEANS: usize = 7;

/// Everything measured at one point, merged over batches in order.
#[derive(Clone, Debug)]
struct Acc {
    means: [ClusteredMean; MEANS],
    hist_t: Histogram,
    ni_mb_counts: Vec<u64>,
    t_samples: Vec<f64>,
    truncated: u64,
    /// Σ N_I,mb over hitting rays (for the geometric fit's exact mean).
    ni_mb_hit_sum: f64,
    bf_checked: u64,
    bf_mismatches: u64,
    bf_time: f64,
    trace_time: f64,
    generated: u64,
}

impl Acc {
    fn new(t_hi: f64, bins: usize) -> Self {
        Self {
            means: Default::default(),
            hist_t: Histogram::new(0.0, t_hi, bins),
            ni_mb_counts: vec![0; NI_BINS + 1],
            t_samples: Vec::new(),
            truncated: 0,
            ni_mb_hit_sum: 0.0,
            bf_checked: 0,
            bf_mismatches: 0,
            bf_time: 0.0,
            trace_time: 0.0,
            generated: 0,
        }
    }

    fn mean(&self, m: M) -> crate::stats::Estimate {
        self.means[m as usize].estimate()
    }

    fn push(&mut self, m: M, x: f64) {
        self.means[m as usize].push(x);
    }

    fn end_batch(&mut self) {
        self.means.iter_mut().for_each(ClusteredMean::end_batch);
    }

    /// Adds all of `o` (closed batches) into the current open batch: used to make one cluster of a
    /// whole replica.
    fn absorb(&mut self, o: &Acc) {
        for (m, x) in self.means.iter_mut().zip(&o.means) {
            m.absorb(x);
        }
        let mut rest = o.clone();
        rest.means = Default::default();
        self.merge(&rest);
    }

    fn merge(&mut self, o: &Acc) {
        for (m, x) in self.means.iter_mut().zip(&o.means) {
            m.merge(x);
        }
        self.hist_t.merge(&o.hist_t);
        for (a, b) in self.ni_mb_counts.iter_mut().zip(&o.ni_mb_counts) {
            *a += b;
        }
        let room = KS_CAP.saturating_sub(self.t_samples.len());
        self.t_samples.extend(o.t_samples.iter().take(room));
        self.truncated += o.truncated;
        self.ni_mb_hit_sum += o.ni_mb_hit_sum;
        self.bf_checked += o.bf_checked;
        self.bf_mismatches += o.bf_mismatches;
        self.bf_time += o.bf_time;
        self.trace_time += o.trace_time;
        self.generated += o.generated;
    }

    fn record(&mut self, c: &TraceCounts, thresholds: Option<(f64, f64)>) {
        self.push(M::NI, f64::from(c.n_i));
        self.push(M::NIMb, f64::from(c.n_i_mb));
        self.push(M::NS, f64::from(c.n_s));
        self.truncated += u64::from(c.truncated);
        match c.hit {
            Some(h) => {
                self.push(M::Hit, 1.0);
                self.push(M::THit, h.t);
                self.hist_t.push(h.t);
                self.t_samples.push(h.t);
                self.ni_mb_counts[(c.n_i_mb as usize).min(NI_BINS)] += 1;
                self.ni_mb_hit_sum += f64::from(c.n_i_mb);
            }
            None => self.push(M::Hit, 0.0),
        }
        if let Some((h_log, h_sqrt)) = thresholds {
            self.push(M::PLog, f64::from(u8::from(f64::from(c.n_i) >= h_log)));
            self.push(M::PSqrt, f64::from(u8::from(f64::from(c.n_i) >= h_sqrt)));
        }
    }
}

/// The built scene of a finite point.
struct Finite {
    spheres: Vec<Sphere>,
    grid: FiniteGrid,
    build_s: f64,
}

/// The theory input of a config.
pub fn theory_input(cfg: &GridConfig) -> GridTheoryInput<'_> {
    GridTheoryInput {
        intensity: cfg.intensity,
        classes: &cfg.classes,
        draw: cfg.draw,
        cell_width: cfg.cell_width,
    }
}

/// Builds replica `replica` of a finite point's scene.
fn build_finite(cfg: &GridConfig, fs: &FiniteScene, point: u64, replica: u64) -> Finite {
    let start = Instant::now();
    let spheres = fs.generate(&[domain::SCENE, cfg.seed, point, replica]);
    let rmax = spheres.iter().map(|s| s.r).fold(fs.max_radius(), f64::max);
    let b = fs.centre_box();
    let bounds = Aabb::new(b.lo - DVec3::splat(rmax), b.hi + DVec3::splat(rmax));
    let grid = FiniteGrid::build(frame_around(bounds, cfg.cell_width, fs.center), &spheres);
    Finite {
        spheres,
        grid,
        build_s: start.elapsed().as_secs_f64(),
    }
}

/// Runs one point. `progress` is called with the number of rays finished, per chunk of batches.
///
/// Infinite scenes: every group of `rays_per_scene` rays has its own realisation, and the standard
/// errors are clustered by batch. Finite scenes: `replicas` independent realisations share the rays;
/// with two or more, the standard errors are clustered by replica and so include the variation from
/// one configuration of spheres to the next (the paper's expectation is over configurations); with
/// one, they are conditional on that one scene.
pub fn run_point(
    cfg: &GridConfig,
    point: u64,
    machine: Option<MachineCosts>,
    progress: &(dyn Fn(u64) + Sync),
) -> PointOutput<GridTables> {
    let inp = theory_input(cfg);
    let mean_t = th::mean_first_hit(&inp);
    let t_hi = cfg.t_max_mfp * mean_t;
    let replicas = match &cfg.scene {
        SceneModel::Infinite => 1,
        SceneModel::Finite(_) => cfg.replicas,
    };
    let mut total = Acc::new(t_hi, cfg.bins);
    let mut report: Option<Finite> = None;
    let (mut build_s, mut bf_time, mut wall) = (0.0, 0.0, 0.0);
    for replica in 0..replicas {
        // Rays of this replica: an even share, the first replicas taking the remainder.
        let rays = cfg.rays / replicas + u64::from(replica < cfg.rays % replicas);
        // Free the previous replica before building the next (peak memory of one scene).
        drop(report.take());
        let finite = match &cfg.scene {
            SceneModel::Infinite => None,
            SceneModel::Finite(fs) => Some(build_finite(cfg, fs, point, replica)),
        };
        build_s += finite.as_ref().map_or(0.0, |f| f.build_s);
        let start = Instant::now();
        let acc = run_replica(cfg, point, replica, rays, finite.as_ref(), t_hi, progress);
        wall += start.elapsed().as_secs_f64();
        bf_time += acc.bf_time;
        if replicas > 1 {
            // One cluster per replica: the replica's batches pooled into one open cluster.
            let mut pooled = Acc::new(t_hi, cfg.bins);
            pooled.absorb(&acc);
            pooled.end_batch();
            total.merge(&pooled);
        } else {
            total.merge(&acc);
        }
        report = finite;
    }
    if let Some(f) = report.as_mut() {
        f.build_s = build_s / replicas as f64;
    }
    // Brute-force time is not tracing time.
    let trace_s = (wall - bf_time / rayon::current_num_threads() as f64).max(1e-9);
    make_result(cfg, &inp, &total, report.as_ref(), machine, trace_s, mean_t)
}

/// Traces `rays` rays of one replica (batches in parallel, merged in batch order).
fn run_replica(
    cfg: &GridConfig,
    point: u64,
    replica: u64,
    rays: u64,
    finite: Option<&Finite>,
    t_hi: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Acc {
    let a = cfg.cell_width;
    let anchor = match &cfg.scene {
        SceneModel::Infinite => DVec3::ZERO,
        SceneModel::Finite(fs) => fs.center,
    };
    let thresholds = finite.filter(|_| cfg.variant == Variant::Scaling).map(|f| {
        let n = (f.spheres.len().max(2)) as f64;
        (cfg.concentration_c * n.ln(), cfg.concentration_c * n.sqrt())
    });
    let brute = replica == 0
        && cfg.variant == Variant::Scaling
        && finite.is_some_and(|f| f.spheres.len() as u64 <= cfg.brute_force_max_n);
    let max_steps = u32::try_from(cfg.max_steps).unwrap_or(u32::MAX);
    let run_batch = |caches: &mut InfiniteCaches, b: u64| -> Acc {
        let mut acc = Acc::new(t_hi, cfg.bins);
        let mut rng = stream(&[domain::RAYS, cfg.seed, point, replica, b]);
        let n_rays = BATCH.min(rays - b * BATCH);
        let rays: Vec<Ray> = (0..n_rays)
            .map(|_| {
                let d = uniform_direction(&mut rng);
                let eye = match cfg.eye {
                    Eye::Corner => anchor,
                    Eye::Uniform => anchor + uniform_unit_cube(&mut rng) * a,
                };
                Ray::new(eye, d)
            })
            .collect();
        let mut mailbox = Mailbox::default();
        let start = Instant::now();
        let counts: Vec<TraceCounts> = match finite {
            Some(f) => {
                let mut lists = &f.grid;
                rays.iter()
                    .map(|r| trace(&mut lists, r, &mut mailbox, cfg.mailbox, max_steps))
                    .collect()
            }
            None => {
                let scene = InfiniteScene {
                    intensity: cfg.intensity,
                    classes: &cfg.classes,
                    draw: cfg.draw,
                };
                let walk = Walk {
                    cell_width: a,
                    eye_magnitude: 2.0 * a,
                    rays_per_scene: cfg.rays_per_scene as usize,
                    mailbox: cfg.mailbox,
                    max_steps,
                };
                let key = [domain::SCENE, cfg.seed, point, b];
                let mut c = Vec::with_capacity(rays.len());
                acc.generated += scene.trace_batch(&walk, &key, &rays, caches, &mut c);
                c
            }
        };
        acc.trace_time += start.elapsed().as_secs_f64();
        for c in &counts {
            acc.record(c, thresholds);
        }
        if brute {
            let f = finite.expect("brute force runs on finite scenes");
            let check = cfg.brute_force_rays.saturating_sub(b * BATCH).min(n_rays) as usize;
            let start = Instant::now();
            for (ray, c) in rays.iter().zip(&counts).take(check) {
                acc.bf_checked += 1;
                if brute_force(&f.spheres, ray).map(|h| h.id) != c.hit.map(|h| h.id) {
                    acc.bf_mismatches += 1;
                }
            }
            acc.bf_time += start.elapsed().as_secs_f64();
        }
        acc.end_batch();
        acc
    };
    let batches = rays.div_ceil(BATCH);
    let mut total = Acc::new(t_hi, cfg.bins);
    let mut b0 = 0;
    while b0 < batches {
        let b1 = (b0 + CHUNK_BATCHES).min(batches);
        let parts: Vec<Acc> = (b0..b1)
            .into_par_iter()
            .map_init(InfiniteCaches::default, run_batch)
            .collect();
        for p in &parts {
            total.merge(p);
        }
        progress((b1 * BATCH).min(rays) - (b0 * BATCH).min(rays));
        b0 = b1;
    }
    total
}

fn make_result(
    cfg: &GridConfig,
    inp: &GridTheoryInput,
    acc: &Acc,
    finite: Option<&Finite>,
    machine: Option<MachineCosts>,
    trace_s: f64,
    mean_t: f64,
) -> PointOutput<GridTables> {
    let mut row = Row::default();
    let mut summary = Vec::new();
    let band = th::n_i_band(inp);
    let n_s_th = th::n_s_mean(inp, cfg.eye);
    // Every hitting ray tests at least one sphere: a predictor below 1 is outside its expansion.
    let at_least_one = |x: f64| if x >= 1.0 { x } else { f64::NAN };
    let n_i_th = at_least_one(th::n_i_predictor_for_eye(inp, cfg.eye));
    let n_i_mb_th = at_least_one(th::n_i_mb_predictor_for_eye(inp, cfg.eye));
    let (n_i, n_i_mb, n_s) = (acc.mean(M::NI), acc.mean(M::NIMb), acc.mean(M::NS));
    let in_band = |theory| Theory::Band {
        prediction: theory,
        lower: band.lower,
        upper: band.upper,
    };
    Metric::new(&col::N_I, n_i, in_band(n_i_th)).write(&mut row, &mut summary);
    Metric::new(&col::N_I_MB, n_i_mb, in_band(n_i_mb_th)).write(&mut row, &mut summary);
    row.put(&col::N_I_PLAIN_THEORY, th::n_i_plain_predictor(inp, n_s_th));
    // The sharper predictors are derived for r < a/2 (no overlap of non-adjacent cells' offsets).
    let r_max = cfg
        .classes
        .iter()
        .map(|c| c.radius.max())
        .fold(0.0, f64::max);
    row.put(
        &col::PREDICTOR_REGIME,
        if r_max < 0.5 * cfg.cell_width {
            "r<a/2"
        } else {
            "r>=a/2"
        },
    );
    Metric::new(&col::N_S, n_s, Theory::Prediction(n_s_th)).write(&mut row, &mut summary);

    let t_hit = acc.mean(M::THit);
    let hit = acc.mean(M::Hit);
    // In a finite cube hits are cut off at the faces: condition the law on hitting inside.
    let (hit_th, mean_t) = match finite {
        None => (1.0, mean_t),
        Some(_) => finite_hit_theory(cfg, inp),
    };
    Metric::new(&col::T_HIT, t_hit, Theory::Prediction(mean_t)).write(&mut row, &mut summary);
    Metric::new(&col::HIT, hit, Theory::Prediction(hit_th)).write(&mut row, &mut summary);

    // Laws: exponential first-hit distance (KS and χ² on the histogram), geometric N_I.
    let mut sorted = acc.t_samples.clone();
    sorted.sort_by(f64::total_cmp);
    // The tests are against the infinite-scene law; in a finite cube that law does not hold
    // (hits are cut off at the faces), so there they are NaN rather than a misleading rejection.
    let infinite = finite.is_none();
    let law = th::first_hit_survival_fn(inp);
    let survival = |t: f64| if infinite { law(t) } else { f64::NAN };
    let d = if infinite {
        gof::ks_statistic(&sorted, |t| 1.0 - survival(t))
    } else {
        f64::NAN
    };
    row.put(&col::T_HIT_KS, d)
        .put(&col::T_HIT_KS_P, gof::ks_p_value(d, sorted.len()));
    let hits = acc.hist_t.total();
    let mut obs: Vec<u64> = acc.hist_t.counts.clone();
    obs.push(acc.hist_t.overflow);
    let mut exp: Vec<f64> = (0..acc.hist_t.counts.len())
        .map(|k| {
            let (lo, hi) = acc.hist_t.edges(k);
            hits as f64 * (survival(lo) - survival(hi))
        })
        .collect();
    exp.push(hits as f64 * survival(acc.hist_t.hi));
    let chi_t = if infinite {
        gof::chi_square(&obs, &exp, 0)
    } else {
        gof::ChiSquare {
            statistic: f64::NAN,
            dof: 0,
            p_value: f64::NAN,
        }
    };
    row.put(&col::T_HIT_CHI2, chi_t.statistic)
        .put(&col::T_HIT_CHI2_DOF, chi_t.dof)
        .put(&col::T_HIT_CHI2_P, chi_t.p_value);

    let mut hist = Vec::new();
    for k in 0..acc.hist_t.counts.len() {
        let (lo, hi) = acc.hist_t.edges(k);
        hist.push(hist_row("t_hit", lo, hi, obs[k], exp[k]));
    }
    hist.push(hist_row(
        "t_hit",
        acc.hist_t.hi,
        f64::INFINITY,
        acc.hist_t.overflow,
        *exp.last().expect("overflow bin"),
    ));

    // Geometric law of N_I (distinct tests, hitting rays), p fitted by the mean: p = 1/E[N_I].
    let n_hits: u64 = acc.ni_mb_counts.iter().sum();
    // Exact mean over hitting rays (the histogram clamps large N_I into its overflow bin).
    let mean_hit_ni = acc.ni_mb_hit_sum / n_hits.max(1) as f64;
    let p = (1.0 / mean_hit_ni).clamp(1e-12, 1.0);
    let kmax = acc
        .ni_mb_counts
        .iter()
        .rposition(|&c| c > 0)
        .unwrap_or(1)
        .clamp(1, NI_BINS - 1);
    let mut g_obs: Vec<u64> = acc.ni_mb_counts[1..=kmax].to_vec();
    g_obs.push(acc.ni_mb_counts[kmax + 1..].iter().sum());
    let mut g_exp: Vec<f64> = (1..=kmax as u64)
        .map(|k| n_hits as f64 * th::geometric_pmf(p, k))
        .collect();
    g_exp.push(n_hits as f64 * (1.0 - p).powi(kmax as i32));
    let chi_g = gof::chi_square(&g_obs, &g_exp, 1);
    let r0 = cfg.classes[0].radius.expect(|r| r);
    row.put(&col::N_I_GEOMETRIC_P, p)
        .put(&col::N_I_CYLINDER_RADIUS, r0 * (1.0 / p.sqrt() - 1.0));
    row.put(&col::N_I_MB_CHI2, chi_g.statistic)
        .put(&col::N_I_MB_CHI2_DOF, chi_g.dof)
        .put(&col::N_I_MB_CHI2_P, chi_g.p_value);
    for (k, (&o, &e)) in g_obs.iter().zip(&g_exp).enumerate() {
        let lo = (k + 1) as f64;
        let hi = if k + 1 == g_obs.len() {
            f64::INFINITY
        } else {
            lo + 1.0
        };
        hist.push(hist_row("n_i_mb", lo, hi, o, e));
    }

    row.put(&col::TRUNCATED, acc.truncated);
    match finite {
        None => {
            let batches = cfg.rays.div_ceil(BATCH);
            row.put(&col::GENERATED, acc.generated as f64 / batches as f64);
        }
        Some(f) => {
            row.put(&col::SPHERES, f.spheres.len())
                .put(&col::GRID_CELLS, f.grid.cells())
                .put(&col::GRID_LISTINGS, f.grid.listings())
                .put(&col::GRID_BYTES, f.grid.bytes());
        }
    }
    let mut checks = Vec::new();
    if cfg.variant == Variant::Scaling {
        let (pl, ps) = (acc.mean(M::PLog), acc.mean(M::PSqrt));
        let n = finite.map_or(2, |f| f.spheres.len().max(2)) as f64;
        row.put(&col::H_LOG, cfg.concentration_c * n.ln())
            .put_estimate(&col::P_LOG, &pl);
        row.put(&col::H_SQRT, cfg.concentration_c * n.sqrt())
            .put_estimate(&col::P_SQRT, &ps);
        row.put(&col::BF_RAYS, acc.bf_checked)
            .put(&col::BF_MISMATCHES, acc.bf_mismatches);
        checks.push(Check {
            name: col::BF_MISMATCHES.name,
            what: "the grid's first hit ≠ brute force's",
            failures: acc.bf_mismatches,
            checked: acc.bf_checked,
        });
        row.put(
            &col::BF_RAYS_PER_S,
            if acc.bf_time > 0.0 {
                acc.bf_checked as f64 / acc.bf_time
            } else {
                f64::NAN
            },
        );
    }

    // Timing columns (the only ones allowed to differ between runs).
    let rays_per_s = cfg.rays as f64 / trace_s;
    row.put(&col::TRACE_S, trace_s)
        .put(&col::RAYS_PER_S, rays_per_s)
        .put(&col::TIME_PER_RAY_S, acc.trace_time / cfg.rays as f64);
    if let Some(f) = finite {
        row.put(&col::BUILD_S, f.build_s);
    }
    if let Some(m) = machine {
        let tested = if cfg.mailbox { n_i_mb.mean } else { n_i.mean };
        let tested_th = if cfg.mailbox { n_i_mb_th } else { n_i_th };
        row.put(&col::T_I_S, m.t_i).put(&col::T_S_S, m.t_s);
        row.put(
            &col::TIME_MODEL_S,
            th::query_time(tested_th, n_s_th, m.t_i, m.t_s),
        );
        row.put(
            &col::TIME_COUNTS_MODEL_S,
            th::query_time(tested, n_s.mean, m.t_i, m.t_s),
        );
    }
    PointOutput {
        row,
        tables: GridTables { hist },
        summary,
        checks,
        rate: Rate {
            per_s: rays_per_s,
            unit: "rays",
        },
        warnings: Vec::new(),
    }
}

/// One row of the histogram table.
fn hist_row(metric: &str, lo: f64, hi: f64, count: u64, expected: f64) -> Row {
    let mut r = Row::default();
    r.put(&col::HIST_METRIC, metric)
        .put(&col::HIST_BIN_LO, lo)
        .put(&col::HIST_BIN_HI, hi)
        .put(&col::HIST_COUNT, count)
        .put(&col::HIST_EXPECTED, expected);
    r
}

/// The exponential law restricted to a finite cube: `(P(hit), E[t* | hit])` for rays from the eye
/// (at the centre, or uniform in its cell) to the faces of the cube holding the centres.
///
/// With L the distance to the cube along the ray, P(hit) = E[1 − S(L)] and
/// E[t*·1{hit}] = E[∫₀^L S(t) dt − L·S(L)], where S is the infinite-scene survival function. Both
/// expectations are over directions (a 100 × 200 midpoint rule in z and φ, uniform on the sphere)
/// and over eye positions (the corner, or a 3 × 3 × 3 midpoint rule in the cell); the t integral
/// uses 8-node Gauss–Legendre. An approximation: it ignores the layer of width r beyond the faces
/// where spheres centred inside the cube can still be hit.
fn finite_hit_theory(cfg: &GridConfig, inp: &GridTheoryInput) -> (f64, f64) {
    let SceneModel::Finite(fs) = &cfg.scene else {
        return (1.0, th::mean_first_hit(inp));
    };
    let b = fs.centre_box();
    let a = cfg.cell_width;
    let eyes: Vec<DVec3> = match cfg.eye {
        Eye::Corner => vec![fs.center],
        Eye::Uniform => (0..27)
            .map(|k| {
                fs.center
                    + DVec3::new(
                        (k % 3) as f64 + 0.5,
                        (k / 3 % 3) as f64 + 0.5,
                        (k / 9) as f64 + 0.5,
                    ) * (a / 3.0)
            })
            .collect(),
    };
    let (gx, gw) = crate::scene::radius::gauss_legendre(8);
    let (nz, nphi) = (100, 200);
    let (mut p_hit, mut t_hit) = (0.0, 0.0);
    for i in 0..nz {
        let z = -1.0 + (i as f64 + 0.5) * 2.0 / nz as f64;
        let s = (1.0 - z * z).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) * std::f64::consts::TAU / nphi as f64;
            let d = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            for e in &eyes {
                // Distance to the cube's faces along d.
                let l = (0..3)
                    .map(|k| {
                        let (dk, ek) = (d[k], e[k]);
                        if dk > 0.0 {
                            ((b.hi[k] - ek) / dk).max(0.0)
                        } else if dk < 0.0 {
                            ((b.lo[k] - ek) / dk).max(0.0)
                        } else {
                            f64::INFINITY
                        }
                    })
                    .fold(f64::INFINITY, f64::min);
                let s_l = th::first_hit_survival(inp, l);
                p_hit += 1.0 - s_l;
                let integral: f64 = gx
                    .iter()
                    .zip(&gw)
                    .map(|(x, w)| 0.5 * l * w * th::first_hit_survival(inp, 0.5 * l * (x + 1.0)))
                    .sum();
                t_hit += integral - l * s_l;
            }
        }
    }
    (p_hit / (nz * nphi * eyes.len()) as f64, t_hit / p_hit)
}
