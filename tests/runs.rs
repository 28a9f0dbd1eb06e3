//! Samples a referee accepts: common random numbers (every sweep point on the same
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

/// The §4.1 predictor on the Cornell box's centre sphere, each replica timing both engines warm.
fn predictor_spec(warm_repeats: u64, predict: bool) -> String {
    let scene = crate::common::root().join("experiments/scenes/cornell-centre.toml");
    let engine = if predict { "predicted" } else { "sphere-cache" };
    format!(
        r#"
[experiment]
name = "warm"
kind = "quasi-static"
seed = 2

[detp]
source = "scene"
scene = "{}"
photons = 3000
point_spacing = 40.0
disc_radius = 20.0
engine = "{engine}"
replicas = 3

[dynamic]
frames = 2
ratio = 0.2
warm_repeats = {warm_repeats}
"#,
        scene.display()
    )
}

#[test]
fn the_predictor_writes_every_replicas_pick_and_warm_timings_of_both_engines() {
    let tmp = tempfile::tempdir().expect("temp");
    let csv = run(tmp.path(), "warm", &predictor_spec(4, true));
    for r in 0..3 {
        let pick = column(&csv, &format!("pick_replica_{r}"));
        assert!(
            pick[0] == "sphere-cache" || pick[0] == "disc-index",
            "{pick:?}"
        );
    }
    for e in ["sphere_cache", "disc_index"] {
        assert_eq!(column(&csv, &format!("warm_{e}_s_n")), ["12"]);
        assert_eq!(column(&csv, &format!("warm_{e}_s_clusters")), ["3"]);
        let s: f64 = column(&csv, &format!("warm_{e}_s_mean"))[0]
            .parse()
            .unwrap();
        assert!(s > 0.0 && s.is_finite(), "{e}: {s}");
    }
    // Each replica's static index build, on its frame 0 row only.
    let frames = csv.with_file_name("warm.frames.csv");
    let frame = column(&frames, "frame");
    let build = column(&frames, "static_index_build_s");
    assert_eq!(frame.iter().filter(|f| *f == "0").count(), 3);
    for (f, b) in frame.iter().zip(&build) {
        let b: f64 = b.parse().unwrap();
        assert_eq!(f == "0", b.is_finite() && b >= 0.0, "frame {f}: {b}");
    }
}

#[test]
fn the_points_table_gives_each_points_distance_to_an_edge() {
    let tmp = tempfile::tempdir().expect("temp");
    let scene = crate::common::root().join("experiments/scenes/cornell.toml");
    let d = 15.0;
    let text = format!(
        r#"
[experiment]
name = "edges"
kind = "detp"
seed = 2

[detp]
source = "scene"
scene = "{}"
photons = 2000
point_spacing = 40.0
disc_radius = {d}
write_points = true
"#,
        scene.display()
    );
    let csv = run(tmp.path(), "edges", &text);
    let s: Vec<f64> = column(&csv.with_file_name("edges.points.csv"), "edge_distance")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(s.iter().all(|&x| (0.0..=2.0 * d).contains(&x)), "{s:?}");
    // The box's corners and edges are near some points, its wall centres far from any.
    assert!(s.iter().any(|&x| x < d) && s.contains(&(2.0 * d)), "{s:?}");
}

#[test]
fn warm_timings_need_the_predictor() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "warm", &predictor_spec(4, false));
    let out = tmp.path().join("out");
    run_quiet(&spec, &out)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("dynamic.warm_repeats"));
    assert!(!out.exists(), "nothing written");
}

/// The number after `label` in `text` (a float as Rust prints it: exact).
fn number_after(text: &str, label: &str) -> String {
    let rest = &text[text
        .find(label)
        .unwrap_or_else(|| panic!("{label} in {text}"))
        + label.len()..];
    rest.chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | '-'))
        .collect()
}

#[test]
fn lengths_in_units_of_the_scenes_radius_are_the_scaled_lengths() {
    let tmp = tempfile::tempdir().expect("temp");
    let scene = crate::common::root().join("experiments/scenes/cornell.toml");
    let spec = |unit: &str, spacing: &str, d: &str| {
        format!(
            r#"
[experiment]
name = "units"
kind = "detp"
seed = 2

[detp]
source = "scene"
scene = "{}"
photons = 2000
length_unit = "{unit}"
point_spacing = {spacing}
disc_radius = {d}
"#,
            scene.display()
        )
    };
    let relative = write_spec(tmp.path(), "relative", &spec("root", "0.1", "0.03"));
    let out = raycost()
        .arg("check")
        .arg(&relative)
        .output()
        .expect("check");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let (s, d) = (
        number_after(&text, "at spacing "),
        number_after(&text, "d = "),
    );
    let (sv, dv): (f64, f64) = (s.parse().unwrap(), d.parse().unwrap());
    // The Cornell box is hundreds of units across: r_s scales both lengths alike.
    assert!(sv > 10.0 && (sv / dv - 0.1 / 0.03).abs() < 1e-9, "{s} {d}");
    let a = run(tmp.path(), "root", &spec("root", "0.1", "0.03"));
    let b = run(tmp.path(), "scene", &spec("scene", &s, &d));
    for c in ["points", "irradiance_mean", "tests_sphere_cache"] {
        assert_eq!(column(&a, c), column(&b, c), "{c}");
    }
    // Each table states the unit its lengths are in: r_s where the spec wrote them in root units,
    // the scene's length where it wrote them in the scene's; the same d in each.
    for (table, lengths, d) in [(&a, "r_s", "0.03"), (&b, "length", d.as_str())] {
        let unit = declared_units(table);
        for c in ["detp.disc_radius", "detp.point_spacing", "disc_radius_used"] {
            assert_eq!(unit(c), lengths, "{c} in {}", table.display());
        }
        assert_eq!(unit("detp.photons"), "photons");
        assert_eq!(unit("detp.q"), "");
        assert_eq!(unit("disc_radius_used_root"), "r_s");
        let d: f64 = d.parse().expect("d");
        for c in ["detp.disc_radius", "disc_radius_used"] {
            let v: f64 = column(table, c)[0].parse().expect("a number");
            assert!((v / d - 1.0).abs() < 1e-12, "{c}: {v} against {d}");
        }
    }
}

/// Column name → the unit `csv`'s metadata declares for it in the main table.
fn declared_units(csv: &Path) -> impl Fn(&str) -> String {
    let meta = raycost::output::meta::Meta::read(&csv.with_extension("meta.toml")).expect("meta");
    let main = meta.columns.get("main").expect("main columns").clone();
    move |name| {
        main.iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no column {name}"))
            .unit
            .clone()
    }
}
