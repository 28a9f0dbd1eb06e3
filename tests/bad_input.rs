//! Every spec under `tests/specs/bad/` must be refused with exit code 2, one clear message naming
//! the file, line, column and key (each spec's first line says what to expect, `# also:` lines what
//! else the message must say), and no output.

use crate::common::{files_below, raycost, root, run_quiet};

#[test]
fn every_bad_spec_is_refused_with_its_location_and_nothing_is_written() {
    let dir = root().join("tests/specs/bad");
    let mut specs: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/specs/bad exists")
        .flatten()
        .map(|e| e.path())
        .collect();
    specs.sort();
    assert!(
        specs.len() >= 20,
        "expected the whole bad-input suite, found {}",
        specs.len()
    );
    for spec in specs {
        let text = std::fs::read_to_string(&spec).expect("readable");
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{} lacks '# expect: '", spec.display()))
            .to_string();
        // Further parts of the message (e.g. an error inside a scene file the spec names).
        let also: Vec<&str> = text
            .lines()
            .skip(1)
            .map_while(|l| l.strip_prefix("# also: "))
            .collect();
        let out = tempfile::tempdir().expect("temp dir");
        for cmd in ["run", "check"] {
            let mut c = raycost();
            c.arg(cmd).arg(&spec);
            if cmd == "run" {
                c.arg("--out").arg(out.path()).arg("--quiet");
            }
            let o = c.output().expect("runs");
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert_eq!(
                o.status.code(),
                Some(2),
                "{} ({cmd}): exit code; stderr: {stderr}",
                spec.display()
            );
            let want = format!(
                "error: {}{}",
                spec.display(),
                if expect.starts_with(':') { "" } else { ": " }
            );
            assert!(
                stderr.starts_with(&want),
                "{}: stderr should start with {want:?}: {stderr}",
                spec.display()
            );
            for want in std::iter::once(expect.as_str()).chain(also.iter().copied()) {
                assert!(
                    stderr.contains(want),
                    "{}: stderr should contain {want:?}: {stderr}",
                    spec.display()
                );
            }
            assert_eq!(
                stderr.lines().filter(|l| l.starts_with("error:")).count(),
                1,
                "one message: {stderr}"
            );
        }
        assert!(
            files_below(out.path()).is_empty(),
            "{}: nothing may be written",
            spec.display()
        );
    }
}

#[test]
fn bad_set_flags_name_the_flag() {
    let spec = root().join("experiments/quickstart.toml");
    for (set, expect) in [
        (
            "grid.cel_width=1",
            "error: --set grid.cel_width=1: grid.cel_width: unknown field",
        ),
        (
            "scene.radius=-2",
            "error: --set scene.radius=-2: scene.radius: got -2",
        ),
        ("scene.radius=nan", "scene.radius: got NaN"),
        ("novalue", "error: --set novalue: expected KEY=VALUE"),
        (
            "grid.cell_width=\"wide\"",
            "grid.cell_width: got \"wide\", expected a number",
        ),
    ] {
        let o = raycost()
            .args(["check"])
            .arg(&spec)
            .args(["--set", set])
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{set}: {stderr}");
        assert!(
            stderr.contains(expect),
            "{set}: want {expect:?} in {stderr}"
        );
    }
}

#[test]
fn missing_spec_and_bad_flags_exit_2() {
    let o = raycost()
        .args(["run", "no/such/spec.toml", "--quiet"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr)
        .contains("error: no/such/spec.toml: cannot read the spec"));
    let o = raycost()
        .args(["run", "x.toml", "--threads", "many"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2), "clap usage errors exit 2");
    let o = raycost()
        .args([
            "theory",
            "grid",
            "--intensity=-1",
            "--radius",
            "0.1",
            "--cell-width",
            "1",
        ])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--intensity: got -1"));
}

#[test]
fn an_unwritable_output_directory_is_refused_before_any_work() {
    let tmp = tempfile::tempdir().expect("temp dir");
    // A file where the results folder should be.
    let blocker = tmp.path().join("results");
    std::fs::write(&blocker, "not a folder").expect("write");
    let spec = root().join("experiments/quickstart.toml");
    let o = run_quiet(&spec, &blocker).output().expect("runs");
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot create the results folder"));
    assert_eq!(
        std::fs::read_to_string(&blocker).expect("still there"),
        "not a folder"
    );
}
