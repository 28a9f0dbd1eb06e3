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

/// A k that grows with the photon count, k(N) = k₀·(N/N₀)^β, so that the photon map's error keeps
/// falling as photons are added; the fixed-k estimate is [`estimate`] with a constant k.
///
/// # Why k must grow, and how fast
/// Photon n carries w = Φ/N, so on a surface of irradiance E the impacts have density ρ = N·E/Φ per
/// area, and the disc through the k-th nearest impact has radius r with πr²ρ ≈ k. The estimate
/// Ê = k·w/(πr²) then has
/// - relative variance ≈ 1/k (k impacts in the disc: a Poisson count), whatever N;
/// - relative bias ≈ r²·∇²E/(8E) on a smooth surface with a smooth E (the mean of a function over a
///   disc of radius r is its centre value plus r²/8 times its Laplacian), i.e. b·k/N with
///   b = Φ·∇²E/(8π·E²).
///
/// (The k-th-neighbour radius adds a bias of its own, a factor k/(k − 1): O(1/k), whose square is
/// negligible beside the variance.) So MSE/E² ≈ 1/k + b²·(k/N)². With k fixed the first term
/// stays: the error stops falling (the Cornell box's 9–10 % at k = 64 whatever the photons). It
/// falls to 0 exactly when k → ∞ and k/N → 0 (Loftsgaarden & Quesenberry 1965), i.e. 0 < β < 1.
/// Setting the derivative in k to zero, −1/k² + 2b²k/N² = 0, gives k* = (N²/(2b²))^{1/3} ∝ N^{2/3}: **β = 2/3** minimises the MSE of a
/// 2D k-NN estimate of a smooth density (in d dimensions, 4/(d + 4)), and then the relative RMSE
/// falls as N^{−1/3}. Where the disc meets an edge, a crease or a shadow boundary, E is not smooth
/// over it and the bias is first order, O(r) = O((k/N)^{1/2}): MSE ≈ 1/k + c·k/N, minimised by
/// β = 1/2 (RMSE ∝ N^{−1/4}). Hence β is a parameter: 2/3 where smooth interiors dominate, 1/2 where
/// edges do; k₀ at N₀ sets the constant (b is unknown, and the cone filter changes it, not the
/// exponents).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KGrowth {
    /// k at `n0` photons (≥ 1).
    pub k0: f64,
    /// The photon count at which k = `k0` (> 0).
    pub n0: f64,
    /// The exponent β, in [0, 1) (0: a fixed k).
    pub beta: f64,
}

impl KGrowth {
    /// The MSE-optimal exponent for a smooth 2D density (see the type's doc).
    pub const SMOOTH_BETA: f64 = 2.0 / 3.0;

    /// k(N) = k₀·(N/N₀)^β, rounded to the nearest integer, at least 1 and at most N.
    ///
    /// # Panics
    /// If k₀ < 1, N₀ ≤ 0 or β is outside [0, 1) (a spec refuses these before).
    pub fn k(&self, photons: u64) -> usize {
        assert!(
            self.k0 >= 1.0 && self.n0 > 0.0 && (0.0..1.0).contains(&self.beta),
            "k growth needs k0 ≥ 1, n0 > 0 and β in [0, 1): {self:?}"
        );
        let k = (self.k0 * (photons as f64 / self.n0).powf(self.beta)).round();
        (k as usize).clamp(1, (photons as usize).max(1))
    }
}

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

/// The estimate at each point (power per area), from the store's impacts: [`PhotonMap::build`]
/// then [`PhotonMap::estimate`].
pub fn estimate(
    store: &SegmentStore,
    points: &[DVec3],
    normals: &[DVec3],
    k: usize,
    filter: Filter,
) -> Vec<f64> {
    PhotonMap::build(store).estimate(points, normals, k, filter)
}

/// A store's impacts in a kd-tree: built once (a cost paid once per photon set), then queried per
/// point (a cost per point), so the two can be timed apart.
pub struct PhotonMap<'a> {
    store: &'a SegmentStore,
    /// Indices of the segments that end at an impact.
    impacts: Vec<usize>,
    /// Their impact points, in the rotated frame.
    coords: Vec<[f64; 3]>,
    /// The tree over `coords` (`None`: brute force, see [`build`]).
    tree: Option<ImmutableKdTree<f64, 3>>,
}

impl<'a> PhotonMap<'a> {
    /// The map of `store`'s impacts.
    pub fn build(store: &'a SegmentStore) -> Self {
        let impacts: Vec<usize> = (0..store.len())
            .filter(|&i| store.segments[i].t_hit.is_finite())
            .collect();
        let at = |i: usize| {
            let s = &store.segments[i];
            s.o() + s.d() * f64::from(s.t_hit)
        };
        // The tree holds the impacts in a generically rotated frame: axis-aligned surfaces give
        // thousands of impacts with exactly equal coordinates (a floor's y = 0), which kiddo's
        // immutable tree cannot split (a leaf overflows and it panics). Distances are
        // rotation-invariant, so the neighbours are the same up to rounding (~1e-16 relative).
        let coords: Vec<[f64; 3]> = impacts
            .iter()
            .map(|&i| (FRAME * at(i)).to_array())
            .collect();
        let tree = if coords.is_empty() {
            None
        } else {
            build(&coords)
        };
        Self {
            store,
            impacts,
            coords,
            tree,
        }
    }

    /// Impacts held.
    pub fn len(&self) -> usize {
        self.impacts.len()
    }

    /// Does it hold no impact?
    pub fn is_empty(&self) -> bool {
        self.impacts.is_empty()
    }

    /// The estimate at each point (power per area) from its `k` nearest impacts.
    pub fn estimate(
        &self,
        points: &[DVec3],
        normals: &[DVec3],
        k: usize,
        filter: Filter,
    ) -> Vec<f64> {
        let (store, impacts, coords, tree) = (self.store, &self.impacts, &self.coords, &self.tree);
        if impacts.is_empty() {
            return vec![0.0; points.len()];
        }
        let k = k.min(impacts.len()).max(1);
        points
            .par_iter()
            .zip(normals)
            .map(|(p, n)| {
                let q = (FRAME * *p).to_array();
                let near = match tree {
                    Some(t) => t.nearest_n::<SquaredEuclidean>(&q, k),
                    None => brute_nearest(coords, &q, k),
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detp::fixed::PowerScale;
    use crate::detp::store::{Segment, SegmentStore};
    use crate::sample::directions::uniform_direction;
    use crate::sample::rng::stream;
    use glam::DVec3;

    /// Built once, queried twice: the same values as [`estimate`]; a store without impacts gives 0.
    #[test]
    fn a_map_built_once_answers_as_the_one_call() {
        let store = point_light_impacts(5000, 3);
        let map = PhotonMap::build(&store);
        assert_eq!(map.len(), store.len());
        let pts = [DVec3::ZERO, DVec3::new(0.3, 0.0, -0.2)];
        for k in [8, 32] {
            assert_eq!(
                map.estimate(&pts, &[DVec3::Y; 2], k, Filter::Cone),
                estimate(&store, &pts, &[DVec3::Y; 2], k, Filter::Cone)
            );
        }
        let mut none = store.clone();
        none.segments
            .iter_mut()
            .for_each(|s| s.t_hit = f32::INFINITY);
        let empty = PhotonMap::build(&none);
        assert!(empty.is_empty());
        assert_eq!(
            empty.estimate(&pts, &[DVec3::Y; 2], 8, Filter::Disc),
            vec![0.0; 2]
        );
    }

    #[test]
    fn k_grows_as_the_power_law_and_stays_in_range() {
        let g = KGrowth {
            k0: 64.0,
            n0: 50_000.0,
            beta: KGrowth::SMOOTH_BETA,
        };
        assert_eq!(g.k(50_000), 64);
        // 8× the photons: 4× the k at β = 2/3.
        assert_eq!(g.k(400_000), 256);
        assert_eq!(g.k(3_200_000), 1024);
        // k/N falls (consistency) while k rises.
        let ks: Vec<(u64, usize)> = [1e4, 1e5, 1e6, 1e7, 1e8]
            .iter()
            .map(|&n| (n as u64, g.k(n as u64)))
            .collect();
        assert!(ks.windows(2).all(|w| w[1].1 > w[0].1
            && (w[1].1 as f64 / w[1].0 as f64) < (w[0].1 as f64 / w[0].0 as f64)));
        // Never above N nor below 1.
        assert_eq!(g.k(10), 1);
        let steep = KGrowth {
            k0: 64.0,
            n0: 10.0,
            beta: 0.5,
        };
        assert_eq!(steep.k(20), 20);
        let tiny = KGrowth {
            k0: 1.0,
            n0: 1e9,
            beta: 0.5,
        };
        assert_eq!(tiny.k(100), 1);
        // β = 0 is the fixed k.
        let fixed = KGrowth {
            k0: 64.0,
            n0: 1.0,
            beta: 0.0,
        };
        assert_eq!(fixed.k(123_456), 64);
    }

    /// `n` photons from a point light (Φ = 100) at height 1 over the plane y = 0: each one that
    /// heads down ends at its impact (the plane absorbs). Irradiance Φ/(4π(1 + x²)^{3/2}).
    fn point_light_impacts(n: u32, seed: u64) -> SegmentStore {
        let watts = 100.0 / f64::from(n);
        let scale = PowerScale::for_max_power(watts);
        let units = scale.units(watts);
        let light = DVec3::Y;
        let mut rng = stream(&[seed]);
        let segs = (0..n)
            .filter_map(|i| {
                let d = uniform_direction(&mut rng);
                (d.y < 0.0).then(|| Segment::new(light, d, -1.0 / d.y, f64::INFINITY, units, i))
            })
            .collect();
        SegmentStore::new(segs, scale)
    }

    /// Relative RMSE of the photon map with k at points spread over |x|, |z| ≤ 0.45.
    fn relative_rmse(store: &SegmentStore, k: usize) -> f64 {
        let pts: Vec<DVec3> = (0..100)
            .map(|i| {
                DVec3::new(
                    -0.45 + 0.1 * (i % 10) as f64,
                    0.0,
                    -0.45 + 0.1 * (i / 10) as f64,
                )
            })
            .collect();
        let est = estimate(store, &pts, &[DVec3::Y; 100], k, Filter::Disc);
        let (mut se2, mut sum) = (0.0, 0.0);
        for (p, e) in pts.iter().zip(&est) {
            let want =
                100.0 / (4.0 * std::f64::consts::PI * (1.0 + p.x * p.x + p.z * p.z).powf(1.5));
            se2 += (e - want).powi(2);
            sum += want;
        }
        (se2 / 100.0).sqrt() / (sum / 100.0)
    }

    /// With a fixed k the error stops falling at ≈ 1/√k; with k ∝ N^{2/3} it keeps falling
    /// (≈ 2× per 8× photons: N^{−1/3}).
    #[test]
    fn a_growing_k_keeps_the_error_falling_where_a_fixed_k_stalls() {
        let growth = KGrowth {
            k0: 32.0,
            n0: 20_000.0,
            beta: KGrowth::SMOOTH_BETA,
        };
        let mut fixed = Vec::new();
        let mut growing = Vec::new();
        for (j, n) in [20_000u32, 160_000, 1_280_000].into_iter().enumerate() {
            let store = point_light_impacts(n, j as u64);
            fixed.push(relative_rmse(&store, 32));
            growing.push(relative_rmse(&store, growth.k(u64::from(n))));
        }
        println!("fixed k = 32: {fixed:?}; growing k: {growing:?}");
        // Fixed: a plateau near 1/√32 = 0.18 (each value within ±35 % of it).
        for e in &fixed {
            assert!((0.115..0.24).contains(e), "{fixed:?}");
        }
        assert!(fixed[2] > 0.6 * fixed[0], "{fixed:?}");
        // Growing: falls at least 1.5× per step (2× expected), far below the plateau at the end.
        assert!(
            growing[1] < growing[0] / 1.5 && growing[2] < growing[1] / 1.5,
            "{growing:?}"
        );
        assert!(growing[2] < 0.4 * fixed[2], "{growing:?} vs {fixed:?}");
    }

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
