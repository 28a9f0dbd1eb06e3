//! Every DETP engine — sphere cache (both list modes, all orders, several Q, thresholds and chunk
//! sizes, every filter path this CPU has), grid index, octree — must give the brute-force sums bit
//! for bit, on random scenes and on adversarial ones: segments grazing disc rims, discs and
//! segments exactly on grid cell faces, edges and octree split planes, segments in a disc's plane,
//! segments ending exactly on it, discs larger than cells, a scene moved by 10⁶, t_end finite and
//! +∞. Adding every segment and then removing some through either index must equal the remaining
//! segments.

use glam::DVec3;
use rand::Rng;
use raycost::detp::brute;
use raycost::detp::disc::Discs;
use raycost::detp::disc_index::{DiscIndex, GridIndex, Octree};
use raycost::detp::fixed::{Acc, PowerScale};
use raycost::detp::order::{permutation, Order};
use raycost::detp::sphere_cache::filter::FilterPath;
use raycost::detp::sphere_cache::{root_sphere, run_with, ListMode, PopRule, SphereCacheParams};
use raycost::detp::store::{Segment, SegmentStore};
use raycost::sample::lines::{uniform_line, uniform_on_sphere};
use raycost::sample::rng::{stream, Stream};

fn store(segs: Vec<Segment>) -> SegmentStore {
    SegmentStore::new(segs, PowerScale::for_max_power(1.0))
}

fn power(rng: &mut Stream) -> u32 {
    rng.gen_range(1..1_000_000)
}

/// μ-random lines through the ball (centre, radius), from their first point on its surface; every
/// other one ends at the second point.
fn lines(rng: &mut Stream, n: u32, center: DVec3, rad: f64) -> Vec<Segment> {
    (0..n)
        .map(|k| {
            let (p, d) = uniform_line(rng);
            let t_end = if k % 2 == 0 {
                f64::INFINITY
            } else {
                -2.0 * p.dot(d) * rad
            };
            Segment::new(center + p * rad, d, 0.0, t_end, power(rng), k)
        })
        .collect()
}

fn ball_discs(rng: &mut Stream, n: usize, center: DVec3, rad: f64, d: f64) -> Discs {
    Discs::in_ball(rng, n, center, rad, d)
}

/// Runs every engine on (store, discs) and asserts equality with brute force; returns the number
/// of discs with a non-zero sum (so callers can check their scene exercises something).
fn all_engines_agree(label: &str, st: &SegmentStore, discs: &Discs, every_path: bool) -> usize {
    let mut want = vec![0 as Acc; discs.len()];
    brute::accumulate(st, discs, None, 1, &mut want);
    let root = root_sphere(&discs.bounds_all());
    let paths = if every_path {
        FilterPath::all_available()
    } else {
        vec![FilterPath::detect()]
    };
    for (q, threshold, chunk) in [(2.0 / 3.0, 100, 64), (0.5, 8, 1_000_000), (0.85, 30, 5)] {
        for (mode, pop) in [
            (ListMode::Exact, PopRule::Chain),
            (ListMode::Exact, PopRule::Paper),
            (ListMode::Inherited, PopRule::Chain),
            (ListMode::Inherited, PopRule::Paper),
        ] {
            for order in [Order::None, Order::Morton, Order::Hilbert] {
                let perm = permutation(&discs.centers, order, 10);
                let params = SphereCacheParams {
                    q,
                    threshold,
                    list_mode: mode,
                    pop_rule: pop,
                    chunk_points: chunk,
                    law_ball: None,
                };
                for &path in &paths {
                    let mut acc = vec![0; discs.len()];
                    run_with(st, discs, &perm, root, &params, &mut acc, path);
                    assert_eq!(
                        acc, want,
                        "{label}: sphere cache Q {q} {mode:?} {pop:?} {order:?} {path:?}"
                    );
                }
            }
        }
    }
    let side = (discs.bounds_all().hi - discs.bounds_all().lo).max_element();
    for width in [side / 7.0, side / 40.0, discs.radius * 0.5] {
        let g = GridIndex::build(discs, width);
        let mut acc = vec![0; discs.len()];
        g.accumulate(st, None, 1, &mut acc);
        assert_eq!(acc, want, "{label}: grid index, cell width {width}");
    }
    for (max_leaf, min_side) in [(1, discs.radius / 2.0), (8, discs.radius), (64, side / 4.0)] {
        let o = Octree::build(discs, max_leaf, min_side);
        let mut acc = vec![0; discs.len()];
        o.accumulate(st, None, 1, &mut acc);
        assert_eq!(acc, want, "{label}: octree max_leaf {max_leaf}");
    }
    want.iter().filter(|&&a| a != 0).count()
}

#[test]
fn random_lines_and_points_in_the_ball() {
    let mut rng = stream(&[0xe0, 1]);
    let st = store(lines(&mut rng, 20_000, DVec3::ZERO, 1.0));
    let discs = ball_discs(&mut rng, 1_000, DVec3::ZERO, 1.0, 0.05);
    let hit = all_engines_agree("random", &st, &discs, true);
    assert!(hit > 500, "only {hit} discs crossed");
}

#[test]
fn a_scene_moved_by_a_million() {
    let off = DVec3::new(1e6, -1e6, 1e6);
    let mut rng = stream(&[0xe0, 2]);
    let st = store(lines(&mut rng, 10_000, off, 1.0));
    let discs = ball_discs(&mut rng, 400, off, 1.0, 0.05);
    let hit = all_engines_agree("offset 1e6", &st, &discs, true);
    assert!(hit > 150, "only {hit} discs crossed");
}

/// Segments aimed at rim points of each disc (the rim is closed: |x − c| ≤ d), nudged by 0 or ±1–4
/// ulps of d, from random directions on the front side, some ending exactly at the rim point.
#[test]
fn segments_grazing_disc_rims() {
    let mut rng = stream(&[0xe0, 3]);
    let discs = ball_discs(&mut rng, 300, DVec3::ZERO, 1.0, 0.08);
    let mut segs = Vec::new();
    for i in 0..discs.len() {
        let (c, n) = (discs.centers[i], discs.normals[i]);
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        for k in 0..12 {
            let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            let nudge = 1.0 + f64::from(rng.gen_range(-4..=4)) * f64::EPSILON;
            let x = c + (u * a.cos() + w * a.sin()) * discs.radius * nudge;
            // A direction against the normal (front side), sometimes almost in the plane.
            let mut dir = uniform_on_sphere(&mut rng);
            if dir.dot(n) > 0.0 {
                dir = -dir;
            }
            if k % 4 == 0 {
                dir = (dir - n * dir.dot(n) * 0.999_999).normalize();
            }
            let back: f64 = rng.gen_range(0.01..1.0);
            let t_end = match k % 3 {
                0 => back,
                1 => f64::INFINITY,
                _ => back * 2.0,
            };
            segs.push(Segment::new(
                x - dir * back,
                dir,
                0.0,
                t_end,
                power(&mut rng),
                0,
            ));
        }
    }
    let st = store(segs);
    let hit = all_engines_agree("rims", &st, &discs, true);
    assert!(hit > 200, "only {hit} discs crossed");
}

/// Discs centred exactly on grid cell faces, edges and corners and on octree split planes, with
/// axis-aligned normals, crossed by axis-parallel segments running in those planes and along those
/// edges, and by segments in a disc's plane (never counted) or ending exactly on it (counted).
#[test]
fn discs_and_segments_on_cell_faces_edges_and_split_planes() {
    // Eight anchors at the corners fix the bounds, so adding interior discs keeps the grid frame
    // and the octree's split planes.
    let d = 0.05;
    let mut centers: Vec<DVec3> = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { -1.0 } else { 1.0 },
                if k & 2 == 0 { -1.0 } else { 1.0 },
                if k & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let mut normals = vec![DVec3::Z; 8];
    let anchors = Discs::new(centers.clone(), normals.clone(), d).unwrap();
    let width = 0.125;
    let frame = *GridIndex::build(&anchors, width).frame();
    let b = anchors.bounds_all();
    let mid = (b.lo + b.hi) * 0.5;
    let quarter = (b.lo + mid) * 0.5;
    // Coordinates on grid planes and octree split planes.
    let mut planes: Vec<[f64; 3]> = Vec::new();
    for k in [3i32, 8, 11] {
        planes.push((frame.origin + DVec3::splat(f64::from(k) * width)).to_array());
    }
    planes.push(mid.to_array());
    planes.push(quarter.to_array());
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut rng = stream(&[0xe0, 4]);
    for p in &planes {
        for q in &planes {
            for r in &planes {
                let c = DVec3::new(p[0], q[1], r[2]);
                centers.push(c);
                normals.push(axes[rng.gen_range(0..3)] * if rng.gen() { 1.0 } else { -1.0 });
            }
        }
    }
    let discs = Discs::new(centers, normals, d).unwrap();
    assert_eq!(
        discs.bounds_all(),
        b,
        "interior discs must not move the bounds"
    );
    assert_eq!(*GridIndex::build(&discs, width).frame(), frame);
    let mut segs = Vec::new();
    for i in 8..discs.len() {
        let (c, n) = (discs.centers[i], discs.normals[i]);
        for (k, &ax) in axes.iter().enumerate() {
            for sgn in [1.0, -1.0] {
                let dir = ax * sgn;
                // Along the axis through the centre (in the cell faces/edges the centre lies on),
                // and offset by exactly d (the rim) along another axis.
                let side = axes[(k + 1) % 3] * d;
                for start in [c - dir * 3.0, c - dir * 3.0 + side, c - dir * 0.5 - side] {
                    for t_end in [f64::INFINITY, 3.0, 0.5, 2.0] {
                        segs.push(Segment::new(start, dir, 0.0, t_end, power(&mut rng), 0));
                    }
                }
            }
        }
        // In the disc's plane (edge-on, never counted).
        let u = n.any_orthonormal_vector();
        segs.push(Segment::new(
            c - u,
            u,
            0.0,
            f64::INFINITY,
            power(&mut rng),
            0,
        ));
        // Ending exactly on the plane (counted), from 0.25 in front.
        let off = n.any_orthonormal_vector() * 0.01;
        segs.push(Segment::new(
            c + n * 0.25 + off,
            -n,
            0.0,
            0.25,
            power(&mut rng),
            0,
        ));
        // Starting exactly on the plane (not counted) and leaving through it.
        segs.push(Segment::new(c + off, -n, 0.0, 1.0, power(&mut rng), 0));
    }
    let st = store(segs);
    let hit = all_engines_agree("faces/edges/split planes", &st, &discs, false);
    assert!(hit > 100, "only {hit} discs crossed");
    // The ending-on-the-plane segments must have counted, the edge-on ones not.
    let mut acc = vec![0; discs.len()];
    brute::accumulate(&st, &discs, None, 1, &mut acc);
    assert!(acc[8..].iter().all(|&a| a > 0));
}

/// Discs larger than grid cells and octree leaves, and near-coplanar segments.
#[test]
fn discs_larger_than_cells_and_near_coplanar_segments() {
    let mut rng = stream(&[0xe0, 5]);
    let discs = ball_discs(&mut rng, 150, DVec3::ZERO, 1.0, 0.4);
    let mut segs = lines(&mut rng, 3_000, DVec3::ZERO, 1.3);
    for i in 0..discs.len() {
        let (c, n) = (discs.centers[i], discs.normals[i]);
        let u = n.any_orthonormal_vector();
        for tilt in [0.0, 1e-12, -1e-12, 1e-6] {
            let dir = (u - n * tilt).normalize();
            segs.push(Segment::new(
                c - u * 0.5 + n * 1e-13,
                dir,
                0.0,
                1.0,
                power(&mut rng),
                0,
            ));
        }
    }
    let st = store(segs);
    let hit = all_engines_agree("large discs", &st, &discs, false);
    assert!(hit > 100, "only {hit} discs crossed");
    for width in [0.05, 0.2] {
        let g = GridIndex::build(&discs, width);
        let mut acc = vec![0; discs.len()];
        let s = g.accumulate(&st, None, 1, &mut acc);
        assert!(s.ray_disc_tests > 0);
    }
}

/// Add every segment, remove a random half, through both indexes, on an adversarial scene:
/// the result equals accumulating the kept half, bit for bit.
#[test]
fn add_then_remove_equals_the_complement() {
    let off = DVec3::new(1e6, 0.0, -1e6);
    let mut rng = stream(&[0xe0, 6]);
    let st = store(lines(&mut rng, 12_000, off, 1.0));
    let discs = ball_discs(&mut rng, 500, off, 1.0, 0.07);
    let removed: Vec<u32> = (0..st.len() as u32).filter(|_| rng.gen()).collect();
    let kept: Vec<Segment> = (0..st.len())
        .filter(|k| removed.binary_search(&(*k as u32)).is_err())
        .map(|k| st.segments[k])
        .collect();
    let mut want = vec![0; discs.len()];
    brute::accumulate(&store(kept), &discs, None, 1, &mut want);
    assert!(want.iter().filter(|&&a| a != 0).count() > 200);
    fn add_remove<I: DiscIndex>(ix: &I, st: &SegmentStore, removed: &[u32], n: usize) -> Vec<Acc> {
        let mut acc = vec![0; n];
        ix.accumulate(st, None, 1, &mut acc);
        ix.accumulate(st, Some(removed), -1, &mut acc);
        acc
    }
    let grid = GridIndex::build(&discs, 0.1);
    assert_eq!(add_remove(&grid, &st, &removed, discs.len()), want, "grid");
    let octree = Octree::build(&discs, 8, 0.05);
    assert_eq!(
        add_remove(&octree, &st, &removed, discs.len()),
        want,
        "octree"
    );
}

/// `detp.edge` remedies: per-disc radii (each in (0, d], some rims grazed by aimed segments) and
/// segments cut at their first impact. Engines bound discs by d, so they must still equal brute
/// force, which tests each disc with its own radius.
#[test]
fn per_disc_radii_and_first_hit_cuts() {
    let mut rng = stream(&[0xe0, 9]);
    let mut segs = lines(&mut rng, 20_000, DVec3::ZERO, 1.0);
    let discs = ball_discs(&mut rng, 1_000, DVec3::ZERO, 1.0, 0.05);
    let radii: Vec<f64> = (0..discs.len())
        .map(|i| match i % 4 {
            0 => 0.05,
            1 => 0.05 * rng.gen_range(0.05..1.0),
            2 => 0.0125,
            _ => 0.05 * f64::EPSILON.max(rng.gen::<f64>()),
        })
        .collect();
    // Segments aimed at the rim of each small disc (rim closed: these count, 1 ulp farther not).
    for i in (1..discs.len()).step_by(4) {
        let (c, n, r) = (discs.centers[i], discs.normals[i], radii[i]);
        let u = n.any_orthonormal_vector();
        let x = c + u * r;
        let v = (-n + u * 0.3).normalize();
        segs.push(Segment::new(x - v * 0.5, v, 0.0, 0.5, power(&mut rng), 0));
    }
    // Cut every other segment somewhere along it, as first-hit does with t_hit + gap.
    for (k, s) in segs.iter_mut().enumerate() {
        if k % 2 == 0 {
            s.t_hit = rng.gen_range(0.0..2.0);
            s.t_end = s.t_end.min(s.t_hit + 0.01);
        }
    }
    let discs = discs.with_radii(radii).unwrap();
    let st = store(segs);
    let hit = all_engines_agree("per-disc radii, cut segments", &st, &discs, false);
    assert!(hit > 300, "only {hit} discs crossed");
    // And the radii matter: with radius d everywhere some sums differ.
    let mut full = vec![0 as Acc; discs.len()];
    let mut plain = discs.clone();
    plain.radii = None;
    brute::accumulate(&st, &plain, None, 1, &mut full);
    let mut small = vec![0 as Acc; discs.len()];
    brute::accumulate(&st, &discs, None, 1, &mut small);
    assert!(full.iter().zip(&small).filter(|(a, b)| a != b).count() > 100);
}
