//! `raycost reproduce DIR`: a fresh run reproduces (exit 0); a tampered counted cell is named with
//! its table, column and row (exit 1), and `scripts/compare_tables.py` finds the same cell; a
//! timing-only difference passes; a changed spec, a changed input or a gone spec is refused naming
//! what changed (exit 2); a `--run R` run, a merged shard set and a crossover result reproduce.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{raycost, read_csv, root, run_quiet, write_spec};

/// A small grid sweep (two cell widths, 3000 rays): a main table with timings and a hist table.
fn grid_spec(dir: &Path, rays: u64) -> PathBuf {
    write_spec(
        dir,
        "tiny-grid",
        &format!(
            "[experiment]\nname = \"tiny-grid\"\nkind = \"grid\"\nseed = 5\nrays = {rays}\n\n\
             [scene]\nintensity = 1.0\nradius = 0.1\nextent = \"infinite\"\n\n\
             [grid]\ncell_width = 0.5\n\n[sweep]\n\"grid.cell_width\" = [0.5, 1.0]\n"
        ),
    )
}

fn reproduce(dir: &Path, args: &[&str]) -> assert_cmd::Command {
    let mut c = raycost();
    c.arg("reproduce").arg(dir).args(args);
    c
}

fn output(c: &mut assert_cmd::Command) -> (i32, String, String) {
    let o = c.output().expect("raycost runs");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Rewrites cell (`row`, `column`) of a CSV with `f` of its text.
fn tamper(path: &Path, row: usize, column: &str, f: impl Fn(&str) -> String) {
    let (header, mut rows) = read_csv(path);
    let col = header.iter().position(|h| h == column).expect("the column");
    rows[row][col] = f(&rows[row][col]);
    let mut w = csv::Writer::from_path(path).expect("write");
    w.write_record(&header).expect("header");
    for r in rows {
        w.write_record(&r).expect("row");
    }
    w.flush().expect("flush");
}

#[test]
fn a_fresh_run_reproduces_and_a_tampered_cell_is_named() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // The spec in a folder of its own: the scratch folders beside it are not inside it.
    let spec_dir = tmp.path().join("spec");
    fs::create_dir(&spec_dir).expect("spec folder");
    let spec = grid_spec(&spec_dir, 3000);
    let results = tmp.path().join("results");
    run_quiet(&spec, &results).assert().success();
    let dir = results.join("tiny-grid");

    let scratch = tmp.path().join("scratch");
    let (code, out, err) = output(
        reproduce(&dir, &["--out", scratch.to_str().unwrap()])
            .arg("--threads")
            .arg("1"),
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("tiny-grid.csv (main):"), "{out}");
    assert!(out.contains("tiny-grid.hist.csv (hist):"), "{out}");
    assert!(out.contains("\nreproduced: 2 table(s)"), "{out}");
    assert!(scratch.join("tiny-grid/tiny-grid.csv").is_file());
    // The same scratch again is refused (nothing overwritten) unless --force.
    let (code, _, err) = output(&mut reproduce(&dir, &["--out", scratch.to_str().unwrap()]));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--force"), "{err}");
    reproduce(&dir, &["--out", scratch.to_str().unwrap(), "--force"])
        .assert()
        .success();
    // Never into the result folder or the spec's.
    for inside in [dir.join("x"), spec_dir.join("y")] {
        let (code, _, err) = output(&mut reproduce(&dir, &["--out", inside.to_str().unwrap()]));
        assert_eq!(code, 2, "{}: {err}", inside.display());
        assert!(err.contains("must not write there"), "{err}");
    }

    // Python's comparison agrees on the untouched pair.
    let compare = |new: &Path| {
        std::process::Command::new("python3")
            .arg(root().join("scripts/compare_tables.py"))
            .arg(&results)
            .arg(new)
            .output()
            .expect("python3 runs")
    };
    let py = compare(&scratch);
    assert_eq!(
        py.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&py.stdout)
    );

    // A timing cell (no interval) may differ: reported, not counted.
    let main = dir.join("tiny-grid.csv");
    let original = fs::read(&main).expect("read");
    tamper(&main, 1, "time_per_ray_s", |s| {
        (s.parse::<f64>().expect("a number") * 2.0).to_string()
    });
    let (code, out, err) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("seconds new/old"), "{out}");

    // One measured cell changed: exit 1, the table, the column and the row named.
    fs::write(&main, &original).expect("restore");
    tamper(&main, 1, "n_s_mean", |s| format!("{s}1"));
    let scratch2 = tmp.path().join("scratch2");
    let (code, out, err) =
        output(reproduce(&dir, &["--out", scratch2.to_str().unwrap()]).arg("--json"));
    assert_eq!(code, 1, "{out}{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(json["reproduced"], false);
    let main_json = &json["tables"][0];
    assert_eq!(main_json["table"], "main");
    assert_eq!(main_json["cells_differ"], 1);
    assert_eq!(main_json["differences"][0]["column"], "n_s_mean");
    assert_eq!(main_json["differences"][0]["row"], 1);
    assert_eq!(
        json["tables"][1]["same"], true,
        "the hist table is untouched"
    );
    let (code, out, _) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 1);
    assert!(
        out.contains("DIFFERS tiny-grid.csv (main)") && out.contains("row 1 (point 1) n_s_mean"),
        "{out}"
    );
    assert!(
        out.contains("NOT reproduced: 1 of 2 table(s) differ (tiny-grid.csv)"),
        "{out}"
    );
    // The temporary rerun of a result that differs is kept for inspection.
    let kept = out
        .rsplit("the rerun is kept in ")
        .next()
        .expect("kept")
        .trim();
    assert!(
        Path::new(kept).join("tiny-grid/tiny-grid.csv").is_file(),
        "{kept}"
    );
    fs::remove_dir_all(kept).ok();
    // … and Python's comparison names the same cell.
    let py = compare(&scratch2);
    let text = String::from_utf8_lossy(&py.stdout);
    assert_eq!(py.status.code(), Some(1), "{text}");
    assert!(
        text.contains("DIFFERS tiny-grid:") && text.contains("row 1 n_s_mean"),
        "{text}"
    );
}

#[test]
fn a_changed_spec_a_changed_input_and_a_gone_spec_are_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = grid_spec(tmp.path(), 3000);
    let results = tmp.path().join("results");
    run_quiet(&spec, &results).assert().success();
    let dir = results.join("tiny-grid");
    // `--check` accepts the result as it stands, running and writing nothing.
    let scratch = tmp.path().join("scratch");
    let (code, out, err) = output(&mut reproduce(
        &dir,
        &["--check", "--out", scratch.to_str().unwrap()],
    ));
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("rerunnable") && !scratch.exists(), "{out}");
    let meta = fs::read_to_string(dir.join("tiny-grid.meta.toml")).expect("meta");
    let then = meta
        .lines()
        .find_map(|l| l.strip_prefix("spec_hash = \""))
        .expect("a hash")
        .trim_end_matches('"')
        .to_string();
    grid_spec(tmp.path(), 4000);
    // … and refuses it, naming the key, once the spec changed.
    let (code, _, err) = output(&mut reproduce(&dir, &["--check"]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("experiment.rays = 3000 then, 4000 now"),
        "{err}"
    );
    let (code, out, err) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("tiny-grid.toml") && err.contains(&then),
        "{err}"
    );
    assert!(
        err.contains("experiment.rays = 3000 then, 4000 now"),
        "{err}"
    );
    fs::remove_file(&spec).expect("remove");
    let (code, _, err) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 2);
    assert!(err.contains("is gone"), "{err}");

    // A points file read by the run, changed since: named.
    let pts = tmp.path().join("pts.csv");
    let points = |shift: f64| {
        let mut s = String::from("x,y,z,nx,ny,nz\n");
        for i in 0..10 {
            let t = i as f64 / 10.0 - 0.5 + shift;
            s.push_str(&format!("{t},{},{},0,0,1\n", 0.3 * t, -0.2 * t));
        }
        fs::write(&pts, s).expect("points");
    };
    points(0.0);
    let detp = write_spec(
        tmp.path(),
        "pts",
        "[experiment]\nname = \"pts\"\nkind = \"detp\"\nseed = 3\n\n[detp]\nphotons = 2000\n\
         point_source = \"file\"\npoints_file = \"pts.csv\"\ndisc_radius = 0.1\n\
         engines = [\"sphere-cache\"]\n",
    );
    run_quiet(&detp, &results).assert().success();
    reproduce(&results.join("pts"), &[]).assert().success();
    points(0.01);
    let (code, _, err) = output(&mut reproduce(&results.join("pts"), &["--check"]));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("pts.csv"), "{err}");
    let (code, _, err) = output(&mut reproduce(&results.join("pts"), &[]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("pts.csv") && err.contains("content changed"),
        "{err}"
    );
}

/// A run of `--run R` reruns as run R (its own seed); a merged shard set reruns unsplit.
#[test]
fn a_run_index_and_a_merged_shard_set_rerun_as_recorded() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = grid_spec(tmp.path(), 2000);
    let results = tmp.path().join("results");
    run_quiet(&spec, &results)
        .args(["--run", "1"])
        .assert()
        .success();
    let (code, out, err) = output(&mut reproduce(&results.join("tiny-grid/runs/1"), &[]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("  run: 1\n"), "{out}");

    let sharded = tmp.path().join("sharded");
    for k in 0..2 {
        run_quiet(&spec, &sharded)
            .args(["--shard", &format!("{k}/2")])
            .assert()
            .success();
    }
    let dir = sharded.join("tiny-grid");
    let (code, out, err) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 2, "two shards and no merged table: {out}{err}");
    raycost().arg("merge").arg(&dir).assert().success();
    let (code, out, err) = output(&mut reproduce(&dir, &[]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("merged from 2 shards (rerun unsplit)"),
        "{out}"
    );
}

#[test]
fn a_crossover_result_reruns_on_its_recorded_inputs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (fronts, points) = crate::crossover::runs(tmp.path());
    let out = tmp.path().join("x");
    crate::crossover::crossover(&fronts, &points, &out)
        .assert()
        .success();
    let (code, text, err) = output(&mut reproduce(&out, &[]));
    assert_eq!(code, 0, "{text}{err}");
    assert!(
        text.contains("crossover.csv (main):") && text.contains("best.csv (best):"),
        "{text}"
    );
    assert!(text.contains("targets: 0.5,0.2"), "{text}");
    let (code, text, err) = output(&mut reproduce(&out, &["--check"]));
    assert_eq!(code, 0, "{text}{err}");
    assert!(text.contains("rerunnable"), "{text}");
    // A crossover input changed since: named (by --check too, which hashes the recorded inputs).
    tamper(&points.join("points.csv"), 0, "experiment.seed", |s| {
        format!("{s}0")
    });
    let (code, _, err) = output(&mut reproduce(&out, &["--check"]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("points.csv") && err.contains("other content"),
        "{err}"
    );
    let (code, _, err) = output(&mut reproduce(&out, &[]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("points.csv") && err.contains("content changed"),
        "{err}"
    );
}

/// An input given as runs (`DIR/runs/R`, whose files share their names) is recorded run by run
/// (`runs/0/NAME.csv`, `runs/1/NAME.csv`), so a reproduce matches each file to its own and names
/// the run whose file changed.
#[test]
fn a_crossover_over_runs_reruns_and_names_the_run_that_changed() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (fronts, _) = crate::crossover::runs(tmp.path());
    let repeated = tmp.path().join("repeated");
    for r in ["0", "1"] {
        crate::common::run_quiet(&tmp.path().join("points.toml"), &repeated)
            .args(["--run", r])
            .assert()
            .success();
    }
    let points = repeated.join("points");
    let out = tmp.path().join("x");
    crate::crossover::crossover(&fronts, &points, &out)
        .assert()
        .success();
    let meta = std::fs::read_to_string(out.join("crossover.meta.toml")).expect("meta");
    for r in ["0", "1"] {
        assert!(
            meta.contains(&format!("location = \"runs/{r}/points.csv\"")),
            "{meta}"
        );
    }
    let (code, text, err) = output(&mut reproduce(&out, &[]));
    assert_eq!(code, 0, "{text}{err}");
    tamper(
        &points.join("runs/1/points.csv"),
        0,
        "experiment.seed",
        |s| format!("{s}0"),
    );
    let (code, _, err) = output(&mut reproduce(&out, &[]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("runs/1/points.csv") && err.contains("content changed"),
        "{err}"
    );
}

/// A result with separate committed runs (`--repeat 3`) holds a rerun's timing means to the band
/// those runs give one more run, after the rerun's machine factor: a uniformly faster or slower
/// machine is reported as the factor and still reproduces; one cell far outside the runs' spread
/// (there, as in every committed run) is named.
#[test]
fn timings_are_held_to_the_spread_between_committed_runs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec_dir = tmp.path().join("spec");
    fs::create_dir(&spec_dir).expect("spec folder");
    let spec = write_spec(
        &spec_dir,
        "tiny-detp",
        "[experiment]\nname = \"tiny-detp\"\nkind = \"detp\"\nseed = 3\n[detp]\nphotons = 4000\n\
         points = 200\ndisc_radius = 0.1\n[sweep]\n\"detp.disc_radius\" = [0.05, 0.1, 0.2, 0.3]\n",
    );
    let results = tmp.path().join("results");
    run_quiet(&spec, &results)
        .args(["--repeat", "3", "--threads", "1"])
        .assert()
        .success();
    let runs: Vec<PathBuf> = (0..3)
        .map(|r| results.join(format!("tiny-detp/runs/{r}")))
        .collect();
    let column = "cost_sphere_cache_per_replica_s_mean";
    let scale = |row: Option<usize>, by: f64| {
        for run in &runs {
            let table = run.join("tiny-detp.csv");
            let rows = read_csv(&table).1.len();
            for r in (0..rows).filter(|r| row.is_none_or(|x| x == *r)) {
                tamper(&table, r, column, |s| {
                    (s.parse::<f64>().expect("a number") * by).to_string()
                });
            }
        }
    };
    let json = |args: &[&str]| {
        let (code, out, err) = output(reproduce(&runs[1], args).arg("--json"));
        let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|_| panic!("{err}"));
        (code, v)
    };
    // Every committed run twice as slow as this machine: factor about ½, counted cells identical.
    scale(None, 2.0);
    let (_, v) = json(&[]);
    let timing = &v["tables"][0]["timing"];
    assert_eq!(v["tables"][0]["cells_differ"], 0, "{v}");
    assert_eq!(timing["committed_runs"], 3, "{v}");
    assert_eq!(timing["judged_between_runs"], 4, "{v}");
    let factor = timing["run_factor"].as_f64().expect("a factor");
    assert!((0.2..1.0).contains(&factor), "{factor}");
    // Row 2 ten thousand times slower in every committed run: outside the band, named.
    scale(Some(2), 1e4);
    let (code, v) = json(&[]);
    assert_eq!(code, 1, "{v}");
    let timing = &v["tables"][0]["timing"];
    let outside = timing["first_outside"].as_array().expect("cells");
    assert!(
        outside
            .iter()
            .any(|c| c["row"] == 2 && c["column"] == column),
        "{v}"
    );
    // `--timings report` holds nothing.
    let (code, v) = json(&["--timings", "report"]);
    assert_eq!(code, 0, "{v}");
}
