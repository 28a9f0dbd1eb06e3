//! The Slurm scripts without a cluster: `sweep.sbatch` run once per array task id and
//! `merge.sbatch` after them, as Slurm would, give the table of one local run; `submit.sh` refuses
//! bad arguments before submitting anything. The real cluster test is `scripts/slurm/ci_test.sh`
//! (run by `.ci/run`).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{raycost, root};
use crate::merge::{assert_same_measured, run_ok, sweep_spec};
use crate::photon_shards::assert_same_but_index_work;

fn script(name: &str) -> PathBuf {
    root().join("scripts/slurm").join(name)
}

fn bash(script: &Path) -> Command {
    let mut c = Command::new("bash");
    c.arg(script);
    // Whatever Slurm environment the test itself runs in must not leak into the scripts.
    for (k, _) in std::env::vars() {
        if k.starts_with("SLURM_") || k.starts_with("SBATCH_") {
            c.env_remove(k);
        }
    }
    c
}

/// `merge.sbatch` for `OUT/NAME`, as the dependent job runs it; it must succeed.
fn merge_job(out: &Path, name: &str) -> std::process::Output {
    let o = bash(&script("merge.sbatch"))
        .env("OUT", out)
        .env("NAME", name)
        .env("RAYCOST", assert_cmd::cargo::cargo_bin("raycost"))
        .output()
        .expect("bash merge.sbatch");
    assert!(
        o.status.success(),
        "merge: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn scripts_parse() {
    for s in [
        "cluster.sh",
        "submit.sh",
        "sweep.sbatch",
        "merge.sbatch",
        "ci_test.sh",
    ] {
        let out = Command::new("bash")
            .arg("-n")
            .arg(script(s))
            .output()
            .expect("bash");
        assert!(
            out.status.success(),
            "{s}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn the_slurm_spec_has_eight_points() {
    let out = raycost().arg("check").arg(sweep_spec()).assert().success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    assert!(text.contains(", 8 point(s),"), "{text}");
}

#[test]
fn array_tasks_then_merge_job_give_the_local_table() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("cluster");
    let bin = assert_cmd::cargo::cargo_bin("raycost");
    for k in 0..4 {
        let o = bash(&script("sweep.sbatch"))
            .env("SPEC", sweep_spec())
            .env("OUT", &out)
            .env("SHARDS", "4")
            .env("RAYCOST", &bin)
            .env("SLURM_ARRAY_TASK_ID", k.to_string())
            .env("SLURM_ARRAY_JOB_ID", "77")
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .expect("bash sweep.sbatch");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "task {k}: {err}");
        assert!(
            err.contains(&format!("job=77_{k}"))
                && err.contains(&format!("end shard={k}/4 exit=0")),
            "task {k} log: {err}"
        );
    }
    let o = merge_job(&out, "slurm-sweep");
    assert!(String::from_utf8_lossy(&o.stdout).contains("merged 4 shards, 8 points"));

    let local = tmp.path().join("local");
    run_ok(&sweep_spec(), &local, &[]);
    let (m, l) = (out.join("slurm-sweep"), local.join("slurm-sweep"));
    assert_eq!(
        assert_same_measured(&m.join("slurm-sweep.csv"), &l.join("slurm-sweep.csv")),
        8
    );
    assert_eq!(
        std::fs::read(m.join("slurm-sweep.hist.csv")).expect("hist"),
        std::fs::read(l.join("slurm-sweep.hist.csv")).expect("hist")
    );
    let meta = std::fs::read_to_string(m.join("slurm-sweep.shard-2-of-4.meta.toml")).expect("meta");
    assert!(
        meta.contains("threads = 1"),
        "SLURM_CPUS_PER_TASK did not set --threads: {meta}"
    );

    // A task that fails (here: its shard exists already) fails the array task with raycost's code.
    let o = bash(&script("sweep.sbatch"))
        .env("SPEC", sweep_spec())
        .env("OUT", &out)
        .env("SHARDS", "4")
        .env("RAYCOST", &bin)
        .env("SLURM_ARRAY_TASK_ID", "1")
        .output()
        .expect("bash sweep.sbatch");
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("exit=2"));
    // Resubmitted with --resume (as after a time limit), a finished shard is left alone.
    let before = std::fs::read(m.join("slurm-sweep.shard-1-of-4.csv")).expect("shard");
    let o = bash(&script("sweep.sbatch"))
        .env("SPEC", sweep_spec())
        .env("OUT", &out)
        .env("SHARDS", "4")
        .env("NAME", "slurm-sweep")
        .env("RAYCOST", &bin)
        .env("RAYCOST_ARGS", "--resume")
        .env("SLURM_ARRAY_TASK_ID", "1")
        .output()
        .expect("bash sweep.sbatch");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("finished already"));
    assert_eq!(
        before,
        std::fs::read(m.join("slurm-sweep.shard-1-of-4.csv")).expect("shard")
    );
}

/// `spec` (experiment `name`) as 3 photon-shard array tasks run in the order 2, 0, 1 and the merge
/// job, and as a local unsplit run: the merged and the local results folders.
fn photon_array(tmp: &Path, spec: &Path, name: &str) -> (PathBuf, PathBuf) {
    let out = tmp.join("cluster");
    let bin = assert_cmd::cargo::cargo_bin("raycost");
    for k in [2, 0, 1] {
        let o = bash(&script("sweep.sbatch"))
            .env("SPEC", spec)
            .env("OUT", &out)
            .env("SHARDS", "3")
            .env("SPLIT", "photons")
            .env("RAYCOST", &bin)
            .env("SLURM_ARRAY_TASK_ID", k.to_string())
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .expect("bash sweep.sbatch");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "task {k}: {err}");
        assert!(err.contains("split=photons"), "task {k} log: {err}");
    }
    merge_job(&out, name);
    let local = tmp.join("local");
    run_ok(spec, &local, &[]);
    (out.join(name), local.join(name))
}

#[test]
fn photon_shard_array_tasks_then_merge_job_give_the_unsplit_table() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = root().join("tests/specs/slurm-photons.toml");
    let (m, l) = photon_array(tmp.path(), &spec, "slurm-photons");
    assert_eq!(
        assert_same_measured(&m.join("slurm-photons.csv"), &l.join("slurm-photons.csv")),
        2
    );
    let points = |d: &Path| crate::common::measured_columns(&d.join("slurm-photons.points.csv"));
    assert_eq!(points(&m), points(&l));
    // SPLIT must be one of the two.
    let o = bash(&script("sweep.sbatch"))
        .env("SPEC", &spec)
        .env("OUT", tmp.path().join("cluster"))
        .env("SHARDS", "3")
        .env("SPLIT", "rays")
        .env("SLURM_ARRAY_TASK_ID", "0")
        .output()
        .expect("bash sweep.sbatch");
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn quasi_static_photon_shard_array_gives_the_unsplit_tables() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = root().join("tests/specs/slurm-photons-qs.toml");
    let name = "slurm-photons-qs";
    let (m, l) = photon_array(tmp.path(), &spec, name);
    let t = |d: &Path, t: &str| d.join(format!("{name}{t}.csv"));
    assert_eq!(assert_same_but_index_work(&t(&l, ""), &t(&m, "")), 2);
    assert_eq!(
        assert_same_but_index_work(&t(&l, ".frames"), &t(&m, ".frames")),
        16
    );
    let points = |d: &Path| crate::common::measured_columns(&t(d, ".points"));
    assert_eq!(points(&m), points(&l));
}

#[test]
fn submit_refuses_bad_arguments_before_submitting() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for (args, needle) in [
        (
            vec![
                sweep_spec().display().to_string(),
                "0".into(),
                tmp.path().display().to_string(),
            ],
            "SHARDS must be a positive integer",
        ),
        (
            vec![
                sweep_spec().display().to_string(),
                "x".into(),
                tmp.path().display().to_string(),
            ],
            "SHARDS must be a positive integer",
        ),
        (
            vec![
                tmp.path().join("nope.toml").display().to_string(),
                "4".into(),
                tmp.path().display().to_string(),
            ],
            "no such file",
        ),
        (vec!["only-one".into()], "usage"),
    ] {
        let o = bash(&script("submit.sh"))
            .args(&args)
            .output()
            .expect("bash submit.sh");
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(needle),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// `submit.sh --check` (no Slurm needed) lists the shards whose file is missing — photon shards
/// and point shards — with exit 1, and exit 0 once the set is complete; the merge of the
/// incomplete photon set names the missing shard and writes nothing.
#[test]
fn submit_check_lists_the_missing_shards() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("cluster");
    let bin = assert_cmd::cargo::cargo_bin("raycost");
    let check = |spec: &Path, photons: bool, n: &str| {
        let mut c = bash(&script("submit.sh"));
        c.env("RAYCOST", &bin).arg("--check");
        if photons {
            c.arg("--photons");
        }
        let o = c.arg(spec).arg(n).arg(&out).output().expect("submit.sh");
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stdout).trim().to_string(),
        )
    };
    let photons = root().join("tests/specs/slurm-photons.toml");
    for k in [0, 2] {
        run_ok(&photons, &out, &["--photon-shard", &format!("{k}/3")]);
    }
    assert_eq!(check(&photons, true, "3"), (Some(1), "MISSING=1".into()));
    let dir = out.join("slurm-photons");
    let before = crate::common::files_below(&dir);
    crate::common::raycost()
        .arg("merge")
        .arg(&dir)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("photon shard(s) 1 of 3 missing"))
        .stderr(predicates::str::contains(
            "slurm-photons.photon-shard-K-of-3.json",
        ));
    assert_eq!(
        crate::common::files_below(&dir),
        before,
        "a refused merge wrote something"
    );
    run_ok(&photons, &out, &["--photon-shard", "1/3"]);
    assert_eq!(check(&photons, true, "3"), (Some(0), "MISSING=".into()));

    let sweep = sweep_spec();
    for k in [0, 3] {
        run_ok(&sweep, &out, &["--shard", &format!("{k}/4")]);
    }
    assert_eq!(check(&sweep, false, "4"), (Some(1), "MISSING=1,2".into()));
    crate::common::raycost()
        .arg("merge")
        .arg(out.join("slurm-sweep"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("shards 1, 2 of 4 are missing"));
}
