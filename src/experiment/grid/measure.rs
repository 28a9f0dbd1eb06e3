//! What one grid point measured, typed: the per-ray means with their standard errors, the fits of
//! the first-hit and N_I laws (KS, χ², the geometric law's p), the histograms against those laws
//! (`NAME.hist.csv`), the scene's size, the brute-force check and the timings. Made once from the
//! tracer's merged accumulator; `columns.rs` declares how each value becomes a column.

use super::config::{GridConfig, Variant};
use super::run::{Acc, Traced, BATCH, M, NI_BINS};
use super::theory::{self, GridTheory};
use crate::experiment::machine::MachineCosts;
use crate::stats::gof::{self, ChiSquare};
use crate::stats::Estimate;
use crate::theory::grid as th;

/// One grid point's measurement, with its closed forms.
#[derive(Clone, Debug)]
pub struct GridMeasured {
    /// The closed forms of the point.
    pub theory: GridTheory,
    /// N_I per ray.
    pub n_i: Estimate,
    /// N_I with mailboxing.
    pub n_i_mb: Estimate,
    /// N_S per ray.
    pub n_s: Estimate,
    /// t* of hitting rays.
    pub t_hit: Estimate,
    /// The hit fraction.
    pub hit: Estimate,
    /// The laws' fits.
    pub laws: Laws,
    /// Rays cut off at `grid.max_steps`.
    pub truncated: u64,
    /// The scene's size.
    pub scene: SceneFacts,
    /// `grid-scaling`: concentration and the brute-force check.
    pub scaling: Option<Scaling>,
    /// Wall seconds tracing (brute force excluded).
    pub trace_s: f64,
    /// Rays per wall second.
    pub rays_per_s: f64,
    /// Thread seconds per ray.
    pub time_per_ray_s: f64,
    /// `grid-cost-model`: the machine's T_I and T_S.
    pub machine: Option<MachineCosts>,
}

/// The first-hit law and the N_I law against the measurement.
#[derive(Clone, Copy, Debug)]
pub struct Laws {
    /// Kolmogorov–Smirnov distance of t* from the exponential law (NaN in a finite cube).
    pub ks: f64,
    /// Its p-value.
    pub ks_p: f64,
    /// χ² of the t* histogram against the exponential law.
    pub chi_t: ChiSquare,
    /// p of the geometric law fitted to N_I,mb of hitting rays.
    pub geometric_p: f64,
    /// The cylinder radius that p implies (eq. 9).
    pub cylinder_radius: f64,
    /// χ² of N_I,mb against the fitted geometric law.
    pub chi_g: ChiSquare,
}

/// The scene a point traced.
#[derive(Clone, Copy, Debug)]
pub enum SceneFacts {
    /// An infinite scene: sphere centres drawn per batch of rays.
    Infinite {
        /// Mean per batch.
        generated_per_batch: f64,
    },
    /// A finite scene's last replica.
    Finite(FiniteFacts),
}

/// A finite scene's last replica.
#[derive(Clone, Copy, Debug)]
pub struct FiniteFacts {
    /// Spheres.
    pub spheres: usize,
    /// Cells of its grid.
    pub cells: usize,
    /// Listings in the cell lists.
    pub listings: usize,
    /// Bytes of the cell lists.
    pub bytes: u64,
    /// Seconds to build the grid (mean over replicas).
    pub build_s: f64,
}

/// `grid-scaling`: Proposition 4.1's tails and the brute-force check.
#[derive(Clone, Copy, Debug)]
pub struct Scaling {
    /// n, the spheres of the (last) scene, at least 2.
    pub n: f64,
    /// P(N_I ≥ c·ln n).
    pub p_log: Estimate,
    /// P(N_I ≥ c·√n).
    pub p_sqrt: Estimate,
    /// Rays also traced by brute force.
    pub bf_rays: u64,
    /// Rays whose first hit differs from brute force.
    pub bf_mismatches: u64,
    /// Brute force's speed (NaN if it did not run).
    pub bf_rays_per_s: f64,
}

/// One bin of `NAME.hist.csv`.
#[derive(Clone, Copy, Debug)]
pub struct HistBin {
    /// `t_hit` or `n_i_mb`.
    pub metric: &'static str,
    /// Bin start.
    pub lo: f64,
    /// Bin end (∞ for the overflow bin).
    pub hi: f64,
    /// Rays in the bin.
    pub count: u64,
    /// Rays the law expects in it.
    pub expected: f64,
}

/// The measurement of a traced point, and its histogram bins.
pub(super) fn measure(
    cfg: &GridConfig,
    traced: &Traced,
    machine: Option<MachineCosts>,
) -> (GridMeasured, Vec<HistBin>) {
    let acc = &traced.acc;
    let finite = traced.finite.as_ref();
    let mut bins = Vec::new();
    let laws = laws(cfg, acc, finite.is_none(), &mut bins);
    let scene = match finite {
        None => SceneFacts::Infinite {
            generated_per_batch: acc.generated as f64 / cfg.rays.div_ceil(BATCH) as f64,
        },
        Some(f) => SceneFacts::Finite(FiniteFacts {
            spheres: f.spheres.len(),
            cells: f.grid.cells(),
            listings: f.grid.listings(),
            bytes: f.grid.bytes(),
            build_s: f.build_s,
        }),
    };
    let scaling = (cfg.variant == Variant::Scaling).then(|| Scaling {
        n: finite.map_or(2, |f| f.spheres.len().max(2)) as f64,
        p_log: acc.mean(M::PLog),
        p_sqrt: acc.mean(M::PSqrt),
        bf_rays: acc.bf_checked,
        bf_mismatches: acc.bf_mismatches,
        bf_rays_per_s: if acc.bf_time > 0.0 {
            acc.bf_checked as f64 / acc.bf_time
        } else {
            f64::NAN
        },
    });
    let measured = GridMeasured {
        theory: GridTheory::of(cfg),
        n_i: acc.mean(M::NI),
        n_i_mb: acc.mean(M::NIMb),
        n_s: acc.mean(M::NS),
        t_hit: acc.mean(M::THit),
        hit: acc.mean(M::Hit),
        laws,
        truncated: acc.truncated,
        scene,
        scaling,
        trace_s: traced.trace_s,
        rays_per_s: cfg.rays as f64 / traced.trace_s,
        time_per_ray_s: acc.trace_time / cfg.rays as f64,
        machine,
    };
    (measured, bins)
}

/// The exponential first-hit law (KS, χ² on the histogram) and the geometric N_I law (p fitted by
/// the mean), with the histograms' bins against them.
fn laws(cfg: &GridConfig, acc: &Acc, infinite: bool, bins: &mut Vec<HistBin>) -> Laws {
    let inp = theory::input(cfg);
    let mut sorted = acc.t_samples.clone();
    sorted.sort_by(f64::total_cmp);
    // The tests are against the infinite-scene law; in a finite cube that law does not hold
    // (hits are cut off at the faces), so there they are NaN rather than a misleading rejection.
    let law = th::first_hit_survival_fn(&inp);
    let survival = |t: f64| if infinite { law(t) } else { f64::NAN };
    let ks = if infinite {
        gof::ks_statistic(&sorted, |t| 1.0 - survival(t))
    } else {
        f64::NAN
    };
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
        ChiSquare {
            statistic: f64::NAN,
            dof: 0,
            p_value: f64::NAN,
        }
    };
    for k in 0..acc.hist_t.counts.len() {
        let (lo, hi) = acc.hist_t.edges(k);
        bins.push(bin("t_hit", lo, hi, obs[k], exp[k]));
    }
    bins.push(bin(
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
    for (k, (&o, &e)) in g_obs.iter().zip(&g_exp).enumerate() {
        let lo = (k + 1) as f64;
        let hi = if k + 1 == g_obs.len() {
            f64::INFINITY
        } else {
            lo + 1.0
        };
        bins.push(bin("n_i_mb", lo, hi, o, e));
    }
    let r0 = cfg.classes[0].radius.expect(|r| r);
    Laws {
        ks,
        ks_p: gof::ks_p_value(ks, sorted.len()),
        chi_t,
        geometric_p: p,
        cylinder_radius: r0 * (1.0 / p.sqrt() - 1.0),
        chi_g,
    }
}

fn bin(metric: &'static str, lo: f64, hi: f64, count: u64, expected: f64) -> HistBin {
    HistBin {
        metric,
        lo,
        hi,
        count,
        expected,
    }
}
