//! The paper predictor's theory against brute force on μ-random lines, its seam with the subsample
//! predictor, and its determinism across thread counts.

use glam::DVec3;

use super::*;
use crate::detp::order::Order;
use crate::detp::quasi_static::tests::{params, scene};
use crate::detp::quasi_static::Engine;
use crate::detp::sphere_cache::{ListMode, PopRule};
use crate::sample::rng::stream;

/// Q = 2/3, threshold 100, exact lists (every list is exactly the lines meeting its sphere, the law
/// n_R·(r_i/r_0)² holds for spheres inside the ball).
fn cache() -> SphereCacheParams {
    SphereCacheParams {
        q: 2.0 / 3.0,
        threshold: 100,
        list_mode: ListMode::Exact,
        pop_rule: PopRule::Chain,
        chunk_points: 512,
        law_ball: None,
    }
}

/// 2¹⁷ μ-random lines through the unit ball, 3000 points uniform in the ball of radius 0.5 (so
/// every sphere from level 2 on, r_2 = 0.44, lies inside the unit ball), Hilbert order.
fn lines_and_points() -> (SegmentStore, Discs, Vec<u32>) {
    let store = SegmentStore::test_lines(&mut stream(&[0x5c, 7]), 1 << 17);
    let discs = Discs::in_ball(&mut stream(&[0xba, 7]), 3000, DVec3::ZERO, 0.5, 0.002);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    (store, discs, perm)
}

const UNIT: (DVec3, f64) = (DVec3::ZERO, 1.0);

#[test]
fn theory_levels_match_the_measured_rays_and_spheres_per_level() {
    let (store, discs, perm) = lines_and_points();
    let mut acc = vec![0; discs.len()];
    let full = sphere_cache::run(&store, &discs, &perm, UNIT, &cache(), &mut acc);
    let split = 3;
    let p = paper_cache_count(&store, &discs, &perm, UNIT, &cache(), 1.0, split);
    // n_R·Q^(2i) ≥ 100 down to level 8 (199.9), so levels 4 … 9 come from theory.
    let levels: Vec<usize> = p.theory.iter().map(|t| t.level).collect();
    assert_eq!(levels, (4..=9).collect::<Vec<_>>());
    // (The run also builds a few level-10 spheres, under the level-9 spheres whose lists exceed
    // the threshold by chance: theory's expectation stops at level 9.)
    assert!(full.levels.len() >= 10, "the run builds levels 0 … 9");
    // The anchor's own standard error, carried down by Q^(2(i−s)).
    let (_, anchor_se) = full.levels[split].mean_rays().expect("level 3 built");
    let anchor_se = anchor_se.expect("several builds");
    let q2 = cache().q * cache().q;
    let mut zs = Vec::new();
    for t in &p.theory {
        let l = &full.levels[t.level];
        let (mean, se) = l.mean_rays().expect("built");
        let se = se.expect("several builds");
        let carried = anchor_se * q2.powi((t.level - split) as i32);
        let z = (t.rays - mean) / (se * se + carried * carried).sqrt();
        zs.push(z);
        // Spheres per level from the points alone are exact wherever every parent was subdivided.
        if full.levels[t.level - 1].leaf_builds == 0 {
            assert_eq!(t.spheres, l.builds, "level {}: spheres", t.level);
        }
    }
    let mean_abs = zs.iter().map(|z| z.abs()).sum::<f64>() / zs.len() as f64;
    assert!(
        mean_abs <= 1.5 && zs.iter().all(|z| z.abs() < 4.0),
        "predicted vs measured rays per level, in standard errors: {zs:?}"
    );
}

/// The total: the theory's tests per level, m_i·N_(i−1), are the paper's cache's (a child tests its
/// parent's list: inherited lists); exact lists test a farther ancestor's, which theory does not
/// model.
#[test]
fn theory_total_matches_the_paper_cache_counted_tests() {
    let (store, discs, perm) = lines_and_points();
    let inherited = SphereCacheParams {
        list_mode: ListMode::Inherited,
        ..cache()
    };
    let mut acc = vec![0; discs.len()];
    let full = sphere_cache::run(&store, &discs, &perm, UNIT, &inherited, &mut acc);
    let counted = (full.ray_sphere_tests + full.ray_disc_tests) as f64;
    let p = paper_cache_count(&store, &discs, &perm, UNIT, &inherited, 1.0, 3);
    // Within the paper's own "less than 5 % in most of the cases" (§5); 0.5 % here.
    assert!(
        (p.predicted / counted - 1.0).abs() < 0.05,
        "predicted tests {} vs counted {counted}",
        p.predicted
    );
}

#[test]
fn everything_simulated_is_the_subsample_exactly() {
    let (store, discs, perm) = lines_and_points();
    let quarter = SegmentStore::new(
        store
            .segments
            .iter()
            .filter(|s| s.photon % 4 == 0)
            .copied()
            .collect(),
        store.scale,
    );
    let mut acc = vec![0; discs.len()];
    let sub = sphere_cache::run(&quarter, &discs, &perm, UNIT, &cache(), &mut acc);
    let counted = (sub.ray_sphere_tests + sub.ray_disc_tests) as f64;
    // The deepest level the cache can build: r_15 = (2/3)^15 ≥ d = 0.002 > r_16. (Splitting at the
    // subsample's own deepest level is not enough: its lists there, scaled by 1/f, still exceed the
    // threshold, and theory adds the levels the whole run would build.)
    assert!(sub.levels.len() <= 16);
    for split in [15, 40, MAX_LEVEL] {
        let p = paper_cache_count(&quarter, &discs, &perm, UNIT, &cache(), 0.25, split);
        assert!(p.theory.is_empty(), "split {split}: nothing from theory");
        assert_eq!(p.subsample_units, counted, "split {split}");
        assert_eq!(p.predicted, counted / 0.25);
    }
    // One level shallower, the theory takes the deepest level over.
    let p = paper_cache_count(&quarter, &discs, &perm, UNIT, &cache(), 0.25, 2);
    assert!(!p.theory.is_empty());
    assert_ne!(p.subsample_units, counted);
    // A scale of exactly 1 gives the subsample predictor's seconds bit for bit.
    let (fixed, part) = (0.001_234_5, 0.009_876_5);
    assert_eq!(
        predicted_seconds(fixed, part, 1.0, 0.05).to_bits(),
        (fixed + (part - fixed).max(0.0) / 0.05).to_bits()
    );
}

#[test]
fn split_is_where_the_subsample_lists_fall_below_the_threshold() {
    // 10 000 rays, Q = 1/2: 10 000·4^(−s) ≥ 100 for s ≤ 3, so level 4's parent (level 3: 156) is the
    // last one with enough rays.
    assert_eq!(split_level(10_000, 0.5, 100), 4);
    assert_eq!(split_level(99, 0.5, 100), 0);
    assert_eq!(split_level(100, 0.5, 100), 1);
}

/// The quasi-static run's own path: with the split as deep as the cache goes, the paper's counted
/// tests equal the sphere cache's on the subsample, so its scale is exactly 1; the counts and the
/// split are the same on 1 and 2 threads.
#[test]
fn in_a_scene_the_seam_holds_and_counts_do_not_depend_on_threads() {
    let (qs, _) = QuasiStatic::start(scene(), params(Engine::Hybrid, 20_000, 2));
    let f = 0.25;
    let part = qs.subsample(f);
    let counted = qs.dynamic_sums_with(&part, false, Some(Used::SphereCache), Some(0))[0].3;
    let deep = qs.paper_count(&part, 0, f, Some(MAX_LEVEL));
    assert!(deep.theory.is_empty());
    assert_eq!(
        deep.subsample_units,
        (counted.disc_tests + counted.sphere_tests) as f64
    );
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| qs.paper_count(&part, 0, f, None))
    };
    let one = on(1);
    assert_eq!(one, on(2));
    assert!(one.split > 0, "the root holds more than the threshold");
}
