//! `raycost merge`: joins the shard files of a sweep (`NAME.shard-K-of-N.csv`, their side tables such
//! as `.hist.csv`, and their `.meta.toml`) into the table one unsharded run would have written.
//!
//! Everything is read and checked before anything is written: all N shards present once, one spec
//! hash and one raycost version, one header per table, every point of the sweep present exactly once
//! and in the shard it belongs to, no torn line (a file not ending in a newline, or a row with the
//! wrong number of fields). Any problem is an [`OutputError`] naming the file (exit code 2), and no
//! output is created. Rows are re-serialised with the same CSV writer settings as the runner, so the
//! merged table is byte-identical to an unsharded run's in every non-timing column; side-table rows
//! keep their order within a point. Every row is read back and checked ([`super::readback`]; a torn
//! row anywhere is refused), and each table's header must be the columns its metadata records.
//!
//! Written through the result-folder protocol ([`super::folder`]): the shards' locks are held while
//! they are read (a shard being rerun or resumed is refused), the output's lock while it is written;
//! an `--out` that would overwrite any file the merge reads is refused; outputs are staged as new
//! temporary files, fsynced, and published with the main table last. Existing outputs are replaced
//! only with `--force`.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::folder::{self, Lock};
use super::meta::{changed_input, Meta, ShardRecord};
use super::readback::{check_table, Line, Table, Torn};
use super::OutputError;

fn err(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Merges the shards named by `inputs` (one results folder, or shard CSV files) and prints what it
/// wrote unless `quiet`. `out` names the merged main table (default: `NAME.csv` beside the shards).
pub fn run(inputs: &[PathBuf], out: Option<&Path>, force: bool, quiet: bool) -> anyhow::Result<()> {
    let merged = merge(inputs, out, force)?;
    if !quiet {
        let mut so = std::io::stdout().lock();
        writeln!(
            so,
            "merged {} shards, {} points",
            merged.shards, merged.points
        )?;
        for p in &merged.written {
            writeln!(so, "wrote {}", p.display())?;
        }
    }
    Ok(())
}

/// What a merge wrote.
#[derive(Debug)]
pub struct Merged {
    /// Number of shards joined.
    pub shards: usize,
    /// Number of points in the merged table.
    pub points: usize,
    /// The files written: main table, side tables, metadata.
    pub written: Vec<PathBuf>,
}

/// Checks and merges; see the module documentation.
pub fn merge(inputs: &[PathBuf], out: Option<&Path>, force: bool) -> Result<Merged, OutputError> {
    let files = collect(inputs)?;
    let n = files[0].n;
    let name = files[0].name.clone();
    let default_out = files[0].csv.with_file_name(format!("{name}.csv"));
    // No shard may be written while it is read (a rerun with --force, a --resume).
    let _shard_locks = files
        .iter()
        .map(|f| Lock::acquire_if_writable(parent_dir(&f.csv), &f.stem))
        .collect::<Result<Vec<_>, _>>()?;
    let shards: Vec<Shard> = files
        .into_iter()
        .map(Shard::load)
        .collect::<Result<_, _>>()?;
    check_same_run(&shards)?;
    let total = shards[0].points_total;
    // Main table: one header, every point exactly once, in its own shard.
    let with_rows: Vec<&Shard> = shards.iter().filter(|s| s.main.header.is_some()).collect();
    let header = with_rows.first().and_then(|s| s.main.header.clone());
    for s in &with_rows[..] {
        check_header(&s.main, &with_rows[0].main)?;
    }
    check_main_rows(&shards, n, total)?;
    let table_names = check_side_tables(&shards)?;
    let outputs = Outputs::new(out, &shards[0], &name, &table_names)?;
    let _out_lock = outputs.claim(&shards, force, |main| {
        refuse_out_inside_inputs(main, inputs, &default_out)
    })?;
    let contents = outputs.assemble(&shards, header, total, n);
    outputs.publish(&contents)?;
    Ok(Merged {
        shards: n,
        points: total,
        written: outputs.all,
    })
}

/// Refuses an `--out` inside a folder the merge reads, unless it names the merged table where the
/// merge puts it by default (`default`, `NAME.csv` beside the shards, where the unsplit run writes
/// it): any other table there would make the shards' folder hold two runs.
fn refuse_out_inside_inputs(
    main: &Path,
    inputs: &[PathBuf],
    default: &Path,
) -> Result<(), OutputError> {
    use super::location::{refuse_inside, resolve};
    if resolve(main) == resolve(default) {
        return Ok(());
    }
    let folders: Vec<&Path> = inputs
        .iter()
        .map(|p| {
            if p.is_dir() {
                p.as_path()
            } else {
                parent_dir(p)
            }
        })
        .collect();
    refuse_inside(main, "--out", &folders)
}

/// One spec, one version, one set of inputs, one sweep size.
fn check_same_run(shards: &[Shard]) -> Result<(), OutputError> {
    let first = &shards[0];
    for s in &shards[1..] {
        if s.spec_hash != first.spec_hash {
            return Err(err(
                &s.meta_path,
                format!(
                    "spec hash {} differs from {} in {}: the shards come from different specs (or different --set overrides); rerun them from one spec",
                    short_hash(&s.spec_hash),
                    short_hash(&first.spec_hash),
                    first.meta_path.display()
                ),
            ));
        }
        if s.version != first.version {
            return Err(err(
                &s.meta_path,
                format!("written by raycost {}, but {} by raycost {}: rerun the shards with one raycost version", s.version, first.meta_path.display(), first.version),
            ));
        }
        if let Some(file) = changed_input(&first.meta.inputs, &s.meta.inputs) {
            return Err(err(
                &s.meta_path,
                format!(
                    "was computed from other input files than {}: {file}; rerun the shards on the same inputs",
                    first.meta_path.display()
                ),
            ));
        }
        if s.points_total != first.points_total {
            return Err(err(
                &s.meta_path,
                format!(
                    "records {} sweep points, but {} records {}",
                    s.points_total,
                    first.meta_path.display(),
                    first.points_total
                ),
            ));
        }
    }
    Ok(())
}

/// Every point exactly once, in its own shard, and each shard's rows the points its metadata
/// lists.
fn check_main_rows(shards: &[Shard], n: usize, total: usize) -> Result<(), OutputError> {
    let mut seen: BTreeMap<usize, (&Path, u64)> = BTreeMap::new();
    for s in shards {
        for r in &s.main.rows {
            if r.point >= total {
                return Err(err(
                    &s.main.path,
                    format!(
                        "line {}: point {} is out of range: the spec has {total} points (0 to {})",
                        r.line,
                        r.point,
                        total.saturating_sub(1)
                    ),
                ));
            }
            if r.point % n != s.k {
                return Err(err(
                    &s.main.path,
                    format!(
                        "line {}: point {} does not belong to shard {}/{n} (it is in shard {}/{n})",
                        r.line,
                        r.point,
                        s.k,
                        r.point % n
                    ),
                ));
            }
            if let Some((p, line)) = seen.get(&r.point) {
                return Err(err(
                    &s.main.path,
                    format!(
                        "line {}: point {} is duplicated (also at {} line {line})",
                        r.line,
                        r.point,
                        p.display()
                    ),
                ));
            }
            seen.insert(r.point, (&s.main.path, r.line));
        }
    }
    for s in shards {
        let missing: Vec<usize> = (s.k..total)
            .step_by(n)
            .filter(|p| !seen.contains_key(p))
            .collect();
        if !missing.is_empty() {
            return Err(err(
                &s.main.path,
                format!(
                    "{} missing (they belong to shard {}/{n}; the sweep has {total} points)",
                    list_points(&missing),
                    s.k
                ),
            ));
        }
        let listed: BTreeSet<usize> = s.meta_points.iter().copied().collect();
        let rows: BTreeSet<usize> = s.main.rows.iter().map(|r| r.point).collect();
        if listed != rows {
            let extra: Vec<usize> = rows.difference(&listed).copied().collect();
            let absent: Vec<usize> = listed.difference(&rows).copied().collect();
            let what = if !extra.is_empty() {
                format!(
                    "has rows for points {} that {} does not list",
                    join(&extra),
                    s.meta_path.display()
                )
            } else {
                format!(
                    "has no rows for points {} that {} lists",
                    join(&absent),
                    s.meta_path.display()
                )
            };
            return Err(err(
                &s.main.path,
                format!("{what}: the CSV and its metadata come from different runs"),
            ));
        }
    }

    Ok(())
}

/// Side tables (e.g. `hist`): every shard with points has the same ones, with one header, and
/// their rows belong to points of the shard's main table. Returns their names.
fn check_side_tables(shards: &[Shard]) -> Result<BTreeSet<String>, OutputError> {
    let mut table_names: BTreeSet<String> = BTreeSet::new();
    for s in shards {
        table_names.extend(s.tables.keys().cloned());
    }
    for t in &table_names {
        let mut reference: Option<&Table> = None;
        for s in shards {
            let Some(tab) = s.tables.get(t) else {
                if s.main.rows.is_empty() {
                    continue;
                }
                let want = s.csv.with_file_name(format!("{}.{t}.csv", s.stem));
                return Err(err(
                    &want,
                    format!("is missing: other shards have a {t} table"),
                ));
            };
            let main_points: BTreeSet<usize> = s.main.rows.iter().map(|r| r.point).collect();
            if let Some(r) = tab.rows.iter().find(|r| !main_points.contains(&r.point)) {
                return Err(err(
                    &tab.path,
                    format!(
                        "line {}: a row of point {}, which has no row in {}",
                        r.line,
                        r.point,
                        s.main.path.display()
                    ),
                ));
            }
            if tab.header.is_some() {
                match reference {
                    None => reference = Some(tab),
                    Some(re) => check_header(tab, re)?,
                }
            }
        }
    }

    Ok(table_names)
}

/// Where a merge writes: the main table, each side table beside it, the metadata.
struct Outputs {
    main: PathBuf,
    /// The main table's path without `.csv`.
    base: String,
    meta: PathBuf,
    /// Every output, the main table first and the metadata last.
    all: Vec<PathBuf>,
}

impl Outputs {
    /// The paths for `--out` (or `NAME.csv` beside the first shard).
    fn new(
        out: Option<&Path>,
        first: &Shard,
        name: &str,
        table_names: &BTreeSet<String>,
    ) -> Result<Self, OutputError> {
        let main = match out {
            Some(p) => {
                if p.extension().and_then(|e| e.to_str()) != Some("csv") {
                    return Err(err(p, "--out must name the merged .csv file (its .hist.csv and .meta.toml go beside it)"));
                }
                p.to_path_buf()
            }
            None => first.csv.with_file_name(format!("{name}.csv")),
        };
        let base = main
            .to_string_lossy()
            .strip_suffix(".csv")
            .map(str::to_string)
            .unwrap_or_default();
        let meta = PathBuf::from(format!("{base}.meta.toml"));
        let mut o = Outputs {
            main: main.clone(),
            base,
            meta: meta.clone(),
            all: vec![main],
        };
        let tables: Vec<PathBuf> = table_names.iter().map(|t| o.table(t)).collect();
        o.all.extend(tables);
        o.all.push(meta);
        Ok(o)
    }

    fn table(&self, t: &str) -> PathBuf {
        PathBuf::from(format!("{}.{t}.csv", self.base))
    }

    /// Refuses an output that is one of the inputs, that `inside` refuses (an `--out` inside a
    /// folder the merge reads), or that exists without `--force`; takes the output's lock and
    /// removes a killed merge's temporaries. The lock is held while it lives.
    fn claim(
        &self,
        shards: &[Shard],
        force: bool,
        inside: impl Fn(&Path) -> Result<(), OutputError>,
    ) -> Result<Lock, OutputError> {
        let outputs = &self.all;
        let main_out = &self.main;
        let base = &self.base;
        let read: Vec<&Path> = shards.iter().flat_map(Shard::files).collect();
        for p in outputs {
            if let Some(input) = read.iter().find(|r| same_file(p, r)) {
                return Err(err(
                    p,
                    format!(
                        "would overwrite {}, which this merge reads; choose another --out",
                        input.display()
                    ),
                ));
            }
        }
        inside(main_out)?;
        let out_dir = parent_dir(main_out);
        fs::create_dir_all(out_dir)
            .map_err(|e| err(out_dir, format!("cannot create the folder: {e}")))?;
        let out_stem = Path::new(base)
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        let lock = Lock::acquire(out_dir, &out_stem)?;
        folder::remove_stale_temporaries(outputs).map_err(|e| {
            err(
                out_dir,
                format!("cannot remove a killed merge's temporary files: {e}"),
            )
        })?;
        for p in outputs {
            if p.exists() && !force {
                return Err(err(
                    p,
                    "exists already; pass --force to replace it (nothing was written)",
                ));
            }
        }
        Ok(lock)
    }

    /// The merged files' bytes, in point order (stable: side-table rows keep their order within
    /// a point), the main table last (published last).
    fn assemble(
        &self,
        shards: &[Shard],
        header: Option<Vec<u8>>,
        total: usize,
        n: usize,
    ) -> Vec<(PathBuf, Vec<u8>)> {
        let table_names: Vec<String> = shards
            .iter()
            .flat_map(|s| s.tables.keys().cloned())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let mut contents: Vec<(PathBuf, Vec<u8>)> = Vec::new();
        let mut main_bytes = header.unwrap_or_default();
        let mut rows: Vec<&Line> = shards.iter().flat_map(|s| s.main.rows.iter()).collect();
        rows.sort_by_key(|r| r.point);
        for r in rows {
            main_bytes.extend_from_slice(&r.bytes);
        }
        for t in &table_names {
            let tabs: Vec<&Table> = shards.iter().filter_map(|s| s.tables.get(t)).collect();
            let mut bytes = tabs
                .iter()
                .find_map(|t| t.header.clone())
                .unwrap_or_default();
            let mut rows: Vec<&Line> = tabs.iter().flat_map(|t| t.rows.iter()).collect();
            rows.sort_by_key(|r| r.point);
            for r in rows {
                bytes.extend_from_slice(&r.bytes);
            }
            contents.push((self.table(t), bytes));
        }
        contents.push((
            self.meta.clone(),
            merged_meta(shards, total, n).render().into_bytes(),
        ));
        contents.push((self.main.clone(), main_bytes));
        contents
    }

    /// Stages every file, then publishes them all (the main table last).
    fn publish(&self, contents: &[(PathBuf, Vec<u8>)]) -> Result<(), OutputError> {
        let main_out = &self.main;
        let staged = contents
            .iter()
            .map(|(p, bytes)| {
                folder::stage(p, bytes).map_err(|e| {
                    err(
                        p,
                        format!("cannot write the merged file: {e} (nothing was replaced)"),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        folder::publish_staged(staged).map_err(|e| {
            err(
                main_out,
                format!("cannot move the merged files into place: {e}"),
            )
        })?;
        Ok(())
    }
}

/// One shard's file names.
#[derive(Debug, Clone)]
struct ShardFile {
    csv: PathBuf,
    name: String,
    stem: String,
    k: usize,
    n: usize,
}

/// `NAME.shard-K-of-N.csv` → (NAME, K, N).
fn parse_shard_name(file_name: &str) -> Option<(String, usize, usize)> {
    let stem = file_name.strip_suffix(".csv")?;
    let (name, kn) = stem.rsplit_once(".shard-")?;
    let (k, n) = kn.split_once("-of-")?;
    let num = |s: &str| {
        (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse::<usize>().ok())
            .flatten()
    };
    (!name.is_empty()).then_some(())?;
    Some((name.to_string(), num(k)?, num(n)?))
}

fn shard_file(csv: PathBuf) -> Option<ShardFile> {
    let file_name = csv.file_name()?.to_str()?.to_string();
    let (name, k, n) = parse_shard_name(&file_name)?;
    let stem = file_name.strip_suffix(".csv")?.to_string();
    Some(ShardFile {
        csv,
        name,
        stem,
        k,
        n,
    })
}

/// The shard files named by the inputs, checked for one experiment, one N, and all K present once;
/// sorted by K.
fn collect(inputs: &[PathBuf]) -> Result<Vec<ShardFile>, OutputError> {
    let mut files: Vec<ShardFile> = Vec::new();
    let mut partials: Vec<PathBuf> = Vec::new();
    for input in inputs {
        if input.is_dir() {
            let entries = fs::read_dir(input)
                .map_err(|e| err(input, format!("cannot list the folder: {e}")))?;
            let mut found = Vec::new();
            for entry in entries {
                let entry =
                    entry.map_err(|e| err(input, format!("cannot list the folder: {e}")))?;
                let path = entry.path();
                if !path.is_file() {
                    continue;
                }
                let fname = entry.file_name().to_string_lossy().to_string();
                if fname
                    .strip_suffix(".partial")
                    .and_then(parse_shard_name)
                    .is_some()
                {
                    partials.push(path);
                } else if let Some(f) = shard_file(path) {
                    found.push(f);
                }
            }
            if found.is_empty() {
                let hint = if partials.is_empty() {
                    String::new()
                } else {
                    format!(" (only unfinished runs: {}; complete them with raycost run SPEC --shard K/N --resume)", names(&partials))
                };
                return Err(err(
                    input,
                    format!("no shard files NAME.shard-K-of-N.csv in this folder{hint}"),
                ));
            }
            found.sort_by(|a, b| a.csv.cmp(&b.csv));
            files.extend(found);
        } else if input.is_file() {
            files.push(shard_file(input.clone()).ok_or_else(|| {
                err(
                    input,
                    "is not a shard table: expected a folder or files named NAME.shard-K-of-N.csv",
                )
            })?);
        } else {
            return Err(err(input, "no such file or folder"));
        }
    }
    let Some(first) = files.first().cloned() else {
        return Err(err(
            Path::new("."),
            "nothing to merge: name a results folder or shard files",
        ));
    };
    for f in &files[1..] {
        if f.name != first.name {
            return Err(err(&f.csv, format!("is a shard of experiment '{}', but {} is of '{}': merge one experiment at a time", f.name, first.csv.display(), first.name)));
        }
        if f.n != first.n {
            return Err(err(
                &f.csv,
                format!("is one of {} shards, but {} is one of {}: shards of different splits cannot be merged (remove one set, or name the files to merge)", f.n, first.csv.display(), first.n),
            ));
        }
    }
    let n = first.n;
    if n == 0 {
        return Err(err(&first.csv, "has N = 0 in its name: expected K < N"));
    }
    let mut by_k: BTreeMap<usize, &ShardFile> = BTreeMap::new();
    for f in &files {
        if f.k >= n {
            return Err(err(
                &f.csv,
                format!("has K = {} ≥ N = {n} in its name", f.k),
            ));
        }
        if let Some(other) = by_k.insert(f.k, f) {
            let what = if same_file(&other.csv, &f.csv) {
                "is given twice".to_string()
            } else {
                format!("is shard {}/{n}, like {}", f.k, other.csv.display())
            };
            return Err(err(&f.csv, what));
        }
    }
    let missing: Vec<usize> = (0..n).filter(|k| !by_k.contains_key(k)).collect();
    if let Some(&k) = missing.first() {
        let want = first
            .csv
            .with_file_name(format!("{}.shard-{k}-of-{n}.csv", first.name));
        let partial = PathBuf::from(format!("{}.partial", want.display()));
        let hint = if partial.exists() {
            format!(" (an unfinished run left {}: complete it with raycost run SPEC --shard {k}/{n} --resume)", partial.display())
        } else {
            format!(" (run it with raycost run SPEC --shard {k}/{n})")
        };
        let all = if missing.len() > 1 {
            format!(
                "; shards {} of {n} are missing in all",
                missing
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        } else {
            String::new()
        };
        return Err(err(
            &want,
            format!("is missing: shard {k} of {n} is needed{hint}{all}"),
        ));
    }
    files.sort_by_key(|f| f.k);
    Ok(files)
}

fn check_header(t: &Table, reference: &Table) -> Result<(), OutputError> {
    if t.header == reference.header {
        return Ok(());
    }
    let i = t
        .columns
        .iter()
        .zip(&reference.columns)
        .position(|(a, b)| a != b)
        .unwrap_or(t.columns.len().min(reference.columns.len()));
    let col = |c: &[String]| {
        c.get(i)
            .map_or_else(|| "(none)".to_string(), |s| format!("'{s}'"))
    };
    Err(err(
        &t.path,
        format!(
            "its header differs from {}'s: column {} is {} there and {} here ({} vs {} columns)",
            reference.path.display(),
            i + 1,
            col(&reference.columns),
            col(&t.columns),
            reference.columns.len(),
            t.columns.len()
        ),
    ))
}

/// A finished table of a shard, every row checked (a torn row anywhere is refused); its header must
/// be the columns `meta` records for `table`.
fn read_finished(path: &Path, meta: &Meta, table: &str) -> Result<Table, OutputError> {
    let text = fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
    check_table(path, text, meta.declared(table).as_deref(), Torn::Refuse)
}

/// One shard, read and checked on its own.
#[derive(Debug)]
struct Shard {
    csv: PathBuf,
    stem: String,
    k: usize,
    meta_path: PathBuf,
    meta: Meta,
    spec_hash: String,
    version: String,
    points_total: usize,
    /// `run.points` and `run.resumed_points` of the metadata.
    meta_points: Vec<usize>,
    main: Table,
    tables: BTreeMap<String, Table>,
}

impl Shard {
    /// Every file of the shard this merge reads.
    fn files(&self) -> impl Iterator<Item = &Path> {
        [self.csv.as_path(), self.meta_path.as_path()]
            .into_iter()
            .chain(self.tables.values().map(|t| t.path.as_path()))
    }

    fn load(f: ShardFile) -> Result<Shard, OutputError> {
        let meta_path = f.csv.with_file_name(format!("{}.meta.toml", f.stem));
        if !meta_path.is_file() {
            return Err(err(
                &meta_path,
                "is missing: it holds the spec hash and input hashes the merge checks",
            ));
        }
        let meta = Meta::read(&meta_path)?;
        let shard = meta.run.shard.clone();
        if shard != format!("{}/{}", f.k, f.n) {
            return Err(err(
                &meta_path,
                format!(
                    "records shard {shard}, but the file name says {}/{}: was it renamed?",
                    f.k, f.n
                ),
            ));
        }
        let mut meta_points = meta.run.points.clone();
        meta_points.extend(meta.run.resumed_points.iter().copied());

        let main = read_finished(&f.csv, &meta, "main")?;
        let mut tables = BTreeMap::new();
        let dir = match f.csv.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let prefix = format!("{}.", f.stem);
        let entries =
            fs::read_dir(&dir).map_err(|e| err(&dir, format!("cannot list the folder: {e}")))?;
        for entry in entries.flatten() {
            let fname = entry.file_name().to_string_lossy().to_string();
            let Some(table) = fname
                .strip_prefix(&prefix)
                .and_then(|r| r.strip_suffix(".csv"))
            else {
                continue;
            };
            if table.is_empty() || table.contains('.') || !entry.path().is_file() {
                continue;
            }
            tables.insert(
                table.to_string(),
                read_finished(&entry.path(), &meta, table)?,
            );
        }
        Ok(Shard {
            csv: f.csv,
            stem: f.stem,
            k: f.k,
            meta_path,
            spec_hash: meta.run.spec_hash.clone(),
            version: meta.raycost.version.clone(),
            points_total: meta.run.points_total,
            meta,
            meta_points,
            main,
            tables,
        })
    }
}

/// The merged metadata: the first shard's build, machine, inputs, columns and spec (checked equal
/// where it matters), the run as one (earliest start, latest end, every point with its wall time),
/// and one [`ShardRecord`] per shard with its own machine and run.
fn merged_meta(shards: &[Shard], total: usize, n: usize) -> Meta {
    let first = &shards[0].meta;
    let mut merged = first.clone();
    let mut walls = vec![f64::NAN; total];
    let mut memory: Vec<_> = shards
        .iter()
        .flat_map(|s| s.meta.run.point_memory.iter().cloned())
        .collect();
    memory.sort_by_key(|m| m.point);
    for s in shards {
        for (&p, &w) in s.meta.run.points.iter().zip(&s.meta.run.point_wall_s) {
            if p < total {
                walls[p] = w;
            }
        }
        for w in &s.meta.warnings {
            if !merged.warnings.contains(w) {
                merged.warnings.push(w.clone());
            }
        }
    }
    let run = &mut merged.run;
    run.command = "merge".into();
    run.shard = format!("merged from {n} shards");
    run.started = shards
        .iter()
        .map(|s| s.meta.run.started.clone())
        .min()
        .unwrap_or_default();
    run.finished = shards
        .iter()
        .filter_map(|s| s.meta.run.finished.clone())
        .max();
    run.wall_s = None;
    run.load_start = Vec::new();
    run.load_end = Vec::new();
    run.points_total = total;
    run.points = (0..total).collect();
    run.point_wall_s = walls;
    run.point_memory = memory;
    run.resumed_points = Vec::new();
    merged.shards = shards
        .iter()
        .map(|s| ShardRecord {
            file: s
                .csv
                .file_name()
                .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
            raycost: s.meta.raycost.clone(),
            machine: s.meta.machine.clone(),
            run: s.meta.run.clone(),
        })
        .collect();
    merged
}

/// The folder of `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

fn short_hash(h: &str) -> &str {
    &h[..h.len().min(16)]
}

fn join(points: &[usize]) -> String {
    let mut s = points
        .iter()
        .take(10)
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ");
    if points.len() > 10 {
        s.push_str(&format!(", … ({} in all)", points.len()));
    }
    s
}

fn list_points(points: &[usize]) -> String {
    if points.len() == 1 {
        format!("point {} is", points[0])
    } else {
        format!("points {} are", join(points))
    }
}

fn names(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| {
            p.file_name()
                .map_or_else(String::new, |f| f.to_string_lossy().into_owned())
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_names() {
        assert_eq!(
            parse_shard_name("grid.shard-2-of-4.csv"),
            Some(("grid".into(), 2, 4))
        );
        assert_eq!(
            parse_shard_name("a.b.shard-0-of-10.csv"),
            Some(("a.b".into(), 0, 10))
        );
        assert_eq!(parse_shard_name("grid.shard-2-of-4.hist.csv"), None);
        assert_eq!(parse_shard_name("grid.csv"), None);
        assert_eq!(parse_shard_name("grid.shard--of-4.csv"), None);
        assert_eq!(parse_shard_name(".shard-1-of-2.csv"), None);
    }
}
