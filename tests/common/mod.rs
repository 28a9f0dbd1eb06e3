//! Helpers shared by the integration tests.

use std::path::{Path, PathBuf};

/// The `raycost` binary under test.
pub fn raycost() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("raycost").expect("the raycost binary is built")
}

/// Writes spec text to `DIR/NAME.toml` and returns its path.
pub fn write_spec(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).expect("write spec");
    p
}

/// `raycost run SPEC --out OUT --quiet`, ready for more arguments.
pub fn run_quiet(spec: &Path, out: &Path) -> assert_cmd::Command {
    let mut c = raycost();
    c.arg("run").arg(spec).arg("--out").arg(out).arg("--quiet");
    c
}

/// The repository root (where `experiments/` and `tests/specs/` live).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file below `dir`, relative, sorted: to assert that a failed run wrote nothing.
pub fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files_below(&p));
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Parses a CSV into (header, rows).
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let header = r
        .headers()
        .expect("a header")
        .iter()
        .map(str::to_string)
        .collect();
    let rows = r
        .records()
        .map(|rec| rec.expect("a record").iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

/// The reproducible columns of a CSV (every class but timing), as the run's own `meta.toml`
/// declares them: `DIR/STEM.csv` is table `main` of `DIR/STEM.meta.toml`, `DIR/STEM.T.csv` table `T`.
/// A header column that the metadata does not declare fails the test.
pub fn measured_columns(path: &Path) -> Vec<Vec<(String, String)>> {
    let name = path.file_name().unwrap().to_str().unwrap();
    let base = name.strip_suffix(".csv").expect("a CSV");
    let dir = path.parent().unwrap();
    let (stem, table) = if dir.join(format!("{base}.meta.toml")).exists() {
        (base.to_string(), "main".to_string())
    } else {
        let (stem, table) = base.rsplit_once('.').expect("STEM.TABLE.csv");
        (stem.to_string(), table.to_string())
    };
    let meta = raycost::output::meta::Meta::read(&dir.join(format!("{stem}.meta.toml")))
        .expect("the run's metadata");
    let declared: Vec<String> = meta
        .columns
        .get(&table)
        .map_or(Vec::new(), |c| c.iter().map(|c| c.name.clone()).collect());
    let keep = meta.reproducible_columns(&table);
    let (h, rows) = read_csv(path);
    for c in &h {
        assert!(
            declared.contains(c),
            "{}: column {c} is not declared in {stem}.meta.toml",
            path.display()
        );
    }
    rows.into_iter()
        .map(|r| {
            h.iter()
                .cloned()
                .zip(r)
                .filter(|(c, _)| keep.contains(c))
                .collect()
        })
        .collect()
}
