use glam::DVec3;
use rand::seq::SliceRandom;
use rand::Rng;

use super::*;
use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::disc_index::{self, GridIndex, Octree, SimdPath};
use crate::detp::order::{permutation, Order};
use crate::detp::sphere_cache::{self, filter::FilterPath, SphereCacheParams};
use crate::detp::store::SegmentStore;
use crate::sample::rng::stream;

fn scene(n_seg: u32, n_disc: usize, d: f64, seed: u64) -> (SegmentStore, Discs) {
    let mut rng = stream(&[0x4e, seed]);
    let store = SegmentStore::test_lines(&mut rng, n_seg);
    (store, Discs::in_ball(&mut rng, n_disc, DVec3::ZERO, 1.0, d))
}

fn kept_by_brute(store: &SegmentStore, discs: &Discs, k: usize) -> Vec<Vec<Crossing>> {
    let t = Nearest::new(k);
    let mut acc = t.empties(discs.len());
    brute::accumulate_with(store, discs, None, &t, &mut acc);
    acc.iter().map(Kept::sorted).collect()
}

#[test]
fn the_kept_set_does_not_depend_on_the_arrival_order_even_with_ties() {
    let mut rng = stream(&[0x4e, 1]);
    for round in 0..200 {
        let k = rng.gen_range(1..12);
        // Few distinct distances and powers: many ties on ρ², and on (ρ², power).
        let xs: Vec<Crossing> = (0..rng.gen_range(0..40))
            .map(|seg| Crossing {
                rho_sq_bits: f64::from(rng.gen_range(0..4u32)).to_bits(),
                power: rng.gen_range(1..3),
                seg,
            })
            .collect();
        let mut want = xs.clone();
        want.sort();
        want.truncate(k);
        for _ in 0..5 {
            let mut ys = xs.clone();
            ys.shuffle(&mut rng);
            // Offered one by one, and as two heaps merged in either order.
            let mut one = Kept::default();
            ys.iter().for_each(|&x| one.offer(k, x));
            assert_eq!(one.sorted(), want, "round {round}");
            let cut = rng.gen_range(0..=ys.len());
            let (mut a, mut b) = (Kept::default(), Kept::default());
            ys[..cut].iter().for_each(|&x| a.offer(k, x));
            ys[cut..].iter().for_each(|&x| b.offer(k, x));
            if k >= MIN_K {
                let t = Nearest::new(k);
                let (a2, b2) = (a.clone(), b.clone());
                t.merge(&mut a, b);
                assert_eq!(a.sorted(), want, "round {round}: merged");
                let mut b2 = b2;
                t.merge(&mut b2, a2);
                assert_eq!(b2.sorted(), want, "round {round}: merged the other way");
            }
        }
    }
}

#[test]
fn brute_force_keeps_exactly_the_k_nearest_crossings_of_each_disc() {
    let (store, discs) = scene(4_000, 300, 0.1, 2);
    let k = 5;
    let kept = kept_by_brute(&store, &discs, k);
    let mut full = 0;
    for (i, got) in kept.iter().enumerate() {
        // The oracle: every crossing of disc i, sorted by the total order, the first k.
        let (c, n) = (discs.centers[i], discs.normals[i]);
        let mut all: Vec<Crossing> = (0..store.len())
            .filter(|&s| discs.crossed_by(&store.segments[s], i))
            .map(|s| Crossing {
                rho_sq_bits: crossing_distance_sq(&store.segments[s], c, n).to_bits(),
                power: store.segments[s].power,
                seg: s as u32,
            })
            .collect();
        all.sort();
        let within = all.len();
        all.truncate(k);
        assert_eq!(got, &all, "disc {i}");
        let sel = Kept(got.iter().copied().collect()).select(k, discs.radius);
        if within >= k {
            full += 1;
            assert!(sel.full && sel.radius <= discs.radius);
            assert_eq!(sel.radius, f64::from_bits(all[k - 1].rho_sq_bits).sqrt());
            let inner: Acc = all[..k - 1].iter().map(|x| Acc::from(x.power)).sum();
            assert_eq!(sel.units, inner, "disc {i}: the k − 1 nearer count");
        } else {
            assert!(!sel.full);
            assert_eq!(sel.radius, discs.radius);
            let every: Acc = all.iter().map(|x| Acc::from(x.power)).sum();
            assert_eq!(sel.units, every);
        }
    }
    assert!(
        full > 50 && full < kept.len(),
        "both cases occur: {full} full"
    );
}

#[test]
fn brute_force_the_disc_indexes_and_the_sphere_cache_keep_the_same_crossings() {
    for (seed, k) in [(3u64, 2usize), (4, 7), (5, 40)] {
        let (store, discs) = scene(12_000, 1_500, 0.12, seed);
        let want = kept_by_brute(&store, &discs, k);
        assert!(want.iter().filter(|w| w.len() == k).count() > 100);
        let t = Nearest::new(k);
        for path in SimdPath::all_available() {
            let ixs: Vec<(&str, Box<dyn disc_index::DiscIndex>)> = vec![
                (
                    "grid",
                    Box::new(GridIndex::build(&discs, 0.15).with_path(path)),
                ),
                (
                    "octree",
                    Box::new(Octree::build(&discs, 8, 0.12).with_path(path)),
                ),
            ];
            for (name, ix) in ixs {
                let mut acc = t.empties(discs.len());
                disc_index::accumulate_with(ix.as_ref(), &store, None, &t, &mut acc);
                let got: Vec<_> = acc.iter().map(Kept::sorted).collect();
                assert!(got == want, "{name} {path:?} seed {seed} k {k}");
            }
        }
        let perm = permutation(&discs.centers, Order::Hilbert, 10);
        let root = sphere_cache::root_sphere(&discs.bounds_all());
        let params = SphereCacheParams {
            threshold: 64,
            chunk_points: 97,
            ..SphereCacheParams::default()
        };
        for path in FilterPath::all_available() {
            let mut acc = t.empties(discs.len());
            sphere_cache::run_tally(&store, &discs, &perm, root, &params, &t, &mut acc, path);
            let got: Vec<_> = acc.iter().map(Kept::sorted).collect();
            assert!(got == want, "sphere cache {path:?} seed {seed} k {k}");
        }
    }
}

#[test]
fn with_k_above_every_count_the_estimate_is_the_papers() {
    let (store, discs) = scene(3_000, 200, 0.1, 6);
    let mut sums = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut sums);
    let t = Nearest::new(100_000);
    let mut acc = t.empties(discs.len());
    brute::accumulate_with(&store, &discs, None, &t, &mut acc);
    for (i, (kept, &sum)) in acc.iter().zip(&sums).enumerate() {
        let sel = kept.select(t.k, discs.radius);
        assert_eq!(
            (sel.units, sel.radius, sel.full),
            (sum, discs.radius, false),
            "disc {i}"
        );
    }
}

/// μ-random lines through the unit ball: a small disc of area A inside it is crossed from the
/// front by each line with probability A/(4π) (Cauchy: 2A/(4π) for either side, half of them
/// against the normal), uniformly over the disc. The field's irradiance is therefore
/// Σ power / (4π) everywhere inside; the k-nearest estimate's mean over well-separated discs must
/// agree within its standard error (three of them). Counting the k-th crossing as well would be
/// high by k/(k − 1) = 1.14 here, some ten standard errors.
#[test]
fn in_a_uniform_field_the_estimate_is_unbiased() {
    let mut rng = stream(&[0x4e, 7]);
    let n = 40_000u32;
    let store = SegmentStore::test_lines(&mut rng, n);
    let discs = Discs::in_ball(&mut rng, 1_600, DVec3::ZERO, 0.6, 0.3);
    let k = 8;
    let t = Nearest::new(k);
    let mut acc = t.empties(discs.len());
    brute::accumulate_with(&store, &discs, None, &t, &mut acc);
    let truth: f64 = store
        .segments
        .iter()
        .map(|s| f64::from(s.power))
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI);
    let est: Vec<f64> = acc
        .iter()
        .map(|kept| {
            let sel = kept.select(k, discs.radius);
            assert!(sel.full, "every disc finds k crossings within d");
            sel.units as f64 / (std::f64::consts::PI * sel.radius * sel.radius)
        })
        .collect();
    let m = est.len() as f64;
    let mean = est.iter().sum::<f64>() / m;
    let var = est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (m - 1.0);
    let se = (var / m).sqrt();
    eprintln!("uniform field: mean {mean:.6e}, truth {truth:.6e}, se {se:.3e}");
    assert!(
        (mean - truth).abs() <= 3.0 * se,
        "mean {mean} vs truth {truth}: {} standard errors",
        (mean - truth) / se
    );
    assert!(se < 0.02 * truth, "the test has power: se {se} vs {truth}");
}

#[test]
fn k_grows_as_the_two_thirds_power_of_the_photons() {
    assert_eq!(k_for(16, 1_000, None), 16);
    assert_eq!(k_for(16, 1_000, Some(1_000)), 16);
    // 8× the photons: 4× the crossings; 1/8: a quarter.
    assert_eq!(k_for(16, 8_000, Some(1_000)), 64);
    assert_eq!(k_for(16, 125, Some(1_000)), 4);
    // 27×: 9×; 1000×: 100×.
    assert_eq!(k_for(10, 27_000, Some(1_000)), 90);
    assert_eq!(k_for(3, 1_000_000, Some(1_000)), 300);
    // 10 · 2^(2/3) = 15.87 rounds to 16; never below the smallest k.
    assert_eq!(k_for(10, 2_000, Some(1_000)), 16);
    assert_eq!(k_for(16, 1, Some(1_000_000)), MIN_K);
}
