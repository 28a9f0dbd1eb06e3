//! The §4.1 predictors: which dynamic-point engine is cheaper for a mover, decided before the frames.
//!
//! Both run each engine on the segments of the first fraction f of the photons (the *subsample*)
//! and time it; cost(n_R) = fixed + per-ray·n_R, the fixed part (posing the discs, building the
//! index or the order) timed on no segments and not scaled.
//! - [`Predictor::Subsample`]: predicted seconds = fixed + (subsample seconds − fixed)/f.
//! - [`Predictor::Paper`], the paper's hybrid (§4.1: "run with only the upper levels of the sphere
//!   list … the lower levels can be estimated accurately by the theoretical approach"): the sphere
//!   cache's counted tests are predicted level by level ([`paper_cache_count`]): levels 0 … s are
//!   simulated on the subsample (where few large spheres hold many rays, the actual counts matter),
//!   levels below s come from theory — rays per sphere N_i = N_s·Q^(2(i−s)) anchored at the
//!   subsample's measured mean at level s scaled by 1/f, spheres per level m_i from the points alone
//!   (the same cache replayed over the same ordered points with no rays and no threshold), tests per
//!   level m_i·N_(i−1), and the deepest level K where the lists fall below the threshold (or r_K
//!   reaches d) gives the disc tests n_P·N_K. The seconds follow from the subsample's: the part that
//!   grows with the rays is scaled by (predicted tests)/(the subsample's counted tests)·(1/f)
//!   instead of 1/f. The disc index's tests are proportional to the segments crossing each disc,
//!   linear in n_R: its prediction is the subsample's counted tests scaled by 1/f (not eqs. 7–8's
//!   closed form, which assumes a balanced index), i.e. the subsample predictor's own seconds.
//!
//! The split s: the paper gives none. It is the deepest level whose parent's list, in the
//! subsample, still expects at least the threshold's rays (N_0·Q^(2(s−1)) ≥ threshold, N_0 the
//! subsample's segments meeting the root): down to s the subsample builds the levels the full run
//! builds; below, its lists fall under the threshold where the full run's do not, and theory takes
//! over. With s at or below the deepest level the cache can build, nothing comes from theory and
//! the prediction is the subsample's, exactly (the tests pin this seam).

use super::{timed, QuasiStatic, Used};
use crate::detp::disc::Discs;
use crate::detp::order::permutation;
use crate::detp::sphere_cache::filter::{kappa, meets, MAX_LEVEL};
use crate::detp::sphere_cache::{self, SphereCacheParams};
use crate::detp::store::SegmentStore;

/// Which §4.1 predictor picks the engine (`dynamic.predictor`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Predictor {
    /// Both engines timed on a fraction of the photons, scaled by 1/fraction.
    #[default]
    Subsample,
    /// The sphere cache's upper levels simulated on the fraction, its lower levels from theory.
    Paper,
}

impl Predictor {
    /// The spelling in specs.
    pub fn as_str(self) -> &'static str {
        match self {
            Predictor::Subsample => "subsample",
            Predictor::Paper => "paper",
        }
    }
}

/// The §4.1 predictor for one mover: each engine's dynamic-point cost predicted from a fraction of
/// the photons, and measured on all of them at the same frame.
#[derive(Clone, Copy, Debug)]
pub struct Prediction {
    /// Predicted seconds (sphere cache, disc index).
    pub predicted: [f64; 2],
    /// Measured seconds on every segment (sphere cache, disc index).
    pub measured: [f64; 2],
    /// The engine the prediction picks.
    pub pick: Used,
    /// The engine that was faster on every segment.
    pub best: Used,
    /// [`Predictor::Paper`]: the level split s and the sphere cache's predicted counted tests.
    pub paper: Option<(usize, f64)>,
}

/// One level of the sphere cache taken from theory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TheoryLevel {
    /// The level i.
    pub level: usize,
    /// Expected rays per sphere, N_i (all photons).
    pub rays: f64,
    /// Spheres built at this level, m_i, from the points alone.
    pub spheres: u64,
}

/// The paper's predicted count of the sphere cache's tests (ray–sphere + ray–disc, the paper's
/// accounting t = u).
#[derive(Clone, Debug, PartialEq)]
pub struct PaperCount {
    /// Levels 0 … split are simulated.
    pub split: usize,
    /// The predicted tests in the subsample's units: the simulated levels' counted tests plus f
    /// times the theory's (the subsample's own counted tests when nothing comes from theory).
    pub subsample_units: f64,
    /// The predicted tests for all photons: `subsample_units`/f.
    pub predicted: f64,
    /// The levels from theory, in order (empty: everything simulated).
    pub theory: Vec<TheoryLevel>,
}

/// The split s: the deepest level whose parent's list holds at least `threshold` of the subsample's
/// `root_rays` in expectation (root_rays·Q^(2(s−1)) ≥ threshold); 0 when even the root holds fewer.
pub fn split_level(root_rays: u64, q: f64, threshold: usize) -> usize {
    let mut s = 0;
    while s < MAX_LEVEL && root_rays as f64 * q.powi(2 * s as i32) >= threshold as f64 {
        s += 1;
    }
    s
}

/// The sphere cache's predicted tests for all photons from the subsample `sub` (a fraction
/// `fraction` of them): levels 0 … `split` simulated, deeper ones from theory (module doc).
pub fn paper_cache_count(
    sub: &SegmentStore,
    discs: &Discs,
    perm: &[u32],
    root: (glam::DVec3, f64),
    params: &SphereCacheParams,
    fraction: f64,
    split: usize,
) -> PaperCount {
    let mut acc = vec![0; discs.len()];
    let sim = sphere_cache::run_to_level(sub, discs, perm, root, params, &mut acc, split);
    let d = discs.radius;
    let q2 = params.q * params.q;
    let mut theory = Vec::new();
    // Tests of the theory's levels: each sphere tests its parent's list, each disc its deepest.
    let mut tests = 0.0;
    if let Some(anchor) = sim.levels.get(split).filter(|l| l.builds > 0) {
        // Spheres per level from the points: the same cache, no rays, always subdividing.
        let empty = SegmentStore::new(Vec::new(), sub.scale);
        let always = SphereCacheParams {
            threshold: 0,
            ..*params
        };
        acc.iter_mut().for_each(|a| *a = 0);
        let geometry = sphere_cache::run(&empty, discs, perm, root, &always, &mut acc);
        let mut parent = anchor.rays_held as f64 / anchor.builds as f64 / fraction;
        let mut i = split + 1;
        // The engine's own rule: a child while the list holds ≥ threshold and r_i ≥ d.
        while parent >= params.threshold as f64
            && i <= MAX_LEVEL
            && root.1 * params.q.powi(i as i32) >= d
        {
            let spheres = geometry.levels.get(i).map_or(0, |l| l.builds);
            tests += spheres as f64 * parent;
            parent *= q2;
            theory.push(TheoryLevel {
                level: i,
                rays: parent,
                spheres,
            });
            i += 1;
        }
    }
    let subsample_units = match theory.last() {
        None => (sim.ray_sphere_tests + sim.ray_disc_tests) as f64,
        Some(deepest) => {
            // A disc outside the root tests every segment, as the engine does.
            let outside = discs
                .centers
                .iter()
                .filter(|&&c| (c - root.0).length() + d > root.1)
                .count();
            tests += (discs.len() - outside) as f64 * deepest.rays;
            sim.ray_sphere_tests as f64
                + fraction * tests
                + (outside as u64 * sub.len() as u64) as f64
        }
    };
    PaperCount {
        split,
        subsample_units,
        predicted: subsample_units / fraction,
        theory,
    }
}

/// The predicted seconds from the timings on no segments (`fixed`) and on the subsample
/// (`part_s`): the part that grows with the rays scaled by `scale`/f (`scale` = 1 for the
/// subsample predictor, exactly, so both agree bit for bit where the paper's takes nothing from
/// theory).
pub fn predicted_seconds(fixed: f64, part_s: f64, scale: f64, fraction: f64) -> f64 {
    fixed + (part_s - fixed).max(0.0) * scale / fraction
}

impl QuasiStatic {
    /// The §4.1 predictor (module doc): runs each dynamic-point engine on the segments of the first
    /// `fraction` of the photons, predicts its seconds on all of them with `predictor`, and (with
    /// `apply`) picks the cheaper one per mover for the frames that follow. To say whether the pick
    /// was right, both engines also run on every segment once.
    pub fn predict_and_pick(
        &mut self,
        fraction: f64,
        predictor: Predictor,
        apply: bool,
    ) -> Vec<Prediction> {
        self.predict_with_split(fraction, predictor, None, apply)
    }

    /// [`Self::predict_and_pick`] with the paper predictor's split forced to `split` (None: the
    /// module doc's rule).
    pub fn predict_with_split(
        &mut self,
        fraction: f64,
        predictor: Predictor,
        split: Option<usize>,
        apply: bool,
    ) -> Vec<Prediction> {
        assert!(fraction > 0.0 && fraction <= 1.0, "fraction in (0, 1]");
        let part = self.subsample(fraction);
        let live = self.live_store();
        let none = SegmentStore::new(Vec::new(), live.scale);
        let time = |store: &SegmentStore, u: Used, m: usize| {
            let (out, s) = timed(|| self.dynamic_sums_with(store, false, Some(u), Some(m)));
            let c = out.first().map_or(0, |o| o.3.disc_tests + o.3.sphere_tests);
            (s, c)
        };
        let engines = [Used::SphereCache, Used::DiscIndex];
        let pick_of = |c: [f64; 2]| if c[0] <= c[1] { engines[0] } else { engines[1] };
        let movers: Vec<usize> = self.dynamic.iter().map(|dp| dp.mover).collect();
        let out: Vec<Prediction> = movers
            .into_iter()
            .map(|m| {
                let paper = (predictor == Predictor::Paper)
                    .then(|| self.paper_count(&part, m, fraction, split));
                let predicted = engines.map(|u| {
                    let (fixed, _) = time(&none, u, m);
                    let (part_s, counted) = time(&part, u, m);
                    let scale = match (&paper, u) {
                        (Some(p), Used::SphereCache) if counted > 0 => {
                            p.subsample_units / counted as f64
                        }
                        _ => 1.0,
                    };
                    predicted_seconds(fixed, part_s, scale, fraction)
                });
                let measured = engines.map(|u| time(&live, u, m).0);
                Prediction {
                    predicted,
                    measured,
                    pick: pick_of(predicted),
                    best: pick_of(measured),
                    paper: paper.map(|p| (p.split, p.predicted)),
                }
            })
            .collect();
        if apply {
            self.picked = out.iter().map(|p| p.pick).collect();
        }
        out
    }

    /// The live segments of the first `fraction` of the photons (at least one photon).
    pub fn subsample(&self, fraction: f64) -> SegmentStore {
        let live = self.live_store();
        let cut = ((self.params.photons as f64 * fraction).ceil() as u32).max(1);
        SegmentStore::new(
            live.segments
                .iter()
                .filter(|s| s.photon < cut)
                .copied()
                .collect(),
            live.scale,
        )
    }

    /// [`paper_cache_count`] for mover `m`'s points at the current pose, as the sphere cache runs
    /// them (its padded root, its order), with the split of the module doc unless forced.
    pub fn paper_count(
        &self,
        part: &SegmentStore,
        m: usize,
        fraction: f64,
        split: Option<usize>,
    ) -> PaperCount {
        let dp = &self.dynamic[m];
        let discs = dp.posed(&self.scene, self.scene.tau(), self.params.disc_radius);
        let perm = permutation(&discs.centers, self.params.order, 10);
        let root = self.dynamic_root(m);
        let split = split.unwrap_or_else(|| {
            let k = kappa(0);
            let n0 = part
                .segments
                .iter()
                .filter(|s| meets(s, root.0, root.1, k))
                .count();
            split_level(n0 as u64, self.params.cache.q, self.params.cache.threshold)
        });
        paper_cache_count(
            part,
            &discs,
            &perm,
            root,
            &self.params.cache,
            fraction,
            split,
        )
    }
}

#[cfg(test)]
#[path = "predict_tests.rs"]
mod tests;
