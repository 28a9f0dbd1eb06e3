//! Numerical stability wherever a scene sits and whatever its unit: the photon tracer,
//! the discs and the crossing test give the same irradiance for the Cornell box translated by
//! 10⁰ … 10¹² of its size, scaled by 10⁻⁹ … 10⁶ (and by powers of two, exactly), and rotated — bit
//! for bit where the arithmetic allows it, within the standard error elsewhere — or the scene is
//! refused, naming the precision lost (`raycost::lt::precision`). Plus the hard geometry: grazing
//! light, coincident and nearly coincident surfaces, slivers, and points exactly on edges and
//! corners, where every DETP engine must still agree with brute force.
//!
//! Each variant traces the same photon streams (same seed) through the transformed scene and sums
//! the crossings of the same sample points, transformed alike, by brute force.

use std::path::Path;

use glam::{DMat3, DVec3};
use raycost::detp::stability::{compare, measure, place_scene_text, Placement, PointResult, Setup};
use raycost::lt::Scene;

use crate::common::{raycost, root, write_spec};

/// Disc radius and point spacing at scale 1 (mm in the Cornell box, whose size is 960 mm).
const D: f64 = 20.0;
const SETUP: Setup = Setup {
    disc_radius: D,
    spacing: 60.0,
    photons: 20_000,
    seed: 7,
};

fn cornell_text() -> String {
    std::fs::read_to_string(root().join("experiments/scenes/cornell.toml"))
        .expect("the Cornell box")
}

/// The Cornell box's text placed by `at`.
fn cornell(at: &Placement) -> String {
    place_scene_text(&cornell_text(), at).expect("placed")
}

fn moved(t: DVec3) -> Placement {
    Placement {
        translation: t,
        ..Placement::IDENTITY
    }
}

/// The result at the Cornell box's surface points, everything placed by `at`.
fn run(at: &Placement) -> Vec<PointResult> {
    measure(&cornell_text(), at, &SETUP).expect("measured")
}

/// (points whose crossing sums differ, mean z², largest |z|) of `b` against `a`.
fn z(a: &[PointResult], b: &[PointResult]) -> (usize, f64, f64) {
    let c = compare(a, b);
    (c.differ, c.mean_z2, c.max_z)
}

fn bits(t: f64) -> f64 {
    let p = raycost::lt::precision::Precision {
        magnitude: t + 560.0,
        size: 960.7,
    };
    p.bits(D)
}

/// Translations by 10⁰ … 10¹² of the box's size S along (1, −½, ¼), d = 20 mm: which outcome
/// each gets is asserted. Up to 10⁴·S every crossing sum is the same bit for bit (the irradiance
/// too, but for the last bits of the light's area, which a decimal shift rounds differently);
/// 10⁵ … 10⁷·S (≥ 23 bits left for d) the same within the SE, a few points' sums differing; from
/// 10⁸·S (19.8 bits) refused, naming the bits. Before tolerances followed the scene's scale, the
/// box at 10¹¹ mm never finished, and at 10¹⁰ most of its surface points were taken for covered by
/// a contact distance of 10 mm.
#[test]
fn translations_give_the_same_irradiance_or_are_refused() {
    let at0 = run(&Placement::IDENTITY);
    let size = 960.7;
    let mean = raycost::detp::stability::mean_and_se(&at0).0;
    for k in 0..=12 {
        let t = 10f64.powi(k) * size;
        let shift = DVec3::new(t, -0.5 * t, 0.25 * t);
        let scene = Scene::parse(&cornell(&moved(shift)), Path::new("c.toml")).expect("scene");
        let check = scene.precision().check(D);
        assert_eq!(
            check.is_err(),
            bits(t) < raycost::lt::precision::BITS_NEEDED,
            "10^{k}: {check:?}"
        );
        if k >= 8 {
            let e = check.expect_err("too far to keep 20 bits for d");
            assert!(
                e.contains("bits of f64") && e.contains("disc radius d = 20"),
                "{e}"
            );
            continue;
        }
        check.unwrap_or_else(|e| panic!("10^{k}: {e}"));
        let got = run(&moved(shift));
        let c = compare(&at0, &got);
        let (differ, z2, zmax) = (c.differ, c.mean_z2, c.max_z);
        if k <= 4 {
            assert!(
                differ == 0 && c.max_abs_diff <= 1e-14 * mean,
                "translation 10^{k}·S: {differ} sums differ, irradiance by up to {:e}",
                c.max_abs_diff
            );
        }
        assert!(
            z2 < 0.05 && zmax < 3.0 && differ * 10 < at0.len(),
            "translation 10^{k}·S ({:.1} bits for d): {differ} of {} points differ, mean z² {z2:.3}, max |z| {zmax:.2}",
            bits(t),
            at0.len()
        );
    }
}

/// Powers-of-two scales are exact in binary: every coordinate, distance, offset, power and area
/// scales exactly, so the sums are bit for bit the same from 2⁻³⁰ (nm-sized) to 2²⁰. Decimal
/// units (nm, m, km of a mm scene) round: the same within the SE.
#[test]
fn scales_give_the_same_irradiance() {
    let at1 = run(&Placement::IDENTITY);
    for k in [-30, -10, -1, 1, 10, 20] {
        let s = 2f64.powi(k);
        let got = run(&Placement {
            scale: s,
            ..Placement::IDENTITY
        });
        assert!(
            compare(&at1, &got).bit_identical,
            "scale 2^{k} changed an irradiance"
        );
    }
    for s in [1e-9, 1e-6, 1e-3, 1e3, 1e6] {
        let got = run(&Placement {
            scale: s,
            ..Placement::IDENTITY
        });
        let (differ, z2, zmax) = z(&at1, &got);
        assert!(
            z2 < 0.05 && zmax < 3.0,
            "scale {s:e}: {differ} of {} differ, mean z² {z2:.3}, max |z| {zmax:.2}",
            at1.len()
        );
    }
}

/// Rotations about the box's centre: the photons leave in other tangent frames (different paths
/// from the same random numbers), so the irradiance agrees within its SE, not bit for bit.
#[test]
fn rotations_give_the_same_irradiance_within_the_se() {
    let at0 = run(&Placement::IDENTITY);
    let c = DVec3::new(278.0, 274.4, 279.6);
    for (axis, deg) in [
        (DVec3::Y, 90.0),
        (DVec3::X, 180.0),
        (DVec3::new(1.0, 2.0, 3.0), 37.0),
    ] {
        let r = DMat3::from_axis_angle(axis.normalize(), f64::to_radians(deg));
        let got = run(&Placement {
            rotation: r,
            centre: c,
            ..Placement::IDENTITY
        });
        let (_, z2, zmax) = z(&at0, &got);
        // Independent estimates: mean z² ≈ 1; a handful of points past 3σ among hundreds.
        assert!(
            z2 < 1.5 && zmax < 5.0,
            "rotation {deg}° about {axis}: mean z² {z2:.3}, max |z| {zmax:.2}"
        );
    }
}

/// Beyond the threshold, measured (the library bypasses `check`): how far the answer drifts once
/// fewer than 20 bits remain for d — the evidence for where the line is drawn. Prints the table
/// `cargo test --release stability -- --nocapture` shows, and asserts that the drift grows.
#[test]
fn precision_is_lost_beyond_the_threshold() {
    let at0 = run(&Placement::IDENTITY);
    let mut rows = Vec::new();
    for k in [6, 8, 10, 12] {
        let t = 10f64.powi(k) * 960.7;
        let shift = DVec3::splat(t);
        let got = run(&moved(shift));
        let (differ, z2, zmax) = z(&at0, &got);
        eprintln!(
            "translation 10^{k}·S: {:.1} bits for d, {differ}/{} points differ, mean z² {z2:.3}, max |z| {zmax:.2}",
            bits(t),
            at0.len()
        );
        rows.push((k, differ, z2));
    }
    let first = rows[0];
    let last = rows[rows.len() - 1];
    assert!(first.1 * 4 < at0.len(), "{rows:?}");
    assert!(last.1 > first.1 && last.2 > first.2, "{rows:?}");
}

/// `raycost check` refuses the tester's scene — the box 10¹¹ mm away with d = 10 — with exit 2,
/// naming the key, the magnitude and the bits; the same box at 10¹⁰ mm is accepted.
#[test]
fn check_refuses_a_scene_too_far_for_its_discs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for (t, ok) in [(1e10, true), (1e11, false)] {
        let shift = DVec3::splat(t);
        std::fs::write(tmp.path().join("far-box.toml"), cornell(&moved(shift))).expect("scene");
        let spec = write_spec(
            tmp.path(),
            "far",
            "[experiment]\nname = \"far\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = \"far-box.toml\"\nphotons = 1000\npoint_spacing = 100.0\ndisc_radius = 10.0\n",
        );
        let o = raycost().arg("check").arg(&spec).output().expect("check");
        let err = String::from_utf8_lossy(&o.stderr);
        if ok {
            assert!(o.status.success(), "{t:e}: {err}");
        } else {
            assert_eq!(o.status.code(), Some(2), "{err}");
            assert!(
                err.contains("detp.scene") && err.contains("18.8 bits") && err.contains("d = 10"),
                "{err}"
            );
        }
    }
}

/// The hard geometry, each against brute force through every DETP engine (a run fails on any
/// disagreement): grazing light (a point light in the plane of a wall), coincident surfaces (a
/// quad lying on the floor; the floor given twice is refused, nothing left uncovered), a nearly coincident one (10⁻⁹ above), slivers
/// (triangles 10⁻⁷ wide), and sample points exactly on edges and corners.
#[test]
fn hard_geometry_agrees_with_brute_force() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let floor = "[[surface]]\nname = \"floor\"\nkind = \"quad\"\nvertices = [[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]\nalbedo = 0.5\n";
    let wall = "[[surface]]\nname = \"wall\"\nkind = \"quad\"\nvertices = [[-1, 0, 1], [-1, 1, 1], [1, 1, 1], [1, 0, 1]]\nalbedo = 0.5\n";
    let light = |p: &str| format!("[[light]]\nkind = \"point\"\nposition = {p}\npower = 10.0\n");
    let cases = [
        ("grazing", format!("{floor}{wall}{}", light("[0, 0, 0.5]"))),
        (
            "coincident",
            format!("{floor}[[surface]]\nname = \"mat\"\nkind = \"quad\"\nvertices = [[-0.5, 0, -0.5], [-0.5, 0, 0.5], [0.5, 0, 0.5], [0.5, 0, -0.5]]\nalbedo = 0.2\n{}", light("[0, 1, 0]")),
        ),
        (
            "nearly-coincident",
            format!("{floor}[[surface]]\nname = \"film\"\nkind = \"quad\"\nvertices = [[-0.5, 1e-9, -0.5], [-0.5, 1e-9, 0.5], [0.5, 1e-9, 0.5], [0.5, 1e-9, -0.5]]\nalbedo = 0.2\n{}", light("[0, 1, 0]")),
        ),
        (
            "slivers",
            format!("{floor}[[surface]]\nname = \"sliver\"\nkind = \"triangle\"\nvertices = [[-1, 0.5, 0], [1, 0.5, 1e-7], [1, 0.5, 0]]\nalbedo = 0.5\n[[surface]]\nname = \"needle\"\nkind = \"triangle\"\nvertices = [[0, 0.2, 0], [0, 0.9, 0], [1e-7, 0.2, 0]]\nalbedo = 0.5\n{}", light("[0.2, 1, 0.3]")),
        ),
    ];
    // Points exactly on the floor's edges and corners (and its centre), facing up.
    std::fs::write(
        tmp.path().join("edges.csv"),
        "x,y,z,nx,ny,nz\n-1,0,-1,0,1,0\n1,0,1,0,1,0\n0,0,1,0,1,0\n-1,0,0,0,1,0\n0,0,0,0,1,0\n0.5,0,-0.5,0,1,0\n",
    )
    .expect("points");
    for (name, scene) in cases {
        std::fs::write(tmp.path().join(format!("scene-{name}.toml")), scene).expect("scene");
        for points in [
            "point_spacing = 0.25",
            "point_source = \"file\"\npoints_file = \"edges.csv\"",
        ] {
            let spec = write_spec(
                tmp.path(),
                name,
                &format!(
                    "[experiment]\nname = \"{name}\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = \"scene-{name}.toml\"\nphotons = 20000\ndisc_radius = 0.1\n{points}\nengines = [\"sphere-cache\", \"disc-index\", \"brute-force\"]\nedge = \"clamp-first-hit\"\n"
                ),
            );
            let o = crate::common::run_quiet(&spec, &tmp.path().join("out"))
                .arg("--force")
                .output()
                .expect("run");
            assert!(
                o.status.success(),
                "{name} ({points}): {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let (h, rows) =
                crate::common::read_csv(&tmp.path().join(format!("out/{name}/{name}.csv")));
            let m = h
                .iter()
                .position(|c| c == "mismatches")
                .expect("mismatches column");
            assert_eq!(rows[0][m], "0", "{name} ({points})");
        }
    }
    // The floor given twice: each copy covers the other's every lattice point, so nothing is left
    // to measure — refused by what covers what (it used to panic in the disc index).
    std::fs::write(
        tmp.path().join("floor-twice.toml"),
        format!("{floor}{floor}{}", light("[0, 1, 0]")),
    )
    .expect("scene");
    let spec = write_spec(
        tmp.path(),
        "twice",
        "[experiment]\nname = \"twice\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = \"floor-twice.toml\"\nphotons = 1000\ndisc_radius = 0.1\npoint_spacing = 0.25\n",
    );
    let o = crate::common::run_quiet(&spec, &tmp.path().join("out"))
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("detp.scene")
            && err.contains("all 144 surface points are covered")
            && err.contains("coincident"),
        "{err}"
    );
}

/// The grid's hard cases not in `tests/oracle.rs` (which has rays along cell edges, eyes on faces,
/// in-plane rays through a lattice and grazing rays at random): spheres exactly tangent to cell
/// walls — filling their cell (r = a/2 at its centre), or touching one wall from either side — hit
/// by rays running *in* that wall's plane through the tangent point, along an axis or at any angle
/// in the plane, and by rays along the wall's edges. The tangent point lies on the boundary of two
/// cells, so the grid must list the sphere where the walk looks; the grid, every fast walk and
/// brute force must return the same sphere at the same distance, bit for bit.
#[test]
fn grid_rays_along_cell_faces_meet_spheres_tangent_to_cell_walls() {
    use rand::Rng;
    use raycost::geom::{Ray, Sphere};
    use raycost::sample::{directions::uniform_direction, rng::stream};

    let a = 0.5;
    let cells = 16;
    let lo = DVec3::splat(-4.0);
    let f = crate::oracle::frame(lo, a, cells);
    let mut rng = stream(&[26, 4]);
    let mut spheres = Vec::new();
    // (sphere, tangent point, wall axis) for the rays below.
    let mut tangents = Vec::new();
    for id in 0..1500u64 {
        let cell = DVec3::new(
            rng.gen_range(1..cells - 1) as f64,
            rng.gen_range(1..cells - 1) as f64,
            rng.gen_range(1..cells - 1) as f64,
        );
        let axis = rng.gen_range(0..3usize);
        let (c, r, p) = if id % 3 == 0 {
            // Filling its cell: tangent to all six walls.
            let c = lo + (cell + DVec3::splat(0.5)) * a;
            let mut p = c;
            p[axis] -= 0.5 * a;
            (c, 0.5 * a, p)
        } else {
            // Touching the wall x_axis = k from below (id odd) or above, at a random spot.
            let r = rng.gen_range(0.05..0.45) * a;
            let mut p = lo + (cell + DVec3::new(rng.gen(), rng.gen(), rng.gen())) * a;
            p[axis] = lo[axis] + cell[axis] * a;
            let mut c = p;
            c[axis] += if id % 2 == 1 { -r } else { r };
            (c, r, p)
        };
        spheres.push(Sphere { c, r, id });
        tangents.push((p, axis));
    }
    let mut rays = Vec::new();
    for &(p, axis) in &tangents {
        // Two in-plane unit directions of the wall.
        let (u, v) = match axis {
            0 => (DVec3::Y, DVec3::Z),
            1 => (DVec3::Z, DVec3::X),
            _ => (DVec3::X, DVec3::Y),
        };
        for k in 0..6 {
            let d = match k {
                0 => u,
                1 => -v,
                _ => {
                    let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                    (u * phi.cos() + v * phi.sin()).normalize()
                }
            };
            rays.push(Ray::new(p - d * rng.gen_range(0.2..2.0), d));
        }
        // Along the wall's edge through the cell corner nearest p, and one off the plane.
        let corner = lo + ((p - lo) / a).round() * a;
        let mut along = corner;
        along[axis] = p[axis];
        rays.push(Ray::new(along - u * 1.5, u));
        rays.push(Ray::new(
            p - uniform_direction(&mut rng),
            uniform_direction(&mut rng),
        ));
    }
    let hits = crate::oracle::check("tangent walls", f, &spheres, &rays);
    assert!(hits > rays.len() / 2, "{hits} of {} rays hit", rays.len());
}
