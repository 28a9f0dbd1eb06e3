//! `raycost check`'s total work: what a whole run asks for, summed over its points, and a warning
//! above a threshold it states.
//!
//! A point does `units` of something (rays, lines, photons, photon-frames), each held against
//! `points` sample points (DETP's discs; 1 for rays and lines). The total is Σ units × points: for
//! DETP the photon–disc pairs that brute force and the path-traced reference's per-point work scale
//! with, and the bound of what every engine does (the sphere cache and disc index test about
//! n_R·∛n_P of them). Above [`WORK_WARNING`] pairs `check` warns: measured on the Cornell box
//! (1.4·10⁴ points × 5·10⁵ photons, 7·10⁹ pairs: 4 s with the sphere cache, 2 cores), a run past it
//! is seconds to minutes with the sphere cache or disc index and hours with brute force; many of
//! the shipped experiments are past it, and say so.

/// The total above which `check` warns (unit × point pairs in one run).
pub const WORK_WARNING: f64 = 1e10;

/// One point's work: units, what they are, and the sample points each meets.
pub type PointWork<'a> = (u64, &'a str, u64);

/// The total work line(s) of a run of `points`, and a warning if any total passes
/// [`WORK_WARNING`].
pub fn total(points: &[PointWork]) -> (Vec<String>, Option<String>) {
    let mut by_unit: Vec<(&str, f64, f64, bool)> = Vec::new();
    for &(units, unit, pts) in points {
        let pairs = units as f64 * pts.max(1) as f64;
        match by_unit.iter_mut().find(|(u, ..)| *u == unit) {
            Some(e) => {
                e.1 += units as f64;
                e.2 += pairs;
                e.3 |= pts > 1;
            }
            None => by_unit.push((unit, units as f64, pairs, pts > 1)),
        }
    }
    let mut lines = Vec::new();
    let mut warning = None;
    for (unit, units, pairs, with_points) in by_unit {
        let what = if with_points {
            format!("{pairs:.3e} {unit} × sample points ({units:.3e} {unit} in all)")
        } else {
            format!("{units:.3e} {unit}")
        };
        lines.push(format!("total work: {what}"));
        if pairs > WORK_WARNING {
            warning = Some(if with_points {
                format!(
                    "the total work, {pairs:.3e} {unit} × point pairs, is above {WORK_WARNING:.0e}: \
                     brute force tests every pair (hours), the sphere cache and disc index about \
                     {unit} × ∛points (seconds to minutes); check detp.engines, reduce the {unit} \
                     or the points, or split the sweep over machines with --shard K/N"
                )
            } else {
                format!(
                    "the total work, {units:.3e} {unit}, is above {WORK_WARNING:.0e}: expect hours; \
                     reduce the {unit}, or split the sweep over machines with --shard K/N"
                )
            });
        }
    }
    (lines, warning)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photons_times_points_is_summed_and_warned_above_the_threshold() {
        // The reported case: 10⁴ points × 5·10⁶ photons.
        let (lines, w) = total(&[(5_000_000, "photons", 10_000)]);
        assert!(
            lines[0].contains("5.000e10 photons × sample points"),
            "{lines:?}"
        );
        assert!(w.expect("a warning").contains("above 1e10"));
        let (lines, w) = total(&[(200_000, "rays", 1), (200_000, "rays", 1)]);
        assert_eq!(lines, ["total work: 4.000e5 rays"]);
        assert!(w.is_none());
    }
}
