//! `detp.points` with `point_source = "surface"`: the first n of the surface lattice in an order
//! keyed by the seed alone — the same points at every sweep point, a smaller n a prefix of a larger
//! one's, and a clear refusal when the lattice holds fewer than n.

use std::path::Path;

use crate::common::{files_below, read_csv, root, run_quiet, write_spec};

/// The Cornell box on a 60 mm lattice, n points kept, two sweep points (d = 10 and 20 mm).
fn spec(dir: &Path, name: &str, n: u64) -> std::path::PathBuf {
    let scene = root().join("experiments/scenes/cornell.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"
[experiment]
name = "{name}"
kind = "detp"
seed = 4

[detp]
source = "scene"
scene = "{}"
point_source = "surface"
points = {n}
point_spacing = 60.0
photons = 2000
disc_radius = 10.0
engines = ["disc-index"]
write_points = true

[sweep]
"detp.disc_radius" = [10.0, 20.0]
"#,
            scene.display()
        ),
    )
}

/// Each sweep point's (x, y, z, nx, ny, nz) in sample order.
fn points_by_sweep_point(out: &Path, name: &str) -> Vec<Vec<Vec<String>>> {
    let (h, rows) = read_csv(&out.join(name).join(format!("{name}.points.csv")));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    let cols: Vec<usize> = ["x", "y", "z", "nx", "ny", "nz"]
        .iter()
        .map(|c| at(c))
        .collect();
    let mut by: Vec<Vec<Vec<String>>> = Vec::new();
    for r in &rows {
        let p: usize = r[at("point")].parse().expect("a point index");
        let s: usize = r[at("sample")].parse().expect("a sample index");
        if by.len() <= p {
            by.resize(p + 1, Vec::new());
        }
        assert_eq!(s, by[p].len(), "samples in order");
        by[p].push(cols.iter().map(|&c| r[c].clone()).collect());
    }
    by
}

#[test]
fn surface_subsamples_are_keyed_by_the_seed_alone_and_nested() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("out");
    for (name, n) in [("sub-small", 15), ("sub-large", 40)] {
        run_quiet(&spec(tmp.path(), name, n), &out)
            .assert()
            .success();
    }
    let small = points_by_sweep_point(&out, "sub-small");
    let large = points_by_sweep_point(&out, "sub-large");
    assert_eq!((small.len(), large.len()), (2, 2), "two sweep points each");
    assert_eq!(small[0].len(), 15);
    assert_eq!(large[0].len(), 40);
    // The same n: the same points at both sweep points (d differs between them).
    assert_eq!(small[0], small[1]);
    assert_eq!(large[0], large[1]);
    // n₁ < n₂: a prefix.
    assert_eq!(small[0][..], large[0][..15]);
    // Distinct points (a subsample, not repeats).
    let mut sorted = large[0].clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), 40);
}

#[test]
fn more_surface_points_than_the_lattice_holds_are_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("out");
    let o = run_quiet(&spec(tmp.path(), "sub-many", 1_000_000), &out)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        stderr.contains("detp.points") && stderr.contains("got 1000000 points"),
        "{stderr}"
    );
    assert!(
        files_below(&out)
            .iter()
            .all(|p| !p.to_string_lossy().ends_with(".csv")),
        "no table written: {:?}",
        files_below(&out)
    );
}
