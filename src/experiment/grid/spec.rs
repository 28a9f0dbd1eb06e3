//! The spec file of the grid kinds (`grid`, `grid-scaling`, `grid-cost-model`): `[scene]` (the
//! Poisson sphere scene), `[grid]`, `[histogram]` and `[scaling]`. Every table denies unknown keys,
//! and every number is range-checked as it is read, so a bad value is reported at its own line and
//! column.

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use crate::spec::de::{
    check_positive, count, fraction, opt_count, opt_finite3, opt_positive, positive,
};
use crate::spec::RawExperiment;

/// A spec file of a grid kind.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// `[experiment]`.
    pub experiment: RawExperiment,
    /// `[scene]`: the Poisson sphere scene.
    pub scene: RawScene,
    /// `[grid]`: the acceleration structure.
    pub grid: RawGrid,
    /// `[histogram]`: binning of the t* and N_I distributions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub histogram: Option<RawHistogram>,
    /// `[scaling]`: brute-force comparison and concentration thresholds (kind `grid-scaling`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scaling: Option<RawScaling>,
    /// `[sweep]` (expanded by the spec layer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<toml::Table>,
}

/// `[scene]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    /// ρ: centres per unit volume.
    #[serde(deserialize_with = "positive")]
    pub intensity: f64,
    /// One radius for all spheres (or use `[[scene.class]]`).
    #[serde(
        default,
        deserialize_with = "opt_positive",
        skip_serializing_if = "Option::is_none"
    )]
    pub radius: Option<f64>,
    /// Radius classes of Result 3.2.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub class: Vec<RawClass>,
    /// `"infinite"` or a cube side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extent: Option<Extent>,
    /// Exact sphere count of a finite scene (side (n/ρ)^⅓); excludes a numeric `extent`.
    #[serde(
        default,
        deserialize_with = "opt_count",
        skip_serializing_if = "Option::is_none"
    )]
    pub spheres: Option<u64>,
    /// Independent realisations of a finite scene per point (the rays are shared among them); with
    /// two or more, standard errors include the scene-to-scene variation.
    #[serde(
        default,
        deserialize_with = "opt_count",
        skip_serializing_if = "Option::is_none"
    )]
    pub replicas: Option<u64>,
    /// Centre of a finite scene (where the eye is).
    #[serde(
        default,
        deserialize_with = "opt_finite3",
        skip_serializing_if = "Option::is_none"
    )]
    pub center: Option<[f64; 3]>,
    /// `"per-sphere"` (default) or `"per-scene"` (the paper's literal Result 3.2 setting).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_draw: Option<RawDraw>,
}

/// `extent = "infinite"` or a positive side length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Extent {
    /// The lazily generated infinite scene.
    Infinite,
    /// A cube of this side.
    Side(f64),
}

impl<'de> Deserialize<'de> for Extent {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match toml::Value::deserialize(d)? {
            toml::Value::String(s) if s == "infinite" => Ok(Extent::Infinite),
            toml::Value::Float(x) if x.is_finite() && x > 0.0 => Ok(Extent::Side(x)),
            toml::Value::Integer(i) if i > 0 => Ok(Extent::Side(i as f64)),
            other => Err(D::Error::custom(format!(
                "got {other}, expected \"infinite\" or a finite cube side > 0"
            ))),
        }
    }
}

impl Serialize for Extent {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Extent::Infinite => s.serialize_str("infinite"),
            Extent::Side(x) => s.serialize_f64(*x),
        }
    }
}

impl Serialize for RawDraw {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(match self {
            RawDraw::PerSphere => "per-sphere",
            RawDraw::PerScene => "per-scene",
        })
    }
}

/// Radius draw mode.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RawDraw {
    /// Each sphere draws its radius.
    PerSphere,
    /// One radius per class per scene.
    PerScene,
}

/// `[[scene.class]]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawClass {
    /// α_i ∈ (0, 1].
    #[serde(deserialize_with = "fraction")]
    pub fraction: f64,
    /// A number, or a distribution table.
    pub radius: RawRadius,
}

/// A class radius: a constant or a distribution.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum RawRadius {
    /// Constant radius.
    Constant(f64),
    /// `{ dist = "uniform", lo, hi }` or `{ dist = "lognormal", median, sigma, max }`.
    Dist(RawDist),
}

impl<'de> Deserialize<'de> for RawRadius {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = toml::Value::deserialize(d)?;
        match v {
            toml::Value::Float(x) => check_positive(x).map(RawRadius::Constant).map_err(D::Error::custom),
            toml::Value::Integer(i) => check_positive(i as f64).map(RawRadius::Constant).map_err(D::Error::custom),
            toml::Value::Table(t) => {
                let dist: RawDist = toml::Value::Table(t).try_into().map_err(|e: toml::de::Error| D::Error::custom(e.message()))?;
                dist.check().map_err(D::Error::custom)?;
                Ok(RawRadius::Dist(dist))
            }
            other => Err(D::Error::custom(format!(
                "got {other}, expected a radius > 0 or a table {{ dist = \"uniform\", lo, hi }} / {{ dist = \"lognormal\", median, sigma, max }}"
            ))),
        }
    }
}

/// A radius distribution table.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "dist", rename_all = "kebab-case", deny_unknown_fields)]
pub enum RawDist {
    /// Uniform on `[lo, hi]`.
    Uniform {
        /// Smallest radius.
        lo: f64,
        /// Largest radius.
        hi: f64,
    },
    /// Truncated lognormal.
    Lognormal {
        /// Median.
        median: f64,
        /// σ of ln R.
        sigma: f64,
        /// Truncation radius.
        max: f64,
    },
}

impl RawDist {
    fn check(&self) -> Result<(), crate::error::Invalid> {
        match *self {
            RawDist::Uniform { lo, hi } => {
                check_positive(lo)?;
                check_positive(hi)?;
                if hi < lo {
                    return Err(
                        format!("uniform radius needs lo ≤ hi, got lo = {lo}, hi = {hi}").into(),
                    );
                }
            }
            RawDist::Lognormal { median, sigma, max } => {
                check_positive(median)?;
                check_positive(sigma)?;
                check_positive(max)?;
                if max < median * (-6.0 * sigma).exp() {
                    return Err(format!("lognormal max = {max} cuts away almost all of the law (median {median}, sigma {sigma})").into());
                }
            }
        }
        Ok(())
    }
}

/// `[grid]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawGrid {
    /// a: cell width.
    #[serde(deserialize_with = "positive")]
    pub cell_width: f64,
    /// Skip repeated tests of a sphere within one ray (changes time, not the reported counts).
    #[serde(default = "yes")]
    pub mailbox: bool,
    /// `"corner"` or `"uniform"` (default): eye at a cell corner or uniform in its cell.
    #[serde(default)]
    pub eye: Eye,
    /// Memory the cell lists of a finite grid may take, GiB.
    #[serde(default = "default_budget", deserialize_with = "positive")]
    pub memory_budget_gib: f64,
    /// Rays that share one realisation of an infinite scene (1 ..= 256). The default, 1, gives
    /// independent samples (exact standard errors and goodness-of-fit p-values) and the fastest
    /// engine (each ray's realisation drawn only where its walk reads, `scene::tube`); more make
    /// rays of a group meet the same spheres (`scene::lazy`).
    #[serde(default = "default_rays_per_scene", deserialize_with = "count")]
    pub rays_per_scene: u64,
    /// Most cells one ray may visit in an infinite scene before it is cut off.
    #[serde(default = "default_max_steps", deserialize_with = "count")]
    pub max_steps: u64,
}

pub use crate::theory::grid::Eye;

/// `[histogram]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawHistogram {
    /// Number of bins of the t* histogram.
    #[serde(default = "default_bins", deserialize_with = "count")]
    pub bins: u64,
    /// Right edge of the t* histogram in mean free paths.
    #[serde(default = "default_t_max", deserialize_with = "positive")]
    pub t_max_mfp: f64,
}

impl Default for RawHistogram {
    fn default() -> Self {
        Self {
            bins: default_bins(),
            t_max_mfp: default_t_max(),
        }
    }
}

/// `[scaling]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawScaling {
    /// Brute force runs only where n ≤ this.
    #[serde(default = "default_bf_n", deserialize_with = "count")]
    pub brute_force_max_n: u64,
    /// Rays traced by brute force (the first ones of the point).
    #[serde(default = "default_bf_rays", deserialize_with = "count")]
    pub brute_force_rays: u64,
    /// c of Proposition 4.1: the columns report P(N_I ≥ c·ln n) and P(N_I ≥ c·√n).
    #[serde(default = "one", deserialize_with = "positive")]
    pub c: f64,
}

impl Default for RawScaling {
    fn default() -> Self {
        Self {
            brute_force_max_n: default_bf_n(),
            brute_force_rays: default_bf_rays(),
            c: 1.0,
        }
    }
}

fn yes() -> bool {
    true
}
fn one() -> f64 {
    1.0
}
fn default_budget() -> f64 {
    4.0
}
fn default_max_steps() -> u64 {
    10_000_000
}
fn default_rays_per_scene() -> u64 {
    DEFAULT_RAYS_PER_SCENE
}

/// `grid.rays_per_scene` when a spec leaves it out: independent rays.
pub const DEFAULT_RAYS_PER_SCENE: u64 = 1;
fn default_bins() -> u64 {
    40
}
fn default_t_max() -> f64 {
    6.0
}
fn default_bf_n() -> u64 {
    20_000
}
fn default_bf_rays() -> u64 {
    2_000
}
