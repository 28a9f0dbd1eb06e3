//! What the report shows of a `NAME.meta.toml`: one flat view over the two metadata layouts that
//! exist in result folders. Schema 2 (the current one, [`crate::output::meta::Meta`]) is read by
//! its own codec; schema 1 files (written before the schema was versioned: no `schema` key, the
//! commit under `[raycost]`, no CPU; a bench's under `[bench]`) are read key by key, and whatever
//! they do not record is left `None`, which the page shows as "not recorded". A file that is not
//! TOML, an empty file, TOML with none of either schema's tables, a schema-2 file its codec refuses,
//! or a schema this raycost does not know, is an error: the report would otherwise show wrong
//! provenance.

use std::path::Path;

use crate::error::InputError;
use crate::output::column::ColumnInfo;
use crate::output::meta::{Meta, SCHEMA};

/// Provenance of one result folder, as the page lists it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MetaView {
    /// 1 or 2.
    pub schema: u32,
    /// `experiment.name` of the spec.
    pub name: Option<String>,
    /// `experiment.kind`.
    pub kind: Option<String>,
    /// `experiment.description`.
    pub description: Option<String>,
    /// The spec file the run read.
    pub spec_path: Option<String>,
    /// SHA-256 of the normalised spec.
    pub spec_hash: Option<String>,
    /// Git commit of the binary (with ", dirty tree" when it was).
    pub commit: Option<String>,
    /// CPU model.
    pub cpu: Option<String>,
    /// Host name.
    pub host: Option<String>,
    /// Worker threads.
    pub threads: Option<i64>,
    /// Start and end, RFC 3339.
    pub started: Option<String>,
    /// End.
    pub finished: Option<String>,
    /// Wall seconds.
    pub wall_s: Option<f64>,
    /// Load averages (1, 5, 15 min) at start and end (schema 2 only).
    pub load_start: Vec<f64>,
    /// The same at the end.
    pub load_end: Vec<f64>,
    /// The swept spec keys (`spec.sweep`), in file order: the parameters that tell points apart.
    pub sweep_keys: Vec<String>,
    /// The run's counted warnings (schema 2 only).
    pub warnings: Vec<String>,
    /// The columns the metadata declares for the main table, in header order (schema 2 only;
    /// empty where it declares none): the report checks the table's header against them and
    /// takes each column's class from them.
    pub main_columns: Vec<ColumnInfo>,
}

impl MetaView {
    /// "schema 2" or "schema 1 (older run)".
    pub fn schema_label(&self) -> String {
        if self.schema < SCHEMA {
            format!("schema {} (older run)", self.schema)
        } else {
            format!("schema {}", self.schema)
        }
    }

    /// Reads `path`; an unreadable or unknown file is an [`InputError`] naming it.
    pub fn read(path: &Path) -> Result<MetaView, InputError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| InputError::new(&file, format!("cannot read the metadata: {e}")))?;
        Self::parse(&text).map_err(|m| InputError::new(&file, m))
    }

    /// Parses metadata text of either schema.
    pub fn parse(text: &str) -> Result<MetaView, String> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| format!("not TOML: {}", e.message().trim()))?;
        match table.get("schema") {
            // A schema-1 file has at least one of its tables; an empty file (a run killed or a disk
            // full while writing it, by a raycost older than the result-folder protocol) or
            // unrelated TOML is not an older run.
            None if !["raycost", "run", "bench", "spec"]
                .iter()
                .any(|t| table.get(*t).is_some_and(toml::Value::is_table)) =>
            {
                Err(if text.trim().is_empty() {
                    "is empty: not the metadata of a finished run (a write cut short?); rerun or                      --resume the experiment, or move the folder out of the results"
                        .to_string()
                } else {
                    "has none of raycost's metadata tables ([raycost], [run], [bench], [spec]):                      not the metadata of a run"
                        .to_string()
                })
            }
            None => Ok(schema1(&table)),
            Some(toml::Value::Integer(1)) => Ok(schema1(&table)),
            Some(toml::Value::Integer(v)) if *v == i64::from(SCHEMA) => {
                let meta = Meta::parse(text).map_err(|e| e.0)?;
                Ok(schema2(&meta))
            }
            Some(v) => Err(format!(
                "metadata schema {v}; this raycost reads schemas 1 and {SCHEMA} (written by a newer raycost?)"
            )),
        }
    }
}

/// The current schema, typed.
fn schema2(m: &Meta) -> MetaView {
    let nonempty = |s: &str| (!s.is_empty()).then(|| s.to_string());
    let dirty = if m.raycost.git_dirty == "true" {
        ", dirty tree"
    } else {
        ""
    };
    MetaView {
        schema: SCHEMA,
        name: spec_str(&m.spec, "name"),
        kind: spec_str(&m.spec, "kind"),
        description: spec_str(&m.spec, "description"),
        spec_path: nonempty(&m.run.spec_path),
        spec_hash: nonempty(&m.run.spec_hash),
        commit: nonempty(&m.raycost.git_commit).map(|c| format!("{c}{dirty}")),
        cpu: nonempty(&m.machine.cpu),
        host: nonempty(&m.machine.host),
        threads: Some(m.run.threads as i64),
        started: nonempty(&m.run.started),
        finished: m.run.finished.clone(),
        wall_s: m.run.wall_s,
        load_start: m.run.load_start.clone(),
        load_end: m.run.load_end.clone(),
        sweep_keys: sweep_keys(&m.spec),
        warnings: m.warnings.clone(),
        main_columns: m.columns.get("main").cloned().unwrap_or_default(),
    }
}

/// The layout before schemas: `[raycost]`, `[run]` (with `host`), `[spec]`; or a bench's `[bench]`.
fn schema1(t: &toml::Table) -> MetaView {
    let get = |path: &[&str]| -> Option<&toml::Value> {
        let (last, tables) = path.split_last()?;
        let mut cur = t;
        for k in tables {
            cur = cur.get(*k)?.as_table()?;
        }
        cur.get(*last)
    };
    let s = |path: &[&str]| get(path).and_then(|v| v.as_str()).map(str::to_string);
    let spec = get(&["spec"])
        .and_then(|v| v.as_table())
        .cloned()
        .unwrap_or_default();
    MetaView {
        schema: 1,
        name: spec_str(&spec, "name"),
        kind: spec_str(&spec, "kind"),
        description: spec_str(&spec, "description"),
        spec_path: s(&["run", "spec_path"]),
        spec_hash: s(&["run", "spec_hash"]),
        commit: s(&["raycost", "git_commit"]).or_else(|| s(&["bench", "commit"])),
        cpu: s(&["machine", "cpu"]).or_else(|| s(&["bench", "cpu"])),
        host: s(&["run", "host"]).or_else(|| s(&["bench", "host"])),
        threads: get(&["run", "threads"])
            .or_else(|| get(&["bench", "threads"]))
            .and_then(|v| v.as_integer()),
        started: s(&["run", "started"]),
        finished: s(&["run", "finished"]).or_else(|| s(&["bench", "finished"])),
        wall_s: get(&["run", "wall_s"]).and_then(|v| v.as_float()),
        load_start: Vec::new(),
        load_end: Vec::new(),
        sweep_keys: sweep_keys(&spec),
        warnings: Vec::new(),
        main_columns: Vec::new(),
    }
}

/// `spec.base.experiment.KEY` as text.
fn spec_str(spec: &toml::Table, key: &str) -> Option<String> {
    spec.get("base")?
        .get("experiment")?
        .get(key)?
        .as_str()
        .map(str::to_string)
}

/// The keys of `spec.sweep`.
fn sweep_keys(spec: &toml::Table) -> Vec<String> {
    spec.get("sweep")
        .and_then(|v| v.as_table())
        .map(|t| t.keys().cloned().collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    const OLD: &str = r#"timing_columns = ["trace_s"]

[raycost]
version = "0.1.0"
git_commit = "6008c82b"

[run]
spec_path = "experiments/x.toml"
spec_hash = "266e"
threads = 2
host = "vm"

[spec.base.experiment]
name = "x"
kind = "grid"
description = "a <b> test"

[spec.sweep]
"grid.cell_width" = [0.1, 0.2]
"#;

    #[test]
    fn a_schema_1_file_is_read_key_by_key() {
        let v = MetaView::parse(OLD).expect("schema 1");
        assert_eq!(v.schema_label(), "schema 1 (older run)");
        assert_eq!(v.kind.as_deref(), Some("grid"));
        assert_eq!(v.description.as_deref(), Some("a <b> test"));
        assert_eq!(v.commit.as_deref(), Some("6008c82b"));
        assert_eq!(v.spec_hash.as_deref(), Some("266e"));
        assert_eq!(v.cpu, None);
        assert_eq!(v.sweep_keys, ["grid.cell_width"]);
        let bench = "[bench]\ncpu = \"AMD EPYC\"\ncommit = \"abc\"\nthreads = 2\n";
        let b = MetaView::parse(bench).expect("schema 1 bench");
        assert_eq!(
            (b.cpu.as_deref(), b.commit.as_deref(), b.threads),
            (Some("AMD EPYC"), Some("abc"), Some(2))
        );
    }

    #[test]
    fn a_schema_2_file_is_read_by_its_codec() {
        let mut m = Meta::begin("run", Default::default());
        m.run.spec_hash = "ff".into();
        m.raycost.git_dirty = "true".into();
        let mut exp = toml::Table::new();
        exp.insert("kind".into(), "detp".into());
        let mut base = toml::Table::new();
        base.insert("experiment".into(), exp.into());
        m.spec.insert("base".into(), base.into());
        let v = MetaView::parse(&m.render()).expect("schema 2");
        assert_eq!(v.schema_label(), "schema 2");
        assert_eq!(v.kind.as_deref(), Some("detp"));
        assert_eq!(v.spec_hash.as_deref(), Some("ff"));
        assert!(v.commit.expect("commit").ends_with(", dirty tree"));
        assert_eq!(v.cpu, Some(m.machine.cpu));
        assert_eq!(v.load_start, m.run.load_start);
    }

    #[test]
    fn unreadable_and_unknown_files_are_refused() {
        assert!(MetaView::parse("x = [")
            .expect_err("bad")
            .contains("not TOML"));
        assert!(MetaView::parse("schema = 3")
            .expect_err("newer")
            .contains("schema 3"));
        // A schema-2 file missing required tables is refused by the codec, not half-shown.
        assert!(MetaView::parse("schema = 2").is_err());
        // An empty file (a write cut short) is not an older schema, nor is other TOML.
        for empty in ["", "\n  \n"] {
            let e = MetaView::parse(empty).expect_err("empty");
            assert!(e.contains("is empty"), "{e}");
        }
        assert!(MetaView::parse("title = \"x\"\n")
            .expect_err("not metadata")
            .contains("none of raycost's metadata tables"));
    }
}
