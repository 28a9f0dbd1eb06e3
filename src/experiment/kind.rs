//! The one interface every experiment kind implements ([`Kind`]), and its type-erased form
//! ([`DynKind`]) that the runner, `check`, `merge`, the docs and the registry see.
//!
//! A kind owns, in its own module: its name and description; its spec file's serde struct
//! ([`Kind::Raw`], which denies unknown tables and keys, so a table another kind owns is refused by
//! serde with the list of this kind's tables); the translation of one point's raw spec into the
//! engines' own types ([`Kind::configure`], with input files loaded once through [`Inputs`]); its side
//! tables, as a struct with one field per table ([`side_tables!`]: a table that is not declared cannot
//! be written, because there is no field for it); its column declarations; its description and work
//! count for `check` and progress; its memory needs (refused before anything is allocated); and its
//! point runner, which returns one row, the side tables, the summary lines and a typed list of
//! built-in [`Check`]s that the runner handles the same way for every kind (table kept, exit 1).
//!
//! Adding a kind is one module and one line in [`super::registry::KINDS`].

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
use crate::spec::de::{from_text, from_tree, KeyError, TextError};

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
}

/// A point's memory: its needs and the spec's budget for them (key, GiB), if the kind has one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Memory {
    /// The large structures.
    pub needs: Vec<Need>,
    /// `(budget key, GiB)`.
    pub budget: Option<(&'static str, f64)>,
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

/// What one point of a kind produced.
#[derive(Debug)]
pub struct PointOutput<T> {
    /// The main row (without `point` and the parameters, which the runner prepends).
    pub row: Row,
    /// The side tables' rows.
    pub tables: T,
    /// Summary lines (measured ± CI, theory, verdict), from declared metrics.
    pub summary: Vec<SummaryLine>,
    /// Built-in checks.
    pub checks: Vec<Check>,
    /// The point's speed, for the summary.
    pub rate: Rate,
    /// Counted warnings found while running.
    pub warnings: Vec<String>,
}

/// A kind's side tables: a struct with one `Vec<Row>` per table, declared with [`side_tables!`].
pub trait SideTables: Default + Send + 'static {
    /// Table names, as in `STEM.NAME.csv`.
    const NAMES: &'static [&'static str];
    /// `(name, rows)` of every table, in [`SideTables::NAMES`] order.
    fn into_named(self) -> Vec<(&'static str, Vec<Row>)>;
}

/// Declares a kind's side tables: `side_tables!(GridTables { hist })` makes `struct GridTables {
/// pub hist: Vec<Row> }` and its [`SideTables`] impl (`STEM.hist.csv`).
#[macro_export]
macro_rules! side_tables {
    ($(#[$m:meta])* $name:ident { $($(#[$fm:meta])* $field:ident),* $(,)? }) => {
        $(#[$m])*
        #[derive(Debug, Default)]
        pub struct $name { $($(#[$fm])* #[doc = concat!("Rows of `NAME.", stringify!($field), ".csv`.")] pub $field: Vec<$crate::output::row::Row>),* }
        impl $crate::experiment::kind::SideTables for $name {
            const NAMES: &'static [&'static str] = &[$(stringify!($field)),*];
            fn into_named(self) -> Vec<(&'static str, Vec<$crate::output::row::Row>)> {
                vec![$((stringify!($field), self.$field)),*]
            }
        }
    };
}

/// No side tables.
#[derive(Debug, Default)]
pub struct NoTables;

impl SideTables for NoTables {
    const NAMES: &'static [&'static str] = &[];
    fn into_named(self) -> Vec<(&'static str, Vec<Row>)> {
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
    /// The point's index in the sweep (part of every random stream's key).
    pub index: u64,
    /// Called with the number of work units just finished.
    pub progress: &'a (dyn Fn(u64) + Sync),
}

/// One experiment kind (see the module doc).
pub trait Kind: Send + Sync + 'static {
    /// `experiment.kind` spelling.
    const NAME: &'static str;
    /// What it measures, one paragraph (for `raycost doc` and `check`).
    const ABOUT: &'static str;
    /// Keys that cannot be swept, and why.
    const FIXED: &'static [(&'static str, &'static str)] = &[];
    /// The spec file of this kind: `[experiment]`, `[sweep]` and the kind's own tables.
    type Raw: DeserializeOwned + Serialize;
    /// One point, validated, in the engines' own types.
    type Point: Send + Sync + 'static;
    /// The side tables.
    type Tables: SideTables;
    /// What a run measures once and shares with its points (the cost model's machine constants).
    type Shared: Send + Sync + 'static;

    /// Every column the kind can write: `("main", …)` and one entry per side table.
    fn columns() -> Vec<(&'static str, &'static [Column])>;
    /// Validates one point's raw spec into a runnable point.
    fn configure(raw: Self::Raw, inputs: &mut Inputs) -> Result<Self::Point, ConfigError>;
    /// One line for `raycost check`.
    fn describe(p: &Self::Point) -> String;
    /// Work, for progress.
    fn work(p: &Self::Point) -> Work;
    /// Memory, refused before anything is allocated when it does not fit.
    fn memory(_p: &Self::Point) -> Memory {
        Memory::default()
    }
    /// Counted warnings known before running (a scene's degenerate triangles, objects that may
    /// overlap).
    fn warnings(_p: &Self::Point) -> Vec<String> {
        Vec::new()
    }
    /// What the run measures once before its points.
    fn shared(points: &[&Self::Point]) -> Result<Self::Shared, Error>;
    /// Facts of the shared measurement for the metadata.
    fn shared_meta(_s: &Self::Shared) -> toml::Table {
        toml::Table::new()
    }
    /// Runs one point.
    fn run(
        p: &Self::Point,
        shared: &Self::Shared,
        ctx: &Context,
    ) -> Result<PointOutput<Self::Tables>, Error>;
}

/// A point of some kind, type-erased.
pub trait DynPoint: Send + Sync {
    /// One line for `raycost check`.
    fn describe(&self) -> String;
    /// Work, for progress.
    fn work(&self) -> Work;
    /// Memory.
    fn memory(&self) -> Memory;
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
    fn memory(&self) -> Memory {
        K::memory(&self.0)
    }
    fn warnings(&self) -> Vec<String> {
        K::warnings(&self.0)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A point's output, type-erased (side tables by name).
pub type ErasedOutput = PointOutput<Vec<(&'static str, Vec<Row>)>>;

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
    /// Column declarations per table.
    fn columns(&self) -> Vec<(&'static str, &'static [Column])>;
    /// Reads the whole file with this kind's serde struct (errors located by line and column).
    fn check_text(&self, text: &str) -> Result<(), TextError>;
    /// The tree read and written back with defaults filled in (the normalised spec).
    fn normalize(&self, tree: &toml::Table) -> Result<toml::Value, KeyError>;
    /// Validates one point's tree.
    fn configure(
        &self,
        tree: &toml::Table,
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
}

/// Kind `K` behind [`DynKind`].
pub struct Registered<K: Kind>(PhantomData<fn() -> K>);

impl<K: Kind> Registered<K> {
    /// The registry entry.
    pub const NEW: Self = Self(PhantomData);
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
        <K::Tables as SideTables>::NAMES
    }
    fn columns(&self) -> Vec<(&'static str, &'static [Column])> {
        K::columns()
    }
    fn check_text(&self, text: &str) -> Result<(), TextError> {
        from_text::<K::Raw>(text).map(|_| ())
    }
    fn normalize(&self, tree: &toml::Table) -> Result<toml::Value, KeyError> {
        let raw: K::Raw = from_tree(tree)?;
        toml::Value::try_from(&raw).map_err(|e| KeyError::new("", e.to_string()))
    }
    fn configure(
        &self,
        tree: &toml::Table,
        inputs: &mut Inputs,
    ) -> Result<Box<dyn DynPoint>, ConfigError> {
        let raw: K::Raw = from_tree(tree)?;
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
        let shared = shared
            .downcast_ref::<K::Shared>()
            .expect("the shared measurement comes from the same kind");
        let out = K::run(point_of::<K>(point), shared, ctx)?;
        Ok(PointOutput {
            row: out.row,
            tables: out.tables.into_named(),
            summary: out.summary,
            checks: out.checks,
            rate: out.rate,
            warnings: out.warnings,
        })
    }
}
