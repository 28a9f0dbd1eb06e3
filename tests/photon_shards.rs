//! `--photon-shard K/N` (issue 29 item 5): one run's photons split over N shards, run in any order,
//! merged by `raycost merge` into the table the unsplit run writes, every measured column (main
//! table and side tables) equal bit for bit; incomplete or mixed shard sets, kinds without photons
//! and engines whose counts do not add are refused with exit code 2 and nothing written.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{files_below, measured_columns, raycost, root, run_quiet, write_spec};
use crate::merge::assert_same_measured;

/// Photons from the Cornell box onto its surface points, two replicas, a two-point sweep, every
/// engine whose counts add (and the reference, computed by the merge).
fn scene_spec(dir: &Path) -> PathBuf {
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
    let scene = root().join("experiments/scenes/cornell-dynamic.toml");
    let qs = write_spec(
        tmp.path(),
        "ps-qs",
        &format!(
            "[experiment]\nname = \"ps-qs\"\nkind = \"quasi-static\"\nseed = 1\n\n[detp]\nsource = \"scene\"\nscene = \"{}\"\nphotons = 1000\npoint_spacing = 60.0\ndisc_radius = 20.0\n\n[dynamic]\nframes = 3\n",
            scene.display().to_string().replace('\\', "/")
        ),
    );
    shard_refused(&qs, "kind quasi-static cannot split its photons");
    // With --shard: clap refuses the pair (usage, exit 2).
    let out = run_quiet(&qs, tmp.path())
        .args(["--photon-shard", "0/2", "--shard", "0/2"])
        .assert()
        .code(2);
    assert!(String::from_utf8_lossy(&out.get_output().stderr).contains("--shard"));
}
