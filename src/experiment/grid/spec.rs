//! The spec file of the grid kinds (`grid`, `grid-scaling`, `grid-cost-model`): `[scene]` (the
//! Poisson sphere scene), `[grid]`, `[histogram]` and `[scaling]`. Every table denies unknown keys,
//! and every number is range-checked as it is read, so a bad value is reported at its own line and
//! column.

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use crate::spec::RawExperiment;
use crate::toml_text::de::{
    check_positive, count, fraction, opt_count, opt_finite3, opt_positive, positive,
};
use crate::toml_text::keys::{key, IfAbsent::*, KeyDoc};

/// The keys of the grid kinds' tables (`raycost doc spec`; a test checks them against the structs).
pub const KEYS: &[KeyDoc] = &[
    key("scene.intensity", "number", "1/length³", Required, "> 0",
        "ρ: sphere centres per unit volume of the Poisson scene."),
    key("scene.radius", "number", "length", Absent("give `[[scene.class]]` instead"), "> 0",
        "One radius for every sphere (exactly one of `radius` and `[[scene.class]]`)."),
    key("scene.class[].fraction", "number", "", Required, "(0, 1]; the fractions sum to 1",
        "α_i: the share of the spheres in this radius class (Result 3.2)."),
    key("scene.class[].radius", "number or table", "length", Required,
        "> 0, or `{ dist = \"uniform\", lo, hi }` (0 < lo ≤ hi), or `{ dist = \"lognormal\", median, sigma, max }` (all > 0)",
        "The class's radius: a constant or a distribution drawn per sphere (or per scene, see `radius_draw`)."),
    key("scene.extent", "number or string", "length", Absent("infinite unless `spheres` is given"),
        "`\"infinite\"` or a cube side > 0",
        "The lazily generated infinite scene, or a finite cube of this side around `center`."),
    key("scene.spheres", "integer", "spheres", Absent("none"), "≥ 1; not with a numeric `extent`",
        "Exact sphere count of a finite scene (its side is (n/ρ)^⅓)."),
    key("scene.replicas", "integer", "", Absent("1"), "≥ 1",
        "Independent realisations of a finite scene per point, sharing the rays; with two or more the standard errors include the scene-to-scene spread."),
    key("scene.center", "[x, y, z]", "length", Absent("the origin"), "finite",
        "Centre of a finite scene (the eye sits in its cell)."),
    key("scene.radius_draw", "string", "", Absent("`\"per-sphere\"`"), "`\"per-sphere\"`, `\"per-scene\"`",
        "Each sphere draws its radius, or one radius per class per scene (the paper's literal Result 3.2)."),
    key("grid.cell_width", "number", "length", Required, "> 0",
        "a: the grid's cell width."),
    key("grid.mailbox", "bool", "", Value("true"), "`true`, `false`",
        "Skip repeated tests of a sphere within one ray (changes time, not the reported counts: `n_i` and `n_i_mb` are both counted)."),
    key("grid.eye", "string", "", Value("\"uniform\""), "`\"corner\"`, `\"uniform\"`",
        "The eye on a cell corner, or uniform inside its cell (changes E[N_S])."),
    key("grid.memory_budget_gib", "number", "GiB", Value("4.0"), "> 0",
        "Memory the cell lists of a finite grid may take; a point needing more is refused before it allocates."),
    key("grid.rays_per_scene", "integer", "rays", Value("1"), "1 … 256",
        "Rays sharing one realisation of an infinite scene: 1 gives independent samples (exact SE and p-values) and the fastest engine."),
    key("grid.max_steps", "integer", "cells", Value("10000000"), "≥ 1",
        "Most cells one ray may visit in an infinite scene before it is cut off (counted)."),
    key("histogram.bins", "integer", "", Value("40"), "≥ 1",
        "Bins of the t* histogram (`NAME.hist.csv`)."),
    key("histogram.t_max_mfp", "number", "mean free paths", Value("6.0"), "> 0",
        "Right edge of the t* histogram."),
    key("scaling.brute_force_max_n", "integer", "spheres", Value("20000"), "≥ 1",
        "Kind `grid-scaling`: brute force runs only where n ≤ this."),
    key("scaling.brute_force_rays", "integer", "rays", Value("2000"), "≥ 1",
        "Kind `grid-scaling`: rays traced by brute force (the point's first ones)."),
    key("scaling.c", "number", "", Value("1.0"), "> 0",
        "Kind `grid-scaling`: c of Proposition 4.1 (columns P(N_I ≥ c·ln n) and P(N_I ≥ c·√n))."),
];

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
