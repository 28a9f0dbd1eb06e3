//! `raycost bench --quick` end to end: the columns docs/bench.md documents, every engine present, zero
//! mismatches, the per-round table the ratios come from, and no overwriting without `--force`.

use std::collections::BTreeSet;

use crate::common::{files_below, raycost, read_csv};

#[test]
fn quick_bench_writes_every_engine_with_zero_mismatches_and_refuses_to_overwrite() {
    let tmp = tempfile::tempdir().expect("temp");
    let out = tmp.path().join("results");
    let o = raycost()
        .args(["bench", "--quick", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("cell width a ="), "{stdout}");

    let dir = out.join("bench");
    let (header, rows) = read_csv(&dir.join("bench.csv"));
    for c in [
        "engine",
        "n",
        "threads",
        "rays_per_s",
        "build_s",
        "peak_mem_bytes",
        "mismatches",
        "cell_s",
        "n_i_mean",
        "n_s_mean",
    ] {
        assert!(
            header.iter().any(|h| h == c),
            "column {c} missing: {header:?}"
        );
    }
    let col = |name: &str| header.iter().position(|h| h == name).expect("column");
    let (engine, n, threads) = (col("engine"), col("n"), col("threads"));
    let keys: BTreeSet<(String, String, String)> = rows
        .iter()
        .map(|r| (r[engine].clone(), r[n].clone(), r[threads].clone()))
        .collect();
    let all = std::thread::available_parallelism()
        .map_or(1, |p| p.get())
        .to_string();
    for size in ["10000", "100000"] {
        for t in ["1", all.as_str()] {
            assert!(
                keys.contains(&("grid".into(), size.into(), t.into())),
                "no grid row for n = {size}, {t} threads: {keys:?}"
            );
        }
        assert!(keys.iter().any(|k| k.0 == "brute-force" && k.1 == size));
    }
    assert!(keys.iter().any(|k| k.0 == "grid-infinite"));
    for r in &rows {
        assert_eq!(r[col("mismatches")], "0", "row {r:?}");
        let rate: f64 = r[col("rays_per_s")].parse().expect("a rate");
        assert!(rate > 0.0, "row {r:?}");
        if r[engine] == "grid" {
            let checked: u64 = r[col("checked")].parse().expect("a count");
            assert!(checked > 0, "the grid's answers are checked: {r:?}");
        }
    }

    // Every timed grid row has one line per round in the rounds table.
    let (rh, rounds) = read_csv(&dir.join("bench.rounds.csv"));
    assert_eq!(rh, ["engine", "n", "threads", "round", "rays", "round_s"]);
    let grid_rounds = rounds.iter().filter(|r| r[0] == "grid").count();
    let grid_rows = rows.iter().filter(|r| r[engine] == "grid").count();
    assert!(grid_rows > 0 && grid_rounds % grid_rows == 0 && grid_rounds >= 2 * grid_rows);
    // Bench writes the same metadata schema as a run, its calibration under `extra.bench`.
    let meta = raycost::output::meta::Meta::read(&dir.join("bench.meta.toml")).expect("meta");
    assert_eq!(meta.run.command, "bench");
    let t_i = meta.extra["bench"]["calibration"]["t_i_s"]
        .as_float()
        .expect("T_I");
    assert!(t_i > 0.0, "{meta:?}");
    assert!(meta.columns["main"].iter().any(|c| c.name == "rays_per_s"));
    // Every table the bench wrote is declared, side tables included, with the header it has.
    for (table, file) in [
        ("main", "bench.csv"),
        ("rounds", "bench.rounds.csv"),
        ("infinite-rounds", "bench.infinite-rounds.csv"),
    ] {
        let text = std::fs::read_to_string(dir.join(file)).expect(file);
        let header: Vec<&str> = text.lines().next().expect("a header").split(',').collect();
        let declared: Vec<&str> = meta.columns[table]
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(header, declared, "{file}");
    }

    // A second run without --force refuses (exit 2) and leaves every file as it was.
    let snapshot = || -> Vec<_> {
        files_below(&out)
            .into_iter()
            .map(|p| (p.clone(), std::fs::read(&p).expect("read")))
            .collect()
    };
    let before = snapshot();
    let again = raycost()
        .args(["bench", "--quick", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(again.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert!(
        stderr.contains("bench.csv") && stderr.contains("--force"),
        "{stderr}"
    );
    assert_eq!(before, snapshot(), "a refused bench changed the results");
}
