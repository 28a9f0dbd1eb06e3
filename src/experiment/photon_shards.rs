//! `raycost run SPEC --photon-shard K/N` and the `raycost merge` of its shards: one run's photons
//! split over N processes or machines, joined into the table the unsplit run writes.
//!
//! A shard writes no table: for every point it asks the kind for the point's part
//! ([`super::kind::Kind::trace_part`]: integer sums and counts of photons `[K·P/N, (K+1)·P/N)`,
//! whose random streams are keyed by photon index, never by shard) and writes them, with what is
//! needed to check that shards belong together (spec path and hash, `--set` flags, seed, build,
//! input hashes, K and N), to `DIR/NAME/NAME.photon-shard-K-of-N.json`, atomically (a temporary file
//! renamed into place: a killed shard leaves no file). The merge refuses a set that is incomplete,
//! duplicated, mixed (other N, spec, seed, build, inputs) or not the spec's now, then runs the
//! spec through the ordinary runner with every point's parts ([`super::kind::Context::merged`]):
//! the kind adds them and measures the point with the code of an unsplit run, and the shared code
//! writes its rows, so every measured column equals the unsplit run's bit for bit. Timing columns
//! are sums over the shards (the reference, which needs no photons, is timed in the merge).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::plan::Plan;
use super::runner::{self, RunOptions, Shard};
use crate::error::{Error, OutputError};
use crate::output::meta::{changed_input, host_name, Build, InputFile};
use crate::output::progress::progress;

/// The shard file's format, refused by name when it differs.
const FORMAT: &str = "raycost-photon-shard/1";

/// One photon shard's file.
#[derive(Debug, Serialize, Deserialize)]
struct ShardFile {
    /// [`FORMAT`].
    format: String,
    /// The binary that traced it.
    raycost: Build,
    /// `experiment.kind`.
    kind: String,
    /// The spec, as an absolute path (the merge reads it again).
    spec_path: String,
    /// The spec's place relative to this file's folder (`../../ps.toml`): where the merge looks
    /// when `spec_path` is gone (the spec and its results moved together). Empty in older files.
    #[serde(default)]
    spec_from_shard: String,
    /// SHA-256 of the normalised spec.
    spec_hash: String,
    /// `--set` flags.
    set: Vec<String>,
    /// `experiment.seed`.
    seed: u64,
    /// Files the spec read, with their hashes.
    inputs: Vec<InputFile>,
    /// This shard.
    k: u64,
    /// Shards in all.
    n: u64,
    /// Where and how it ran.
    host: String,
    /// Worker threads.
    threads: usize,
    /// Seconds.
    wall_s: f64,
    /// Each point's part, by point index.
    points: BTreeMap<usize, serde_json::Value>,
}

/// `NAME.photon-shard-K-of-N.json`.
fn file_name(name: &str, s: Shard) -> String {
    format!("{name}.photon-shard-{}-of-{}.json", s.k, s.n)
}

/// Whether `path` is named like a photon shard's file.
fn is_shard_file(path: &Path) -> bool {
    path.file_name()
        .and_then(|f| f.to_str())
        .is_some_and(|f| f.contains(".photon-shard-") && f.ends_with(".json"))
}

/// The photon shard files `inputs` name: the files themselves, or those inside a folder (empty
/// when there are none, so `raycost merge` joins sweep shards as before).
pub fn files(inputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = inputs
        .iter()
        .flat_map(|p| {
            if p.is_dir() {
                std::fs::read_dir(p)
                    .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
                    .unwrap_or_default()
            } else {
                vec![p.clone()]
            }
        })
        .filter(|p| is_shard_file(p))
        .collect();
    out.sort();
    out
}

/// Refuses what `--photon-shard` cannot do with `plan` and `opts`, before anything runs.
fn refuse(plan: &Plan, opts: &RunOptions) -> Result<(), Error> {
    if opts.shard.is_some() {
        return Err(Error::usage(
            "--photon-shard and --shard cannot be combined: split a run by its photons or by its sweep points, not both",
        ));
    }
    if opts.resume {
        return Err(Error::usage(
            "--photon-shard cannot --resume: a shard's file is written whole at its end; run the shard again",
        ));
    }
    for (i, p) in plan.points.iter().enumerate() {
        if let Some(why) = plan.kind.photon_refusal(p.as_ref()) {
            return Err(Error::usage(format!("--photon-shard: point {i}: {why}")));
        }
    }
    Ok(())
}

/// `raycost run SPEC --photon-shard K/N`: every point's part, written to the shard's file.
/// Returns the file and a one-line summary.
pub fn run_shard(plan: &Plan, opts: &RunOptions, shard: Shard) -> Result<(PathBuf, String), Error> {
    refuse(plan, opts)?;
    let name = &plan.spec.experiment.name;
    let dir = opts.out.join(name);
    let path = dir.join(file_name(name, shard));
    if path.exists() && !opts.force {
        return Err(OutputError::new(
            &path,
            "exists already; pass --force to replace it (nothing was written)",
        )
        .into());
    }
    let start = std::time::Instant::now();
    let points: Vec<&dyn super::kind::DynPoint> = plan.points.iter().map(|p| p.as_ref()).collect();
    let shared = plan.kind.shared(&points)?;
    let total: u64 = points.iter().map(|p| p.work().units / shard.n as u64).sum();
    let unit = points.first().map_or("photons", |p| p.work().unit);
    let bar = progress(total, unit, points.len(), opts.quiet);
    let mut parts = BTreeMap::new();
    for (i, p) in points.iter().enumerate() {
        bar.point(i, points.len());
        let ctx = super::kind::Context {
            stream_point: plan.spec.experiment.stream_point(i),
            threads: opts.threads,
            progress: &|k| bar.inc(k),
            merged: None,
        };
        let part =
            plan.kind
                .trace_part(*p, shared.as_ref(), &ctx, (shard.k as u64, shard.n as u64))?;
        parts.insert(i, part);
    }
    bar.finish();
    let spec_path = std::fs::canonicalize(&plan.spec.path)
        .map_or_else(|_| plan.spec.path.clone(), |p| p.display().to_string());
    let file = ShardFile {
        format: FORMAT.into(),
        raycost: Build::current(),
        kind: plan.kind.name().into(),
        spec_from_shard: crate::output::location::relative_location(
            &dir,
            Path::new(&plan.spec.path),
        ),
        spec_path,
        spec_hash: plan.hash.clone(),
        set: opts.sets.clone(),
        seed: plan.spec.experiment.seed,
        inputs: plan.inputs.clone(),
        k: shard.k as u64,
        n: shard.n as u64,
        host: host_name(),
        threads: opts.threads,
        wall_s: start.elapsed().as_secs_f64(),
        points: parts,
    };
    let text = serde_json::to_string(&file).map_err(Error::internal)?;
    write_atomically(&dir, &path, &text)?;
    let msg = format!(
        "photon shard {}/{} of {name}: {} point(s); when every shard is done: raycost merge {}\n",
        shard.k,
        shard.n,
        file.points.len(),
        dir.display()
    );
    Ok((path, msg))
}

/// Writes `text` to `path` through a temporary file in the same folder, renamed into place.
fn write_atomically(dir: &Path, path: &Path, text: &str) -> Result<(), Error> {
    let fail = |e: std::io::Error| Error::from(OutputError::new(path, e.to_string()));
    std::fs::create_dir_all(dir).map_err(fail)?;
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, text).map_err(fail)?;
    std::fs::rename(&tmp, path).map_err(fail)
}

/// Reads one shard file.
fn read(path: &Path) -> Result<ShardFile, Error> {
    let bad = |m: String| Error::usage(format!("{}: {m}", path.display()));
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let file: ShardFile =
        serde_json::from_str(&text).map_err(|e| bad(format!("not a photon shard file ({e})")))?;
    if file.format != FORMAT {
        return Err(bad(format!(
            "format {:?}, this raycost reads {FORMAT:?}",
            file.format
        )));
    }
    let named = path.file_name().and_then(|f| f.to_str()).unwrap_or("");
    let suffix = format!(".photon-shard-{}-of-{}.json", file.k, file.n);
    if !named.ends_with(&suffix) {
        let (k, n) = named
            .rsplit_once(".photon-shard-")
            .and_then(|(_, t)| t.strip_suffix(".json")?.split_once("-of-"))
            .unwrap_or(("?", "?"));
        return Err(bad(format!(
            "is named as shard {k} of {n} but holds shard {} of {}",
            file.k, file.n
        )));
    }
    Ok(file)
}

/// The first field in which `b` differs from `a` so that they cannot be merged.
fn mismatch(a: &ShardFile, b: &ShardFile) -> Option<String> {
    let differ = |what: &str, x: &dyn std::fmt::Debug, y: &dyn std::fmt::Debug| {
        Some(format!("its {what} is {y:?}, shard {}'s {x:?}", a.k))
    };
    if a.n != b.n {
        return differ("shard count N", &a.n, &b.n);
    }
    if a.seed != b.seed {
        return differ("seed", &a.seed, &b.seed);
    }
    if a.spec_hash != b.spec_hash || a.set != b.set || a.kind != b.kind {
        return differ(
            "spec (hash, --set)",
            &(&a.spec_hash, &a.set),
            &(&b.spec_hash, &b.set),
        );
    }
    if (&a.raycost.version, &a.raycost.git_commit) != (&b.raycost.version, &b.raycost.git_commit) {
        return differ(
            "raycost build",
            &a.raycost.describe(),
            &b.raycost.describe(),
        );
    }
    if let Some(f) = changed_input(&a.inputs, &b.inputs) {
        return Some(format!("it read another input file: {f}"));
    }
    (a.points.keys().ne(b.points.keys())).then(|| "its points differ".to_string())
}

/// Checks that `files` are the N shards of one run, once each, consistent with each other;
/// returns them in shard order.
fn complete_set(files: &[PathBuf]) -> Result<Vec<ShardFile>, Error> {
    let mut by_k: BTreeMap<u64, (PathBuf, ShardFile)> = BTreeMap::new();
    for path in files {
        let f = read(path)?;
        if let Some((first, g)) = by_k.values().next() {
            if let Some(why) = mismatch(g, &f) {
                return Err(Error::usage(format!(
                    "{} does not belong with {}: {why}",
                    path.display(),
                    first.display()
                )));
            }
        }
        if let Some((other, _)) = by_k.get(&f.k) {
            return Err(Error::usage(format!(
                "{} and {} are both photon shard {}",
                other.display(),
                path.display(),
                f.k
            )));
        }
        by_k.insert(f.k, (path.clone(), f));
    }
    let n = by_k.values().next().map_or(0, |(_, f)| f.n);
    let missing: Vec<String> = (0..n)
        .filter(|k| !by_k.contains_key(k))
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() {
        let (first_path, _) = by_k.values().next().expect("at least one shard was read");
        let named = first_path
            .file_name()
            .map_or(String::new(), |f| f.to_string_lossy().into_owned());
        let stem = named.split(".photon-shard-").next().unwrap_or("");
        let want = first_path.with_file_name(format!("{stem}.photon-shard-K-of-{n}.json"));
        return Err(Error::usage(format!(
            "photon shard(s) {} of {n} missing: no {} for K = {} (run each with raycost run SPEC --photon-shard K/{n}, or on Slurm scripts/slurm/submit.sh --missing --photons SPEC {n} OUT; nothing was written)",
            missing.join(", "),
            want.display(),
            missing.join(", ")
        )));
    }
    Ok(by_k.into_values().map(|(_, f)| f).collect())
}

/// The shards' spec, planned again: at the absolute path the shards recorded, else at its place
/// relative to the shard files' folder (a spec moved together with its results). The spec is
/// identified by its hash, not its path: a file there with another hash is refused as changed.
fn find_spec(first: &ShardFile, shard_dir: &Path, threads: usize) -> Result<Plan, Error> {
    let mut candidates = vec![PathBuf::from(&first.spec_path)];
    if !first.spec_from_shard.is_empty() {
        let beside = crate::output::location::normalise(&shard_dir.join(&first.spec_from_shard));
        candidates.push(beside);
    }
    let mut changed = None;
    for c in candidates.iter().filter(|c| c.is_file()) {
        let plan = Plan::load(c, &first.set, threads)?;
        if plan.hash == first.spec_hash {
            return Ok(plan);
        }
        changed.get_or_insert((c.clone(), plan.hash));
    }
    if let Some((path, now)) = changed {
        return Err(Error::usage(format!(
            "{} changed since the photon shards ran (spec hash {} then, {} now)",
            path.display(),
            &first.spec_hash[..12.min(first.spec_hash.len())],
            &now[..12.min(now.len())]
        )));
    }
    let looked: Vec<String> = candidates.iter().map(|c| c.display().to_string()).collect();
    Err(Error::usage(format!(
        "the photon shards' spec is gone: no file at {} (put the spec back, unchanged, where it was)",
        looked.join(" nor at ")
    )))
}

/// `raycost merge` of photon shard files: checks them, plans their spec again (refused if it or an
/// input changed since), and runs it with every point's parts. The merged table goes where the
/// unsplit run writes it: beside the shard files. Returns the written paths and the summary.
pub fn merge(
    files: &[PathBuf],
    force: bool,
    quiet: bool,
    threads: usize,
) -> Result<(Vec<PathBuf>, String), Error> {
    let shards = complete_set(files)?;
    let first = &shards[0];
    let shard_dir = files[0].parent().unwrap_or(Path::new("."));
    let plan = find_spec(first, shard_dir, threads)?;
    if let Some(f) = changed_input(&first.inputs, &plan.inputs) {
        return Err(Error::usage(format!(
            "an input changed since the photon shards ran: {f}"
        )));
    }
    if first.points.len() != plan.points.len() {
        return Err(Error::usage(format!(
            "the shards hold {} point(s), the spec has {}",
            first.points.len(),
            plan.points.len()
        )));
    }
    let sets = first.set.clone();
    let mut merged: BTreeMap<usize, Vec<serde_json::Value>> = BTreeMap::new();
    for s in shards {
        for (i, v) in s.points {
            merged.entry(i).or_default().push(v);
        }
    }
    // The merged table goes into the shards' own folder, however it was named on the command
    // line (`.` from inside it included); the runner writes OUT/NAME, so that folder is OUT/NAME.
    let folder = crate::output::location::resolve(shard_dir);
    let name = &plan.spec.experiment.name;
    if folder.file_name().and_then(|f| f.to_str()) != Some(name.as_str()) {
        return Err(Error::usage(format!(
            "{}: photon shards of experiment '{name}' merge into their folder, which must be named {name} as the run made it (rename it back)",
            folder.display()
        )));
    }
    let dir = folder.parent().unwrap_or(Path::new("/")).to_path_buf();
    let opts = RunOptions {
        out: dir,
        force,
        resume: false,
        quiet,
        shard: None,
        sets,
        threads,
        run: None,
        merged: Some(merged),
    };
    runner::run(&plan, &opts)
}

/// A replica's part over a range of its photon ids, which adds to the part of the range that
/// follows it (a kind's `--photon-shard` part).
pub trait RangePart: Clone {
    /// The photon ids it covers, `[lo, hi)`.
    fn ids(&self) -> (u64, u64);
    /// The part of its photons and those of `next`, whose range follows it, or what does not fit.
    fn then(&self, next: &Self) -> Result<Self, String>;
}

/// Every replica's part summed over the shards (`shards`: one list of `replicas` parts per shard,
/// in shard order), checked to cover photons `0..photons` of every replica once, in order.
pub fn add_replica_parts<P: RangePart>(
    replicas: usize,
    photons: u64,
    shards: &[Vec<P>],
) -> Result<Vec<P>, String> {
    if let Some(s) = shards.iter().position(|s| s.len() != replicas) {
        return Err(format!(
            "shard {s} has {} replica(s), the spec {replicas}",
            shards[s].len()
        ));
    }
    (0..replicas)
        .map(|r| {
            let mut it = shards.iter().map(|s| &s[r]);
            let first = it.next().ok_or("no shards")?.clone();
            if first.ids().0 != 0 {
                return Err(format!("replica {r}: no shard starts at photon 0"));
            }
            let total = it.try_fold(first, |acc, p| {
                let (a, b) = (acc.ids(), p.ids());
                if b.0 != a.1 {
                    return Err(format!(
                        "photons {}..{} do not follow photons {}..{}",
                        b.0, b.1, a.0, a.1
                    ));
                }
                acc.then(p)
            })?;
            if total.ids().1 != photons {
                return Err(format!(
                    "replica {r}: the shards cover photons 0..{}, the spec has {photons}",
                    total.ids().1
                ));
            }
            Ok(total)
        })
        .collect()
}

/// The parts of a point's replicas over the photons of `a` and then of `b` (both a
/// [`super::kind::Kind::trace_part`] of every replica, `b`'s photons following `a`'s): what a point
/// traced in photon batches keeps between its batches (see [`super::photon_batches`]).
pub fn add_following<P>(
    a: serde_json::Value,
    b: serde_json::Value,
) -> Result<serde_json::Value, Error>
where
    P: RangePart + Serialize + serde::de::DeserializeOwned,
{
    let read = |v: serde_json::Value| {
        serde_json::from_value::<Vec<P>>(v)
            .map_err(|e| Error::internal(format!("a photon batch's part does not read: {e}")))
    };
    let (a, b) = (read(a)?, read(b)?);
    if a.len() != b.len() {
        return Err(Error::internal(format!(
            "photon batches of {} and {} replica(s)",
            a.len(),
            b.len()
        )));
    }
    let sum = a
        .iter()
        .zip(&b)
        .map(|(x, y)| {
            if y.ids().0 != x.ids().1 {
                return Err(format!(
                    "photons {}..{} do not follow photons {}..{}",
                    y.ids().0,
                    y.ids().1,
                    x.ids().0,
                    x.ids().1
                ));
            }
            x.then(y)
        })
        .collect::<Result<Vec<P>, String>>()
        .map_err(Error::internal)?;
    serde_json::to_value(sum).map_err(Error::internal)
}
