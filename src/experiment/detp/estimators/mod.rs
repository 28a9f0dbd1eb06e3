//! The estimators of kind `detp`, one file each, registered by one line in [`estimators!`] below
//! (as kinds are by `kinds!`): the spec spelling in `detp.engines`, its checks, what it needs in
//! memory, how photon shards treat it, its measured type and its main-table columns are all the
//! estimator's own ([`Estimator`]). The spec's parsing ([`EngineChoice`] reads a name through the
//! registry), the point runner (`measure.rs`), `raycost doc`, photon shards and their merge, kind
//! `quasi-static` and `raycost render` see estimators only through [`ESTIMATORS`].
//!
//! Adding one (docs/architecture.md, "Adding an estimator"): a file here with a unit struct
//! implementing [`Estimator`] and its engine (`super::engines::Engine`, what it runs on one replica),
//! and one line in the registry. Its columns appear in `raycost doc columns`, its name in
//! `raycost doc spec`.
//!
//! DETP estimators ([`Role::Detp`]) return integer sums per disc, which must agree bit for bit;
//! baselines ([`Role::Baseline`]) their own estimates, judged against the reference
//! ([`Role::Reference`]).

use std::any::Any;
use std::fmt;
use std::marker::PhantomData;
use std::sync::{Arc, OnceLock};

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::config::DetpConfig;
use super::engines::{Engine, ReferenceCache};
use super::spec::RawDetp;
use crate::experiment::kind::{ConfigError, Need};
use crate::output::column::Column;
use crate::output::table::{cells, Cells, Table};

// Declares the estimator modules and registers their estimators, one line per module:
// `module => Estimator` declares `pub mod module;` and adds the estimator to `ESTIMATORS`, in the
// order `raycost doc` lists their columns and names. The first is `detp.engines`' default.
macro_rules! estimators {
    ($($(#[$m:meta])* $module:ident => $est:ty),* $(,)?) => {
        $($(#[$m])* pub mod $module;)*
        /// Every estimator, in registry order.
        pub(crate) static ESTIMATORS: &[&dyn $crate::experiment::detp::estimators::DynEstimator] = &[
            $(&$crate::experiment::detp::estimators::Registered::<$est>::NEW),*
        ];
    };
}

// The registry: one line per estimator (its module and its type).
estimators! {
    sphere_cache => sphere_cache::SphereCache,
    disc_index => disc_index::DiscIndex,
    brute_force => brute_force::BruteForce,
    photon_map => photon_map::PhotonMap,
    photon_map_growing => photon_map_growing::PhotonMapGrowing,
    path_tracing => path_tracing::PathTracing,
    reference => reference::Reference,
}

/// What an estimator's values are to the point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A DETP engine: integer sums per disc, equal to every other DETP engine's bit for bit.
    Detp,
    /// A baseline beside the DETP engines: its own estimate per disc, judged against the reference.
    Baseline,
    /// The ground truth the others are judged against (its estimate and SE per disc).
    Reference,
}

/// How `raycost crossover` compares an estimator (which method when): the estimator says, so a new
/// one joins the comparison from its own file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossover {
    /// A DETP engine: its errors are DETP's (every DETP engine's, bit for bit), its seconds its own.
    Detp,
    /// A photon map: its own errors, one per replica in the points-table family `replica`, and its
    /// own seconds.
    PhotonMap {
        /// The points table's per-replica estimates (member: the replica).
        replica: &'static Column,
    },
    /// Per-point path tracing: errors from its per-path variance, seconds per path.
    PathTracing,
}

/// How `--photon-shard` treats an estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shards {
    /// Its counts add across disjoint photon subsets: a shard keeps them, the merge adds them.
    Add,
    /// It reads no photons: a shard skips it and the merge computes it, once.
    Skip,
    /// Its counts do not add; why, for the refusal ("the sphere cache subdivides …").
    Refuse(&'static str),
}

/// One estimator of kind `detp` (see the module doc). A unit struct: its engine
/// ([`Estimator::engine`]) holds what one point's replicas measure.
pub(crate) trait Estimator: 'static {
    /// Its spelling in `detp.engines` (`"sphere-cache"`).
    const NAME: &'static str;
    /// Its column stem: the member of every engine family it writes (`tests_{}` →
    /// `tests_sphere_cache`).
    const COLUMN: &'static str;
    /// DETP engine, baseline or reference.
    const ROLE: Role;
    /// What photon shards do with it.
    const SHARDS: Shards;
    /// Its sums are brute force's: where it runs, every disc is checked against it and no keyed
    /// subset is re-computed.
    const ORACLE: bool = false;
    /// How `raycost crossover` compares it (`None`: not at all).
    const CROSSOVER: Option<Crossover> = None;
    /// What it measured over a point's replicas.
    type Measured: fmt::Debug + Send + Sync + 'static;
    /// Its group of main-table columns, read from [`Estimator::Measured`].
    const COLUMNS: Table<DetpConfig, Self::Measured>;
    /// Its own refusals of `[detp]` (`lines`: the rays are μ-random lines, not a scene's photons).
    fn check(_d: &RawDetp, _lines: bool) -> Result<(), ConfigError> {
        Ok(())
    }
    /// Its large structures for a point of `segments` segments run on `threads` threads.
    fn memory(_cfg: &DetpConfig, _segments: f64, _threads: f64) -> Vec<Need> {
        Vec::new()
    }
    /// A fresh engine for one point (it reads and fills the run's `refs` where it shares values
    /// across sweep points).
    fn engine(refs: &ReferenceCache) -> Box<dyn Engine>;
}

/// [`Estimator`] as an object, for the registry.
pub(crate) trait DynEstimator: Sync {
    /// [`Estimator::NAME`].
    fn name(&self) -> &'static str;
    /// [`Estimator::COLUMN`].
    fn column(&self) -> &'static str;
    /// [`Estimator::ROLE`].
    fn role(&self) -> Role;
    /// [`Estimator::SHARDS`].
    fn shards(&self) -> Shards;
    /// [`Estimator::ORACLE`].
    fn oracle(&self) -> bool;
    /// [`Estimator::CROSSOVER`].
    fn crossover(&self) -> Option<Crossover>;
    /// Its main-table columns.
    fn columns(&self) -> Vec<&'static Column>;
    /// [`Estimator::check`].
    fn check(&self, d: &RawDetp, lines: bool) -> Result<(), ConfigError>;
    /// [`Estimator::memory`].
    fn memory(&self, cfg: &DetpConfig, segments: f64, threads: f64) -> Vec<Need>;
    /// [`Estimator::engine`].
    fn engine(&self, refs: &ReferenceCache) -> Box<dyn Engine>;
}

/// An estimator type as a registry entry.
pub struct Registered<E>(PhantomData<fn() -> E>);

impl<E> Registered<E> {
    /// The entry.
    pub const NEW: Self = Self(PhantomData);
}

impl<E: Estimator> DynEstimator for Registered<E> {
    fn name(&self) -> &'static str {
        E::NAME
    }
    fn column(&self) -> &'static str {
        E::COLUMN
    }
    fn role(&self) -> Role {
        E::ROLE
    }
    fn shards(&self) -> Shards {
        E::SHARDS
    }
    fn oracle(&self) -> bool {
        E::ORACLE
    }
    fn crossover(&self) -> Option<Crossover> {
        E::CROSSOVER
    }
    fn columns(&self) -> Vec<&'static Column> {
        E::COLUMNS.columns()
    }
    fn check(&self, d: &RawDetp, lines: bool) -> Result<(), ConfigError> {
        E::check(d, lines)
    }
    fn memory(&self, cfg: &DetpConfig, segments: f64, threads: f64) -> Vec<Need> {
        E::memory(cfg, segments, threads)
    }
    fn engine(&self, refs: &ReferenceCache) -> Box<dyn Engine> {
        E::engine(refs)
    }
}

/// One name of `detp.engines`: an estimator of the registry.
#[derive(Clone, Copy)]
pub struct EngineChoice(&'static dyn DynEstimator);

impl EngineChoice {
    /// The estimator named `name`.
    pub fn named(name: &str) -> Option<Self> {
        ESTIMATORS
            .iter()
            .find(|e| e.name() == name)
            .map(|&e| Self(e))
    }
    /// Its spelling in specs.
    pub fn as_str(self) -> &'static str {
        self.0.name()
    }
    /// Its column stem.
    pub fn column(self) -> &'static str {
        self.0.column()
    }
    /// Its estimator.
    pub(crate) fn estimator(self) -> &'static dyn DynEstimator {
        self.0
    }
    /// A baseline or the reference beside the DETP engines (its own estimates, not DETP's sums)?
    pub fn is_baseline(self) -> bool {
        self.0.role() != Role::Detp
    }
    /// Does it read the photons? Those that do not are skipped by a photon shard and computed
    /// once by the merge.
    pub fn reads_photons(self) -> bool {
        self.0.shards() != Shards::Skip
    }
    /// How `raycost crossover` compares it.
    pub fn crossover(self) -> Option<Crossover> {
        self.0.crossover()
    }
    /// Every estimator, in registry order.
    pub fn all() -> impl Iterator<Item = EngineChoice> {
        ESTIMATORS.iter().map(|&e| Self(e))
    }
    /// Is it estimator `E`?
    pub(crate) fn is<E: Estimator>(self) -> bool {
        self.as_str() == E::NAME
    }
}

impl PartialEq for EngineChoice {
    fn eq(&self, o: &Self) -> bool {
        self.as_str() == o.as_str()
    }
}

impl Eq for EngineChoice {}

impl fmt::Debug for EngineChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for EngineChoice {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        let s = String::deserialize(d)?;
        Self::named(&s).ok_or_else(|| {
            let allowed: Vec<String> = ESTIMATORS
                .iter()
                .map(|e| format!("\"{}\"", e.name()))
                .collect();
            D::Error::custom(format!("got \"{s}\", expected one of {}", allowed.join(", ")))
        })
    }
}

impl Serialize for EngineChoice {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl crate::toml_text::keys::Omit for EngineChoice {}

/// `detp.engines`' default: the first estimator registered.
pub fn default_engines() -> Vec<EngineChoice> {
    vec![EngineChoice(ESTIMATORS[0])]
}

/// `detp.engines`' allowed values for `raycost doc spec`: every name, quoted, in registry order.
pub fn spellings() -> &'static str {
    static S: OnceLock<String> = OnceLock::new();
    S.get_or_init(|| {
        ESTIMATORS
            .iter()
            .map(|e| format!("`\"{}\"`", e.name()))
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// The names of the estimators of `role`, joined as a list is in a sentence ("a, b or c").
pub(crate) fn names_of(role: Role, last: &str) -> String {
    let names: Vec<&str> = ESTIMATORS
        .iter()
        .filter(|e| e.role() == role)
        .map(|e| e.name())
        .collect();
    match names.split_last() {
        None => String::new(),
        Some((l, [])) => (*l).to_string(),
        Some((l, rest)) => format!("{} {last} {l}", rest.join(", ")),
    }
}

/// What one estimator measured over a point's replicas, with the columns it is written in.
#[derive(Clone)]
pub struct EngineMeasured(Arc<dyn MeasuredCells>);

/// A measurement that knows its estimator's columns.
trait MeasuredCells: Send + Sync {
    fn column(&self) -> &'static str;
    fn cells(&self, p: &DetpConfig) -> Cells;
    fn any(&self) -> &dyn Any;
    fn debug(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result;
}

/// Estimator `E`'s measurement.
struct Typed<E: Estimator>(E::Measured);

impl<E: Estimator> MeasuredCells for Typed<E> {
    fn column(&self) -> &'static str {
        E::COLUMN
    }
    fn cells(&self, p: &DetpConfig) -> Cells {
        cells(E::COLUMNS.entries, p, &self.0)
    }
    fn any(&self) -> &dyn Any {
        &self.0
    }
    fn debug(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.0, f)
    }
}

impl EngineMeasured {
    /// Estimator `E`'s measurement `m`.
    pub(crate) fn of<E: Estimator>(m: E::Measured) -> Self {
        Self(Arc::new(Typed::<E>(m)))
    }
    /// Its estimator's column stem.
    pub fn column(&self) -> &'static str {
        self.0.column()
    }
    /// Its cells in the main table.
    pub fn cells(&self, p: &DetpConfig) -> Cells {
        self.0.cells(p)
    }
    /// The measurement, if it is an `M`.
    pub fn get<M: 'static>(&self) -> Option<&M> {
        self.0.any().downcast_ref()
    }
}

impl fmt::Debug for EngineMeasured {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ", self.column())?;
        self.0.debug(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// Names and column stems are unique, a stem is the name in snake case, and every estimator
    /// declares columns.
    #[test]
    fn the_registry_is_consistent() {
        let names: BTreeSet<&str> = ESTIMATORS.iter().map(|e| e.name()).collect();
        assert_eq!(names.len(), ESTIMATORS.len(), "a name is registered twice");
        for e in ESTIMATORS {
            assert_eq!(e.column(), e.name().replace('-', "_"), "{}", e.name());
            assert!(!e.columns().is_empty(), "{} declares no column", e.name());
            assert_eq!(EngineChoice::named(e.name()).map(|c| c.as_str()), Some(e.name()));
        }
        assert!(EngineChoice::named("no-such-engine").is_none());
    }
}
