//! Reading the result tables `raycost crossover` combines: a run's folder holds `NAME.csv`,
//! `NAME.meta.toml` and side tables `NAME.TABLE.csv` (a large points table may be kept as
//! `NAME.points.csv.gz`). Every table is checked as `raycost merge` checks a finished one
//! ([`crate::output::readback`]: header first column `point`, every row complete, no torn tail),
//! then read as text cells; a missing folder, table or column is an [`OutputError`] naming the file
//! (exit 2, nothing written).
//!
//! Columns are read through their declarations, never by a name typed at the reading site: a
//! measured or timed column by the [`Column`] its writer puts it with ([`Csv::value`]: a value
//! or an estimate's `_mean`; [`Csv::member`]), a parameter by its spec key ([`Key`], from [`keys`]). Where the
//! result's metadata declares the column (every result since columns were recorded), its unit and
//! class must be the declaration's: a column renamed, or given another meaning since the result was
//! written, is refused by name rather than read as something it is not.

use std::path::{Path, PathBuf};

use crate::error::OutputError;
use crate::output::column::{part, Class, Column, ColumnInfo, Shape};
use crate::output::meta::Meta;
use crate::output::readback::{check_table, finished_table_bytes, text_cells, Torn};

/// A spec key whose value every row records in its parameter column (`detp.photons`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key(pub &'static str);

/// The spec keys the crossover reads back (each a key of kind detp or quasi-static: tested).
pub mod keys {
    use super::Key;
    /// The run's seed (the bootstrap's too).
    pub const SEED: Key = Key("experiment.seed");
    /// Replicas per sweep point.
    pub const REPLICAS: Key = Key("detp.replicas");
    /// Photons per replica.
    pub const PHOTONS: Key = Key("detp.photons");
    /// The disc radius d.
    pub const DISC_RADIUS: Key = Key("detp.disc_radius");
    /// The direct part's estimator.
    pub const DIRECT: Key = Key("detp.direct");
    /// The edge remedy.
    pub const EDGE: Key = Key("detp.edge");
    /// The scene.
    pub const SCENE: Key = Key("detp.scene");
    /// Path tracing's paths per point.
    pub const PATH_SAMPLES: Key = Key("detp.path_samples");
    /// The clamp-radius rule's κ.
    pub const EDGE_RADIUS_FACTOR: Key = Key("detp.edge_radius_factor");
    /// A radius schedule's reference photon count.
    pub const RADIUS_SCHEDULE_PHOTONS: Key = Key("detp.radius_schedule_photons");
    /// A radius schedule's exponent.
    pub const RADIUS_SCHEDULE_EXPONENT: Key = Key("detp.radius_schedule_exponent");
    /// Every key above.
    pub const ALL: [Key; 11] = [
        SEED,
        REPLICAS,
        PHOTONS,
        DISC_RADIUS,
        DIRECT,
        EDGE,
        SCENE,
        PATH_SAMPLES,
        EDGE_RADIUS_FACTOR,
        RADIUS_SCHEDULE_PHOTONS,
        RADIUS_SCHEDULE_EXPONENT,
    ];
}

/// A result folder: its path and `NAME`.
#[derive(Clone, Debug)]
pub struct Results {
    /// The folder.
    pub dir: PathBuf,
    /// The run's name (`NAME.csv`).
    pub name: String,
}

impl Results {
    /// The run in `dir`: the one `NAME` with both `NAME.csv` and `NAME.meta.toml` there.
    pub fn find(dir: &Path) -> Result<Results, OutputError> {
        let entries = std::fs::read_dir(dir)
            .map_err(|e| OutputError::new(dir, format!("cannot read the results folder: {e}")))?;
        let mut names: Vec<String> = entries
            .flatten()
            .filter_map(|e| {
                let n = e.file_name().to_string_lossy().into_owned();
                let stem = n.strip_suffix(".meta.toml")?.to_string();
                dir.join(format!("{stem}.csv")).is_file().then_some(stem)
            })
            .collect();
        names.sort();
        match names.as_slice() {
            [one] => Ok(Results {
                dir: dir.to_path_buf(),
                name: one.clone(),
            }),
            [] => Err(OutputError::new(
                dir,
                "holds no finished run (no NAME.csv beside a NAME.meta.toml): give the folder `raycost run` wrote",
            )),
            many => Err(OutputError::new(
                dir,
                format!(
                    "holds several runs ({}): give a folder with one",
                    many.join(", ")
                ),
            )),
        }
    }

    /// `NAME.SUFFIX` in the folder.
    pub fn file(&self, suffix: &str) -> PathBuf {
        self.dir.join(format!("{}.{suffix}", self.name))
    }

    /// The main table, its header checked against the columns the metadata records.
    pub fn main(&self) -> Result<Csv, OutputError> {
        Csv::read(&self.file("csv"), self.declared("main")?)
    }

    /// Side table `NAME.TABLE.csv`, or its gzip-compressed `NAME.TABLE.csv.gz`, its header checked
    /// against the columns the metadata records for `TABLE`.
    pub fn side(&self, table: &str) -> Result<Csv, OutputError> {
        let plain = self.file(&format!("{table}.csv"));
        let gz = self.file(&format!("{table}.csv.gz"));
        let declared = self.declared(table)?;
        if plain.is_file() || !gz.is_file() {
            Csv::read(&plain, declared)
        } else {
            Csv::read(&gz, declared)
        }
    }

    /// The columns the run's metadata records for `table` (`None` where it declares none).
    fn declared(&self, table: &str) -> Result<Option<Vec<ColumnInfo>>, OutputError> {
        Ok(self.meta()?.columns.get(table).cloned())
    }

    /// Whether side table `NAME.TABLE.csv` (or `.csv.gz`) is there.
    pub fn has_side(&self, table: &str) -> bool {
        ["csv", "csv.gz"]
            .iter()
            .any(|ext| self.file(&format!("{table}.{ext}")).is_file())
    }

    /// The run's metadata.
    pub fn meta(&self) -> Result<Meta, OutputError> {
        Meta::read(&self.file("meta.toml"))
    }
}

/// A checked table as text cells.
#[derive(Clone, Debug)]
pub struct Csv {
    /// The file read.
    pub path: PathBuf,
    /// Column names.
    pub columns: Vec<String>,
    /// Rows of cells, in file order.
    pub rows: Vec<Vec<String>>,
    /// What the run's metadata declares for each column (empty: it declares none).
    pub declared: Vec<ColumnInfo>,
}

impl Csv {
    /// Reads and checks `path` (gzip-decompressed if its name ends in `.gz`); with `declared`, its
    /// header must be exactly those columns, and typed reads check their unit and class.
    pub fn read(path: &Path, declared: Option<Vec<ColumnInfo>>) -> Result<Csv, OutputError> {
        let text = finished_table_bytes(path)?;
        let names: Option<Vec<String>> = declared
            .as_ref()
            .map(|d| d.iter().map(|c| c.name.clone()).collect());
        let table = check_table(path, text, names.as_deref(), Torn::Refuse)?;
        let mut csv = Self::parse(path, &table.text)?;
        csv.declared = declared.unwrap_or_default();
        Ok(csv)
    }

    /// Cells of checked CSV text.
    fn parse(path: &Path, text: &[u8]) -> Result<Csv, OutputError> {
        let (columns, rows) = text_cells(path, text)?;
        Ok(Csv {
            path: path.to_path_buf(),
            columns,
            rows,
            declared: Vec::new(),
        })
    }

    /// A table from CSV text in memory (the pure steps' tests).
    #[cfg(test)]
    pub fn from_text(text: &str) -> Csv {
        Self::parse(Path::new("t.csv"), text.as_bytes()).expect("valid CSV")
    }

    /// Declared column `c` (not a family) as numbers: its value, or an estimate's `_mean`.
    pub fn value(&self, c: &Column) -> Result<Vec<f64>, OutputError> {
        self.numbers(&self.typed(c, None)?, c.doc)
    }

    /// Declared column `c` as text (a label such as `estimator`).
    pub fn text(&self, c: &Column) -> Result<Vec<String>, OutputError> {
        self.texts(&self.typed(c, None)?, c.doc)
    }

    /// Member `part` of declared family `c` (`cost_{}_s` with `disc_index`) as numbers.
    pub fn member(&self, c: &Column, part: &str) -> Result<Vec<f64>, OutputError> {
        self.numbers(&self.typed(c, Some(part))?, c.doc)
    }

    /// Whether the table has member `part` of declared family `c` (or column `c` itself).
    pub fn has_member(&self, c: &Column, part: &str) -> bool {
        self.has(&c.member(part))
    }

    /// Whether the table has declared column `c` (its first CSV column: `NAME` or `NAME_mean`).
    pub fn has_column(&self, c: &Column) -> bool {
        c.expand(c.name).first().is_some_and(|i| self.has(&i.name))
    }

    /// The parameter column of spec key `k`.
    pub fn param(&self, k: Key) -> Result<Vec<f64>, OutputError> {
        self.check_parameter(k)?;
        self.numbers(k.0, "a spec key's value in each row")
    }

    /// The parameter column of spec key `k`, as text.
    pub fn param_texts(&self, k: Key) -> Result<Vec<String>, OutputError> {
        self.check_parameter(k)?;
        self.texts(k.0, "a spec key's value in each row")
    }

    /// Whether the table records spec key `k`.
    pub fn has_param(&self, k: Key) -> bool {
        self.has(k.0)
    }

    fn check_parameter(&self, k: Key) -> Result<(), OutputError> {
        match self.declared.iter().find(|i| i.name == k.0) {
            Some(i) if i.class != Class::Parameter => Err(OutputError::new(
                &self.path,
                format!(
                    "declares '{}' as {}, not as the spec key's parameter column",
                    k.0,
                    i.class.as_str()
                ),
            )),
            _ => Ok(()),
        }
    }

    /// The CSV name declaration `c` is read under (its value, or an estimate's `_mean`; `part` fills
    /// a family's `{}`), after checking that the metadata, where it declares that name, gives it
    /// the declaration's unit and class.
    fn typed(&self, c: &Column, part: Option<&str>) -> Result<String, OutputError> {
        let stem = match part {
            Some(p) => c.member(p),
            None => {
                debug_assert!(!c.is_family(), "{}: a family is read by member", c.name);
                c.name.to_string()
            }
        };
        let want = c
            .expand(&stem)
            .into_iter()
            .next()
            .expect("a declaration expands to at least one column");
        debug_assert!(
            c.shape == Shape::Value || part::stem(&want.name, part::MEAN).is_some(),
            "{}",
            want.name
        );
        if let Some(got) = self.declared.iter().find(|i| i.name == want.name) {
            if got.unit != want.unit || got.class != want.class {
                return Err(OutputError::new(
                    &self.path,
                    format!(
                        "declares '{}' in {} ({}), which this raycost reads in {} ({}): a column that changed meaning since the result was written (see CHANGELOG)",
                        want.name,
                        if got.unit.is_empty() { "no unit" } else { &got.unit },
                        got.class.as_str(),
                        if want.unit.is_empty() { "no unit" } else { &want.unit },
                        want.class.as_str()
                    ),
                ));
            }
        }
        Ok(want.name)
    }

    /// Index of column `name`, or an error naming the table and what needs it.
    pub fn column(&self, name: &str, why: &str) -> Result<usize, OutputError> {
        self.columns.iter().position(|c| c == name).ok_or_else(|| {
            OutputError::new(
                &self.path,
                format!("has no column '{name}' ({why}): was it written by an older raycost, or by another kind or engine set?"),
            )
        })
    }

    /// Whether column `name` exists.
    pub fn has(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    /// Column `name` as numbers (`NaN` and unreadable cells: NaN).
    pub fn numbers(&self, name: &str, why: &str) -> Result<Vec<f64>, OutputError> {
        let i = self.column(name, why)?;
        Ok(self
            .rows
            .iter()
            .map(|r| r[i].parse::<f64>().unwrap_or(f64::NAN))
            .collect())
    }

    /// Column `name` as text.
    pub fn texts(&self, name: &str, why: &str) -> Result<Vec<String>, OutputError> {
        let i = self.column(name, why)?;
        Ok(self.rows.iter().map(|r| r[i].clone()).collect())
    }

    /// The members of family `prefix{}` (`irradiance_replica_0`, `_1`, …) whose part is an integer,
    /// in increasing order: (part, column name).
    pub fn family(&self, prefix: &str) -> Vec<(u64, String)> {
        let mut out: Vec<(u64, String)> = self
            .columns
            .iter()
            .filter_map(|c| Some((c.strip_prefix(prefix)?.parse::<u64>().ok()?, c.clone())))
            .collect();
        out.sort();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_and_gzip_tables_read_alike_and_missing_columns_are_named() {
        use std::io::Write as _;
        let d = tempfile::tempdir().expect("tempdir");
        let text = "point,a,b_1,b_0\n0,1.5,x,NaN\n1,2.5,y,3\n";
        std::fs::write(d.path().join("r.csv"), text).expect("write");
        let mut meta = Meta::begin("test", Default::default());
        let declared = |names: &[&str]| -> Vec<crate::output::column::ColumnInfo> {
            names
                .iter()
                .map(|&name| crate::output::column::ColumnInfo {
                    name: name.into(),
                    class: crate::output::column::Class::Measured,
                    unit: String::new(),
                })
                .collect()
        };
        meta.columns
            .insert("main".into(), declared(&["point", "a", "b_1", "b_0"]));
        std::fs::write(d.path().join("r.meta.toml"), meta.render()).expect("write");
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        gz.write_all(text.as_bytes()).expect("gzip");
        std::fs::write(d.path().join("r.points.csv.gz"), gz.finish().expect("gzip"))
            .expect("write");
        let r = Results::find(d.path()).expect("one run");
        assert_eq!(r.name, "r");
        let (main, side) = (r.main().expect("main"), r.side("points").expect("gz"));
        assert_eq!(main.rows, side.rows);
        assert_eq!(main.numbers("a", "test").expect("a"), [1.5, 2.5]);
        assert!(main.numbers("b_0", "test").expect("b")[0].is_nan());
        assert_eq!(
            main.family("b_"),
            [(0, "b_0".to_string()), (1, "b_1".to_string())]
        );
        let e = main.numbers("zzz", "the fit").expect_err("missing");
        assert!(
            e.message.contains("'zzz'") && e.message.contains("the fit"),
            "{e}"
        );
        assert!(Results::find(&d.path().join("nope")).is_err());
        // A header that is not what the metadata declares is refused, naming the file; a table it
        // declares nothing for is read on the readback checks alone.
        meta.columns
            .insert("main".into(), declared(&["point", "a", "b_0", "b_1"]));
        std::fs::write(d.path().join("r.meta.toml"), meta.render()).expect("write");
        let e = r.main().expect_err("header differs from the declaration");
        assert!(e.to_string().contains("r.csv"), "{e}");
        assert!(r.side("points").is_ok());
    }

    /// Every key the crossover reads is a key of kind detp or quasi-static (the kinds whose results
    /// it combines), so a renamed spec key cannot leave a reader looking for a column no run writes.
    #[test]
    fn every_key_read_is_a_spec_key_of_the_kinds_read() {
        use crate::experiment::registry;
        let declared: Vec<String> = ["detp", "quasi-static"]
            .iter()
            .flat_map(|k| registry::find(k).expect("kind").keys())
            .map(|d| d.key)
            .collect();
        for k in keys::ALL {
            assert!(declared.iter().any(|d| d == k.0), "{} is no spec key", k.0);
        }
    }

    /// A typed read refuses a column the metadata declares with another unit or class, naming it
    /// (a column renamed or given another meaning since the result was written), and reads one it
    /// declares alike.
    #[test]
    fn a_typed_read_checks_the_declared_unit_and_class() {
        use crate::experiment::detp::columns::TRACE_S;
        let mut t = Csv::from_text("point,trace_s,detp.photons\n0,1.5,100\n");
        let info = |name: &str, unit: &str, class: Class| ColumnInfo {
            name: name.into(),
            unit: unit.into(),
            class,
        };
        t.declared = vec![
            info("point", "1", Class::Parameter),
            info("trace_s", "s", Class::Timing),
            info("detp.photons", "photons", Class::Parameter),
        ];
        assert_eq!(t.value(&TRACE_S).expect("declared alike"), [1.5]);
        assert_eq!(t.param(keys::PHOTONS).expect("a parameter"), [100.0]);
        t.declared[1] = info("trace_s", "ms", Class::Timing);
        let e = t.value(&TRACE_S).expect_err("another unit");
        assert!(
            e.message.contains("'trace_s'") && e.message.contains("ms"),
            "{e}"
        );
        t.declared[1] = info("trace_s", "s", Class::Measured);
        assert!(t.value(&TRACE_S).is_err(), "another class");
        t.declared[2] = info("detp.photons", "photons", Class::Measured);
        assert!(
            t.param(keys::PHOTONS).is_err(),
            "a key's column not a parameter"
        );
        // Undeclared (results written before columns were recorded): read by name.
        t.declared.clear();
        assert_eq!(t.value(&TRACE_S).expect("undeclared"), [1.5]);
    }
}
