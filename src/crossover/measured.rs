//! N* from the measured seconds rather than from the global cost model: per run of the n_P sweep,
//! a configuration's seconds at N_ε at each measured n_P (linear in N between the two photon
//! counts that bracket N_ε, or the end pair's line outside them: every part of the cost is affine
//! in N at a fixed n_P) and path tracing's (n_P × paths ×
//! that row's own seconds per path), then where the two curves cross, interpolated between the
//! neighbouring measured n_P in two forms: log–log (log T_DETP − log T_PT linear in log n_P, the
//! headline) and linear (T_DETP − T_PT linear in n_P). A crossing outside the measured n_P is
//! extrapolated from the end pair and marked so.
//!
//! The interval is a percentile bootstrap whose resample draws the fronts' replicas (errors, cv²),
//! the runs of the sweep (when ≥ 2 runs exist: between-run timing variation) and, within each run
//! and n_P, path tracing's per-row timings (so its timing noise is inside the interval); it is then
//! widened to hold the other interpolation form's interval and the global model's N* (the model's
//! form error).

use super::costs::CostSamples;
use super::method::Config;
use crate::sample::rng::Stream;
use crate::stats::fit::ErrorModel;
use crate::stats::time_to_target::{bootstrap_with, Interval, PathTracingCost, ReplicaErrors};

/// One run of the n_P sweep: its seconds per configuration and path tracing's per row.
#[derive(Clone, Debug, PartialEq)]
pub struct RunTimings {
    /// Per configuration, (N, n_P, seconds of one replica).
    pub costs: Vec<CostSamples>,
    /// Path tracing, one per row: (n_P, seconds per path).
    pub path: Vec<(f64, f64)>,
}

/// How the seconds are interpolated between neighbouring measured n_P.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// log T linear in log n_P.
    LogLog,
    /// T linear in n_P.
    Linear,
}

/// Where the measured curves cross.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    /// N* (+∞: never, the curves do not approach each other).
    pub n_star: f64,
    /// N* lies outside the measured n_P (from the end pair's trend).
    pub extrapolated: bool,
}

/// The configuration's seconds at `photons` at each n_P of `samples` (N, n_P, seconds), increasing
/// in n_P: at each n_P the mean seconds per N, interpolated linearly between the two N that
/// bracket `photons` (or the nearest pair's line outside them, no lower than half the nearest
/// pair's smaller seconds; with one N, its seconds).
pub fn seconds_at(samples: &[(f64, f64, f64)], photons: f64) -> Vec<(f64, f64)> {
    let mut points: Vec<f64> = samples.iter().map(|s| s.1).collect();
    points.sort_by(f64::total_cmp);
    points.dedup();
    points
        .into_iter()
        .filter_map(|p| {
            let mut by_n: Vec<(f64, f64, f64)> = Vec::new();
            for s in samples.iter().filter(|s| s.1 == p && s.2 > 0.0) {
                match by_n.iter_mut().find(|b| b.0 == s.0) {
                    Some(b) => (b.1, b.2) = (b.1 + s.2, b.2 + 1.0),
                    None => by_n.push((s.0, s.2, 1.0)),
                }
            }
            by_n.sort_by(|a, b| a.0.total_cmp(&b.0));
            let n: Vec<(f64, f64)> = by_n.iter().map(|b| (b.0, b.1 / b.2)).collect();
            let s = match n.len() {
                0 => return None,
                1 => n[0].1,
                k => {
                    let j = n.partition_point(|x| x.0 < photons).clamp(1, k - 1);
                    let ((x1, y1), (x2, y2)) = (n[j - 1], n[j]);
                    (y1 + (y2 - y1) * (photons - x1) / (x2 - x1)).max(0.5 * y1.min(y2))
                }
            };
            Some((p, s))
        })
        .collect()
}

/// Where DETP's seconds (`curve`: n_P, DETP's, path tracing's, increasing in n_P) fall below path
/// tracing's for good: the last step from "not faster" to "faster" between neighbouring n_P,
/// interpolated in `form`; faster at every n_P: extrapolated below from the first pair; faster at
/// none: extrapolated beyond from the last pair if the gap closes there, else never.
pub fn crossing(curve: &[(f64, f64, f64)], form: Form) -> Found {
    let at = |i: usize, j: usize| -> f64 {
        let ((x1, a1, b1), (x2, a2, b2)) = (curve[i], curve[j]);
        match form {
            Form::LogLog => {
                let (r1, r2) = ((a1 / b1).ln(), (a2 / b2).ln());
                if r1 == r2 {
                    return f64::INFINITY;
                }
                (x1.ln() + (0.0 - r1) * (x2.ln() - x1.ln()) / (r2 - r1)).exp()
            }
            Form::Linear => {
                let (d1, d2) = (a1 - b1, a2 - b2);
                if d1 == d2 {
                    return f64::INFINITY;
                }
                x1 + d1 * (x2 - x1) / (d1 - d2)
            }
        }
    };
    let never = Found {
        n_star: f64::INFINITY,
        extrapolated: false,
    };
    let n = curve.len();
    if n < 2 {
        return never;
    }
    let faster: Vec<bool> = curve.iter().map(|c| c.1 < c.2).collect();
    if let Some(i) = (0..n - 1).rev().find(|&i| !faster[i] && faster[i + 1]) {
        return Found {
            n_star: at(i, i + 1),
            extrapolated: false,
        };
    }
    if faster[n - 1] {
        // Faster at every n_P measured: the crossing is below them.
        let x = at(0, 1);
        return Found {
            n_star: if x.is_finite() && x > 0.0 && x <= curve[0].0 {
                x
            } else {
                0.0
            },
            extrapolated: true,
        };
    }
    // Faster at none: beyond the last n_P, if the gap closes there.
    let x = at(n - 2, n - 1);
    if x.is_finite() && x > curve[n - 1].0 {
        Found {
            n_star: x,
            extrapolated: true,
        }
    } else {
        never
    }
}

/// What one configuration's measured N* needs.
pub struct MeasuredInputs<'a> {
    /// The configuration.
    pub config: &'a Config,
    /// Its error model (its radius rule's).
    pub model: ErrorModel,
    /// Photon counts of the error fit.
    pub photons: &'a [f64],
    /// The fronts' replicas.
    pub replicas: &'a [ReplicaErrors],
    /// The sweep's runs.
    pub runs: &'a [RunTimings],
    /// Target relative RMSE.
    pub target: f64,
}

/// The seconds curves (n_P, DETP's, path tracing's) at `target` for the replicas `pick` (errors),
/// the runs `runs` (averaged at each n_P) and, if `rng`, path tracing's rows resampled within each
/// run and n_P. None where the target is out of reach or no run timed the configuration.
fn curve(
    m: &MeasuredInputs,
    pick: &[usize],
    runs: &[usize],
    mut rng: Option<&mut Stream>,
) -> Option<Vec<(f64, f64, f64)>> {
    let k = pick.len() as f64;
    let mse: Vec<f64> = (0..m.photons.len())
        .map(|j| pick.iter().map(|&r| m.replicas[r].detp_mse[j]).sum::<f64>() / k)
        .collect();
    let n_eps = m.model.fit(m.photons, &mse).photons_for(m.target)?;
    let cv2 = pick.iter().map(|&r| m.replicas[r].pt_cv2).sum::<f64>() / k;
    let paths = PathTracingCost {
        cv: cv2.max(0.0).sqrt(),
        seconds_per_path: 0.0,
    }
    .paths_for(m.target) as f64;
    let mut sum: Vec<(f64, f64, f64, f64)> = Vec::new();
    for &r in runs {
        let run = &m.runs[r];
        let Some(cost) = run.costs.iter().find(|c| m.config.matches(&c.config)) else {
            continue;
        };
        for (p, detp) in seconds_at(&cost.samples, n_eps) {
            let rows: Vec<f64> = run
                .path
                .iter()
                .filter(|x| x.0 == p && x.1.is_finite() && x.1 > 0.0)
                .map(|x| x.1)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let spp = match rng.as_deref_mut() {
                Some(rng) => {
                    (0..rows.len())
                        .map(|_| rows[rand::Rng::gen_range(rng, 0..rows.len())])
                        .sum::<f64>()
                        / rows.len() as f64
                }
                None => rows.iter().sum::<f64>() / rows.len() as f64,
            };
            let pt = p * paths * spp;
            match sum.iter_mut().find(|s| s.0 == p) {
                Some(s) => (s.1, s.2, s.3) = (s.1 + detp, s.2 + pt, s.3 + 1.0),
                None => sum.push((p, detp, pt, 1.0)),
            }
        }
    }
    sum.sort_by(|a, b| a.0.total_cmp(&b.0));
    (sum.len() >= 2).then(|| sum.iter().map(|s| (s.0, s.1 / s.3, s.2 / s.3)).collect())
}

/// The measured N* of one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredStar {
    /// Log–log interpolation (the headline).
    pub loglog: Found,
    /// Linear interpolation.
    pub linear: Found,
    /// The log–log form's bootstrap interval.
    pub loglog_ci: Interval,
    /// The linear form's.
    pub linear_ci: Interval,
    /// The measured n_P range (smallest, largest).
    pub range: (f64, f64),
}

/// N* from the measured seconds in both forms, with their bootstrap intervals (see the module
/// doc): `draws` resamples from the stream of `seed`. None where no run timed the configuration at
/// ≥ 2 n_P or the target is out of reach.
pub fn measured_star(
    m: &MeasuredInputs,
    draws: usize,
    level: f64,
    seed: u64,
) -> Option<MeasuredStar> {
    let all: Vec<usize> = (0..m.replicas.len()).collect();
    // The runs that timed this configuration (runs may add configurations of their own, e.g. a
    // radius rule run apart): the bootstrap resamples these.
    let runs: Vec<usize> = (0..m.runs.len())
        .filter(|&r| m.runs[r].costs.iter().any(|c| m.config.matches(&c.config)))
        .collect();
    let c = curve(m, &all, &runs, None)?;
    let range = (c[0].0, c[c.len() - 1].0);
    let ci = |form: Form| {
        bootstrap_with(m.replicas.len(), draws, level, seed, |pick, rng| {
            let Some(rng) = rng else {
                return crossing(&c, form).n_star;
            };
            let runs: Vec<usize> = if runs.len() >= 2 {
                (0..runs.len())
                    .map(|_| runs[rand::Rng::gen_range(rng, 0..runs.len())])
                    .collect()
            } else {
                runs.clone()
            };
            curve(m, pick, &runs, Some(rng)).map_or(f64::INFINITY, |c| crossing(&c, form).n_star)
        })
    };
    Some(MeasuredStar {
        loglog: crossing(&c, Form::LogLog),
        linear: crossing(&c, Form::Linear),
        loglog_ci: ci(Form::LogLog),
        linear_ci: ci(Form::Linear),
        range,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crossover::method::Method;

    /// A synthetic sweep: DETP takes a + b·n_P seconds (a = 1 s at N = 10⁵, twice at 2·10⁵),
    /// path tracing n_P·paths·t: with cv² = 1 and a 10 % target, 100 paths per point.
    fn sweep(spp: &[f64], n_p: &[f64]) -> RunTimings {
        let config = Config {
            method: Method::named("sphere-cache").unwrap(),
            direct: Some("photons".into()),
            edge: Some("paper".into()),
            disc_radius: Some(5.0),
            radius_rule: Some(Default::default()),
        };
        let mut samples = Vec::new();
        let mut path = Vec::new();
        for &p in n_p {
            for n in [1e5, 2e5] {
                samples.push((n, p, n / 1e5 + 1e-5 * p));
            }
            for &t in spp {
                path.push((p, t));
            }
        }
        RunTimings {
            costs: vec![CostSamples { config, samples }],
            path,
        }
    }

    fn replicas(n: usize) -> Vec<ReplicaErrors> {
        // MSE exactly 1/N·10³ (B = 0): at a 10 % target N_ε = 10⁵.
        (0..n)
            .map(|_| ReplicaErrors {
                detp_mse: vec![1e3 / 1e4, 1e3 / 1e5, 1e3 / 1e6],
                pt_cv2: 1.0,
            })
            .collect()
    }

    /// Both forms find the crossing of two straight lines between the measured n_P it lies
    /// between; linear exactly (1 + 10⁻⁵·x = 10⁻⁴·x at x = 1/(9·10⁻⁵)), log–log close to it; not
    /// extrapolated.
    #[test]
    fn a_known_crossing_is_found_between_its_neighbours() {
        let run = sweep(&[1e-6], &[1e3, 4e3, 1.6e4, 6.4e4]);
        let reps = replicas(3);
        let config = run.costs[0].config.clone();
        let m = MeasuredInputs {
            config: &config,
            model: ErrorModel::Floor,
            photons: &[1e4, 1e5, 1e6],
            replicas: &reps,
            runs: std::slice::from_ref(&run),
            target: 0.1,
        };
        let s = measured_star(&m, 200, 0.95, 1).expect("measured");
        let truth = 1.0 / 9e-5;
        assert!((s.linear.n_star / truth - 1.0).abs() < 1e-9, "{s:?}");
        assert!(s.loglog.n_star > 4e3 && s.loglog.n_star < 1.6e4, "{s:?}");
        assert!((s.loglog.n_star / truth - 1.0).abs() < 0.1, "{s:?}");
        assert!(!s.loglog.extrapolated && !s.linear.extrapolated);
        assert_eq!(s.range, (1e3, 6.4e4));
        // Nothing varies: the intervals collapse on the estimates.
        assert!(
            (s.linear_ci.lo / s.linear.n_star - 1.0).abs() < 1e-9,
            "{s:?}"
        );
        assert!(
            (s.linear_ci.hi / s.linear.n_star - 1.0).abs() < 1e-9,
            "{s:?}"
        );
    }

    /// A sweep that stops before the crossing: N* from the last pair's trend, marked extrapolated;
    /// one that starts after it: marked too; one whose gap widens: never.
    #[test]
    fn a_crossing_outside_the_sweep_is_marked_extrapolated() {
        let beyond = [(1e2, 2.0, 1.0), (1e3, 3.0, 2.0)];
        // D = 1 at both: never in the linear form; the ratio closes (2 → 1.5): extrapolated.
        let f = crossing(&beyond, Form::Linear);
        assert!(f.n_star == f64::INFINITY && !f.extrapolated, "{f:?}");
        let f = crossing(&beyond, Form::LogLog);
        assert!(
            f.extrapolated && f.n_star > 1e3 && f.n_star.is_finite(),
            "{f:?}"
        );
        let closing = [(1e2, 2.0, 1.0), (1e3, 3.0, 2.5)];
        let f = crossing(&closing, Form::Linear);
        // D falls 1 → 0.5 over 900: zero at 1000 + 900.
        assert!(f.extrapolated && (f.n_star - 1900.0).abs() < 1e-9, "{f:?}");
        let f = crossing(&closing, Form::LogLog);
        assert!(f.extrapolated && f.n_star > 1e3, "{f:?}");
        let below = [(1e3, 1.0, 2.0), (1e4, 1.0, 20.0)];
        let f = crossing(&below, Form::LogLog);
        assert!(f.extrapolated && f.n_star < 1e3, "{f:?}");
        let inside = [(1e2, 2.0, 1.0), (1e3, 1.0, 2.0)];
        assert!(!crossing(&inside, Form::Linear).extrapolated);
    }

    /// DETP's seconds at N_ε between the photon counts: exact on seconds affine in N.
    #[test]
    fn seconds_are_interpolated_linearly_in_photons() {
        // 1 + 10⁻⁵·N at n_P = 10, 2 + 2·10⁻⁵·N at n_P = 20.
        let s = [
            (1e5, 10.0, 2.0),
            (4e5, 10.0, 5.0),
            (1e5, 20.0, 4.0),
            (4e5, 20.0, 10.0),
        ];
        let at = seconds_at(&s, 2e5);
        assert_eq!(at.len(), 2);
        assert!(
            (at[0].1 - 3.0).abs() < 1e-12 && (at[1].1 - 6.0).abs() < 1e-12,
            "{at:?}"
        );
        // Beyond the pair: its line.
        assert!((seconds_at(&s, 8e5)[0].1 - 9.0).abs() < 1e-9);
    }

    /// Path tracing's per-row timings and the runs are resampled: the interval is wider when they
    /// vary than when they do not, and holds the estimate.
    #[test]
    fn varying_timings_widen_the_interval() {
        let n_p = [1e3, 4e3, 1.6e4, 6.4e4];
        let reps = replicas(3);
        let steady = sweep(&[1e-6], &n_p);
        let config = steady.costs[0].config.clone();
        let width = |runs: &[RunTimings]| {
            let m = MeasuredInputs {
                config: &config,
                model: ErrorModel::Floor,
                photons: &[1e4, 1e5, 1e6],
                replicas: &reps,
                runs,
                target: 0.1,
            };
            let s = measured_star(&m, 400, 0.95, 7).expect("measured");
            assert!(s.loglog_ci.lo <= s.loglog.n_star && s.loglog.n_star <= s.loglog_ci.hi);
            s.loglog_ci.hi / s.loglog_ci.lo
        };
        let one = width(std::slice::from_ref(&steady));
        assert!((one - 1.0).abs() < 1e-9, "{one}");
        // Rows of one run vary.
        let noisy = sweep(&[0.6e-6, 1e-6, 1.4e-6], &n_p);
        let rows = width(std::slice::from_ref(&noisy));
        assert!(rows > 1.05, "{rows}");
        // Runs vary (each steady within).
        let runs = [
            sweep(&[0.8e-6], &n_p),
            sweep(&[1e-6], &n_p),
            sweep(&[1.2e-6], &n_p),
        ];
        let between = width(&runs);
        assert!(between > 1.05, "{between}");
    }
}
