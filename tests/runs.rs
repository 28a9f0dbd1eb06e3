//! Issue 25's samples a referee accepts: common random numbers (every sweep point on the same
//! lines, photons, points and scenes) and separate runs (`--run R`, `--repeat K`), each with its own
//! seed, written where the claims engine pools them (`OUT/NAME/runs/R/NAME.csv`).

use std::collections::BTreeMap;
use std::path::Path;

use crate::common::{measured_columns, raycost, read_csv, run_quiet, write_spec};

/// Lines through the unit ball gathered by the sphere cache at two Q: Q changes the engine's work,
/// never the lines, the points or the irradiance.
fn detp_q_spec(crn: bool) -> String {
    format!(
        r#"
[experiment]
name = "crn-q"
kind = "detp"
seed = 3
common_random_numbers = {crn}

[detp]
photons = 4000
points = 300
disc_radius = 0.1
replicas = 2
engines = ["sphere-cache"]

[sweep]
"detp.q" = [0.5, 0.7]
"#
    )
}

/// A grid with and without mailboxing: the rays and the scene are the sweep point's, the cell steps
/// are the rays'.
fn grid_mailbox_spec(crn: bool) -> String {
    format!(
        r#"
[experiment]
name = "crn-grid"
kind = "grid"
seed = 5
rays = 3000
common_random_numbers = {crn}

[scene]
intensity = 1.0
radius = 0.2

[grid]
cell_width = 0.5

[sweep]
"grid.mailbox" = [true, false]
"#
    )
}

/// `column` of every row of a main table.
fn column(csv: &Path, column: &str) -> Vec<String> {
    let (h, rows) = read_csv(csv);
    let i = h
        .iter()
        .position(|c| c == column)
        .unwrap_or_else(|| panic!("{} has no column {column}", csv.display()));
    rows.into_iter().map(|r| r[i].clone()).collect()
}

/// Runs `text` as spec NAME into a fresh folder and returns its main table's path.
fn run(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let spec = write_spec(dir, name, text);
    let out = dir.join(format!("out-{name}"));
    run_quiet(&spec, &out).assert().success();
    let table = std::fs::read_dir(&out)
        .expect("the results folder")
        .next()
        .expect("one experiment")
        .expect("an entry")
        .path();
    let stem = table.file_name().unwrap().to_str().unwrap().to_string();
    table.join(format!("{stem}.csv"))
}

#[test]
fn common_random_numbers_give_every_point_the_same_lines_and_points() {
    let tmp = tempfile::tempdir().expect("temp");
    let shared = run(tmp.path(), "shared", &detp_q_spec(true));
    let own = run(tmp.path(), "own", &detp_q_spec(false));
    for c in ["irradiance_mean", "irradiance_rmse_mean", "segments"] {
        let v = column(&shared, c);
        assert_eq!(v[0], v[1], "{c} under common random numbers: {v:?}");
    }
    let v = column(&own, "irradiance_mean");
    assert_ne!(v[0], v[1], "each point draws its own lines without the key");
    // The engine's work still depends on Q: the key shares samples, not results.
    let t = column(&shared, "tests_sphere_cache");
    assert_ne!(t[0], t[1], "{t:?}");
    assert_eq!(
        column(&shared, "experiment.common_random_numbers"),
        ["true", "true"]
    );
    assert_eq!(
        column(&own, "experiment.common_random_numbers"),
        ["false", "false"]
    );
    // Point 0 keeps its own streams: the key changes only the later points.
    assert_eq!(
        column(&shared, "irradiance_mean")[0],
        column(&own, "irradiance_mean")[0]
    );
}

#[test]
fn common_random_numbers_give_every_grid_point_the_same_rays_and_scene() {
    let tmp = tempfile::tempdir().expect("temp");
    let shared = run(tmp.path(), "shared", &grid_mailbox_spec(true));
    let own = run(tmp.path(), "own", &grid_mailbox_spec(false));
    for c in ["n_s_mean", "t_hit_mean", "n_i_mean"] {
        let v = column(&shared, c);
        assert_eq!(v[0], v[1], "{c} under common random numbers: {v:?}");
    }
    let v = column(&own, "n_s_mean");
    assert_ne!(v[0], v[1], "each point draws its own rays without the key");
}

/// The measured cells of a table by column name (the parameter columns' order depends on how
/// `experiment.run` was given; their values do not).
fn by_name(csv: &Path) -> Vec<BTreeMap<String, String>> {
    measured_columns(csv)
        .into_iter()
        .map(|r| r.into_iter().collect())
        .collect()
}

#[test]
fn repeated_runs_are_separate_seeds_each_as_it_runs_alone() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "rep", &detp_q_spec(true));
    let out = tmp.path().join("out");
    run_quiet(&spec, &out)
        .args(["--repeat", "3"])
        .assert()
        .success();
    let run_csv = |root: &Path, r: u64| root.join(format!("crn-q/runs/{r}/crn-q.csv"));
    for r in 0..3 {
        assert!(run_csv(&out, r).exists(), "run {r}");
        assert!(out.join(format!("crn-q/runs/{r}/crn-q.meta.toml")).exists());
        assert_eq!(
            column(&run_csv(&out, r), "experiment.run"),
            vec![r.to_string(); 2]
        );
    }
    assert!(
        !out.join("crn-q/crn-q.csv").exists(),
        "no pooled table is written"
    );
    // Runs are independent samples: new lines each.
    let irr: Vec<String> = (0..3)
        .map(|r| column(&run_csv(&out, r), "irradiance_mean")[0].clone())
        .collect();
    assert!(
        irr[0] != irr[1] && irr[1] != irr[2] && irr[0] != irr[2],
        "{irr:?}"
    );
    // Run 1 alone is run 1 of the repeat.
    let alone = tmp.path().join("alone");
    run_quiet(&spec, &alone)
        .args(["--run", "1"])
        .assert()
        .success();
    assert_eq!(by_name(&run_csv(&alone, 1)), by_name(&run_csv(&out, 1)));
    // Run 0 is the spec run without --run: the seed as given.
    let plain = tmp.path().join("plain");
    run_quiet(&spec, &plain).assert().success();
    assert_eq!(
        by_name(&plain.join("crn-q/crn-q.csv")),
        by_name(&run_csv(&out, 0))
    );
}

#[test]
fn a_run_is_chosen_by_flag_never_by_set() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "rep", &detp_q_spec(false));
    let out = tmp.path().join("out");
    run_quiet(&spec, &out)
        .args(["--set", "experiment.run=2"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--run R"));
    raycost()
        .arg("run")
        .arg(&spec)
        .args(["--run", "1", "--repeat", "2"])
        .assert()
        .code(2);
    assert!(!out.exists(), "nothing written");
}
