//! Runs a [`Plan`]: the points of this shard that are not done yet, in index order, each appended to
//! the sink as soon as it finishes. The runner knows kinds only through [`DynKind`]: every kind's
//! rows get the same `point` and parameter columns, every kind's built-in checks are handled alike
//! (the table is written, then the run fails with exit 1), and the metadata is one typed schema.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use super::kind::{Check, Context, DynKind, ErasedOutput};
use super::plan::{Param, Plan};
use crate::error::{Context as _, Error};
use crate::output::column::{declaration, resolve_unit, Class, ColumnInfo, POINT};
use crate::output::meta::Meta;
use crate::output::progress::progress;
use crate::output::row::{Row, Value};
use crate::output::sink::{Sink, SinkOptions};
use crate::output::summary;

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
    pub out: PathBuf,
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
    /// Worker threads (`--threads`, or the machine's): passed to every point and recorded.
    pub threads: usize,
    /// `--run R`: the results go to `OUT/NAME/runs/R/` (the spec's `experiment.run` is R).
    pub run: Option<u64>,
    /// `raycost merge` of photon shards: each point's parts, one per shard in shard order
    /// (`super::photon_shards`); points measure these instead of tracing.
    pub merged: Option<BTreeMap<usize, Vec<serde_json::Value>>>,
}

impl RunOptions {
    /// The folder of experiment `name`'s results: `OUT/NAME`, or `OUT/NAME/runs/R` for run R.
    pub fn dir(&self, name: &str) -> PathBuf {
        let dir = self.out.join(name);
        match self.run {
            None => dir,
            Some(r) => dir.join("runs").join(r.to_string()),
        }
    }
}

/// The file stem of a run.
pub fn stem(name: &str, shard: Option<Shard>) -> String {
    match shard {
        None => name.to_string(),
        Some(s) => format!("{name}.shard-{}-of-{}", s.k, s.n),
    }
}

/// The SIMD path each kernel takes on this machine (for the metadata).
pub fn simd_paths() -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    m.insert(
        "query_grid_walk".into(),
        format!("{:?}", crate::grid::fast::Walk::detect()),
    );
    m.insert(
        "sphere_cache_filter".into(),
        crate::detp::sphere_cache::filter::FilterPath::detect()
            .name()
            .to_string(),
    );
    m
}

/// The metadata of a run of `plan` as it starts.
fn start_meta(plan: &Plan, opts: &RunOptions, warnings: Vec<String>) -> Meta {
    let mut meta = Meta::begin("run", simd_paths());
    meta.run.spec_path = plan.spec.path.clone();
    meta.run.spec_hash = plan.hash.clone();
    meta.run.seed = plan.spec.experiment.seed;
    meta.run.shard = opts
        .shard
        .map_or("all".into(), |s| format!("{}/{}", s.k, s.n));
    meta.run.set = opts.sets.clone();
    meta.run.points_total = plan.points.len();
    meta.run.threads = opts.threads;
    meta.inputs = plan.inputs.clone();
    meta.warnings = warnings;
    meta.spec = plan.normalized.clone();
    meta
}

/// Prepends `point` and the parameter columns to a result row, and states a length written as
/// the spec writes lengths in the unit this point's are in (`lengths`, see [`resolve_unit`]).
fn with_point_columns(index: usize, params: &[Param], lengths: &'static str, row: &Row) -> Row {
    let mut r = Row::default();
    r.put(&POINT, index as u64);
    for p in params {
        r.param(&p.key, p.unit, p.value.clone());
    }
    r.extend(row);
    for cell in &mut r.0 {
        cell.unit = resolve_unit(cell.unit, lengths);
    }
    r
}

/// Ctrl-C during a run. The handler asks the runner to stop ([`interrupt::requested`]); the runner
/// stops after the point in progress (its row kept) and returns [`Error::Interrupted`], whose exit
/// code is 130, with the command that resumes. A point that does not finish within a second of the
/// signal is not waited for: the handler then says what was kept (the point in progress is lost,
/// as a kill would lose it) and exits with 130 itself.
mod interrupt {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Mutex;
    use std::time::{Duration, Instant};

    static REQUESTED: AtomicBool = AtomicBool::new(false);
    static HEEDED: AtomicBool = AtomicBool::new(false);
    /// What was kept so far and how to resume (updated after every point).
    static KEPT: Mutex<Option<String>> = Mutex::new(None);
    /// How long the handler waits for the runner to heed it.
    const GRACE: Duration = Duration::from_secs(1);

    /// Installs the handler once per process.
    pub fn install() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            let _ = ctrlc::set_handler(|| {
                REQUESTED.store(true, Ordering::SeqCst);
                let t0 = Instant::now();
                while t0.elapsed() < GRACE {
                    if HEEDED.load(Ordering::SeqCst) {
                        return;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                let kept = KEPT.lock().ok().and_then(|m| m.clone());
                let kept = kept.unwrap_or_else(|| "before any point finished".into());
                eprintln!("\nerror: interrupted: {kept} (the point in progress is lost)");
                crate::output::folder::release_locks();
                std::process::exit(130);
            });
        });
    }

    /// Records what Ctrl-C should say now.
    pub fn kept(line: String) {
        if let Ok(mut m) = KEPT.lock() {
            *m = Some(line);
        }
    }

    /// Whether Ctrl-C was pressed (and, if so, the runner now heeds it).
    pub fn requested() -> bool {
        let r = REQUESTED.load(Ordering::SeqCst);
        if r {
            HEEDED.store(true, Ordering::SeqCst);
        }
        r
    }
}

/// What Ctrl-C says after `done` of `total` points are in `partial`.
fn interrupt_line(
    plan: &Plan,
    opts: &RunOptions,
    partial: &std::path::Path,
    done: usize,
    total: usize,
) -> String {
    let mut cmd = format!(
        "raycost run {} --resume --out {}",
        plan.spec.path,
        opts.out.display()
    );
    if let Some(s) = opts.shard {
        cmd.push_str(&format!(" --shard {}/{}", s.k, s.n));
    }
    if let Some(r) = opts.run {
        cmd.push_str(&format!(" --run {r}"));
    }
    for s in &opts.sets {
        cmd.push_str(&format!(" --set '{s}'"));
    }
    format!(
        "{done} of {total} point(s) kept in {}; continue with: {cmd}",
        partial.display()
    )
}

/// One finished point: its index, its parameters as the summary shows them, what it produced, its
/// wall seconds.
type Finished = (usize, String, ErasedOutput, f64);

/// The warnings of this shard's points known before running, each once.
fn known_warnings(plan: &Plan, mine: &[usize]) -> Vec<String> {
    crate::output::meta::point_warnings(
        &mine
            .iter()
            .flat_map(|&i| plan.points[i].warnings().into_iter().map(move |w| (i, w)))
            .collect::<Vec<_>>(),
    )
}

/// Runs `plan`; returns the written paths and the summary text.
pub fn run(plan: &Plan, opts: &RunOptions) -> Result<(Vec<PathBuf>, String), Error> {
    let kind: &dyn DynKind = plan.kind;
    let name = &plan.spec.experiment.name;
    let dir = opts.dir(name);
    let stem = stem(name, opts.shard);
    let mine: Vec<usize> = (0..plan.points.len())
        .filter(|i| opts.shard.is_none_or(|s| i % s.n == s.k))
        .collect();
    let mut meta = start_meta(plan, opts, known_warnings(plan, &mine));
    let sink_options = SinkOptions {
        force: opts.force,
        resume: opts.resume,
        tables: kind.table_names(),
    };
    let Some(mut sink) = Sink::open(&dir, &stem, &meta, sink_options)? else {
        // --resume on a finished table: nothing to do, and nothing is touched.
        let msg = format!(
            "{}: finished already, nothing to resume\n",
            dir.join(format!("{stem}.csv")).display()
        );
        return Ok((Vec::new(), msg));
    };
    meta.run.started = sink.started().to_string();
    if let Some(then) = sink.previous() {
        meta.columns = then.columns.clone();
    }
    meta.warnings.extend(sink.notes().iter().cloned());
    // Warnings are printed even with --quiet (which silences progress and the summary only).
    for w in &meta.warnings {
        eprintln!("warning: {w}");
    }
    let t0 = Instant::now();
    let (resumed, todo): (Vec<usize>, Vec<usize>) =
        mine.iter().partition(|i| sink.done().contains(i));
    let finished = run_points(plan, opts, &todo, resumed.len(), &mut meta, &mut sink)?;
    interrupt::kept(
        "the run was finishing its files; run the same command with --resume to complete it".into(),
    );
    meta.end(t0.elapsed().as_secs_f64());
    if meta.busy() {
        if let Some(w) = meta.warnings.last() {
            eprintln!("warning: {w}");
        }
    }
    meta.run.resumed_points = resumed;
    let failed: Vec<String> = finished
        .iter()
        .flat_map(|(i, params, out, _)| {
            out.checks
                .iter()
                .filter(|c| c.failures > 0)
                .map(move |c| describe_failure(*i, params, c))
        })
        .collect();
    let written = sink
        .finish(&meta)
        .map_err(|e| Error::Internal(e.into()))
        .context_with(|| format!("could not finish the result files in {}", dir.display()))?;
    if !failed.is_empty() {
        return Err(Error::CheckFailed(format!(
            "{}; the tables were written to {} for inspection",
            failed.join("; "),
            dir.display()
        )));
    }
    let shown: Vec<summary::SummaryPoint> = finished
        .iter()
        .map(|(index, params, out, wall)| summary::SummaryPoint {
            index: *index,
            params,
            lines: &out.summary,
            rate: out.rate,
            wall: *wall,
        })
        .collect();
    Ok((written, summary::render(&shown)))
}

/// Runs the points `todo` (after `resumed` points of an earlier run), appending each to the sink
/// as it finishes; stops with [`Error::Interrupted`] after the point in progress on Ctrl-C.
fn run_points(
    plan: &Plan,
    opts: &RunOptions,
    todo: &[usize],
    resumed: usize,
    meta: &mut Meta,
    sink: &mut Sink,
) -> Result<Vec<Finished>, Error> {
    let kind = plan.kind;
    let todo_points: Vec<&dyn super::kind::DynPoint> =
        todo.iter().map(|&i| plan.points[i].as_ref()).collect();
    let shared = kind.shared(&todo_points)?;
    meta.extra = kind.shared_meta(shared.as_ref());
    let total: u64 = todo_points.iter().map(|p| p.work().units).sum();
    let unit = todo_points.first().map_or("rays", |p| p.work().unit);
    let bar = progress(total, unit, todo.len(), opts.quiet);
    let name = &plan.spec.experiment.name;
    let partial = opts
        .dir(name)
        .join(format!("{}.csv.partial", stem(name, opts.shard)));
    let all = resumed + todo.len();
    interrupt::kept(interrupt_line(plan, opts, &partial, resumed, all));
    interrupt::install();
    let mut finished: Vec<Finished> = Vec::new();
    for (n, &i) in todo.iter().enumerate() {
        bar.point(n, todo.len());
        let start = Instant::now();
        let ctx = Context {
            stream_point: plan.spec.experiment.stream_point(i),
            threads: opts.threads,
            progress: &|k| bar.inc(k),
            merged: opts
                .merged
                .as_ref()
                .and_then(|m| m.get(&i))
                .map(Vec::as_slice),
        };
        let point = plan.points[i].as_ref();
        // A point merged from photon shards was traced by them, in one part each.
        let batches = if ctx.merged.is_some() {
            1
        } else {
            plan.batches[i]
        };
        let out = match batches {
            1 => kind.run(point, shared.as_ref(), &ctx),
            b => super::photon_batches::run(kind, point, shared.as_ref(), &ctx, b),
        }
        .context_with(|| format!("point {i}"))?;
        let wall = start.elapsed().as_secs_f64();
        if let Some(m) = point_memory(plan, i, batches) {
            meta.run.point_memory.push(m);
        }
        finished.push(keep_point(plan, i, out, wall, meta, sink)?);
        let line = interrupt_line(plan, opts, &partial, resumed + n + 1, all);
        if interrupt::requested() {
            bar.finish();
            return Err(Error::Interrupted(line));
        }
        interrupt::kept(line);
    }
    bar.finish();
    Ok(finished)
}

/// Appends point `i`'s rows (with `point` and its parameters) to the sink, records its columns,
/// warnings and wall time in the metadata, and adds its checks' summary lines.
fn keep_point(
    plan: &Plan,
    i: usize,
    mut out: ErasedOutput,
    wall: f64,
    meta: &mut Meta,
    sink: &mut Sink,
) -> Result<Finished, Error> {
    let kind = plan.kind;
    // An overflow names the point and its parameters, not only the column.
    let at = |e: Error| {
        let params: Vec<String> = plan.spec.points[i]
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {}", crate::spec::sweep::show(v)))
            .collect();
        Error::internal(format!("point {i} ({}): {e:#}", params.join(", ")))
    };
    check_declared(kind, "main", std::slice::from_ref(&out.row)).map_err(at)?;
    for (name, rows) in &out.tables {
        check_declared(kind, name, rows).map_err(at)?;
    }
    let row = with_point_columns(i, &plan.params[i], plan.lengths[i], &out.row);
    let side: Vec<(&'static str, Vec<Row>)> = out
        .tables
        .iter()
        .map(|(name, rows)| {
            let rows = rows
                .iter()
                .map(|r| with_point_columns(i, &[], plan.lengths[i], r))
                .collect();
            (*name, rows)
        })
        .collect();
    record_columns(&mut meta.columns, "main", &row);
    for (name, rows) in &side {
        if let Some(r) = rows.first() {
            record_columns(&mut meta.columns, name, r);
        }
    }
    sink.append(&row, &side, meta)
        .map_err(|e| Error::Internal(e.into()))
        .context_with(|| format!("could not append point {i}"))?;
    for w in &out.warnings {
        let w = format!("point {i}: {w}");
        eprintln!("warning: {w}");
        if !meta.warnings.contains(&w) {
            meta.warnings.push(w);
        }
    }
    meta.run.points.push(i);
    meta.run.point_wall_s.push(wall);
    // Every built-in check gets a summary line, failed or not.
    for c in &out.checks {
        out.summary.push(summary::SummaryLine {
            metric: c.name.to_string(),
            measured: crate::stats::Estimate {
                mean: c.failures as f64,
                se: 0.0,
                n: c.checked,
                clusters: c.checked,
            },
            theory: format!("0 of {}", c.checked),
            verdict: crate::stats::Verdict::of_check(c.failures),
        });
    }
    let params = plan.spec.points[i]
        .params
        .iter()
        .map(|(k, v)| format!("{}={v}", short(k)))
        .collect::<Vec<_>>()
        .join(" ");
    Ok((i, params, out, wall))
}

/// Point `i`'s memory record after it ran in `batches` photon batches (None for a kind without a
/// budget).
fn point_memory(plan: &Plan, i: usize, batches: u64) -> Option<crate::output::meta::PointMemory> {
    let m = plan.points[i].memory(plan.threads);
    let (key, gib) = m.budget?;
    let split = super::photon_batches::Split::of(&m.needs);
    Some(crate::output::meta::PointMemory {
        point: i,
        batches,
        model_bytes: m.batching.map_or(split.fixed + split.per_photon, |b| {
            split.per_batch(b.photons, batches)
        }),
        budget_key: key.into(),
        budget_gib: gib,
        peak_rss_bytes: crate::output::meta::peak_memory(),
    })
}

/// Every cell of a kind's rows of `table` must come from the kind's declaration of that table, with
/// the class declared there (a bug in the kind otherwise), and no result is ever written as ±∞
/// unless its column is declared open-ended (a histogram's last edge): an overflow fails the run
/// naming the column, before anything of the point is written. NaN stays: it means "no value" (the
/// standard error of one sample, a theory without a closed form). Declarations are looked up once
/// per distinct column name, so a points table of 10⁵ rows costs a pass over its values.
fn check_declared(kind: &dyn DynKind, table: &str, rows: &[Row]) -> Result<(), Error> {
    let columns = kind.columns();
    let declared = columns
        .iter()
        .find(|(t, _)| *t == table)
        .map_or(&[][..], |(_, c)| c.as_slice());
    // Column name → may it be infinite.
    let mut checked: std::collections::HashMap<&str, bool> = std::collections::HashMap::new();
    for row in rows {
        for cell in &row.0 {
            let infinite_ok = match checked.get(cell.name.as_str()) {
                Some(&ok) => ok,
                None => {
                    let ok = match declaration(declared, &cell.name) {
                        // A measured cell may be written as a timing where seconds decided it
                        // (a column declared `decided_by_timing`); never the other way.
                        Some((column, class))
                            if class == cell.class
                                || (class == Class::Measured && cell.class == Class::Timing) =>
                        {
                            column.infinite_ok
                        }
                        Some((_, class)) => {
                            return Err(Error::internal(format!(
                                "kind {}: column {table}.{} is written as {} but declared {}",
                                kind.name(),
                                cell.name,
                                cell.class.as_str(),
                                class.as_str()
                            )))
                        }
                        None => {
                            return Err(Error::internal(format!(
                                "kind {}: column {table}.{} is not declared",
                                kind.name(),
                                cell.name
                            )))
                        }
                    };
                    checked.insert(cell.name.as_str(), ok);
                    ok
                }
            };
            if !infinite_ok && matches!(cell.value, Value::F(x) if x.is_infinite()) {
                return Err(Error::internal(format!(
                    "column {table}.{} overflowed to {} (the inputs' magnitudes exceed f64 arithmetic); nothing of this point was written",
                    cell.name,
                    cell.value.render()
                )));
            }
        }
    }
    Ok(())
}

fn describe_failure(i: usize, params: &str, c: &Check) -> String {
    format!(
        "point {i} ({params}): {} {} of {} checked ({})",
        c.name, c.failures, c.checked, c.what
    )
}

/// Records the columns of `row` as those of `table`: the first row of a table defines them, a
/// column any later row writes as a timing (a value decided by seconds in that row) is a timing,
/// and one whose rows are in different units (lengths where a sweep changes `length_unit`) says
/// so ([`MIXED_UNITS`]).
fn record_columns(columns: &mut BTreeMap<String, Vec<ColumnInfo>>, table: &str, row: &Row) {
    let cols = columns
        .entry(table.to_string())
        .or_insert_with(|| row.columns());
    for cell in &row.0 {
        if let Some(c) = cols.iter_mut().find(|c| c.name == cell.name) {
            if cell.class == Class::Timing {
                c.class = Class::Timing;
            }
            if c.unit != cell.unit {
                c.unit = MIXED_UNITS.to_string();
            }
        }
    }
}

/// The unit recorded for a column whose rows are in different units.
const MIXED_UNITS: &str = "per row: length or r_s, as the row's length_unit";

fn short(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::inputs::Inputs;
    use crate::experiment::kind::{
        col, Cell, Check, ConfigError, Context, Kind, NoTables, Output, Rate, Registered, Table,
        Work,
    };
    use crate::output::column::{Class, Column};

    crate::spec_file! {
        /// The planted kind's spec.
        pub struct PlantedSpec {
            /// `[planted]`.
            planted: PlantedTable = {table};
        }
    }

    crate::spec_table! {
        /// `[planted]`.
        pub struct PlantedTable {
            /// What the point does (see [`Planted`]).
            value: f64 = {required}, "number", "", "any";
        }
    }

    const VALUE: Column = Column::value("value", "1", Class::Measured, "the point's value");
    const BAD: Column = Column::value("bad", "1", Class::Check, "failures");

    /// A test kind whose point misbehaves as its parameter `planted.value` says: 0.2 fails its
    /// built-in check, 0.3 overflows to ∞, 0.4 gives a cell that does not fit its column's shape;
    /// any other value is a good point.
    struct Planted;

    impl Kind for Planted {
        const NAME: &'static str = "planted";
        const ABOUT: &'static str = "a test kind";
        type Raw = PlantedSpec;
        type Point = f64;
        type Measured = u64;
        type Tables = NoTables;
        type Shared = ();
        const MAIN: Table<f64, u64> = Table::of(&[
            col(&VALUE, |p, _| {
                if *p == 0.3 {
                    f64::INFINITY.into()
                } else if *p == 0.4 {
                    Cell::Estimate(crate::stats::Estimate {
                        mean: 1.0,
                        se: 0.0,
                        n: 1,
                        clusters: 1,
                    })
                } else {
                    (*p).into()
                }
            }),
            col(&BAD, |_, failures| (*failures).into()),
        ]);
        fn configure(raw: &PlantedSpec, _: &mut Inputs) -> Result<f64, ConfigError> {
            Ok(raw.planted.value)
        }
        fn describe(p: &f64) -> String {
            p.to_string()
        }
        fn work(_: &f64) -> Work {
            Work {
                units: 1,
                unit: "points",
                points: 1,
            }
        }
        fn shared(_: &[&f64]) -> Result<(), Error> {
            Ok(())
        }
        fn run(p: &f64, _: &(), _: &Context) -> Result<Output<u64, NoTables>, Error> {
            let failures = u64::from(*p == 0.2);
            Ok(Output {
                measured: failures,
                tables: NoTables,
                checks: vec![Check {
                    name: "bad",
                    what: "a planted failure",
                    failures,
                    checked: 1,
                }],
                rate: Rate {
                    per_s: 1.0,
                    unit: "points",
                },
                warnings: Vec::new(),
            })
        }
    }

    static PLANTED: Registered<Planted> = Registered::NEW;

    /// Runs kind `planted` over `planted.value` = `sweep`; returns its error and the lines of the
    /// main table (finished or partial).
    fn run_planted(sweep: &str) -> (Error, Vec<String>) {
        let dir = tempfile::tempdir().unwrap();
        let text = format!("[experiment]\nname = \"p\"\nkind = \"planted\"\n[planted]\nvalue = 0.5\n[sweep]\n\"planted.value\" = {sweep}\n");
        let path = dir.path().join("p.toml");
        std::fs::write(&path, text).unwrap();
        let spec = crate::spec::Spec::read(&path, &[]).unwrap();
        let plan = Plan::with_kind(spec, &PLANTED, 1).unwrap();
        let opts = RunOptions {
            out: dir.path().join("out"),
            force: false,
            resume: false,
            quiet: true,
            shard: None,
            sets: Vec::new(),
            threads: 1,
            run: None,
            merged: None,
        };
        let e = run(&plan, &opts).expect_err("a planted fault");
        let table = ["out/p/p.csv", "out/p/p.csv.partial"]
            .iter()
            .find_map(|f| std::fs::read_to_string(dir.path().join(f)).ok())
            .unwrap_or_default();
        (e, table.lines().map(str::to_string).collect())
    }

    /// Every kind's checks are handled alike (the quasi-static kind once lost its row instead): all
    /// rows reach the finished table, then the run fails with exit code 1 naming the point.
    #[test]
    fn a_failed_check_keeps_every_row_and_fails_the_run() {
        let (e, table) = run_planted("[0.1, 0.2, 0.5]");
        assert_eq!(e.exit_code(), 1);
        let msg = e.to_string();
        assert!(
            msg.contains("point 1") && msg.contains("a planted failure"),
            "{msg}"
        );
        assert_eq!(table.len(), 4, "header and three rows: {table:?}");
        assert!(table[2].ends_with(",1"), "{table:?}");
    }

    /// An overflow is never written (the run stops before the point's row), and neither is a cell
    /// that does not fit its declared column.
    #[test]
    fn overflows_and_misdeclared_cells_never_reach_a_table() {
        for (sweep, want) in [
            ("[0.1, 0.3]", "main.value overflowed to inf"),
            (
                "[0.1, 0.4]",
                "column value is declared Value but its accessor gave Estimate",
            ),
        ] {
            let (e, table) = run_planted(sweep);
            let msg = format!("{e:#}");
            assert!(msg.contains(want), "{msg}");
            assert_eq!(table.len(), 2, "only point 0 is written: {table:?}");
            assert!(!table.iter().any(|l| l.contains("inf")));
        }
    }
}
