//! `detp.edge` on the vendored hard-case scene: the clamped radius is the distance to the nearest
//! other surface (a box's faces and bottom count, the floor's own plane does not); the closed-form
//! direct light is 0 under and behind the box and matches the point-light formula where lit;
//! cutting at the first impact removes the light that DETP's second-intersection rule lets through
//! the box; every engine agrees with brute force under every mode on traced photons.

use std::path::Path;

use glam::DVec3;
use raycost::detp::brute;
use raycost::detp::disc::Discs;
use raycost::detp::disc_index::{DiscIndex, GridIndex, Octree};
use raycost::detp::edge::{clamped_radii, clip_to_first_hit, nearest_other_surface};
use raycost::detp::order::{permutation, Order};
use raycost::detp::photon::trace_photons;
use raycost::detp::sphere_cache::{root_sphere, run, SphereCacheParams};
use raycost::lt::Scene;

fn scene() -> Scene {
    Scene::load(Path::new("experiments/scenes/hard/hard-cases.toml")).expect("vendored scene")
}

#[test]
fn nearest_other_surface_sees_the_box_not_the_floor() {
    let s = scene();
    let y = DVec3::Y;
    // Floor beside the box's +x face (x = 0.25), 0.03 away: the face (and its bottom edge).
    let d = nearest_other_surface(&s, DVec3::new(0.28, 0.0, 0.0), y, 1.0);
    assert!((d - 0.03).abs() < 1e-12, "{d}");
    // Under the box: its bottom face lies in the floor's plane but faces down: distance 0.
    let d = nearest_other_surface(&s, DVec3::new(0.1, 0.0, 0.0), y, 1.0);
    assert!(d < 1e-12, "{d}");
    // Open floor far from everything: capped at the reach.
    assert_eq!(
        nearest_other_surface(&s, DVec3::new(-2.0, 0.0, 2.0), y, 0.05),
        0.05
    );
    // On the box's top, 0.02 from its edge: the +x face is 0.02 away (its own plane is the top).
    let d = nearest_other_surface(&s, DVec3::new(0.23, 0.5, 0.0), y, 1.0);
    assert!((d - 0.02).abs() < 1e-12, "{d}");
    let r = clamped_radii(
        &s,
        &[DVec3::new(0.28, 0.0, 0.0), DVec3::new(0.1, 0.0, 0.0)],
        &[y, y],
        0.05,
        0.25,
        1.0,
    );
    assert!((r[0] - 0.03).abs() < 1e-12 && r[1] == 0.0125, "{r:?}");
    // κ = 0.5: half the distance (0.015), the floor of 0.25·d unchanged under the box; κ = 2 reaches
    // d where 2·0.03 > 0.05.
    let at = [DVec3::new(0.28, 0.0, 0.0), DVec3::new(0.1, 0.0, 0.0)];
    let r = clamped_radii(&s, &at, &[y, y], 0.05, 0.25, 0.5);
    assert!((r[0] - 0.015).abs() < 1e-12 && r[1] == 0.0125, "{r:?}");
    let r = clamped_radii(&s, &at, &[y, y], 0.05, 0.25, 2.0);
    assert!(r[0] == 0.05 && r[1] == 0.0125, "{r:?}");
}

#[test]
fn direct_light_is_shadowed_and_matches_the_spot_formula() {
    let s = scene();
    let y = DVec3::Y;
    // Under the box and in its shadow beside the −x face: 0.
    assert_eq!(s.exact_irradiance(DVec3::new(0.0, 0.0, 0.0), y), Some(0.0));
    assert_eq!(s.exact_irradiance(DVec3::new(-0.3, 0.0, 0.0), y), Some(0.0));
    // Straight under the main spot (0.9, 2, 0; 100 W, 45° cone): I·cos/r² with cos = 1, r = 2.
    let e = s.exact_irradiance(DVec3::new(0.9, 0.0, 0.0), y).unwrap();
    let i = 100.0 / (2.0 * std::f64::consts::PI * (1.0 - 45f64.to_radians().cos()));
    assert!((e - i / 4.0).abs() < 1e-9 * e, "{e} vs {}", i / 4.0);
}

#[test]
fn engines_agree_under_every_mode_and_first_hit_stops_the_leak() {
    let s = scene();
    let d = 0.05;
    // Floor under the box near its −x edge, beside its shadowed face, and on its top.
    let mut c = Vec::new();
    for z in [-0.15, -0.05, 0.05, 0.15] {
        for x in [-0.24, -0.26, -0.2, -0.3, 0.3, -2.0] {
            c.push(DVec3::new(x, 0.0, z));
        }
        c.push(DVec3::new(0.24, 0.5, z));
    }
    let n = vec![DVec3::Y; c.len()];
    let plain = Discs::new(c.clone(), n.clone(), d).unwrap();
    let clamp = |d: f64, factor: f64| {
        Discs::new(c.clone(), n.clone(), d)
            .unwrap()
            .with_radii(clamped_radii(&s, &c, &n, d, 0.25, factor))
            .unwrap()
    };
    let clamped = clamp(d, 1.0);
    // `detp.edge_radius_factor` κ below and above 1, and a scheduled d(N) below d with κ = 0.5:
    // per-disc radii every engine must honour exactly.
    let (narrow, wide) = (clamp(d, 0.5), clamp(d, 2.0));
    let d_sched = raycost::theory::detp::scheduled_radius(d, 800_000.0, 200_000.0, 1.0 / 6.0);
    let scheduled = clamp(d_sched, 0.5);
    assert!(narrow.radii != clamped.radii && wide.radii != clamped.radii);
    let traced = trace_photons(&s, 200_000, 7);
    let mut cut = traced.clone();
    clip_to_first_hit(&mut cut, 0.05 * d);
    let mut under_paper = 0;
    for (label, discs, st) in [
        ("paper", &plain, &traced),
        ("clamp-radius", &clamped, &traced),
        ("first-hit", &plain, &cut),
        ("clamp-first-hit", &clamped, &cut),
        ("clamp-radius κ = 0.5", &narrow, &traced),
        ("clamp-radius κ = 2", &wide, &traced),
        ("clamp-first-hit κ = 0.5, d(N)", &scheduled, &cut),
    ] {
        let mut want = vec![0; discs.len()];
        brute::accumulate(st, discs, None, 1, &mut want);
        let perm = permutation(&discs.centers, Order::Hilbert, 10);
        let root = root_sphere(&s.bounds());
        let mut acc = vec![0; discs.len()];
        run(
            st,
            discs,
            &perm,
            root,
            &SphereCacheParams::default(),
            &mut acc,
        );
        assert_eq!(acc, want, "{label}: sphere cache");
        for ix in [
            Box::new(Octree::build(discs, 8, discs.radius)) as Box<dyn DiscIndex>,
            Box::new(GridIndex::build(discs, 2.0 * discs.radius)),
            Box::new(GridIndex::build(discs, 0.3 * discs.radius)),
        ] {
            let mut acc = vec![0; discs.len()];
            ix.accumulate(st, None, 1, &mut acc);
            assert_eq!(acc, want, "{label}: disc index");
        }
        // Discs wholly under the box (x = −0.2, 0.05 inside its −x face): true irradiance 0.
        let under: i64 = (0..discs.len())
            .filter(|&i| discs.centers[i].x == -0.2)
            .map(|i| want[i])
            .sum();
        if label.contains("first-hit") {
            assert_eq!(under, 0, "{label}: light under the box");
        } else {
            assert!(
                under > 0,
                "{label}: the second-intersection rule lets light through"
            );
            under_paper += under;
        }
    }
    assert!(under_paper > 0);
}
