//! The CLI end to end: results land where docs/cli.md says, existing results are never lost,
//! and measured columns do not depend on the thread count.

use crate::common::{
    files_below, measured_columns, raycost, read_csv, root, run_quiet, write_spec,
};

const SMALL: &str = r#"
[experiment]
name = "small"
kind = "grid"
seed = 7
rays = 3000

[scene]
intensity = 1.0
radius = 0.2

[grid]
cell_width = 0.5

[sweep]
"grid.cell_width" = [0.3, 0.8]
"grid.eye" = ["corner", "uniform"]
"#;

#[test]
fn run_writes_csv_meta_and_histograms_with_contract_columns() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "small", SMALL);
    let out = tmp.path().join("results");
    let o = raycost()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("measured ± 95% CI") && stdout.contains("n_i_mb"),
        "summary table: {stdout}"
    );
    let (header, rows) = read_csv(&out.join("small/small.csv"));
    assert_eq!(rows.len(), 4);
    assert_eq!(&header[..3], ["point", "grid.cell_width", "grid.eye"]);
    for col in [
        "n_i_mean",
        "n_i_se",
        "n_i_n",
        "n_i_lower",
        "n_i_upper",
        "n_i_theory",
        "n_i_mb_mean",
        "n_s_mean",
        "n_s_theory",
        "t_hit_mean",
        "t_hit_theory",
        "hit_mean",
        "rays_per_s",
    ] {
        assert!(header.iter().any(|h| h == col), "missing column {col}");
    }
    assert_eq!(rows[3][0], "3");
    assert_eq!(rows[3][2], "uniform");
    // The metadata declares every column's class: N_S is measured (`n_s_mean` was once
    // taken for a timing by its `_s_mean` suffix), speeds are timings.
    let meta = raycost::output::meta::Meta::read(&out.join("small/small.meta.toml")).expect("meta");
    assert!(!meta.run.spec_hash.is_empty() && !meta.raycost.git_commit.is_empty());
    let class = |name: &str| {
        meta.columns["main"]
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("{name} not declared"))
            .class
    };
    use raycost::output::column::Class;
    for m in [
        "n_s_mean",
        "n_s_se",
        "n_s_n",
        "n_i_mean",
        "n_i_mb_mean",
        "t_hit_mean",
    ] {
        assert_eq!(class(m), Class::Measured, "{m}");
    }
    for t in ["rays_per_s", "trace_s"] {
        assert_eq!(class(t), Class::Timing, "{t}");
    }
    let reproducible = meta.reproducible_columns("main");
    assert!(reproducible.iter().any(|c| c == "n_s_mean"));
    assert!(!reproducible.iter().any(|c| c == "rays_per_s"));
    let (h, hist) = read_csv(&out.join("small/small.hist.csv"));
    assert_eq!(
        h,
        ["point", "metric", "bin_lo", "bin_hi", "count", "expected"]
    );
    assert!(hist.iter().any(|r| r[1] == "t_hit") && hist.iter().any(|r| r[1] == "n_i_mb"));
    assert!(
        !files_below(&out)
            .iter()
            .any(|p| p.to_string_lossy().ends_with(".partial")),
        "no partial file left"
    );
}

#[test]
fn existing_results_are_never_replaced_without_force() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "small",
        &SMALL.replace("rays = 3000", "rays = 500"),
    );
    let out = tmp.path().join("results");
    run_quiet(&spec, &out).assert().success();
    let csv = out.join("small/small.csv");
    std::fs::write(&csv, "my precious edits\n").expect("edit");
    let o = run_quiet(&spec, &out).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"));
    assert_eq!(
        std::fs::read_to_string(&csv).expect("kept"),
        "my precious edits\n"
    );
    run_quiet(&spec, &out).arg("--force").assert().success();
    assert!(std::fs::read_to_string(&csv)
        .expect("replaced")
        .starts_with("point,"));
}

#[test]
fn measured_columns_are_identical_for_one_and_two_threads() {
    let tmp = tempfile::tempdir().expect("temp");
    let finite = SMALL.replace("radius = 0.2", "radius = 0.2\nspheres = 20000");
    for (name, text) in [("infinite", SMALL.to_string()), ("finite", finite)] {
        let spec = write_spec(tmp.path(), "small", &text);
        let mut tables = Vec::new();
        for threads in ["1", "2"] {
            let out = tmp.path().join(format!("{name}-{threads}"));
            raycost()
                .arg("run")
                .arg(&spec)
                .arg("--out")
                .arg(&out)
                .args(["--quiet", "--threads", threads])
                .assert()
                .success();
            tables.push((
                measured_columns(&out.join("small/small.csv")),
                std::fs::read(out.join("small/small.hist.csv")).expect("hist"),
            ));
        }
        assert_eq!(
            tables[0], tables[1],
            "{name}: thread count changed a measured column"
        );
    }
}

#[test]
fn check_prints_points_and_runs_nothing() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "small", SMALL);
    let o = raycost()
        .arg("check")
        .arg(&spec)
        .args(["--set", "grid.cell_width=0.7"])
        .current_dir(tmp.path())
        .output()
        .expect("runs");
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("2 point(s)") && s.contains("grid.cell_width = 0.7"),
        "{s}"
    );
    assert!(!tmp.path().join("results").exists());
}

#[test]
fn theory_prints_the_closed_forms() {
    let o = raycost()
        .args([
            "theory",
            "grid",
            "--intensity",
            "1",
            "--radius",
            "0.1",
            "--cell-width",
            "0.5",
        ])
        .output()
        .expect("runs");
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    // E[t*] = 1/(ρπr²) = 31.8310, E[N_S] uniform = 1.5·E[t*]/a = 95.4930.
    assert!(s.contains("31.830989") && s.contains("95.492966"), "{s}");
}

#[test]
fn theory_detp_prints_theorem_1_and_the_crossover() {
    let o = raycost()
        .args([
            "theory", "detp", "--rays", "1048576", "--points", "1000000", "--q", "0.6",
        ])
        .output()
        .expect("runs");
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    // Level 9 at Q = 0.6: 2²⁰·0.6¹⁸ = 106.493; 1/(Q²(1−Q)) = 6.944444; disc indexing n_R·∛n_P.
    assert!(s.contains("106.493"), "{s}");
    assert!(s.contains("6.944444e0"), "{s}");
    assert!(s.contains("1.048576e8"), "{s}");
    let o = raycost()
        .args([
            "theory", "detp", "--rays", "1000", "--points", "1000", "--q", "1.5",
        ])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--q: got 1.5"));
}

/// The shipped quickstart spec is valid and every shipped experiment spec checks.
#[test]
fn shipped_specs_check() {
    for e in std::fs::read_dir(root().join("experiments"))
        .expect("experiments/")
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "toml"))
    {
        let o = raycost().arg("check").arg(e.path()).output().expect("runs");
        assert!(
            o.status.success(),
            "{}: {}",
            e.path().display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn resume_of_a_finished_run_changes_nothing() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "small",
        &SMALL.replace("rays = 3000", "rays = 300"),
    );
    let out = tmp.path().join("results");
    run_quiet(&spec, &out).assert().success();
    let before: Vec<_> = files_below(&out)
        .iter()
        .map(|p| (p.clone(), std::fs::read(p).expect("read")))
        .collect();
    let o = raycost()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(&out)
        .arg("--resume")
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("finished already"));
    let after: Vec<_> = files_below(&out)
        .iter()
        .map(|p| (p.clone(), std::fs::read(p).expect("read")))
        .collect();
    assert_eq!(before, after);
}

/// A run killed inside its final renames (histogram and metadata already in place, the main table
/// still `.partial`) is completed by `--resume`, not refused.
#[test]
fn resume_recovers_a_run_killed_while_finishing() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "small",
        &SMALL.replace("rays = 3000", "rays = 300"),
    );
    let out = tmp.path().join("results");
    run_quiet(&spec, &out).assert().success();
    let dir = out.join("small");
    let want = measured_columns(&dir.join("small.csv"));
    std::fs::rename(dir.join("small.csv"), dir.join("small.csv.partial")).expect("rename");
    let o = raycost()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(&out)
        .args(["--resume", "--quiet"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(measured_columns(&dir.join("small.csv")), want);
    assert!(dir.join("small.hist.csv").exists() && dir.join("small.meta.toml").exists());
    assert!(!files_below(&out)
        .iter()
        .any(|p| p.to_string_lossy().ends_with(".partial")));
}

/// `--threads 100000` once ran for minutes on a 0.2 s job; more than 8 threads per CPU is
/// refused as a usage error, and nothing is written.
#[test]
fn absurd_thread_counts_are_refused() {
    let tmp = tempfile::tempdir().expect("temp");
    let o = raycost()
        .arg("run")
        .arg(root().join("experiments/quickstart.toml"))
        .args(["--threads", "100000", "--out"])
        .arg(tmp.path())
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--threads: got 100000") && err.contains("logical CPU"),
        "{err}"
    );
    assert!(files_below(tmp.path()).is_empty());
    // render and bench take the same flag, with the same limit.
    for args in [
        vec![
            "render",
            "experiments/render-cornell.toml",
            "--threads",
            "100000",
        ],
        vec!["bench", "--quick", "--threads", "100000"],
    ] {
        let o = raycost()
            .current_dir(root())
            .args(&args)
            .arg("--out")
            .arg(tmp.path().join("x"))
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(String::from_utf8_lossy(&o.stderr).contains("--threads: got 100000"));
    }
    assert!(files_below(tmp.path()).is_empty());
}

/// 3·10⁷ photons under a 2 GB memory limit once aborted after 37 s ("memory allocation
/// failed"); the budget now takes the memory this process may use (MemAvailable, the cgroup limit,
/// `ulimit -v`), and the run is refused before anything is allocated, naming the key.
#[test]
fn a_run_over_the_processes_memory_limit_is_refused_before_allocating() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "big",
        "[experiment]\nname = \"big\"\nkind = \"detp\"\n[detp]\nphotons = 30_000_000\npoints = 1000\ndisc_radius = 0.01\n",
    );
    let bin = assert_cmd::cargo::cargo_bin("raycost");
    let o = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v 2000000 && exec {} run {} --quiet --out {}",
            bin.display(),
            spec.display(),
            tmp.path().join("out").display()
        ))
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("detp.photons: would need about") && err.contains("available"),
        "{err}"
    );
    assert!(!tmp.path().join("out").exists());
}

/// `--version` names the commit the binary was built from, as `meta.toml` does.
#[test]
fn version_names_the_commit() {
    let o = raycost().arg("--version").output().expect("runs");
    let text = String::from_utf8_lossy(&o.stdout);
    let meta = raycost::output::meta::Build::current();
    assert!(
        text.contains(&meta.git_commit) && text.contains("rustc"),
        "{text}"
    );
}
