//! Metrics declared once: a kind names each measured metric, its estimate and its theory, and the
//! row columns (`M_mean, M_se, M_n`, `M_theory`, and for a band `M_lower, M_upper, M_band`) and the
//! terminal summary line (measured ± CI, theory, verdict) follow from that one declaration, so every
//! kind writes them alike.

use crate::output::column::{Class, Column, Shape};
use crate::output::row::{Row, Value};
use crate::stats::Estimate;

pub use crate::output::summary::SummaryLine;

/// What a metric is held against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Theory {
    /// A prediction: the verdict is "ok" within the 99 % CI, else the distance in SE.
    Prediction(f64),
    /// A prediction and a band `[lower, upper]`: the verdict says where the 95 % CI falls.
    Band {
        /// The prediction.
        prediction: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
}

impl Theory {
    /// The verdict of `est` against this theory: [`z_verdict`] for a prediction, [`band_verdict`]
    /// for a band. The one place both the terminal summary and `raycost report` take it from.
    pub fn verdict(&self, est: &Estimate) -> String {
        match *self {
            Theory::Prediction(p) => z_verdict(est, p),
            Theory::Band { lower, upper, .. } => band_verdict(est, lower, upper).into(),
        }
    }

    /// The theory as the summary prints it: `prediction` or `prediction [lower, upper]`.
    pub fn describe(&self) -> String {
        match *self {
            Theory::Prediction(p) => format!("{p:.4}"),
            Theory::Band {
                prediction,
                lower,
                upper,
            } => format!("{prediction:.3} [{lower:.3}, {upper:.3}]"),
        }
    }
}

/// A measured metric and its theory: a declared estimate column ([`Shape::EstimateVsPrediction`] or
/// [`Shape::EstimateVsBand`]) with its value.
#[derive(Clone, Debug, PartialEq)]
pub struct Metric {
    column: &'static Column,
    stem: String,
    est: Estimate,
    theory: Theory,
}

impl Metric {
    /// Metric `column` with its estimate and theory.
    pub fn new(column: &'static Column, est: Estimate, theory: Theory) -> Self {
        Self::member(column, "", est, theory)
    }

    /// Member `part` of the metric family `column` (`rays_L{}` → `rays_L3`).
    pub fn member(column: &'static Column, part: &str, est: Estimate, theory: Theory) -> Self {
        debug_assert!(
            matches!(
                (column.shape, theory),
                (Shape::EstimateVsPrediction, Theory::Prediction(_))
                    | (Shape::EstimateVsBand, Theory::Band { .. })
            ),
            "{}: the theory does not match the declared shape",
            column.name
        );
        Self {
            column,
            stem: column.member(part),
            est,
            theory,
        }
    }

    /// The verdict against the theory.
    pub fn verdict(&self) -> String {
        self.theory.verdict(&self.est)
    }

    /// Appends its columns to `row` and its line to `summary`.
    pub fn write(&self, row: &mut Row, summary: &mut Vec<SummaryLine>) {
        let m = &self.stem;
        let unit = self.column.unit;
        row.estimate_cells(self.column, m, &self.est);
        match self.theory {
            Theory::Prediction(p) => {
                row.derived_cell(m, "_theory", Class::Theory, unit, Value::F(p));
            }
            Theory::Band {
                prediction,
                lower,
                upper,
            } => {
                row.derived_cell(m, "_theory", Class::Theory, unit, Value::F(prediction))
                    .derived_cell(m, "_lower", Class::Theory, unit, Value::F(lower))
                    .derived_cell(m, "_upper", Class::Theory, unit, Value::F(upper))
                    .derived_cell(m, "_band", Class::Check, "1", Value::S(self.verdict()));
            }
        }
        summary.push((m.clone(), self.est, self.theory.describe(), self.verdict()));
    }
}

/// Where a measured mean falls against a band `[lower, upper]`, judged by its 95 % CI: `below`,
/// `inside` or `above`; `n/a` when the estimate has no standard error (a single cluster), because
/// then nothing can be said about where the true mean lies.
pub fn band_verdict(e: &Estimate, lower: f64, upper: f64) -> &'static str {
    let h = e.half_width(0.95);
    if !h.is_finite() || !e.mean.is_finite() {
        "n/a"
    } else if e.mean + h < lower {
        "below"
    } else if e.mean - h > upper {
        "above"
    } else {
        "inside"
    }
}

/// The verdict against a law the experiment documents as not applying (`why`: e.g. photons of a
/// scene against the uniform-line law): the ratio measured/law, marked as not judged, never a
/// distance in SE.
pub fn not_judged(e: &Estimate, law: f64, why: &str) -> String {
    if e.mean.is_finite() && law.is_finite() && law != 0.0 {
        format!("×{:.2} ({why}: not judged)", e.mean / law)
    } else {
        format!("({why}: not judged)")
    }
}

/// "ok" when the measurement is within its 99 % CI (Student-t, clusters − 1 dof) of a prediction,
/// else how many SE away; `n/a` without a standard error or a finite prediction.
pub fn z_verdict(e: &Estimate, theory: f64) -> String {
    if !theory.is_finite() || !e.mean.is_finite() {
        return "n/a".into();
    }
    if e.se == 0.0 {
        return if e.mean == theory {
            "ok (exact)".into()
        } else {
            "differs (SE 0)".into()
        };
    }
    let h = e.half_width(0.99);
    if !h.is_finite() {
        return "n/a".into();
    }
    let z = (e.mean - theory) / e.se;
    if (e.mean - theory).abs() <= h {
        "ok (99% CI)".into()
    } else {
        format!("{z:+.1} SE")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn est(mean: f64, se: f64, clusters: u64) -> Estimate {
        Estimate {
            mean,
            se,
            n: 1000,
            clusters,
        }
    }

    #[test]
    fn band_verdicts_use_the_confidence_interval_and_refuse_without_one() {
        assert_eq!(band_verdict(&est(5.0, 0.1, 100), 1.0, 10.0), "inside");
        assert_eq!(band_verdict(&est(10.1, 0.1, 100), 1.0, 10.0), "inside"); // CI reaches 10
        assert_eq!(band_verdict(&est(11.0, 0.1, 100), 1.0, 10.0), "above");
        assert_eq!(band_verdict(&est(0.5, 0.1, 100), 1.0, 10.0), "below");
        assert_eq!(band_verdict(&est(4.5, f64::NAN, 1), 1.0, 2.7), "n/a");
    }

    #[test]
    fn a_law_that_does_not_apply_gives_a_ratio_not_a_verdict() {
        let v = not_judged(&est(120.0, 0.1, 100), 100.0, "photons");
        assert_eq!(v, "×1.20 (photons: not judged)");
        assert!(!v.contains("SE") && !v.contains("ok"));
        assert_eq!(
            not_judged(&est(1.0, 0.1, 100), 0.0, "photons"),
            "(photons: not judged)"
        );
    }

    #[test]
    fn z_verdicts_widen_with_few_clusters() {
        // 3 SE away: outside a 99 % normal CI, inside the t₃ one (5.84 SE).
        assert_eq!(z_verdict(&est(3.0, 1.0, 1000), 0.0), "+3.0 SE");
        assert_eq!(z_verdict(&est(3.0, 1.0, 4), 0.0), "ok (99% CI)");
        assert_eq!(z_verdict(&est(1.0, 0.0, 10), 1.0), "ok (exact)");
        assert_eq!(z_verdict(&est(1.0, f64::NAN, 1), 1.0), "n/a");
    }

    #[test]
    fn a_declared_band_metric_writes_its_columns_and_summary_line() {
        let (mut row, mut summary) = (Row::default(), Vec::new());
        static N_I: Column = Column::vs_band("n_i", "tests", "ray-sphere tests");
        Metric::new(
            &N_I,
            est(5.0, 0.1, 100),
            Theory::Band {
                prediction: 5.1,
                lower: 1.0,
                upper: 10.0,
            },
        )
        .write(&mut row, &mut summary);
        let cols: Vec<&str> = row.0.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            cols,
            [
                "n_i_mean",
                "n_i_se",
                "n_i_n",
                "n_i_clusters",
                "n_i_theory",
                "n_i_lower",
                "n_i_upper",
                "n_i_band"
            ]
        );
        assert_eq!(summary[0].3, "inside");
        assert_eq!(summary[0].2, "5.100 [1.000, 10.000]");
    }
}
