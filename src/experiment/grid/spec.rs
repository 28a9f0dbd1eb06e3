//! The spec file of the grid kinds (`grid`, `grid-scaling`, `grid-cost-model`): `[scene]` (the
//! Poisson sphere scene), `[grid]`, `[histogram]` and `[scaling]`. Every table denies unknown keys,
//! and every number is range-checked as it is read, so a bad value is reported at its own line and
//! column.

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use crate::toml_text::de::{
    check_positive, count, fraction, opt_count, opt_finite3, opt_positive, positive,
};

crate::spec_file! {
    /// A spec file of a grid kind. The three kinds share it, `[scaling]` included (refused for
    /// the kinds other than `grid-scaling` where the point is configured): every row carries every
    /// key its kind accepts as a parameter column, and a struct per kind would drop the
    /// `scaling.*` columns from the `grid` and `grid-cost-model` tables, whose CSV is a contract.
    pub struct GridSpec {
        /// `[scene]`: the Poisson sphere scene.
        scene: RawScene = {table};
        /// `[grid]`: the acceleration structure.
        grid: RawGrid = {table};
        /// `[histogram]`: binning of the t* and N_I distributions.
        histogram: Option<RawHistogram> = {optional_table};
        /// `[scaling]`: brute-force comparison and concentration thresholds (kind
        /// `grid-scaling`).
        scaling: Option<RawScaling> = {optional_table};
    }
}

crate::spec_table! {
    /// `[scene]`.
    pub struct RawScene {
        /// ρ: sphere centres per unit volume of the Poisson scene.
        intensity: f64 = {required} read positive, "number", "1/length³", "> 0";
        /// One radius for every sphere (exactly one of `radius` and `[[scene.class]]`).
        radius: Option<f64> = {absent "give `[[scene.class]]` instead"} read opt_positive,
            "number", "length", "> 0";
        /// Radius classes of Result 3.2.
        class: Vec<RawClass> = {tables};
        /// The lazily generated infinite scene, or a finite cube of this side around `center`.
        extent: Option<Extent> = {absent "infinite unless `spheres` is given"},
            "number or string", "length", "`\"infinite\"` or a cube side > 0";
        /// Exact sphere count of a finite scene (its side is (n/ρ)^⅓).
        spheres: Option<u64> = {absent "none"} read opt_count,
            "integer", "spheres", "≥ 1; not with a numeric `extent`";
        /// Independent realisations of a finite scene per point, sharing the rays; with two or
        /// more the standard errors include the scene-to-scene spread.
        replicas: Option<u64> = {absent "1"} read opt_count, "integer", "", "≥ 1";
        /// Centre of a finite scene (the eye sits in its cell).
        center: Option<[f64; 3]> = {absent "the origin"} read opt_finite3,
            "[x, y, z]", "length", "finite";
        /// Each sphere draws its radius, or one radius per class per scene (the paper's literal
        /// Result 3.2).
        radius_draw: Option<RawDraw> = {absent "`\"per-sphere\"`"},
            "string", "", "`\"per-sphere\"`, `\"per-scene\"`";
    }
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

crate::spec_table! {
    /// `[[scene.class]]`.
    pub struct RawClass {
        /// α_i: the share of the spheres in this radius class (Result 3.2).
        fraction: f64 = {required} read fraction, "number", "", "(0, 1]; the fractions sum to 1";
        /// The class's radius: a constant or a distribution drawn per sphere (or per scene, see
        /// `radius_draw`).
        radius: RawRadius = {required}, "number or table", "length",
            "> 0, or `{ dist = \"uniform\", lo, hi }` (0 < lo ≤ hi), or `{ dist = \"lognormal\", median, sigma, max }` (all > 0)";
    }
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

crate::spec_table! {
    /// `[grid]`.
    pub struct RawGrid {
        /// a: the grid's cell width.
        cell_width: f64 = {required} read positive, "number", "length", "> 0";
        /// Skip repeated tests of a sphere within one ray (changes time, not the reported counts:
        /// `n_i` and `n_i_mb` are both counted).
        mailbox: bool = {default true}, "bool", "", "`true`, `false`";
        /// The eye on a cell corner, or uniform inside its cell (changes E[N_S]).
        eye: Eye = {default Eye::Uniform}, "string", "", "`\"corner\"`, `\"uniform\"`";
        /// Memory the cell lists of a finite grid may take; a point needing more is refused
        /// before it allocates.
        memory_budget_gib: f64 = {default 4.0} read positive, "number", "GiB", "> 0";
        /// Rays sharing one realisation of an infinite scene: 1 gives independent samples (exact
        /// SE and p-values) and the fastest engine.
        rays_per_scene: u64 = {default DEFAULT_RAYS_PER_SCENE} read count,
            "integer", "rays", "1 … 256";
        /// Most cells one ray may visit in an infinite scene before it is cut off (counted).
        max_steps: u64 = {default 10_000_000} read count, "integer", "cells", "≥ 1";
    }
}

pub use crate::theory::grid::Eye;

impl crate::toml_text::keys::Omit for Eye {}
impl crate::toml_text::keys::Omit for Extent {}
impl crate::toml_text::keys::Omit for RawDraw {}
impl crate::toml_text::keys::Omit for RawRadius {}

crate::spec_table! {
    /// `[histogram]`.
    pub struct RawHistogram with Default {
        /// Bins of the t* histogram (`NAME.hist.csv`).
        bins: u64 = {default 40} read count, "integer", "", "≥ 1";
        /// Right edge of the t* histogram.
        t_max_mfp: f64 = {default 6.0} read positive, "number", "mean free paths", "> 0";
    }
}

crate::spec_table! {
    /// `[scaling]`: brute-force comparison and concentration thresholds (kind `grid-scaling`).
    pub struct RawScaling with Default {
        /// Kind `grid-scaling`: brute force runs only where n ≤ this.
        brute_force_max_n: u64 = {default 20_000} read count, "integer", "spheres", "≥ 1";
        /// Kind `grid-scaling`: rays traced by brute force (the point's first ones).
        brute_force_rays: u64 = {default 2_000} read count, "integer", "rays", "≥ 1";
        /// Kind `grid-scaling`: c of Proposition 4.1 (columns P(N_I ≥ c·ln n) and
        /// P(N_I ≥ c·√n)).
        c: f64 = {default 1.0} read positive, "number", "", "> 0";
    }
}

/// `grid.rays_per_scene` when a spec leaves it out: independent rays.
pub const DEFAULT_RAYS_PER_SCENE: u64 = 1;
