//! The result files of one run: `DIR/NAME/STEM.csv`, its side tables `STEM.TABLE.csv` (the kind
//! declares them: `hist` for the grid study, `levels` and `points` for DETP) and `STEM.meta.toml`,
//! with `STEM = NAME` or `NAME.shard-K-of-N`, written through the result-folder protocol
//! ([`super::folder`]).
//!
//! A run holds `STEM.lock` from the first check to the last rename, so a second writer (a Slurm
//! requeue, a second Enter, a `--resume` while the run still goes) is refused before it reads or
//! writes anything. While a run goes, rows are appended to `STEM.csv.partial` (and
//! `.TABLE.csv.partial`), created new (never through a symlink) and fsynced after every point, so a
//! killed run keeps every finished point. `STEM.meta.toml.partial` is only ever replaced whole (a
//! temporary file and a rename), first when the run starts and again when a table's columns become
//! known, so a full disk can never truncate it.
//!
//! `--resume` checks that the spec hash and every input file's content hash recorded in
//! `STEM.meta.toml.partial` are the same now (naming the file that changed), then reads every row
//! back ([`super::readback`]): a torn last row is dropped and reported (its point runs again), any
//! other bad row, a header that is not the recorded columns, a duplicated point or one outside this
//! shard is refused. Only a finished run publishes its files, the main table last
//! ([`folder::publish`]).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::column::ColumnInfo;
use super::csv::{header, record};
use super::folder::{self, Lock};
use super::meta::{changed_input, Meta};
use super::readback::{read_table, Torn};
use super::row::Row;
use super::OutputError;

/// How a run treats existing files.
#[derive(Clone, Copy, Debug, Default)]
pub struct SinkOptions {
    /// Replace existing final results.
    pub force: bool,
    /// Continue a partial run.
    pub resume: bool,
    /// Names of the side tables, `STEM.TABLE.csv` (a table no point writes to is not kept).
    pub tables: &'static [&'static str],
}

/// One open side table.
#[derive(Debug)]
struct SideTable {
    /// Its name, as in `STEM.NAME.csv`.
    name: &'static str,
    /// File suffix `NAME.csv`.
    suffix: String,
    file: File,
    has_header: bool,
}

/// Open result files of a run in progress (and the lock on them).
#[derive(Debug)]
pub struct Sink {
    dir: PathBuf,
    stem: String,
    csv: File,
    tables: Vec<SideTable>,
    csv_has_header: bool,
    /// The header of a resumed table: this run's rows must have the same columns.
    resumed_header: Option<String>,
    done: BTreeSet<usize>,
    started: String,
    previous: Option<Meta>,
    /// The columns `STEM.meta.toml.partial` records now.
    recorded_columns: BTreeMap<String, Vec<ColumnInfo>>,
    /// What opening found and mended (a stale lock taken over, a torn row dropped).
    notes: Vec<String>,
    /// Held until the sink is finished or dropped.
    _lock: Lock,
}

/// Refuses to continue a run whose recorded metadata `then` differs from `now` in the spec or an
/// input file's content.
fn same_run(then: &Meta, now: &Meta, what: &Path) -> Result<(), OutputError> {
    if then.run.spec_hash != now.run.spec_hash {
        return Err(OutputError::new(what, "was written by a different spec (spec hash differs); --resume cannot continue it. Move it away or pass --force without --resume to start over"));
    }
    if let Some(file) = changed_input(&then.inputs, &now.inputs) {
        return Err(OutputError::new(what, format!("was computed from other input files: {file}; --resume cannot continue it. Pass --force without --resume to start over")));
    }
    Ok(())
}

/// A refusal about `path`: an [`OutputError`] (exit code 2, nothing written).
fn err(path: &Path, message: impl Into<String>) -> anyhow::Error {
    OutputError::new(path, message).into()
}

/// A failure after files were touched (exit 1), naming the file.
fn failed(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("{}: {e}", path.display())
}

/// The shard `K/N` a run's metadata records (`all`: 0/1).
fn shard_of(meta: &Meta) -> (usize, usize) {
    meta.run
        .shard
        .split_once('/')
        .and_then(|(k, n)| Some((k.parse().ok()?, n.parse().ok()?)))
        .filter(|&(k, n)| n > 0 && k < n)
        .unwrap_or((0, 1))
}

/// Names of the columns `meta` records for `table`.
fn recorded_names(meta: &Meta, table: &str) -> Option<Vec<String>> {
    meta.columns
        .get(table)
        .map(|c| c.iter().map(|c| c.name.clone()).collect())
}

/// What resuming read back from the partial files.
struct Resumed {
    done: BTreeSet<usize>,
    header: Option<String>,
    table_has_header: Vec<bool>,
}

impl Sink {
    /// Path of a file of this run: `suffix` is `csv`, `TABLE.csv` or `meta.toml`.
    pub fn path(dir: &Path, stem: &str, suffix: &str) -> PathBuf {
        dir.join(format!("{stem}.{suffix}"))
    }

    fn partial(dir: &Path, stem: &str, suffix: &str) -> PathBuf {
        dir.join(format!("{stem}.{suffix}.partial"))
    }

    /// Opens (or, with `resume`, reopens) the files of run `stem` in `dir`, holding its lock.
    /// Refuses, before anything is written, a result another process is writing, to replace a
    /// finished result without `force`, or to discard a partial one without `resume` or `force`.
    /// With `resume`, a finished result is left alone and `None` comes back. Refusals are
    /// [`OutputError`]s (exit 2, nothing written); failures after files were touched (recovering a
    /// half-finished run) are plain errors (exit 1).
    pub fn open(
        dir: &Path,
        stem: &str,
        meta: &Meta,
        opts: SinkOptions,
    ) -> anyhow::Result<Option<Sink>> {
        std::fs::create_dir_all(dir)
            .map_err(|e| err(dir, format!("cannot create the results folder: {e}")))?;
        let lock = Lock::acquire(dir, stem)?;
        let mut notes: Vec<String> = lock.took_over().into_iter().collect();
        let suffixes: Vec<String> = opts.tables.iter().map(|t| format!("{t}.csv")).collect();
        let csv_p = Self::partial(dir, stem, "csv");
        let meta_p = Self::partial(dir, stem, "meta.toml");
        let final_csv = Self::path(dir, stem, "csv");
        let mine: Vec<PathBuf> = ["csv", "meta.toml"]
            .into_iter()
            .chain(suffixes.iter().map(String::as_str))
            .flat_map(|s| [Self::path(dir, stem, s), Self::partial(dir, stem, s)])
            .collect();
        folder::remove_stale_temporaries(&mine).map_err(|e| failed(dir, e))?;
        if final_csv.exists() && opts.resume && !csv_p.exists() {
            // Finished already: a no-op, but only for the same spec and the same input files.
            let then = Meta::read(&Self::path(dir, stem, "meta.toml"))?;
            same_run(&then, meta, &final_csv)?;
            return Ok(None);
        }
        if opts.resume && csv_p.exists() {
            // A run killed while publishing has moved some files already (never the main table,
            // which goes last): take them back.
            for suffix in suffixes.iter().map(String::as_str).chain(["meta.toml"]) {
                let partial = &Self::partial(dir, stem, suffix);
                let done = Self::path(dir, stem, suffix);
                if done.exists() && !partial.exists() {
                    folder::rename(&done, partial).map_err(|e| {
                        anyhow::anyhow!("could not recover {}: {e}", done.display())
                    })?;
                }
            }
        }
        for suffix in ["csv", "meta.toml"]
            .into_iter()
            .chain(suffixes.iter().map(String::as_str))
        {
            let p = Self::path(dir, stem, suffix);
            if p.exists() && !opts.force {
                let why = if opts.resume {
                    "exists already beside the partial run being resumed (that run was started \
                     with --force); pass --resume --force to complete it and replace this file"
                } else {
                    "exists already; pass --force to replace it (nothing was written)"
                };
                return Err(err(&p, why));
            }
        }
        let mut previous = None;
        let resumed = if csv_p.exists() && opts.resume {
            let then = Meta::read(&meta_p).map_err(|e| {
                err(
                    &meta_p,
                    format!("{}; the partial run cannot be checked, so it cannot be resumed: pass --force without --resume to start over", e.message),
                )
            })?;
            same_run(&then, meta, &csv_p)?;
            let r = Self::read_back(dir, stem, &suffixes, &then, &mut notes)?;
            previous = Some(then);
            r
        } else if csv_p.exists() && !opts.force {
            return Err(err(
                &csv_p,
                "a partial run exists: pass --resume to continue it, or --force to start over",
            ));
        } else {
            Self::start_new(dir, stem, &suffixes, meta)?;
            Resumed {
                done: BTreeSet::new(),
                header: None,
                table_has_header: vec![false; suffixes.len()],
            }
        };
        let open = |p: &Path| folder::open_existing(p, true).map_err(|e| failed(p, e));
        let mut tables = Vec::with_capacity(suffixes.len());
        for ((name, suffix), has_header) in opts
            .tables
            .iter()
            .zip(suffixes)
            .zip(resumed.table_has_header)
        {
            tables.push(SideTable {
                name,
                file: open(&Self::partial(dir, stem, &suffix))?,
                suffix,
                has_header,
            });
        }
        let recorded_columns = previous
            .as_ref()
            .map_or_else(|| meta.columns.clone(), |p: &Meta| p.columns.clone());
        Ok(Some(Sink {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            csv: open(&csv_p)?,
            tables,
            csv_has_header: resumed.header.is_some(),
            resumed_header: resumed.header,
            done: resumed.done,
            started: previous.as_ref().map_or_else(
                || meta.run.started.clone(),
                |p: &Meta| p.run.started.clone(),
            ),
            previous,
            recorded_columns,
            notes,
            _lock: lock,
        }))
    }

    /// A fresh start: leftovers of an earlier run are removed (a symlink planted at a partial path
    /// goes too, never its target), the partial metadata is written whole, then the partial tables
    /// are created new.
    fn start_new(dir: &Path, stem: &str, suffixes: &[String], meta: &Meta) -> anyhow::Result<()> {
        let all = ["csv", "meta.toml"]
            .into_iter()
            .chain(suffixes.iter().map(String::as_str));
        for suffix in all {
            let p = Self::partial(dir, stem, suffix);
            folder::remove_if_exists(&p).map_err(|e| err(&p, format!("cannot remove: {e}")))?;
        }
        let meta_p = Self::partial(dir, stem, "meta.toml");
        folder::write_atomic(&meta_p, meta.render().as_bytes())
            .map_err(|e| err(&meta_p, e.to_string()))?;
        for suffix in ["csv"]
            .into_iter()
            .chain(suffixes.iter().map(String::as_str))
        {
            let p = Self::partial(dir, stem, suffix);
            folder::create_new(&p).map_err(|e| err(&p, e.to_string()))?;
        }
        Ok(())
    }

    /// Reads the partial tables of the run `then` back, checking every row; a torn last row is
    /// dropped (noted in `notes`) and side-table rows of points without a main row are removed,
    /// each file rewritten whole if it changed.
    fn read_back(
        dir: &Path,
        stem: &str,
        suffixes: &[String],
        then: &Meta,
        notes: &mut Vec<String>,
    ) -> anyhow::Result<Resumed> {
        let csv_p = Self::partial(dir, stem, "csv");
        let main = read_table(
            &csv_p,
            recorded_names(then, "main").as_deref(),
            Torn::DropLast,
        )?;
        let (k, n) = shard_of(then);
        let total = then.run.points_total;
        let mut done = BTreeSet::new();
        for r in &main.rows {
            let bad = if total > 0 && r.point >= total {
                Some(format!(
                    "point {} is out of range (the spec has {total} points)",
                    r.point
                ))
            } else if r.point % n != k {
                Some(format!(
                    "point {} does not belong to shard {k}/{n}",
                    r.point
                ))
            } else if !done.insert(r.point) {
                Some(format!(
                    "point {} is duplicated (two runs wrote this file?)",
                    r.point
                ))
            } else {
                None
            };
            if let Some(b) = bad {
                return Err(err(&csv_p, format!("line {}: {b}; the partial run cannot be resumed: pass --force without --resume to start over", r.line)));
            }
        }
        if let Some(d) = &main.dropped {
            notes.push(d.clone());
            folder::write_atomic(&csv_p, &main.text[..main.valid_len])
                .map_err(|e| failed(&csv_p, e))?;
        }
        let mut table_has_header = Vec::with_capacity(suffixes.len());
        for suffix in suffixes {
            let p = Self::partial(dir, stem, suffix);
            if !p.exists() && std::fs::symlink_metadata(&p).is_err() {
                folder::create_new(&p).map_err(|e| failed(&p, e))?;
                table_has_header.push(false);
                continue;
            }
            let name = suffix.strip_suffix(".csv").unwrap_or(suffix);
            let t = read_table(&p, recorded_names(then, name).as_deref(), Torn::DropLast)?;
            notes.extend(t.dropped.clone());
            // Keep side-table rows only of points whose main row was written.
            let kept = t.kept(|r| done.contains(&r.point));
            if kept.len() != t.text.len() {
                folder::write_atomic(&p, &kept).map_err(|e| failed(&p, e))?;
            }
            table_has_header.push(t.header.is_some());
        }
        Ok(Resumed {
            done,
            header: main
                .header
                .map(|h| String::from_utf8_lossy(&h).trim_end().to_string()),
            table_has_header,
        })
    }

    /// When the run began: the first session's start, for a resumed run.
    pub fn started(&self) -> &str {
        &self.started
    }

    /// The metadata of the partial run being resumed.
    pub fn previous(&self) -> Option<&Meta> {
        self.previous.as_ref()
    }

    /// Points already finished (from a resumed partial run).
    pub fn done(&self) -> &BTreeSet<usize> {
        &self.done
    }

    /// What opening found and mended, one line each, for the run's warnings: a stale lock taken
    /// over, a torn last row dropped.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Appends one point: its rows of each side table first, then its main row, each flushed to
    /// disk (so a point whose main row is on disk has all its side rows there too). Side tables are
    /// named by the kind's declaration, which is also what the sink was opened with. When `meta`
    /// records columns the partial metadata does not have yet, the partial metadata is replaced
    /// first (whole), so `--resume` can check the tables' headers against it.
    pub fn append(
        &mut self,
        row: &Row,
        side: &[(&'static str, Vec<Row>)],
        meta: &Meta,
    ) -> std::io::Result<()> {
        if meta.columns != self.recorded_columns && !meta.columns.is_empty() {
            let meta_p = Self::partial(&self.dir, &self.stem, "meta.toml");
            folder::write_atomic(&meta_p, meta.render().as_bytes())?;
            self.recorded_columns = meta.columns.clone();
        }
        for (name, rows) in side {
            let Some(t) = self.tables.iter_mut().find(|t| t.name == *name) else {
                return Err(std::io::Error::other(format!(
                    "side table '{name}' was not declared for this kind"
                )));
            };
            let mut h = Vec::new();
            if !rows.is_empty() && !t.has_header {
                h.extend(header(&rows[0]));
                t.has_header = true;
            }
            for r in rows {
                h.extend(record(r));
            }
            t.file.write_all(&h)?;
            t.file.sync_data()?;
        }
        let mut m = Vec::new();
        if let Some(then) = self.resumed_header.take() {
            let now = String::from_utf8_lossy(&header(row)).trim_end().to_string();
            if then.trim_end() != now {
                return Err(std::io::Error::other(format!(
                    "{}: its columns differ from this run's (written by an older raycost, \
                     before every row carried every parameter of its point): \
                     --resume cannot continue it; pass --force without --resume to start over",
                    Self::partial(&self.dir, &self.stem, "csv").display()
                )));
            }
        }
        if !self.csv_has_header {
            m.extend(header(row));
            self.csv_has_header = true;
        }
        m.extend(record(row));
        self.csv.write_all(&m)?;
        self.csv.sync_data()
    }

    /// Writes the metadata (whole, through a temporary file) and publishes the partial files, the
    /// main table last; then releases the lock. A failure at any step leaves a resumable run.
    pub fn finish(self, meta: &Meta) -> std::io::Result<Vec<PathBuf>> {
        let (dir, stem) = (&self.dir, &self.stem);
        let meta_p = Self::partial(dir, stem, "meta.toml");
        folder::write_atomic(&meta_p, meta.render().as_bytes())?;
        let mut moves = Vec::new();
        let mut written = vec![
            Self::path(dir, stem, "csv"),
            Self::path(dir, stem, "meta.toml"),
        ];
        for t in &self.tables {
            let table_p = Self::partial(dir, stem, &t.suffix);
            let done = Self::path(dir, stem, &t.suffix);
            if t.file.metadata()?.len() > 0 {
                moves.push((table_p, done.clone()));
                written.push(done);
            } else {
                folder::remove_if_exists(&table_p)?;
                // A side table of an earlier run (replaced with --force) must not sit beside this one.
                folder::remove_if_exists(&done)?;
            }
        }
        moves.push((meta_p, Self::path(dir, stem, "meta.toml")));
        moves.push((
            Self::partial(dir, stem, "csv"),
            Self::path(dir, stem, "csv"),
        ));
        folder::publish(&moves)?;
        Ok(written)
    }
}
