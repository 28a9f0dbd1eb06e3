//! Per-point path tracing as a *competitor* of DETP: the estimator of
//! [`crate::lt::reference`] — next-event estimation, the same physics, the very same
//! [`reference::sample`] — run on its own streams, so that it is statistically independent of the
//! reference it is judged against, and instrumented for a speed-against-error front.
//!
//! One run traces K paths per point and returns, for every point, the running mean after the first
//! c paths at each checkpoint c (say 1, 2, 4, …, K): the prefix means of one sample sequence, so a
//! run with K = c would give the identical value at c, and one run gives the whole front. Beside
//! them, per checkpoint and summed over the points: the rays cast (continuation and shadow rays
//! apart, exact counts) and the seconds spent.
//!
//! # Streams
//! Point i of replica r draws from `[PATH_TRACE, seed, r, i]`, one path after another: a point's
//! values depend on neither the thread count nor the other points, and the domain differs from the
//! reference's `[REFERENCE, …]`, so competitor and truth share no random number.
//!
//! # Timing
//! Reading the clock at every path would perturb short paths (≈ 25 ns against ≈ 1–3 µs a path);
//! reading it only at the checkpoints costs log₂K + 1 reads per point (≈ 0.3 µs against K paths).
//! So each point's thread time to each checkpoint is measured, and the sums over points
//! (`thread_s`, CPU-seconds of the workers) are rescaled so that the last equals the wall-clock time
//! of the whole parallel run: `seconds[c] = thread_s[c] · wall / thread_s[last]`. This splits the
//! measured wall time in proportion to measured work, so it compares with DETP's wall-clock
//! tracing and engine seconds on the same threads. (The alternative, rays × a per-ray cost
//! measured once, was rejected: a shadow ray, a continuation ray and the shading between them cost
//! differently per scene.) Values are deterministic; `thread_s`, `seconds` and `wall_s` are timings.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::reference::{self, Lights, RayTally};
use super::Scene;
use crate::sample::rng::{domain, stream};

/// Checkpoints 1, 2, 4, … up to `max` (`max` itself last, even when it is not a power of two).
///
/// # Panics
/// If `max` is 0.
pub fn powers_of_two(max: u64) -> Vec<u64> {
    assert!(max >= 1, "at least one path per point");
    let mut c: Vec<u64> = (0..64)
        .map(|k| 1u64 << k)
        .take_while(|&p| p <= max)
        .collect();
    if c.last() != Some(&max) {
        c.push(max);
    }
    c
}

/// What one run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct PathTraceRun {
    /// Paths per point at each checkpoint, strictly increasing; the last is K.
    pub checkpoints: Vec<u64>,
    /// Running mean of point i after `checkpoints[c]` paths at `[i · checkpoints.len() + c]`
    /// (irradiance, the scene's units).
    pub means: Vec<f64>,
    /// Per point: the sample variance of its K paths (NaN with K = 1), the per-path spread that sets
    /// how the error falls with more paths.
    pub variance: Vec<f64>,
    /// Per checkpoint: rays cast by the first `checkpoints[c]` paths of every point.
    pub rays: Vec<RayTally>,
    /// Per checkpoint: the workers' seconds for the first `checkpoints[c]` paths of every point,
    /// summed over points (CPU-seconds; a timing).
    pub thread_s: Vec<f64>,
    /// Per checkpoint: `thread_s` rescaled to the run's wall-clock time (see the module doc; a
    /// timing).
    pub seconds: Vec<f64>,
    /// Wall-clock seconds of the whole run (a timing).
    pub wall_s: f64,
}

impl PathTraceRun {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.variance.len()
    }

    /// Are there no points?
    pub fn is_empty(&self) -> bool {
        self.variance.is_empty()
    }

    /// Point i's running mean at checkpoint index `c`.
    pub fn mean(&self, i: usize, c: usize) -> f64 {
        self.means[i * self.checkpoints.len() + c]
    }

    /// Every point's running mean at checkpoint index `c`.
    pub fn means_at(&self, c: usize) -> Vec<f64> {
        (0..self.len()).map(|i| self.mean(i, c)).collect()
    }

    /// Wall-clock seconds per path (all points, all K paths).
    pub fn seconds_per_path(&self) -> f64 {
        let paths = self.len() as f64 * *self.checkpoints.last().unwrap_or(&0) as f64;
        self.wall_s / paths
    }
}

/// What one point's K paths gave: running means, ray counts and thread seconds per checkpoint.
struct PointTrace {
    means: Vec<f64>,
    variance: f64,
    rays: Vec<RayTally>,
    secs: Vec<f64>,
}

/// Traces `checkpoints.last()` paths at every (point, normal) of replica `replica` (normals need not
/// be unit length) and reports the running means, rays and seconds at each checkpoint.
///
/// # Panics
/// If the points and normals differ in number, or the checkpoints are empty, start at 0 or do not
/// increase strictly.
pub fn path_trace(
    scene: &Scene,
    points: &[DVec3],
    normals: &[DVec3],
    checkpoints: &[u64],
    seed: u64,
    replica: u64,
) -> PathTraceRun {
    assert_eq!(points.len(), normals.len(), "one normal per point");
    assert!(
        !checkpoints.is_empty()
            && checkpoints[0] >= 1
            && checkpoints.windows(2).all(|w| w[0] < w[1]),
        "checkpoints must be positive and strictly increasing: {checkpoints:?}"
    );
    let lights = Lights::new(scene);
    let start = Instant::now();
    let traces: Vec<PointTrace> = points
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (&p, &n))| {
            let key = [domain::PATH_TRACE, seed, replica, i as u64];
            trace_point(scene, &lights, p, n.normalize(), &key, checkpoints)
        })
        .collect();
    let wall_s = start.elapsed().as_secs_f64();
    let nc = checkpoints.len();
    let mut rays = vec![RayTally::default(); nc];
    let mut thread_s = vec![0.0; nc];
    let mut means = Vec::with_capacity(traces.len() * nc);
    let mut variance = Vec::with_capacity(traces.len());
    // Reduced in point order: the sums are the same whatever the thread count.
    for t in &traces {
        means.extend_from_slice(&t.means);
        variance.push(t.variance);
        for c in 0..nc {
            rays[c].path += t.rays[c].path;
            rays[c].shadow += t.rays[c].shadow;
            thread_s[c] += t.secs[c];
        }
    }
    let total = thread_s.last().copied().unwrap_or(0.0);
    let seconds = thread_s
        .iter()
        .map(|&s| if total > 0.0 { s * wall_s / total } else { 0.0 })
        .collect();
    PathTraceRun {
        checkpoints: checkpoints.to_vec(),
        means,
        variance,
        rays,
        thread_s,
        seconds,
        wall_s,
    }
}

/// One point's paths from the stream `key`, with a snapshot at each checkpoint.
fn trace_point(
    scene: &Scene,
    lights: &Lights,
    p: DVec3,
    n: DVec3,
    key: &[u64],
    checkpoints: &[u64],
) -> PointTrace {
    let mut rng = stream(key);
    let nc = checkpoints.len();
    let mut out = PointTrace {
        means: Vec::with_capacity(nc),
        variance: f64::NAN,
        rays: Vec::with_capacity(nc),
        secs: Vec::with_capacity(nc),
    };
    let mut tally = RayTally::default();
    // Welford, as the reference: stable for the long tails of rare bright paths.
    let (mut mean, mut m2) = (0.0, 0.0);
    let start = Instant::now();
    let mut next = 0;
    let k_max = checkpoints[nc - 1];
    for k in 1..=k_max {
        let x = reference::sample(scene, scene, lights, &mut rng, p, n, &mut tally);
        let delta = x - mean;
        mean += delta / k as f64;
        m2 += delta * (x - mean);
        if k == checkpoints[next] {
            out.secs.push(start.elapsed().as_secs_f64());
            out.means.push(mean);
            out.rays.push(tally);
            next += 1;
        }
    }
    if k_max >= 2 {
        out.variance = m2 / (k_max - 1) as f64;
    }
    out
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::lt::direct::tests::FURNACE;
    use crate::lt::reference::tests::{point_light_over_plane, scene};

    /// Points on the furnace sphere, facing in.
    fn furnace_points(n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
        let p: Vec<DVec3> = (0..n)
            .map(|i| {
                // A Fibonacci lattice: distinct points spread over the sphere.
                let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                let phi = i as f64 * PI * (3.0 - 5f64.sqrt());
                let s = (1.0 - z * z).sqrt();
                DVec3::new(s * phi.cos(), s * phi.sin(), z)
            })
            .collect();
        let n = p.iter().map(|x| -*x).collect();
        (p, n)
    }

    #[test]
    fn checkpoints_are_powers_of_two_up_to_the_maximum() {
        assert_eq!(powers_of_two(1), vec![1]);
        assert_eq!(powers_of_two(8), vec![1, 2, 4, 8]);
        assert_eq!(powers_of_two(12), vec![1, 2, 4, 8, 12]);
        assert_eq!(powers_of_two(1024).len(), 11);
    }

    /// A prefix mean is the very mean a shorter run computes, bit for bit, and the rays of the
    /// prefix are the shorter run's rays.
    #[test]
    fn prefix_means_equal_shorter_runs() {
        let s = scene(FURNACE);
        let (p, n) = furnace_points(7);
        let long = path_trace(&s, &p, &n, &[1, 2, 4, 8, 16], 5, 2);
        for (c, &k) in long.checkpoints.iter().enumerate() {
            let short = path_trace(&s, &p, &n, &[k], 5, 2);
            assert_eq!(short.means_at(0), long.means_at(c), "checkpoint {k}");
            assert_eq!(short.rays[0], long.rays[c], "checkpoint {k}");
        }
        // Cumulative: rays and seconds never fall from one checkpoint to the next.
        assert!(long.rays.windows(2).all(|w| w[0].total() < w[1].total()));
        assert!(long.seconds.windows(2).all(|w| w[0] <= w[1]));
        assert!((long.seconds[4] - long.wall_s).abs() <= 1e-12 * long.wall_s);
    }

    #[test]
    fn values_and_rays_do_not_depend_on_the_thread_count() {
        let s = scene(FURNACE);
        let (p, n) = furnace_points(40);
        let pool = |k| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(k)
                .build()
                .expect("pool")
        };
        let one = pool(1).install(|| path_trace(&s, &p, &n, &[1, 4, 32], 9, 0));
        let two = pool(2).install(|| path_trace(&s, &p, &n, &[1, 4, 32], 9, 0));
        assert_eq!(one.means, two.means);
        assert_eq!(one.variance, two.variance);
        assert_eq!(one.rays, two.rays);
        // Another replica is another sample.
        let other = path_trace(&s, &p, &n, &[1, 4, 32], 9, 1);
        assert_ne!(one.means, other.means);
    }

    /// In the closed furnace every path reaches a surface: each vertex casts one shadow ray and
    /// one continuation ray, and a path has 1/(1 − α) vertices on average. The mean of each point
    /// is π·L_e/(1 − α) within its SE.
    #[test]
    fn the_furnace_is_pi_le_over_one_minus_albedo_with_two_vertices_per_path() {
        let s = scene(FURNACE);
        let (p, n) = furnace_points(16);
        let k = 4096;
        let run = path_trace(&s, &p, &n, &powers_of_two(k), 3, 0);
        let want = PI / (1.0 - 0.5);
        let last = run.checkpoints.len() - 1;
        let mut z2 = 0.0;
        for i in 0..run.len() {
            let se = (run.variance[i] / k as f64).sqrt();
            let z = (run.mean(i, last) - want) / se;
            assert!(z.abs() < 4.5, "point {i}: z = {z}");
            z2 += z * z;
        }
        let chi = z2 / run.len() as f64;
        assert!((0.3..2.5).contains(&chi), "mean z² {chi}");
        let rays = run.rays[last];
        assert_eq!(rays.path, rays.shadow, "one of each per vertex");
        // Vertices per path: geometric with mean 2, SD √2 per path.
        let paths = (run.len() as u64 * k) as f64;
        let per_path = rays.path as f64 / paths;
        let se = 2f64.sqrt() / paths.sqrt();
        assert!((per_path - 2.0).abs() < 4.0 * se, "{per_path} ± {se}");
    }

    /// A point light over a black plane: each path is one shadow ray and one continuation ray that
    /// escapes, and every sample is Φ·cos θ/(4π r²) exactly.
    #[test]
    fn a_point_light_over_a_black_plane_costs_two_rays_a_path() {
        let s = point_light_over_plane(0.0);
        let p = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.5)];
        let run = path_trace(&s, &p, &[DVec3::Y; 2], &[1, 2, 8], 1, 0);
        for (i, x) in p.iter().enumerate() {
            let r = (DVec3::Y - *x).length();
            let want = 100.0 / (4.0 * PI) / (r * r * r);
            for c in 0..3 {
                assert!((run.mean(i, c) - want).abs() < 1e-12 * want);
            }
        }
        assert_eq!(
            run.rays[2],
            RayTally {
                path: 16,
                shadow: 16
            }
        );
        assert_eq!(run.rays[0], RayTally { path: 2, shadow: 2 });
    }

    /// Competitor and reference share no random number: over many furnace points their errors are
    /// uncorrelated (shared streams would give correlation 1), though both are unbiased.
    #[test]
    fn the_competitor_is_independent_of_the_reference() {
        let s = scene(FURNACE);
        let (p, n) = furnace_points(400);
        let run = path_trace(&s, &p, &n, &[16], 1, 0);
        let refr = reference::irradiance(&s, &p, &n, 16, 1);
        let want = PI / (1.0 - 0.5);
        let a: Vec<f64> = run.means_at(0).iter().map(|m| m - want).collect();
        let b: Vec<f64> = refr.iter().map(|r| r.mean - want).collect();
        let (ma, mb) = (
            a.iter().sum::<f64>() / a.len() as f64,
            b.iter().sum::<f64>() / b.len() as f64,
        );
        let cov: f64 = a.iter().zip(&b).map(|(x, y)| (x - ma) * (y - mb)).sum();
        let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
        let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
        let rho = cov / (va * vb).sqrt();
        // |ρ| of independent samples: SD 1/√n = 0.05.
        assert!(rho.abs() < 0.2, "correlation {rho}");
    }
}
