//! Kind quasi-static with `"path-tracing"` in `detp.engines`: at frame 0 and
//! every checked frame it is `path_trace` on the scene posed at that frame, at kind detp's keyed
//! subset of that frame's points; its measured columns do not depend on the thread count; and
//! switching it on changes no other column (the header without it is the header of before).

use raycost::experiment::detp::path_tracing::subset;
use raycost::experiment::plan::Plan;
use raycost::experiment::quasi_static::path_tracing::frame_seed;
use raycost::experiment::quasi_static::{run_point, start, QuasiStaticKind};
use raycost::lt::pathtrace::{path_trace, powers_of_two};

use crate::common::{measured_columns, raycost, read_csv, root, write_spec};

/// A tiny run: the sphere circling the Cornell box, 4 frames (2 and 3 checked), 2 replicas; path
/// tracing (K = 8 paths at P = 4 points) where `on`.
fn spec(dir: &std::path::Path, name: &str, on: bool) -> std::path::PathBuf {
    let scene = root().join("experiments/scenes/cornell-sphere-circle.toml");
    let engines = if on {
        r#"["sphere-cache", "path-tracing"]"#
    } else {
        r#"["sphere-cache"]"#
    };
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "quasi-static"
seed = 5

[detp]
source = "scene"
scene = "{}"
photons = 3000
point_spacing = 40.0
disc_radius = 20.0
index = "grid"
replicas = 2
engines = {engines}
path_samples = 8
path_points = 4

[dynamic]
frames = 4
check_every = 2
ratio = 0.1
"#,
            scene.display().to_string().replace('\\', "/")
        ),
    )
}

/// Every frame's figures are those of `path_trace` called here on the run's scene posed at that
/// frame, at the subset of its points and the frame's key; the main table pools frames × replicas.
#[test]
fn a_frame_is_path_traced_in_its_own_pose() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "ptq", true);
    let plan = Plan::load(&s, &[], 1).unwrap();
    let cfg = plan.point::<QuasiStaticKind>(0).unwrap();
    let out = run_point(cfg, &|_| {});
    let rows = &out.tables.frames;
    assert_eq!(rows.len(), 8, "4 frames × 2 replicas");
    let mut cvs = Vec::new();
    for replica in 0..2u64 {
        let (mut qs, _) = start(cfg, replica);
        for f in 0..4u32 {
            if f > 0 {
                qs.step(f);
            }
            let row = rows
                .iter()
                .find(|r| r.replica == replica && r.stats.frame == f)
                .expect("a row per frame");
            if f == 1 {
                assert_eq!(row.path_tracing, None, "frame 1 is not checked");
                continue;
            }
            let tau = raycost::lt::motion::tau(f, 4);
            assert_eq!(qs.scene.tau(), tau, "the scene is posed at frame {f}");
            let discs = qs.discs();
            let points = subset(5, discs.len(), Some(4));
            assert_eq!(points.len(), 4);
            let at = |v: &[glam::DVec3]| points.iter().map(|&i| v[i]).collect::<Vec<_>>();
            let run = path_trace(
                &qs.scene,
                &at(&discs.centers),
                &at(&discs.normals),
                &powers_of_two(8),
                frame_seed(5, f),
                replica,
            );
            let last = run.checkpoints.len() - 1;
            assert_eq!(run.checkpoints[last], 8);
            let mean_var = run.variance.iter().sum::<f64>() / 4.0;
            let mean_e = run.means_at(last).iter().sum::<f64>() / 4.0;
            let cv = mean_var.sqrt() / mean_e;
            assert!(cv.is_finite() && cv > 0.0, "frame {f}: cv {cv}");
            let t = row
                .path_tracing
                .expect("frame 0 and the checked frames are traced");
            assert_eq!(t.frame, f);
            assert_eq!(t.points, 4);
            assert_eq!(t.cv, cv, "replica {replica} frame {f}");
            let rays = run.rays[last];
            assert_eq!(t.rays_path, rays.path as f64 / 32.0);
            assert_eq!(t.rays_shadow, rays.shadow as f64 / 32.0);
            assert!(t.s_per_path > 0.0);
            cvs.push(cv);
        }
    }
    // Frames and replicas draw their own streams.
    let mut distinct = cvs.clone();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    assert_eq!(distinct.len(), cvs.len(), "independent frames: {cvs:?}");
    let m = out.measured.path_tracing.expect("pooled");
    assert_eq!((m.points, m.cv.n, m.cv.clusters), (4, 6, 2));
    assert!((m.cv.mean - cvs.iter().sum::<f64>() / 6.0).abs() <= 1e-15 * m.cv.mean);
    assert_eq!((m.s_per_path.n, m.s_per_path.clusters), (6, 2));
}

/// Path tracing's measured columns are the same on 1 and 2 threads; with it off the tables have
/// none of its columns, and every other column a run with it holds is the same (its seconds are in
/// no other timing, so those differ by the clock alone).
#[test]
fn path_tracing_is_thread_independent_and_changes_no_other_column() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, on: bool, threads: &str| {
        let s = spec(dir.path(), name, on);
        let out = dir.path().join(format!("out-{name}-{on}-{threads}"));
        raycost()
            .args(["run", s.to_str().unwrap(), "--quiet", "--threads", threads])
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let path = |t: &str| out.join(format!("{name}/{name}{t}.csv"));
        (path(""), path(".frames"))
    };
    let on1 = run("pt", true, "1");
    let on2 = run("pt", true, "2");
    let off = run("pt", false, "1");
    for (a, b) in [(&on1.0, &on2.0), (&on1.1, &on2.1)] {
        let (ma, mb) = (measured_columns(a), measured_columns(b));
        assert!(ma[0].iter().any(|(c, _)| c.starts_with("path_tracing_cv")));
        assert_eq!(ma, mb, "measured columns differ between 1 and 2 threads");
    }
    let path_tracing = |c: &str| c.starts_with("path_tracing_");
    for (with, without, added) in [(&on1.0, &off.0, 11), (&on1.1, &off.1, 2)] {
        let (h_on, rows_on) = read_csv(with);
        let (h_off, rows_off) = read_csv(without);
        assert!(!h_off.iter().any(|c| path_tracing(c)), "off: {h_off:?}");
        let kept: Vec<&String> = h_on.iter().filter(|c| !path_tracing(c)).collect();
        assert_eq!(
            kept,
            h_off.iter().collect::<Vec<_>>(),
            "the header without it"
        );
        assert_eq!(h_on.len(), h_off.len() + added);
        assert_eq!(rows_on.len(), rows_off.len());
        // Every measured column identical (timings differ by the clock alone).
        let reproducible = |path: &std::path::Path| -> Vec<Vec<(String, String)>> {
            measured_columns(path)
                .into_iter()
                .map(|r| {
                    r.into_iter()
                        .filter(|(c, _)| !path_tracing(c) && c != "detp.engines")
                        .collect()
                })
                .collect()
        };
        assert_eq!(
            reproducible(with),
            reproducible(without),
            "{}",
            with.display()
        );
    }
    // Traced frames (0, 2 and the last) carry numbers, frame 1 NaN.
    let (h, rows) = read_csv(&on1.1);
    let at = |c: &str| h.iter().position(|x| x == c).unwrap();
    for r in &rows {
        let frame: u32 = r[at("frame")].parse().unwrap();
        for c in ["path_tracing_cv", "path_tracing_s_per_path"] {
            let v: f64 = r[at(c)].parse().unwrap();
            assert_eq!(v.is_nan(), frame == 1, "frame {frame} {c}: {v}");
        }
    }
}
