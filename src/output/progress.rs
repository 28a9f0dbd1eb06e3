//! Progress on stderr: a bar on a terminal, periodic plain log lines otherwise (batch jobs, Slurm),
//! nothing with `--quiet`. Advanced per chunk of batches, never per ray.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

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
        /// State: (rays done, start, last line).
        state: Mutex<(u64, Instant, Instant)>,
        /// Interval between lines.
        every: Duration,
    },
}

/// Builds the progress display for `total` rays over `points` points.
pub fn progress(total: u64, points: usize, quiet: bool) -> Progress {
    if quiet {
        return Progress::Hidden;
    }
    if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} rays · {per_sec} · eta {eta} · {msg}")
                .expect("a valid template")
                .progress_chars("█▉ "),
        );
        bar.set_message(format!("{points} points"));
        Progress::Bar(bar)
    } else {
        let now = Instant::now();
        Progress::Log {
            total,
            state: Mutex::new((0, now, now)),
            every: Duration::from_secs(10),
        }
    }
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
                s.0 += n;
                if s.2.elapsed() >= *every {
                    s.2 = Instant::now();
                    let el = s.1.elapsed().as_secs_f64();
                    let rate = s.0 as f64 / el.max(1e-9);
                    let eta = (*total - s.0.min(*total)) as f64 / rate.max(1e-9);
                    eprintln!(
                        "progress: {}/{} rays ({:.1} %), {:.3e} rays/s, eta {:.0} s",
                        s.0,
                        total,
                        100.0 * s.0 as f64 / *total as f64,
                        rate,
                        eta
                    );
                }
            }
        }
    }

    /// Sets the point being run.
    pub fn point(&self, done: usize, points: usize) {
        match self {
            Progress::Bar(b) => b.set_message(format!("point {}/{points}", done + 1)),
            Progress::Log { .. } => eprintln!("progress: point {}/{points}", done + 1),
            Progress::Hidden => {}
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Progress::Bar(b) = self {
            b.finish_and_clear();
        }
    }
}
