//! Photon batches: a point whose segments would not fit `detp.memory_budget_gib` is traced in B
//! batches in one process and measured from their sum. Its tables equal a single pass's bit for
//! bit in every measured column (kind `detp` with the disc index, brute force and the reference;
//! kind `quasi-static` frame by frame, where the segment index's own work is set apart as timing,
//! as for photon shards) — with B forced by `detp.photon_batches` and chosen by "auto" under a
//! small budget; `raycost check` says B; the metadata records it; engines whose counts do not add
//! are refused over the budget (exit 2, nothing written).

use std::path::{Path, PathBuf};

use crate::common::{files_below, measured_columns, raycost, run_quiet, write_spec};
use crate::merge::assert_same_measured;
use crate::photon_shards::{assert_same_but_index_work, quasi_static_spec, scene_spec};
use raycost::output::meta::Meta;

/// `spec` copied into `dir` with `lines` added at the top of its `[detp]` table.
fn with_detp_lines(spec: &Path, dir: &Path, lines: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(spec).unwrap();
    assert!(text.contains("[detp]\n"));
    let name = spec.file_stem().unwrap().to_str().unwrap();
    write_spec(
        dir,
        name,
        &text.replacen("[detp]\n", &format!("[detp]\n{lines}\n"), 1),
    )
}

/// `raycost check SPEC --json`.
fn check_json(spec: &Path) -> serde_json::Value {
    let out = raycost()
        .args(["check", "--json"])
        .arg(spec)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Every point's photon batches as `check --json` says.
fn batches_of(check: &serde_json::Value) -> Vec<u64> {
    check["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["memory"]["batches"].as_u64().unwrap())
        .collect()
}

/// A budget (GiB) that every point of `spec` exceeds in one pass but fits in a few batches: the
/// largest fixed part plus a third of the smallest photon part, from `check --json`'s needs.
fn tight_budget(spec: &Path) -> f64 {
    let check = check_json(spec);
    let (mut fixed, mut per_photon) = (0.0f64, f64::INFINITY);
    for p in check["points"].as_array().unwrap() {
        let needs = p["memory"]["needs"].as_array().unwrap();
        let sum = |scales: bool| {
            needs
                .iter()
                .filter(|n| n["per_photon"].as_bool() == Some(scales))
                .map(|n| n["bytes"].as_f64().unwrap())
                .sum::<f64>()
        };
        fixed = fixed.max(sum(false));
        per_photon = per_photon.min(sum(true));
    }
    assert!(per_photon > fixed, "the segments dominate the fixed part");
    (fixed + per_photon / 3.0) / (1u64 << 30) as f64
}

/// `spec` forced into 3 photon batches, and `spec` under a budget that "auto" meets with a few:
/// each a copy in its own folder below `dir`.
fn batched_variants(spec: &Path, dir: &Path) -> (PathBuf, PathBuf) {
    let forced = with_detp_lines(spec, &dir.join("forced"), "photon_batches = 3");
    let budget = tight_budget(spec);
    let auto = with_detp_lines(
        spec,
        &dir.join("auto"),
        &format!("memory_budget_gib = {budget:e}"),
    );
    (forced, auto)
}

/// Runs each spec into `DIR/out/FOLDER`; returns `DIR/out`.
fn run_each(specs: &[(&PathBuf, &str)], dir: &Path) -> PathBuf {
    let runs = dir.join("out");
    for (spec, out) in specs {
        run_quiet(spec, &runs.join(out)).assert().success();
    }
    runs
}

/// Every point's photon batches as the run's metadata records them.
fn recorded_batches(table: &Path) -> Vec<u64> {
    let meta = Meta::read(&table.with_extension("meta.toml")).unwrap();
    assert!(meta.run.point_memory.iter().all(
        |m| m.budget_key == "detp.memory_budget_gib" && m.peak_rss_bytes.is_some_and(|b| b > 0)
    ));
    meta.run.point_memory.iter().map(|m| m.batches).collect()
}

/// `a` and `b` have the same measured cells, row by row, but for the column `except`.
fn same_measured_except(a: &Path, b: &Path, except: &str) -> usize {
    let drop = |rows: Vec<Vec<(String, String)>>| -> Vec<Vec<(String, String)>> {
        rows.into_iter()
            .map(|r| r.into_iter().filter(|(c, _)| c != except).collect())
            .collect()
    };
    let (x, y) = (drop(measured_columns(a)), drop(measured_columns(b)));
    assert!(x.first().is_some_and(|r| r.len() > 10));
    assert_eq!(x, y, "{} and {} differ", a.display(), b.display());
    x.len()
}

#[test]
fn photon_batches_of_a_scene_equal_one_pass() {
    let tmp = tempfile::tempdir().unwrap();
    let name = "ps-scene";
    let whole_spec = scene_spec(tmp.path());
    let (forced, auto) = batched_variants(&whole_spec, tmp.path());
    assert_eq!(batches_of(&check_json(&whole_spec)), vec![1; 4]);
    assert_eq!(batches_of(&check_json(&forced)), vec![3; 4]);
    let auto_batches = batches_of(&check_json(&auto));
    assert!(auto_batches.iter().all(|&b| b >= 2), "{auto_batches:?}");
    let text = raycost().arg("check").arg(&auto).output().unwrap();
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains(&format!("{} photon batches of about", auto_batches[0])),
        "{text}"
    );

    let table = |out: &Path, t: &str| out.join(name).join(format!("{name}{t}.csv"));
    let runs = run_each(
        &[(&whole_spec, "whole"), (&forced, "forced"), (&auto, "auto")],
        tmp.path(),
    );
    let (whole, forced, auto) = (runs.join("whole"), runs.join("forced"), runs.join("auto"));
    assert_eq!(
        assert_same_measured(&table(&whole, ""), &table(&forced, "")),
        4
    );
    assert_eq!(
        same_measured_except(
            &table(&whole, ""),
            &table(&auto, ""),
            "detp.memory_budget_gib"
        ),
        4
    );
    let points = |d: &Path| measured_columns(&table(d, ".points"));
    assert!(
        points(&whole).len() > 100,
        "the points table holds every disc"
    );
    assert_eq!(
        points(&whole),
        points(&forced),
        "points table, forced batches"
    );
    assert_eq!(
        same_measured_except(&table(&whole, ".points"), &table(&auto, ".points"), ""),
        points(&whole).len()
    );
    assert_eq!(recorded_batches(&table(&whole, "")), vec![1; 4]);
    assert_eq!(recorded_batches(&table(&forced, "")), vec![3; 4]);
    assert_eq!(recorded_batches(&table(&auto, "")), auto_batches);
}

#[test]
fn photon_batches_of_moving_objects_equal_one_pass() {
    let tmp = tempfile::tempdir().unwrap();
    let name = "pb-moving";
    let whole_spec = quasi_static_spec(tmp.path(), name, "disc-index", "");
    let (forced, auto) = batched_variants(&whole_spec, tmp.path());
    let auto_batches = batches_of(&check_json(&auto));
    assert!(auto_batches.iter().all(|&b| b >= 2), "{auto_batches:?}");
    let runs = run_each(
        &[(&whole_spec, "whole"), (&forced, "forced"), (&auto, "auto")],
        tmp.path(),
    );
    let table = |out: &str, t: &str| runs.join(out).join(name).join(format!("{name}{t}.csv"));
    for t in ["", ".frames"] {
        assert_same_but_index_work(&table("whole", t), &table("forced", t));
    }
    // The points table holds no index work: every measured column equal.
    let points = |out: &str| measured_columns(&table(out, ".points"));
    assert!(!points("whole").is_empty());
    assert_eq!(
        points("whole"),
        points("forced"),
        "points table, forced batches"
    );
    assert_eq!(
        points("whole"),
        points("auto"),
        "points table, auto batches"
    );
    // The auto run's budget is a parameter column: the rest is compared as above.
    assert_same_but_index_work(&table("whole", ".frames"), &table("auto", ".frames"));
    let main = |out: &str| {
        measured_columns(&table(out, ""))
            .into_iter()
            .map(|r| {
                r.into_iter()
                    .filter(|(c, _)| c != "detp.memory_budget_gib")
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
    };
    // Columns the batched run classes timing (the index's work) drop out of its side.
    let (w, a) = (main("whole"), main("auto"));
    for (rw, ra) in w.iter().zip(&a) {
        for (c, v) in ra {
            let u = rw.iter().find(|(d, _)| d == c).map(|(_, u)| u);
            assert_eq!(u, Some(v), "column {c}");
        }
    }
    assert_eq!(recorded_batches(&table("forced", "")), vec![3; 2]);
    assert_eq!(recorded_batches(&table("auto", "")), auto_batches);
}

/// μ-random lines gathered by the sphere cache, whose counts do not add across photon batches.
fn sphere_cache_spec(dir: &Path, detp: &str) -> PathBuf {
    write_spec(
        dir,
        "pb-cache",
        &format!(
            r#"[experiment]
name = "pb-cache"
kind = "detp"

[detp]
photons = 100_000
points = 100
disc_radius = 0.05
engines = ["sphere-cache"]
{detp}
"#
        ),
    )
}

/// `raycost check` and `raycost run` of `spec` fail with exit 2 saying every one of `what`, and
/// write nothing.
fn refused(spec: &Path, what: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    for cmd in ["check", "run"] {
        let mut c = raycost();
        c.arg(cmd).arg(spec);
        if cmd == "run" {
            c.arg("--out").arg(out.path()).arg("--quiet");
        }
        let got = c.assert().code(2);
        let err = String::from_utf8_lossy(&got.get_output().stderr).to_string();
        for w in what {
            assert!(err.contains(w), "{cmd}: {err}");
        }
    }
    assert!(files_below(out.path()).is_empty(), "a refused run wrote");
}

#[test]
fn engines_whose_counts_do_not_add_are_refused_over_the_budget() {
    let tmp = tempfile::tempdir().unwrap();
    let over = sphere_cache_spec(tmp.path(), "memory_budget_gib = 0.001");
    refused(
        &over,
        &[
            "pb-cache.toml:",
            "detp.memory_budget_gib = 0.001 GiB",
            "cannot be traced in batches",
            "sphere-cache",
        ],
    );
    let forced = sphere_cache_spec(tmp.path(), "photon_batches = 2");
    refused(
        &forced,
        &[
            "pb-cache.toml:",
            "detp.photon_batches",
            "cannot be traced in batches",
        ],
    );
}

#[test]
fn bad_photon_batches_are_refused_where_they_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    for bad in ["0", "\"many\"", "2.5"] {
        let spec = sphere_cache_spec(tmp.path(), &format!("photon_batches = {bad}"));
        refused(&spec, &["pb-cache.toml:10:", "photon_batches", "\"auto\""]);
    }
}
