//! The result files of one run: `DIR/NAME/STEM.csv`, its side tables `STEM.TABLE.csv` (the kind
//! declares them: `hist` for the grid study, `levels` and `points` for DETP) and `STEM.meta.toml`,
//! with `STEM = NAME` or `NAME.shard-K-of-N`.
//!
//! While a run goes, rows are appended to `STEM.csv.partial` (and `.TABLE.csv.partial`) and flushed
//! after every point, so a killed run keeps every finished point; `--resume` reads them back (after
//! checking that the spec hash and the content hash of every input file recorded in
//! `STEM.meta.toml.partial` are the same now, naming the file that changed), drops a torn last line,
//! and goes on. Only a finished run renames the partial files into place.

use std::collections::BTreeSet;
use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::csv::{header, record};
use super::meta::{changed_input, Meta};
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

/// Open result files of a run in progress.
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
    OutputError {
        path: path.display().to_string(),
        message: message.into(),
    }
    .into()
}

impl Sink {
    /// Path of a file of this run: `suffix` is `csv`, `TABLE.csv` or `meta.toml`.
    pub fn path(dir: &Path, stem: &str, suffix: &str) -> PathBuf {
        dir.join(format!("{stem}.{suffix}"))
    }

    fn partial(dir: &Path, stem: &str, suffix: &str) -> PathBuf {
        dir.join(format!("{stem}.{suffix}.partial"))
    }

    /// Opens (or, with `resume`, reopens) the files of run `stem` in `dir`. Refuses, before anything
    /// is written, to replace a finished result without `force` or to discard a partial one without
    /// `resume` or `force`. With `resume`, a finished result is left alone and `None` comes back.
    /// Refusals are [`OutputError`]s (exit 2, nothing written); failures after files were touched
    /// (recovering a half-finished run) are plain errors (exit 1).
    pub fn open(
        dir: &Path,
        stem: &str,
        meta: &Meta,
        opts: SinkOptions,
    ) -> anyhow::Result<Option<Sink>> {
        fs::create_dir_all(dir)
            .map_err(|e| err(dir, format!("cannot create the results folder: {e}")))?;
        let probe = dir.join(format!(".{stem}.write-test"));
        File::create(&probe)
            .map_err(|e| err(dir, format!("the results folder is not writable: {e}")))?;
        let _ = fs::remove_file(&probe);
        let suffixes: Vec<String> = opts.tables.iter().map(|t| format!("{t}.csv")).collect();
        let csv_p = Self::partial(dir, stem, "csv");
        let meta_p = Self::partial(dir, stem, "meta.toml");
        let final_csv = Self::path(dir, stem, "csv");
        if final_csv.exists() && opts.resume && !csv_p.exists() {
            // Finished already: a no-op, but only for the same spec and the same input files.
            let then = Meta::read(&Self::path(dir, stem, "meta.toml"))?;
            same_run(&then, meta, &final_csv)?;
            return Ok(None);
        }
        if opts.resume && csv_p.exists() {
            // A run killed inside `finish` has renamed some files already: take them back.
            for suffix in suffixes.iter().map(String::as_str).chain(["meta.toml"]) {
                let partial = &Self::partial(dir, stem, suffix);
                let done = Self::path(dir, stem, suffix);
                if done.exists() && !partial.exists() {
                    // Files are being changed now: a failure here is not "nothing written" (exit 1).
                    fs::rename(&done, partial).map_err(|e| {
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
                return Err(err(
                    &p,
                    "exists already; pass --force to replace it (nothing was written)",
                ));
            }
        }
        let started: Option<String>;
        let mut previous = None;
        let mut done = BTreeSet::new();
        let mut csv_has_header = false;
        let mut resumed_header = None;
        let mut table_has_header = vec![false; suffixes.len()];
        if csv_p.exists() && opts.resume {
            let then = Meta::read(&meta_p)?;
            same_run(&then, meta, &csv_p)?;
            started = Some(then.run.started.clone());
            previous = Some(then);
            let rows = read_complete(&csv_p).map_err(|e| err(&csv_p, e))?;
            csv_has_header = !rows.is_empty();
            resumed_header = rows.first().cloned();
            for line in rows.iter().skip(1) {
                let point = line
                    .split(',')
                    .next()
                    .and_then(|p| p.parse::<usize>().ok())
                    .ok_or_else(|| err(&csv_p, format!("unreadable row: {line}")))?;
                done.insert(point);
            }
            // Keep side-table rows only of points whose main row was written.
            for (suffix, has_header) in suffixes.iter().zip(table_has_header.iter_mut()) {
                let table_p = Self::partial(dir, stem, suffix);
                let rows = if table_p.exists() {
                    read_complete(&table_p).map_err(|e| err(&table_p, e))?
                } else {
                    Vec::new()
                };
                let mut kept = String::new();
                for (i, line) in rows.iter().enumerate() {
                    let keep = i == 0
                        || line
                            .split(',')
                            .next()
                            .and_then(|p| p.parse::<usize>().ok())
                            .is_some_and(|p| done.contains(&p));
                    if keep {
                        kept.push_str(line);
                        kept.push('\n');
                    }
                }
                *has_header = !rows.is_empty();
                // Rewrite through a temporary file: a kill here must not lose finished points' rows.
                let tmp = Self::partial(dir, stem, &format!("{suffix}.tmp"));
                fs::write(&tmp, kept)
                    .and_then(|()| fs::rename(&tmp, &table_p))
                    .map_err(|e| anyhow::anyhow!("could not rewrite {}: {e}", table_p.display()))?;
            }
        } else if csv_p.exists() && !opts.force {
            return Err(err(
                &csv_p,
                "a partial run exists: pass --resume to continue it, or --force to start over",
            ));
        } else {
            for suffix in ["csv"]
                .into_iter()
                .chain(suffixes.iter().map(String::as_str))
            {
                let p = Self::partial(dir, stem, suffix);
                File::create(&p).map_err(|e| err(&p, e.to_string()))?;
            }
            fs::write(&meta_p, meta.render()).map_err(|e| err(&meta_p, e.to_string()))?;
            started = Some(meta.run.started.clone());
        }
        let open = |p: &Path| {
            OpenOptions::new()
                .append(true)
                .open(p)
                .map_err(|e| err(p, e.to_string()))
        };
        let mut tables = Vec::with_capacity(suffixes.len());
        for ((name, suffix), has_header) in opts.tables.iter().zip(suffixes).zip(table_has_header) {
            tables.push(SideTable {
                name,
                file: open(&Self::partial(dir, stem, &suffix))?,
                suffix,
                has_header,
            });
        }
        Ok(Some(Sink {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            csv: open(&csv_p)?,
            tables,
            csv_has_header,
            resumed_header,
            done,
            started: started.unwrap_or_else(super::time::now_rfc3339),
            previous,
        }))
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

    /// Appends one point: its rows of each side table first, then its main row, each flushed to
    /// disk (so a point whose main row is on disk has all its side rows there too). Side tables are
    /// named by the kind's declaration, which is also what the sink was opened with.
    pub fn append(&mut self, row: &Row, side: &[(&'static str, Vec<Row>)]) -> std::io::Result<()> {
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

    /// Writes the metadata and renames the partial files into place.
    pub fn finish(self, meta: &Meta) -> std::io::Result<Vec<PathBuf>> {
        let (dir, stem) = (self.dir, self.stem);
        drop(self.csv);
        let meta_p = Self::partial(&dir, &stem, "meta.toml");
        fs::write(&meta_p, meta.render())?;
        let mut written = Vec::new();
        for t in self.tables {
            drop(t.file);
            let table_p = Self::partial(&dir, &stem, &t.suffix);
            if fs::metadata(&table_p)?.len() > 0 {
                fs::rename(&table_p, Self::path(&dir, &stem, &t.suffix))?;
                written.push(Self::path(&dir, &stem, &t.suffix));
            } else {
                fs::remove_file(&table_p)?;
                // A side table of an earlier run (replaced with --force) must not sit beside this one.
                let stale = Self::path(&dir, &stem, &t.suffix);
                if stale.exists() {
                    fs::remove_file(stale)?;
                }
            }
        }
        fs::rename(&meta_p, Self::path(&dir, &stem, "meta.toml"))?;
        fs::rename(
            Self::partial(&dir, &stem, "csv"),
            Self::path(&dir, &stem, "csv"),
        )?;
        written.insert(0, Self::path(&dir, &stem, "meta.toml"));
        written.insert(0, Self::path(&dir, &stem, "csv"));
        Ok(written)
    }
}

/// The complete lines of a file; a torn last line (no newline: the writer was killed mid-write) is
/// cut off the file itself, so appending continues cleanly.
fn read_complete(p: &Path) -> Result<Vec<String>, String> {
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .open(p)
        .map_err(|e| e.to_string())?;
    let mut text = String::new();
    f.read_to_string(&mut text).map_err(|e| e.to_string())?;
    let keep = text.rfind('\n').map_or(0, |i| i + 1);
    if keep < text.len() {
        f.set_len(keep as u64).map_err(|e| e.to_string())?;
        f.seek(SeekFrom::End(0)).map_err(|e| e.to_string())?;
    }
    Ok(text[..keep].lines().map(str::to_string).collect())
}
