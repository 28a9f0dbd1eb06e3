//! Kill and resume: a run interrupted by SIGINT or SIGKILL keeps every finished point in
//! its `.partial` files, and `raycost run --resume` completes a table identical (outside timing
//! columns) to an uninterrupted run. Resuming with another spec, or starting over a partial run
//! without `--resume`/`--force`, is refused with exit code 2 and the partial run left untouched.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use predicates::prelude::PredicateBooleanExt;

use crate::common::{files_below, run_quiet, write_spec};
use crate::merge::{assert_same_measured, run_ok};

/// 16 points of a few tenths of a second each: long enough to be interrupted mid-way.
const SPEC: &str = r#"
[experiment]
name = "resume-me"
kind = "grid"
seed = 11
rays = 10_000

[scene]
intensity = 1.0
radius = 0.1
extent = "infinite"

[grid]
cell_width = 0.5
mailbox = true
eye = "uniform"

[sweep]
"scene.intensity" = [1.0, 4.0]
"grid.cell_width" = [0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0]
"#;

fn data_rows(p: &Path) -> usize {
    fs::read(p).map_or(0, |b| {
        b.iter().filter(|&&c| c == b'\n').count().saturating_sub(1)
    })
}

/// Starts `raycost run` on a 16-point spec named `resume-me`, waits until its partial CSV holds at
/// least 2 finished points, sends `signal` with kill(1), and returns the number of points finished
/// before the signal.
pub fn interrupt(spec: &Path, out: &Path, signal: &str) -> usize {
    let bin = assert_cmd::cargo::cargo_bin("raycost");
    let mut child = Command::new(bin)
        .arg("run")
        .arg(spec)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start raycost");
    let partial = out.join("resume-me/resume-me.csv.partial");
    let t0 = Instant::now();
    loop {
        if data_rows(&partial) >= 2 {
            break;
        }
        if let Some(status) = child.try_wait().expect("wait") {
            panic!("the run ended ({status}) before it could be interrupted");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "no 2 rows in {} after 300 s",
            partial.display()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let pid = child.id().to_string();
    let ok = Command::new("kill")
        .arg(signal)
        .arg(&pid)
        .status()
        .expect("run kill");
    assert!(ok.success(), "kill {signal} {pid} failed");
    let o = child.wait_with_output().expect("wait");
    let status = o.status;
    assert!(!status.success(), "the run was not interrupted: {status}");
    if signal == "-INT" {
        // Ctrl-C says in one line what was kept and how to continue (exit code 130).
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(
            err.contains("interrupted:")
                && err.contains("resume-me.csv.partial")
                && err.contains("--resume"),
            "{err}"
        );
    }
    assert!(
        !out.join("resume-me/resume-me.csv").exists(),
        "an interrupted run renamed its table into place"
    );
    let rows = data_rows(&partial);
    assert!((2..16).contains(&rows), "{rows} rows after the signal");
    rows
}

fn resume_matches_uninterrupted(signal: &str, tear: bool) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = write_spec(tmp.path(), "resume-me", SPEC);
    let whole = tmp.path().join("whole");
    run_ok(&spec, &whole, &[]);
    let out = tmp.path().join("killed");
    let done = interrupt(&spec, &out, signal);
    let dir = out.join("resume-me");
    if tear {
        // A row cut mid-write (no newline): resume must drop it and redo that point.
        let p = dir.join("resume-me.csv.partial");
        let mut text = fs::read(&p).expect("partial");
        text.extend_from_slice(format!("{done},0.5,1.0,17.2").as_bytes());
        fs::write(&p, text).expect("write");
        let p = dir.join("resume-me.hist.csv.partial");
        let mut text = fs::read(&p).expect("partial hist");
        // A whole row of the unfinished point, then one cut short (rows are 6 fields wide).
        text.extend_from_slice(
            format!("{done},t_hit,0.0,9.5,41,40.5\n{done},t_hit,9.5").as_bytes(),
        );
        fs::write(&p, text).expect("write");
    }
    run_ok(&spec, &out, &["--resume"]);
    let w = whole.join("resume-me");
    assert_eq!(
        assert_same_measured(&w.join("resume-me.csv"), &dir.join("resume-me.csv")),
        16
    );
    assert_eq!(
        fs::read(w.join("resume-me.hist.csv")).expect("hist"),
        fs::read(dir.join("resume-me.hist.csv")).expect("hist"),
        "hist tables differ"
    );
    let meta: toml::Table = fs::read_to_string(dir.join("resume-me.meta.toml"))
        .expect("meta")
        .parse()
        .expect("TOML");
    let resumed = meta["run"]["resumed_points"]
        .as_array()
        .expect("resumed_points")
        .len();
    assert!(
        resumed >= done.min(2),
        "resumed_points has {resumed}, {done} were done"
    );
    assert_eq!(
        resumed + meta["run"]["points"].as_array().expect("points").len(),
        16
    );
    assert!(
        files_below(&dir)
            .iter()
            .all(|p| !p.to_string_lossy().ends_with(".partial")),
        "partial files left: {:?}",
        files_below(&dir)
    );
}

#[test]
fn sigint_then_resume_equals_an_uninterrupted_run() {
    resume_matches_uninterrupted("-INT", false);
}

#[test]
fn sigkill_and_a_torn_row_then_resume_equals_an_uninterrupted_run() {
    resume_matches_uninterrupted("-KILL", true);
}

/// A partial run of the spec, made by hand (a header, one row, and the spec hash of `hash`).
fn fake_partial(dir: &Path, hash: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let d = dir.join("resume-me");
    fs::create_dir_all(&d).expect("mkdir");
    fs::write(
        d.join("resume-me.csv.partial"),
        "point,grid.cell_width,scene.intensity,n_i_mean\n0,0.3,1.0,16.9\n",
    )
    .expect("write");
    fs::write(d.join("resume-me.hist.csv.partial"), "").expect("write");
    fs::write(d.join("resume-me.meta.toml.partial"), {
        let mut m = raycost::output::meta::Meta::begin("run", Default::default());
        m.run.spec_hash = hash.to_string();
        m.run.started = "2026-01-01T00:00:00Z".into();
        m.render()
    })
    .expect("write");
    files_below(&d)
        .into_iter()
        .map(|p| (p.clone(), fs::read(&p).expect("read")))
        .collect()
}

fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    files_below(dir)
        .into_iter()
        .map(|p| (p.clone(), fs::read(&p).expect("read")))
        .collect()
}

#[test]
fn resume_with_a_changed_spec_is_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = write_spec(tmp.path(), "resume-me", SPEC);
    let out = tmp.path().join("out");
    let before = fake_partial(
        &out,
        "0000000000000000000000000000000000000000000000000000000000000000",
    );
    run_quiet(&spec, &out)
        .arg("--resume")
        .assert()
        .code(2)
        .stderr(
            predicates::str::contains("resume-me.csv.partial")
                .and(predicates::str::contains("different spec")),
        );
    assert_eq!(
        before,
        snapshot(&out.join("resume-me")),
        "a refused resume changed the partial run"
    );
}

#[test]
fn resume_after_editing_the_spec_is_refused() {
    // A real partial run (first shard of 8 finished, as from a killed job), then the spec edited.
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = write_spec(tmp.path(), "resume-me", SPEC);
    let out = tmp.path().join("out");
    fs::create_dir_all(&out).expect("mkdir");
    let real = tmp.path().join("real");
    run_ok(&spec, &real, &["--shard", "0/8"]);
    let hash: toml::Table =
        fs::read_to_string(real.join("resume-me/resume-me.shard-0-of-8.meta.toml"))
            .expect("meta")
            .parse()
            .expect("TOML");
    let hash = hash["run"]["spec_hash"].as_str().expect("hash").to_string();
    let before = fake_partial(&out, &hash);
    write_spec(
        tmp.path(),
        "resume-me",
        &SPEC.replace("rays = 10_000", "rays = 12_000"),
    );
    run_quiet(&spec, &out)
        .arg("--resume")
        .assert()
        .code(2)
        .stderr(predicates::str::contains("spec hash differs"));
    assert_eq!(before, snapshot(&out.join("resume-me")));
}

#[test]
fn a_partial_run_is_not_replaced_without_resume_or_force() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let spec = write_spec(tmp.path(), "resume-me", SPEC);
    let out = tmp.path().join("out");
    let before = fake_partial(&out, "abc");
    run_quiet(&spec, &out)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--resume").and(predicates::str::contains("--force")));
    assert_eq!(
        before,
        snapshot(&out.join("resume-me")),
        "the partial run was touched"
    );
}
