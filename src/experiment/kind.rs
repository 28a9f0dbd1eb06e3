//! The one interface every experiment kind implements ([`Kind`]), and its type-erased form
//! ([`DynKind`]) that the runner, `check`, `merge`, the docs and the registry see.
//!
//! A kind owns, in its own module: its name and description; its spec file's serde struct
//! ([`Kind::Raw`], which denies unknown tables and keys, so a table another kind owns is refused by
//! serde with the list of this kind's tables); the translation of one point's raw spec into the
//! engines' own types ([`Kind::configure`], with input files loaded once through [`Inputs`]); its
//! description and work count for `check` and progress; its memory needs (refused before anything is
//! allocated); and its point runner, which returns a typed measurement ([`Kind::Measured`]), typed
//! side-table rows ([`side_tables!`]: a struct with one field per table, so a table that is not
//! declared cannot be written) and a typed list of built-in [`Check`]s that the runner handles the
//! same way for every kind (table kept, exit 1).
//!
//! A kind never writes a cell: it declares each table once as (column, accessor) entries
//! ([`Kind::MAIN`], and one [`Table`] per side table), and the shared code of
//! [`crate::output::table`] turns the measurements into rows, summary lines and verdicts
//! ([`Registered`] does it for every kind alike).
//!
//! Adding a kind is one module and one line in the registry ([`super::KINDS`]).

use std::any::Any;
use std::marker::PhantomData;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::inputs::Inputs;
use crate::error::{Error, InputError};
use crate::output::column::Column;
use crate::output::row::Row;
pub use crate::output::summary::Rate;
use crate::output::summary::SummaryLine;
use crate::output::table;
pub use crate::output::table::{col, Cell, Cells, Entry, Line, Table};
use crate::toml_text::de::{from_tree, KeyError};
use crate::toml_text::keys::{keys_of, KeyDoc, SpecTable};

/// What a point does, for progress and ETA: `units` of `unit` (rays, photons, photon-frames); and
/// for `raycost check`'s total, the sample points each unit meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Work {
    /// How many.
    pub units: u64,
    /// Of what (plural noun).
    pub unit: &'static str,
    /// Sample points each unit is held against (DETP's discs); 1 where units meet no points (rays
    /// of the grid kinds, lines). `check` sums `units × points` and warns above its threshold.
    pub points: u64,
}

/// Memory a point needs before it allocates: one entry per large structure.
#[derive(Clone, Debug, PartialEq)]
pub struct Need {
    /// Bytes.
    pub bytes: f64,
    /// The spec key that drives it (named when the run is refused).
    pub key: &'static str,
    /// What it is ("grid cell lists", "segment store", …).
    pub what: String,
    /// Whether it grows with the photons traced at once (the segment store): the part that photon
    /// batches divide. The rest (discs, their sums, indices over the discs) is held whole by every
    /// batch.
    pub per_photon: bool,
}

/// A point's memory: its needs and the spec's budget for them (key, GiB), if the kind has one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Memory {
    /// The large structures.
    pub needs: Vec<Need>,
    /// `(budget key, GiB)`.
    pub budget: Option<(&'static str, f64)>,
    /// Where the kind can trace a point's photons in batches (see
    /// [`super::photon_batches`]): its key and photon count (None: no photons to batch).
    pub batching: Option<Batching>,
}

/// A point's photons as photon batches see them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Batching {
    /// The spec key that forces a batch count (`detp.photon_batches`).
    pub key: &'static str,
    /// The count it forces (None: `"auto"`, as the budget needs).
    pub forced: Option<u64>,
    /// Photons per replica, P: batch K of B traces photons `[K·P/B, (K+1)·P/B)`.
    pub photons: u64,
}

/// A built-in check of one point: how many items failed out of how many checked. Every kind's checks
/// are handled alike: the row is written, then the run fails (exit 1) with the tables kept as
/// evidence.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Check {
    /// Its CSV column (`mismatches`, `full_mismatch`, `bf_mismatches`).
    pub name: &'static str,
    /// What a failure means ("engines ≠ brute force").
    pub what: &'static str,
    /// Failures (0 when correct).
    pub failures: u64,
    /// Items checked.
    pub checked: u64,
}

/// What one point of a kind measured: typed values, never cells (the kind's declared tables turn
/// them into rows).
#[derive(Debug)]
pub struct Output<M, T> {
    /// The main row's measurement ([`Kind::MAIN`] reads it).
    pub measured: M,
    /// The side tables' rows, typed.
    pub tables: T,
    /// Built-in checks.
    pub checks: Vec<Check>,
    /// The point's speed, for the summary.
    pub rate: Rate,
    /// Counted warnings found while running.
    pub warnings: Vec<String>,
}

/// A kind's side tables: a struct with one `Vec` of typed rows per table, each read by its declared
/// [`Table`], made with [`side_tables!`].
pub trait SideTables<P>: Default + Send + 'static {
    /// Table names, as in `STEM.NAME.csv`.
    const NAMES: &'static [&'static str];
    /// Every table's declared columns, in [`SideTables::NAMES`] order.
    fn columns() -> Vec<(&'static str, Vec<&'static Column>)>;
    /// Every table's rows (as cells) and summary lines, in [`SideTables::NAMES`] order.
    fn cells(&self, p: &P) -> Vec<(&'static str, Vec<Cells>, Vec<Line>)>;
}

/// Declares a kind's side tables: `side_tables!(GridTables for GridConfig { hist: HistBin =
/// columns::HIST })` makes `struct GridTables { pub hist: Vec<HistBin> }`, whose rows
/// `columns::HIST` (a [`Table<GridConfig, HistBin>`]) reads into `STEM.hist.csv`.
#[macro_export]
macro_rules! side_tables {
    ($(#[$m:meta])* $name:ident for $point:ty { $($(#[$fm:meta])* $field:ident : $row:ty = $table:expr),* $(,)? }) => {
        $(#[$m])*
        #[derive(Debug, Default)]
        pub struct $name { $($(#[$fm])* #[doc = concat!("Rows of `NAME.", stringify!($field), ".csv`.")] pub $field: Vec<$row>),* }
        impl $crate::experiment::kind::SideTables<$point> for $name {
            const NAMES: &'static [&'static str] = &[$(stringify!($field)),*];
            fn columns() -> Vec<(&'static str, Vec<&'static $crate::output::column::Column>)> {
                vec![$((stringify!($field), $table.columns())),*]
            }
            fn cells(&self, p: &$point) -> Vec<(&'static str, Vec<$crate::output::table::Cells>, Vec<$crate::output::table::Line>)> {
                vec![$({
                    let t = &$table;
                    let rows = self.$field.iter().map(|r| $crate::output::table::cells(t.entries, p, r)).collect();
                    let lines = self.$field.iter().flat_map(|r| (t.lines)(p, r)).collect();
                    (stringify!($field), rows, lines)
                }),*]
            }
        }
    };
}

/// No side tables.
#[derive(Debug, Default)]
pub struct NoTables;

impl<P> SideTables<P> for NoTables {
    const NAMES: &'static [&'static str] = &[];
    fn columns() -> Vec<(&'static str, Vec<&'static Column>)> {
        Vec::new()
    }
    fn cells(&self, _: &P) -> Vec<(&'static str, Vec<Cells>, Vec<Line>)> {
        Vec::new()
    }
}

/// Why a point's spec cannot run: a key of the spec (located by the spec layer), or a file it names
/// (located in that file).
#[derive(Clone, Debug, PartialEq)]
pub enum ConfigError {
    /// A key of the spec.
    Key(KeyError),
    /// A file the spec names (a scene, a points CSV).
    Input(InputError),
}

impl From<KeyError> for ConfigError {
    fn from(e: KeyError) -> Self {
        ConfigError::Key(e)
    }
}

impl From<InputError> for ConfigError {
    fn from(e: InputError) -> Self {
        ConfigError::Input(e)
    }
}

/// `Err(ConfigError::Key)` about `key`.
pub fn refuse<T>(key: &str, message: impl Into<String>) -> Result<T, ConfigError> {
    Err(ConfigError::Key(KeyError::new(key, message)))
}

/// What a point runner is given.
pub struct Context<'a> {
    /// The point's part of every random stream's key: its index in the sweep, or 0 for every
    /// point under `experiment.common_random_numbers` (so points share their samples).
    pub stream_point: u64,
    /// Worker threads of the run (`--threads`, or the machine's), passed down, never read back
    /// from the pool. Only timings may depend on it.
    pub threads: usize,
    /// Called with the number of work units just finished.
    pub progress: &'a (dyn Fn(u64) + Sync),
    /// `raycost merge` of photon shards, or a point traced in photon batches: the point's parts,
    /// one per shard in shard order ([`Kind::trace_part`], or batches added with
    /// [`Kind::add_parts`]), to measure instead of tracing photons.
    pub merged: Option<&'a [serde_json::Value]>,
}

/// One experiment kind (see the module doc).
pub trait Kind: Send + Sync + 'static {
    /// `experiment.kind` spelling.
    const NAME: &'static str;
    /// What it measures, one paragraph (for `raycost doc` and `check`).
    const ABOUT: &'static str;
    /// Keys that cannot be swept, and why.
    const FIXED: &'static [(&'static str, &'static str)] = &[];
    /// The spec file of this kind: `[experiment]`, `[sweep]` and the kind's own tables, declared
    /// with [`crate::spec_file!`] (its keys, defaults and docs declared once).
    type Raw: DeserializeOwned + Serialize + SpecTable + Send + Sync + 'static;
    /// One point, validated, in the engines' own types.
    type Point: Send + Sync + 'static;
    /// What one point measures (its main row).
    type Measured: 'static;
    /// The side tables.
    type Tables: SideTables<Self::Point>;
    /// What a run measures once and shares with its points (the cost model's machine constants).
    type Shared: Send + Sync + 'static;
    /// The main table: every column with the accessor that reads it from a measurement.
    const MAIN: Table<Self::Point, Self::Measured>;

    /// Validates one point's spec, read once, into a runnable point.
    fn configure(raw: &Self::Raw, inputs: &mut Inputs) -> Result<Self::Point, ConfigError>;
    /// One line for `raycost check`.
    fn describe(p: &Self::Point) -> String;
    /// Work, for progress.
    fn work(p: &Self::Point) -> Work;
    /// Memory on `threads` worker threads, refused before anything is allocated when it does not
    /// fit.
    fn memory(_p: &Self::Point, _threads: usize) -> Memory {
        Memory::default()
    }
    /// Counted warnings known before running (a scene's degenerate triangles, objects that may
    /// overlap).
    fn warnings(_p: &Self::Point) -> Vec<String> {
        Vec::new()
    }
    /// Whether a clock decides some of the point's measured values (the columns declared
    /// [`Column::decided_by_timing`] are then written as timings).
    fn timed_decision(_p: &Self::Point) -> bool {
        false
    }
    /// What the run measures once before its points.
    fn shared(points: &[&Self::Point]) -> Result<Self::Shared, Error>;
    /// Facts of the shared measurement for the metadata.
    fn shared_meta(_s: &Self::Shared) -> toml::Table {
        toml::Table::new()
    }
    /// Runs one point (from [`Context::merged`] parts where given).
    fn run(
        p: &Self::Point,
        shared: &Self::Shared,
        ctx: &Context,
    ) -> Result<Output<Self::Measured, Self::Tables>, Error>;
    /// `--photon-shard`: why this point's photons cannot be split (None: they can). A kind without
    /// photons keeps this default.
    fn photon_refusal(_p: &Self::Point) -> Option<String> {
        Some(format!("kind {} has no photons to split", Self::NAME))
    }
    /// `--photon-shard K/N`: the point's photons `[K·P/N, (K+1)·P/N)` traced into parts that add
    /// across shards; [`Kind::run`] with every shard's part measures the point as an unsplit run.
    fn trace_part(
        _p: &Self::Point,
        _shared: &Self::Shared,
        _ctx: &Context,
        _shard: (u64, u64),
    ) -> Result<serde_json::Value, Error> {
        Err(Error::internal(format!(
            "kind {} has no photons to split",
            Self::NAME
        )))
    }
    /// Photon batches: the part of the photons of `a` and of `b` (whose photons follow `a`'s), both
    /// from [`Kind::trace_part`] of this point, so that a point traced in B batches keeps one part.
    fn add_parts(
        _p: &Self::Point,
        _a: serde_json::Value,
        _b: serde_json::Value,
    ) -> Result<serde_json::Value, Error> {
        Err(Error::internal(format!(
            "kind {} has no photons to split",
            Self::NAME
        )))
    }
}

/// A spec tree read once by a kind ([`DynKind::read`]).
pub struct Reading {
    /// The kind's typed spec ([`Kind::Raw`]).
    raw: Box<dyn Any + Send + Sync>,
    /// Its values written back, defaults filled in.
    pub normalized: toml::Value,
}

/// A point of some kind, type-erased.
pub trait DynPoint: Send + Sync {
    /// One line for `raycost check`.
    fn describe(&self) -> String;
    /// Work, for progress.
    fn work(&self) -> Work;
    /// Memory on `threads` worker threads.
    fn memory(&self, threads: usize) -> Memory;
    /// Warnings known before running.
    fn warnings(&self) -> Vec<String>;
    /// For the kind's own downcast.
    fn as_any(&self) -> &dyn Any;
}

/// The point of kind `K`.
pub struct PointOf<K: Kind>(pub K::Point);

impl<K: Kind> DynPoint for PointOf<K> {
    fn describe(&self) -> String {
        K::describe(&self.0)
    }
    fn work(&self) -> Work {
        K::work(&self.0)
    }
    fn memory(&self, threads: usize) -> Memory {
        K::memory(&self.0, threads)
    }
    fn warnings(&self) -> Vec<String> {
        K::warnings(&self.0)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A point's output as the runner sees it: rows built from the kind's declared tables.
#[derive(Debug)]
pub struct ErasedOutput {
    /// The main row (without `point` and the parameters, which the runner prepends).
    pub row: Row,
    /// The side tables' rows, by name.
    pub tables: Vec<(&'static str, Vec<Row>)>,
    /// Summary lines: the side tables' lines, the main row's judged cells, the main table's lines.
    pub summary: Vec<SummaryLine>,
    /// Built-in checks.
    pub checks: Vec<Check>,
    /// The point's speed.
    pub rate: Rate,
    /// Counted warnings found while running.
    pub warnings: Vec<String>,
}

/// A kind as the runner, `check`, the docs and the registry see it.
pub trait DynKind: Send + Sync {
    /// `experiment.kind` spelling.
    fn name(&self) -> &'static str;
    /// Description.
    fn about(&self) -> &'static str;
    /// Keys that cannot be swept, and why.
    fn fixed(&self) -> &'static [(&'static str, &'static str)];
    /// Side table names.
    fn table_names(&self) -> &'static [&'static str];
    /// Column declarations per table (`main` first).
    fn columns(&self) -> Vec<(&'static str, Vec<Column>)>;
    /// Every key this kind's spec accepts, in declaration order (`[]` after an array of tables),
    /// with its reference entry.
    fn keys(&self) -> Vec<KeyDoc>;
    /// Reads a spec tree with this kind's spec struct, once: the typed spec and its values
    /// written back with defaults filled in (the normalised spec, the parameter columns).
    fn read(&self, tree: &toml::Table) -> Result<Reading, KeyError>;
    /// Validates one point's reading.
    fn configure(
        &self,
        reading: &Reading,
        inputs: &mut Inputs,
    ) -> Result<Box<dyn DynPoint>, ConfigError>;
    /// The shared measurement of a run.
    fn shared(&self, points: &[&dyn DynPoint]) -> Result<Box<dyn Any + Send + Sync>, Error>;
    /// Its facts for the metadata.
    fn shared_meta(&self, shared: &(dyn Any + Send + Sync)) -> toml::Table;
    /// Runs one point.
    fn run(
        &self,
        point: &dyn DynPoint,
        shared: &(dyn Any + Send + Sync),
        ctx: &Context,
    ) -> Result<ErasedOutput, Error>;
    /// [`Kind::photon_refusal`].
    fn photon_refusal(&self, point: &dyn DynPoint) -> Option<String>;
    /// [`Kind::trace_part`].
    fn trace_part(
        &self,
        point: &dyn DynPoint,
        shared: &(dyn Any + Send + Sync),
        ctx: &Context,
        shard: (u64, u64),
    ) -> Result<serde_json::Value, Error>;
    /// [`Kind::add_parts`].
    fn add_parts(
        &self,
        point: &dyn DynPoint,
        a: serde_json::Value,
        b: serde_json::Value,
    ) -> Result<serde_json::Value, Error>;
}

/// Kind `K` behind [`DynKind`].
pub struct Registered<K: Kind>(PhantomData<fn() -> K>);

impl<K: Kind> Registered<K> {
    /// The registry entry.
    pub const NEW: Self = Self(PhantomData);
}

fn shared_of<K: Kind>(s: &(dyn Any + Send + Sync)) -> &K::Shared {
    s.downcast_ref::<K::Shared>()
        .expect("the shared measurement comes from the same kind")
}

fn point_of<K: Kind>(p: &dyn DynPoint) -> &K::Point {
    &p.as_any()
        .downcast_ref::<PointOf<K>>()
        .expect("a point is run by the kind that configured it")
        .0
}

impl<K: Kind> DynKind for Registered<K> {
    fn name(&self) -> &'static str {
        K::NAME
    }
    fn about(&self) -> &'static str {
        K::ABOUT
    }
    fn fixed(&self) -> &'static [(&'static str, &'static str)] {
        K::FIXED
    }
    fn table_names(&self) -> &'static [&'static str] {
        <K::Tables as SideTables<K::Point>>::NAMES
    }
    fn columns(&self) -> Vec<(&'static str, Vec<Column>)> {
        let copy = |cols: Vec<&'static Column>| cols.into_iter().copied().collect();
        std::iter::once(("main", copy(K::MAIN.columns())))
            .chain(
                <K::Tables as SideTables<K::Point>>::columns()
                    .into_iter()
                    .map(|(t, c)| (t, copy(c))),
            )
            .collect()
    }
    fn keys(&self) -> Vec<KeyDoc> {
        keys_of::<K::Raw>()
    }
    fn read(&self, tree: &toml::Table) -> Result<Reading, KeyError> {
        let raw: K::Raw = from_tree(tree)?;
        let normalized =
            toml::Value::try_from(&raw).map_err(|e| KeyError::new("", e.to_string()))?;
        Ok(Reading {
            raw: Box::new(raw),
            normalized,
        })
    }
    fn configure(
        &self,
        reading: &Reading,
        inputs: &mut Inputs,
    ) -> Result<Box<dyn DynPoint>, ConfigError> {
        let raw = reading
            .raw
            .downcast_ref::<K::Raw>()
            .expect("a reading is configured by the kind that read it");
        Ok(Box::new(PointOf::<K>(K::configure(raw, inputs)?)))
    }
    fn shared(&self, points: &[&dyn DynPoint]) -> Result<Box<dyn Any + Send + Sync>, Error> {
        let typed: Vec<&K::Point> = points.iter().map(|p| point_of::<K>(*p)).collect();
        Ok(Box::new(K::shared(&typed)?))
    }
    fn shared_meta(&self, shared: &(dyn Any + Send + Sync)) -> toml::Table {
        shared
            .downcast_ref::<K::Shared>()
            .map(K::shared_meta)
            .unwrap_or_default()
    }
    fn run(
        &self,
        point: &dyn DynPoint,
        shared: &(dyn Any + Send + Sync),
        ctx: &Context,
    ) -> Result<ErasedOutput, Error> {
        let shared = shared_of::<K>(shared);
        let p = point_of::<K>(point);
        let out = K::run(p, shared, ctx)?;
        rows_of::<K>(p, out, ctx.merged.is_some())
            .map_err(|e| Error::internal(format!("kind {}: {e}", K::NAME)))
    }
    fn photon_refusal(&self, point: &dyn DynPoint) -> Option<String> {
        K::photon_refusal(point_of::<K>(point))
    }
    fn trace_part(
        &self,
        point: &dyn DynPoint,
        shared: &(dyn Any + Send + Sync),
        ctx: &Context,
        shard: (u64, u64),
    ) -> Result<serde_json::Value, Error> {
        let shared = shared_of::<K>(shared);
        K::trace_part(point_of::<K>(point), shared, ctx, shard)
    }
    fn add_parts(
        &self,
        point: &dyn DynPoint,
        a: serde_json::Value,
        b: serde_json::Value,
    ) -> Result<serde_json::Value, Error> {
        K::add_parts(point_of::<K>(point), a, b)
    }
}

/// The rows and summary lines of one point's output, from the kind's declared tables.
/// `photon_merged`: the point was measured from photon shards' parts.
fn rows_of<K: Kind>(
    p: &K::Point,
    out: Output<K::Measured, K::Tables>,
    photon_merged: bool,
) -> Result<ErasedOutput, String> {
    let demote = table::Demote {
        timed: K::timed_decision(p),
        photon_merged,
    };
    let main = table::cells(K::MAIN.entries, p, &out.measured);
    let (row, judged) = table::row(&main, demote, true)?;
    let mut summary = Vec::new();
    let mut tables = Vec::new();
    for (name, rows, lines) in out.tables.cells(p) {
        let rows = rows
            .iter()
            .map(|cells| table::row(cells, demote, false).map(|(r, _)| r))
            .collect::<Result<Vec<Row>, String>>()?;
        summary.extend(lines.iter().map(Line::judge));
        tables.push((name, rows));
    }
    summary.extend(judged);
    summary.extend((K::MAIN.lines)(p, &out.measured).iter().map(Line::judge));
    Ok(ErasedOutput {
        row,
        tables,
        summary,
        checks: out.checks,
        rate: out.rate,
        warnings: out.warnings,
    })
}
