//! Do the engines return the same first sphere on every ray? The bench's `mismatches` column.
//!
//! The grid and brute force call the same f64 intersection routine, so they must agree exactly:
//! same sphere, same distance to the bit. Embree decides hits in f32, so it is compared by sphere
//! only, and a disagreement counts as a mismatch unless the exact geometry shows it is one f32
//! cannot resolve (a near-tie or a graze, counted apart as `f32_ties`).

use rayon::prelude::*;

use crate::geom::{Ray, Sphere};
use crate::grid::{brute_force, Hit};

/// The outcome of comparing one engine with a reference on a set of rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Agreement {
    /// Rays compared.
    pub checked: u64,
    /// Rays on which the answers differ beyond what the engine's arithmetic explains.
    pub mismatches: u64,
    /// Disagreements explained by f32 resolution (near-ties and grazes; Embree only).
    pub f32_ties: u64,
    /// Largest relative difference of the hit distance where both report the same sphere.
    pub t_rel_diff_max: f64,
}

/// Compares the grid's answers on `rays` with brute force over all `spheres` (exact agreement).
pub fn grid_vs_brute_force(spheres: &[Sphere], rays: &[Ray], grid: &[Option<Hit>]) -> Agreement {
    let mismatches = rays
        .par_iter()
        .zip(grid)
        .filter(|(ray, g)| {
            let want = brute_force(spheres, ray);
            let same = want.map(|h| (h.id, h.t.to_bits())) == g.map(|h| (h.id, h.t.to_bits()));
            if !same {
                eprintln!(
                    "grid mismatch: o = {:?} d = {:?}: grid {g:?}, brute force {want:?}",
                    ray.o, ray.d
                );
            }
            !same
        })
        .count() as u64;
    Agreement {
        checked: rays.len() as u64,
        mismatches,
        f32_ties: 0,
        t_rel_diff_max: 0.0,
    }
}

/// Compares Embree's answers (index into `spheres`, f32 distance) with the grid's on every ray.
#[cfg_attr(not(feature = "embree"), allow(dead_code))] // unit-tested in every build
pub fn embree_vs_grid(
    spheres: &[Sphere],
    rays: &[Ray],
    embree: &[Option<(usize, f64)>],
    grid: &[Option<Hit>],
) -> Agreement {
    let mut out = Agreement {
        checked: rays.len() as u64,
        ..Agreement::default()
    };
    for ((ray, e), g) in rays.iter().zip(embree).zip(grid) {
        match (e, g) {
            (Some((ei, te)), Some(gh)) if spheres[*ei].id == gh.id => {
                out.t_rel_diff_max = out.t_rel_diff_max.max((te - gh.t).abs() / gh.t);
            }
            (None, None) => {}
            _ => {
                let by_index = |h: &Hit| {
                    spheres
                        .iter()
                        .find(|s| s.id == h.id)
                        .expect("the grid reports ids of the scene's spheres")
                };
                let explained = match (e, g) {
                    (Some((ei, _)), Some(gh)) => {
                        near_tie(&spheres[*ei], ray, gh.t)
                            || grazed(&spheres[*ei], ray)
                            || grazed(by_index(gh), ray)
                    }
                    (Some((ei, _)), None) => grazed(&spheres[*ei], ray),
                    (None, Some(gh)) => grazed(by_index(gh), ray),
                    (None, None) => true,
                };
                if explained {
                    out.f32_ties += 1;
                } else {
                    out.mismatches += 1;
                    eprintln!(
                        "embree mismatch: o = {:?} d = {:?}: embree {e:?} (f64 t {:?}), grid {g:?}",
                        ray.o,
                        ray.d,
                        e.and_then(|(i, _)| spheres[i].intersect(ray))
                    );
                }
            }
        }
    }
    out
}

/// Does `ray` enter `s` within 1e-5 relative of `t_ref` (a tie f32 cannot order)?
#[cfg_attr(not(feature = "embree"), allow(dead_code))]
fn near_tie(s: &Sphere, ray: &Ray, t_ref: f64) -> bool {
    s.intersect(ray)
        .is_some_and(|t| (t - t_ref).abs() <= 1e-5 * t_ref)
}

/// Does `ray` graze `s` within f32 resolution? Embree forms the discriminant from |f|² − b² in
/// f32, so its absolute error is a few ε₃₂·|f|².
#[cfg_attr(not(feature = "embree"), allow(dead_code))]
fn grazed(s: &Sphere, ray: &Ray) -> bool {
    let f = s.c - ray.o;
    let v = f - f.dot(ray.d) * ray.d;
    (v.length_squared() - s.r * s.r).abs() <= 8.0 * f64::from(f32::EPSILON) * f.length_squared()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    fn sphere(c: [f64; 3], r: f64, id: u64) -> Sphere {
        Sphere {
            c: DVec3::from(c),
            r,
            id,
        }
    }

    #[test]
    fn exact_agreement_is_required_of_the_grid() {
        let spheres = [
            sphere([5.0, 0.0, 0.0], 1.0, 0),
            sphere([9.0, 0.0, 0.0], 1.0, 1),
        ];
        let rays = [
            Ray::new(DVec3::ZERO, DVec3::X),
            Ray::new(DVec3::ZERO, DVec3::Y),
        ];
        let right = [Some(Hit { id: 0, t: 4.0 }), None];
        assert_eq!(grid_vs_brute_force(&spheres, &rays, &right).mismatches, 0);
        let wrong_sphere = [Some(Hit { id: 1, t: 8.0 }), None];
        assert_eq!(
            grid_vs_brute_force(&spheres, &rays, &wrong_sphere).mismatches,
            1
        );
        let wrong_t = [
            Some(Hit {
                id: 0,
                t: 4.0 + 1e-15,
            }),
            None,
        ];
        assert_eq!(grid_vs_brute_force(&spheres, &rays, &wrong_t).mismatches, 1);
    }

    #[test]
    fn embree_disagreements_are_mismatches_unless_f32_explains_them() {
        // Two spheres entered at t = 4 and t = 4(1 + 1e-7): a near-tie f32 cannot order.
        let spheres = [
            sphere([5.0, 0.0, 0.0], 1.0, 0),
            sphere([5.0 + 4e-7, 0.0, 0.0], 1.0, 1),
            sphere([0.0, 20.0, 0.0], 1.0, 2),
        ];
        let rays = [
            Ray::new(DVec3::ZERO, DVec3::X),
            Ray::new(DVec3::ZERO, DVec3::Y),
        ];
        let grid = [Some(Hit { id: 0, t: 4.0 }), Some(Hit { id: 2, t: 19.0 })];
        let tie = embree_vs_grid(&spheres, &rays, &[Some((1, 4.0)), Some((2, 19.0))], &grid);
        assert_eq!((tie.mismatches, tie.f32_ties), (0, 1));
        // Missing a sphere hit head-on is not something f32 explains.
        let miss = embree_vs_grid(&spheres, &rays, &[Some((0, 4.0)), None], &grid);
        assert_eq!((miss.mismatches, miss.f32_ties), (1, 0));
    }
}
