//! `--photon-shard K/N`: one run's photons split over N shards, run in any order,
//! merged by `raycost merge` into the table the unsplit run writes, every measured column (main
//! table and side tables) equal bit for bit — for kind `detp`, and for kind `quasi-static` frame by
//! frame, where only the segment index's own work (summed over the shards' indexes) is set apart
//! as timing; incomplete or mixed shard sets, kinds without photons and engines whose counts do not
//! add are refused with exit code 2 and nothing written.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{
    files_below, measured_columns, raycost, read_csv, root, run_quiet, write_spec,
};
use crate::merge::assert_same_measured;

/// Photons from the Cornell box onto its surface points, two replicas, a two-point sweep, every
/// engine whose counts add (and the reference, computed by the merge).
pub fn scene_spec(dir: &Path) -> PathBuf {
    let scene = root().join("experiments/scenes/cornell.toml");
    write_spec(
        dir,
        "ps-scene",
        &format!(
            r#"[experiment]
name = "ps-scene"
kind = "detp"
seed = 11

[detp]
source = "scene"
scene = "{}"
photons = 6001
point_spacing = 90.0
disc_radius = 25.0
engines = ["disc-index", "brute-force", "reference"]
reference_samples = 16
replicas = 2
edge = "first-hit"
write_points = true

[sweep]
"detp.disc_radius" = [25.0, 40.0]
"detp.index" = ["grid", "octree"]
"#,
            scene.display().to_string().replace('\\', "/")
        ),
    )
}

/// μ-random lines (keyed by batches of 4096 lines, which the shards cut) with the brute-force check
/// on a keyed subset of discs.
fn lines_spec(dir: &Path) -> PathBuf {
    write_spec(
        dir,
        "ps-lines",
        r#"[experiment]
name = "ps-lines"
kind = "detp"
seed = 4

[detp]
photons = 10_000
points = 400
disc_radius = 0.05
engines = ["disc-index"]
brute_force_points = 50
write_points = true
"#,
    )
}

/// Runs `spec` unsplit into `whole`, as `n` photon shards in the order `order` into `split`, merges
/// them, and compares every table's measured columns.
fn split_equals_whole(spec: &Path, name: &str, n: usize, order: &[usize]) {
    let tmp = tempfile::tempdir().unwrap();
    let (whole, split) = (tmp.path().join("whole"), tmp.path().join("split"));
    run_quiet(spec, &whole).assert().success();
    for &k in order {
        run_quiet(spec, &split)
            .args(["--threads", "1", "--photon-shard", &format!("{k}/{n}")])
            .assert()
            .success();
    }
    let dir = split.join(name);
    assert!(
        !dir.join(format!("{name}.csv")).exists(),
        "a photon shard writes no table"
    );
    raycost()
        .args(["merge", "--quiet"])
        .arg(&dir)
        .assert()
        .success();
    let rows = assert_same_measured(
        &whole.join(name).join(format!("{name}.csv")),
        &dir.join(format!("{name}.csv")),
    );
    assert!(rows >= 1);
    let points = |d: &Path| measured_columns(&d.join(format!("{name}.points.csv")));
    let (a, b) = (points(&whole.join(name)), points(&dir));
    assert!(a.len() > 100, "the points table holds every disc");
    assert_eq!(a, b, "{name}.points.csv differs");
}

#[test]
fn photon_shards_of_a_scene_merge_into_the_unsplit_table() {
    let tmp = tempfile::tempdir().unwrap();
    split_equals_whole(&scene_spec(tmp.path()), "ps-scene", 3, &[2, 0, 1]);
}

#[test]
fn photon_shards_of_lines_merge_into_the_unsplit_table() {
    let tmp = tempfile::tempdir().unwrap();
    split_equals_whole(&lines_spec(tmp.path()), "ps-lines", 3, &[1, 2, 0]);
}

/// A sphere and a box moving through the Cornell box over 4 frames, every frame checked against a
/// full recalculation, two replicas, the points table at frame 2; the dynamic points by the disc
/// index, fed every segment (the paper's model) or the segment index's answer. `extra`: more
/// `[dynamic]` lines, `engine`: `detp.engine`.
pub fn quasi_static_spec(dir: &Path, name: &str, engine: &str, extra: &str) -> PathBuf {
    let scene = root().join("experiments/scenes/cornell-dynamic.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "quasi-static"
seed = 7

[detp]
source = "scene"
scene = "{}"
photons = 3001
point_spacing = 60.0
disc_radius = 20.0
engine = "{engine}"
replicas = 2
write_points = true

[dynamic]
frames = 4
check_every = 1
points_frame = 2
{extra}
[sweep]
"dynamic.feed" = ["paper", "segment-index"]
"#,
            scene.display().to_string().replace('\\', "/")
        ),
    )
}

/// The stems of the columns that count the segment index's work: a photon shard searches an index
/// of its own segments, so a merged table sums them and classes them timing.
const INDEX_WORK: &[&str] = &[
    "search_cells",
    "search_tests",
    "search_listings",
    "dynamic_feed",
];

/// `whole` and `merged` (the same table of an unsplit and a merged run) have the same header and
/// rows, and the same cells in every column the merged run's metadata calls reproducible; the
/// columns it does not, beyond the unsplit run's timings, are exactly the index's work. Returns
/// the rows.
pub fn assert_same_but_index_work(whole: &Path, merged: &Path) -> usize {
    assert_eq!(
        read_csv(whole).0,
        read_csv(merged).0,
        "{}: headers",
        merged.display()
    );
    let (w, m) = (measured_columns(whole), measured_columns(merged));
    assert_eq!(w.len(), m.len(), "{}: rows", merged.display());
    for (n, (a, b)) in w.iter().zip(&m).enumerate() {
        let kept: Vec<&(String, String)> = a
            .iter()
            .filter(|(c, _)| b.iter().any(|(d, _)| d == c))
            .collect();
        assert_eq!(
            kept.len(),
            b.len(),
            "row {n}: merged columns the unsplit run times"
        );
        for ((c, u), (_, v)) in kept.into_iter().zip(b) {
            assert_eq!(
                u,
                v,
                "{} row {n} column {c}: unsplit {u}, merged {v}",
                merged.display()
            );
        }
        let demoted: Vec<&String> = a
            .iter()
            .map(|(c, _)| c)
            .filter(|c| !b.iter().any(|(d, _)| d == *c))
            .collect();
        assert!(
            !demoted.is_empty(),
            "row {n}: the index's work is not set apart"
        );
        for c in demoted {
            assert!(
                INDEX_WORK.iter().any(|s| c.starts_with(s)),
                "row {n}: column {c} is not the index's work but differs in class"
            );
        }
    }
    w.len()
}

#[test]
fn photon_shards_of_moving_objects_merge_into_the_unsplit_tables() {
    let tmp = tempfile::tempdir().unwrap();
    let name = "ps-moving";
    let spec = quasi_static_spec(tmp.path(), name, "disc-index", "");
    let (whole, split) = (tmp.path().join("whole"), tmp.path().join("split"));
    run_quiet(&spec, &whole).assert().success();
    for k in [2, 0, 1] {
        run_quiet(&spec, &split)
            .args(["--threads", "1", "--photon-shard", &format!("{k}/3")])
            .assert()
            .success();
    }
    let dir = split.join(name);
    raycost()
        .args(["merge", "--quiet"])
        .arg(&dir)
        .assert()
        .success();
    let table = |d: &Path, t: &str| d.join(name).join(format!("{name}{t}.csv"));
    assert_eq!(
        assert_same_but_index_work(&table(&whole, ""), &table(&split, "")),
        2
    );
    // Every frame of both replicas of both points, and objects that did move: photons re-traced.
    let frames = table(&whole, ".frames");
    assert_eq!(
        assert_same_but_index_work(&frames, &table(&split, ".frames")),
        16
    );
    let (h, rows) = read_csv(&frames);
    let at = |c: &str| h.iter().position(|x| x == c).unwrap();
    let retraced: u64 = rows
        .iter()
        .filter(|r| r[at("frame")] != "0")
        .map(|r| r[at("photons_retraced")].parse::<u64>().unwrap())
        .sum();
    assert!(retraced > 0, "no photon was re-traced: the test is vacuous");
    assert!(rows
        .iter()
        .all(|r| ["NaN", "0"].contains(&r[at("full_mismatch")].as_str())));
    let points = |d: &Path| measured_columns(&table(d, ".points"));
    let (a, b) = (points(&whole), points(&split));
    assert!(a.len() > 100, "the points table holds every point");
    assert_eq!(a, b, "{name}.points.csv differs");
}

/// `raycost merge DIR` fails with exit 2, saying `what`, and writes no table.
fn merge_refused(dir: &Path, what: &str) {
    let before = files_below(dir);
    let out = raycost().arg("merge").arg(dir).assert().code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains(what), "expected {what:?} in: {err}");
    assert_eq!(files_below(dir), before, "a refused merge wrote something");
}

#[test]
fn incomplete_or_mixed_photon_shards_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = lines_spec(tmp.path());
    let out = tmp.path().join("out");
    let dir = out.join("ps-lines");
    for k in [0, 2] {
        run_quiet(&spec, &out)
            .args(["--photon-shard", &format!("{k}/3")])
            .assert()
            .success();
    }
    merge_refused(&dir, "photon shard(s) 1 of 3 missing");
    // Shard 1 with another seed: the set is complete but mixed.
    run_quiet(&spec, &out)
        .args(["--photon-shard", "1/3", "--set", "experiment.seed=5"])
        .assert()
        .success();
    merge_refused(&dir, "seed");
    run_quiet(&spec, &out)
        .args(["--photon-shard", "1/3", "--force"])
        .assert()
        .success();
    // A shard of another split beside them.
    run_quiet(&spec, &out)
        .args(["--photon-shard", "1/4"])
        .assert()
        .success();
    merge_refused(&dir, "shard count N");
    // A file renamed to another shard's name.
    let other = dir.join("ps-lines.photon-shard-1-of-4.json");
    fs::rename(&other, dir.join("ps-lines.photon-shard-3-of-3.json")).unwrap();
    merge_refused(&dir, "is named as shard 3 of 3 but holds shard 1 of 4");
    fs::remove_file(dir.join("ps-lines.photon-shard-3-of-3.json")).unwrap();
    // The spec edited since the shards ran.
    let text = fs::read_to_string(&spec).unwrap();
    fs::write(&spec, text.replace("points = 400", "points = 401")).unwrap();
    merge_refused(&dir, "changed since the photon shards ran");
    fs::write(&spec, text).unwrap();
    raycost()
        .args(["merge", "--quiet"])
        .arg(&dir)
        .assert()
        .success();
}

/// `raycost run SPEC --photon-shard 0/2` fails with exit 2 naming `what`, writing nothing.
fn shard_refused(spec: &Path, what: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let out = run_quiet(spec, tmp.path())
        .args(["--photon-shard", "0/2"])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains(what), "expected {what:?} in: {err}");
    assert!(files_below(tmp.path()).is_empty(), "a refused shard wrote");
}

#[test]
fn kinds_and_engines_whose_counts_do_not_add_are_refused() {
    shard_refused(
        &root().join("tests/specs/slurm-sweep.toml"),
        "kind grid has no photons to split",
    );
    let tmp = tempfile::tempdir().unwrap();
    let text = fs::read_to_string(lines_spec(tmp.path())).unwrap();
    let cache = write_spec(
        tmp.path(),
        "ps-cache",
        &text.replace(r#"["disc-index"]"#, r#"["sphere-cache", "disc-index"]"#),
    );
    shard_refused(&cache, "detp.engines has sphere-cache");
    // Quasi-static: only the disc index's counts add; the predictor and the reference run need
    // every photon.
    for (engine, extra, what) in [
        ("hybrid", "", r#"detp.engine is "hybrid""#),
        ("sphere-cache", "", r#"detp.engine is "sphere-cache""#),
        ("predicted", "", r#"detp.engine is "predicted""#),
        ("disc-index", "predict = 0.1\n", "dynamic.predict"),
        (
            "disc-index",
            "reference_photons = 100\n",
            "dynamic.reference_photons",
        ),
    ] {
        let qs = quasi_static_spec(tmp.path(), "ps-qs", engine, extra);
        shard_refused(&qs, what);
    }
    // Path tracing runs in each replica's posed scene, which no merge holds.
    let qs = quasi_static_spec(tmp.path(), "ps-qs", "disc-index", "");
    let text = fs::read_to_string(&qs).unwrap().replace(
        "engine = \"disc-index\"",
        "engine = \"disc-index\"\nengines = [\"sphere-cache\", \"path-tracing\"]",
    );
    fs::write(&qs, text).unwrap();
    shard_refused(&qs, r#"detp.engines has "path-tracing""#);
    let qs = quasi_static_spec(tmp.path(), "ps-qs", "hybrid", "");
    // With --shard: clap refuses the pair (usage, exit 2).
    let out = run_quiet(&qs, tmp.path())
        .args(["--photon-shard", "0/2", "--shard", "0/2"])
        .assert()
        .code(2);
    assert!(String::from_utf8_lossy(&out.get_output().stderr).contains("--shard"));
}
