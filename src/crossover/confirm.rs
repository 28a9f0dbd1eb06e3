//! The head-to-head check of N*: a kind-`detp` run on one scene that, at a few n_P around the
//! predicted N* (e.g. N*/3, N*, 3·N*), runs DETP at its N_ε (`detp.photons`) and path tracing at
//! its paths per point (`detp.path_samples`, on every point: no `detp.path_points`) on the same
//! points. Each method's measured seconds to the target at each n_P (one replica: the main
//! table's sums over `detp.replicas`, as [`super::costs`] reads them; path tracing n_P × K × its
//! row's seconds per path), and where they cross ([`crossing`], log–log between the neighbouring
//! n_P): the measured N* beside the predicted one.

use super::analysis::CrossRow;
use super::costs::run_timings;
use super::input::{keys, Csv};
use super::measured::{crossing, seconds_at, Form, Found};
use super::method::Config;
use crate::error::OutputError;

/// Seconds to the target at each n_P: (n_P, DETP's, path tracing's), increasing in n_P.
pub type Curve = Vec<(f64, f64, f64)>;

/// What the head-to-head run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadToHead {
    /// Path tracing's paths per point.
    pub paths: f64,
    /// Per configuration it timed, the photons it ran at and (n_P, DETP's seconds, path
    /// tracing's seconds), increasing in n_P.
    pub configs: Vec<(Config, f64, Curve)>,
}

impl HeadToHead {
    /// Reads the run's main table.
    pub fn read(main: &Csv) -> Result<HeadToHead, OutputError> {
        let run = run_timings(main)?;
        let paths = main
            .param(keys::PATH_SAMPLES)?
            .into_iter()
            .next()
            .ok_or_else(|| OutputError::new(&main.path, "has no rows"))?;
        let mut configs = Vec::new();
        for c in &run.costs {
            let photons = c.samples.first().map_or(f64::NAN, |s| s.0);
            let curve = seconds_at(&c.samples, photons)
                .into_iter()
                .filter_map(|(p, detp)| {
                    let rows: Vec<f64> = run
                        .path
                        .iter()
                        .filter(|x| x.0 == p && x.1.is_finite() && x.1 > 0.0)
                        .map(|x| x.1)
                        .collect();
                    let spp = rows.iter().sum::<f64>() / rows.len() as f64;
                    (!rows.is_empty()).then_some((p, detp, p * paths * spp))
                })
                .collect();
            configs.push((c.config.clone(), photons, curve));
        }
        Ok(HeadToHead { paths, configs })
    }

    /// The measured crossing of `config` run at about `photons` and `paths` (each within 25 %:
    /// the head-to-head was run for this target) and the seconds it was read from, else None.
    pub fn crossing_for(
        &self,
        config: &Config,
        photons: f64,
        paths: f64,
    ) -> Option<(Found, &Curve)> {
        let near = |a: f64, b: f64| (a / b - 1.0).abs() <= 0.25;
        if !near(self.paths, paths) {
            return None;
        }
        self.configs
            .iter()
            .find(|(c, n, curve)| config.matches(c) && near(*n, photons) && curve.len() >= 2)
            .map(|(_, _, curve)| (crossing(curve, Form::LogLog), curve))
    }

    /// Adds the measured crossing (and the seconds to the target of both methods at each n_P) to
    /// every row the run confirms: a DETP or photon-map row whose N_ε and whose target's path
    /// count it ran at.
    pub fn confirm(&self, rows: &mut [CrossRow]) {
        let paths: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.config.method.is_path_tracing())
            .map(|r| (r.target, r.photons))
            .collect();
        for row in rows.iter_mut() {
            let Some(&(_, k)) = paths.iter().find(|p| p.0 == row.target) else {
                continue;
            };
            if row.config.method.is_path_tracing() || !row.photons.is_finite() {
                continue;
            }
            let Some((found, curve)) = self.crossing_for(&row.config, row.photons, k) else {
                continue;
            };
            row.n_star_head_to_head = found.n_star;
            let seconds: Vec<String> = curve
                .iter()
                .map(|(p, d, t)| format!("n_P {p:.0}: {d:.3} s vs {t:.3} s"))
                .collect();
            let mark = if found.extrapolated {
                ", extrapolated"
            } else {
                ""
            };
            let why = format!(
                "head to head at N = {:.0}, {k:.0} paths ({}){mark}",
                self.configs
                    .iter()
                    .find(|c| row.config.matches(&c.0))
                    .map_or(f64::NAN, |c| c.1),
                seconds.join(", ")
            );
            if row.reason.is_empty() {
                row.reason = why;
            } else {
                row.reason = format!("{}; {why}", row.reason);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// DETP 1 s + 10⁻⁴ s per point, path tracing 4 paths × 5·10⁻⁵ s: equal at 10⁴ points, measured
    /// at 3·10³, 10⁴ and 3·10⁴; a run at other paths or photons does not confirm this target.
    #[test]
    fn the_measured_crossing_is_read_from_the_head_to_head_run() {
        let mut text = String::from(
            "point,detp.direct,detp.edge,detp.disc_radius,detp.replicas,detp.photons,points,trace_s,edge_s,direct_s,build_sphere_cache_s,cost_sphere_cache_s,path_tracing_s_per_path,detp.path_samples\n",
        );
        for (k, p) in [3e3, 1e4, 3e4].into_iter().enumerate() {
            let s = 2.0 * (1.0 + 1e-4 * p);
            text.push_str(&format!(
                "{k},photons,paper,5,2,50000,{p},{s},0,0,0,0,5e-5,4\n"
            ));
        }
        let h = HeadToHead::read(&Csv::from_text(&text)).expect("read");
        assert_eq!(h.paths, 4.0);
        let config = h.configs[0].0.clone();
        let (f, _) = h.crossing_for(&config, 5e4, 4.0).expect("this target");
        assert!(!f.extrapolated, "{f:?}");
        // DETP/PT = (1 + 10⁻⁴x)/(2·10⁻⁴x): 1 at x = 10⁴, measured there.
        assert!((f.n_star / 1e4 - 1.0).abs() < 1e-9, "{f:?}");
        assert!(h.crossing_for(&config, 5e4, 16.0).is_none());
        assert!(h.crossing_for(&config, 2e5, 4.0).is_none());
    }
}
