//! Closed forms of the DETP paper (restated, with the derivations its scan garbles, in
//! `docs/theory.md` §2): rays per sphere-cache level, Theorem 1 for the sphere cache and for disc indexing,
//! Proposition 1's optimal ratio Q = 2/3, and the quasi-static re-traced rays f_R with Theorem 2's
//! crossover. Pure functions: no I/O, no randomness.
//!
//! Symbols: n_R rays, n_P points, Q ratio of consecutive radii (r_i = r_0·Q^i), t one ray–sphere test,
//! u one ray–disc test, r_D/r_0 the dynamic object's bounding radius over the root sphere's.

use std::f64::consts::PI;

/// Expected rays held by a level-`level` sphere inside the root: integral geometry says a μ-random
/// line meeting a convex body K meets a convex K' ⊂ K with probability area(K')/area(K), so a sphere
/// of radius r_i anywhere inside the root holds n_R·(r_i/r_0)² = n_R·Q^(2i) of the root's rays.
pub fn rays_per_level(n_r: f64, q: f64, level: u32) -> f64 {
    n_r * q.powi(2 * level as i32)
}

/// Expected rays of a sphere of radius `r` (centre at distance `c` from the root's centre) for
/// μ-random lines that meet the root of radius `r0`, *when the sphere sticks out of the root*: the
/// lines must meet the root, and only those meeting the lens S ∩ B are certain to; a line can also
/// pass through S \ B and B \ S without meeting the lens, which this lower estimate leaves out. The
/// lens is convex, so P(meets lens) = area(lens)/area(B) exactly; for spheres inside the root this is
/// (r/r0)², the law above. Used as the "clipped" theory column where levels reach the root's rim.
pub fn rays_in_clipped_sphere(n_r: f64, r0: f64, c: f64, r: f64) -> f64 {
    n_r * lens_area(r0, c, r) / (4.0 * PI * r0 * r0)
}

/// Surface area of the lens B(0, r0) ∩ B(c, r) (centres `c` apart), exact: the part of each sphere's
/// surface inside the other ball, two spherical caps.
pub fn lens_area(r0: f64, c: f64, r: f64) -> f64 {
    if c + r <= r0 {
        return 4.0 * PI * r * r; // inside the root
    }
    if c + r0 <= r {
        return 4.0 * PI * r0 * r0; // contains the root
    }
    if c >= r0 + r {
        return 0.0; // apart
    }
    // Plane of the intersection circle at distance x from the root's centre.
    let x = (c * c + r0 * r0 - r * r) / (2.0 * c);
    // Cap of the small sphere inside B: height h_s along the axis, area 2π r h.
    let h_small = r - (c - x); // part of sphere S on the root's side of the plane
    let h_root = r0 - x; // part of the root's surface beyond the plane (inside S)
    2.0 * PI * r * h_small + 2.0 * PI * r0 * h_root
}

/// Mean of [`rays_in_clipped_sphere`] over sphere centres uniform in the root ball (what a level
/// built around points uniform in the unit ball holds on average), by Gauss–Legendre quadrature over
/// the centre's radial distance (density 3c²/r0³).
pub fn rays_per_level_uniform_centres(n_r: f64, r0: f64, r: f64) -> f64 {
    // 64-point composite midpoint over [0, r0] in c³ (uniform in volume), exact enough (1e-6).
    let m = 4096;
    let mut s = 0.0;
    for k in 0..m {
        let u = (k as f64 + 0.5) / m as f64; // u = (c/r0)³ uniform
        let c = r0 * u.cbrt();
        s += rays_in_clipped_sphere(n_r, r0, c, r);
    }
    s / m as f64
}

/// Proposition 1's factor 1/(Q²(1 − Q)) of the re-building cost.
pub fn rebuild_factor(q: f64) -> f64 {
    1.0 / (q * q * (1.0 - q))
}

/// Proposition 1: the factor is minimal at Q = 2/3 (value 27/4).
pub const OPTIMAL_Q: f64 = 2.0 / 3.0;

/// Theorem 1, sphere cache: re-building T_R = (t·n_R/Q²)(∛n_P − 1)/(1 − Q) plus inner spheres
/// T_I = (4/3)·u·n_R·∛n_P. Returns (T_R, T_I).
pub fn sphere_cache_cost(t: f64, u: f64, n_r: f64, n_p: f64, q: f64) -> (f64, f64) {
    let c = n_p.cbrt();
    (
        t * n_r / (q * q) * (c - 1.0) / (1.0 - q),
        4.0 / 3.0 * u * n_r * c,
    )
}

/// Theorem 1, disc indexing: T = u·n_R·∛n_P (a balanced index whose voxels stop at the point spacing).
pub fn disc_index_cost(u: f64, n_r: f64, n_p: f64) -> f64 {
    u * n_r * n_p.cbrt()
}

/// Disc radius of points on a regular grid of spacing d with ∛n_P per side inside the root sphere
/// (eq. 4): r_0 = √3·d·∛n_P / 2, so d = 2 r_0 / (√3·∛n_P).
pub fn grid_spacing_for_root(r0: f64, n_p: f64) -> f64 {
    2.0 * r0 / (3f64.sqrt() * n_p.cbrt())
}

/// Mean spacing of n_P points uniform in a ball of radius r0: the side of the cube of the same volume
/// per point, (4π/3 · r0³ / n_P)^(1/3).
pub fn ball_spacing(r0: f64, n_p: f64) -> f64 {
    (4.0 * PI / 3.0 * r0.powi(3) / n_p).cbrt()
}

/// The radius schedule d(N) = d_ref·(N/N_ref)^(−β): the disc radius at N photons.
///
/// For a disc estimate of a smooth irradiance field E, the disc average is E + (d²/8)·ΔE + O(d⁴)
/// (bias ∝ d²) and the count of crossings is Poisson with mean ∝ N·d² (relative variance
/// ∝ 1/(N·d²)); MSE = a·d⁴ + b/(N·d²) is least at d⁶ = b/(2a·N), so β = 1/6 and the RMSE at that d
/// falls as N^(−1/3). At N = N_ref the result is d_ref exactly.
pub fn scheduled_radius(d_ref: f64, n: f64, n_ref: f64, beta: f64) -> f64 {
    d_ref * (n / n_ref).powf(-beta)
}

/// Deepest level a sphere cache can reach: the last i with n_R·Q^(2(i−1)) ≥ threshold (its parent is
/// subdivided) and r_0·Q^i ≥ d (it still holds the disc).
pub fn deepest_level(n_r: f64, q: f64, threshold: f64, r0: f64, d: f64) -> u32 {
    let mut i = 0;
    while rays_per_level(n_r, q, i) >= threshold && r0 * q.powi(i as i32 + 1) >= d {
        i += 1;
    }
    i
}

/// Quasi-static re-traced rays per frame, eq. 11: f_R ≈ n_R·(r_D/r_0)².
pub fn retraced_rays(n_r: f64, ratio: f64) -> f64 {
    n_r * ratio * ratio
}

/// The share of μ-random lines through the unit ball that meet a ball of radius `r` at either of
/// two poses whose centres are `shift` apart (both balls inside the unit ball; lengths in units of
/// r_0): the expected union of the old and the new pose of eq. 11's count, over n_R.
///
/// Lines of one direction u meet a ball iff they cross its projection on the plane ⊥ u, a disc of
/// radius r; the two poses project to discs whose centres are s = shift·sin θ apart (θ between u
/// and the shift), whose union has area 2πr² − L(s) with the lens L(s) = 2r²·acos(s/2r) −
/// (s/2)·√(4r² − s²) for s < 2r (0 beyond). μ-random lines are isotropic with a uniform foot in
/// every direction's projected unit disc (area π), and cos θ is uniform on [0, 1], so
///
///   share = 2r² − (1/π)·∫₀¹ L(shift·√(1 − c²)) dc
///
/// (r² at shift 0; below 2r² at every shift, since lines nearly along the shift meet both poses).
/// The integral is a composite Simpson sum over 4096
/// intervals (the integrand is continuous; its one kink, at s = 2r, costs < 10⁻⁶ of the share).
pub fn union_lines_share(r: f64, shift: f64) -> f64 {
    let lens = |s: f64| {
        if s >= 2.0 * r {
            0.0
        } else {
            2.0 * r * r * (s / (2.0 * r)).acos() - 0.5 * s * (4.0 * r * r - s * s).max(0.0).sqrt()
        }
    };
    let f = |c: f64| lens(shift * (1.0 - c * c).max(0.0).sqrt());
    const N: usize = 4096;
    let h = 1.0 / N as f64;
    let inner: f64 = (1..N)
        .map(|k| {
            let w = if k % 2 == 1 { 4.0 } else { 2.0 };
            w * f(k as f64 * h)
        })
        .sum();
    let integral = (f(0.0) + inner + f(1.0)) * h / 3.0;
    2.0 * r * r - integral / std::f64::consts::PI
}

/// Constant of the sphere cache's cost per ray and ∛n (eqs. 12–13): 1/(Q²(1−Q))·(∛n − 1)/∛n + 4/3,
/// which at Q = 2/3 and large n is 6.75 + 4/3 = 8.08.
pub fn sphere_cache_constant(q: f64, n: f64) -> f64 {
    let c = n.cbrt();
    let share = if c.is_finite() { (c - 1.0) / c } else { 1.0 };
    rebuild_factor(q) * share + 4.0 / 3.0
}

/// Static points, eqs. 13–14 (t ≈ u): (sphere cache, disc indexing) costs in units of t.
pub fn static_points_cost(f_r: f64, n_s: f64, q: f64) -> (f64, f64) {
    let c = n_s.cbrt();
    (sphere_cache_constant(q, n_s) * f_r * c, 2.0 * f_r * c)
}

/// Dynamic points, eqs. 15–16 (t ≈ u): (sphere cache, disc indexing) costs in units of t.
pub fn dynamic_points_cost(n_r: f64, ratio: f64, n_d: f64, q: f64) -> (f64, f64) {
    let c = n_d.cbrt();
    (
        sphere_cache_constant(q, n_d) * retraced_rays(n_r, ratio) * c,
        n_r * c,
    )
}

/// Theorem 2's crossover r_D/r_0 where both engines cost the same for dynamic points:
/// 1/√(sphere-cache constant). `n_d = ∞` gives the paper's 1/√8.08 ≈ 0.35.
pub fn crossover_ratio(q: f64, n_d: f64) -> f64 {
    1.0 / sphere_cache_constant(q, n_d).sqrt()
}

/// E[X | X < k] for X ~ Poisson(λ): the mean rays of a sphere that is not subdivided when its
/// count is Poisson(λ) and a sphere holding k or more is (docs/theory.md §2: λ = 106.5, k = 100 gives
/// 93.6, the likely reading of the paper's "94.6 at level 9"). Uses E[X·1{X<k}] = λ·P(X ≤ k−2), so
/// the value is λ·P(X ≤ k−2)/P(X ≤ k−1); NaN for k = 0.
pub fn poisson_mean_below(lambda: f64, k: u64) -> f64 {
    if k == 0 || lambda.is_nan() || lambda < 0.0 {
        return f64::NAN;
    }
    if k == 1 || lambda == 0.0 {
        return 0.0;
    }
    // Terms relative to the largest one below k (log space: λ can be 10⁶).
    let ln_pmf = |x: u64| x as f64 * lambda.ln() - lambda - ln_factorial(x);
    let top = ln_pmf((k - 1).min(lambda.floor() as u64));
    let (mut below_k1, mut below_k2) = (0.0, 0.0);
    for x in 0..k {
        let p = (ln_pmf(x) - top).exp();
        below_k1 += p;
        if x + 2 <= k {
            below_k2 += p;
        }
    }
    lambda * below_k2 / below_k1
}

/// ln(x!) by summation below 256 and Stirling's series above (error < 1e-12 relative there).
fn ln_factorial(x: u64) -> f64 {
    if x < 256 {
        (2..=x).map(|i| (i as f64).ln()).sum()
    } else {
        let n = x as f64;
        n * n.ln() - n + 0.5 * (2.0 * std::f64::consts::PI * n).ln() + 1.0 / (12.0 * n)
            - 1.0 / (360.0 * n.powi(3))
    }
}

#[cfg(test)]
mod tests {

    /// d(N) at the reference count is d_ref exactly; each doubling of N divides d by 2^β; β = 0
    /// keeps d; the MSE a·d⁴ + b/(N·d²) at the scheduled d with β = 1/6 falls as N^(−2/3).
    #[test]
    fn scheduled_radius_follows_the_power_law_and_minimises_the_mse() {
        use super::scheduled_radius;
        assert_eq!(scheduled_radius(0.05, 1e5, 1e5, 1.0 / 6.0), 0.05);
        assert_eq!(scheduled_radius(0.05, 4e5, 1e5, 0.0), 0.05);
        let (d1, d2) = (
            scheduled_radius(0.05, 2e5, 1e5, 0.25),
            scheduled_radius(0.05, 4e5, 1e5, 0.25),
        );
        assert!((d1 / d2 - 2f64.powf(0.25)).abs() < 1e-14, "{d1} {d2}");
        assert!((scheduled_radius(0.05, 1e5 * 64.0, 1e5, 1.0 / 6.0) - 0.025).abs() < 1e-15);
        // The MSE-optimal d of a·d⁴ + b/(N·d²) is (b/(2aN))^(1/6): a schedule through it at N_ref
        // stays on it at every N, and a numerical minimum agrees.
        let (a, b) = (3.0, 0.7);
        let opt = |n: f64| (b / (2.0 * a * n)).powf(1.0 / 6.0);
        let mse = |d: f64, n: f64| a * d.powi(4) + b / (n * d * d);
        for n in [1e3, 1e5, 1e7] {
            let d = scheduled_radius(opt(1e3), n, 1e3, 1.0 / 6.0);
            assert!((d / opt(n) - 1.0).abs() < 1e-12, "{n}: {d} vs {}", opt(n));
            assert!(mse(d, n) <= mse(d * 1.01, n) && mse(d, n) <= mse(d * 0.99, n));
        }
    }

    /// docs/theory.md §2's number, and a brute-force sum of the conditional mean.
    #[test]
    fn poisson_mean_below_the_threshold() {
        let m = poisson_mean_below(106.5, 100);
        assert!((m - 93.6).abs() < 0.05, "{m}");
        for (lambda, k) in [(3.0f64, 5u64), (50.0, 40), (200.0, 250), (0.5, 2)] {
            let mut pmf = (-lambda).exp();
            let (mut num, mut den) = (0.0, 0.0);
            for x in 0..k {
                if x > 0 {
                    pmf *= lambda / x as f64;
                }
                num += x as f64 * pmf;
                den += pmf;
            }
            let want = num / den;
            let got = poisson_mean_below(lambda, k);
            assert!(
                (got - want).abs() < 1e-9 * want.max(1.0),
                "{lambda} {k}: {got} vs {want}"
            );
        }
        assert_eq!(poisson_mean_below(10.0, 1), 0.0);
        assert!(poisson_mean_below(10.0, 0).is_nan());
    }

    use super::*;

    #[test]
    fn proposition_1_optimum_is_two_thirds() {
        let f = rebuild_factor(OPTIMAL_Q);
        assert!((f - 6.75).abs() < 1e-12);
        for k in 1..100 {
            let q = k as f64 / 100.0;
            assert!(rebuild_factor(q) >= f - 1e-12, "Q = {q}");
        }
    }

    #[test]
    fn theorem_2_crossover_is_035() {
        let r = crossover_ratio(OPTIMAL_Q, f64::INFINITY);
        assert!((r - 1.0 / (6.75f64 + 4.0 / 3.0).sqrt()).abs() < 1e-12);
        assert!((r - 0.3517).abs() < 1e-4, "{r}");
        let (sc, di) = dynamic_points_cost(1e6, r, 1e4, OPTIMAL_Q);
        let scale =
            sphere_cache_constant(OPTIMAL_Q, 1e4) / sphere_cache_constant(OPTIMAL_Q, f64::INFINITY);
        assert!((sc / di - scale).abs() < 1e-12);
        // At the finite-n crossover the two are equal exactly.
        let rn = crossover_ratio(OPTIMAL_Q, 1e4);
        let (sc, di) = dynamic_points_cost(1e6, rn, 1e4, OPTIMAL_Q);
        assert!((sc / di - 1.0).abs() < 1e-12);
    }

    /// The union's share against a Monte Carlo count of μ-random lines (the law the quasi-static
    /// lines draw) meeting either of two balls inside the unit ball, for shifts from 0 to beyond
    /// the two balls' overlap: within 4.5 binomial standard errors, and r² at shift 0 exactly.
    #[test]
    fn union_of_two_poses_matches_a_monte_carlo_count_of_lines() {
        use crate::sample::lines::uniform_line;
        use crate::sample::rng::{domain, stream};
        let meets = |p: glam::DVec3, d: glam::DVec3, c: glam::DVec3, r: f64| {
            let t = (c - p).dot(d);
            (p + d * t).distance_squared(c) <= r * r
        };
        assert!((union_lines_share(0.3, 0.0) - 0.09).abs() < 1e-9);
        // Far apart, only lines within ≈ 2r/shift of the shift's direction meet both.
        let far = union_lines_share(0.05, 1.8);
        assert!(far < 0.005 && far > 0.005 - 0.0025 * 0.1 / 1.8, "{far}");
        let n = 200_000u64;
        for (k, &(r, shift)) in [
            (0.3, 0.35 * 2f64.sqrt()),
            (0.1, 0.05),
            (0.25, 0.3),
            (0.4, 0.1),
        ]
        .iter()
        .enumerate()
        {
            let a = glam::DVec3::new(-shift / 2.0, 0.1, 0.0);
            let b = a + glam::DVec3::new(shift * 0.6, shift * 0.8, 0.0);
            let mut rng = stream(&[domain::LINES, 99, k as u64]);
            let hits = (0..n)
                .filter(|_| {
                    let (p, d) = uniform_line(&mut rng);
                    meets(p, d, a, r) || meets(p, d, b, r)
                })
                .count() as f64;
            let share = union_lines_share(r, shift);
            let se = (share * (1.0 - share) / n as f64).sqrt();
            let z = (hits / n as f64 - share) / se;
            assert!(
                z.abs() < 4.5,
                "r {r}, shift {shift}: MC {} vs {share} (z {z:.2})",
                hits / n as f64
            );
            // Neither one pose nor twice it: the union lies strictly between.
            assert!(share > r * r && share < 2.0 * r * r, "r {r}, shift {shift}");
        }
    }

    #[test]
    fn static_points_disc_index_wins_by_the_papers_factor() {
        let (sc, di) = static_points_cost(1000.0, 1e30, OPTIMAL_Q);
        assert!((sc / di - 8.0833 / 2.0).abs() < 1e-3);
    }

    #[test]
    fn level_nine_of_the_papers_validation_holds_106_rays() {
        let r = rays_per_level(1024.0 * 1024.0, 0.6, 9);
        assert!((r - 106.5).abs() < 0.1, "{r}");
    }

    #[test]
    fn lens_area_limits_and_continuity() {
        let full = 4.0 * PI;
        assert_eq!(lens_area(1.0, 0.2, 0.5), PI);
        assert!((lens_area(1.0, 0.5 - 1e-12, 0.5) - PI).abs() < 1e-9);
        assert!(
            (lens_area(1.0, 0.5 + 1e-9, 0.5) - PI).abs() < 1e-6,
            "continuous at tangency"
        );
        assert!(
            (lens_area(1.0, 1.5 - 1e-9, 0.5)).abs() < 1e-6,
            "vanishes as the spheres part"
        );
        assert_eq!(lens_area(1.0, 0.1, 2.0), full);
        // Half-way case: a sphere of radius r centred on the root's surface, small r: about half its
        // area inside plus a root cap of area ≈ π r².
        let r = 1e-3;
        let a = lens_area(1.0, 1.0, r);
        assert!(
            (a / (2.0 * PI * r * r + PI * r * r) - 1.0).abs() < 1e-2,
            "{a}"
        );
    }

    #[test]
    fn clipped_mean_is_below_the_inside_law_and_approaches_it_for_small_spheres() {
        let n = 1e6;
        let inside = rays_per_level(n, 0.6, 4);
        let clipped = rays_per_level_uniform_centres(n, 1.0, 0.6f64.powi(4));
        assert!(clipped < inside);
        let small = rays_per_level_uniform_centres(n, 1.0, 1e-3);
        assert!((small / (n * 1e-6) - 1.0).abs() < 1e-2);
    }

    #[test]
    fn theorem_1_reads_as_stated() {
        let (tr, ti) = sphere_cache_cost(1.0, 1.0, 1e6, 1e6, OPTIMAL_Q);
        assert!((tr - 1e6 * 6.75 * 99.0).abs() < 1e-3);
        assert!((ti - 4.0 / 3.0 * 1e8).abs() < 1e-3);
        assert!((disc_index_cost(1.0, 1e6, 1e6) - 1e8).abs() < 1e-3);
        assert_eq!(deepest_level(1024.0 * 1024.0, 0.6, 100.0, 1.0, 1e-6), 10);
    }
}
