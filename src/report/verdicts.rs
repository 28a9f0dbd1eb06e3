//! The claims of one result table, point by point: every metric the run held against theory, read
//! back from `NAME.csv` and judged by the code the terminal summary uses ([`Theory::verdict`],
//! [`crate::output::summary::measured`]), so the page and the terminal cannot disagree on a rule.
//! Verdicts are typed ([`Verdict`]): a verdict cell of a table (`M_band`) is read back with
//! `Verdict::from_str`, which accepts exactly what a run writes, and every verdict is coloured by
//! its [`Tone`], never by the first letters of its text. A claim of `claims.toml` is coloured by
//! its typed `outcome` ([`Outcome`]), or, in a file written before that key existed, by its
//! verdict text read as an outcome or a verdict ([`claim_tone`]).
//!
//! A metric is a `M_mean` column with a `M_theory` beside it (a prediction), or also `M_lower` and
//! `M_upper` (a band) — the columns a judged cell of a declared table writes
//! ([`crate::output::table::Cell::Judged`]). The Student-t
//! interval takes its degrees of freedom from `M_clusters` (the independent clusters behind `M_se`),
//! as the run did. Tables written before that column existed have only `M_n`, which is used instead:
//! exact for per-replica estimates, narrower than the run's where a metric had few clusters and many
//! samples (a grid kind's finite scene with several replicas; a quasi-static run of more than 32
//! frames). So where the run wrote its own band verdict (`M_band`) and it differs, the page shows both.
//!
//! A single measured value with a `_theory` column and no `_mean` (an exact count against a cost
//! model) has no standard error; it is listed with the ratio and no verdict.

use std::fmt;
use std::str::FromStr;

use crate::output::column::{part, Class, POINT};
use crate::output::summary::measured;
pub use crate::stats::verdict::Tone;
use crate::stats::verdict::{Theory, Verdict};
use crate::stats::Estimate;

use super::table::{display, Table};

/// What became of a paper's claim (`outcome` in `claims.toml`, written by `scripts/claims.py`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Outcome {
    /// `holds`: the measurement agrees with the claim.
    Holds,
    /// `holds-in-part`: it agrees with part of it, or under some readings only.
    HoldsInPart,
    /// `differs`: the measurement differs from the paper's number.
    Differs,
    /// `refuted`: the claim is wrong.
    Refuted,
    /// `inconclusive`: the measurement cannot decide.
    Inconclusive,
}

impl Outcome {
    /// Every outcome with its spelling.
    pub const ALL: [(&'static str, Outcome); 5] = [
        ("holds", Outcome::Holds),
        ("holds-in-part", Outcome::HoldsInPart),
        ("differs", Outcome::Differs),
        ("refuted", Outcome::Refuted),
        ("inconclusive", Outcome::Inconclusive),
    ];

    /// What it means for the page's colours.
    pub fn tone(self) -> Tone {
        match self {
            Outcome::Holds => Tone::Agrees,
            Outcome::Differs | Outcome::Refuted => Tone::Disagrees,
            Outcome::HoldsInPart | Outcome::Inconclusive => Tone::Inconclusive,
        }
    }

    /// An outcome written as the words of an older claims file's `verdict` (`holds in part`).
    fn from_words(text: &str) -> Option<Outcome> {
        text.replace(' ', "-").parse().ok()
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = Outcome::ALL
            .iter()
            .find(|(_, o)| o == self)
            .map_or("", |(n, _)| *n);
        f.pad(name)
    }
}

impl FromStr for Outcome {
    type Err = String;
    fn from_str(s: &str) -> Result<Outcome, String> {
        Outcome::ALL
            .iter()
            .find(|(n, _)| *n == s)
            .map(|(_, o)| *o)
            .ok_or_else(|| {
                let allowed: Vec<String> = Outcome::ALL
                    .iter()
                    .map(|(n, _)| format!("\"{n}\""))
                    .collect();
                format!("got \"{s}\", expected one of {}", allowed.join(", "))
            })
    }
}

impl<'de> serde::Deserialize<'de> for Outcome {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        String::deserialize(d)?
            .parse()
            .map_err(serde::de::Error::custom)
    }
}

/// The tone of a claim: its typed `outcome` where the file has one; else its verdict text read as
/// an outcome (`holds`, `holds in part`, …) or as a verdict a run writes (`ok (99% CI)`, `+3.1 SE`);
/// a text that is neither is inconclusive (shown, not coloured as either).
pub fn claim_tone(outcome: Option<Outcome>, verdict: &str) -> Tone {
    outcome
        .or_else(|| Outcome::from_words(verdict))
        .map(Outcome::tone)
        .or_else(|| verdict.parse::<Verdict>().ok().map(|v| v.tone()))
        .unwrap_or(Tone::Inconclusive)
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
                point: t.cell(r, POINT.name).map_or(r.to_string(), str::to_string),
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
            // A theory column, declared as one where the metadata declares classes.
            let theory = |stem: &str| {
                let n = part::name(stem, part::THEORY);
                t.has(&n) && t.class(&n).is_none_or(|c| c == Class::Theory)
            };
            if let Some(stem) = part::stem(h, part::MEAN) {
                theory(stem).then(|| Stem::Estimate(stem.to_string()))
            } else {
                (theory(h) && !t.has(&part::name(h, part::SE))).then(|| Stem::Value(h.clone()))
            }
        })
        .collect()
}

/// The estimate of metric `m` in row `r`: `M_mean`, `M_se`, `M_n`, and as the cluster count
/// `M_clusters` where the table has it, else `M_n` (see the module doc).
pub fn estimate(t: &Table, r: usize, m: &str) -> Estimate {
    let count = |suffix: &str| {
        let x = t.number(r, &part::name(m, suffix));
        (x.is_finite() && x >= 0.0).then_some(x as u64)
    };
    let n = count(part::N).unwrap_or(0);
    Estimate {
        mean: t.number(r, &part::name(m, part::MEAN)),
        se: t.number(r, &part::name(m, part::SE)),
        n,
        clusters: count(part::CLUSTERS).unwrap_or(n),
    }
}

/// The claim of stem `s` in row `r`.
fn claim(t: &Table, r: usize, s: &Stem) -> Claim {
    match s {
        Stem::Estimate(m) => {
            let num = |suffix: &str| t.number(r, &part::name(m, suffix));
            let est = estimate(t, r, m);
            let theory = if t.has(&part::name(m, part::LOWER)) && t.has(&part::name(m, part::UPPER))
            {
                Theory::Band {
                    prediction: num(part::THEORY),
                    lower: num(part::LOWER),
                    upper: num(part::UPPER),
                }
            } else {
                Theory::Prediction(num(part::THEORY))
            };
            let verdict = theory.verdict(&est);
            let mut text = verdict.to_string();
            // The run's own band verdict, read as a verdict (a text that is none is shown too).
            if let Some(run) = t
                .cell(r, &part::name(m, part::BAND))
                .filter(|c| !c.is_empty())
            {
                if run.parse::<Verdict>().ok().as_ref() != Some(&verdict) {
                    text = format!("{text} (the run: {run})");
                }
            }
            Claim {
                metric: m.clone(),
                measured: measured(&est),
                theory: theory.describe(),
                tone: verdict.tone(),
                verdict: text,
            }
        }
        Stem::Value(m) => {
            let (v, th) = (t.number(r, m), t.number(r, &part::name(m, part::THEORY)));
            let verdict = if v.is_finite() && th.is_finite() && th != 0.0 {
                Verdict::OneValue(v / th)
            } else {
                Verdict::NotAvailable
            };
            Claim {
                metric: m.clone(),
                measured: t.cell(r, m).map(display).unwrap_or_default(),
                theory: display(&th.to_string()),
                tone: verdict.tone(),
                verdict: verdict.to_string(),
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
        assert_eq!(p[1].claims[2].tone, Tone::Inconclusive);
        assert_eq!(p[0].claims[2].tone, Tone::NotJudged);
    }

    /// With the metadata's declarations, a column is a metric's theory only if declared as one:
    /// a measured column that happens to end in `_theory` is no prediction; and a header unlike
    /// the declarations is refused, naming the first column that differs.
    #[test]
    fn declarations_decide_what_is_a_theory_and_the_header_must_match_them() {
        use crate::output::column::ColumnInfo;
        let t = Table::parse(CSV).expect("csv");
        let declared: Vec<ColumnInfo> = t
            .header
            .iter()
            .map(|h| ColumnInfo {
                name: h.clone(),
                class: if h == "n_s_theory" {
                    Class::Measured
                } else if h.ends_with("_theory") {
                    Class::Theory
                } else {
                    Class::Measured
                },
                unit: String::new(),
            })
            .collect();
        let path = std::path::Path::new("r/r.csv");
        let d = t
            .clone()
            .declared(path, &declared)
            .expect("the header matches");
        let names: Vec<String> = claims(&d, &[])[0]
            .claims
            .iter()
            .map(|c| c.metric.clone())
            .collect();
        assert_eq!(names, ["n_i", "tests"], "n_s_theory is declared measured");
        let mut other = declared.clone();
        other.swap(2, 3);
        let e = t.declared(path, &other).unwrap_err().to_string();
        assert!(
            e.contains("r/r.csv") && e.contains("column 3 is 'n_i_mean'"),
            "{e}"
        );
    }

    /// A past defect: every claim of the committed report was coloured as a disagreement, because
    /// "holds" does not start with "ok". A claim is coloured by its typed outcome, else by its
    /// verdict read whole, never by a prefix.
    #[test]
    fn claims_are_coloured_by_their_outcome_then_by_their_whole_verdict() {
        assert_eq!(claim_tone(Some(Outcome::Holds), "anything"), Tone::Agrees);
        assert_eq!(claim_tone(Some(Outcome::Refuted), "holds"), Tone::Disagrees);
        assert_eq!(claim_tone(None, "holds"), Tone::Agrees);
        assert_eq!(claim_tone(None, "holds in part"), Tone::Inconclusive);
        assert_eq!(claim_tone(None, "differs"), Tone::Disagrees);
        assert_eq!(claim_tone(None, "ok (99% CI)"), Tone::Agrees);
        assert_eq!(claim_tone(None, "-2.9 SE"), Tone::Disagrees);
        // Free text decides nothing (it used to read as a disagreement, or as agreement for "ok…").
        assert_eq!(
            claim_tone(None, "holds in seconds, not in counted tests"),
            Tone::Inconclusive
        );
        assert_eq!(claim_tone(None, "okay-ish"), Tone::Inconclusive);
        for (name, o) in Outcome::ALL {
            assert_eq!(name.parse::<Outcome>(), Ok(o));
            assert_eq!(o.to_string(), name);
        }
        assert!("holds in part".parse::<Outcome>().is_err());
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
