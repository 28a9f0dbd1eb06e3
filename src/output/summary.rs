//! The terminal summary: every point, each metric measured ± 95 % CI beside its theory.

use std::fmt::Write;

use crate::experiment::PointResult;
use crate::stats::Estimate;

/// Formats the summary table of the finished points.
pub fn render(points: &[(usize, String, PointResult, f64)]) -> String {
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
        "rays/s",
        "wall s"
    );
    for (index, params, r, wall) in points {
        for (i, (metric, e, theory, verdict)) in r.summary.iter().enumerate() {
            let (p, pr, rs, w) = if i == 0 {
                (
                    index.to_string(),
                    params.clone(),
                    format!("{:.3e}", r.rays_per_s),
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

fn measured(e: &Estimate) -> String {
    format!("{:.4} ± {:.4}", e.mean, e.half_width(0.95))
}
