//! The claims of one result table, point by point: every metric the run held against theory, read
//! back from `NAME.csv` and judged by the code the terminal summary uses ([`Theory::verdict`],
//! [`crate::output::summary::measured`]), so the page and the terminal cannot disagree on a rule.
//!
//! A metric is a `M_mean` column with a `M_theory` beside it (a prediction), or also `M_lower` and
//! `M_upper` (a band) — the columns [`crate::experiment::metric::Metric`] writes. The Student-t
//! interval takes its degrees of freedom from `M_clusters` (the independent clusters behind `M_se`),
//! as the run did. Tables written before that column existed have only `M_n`, which is used instead:
//! exact for per-replica estimates, narrower than the run's where a metric had few clusters and many
//! samples (a grid kind's finite scene with several replicas; a quasi-static run of more than 32
//! frames). So where the run wrote its own band verdict (`M_band`) and it differs, the page shows both.
//!
//! A single measured value with a `_theory` column and no `_mean` (an exact count against a cost
//! model) has no standard error; it is listed with the ratio and no verdict.

use crate::experiment::metric::Theory;
use crate::output::summary::measured;
use crate::stats::Estimate;

use super::table::{display, Table};

/// How a verdict reads, for colour only (the text is the verdict).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tone {
    /// Agrees: `ok …`, `inside`.
    Agrees,
    /// Disagrees: `±k SE`, `above`, `below`, `differs …`.
    Disagrees,
    /// No verdict possible: `n/a`, or a single value against a model.
    Neutral,
}

impl Tone {
    /// The tone of a verdict text.
    pub fn of(verdict: &str) -> Tone {
        if verdict.starts_with("ok") || verdict.starts_with("inside") {
            Tone::Agrees
        } else if verdict.starts_with("n/a") || verdict.starts_with("no verdict") {
            Tone::Neutral
        } else {
            Tone::Disagrees
        }
    }
}

/// One metric of one point.
#[derive(Clone, Debug, PartialEq)]
pub struct Claim {
    /// Metric name (the column stem).
    pub metric: String,
    /// Measured ± 95 % CI, as the summary prints it.
    pub measured: String,
    /// The theory, as the summary prints it.
    pub theory: String,
    /// The verdict.
    pub verdict: String,
    /// Its tone.
    pub tone: Tone,
}

/// The claims of one point (one CSV row).
#[derive(Clone, Debug, PartialEq)]
pub struct PointClaims {
    /// The `point` cell (or the row number).
    pub point: String,
    /// Its swept parameters, `key=value` joined by spaces.
    pub params: String,
    /// Its metrics, in column order.
    pub claims: Vec<Claim>,
}

/// The claims of every row of `t`; `sweep_keys` name the parameters shown for each point.
pub fn claims(t: &Table, sweep_keys: &[String]) -> Vec<PointClaims> {
    let stems = metric_stems(t);
    (0..t.rows.len())
        .map(|r| {
            let params = sweep_keys
                .iter()
                .filter_map(|k| t.cell(r, k).map(|v| format!("{k}={}", display(v))))
                .collect::<Vec<_>>()
                .join(" ");
            let claims = stems.iter().map(|s| claim(t, r, s)).collect();
            PointClaims {
                point: t.cell(r, "point").map_or(r.to_string(), str::to_string),
                params,
                claims,
            }
        })
        .collect()
}

/// What a column stem holds.
enum Stem {
    /// `M_mean` + `M_theory` (+ `M_lower`, `M_upper`).
    Estimate(String),
    /// `M` + `M_theory`, no `M_mean`.
    Value(String),
}

/// The metric stems of `t`, in column order.
fn metric_stems(t: &Table) -> Vec<Stem> {
    t.header
        .iter()
        .filter_map(|h| {
            if let Some(stem) = h.strip_suffix("_mean") {
                t.has(&format!("{stem}_theory"))
                    .then(|| Stem::Estimate(stem.to_string()))
            } else {
                (t.has(&format!("{h}_theory")) && !t.has(&format!("{h}_se")))
                    .then(|| Stem::Value(h.clone()))
            }
        })
        .collect()
}

/// The estimate of metric `m` in row `r`: `M_mean`, `M_se`, `M_n`, and as the cluster count
/// `M_clusters` where the table has it, else `M_n` (see the module doc).
pub fn estimate(t: &Table, r: usize, m: &str) -> Estimate {
    let count = |suffix: &str| {
        let x = t.number(r, &format!("{m}{suffix}"));
        (x.is_finite() && x >= 0.0).then_some(x as u64)
    };
    let n = count("_n").unwrap_or(0);
    Estimate {
        mean: t.number(r, &format!("{m}_mean")),
        se: t.number(r, &format!("{m}_se")),
        n,
        clusters: count("_clusters").unwrap_or(n),
    }
}

/// The claim of stem `s` in row `r`.
fn claim(t: &Table, r: usize, s: &Stem) -> Claim {
    match s {
        Stem::Estimate(m) => {
            let num = |suffix: &str| t.number(r, &format!("{m}{suffix}"));
            let est = estimate(t, r, m);
            let theory = if t.has(&format!("{m}_lower")) && t.has(&format!("{m}_upper")) {
                Theory::Band {
                    prediction: num("_theory"),
                    lower: num("_lower"),
                    upper: num("_upper"),
                }
            } else {
                Theory::Prediction(num("_theory"))
            };
            let mut verdict = theory.verdict(&est);
            if let Some(run) = t.cell(r, &format!("{m}_band")) {
                if !run.is_empty() && run != verdict {
                    verdict = format!("{verdict} (the run: {run})");
                }
            }
            Claim {
                metric: m.clone(),
                measured: measured(&est),
                theory: theory.describe(),
                tone: Tone::of(&verdict),
                verdict,
            }
        }
        Stem::Value(m) => {
            let (v, th) = (t.number(r, m), t.number(r, &format!("{m}_theory")));
            let verdict = if v.is_finite() && th.is_finite() && th != 0.0 {
                format!("no verdict (one value; measured/theory = {:.3})", v / th)
            } else {
                "n/a".to_string()
            };
            Claim {
                metric: m.clone(),
                measured: t.cell(r, m).map(display).unwrap_or_default(),
                theory: display(&th.to_string()),
                tone: Tone::of(&verdict),
                verdict,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str =
        "point,grid.cell_width,n_i_mean,n_i_se,n_i_n,n_i_theory,n_i_lower,n_i_upper,n_i_band,\
n_s_mean,n_s_se,n_s_n,n_s_theory,trace_s,tests,tests_theory\n\
0,0.25,14.28,0.02,400000,13.9,1.1,28.4,inside,190.6,0.3,400000,190.98,0.8,1000,800\n\
1,0.5,7.19,0.01,400000,5.27,1.0,6.42,above,21.0,0.03,400000,21.22,0.2,10,0\n";

    #[test]
    fn every_metric_with_a_theory_is_judged_like_the_summary() {
        let t = Table::parse(CSV).expect("csv");
        let p = claims(&t, &["grid.cell_width".to_string()]);
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].params, "grid.cell_width=0.2500");
        let names: Vec<&str> = p[0].claims.iter().map(|c| c.metric.as_str()).collect();
        assert_eq!(names, ["n_i", "n_s", "tests"]);
        let c = &p[0].claims[0];
        assert_eq!(c.theory, "13.900 [1.100, 28.400]");
        assert_eq!((c.verdict.as_str(), c.tone), ("inside", Tone::Agrees));
        // 190.6 vs 190.98 is 1.3 SE: inside the 99 % CI.
        assert_eq!(p[0].claims[1].verdict, "ok (99% CI)");
        assert!(p[0].claims[1].measured.starts_with("190.6000 ± 0.58"));
        // 21.0 vs 21.22 is −7.3 SE.
        assert_eq!(p[1].claims[1].verdict, "-7.3 SE");
        assert_eq!(p[1].claims[1].tone, Tone::Disagrees);
        assert_eq!(p[1].claims[0].verdict, "above");
        assert_eq!(
            p[0].claims[2].verdict,
            "no verdict (one value; measured/theory = 1.250)"
        );
        assert_eq!(p[1].claims[2].verdict, "n/a", "theory 0: no ratio");
    }

    #[test]
    fn a_cluster_count_column_widens_the_interval_like_the_run() {
        // 2.9 SE: outside the normal 99 % CI (2.58), inside Student-t with 15 dof (2.95).
        let csv = "point,m_mean,m_se,m_n,m_theory\n0,2.9,1.0,400,0.0\n";
        let t = Table::parse(csv).expect("csv");
        assert_eq!(claims(&t, &[])[0].claims[0].verdict, "+2.9 SE");
        let with = csv
            .replace("m_theory\n", "m_theory,m_clusters\n")
            .replace(",0.0\n", ",0.0,16\n");
        let t = Table::parse(&with).expect("csv");
        assert_eq!(claims(&t, &[])[0].claims[0].verdict, "ok (99% CI)");
    }

    #[test]
    fn a_band_verdict_that_differs_from_the_runs_shows_both() {
        let csv = CSV.replace(",inside,", ",below,");
        let t = Table::parse(&csv).expect("csv");
        let p = claims(&t, &[]);
        assert_eq!(p[0].params, "");
        assert_eq!(p[0].claims[0].verdict, "inside (the run: below)");
    }
}
