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

use super::config::{GridConfig, SceneModel, Variant};
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::{
    brute_force, build::frame_around, mailbox::Mailbox, trace, FiniteGrid, TraceCounts,
};
use crate::sample::{directions::uniform_direction, rng::domain, rng::stream};
use crate::scene::finite::FiniteScene;
use crate::scene::infinite::{InfiniteCaches, InfiniteScene, Walk};
use crate::stats::{ClusteredMean, Histogram};
use crate::theory::grid::{self as th, Eye};

/// Rays per batch (fixed: it must not depend on the thread count).
pub const BATCH: u64 = 256;
/// Batches handed to the thread pool at a time (bounds memory; progress advances per chunk).
const CHUNK_BATCHES: u64 = 64;
/// First-hit distances kept for the Kolmogorov–Smirnov test.
const KS_CAP: usize = 1_000_000;
/// N_I values histogrammed exactly (1..NI_BINS); larger ones pool into an overflow bin.
pub(super) const NI_BINS: usize = 4000;

/// The per-ray means of a point, in one array so that batches and replicas merge in one loop.
#[derive(Clone, Copy, Debug)]
pub(super) enum M {
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
pub(super) struct Acc {
    means: [ClusteredMean; MEANS],
    pub(super) hist_t: Histogram,
    pub(super) ni_mb_counts: Vec<u64>,
    pub(super) t_samples: Vec<f64>,
    pub(super) truncated: u64,
    /// Σ N_I,mb over hitting rays (for the geometric fit's exact mean).
    pub(super) ni_mb_hit_sum: f64,
    pub(super) bf_checked: u64,
    pub(super) bf_mismatches: u64,
    pub(super) bf_time: f64,
    pub(super) trace_time: f64,
    pub(super) generated: u64,
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

    pub(super) fn mean(&self, m: M) -> crate::stats::Estimate {
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
pub(super) struct Finite {
    pub(super) spheres: Vec<Sphere>,
    pub(super) grid: FiniteGrid,
    pub(super) build_s: f64,
}

/// What tracing one point leaves: every ray's counts merged, the last finite scene (its build time
/// the mean over replicas), and the wall seconds spent tracing (brute force excluded).
pub(super) struct Traced {
    pub(super) acc: Acc,
    pub(super) finite: Option<Finite>,
    pub(super) trace_s: f64,
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
pub(super) fn run_point(
    cfg: &GridConfig,
    point: u64,
    threads: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Traced {
    let mean_t = th::mean_first_hit(&super::theory::input(cfg));
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
    Traced {
        acc: total,
        finite: report,
        // Brute-force time is not tracing time.
        trace_s: (wall - bf_time / threads as f64).max(1e-9),
    }
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
                    slabs: crate::scene::tube::SlabDraw::Gaps,
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
