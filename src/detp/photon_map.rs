//! The baseline a user would reach for instead of DETP: Jensen's photon map. The impacts of the same
//! photons (each segment that hit a surface ends at an impact with its power) go into a kd-tree
//! (`kiddo`); the irradiance at a point is the power of its k nearest impacts that arrived from the
//! front of its normal, over the area of the disc through the k-th (averaging over photons, where
//! DETP averages over a fixed area).

use std::f64::consts::PI;

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::store::SegmentStore;

/// The cone filter's constant (Jensen's usual 1.1: weights stay positive at the k-th photon).
const K_CONE: f64 = 1.1;

/// Density-estimation filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Plain disc: Σ power / (π r_k²).
    Disc,
    /// Jensen's cone filter with k_cone = 1.1: weights 1 − d/(k_cone·r_k), normalised by
    /// (1 − 2/(3·k_cone)).
    Cone,
}

/// A fixed rotation (0.577 rad about the axis (0.3, −0.5, 0.8)), so that no plane of a scene is
/// axis-aligned in the tree's frame.
const FRAME: glam::DMat3 = glam::DMat3::from_cols_array(&[
    0.852971051133179,
    0.41606017788847083,
    0.31517346700535204,
    -0.4656204977312195,
    0.8794032217159783,
    0.09923470022169369,
    -0.2358769552569542,
    -0.2313955531356901,
    0.9438316375115515,
]);

/// The kd-tree over the impacts, or `None` if even the rotated frame cannot be split (more than a
/// leaf's worth of impacts at one exact position): then every query is answered by brute force.
fn build(coords: &[[f64; 3]]) -> Option<ImmutableKdTree<f64, 3>> {
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let tree = std::panic::catch_unwind(|| ImmutableKdTree::new_from_slice(coords)).ok();
    std::panic::set_hook(prev);
    tree
}

/// The k nearest of `coords` to `q` by exhaustive search, nearest first (ties by index).
fn brute_nearest(
    coords: &[[f64; 3]],
    q: &[f64; 3],
    k: usize,
) -> Vec<kiddo::NearestNeighbour<f64, u64>> {
    let d2 = |c: &[f64; 3]| (0..3).map(|a| (c[a] - q[a]).powi(2)).sum::<f64>();
    let mut all: Vec<(f64, usize)> = coords.iter().enumerate().map(|(i, c)| (d2(c), i)).collect();
    let k = k.min(all.len());
    all.select_nth_unstable_by(k - 1, |a, b| a.partial_cmp(b).expect("finite"));
    all.truncate(k);
    all.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    all.into_iter()
        .map(|(distance, i)| kiddo::NearestNeighbour {
            distance,
            item: i as u64,
        })
        .collect()
}

/// The estimate at each point (power per area), from the store's impacts.
pub fn estimate(
    store: &SegmentStore,
    points: &[DVec3],
    normals: &[DVec3],
    k: usize,
    filter: Filter,
) -> Vec<f64> {
    let impacts: Vec<usize> = (0..store.len())
        .filter(|&i| store.segments[i].t_hit.is_finite())
        .collect();
    if impacts.is_empty() {
        return vec![0.0; points.len()];
    }
    let at = |i: usize| {
        let s = &store.segments[i];
        s.o() + s.d() * f64::from(s.t_hit)
    };
    // The tree holds the impacts in a generically rotated frame: axis-aligned surfaces give
    // thousands of impacts with exactly equal coordinates (a floor's y = 0), which kiddo's immutable
    // tree cannot split (a leaf overflows and it panics). Distances are rotation-invariant, so the
    // neighbours are the same up to rounding (~1e-16 relative).
    let coords: Vec<[f64; 3]> = impacts
        .iter()
        .map(|&i| (FRAME * at(i)).to_array())
        .collect();
    let k = k.min(impacts.len()).max(1);
    let tree = build(&coords);
    points
        .par_iter()
        .zip(normals)
        .map(|(p, n)| {
            let q = (FRAME * *p).to_array();
            let near = match &tree {
                Some(t) => t.nearest_n::<SquaredEuclidean>(&q, k),
                None => brute_nearest(&coords, &q, k),
            };
            let r2 = near.iter().map(|x| x.distance).fold(0.0, f64::max);
            if r2 <= 0.0 {
                return 0.0;
            }
            let r = r2.sqrt();
            let mut sum = 0.0;
            for x in &near {
                let s = &store.segments[impacts[x.item as usize]];
                if s.d().dot(*n) >= 0.0 {
                    continue; // arrived from behind
                }
                let w = store.scale.watts(i64::from(s.power));
                sum += match filter {
                    Filter::Disc => w,
                    Filter::Cone => w * (1.0 - x.distance.sqrt() / (K_CONE * r)),
                };
            }
            let norm = match filter {
                Filter::Disc => 1.0,
                Filter::Cone => 1.0 - 2.0 / (3.0 * K_CONE),
            };
            sum / (norm * PI * r2)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detp::store::{Segment, SegmentStore};
    use glam::DVec3;

    #[test]
    fn the_frame_is_a_rotation() {
        let e = FRAME * FRAME.transpose() - glam::DMat3::IDENTITY;
        assert!(e.to_cols_array().iter().all(|x| x.abs() < 1e-15), "{e:?}");
        assert!((FRAME.determinant() - 1.0).abs() < 1e-15);
    }

    /// Thousands of impacts on an axis-aligned floor (exactly equal y), many at the very same
    /// position: the estimate neither panics nor differs from exhaustive search.
    #[test]
    fn a_floor_of_equal_coordinates_and_repeated_impacts_is_answered_exactly() {
        let mut segs = Vec::new();
        for i in 0..20_000u32 {
            let (x, z) = if i % 4 == 0 {
                (0.25, 0.25) // a pile at one spot: more than any leaf holds
            } else {
                (f64::from(i % 137) / 137.0, f64::from(i % 101) / 101.0)
            };
            segs.push(Segment::new(
                DVec3::new(x, 1.0, z),
                DVec3::new(0.0, -1.0, 0.0),
                1.0,
                f64::INFINITY,
                1 << 20,
                i,
            ));
        }
        let store = SegmentStore::new(
            segs,
            crate::detp::fixed::PowerScale {
                watts_per_unit: 1e-6,
            },
        );
        let pts = [DVec3::new(0.25, 0.0, 0.25), DVec3::new(0.6, 0.0, 0.4)];
        let nrm = [DVec3::Y, DVec3::Y];
        let got = estimate(&store, &pts, &nrm, 16, Filter::Disc);
        // Exhaustive: the 16 nearest impacts (in the original frame) and their power.
        for (p, g) in pts.iter().zip(&got) {
            let mut d: Vec<f64> = store
                .segments
                .iter()
                .map(|s| (s.o() + s.d() * f64::from(s.t_hit) - *p).length_squared())
                .collect();
            d.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let r2 = d[15];
            let w = store.scale.watts(1 << 20);
            // 5000 impacts share (0.25, 0, 0.25): the first point's 16 nearest are all there (r = 0:
            // the estimate is 0 by definition); the second's are on the lattice.
            if r2 == 0.0 {
                assert_eq!(*g, 0.0);
                continue;
            }
            let want = 16.0 * w / (PI * r2);
            assert!((g - want).abs() <= 1e-9 * want, "{g} vs {want}");
        }
    }
}
