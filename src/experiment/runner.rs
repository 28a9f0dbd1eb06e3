//! Runs a spec: the points of this shard that are not done yet, in index order, each appended to the
//! sink as soon as it finishes.

use std::time::Instant;

use anyhow::Context;

use super::machine::{self, MachineCosts};
use super::{run_point, side_tables, PointResult};
use crate::output::meta::{host_name, Build, MachineInfo, Meta, RunInfo};
use crate::output::progress::progress;
use crate::output::row::{is_timing_column, Row, Value};
use crate::output::sink::{Sink, SinkOptions};
use crate::output::summary;
use crate::output::time::now_rfc3339;
use crate::spec::{Kind, PointConfig, Spec};

/// A `--shard K/N` selection: points with index ≡ K (mod N). Round robin, because neighbouring points
/// of a sweep tend to cost alike (the last key varies fastest), so blocks would balance worse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0 ≤ k < n.
    pub k: usize,
    /// Number of shards, ≥ 1.
    pub n: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("'{s}': expected K/N, e.g. 0/4"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': K must be a whole number"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': N must be a whole number"))?;
        if n == 0 || k >= n {
            return Err(format!("'{s}': need 0 ≤ K < N and N ≥ 1"));
        }
        Ok(Shard { k, n })
    }
}

/// Options of `raycost run`.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Results root (`DIR`).
    pub out: std::path::PathBuf,
    /// Replace existing results.
    pub force: bool,
    /// Continue a partial run.
    pub resume: bool,
    /// No progress, no summary.
    pub quiet: bool,
    /// Shard selection.
    pub shard: Option<Shard>,
    /// `--set` overrides (recorded in the metadata).
    pub sets: Vec<String>,
}

/// The file stem of a run.
pub fn stem(name: &str, shard: Option<Shard>) -> String {
    match shard {
        None => name.to_string(),
        Some(s) => format!("{name}.shard-{}-of-{}", s.k, s.n),
    }
}

/// Runs `spec`; returns the written paths and the summary text.
pub fn run(spec: &Spec, opts: &RunOptions) -> anyhow::Result<(Vec<std::path::PathBuf>, String)> {
    let name = &spec.base.experiment.name;
    let dir = opts.out.join(name);
    let stem = stem(name, opts.shard);
    let sink = Sink::open(
        &dir,
        &stem,
        &spec.hash,
        SinkOptions {
            force: opts.force,
            resume: opts.resume,
            tables: side_tables(spec.base.experiment.kind),
        },
    )?;
    let Some(mut sink) = sink else {
        // --resume on a finished table: nothing to do, and nothing is touched.
        let msg = format!(
            "{}: finished already, nothing to resume\n",
            dir.join(format!("{stem}.csv")).display()
        );
        return Ok((Vec::new(), msg));
    };
    let started = sink.started().to_string();
    let t0 = Instant::now();
    let mine: Vec<usize> = spec
        .points
        .iter()
        .map(|p| p.index)
        .filter(|i| opts.shard.is_none_or(|s| i % s.n == s.k))
        .collect();
    let resumed: Vec<usize> = mine
        .iter()
        .copied()
        .filter(|i| sink.done().contains(i))
        .collect();
    let todo: Vec<usize> = mine
        .iter()
        .copied()
        .filter(|i| !sink.done().contains(i))
        .collect();

    let machine: Option<MachineCosts> =
        (spec.base.experiment.kind == Kind::GridCostModel).then(machine::measure);
    let total_rays: u64 = todo.iter().map(|&i| spec.points[i].config.work()).sum();
    let bar = progress(total_rays, todo.len(), opts.quiet);
    let mut finished = Vec::new();
    let mut walls = Vec::new();
    let mut timing = Vec::new();
    for (n, &i) in todo.iter().enumerate() {
        bar.point(n, todo.len());
        let p = &spec.points[i];
        let start = Instant::now();
        let result: PointResult = run_point(&p.config, i as u64, machine, &|k| bar.inc(k))
            .with_context(|| format!("point {i}"))?;
        let wall = start.elapsed().as_secs_f64();
        let row = with_point_columns(i, &p.params, &result.row);
        let side: Vec<(&'static str, Vec<Row>)> = result
            .tables
            .iter()
            .map(|(name, rows)| {
                let rows = rows.iter().map(|r| with_point_columns(i, &[], r)).collect();
                (*name, rows)
            })
            .collect();
        if timing.is_empty() {
            timing = row
                .0
                .iter()
                .map(|(c, _)| c.clone())
                .filter(|c| is_timing_column(c))
                .collect();
        }
        sink.append(&row, &side)
            .with_context(|| format!("could not append point {i} to {}", dir.display()))?;
        let params = p
            .params
            .iter()
            .map(|(k, v)| format!("{}={v}", short(k)))
            .collect::<Vec<_>>()
            .join(" ");
        finished.push((i, params, result, wall));
        walls.push(wall);
    }
    bar.finish();

    let mut spec_table = toml::Table::new();
    spec_table.insert(
        "base".into(),
        toml::Value::try_from(&spec.base).context("serialising the spec")?,
    );
    let mut sw = toml::Table::new();
    for (k, v) in &spec.sweep {
        sw.insert(k.clone(), toml::Value::Array(v.clone()));
    }
    spec_table.insert("sweep".into(), toml::Value::Table(sw));
    let meta = Meta {
        raycost: Build::current(),
        run: RunInfo {
            spec_path: spec.path.clone(),
            spec_hash: spec.hash.clone(),
            seed: spec.base.experiment.seed,
            threads: rayon::current_num_threads(),
            shard: opts
                .shard
                .map_or("all".into(), |s| format!("{}/{}", s.k, s.n)),
            set: opts.sets.clone(),
            host: host_name(),
            started,
            finished: now_rfc3339(),
            wall_s: t0.elapsed().as_secs_f64(),
            points_total: spec.points.len(),
            points: todo.clone(),
            point_wall_s: walls,
            resumed_points: resumed,
        },
        machine: machine.map(|m| MachineInfo {
            t_i_s: m.t_i,
            t_s_s: m.t_s,
        }),
        timing_columns: timing,
        spec: spec_table,
    };
    // Every engine must agree with brute force on everything checked (the grid on first hits, the
    // DETP engines on disc sums); the table is kept as evidence.
    let disagreements: Vec<String> = finished
        .iter()
        .filter_map(|(i, params, r, _)| {
            let m = ["bf_mismatches", "mismatches"]
                .iter()
                .filter_map(|c| r.row.get(c).and_then(|v| v.as_f64()))
                .sum::<f64>();
            (m > 0.0).then(|| format!("point {i} ({params}): {m} disagreements"))
        })
        .collect();
    let written = sink
        .finish(&meta.render())
        .with_context(|| format!("could not finish the result files in {}", dir.display()))?;
    if !disagreements.is_empty() {
        anyhow::bail!(
            "an engine disagreed with brute force ({}); the table was written to {} for inspection",
            disagreements.join("; "),
            dir.display()
        );
    }
    let shown: Vec<summary::SummaryPoint> = finished
        .iter()
        .map(|(index, params, r, wall)| summary::SummaryPoint {
            index: *index,
            params,
            lines: &r.summary,
            rays_per_s: r.rays_per_s,
            wall: *wall,
        })
        .collect();
    Ok((written, summary::render(&shown)))
}

fn short(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

/// Prepends `point` and the parameter columns to a result row.
fn with_point_columns(index: usize, params: &[(String, toml::Value)], row: &Row) -> Row {
    let mut r = Row::default();
    r.u("point", index as u64);
    for (k, v) in params {
        let value = match v {
            toml::Value::Float(x) => Value::F(*x),
            toml::Value::Integer(i) => Value::F(*i as f64),
            toml::Value::String(s) => Value::S(s.clone()),
            other => Value::S(other.to_string()),
        };
        r.push(k.clone(), value);
    }
    r.0.extend(row.0.iter().cloned());
    r
}

/// Validates a spec and describes its points (`raycost check`).
pub fn describe(spec: &Spec) -> String {
    let mut s = format!(
        "{}: kind {}, {} point(s), spec hash {}\n",
        spec.path,
        spec.base.experiment.kind.as_str(),
        spec.points.len(),
        &spec.hash[..16]
    );
    for p in &spec.points {
        let params = p
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ");
        let what = match &p.config {
            PointConfig::Grid(g) => {
                let scene = match &g.scene {
                    crate::spec::SceneModel::Infinite => "infinite scene".to_string(),
                    crate::spec::SceneModel::Finite(f) => format!(
                        "finite scene, ~{:.0} spheres, side {:.4}",
                        f.expected_count(),
                        f.side()
                    ),
                };
                format!("{scene}, {} rays", g.rays)
            }
            PointConfig::Detp(d) => super::detp::describe(d),
            PointConfig::QuasiStatic(q) => super::quasi_static::describe(q),
        };
        s.push_str(&format!(
            "  point {:>4}: {params}{}{what}\n",
            p.index,
            if params.is_empty() { "" } else { "; " },
        ));
    }
    s
}
