//! `raycost crossover FRONTS_DIR POINTS_DIR [FRAMES_DIR] --targets … --out DIR`: which method when
//! (DETP, a photon map or per-point path tracing), from three runs of one scene — the fronts
//! (errors of every method against a reference, ≥ 2 replicas, read from `NAME.replica_errors.csv`
//! or an older run's points table; one run, or several in `runs/R` that add configurations, e.g. a
//! radius rule that cannot share the first run's sweep), the n_P sweep (seconds over photons ×
//! points; one run or several) and optionally a quasi-static frames run (incremental costs). Writes
//! `DIR/crossover.csv` (per target and method configuration: photons or paths needed, seconds once
//! and per point, N* with a bootstrap CI over the fronts' replicas, or why never), `DIR/best.csv`
//! (per target and n_P ∈ {10², …, 10⁶} the two fastest configurations), `DIR/frames.csv` (F*, with
//! FRAMES_DIR) and `DIR/crossover.meta.toml` (this build and machine, every input file's hash, and
//! each input run's CPU, load and commit).
//!
//! The steps are pure and tested one by one: [`fronts`] (errors), [`costs`] (seconds),
//! [`analysis`] (N*, best), [`frames`] (F*); this file reads the folders ([`input`]) and writes
//! through the result-folder protocol ([`crate::output::folder`]): refused before anything is
//! computed if `--out` is or lies inside one of the input folders (it would then hold two runs and
//! be refused as an input from then on), or if an output exists without `--force`, then under `DIR/crossover.lock` every file is
//! written to a temporary beside it and renamed into place, `crossover.csv` last. Bad input is an
//! [`OutputError`] naming the file (exit 2, nothing written).

pub mod analysis;
pub mod columns;
pub mod confirm;
pub mod costs;
pub mod frames;
pub mod fronts;
pub mod input;
pub mod measured;
pub mod method;

use std::path::{Path, PathBuf};

use crate::error::{Error, OutputError};
use crate::output::csv::serialize;
use crate::output::folder::{self, Lock};
use crate::output::meta::{InputFile, Meta};
use crate::output::row::Row;
use input::{Csv, Results};

/// What `raycost crossover` was asked.
#[derive(Clone, Debug)]
pub struct Options {
    /// The fronts' result folder.
    pub fronts: PathBuf,
    /// The n_P sweep's result folder.
    pub points: PathBuf,
    /// The frames run's result folder, if any.
    pub frames: Option<PathBuf>,
    /// The head-to-head run's result folder, if any ([`confirm`]).
    pub confirm: Option<PathBuf>,
    /// Target relative RMSEs.
    pub targets: Vec<f64>,
    /// Output folder.
    pub out: PathBuf,
    /// Replace existing outputs.
    pub force: bool,
}

/// The tables the analysis writes, in publication order (the main table last: the commit point).
struct Outputs {
    best: Vec<Row>,
    frames: Option<Vec<Row>>,
    meta: Meta,
    main: Vec<Row>,
}

const FILES: [&str; 4] = [
    "best.csv",
    "frames.csv",
    "crossover.meta.toml",
    "crossover.csv",
];

/// Runs the analysis and writes its files; returns their paths.
pub fn run(o: &Options) -> crate::error::Result<Vec<PathBuf>> {
    if o.targets.is_empty() || o.targets.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(Error::usage(format!(
            "--targets: {:?}: give relative RMSEs > 0, e.g. --targets 0.1,0.05,0.02",
            o.targets
        )));
    }
    let mut reads: Vec<&Path> = vec![&o.fronts, &o.points];
    reads.extend(o.frames.as_deref());
    reads.extend(o.confirm.as_deref());
    crate::output::location::refuse_inside(&o.out, "--out", &reads)?;
    refuse_existing(&o.out, o.force)?;
    let t0 = std::time::Instant::now();
    let mut outputs = compute(o)?;
    outputs.meta.end(t0.elapsed().as_secs_f64());
    write(&o.out, o.force, outputs)
}

/// Refuses, before anything is computed or written, an output that exists without `--force`.
fn refuse_existing(out: &Path, force: bool) -> Result<(), OutputError> {
    if force {
        return Ok(());
    }
    for f in FILES {
        let p = out.join(f);
        if p.exists() {
            return Err(OutputError::new(
                &p,
                "exists already; pass --force to replace it (nothing was written)",
            ));
        }
    }
    Ok(())
}

/// One input run: its tables read, and its provenance for the metadata.
struct Source {
    results: Results,
    meta: Meta,
    files: Vec<PathBuf>,
}

impl Source {
    fn open(dir: &Path) -> Result<Source, OutputError> {
        let results = Results::find(dir)?;
        let meta = results.meta()?;
        Ok(Source {
            results,
            meta,
            files: Vec::new(),
        })
    }

    fn main(&mut self) -> Result<Csv, OutputError> {
        let t = self.results.main()?;
        self.files.push(t.path.clone());
        Ok(t)
    }

    fn side(&mut self, table: &str) -> Result<Csv, OutputError> {
        let t = self.results.side(table)?;
        self.files.push(t.path.clone());
        Ok(t)
    }

    /// What the fronts judged: `NAME.replica_errors.csv` where the run wrote one, else its points
    /// table (returned too: path tracing's truth comes from it in tables written before
    /// `ref_mean`).
    fn judged(&mut self, main: &Csv) -> Result<(fronts::Judged, Option<Csv>), OutputError> {
        if self.results.has_side("replica_errors") {
            let t = self.side("replica_errors")?;
            return Ok((fronts::Judged::from_table(&t)?, None));
        }
        let replicas = first(main, main.param(input::keys::REPLICAS)?)?;
        let points = self.side("points")?;
        Ok((
            fronts::Judged::from_points(&points, replicas)?,
            Some(points),
        ))
    }

    /// What the metadata keeps of this input: its files' hashes and its run's machine.
    fn record(&self, role: &str, meta: &mut Meta) -> Result<(), OutputError> {
        self.record_from(role, &self.results.dir, meta)
    }

    /// [`Source::record`] with every file's location taken relative to `base`: the folder given
    /// on the command line, so that the runs `base/runs/R` of one input, whose files share their
    /// names, keep distinct locations (`runs/0/NAME.csv`, `runs/1/NAME.csv`) and `raycost
    /// reproduce` matches each file to its own.
    fn record_from(&self, role: &str, base: &Path, meta: &mut Meta) -> Result<(), OutputError> {
        for f in &self.files {
            let h = InputFile::hash(f, role, base)
                .map_err(|e| OutputError::new(f, format!("cannot read: {e}")))?;
            meta.inputs.push(h);
        }
        let m = &self.meta;
        let mut t = toml::Table::new();
        let s = |x: &str| toml::Value::String(x.to_string());
        let list =
            |v: &[f64]| toml::Value::Array(v.iter().map(|&x| toml::Value::Float(x)).collect());
        t.insert("dir".into(), s(&self.results.dir.display().to_string()));
        t.insert("name".into(), s(&self.results.name));
        t.insert("cpu".into(), s(&m.machine.cpu));
        t.insert("git_commit".into(), s(&m.raycost.git_commit));
        t.insert("git_dirty".into(), s(&m.raycost.git_dirty));
        t.insert("started".into(), s(&m.run.started));
        t.insert("load_start".into(), list(&m.run.load_start));
        t.insert("load_end".into(), list(&m.run.load_end));
        if let Some(c) = m.run.other_cores {
            t.insert("other_cores".into(), toml::Value::Float(c));
        }
        meta.extra.insert(role.into(), toml::Value::Table(t));
        Ok(())
    }
}

/// The scene's name: the fronts' `detp.scene` file stem, else the run's name.
fn scene_name(main: &Csv, run: &str) -> String {
    main.param_texts(input::keys::SCENE)
        .ok()
        .and_then(|v| v.into_iter().next())
        .and_then(|s| {
            Path::new(&s)
                .file_stem()
                .map(|x| x.to_string_lossy().into_owned())
        })
        .filter(|s| !s.is_empty() && s != "NaN")
        .unwrap_or_else(|| run.to_string())
}

/// The first row's value of a column `t` was read from.
fn first(t: &Csv, column: Vec<f64>) -> Result<f64, OutputError> {
    column
        .into_iter()
        .next()
        .ok_or_else(|| OutputError::new(&t.path, "has no rows"))
}

/// An input's runs (the n_P sweep's, or the fronts'): `DIR/runs/R` for every run R that
/// `raycost run --run R` (or `--repeat`) wrote there, in run order; else the one run in `DIR`.
fn sweep_runs(dir: &Path) -> Result<Vec<Source>, OutputError> {
    let runs = dir.join("runs");
    if !runs.is_dir() {
        return Ok(vec![Source::open(dir)?]);
    }
    let entries = std::fs::read_dir(&runs)
        .map_err(|e| OutputError::new(&runs, format!("cannot read the runs folder: {e}")))?;
    let mut numbered: Vec<(u64, PathBuf)> = entries
        .flatten()
        .filter_map(|e| {
            let r = e.file_name().to_string_lossy().parse::<u64>().ok()?;
            e.path().is_dir().then(|| (r, e.path()))
        })
        .collect();
    numbered.sort();
    if numbered.is_empty() {
        return Err(OutputError::new(
            &runs,
            "holds no run folder (runs/R, as raycost run --run R writes)",
        ));
    }
    numbered.iter().map(|(_, d)| Source::open(d)).collect()
}

/// A multi-run input's provenance (the n_P sweep's runs, or the fronts' runs): every run's files
/// under `role`, and `[extra.ROLE]` naming the folder given (so that `raycost reproduce` reruns on
/// every run) with each run's machine in `[extra.ROLE.runs.R]`.
fn record_runs(
    role: &str,
    dir: &Path,
    runs: &[Source],
    meta: &mut Meta,
) -> Result<(), OutputError> {
    if let [one] = runs {
        if one.results.dir == dir {
            return one.record(role, meta);
        }
    }
    let mut table = toml::Table::new();
    for s in runs {
        let mut m = Meta::begin("crossover", Default::default());
        s.record_from(role, dir, &mut m)?;
        meta.inputs.extend(m.inputs);
        if let Some(t) = m.extra.remove(role) {
            let run = s
                .results
                .dir
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            table.insert(run, t);
        }
    }
    let mut t = toml::Table::new();
    t.insert("dir".into(), toml::Value::String(dir.display().to_string()));
    t.insert("runs".into(), toml::Value::Table(table));
    meta.extra.insert(role.into(), toml::Value::Table(t));
    Ok(())
}

/// The DETP errors of the fronts' further runs (`FRONTS_DIR/runs/R` beyond the first: e.g. a
/// radius rule that cannot share the first run's sweep, such as κ, which only a clamping edge
/// remedy takes), added to the first run's; a configuration in two runs is refused (which
/// run's errors would it be?).
fn add_fronts_runs(
    detp: &mut Vec<fronts::DetpErrors>,
    more: &mut [Source],
) -> Result<(), OutputError> {
    for src in more {
        let main = src.main()?;
        let (judged, _) = src.judged(&main)?;
        for e in fronts::detp_errors(&main, &judged)? {
            if detp.iter().any(|d| d.config == e.config) {
                return Err(OutputError::new(
                    &main.path,
                    format!(
                        "repeats the configuration {} of an earlier run of the fronts: each run must add its own configurations",
                        e.config.describe()
                    ),
                ));
            }
            detp.push(e);
        }
    }
    Ok(())
}

/// Reads every input and runs the analysis.
fn compute(o: &Options) -> Result<Outputs, OutputError> {
    let mut fronts_runs = sweep_runs(&o.fronts)?;
    let mut more_fronts = fronts_runs.split_off(1);
    let fronts = &mut fronts_runs[0];
    let main = fronts.main()?;
    let (judged, points) = fronts.judged(&main)?;
    let pt_side = fronts.side("path_tracing")?;
    let seed = first(&main, main.param(input::keys::SEED)?)? as u64;
    let scene = scene_name(&main, &fronts.results.name);
    let mut detp = fronts::detp_errors(&main, &judged)?;
    add_fronts_runs(&mut detp, &mut more_fronts)?;
    let maps = fronts::map_errors(&main, &judged)?;
    let (pt_point, pt_cv2) = fronts::path_tracing_cv2(&pt_side, points.as_ref())?;
    let mut sweeps = sweep_runs(&o.points)?;
    let mut tables = Vec::new();
    for s in &mut sweeps {
        tables.push(s.main()?);
    }
    let runs = tables
        .iter()
        .map(costs::run_timings)
        .collect::<Result<Vec<_>, _>>()?;
    let inputs = analysis::Inputs {
        scene: scene.clone(),
        seed,
        detp,
        maps,
        pt_cv2,
        pt_point,
        timing: costs::path_timing(&tables)?,
        costs: costs::pooled(&runs),
        runs,
    };
    let mut rows = analysis::crossover_rows(&inputs, &o.targets);
    let mut confirm = match &o.confirm {
        Some(dir) => {
            let mut src = Source::open(dir)?;
            let table = src.main()?;
            confirm::HeadToHead::read(&table)?.confirm(&mut rows);
            Some(src)
        }
        None => None,
    };
    // The fronts' own point count joins the grid: "at the points I measured, which is fastest?"
    let fronts_points = first(
        &main,
        main.value(&crate::experiment::detp::columns::POINTS)?,
    )?;
    let best = analysis::best_rows(
        &rows,
        &o.targets,
        &[fronts_points],
        costs::measured_points(&inputs.runs),
    );
    let mut meta = Meta::begin("crossover", Default::default());
    meta.run.seed = seed;
    fronts_runs.extend(more_fronts);
    record_runs("fronts", &o.fronts, &fronts_runs, &mut meta)?;
    record_runs("points", &o.points, &sweeps, &mut meta)?;
    if let Some(src) = confirm.as_mut() {
        src.record("confirm", &mut meta)?;
    }
    let frames = match &o.frames {
        Some(dir) => {
            let mut src = Source::open(dir)?;
            let table = src.main()?;
            let read = frames::read_frames(&table)?;
            src.record("frames", &mut meta)?;
            let out = frames::frames_rows(&scene, &inputs.detp, &read, &o.targets);
            Some(out.iter().map(columns::frames_row).collect::<Vec<Row>>())
        }
        None => None,
    };
    let main_rows: Vec<Row> = rows.iter().map(columns::crossover_row).collect();
    let best_rows: Vec<Row> = best.iter().map(columns::best_row).collect();
    for (name, t) in [
        ("main", Some(&main_rows)),
        ("best", Some(&best_rows)),
        ("frames", frames.as_ref()),
    ] {
        if let Some(first) = t.and_then(|t| t.first()) {
            meta.columns.insert(name.into(), first.columns());
        }
    }
    Ok(Outputs {
        best: best_rows,
        frames,
        meta,
        main: main_rows,
    })
}

/// Writes the outputs under the lock: temporaries renamed into place, `crossover.csv` last.
fn write(out: &Path, force: bool, o: Outputs) -> crate::error::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out)
        .map_err(|e| OutputError::new(out, format!("cannot create the output folder: {e}")))?;
    let _lock = Lock::acquire(out, "crossover")?;
    refuse_existing(out, force)?;
    let files: Vec<(PathBuf, Vec<u8>)> = [
        Some(("best.csv", serialize(&o.best))),
        o.frames.as_ref().map(|f| ("frames.csv", serialize(f))),
        Some(("crossover.meta.toml", o.meta.render().into_bytes())),
        Some(("crossover.csv", serialize(&o.main))),
    ]
    .into_iter()
    .flatten()
    .map(|(name, bytes)| (out.join(name), bytes))
    .collect();
    let targets: Vec<PathBuf> = FILES.iter().map(|f| out.join(f)).collect();
    folder::remove_stale_temporaries(&targets)?;
    let staged = files
        .iter()
        .map(|(p, bytes)| folder::stage(p, bytes))
        .collect::<std::io::Result<Vec<_>>>()?;
    folder::publish_staged(staged)?;
    if o.frames.is_none() {
        // A frames table of an earlier analysis (replaced with --force) does not belong to this one.
        folder::remove_if_exists(&out.join("frames.csv"))?;
    }
    Ok(files.into_iter().map(|(p, _)| p).collect())
}
