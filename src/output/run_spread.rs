//! How much a timing mean moves between separate runs of one spec, read from a committed repeat
//! set (`results/NAME/runs/R`): what `raycost reproduce` holds a rerun's seconds against when the
//! result has such runs.
//!
//! Why: a timing's standard error covers the replicas *within* one run. Between runs the whole
//! machine drifts (measured on the 2-vCPU VMs this project runs on: one result's rerun took 0.79×,
//! another's 1.16× the recorded seconds at the median, with every counted cell identical), so a
//! within-run interval rejects a faithful rerun. The model here: a run multiplies every timing of a
//! column by its own factor, log-normal with one relative spread σ per column, estimated from the K
//! committed runs pooled over the table's rows,
//!   σ² = Σ_rows Σ_k (ln x_k − mean_k ln x)² / (rows·(K − 1)),
//! and a new run's cell has the offset ln v − mean_k ln x with variance σ²·(1 + 1/K) + (se_v/v)² —
//! that of one more run, widened by the rerun's own standard error. The whole machine also drifts
//! between sessions (measured: see [`judge_offsets`]), so the rerun's own factor, the median offset,
//! is reported, not judged, and each cell is held to 3σ of its offset from that factor: what must
//! reproduce is the shape of the timings (which engine is faster and by how much, what the
//! crossovers rest on), not the VM's speed that day. Rows where any run has no positive mean carry
//! no band; with fewer than two runs there is none at all.

use std::collections::BTreeMap;
use std::path::Path;

use super::column::{part, Class};
use super::compare::{read_cells, Side, TIMING_SIGMAS};
use crate::error::OutputError;

/// One timing column over K runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnSpread {
    /// Per row: the mean of ln(seconds) over the runs (NaN where a run has no positive value).
    pub log_mean: Vec<f64>,
    /// The pooled relative spread σ between runs.
    pub sigma: f64,
    /// Runs it was estimated from.
    pub runs: usize,
}

impl ColumnSpread {
    /// Row `row`'s new value `v` (standard error `se`, NaN if none) as (ln v − mean ln x, the
    /// variance of that offset for one more run: σ²·(1 + 1/K) + (se/v)²); `None` where the row has
    /// no band.
    pub fn offset(&self, row: usize, v: f64, se: f64) -> Option<(f64, f64)> {
        let m = *self.log_mean.get(row)?;
        if !(m.is_finite() && v > 0.0 && self.sigma.is_finite()) {
            return None;
        }
        let own = if se.is_finite() { se / v } else { 0.0 };
        let k = self.runs as f64;
        Some((v.ln() - m, self.sigma.powi(2) * (1.0 + 1.0 / k) + own * own))
    }
}

/// The machine factor of a rerun and which offsets lie in their band once it is divided out.
///
/// A VM's speed drifts between sessions as a whole (measured on 2026-12-03: Embree's own seconds
/// per ray moved by 25 % within ten minutes, and a rerun of a three-run set took 1.2–1.4× the
/// seconds of all three in every timing column), so the rerun's factor, the median offset f̂, is
/// reported rather than judged, and each cell is judged on its offset from it:
/// |offset − f̂| ≤ 3·√(var + (π/2)·median(var)/n), the last term the variance of a median of n.
/// Returns (f̂, inside per offset).
pub fn judge_offsets(offsets: &[(f64, f64)]) -> (f64, Vec<bool>) {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    };
    if offsets.is_empty() {
        return (f64::NAN, Vec::new());
    }
    let f = median(offsets.iter().map(|o| o.0).collect());
    let var_f = std::f64::consts::FRAC_PI_2 * median(offsets.iter().map(|o| o.1).collect())
        / offsets.len() as f64;
    let inside = offsets
        .iter()
        .map(|&(x, var)| (x - f).abs() <= TIMING_SIGMAS * (var + var_f).sqrt())
        .collect();
    (f, inside)
}

/// Every timing mean's spread, by table and column.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSpread {
    /// The committed runs it comes from (their folders, for the report).
    pub folders: Vec<String>,
    columns: BTreeMap<(String, String), ColumnSpread>,
}

impl RunSpread {
    /// The spread of the separate runs `runs` (each one result folder's tables), or `None` with
    /// fewer than two. Only `X_mean` columns of class timing count; a run whose table has another
    /// header or row count than the first run's is left out of that table.
    pub fn of_runs(runs: &[Side]) -> Result<Option<Self>, OutputError> {
        let Some(first) = runs.first() else {
            return Ok(None);
        };
        if runs.len() < 2 {
            return Ok(None);
        }
        let mut out = RunSpread::default();
        for (table, classes) in &first.meta.columns {
            let mut cells = Vec::new();
            for side in runs {
                if let Some(path) = side.file(table) {
                    cells.push(read_cells(path)?);
                }
            }
            let Some(head) = cells.first() else { continue };
            let (header, rows) = (head.header.clone(), head.rows.len());
            cells.retain(|c| c.header == header && c.rows.len() == rows);
            if cells.len() < 2 {
                continue;
            }
            for info in classes {
                if info.class != Class::Timing || part::stem(&info.name, part::MEAN).is_none() {
                    continue;
                }
                let Some(col) = header.iter().position(|h| *h == info.name) else {
                    continue;
                };
                let logs: Vec<Vec<f64>> = (0..rows)
                    .map(|r| {
                        cells
                            .iter()
                            .map(|c| c.rows[r][col].parse::<f64>().map_or(f64::NAN, f64::ln))
                            .collect()
                    })
                    .collect();
                out.columns.insert(
                    (table.clone(), info.name.clone()),
                    pooled(&logs, cells.len()),
                );
            }
        }
        out.folders = runs.iter().map(|s| s.folder.clone()).collect();
        Ok(Some(out))
    }

    /// The spread of `column` in `table`, if the runs have one.
    pub fn column(&self, table: &str, column: &str) -> Option<&ColumnSpread> {
        self.columns.get(&(table.to_string(), column.to_string()))
    }

    /// The committed runs of the result in `dir` (`results/NAME` or `results/NAME/runs/R`): the
    /// folders `results/NAME/runs/*` holding a `NAME.meta.toml`, in order of R.
    pub fn sibling_runs(dir: &Path, name: &str) -> Vec<std::path::PathBuf> {
        let base = match dir.parent() {
            Some(p) if p.file_name().is_some_and(|f| f == "runs") => {
                p.parent().unwrap_or(dir).to_path_buf()
            }
            _ => dir.to_path_buf(),
        };
        let Ok(entries) = std::fs::read_dir(base.join("runs")) else {
            return Vec::new();
        };
        let mut runs: Vec<(u64, std::path::PathBuf)> = entries
            .flatten()
            .filter_map(|e| {
                let r = e.file_name().to_str()?.parse::<u64>().ok()?;
                let p = e.path();
                p.join(format!("{name}.meta.toml"))
                    .is_file()
                    .then_some((r, p))
            })
            .collect();
        runs.sort();
        runs.into_iter().map(|(_, p)| p).collect()
    }
}

/// Per-row means of the logs and the pooled spread (rows with a non-finite log are left out).
fn pooled(logs: &[Vec<f64>], k: usize) -> ColumnSpread {
    let (mut ss, mut rows) = (0.0, 0usize);
    let log_mean = logs
        .iter()
        .map(|l| {
            if !l.iter().all(|x| x.is_finite()) {
                return f64::NAN;
            }
            let m = l.iter().sum::<f64>() / k as f64;
            ss += l.iter().map(|x| (x - m).powi(2)).sum::<f64>();
            rows += 1;
            m
        })
        .collect();
    let sigma = if rows > 0 {
        (ss / (rows * (k - 1)) as f64).sqrt()
    } else {
        f64::NAN
    };
    ColumnSpread {
        log_mean,
        sigma,
        runs: k,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three runs whose seconds differ by a factor per run: σ is that factor's spread; a rerun
    /// that is uniformly 1.3× slower has factor 1.3 and every cell inside, while one cell twice as
    /// slow as the rest is outside; a row with a missing value has no band.
    #[test]
    fn a_run_factor_sets_the_band() {
        let f = [1.0f64, 1.1, 0.9];
        let base = [2.0f64, 5.0, 7.0, 3.0, 4.0, 6.0];
        let mut logs: Vec<Vec<f64>> = base
            .iter()
            .map(|b| f.iter().map(|x| (b * x).ln()).collect())
            .collect();
        logs.push(vec![1.0, f64::NAN, 1.0]);
        let s = pooled(&logs, 3);
        let lf: Vec<f64> = f.iter().map(|x| x.ln()).collect();
        let m = lf.iter().sum::<f64>() / 3.0;
        let want = (lf.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 2.0).sqrt();
        assert!((s.sigma - want).abs() < 1e-12, "{} vs {want}", s.sigma);
        let gm = (lf.iter().sum::<f64>() / 3.0).exp();
        let slower: Vec<(f64, f64)> = base
            .iter()
            .enumerate()
            .map(|(r, b)| s.offset(r, 1.3 * b * gm, f64::NAN).unwrap())
            .collect();
        let (factor, inside) = judge_offsets(&slower);
        assert!((factor.exp() - 1.3).abs() < 1e-9, "{}", factor.exp());
        assert!(inside.iter().all(|&x| x));
        let mut odd = slower.clone();
        odd[1] = s.offset(1, 2.6 * base[1] * gm, f64::NAN).unwrap();
        let (_, inside) = judge_offsets(&odd);
        assert_eq!(inside, [true, false, true, true, true, true]);
        // The rerun's own standard error widens the band.
        odd[1] = s.offset(1, 2.6 * base[1] * gm, 2.6 * base[1] * gm).unwrap();
        assert!(judge_offsets(&odd).1[1]);
        assert_eq!(s.offset(6, 1.0, f64::NAN), None);
        assert_eq!(s.offset(0, 0.0, f64::NAN), None);
    }
}
