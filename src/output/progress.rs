//! Progress on stderr: a bar on a terminal, periodic plain log lines otherwise (batch jobs, Slurm),
//! nothing with `--quiet`. Advanced per chunk of batches, never per ray.
//!
//! A log line reads `progress: 3/8 points, 1200000/3200000 rays (37.5 %), 2.41e5 rays/s, eta 8 s,
//! elapsed 5 s`: one when the run starts, then at most one per interval (10 s), and a last one when it
//! ends.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// State of the log-line display.
#[derive(Debug)]
pub struct LogState {
    /// What is counted (plural noun: rays, photons, photon-frames).
    unit: &'static str,
    /// Units done.
    rays: u64,
    /// Points done.
    points_done: usize,
    /// Points to do.
    points: usize,
    /// When the run started.
    start: Instant,
    /// When the last line was printed.
    last: Instant,
}

/// How progress is shown.
pub enum Progress {
    /// Nothing.
    Hidden,
    /// An indicatif bar (stderr is a terminal).
    Bar(ProgressBar),
    /// A log line at most every `every` (stderr is a file or pipe).
    Log {
        /// Total rays.
        total: u64,
        /// Counters and clocks.
        state: Mutex<LogState>,
        /// Interval between lines.
        every: Duration,
    },
}

/// Builds the progress display for `total` units of work (`unit`: rays, photons, …) over `points`
/// points.
pub fn progress(total: u64, unit: &'static str, points: usize, quiet: bool) -> Progress {
    if quiet {
        return Progress::Hidden;
    }
    if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} {prefix} · {per_sec} · eta {eta} · {msg}")
                .expect("a valid template")
                .progress_chars("█▉ "),
        );
        bar.set_prefix(unit);
        bar.set_message(format!("0/{points} points"));
        Progress::Bar(bar)
    } else {
        let now = Instant::now();
        let state = LogState {
            unit,
            rays: 0,
            points_done: 0,
            points,
            start: now,
            last: now,
        };
        eprintln!("{}", log_line(&state, total, Duration::ZERO));
        Progress::Log {
            total,
            state: Mutex::new(state),
            every: Duration::from_secs(10),
        }
    }
}

/// One log line: points done / total, rays done / total, rays/s and the ETA (from the ray rate).
pub fn log_line(s: &LogState, total: u64, elapsed: Duration) -> String {
    let el = elapsed.as_secs_f64();
    let pct = if total == 0 {
        100.0
    } else {
        100.0 * s.rays.min(total) as f64 / total as f64
    };
    let (rate, eta) = if s.rays == 0 || el <= 0.0 {
        (format!("- {}/s", s.unit), "eta -".to_string())
    } else {
        let rate = s.rays as f64 / el;
        (
            format!("{rate:.3e} {}/s", s.unit),
            format!("eta {:.0} s", total.saturating_sub(s.rays) as f64 / rate),
        )
    };
    format!(
        "progress: {}/{} points, {}/{} {} ({pct:.1} %), {rate}, {eta}, elapsed {el:.0} s",
        s.points_done, s.points, s.rays, total, s.unit
    )
}

impl Progress {
    /// Counts `n` more rays done.
    pub fn inc(&self, n: u64) {
        match self {
            Progress::Hidden => {}
            Progress::Bar(b) => b.inc(n),
            Progress::Log {
                total,
                state,
                every,
            } => {
                let mut s = state.lock().expect("progress lock");
                s.rays += n;
                if s.last.elapsed() >= *every {
                    s.last = Instant::now();
                    eprintln!("{}", log_line(&s, *total, s.start.elapsed()));
                }
            }
        }
    }

    /// Records that `done` of `points` points are finished (called before each point starts).
    pub fn point(&self, done: usize, points: usize) {
        match self {
            Progress::Bar(b) => b.set_message(format!("{done}/{points} points")),
            Progress::Log { state, .. } => {
                let mut s = state.lock().expect("progress lock");
                s.points_done = done;
                s.points = points;
            }
            Progress::Hidden => {}
        }
    }

    /// Removes the bar, or prints the last log line.
    pub fn finish(&self) {
        match self {
            Progress::Bar(b) => b.finish_and_clear(),
            Progress::Log { total, state, .. } => {
                let mut s = state.lock().expect("progress lock");
                s.points_done = s.points;
                eprintln!("{}", log_line(&s, *total, s.start.elapsed()));
            }
            Progress::Hidden => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_line_shows_points_rate_and_eta() {
        let now = Instant::now();
        let s = LogState {
            unit: "rays",
            rays: 1_000,
            points_done: 3,
            points: 8,
            start: now,
            last: now,
        };
        let line = log_line(&s, 4_000, Duration::from_secs(2));
        assert_eq!(
            line,
            "progress: 3/8 points, 1000/4000 rays (25.0 %), 5.000e2 rays/s, eta 6 s, elapsed 2 s"
        );
        let s = LogState {
            unit: "rays",
            rays: 0,
            points_done: 0,
            points: 0,
            start: now,
            last: now,
        };
        assert_eq!(
            log_line(&s, 0, Duration::ZERO),
            "progress: 0/0 points, 0/0 rays (100.0 %), - rays/s, eta -, elapsed 0 s"
        );
    }
}
