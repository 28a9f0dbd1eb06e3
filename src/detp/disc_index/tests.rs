//! Both indexes against the oracle, add-then-remove, thread-count independence, the slab clip.

use glam::DVec3;

use super::*;
use crate::detp::brute;
use crate::sample::rng::stream;

pub(super) fn scene(n_seg: u32, n_disc: usize, d: f64, seed: u64) -> (SegmentStore, Discs) {
    let mut rng = stream(&[0xd1, seed]);
    let store = SegmentStore::test_lines(&mut rng, n_seg);
    (store, Discs::in_ball(&mut rng, n_disc, DVec3::ZERO, 1.0, d))
}

/// Segments that stress the walks' arithmetic: starting at disc centres and on the discs' box
/// (the root's and the grid's faces), axis-parallel and in coordinate planes (zero direction
/// components), with tiny components, of zero and tiny length, through the box's corners.
pub(super) fn adversarial_segments(discs: &Discs, seed: u64) -> Vec<Segment> {
    use rand::Rng;
    let mut rng = stream(&[0xad5, seed]);
    let b = discs.bounds_all();
    let dirs = [
        DVec3::X,
        -DVec3::Y,
        DVec3::Z,
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, -1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, 1e-30, -1e-30),
        DVec3::new(-1.0, 1.0, 1e-300),
    ];
    let mut out = Vec::new();
    for k in 0..600u32 {
        let c = discs.centers[rng.gen_range(0..discs.len())];
        let o = match k % 4 {
            0 => c,
            1 => DVec3::new(b.lo.x, c.y, c.z),
            2 => b.hi,
            _ => DVec3::new(c.x, b.lo.y, b.hi.z),
        };
        let d = if k % 3 == 0 {
            crate::sample::lines::uniform_on_sphere(&mut rng)
        } else {
            dirs[rng.gen_range(0..dirs.len())] * if rng.gen_bool(0.5) { 1.0 } else { -1.0 }
        };
        let t_end = match k % 5 {
            0 => 0.0,
            1 => 1e-9,
            2 => rng.gen_range(0.0..0.5),
            _ => f64::INFINITY,
        };
        out.push(Segment::new(o, d, 0.0, t_end, 1 + k % 7, k));
    }
    out
}

fn indexes(discs: &Discs) -> Vec<(&'static str, Box<dyn Run>)> {
    vec![
        ("grid", Box::new(GridIndex::build(discs, 0.1))),
        ("octree", Box::new(Octree::build(discs, 8, 0.02))),
    ]
}

/// Object-safe view of [`DiscIndex::accumulate`] for looping over both indexes.
trait Run: Sync {
    fn run(&self, s: &SegmentStore, seg: Option<&[u32]>, sign: i8, acc: &mut [Acc]) -> IndexStats;
    fn size(&self) -> usize;
}

impl<T: DiscIndex> Run for T {
    fn run(&self, s: &SegmentStore, seg: Option<&[u32]>, sign: i8, acc: &mut [Acc]) -> IndexStats {
        self.accumulate(s, seg, sign, acc)
    }
    fn size(&self) -> usize {
        self.bytes()
    }
}

#[test]
fn both_indexes_equal_brute_force_and_add_then_remove_equals_the_complement() {
    let (store, discs) = scene(20_000, 2_000, 0.06, 1);
    let mut want = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut want);
    assert!(want.iter().filter(|&&a| a != 0).count() > 1000);
    let removed: Vec<u32> = (0..store.len() as u32).filter(|k| k % 3 == 1).collect();
    let kept: Vec<u32> = (0..store.len() as u32).filter(|k| k % 3 != 1).collect();
    let only_kept = {
        let st = SegmentStore::new(
            kept.iter().map(|&k| store.segments[k as usize]).collect(),
            store.scale,
        );
        let mut a = vec![0; discs.len()];
        brute::accumulate(&st, &discs, None, 1, &mut a);
        a
    };
    for (name, ix) in indexes(&discs) {
        let mut acc = vec![0; discs.len()];
        let s = ix.run(&store, None, 1, &mut acc);
        assert_eq!(acc, want, "{name}");
        assert!(
            s.ray_disc_tests < store.len() as u64 * discs.len() as u64 / 10,
            "{name} culls"
        );
        ix.run(&store, Some(&removed), -1, &mut acc);
        // Discs (48 B each) plus at least one listing (4 B) per disc.
        assert!(ix.size() >= discs.len() * 52, "{name}: {} bytes", ix.size());
        assert_eq!(acc, only_kept, "{name}: add all, remove a third");
    }
}

/// Every SIMD path, on random and adversarial segments, with one radius and radii per disc: the
/// sums equal brute force, and `traversal_only` counts exactly what `accumulate` counts (all
/// segments, or a listed subset).
#[test]
fn every_path_equals_brute_force_and_the_walk_alone_counts_the_same() {
    let (mut store, discs) = scene(4_000, 1_500, 0.05, 5);
    store.segments.extend(adversarial_segments(&discs, 5));
    let radii = (0..discs.len()).map(|i| 0.01 + 0.04 * (i % 5) as f64 / 4.0);
    let each = discs.clone().with_radii(radii.collect()).unwrap();
    for discs in [discs, each] {
        let mut want = vec![0; discs.len()];
        brute::accumulate(&store, &discs, None, 1, &mut want);
        for path in SimdPath::all_available() {
            let ixs: Vec<(&str, Box<dyn DiscIndex>)> = vec![
                (
                    "grid",
                    Box::new(GridIndex::build(&discs, 0.1).with_path(path)),
                ),
                (
                    "octree",
                    Box::new(Octree::build(&discs, 8, 0.02).with_path(path)),
                ),
            ];
            for (name, ix) in ixs {
                let mut acc = vec![0; discs.len()];
                let st = ix.accumulate(&store, None, 1, &mut acc);
                assert_eq!(acc, want, "{name} {path:?}");
                assert_eq!(ix.traversal_only(&store, None), st, "{name} {path:?}");
                // And over a listed subset (how quasi-static frames walk the index).
                let some: Vec<u32> = (0..store.len() as u32).step_by(3).collect();
                let st = ix.accumulate(&store, Some(&some), 1, &mut acc);
                assert_eq!(
                    ix.traversal_only(&store, Some(&some)),
                    st,
                    "{name} {path:?}"
                );
            }
        }
    }
}

#[test]
fn the_octree_splits_until_leaves_are_small_or_sides_reach_the_limit() {
    let (_, discs) = scene(1, 4_000, 0.01, 4);
    let deep = Octree::build(&discs, 8, 0.01);
    let shallow = Octree::build(&discs, 8, 0.5);
    // Sides halve from ~2: a 0.5 limit allows two splits (at most 1 + 8 + 64 nodes).
    assert!(
        shallow.nodes() > 9 && shallow.nodes() <= 73,
        "{}",
        shallow.nodes()
    );
    assert!(
        deep.nodes() > 8 * shallow.nodes(),
        "{} vs {}",
        deep.nodes(),
        shallow.nodes()
    );
}

#[test]
fn counters_do_not_depend_on_the_thread_count() {
    let (store, discs) = scene(8_000, 500, 0.05, 2);
    for (name, ix) in indexes(&discs) {
        let on = |k: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(k)
                .build()
                .unwrap();
            pool.install(|| {
                let mut acc = vec![0; discs.len()];
                let s = ix.run(&store, None, 1, &mut acc);
                (acc, s)
            })
        };
        assert_eq!(on(1), on(2), "{name}");
    }
}

#[test]
fn far_origins_fall_back_to_every_disc() {
    let (mut store, discs) = scene(200, 50, 0.1, 3);
    // Move one segment's origin 10⁷ away along its line, keeping the line.
    let s = store.segments[0];
    let back = 1e7;
    store.segments[0] = Segment::new(s.o() - s.d() * back, s.d(), 0.0, f64::INFINITY, 5, 0);
    let mut want = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut want);
    for (name, ix) in indexes(&discs) {
        let mut acc = vec![0; discs.len()];
        let st = ix.run(&store, None, 1, &mut acc);
        assert_eq!(acc, want, "{name}");
        assert!(st.ray_disc_tests >= discs.len() as u64, "{name}");
    }
}

#[test]
fn clip_handles_axis_parallel_segments_and_ranges() {
    let b = Aabb::new(DVec3::ZERO, DVec3::ONE);
    assert_eq!(
        clip(DVec3::new(-1.0, 0.5, 0.5), DVec3::X, &b, 0.0, 10.0),
        Some((1.0, 2.0))
    );
    assert_eq!(
        clip(DVec3::new(-1.0, 1.5, 0.5), DVec3::X, &b, 0.0, 10.0),
        None
    );
    // On the face: the closed box keeps it.
    assert_eq!(
        clip(DVec3::new(-1.0, 1.0, 0.5), DVec3::X, &b, 0.0, 10.0),
        Some((1.0, 2.0))
    );
    assert_eq!(
        clip(DVec3::new(-1.0, 0.5, 0.5), DVec3::X, &b, 0.0, 0.5),
        None
    );
}

#[test]
fn mailbox_forgets_on_clear_and_survives_stamp_wraparound() {
    let mut m = Mailbox::new(4);
    m.clear();
    assert!(m.insert(2) && !m.insert(2) && m.insert(3));
    m.clear();
    assert!(m.insert(2));
    m.stamp = u32::MAX;
    m.seen[1] = 1;
    m.clear();
    assert_eq!(m.stamp, 1);
    assert!(
        m.insert(1),
        "a stale stamp equal to the restarted one must have been reset"
    );
}
