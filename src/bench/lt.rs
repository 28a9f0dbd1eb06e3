//! Light transport: the photon tracer and the reference path tracer on the Cornell box, the BART
//! kitchen and the BART museum, with rays cast by raycost's exact core and (feature `embree`) by
//! Embree 3, one thread, in alternating rounds.
//!
//! Each round traces the same photons (stream key = round) and the same reference samples with
//! every engine in turn, through the same loops ([`trace_photons_with`], [`irradiance_with`]), so
//! the per-round ratio compares the engines' ray casting under the same machine conditions and
//! with the same random numbers, light sampling and bookkeeping around it. Rates:
//! - `lt-photons*`: photon segments per second (a segment is one ray, answered with its nearest
//!   hit and the next crossing: Embree finds the latter by a second ray from just past the first);
//! - `lt-paths*`: rays per second of the reference (every ray cast: path rays and shadow rays;
//!   Embree answers shadow rays with `rtcOccluded1`).
//!
//! Checks (`mismatches`, must be 0): the core's photon store and reference estimates are bit for
//! bit the same on the portable scalar path as on the detected SIMD path, and on all threads as on
//! one. `embree_disagree` counts rays (the core's round-0 photon segments, their origin and
//! f32 direction) whose first hit Embree places more than 10⁻⁴ (relative) away from the core's, or
//! not at all, out of `checked` (f32 geometry: grazing rays, rays through edges and rays leaving
//! a surface within Embree's self-intersection floor).

use std::path::PathBuf;

use glam::DVec3;
use rand::Rng;

use super::columns as bc;
use super::rounds::{alternate, median, paired_ratios, RoundTimes};
use crate::detp::photon::trace_photons_with;
use crate::lt::bvh::Path;
use crate::lt::cast::Caster;
use crate::lt::reference::irradiance_with;
use crate::lt::Scene;
use crate::output::row::Row;
use crate::sample::rng::stream;

/// The scenes: (name, path in the repository).
pub const SCENES: [(&str, &str); 3] = [
    ("cornell", "experiments/scenes/cornell.toml"),
    ("kitchen", super::quasi_static::KITCHEN),
    ("museum", "experiments/scenes/bart/museum/museum5.aff"),
];

/// Sizes of one run.
#[derive(Clone, Copy, Debug)]
struct Plan {
    rounds: usize,
    photons: u64,
    points: usize,
    samples: u64,
    /// Segments Embree's answers are compared on.
    checked: usize,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                rounds: 3,
                photons: 2_000,
                points: 16,
                samples: 8,
                checked: 2_000,
            }
        } else {
            Self {
                rounds: 7,
                photons: 60_000,
                points: 64,
                samples: 64,
                checked: 50_000,
            }
        }
    }
}

/// One engine and workload on one scene.
#[derive(Clone, Debug)]
pub struct LtRow {
    /// Scene name.
    pub scene: &'static str,
    /// `lt-photons`, `lt-photons-embree`, `lt-paths`, `lt-paths-embree`.
    pub engine: &'static str,
    /// Triangles in the scene.
    pub triangles: u64,
    /// Rays (segments) of each round.
    pub rays: Vec<u64>,
    /// Seconds of each round.
    pub secs: Vec<f64>,
    /// Median over rounds of (this engine's seconds per ray) / (Embree's), NaN for Embree rows.
    pub embree_ratio: f64,
    /// Segments compared with Embree.
    pub checked: u64,
    /// Differences between SIMD paths or thread counts (0 when correct).
    pub mismatches: u64,
    /// Segments whose first hit Embree places elsewhere.
    pub embree_disagree: u64,
    /// The core's instruction-set path.
    pub bvh_path: &'static str,
}

impl LtRow {
    /// Rays per second over all rounds (median round rate).
    pub fn rays_per_s(&self) -> f64 {
        let rates: Vec<f64> = self
            .rays
            .iter()
            .zip(&self.secs)
            .map(|(&n, &s)| n as f64 / s)
            .collect();
        median(&rates)
    }

    /// Its bench row.
    pub fn row(&self) -> Row {
        let mut row = Row::default();
        row.put(&bc::ENGINE, self.engine)
            .put(&bc::SCENE, self.scene)
            .put(&bc::N, self.triangles)
            .put(&bc::THREADS, 1u64)
            .put(&bc::RAYS, self.rays.iter().sum::<u64>())
            .put(&bc::ROUNDS, self.secs.len() as u64)
            .put(&bc::RAYS_PER_S, self.rays_per_s())
            .put(&bc::ROUND_MEDIAN_S, median(&self.secs))
            .put(&bc::EMBREE_RATIO, self.embree_ratio)
            .put(&bc::CHECKED, self.checked)
            .put(&bc::MISMATCHES, self.mismatches)
            .put(&bc::EMBREE_DISAGREE, self.embree_disagree)
            .put(&bc::BVH_PATH, self.bvh_path);
        row
    }
}

/// A repository file: in the working directory's repository, beside the binary, or where this
/// binary was built.
pub fn find(rel: &str) -> Option<PathBuf> {
    let mut roots = vec![PathBuf::from(".")];
    if let Ok(exe) = std::env::current_exe() {
        roots.extend(
            exe.ancestors()
                .skip(1)
                .take(4)
                .map(std::path::Path::to_path_buf),
        );
    }
    roots.push(env!("CARGO_MANIFEST_DIR").into());
    roots.into_iter().map(|r| r.join(rel)).find(|p| p.is_file())
}

/// Runs every scene found; warnings name the scenes that were not.
pub fn run(quick: bool) -> anyhow::Result<(Vec<LtRow>, Vec<String>)> {
    let plan = Plan::new(quick);
    let mut rows = Vec::new();
    let mut warnings = Vec::new();
    for (name, rel) in SCENES {
        let Some(path) = find(rel) else {
            warnings.push(format!(
                "{rel} was not found: the lt-* rows of {name} are missing"
            ));
            continue;
        };
        let mut scene = Scene::load(&path).map_err(|e| anyhow::anyhow!("{e}"))?;
        scene.set_tau(0.0);
        rows.extend(bench_scene(name, &scene, plan)?);
    }
    Ok((rows, warnings))
}

/// Points on the scene's triangles, uniform by area, each with its triangle's normal.
fn points(scene: &Scene, n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut rng = stream(&[0x6c74, n as u64]);
    let mut cum = Vec::with_capacity(scene.triangles.len());
    let mut acc = 0.0;
    for t in &scene.triangles {
        acc += t.area();
        cum.push(acc);
    }
    (0..n)
        .map(|_| {
            let k = cum.partition_point(|&c| c <= rng.gen::<f64>() * acc);
            let t = scene.triangles[k.min(cum.len() - 1)];
            let (mut a, mut b): (f64, f64) = (rng.gen(), rng.gen());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let p = t.v[0] + (t.v[1] - t.v[0]) * a + (t.v[2] - t.v[0]) * b;
            // Just off the surface on its light-receiving side.
            (p + t.normal() * 1e-6 * scene.magnitude(), t.normal())
        })
        .unzip()
}

/// The engines' rows on one scene.
fn bench_scene(name: &'static str, scene: &Scene, plan: Plan) -> anyhow::Result<Vec<LtRow>> {
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    #[cfg(feature = "embree")]
    let embree = crate::embree::triangles::EmbreeTriangles::build(scene)?;
    // The core with the f32 triangle pre-test (same answers, checked below), where the CPU has it.
    let mut pretest = scene.clone();
    let mut casters: Vec<(&'static str, &dyn DynCaster)> = vec![("", scene)];
    if Path::Avx2Pretest.available() {
        pretest.set_bvh_path(Path::Avx2Pretest);
        casters.push(("-f32-pretest", &pretest));
    }
    #[cfg(feature = "embree")]
    casters.push(("-embree", &embree));
    let embree_at = casters.iter().position(|c| c.0 == "-embree");
    let (pts, nrm) = points(scene, plan.points);
    let engines = casters.len();
    // Contestant c: engine c % engines; photons if c < engines, else paths.
    let mut rays = vec![Vec::new(); 2 * engines];
    let times: RoundTimes = one.install(|| {
        alternate(2 * engines, plan.rounds, |c, r| {
            let caster = casters[c % engines].1;
            let n = if c < engines {
                caster.photons(scene, plan.photons, r as u64)
            } else {
                caster.paths(scene, &pts, &nrm, plan.samples, r as u64)
            };
            rays[c].push(n);
        })
    });
    let (mismatches_photons, mismatches_paths) = self_checks(scene, &pts, &nrm, plan, None)?;
    let (pretest_photons, pretest_paths) = if Path::Avx2Pretest.available() {
        self_checks(scene, &pts, &nrm, plan, Some(&pretest))?
    } else {
        (0, 0)
    };
    let store = one.install(|| trace_photons_with(scene, scene, plan.photons, 0));
    let mut out = Vec::new();
    for c in 0..2 * engines {
        let (suffix, caster) = casters[c % engines];
        let photons = c < engines;
        let embree = embree_at.filter(|&e| e != c % engines);
        let embree_ratio = if let Some(e) = embree {
            // Seconds per ray of the core over Embree's, round by round.
            let per_ray = |k: usize| -> Vec<f64> {
                times.secs[k]
                    .iter()
                    .zip(&rays[k])
                    .map(|(s, &n)| s / n as f64)
                    .collect()
            };
            let ratios = paired_ratios(
                &RoundTimes {
                    secs: vec![per_ray(e + c - c % engines), per_ray(c)],
                },
                0,
                1,
            );
            median(&ratios)
        } else {
            f64::NAN
        };
        let is_embree = suffix == "-embree";
        let (checked, disagree) = if is_embree {
            caster.disagreements(scene, &store, plan.checked)
        } else {
            (0, 0)
        };
        out.push(LtRow {
            scene: name,
            engine: match (photons, suffix) {
                (true, "") => "lt-photons",
                (false, "") => "lt-paths",
                (true, "-f32-pretest") => "lt-photons-f32-pretest",
                (false, "-f32-pretest") => "lt-paths-f32-pretest",
                (true, _) => "lt-photons-embree",
                (false, _) => "lt-paths-embree",
            },
            triangles: scene.triangles.len() as u64,
            rays: rays[c].clone(),
            secs: times.secs[c].clone(),
            embree_ratio,
            checked,
            mismatches: match (suffix, photons) {
                ("", true) => mismatches_photons,
                ("", false) => mismatches_paths,
                ("-f32-pretest", true) => pretest_photons,
                ("-f32-pretest", false) => pretest_paths,
                _ => 0,
            },
            embree_disagree: disagree,
            bvh_path: if is_embree {
                "embree"
            } else {
                caster_path(suffix, scene)
            },
        });
    }
    Ok(out)
}

/// The core's path a row ran (the pre-test rows run [`Path::Avx2Pretest`]).
fn caster_path(suffix: &str, scene: &Scene) -> &'static str {
    if suffix == "-f32-pretest" {
        Path::Avx2Pretest.name()
    } else {
        scene.bvh_path().name()
    }
}

/// The core's answers on `other` (by default the scalar path) and on all threads against the
/// detected path on one thread: (differing photon segments, differing reference estimates).
fn self_checks(
    scene: &Scene,
    pts: &[DVec3],
    nrm: &[DVec3],
    plan: Plan,
    other: Option<&Scene>,
) -> anyhow::Result<(u64, u64)> {
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let scalar = other.cloned().unwrap_or_else(|| {
        let mut s = scene.clone();
        s.set_bvh_path(Path::Scalar);
        s
    });
    let base = one.install(|| trace_photons_with(scene, scene, plan.photons, 0));
    let mut photons = 0;
    for other in [
        one.install(|| trace_photons_with(&scalar, &scalar, plan.photons, 0)),
        trace_photons_with(scene, scene, plan.photons, 0),
    ] {
        photons += base
            .segments
            .iter()
            .zip(&other.segments)
            .filter(|(a, b)| a != b)
            .count() as u64
            + base.segments.len().abs_diff(other.segments.len()) as u64;
    }
    let est = |s: &Scene| irradiance_with(s, s, pts, nrm, plan.samples, 0);
    let (base, n) = one.install(|| est(scene));
    let mut paths = 0;
    for (other, m) in [one.install(|| est(&scalar)), est(scene)] {
        paths += base.iter().zip(&other).filter(|(a, b)| a != b).count() as u64 + u64::from(m != n);
    }
    Ok((photons, paths))
}

/// A [`Caster`] behind a reference, with the bench's workloads.
trait DynCaster: Sync {
    /// Traces photons (stream key `seed`) and returns the segments stored.
    fn photons(&self, scene: &Scene, photons: u64, seed: u64) -> u64;
    /// Reference samples at every point (stream key `key`); returns the rays cast.
    fn paths(&self, scene: &Scene, pts: &[DVec3], nrm: &[DVec3], samples: u64, key: u64) -> u64;
    /// (segments checked, segments whose first hit this caster places elsewhere).
    fn disagreements(
        &self,
        scene: &Scene,
        store: &crate::detp::store::SegmentStore,
        n: usize,
    ) -> (u64, u64);
}

impl<C: Caster> DynCaster for C {
    fn photons(&self, scene: &Scene, photons: u64, seed: u64) -> u64 {
        trace_photons_with(scene, self, photons, seed)
            .segments
            .len() as u64
    }
    fn paths(&self, scene: &Scene, pts: &[DVec3], nrm: &[DVec3], samples: u64, key: u64) -> u64 {
        irradiance_with(scene, self, pts, nrm, samples, key).1
    }
    fn disagreements(
        &self,
        scene: &Scene,
        store: &crate::detp::store::SegmentStore,
        n: usize,
    ) -> (u64, u64) {
        let eps = 1e-9 * scene.magnitude();
        let mut bad = 0;
        let segs = &store.segments[..n.min(store.segments.len())];
        for s in segs {
            let want = scene
                .first_hit(s.o(), s.d(), eps, None)
                .map_or(f64::INFINITY, |h| h.t);
            let got = self
                .first_hit(s.o(), s.d(), eps, None)
                .map_or(f64::INFINITY, |h| h.t);
            let agree = if want.is_finite() {
                (got - want).abs() <= 1e-4 * want
            } else {
                got.is_infinite()
            };
            bad += u64::from(!agree);
        }
        (segs.len() as u64, bad)
    }
}
