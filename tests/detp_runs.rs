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

/// The disc index's walk alone (eq. 8 in seconds): `traversal_disc_index_per_replica_s` beside
/// `cost_disc_index_per_replica_s`, positive with one sample per replica, in the disc index's
/// columns only, classed timing.
fn traversal_is_timed_per_replica(csv: &Path, replicas: usize) {
    let (h, rows) = crate::common::read_csv(csv);
    let at = |c: &str| {
        h.iter()
            .position(|x| x == c)
            .unwrap_or_else(|| panic!("{c}"))
    };
    let family = "traversal_disc_index_per_replica_s";
    for r in &rows {
        let v = |c: &str| r[at(&format!("{family}_{c}"))].parse::<f64>().unwrap();
        assert!(v("mean").is_finite() && v("mean") > 0.0, "{}", v("mean"));
        assert!(v("se").is_finite() && v("se") >= 0.0, "{}", v("se"));
        assert_eq!((v("n"), v("clusters")), (replicas as f64, replicas as f64));
    }
    assert!(!h.iter().any(|c| c.starts_with("traversal_sphere_cache")));
    let meta = raycost::output::meta::Meta::read(&csv.with_extension("meta.toml"))
        .expect("the run's metadata");
    let class = |name: &str| {
        meta.columns["main"]
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("{name}"))
            .class
            .as_str()
            .to_string()
    };
    assert_eq!(class(&format!("{family}_mean")), "timing");
}

/// Without the disc index there is no walk to time: the family is not written.
#[test]
fn without_the_disc_index_no_traversal_is_written() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let text = SPEC
        .replace(
            r#"engines = ["sphere-cache", "disc-index"]"#,
            r#"engines = ["sphere-cache"]"#,
        )
        .replace("photons = 20_000", "photons = 2_000")
        .replace("points = 2_000", "points = 200")
        .replace("chunk_points = 500", "chunk_points = 100");
    let spec = write_spec(tmp.path(), "detp-small", &text);
    let out = tmp.path().join("out");
    run_ok(&spec, &out, &[]);
    let (h, _) = crate::common::read_csv(&out.join("detp-small/detp-small.csv"));
    assert!(h
        .iter()
        .any(|c| c == "cost_sphere_cache_per_replica_s_mean"));
    assert!(!h.iter().any(|c| c.starts_with("traversal_")), "{h:?}");
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
    traversal_is_timed_per_replica(&w.join("detp-small.csv"), 2);
    traversal_is_timed_per_replica(&s.join("detp-small.csv"), 2);
    // Points in the ball are drawn per replica: one row per replica and disc (samples 0 … 2n − 1 of
    // each sweep point), no per-replica columns (disc i is another point in each replica).
    let (h, rows) = crate::common::read_csv(&w.join("detp-small.points.csv"));
    assert!(
        !h.iter().any(|c| c.starts_with("irradiance_replica_")),
        "{h:?}"
    );
    assert_eq!(rows.len(), 4 * 2 * 2_000);
}

/// The points of each replica of a lines point as (x, y, z, nx, ny, nz) text, from the points
/// table of sweep point `point` (replica k's discs are samples k·n … (k + 1)·n − 1).
fn replica_points(dir: &Path, stem: &str, point: &str, n: usize) -> Vec<Vec<Vec<String>>> {
    let (h, rows) = crate::common::read_csv(&dir.join(format!("{stem}.points.csv")));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    let mut mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[at("point")] == point).collect();
    mine.sort_by_key(|r| r[at("sample")].parse::<usize>().unwrap());
    mine.chunks(n)
        .map(|c| {
            c.iter()
                .map(|r| {
                    ["x", "y", "z", "nx", "ny", "nz"]
                        .iter()
                        .map(|k| r[at(k)].clone())
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// A lines point's replicas are new lines *and* new points (the specs' "new lines and points
/// each"): points uniform in the ball differ between replicas, the lattice keeps its centres and
/// draws new normals; the run is the same on 1 and 2 threads; and the sphere cache's misses per
/// level, which depend on the points, vary between replicas: an SE of zero at every coarse level
/// was the sign of one point set shared by the replicas.
#[test]
fn lines_replicas_draw_their_own_points() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let text = SPEC
        .replace("replicas = 2", "replicas = 3")
        .replace("points = 2_000", "points = 1_000")
        .replace(
            "[sweep]\n\"detp.q\" = [0.5, 0.8]\n\"detp.order\" = [\"morton\", \"hilbert\"]",
            "[sweep]\n\"detp.point_source\" = [\"ball\", \"grid\"]",
        )
        .replace("points = 1_000", "points = 1_000\nq = 0.5");
    assert!(text.contains("point_source"), "{text}");
    let spec = write_spec(tmp.path(), "detp-small", &text);
    let (one, two) = (tmp.path().join("one"), tmp.path().join("two"));
    run_ok(&spec, &one, &["--threads", "1"]);
    run_ok(&spec, &two, &["--threads", "2"]);
    let (a, b) = (one.join("detp-small"), two.join("detp-small"));
    assert_eq!(
        assert_same_measured(&a.join("detp-small.csv"), &b.join("detp-small.csv")),
        2
    );
    same_side_tables(&a, &b, "detp-small");
    // Ball (point 0): every replica its own points.
    let ball = replica_points(&a, "detp-small", "0", 1_000);
    assert_eq!(ball.len(), 3);
    for (i, x) in ball.iter().enumerate() {
        for y in &ball[i + 1..] {
            let same = x.iter().zip(y).filter(|(p, q)| p[..3] == q[..3]).count();
            assert_eq!(same, 0, "replicas share {same} of their points");
        }
    }
    // The lattice (point 1, 10³ points): the same centres, new normals.
    let grid = replica_points(&a, "detp-small", "1", 1_000);
    assert_eq!(grid.len(), 3);
    for y in &grid[1..] {
        assert!(grid[0].iter().zip(y).all(|(p, q)| p[..3] == q[..3]));
        assert!(grid[0].iter().zip(y).all(|(p, q)| p[3..] != q[3..]));
    }
    // The misses of the ball's coarse levels (1 … 9) now vary with the points.
    let (h, rows) = crate::common::read_csv(&a.join("detp-small.levels.csv"));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    let varying: Vec<String> = rows
        .iter()
        .filter(|r| r[at("point")] == "0")
        .filter(|r| (1..=9).contains(&r[at("level")].parse::<u32>().unwrap()))
        .filter(|r| r[at("misses_level_per_replica_se")].parse::<f64>().unwrap() > 0.0)
        .map(|r| r[at("level")].clone())
        .collect();
    assert!(
        !varying.is_empty(),
        "no coarse level's misses vary: {rows:?}"
    );
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
