//! The disc radius rules through the runner: `detp.edge_radius_factor` (κ) and the radius schedule
//! d(N) = d_ref·(N/N_ref)^(−β). Every DETP engine stays exact against brute force under them (the
//! run fails on a mismatch), `disc_radius_used` is the schedule's d(N), the keys are absent from
//! the normalised spec when not given (old spec hashes stay), and in kind quasi-static a schedule is
//! the fixed d it computes: incremental = full in every checked frame, and the measured columns of a
//! spec that writes d(N) directly. The k-nearest-crossings rule (engine level, no spec key yet)
//! keeps the same crossings in every engine on traced photons.

use crate::common::{read_csv, root, run_quiet, write_spec};
use raycost::theory::detp::scheduled_radius;

fn column<'a>(h: &[String], row: &'a [String], name: &str) -> &'a str {
    &row[h
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"))]
}

#[test]
fn a_schedule_sweep_with_kappa_shrinks_d_and_every_engine_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("experiments/scenes/hard/hard-cases.toml");
    let spec = write_spec(
        dir.path(),
        "radius",
        &format!(
            r#"[experiment]
name = "radius"
kind = "detp"
seed = 11

[detp]
source = "scene"
scene = "{}"
photons = 4000
points = 300
disc_radius = 0.1
edge = "clamp-first-hit"
edge_radius_factor = 0.5
radius_schedule_photons = 4000
engines = ["sphere-cache", "disc-index", "brute-force"]
brute_force_points = 300

[sweep]
"detp.photons" = [4000, 32000]
"#,
            scene.display()
        ),
    );
    let out = dir.path().join("out");
    run_quiet(&spec, &out).assert().success();
    let (h, rows) = read_csv(&out.join("radius/radius.csv"));
    assert_eq!(rows.len(), 2);
    let r_s = raycost::detp::sphere_cache::root_sphere(
        &raycost::lt::Scene::load(&scene).unwrap().bounds(),
    )
    .1;
    for (row, n) in rows.iter().zip([4000.0, 32000.0]) {
        assert_eq!(column(&h, row, "mismatches"), "0");
        let used: f64 = column(&h, row, "disc_radius_used").parse().unwrap();
        let want = scheduled_radius(0.1, n, 4000.0, 1.0 / 6.0);
        assert!(
            (used / want - 1.0).abs() < 1e-12,
            "N = {n}: {used} vs {want}"
        );
        let root_used: f64 = column(&h, row, "disc_radius_used_root").parse().unwrap();
        assert!(
            (root_used / (want / r_s) - 1.0).abs() < 1e-12,
            "{root_used}"
        );
        // κ = 0.5 shrinks discs near the box below d(N).
        let mean: f64 = column(&h, row, "edge_radius").parse().unwrap();
        assert!(mean > 0.25 && mean < 1.0, "{mean}");
    }
    let meta: toml::Table = std::fs::read_to_string(out.join("radius/radius.meta.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let detp = meta["spec"]["base"]["detp"]
        .as_table()
        .expect("[spec.base.detp]");
    assert_eq!(detp["edge_radius_factor"].as_float(), Some(0.5));
    assert_eq!(detp["radius_schedule_photons"].as_integer(), Some(4000));
}

#[test]
fn the_radius_keys_are_absent_from_the_normalised_spec_when_not_given() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("experiments/scenes/hard/hard-cases.toml");
    let spec = write_spec(
        dir.path(),
        "plain",
        &format!(
            "[experiment]\nname = \"plain\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = \"{}\"\nphotons = 2000\npoints = 100\ndisc_radius = 0.1\nedge = \"clamp-radius\"\nengines = [\"disc-index\"]\n",
            scene.display()
        ),
    );
    let out = dir.path().join("out");
    run_quiet(&spec, &out).assert().success();
    // The normalised spec (what the spec hash is taken of) is the metadata's [spec.base]: a spec
    // that does not give the new keys normalises, and hashes, as it did before they existed.
    let meta: toml::Table = std::fs::read_to_string(out.join("plain/plain.meta.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let detp = meta["spec"]["base"]["detp"]
        .as_table()
        .expect("[spec.base.detp]");
    assert_eq!(detp["edge"].as_str(), Some("clamp-radius"));
    for key in [
        "edge_radius_factor",
        "radius_schedule_photons",
        "radius_schedule_exponent",
    ] {
        assert!(!detp.contains_key(key), "{key} in the normalised spec");
    }
    let (h, rows) = read_csv(&out.join("plain/plain.csv"));
    assert_eq!(column(&h, &rows[0], "disc_radius_used"), "0.1");
}

fn qs_spec(dir: &std::path::Path, name: &str, radius: &str) -> std::path::PathBuf {
    let scene = root().join("experiments/scenes/cornell-dynamic.toml");
    write_spec(
        dir,
        name,
        &format!(
            r#"[experiment]
name = "{name}"
kind = "quasi-static"
seed = 3

[detp]
source = "scene"
scene = "{}"
photons = 4000
point_spacing = 40.0
{radius}
index = "grid"

[dynamic]
frames = 8
check_every = 1
ratio = 0.08
"#,
            scene.display()
        ),
    )
}

/// Columns of a CSV by name, without the spec's own parameter columns (which say how d was given).
fn outcome(path: &std::path::Path) -> Vec<(String, String)> {
    crate::common::measured_columns(path)
        .into_iter()
        .flatten()
        .filter(|(c, _)| !c.starts_with("detp.") && !c.starts_with("experiment."))
        .collect()
}

#[test]
fn a_quasi_static_schedule_is_exact_per_frame_and_equals_its_fixed_d() {
    let dir = tempfile::tempdir().unwrap();
    let d = scheduled_radius(20.0, 4000.0, 1000.0, 1.0 / 6.0);
    let scheduled = qs_spec(
        dir.path(),
        "qs",
        "disc_radius = 20.0\nradius_schedule_photons = 1000",
    );
    let fixed = qs_spec(dir.path(), "qs", &format!("disc_radius = {d:?}"));
    let mut tables = Vec::new();
    for (i, s) in [scheduled, fixed].iter().enumerate() {
        let out = dir.path().join(format!("out{i}"));
        run_quiet(s, &out).assert().success();
        let csv = out.join("qs/qs.csv");
        let (h, rows) = read_csv(&csv);
        assert_eq!(column(&h, &rows[0], "full_mismatch"), "0");
        assert_eq!(column(&h, &rows[0], "full_checked"), "7");
        tables.push((outcome(&csv), outcome(&out.join("qs/qs.frames.csv"))));
    }
    assert!(!tables[0].0.is_empty() && !tables[0].1.is_empty());
    assert_eq!(
        tables[0], tables[1],
        "a schedule is the fixed d(N) it computes"
    );
}

/// The k-nearest-crossings rule on traced photons: brute force, both disc indexes (a coarse and a
/// fine grid, an octree) and the sphere cache keep the same k crossings of every disc, bit for
/// bit, on the paper's segments and on segments cut at their first impact, for a small and a
/// large k; and the selection's radius is the k-th distance, below d, where k crossings are found.
#[test]
fn k_nearest_crossings_agree_bit_for_bit_across_engines_on_a_scene() {
    use glam::DVec3;
    use raycost::detp::disc::Discs;
    use raycost::detp::disc_index::{self, DiscIndex, GridIndex, Octree};
    use raycost::detp::nearest::{k_for, Kept, Nearest};
    use raycost::detp::order::{permutation, Order};
    use raycost::detp::sphere_cache::{filter::FilterPath, root_sphere, run_tally};
    use raycost::detp::tally::Tally;
    use raycost::detp::{brute, edge::clip_to_first_hit, photon::trace_photons};

    let s = raycost::lt::Scene::load(&root().join("experiments/scenes/hard/hard-cases.toml"))
        .expect("vendored scene");
    let d = 0.1;
    // Floor points around the box (some under it, some beside its faces) and on its top.
    let mut c = Vec::new();
    for i in 0..24 {
        for j in 0..24 {
            c.push(DVec3::new(
                -1.15 + 0.1 * f64::from(i),
                0.0,
                -1.15 + 0.1 * f64::from(j),
            ));
        }
    }
    for z in [-0.15, 0.0, 0.15] {
        c.push(DVec3::new(0.24, 0.5, z));
    }
    let n = vec![DVec3::Y; c.len()];
    let discs = Discs::new(c, n, d).unwrap();
    let traced = trace_photons(&s, 100_000, 3);
    let mut cut = traced.clone();
    clip_to_first_hit(&mut cut, 0.05 * d);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let root = root_sphere(&s.bounds());
    for (label, st) in [("paper", &traced), ("first-hit", &cut)] {
        for k in [k_for(3, 100_000, None), k_for(8, 100_000, Some(12_500))] {
            let t = Nearest::new(k);
            let sorted = |acc: &[Kept]| acc.iter().map(Kept::sorted).collect::<Vec<_>>();
            let mut want = t.empties(discs.len());
            brute::accumulate_with(st, &discs, None, &t, &mut want);
            let full = want.iter().filter(|w| w.len() == k).count();
            assert!(
                full > 100 && full < discs.len(),
                "{label} k {k}: {full} full"
            );
            for w in &want {
                let sel = w.select(k, d);
                assert_eq!(sel.full, w.len() == k);
                assert!(sel.radius <= d && (sel.full || sel.radius == d));
            }
            let want = sorted(&want);
            let mut acc = t.empties(discs.len());
            let params = raycost::detp::sphere_cache::SphereCacheParams::default();
            run_tally(
                st,
                &discs,
                &perm,
                root,
                &params,
                &t,
                &mut acc,
                FilterPath::detect(),
            );
            assert!(sorted(&acc) == want, "{label} k {k}: sphere cache");
            for ix in [
                Box::new(Octree::build(&discs, 8, d)) as Box<dyn DiscIndex>,
                Box::new(GridIndex::build(&discs, 2.0 * d)),
                Box::new(GridIndex::build(&discs, 0.3 * d)),
            ] {
                let mut acc = t.empties(discs.len());
                disc_index::accumulate_with(ix.as_ref(), st, None, &t, &mut acc);
                assert!(sorted(&acc) == want, "{label} k {k}: disc index");
            }
        }
    }
}
