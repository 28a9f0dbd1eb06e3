//! Light transport: the shipped scenes load as published, photon tracing is reproducible photon by
//! photon and thread-count independent, and DETP (brute force) and the photon map reproduce the
//! closed forms of the two analytic scenes within their statistical error.

use glam::DVec3;
use raycost::detp::disc::Discs;
use raycost::detp::photon::{retrace, trace_photons};
use raycost::detp::photon_map::{estimate, Filter};
use raycost::detp::{brute, surface_points::surface_points};
use raycost::lt::Scene;

use crate::common::root;

fn scene(name: &str) -> Scene {
    Scene::load(&root().join("experiments/scenes").join(name)).expect("shipped scene loads")
}

#[test]
fn the_cornell_box_is_cornells_and_faces_inward() {
    let s = scene("cornell.toml");
    assert_eq!(s.triangles.len(), 32, "15 quads and the light");
    assert!(s.warnings.is_empty());
    let light = s.lights[0].power();
    assert!(
        (light - std::f64::consts::PI * 130.0 * 105.0).abs() < 1e-6,
        "{light}"
    );
    let b = s.bounds();
    assert_eq!((b.lo.y, b.hi.y), (0.0, 548.8));
    // Walls, floor and ceiling face the box's inside; block faces face away from their block.
    let inside = DVec3::new(278.0, 274.0, 280.0);
    for t in &s.triangles {
        let name = &s.surfaces[t.surface as usize].name;
        let n = t.normal();
        let c = t.centroid();
        let towards = if name.contains("block") {
            let block = if name.contains("short") {
                DVec3::new(186.0, 82.5, 169.0)
            } else {
                DVec3::new(368.5, 165.0, 351.0)
            };
            c - block
        } else {
            inside - c
        };
        assert!(
            n.dot(towards) > 0.0,
            "{name}: normal {n} faces the wrong way"
        );
    }
}

#[test]
fn degenerate_triangles_are_skipped_with_a_counted_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path().join("s.toml");
    std::fs::write(
        &p,
        "[[surface]]\nkind = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\nalbedo = 0.5\n\n\
         [[surface]]\nkind = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 0, 1]]\nalbedo = 0.5\n\n\
         [[light]]\nkind = \"point\"\nposition = [0, 1, 0]\npower = 1\n",
    )
    .expect("write");
    let s = Scene::load(&p).expect("loads");
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("skipped 1 degenerate triangle"));
}

#[test]
fn photons_are_the_same_on_any_thread_count_and_retrace_alone() {
    let s = scene("cornell.toml");
    let pool = |k| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .expect("pool")
    };
    let one = pool(1).install(|| trace_photons(&s, 3000, 7));
    let two = pool(2).install(|| trace_photons(&s, 3000, 7));
    assert_eq!(one, two);
    assert_eq!(one.photon_start.len(), 3001);
    for p in [0u32, 1, 17, 1234, 2999] {
        assert_eq!(
            retrace(&s, 7, 3000, p),
            one.photon(p as usize),
            "photon {p}"
        );
    }
    // Segments chain: each bounce starts where the previous one hit.
    for p in 0..100 {
        for w in one.photon(p).windows(2) {
            let end = w[0].o() + w[0].d() * f64::from(w[0].t_hit);
            assert!(
                (end - w[1].o()).length() < 1e-3,
                "photon {p}: {end} vs {}",
                w[1].o()
            );
        }
    }
}

#[test]
fn in_the_closed_sphere_a_photon_flies_1_over_1_minus_albedo_times() {
    let s = scene("closed-sphere.toml");
    let n = 200_000u64;
    let store = trace_photons(&s, n, 3);
    // Path length is geometric: P(≥ k + 1 flights) = α^k, mean 1/(1 − α) = 2, variance α/(1−α)² = 2.
    let mean = store.len() as f64 / n as f64;
    let se = (2.0 / n as f64).sqrt();
    assert!((mean - 2.0).abs() < 4.0 * se, "{mean} flights per photon");
    assert!(
        store.segments.iter().all(|s| s.t_hit.is_finite()),
        "nothing leaves a closed sphere"
    );
}

/// DETP by brute force at sample points, against the closed form, with the Poisson SE of each
/// point's sum (all segments carry the same power w: SE = √(E·w/πd²)).
fn detp_vs_exact(name: &str, photons: u64, d: f64, spacing: f64, keep: impl Fn(DVec3) -> bool) {
    let s = scene(name);
    let store = trace_photons(&s, photons, 11);
    let (p, n) = surface_points(&s, spacing, 0);
    let (p, n): (Vec<DVec3>, Vec<DVec3>) = p.into_iter().zip(n).filter(|(x, _)| keep(*x)).unzip();
    let discs = Discs::new(p, n, d).expect("discs");
    let mut acc = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut acc);
    let area = std::f64::consts::PI * d * d;
    let w = s.total_power() / photons as f64;
    let (mut z2, mut count) = (0.0, 0usize);
    for (i, &a) in acc.iter().enumerate() {
        let e = store.scale.watts(a) / area;
        let exact = s
            .exact_irradiance(discs.centers[i], discs.normals[i])
            .expect("closed form");
        let se = (exact * w / area).sqrt();
        z2 += ((e - exact) / se).powi(2);
        count += 1;
    }
    // Mean squared z near 1 (bias from d is below the noise at these sizes).
    let chi = z2 / count as f64;
    assert!(
        count >= 20 && (0.7..1.4).contains(&chi),
        "{name}: mean z² = {chi} over {count} points"
    );
    let pm = estimate(&store, &discs.centers, &discs.normals, 64, Filter::Disc);
    let rel: f64 = (0..discs.len())
        .map(|i| {
            pm[i]
                / s.exact_irradiance(discs.centers[i], discs.normals[i])
                    .unwrap()
                - 1.0
        })
        .sum::<f64>()
        / discs.len() as f64;
    assert!(
        rel.abs() < 0.05,
        "{name}: photon map mean relative error {rel}"
    );
}

#[test]
fn detp_and_the_photon_map_reproduce_a_point_light_over_a_plane() {
    detp_vs_exact("point-over-plane.toml", 400_000, 0.02, 0.1, |x| {
        x.x.abs() < 0.5 && x.z.abs() < 0.5
    });
}

#[test]
fn detp_and_the_photon_map_reproduce_the_closed_sphere() {
    detp_vs_exact("closed-sphere.toml", 200_000, 0.05, 0.15, |_| true);
}

/// A user's points: read from a CSV, and every one of them gets its row in NAME.points.csv with the
/// scene's exact irradiance beside the estimate.
#[test]
fn user_points_from_a_csv_get_their_irradiance_table() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("pts.csv"),
        "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n0.5,0,0,0,2,0\n1,0,1,0,1,0\n",
    )
    .expect("write");
    let scene = root().join("experiments/scenes/point-over-plane.toml");
    let spec = crate::common::write_spec(
        dir.path(),
        "mine",
        &format!(
            "[experiment]\nname = \"mine\"\nkind = \"detp\"\n\n[detp]\nsource = \"scene\"\n\
             scene = {:?}\nphotons = 200000\ndisc_radius = 0.1\npoint_source = \"file\"\n\
             points_file = \"pts.csv\"\nengines = [\"sphere-cache\", \"brute-force\"]\nwrite_points = true\n",
            scene.display().to_string()
        ),
    );
    let out = dir.path().join("out");
    crate::common::run_quiet(&spec, &out).assert().success();
    let (h, rows) = crate::common::read_csv(&out.join("mine/mine.points.csv"));
    let at = |c: &str| h.iter().position(|x| x == c).expect(c);
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1][at("x")], "0.5");
    assert_eq!(rows[1][at("ny")], "1.0", "normals are normalised");
    for r in &rows {
        let (e, se, exact): (f64, f64, f64) = (
            r[at("irradiance_mean")].parse().unwrap(),
            r[at("irradiance_se")].parse().unwrap(),
            r[at("irradiance_exact")].parse().unwrap(),
        );
        // Within 5 SE of the closed form, allowing the disc's averaging of the gradient (≤ 3 %).
        assert!(
            (e - exact).abs() < 5.0 * se + 0.03 * exact,
            "{e} ± {se} vs {exact}"
        );
    }
}
