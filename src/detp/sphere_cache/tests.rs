//! Sphere cache against the brute-force oracle, its counters across thread counts, and the
//! rays-per-level law of integral geometry.

use glam::DVec3;

use super::filter::FilterPath;
use super::*;
use crate::detp::brute;
use crate::detp::order::{permutation, Order};
use crate::sample::rng::stream;

/// `n` μ-random lines through the unit ball as segments from their first point on the sphere:
/// t_end = +∞ for even k, the chord (to the second point) for odd k; powers 1..1000.
fn lines(n: u32, seed: u64) -> SegmentStore {
    SegmentStore::test_lines(&mut stream(&[0x5c, seed]), n)
}

/// `n` points uniform in the ball of radius `rad`, uniform normals, disc radius `d`.
fn ball_points(n: usize, rad: f64, d: f64, seed: u64) -> Discs {
    let mut rng = stream(&[0xba, seed]);
    Discs::in_ball(&mut rng, n, DVec3::ZERO, rad, d)
}

fn oracle(store: &SegmentStore, discs: &Discs) -> Vec<Acc> {
    let mut acc = vec![0; discs.len()];
    brute::accumulate(store, discs, None, 1, &mut acc);
    acc
}

const UNIT: (DVec3, f64) = (DVec3::ZERO, 1.0);

/// Every list mode with every pop rule.
const MODES: [(ListMode, PopRule); 4] = [
    (ListMode::Exact, PopRule::Chain),
    (ListMode::Exact, PopRule::Paper),
    (ListMode::Inherited, PopRule::Chain),
    (ListMode::Inherited, PopRule::Paper),
];

#[test]
fn both_list_modes_every_order_and_filter_path_equal_brute_force() {
    let store = lines(20_000, 1);
    let discs = ball_points(600, 1.0, 0.05, 2);
    let want = oracle(&store, &discs);
    assert!(
        want.iter().filter(|&&a| a != 0).count() > 300,
        "a test that could not fail"
    );
    for (q, threshold, chunk) in [(2.0 / 3.0, 100, 128), (0.5, 20, 1000), (0.9, 300, 7)] {
        for (mode, pop) in MODES {
            for order in [Order::None, Order::Morton, Order::Hilbert] {
                let perm = permutation(&discs.centers, order, 10);
                let params = SphereCacheParams {
                    q,
                    threshold,
                    list_mode: mode,
                    pop_rule: pop,
                    chunk_points: chunk,
                    law_ball: Some((DVec3::ZERO, 1.0)),
                };
                for path in FilterPath::all_available() {
                    let mut acc = vec![0; discs.len()];
                    let s = run_with(&store, &discs, &perm, UNIT, &params, &mut acc, path);
                    assert_eq!(acc, want, "Q {q} {mode:?} {pop:?} {order:?} {path:?}");
                    assert!(
                        s.levels.len() > 3,
                        "the cache must go deep: {:?}",
                        s.levels.len()
                    );
                }
            }
        }
    }
}

#[test]
fn counters_do_not_depend_on_the_thread_count() {
    let store = lines(10_000, 3);
    let discs = ball_points(800, 1.0, 0.04, 4);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let params = SphereCacheParams {
        chunk_points: 100,
        ..Default::default()
    };
    let run_on = |k: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .unwrap();
        pool.install(|| {
            let mut acc = vec![0; discs.len()];
            let s = run(&store, &discs, &perm, UNIT, &params, &mut acc);
            (acc, s)
        })
    };
    let (a1, s1) = run_on(1);
    let (a2, s2) = run_on(2);
    assert_eq!(a1, a2);
    assert_eq!(s1, s2);
    assert_eq!(a1, oracle(&store, &discs));
    // Eight chunks, each with a cold cache: a chunk whose first disc lies in the root builds the
    // levels below it for that point, which are not misses (the module doc); a chunk whose first
    // disc sticks out of the root (a disc near the unit sphere) tests it against every segment and
    // builds nothing for it.
    let cold = perm
        .chunks(params.chunk_points)
        .filter(|c| discs.centers[c[0] as usize].length() + discs.radius <= UNIT.1)
        .count() as u64;
    assert_eq!(perm.len().div_ceil(params.chunk_points), 8);
    assert!(cold >= 1);
    assert_eq!(
        s1.levels[1].builds - s1.levels[1].misses,
        cold,
        "level 1: {} builds, {} misses",
        s1.levels[1].builds,
        s1.levels[1].misses
    );
    let by_level: u64 = s1.levels.iter().map(|l| l.ray_sphere_tests).sum();
    assert_eq!(by_level, s1.ray_sphere_tests);
}

#[test]
fn a_disc_outside_the_root_is_tested_against_every_segment() {
    let store = lines(5_000, 5);
    let discs = ball_points(50, 1.0, 0.1, 6);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let mut acc = vec![0; discs.len()];
    // A root that holds only the inner part of the scene.
    let s = run(
        &store,
        &discs,
        &perm,
        (DVec3::ZERO, 0.5),
        &Default::default(),
        &mut acc,
    );
    assert_eq!(acc, oracle(&store, &discs));
    let outside = discs
        .centers
        .iter()
        .filter(|c| c.length() + 0.1 > 0.5)
        .count() as u64;
    assert!(outside > 0 && s.ray_disc_tests >= outside * 5_000);
}

/// Integral geometry: a μ-random line meeting the unit ball meets a concentric ball of radius r_i
/// with probability (r_i/r_0)² = Q^(2i), so an exact list at level i is Binomial(n_R, Q^(2i)).
#[test]
fn exact_lists_follow_the_area_law_for_concentric_spheres() {
    let n_r = 1u32 << 16;
    let store = lines(n_r, 7);
    let discs = Discs::new(vec![DVec3::ZERO], vec![DVec3::Z], 1e-3).unwrap();
    let params = SphereCacheParams {
        threshold: 1,
        list_mode: ListMode::Exact,
        ..Default::default()
    };
    let mut acc = vec![0; 1];
    let s = run(&store, &discs, &[0], UNIT, &params, &mut acc);
    let mut checked = 0;
    for (i, l) in s.levels.iter().enumerate() {
        let p = params.q.powi(2 * i as i32);
        let mean = f64::from(n_r) * p;
        if mean < 20.0 {
            continue;
        }
        let sd = (mean * (1.0 - p)).sqrt();
        assert_eq!(l.builds, 1);
        assert!(
            (l.rays_held as f64 - mean).abs() <= 4.5 * sd.max(1e-9),
            "level {i}: {} rays, theory {mean:.1} ± {sd:.1}",
            l.rays_held
        );
        checked += 1;
    }
    assert!(checked >= 8, "only {checked} levels checked");
}

/// Off-centre spheres inside the unit ball obey the same law in Exact mode; the paper's inherited
/// lists fall short where children stick out of their parents (docs/theory.md §2, pitfall 2).
#[test]
fn exact_lists_follow_the_area_law_off_centre_and_inherited_lists_fall_short() {
    let n_r = 1u32 << 17;
    let store = lines(n_r, 8);
    let discs = ball_points(3000, 0.3, 2e-3, 9);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let stats = |mode| {
        let params = SphereCacheParams {
            law_ball: None,
            q: 0.7,
            list_mode: mode,
            ..Default::default()
        };
        let mut acc = vec![0; discs.len()];
        run(&store, &discs, &perm, UNIT, &params, &mut acc)
    };
    let exact = stats(ListMode::Exact);
    let inherited = stats(ListMode::Inherited);
    let mut checked = 0;
    let mut short = 0;
    for (i, l) in exact.levels.iter().enumerate().skip(1) {
        // Spheres centred within 0.3 of the centre lie inside the unit ball while r_i ≤ 0.7.
        let theory = f64::from(n_r) * 0.7f64.powi(2 * i as i32);
        if l.radius > 0.7 || theory < 200.0 || l.builds < 30 {
            continue;
        }
        let (mean, _) = l.mean_rays().unwrap();
        assert!(
            (mean / theory - 1.0).abs() < 0.03,
            "level {i}: exact mean {mean:.1} vs theory {theory:.1}"
        );
        let (inh, _) = inherited.levels[i].mean_rays().unwrap();
        assert!(
            inh <= mean * 1.01,
            "level {i}: inherited {inh:.1} > exact {mean:.1}"
        );
        if inh < 0.97 * theory {
            short += 1;
        }
        checked += 1;
    }
    assert!(checked >= 4, "only {checked} levels checked");
    assert!(short >= 1, "inherited lists never fell short");
    assert!(inherited.ray_sphere_tests < exact.ray_sphere_tests);
}

/// With the law ball given, the builds of spheres that lie inside it are counted apart, and they
/// follow n_R·(r_i/R)² wherever they sit — also at the top levels, where most spheres built around
/// points of the whole ball stick out of it and hold fewer rays.
#[test]
fn spheres_inside_the_law_ball_follow_the_area_law_at_every_level() {
    let n_r = 1u32 << 17;
    let store = lines(n_r, 12);
    let discs = ball_points(4000, 1.0, 2e-3, 13);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let params = SphereCacheParams {
        q: 0.7,
        law_ball: Some(UNIT),
        list_mode: ListMode::Exact,
        ..Default::default()
    };
    let mut acc = vec![0; discs.len()];
    let st = run(&store, &discs, &perm, UNIT, &params, &mut acc);
    let mut checked = 0;
    let mut sticking_out = 0;
    for (i, l) in st.levels.iter().enumerate().skip(1) {
        assert!(l.inside_builds <= l.builds);
        let theory = f64::from(n_r) * 0.7f64.powi(2 * i as i32);
        if l.inside_builds < 30 || theory < 200.0 {
            continue;
        }
        let inside = l.inside_rays_held as f64 / l.inside_builds as f64;
        assert!(
            (inside / theory - 1.0).abs() < 0.03,
            "level {i}: inside mean {inside:.1} vs theory {theory:.1}"
        );
        let all = l.rays_held as f64 / l.builds as f64;
        if l.inside_builds < l.builds && all < 0.97 * theory {
            sticking_out += 1;
        }
        checked += 1;
    }
    assert!(checked >= 4, "only {checked} levels checked");
    assert!(
        sticking_out >= 1,
        "no level showed the deficit of spheres sticking out"
    );
}

/// Sorting the points along a curve is what keeps spheres in use: Hilbert and Morton orders
/// rebuild far less often than the input (random) order.
#[test]
fn curve_orders_cut_the_misses() {
    let store = lines(8_000, 10);
    let discs = ball_points(3_000, 1.0, 0.02, 11);
    let misses = |order| {
        let perm = permutation(&discs.centers, order, 10);
        let mut acc = vec![0; discs.len()];
        let s = run(
            &store,
            &discs,
            &perm,
            (DVec3::ZERO, 1.03),
            &Default::default(),
            &mut acc,
        );
        s.levels.iter().map(|l| l.misses).sum::<u64>()
    };
    let (none, morton, hilbert) = (
        misses(Order::None),
        misses(Order::Morton),
        misses(Order::Hilbert),
    );
    assert!(
        hilbert * 2 < none && morton * 2 < none,
        "none {none} morton {morton} hilbert {hilbert}"
    );
}

/// The paper's pop rule keeps levels the chain rule drops (a protruding child's parent), so with
/// exact lists it rebuilds less; with inherited lists it is cut back to the chain wherever it kept a
/// level not containing the disc, which makes it the chain rule exactly (repairs counted).
#[test]
fn the_paper_pop_rule_rebuilds_less_with_exact_lists_and_is_the_chain_with_inherited() {
    let store = lines(1 << 15, 12);
    let discs = ball_points(4000, 1.0, 5e-3, 13);
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    let stats = |list_mode, pop_rule| {
        let params = SphereCacheParams {
            q: 0.6,
            threshold: 20,
            list_mode,
            pop_rule,
            chunk_points: 1 << 20,
            law_ball: None,
        };
        let mut acc = vec![0; discs.len()];
        run(&store, &discs, &perm, UNIT, &params, &mut acc)
    };
    let exact_chain = stats(ListMode::Exact, PopRule::Chain);
    let exact_paper = stats(ListMode::Exact, PopRule::Paper);
    assert_eq!(exact_chain.pop_repairs, 0);
    assert!(exact_paper.pop_repairs > 0, "no level was ever kept");
    assert!(
        exact_paper.builds() < exact_chain.builds(),
        "paper {} vs chain {} builds",
        exact_paper.builds(),
        exact_chain.builds()
    );
    assert!(exact_paper.rays_copied() < exact_chain.rays_copied());
    let inh_chain = stats(ListMode::Inherited, PopRule::Chain);
    let mut inh_paper = stats(ListMode::Inherited, PopRule::Paper);
    assert!(inh_paper.pop_repairs > 0);
    inh_paper.pop_repairs = 0;
    assert_eq!(inh_paper, inh_chain);
}
