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
    let coords: Vec<[f64; 3]> = impacts.iter().map(|&i| at(i).to_array()).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&coords);
    let k = k.min(impacts.len()).max(1);
    points
        .par_iter()
        .zip(normals)
        .map(|(p, n)| {
            let near = tree.nearest_n::<SquaredEuclidean>(&p.to_array(), k);
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
