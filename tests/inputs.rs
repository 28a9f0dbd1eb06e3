//! Inputs are identified by what they are — their role, their place relative to the spec that
//! names them, their content hash — never by how a path was spelled: photon shards and point shards
//! run from several working folders (the spec's folder, its parent, an unrelated folder with an
//! absolute path, a path through `..`) merge from yet another folder into the unsplit run's table,
//! a resume works from another working folder, and a result folder moved together with its spec
//! still merges. A changed scene file is refused, named. And no command writes its output inside a
//! folder it reads.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common::{files_below, raycost, root};
use crate::merge::assert_same_measured;

/// A project folder `proj/` holding `ps.toml` and, beside it, the Cornell box it names as
/// `cornell.toml`; `proj/sub/` and an unrelated `other/` exist too. Two sweep points.
struct Project {
    _tmp: tempfile::TempDir,
    root: PathBuf,
    proj: PathBuf,
    other: PathBuf,
}

fn project() -> Project {
    let tmp = tempfile::tempdir().expect("tempdir");
    let root = tmp.path().canonicalize().expect("canonical tempdir");
    let proj = root.join("proj");
    let other = root.join("other");
    fs::create_dir_all(proj.join("sub")).expect("mkdir");
    fs::create_dir_all(&other).expect("mkdir");
    fs::copy(
        crate::common::root().join("experiments/scenes/cornell.toml"),
        proj.join("cornell.toml"),
    )
    .expect("copy the scene");
    fs::write(
        proj.join("ps.toml"),
        r#"[experiment]
name = "ps"
kind = "detp"
seed = 5

[detp]
source = "scene"
scene = "cornell.toml"
photons = 3001
point_spacing = 90.0
disc_radius = 25.0
engines = ["disc-index"]
replicas = 2

[sweep]
"detp.disc_radius" = [25.0, 40.0]
"#,
    )
    .expect("write the spec");
    Project {
        _tmp: tmp,
        root,
        proj,
        other,
    }
}

/// `raycost ARGS` started in `cwd`, which must succeed.
fn ok_in(cwd: &Path, args: &[&str]) {
    raycost().current_dir(cwd).args(args).assert().success();
}

/// The ways to name the spec and the results root: from the spec's folder, from its parent, from
/// an unrelated folder by absolute paths, and through `..`.
fn spellings(p: &Project) -> Vec<(PathBuf, String, String)> {
    let abs = |x: &Path| x.display().to_string();
    vec![
        (p.proj.clone(), "ps.toml".into(), "results".into()),
        (p.root.clone(), "proj/ps.toml".into(), "proj/results".into()),
        (
            p.other.clone(),
            abs(&p.proj.join("ps.toml")),
            abs(&p.proj.join("results")),
        ),
        (
            p.other.clone(),
            "../proj/sub/../ps.toml".into(),
            "../proj/sub/../results".into(),
        ),
    ]
}

/// The unsplit run, into `proj/whole/ps/`.
fn whole(p: &Project) -> PathBuf {
    ok_in(&p.proj, &["run", "ps.toml", "--out", "whole", "--quiet"]);
    p.proj.join("whole/ps/ps.csv")
}

#[test]
fn photon_shards_from_any_working_folder_merge_from_another() {
    let p = project();
    let want = whole(&p);
    let ways = spellings(&p);
    for (k, (cwd, spec, out)) in ways.iter().enumerate() {
        let shard = format!("{k}/{}", ways.len());
        ok_in(
            cwd,
            &[
                "run",
                spec,
                "--out",
                out,
                "--quiet",
                "--photon-shard",
                &shard,
            ],
        );
    }
    // Merged from inside the result folder.
    let dir = p.proj.join("results/ps");
    ok_in(&dir, &["merge", ".", "--quiet"]);
    assert_eq!(assert_same_measured(&want, &dir.join("ps.csv")), 2);
    assert!(
        !dir.join("ps").exists(),
        "the merge wrote a folder inside the shards' folder"
    );
}

#[test]
fn point_shards_from_any_working_folder_merge_from_another() {
    let p = project();
    let want = whole(&p);
    let ways = spellings(&p);
    let n = 2;
    for (k, (cwd, spec, out)) in ways.iter().take(n).enumerate() {
        ok_in(
            cwd,
            &[
                "run",
                spec,
                "--out",
                out,
                "--quiet",
                "--shard",
                &format!("{k}/{n}"),
            ],
        );
    }
    // A second set from the two other spellings, merged too.
    for (k, (cwd, spec, out)) in ways.iter().skip(n).enumerate() {
        let out = format!("{out}2");
        ok_in(
            cwd,
            &[
                "run",
                spec,
                "--out",
                &out,
                "--quiet",
                "--shard",
                &format!("{k}/{n}"),
            ],
        );
    }
    for folder in ["results/ps", "results2/ps"] {
        let dir = p.proj.join(folder);
        ok_in(&dir, &["merge", ".", "--quiet"]);
        assert_eq!(assert_same_measured(&want, &dir.join("ps.csv")), 2);
    }
    // Shards of one sweep made in different working folders join across folders as well.
    let files = [
        p.proj.join("results/ps/ps.shard-0-of-2.csv"),
        p.proj.join("results2/ps/ps.shard-1-of-2.csv"),
    ];
    let out = p.other.join("joined.csv");
    raycost()
        .current_dir(&p.root)
        .arg("merge")
        .args(&files)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .assert()
        .success();
    assert_eq!(assert_same_measured(&want, &out), 2);
}

/// A finished run made partial again by hand: point 0's rows kept, the files renamed back to
/// their `.partial` names, as a run killed after its first point leaves them.
fn make_partial(dir: &Path) {
    for f in files_below(dir) {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".csv") {
            let text = fs::read_to_string(&f).expect("read");
            let kept: Vec<&str> = text
                .lines()
                .enumerate()
                .filter(|(i, l)| *i == 0 || l.split(',').next() == Some("0"))
                .map(|(_, l)| l)
                .collect();
            assert!(kept.len() >= 2, "{name}: point 0 has rows");
            fs::write(&f, format!("{}\n", kept.join("\n"))).expect("write");
        }
        if name.ends_with(".csv") || name.ends_with(".meta.toml") {
            fs::rename(&f, f.with_file_name(format!("{name}.partial"))).expect("rename");
        }
    }
}

#[test]
fn a_resume_from_another_working_folder_continues_the_run() {
    let p = project();
    let want = whole(&p);
    ok_in(&p.proj, &["run", "ps.toml", "--out", "results", "--quiet"]);
    let dir = p.proj.join("results/ps");
    make_partial(&dir);
    let ways = spellings(&p);
    let (cwd, spec, out) = &ways[3];
    ok_in(cwd, &["run", spec, "--out", out, "--quiet", "--resume"]);
    assert_eq!(assert_same_measured(&want, &dir.join("ps.csv")), 2);
    let meta = raycost::output::meta::Meta::read(&dir.join("ps.meta.toml")).expect("meta");
    assert_eq!(meta.run.resumed_points, [0], "point 0 was carried over");
    assert_eq!(meta.inputs.len(), 1);
    assert_eq!(meta.inputs[0].location, "cornell.toml");
}

#[test]
fn a_result_folder_moved_with_its_spec_still_merges() {
    let p = project();
    let want = whole(&p);
    for k in 0..2 {
        ok_in(
            &p.proj,
            &[
                "run",
                "ps.toml",
                "--out",
                "results",
                "--quiet",
                "--photon-shard",
                &format!("{k}/2"),
            ],
        );
    }
    let moved = p.root.join("moved");
    fs::rename(&p.proj, &moved).expect("move the project");
    let dir = moved.join("results/ps");
    ok_in(&p.other, &["merge", dir.to_str().unwrap(), "--quiet"]);
    let want = moved.join(want.strip_prefix(&p.proj).unwrap());
    assert_eq!(assert_same_measured(&want, &dir.join("ps.csv")), 2);
}

#[test]
fn a_changed_scene_file_is_refused_by_name() {
    let p = project();
    for k in 0..2 {
        ok_in(
            &p.root,
            &[
                "run",
                "proj/ps.toml",
                "--out",
                "proj/results",
                "--quiet",
                "--photon-shard",
                &format!("{k}/2"),
            ],
        );
        ok_in(
            &p.proj,
            &[
                "run",
                "ps.toml",
                "--out",
                "points",
                "--quiet",
                "--shard",
                &format!("{k}/2"),
            ],
        );
    }
    // Shard 1 of the point shards again, on a changed scene (a comment: the same geometry).
    let scene = p.proj.join("cornell.toml");
    let original = fs::read_to_string(&scene).expect("scene");
    fs::write(&scene, format!("{original}\n# changed\n")).expect("change the scene");
    ok_in(
        &p.other,
        &[
            "run",
            "../proj/ps.toml",
            "--out",
            "../proj/points",
            "--quiet",
            "--shard",
            "1/2",
            "--force",
        ],
    );
    let refused = |cwd: &Path, dir: &str| {
        let before = files_below(&p.proj);
        let o = raycost()
            .current_dir(cwd)
            .args(["merge", dir])
            .output()
            .expect("merge");
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(
            files_below(&p.proj),
            before,
            "a refused merge wrote something"
        );
        err
    };
    let err = refused(&p.other, "../proj/results/ps");
    assert!(
        err.contains("scene file cornell.toml (content changed"),
        "{err}"
    );
    let err = refused(&p.proj, "points/ps");
    assert!(
        err.contains("scene file cornell.toml (content changed"),
        "{err}"
    );
}

/// The reported case: `crossover --out` naming one of its own input folders (or a folder inside
/// one) left that folder holding two results, refused as an input from then on.
#[test]
fn crossover_refuses_an_out_inside_an_input() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (fronts, points) = (tmp.path().join("fronts"), tmp.path().join("points"));
    fs::create_dir_all(&fronts).expect("mkdir");
    fs::create_dir_all(&points).expect("mkdir");
    fs::write(fronts.join("keep.txt"), "x").expect("write");
    for out in [
        fronts.clone(),
        points.join("crossover"),
        tmp.path().join("points/../fronts/x"),
    ] {
        let o = raycost()
            .arg("crossover")
            .arg(&fronts)
            .arg(&points)
            .args(["--targets", "0.1", "--force", "--out"])
            .arg(&out)
            .output()
            .expect("crossover");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", out.display());
        assert!(err.contains("a folder this command reads"), "{err}");
    }
    assert_eq!(
        files_below(tmp.path()),
        [fronts.join("keep.txt")],
        "a refused crossover wrote something"
    );
}

#[test]
fn merge_refuses_an_out_inside_a_folder_it_reads() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = root().join("tests/specs/slurm-sweep.toml");
    for k in 0..2 {
        crate::merge::run_ok(&spec, tmp.path(), &["--shard", &format!("{k}/2")]);
    }
    let dir = tmp.path().join("slurm-sweep");
    let before = files_below(tmp.path());
    for out in [dir.join("merged.csv"), dir.join("sub/slurm-sweep.csv")] {
        let o = raycost()
            .arg("merge")
            .arg(&dir)
            .arg("--out")
            .arg(&out)
            .output()
            .expect("merge");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", out.display());
        assert!(err.contains("a folder this command reads"), "{err}");
    }
    assert_eq!(
        files_below(tmp.path()),
        before,
        "a refused merge wrote something"
    );
    // The default place, named or not, and a folder outside are fine.
    raycost()
        .arg("merge")
        .arg(&dir)
        .arg("--out")
        .arg(dir.join("slurm-sweep.csv"))
        .arg("--quiet")
        .assert()
        .success();
    raycost()
        .arg("merge")
        .arg(&dir)
        .arg("--out")
        .arg(tmp.path().join("elsewhere/x.csv"))
        .arg("--quiet")
        .assert()
        .success();
}

#[test]
fn report_refuses_an_out_inside_a_run_folder() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = root().join("tests/specs/slurm-sweep.toml");
    crate::merge::run_ok(&spec, tmp.path(), &[]);
    let run = tmp.path().join("slurm-sweep");
    for out in [run.clone(), run.join("report")] {
        raycost()
            .arg("report")
            .arg(tmp.path())
            .arg("--out")
            .arg(&out)
            .assert()
            .code(2)
            .stderr(predicates::str::contains("a folder this command reads"));
    }
    assert!(!run.join("report").exists());
    raycost()
        .arg("report")
        .arg(tmp.path())
        .arg("--out")
        .arg(tmp.path().join("report"))
        .assert()
        .success();
}
