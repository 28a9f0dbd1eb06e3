//! Kind quasi-static end to end: a run writes its tables with every checked frame exact, the same
//! spec gives the same measured columns on 1 and 2 threads, and overlapping objects are a counted
//! warning, not an error.

use crate::common::{measured_columns, raycost, read_csv, root, write_spec};

fn spec(dir: &std::path::Path, name: &str) -> std::path::PathBuf {
    let scene = root().join("experiments/scenes/cornell-dynamic.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "quasi-static"
seed = 3

[detp]
source = "scene"
scene = "{}"
photons = 4000
point_spacing = 40.0
disc_radius = 20.0
index = "grid"

[dynamic]
frames = 12
check_every = 1
ratio = 0.08
"#,
            scene.display()
        ),
    )
}

#[test]
fn a_run_is_exact_and_thread_independent() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "qs");
    let mut tables = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("out{threads}"));
        raycost()
            .args([
                "run",
                s.to_str().unwrap(),
                "--quiet",
                "--threads",
                threads,
                "--out",
            ])
            .arg(&out)
            .assert()
            .success();
        let csv = out.join("qs/qs.csv");
        let (h, rows) = read_csv(&csv);
        let col = |n: &str| {
            &rows[0][h
                .iter()
                .position(|c| c == n)
                .unwrap_or_else(|| panic!("{n}"))]
        };
        assert_eq!(col("full_mismatch"), "0");
        assert_eq!(col("full_checked"), "11");
        let (_, frames) = read_csv(&out.join("qs/qs.frames.csv"));
        assert_eq!(frames.len(), 12, "one row per frame");
        tables.push((
            measured_columns(&csv),
            measured_columns(&out.join("qs/qs.frames.csv")),
        ));
    }
    assert_eq!(
        tables[0], tables[1],
        "measured columns differ between 1 and 2 threads"
    );
}

#[test]
fn overlapping_objects_are_a_counted_warning() {
    let dir = tempfile::tempdir().unwrap();
    let s = root().join("tests/specs/qs-overlapping.toml");
    let o = raycost()
        .args(["run", s.to_str().unwrap(), "--quiet", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("\"a\" and \"b\" may overlap"), "{err}");
    let (h, rows) = read_csv(&dir.path().join("overlapping/overlapping.csv"));
    let w = h.iter().position(|c| c == "warnings").unwrap();
    assert_eq!(rows[0][w], "1");
    let m = h.iter().position(|c| c == "full_mismatch").unwrap();
    assert_eq!(rows[0][m], "0");
}
