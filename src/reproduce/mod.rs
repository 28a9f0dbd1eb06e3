//! `raycost reproduce DIR`: reruns a result from its metadata and says whether it still comes out
//! the same.
//!
//! A run's `NAME.meta.toml` pins the spec (path and hash of its normalised form), the `--set`
//! flags, the seed, the run index (`experiment.run`, from `--run R`), the shard and the content of
//! every file it read. The spec is planned again with those flags through the code `raycost run`
//! uses ([`Plan::load`], [`runner::run`]); a spec that is gone, a spec whose hash differs (the
//! keys that differ are named) or an input whose content changed ([`changed_input`]) is refused
//! before anything runs (exit 2). A shard reruns as that shard; a merged shard set reruns unsplit
//! (the same counted columns, by the runner's own guarantee). A `raycost crossover` folder
//! (`crossover.meta.toml`) reruns [`crate::crossover::run`] on its recorded input folders and
//! targets. The rerun goes to a scratch folder (a fresh temporary one unless `--out`; never inside
//! DIR or the spec's folder; nothing overwritten without `--force`) and its tables are held against
//! DIR's by [`compare`]: counted columns byte for byte, timings against their stated intervals
//! (module [`crate::output::compare`] states the rule).
//!
//! A result made by another commit or a dirty build is reproduced anyway, and the report says so:
//! a dirty build's tables cannot be tied to any commit.

use std::path::{Path, PathBuf};

use crate::crossover::input::Results;
use crate::error::{Error, OutputError};
use crate::experiment::plan::Plan;
use crate::experiment::runner::{self, RunOptions, Shard};
use crate::output::compare::{compare, RunSpread, Side, TableComparison};
use crate::output::meta::{changed_input, Build, InputFile, Meta};

/// What `raycost reproduce` was asked.
#[derive(Clone, Debug)]
pub struct Options {
    /// The result folder.
    pub dir: PathBuf,
    /// The scratch folder (default: a fresh temporary folder, removed when the result reproduces).
    pub out: Option<PathBuf>,
    /// Worker threads of the rerun.
    pub threads: usize,
    /// Replace files in `out`.
    pub force: bool,
    /// Hold timing means against their stated intervals (`--timings judge`, the default) or only
    /// report them (`--timings report`): a run's standard errors cover its replicas, not the
    /// spread between separate runs, which can be wider.
    pub judge_timings: bool,
    /// Only check that the result could be rerun as recorded (its spec and its keys' defaults, its
    /// input files, its point count; a crossover's input files), without rerunning it: what CI
    /// asks of every committed result.
    pub check_only: bool,
}

/// What a reproduction found.
#[derive(Clone, Debug)]
pub struct Report {
    /// The result folder.
    pub dir: PathBuf,
    /// How the result was rerun (spec, hash, flags, seed, run, shard; or crossover inputs).
    pub rerun: Vec<(String, String)>,
    /// Facts a reader must know (another commit, a dirty build).
    pub notes: Vec<String>,
    /// Where the rerun's tables are (`None` once a temporary folder was removed).
    pub scratch: Option<PathBuf>,
    /// Every table compared.
    pub tables: Vec<TableComparison>,
    /// Only checked, not rerun ([`Options::check_only`]).
    pub checked_only: bool,
}

impl Report {
    /// Whether every counted column of every table is the same.
    pub fn same(&self) -> bool {
        self.tables.iter().all(TableComparison::same)
    }

    /// The verdict line.
    pub fn verdict(&self) -> String {
        let differ: Vec<&str> = self
            .tables
            .iter()
            .filter(|t| !t.same())
            .map(|t| t.file.as_str())
            .collect();
        let compared: usize = self.tables.iter().map(|t| t.compared).sum();
        if self.checked_only {
            "rerunnable: everything it read is as recorded (spec and its keys' defaults, inputs, points; --check: not rerun)".into()
        } else if differ.is_empty() {
            format!(
                "reproduced: {} table(s), {compared} counted column(s), every cell identical",
                self.tables.len()
            )
        } else {
            format!(
                "NOT reproduced: {} of {} table(s) differ ({}){}",
                differ.len(),
                self.tables.len(),
                differ.join(", "),
                self.scratch.as_ref().map_or(String::new(), |s| format!(
                    "; the rerun is kept in {}",
                    s.display()
                ))
            )
        }
    }

    /// The report as text: how it was rerun, notes, one line per table, the verdict.
    pub fn text(&self) -> String {
        let mut s = format!("reproduce {}\n", self.dir.display());
        for (k, v) in &self.rerun {
            s.push_str(&format!("  {k}: {v}\n"));
        }
        for n in &self.notes {
            s.push_str(&format!("note: {n}\n"));
        }
        for t in &self.tables {
            s.push_str(&t.line());
            s.push('\n');
        }
        s.push_str(&self.verdict());
        s.push('\n');
        s
    }

    /// The report as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "result": self.dir.display().to_string(),
            "reproduced": self.same(),
            "rerun": serde_json::Value::Object(
                self.rerun.iter().map(|(k, v)| (k.clone(), v.clone().into())).collect()
            ),
            "notes": self.notes,
            "scratch": self.scratch.as_ref().map(|s| s.display().to_string()),
            "tables": self.tables.iter().map(TableComparison::json).collect::<Vec<_>>(),
            "verdict": self.verdict(),
            "checked_only": self.checked_only,
        })
    }
}

/// Reruns the result in `o.dir` and compares. Refusals are errors with exit code 2; a rerun that
/// fails is its own error; differences are in the report ([`Report::same`]).
pub fn run(o: &Options) -> Result<Report, Error> {
    let crossover_meta = o.dir.join("crossover.meta.toml");
    if crossover_meta.is_file() {
        return reproduce_crossover(o, &crossover_meta);
    }
    let results = find_result(&o.dir)?;
    let meta_path = results.file("meta.toml");
    let meta = Meta::read(&meta_path)?;
    match meta.run.command.as_str() {
        "run" | "merge" => reproduce_run(o, &results, meta, &meta_path),
        other => Err(OutputError::new(
            &meta_path,
            format!(
                "records command \"{other}\": only results of raycost run, merge and crossover can be reproduced"
            ),
        )
        .into()),
    }
}

/// The thread count the result in `dir` recorded, at most this machine's logical CPUs (`None` for a
/// crossover, or where the metadata cannot be read: the refusal then comes from [`run`]).
/// `raycost reproduce` reruns with it unless `--threads` says otherwise: the counted columns do not
/// depend on it, but the timings it holds against their intervals do (a one-thread result rerun on
/// two threads runs in about half the time).
pub fn recorded_threads(dir: &Path) -> Option<usize> {
    if dir.join("crossover.meta.toml").is_file() {
        return None;
    }
    let results = find_result(dir).ok()?;
    let meta = Meta::read(&results.file("meta.toml")).ok()?;
    let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
    (meta.run.threads > 0).then_some(meta.run.threads.min(cpus))
}

/// The result in `dir`: its one `NAME.csv` beside a `NAME.meta.toml`; where a merged table sits
/// beside the shards it was merged from, the merged one.
fn find_result(dir: &Path) -> Result<Results, OutputError> {
    match Results::find(dir) {
        Err(e) if e.message.contains("several runs") => {
            let merged: Vec<String> = std::fs::read_dir(dir)
                .into_iter()
                .flatten()
                .flatten()
                .filter_map(|e| {
                    let n = e.file_name().to_string_lossy().into_owned();
                    let stem = n.strip_suffix(".meta.toml")?.to_string();
                    (!stem.contains(".shard-") && dir.join(format!("{stem}.csv")).is_file())
                        .then_some(stem)
                })
                .collect();
            match merged.as_slice() {
                [one] => Ok(Results {
                    dir: dir.to_path_buf(),
                    name: one.clone(),
                }),
                _ => Err(e),
            }
        }
        other => other,
    }
}

/// A path recorded relative to the folder a run was started in, found again: as recorded (from
/// here), else from each folder above `dir` (a result folder sits below the repository root the
/// run started in, `results/NAME` or `results/NAME/runs/R`).
fn locate(recorded: &str, dir: &Path) -> Option<PathBuf> {
    let p = Path::new(recorded);
    if p.is_absolute() || p.exists() {
        return p.exists().then(|| p.to_path_buf());
    }
    let dir = std::fs::canonicalize(dir).ok()?;
    dir.ancestors()
        .map(|a| a.join(p))
        .find(|candidate| candidate.exists())
}

/// `path` made absolute without requiring it to exist: its deepest existing ancestor resolved
/// through the file system, the rest appended.
fn absolute(path: &Path) -> PathBuf {
    let path = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(path)
    };
    let mut rest = Vec::new();
    let mut at = path.as_path();
    loop {
        if let Ok(c) = std::fs::canonicalize(at) {
            return rest.iter().rev().fold(c, |acc, part| acc.join(part));
        }
        match (at.parent(), at.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                at = parent;
            }
            _ => return path,
        }
    }
}

/// The scratch folder: `--out` (refused inside any of `forbidden`), or a fresh temporary folder.
/// Returns it and whether it is a temporary one (removed when the result reproduces).
fn scratch(o: &Options, name: &str, forbidden: &[(&Path, &str)]) -> Result<(PathBuf, bool), Error> {
    let Some(out) = &o.out else {
        let base = std::env::temp_dir();
        for n in 0..1000 {
            let p = base.join(format!(
                "raycost-reproduce-{name}-{}-{n}",
                std::process::id()
            ));
            match std::fs::create_dir(&p) {
                Ok(()) => return Ok((p, true)),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    return Err(OutputError::new(
                        &p,
                        format!("cannot create a scratch folder: {e}"),
                    )
                    .into())
                }
            }
        }
        return Err(OutputError::new(&base, "no fresh scratch folder name is free").into());
    };
    let at = absolute(out);
    for (place, what) in forbidden {
        let place = absolute(place);
        if at.starts_with(&place) {
            return Err(OutputError::new(
                out,
                format!(
                    "is inside {what} {}: the rerun must not write there (give another --out)",
                    place.display()
                ),
            )
            .into());
        }
    }
    Ok((out.clone(), false))
}

/// The key = value pairs of a TOML tree, flattened (`base.detp.photons = 1000`).
fn flatten(prefix: &str, v: &toml::Value, out: &mut std::collections::BTreeMap<String, String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        other => {
            out.insert(prefix.to_string(), other.to_string());
        }
    }
}

/// The keys of the normalised spec that differ between the result and now, at most eight.
fn spec_differences(then: &toml::Table, now: &toml::Table) -> Vec<String> {
    let (mut a, mut b) = (Default::default(), Default::default());
    flatten("", &toml::Value::Table(then.clone()), &mut a);
    flatten("", &toml::Value::Table(now.clone()), &mut b);
    let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    let show = |k: &str| k.strip_prefix("base.").unwrap_or(k).to_string();
    let mut out: Vec<String> = keys
        .into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| match (a.get(k), b.get(k)) {
            (Some(x), Some(y)) => format!("{} = {x} then, {y} now", show(k)),
            (Some(x), None) => format!("{} = {x} then, absent now", show(k)),
            (None, Some(y)) => format!("{} absent then, {y} now", show(k)),
            (None, None) => unreachable!("a key of one side"),
        })
        .collect();
    if out.len() > 8 {
        let more = out.len() - 8;
        out.truncate(8);
        out.push(format!("… {more} more"));
    }
    out
}

/// What a reader must know about the build that made a result.
fn build_notes(what: &str, then: &Build, notes: &mut Vec<String>) {
    let now = Build::current();
    let short = |c: &str| c[..c.len().min(12)].to_string();
    if then.git_dirty == "true" {
        notes.push(format!(
            "{what} was made by a dirty build (uncommitted changes on commit {}): its tables cannot be tied to any commit, so reproducing them cannot be guaranteed",
            short(&then.git_commit)
        ));
    }
    if then.git_commit != now.git_commit {
        notes.push(format!(
            "{what} was made by commit {}, this raycost is commit {}{}: anything changed in between may change the tables",
            short(&then.git_commit),
            short(&now.git_commit),
            if now.git_dirty == "true" { " with uncommitted changes" } else { "" }
        ));
    } else if now.git_dirty == "true" {
        notes.push("this raycost is a dirty build: the rerun cannot be tied to a commit".into());
    }
}

/// Whether a result came from `raycost run --run R`: it sits in `runs/R`, or its table has
/// `experiment.run` among the `--set` keys, which come before the other keys (`experiment.seed`
/// precedes `experiment.run` otherwise).
fn made_with_run_flag(dir: &Path, main: &Path) -> bool {
    let in_runs = std::fs::canonicalize(dir)
        .ok()
        .and_then(|d| d.parent().map(|p| p.ends_with("runs")))
        .unwrap_or(false);
    let header: Vec<String> = ::csv::Reader::from_path(main)
        .ok()
        .and_then(|mut r| {
            r.headers()
                .ok()
                .map(|h| h.iter().map(str::to_string).collect())
        })
        .unwrap_or_default();
    let at = |k: &str| header.iter().position(|h| h == k);
    in_runs || matches!((at("experiment.run"), at("experiment.seed")), (Some(r), Some(s)) if r < s)
}

/// The run index a run recorded (`experiment.run`, set by `--run R`).
fn run_index(meta: &Meta) -> Option<u64> {
    meta.spec
        .get("base")
        .and_then(|b| b.get("experiment"))
        .and_then(|e| e.get("run"))
        .and_then(toml::Value::as_integer)
        .and_then(|r| u64::try_from(r).ok())
}

fn reproduce_run(
    o: &Options,
    results: &Results,
    meta: Meta,
    meta_path: &Path,
) -> Result<Report, Error> {
    let recorded = &meta.run.spec_path;
    let spec = locate(recorded, &o.dir).ok_or_else(|| {
        OutputError::new(
            meta_path,
            format!(
                "its spec {recorded} is gone (looked from here and from every folder above {}): it cannot be rerun",
                o.dir.display()
            ),
        )
    })?;
    // `--run R` is given again only where the result came from it: it makes `experiment.run` a
    // `--set` key, which moves its column to the front of the table.
    let run = run_index(&meta).filter(|_| made_with_run_flag(&o.dir, &results.file("csv")));
    let mut sets = meta.run.set.clone();
    sets.extend(run.map(|r| format!("experiment.run={r}")));
    let run_folder = run;
    let plan = Plan::load(&spec, &sets, o.threads)?;
    check_unchanged(&meta, &plan, &spec, meta_path)?;
    // A merged shard set reruns unsplit: the same counted columns, by the runner's guarantee.
    let shard = match meta.run.shard.as_str() {
        s if meta.run.command == "merge" || s == "all" => None,
        s => Some(
            s.parse::<Shard>()
                .map_err(|e| OutputError::new(meta_path, format!("records shard {e}")))?,
        ),
    };
    if o.check_only {
        let mut notes = Vec::new();
        build_notes("the result", &meta.raycost, &mut notes);
        return Ok(checked(
            o,
            rerun_rows(&meta, &plan, &spec, run, shard, o.threads),
            notes,
        ));
    }
    let name = plan.spec.experiment.name.clone();
    let spec_dir = spec.parent().unwrap_or(Path::new(".")).to_path_buf();
    let (out, temporary) = scratch(
        o,
        &name,
        &[
            (&o.dir, "the result folder"),
            (&spec_dir, "the spec's folder"),
        ],
    )?;
    let opts = RunOptions {
        out: out.clone(),
        force: o.force,
        resume: false,
        quiet: true,
        shard,
        sets: meta.run.set.clone(),
        threads: o.threads,
        run: run_folder,
        merged: None,
    };
    let new_dir = opts.dir(&name);
    if absolute(&new_dir).starts_with(absolute(&o.dir))
        || absolute(&o.dir).starts_with(absolute(&new_dir))
    {
        return Err(OutputError::new(
            &out,
            format!(
                "the rerun would write {}, which is the result's own folder or holds it (give another --out)",
                new_dir.display()
            ),
        )
        .into());
    }
    let mut rerun = rerun_rows(&meta, &plan, &spec, run, shard, o.threads);
    let mut notes = Vec::new();
    build_notes("the result", &meta.raycost, &mut notes);
    for s in &meta.shards {
        if s.raycost != meta.raycost {
            build_notes(&format!("shard {}", s.file), &s.raycost, &mut notes);
        }
    }
    let outcome = runner::run(&plan, &opts);
    let outcome = outcome.and_then(|_| {
        let stem = runner::stem(&name, shard);
        let new_meta = Meta::read(&new_dir.join(format!("{stem}.meta.toml")))?;
        let old = Side::of_run(&o.dir, &results.name, meta.clone())?;
        let new = Side::of_run(&new_dir, &stem, new_meta)?;
        let spread = committed_runs_spread(&o.dir, &results.name)?;
        Ok(compare(&old, &new, o.judge_timings, spread.as_ref())?)
    });
    rerun.push(("rerun".into(), new_dir.display().to_string()));
    finish(o, out, temporary, rerun, notes, outcome)
}

/// The spread between the separate runs committed beside the result in `dir` (its `runs/R`
/// folders, or its siblings when it is one of them), if there are at least two.
fn committed_runs_spread(dir: &Path, name: &str) -> Result<Option<RunSpread>, Error> {
    let mut sides = Vec::new();
    for folder in RunSpread::sibling_runs(dir, name) {
        let meta = Meta::read(&folder.join(format!("{name}.meta.toml")))?;
        sides.push(Side::of_run(&folder, name, meta)?);
    }
    Ok(RunSpread::of_runs(&sides)?)
}

/// Refuses a rerun that could not reproduce the result: the spec (or its keys' defaults), an input
/// file or the point count changed since the result was made.
fn check_unchanged(meta: &Meta, plan: &Plan, spec: &Path, meta_path: &Path) -> Result<(), Error> {
    if plan.hash != meta.run.spec_hash {
        let keys = spec_differences(&meta.spec, &plan.normalized);
        return Err(OutputError::new(
            spec,
            format!(
                "spec hash {} recorded in {}, {} now: the spec (or the defaults of its keys) changed since the result was made{}",
                meta.run.spec_hash,
                meta_path.display(),
                plan.hash,
                if keys.is_empty() { String::new() } else { format!(" ({})", keys.join("; ")) }
            ),
        )
        .into());
    }
    if let Some(f) = changed_input(&meta.inputs, &plan.inputs) {
        return Err(OutputError::new(
            meta_path,
            format!("an input changed since the result was made: {f}"),
        )
        .into());
    }
    if meta.run.points_total != 0 && meta.run.points_total != plan.points.len() {
        return Err(OutputError::new(
            meta_path,
            format!(
                "records {} point(s), the spec has {} now",
                meta.run.points_total,
                plan.points.len()
            ),
        )
        .into());
    }
    Ok(())
}

/// The rerun's header rows: what was rerun (spec, seed, sets, run, shard, points, threads, inputs).
fn rerun_rows(
    meta: &Meta,
    plan: &Plan,
    spec: &Path,
    run: Option<u64>,
    shard: Option<Shard>,
    threads: usize,
) -> Vec<(String, String)> {
    vec![
        (
            "spec".to_string(),
            format!("{} (hash {}, unchanged)", spec.display(), &plan.hash[..16]),
        ),
        ("seed".into(), plan.spec.experiment.seed.to_string()),
        (
            "set".into(),
            if meta.run.set.is_empty() {
                "(none)".into()
            } else {
                meta.run.set.join(" ")
            },
        ),
        ("run".into(), run.map_or("(none)".into(), |r| r.to_string())),
        (
            "shard".into(),
            match (shard, meta.run.command.as_str()) {
                (Some(s), _) => format!("{}/{}", s.k, s.n),
                (None, "merge") => format!("{} (rerun unsplit)", meta.run.shard),
                (None, _) => "all".into(),
            },
        ),
        ("points".into(), plan.points.len().to_string()),
        (
            "threads".into(),
            format!("{} (the result: {})", threads, meta.run.threads),
        ),
        (
            "inputs".into(),
            format!("{} file(s), content unchanged", meta.inputs.len()),
        ),
    ]
}

/// The targets of a crossover result: recorded in its metadata, else the `target` column of its
/// `crossover.csv` (each target has rows there), in order of first appearance.
fn crossover_targets(meta: &Meta, dir: &Path) -> Result<Vec<f64>, OutputError> {
    if let Some(t) = meta.extra.get("targets").and_then(toml::Value::as_array) {
        return Ok(t.iter().filter_map(toml::Value::as_float).collect());
    }
    let path = dir.join("crossover.csv");
    let mut reader = ::csv::Reader::from_path(&path)
        .map_err(|e| OutputError::new(&path, format!("cannot read: {e}")))?;
    let bad = |e: ::csv::Error| OutputError::new(&path, format!("unreadable CSV: {e}"));
    let col = reader
        .headers()
        .map_err(bad)?
        .iter()
        .position(|h| h == "target")
        .ok_or_else(|| {
            OutputError::new(&path, "has no column 'target' (the crossover's targets)")
        })?;
    let mut targets: Vec<f64> = Vec::new();
    for r in reader.records() {
        let r = r.map_err(bad)?;
        let t: f64 = r[col].parse().map_err(|_| {
            OutputError::new(&path, format!("target {:?} is not a number", &r[col]))
        })?;
        if !targets.contains(&t) {
            targets.push(t);
        }
    }
    Ok(targets)
}

fn reproduce_crossover(o: &Options, meta_path: &Path) -> Result<Report, Error> {
    let meta = Meta::read(meta_path)?;
    let input = |role: &str| -> Result<Option<PathBuf>, Error> {
        let Some(dir) = meta
            .extra
            .get(role)
            .and_then(|t| t.get("dir"))
            .and_then(toml::Value::as_str)
        else {
            return Ok(None);
        };
        locate(dir, &o.dir).map(Some).ok_or_else(|| {
            OutputError::new(
                meta_path,
                format!("its {role} input folder {dir} is gone: it cannot be rerun"),
            )
            .into()
        })
    };
    let missing = |role: &str| {
        OutputError::new(
            meta_path,
            format!("records no {role} input folder ([extra.{role}] dir)"),
        )
    };
    let fronts = input("fronts")?.ok_or_else(|| missing("fronts"))?;
    let points = input("points")?.ok_or_else(|| missing("points"))?;
    let frames = input("frames")?;
    let confirm = input("confirm")?;
    let targets = crossover_targets(&meta, &o.dir)?;
    if o.check_only {
        return check_crossover_inputs(o, &meta, meta_path);
    }
    let mut forbidden: Vec<(&Path, &str)> = vec![(&o.dir, "the result folder")];
    for d in [
        Some(&fronts),
        Some(&points),
        frames.as_ref(),
        confirm.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        forbidden.push((d, "an input folder"));
    }
    let label = o
        .dir
        .file_name()
        .map_or("crossover".into(), |n| n.to_string_lossy().into_owned());
    let (out, temporary) = scratch(o, &label, &forbidden)?;
    let show = |p: &Option<PathBuf>| {
        p.as_ref()
            .map_or("(none)".into(), |p| p.display().to_string())
    };
    let rerun = vec![
        ("command".to_string(), "crossover".to_string()),
        ("fronts".into(), fronts.display().to_string()),
        ("points".into(), points.display().to_string()),
        ("frames".into(), show(&frames)),
        ("confirm".into(), show(&confirm)),
        (
            "targets".into(),
            targets
                .iter()
                .map(|t| t.to_string())
                .collect::<Vec<_>>()
                .join(","),
        ),
        ("rerun".into(), out.display().to_string()),
    ];
    let mut notes = Vec::new();
    build_notes("the result", &meta.raycost, &mut notes);
    let outcome = crate::crossover::run(&crate::crossover::Options {
        fronts,
        points,
        frames,
        confirm,
        targets,
        out: out.clone(),
        force: o.force,
    })
    .and_then(|_| {
        let new_meta = Meta::read(&out.join("crossover.meta.toml"))?;
        if let Some(f) = changed_input(&meta.inputs, &new_meta.inputs) {
            return Err(OutputError::new(
                meta_path,
                format!("an input changed since the result was made: {f}"),
            )
            .into());
        }
        let old = Side::of_crossover(&o.dir, meta.clone());
        let new = Side::of_crossover(&out, new_meta);
        Ok(compare(&old, &new, o.judge_timings, None)?)
    });
    finish(o, out, temporary, rerun, notes, outcome)
}

/// The report; a temporary scratch folder is removed unless the result differs (then it is kept
/// for inspection).
fn finish(
    o: &Options,
    out: PathBuf,
    temporary: bool,
    rerun: Vec<(String, String)>,
    notes: Vec<String>,
    outcome: Result<Vec<TableComparison>, Error>,
) -> Result<Report, Error> {
    let keep = matches!(&outcome, Ok(t) if !t.iter().all(TableComparison::same));
    if temporary && !keep {
        let _ = std::fs::remove_dir_all(&out);
    }
    Ok(Report {
        dir: o.dir.clone(),
        rerun,
        notes,
        scratch: (!temporary || keep).then_some(out),
        tables: outcome?,
        checked_only: false,
    })
}

/// `--check` of a crossover: every input file it recorded is still there with the same content.
fn check_crossover_inputs(o: &Options, meta: &Meta, meta_path: &Path) -> Result<Report, Error> {
    for i in &meta.inputs {
        let now =
            locate(&i.path, &o.dir).and_then(|p| InputFile::hash(&p, &i.role, Path::new(".")).ok());
        if now.as_ref().is_none_or(|n| n.sha256 != i.sha256) {
            return Err(OutputError::new(
                meta_path,
                format!(
                    "an input changed since the result was made: {} ({})",
                    i.path,
                    if now.is_some() {
                        "other content"
                    } else {
                        "gone"
                    }
                ),
            )
            .into());
        }
    }
    let mut notes = Vec::new();
    build_notes("the result", &meta.raycost, &mut notes);
    let rerun = vec![(
        "inputs".to_string(),
        format!("{} file(s), content unchanged", meta.inputs.len()),
    )];
    Ok(checked(o, rerun, notes))
}

/// The report of a check that found the result rerunnable (nothing run, nothing written).
fn checked(o: &Options, rerun: Vec<(String, String)>, notes: Vec<String>) -> Report {
    Report {
        dir: o.dir.clone(),
        rerun,
        notes,
        scratch: None,
        tables: Vec::new(),
        checked_only: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rerun_takes_the_thread_count_the_result_recorded() {
        // Committed results: a one-thread run, a two-thread run, a crossover.
        assert_eq!(
            recorded_threads(Path::new("results/detp-engines-cost/runs/2")),
            Some(1)
        );
        let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
        assert_eq!(
            recorded_threads(Path::new("results/cornell-levels")),
            Some(2.min(cpus))
        );
        assert_eq!(
            recorded_threads(Path::new("results/crossover-cornell")),
            None
        );
        assert_eq!(recorded_threads(Path::new("results/no-such-result")), None);
    }

    #[test]
    fn spec_differences_name_the_keys() {
        let then: toml::Table = "[base.detp]\nphotons = 1000\nq = 0.5\n[sweep]\n"
            .parse()
            .unwrap();
        let now: toml::Table = "[base.detp]\nphotons = 2000\nq = 0.5\nnew_key = true\n[sweep]\n"
            .parse()
            .unwrap();
        assert_eq!(
            spec_differences(&then, &now),
            [
                "detp.new_key absent then, true now",
                "detp.photons = 1000 then, 2000 now"
            ]
        );
        assert!(spec_differences(&then, &then).is_empty());
    }

    #[test]
    fn a_path_not_yet_made_is_made_absolute_through_its_existing_part() {
        let d = tempfile::tempdir().unwrap();
        let real = std::fs::canonicalize(d.path()).unwrap();
        assert_eq!(absolute(&d.path().join("a/b")), real.join("a/b"));
        assert!(absolute(&d.path().join("a/b")).starts_with(absolute(d.path())));
    }
}
