//! `raycost report RESULTS --out DIR`: one static HTML page, `DIR/index.html`, of everything a
//! results root holds — per experiment its provenance (kind, description, spec hash, commit, CPU),
//! its plots, its claims (measured ± CI against theory, with the summary's verdicts) and links to
//! its tables; the bench table with its CPU and load; and the papers' claims from
//! `RESULTS/claims.toml` when it exists. Plain HTML and CSS, no script; the images are copied to
//! `DIR/img/FOLDER/` (byte-identical copies, which git stores once) so the folder stands alone, and
//! the CSV links are relative paths from DIR.
//!
//! Files, one job each: [`discover`] lists the folders, [`meta_view`] reads metadata of either
//! schema, [`table`] reads CSVs, [`verdicts`] judges a table's metrics, [`bench`] picks the bench
//! columns, [`claims`] loads the claims file, [`page`] writes the HTML (escaping through [`html`]),
//! [`write`] puts the files in place atomically.

pub mod bench;
pub mod claims;
pub mod discover;
pub mod html;
pub mod meta_view;
pub mod page;
pub mod table;
pub mod verdicts;
pub mod write;

use std::path::{Path, PathBuf};

use crate::error::{Error, InputError, OutputError};

use bench::BenchTable;
use claims::PaperClaim;
use discover::Folder;
use meta_view::MetaView;
use verdicts::PointClaims;

/// What to report and where.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// The results root.
    pub results: PathBuf,
    /// The output folder (`DIR/index.html`).
    pub out: PathBuf,
    /// Replace an existing `DIR/index.html`.
    pub force: bool,
}

/// An image on the page: the copy's path relative to DIR and its size.
#[derive(Clone, Debug, PartialEq)]
pub struct Shown {
    /// `img/FOLDER/FILE`, relative to DIR.
    pub rel: PathBuf,
    /// The file name (the `alt` text and caption).
    pub name: String,
    /// Pixels.
    pub size: (u32, u32),
}

/// A link on the page.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// Relative path from DIR.
    pub rel: PathBuf,
    /// The file name shown.
    pub name: String,
}

/// The files of a folder as the page shows them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Files {
    /// Images, copied beside the page.
    pub images: Vec<Shown>,
    /// Tables.
    pub tables: Vec<Link>,
    /// Other files (metadata, logs, images a browser could not draw).
    pub others: Vec<Link>,
}

/// One experiment (a folder with `NAME.meta.toml`).
#[derive(Clone, Debug, PartialEq)]
pub struct ExperimentSection {
    /// Folder name.
    pub name: String,
    /// Its provenance.
    pub meta: MetaView,
    /// The claims of each point of `NAME.csv` (empty if there is none).
    pub points: Vec<PointClaims>,
    /// Whether `NAME.csv` exists.
    pub has_main_table: bool,
    /// Its files.
    pub files: Files,
}

/// The bench folder.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchSection {
    /// `bench.meta.toml`, if present.
    pub meta: Option<MetaView>,
    /// The shown columns of `bench.csv`, if present.
    pub table: Option<BenchTable>,
    /// Its files.
    pub files: Files,
}

/// A folder without metadata (renders, anything else kept in RESULTS).
#[derive(Clone, Debug, PartialEq)]
pub struct OtherSection {
    /// Folder name.
    pub name: String,
    /// Its files.
    pub files: Files,
}

/// Everything the page shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// RESULTS as given on the command line.
    pub results: String,
    /// The raycost that made the page.
    pub made_by: String,
    /// `claims.toml`, if present.
    pub claims: Option<Vec<PaperClaim>>,
    /// The bench folder, if present.
    pub bench: Option<BenchSection>,
    /// Experiments, by name.
    pub experiments: Vec<ExperimentSection>,
    /// Folders without metadata, by name.
    pub others: Vec<OtherSection>,
}

/// A file to copy next to the page: source, destination relative to DIR.
pub type Copy = (PathBuf, PathBuf);

/// Makes the report; returns the page's path.
pub fn run(opts: &ReportOptions) -> Result<PathBuf, Error> {
    let results_label = opts.results.display().to_string();
    if !opts.results.is_dir() {
        return Err(InputError::new(
            &results_label,
            "no such results folder (give the folder `raycost run --out` wrote to, default `results`)",
        )
        .into());
    }
    refuse_out_in_a_run(&opts.results, &opts.out)?;
    let index = opts.out.join("index.html");
    if index.exists() && !opts.force {
        return Err(OutputError::new(
            &index,
            "exists; pass --force to replace it (nothing was written)",
        )
        .into());
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| {
        OutputError::new(&opts.out, format!("cannot create the output folder: {e}"))
    })?;
    // One report writes DIR at a time; the refusal to replace a page is decided under the lock.
    let _lock = crate::output::folder::Lock::acquire(&opts.out, "index")?;
    if index.exists() && !opts.force {
        return Err(OutputError::new(
            &index,
            "exists; pass --force to replace it (nothing was written)",
        )
        .into());
    }
    let canon = |p: &Path| {
        p.canonicalize()
            .map_err(|e| OutputError::new(p, format!("cannot resolve the path: {e}")))
    };
    let (results, out) = (canon(&opts.results)?, canon(&opts.out)?);
    let (report, copies) = assemble(&results, &results_label, &out)?;
    let html = page::render(&report);
    write::write(&out, &html, &copies)?;
    Ok(index)
}

/// Refuses an `--out` that is or lies inside one of the run folders the page reads
/// (`RESULTS/NAME`): the page would become part of that run's folder. A folder of its own beside
/// them (`--out RESULTS/report`, skipped when the folders are listed) is fine.
fn refuse_out_in_a_run(results: &Path, out: &Path) -> Result<(), OutputError> {
    use crate::output::location::{refuse_inside, resolve};
    let own = resolve(out);
    let Ok(entries) = std::fs::read_dir(results) else {
        return Ok(());
    };
    let runs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_dir()
                && !p
                    .file_name()
                    .is_some_and(|f| f.to_string_lossy().starts_with('.'))
        })
        .filter(|p| {
            resolve(p) != own
                || std::fs::read_dir(p).is_ok_and(|d| {
                    d.filter_map(Result::ok)
                        .any(|e| e.file_name().to_string_lossy().ends_with(".meta.toml"))
                })
        })
        .collect();
    let reads: Vec<&Path> = runs.iter().map(PathBuf::as_path).collect();
    refuse_inside(out, "--out", &reads)
}

/// Reads everything under `results` (canonical) into a [`Report`] for a page in `out` (canonical),
/// with the images to copy beside it.
pub fn assemble(
    results: &Path,
    results_label: &str,
    out: &Path,
) -> Result<(Report, Vec<Copy>), InputError> {
    let mut copies = Vec::new();
    let mut report = Report {
        results: results_label.to_string(),
        made_by: crate::output::meta::Build::current().describe(),
        claims: claims::load(results)?.map(|cs| {
            cs.into_iter()
                .map(|c| PaperClaim {
                    link: html::relative(out, &c.link),
                    ..c
                })
                .collect()
        }),
        bench: None,
        experiments: Vec::new(),
        others: Vec::new(),
    };
    for f in discover::folders(results, Some(out))? {
        let files = files(&f, out, &mut copies);
        let meta = f.meta.as_deref().map(MetaView::read).transpose()?;
        if f.name == "bench" {
            let table = f
                .main_table
                .as_deref()
                .map(table::Table::read)
                .transpose()?
                .map(|t| bench::shown(&t));
            report.bench = Some(BenchSection { meta, table, files });
        } else if let Some(meta) = meta {
            let points = match &f.main_table {
                Some(p) => {
                    let t = table::Table::read(p)?.declared(p, &meta.main_columns)?;
                    verdicts::claims(&t, &meta.sweep_keys)
                }
                None => Vec::new(),
            };
            report.experiments.push(ExperimentSection {
                name: f.name,
                meta,
                points,
                has_main_table: f.main_table.is_some(),
                files,
            });
        } else {
            report.others.push(OtherSection {
                name: f.name,
                files,
            });
        }
    }
    Ok((report, copies))
}

/// The page's view of a folder's files; images to copy are added to `copies`.
fn files(f: &Folder, out: &Path, copies: &mut Vec<Copy>) -> Files {
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let link = |p: &Path| Link {
        rel: html::relative(out, p),
        name: name(p),
    };
    let mut files = Files {
        tables: f.tables.iter().map(|p| link(p)).collect(),
        others: f.others.iter().map(|p| link(p)).collect(),
        ..Files::default()
    };
    for im in &f.images {
        match im.size {
            Some(size) => {
                let rel = Path::new("img").join(&f.name).join(name(&im.path));
                copies.push((im.path.clone(), rel.clone()));
                files.images.push(Shown {
                    rel,
                    name: name(&im.path),
                    size,
                });
            }
            None => files.others.push(link(&im.path)),
        }
    }
    files
}

#[cfg(test)]
mod tests;
