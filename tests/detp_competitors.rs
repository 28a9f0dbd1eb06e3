//! DETP's competitors wired into kind `detp`: engine `path-tracing` writes what
//! `lt::pathtrace` computes, whatever the thread count; `direct = "nee"` keeps the DETP engines
//! bit-identical (the run fails otherwise) and sums to the closed sphere's exact irradiance.

use glam::DVec3;
use raycost::lt::pathtrace::{path_trace, powers_of_two};
use raycost::lt::Scene;

use crate::common::{measured_columns, read_csv, root, run_quiet, write_spec};

/// Column `name` of `header`.
fn at(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

fn num(s: &str) -> f64 {
    s.parse().unwrap_or_else(|_| panic!("not a number: {s}"))
}

/// Two open points of the Cornell box (floor, back wall) with their normals.
const POINTS: [([f64; 3], [f64; 3]); 2] = [
    ([100.0, 0.0, 450.0], [0.0, 1.0, 0.0]),
    ([278.0, 300.0, 559.2], [0.0, 0.0, -1.0]),
];

fn cornell_spec(dir: &std::path::Path) -> std::path::PathBuf {
    let csv: String = std::iter::once("x,y,z,nx,ny,nz\n".to_string())
        .chain(
            POINTS
                .iter()
                .map(|(p, n)| format!("{},{},{},{},{},{}\n", p[0], p[1], p[2], n[0], n[1], n[2])),
        )
        .collect();
    std::fs::write(dir.join("two.csv"), csv).expect("points file");
    let scene = root().join("experiments/scenes/cornell.toml");
    write_spec(
        dir,
        "pt",
        &format!(
            r#"[experiment]
name = "pt"
kind = "detp"
seed = 7

[detp]
source = "scene"
scene = "{}"
photons = 2000
point_source = "file"
points_file = "two.csv"
disc_radius = 10.0
engines = ["sphere-cache", "path-tracing", "reference"]
path_samples = 12
reference_samples = 16
replicas = 2
write_points = true
"#,
            scene.display()
        ),
    )
}

#[test]
fn path_tracing_writes_what_the_library_computes_on_any_thread_count() {
    let dir = tempfile::tempdir().expect("temp dir");
    let spec = cornell_spec(dir.path());
    let runs: Vec<_> = ["1", "2"]
        .iter()
        .map(|t| {
            let out = dir.path().join(format!("t{t}"));
            run_quiet(&spec, &out)
                .args(["--threads", t])
                .assert()
                .success();
            out.join("pt")
        })
        .collect();
    for table in ["pt.csv", "pt.path_tracing.csv", "pt.points.csv"] {
        assert_eq!(
            measured_columns(&runs[0].join(table)),
            measured_columns(&runs[1].join(table)),
            "{table}: 1 and 2 threads"
        );
    }
    // The side table's rows at K = 12 paths are the library's run, replica by replica.
    let scene = Scene::load(&root().join("experiments/scenes/cornell.toml")).expect("scene");
    let pts: Vec<DVec3> = POINTS.iter().map(|p| DVec3::from(p.0)).collect();
    let nrm: Vec<DVec3> = POINTS.iter().map(|p| DVec3::from(p.1)).collect();
    let cps = powers_of_two(12);
    assert_eq!(cps, [1, 2, 4, 8, 12]);
    let lib: Vec<_> = (0..2)
        .map(|r| path_trace(&scene, &pts, &nrm, &cps, 7, r))
        .collect();
    let (h, rows) = read_csv(&runs[0].join("pt.path_tracing.csv"));
    assert_eq!(
        rows.len(),
        2 * cps.len(),
        "one row per replica and checkpoint"
    );
    let (hp, points) = read_csv(&runs[0].join("pt.points.csv"));
    let refr: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            (
                num(&p[at(&hp, "reference_e")]),
                num(&p[at(&hp, "reference_se")]),
            )
        })
        .collect();
    for row in &rows {
        let r = num(&row[at(&h, "replica")]) as usize;
        let paths = num(&row[at(&h, "paths")]) as u64;
        let c = cps.iter().position(|&x| x == paths).expect("a checkpoint");
        let run = &lib[r];
        assert_eq!(num(&row[at(&h, "rays_path")]) as u64, run.rays[c].path);
        assert_eq!(num(&row[at(&h, "rays_shadow")]) as u64, run.rays[c].shadow);
        let var = (run.variance[0] + run.variance[1]) / 2.0;
        assert_eq!(num(&row[at(&h, "variance_mean")]), var);
        let mse = (0..2)
            .map(|i| (run.mean(i, c) - refr[i].0).powi(2) - refr[i].1.powi(2))
            .sum::<f64>()
            / 2.0;
        assert_eq!(
            num(&row[at(&h, "ref_mse")]),
            mse,
            "replica {r}, {paths} paths"
        );
    }
    // The points table: the running means, mean over replicas, at every checkpoint.
    for (i, p) in points.iter().enumerate() {
        for (c, k) in cps.iter().enumerate() {
            let want = (lib[0].mean(i, c) + lib[1].mean(i, c)) / 2.0;
            assert_eq!(num(&p[at(&hp, &format!("path_tracing_e_{k}"))]), want);
        }
    }
    let (hm, main) = read_csv(&runs[0].join("pt.csv"));
    let m = &main[0];
    assert_eq!(num(&m[at(&hm, "path_tracing_points")]), 2.0);
    let rays: u64 = lib.iter().map(|r| r.rays[cps.len() - 1].shadow).sum();
    assert_eq!(num(&m[at(&hm, "path_tracing_rays_shadow")]) as u64, rays);
    for c in ["path_tracing_cv", "path_tracing_cv_prefix"] {
        let v = num(&m[at(&hm, c)]);
        assert!(v.is_finite() && v > 0.0, "{c} = {v}");
    }
    // Its RMSE against a 16-path reference: the reference's variance subtracted, at least 0.
    let rmse = num(&m[at(&hm, "path_tracing_ref_rmse_mean")]);
    assert!(rmse.is_finite() && rmse >= 0.0, "{rmse}");
    assert_eq!(num(&m[at(&hm, "build_path_tracing_s")]), 0.0);
}

#[test]
fn a_path_tracing_subset_is_keyed_and_nested() {
    use raycost::experiment::detp::path_tracing::subset;
    assert_eq!(subset(3, 10, None), (0..10).collect::<Vec<_>>());
    assert_eq!(subset(3, 10, Some(10)), (0..10).collect::<Vec<_>>());
    let small = subset(3, 1000, Some(20));
    let large = subset(3, 1000, Some(200));
    assert_eq!(small.len(), 20);
    assert!(small.windows(2).all(|w| w[0] < w[1]));
    assert!(small.iter().all(|i| large.contains(i)), "nested");
    assert_ne!(small, subset(4, 1000, Some(20)), "keyed by the seed");
    assert_ne!(small, (0..20).collect::<Vec<_>>());
}

#[test]
fn nee_direct_and_detp_indirect_give_the_furnace_irradiance_with_engines_bit_identical() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = root().join("experiments/scenes/closed-sphere.toml");
    let spec = write_spec(
        dir.path(),
        "nee",
        &format!(
            r#"[experiment]
name = "nee"
kind = "detp"
seed = 3

[detp]
source = "scene"
scene = "{}"
photons = 20000
point_spacing = 0.35
disc_radius = 0.1
engines = ["sphere-cache", "disc-index", "photon-map", "photon-map-growing"]
direct = "nee"
direct_samples = 4
photon_map_k_photons = 5000
replicas = 4
write_points = true

[sweep]
"detp.direct" = ["photons", "nee"]
"#,
            scene.display()
        ),
    );
    // A mismatch between the engines or against brute force fails the run (exit 1).
    run_quiet(&spec, dir.path()).assert().success();
    // Both modes write the same columns (a CSV with ragged rows does not read).
    let (h, rows) = read_csv(&dir.path().join("nee/nee.csv"));
    assert_eq!(rows.len(), 2);
    let r = &rows[1];
    assert_eq!(r[at(&h, "detp.direct")], "nee");
    assert_eq!(rows[0][at(&h, "direct_s")], "0.0");
    assert_eq!(
        rows[0][at(&h, "segments_indirect")],
        rows[0][at(&h, "segments")]
    );
    let get = |c: &str| num(&r[at(&h, c)]);
    assert_eq!(get("mismatches"), 0.0);
    assert!(get("bf_checked") > 0.0);
    // E = π·L_e/(1 − α) = 2π: NEE gives π (every sample sees the emitting sphere), DETP the rest.
    let (mean, se, theory) = (
        get("irradiance_mean"),
        get("irradiance_se"),
        get("irradiance_theory"),
    );
    assert!(
        (theory - 2.0 * std::f64::consts::PI).abs() < 1e-12,
        "{theory}"
    );
    assert!(
        se > 0.0 && (mean - theory).abs() < 4.0 * se,
        "{mean} ± {se} vs {theory}"
    );
    // Half the segments are indirect (albedo ½: a photon has 2 segments on average, 1 direct).
    let frac = get("segments_indirect") / get("segments");
    assert!((0.4..0.6).contains(&frac), "{frac}");
    assert!(get("direct_rays_shadow") > 0.0);
    // k(N) = 64·(20000/5000)^⅔ = 161.3 → 161.
    assert_eq!(get("photon_map_growing_k"), 161.0);
    let (hp, points) = read_csv(&dir.path().join("nee/nee.points.csv"));
    let n = points.len() / 2;
    assert!(points[..n]
        .iter()
        .all(|p| num(&p[at(&hp, "direct_e")]) == 0.0));
    for p in &points[n..] {
        let d = num(&p[at(&hp, "direct_e")]);
        assert!((d - std::f64::consts::PI).abs() < 1e-9, "direct {d}");
    }
}
