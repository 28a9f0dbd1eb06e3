//! Reading the result tables `raycost crossover` combines: a run's folder holds `NAME.csv`,
//! `NAME.meta.toml` and side tables `NAME.TABLE.csv` (a large points table may be kept as
//! `NAME.points.csv.gz`). Every table is checked as `raycost merge` checks a finished one
//! ([`crate::output::readback`]: header first column `point`, every row complete, no torn tail),
//! then read as text cells; a missing folder, table or column is an [`OutputError`] naming the file
//! (exit 2, nothing written).

use std::io::Read as _;
use std::path::{Path, PathBuf};

use crate::error::OutputError;
use crate::output::meta::Meta;
use crate::output::readback::{check_table, Torn};

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
        Csv::read(&self.file("csv"), self.declared("main")?.as_deref())
    }

    /// Side table `NAME.TABLE.csv`, or its gzip-compressed `NAME.TABLE.csv.gz`, its header checked
    /// against the columns the metadata records for `TABLE`.
    pub fn side(&self, table: &str) -> Result<Csv, OutputError> {
        let plain = self.file(&format!("{table}.csv"));
        let gz = self.file(&format!("{table}.csv.gz"));
        let declared = self.declared(table)?;
        if plain.is_file() || !gz.is_file() {
            Csv::read(&plain, declared.as_deref())
        } else {
            Csv::read(&gz, declared.as_deref())
        }
    }

    /// The columns the run's metadata records for `table` (`None` where it declares none).
    fn declared(&self, table: &str) -> Result<Option<Vec<String>>, OutputError> {
        Ok(self.meta()?.declared(table))
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
}

impl Csv {
    /// Reads and checks `path` (gzip-decompressed if its name ends in `.gz`); with `declared`, its
    /// header must be exactly those columns.
    pub fn read(path: &Path, declared: Option<&[String]>) -> Result<Csv, OutputError> {
        let raw =
            std::fs::read(path).map_err(|e| OutputError::new(path, format!("cannot read: {e}")))?;
        let text = if path.extension().is_some_and(|e| e == "gz") {
            let mut out = Vec::new();
            flate2::read::GzDecoder::new(raw.as_slice())
                .read_to_end(&mut out)
                .map_err(|e| OutputError::new(path, format!("is not a readable gzip file: {e}")))?;
            out
        } else {
            raw
        };
        let table = check_table(path, text, declared, Torn::Refuse)?;
        Self::parse(path, &table.text)
    }

    /// Cells of checked CSV text.
    fn parse(path: &Path, text: &[u8]) -> Result<Csv, OutputError> {
        let mut reader = ::csv::ReaderBuilder::new()
            .has_headers(true)
            .from_reader(text);
        let bad = |e: ::csv::Error| OutputError::new(path, format!("unreadable CSV: {e}"));
        let columns = reader
            .headers()
            .map_err(bad)?
            .iter()
            .map(str::to_string)
            .collect();
        let rows = reader
            .records()
            .map(|r| r.map(|r| r.iter().map(str::to_string).collect()))
            .collect::<Result<Vec<Vec<String>>, _>>()
            .map_err(bad)?;
        Ok(Csv {
            path: path.to_path_buf(),
            columns,
            rows,
        })
    }

    /// A table from CSV text in memory (the pure steps' tests).
    #[cfg(test)]
    pub fn from_text(text: &str) -> Csv {
        Self::parse(Path::new("t.csv"), text.as_bytes()).expect("valid CSV")
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
}
