//! The core against brute force (every triangle, [`Triangle::intersect`]) and against the BVH of
//! f3d7ed0, on adversarial rays, on every instruction-set path.

use glam::DVec3;
use rand::Rng;

use super::kernel::{node_scalar, packet_scalar, RayData};
use super::layout::{f32_down, f32_up, ChildRef, Node, Packet, WIDTH};
use super::*;
use crate::sample::{directions::uniform_direction, rng::stream};

#[path = "legacy.rs"]
mod legacy;

fn tri(a: DVec3, b: DVec3, c: DVec3, surface: u32) -> Triangle {
    Triangle {
        v: [a, b, c],
        surface,
    }
}

/// Random small triangles in a 10-cube scaled by `scale` and shifted by `shift`.
fn soup(seed: u64, n: usize, scale: f64, shift: f64) -> Vec<Triangle> {
    let mut rng = stream(&[seed]);
    (0..n)
        .map(|k| {
            let c =
                (DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 10.0 + DVec3::splat(shift)) * scale;
            tri(
                c,
                c + uniform_direction(&mut rng) * 0.5 * scale,
                c + uniform_direction(&mut rng) * 0.5 * scale,
                k as u32,
            )
        })
        .collect()
}

/// A closed box of quads split in two triangles each (shared edges and vertices everywhere), with
/// a duplicated coplanar quad (exact ties between different triangles) and an inner wall.
fn mesh(cells: usize) -> Vec<Triangle> {
    let mut out = Vec::new();
    let h = 1.0 / cells as f64;
    for face in 0..6u32 {
        let (axis, side) = ((face % 3) as usize, f64::from(face / 3));
        for i in 0..cells {
            for j in 0..cells {
                let p = |a: f64, b: f64| {
                    let mut v = [0.0; 3];
                    v[axis] = side;
                    v[(axis + 1) % 3] = a;
                    v[(axis + 2) % 3] = b;
                    DVec3::from_array(v) * 4.0
                };
                let (a, b) = (i as f64 * h, j as f64 * h);
                let (v0, v1, v2, v3) = (p(a, b), p(a + h, b), p(a + h, b + h), p(a, b + h));
                out.push(tri(v0, v1, v2, face));
                out.push(tri(v0, v2, v3, face));
            }
        }
    }
    let q = [
        DVec3::new(1.0, 1.0, 2.0),
        DVec3::new(3.0, 1.0, 2.0),
        DVec3::new(3.0, 3.0, 2.0),
        DVec3::new(1.0, 3.0, 2.0),
    ];
    for _ in 0..2 {
        out.push(tri(q[0], q[1], q[2], 7));
        out.push(tri(q[0], q[2], q[3], 7));
    }
    out
}

/// Adversarial rays for `tris`: through vertices, edge points and centroids, from points on
/// surfaces, axis-parallel, grazing (in a triangle's plane and within 10⁻¹⁰…10⁻³ rad of it), and
/// random. (origin, direction, t_min, skip).
fn rays(tris: &[Triangle], seed: u64, n: usize) -> Vec<(DVec3, DVec3, f64, u32)> {
    let mut rng = stream(&[seed, 1]);
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for t in tris {
        let (a, b) = t.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let size = (hi - lo).max_element();
    let eps = 1e-9 * lo.abs().max(hi.abs()).max_element().max(1.0);
    let inside = |rng: &mut crate::sample::rng::Stream| {
        lo + (hi - lo) * DVec3::new(rng.gen(), rng.gen(), rng.gen())
    };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let i = rng.gen_range(0..tris.len());
        let t = tris[i];
        let (a, b): (f64, f64) = (rng.gen(), rng.gen());
        let target = match k % 4 {
            0 => t.v[rng.gen_range(0..3)],
            1 => t.v[0] + (t.v[1] - t.v[0]) * a,
            2 => t.centroid(),
            _ => t.v[0] + (t.v[1] - t.v[0]) * a.min(1.0 - b) + (t.v[2] - t.v[0]) * b.min(1.0 - a),
        };
        let ray = match (k / 4) % 8 {
            0 => {
                let o = inside(&mut rng);
                (o, (target - o).normalize(), eps, u32::MAX)
            }
            1 => {
                // From a surface point, leaving it (the photon tracer's case).
                let d = uniform_direction(&mut rng);
                (target, d, eps, i as u32)
            }
            2 => {
                let mut d = DVec3::ZERO;
                d[rng.gen_range(0..3)] = if rng.gen() { 1.0 } else { -1.0 };
                (target - d * size * rng.gen::<f64>(), d, eps, u32::MAX)
            }
            3 => {
                // In the triangle's plane, or tilted out of it by 10⁻¹⁰…10⁻³ rad.
                let n = t.normal();
                let along = (t.v[1] - t.v[0]).normalize();
                let tilt = if rng.gen() {
                    0.0
                } else {
                    10f64.powf(rng.gen_range(-10.0..-3.0))
                };
                let d = (along + n * tilt).normalize();
                (target - d * size * 0.5, d, eps, u32::MAX)
            }
            4 => (target, uniform_direction(&mut rng), 0.0, u32::MAX),
            5 => (
                target + t.normal() * 1e-300,
                uniform_direction(&mut rng),
                0.0,
                u32::MAX,
            ),
            _ => (inside(&mut rng), uniform_direction(&mut rng), eps, u32::MAX),
        };
        out.push(ray);
    }
    out
}

fn paths() -> Vec<Path> {
    [Path::Scalar, Path::Avx2, Path::Avx2Pretest]
        .into_iter()
        .filter(|p| p.available())
        .collect()
}

fn nearest_brute(
    tris: &[Triangle],
    ranks: &[u32],
    (o, d, t_min, skip): (DVec3, DVec3, f64, u32),
    limit: f64,
) -> (f64, u32) {
    let b = two_nearest_brute(tris, ranks, o, d, t_min, skip).first;
    if b.0 < limit {
        b
    } else {
        (f64::INFINITY, u32::MAX)
    }
}

/// Does every hit of the ray lie where the f64 test puts it, within `pad` of its triangle's box?
/// Only then must a BVH find it: a ray within ~10⁻⁹ rad of a triangle's plane can make the f64
/// test accept a t far from the triangle (its determinant is rounding noise), which no box can
/// predict (module doc, "Exactness").
fn hits_lie_in_their_boxes(tris: &[Triangle], o: DVec3, d: DVec3, t_min: f64, pad: f64) -> bool {
    tris.iter().all(|t| {
        t.intersect(o, d, t_min).is_none_or(|h| {
            let (lo, hi) = t.bounds();
            let p = o + d * h;
            (p.clamp(lo, hi) - p).abs().max_element() <= pad
        })
    })
}

/// Every query of every path equals brute force on every ray whose hits lie in their boxes, and
/// those that do not are rare (all grazing).
fn check_scene(name: &str, tris: &[Triangle], seed: u64, n: usize, single_leaf: usize) {
    let bvh = Bvh::build_with(tris, single_leaf);
    let rays = rays(tris, seed, n);
    let magnitude = tris
        .iter()
        .flat_map(|t| t.v)
        .map(|v| v.abs().max_element())
        .fold(1.0, f64::max);
    let unboxed: Vec<usize> = (0..rays.len())
        .filter(|&k| {
            let (o, d, t_min, _) = rays[k];
            !hits_lie_in_their_boxes(tris, o, d, t_min, 1e-9 * magnitude)
        })
        .collect();
    assert!(
        unboxed.iter().all(|k| (k / 4) % 8 == 3) && unboxed.len() * 50 <= rays.len(),
        "{name}: {} rays have hits outside their boxes, not all grazing: {unboxed:?}",
        unboxed.len()
    );
    for path in paths() {
        let bvh = bvh.clone().with_path(path);
        for (k, &(o, d, t_min, skip)) in rays.iter().enumerate() {
            if unboxed.contains(&k) {
                continue;
            }
            let want = two_nearest_brute(tris, bvh.ranks(), o, d, t_min, skip);
            let got = bvh.two_nearest(o, d, t_min, skip);
            assert_eq!(got, want, "{name} {path:?} two_nearest, ray {k}: {o} {d}");
            assert_eq!(
                bvh.nearest(o, d, t_min, skip),
                want.first,
                "{name} {path:?} nearest, ray {k}"
            );
            // Limits at, just before and just after the hits, and in between.
            for limit in [
                want.first.0,
                want.first.0.next_up(),
                want.second.0,
                0.5 * (want.first.0 + want.second.0),
                3.0,
            ] {
                assert_eq!(
                    bvh.nearest_before(o, d, t_min, limit, skip),
                    nearest_brute(tris, bvh.ranks(), (o, d, t_min, skip), limit),
                    "{name} {path:?} nearest_before {limit}, ray {k}"
                );
                assert_eq!(
                    bvh.any_before(o, d, t_min, limit, skip),
                    want.first.0 < limit,
                    "{name} {path:?} any_before {limit}, ray {k}"
                );
            }
        }
    }
}

#[test]
fn random_soup_equals_brute_force_tree_and_single_leaf() {
    let tris = soup(77, 3000, 1.0, 0.0);
    check_scene("soup", &tris, 1, 3000, SINGLE_LEAF);
    let small = soup(78, 40, 1.0, 0.0);
    check_scene("small tree", &small, 2, 2000, 0);
    check_scene("small leaf", &small, 2, 2000, SINGLE_LEAF);
}

#[test]
fn closed_mesh_with_shared_edges_and_duplicates_equals_brute_force() {
    let tris = mesh(12);
    check_scene("mesh tree", &tris, 3, 6000, 0);
    let small = mesh(2);
    check_scene("mesh leaf", &small, 4, 3000, SINGLE_LEAF);
    check_scene("mesh small tree", &small, 4, 3000, 0);
}

#[test]
fn huge_and_tiny_coordinates_equal_brute_force() {
    check_scene("huge", &soup(79, 800, 1e7, 1e3), 5, 1500, 0);
    check_scene("tiny", &soup(80, 800, 1e-7, -5.0), 6, 1500, 0);
    check_scene("far from origin", &soup(81, 800, 1.0, 1e6), 7, 1500, 0);
}

#[test]
fn answers_equal_the_f3d7ed0_bvh() {
    // One leaf then (≤ 64 triangles): its index-order fold is the order-free rule exactly.
    for (tris, single) in [
        (mesh(2), true),
        (soup(82, 60, 1.0, 0.0), true),
        (mesh(10), false),
        (soup(83, 2000, 1.0, 0.0), false),
    ] {
        let old = legacy::Bvh::build(&tris);
        let new = Bvh::build(&tris);
        for (k, &(o, d, t_min, skip)) in rays(&tris, 8, 3000).iter().enumerate() {
            let mut want = TwoNearest::default();
            old.two_nearest(&tris, o, d, t_min, skip, &mut want);
            let got = new.two_nearest(o, d, t_min, skip);
            let old_near = old.nearest(&tris, o, d, t_min, skip);
            if single {
                assert_eq!(got, want, "ray {k}");
                assert_eq!(new.nearest(o, d, t_min, skip), old_near, "ray {k}");
            } else {
                // A tree's traversal order decides exact ties between triangles: compare t.
                assert_eq!(
                    (got.first.0, got.second.0),
                    (want.first.0, want.second.0),
                    "ray {k}"
                );
                assert_eq!(new.nearest(o, d, t_min, skip).0, old_near.0, "ray {k}");
            }
        }
    }
}

#[test]
fn packet_test_is_triangle_intersect_bit_for_bit() {
    let mut rng = stream(&[84]);
    let mut tris = soup(85, 400, 1.0, 0.0);
    tris.extend(mesh(3));
    let rays = rays(&tris, 9, 4000);
    for chunk in tris.chunks(4) {
        let with_ids: Vec<(u32, Triangle)> = chunk.iter().map(|&t| (0, t)).collect();
        let p = Packet::new(&with_ids);
        for _ in 0..40 {
            let (o, d, t_min, _) = rays[rng.gen_range(0..rays.len())];
            let r = RayData::new(o.to_array(), d.to_array(), 100.0);
            let mut ts = [0.0; 4];
            let m = packet_scalar(&p, &r, t_min, &mut ts);
            #[cfg(target_arch = "x86_64")]
            if Path::Avx2.available() {
                let mut ta = [0.0; 4];
                // SAFETY: AVX2 checked.
                let ma = unsafe { super::kernel::avx2::packet(&p, &r, t_min, &mut ta) };
                assert_eq!(ma, m);
                for l in 0..4 {
                    if m & (1 << l) != 0 {
                        assert_eq!(ta[l].to_bits(), ts[l].to_bits());
                    }
                }
            }
            for (l, t) in chunk.iter().enumerate() {
                let want = t.intersect(o, d, t_min);
                let got = (m & (1 << l) != 0).then_some(ts[l]);
                assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
            }
            assert_eq!(m >> chunk.len(), 0, "unused lanes never hit");
        }
    }
}

/// The f32 triangle pre-test never clears a lane the f64 test hits: triangles at scales 10⁻⁷ to
/// 10⁸ (in its domain) and 10¹¹ (out of it), 10⁶ off the origin, slivers and degenerate ones,
/// under the adversarial rays, with t_min at 0, negative, and at and around each lane's own hit
/// distance. It must also do its job: clear most lanes the f64 test misses on the plain soup.
#[cfg(target_arch = "x86_64")]
#[test]
fn f32_pretest_never_clears_a_hit_lane() {
    use super::kernel::{avx2::keep, pretest_t_min};
    use super::layout::PacketF32;
    if !Path::Avx2.available() {
        return;
    }
    let mut rng = stream(&[87]);
    let mut slivers = soup(91, 200, 1.0, 0.0);
    for t in slivers.iter_mut().step_by(2) {
        // A sliver: v2 within 10⁻⁹…10⁻³ of the edge v0v1; every fourth one collapsed onto it.
        let a: f64 = rng.gen();
        let off = 10f64.powf(rng.gen_range(-9.0..-3.0)) * (rng.gen::<u32>() % 4 != 0) as u8 as f64;
        t.v[2] = t.v[0] + (t.v[1] - t.v[0]) * a + uniform_direction(&mut rng) * off;
    }
    let scenes = [
        ("soup", soup(92, 400, 1.0, 0.0)),
        ("mesh", mesh(3)),
        ("slivers", slivers),
        ("tiny", soup(93, 200, 1e-7, -5.0)),
        ("large, in domain", soup(94, 200, 1e7, 0.0)),
        ("huge, out of domain", soup(95, 200, 1e7, 1e3)),
        ("far from origin", soup(96, 200, 1.0, 1e6)),
    ];
    for (name, tris) in scenes {
        let rays = rays(&tris, 10, 3000);
        let packets: Vec<Packet> = tris
            .chunks(4)
            .map(|c| Packet::new(&c.iter().map(|&t| (0, t)).collect::<Vec<_>>()))
            .collect();
        let pre: Vec<PacketF32> = packets.iter().map(PacketF32::new).collect();
        let (mut misses, mut cleared) = (0u64, 0u64);
        for (o, d, t_min, _) in rays {
            let r = RayData::new(o.to_array(), d.to_array(), 100.0).with_pretest();
            let i = rng.gen_range(0..packets.len());
            let j = rng.gen_range(0..packets.len());
            // The lanes' own hit distances, to put t_min on and around them.
            let mut hit_ts = vec![];
            for k in [i, j] {
                let mut ts = [0.0; 4];
                let m = packet_scalar(&packets[k], &r, f64::NEG_INFINITY, &mut ts);
                (0..4)
                    .filter(|l| m & (1 << l) != 0)
                    .for_each(|l| hit_ts.push(ts[l]));
            }
            let mut t_mins = vec![t_min, 0.0, -1.0, f64::NEG_INFINITY];
            for &t in &hit_ts {
                for f in [1.0, 1.0 - 1e-7, 1.0 + 1e-7, 1.0 - 1e-15, 0.5, 2.0] {
                    t_mins.push(t * f);
                }
                t_mins.push(t.next_down());
            }
            for tm in t_mins {
                // SAFETY: AVX2 checked above.
                let kept = unsafe { keep(&pre[i], &pre[j], &r, pretest_t_min(tm)) };
                for (half, k) in [(0, i), (1, j)] {
                    let mut ts = [0.0; 4];
                    let hit = packet_scalar(&packets[k], &r, tm, &mut ts);
                    let kept = (kept >> (4 * half)) & 0xF;
                    assert_eq!(
                        hit & !kept,
                        0,
                        "{name}: the pre-test cleared a hit lane (o {o}, d {d}, t_min {tm})"
                    );
                    let live = pre[k].live;
                    misses += u64::from((live & !hit).count_ones());
                    cleared += u64::from((live & !kept).count_ones());
                }
            }
        }
        let share = cleared as f64 / misses.max(1) as f64;
        eprintln!("{name}: the pre-test cleared {cleared} of {misses} missed lanes ({share:.3})");
        if name == "huge, out of domain" {
            assert_eq!(
                cleared, 0,
                "out of its domain the pre-test keeps every lane"
            );
        } else if name == "soup" {
            assert!(
                share > 0.9,
                "the pre-test clears only {share:.3} of the misses"
            );
        }
    }
}

/// The culled list keeps up to its size, says when it overflowed (the second pass then starts at
/// the root), and orders itself so the nearest subtree is popped first.
#[test]
fn culled_subtrees_are_kept_in_order_until_the_list_overflows() {
    use super::kernel::{Culled, Deferred, CULLED};
    let mut c = Culled::new();
    for k in 0..CULLED {
        c.keep(ChildRef::node(k), ((k * 37) % CULLED) as f32);
    }
    assert!(!c.overflow);
    c.sort_far_first();
    let entries: Vec<f32> = c.entries().map(|e| e.1).collect();
    assert_eq!(entries.len(), CULLED);
    assert!(entries.windows(2).all(|w| w[0] >= w[1]), "{entries:?}");
    c.keep(ChildRef::node(0), 0.0);
    assert!(c.overflow);
    assert_eq!(c.entries().count(), CULLED);
}

/// Conservativeness of the f32 box test: every point of a box, reached along any ray at parameter
/// t, passes the test with t_min = t_max = t (origins far and near, tiny and zero direction
/// components, points on faces and corners).
#[test]
fn f32_box_test_accepts_every_point_of_the_box() {
    let mut rng = stream(&[86]);
    for k in 0..20_000 {
        let scale = 10f64.powi(rng.gen_range(-6..7));
        let c = DVec3::new(rng.gen(), rng.gen(), rng.gen())
            * scale
            * if k % 3 == 0 { 1e3 } else { 1.0 };
        let lo = c;
        let hi = c + DVec3::new(rng.gen(), rng.gen(), rng.gen())
            * scale
            * if k % 5 == 0 { 1e-9 } else { 1.0 };
        // A point of the box: inside, on a face, or a corner.
        let mut p = lo + (hi - lo) * DVec3::new(rng.gen(), rng.gen(), rng.gen());
        for a in 0..3 {
            match rng.gen_range(0..4) {
                0 => p[a] = lo[a],
                1 => p[a] = hi[a],
                _ => {}
            }
        }
        let mut d = uniform_direction(&mut rng);
        for a in 0..3 {
            match rng.gen_range(0..6) {
                0 => d[a] = 0.0,
                1 => d[a] *= 1e-30,
                2 => d[a] = -0.0,
                _ => {}
            }
        }
        if d == DVec3::ZERO {
            d = DVec3::X;
        }
        let t = scale * 10f64.powf(rng.gen_range(-3.0..3.0));
        let o = p - d * t;
        // The parameter at which the f64 ray really reaches p (o was rounded).
        let t = (0..3)
            .filter(|&a| d[a].abs() > 1e-3)
            .map(|a| (p[a] - o[a]) / d[a])
            .next()
            .unwrap_or(t);
        let mut node = Node::empty();
        node.set(3, ChildRef::leaf(0, 1), lo, hi);
        let bound = f64::from(f32_up(lo.abs().max(hi.abs()).max_element()));
        let r = RayData::new(o.to_array(), d.to_array(), bound);
        let mut near = [0.0; WIDTH];
        let (tlo, thi) = (f32_down(t * (1.0 - 1e-15)), f32_up(t * (1.0 + 1e-15)));
        let m = node_scalar(&node, &r, tlo, thi, &mut near);
        assert_eq!(m, 1 << 3, "case {k}: box {lo}–{hi}, o {o}, d {d}, t {t}");
        #[cfg(target_arch = "x86_64")]
        if Path::Avx2.available() {
            let mut near2 = [0.0; WIDTH];
            // SAFETY: AVX2 checked.
            let m2 = unsafe { super::kernel::avx2::node(&node, &r, tlo, thi, &mut near2) };
            assert_eq!(m2, m, "case {k}");
            assert_eq!(near2[3].to_bits(), near[3].to_bits());
        }
    }
}

#[test]
fn boxes_far_from_the_ray_are_culled() {
    // The test must also cull: a ray along +x misses a box above it, and one behind t_max.
    let mut node = Node::empty();
    node.set(
        0,
        ChildRef::leaf(0, 1),
        DVec3::new(1.0, 1.0, -1.0),
        DVec3::new(2.0, 2.0, 1.0),
    );
    node.set(
        1,
        ChildRef::leaf(0, 1),
        DVec3::new(5.0, -1.0, -1.0),
        DVec3::new(6.0, 1.0, 1.0),
    );
    node.set(
        2,
        ChildRef::leaf(0, 1),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(2.0, 1.0, 1.0),
    );
    let r = RayData::new([0.0; 3], [1.0, 0.0, 0.0], 6.0);
    let mut near = [0.0; WIDTH];
    assert_eq!(node_scalar(&node, &r, 0.0, 3.0, &mut near), 1 << 2);
    assert!((near[2] - 1.0).abs() < 1e-5);
}

#[test]
fn equal_t_on_a_shared_edge_is_one_crossing() {
    let mut b = TwoNearest::default();
    b.offer(2.0, 0);
    b.offer(2.0, 1);
    b.offer(5.0, 2);
    assert_eq!(b.first, (2.0, 0));
    assert_eq!(b.second, (5.0, 2));
    // The same through the BVH: a ray through the diagonal of a quad.
    let q = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    let far = [
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::new(1.0, 0.0, 3.0),
        DVec3::new(0.0, 1.0, 3.0),
    ];
    let tris = [
        tri(q[0], q[1], q[2], 0),
        tri(q[0], q[2], q[3], 0),
        tri(far[0], far[1], far[2], 1),
    ];
    for single in [0, 64] {
        let bvh = Bvh::build_with(&tris, single);
        let got = bvh.two_nearest(DVec3::new(0.25, 0.25, -1.0), DVec3::Z, 0.0, u32::MAX);
        assert_eq!(got.first, (1.0, 0));
        assert_eq!(got.second, (4.0, 2));
    }
}

#[test]
fn three_crossings_within_the_tolerance_take_the_second_pass() {
    // Parallel planes 0.6·10⁻¹² apart at t ≈ 1: each within 10⁻¹² of the next, the outer two not;
    // offered farthest first, each new first drops the previous one.
    let plane = |z: f64, id| {
        tri(
            DVec3::new(-1.0, -1.0, z),
            DVec3::new(3.0, -1.0, z),
            DVec3::new(-1.0, 3.0, z),
            id,
        )
    };
    let tris = [
        plane(1.0 + 1.2e-12, 0),
        plane(1.0 + 0.6e-12, 1),
        plane(1.0, 2),
        plane(7.0, 3),
    ];
    let o = DVec3::new(0.1, 0.2, 0.0);
    let ranks: Vec<u32> = (0..4).collect();
    let want = two_nearest_brute(&tris, &ranks, o, DVec3::Z, 0.0, u32::MAX);
    assert_eq!(want.first.1, 2);
    assert_eq!(want.second.1, 0, "the crossing 1.2·10⁻¹² beyond the first");
    // Where the order-dependent fold of f3d7ed0 loses it (the only case it differs).
    let mut fold = TwoNearest::default();
    for (i, t) in tris.iter().enumerate() {
        if let Some(t) = t.intersect(o, DVec3::Z, 0.0) {
            fold.offer(t, i as u32);
        }
    }
    assert_eq!(fold.first, want.first);
    assert_eq!(fold.second.1, 3);
    for single in [0, 64] {
        for path in paths() {
            let bvh = Bvh::build_with(&tris, single).with_path(path);
            assert_eq!(bvh.two_nearest(o, DVec3::Z, 0.0, u32::MAX), want);
        }
    }
}

#[test]
fn near_returns_a_superset_of_the_triangles_within_r() {
    let tris = soup(87, 2000, 1.0, 0.0);
    let bvh = Bvh::build(&tris);
    let mut rng = stream(&[88]);
    for _ in 0..200 {
        let p = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 10.0;
        let r = rng.gen::<f64>();
        let mut got = Vec::new();
        bvh.near(p, r, &mut |i| got.push(i));
        for (i, t) in tris.iter().enumerate() {
            let (lo, hi) = t.bounds();
            if (p.clamp(lo, hi) - p).length() <= r {
                assert!(got.contains(&(i as u32)), "triangle {i} within {r} of {p}");
            }
        }
    }
}
