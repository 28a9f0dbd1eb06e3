//! Timing engines against each other on a machine whose speed drifts.
//!
//! Why rounds: on the shared 2-core VM this bench was developed on, the same query loop measured
//! from 0.62 to 0.95 M rays/s in consecutive quarter-second runs (steal time < 1 %: neighbours share
//! the L3 and memory bandwidth). Timing one engine for a minute and then the other would fold that
//! drift into their ratio. Instead every round traces a fresh slice of rays with every engine in
//! turn, so each round gives a paired ratio measured under the same conditions; the bench reports
//! the median rate and the median of the per-round ratios, with their range.

use std::time::Instant;

/// Seconds of every round, per contestant (in the order they were given).
#[derive(Clone, Debug, Default)]
pub struct RoundTimes {
    /// `secs[c][r]`: seconds contestant `c` took in round `r`.
    pub secs: Vec<Vec<f64>>,
}

/// Runs `rounds` rounds; in round `r` every contestant `c` is called as `run(c, r)` once, in order,
/// and timed. The contestants keep whatever they computed through `run`'s captures.
pub fn alternate(
    contestants: usize,
    rounds: usize,
    mut run: impl FnMut(usize, usize),
) -> RoundTimes {
    let mut secs = vec![Vec::with_capacity(rounds); contestants];
    for r in 0..rounds {
        for (c, s) in secs.iter_mut().enumerate() {
            let start = Instant::now();
            run(c, r);
            s.push(start.elapsed().as_secs_f64());
        }
    }
    RoundTimes { secs }
}

/// The slowest and the fastest round's rate, `per_round` items in each round of `secs` seconds.
pub fn rate_range(per_round: usize, secs: &[f64]) -> (f64, f64) {
    let slowest = secs.iter().copied().fold(0.0, f64::max);
    let fastest = secs.iter().copied().fold(f64::INFINITY, f64::min);
    (per_round as f64 / slowest, per_round as f64 / fastest)
}

/// The median of `xs` (mean of the two middle values for an even count); NaN if empty.
pub fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Per-round ratios of the rates of `a` and `b` (`b`'s seconds over `a`'s): how many times faster
/// `a` was in each round.
pub fn paired_ratios(times: &RoundTimes, a: usize, b: usize) -> Vec<f64> {
    times.secs[a]
        .iter()
        .zip(&times.secs[b])
        .map(|(ta, tb)| tb / ta)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn rounds_call_every_contestant_once_per_round_in_order() {
        let mut calls = Vec::new();
        let t = alternate(2, 3, |c, r| calls.push((c, r)));
        assert_eq!(calls, [(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)]);
        assert_eq!(t.secs.len(), 2);
        assert!(t
            .secs
            .iter()
            .all(|s| s.len() == 3 && s.iter().all(|&x| x >= 0.0)));
    }

    #[test]
    fn paired_ratios_divide_round_by_round() {
        let t = RoundTimes {
            secs: vec![vec![1.0, 2.0, 0.5], vec![4.0, 5.0, 3.0]],
        };
        assert_eq!(paired_ratios(&t, 0, 1), [4.0, 2.5, 6.0]);
        assert_eq!(median(&paired_ratios(&t, 0, 1)), 4.0);
    }
}
