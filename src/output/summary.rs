//! The terminal summary: every point, each metric measured ± 95 % CI beside its theory.

use std::fmt::Write;

use crate::stats::{Estimate, Verdict};

/// A rate for the summary: `per_s` `unit` per second (e.g. rays/s while tracing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate {
    /// Units per second.
    pub per_s: f64,
    /// Of what (plural noun).
    pub unit: &'static str,
}

/// One line of the summary: a metric measured ± CI, its theory, and the verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct SummaryLine {
    /// The metric (a column stem, or a name such as `rays L3`).
    pub metric: String,
    /// What was measured.
    pub measured: Estimate,
    /// The theory as printed (`prediction`, `prediction [lower, upper]`, a law, a ratio's name).
    pub theory: String,
    /// The verdict.
    pub verdict: Verdict,
}

/// One finished point as the summary shows it.
#[derive(Clone, Copy, Debug)]
pub struct SummaryPoint<'a> {
    /// Point index.
    pub index: usize,
    /// Its swept or set parameters, `key=value` joined by spaces.
    pub params: &'a str,
    /// Its metrics.
    pub lines: &'a [SummaryLine],
    /// The point's speed (units per second while working).
    pub rate: Rate,
    /// Wall seconds of the point.
    pub wall: f64,
}

/// Formats the summary table of the finished points.
pub fn render(points: &[SummaryPoint]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:>5}  {:<28} {:<7} {:>26}  {:<30} {:<12} {:>10} {:>8}",
        "point",
        "parameters",
        "metric",
        "measured ± 95% CI",
        "theory (prediction [band])",
        "verdict",
        "speed",
        "wall s"
    );
    for p in points {
        let (index, params, wall) = (p.index, p.params, p.wall);
        for (i, l) in p.lines.iter().enumerate() {
            let (metric, e, theory, verdict) = (&l.metric, &l.measured, &l.theory, &l.verdict);
            let (p, pr, rs, w) = if i == 0 {
                (
                    index.to_string(),
                    params.to_string(),
                    format!("{:.3e} {}/s", p.rate.per_s, p.rate.unit),
                    format!("{wall:.2}"),
                )
            } else {
                (String::new(), String::new(), String::new(), String::new())
            };
            let _ = writeln!(
                out,
                "{p:>5}  {pr:<28} {metric:<7} {:>26}  {theory:<30} {verdict:<12} {rs:>10} {w:>8}",
                measured(e)
            );
        }
    }
    out
}

/// `mean ± half-width` (95 % CI); an exact count (zero half-width) as an integer; no `±` where there
/// is no standard error (one independent sample: one replica, one cluster). Shared with `raycost
/// report`.
pub fn measured(e: &Estimate) -> String {
    let h = e.half_width(0.95);
    let integral = e.mean.fract() == 0.0 && e.mean.abs() < 1e15;
    if integral && h == 0.0 {
        format!("{:.0}", e.mean)
    } else if h.is_finite() {
        format!("{:.4} ± {:.4}", e.mean, h)
    } else {
        format!("{:.4} (no CI: 1 indep. sample)", e.mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_values_read_right() {
        let e = |mean, se, n| Estimate {
            mean,
            se,
            n,
            clusters: n,
        };
        assert_eq!(measured(&e(177_800.0, 0.0, 10)), "177800");
        assert_eq!(
            measured(&e(2.5, f64::NAN, 1)),
            "2.5000 (no CI: 1 indep. sample)"
        );
        // An integral mean without a standard error is not an exact count.
        assert_eq!(
            measured(&e(188.0, f64::NAN, 1)),
            "188.0000 (no CI: 1 indep. sample)"
        );
        assert!(measured(&e(2.5, 0.1, 100)).starts_with("2.5000 ± 0.19"));
    }
}
