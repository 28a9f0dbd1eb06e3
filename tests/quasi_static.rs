//! Kind quasi-static end to end: a run writes its tables with every checked frame exact, the same
//! spec gives the same measured columns on 1 and 2 threads, and overlapping objects are a counted
//! warning, not an error.

use crate::common::{measured_columns, raycost, read_csv, root, run_quiet, write_spec};

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

/// Runs `spec` on `threads` threads into `out`; returns `out`.
fn run_on(spec: &std::path::Path, threads: &str, out: &std::path::Path) -> std::path::PathBuf {
    raycost()
        .args([
            "run",
            spec.to_str().unwrap(),
            "--quiet",
            "--threads",
            threads,
            "--out",
        ])
        .arg(out)
        .assert()
        .success();
    out.to_path_buf()
}

#[test]
fn a_run_is_exact_and_thread_independent() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "qs");
    let mut tables = Vec::new();
    for threads in ["1", "2"] {
        let out = run_on(&s, threads, &dir.path().join(format!("out{threads}")));
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

/// Replicas are independent runs of every frame: replica 0 is the run without replicas (its frames
/// are the same rows), replica 1 traces other photons, every frame of both is exact, and the
/// per-frame estimates' sample count is the number of replicas' frames.
#[test]
fn replicas_are_independent_runs_and_replica_zero_is_the_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "qs");
    let run = |out: &str, extra: &[&str]| {
        let out = dir.path().join(out);
        raycost()
            .args(["run", s.to_str().unwrap(), "--quiet", "--out"])
            .arg(&out)
            .args(extra)
            .assert()
            .success();
        out
    };
    let one = run("one", &[]);
    let two = run("two", &["--set", "detp.replicas=2"]);
    let (h, rows) = read_csv(&two.join("qs/qs.csv"));
    let col = |n: &str| rows[0][h.iter().position(|c| c == n).unwrap()].clone();
    assert_eq!(col("full_mismatch"), "0");
    assert_eq!(col("full_checked"), "22", "11 checked frames per replica");
    assert_eq!(col("retraced_rays_n"), "22", "11 frames per replica");
    let (fh, f1) = read_csv(&one.join("qs/qs.frames.csv"));
    let (fh2, f2) = read_csv(&two.join("qs/qs.frames.csv"));
    assert_eq!(fh, fh2);
    assert_eq!(f2.len(), 24, "12 frames per replica");
    let measured: Vec<usize> = [
        "replica",
        "frame",
        "retraced_rays",
        "segments_added",
        "static_disc_tests",
    ]
    .iter()
    .map(|n| {
        fh.iter()
            .position(|c| c == n)
            .unwrap_or_else(|| panic!("{n}"))
    })
    .collect();
    let pick = |r: &Vec<String>| measured.iter().map(|&i| r[i].clone()).collect::<Vec<_>>();
    let (r0, r1): (Vec<_>, Vec<_>) = f2.iter().partition(|r| r[measured[0]] == "0");
    assert_eq!(
        f1.iter().map(pick).collect::<Vec<_>>(),
        r0.iter().map(|r| pick(r)).collect::<Vec<_>>(),
        "replica 0 = the run without replicas"
    );
    assert_ne!(
        r0.iter().map(|r| pick(r)[2..].to_vec()).collect::<Vec<_>>(),
        r1.iter().map(|r| pick(r)[2..].to_vec()).collect::<Vec<_>>(),
        "replica 1 traces other photons"
    );
}

/// With `detp.engine = "predicted"` the §4.1 predictor picks each object's engine on seconds, so
/// the pick and every count that follows it may differ between runs of one spec and seed (observed:
/// predict-engine's frames picked the disc index in one quiet run and the sphere cache in another).
/// The metadata must class them as timings, so that reproducibility checks skip them, while the
/// static points' counts and the irradiance stay measured.
#[test]
fn a_pick_taken_on_seconds_is_classed_timing() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "pick");
    let text = std::fs::read_to_string(&s)
        .unwrap()
        .replace(
            "index = \"grid\"",
            "index = \"grid\"\nengine = \"predicted\"",
        )
        .replace("frames = 12", "frames = 3\npredict = 0.2");
    std::fs::write(&s, text).unwrap();
    let out = dir.path().join("out");
    run_quiet(&s, &out).assert().success();
    for table in ["main", "frames"] {
        let class = |name: &str| class_of(&out, "pick", table, name);
        assert_eq!(class("engine_used"), "timing", "{table}");
        let (dynamic_tests, static_tests) = if table == "main" {
            ("dynamic_tests_mean", "static_tests_mean")
        } else {
            ("dynamic_disc_tests", "static_disc_tests")
        };
        assert_eq!(class(dynamic_tests), "timing", "{table}");
        assert_eq!(class(static_tests), "measured", "{table}");
    }
    // The same spec with a fixed engine keeps them measured.
    let fixed = dir.path().join("fixed.toml");
    std::fs::write(
        &fixed,
        std::fs::read_to_string(&s)
            .unwrap()
            .replace("name = \"pick\"", "name = \"fixed\"")
            .replace("engine = \"predicted\"", "engine = \"disc-index\""),
    )
    .unwrap();
    run_quiet(&fixed, &out).assert().success();
    assert_eq!(class_of(&out, "fixed", "main", "engine_used"), "measured");
}

/// The class the run's metadata (OUT/NAME/NAME.meta.toml) gives column `name` of `table`.
fn class_of(out: &std::path::Path, name: &str, table: &str, column: &str) -> String {
    let meta = raycost::output::meta::Meta::read(&out.join(format!("{name}/{name}.meta.toml")))
        .expect("the run's metadata");
    meta.columns[table]
        .iter()
        .find(|c| c.name == column)
        .unwrap_or_else(|| panic!("{table}.{column}"))
        .class
        .as_str()
        .to_string()
}

/// `detp.source = "lines"`: μ-random lines and a sphere circling in the unit ball. Every checked
/// frame is exact with both engines, the measured columns are the same on 1 and 2 threads, r_0 = 1,
/// and the lines meeting the sphere's new pose match f_R = n_R·(r_D/r_0)² (eq. 11, one pose) while
/// those meeting its old or new pose (retraced_rays) are nearly twice as many (the two poses a
/// quarter turn apart barely overlap at r_D = 0.05).
#[test]
fn uniform_lines_are_exact_thread_independent_and_count_eq_11() {
    let dir = tempfile::tempdir().unwrap();
    let s = write_spec(
        dir.path(),
        "qsl",
        r#"[experiment]
name = "qsl"
kind = "quasi-static"
seed = 2

[detp]
source = "lines"
photons = 40_000
points = 2000
disc_radius = "spacing"
index = "grid"
replicas = 2

[dynamic]
frames = 5
check_every = 1
ratio = 0.05

[sweep]
"detp.engine" = ["disc-index", "sphere-cache"]
"#,
    );
    let mut tables = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("out{threads}"));
        run_quiet(&s, &out)
            .args(["--threads", threads])
            .assert()
            .success();
        let csv = out.join("qsl/qsl.csv");
        let (h, rows) = read_csv(&csv);
        assert_eq!(rows.len(), 2);
        for r in &rows {
            let col = |n: &str| {
                r[h.iter()
                    .position(|c| c == n)
                    .unwrap_or_else(|| panic!("{n}"))]
                .clone()
            };
            let num = |n: &str| col(n).parse::<f64>().unwrap();
            assert_eq!(col("full_mismatch"), "0");
            assert_eq!(col("full_checked"), "8", "4 frames × 2 replicas");
            assert_eq!(num("r0"), 1.0);
            assert_eq!(num("segments"), 40_000.0, "one segment per line");
            let f_r = 40_000.0 * 0.05 * 0.05;
            assert!((num("retraced_rays_theory") - f_r).abs() < 1e-9);
            // 8 frames of ~100 lines each: Poisson SE of the mean ≈ √(100/8) ≈ 3.5.
            let new = num("rays_meeting_object_mean");
            assert!(
                (new - f_r).abs() < 5.0 * (f_r / 8.0).sqrt(),
                "{new} vs {f_r}"
            );
            let both = num("retraced_rays_mean");
            assert!(
                (both - 2.0 * f_r).abs() < 5.0 * (2.0 * f_r / 8.0).sqrt(),
                "{both} vs 2·{f_r}"
            );
        }
        tables.push((
            measured_columns(&csv),
            measured_columns(&out.join("qsl/qsl.frames.csv")),
        ));
    }
    assert_eq!(
        tables[0], tables[1],
        "measured columns differ between 1 and 2 threads"
    );
}

/// `dynamic_traversal_s` (eq. 8's traversal in seconds): with the disc index gathering the dynamic
/// points it is positive in the main table and every frame, 0 with the sphere cache, classed
/// timing; and the extra walk leaves the measured columns thread-independent as before.
#[test]
fn the_traversal_alone_is_timed_where_the_disc_index_runs() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "trav");
    let text = std::fs::read_to_string(&s)
        .unwrap()
        .replace("frames = 12", "frames = 3")
        .replace(
            "ratio = 0.08",
            "ratio = 0.08\n\n[sweep]\n\"detp.engine\" = [\"sphere-cache\", \"disc-index\"]",
        );
    std::fs::write(&s, text).unwrap();
    let mut tables = Vec::new();
    for threads in ["1", "2"] {
        let out = run_on(&s, threads, &dir.path().join(format!("out{threads}")));
        let (main, frames) = (out.join("trav/trav.csv"), out.join("trav/trav.frames.csv"));
        for (table, path, column) in [
            ("main", &main, "dynamic_traversal_s_mean"),
            ("frames", &frames, "dynamic_traversal_s"),
        ] {
            assert_eq!(class_of(&out, "trav", table, column), "timing");
            let (h, rows) = read_csv(path);
            let at = |c: &str| {
                h.iter()
                    .position(|x| x == c)
                    .unwrap_or_else(|| panic!("{c}"))
            };
            let engines = ["sphere-cache", "disc-index"];
            for r in &rows {
                let engine = if table == "main" {
                    r[at("detp.engine")].as_str()
                } else {
                    engines[r[at("point")].parse::<usize>().unwrap()]
                };
                let v: f64 = r[at(column)].parse().unwrap();
                if engine == "disc-index" {
                    assert!(v.is_finite() && v > 0.0, "{table} {column}: {v}");
                } else {
                    assert_eq!(v, 0.0, "{table} {column} with the sphere cache");
                }
            }
        }
        tables.push((measured_columns(&main), measured_columns(&frames)));
    }
    assert_eq!(
        tables[0], tables[1],
        "measured columns differ between 1 and 2 threads"
    );
}
