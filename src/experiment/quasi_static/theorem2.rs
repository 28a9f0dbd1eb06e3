//! Theorem 2 in its proof's setting, one assumption at a time, from one frame's counts.
//!
//! The proof charges the sphere cache 8.08·t·f_R·∛n_D and the disc index t·∛n_D for every ray of
//! the scene (n_R, eq. 10): the two are equal at r_D/r_0 = 1/√8.08 ≈ 0.35. What the engines do
//! factors exactly into four measured quantities, each with the value the proof assumes:
//!
//! | factor | measured (per frame) | the proof |
//! |---|---|---|
//! | A1 | rays meeting the object at one pose ÷ n_R·Σ(r_D/r_0)² (`rays_at_pose` ÷ f_R) | 1 |
//! | A2 | the sphere cache's ray–disc + ray–sphere tests ÷ (rays at the pose·∛n_D) | 8.08 |
//! | A3 | rays reaching the dynamic points' disc index ÷ n_R | 1 |
//! | A4 | the disc index's ray–disc tests ÷ (rays reaching it·∛n_D) | 1 |
//!
//! so that the sphere cache's counted work is A2·A1·f_R·∛n_D and the disc index's A4·A3·n_R·∛n_D
//! (the paper's accounting, traversal at weight 0). The proof's accounting ([`proof_cost`]) keeps
//! the sphere cache's measured work and charges the disc index n_R·∛n_D (A3 = A4 = 1). Each
//! counterfactual ([`Assumption`], [`cost_assuming`]) puts one factor at the proof's value and keeps
//! the others measured; its crossing beside the measured one says how far that assumption moves
//! the crossover. Each is a cost per frame of the engine the frame used, so the claims engine's
//! crossover (a fit of log(sphere cache / disc index) over the swept ratios) reads it like any
//! other accounting's cost.

use crate::detp::quasi_static::{FrameStats, Used};

/// The sphere cache's constant the proof uses (eqs. 12–13 at Q = 2/3, n → ∞).
pub const PROOF_CACHE_CONSTANT: f64 = 8.08;

/// The engine the frame's (first) object used; None without one.
fn engine(s: &FrameStats) -> Option<Used> {
    s.used.first().copied()
}

/// a ÷ b, NaN (never infinite: a table refuses it) when b is not positive.
fn per(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        f64::NAN
    }
}

/// ∛n_D.
fn cbrt_nd(s: &FrameStats) -> f64 {
    (s.dynamic_points as f64).cbrt()
}

/// The sphere cache's counted work on the dynamic points: ray–disc + ray–sphere tests (t = u).
fn cache_work(s: &FrameStats) -> f64 {
    (s.dynamic_disc_tests + s.dynamic_sphere_tests) as f64
}

/// A1: rays meeting the objects at one pose ÷ f_R = n_R·Σ(r_D/r_0)².
pub fn rays_per_pose_share(s: &FrameStats) -> f64 {
    per(s.meeting_pose as f64, s.f_r_theory())
}

/// A2: the sphere cache's work per ray at the pose per ∛n_D (the proof: 8.08); NaN on a frame
/// whose points used the disc index.
pub fn cache_work_per_ray(s: &FrameStats) -> f64 {
    match engine(s) {
        Some(Used::SphereCache) => per(cache_work(s), s.meeting_pose as f64 * cbrt_nd(s)),
        _ => f64::NAN,
    }
}

/// A3: the share of the scene's rays that reach the dynamic points' disc index (the proof: 1);
/// NaN on a sphere-cache frame.
pub fn reach_share(s: &FrameStats) -> f64 {
    match engine(s) {
        Some(Used::DiscIndex) => per(s.dynamic_rays_reaching as f64, s.segments_live as f64),
        _ => f64::NAN,
    }
}

/// A4: the disc index's ray–disc tests per ray that reaches it, per ∛n_D (the proof: 1); NaN on
/// a sphere-cache frame.
pub fn index_tests_per_ray(s: &FrameStats) -> f64 {
    match engine(s) {
        Some(Used::DiscIndex) => {
            per(
                s.dynamic_disc_tests as f64,
                s.dynamic_rays_reaching as f64 * cbrt_nd(s),
            )
        }
        _ => f64::NAN,
    }
}

/// The proof's accounting: the sphere cache its measured work, the disc index t·∛n_D for every
/// ray of the scene (n_R·∛n_D); NaN without an object.
pub fn proof_cost(s: &FrameStats) -> f64 {
    match engine(s) {
        Some(Used::SphereCache) => cache_work(s),
        Some(Used::DiscIndex) => s.segments_live as f64 * cbrt_nd(s),
        None => f64::NAN,
    }
}

/// One assumption of the proof put in place of its measured factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Assumption {
    /// A1 = 1: the rays at one pose are n_R·Σ(r_D/r_0)².
    RaysPerPose,
    /// A2 = 8.08: the sphere cache's work per ray at the pose is 8.08·∛n_D.
    CacheConstant,
    /// A3 = 1: every ray of the scene reaches the disc index.
    EveryRay,
    /// A4 = 1: a ray reaching the disc index costs ∛n_D ray–disc tests.
    CbrtTests,
}

impl Assumption {
    /// All four, in the order of the factors.
    pub const ALL: [Assumption; 4] = [
        Assumption::RaysPerPose,
        Assumption::CacheConstant,
        Assumption::EveryRay,
        Assumption::CbrtTests,
    ];

    /// Its name in the column `dynamic_cost_assuming_{}`.
    pub fn name(self) -> &'static str {
        match self {
            Assumption::RaysPerPose => "rays_per_pose",
            Assumption::CacheConstant => "cache_constant",
            Assumption::EveryRay => "every_ray",
            Assumption::CbrtTests => "cbrt_tests",
        }
    }
}

/// The frame's counted cost (the paper's accounting: ray–disc + ray–sphere tests, traversal at
/// weight 0) with one factor replaced by the proof's value, the others as measured.
pub fn cost_assuming(s: &FrameStats, a: Assumption) -> f64 {
    let used = match engine(s) {
        Some(u) => u,
        None => return f64::NAN,
    };
    match (used, a) {
        (Used::SphereCache, Assumption::RaysPerPose) => {
            per(cache_work(s) * s.f_r_theory(), s.meeting_pose as f64)
        }
        (Used::SphereCache, Assumption::CacheConstant) => {
            PROOF_CACHE_CONSTANT * s.meeting_pose as f64 * cbrt_nd(s)
        }
        (Used::SphereCache, _) => cache_work(s),
        (Used::DiscIndex, Assumption::EveryRay) => {
            per(
                s.dynamic_disc_tests as f64 * s.segments_live as f64,
                s.dynamic_rays_reaching as f64,
            )
        }
        (Used::DiscIndex, Assumption::CbrtTests) => {
            s.dynamic_rays_reaching as f64 * cbrt_nd(s)
        }
        (Used::DiscIndex, _) => s.dynamic_disc_tests as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame with known counts: n_R = 10⁴, n_D = 1000 (∛ = 10), f_R = 400.
    fn frame(used: Used) -> FrameStats {
        FrameStats {
            used: vec![used],
            segments_live: 10_000,
            dynamic_points: 1000,
            ratio_sq: 0.04,
            meeting_pose: 380,
            dynamic_disc_tests: 20_000,
            dynamic_sphere_tests: 10_000,
            dynamic_rays_reaching: 2_500,
            ..Default::default()
        }
    }

    #[test]
    fn the_factors_multiply_back_to_the_counted_costs() {
        let (sc, di) = (frame(Used::SphereCache), frame(Used::DiscIndex));
        let (a1, a2) = (rays_per_pose_share(&sc), cache_work_per_ray(&sc));
        let (a3, a4) = (reach_share(&di), index_tests_per_ray(&di));
        assert!((a1 - 0.95).abs() < 1e-12);
        assert!((a2 - 30_000.0 / 3_800.0).abs() < 1e-12);
        assert!((a3 - 0.25).abs() < 1e-12);
        assert!((a4 - 20_000.0 / 25_000.0).abs() < 1e-12);
        // Work = A2·A1·f_R·∛n_D and A4·A3·n_R·∛n_D.
        assert!((a2 * a1 * 400.0 * 10.0 - 30_000.0).abs() < 1e-6);
        assert!((a4 * a3 * 10_000.0 * 10.0 - 20_000.0).abs() < 1e-6);
        // Each engine's own factors only.
        assert!(cache_work_per_ray(&di).is_nan() && reach_share(&sc).is_nan());
        assert!(index_tests_per_ray(&sc).is_nan());
    }

    #[test]
    fn the_proof_charges_the_disc_index_every_ray() {
        let (sc, di) = (frame(Used::SphereCache), frame(Used::DiscIndex));
        assert_eq!(proof_cost(&sc), 30_000.0);
        assert!((proof_cost(&di) - 10_000.0 * 10.0).abs() < 1e-6);
        // A3 and A4 both at the proof's value give the proof's charge.
        let both = cost_assuming(&di, Assumption::EveryRay) / index_tests_per_ray(&di);
        assert!((both - proof_cost(&di)).abs() < 1e-6);
        assert!(proof_cost(&FrameStats::default()).is_nan());
    }

    #[test]
    fn each_counterfactual_replaces_its_factor_alone() {
        let (sc, di) = (frame(Used::SphereCache), frame(Used::DiscIndex));
        let a2 = cache_work_per_ray(&sc);
        // A1 = 1: work scaled from 380 rays to 400.
        assert!((cost_assuming(&sc, Assumption::RaysPerPose) - a2 * 400.0 * 10.0).abs() < 1e-6);
        assert!(
            (cost_assuming(&sc, Assumption::CacheConstant) - 8.08 * 380.0 * 10.0).abs() < 1e-6
        );
        assert!((cost_assuming(&di, Assumption::EveryRay) - 20_000.0 * 4.0).abs() < 1e-6);
        assert!((cost_assuming(&di, Assumption::CbrtTests) - 25_000.0).abs() < 1e-6);
        // The other engine keeps its counted cost.
        for a in [Assumption::EveryRay, Assumption::CbrtTests] {
            assert_eq!(cost_assuming(&sc, a), 30_000.0);
        }
        for a in [Assumption::RaysPerPose, Assumption::CacheConstant] {
            assert_eq!(cost_assuming(&di, a), 20_000.0);
        }
    }
}
