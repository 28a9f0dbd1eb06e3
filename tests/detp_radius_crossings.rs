//! `detp.radius_crossings` through the runner: each disc's radius is the distance of its k-th
//! nearest crossing. The sphere cache and the disc index (grid and octree) give the same
//! irradiance, radius and counts in separate runs, whatever the thread count; on μ-random lines
//! (a uniform field) the estimate is unbiased within its standard error (counting the k-th crossing
//! too would be 1/(k − 1) too high, which the same data shows the test would see); photon shards
//! are refused.

use crate::common::{measured_columns, raycost, read_csv, root, run_quiet, write_spec};

fn column<'a>(h: &[String], row: &'a [String], name: &str) -> &'a str {
    &row[h
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"))]
}

fn number(h: &[String], row: &[String], name: &str) -> f64 {
    column(h, row, name)
        .parse()
        .unwrap_or_else(|_| panic!("{name} is not a number"))
}

/// A hard-cases spec with the k-nearest radius under an edge remedy and a growing k.
fn scene_spec(dir: &std::path::Path, name: &str, engines: &str, index: &str) -> std::path::PathBuf {
    let scene = root().join("experiments/scenes/hard/hard-cases.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "detp"
seed = 17

[detp]
source = "scene"
scene = "{}"
photons = 8000
points = 300
disc_radius = 0.15
edge = "clamp-first-hit"
radius_crossings = 6
radius_crossings_photons = 2000
engines = {engines}
index = "{index}"
brute_force_points = 300
replicas = 2
write_points = true
"#,
            scene.display()
        ),
    )
}

/// What DETP estimated, whichever engines ran: the main table's irradiance and radius columns and
/// the points table's measured columns.
fn shared_outcome(out: &std::path::Path, name: &str) -> Vec<Vec<(String, String)>> {
    let main = measured_columns(&out.join(format!("{name}/{name}.csv")))
        .into_iter()
        .map(|row| {
            row.into_iter()
                .filter(|(c, _)| {
                    ["irradiance", "radius_crossings", "edge_radius", "segments"]
                        .iter()
                        .any(|p| c.starts_with(p))
                })
                .collect()
        });
    main.chain(measured_columns(
        &out.join(format!("{name}/{name}.points.csv")),
    ))
    .collect()
}

#[test]
fn the_k_nearest_radius_is_the_same_in_every_engine_and_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let runs = [
        ("cache", r#"["sphere-cache"]"#, "octree", "1"),
        ("octree", r#"["disc-index"]"#, "octree", "2"),
        ("grid", r#"["disc-index"]"#, "grid", "1"),
        ("all", r#"["sphere-cache", "disc-index"]"#, "grid", "2"),
    ];
    let mut outcomes = Vec::new();
    for (name, engines, index, threads) in runs {
        let spec = scene_spec(dir.path(), name, engines, index);
        let out = dir.path().join(format!("out-{name}"));
        run_quiet(&spec, &out)
            .args(["--threads", threads])
            .assert()
            .success();
        let (h, rows) = read_csv(&out.join(format!("{name}/{name}.csv")));
        let row = &rows[0];
        // Brute force re-computed every disc's k nearest crossings and radius: none differs.
        assert_eq!(column(&h, row, "mismatches"), "0", "{name}");
        assert_eq!(column(&h, row, "bf_checked"), "600", "{name}");
        // k = round(6·(8000/2000)^(2/3)) = round(15.1) = 15.
        assert_eq!(column(&h, row, "radius_crossings_k"), "15", "{name}");
        let ratio = number(&h, row, "radius_crossings_ratio");
        assert!(ratio > 0.2 && ratio < 1.0, "{name}: mean r_i/d_i {ratio}");
        // The points table's radius is r_i (mean over replicas), below the cap.
        let (ph, prow) = read_csv(&out.join(format!("{name}/{name}.points.csv")));
        let radii: Vec<f64> = prow.iter().map(|r| number(&ph, r, "disc_radius")).collect();
        assert!(radii.iter().all(|&r| r > 0.0 && r <= 0.15), "{name}");
        assert!(
            radii.iter().any(|&r| r < 0.15 * 0.9),
            "{name}: no disc found k crossings"
        );
        outcomes.push((name, shared_outcome(&out, name)));
    }
    let (first, rest) = outcomes.split_first().unwrap();
    assert!(first
        .1
        .iter()
        .flatten()
        .any(|(c, _)| c == "irradiance_mean"));
    for other in rest {
        assert_eq!(
            first.1, other.1,
            "{} and {}: irradiance, radii and SEs differ",
            first.0, other.0
        );
    }
}

#[test]
fn the_k_nearest_estimate_of_a_uniform_field_is_unbiased_within_its_standard_error() {
    let dir = tempfile::tempdir().unwrap();
    let k = 8.0;
    let spec = write_spec(
        dir.path(),
        "uniform",
        r#"[experiment]
name = "uniform"
kind = "detp"
seed = 23

[detp]
photons = 40000
points = 1500
disc_radius = 0.1
radius_crossings = 8
engines = ["disc-index"]
replicas = 6
"#,
    );
    let out = dir.path().join("out");
    run_quiet(&spec, &out).assert().success();
    let (h, rows) = read_csv(&out.join("uniform/uniform.csv"));
    let row = &rows[0];
    let exact = number(&h, row, "irradiance_theory");
    let mean = number(&h, row, "irradiance_mean");
    let se = number(&h, row, "irradiance_se");
    assert!((exact / (40000.0 / (4.0 * std::f64::consts::PI)) - 1.0).abs() < 1e-12);
    // Every disc holds k crossings well within d (E ≈ 3200 crossings per unit area: r_k ≈ 0.03).
    let ratio = number(&h, row, "radius_crossings_ratio");
    assert!(ratio < 0.5, "{ratio}");
    assert!(
        se > 0.0 && se < 0.01 * exact,
        "SE {se} too large to judge a bias"
    );
    assert!(
        (mean - exact).abs() <= 4.0 * se,
        "biased: {mean} ± {se} against {exact}"
    );
    // Counting the k-th crossing too would estimate k/(k − 1) times as much: this test sees that.
    let biased = mean * k / (k - 1.0);
    assert!(
        (biased - exact).abs() > 4.0 * se,
        "the test could not see the k/(k − 1) bias: {biased} ± {se} against {exact}"
    );
    // The per-replica spread matches the estimator's variance λ²/(k − 2) per disc: the RMSE over
    // discs is E/√(k − 2) within 10 %.
    let rmse = number(&h, row, "irradiance_rmse_mean");
    let want = exact / (k - 2.0).sqrt();
    assert!(
        (rmse / want - 1.0).abs() < 0.1,
        "RMSE {rmse} against {want}"
    );
}

#[test]
fn photon_shards_refuse_the_k_nearest_radius() {
    let dir = tempfile::tempdir().unwrap();
    let spec = write_spec(
        dir.path(),
        "shard",
        "[experiment]\nname = \"shard\"\nkind = \"detp\"\n[detp]\nphotons = 1000\npoints = 100\ndisc_radius = 0.1\nradius_crossings = 4\nengines = [\"disc-index\"]\n",
    );
    let out = dir.path().join("out");
    let o = raycost()
        .arg("run")
        .arg(&spec)
        .args(["--out"])
        .arg(&out)
        .args(["--photon-shard", "0/2", "--quiet"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("detp.radius_crossings keeps each disc's k nearest crossings"),
        "{err}"
    );
    assert!(!out.exists() || crate::common::files_below(&out).is_empty());
}

/// With one replica a disc's standard error is the k-nearest estimator's own: a disc that found
/// its k crossings has relative SE 1/√(k − 2) (1 W lines: w̄ = 1 W), a disc that did not the
/// paper's Poisson SE over its whole radius.
#[test]
fn one_replica_standard_errors_are_the_k_nearest_estimators() {
    let dir = tempfile::tempdir().unwrap();
    let spec = write_spec(
        dir.path(),
        "one",
        "[experiment]\nname = \"one\"\nkind = \"detp\"\nseed = 29\n[detp]\nphotons = 20000\npoints = 400\ndisc_radius = 0.03\nradius_crossings = 6\nengines = [\"disc-index\"]\nwrite_points = true\n",
    );
    let out = dir.path().join("out");
    run_quiet(&spec, &out).assert().success();
    let (h, rows) = read_csv(&out.join("one/one.points.csv"));
    let (mut full, mut open) = (0, 0);
    for r in &rows {
        let (e, se, radius) = (
            number(&h, r, "irradiance_mean"),
            number(&h, r, "irradiance_se"),
            number(&h, r, "disc_radius"),
        );
        if radius < 0.03 {
            full += 1;
            assert!(
                (se / e * 2.0 - 1.0).abs() < 1e-6,
                "{se} / {e}: not 1/√(6 − 2)"
            );
        } else if e > 0.0 {
            open += 1;
            // The paper's sum over the whole disc: √(E·w̄/(π d²)).
            let want = (e / (std::f64::consts::PI * 0.03 * 0.03)).sqrt();
            assert!((se / want - 1.0).abs() < 1e-6, "{se} against {want}");
        }
    }
    assert!(full > 50 && open > 10, "{full} full and {open} open discs");
}
