//! Kind `detp` through the runner: sharded and merged, or killed and resumed, it writes the tables
//! one uninterrupted run writes (main, `levels` and `points`, outside timing columns byte for byte),
//! whatever the thread count.

use std::fs;
use std::path::Path;

use crate::common::{files_below, raycost, write_spec};
use crate::merge::{assert_same_measured, run_ok};
use crate::resume::interrupt;

/// Four points (Q × order), lines through the ball, both engines and brute force on a subset.
const SPEC: &str = r#"
[experiment]
name = "detp-small"
kind = "detp"
seed = 5

[detp]
photons = 20_000
points = 2_000
disc_radius = "spacing"
engines = ["sphere-cache", "disc-index"]
brute_force_points = 100
replicas = 2
chunk_points = 500
write_points = true

[sweep]
"detp.q" = [0.5, 0.8]
"detp.order" = ["morton", "hilbert"]
"#;

fn same_side_tables(a: &Path, b: &Path, stem: &str) {
    for t in ["levels", "points"] {
        let (x, y) = (
            a.join(format!("{stem}.{t}.csv")),
            b.join(format!("{stem}.{t}.csv")),
        );
        assert_eq!(
            fs::read(&x).unwrap_or_else(|e| panic!("{}: {e}", x.display())),
            fs::read(&y).unwrap_or_else(|e| panic!("{}: {e}", y.display())),
            "{t} tables differ"
        );
    }
}

#[test]
fn detp_shards_on_one_thread_merge_into_the_two_thread_table() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = write_spec(tmp.path(), "detp-small", SPEC);
    let whole = tmp.path().join("whole");
    run_ok(&spec, &whole, &["--threads", "2"]);
    let sharded = tmp.path().join("sharded");
    for k in 0..3 {
        run_ok(
            &spec,
            &sharded,
            &["--shard", &format!("{k}/3"), "--threads", "1"],
        );
    }
    raycost()
        .arg("merge")
        .arg(sharded.join("detp-small"))
        .arg("--quiet")
        .assert()
        .success();
    let (w, s) = (whole.join("detp-small"), sharded.join("detp-small"));
    assert_eq!(
        assert_same_measured(&w.join("detp-small.csv"), &s.join("detp-small.csv")),
        4
    );
    same_side_tables(&w, &s, "detp-small");
    let (h, rows) = crate::common::read_csv(&w.join("detp-small.csv"));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    for r in &rows {
        assert_eq!(r[at("mismatches")], "0", "engines agree with brute force");
        assert_eq!(r[at("bf_checked")], "200");
    }
    // Two replicas: every point's value in each replica, whose mean is the pooled value (so a mean
    // error over a group of points can take its SE across replicas).
    let (h, rows) = crate::common::read_csv(&w.join("detp-small.points.csv"));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    assert!(!h.iter().any(|c| c == "irradiance_replica_2"));
    for r in &rows {
        let v = |c: &str| r[at(c)].parse::<f64>().unwrap();
        let mean = (v("irradiance_replica_0") + v("irradiance_replica_1")) / 2.0;
        assert!(
            (mean - v("irradiance_mean")).abs() <= 1e-9 * mean.abs().max(1e-300),
            "{mean} vs {}",
            v("irradiance_mean")
        );
    }
}

#[test]
fn a_killed_detp_run_resumes_into_the_uninterrupted_table() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // 16 points of about a tenth of a second: the name is the one `interrupt` watches.
    let text = SPEC
        .replace("detp-small", "resume-me")
        .replace(
            "\"detp.q\" = [0.5, 0.8]",
            "\"detp.q\" = [0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9]",
        )
        .replace(
            "\"detp.order\" = [\"morton\", \"hilbert\"]",
            "\"detp.order\" = [\"none\", \"hilbert\"]",
        );
    let spec = write_spec(tmp.path(), "resume-me", &text);
    let whole = tmp.path().join("whole");
    run_ok(&spec, &whole, &[]);
    let out = tmp.path().join("killed");
    interrupt(&spec, &out, "-KILL");
    run_ok(&spec, &out, &["--resume"]);
    let (w, k) = (whole.join("resume-me"), out.join("resume-me"));
    assert_eq!(
        assert_same_measured(&w.join("resume-me.csv"), &k.join("resume-me.csv")),
        16
    );
    same_side_tables(&w, &k, "resume-me");
    assert!(files_below(&k)
        .iter()
        .all(|p| !p.to_string_lossy().ends_with(".partial")));
}
