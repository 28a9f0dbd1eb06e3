//! Column declarations: every CSV column raycost writes comes from one [`Column`] — its name, unit,
//! class and meaning — declared once beside the code that fills it. Rows are built only through
//! declarations ([`super::row::Row::put`]), so the class of a cell is data, never guessed from its
//! name: the checks that threads, shards and resume leave results unchanged compare every column that
//! is not [`Class::Timing`], and `raycost doc columns` prints the declarations.
//!
//! A declaration may stand for several CSV columns:
//! - an estimate (`shape = Shape::Estimate`) writes `M_mean`, `M_se`, `M_n`, and with a theory
//!   `M_theory` (a prediction) or `M_theory, M_lower, M_upper, M_band` (a band and where the 95 % CI
//!   falls in it);
//! - a name with `{}` is a family, one column per engine or table (`tests_{}` → `tests_sphere_cache`).

use serde::{Deserialize, Serialize};

/// The suffixes after a stem that name an estimate's CSV columns: the one place they are spelled.
/// [`Column::expand`] and the row writer write them, and every reader of a table (the report,
/// `reproduce`'s comparison, the crossover's typed reads) finds an estimate's parts by them.
pub mod part {
    /// The mean.
    pub const MEAN: &str = "_mean";
    /// Its standard error.
    pub const SE: &str = "_se";
    /// The samples behind it.
    pub const N: &str = "_n";
    /// The independent clusters (replicas, batches) its SE was estimated from.
    pub const CLUSTERS: &str = "_clusters";
    /// The closed form it is held against.
    pub const THEORY: &str = "_theory";
    /// A band's lower edge.
    pub const LOWER: &str = "_lower";
    /// A band's upper edge.
    pub const UPPER: &str = "_upper";
    /// Where the 95 % CI falls in the band (a verdict).
    pub const BAND: &str = "_band";

    /// The CSV name of part `suffix` of the estimate of stem `stem`.
    pub fn name(stem: &str, suffix: &str) -> String {
        format!("{stem}{suffix}")
    }

    /// The stem of `name` if it names part `suffix` of an estimate (`n_i_mean` → `n_i`).
    pub fn stem<'a>(name: &'a str, suffix: &str) -> Option<&'a str> {
        name.strip_suffix(suffix).filter(|s| !s.is_empty())
    }
}

/// What a column holds: decides which columns may differ between two runs of one spec and seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Class {
    /// The point index or a parameter of the point (a spec key).
    Parameter,
    /// A measured count or estimate: identical for the same spec and seed on any machine, thread
    /// count, shard or resume.
    Measured,
    /// Seconds, rates and decisions taken from them: the only columns allowed to differ.
    Timing,
    /// A closed form for the point's parameters.
    Theory,
    /// A check's outcome or a verdict derived from measured values (mismatches, band position).
    Check,
}

impl Class {
    /// The spelling in metadata and docs.
    pub fn as_str(self) -> &'static str {
        match self {
            Class::Parameter => "parameter",
            Class::Measured => "measured",
            Class::Timing => "timing",
            Class::Theory => "theory",
            Class::Check => "check",
        }
    }

    /// Must two runs of the same spec and seed agree on this column?
    pub fn is_reproducible(self) -> bool {
        self != Class::Timing
    }
}

/// How many CSV columns a declaration expands to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// One column.
    Value,
    /// `_mean`, `_se`, `_n`.
    Estimate,
    /// `_mean`, `_se`, `_n`, `_theory`: held against a prediction.
    EstimateVsPrediction,
    /// `_mean`, `_se`, `_n`, `_theory`, `_lower`, `_upper`, `_band`: held against a band.
    EstimateVsBand,
}

/// One declared column (or family of columns, see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// CSV name (or stem, for estimates); `{}` marks the variable part of a family.
    pub name: &'static str,
    /// Unit (`"1"` for a pure number, `"rays"`, `"s"`, `"W/m²"`, …).
    pub unit: &'static str,
    /// Class of the value (for estimates: of `_mean` and `_se`).
    pub class: Class,
    /// How many columns it expands to.
    pub shape: Shape,
    /// What it means, one sentence.
    pub doc: &'static str,
    /// Whether ±∞ is a legitimate value (an open histogram edge); elsewhere an infinite value is an
    /// overflow and is never written.
    pub infinite_ok: bool,
    /// Whether its measured values follow a decision a kind may take on seconds (the quasi-static
    /// predictor's engine pick): in a row where a clock decided, its measured cells are written as
    /// timings (`output::table`).
    pub decided_by_timing: bool,
    /// Whether it counts an accelerator's work that depends on every photon of the run (the
    /// quasi-static segment index's cells, listings and tests: each photon shard searches an index
    /// of its own segments): in a row merged from photon shards it holds the work summed across
    /// them, and its measured cells are written as timings (`output::table`).
    pub accelerator_work: bool,
}

/// One expanded CSV column: what metadata records and `raycost doc columns` prints.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ColumnInfo {
    /// CSV name.
    pub name: String,
    /// Class.
    pub class: Class,
    /// Unit.
    pub unit: String,
}

impl Column {
    /// A single-valued column.
    pub const fn value(
        name: &'static str,
        unit: &'static str,
        class: Class,
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            unit,
            class,
            shape: Shape::Value,
            doc,
            infinite_ok: false,
            decided_by_timing: false,
            accelerator_work: false,
        }
    }

    /// A measured estimate (`_mean`, `_se`, `_n`).
    pub const fn estimate(name: &'static str, unit: &'static str, doc: &'static str) -> Self {
        Self {
            name,
            unit,
            class: Class::Measured,
            shape: Shape::Estimate,
            doc,
            infinite_ok: false,
            decided_by_timing: false,
            accelerator_work: false,
        }
    }

    /// An estimated duration or rate (`_mean`, `_se`, `_n`; timing class).
    pub const fn timed_estimate(name: &'static str, unit: &'static str, doc: &'static str) -> Self {
        Self {
            name,
            unit,
            class: Class::Timing,
            shape: Shape::Estimate,
            doc,
            infinite_ok: false,
            decided_by_timing: false,
            accelerator_work: false,
        }
    }

    /// A measured estimate held against a prediction.
    pub const fn vs_prediction(name: &'static str, unit: &'static str, doc: &'static str) -> Self {
        Self {
            name,
            unit,
            class: Class::Measured,
            shape: Shape::EstimateVsPrediction,
            doc,
            infinite_ok: false,
            decided_by_timing: false,
            accelerator_work: false,
        }
    }

    /// A measured estimate held against a band (and a prediction inside it).
    pub const fn vs_band(name: &'static str, unit: &'static str, doc: &'static str) -> Self {
        Self {
            name,
            unit,
            class: Class::Measured,
            shape: Shape::EstimateVsBand,
            doc,
            infinite_ok: false,
            decided_by_timing: false,
            accelerator_work: false,
        }
    }

    /// The estimate (`_mean`, `_se`, `_n`, `_clusters`) of this per-row value over the rows of
    /// another table (a frame's `frame_s` in the frames table, `frame_s_mean`/`_se` over frames in
    /// the main table): one quantity, one declaration; the name, unit, class and flags are kept,
    /// `doc` says what the mean is over.
    pub const fn mean_over(self, doc: &'static str) -> Self {
        Self {
            shape: Shape::Estimate,
            doc,
            ..self
        }
    }

    /// The same estimate, held against a prediction (`_theory` beside it).
    pub const fn against_prediction(self) -> Self {
        Self {
            shape: Shape::EstimateVsPrediction,
            ..self
        }
    }

    /// The same quantity described for another table (what its rows are): name, unit, class,
    /// shape and flags kept.
    pub const fn described(self, doc: &'static str) -> Self {
        Self { doc, ..self }
    }

    /// The same column, with ±∞ allowed (an open-ended bin edge).
    pub const fn open_ended(self) -> Self {
        Self {
            infinite_ok: true,
            ..self
        }
    }

    /// The same column, its measured values following a decision taken on seconds where a kind
    /// takes one (see [`Column::decided_by_timing`](Self::decided_by_timing)).
    pub const fn decided_by_timing(self) -> Self {
        Self {
            decided_by_timing: true,
            ..self
        }
    }

    /// The same column, counting an accelerator's work whose photon shards do not add up to the
    /// whole run's (see [`Column::accelerator_work`](Self::accelerator_work)).
    pub const fn accelerator_work(self) -> Self {
        Self {
            accelerator_work: true,
            ..self
        }
    }

    /// Is this a family (`{}` in the name)?
    pub fn is_family(&self) -> bool {
        self.name.contains("{}")
    }

    /// The CSV name of family member `part` (the name itself when not a family).
    pub fn member(&self, part: &str) -> String {
        self.name.replacen("{}", part, 1)
    }

    /// The CSV columns it expands to, with the name stem `stem` (the name, or a family member).
    pub fn expand(&self, stem: &str) -> Vec<ColumnInfo> {
        let c = |suffix: &str, class: Class| ColumnInfo {
            name: format!("{stem}{suffix}"),
            class,
            unit: match suffix {
                part::N | part::CLUSTERS | part::BAND => "1".into(),
                _ => self.unit.into(),
            },
        };
        let est = |v: &mut Vec<ColumnInfo>| {
            v.push(c(part::MEAN, self.class));
            v.push(c(part::SE, self.class));
            // The number of samples, and of the independent clusters (replicas or batches) the SE
            // was estimated from, which sets a CI's degrees of freedom: neither depends on the
            // machine, even for a timing estimate.
            v.push(c(part::N, Class::Measured));
            v.push(c(part::CLUSTERS, Class::Measured));
        };
        let mut v = Vec::new();
        match self.shape {
            Shape::Value => v.push(c("", self.class)),
            Shape::Estimate => est(&mut v),
            Shape::EstimateVsPrediction => {
                est(&mut v);
                v.push(c(part::THEORY, Class::Theory));
            }
            Shape::EstimateVsBand => {
                est(&mut v);
                v.push(c(part::THEORY, Class::Theory));
                v.push(c(part::LOWER, Class::Theory));
                v.push(c(part::UPPER, Class::Theory));
                v.push(c(part::BAND, Class::Check));
            }
        }
        v
    }
}

/// The declaration among `declared` that CSV column `name` comes from, with the class it declares
/// for that name. `{}` in a family matches any non-empty part; where several declarations match
/// (`tests_{}` and `tests_{}_theory` both match `tests_grid_theory`), the most specific wins: an exact
/// name, else the pattern with the most fixed characters.
pub fn declared_class(declared: &[Column], name: &str) -> Option<Class> {
    declaration(declared, name).map(|(_, class)| class)
}

/// The declaration among `declared` that CSV column `name` comes from, and the class it declares for
/// that name (see [`declared_class`]).
pub fn declaration<'a>(declared: &'a [Column], name: &str) -> Option<(&'a Column, Class)> {
    declared
        .iter()
        .flat_map(|c| c.expand(c.name).into_iter().map(move |info| (c, info)))
        .filter_map(|(c, info)| match info.name.split_once("{}") {
            None => (info.name == name).then_some((usize::MAX, c, info.class)),
            Some((pre, post)) => (name.len() > pre.len() + post.len()
                && name.starts_with(pre)
                && name.ends_with(post))
            .then_some((pre.len() + post.len(), c, info.class)),
        })
        .max_by_key(|(specificity, ..)| *specificity)
        .map(|(_, c, class)| (c, class))
}

/// The unit of a length written as the spec writes lengths: in the unit its table's `length_unit`
/// names. A run records it per result as what it is there ([`resolve_unit`]): `"r_s"` (the radius
/// of the sphere around the scene's bounds) with `length_unit = "root"`, else `"length"` (the
/// scene's own).
pub const SPEC_LENGTH: &str = "spec length";

/// The unit a cell declared in `unit` is in at a point whose lengths are in `lengths` (`"r_s"` or
/// `"length"`): [`SPEC_LENGTH`] becomes `lengths`, every other unit stays as declared.
pub fn resolve_unit(unit: &'static str, lengths: &'static str) -> &'static str {
    if unit == SPEC_LENGTH {
        lengths
    } else {
        unit
    }
}

/// The point index column that starts every table.
pub const POINT: Column = Column::value(
    "point",
    "1",
    Class::Parameter,
    "the sweep point's index (0-based, in expansion order)",
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_expand_with_their_classes() {
        const N_I: Column = Column::vs_band("n_i", "tests", "ray-sphere tests");
        let names: Vec<(String, Class)> = N_I
            .expand("n_i")
            .into_iter()
            .map(|c| (c.name, c.class))
            .collect();
        assert_eq!(
            names,
            [
                ("n_i_mean".to_string(), Class::Measured),
                ("n_i_se".into(), Class::Measured),
                ("n_i_n".into(), Class::Measured),
                ("n_i_clusters".into(), Class::Measured),
                ("n_i_theory".into(), Class::Theory),
                ("n_i_lower".into(), Class::Theory),
                ("n_i_upper".into(), Class::Theory),
                ("n_i_band".into(), Class::Check),
            ]
        );
        const FRAME: Column = Column::timed_estimate("frame_s", "s", "seconds per frame");
        let classes: Vec<Class> = FRAME.expand("frame_s").iter().map(|c| c.class).collect();
        assert_eq!(
            classes,
            [
                Class::Timing,
                Class::Timing,
                Class::Measured,
                Class::Measured
            ]
        );
        // N_S is measured whatever its name ends with (`n_s_mean` was once classed as timing).
        const N_S: Column = Column::vs_prediction("n_s", "steps", "cell steps");
        assert!(N_S.expand("n_s").iter().all(|c| c.class != Class::Timing));
    }

    #[test]
    fn families_name_their_members() {
        const TESTS: Column = Column::value("tests_{}", "tests", Class::Measured, "tests");
        assert!(TESTS.is_family());
        assert_eq!(TESTS.member("sphere_cache"), "tests_sphere_cache");
        assert!(!POINT.is_family());
        assert_eq!(POINT.member("x"), "point");
    }
}

#[cfg(test)]
mod declared_tests {
    use super::*;

    #[test]
    fn the_most_specific_declaration_wins() {
        const TESTS: Column = Column::value("tests_{}", "tests", Class::Measured, "");
        const THEORY: Column = Column::value("tests_{}_theory", "tests", Class::Theory, "");
        const N_S: Column = Column::vs_prediction("n_s", "steps", "");
        const SPEED: Column = Column::value("rays_per_s", "rays/s", Class::Timing, "");
        let d = [TESTS, THEORY, N_S, SPEED];
        assert_eq!(declared_class(&d, "tests_grid"), Some(Class::Measured));
        assert_eq!(declared_class(&d, "tests_grid_theory"), Some(Class::Theory));
        // N_S is measured whatever its suffix looks like; its theory is theory.
        assert_eq!(declared_class(&d, "n_s_mean"), Some(Class::Measured));
        assert_eq!(declared_class(&d, "n_s_se"), Some(Class::Measured));
        assert_eq!(declared_class(&d, "n_s_theory"), Some(Class::Theory));
        assert_eq!(declared_class(&d, "rays_per_s"), Some(Class::Timing));
        assert_eq!(declared_class(&d, "tests_"), None);
        assert_eq!(declared_class(&d, "n_i_mean"), None);
    }
}
