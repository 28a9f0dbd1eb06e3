//! Sharding and `raycost merge`: a sweep run as shards and merged is the table one run
//! writes (measured columns byte for byte), whatever the thread count; bad shards and bad `--shard`
//! values are refused with exit code 2 and nothing written.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{files_below, raycost, root, run_quiet};

/// The small 8-point sweep shared with the Slurm tests.
pub fn sweep_spec() -> PathBuf {
    root().join("tests/specs/slurm-sweep.toml")
}

/// Header and rows of a CSV, as text cells.
pub fn cells(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    crate::common::read_csv(path)
}

/// Asserts that two tables have the same columns and, outside the columns their metadata declares
/// timings, the same cells, byte for byte; returns the number of rows.
pub fn assert_same_measured(a: &Path, b: &Path) -> usize {
    let (ha, ra) = cells(a);
    let (hb, rb) = cells(b);
    assert_eq!(ha, hb, "headers differ: {} vs {}", a.display(), b.display());
    assert_eq!(
        ra.len(),
        rb.len(),
        "row counts differ: {} vs {}",
        a.display(),
        b.display()
    );
    let (ma, mb) = (
        crate::common::measured_columns(a),
        crate::common::measured_columns(b),
    );
    assert!(
        ma.first().is_some_and(|r| r.len() > 10),
        "too few measured columns in {}",
        a.display()
    );
    for (n, (x, y)) in ma.iter().zip(&mb).enumerate() {
        assert_eq!(
            x.len(),
            y.len(),
            "row {n}: the two tables class their columns differently"
        );
        for ((c, u), (_, v)) in x.iter().zip(y) {
            assert_eq!(
                u,
                v,
                "row {n} column {c}: {} has {u}, {} has {v}",
                a.display(),
                b.display()
            );
        }
    }
    ra.len()
}

/// `raycost run SPEC --out OUT --quiet ARGS...`, which must succeed.
pub fn run_ok(spec: &Path, out: &Path, args: &[&str]) {
    run_quiet(spec, out).args(args).assert().success();
}

fn bytes(p: &Path) -> Vec<u8> {
    fs::read(p).unwrap_or_else(|e| panic!("cannot read {}: {e}", p.display()))
}

/// Runs the sweep as `n` shards into `out/slurm-sweep/`.
fn shards(out: &Path, n: usize) -> PathBuf {
    for k in 0..n {
        run_ok(&sweep_spec(), out, &["--shard", &format!("{k}/{n}")]);
    }
    out.join("slurm-sweep")
}

#[test]
fn three_shards_merge_to_the_unsharded_table() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let whole = tmp.path().join("whole");
    run_ok(&sweep_spec(), &whole, &[]);
    let dir = shards(&tmp.path().join("sharded"), 3);
    // Round robin: shard 1 of 3 holds points 1, 4, 7.
    let (_, rows) = cells(&dir.join("slurm-sweep.shard-1-of-3.csv"));
    assert_eq!(
        rows.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(),
        ["1", "4", "7"]
    );

    raycost()
        .arg("merge")
        .arg(&dir)
        .assert()
        .success()
        .stdout(predicates::str::contains("merged 3 shards, 8 points"));
    let w = whole.join("slurm-sweep");
    assert_eq!(
        assert_same_measured(&w.join("slurm-sweep.csv"), &dir.join("slurm-sweep.csv")),
        8
    );
    assert_eq!(
        bytes(&w.join("slurm-sweep.hist.csv")),
        bytes(&dir.join("slurm-sweep.hist.csv")),
        "hist tables differ"
    );

    // The merged metadata: same spec hash as the single run, one entry per shard, all points.
    let meta: toml::Table = fs::read_to_string(dir.join("slurm-sweep.meta.toml"))
        .expect("merged meta")
        .parse()
        .expect("TOML");
    let single: toml::Table = fs::read_to_string(w.join("slurm-sweep.meta.toml"))
        .expect("meta")
        .parse()
        .expect("TOML");
    assert_eq!(meta["run"]["spec_hash"], single["run"]["spec_hash"]);
    assert_eq!(meta["run"]["points_total"].as_integer(), Some(8));
    assert_eq!(meta["spec"], single["spec"]);
    let list = meta["shards"].as_array().expect("[[shards]]");
    assert_eq!(list.len(), 3);
    for (k, s) in list.iter().enumerate() {
        assert_eq!(s["run"]["shard"].as_str(), Some(format!("{k}/3").as_str()));
        assert!(s["machine"].get("host").is_some(), "shard {k}: {s:?}");
        for key in ["threads", "started", "finished", "wall_s", "point_wall_s"] {
            assert!(s["run"].get(key).is_some(), "shard {k} lacks {key}: {s:?}");
        }
    }
    assert_eq!(
        meta["run"]["point_wall_s"].as_array().map(Vec::len),
        Some(8)
    );
    assert!(meta["columns"]["main"].as_array().is_some_and(|c| c
        .iter()
        .any(
            |c| c["name"].as_str() == Some("rays_per_s") && c["class"].as_str() == Some("timing")
        )));

    // Merging again is refused without --force (nothing changes), allowed with it.
    let before = bytes(&dir.join("slurm-sweep.csv"));
    raycost()
        .arg("merge")
        .arg(&dir)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--force"));
    assert_eq!(before, bytes(&dir.join("slurm-sweep.csv")));
    raycost()
        .arg("merge")
        .arg(&dir)
        .arg("--force")
        .arg("--quiet")
        .assert()
        .success()
        .stdout("");
}

#[test]
fn explicit_files_and_out_and_one_shard() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = shards(tmp.path(), 2);
    let files: Vec<PathBuf> = (0..2)
        .map(|k| dir.join(format!("slurm-sweep.shard-{k}-of-2.csv")))
        .collect();
    let out = tmp.path().join("elsewhere/joined.csv");
    raycost()
        .arg("merge")
        .args(files.iter().rev())
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    for f in ["joined.csv", "joined.hist.csv", "joined.meta.toml"] {
        assert!(
            tmp.path().join("elsewhere").join(f).is_file(),
            "{f} not written"
        );
    }
    assert_eq!(cells(&out).1.len(), 8);
    // The same file twice is refused.
    raycost()
        .arg("merge")
        .arg(&files[0])
        .arg(&files[0])
        .arg(&files[1])
        .arg("--out")
        .arg(tmp.path().join("x.csv"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("given twice"));

    // N = 1: a single shard merges into the whole table.
    let one = tmp.path().join("one");
    run_ok(&sweep_spec(), &one, &["--shard", "0/1"]);
    raycost()
        .arg("merge")
        .arg(one.join("slurm-sweep"))
        .assert()
        .success();
    assert_eq!(cells(&one.join("slurm-sweep/slurm-sweep.csv")).1.len(), 8);
}

#[test]
fn thread_count_does_not_change_measured_columns() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (a, b) = (tmp.path().join("t1"), tmp.path().join("t2"));
    run_ok(&sweep_spec(), &a, &["--threads", "1"]);
    run_ok(&sweep_spec(), &b, &["--threads", "2"]);
    let (a, b) = (a.join("slurm-sweep"), b.join("slurm-sweep"));
    assert_eq!(
        assert_same_measured(&a.join("slurm-sweep.csv"), &b.join("slurm-sweep.csv")),
        8
    );
    assert_eq!(
        bytes(&a.join("slurm-sweep.hist.csv")),
        bytes(&b.join("slurm-sweep.hist.csv"))
    );
}

#[test]
fn bad_shard_values_name_the_flag() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for bad in ["3/2", "0/0", "a/b", "2/2", "1", "-1/2"] {
        raycost()
            .arg("run")
            .arg(sweep_spec())
            .arg("--out")
            .arg(tmp.path())
            .arg(format!("--shard={bad}"))
            .assert()
            .code(2)
            .stderr(predicates::str::contains("--shard"));
    }
    assert!(
        files_below(tmp.path()).is_empty(),
        "a refused run wrote {:?}",
        files_below(tmp.path())
    );
}

/// A folder with 3 good shards of the sweep, made once per test (cheap: 8 small points).
fn three_shards(tmp: &Path) -> PathBuf {
    shards(tmp, 3)
}

/// `raycost merge DIR` must fail with exit 2, a message containing every `needles`, and leave the
/// folder exactly as it was.
fn merge_refused(dir: &Path, needles: &[&str]) {
    let before: Vec<(PathBuf, Vec<u8>)> = files_below(dir)
        .into_iter()
        .map(|p| (p.clone(), bytes(&p)))
        .collect();
    let out = raycost().arg("merge").arg(dir).assert().code(2);
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    for n in needles {
        assert!(stderr.contains(n), "stderr lacks {n:?}: {stderr}");
    }
    assert!(stderr.starts_with("error: "), "{stderr}");
    let after: Vec<(PathBuf, Vec<u8>)> = files_below(dir)
        .into_iter()
        .map(|p| (p.clone(), bytes(&p)))
        .collect();
    assert_eq!(before, after, "a refused merge changed the folder");
    assert!(!dir.join("slurm-sweep.csv").exists());
}

#[test]
fn merge_refuses_shards_of_different_specs_or_versions() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = three_shards(tmp.path());
    // Shard 2 again, from the same spec with another seed.
    let other = tmp.path().join("other.toml");
    fs::write(
        &other,
        fs::read_to_string(sweep_spec())
            .expect("spec")
            .replace("seed = 4", "seed = 5"),
    )
    .expect("write spec");
    run_ok(&other, tmp.path(), &["--shard", "2/3", "--force"]);
    merge_refused(
        &dir,
        &[
            "slurm-sweep.shard-2-of-3.meta.toml",
            "spec hash",
            "different specs",
        ],
    );

    let dir = three_shards(&tmp.path().join("v"));
    let meta = dir.join("slurm-sweep.shard-1-of-3.meta.toml");
    let text = fs::read_to_string(&meta).expect("meta");
    fs::write(
        &meta,
        text.replace(
            &format!("version = \"{}\"", env!("CARGO_PKG_VERSION")),
            "version = \"0.0.1\"",
        ),
    )
    .expect("write");
    merge_refused(
        &dir,
        &[
            "slurm-sweep.shard-1-of-3.meta.toml",
            "raycost 0.0.1",
            "version",
        ],
    );
}

#[test]
fn merge_refuses_a_missing_shard_or_point() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = three_shards(tmp.path());
    fs::remove_file(dir.join("slurm-sweep.shard-1-of-3.csv")).expect("rm");
    merge_refused(&dir, &["slurm-sweep.shard-1-of-3.csv", "missing"]);

    // A row deleted from a shard.
    let dir = three_shards(&tmp.path().join("row"));
    let p = dir.join("slurm-sweep.shard-0-of-3.csv");
    let text = fs::read_to_string(&p).expect("csv");
    let kept: Vec<&str> = text.lines().filter(|l| !l.starts_with("3,")).collect();
    fs::write(&p, kept.join("\n") + "\n").expect("write");
    merge_refused(
        &dir,
        &["slurm-sweep.shard-0-of-3.csv", "point 3 is missing"],
    );

    // Shards of two different splits in one folder.
    let dir = three_shards(&tmp.path().join("mixed"));
    run_ok(
        &sweep_spec(),
        &tmp.path().join("mixed"),
        &["--shard", "0/2"],
    );
    merge_refused(&dir, &["shards of different splits"]);
}

#[test]
fn merge_refuses_a_duplicated_point() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = three_shards(tmp.path());
    let p = dir.join("slurm-sweep.shard-2-of-3.csv");
    let text = fs::read_to_string(&p).expect("csv");
    let last = text.lines().last().expect("a row").to_string();
    fs::write(&p, format!("{text}{last}\n")).expect("write");
    merge_refused(
        &dir,
        &[
            "slurm-sweep.shard-2-of-3.csv",
            "line 4",
            "point 5 is duplicated",
        ],
    );

    // A row copied into the wrong shard.
    let dir = three_shards(&tmp.path().join("wrong"));
    let from = fs::read_to_string(dir.join("slurm-sweep.shard-0-of-3.csv")).expect("csv");
    let row = from.lines().nth(1).expect("a row").to_string();
    let p = dir.join("slurm-sweep.shard-1-of-3.csv");
    let text = fs::read_to_string(&p).expect("csv");
    fs::write(&p, format!("{text}{row}\n")).expect("write");
    merge_refused(
        &dir,
        &[
            "slurm-sweep.shard-1-of-3.csv",
            "point 0 does not belong to shard 1/3",
        ],
    );
}

#[test]
fn merge_refuses_torn_lines() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // The last line cut mid-way (a shard killed while writing, then renamed by hand).
    let dir = three_shards(tmp.path());
    let p = dir.join("slurm-sweep.shard-1-of-3.csv");
    let text = bytes(&p);
    fs::write(&p, &text[..text.len() - 7]).expect("write");
    merge_refused(
        &dir,
        &["slurm-sweep.shard-1-of-3.csv", "line 4 is truncated"],
    );

    // A row with too few fields that still ends in a newline.
    let dir = three_shards(&tmp.path().join("fields"));
    let p = dir.join("slurm-sweep.shard-0-of-3.csv");
    let text = fs::read_to_string(&p).expect("csv");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let short: Vec<&str> = lines[2].split(',').take(10).collect();
    lines[2] = short.join(",");
    fs::write(&p, lines.join("\n") + "\n").expect("write");
    merge_refused(
        &dir,
        &["slurm-sweep.shard-0-of-3.csv", "line 3 has 10 fields"],
    );

    // A torn histogram table.
    let dir = three_shards(&tmp.path().join("hist"));
    let p = dir.join("slurm-sweep.shard-2-of-3.hist.csv");
    let text = bytes(&p);
    fs::write(&p, &text[..text.len() - 3]).expect("write");
    merge_refused(&dir, &["slurm-sweep.shard-2-of-3.hist.csv", "truncated"]);
}

#[test]
fn merge_refuses_missing_metadata_and_empty_folders() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = three_shards(tmp.path());
    fs::remove_file(dir.join("slurm-sweep.shard-0-of-3.meta.toml")).expect("rm");
    merge_refused(&dir, &["slurm-sweep.shard-0-of-3.meta.toml", "spec hash"]);

    let empty = tmp.path().join("empty");
    fs::create_dir_all(&empty).expect("mkdir");
    raycost()
        .arg("merge")
        .arg(&empty)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("no shard files"));
    raycost()
        .arg("merge")
        .arg(tmp.path().join("nope"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("no such file"));
    raycost()
        .arg("merge")
        .arg(sweep_spec())
        .assert()
        .code(2)
        .stderr(predicates::str::contains("not a shard table"));
    raycost().arg("merge").assert().code(2);
}
