//! Silent wrong answers raycost once gave, each with its exact reproduction: a run is pinned to
//! the content of every file it reads, `--set` on a sweep axis replaces the axis, N_S is a measured
//! column, and every kind's built-in check keeps its row and fails the run.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{files_below, raycost, read_csv, root, run_quiet, write_spec};

/// Lines through the unit ball gathered on discs whose centres a CSV gives; six points (a sweep of
/// the disc radius), so a run can be cut after two.
const POINTS_SPEC: &str = r#"
[experiment]
name = "pts"
kind = "detp"
seed = 3

[detp]
photons = 2000
point_source = "file"
points_file = "pts.csv"
disc_radius = 0.1
engines = ["sphere-cache", "brute-force"]

[sweep]
"detp.disc_radius" = [0.05, 0.1, 0.15, 0.2, 0.25, 0.3]
"#;

fn write_points(dir: &Path, shift: f64) -> PathBuf {
    let mut s = String::from("x,y,z,nx,ny,nz\n");
    for i in 0..20 {
        let t = i as f64 / 20.0 - 0.5 + shift;
        s.push_str(&format!("{t},{},{},0,0,1\n", 0.3 * t, -0.2 * t));
    }
    let p = dir.join("pts.csv");
    fs::write(&p, s).expect("write points");
    p
}

fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    files_below(dir)
        .into_iter()
        .map(|p| (p.clone(), fs::read(&p).expect("read")))
        .collect()
}

/// Turns a finished run `DIR/STEM.*` into the partial run a kill after point `keep - 1` leaves.
fn cut_to_partial(dir: &Path, stem: &str, keep: usize) {
    for f in files_below(dir) {
        let name = f.file_name().unwrap().to_str().unwrap().to_string();
        if !name.starts_with(stem) {
            continue;
        }
        let text = fs::read_to_string(&f).expect("read");
        let kept = if name.ends_with(".csv") {
            text.lines()
                .enumerate()
                .filter(|(i, l)| {
                    *i == 0
                        || l.split(',')
                            .next()
                            .and_then(|p| p.parse::<usize>().ok())
                            .is_some_and(|p| p < keep)
                })
                .map(|(_, l)| format!("{l}\n"))
                .collect()
        } else {
            text
        };
        fs::write(format!("{}.partial", f.display()), kept).expect("write");
        fs::remove_file(&f).expect("remove");
    }
}

#[test]
fn resume_after_editing_the_points_csv_is_refused_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = write_spec(tmp.path(), "pts", POINTS_SPEC);
    write_points(tmp.path(), 0.0);
    let out = tmp.path().join("out");
    run_quiet(&spec, &out).assert().success();
    cut_to_partial(&out.join("pts"), "pts", 2);
    // The reported reproduction: the points file changes between the cut and the resume.
    write_points(tmp.path(), 0.01);
    let before = snapshot(&out);
    let o = run_quiet(&spec, &out).arg("--resume").output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("pts.csv") && err.contains("other input files"),
        "the message names the changed file: {err}"
    );
    assert_eq!(before, snapshot(&out), "a refused resume changed files");
    // With the original points back, the resume goes through and equals an uncut run.
    write_points(tmp.path(), 0.0);
    run_quiet(&spec, &out).arg("--resume").assert().success();
    let whole = tmp.path().join("whole");
    run_quiet(&spec, &whole).assert().success();
    crate::merge::assert_same_measured(&out.join("pts/pts.csv"), &whole.join("pts/pts.csv"));
}

#[test]
fn a_finished_run_is_not_called_finished_when_its_points_csv_changed() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = write_spec(tmp.path(), "pts", POINTS_SPEC);
    write_points(tmp.path(), 0.0);
    let out = tmp.path().join("out");
    run_quiet(&spec, &out).assert().success();
    // Unchanged inputs: "finished already", nothing touched.
    let before = snapshot(&out);
    let o = raycost()
        .args(["run", spec.to_str().unwrap(), "--resume", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("finished already"));
    assert_eq!(before, snapshot(&out));
    // Changed points: refused, naming the file; the old table stays as it was.
    write_points(tmp.path(), 0.02);
    let o = run_quiet(&spec, &out).arg("--resume").output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("pts.csv"), "{err}");
    assert_eq!(before, snapshot(&out));
}

#[test]
fn merge_refuses_shards_computed_from_different_points_files() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = write_spec(tmp.path(), "pts", POINTS_SPEC);
    let out = tmp.path().join("out");
    write_points(tmp.path(), 0.0);
    run_quiet(&spec, &out)
        .args(["--shard", "0/2"])
        .assert()
        .success();
    write_points(tmp.path(), 0.05);
    run_quiet(&spec, &out)
        .args(["--shard", "1/2"])
        .assert()
        .success();
    let dir = out.join("pts");
    let before = snapshot(&dir);
    let o = raycost()
        .args(["merge", "--quiet"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("pts.csv"), "the message names the file: {err}");
    assert_eq!(before, snapshot(&dir), "a refused merge wrote something");
}

#[test]
fn set_on_a_sweep_axis_replaces_the_axis() {
    // The reported reproduction, verbatim.
    let spec = root().join("experiments/quickstart.toml");
    let o = raycost()
        .arg("check")
        .arg(&spec)
        .args(["--set", r#"sweep."grid.cell_width"=[0.3, 0.6]"#])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("2 point(s)"), "{text}");
    assert!(
        text.contains("grid.cell_width = 0.3") && text.contains("grid.cell_width = 0.6"),
        "{text}"
    );
    assert!(
        !text.contains("= 0.2,") && !text.contains("= 2.0"),
        "{text}"
    );

    // A run: the axis is a parameter column with the new values; no column named after the flag,
    // and the metadata's sweep is the new axis, not a nested table.
    let tmp = tempfile::tempdir().unwrap();
    let small = write_spec(
        tmp.path(),
        "small",
        &fs::read_to_string(&spec)
            .unwrap()
            .replace("name = \"quickstart\"", "name = \"small\""),
    );
    let out = tmp.path().join("out");
    run_quiet(&small, &out)
        .args(["--set", r#"sweep."grid.cell_width"=[0.3, 0.6]"#])
        .args(["--set", "experiment.rays=2000"])
        .assert()
        .success();
    let (h, rows) = read_csv(&out.join("small/small.csv"));
    assert!(!h.iter().any(|c| c.starts_with("sweep")), "{h:?}");
    let w = h
        .iter()
        .position(|c| c == "grid.cell_width")
        .expect("the axis");
    let values: Vec<&str> = rows.iter().map(|r| r[w].as_str()).collect();
    assert_eq!(values, ["0.3", "0.6"]);
    // A set integer is written as an integer, not 2000.0.
    let r = h
        .iter()
        .position(|c| c == "experiment.rays")
        .expect("the set key");
    assert!(rows.iter().all(|row| row[r] == "2000"), "{rows:?}");
    let meta = raycost::output::meta::Meta::read(&out.join("small/small.meta.toml")).unwrap();
    let sweep = meta.spec["sweep"].as_table().expect("[spec.sweep]");
    assert_eq!(sweep.len(), 1, "{sweep:?}");
    assert_eq!(
        sweep["grid.cell_width"],
        toml::Value::Array(vec![0.3.into(), 0.6.into()])
    );
    assert!(meta.spec["base"].get("sweep").is_none(), "{:?}", meta.spec);

    // A key that is no axis: created as a new axis.
    let o = raycost()
        .arg("check")
        .arg(&spec)
        .args(["--set", r#"sweep."scene.radius"=[0.05, 0.1]"#])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("8 point(s)"), "{text}");
    // Not an array: refused, naming the flag.
    let o = raycost()
        .arg("check")
        .arg(&spec)
        .args(["--set", r#"sweep."grid.cell_width"=0.3"#])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--set") && err.contains("sweep."), "{err}");
}

#[test]
fn the_small_kind_runs_and_meets_its_law() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = root().join("tests/specs/lines-in-sphere.toml");
    let out = tmp.path().join("out");
    run_quiet(&spec, &out).assert().success();
    let (h, rows) = read_csv(&out.join("lines-in-sphere/lines-in-sphere.csv"));
    let col = |n: &str| {
        h.iter()
            .position(|c| c == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    assert_eq!(rows.len(), 3);
    for r in &rows {
        let (m, se, th): (f64, f64, f64) = (
            r[col("hit_fraction_mean")].parse().unwrap(),
            r[col("hit_fraction_se")].parse().unwrap(),
            r[col("hit_fraction_theory")].parse().unwrap(),
        );
        assert!(se > 0.0 && (m - th).abs() < 4.0 * se, "{m} ± {se} vs {th}");
    }
}
