//! The reference path tracer on a real scene: it agrees with a high-photon DETP run at
//! open surface points of the Cornell box within their combined standard error, closed forms hold
//! through the engine, and the surface sampler drops the floor a block stands on.

use glam::DVec3;
use raycost::detp::brute;
use raycost::detp::disc::Discs;
use raycost::detp::photon::trace_photons;
use raycost::detp::surface_points::{open_surface_points, surface_points};
use raycost::lt::reference::irradiance;
use raycost::lt::Scene;

use crate::common::{read_csv, root, run_quiet, write_spec};

fn scene(name: &str) -> Scene {
    Scene::load(&root().join("experiments/scenes").join(name)).expect("shipped scene loads")
}

#[test]
fn the_reference_agrees_with_many_photons_of_detp_on_open_cornell_surfaces() {
    let s = scene("cornell.toml");
    // Open points, ≥ 4d from every edge and block: floor, ceiling, back wall, green wall, short
    // block top.
    let pts = vec![
        DVec3::new(100.0, 0.0, 450.0),
        DVec3::new(420.0, 0.0, 120.0),
        DVec3::new(120.0, 548.8, 120.0),
        DVec3::new(278.0, 300.0, 559.2),
        DVec3::new(0.0, 300.0, 300.0),
        DVec3::new(185.0, 165.0, 169.0),
    ];
    let normals = vec![DVec3::Y, DVec3::Y, -DVec3::Y, -DVec3::Z, DVec3::X, DVec3::Y];
    let (photons, d) = (1_500_000u64, 25.0);
    let store = trace_photons(&s, photons, 5);
    let discs = Discs::new(pts.clone(), normals.clone(), d).expect("discs");
    let mut acc = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut acc);
    let area = std::f64::consts::PI * d * d;
    let w = s.total_power() / photons as f64;
    let refr = irradiance(&s, &pts, &normals, 20_000, 5);
    let mut z2 = 0.0;
    for (i, r) in refr.iter().enumerate() {
        let e = store.scale.watts(acc[i]) / area;
        let se = (e * w / area).sqrt();
        let z = (e - r.mean) / (se * se + r.se * r.se).sqrt();
        println!(
            "{}: DETP {e:.5} ± {se:.5}, reference {:.5} ± {:.5}, z = {z:.2}",
            pts[i], r.mean, r.se
        );
        assert!(r.se < 0.02 * r.mean, "reference SE {:?}", r);
        assert!(z.abs() < 4.0, "{}: z = {z}", pts[i]);
        z2 += z * z;
    }
    // Six points: mean z² of 1 expected; 4 is beyond the 99.9th percentile of χ²₆/6.
    assert!(z2 / 6.0 < 4.0, "mean z² {}", z2 / 6.0);
}

#[test]
fn the_reference_engine_matches_the_closed_forms_of_the_analytic_scenes() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, spacing) in [("point-over-plane", 1.5), ("closed-sphere", 0.6)] {
        let spec = write_spec(
            tmp.path(),
            name,
            &format!(
                "[experiment]\nname = \"{name}\"\nkind = \"detp\"\nseed = 2\n[detp]\nsource = \"scene\"\nscene = {:?}\nphotons = 2000\npoint_spacing = {spacing}\ndisc_radius = 0.1\nengines = [\"sphere-cache\", \"reference\"]\nreference_samples = 4000\nwrite_points = true\n",
                root().join(format!("experiments/scenes/{name}.toml")).display().to_string()
            ),
        );
        let out = tmp.path().join("out");
        let o = run_quiet(&spec, &out).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (head, rows) = read_csv(&out.join(format!("{name}/{name}.points.csv")));
        let col = |c: &str| head.iter().position(|h| h == c).expect(c);
        let (e, se, x) = (
            col("reference_e"),
            col("reference_se"),
            col("irradiance_exact"),
        );
        assert!(rows.len() >= 10, "{name}: {} points", rows.len());
        let mut z2 = 0.0;
        for r in &rows {
            let (e, se, x): (f64, f64, f64) = (
                r[e].parse().unwrap(),
                r[se].parse().unwrap(),
                r[x].parse().unwrap(),
            );
            // The point light over a black plane is exact in every sample (SE 0).
            let z = if se > 0.0 { (e - x) / se } else { 0.0 };
            assert!(
                (e - x).abs() <= 4.0 * se + 1e-9 * x,
                "{name}: {e} ± {se} vs {x}"
            );
            z2 += z * z;
        }
        println!(
            "{name}: {} points, mean z² {:.3}",
            rows.len(),
            z2 / rows.len() as f64
        );
        let mean_z2 = z2 / rows.len() as f64;
        assert!(mean_z2 < 2.0, "{name}: mean z² {mean_z2}");
    }
}

#[test]
fn surface_points_skip_the_floor_under_the_cornell_blocks_and_count_it() {
    let s = scene("cornell.toml");
    let (all, _) = surface_points(&s, 20.0, 0);
    let (open, _, covered) = open_surface_points(&s, 20.0);
    assert_eq!(open.len() as u64 + covered, all.len() as u64);
    // Under the short block (its footprint's inner square) and behind the lamp.
    let under =
        |p: &DVec3| p.y == 0.0 && (150.0..220.0).contains(&p.x) && (120.0..200.0).contains(&p.z);
    let behind_lamp =
        |p: &DVec3| p.y > 548.0 && (240.0..310.0).contains(&p.x) && (240.0..310.0).contains(&p.z);
    assert!(all.iter().any(under) && all.iter().any(behind_lamp));
    assert!(
        !open.iter().any(under),
        "a floor point under the short block survived"
    );
    assert!(
        !open.iter().any(behind_lamp),
        "a ceiling point behind the lamp survived"
    );
    // Open floor stays.
    assert!(open.iter().any(|p| p.y == 0.0 && p.x < 60.0 && p.z > 500.0));
    println!("{covered} of {} Cornell points covered", all.len());
    assert!(covered < all.len() as u64 / 10, "{covered}");
}
