//! `raycost crossover` end to end on tiny tables written by `raycost run`: a fronts run (errors of
//! every method against a reference, two replicas, two d) and an n_P sweep (seconds at one d), then
//! the refusals: an existing output without --force, a missing folder, missing columns — each exit 2
//! with nothing written.

use std::path::{Path, PathBuf};

use crate::common::{files_below, raycost, read_csv, root, run_quiet, write_spec};

fn spec(dir: &Path, name: &str, body: &str, sweep: &str) -> PathBuf {
    let scene = root().join("experiments/scenes/cornell.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "detp"
seed = 3

[detp]
source = "scene"
scene = "{}"
photons = 2000
disc_radius = 40.0
replicas = 2
path_samples = 4
{body}
[sweep]
{sweep}
"#,
            scene.display()
        ),
    )
}

/// The two runs, once per test binary run (they take a few seconds).
pub(crate) fn runs(dir: &Path) -> (PathBuf, PathBuf) {
    let fronts = spec(
        dir,
        "fronts",
        "point_spacing = 160.0\nengines = [\"sphere-cache\", \"disc-index\", \"photon-map\", \"photon-map-growing\", \"path-tracing\", \"reference\"]\nreference_samples = 16\nwrite_points = true\n",
        "\"detp.photons\" = [1000, 4000]\n\"detp.disc_radius\" = [40.0, 80.0]",
    );
    let points = spec(
        dir,
        "points",
        "engines = [\"sphere-cache\", \"disc-index\", \"photon-map\", \"photon-map-growing\", \"path-tracing\"]\n",
        "\"detp.point_spacing\" = [160.0, 80.0]\n\"detp.photons\" = [1000, 4000]",
    );
    let out = dir.join("results");
    for s in [&fronts, &points] {
        run_quiet(s, &out).assert().success();
    }
    (out.join("fronts"), out.join("points"))
}

pub(crate) fn crossover(fronts: &Path, points: &Path, out: &Path) -> assert_cmd::Command {
    let mut c = raycost();
    c.arg("crossover")
        .arg(fronts)
        .arg(points)
        .args(["--targets", "0.5,0.2"])
        .arg("--out")
        .arg(out);
    c
}

#[test]
fn crossover_writes_its_tables_and_refuses_what_it_must() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (fronts, points) = runs(dir.path());
    let out = dir.path().join("x");
    crossover(&fronts, &points, &out).assert().success();
    let (header, rows) = read_csv(&out.join("crossover.csv"));
    assert_eq!(
        header,
        [
            "scene",
            "target",
            "method",
            "direct",
            "edge",
            "disc_radius",
            "edge_radius_factor",
            "radius_schedule_photons",
            "radius_schedule_exponent",
            "photons",
            "photons_measured_max",
            "error_floor",
            "error_fit_c",
            "error_fit_a",
            "error_slope",
            "error_slope_lo",
            "error_slope_hi",
            "error_slope_theory",
            "error_curvature",
            "error_curvature_lo",
            "error_curvature_hi",
            "seconds_once",
            "seconds_per_point",
            "cost_gamma",
            "cost_fixed",
            "cost_per_photon",
            "cost_per_photon_point",
            "cost_per_point",
            "cost_worst_misfit",
            "n_star",
            "n_star_lo",
            "n_star_hi",
            "never_fraction",
            "n_star_linear",
            "n_star_model",
            "n_star_model_lo",
            "n_star_model_hi",
            "extrapolated",
            "sweep_points_min",
            "sweep_points_max",
            "n_star_head_to_head",
            "reason"
        ]
    );
    // Per target: 2 d × 2 DETP engines, 2 photon maps, path tracing.
    assert_eq!(rows.len(), 2 * 7, "{rows:?}");
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    for r in &rows {
        assert_eq!(r[col("scene")], "cornell");
        let d = r[col("disc_radius")].as_str();
        let detp = ["sphere-cache", "disc-index"].contains(&r[col("method")].as_str());
        if detp && d == "80.0" {
            assert!(r[col("reason")].contains("no cost sweep"), "{r:?}");
        }
        // N_ε is judged against the largest photon count the fronts measured (4 000): NaN for
        // path tracing, which has no photons.
        let top = &r[col("photons_measured_max")];
        match r[col("method")].as_str() {
            "path-tracing" => assert_eq!(top, "NaN", "{r:?}"),
            _ => assert_eq!(top, "4000.0", "{r:?}"),
        }
        if detp && d == "40.0" {
            // Timed: a γ on the grid and a bootstrap (or a floor above the target).
            let g: f64 = r[col("cost_gamma")].parse().expect("γ");
            assert!((0.0..=1.0).contains(&g), "{r:?}");
            let never: f64 = r[col("never_fraction")].parse().expect("fraction");
            assert!((0.0..=1.0).contains(&never), "{r:?}");
        }
    }
    // The photon maps are judged per replica (the fronts' points table has each replica's value),
    // not from their mean over replicas.
    let (ph, _) = read_csv(&fronts.join("fronts.points.csv"));
    for map in ["photon_map", "photon_map_growing"] {
        for k in 0..2 {
            assert!(
                ph.contains(&format!("{map}_replica_{k}")),
                "{map} {k}: {ph:?}"
            );
        }
    }
    for r in rows
        .iter()
        .filter(|r| r[col("method")].starts_with("photon-map"))
    {
        assert!(!r[col("reason")].contains("no per-replica values"), "{r:?}");
    }
    // N* from the measured seconds: a row is extrapolated exactly when N* lies outside the
    // measured n_P.
    for r in &rows {
        let n: f64 = r[col("n_star")].parse().expect("n_star");
        let (lo, hi): (f64, f64) = (
            r[col("sweep_points_min")].parse().expect("min"),
            r[col("sweep_points_max")].parse().expect("max"),
        );
        if n.is_finite() && lo.is_finite() {
            let outside = n < lo || n > hi;
            assert_eq!(r[col("extrapolated")] == "true", outside, "{r:?}");
        }
    }
    let pt: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| r[col("method")] == "path-tracing")
        .collect();
    assert_eq!(pt.len(), 2);
    let paths: f64 = pt[0][col("photons")].parse().expect("paths");
    assert!(paths >= 1.0);
    let (bh, best) = read_csv(&out.join("best.csv"));
    assert_eq!(
        bh,
        [
            "scene",
            "target",
            "points",
            "best",
            "best_s",
            "runner_up",
            "runner_up_s",
            "extrapolated"
        ]
    );
    // Per target the grid 10², …, 10⁶ and the fronts' own point count (once, if not on the grid).
    let (fh, fronts_rows) = read_csv(&fronts.join("fronts.csv"));
    let n_p: f64 = fronts_rows[0][fh.iter().position(|h| h == "points").expect("points")]
        .parse()
        .expect("points");
    let on_grid = [1e2, 1e3, 1e4, 1e5, 1e6].contains(&n_p);
    assert_eq!(best.len(), 2 * if on_grid { 5 } else { 6 }, "n_P {n_p}");
    let bp = bh.iter().position(|h| h == "points").expect("points");
    assert!(
        best.iter().any(|r| r[bp].parse::<f64>() == Ok(n_p)),
        "{best:?}"
    );
    // Separate runs of the sweep (runs/R): each run's seconds are read, the runs recorded.
    let repeated = dir.path().join("repeated");
    let points_spec = dir.path().join("points.toml");
    for r in ["0", "1"] {
        run_quiet(&points_spec, &repeated)
            .args(["--run", r])
            .assert()
            .success();
    }
    let by_run = dir.path().join("by-run");
    crossover(&fronts, &repeated.join("points"), &by_run)
        .assert()
        .success();
    let meta = std::fs::read_to_string(by_run.join("crossover.meta.toml")).expect("meta");
    assert!(
        meta.contains("runs/0/points.csv") && meta.contains("runs/1/points.csv"),
        "{meta}"
    );
    let meta = std::fs::read_to_string(out.join("crossover.meta.toml")).expect("meta");
    assert!(
        meta.contains("fronts.replica_errors.csv") && meta.contains("[extra.points]"),
        "{meta}"
    );
    assert!(!out.join("frames.csv").exists());

    // Existing outputs: refused without --force (exit 2, untouched), replaced with it.
    let before: Vec<(PathBuf, Vec<u8>)> = files_below(&out)
        .into_iter()
        .map(|p| (p.clone(), std::fs::read(&p).expect("read")))
        .collect();
    let e = crossover(&fronts, &points, &out).assert().code(2);
    let err = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
    assert!(err.contains("--force"), "{err}");
    let after: Vec<(PathBuf, Vec<u8>)> = files_below(&out)
        .into_iter()
        .map(|p| (p.clone(), std::fs::read(&p).expect("read")))
        .collect();
    assert_eq!(before, after);
    crossover(&fronts, &points, &out)
        .arg("--force")
        .assert()
        .success();
    let (_, again) = read_csv(&out.join("crossover.csv"));
    // Same inputs, same seed: the same measured columns (the photons and fits).
    for (a, b) in rows.iter().zip(&again) {
        assert_eq!(a[..9], b[..9]);
    }

    // A frames folder (a synthetic quasi-static table: its path-tracing columns are new): one row
    // per target and frames row, N_ε from the fronts' configuration at the frames' d.
    let frames = dir.path().join("frames");
    std::fs::create_dir_all(&frames).expect("mkdir");
    let m = std::fs::read_to_string(fronts.join("fronts.meta.toml")).expect("meta");
    std::fs::write(
        frames.join("f.meta.toml"),
        without_declared(&m, "main", None),
    )
    .expect("meta");
    std::fs::write(
        frames.join("f.csv"),
        "point,detp.photons,detp.disc_radius,points_static,points_dynamic,frame0_s,frame_s_mean,full_frame_s_mean,path_tracing_s_per_path_mean,path_tracing_cv_mean\n\
         0,1000,40.0,900,100,1.1,0.11,1.0,1e-6,3\n\
         1,2000,40.0,900,100,2.1,0.21,2.0,1e-6,3\n",
    )
    .expect("frames table");
    let z = dir.path().join("z");
    crossover(&fronts, &points, &z)
        .arg(&frames)
        .assert()
        .success();
    let (fh, fr) = read_csv(&z.join("frames.csv"));
    assert_eq!(fr.len(), 2 * 2, "{fr:?}");
    let at = |name: &str| fh.iter().position(|h| h == name).expect(name);
    assert!(
        fr.iter().all(|r| r[at("fronts_disc_radius")] == "40.0"),
        "{fr:?}"
    );
    let paths: f64 = fr[0][at("path_tracing_paths")].parse().expect("paths");
    assert_eq!(paths, 36.0, "(3/0.5)²");

    // Refusals write nothing: a missing folder, a fronts folder without a points table, a frames
    // folder without the frames columns.
    let fresh = dir.path().join("y");
    let missing = dir.path().join("nope");
    crossover(&missing, &points, &fresh).assert().code(2);
    let e = crossover(&points, &points, &fresh).assert().code(2);
    let err = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
    assert!(err.contains("points.points.csv"), "{err}");
    let e = crossover(&fronts, &points, &fresh)
        .arg(&fronts)
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
    assert!(err.contains("the frames analysis"), "{err}");
    raycost()
        .arg("crossover")
        .arg(&fronts)
        .arg(&points)
        .args(["--targets", "0.1,0"])
        .arg("--out")
        .arg(&fresh)
        .assert()
        .code(2);
    assert!(!fresh.exists(), "nothing written");
}

/// The radius rules as configurations, end to end: a fronts run with d fixed beside the N^(−1/6)
/// schedule at the same d (β swept: 0 is d fixed), a second fronts run (runs/1) adding κ = 0.5 with
/// clamp-first-hit, and an n_P sweep that timed the fixed d and the schedule but not κ. Every rule
/// is its own row, labelled by its parameters; the schedule's rows carry the fitted γ beside the
/// derived 1/3 and no floor; κ's rows say that no cost sweep timed their rule rather than borrow
/// another rule's seconds; a run repeating a configuration is refused.
#[test]
fn crossover_keys_the_radius_rules_and_charges_each_its_own_seconds() {
    let dir = tempfile::tempdir().expect("temp dir");
    let schedule = "radius_schedule_photons = 1000\n";
    let sweep = "\"detp.radius_schedule_exponent\" = [0.0, 0.16666666666666666]\n\"detp.photons\" = [1000, 2000, 4000]";
    let fronts = spec(
        dir.path(),
        "rfronts",
        &format!("point_spacing = 160.0\nengines = [\"sphere-cache\", \"disc-index\", \"path-tracing\", \"reference\"]\nreference_samples = 16\nwrite_points = true\n{schedule}"),
        sweep,
    );
    let points = spec(
        dir.path(),
        "rpoints",
        &format!("engines = [\"sphere-cache\", \"disc-index\", \"path-tracing\"]\n{schedule}"),
        "\"detp.radius_schedule_exponent\" = [0.0, 0.16666666666666666]\n\"detp.point_spacing\" = [160.0, 80.0]\n\"detp.photons\" = [1000, 4000]",
    );
    let out = dir.path().join("results");
    run_quiet(&fronts, &out)
        .args(["--run", "0"])
        .assert()
        .success();
    run_quiet(&fronts, &out)
        .args([
            "--run",
            "1",
            "--set",
            "detp.edge=\"clamp-first-hit\"",
            "--set",
            "detp.edge_radius_factor=0.5",
        ])
        .assert()
        .success();
    run_quiet(&points, &out).assert().success();
    let x = dir.path().join("x");
    crossover(&out.join("rfronts"), &out.join("rpoints"), &x)
        .assert()
        .success();
    let (header, rows) = read_csv(&x.join("crossover.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    let detp: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| r[col("method")] == "sphere-cache")
        .collect();
    // Per target: fixed, schedule (run 0), κ fixed and κ with the schedule (run 1).
    assert_eq!(detp.len(), 2 * 4, "{detp:?}");
    let third = 1.0 / 3.0;
    let mut kinds = std::collections::BTreeSet::new();
    for r in &detp {
        let beta = r[col("radius_schedule_exponent")].as_str();
        let kappa = r[col("edge_radius_factor")].as_str();
        kinds.insert((beta.to_string(), kappa.to_string()));
        let theory: f64 = r[col("error_slope_theory")].parse().expect("theory");
        let slope: f64 = r[col("error_slope")].parse().expect("slope");
        let floor: f64 = r[col("error_floor")].parse().expect("floor");
        if beta == "NaN" {
            assert!(
                theory.is_nan() && slope.is_nan() && floor.is_finite(),
                "{r:?}"
            );
        } else {
            assert_eq!(beta, "0.16666666666666666");
            assert_eq!(r[col("radius_schedule_photons")], "1000.0");
            assert!((theory - third).abs() < 1e-12, "{r:?}");
            assert!(slope.is_finite() && floor.is_nan(), "{r:?}");
        }
        let reason = &r[col("reason")];
        if kappa == "0.5" {
            assert_eq!(r[col("edge")], "clamp-first-hit");
            assert!(
                reason.contains("no cost sweep at this d/edge/direct and radius rule kappa=0.5"),
                "{r:?}"
            );
            assert!(
                r[col("n_star")] == "NaN" && r[col("seconds_once")] == "NaN",
                "{r:?}"
            );
        } else {
            assert_eq!(kappa, "NaN");
            assert!(!reason.contains("no cost sweep"), "{r:?}");
        }
    }
    assert_eq!(kinds.len(), 4, "{kinds:?}");
    // A run that repeats run 0's configurations is refused, nothing written.
    let runs = out.join("rfronts").join("runs");
    let copy = runs.join("2");
    std::fs::create_dir_all(&copy).expect("dir");
    for f in std::fs::read_dir(runs.join("0")).expect("run 0").flatten() {
        std::fs::copy(f.path(), copy.join(f.file_name())).expect("copy");
    }
    let y = dir.path().join("y");
    crossover(&out.join("rfronts"), &out.join("rpoints"), &y)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("repeats the configuration"));
    assert!(!y.join("crossover.csv").exists());
}

/// The kind's `NAME.replica_errors.csv` (and path tracing's `ref_mean`) give the crossover the
/// same bits as the points table does: fronts with only the small table, and fronts as written
/// before it (points table, no `ref_mean`), give byte-identical crossover and best tables.
#[test]
fn crossover_reads_the_replica_errors_as_the_points_table() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (fronts, points) = runs(dir.path());
    let (eh, er) = read_csv(&fronts.join("fronts.replica_errors.csv"));
    assert_eq!(eh, ["point", "estimator", "replica", "relative_mse"]);
    // 4 sweep points × (detp + 2 photon maps) × 2 replicas.
    assert_eq!(er.len(), 4 * 3 * 2, "{er:?}");
    let copy = |name: &str, skip: &dyn Fn(&str) -> bool| {
        let to = dir.path().join(name);
        std::fs::create_dir_all(&to).expect("dir");
        for f in files_below(&fronts) {
            let n = f.file_name().expect("name").to_string_lossy().into_owned();
            if !skip(&n) {
                std::fs::copy(&f, to.join(&n)).expect("copy");
            }
        }
        to
    };
    let small = copy("small", &|n| n.ends_with(".points.csv"));
    let old = copy("old", &|n| n.ends_with(".replica_errors.csv"));
    // The old layout's path tracing table has no ref_mean column.
    let pt = old.join("fronts.path_tracing.csv");
    let (h, rows) = read_csv(&pt);
    let drop = h.iter().position(|c| c == "ref_mean").expect("ref_mean");
    let line = |v: &[String]| {
        let mut v = v.to_vec();
        v.remove(drop);
        v.join(",")
    };
    let mut text = line(&h) + "\n";
    for r in &rows {
        text += &(line(r) + "\n");
    }
    std::fs::write(&pt, text).expect("write");
    let meta = old.join("fronts.meta.toml");
    let m = std::fs::read_to_string(&meta).expect("meta");
    std::fs::write(
        &meta,
        without_declared(&m, "path_tracing", Some("ref_mean")),
    )
    .expect("meta");
    let mut outs = Vec::new();
    for (name, f) in [("a", &fronts), ("b", &small), ("c", &old)] {
        let out = dir.path().join(format!("x-{name}"));
        crossover(f, &points, &out).assert().success();
        outs.push(out);
    }
    for table in ["crossover.csv", "best.csv"] {
        let read = |d: &Path| std::fs::read_to_string(d.join(table)).expect(table);
        let want = read(&outs[0]);
        assert!(want.lines().count() > 1, "{table}: {want}");
        assert_eq!(want, read(&outs[1]), "{table}: replica_errors only");
        assert_eq!(want, read(&outs[2]), "{table}: points table only");
    }
    let meta = std::fs::read_to_string(outs[1].join("crossover.meta.toml")).expect("meta");
    assert!(meta.contains("fronts.replica_errors.csv"), "{meta}");
}

/// Metadata text without the `[[columns.TABLE]]` declarations (all of them, or only `column`'s), for
/// fixtures that write a table of their own beside a copied metadata file.
fn without_declared(meta: &str, table: &str, column: Option<&str>) -> String {
    let head = format!("[[columns.{table}]]");
    meta.split("\n\n")
        .filter(|block| {
            let b = block.trim_start();
            !(b.starts_with(&head)
                && column.is_none_or(|c| b.contains(&format!("name = \"{c}\"\n"))))
        })
        .collect::<Vec<_>>()
        .join("\n\n")
}

/// Tables written before the radius rules read as they always did: the crossover of the
/// hard-cases fronts and n_P sweep as committed then (tests/data/before-rules: the fronts' points
/// table, no replica errors; results/ now holds reruns) gives, in every column it had,
/// exactly the tables the build before the rules gave (tests/expected/crossover-hard, from 274675a),
/// but for two later changes: a photon-map row without per-replica values (N* from the cost model
/// alone) now records the n_P its configuration was timed at (`sweep_points_min/max`, NaN before);
/// and the bootstrap's percentile is Python's (rank ⌊q·(n − 1)⌋ instead of ⌊q·n⌋, both ends one
/// rank of 2 000 lower), so the expected `n_star_model_lo/hi` were updated with it (18 cells, no
/// other column).
#[test]
fn crossover_of_committed_tables_is_unchanged_by_the_rules() {
    let dir = tempfile::tempdir().expect("temp dir");
    let x = dir.path().join("x");
    let mut c = raycost();
    c.current_dir(root())
        .args([
            "crossover",
            "tests/data/before-rules/issue27-fronts-hard",
            "tests/data/before-rules/issue27-points-hard",
            "--targets",
            "0.1,0.05,0.02",
            "--out",
        ])
        .arg(&x)
        .assert()
        .success();
    for table in ["crossover.csv", "best.csv"] {
        let (want_h, want) = read_csv(&root().join("tests/expected/crossover-hard").join(table));
        let (got_h, got) = read_csv(&x.join(table));
        assert_eq!(want.len(), got.len(), "{table}");
        let method = want_h.iter().position(|h| h == "method");
        for (i, name) in want_h.iter().enumerate() {
            let j = got_h.iter().position(|h| h == name).expect(name);
            for (w, g) in want.iter().zip(&got) {
                let model_only = method.is_some_and(|m| w[m].starts_with("photon-map"));
                match name.as_str() {
                    "sweep_points_min" if model_only => assert_eq!(g[j], "100.0"),
                    "sweep_points_max" if model_only => assert_eq!(g[j], "1000000.0"),
                    _ => assert_eq!(w[i], g[j], "{table} {name}"),
                }
            }
        }
    }
}
