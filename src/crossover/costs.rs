//! What the n_P sweep (a kind-`detp` run over detp.points × detp.photons × detp.direct ×
//! detp.edge at one d, no reference; with the radius rules beside the fixed d where the fronts
//! have them) says about seconds: per method configuration (the radius rule included: a rule's
//! seconds are its own) the samples
//! (N, n_P, seconds of one replica) and [`CostModel::fit_best_gamma`] over them; path tracing's
//! seconds per path, per row and run ([`run_timings`]).
//!
//! The main table's timings are summed over replicas (`trace_s`, `edge_s`, `direct_s`,
//! `build_{}_s`, `cost_{}_s`: see their declarations), so a sample divides by `detp.replicas`:
//! one replica is one estimate at N photons. A DETP engine pays `trace_s + edge_s + direct_s +
//! build_{e}_s + cost_{e}_s` (the edge remedy is part of its configuration's price; 0 for the
//! paper's method), a photon map `trace_s + direct_s + build_{e}_s + cost_{e}_s`.

use super::fronts::settings;
use super::input::{keys, Csv};
use super::measured::RunTimings;
use super::method::{Config, Method};
use crate::error::OutputError;
use crate::experiment::detp::columns::{BUILD_S, COST_S, DIRECT_S, EDGE_S, POINTS, TRACE_S};
use crate::experiment::detp::estimators::path_tracing::PATH_TRACING_S_PER_PATH;
use crate::stats::fit::CostModel;

/// γ's grid: 0, 0.05, …, 1.
pub fn gammas() -> Vec<f64> {
    (0..=20).map(|k| f64::from(k) / 20.0).collect()
}

/// One configuration's measured seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct CostSamples {
    /// What was timed (photon maps: d and edge `None`).
    pub config: Config,
    /// (N, n_P, seconds of one replica).
    pub samples: Vec<(f64, f64, f64)>,
}

/// A fitted cost model and how well it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedCost {
    /// The model at the best γ.
    pub model: CostModel,
    /// Its largest relative misfit over the samples.
    pub worst_misfit: f64,
}

impl CostSamples {
    /// [`CostModel::fit_best_gamma`] on the 0.05 grid.
    pub fn fit(&self) -> FittedCost {
        let model = CostModel::fit_best_gamma(&self.samples, &gammas());
        FittedCost {
            model,
            worst_misfit: model.worst_relative_misfit(&self.samples),
        }
    }
}

/// The samples of every engine the table has columns for, per configuration.
pub fn cost_samples(main: &Csv) -> Result<Vec<CostSamples>, OutputError> {
    let reps = main.param(keys::REPLICAS)?;
    let photons = main.param(keys::PHOTONS)?;
    let points = main.value(&POINTS)?;
    let trace = main.value(&TRACE_S)?;
    let edge = main.value(&EDGE_S)?;
    let direct = main.value(&DIRECT_S)?;
    let settings = settings(main)?;
    let mut out: Vec<CostSamples> = Vec::new();
    let maps = Method::maps().into_iter().map(|(m, _)| m);
    for method in Method::detp().into_iter().chain(maps) {
        if !main.has_member(&COST_S, method.member()) {
            continue;
        }
        let build = main.member(&BUILD_S, method.member())?;
        let cost = main.member(&COST_S, method.member())?;
        let detp = method.is_detp();
        for (i, set) in settings.iter().enumerate() {
            let once = trace[i] + direct[i] + build[i] + if detp { edge[i] } else { 0.0 };
            let sample = (photons[i], points[i], (once + cost[i]) / reps[i]);
            let config = Config {
                method,
                direct: Some(set.direct.clone()),
                edge: detp.then(|| set.edge.clone()),
                disc_radius: detp.then_some(set.disc_radius),
                radius_rule: detp.then_some(set.rule),
            };
            match out.iter_mut().find(|s| s.config == config) {
                Some(s) => s.samples.push(sample),
                None => out.push(CostSamples {
                    config,
                    samples: vec![sample],
                }),
            }
        }
    }
    Ok(out)
}

/// One run's timings: its seconds per configuration and path tracing's seconds per path on each
/// row (n_P, seconds per path; each row times its own path tracing).
pub fn run_timings(main: &Csv) -> Result<RunTimings, OutputError> {
    let points = main.value(&POINTS)?;
    let spp = main.value(&PATH_TRACING_S_PER_PATH)?;
    Ok(RunTimings {
        costs: cost_samples(main)?,
        path: points.into_iter().zip(spp).collect(),
    })
}

/// Every run's samples per configuration, pooled (the global model's fit).
pub fn pooled(runs: &[RunTimings]) -> Vec<CostSamples> {
    let mut out: Vec<CostSamples> = Vec::new();
    for c in runs.iter().flat_map(|r| &r.costs) {
        match out.iter_mut().find(|o| o.config == c.config) {
            Some(o) => o.samples.extend_from_slice(&c.samples),
            None => out.push(c.clone()),
        }
    }
    out
}

/// The smallest and largest n_P the runs timed (NaN, NaN without any).
pub fn measured_points(runs: &[RunTimings]) -> (f64, f64) {
    points_range(runs.iter().flat_map(|r| &r.costs).flat_map(|c| &c.samples))
}

/// The smallest and largest n_P among `samples` (NaN, NaN without any).
pub fn points_range<'a>(samples: impl IntoIterator<Item = &'a (f64, f64, f64)>) -> (f64, f64) {
    let (lo, hi) = samples
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.1), hi.max(s.1))
        });
    if lo <= hi {
        (lo, hi)
    } else {
        (f64::NAN, f64::NAN)
    }
}

/// Path tracing's seconds per path over the table's rows: median, least, largest, rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTiming {
    /// Median over the rows.
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Rows with a finite value.
    pub rows: usize,
}

/// The median (and spread) of `path_tracing_s_per_path` over the rows of every table.
pub fn path_timing(mains: &[Csv]) -> Result<PathTiming, OutputError> {
    let mut v: Vec<f64> = Vec::new();
    for main in mains {
        v.extend(
            main.value(&PATH_TRACING_S_PER_PATH)?
                .into_iter()
                .filter(|x| x.is_finite() && *x > 0.0),
        );
    }
    if v.is_empty() {
        let path = mains
            .first()
            .map_or_else(Default::default, |m| m.path.clone());
        return Err(OutputError::new(
            &path,
            "has no finite path_tracing_s_per_path: the n_P sweep must run engine path-tracing",
        ));
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Ok(PathTiming {
        median,
        min: v[0],
        max: v[n - 1],
        rows: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seconds exactly of the cost model (per replica, summed over 2 replicas in the table): the
    /// fit recovers it, with γ = ½, and the pieces are added as documented.
    #[test]
    fn samples_are_per_replica_and_the_fit_recovers_the_model() {
        let truth = CostModel {
            fixed: 0.01,
            per_photon: 1e-6,
            per_photon_point: 3e-9,
            per_point: 2e-6,
            gamma: 0.5,
        };
        let mut text = String::from(
            "point,detp.direct,detp.edge,detp.disc_radius,detp.replicas,detp.photons,points,trace_s,edge_s,direct_s,build_sphere_cache_s,cost_sphere_cache_s,build_photon_map_s,cost_photon_map_s,path_tracing_s_per_path\n",
        );
        let mut k = 0;
        for n in [1e4, 4e4] {
            for p in [1e2, 1e3, 1e4, 1e5] {
                // Two replicas: everything doubled; split across the four parts.
                let s = 2.0 * truth.seconds(n, p);
                text.push_str(&format!(
                    "{k},photons,paper,5,2,{n},{p},{},{},{},{},{},1,1,{}\n",
                    0.25 * s,
                    0.25 * s,
                    0.25 * s,
                    0.125 * s,
                    0.125 * s,
                    1e-6 * (k as f64 + 1.0)
                ));
                k += 1;
            }
        }
        let main = Csv::from_text(&text);
        let s = cost_samples(&main).expect("samples");
        assert_eq!(s.len(), 2, "{s:?}");
        assert_eq!(s[0].config.method.label(), "sphere-cache");
        assert_eq!(s[1].config.edge, None, "a photon map ignores the edge mode");
        for &(n, p, sec) in &s[0].samples {
            assert!((sec / truth.seconds(n, p) - 1.0).abs() < 1e-12);
        }
        let fit = s[0].fit();
        assert_eq!(fit.model.gamma, 0.5);
        assert!(fit.worst_misfit < 1e-9, "{fit:?}");
        // The photon map: trace and direct (half of the sum) plus its own 2 s; the edge remedy
        // is not its cost.
        let (n, p, sec) = s[1].samples[0];
        assert!((sec - (0.5 * 2.0 * truth.seconds(n, p) + 2.0) / 2.0).abs() < 1e-12);
        let t = path_timing(std::slice::from_ref(&main)).expect("timing");
        assert_eq!((t.min, t.max, t.rows), (1e-6, 8e-6, 8));
        assert!((t.median - 4.5e-6).abs() < 1e-18);
    }
}
