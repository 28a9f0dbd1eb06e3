//! Progress on stderr: a bar on a terminal, periodic plain log lines otherwise (batch jobs, Slurm),
//! nothing with `--quiet`. Advanced per chunk of batches, never per ray.
//!
//! A log line reads `progress: 3/8 points, 1200000/3200000 rays (37.5 %), 2.41e5 rays/s, eta 8 s,
//! elapsed 5 s`, counting the unit the kind's work is in (rays, lines, photons, photon-frames): one
//! when the run starts, then one per second for the first minute and one per 10 s after (a ticker
//! thread prints them, so a long point whose kind reports its work only at the end still shows the
//! run is alive), and a last one when it ends.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
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
    /// Set by [`Progress::finish`]: the ticker stops.
    finished: bool,
}

/// Seconds between two log lines `elapsed` into the run: 1 s for the first minute (a short run
/// shows its rate and ETA at once), then 10 s (a day-long batch job's log stays readable).
pub fn log_interval(elapsed: Duration) -> Duration {
    if elapsed < Duration::from_secs(60) {
        Duration::from_secs(1)
    } else {
        Duration::from_secs(10)
    }
}

/// How progress is shown.
pub enum Progress {
    /// Nothing.
    Hidden,
    /// An indicatif bar (stderr is a terminal).
    Bar(ProgressBar),
    /// Log lines every [`log_interval`] (stderr is a file or pipe).
    Log {
        /// Total units.
        total: u64,
        /// Counters and clocks, shared with the ticker thread.
        state: Arc<Mutex<LogState>>,
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
            finished: false,
        };
        eprintln!("{}", log_line(&state, total, Duration::ZERO));
        let state = Arc::new(Mutex::new(state));
        let ticking = Arc::clone(&state);
        // The ticker: wakes every 200 ms, prints when the interval has passed, stops at finish.
        std::thread::spawn(move || loop {
            std::thread::sleep(Duration::from_millis(200));
            let Ok(mut s) = ticking.lock() else { return };
            if s.finished {
                return;
            }
            let el = s.start.elapsed();
            if s.last.elapsed() >= log_interval(el) {
                s.last = Instant::now();
                eprintln!("{}", log_line(&s, total, el));
            }
        });
        Progress::Log { total, state }
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
            Progress::Log { state, .. } => {
                // Lines are printed by the ticker alone, so they come at a steady pace.
                state.lock().expect("progress lock").rays += n;
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
                s.finished = true;
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
    fn log_lines_come_every_second_then_every_ten() {
        assert_eq!(log_interval(Duration::ZERO), Duration::from_secs(1));
        assert_eq!(
            log_interval(Duration::from_secs(59)),
            Duration::from_secs(1)
        );
        assert_eq!(
            log_interval(Duration::from_secs(60)),
            Duration::from_secs(10)
        );
    }

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
            finished: false,
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
            finished: false,
        };
        assert_eq!(
            log_line(&s, 0, Duration::ZERO),
            "progress: 0/0 points, 0/0 rays (100.0 %), - rays/s, eta -, elapsed 0 s"
        );
    }
}
