//! The `[detp]` table of kinds `detp` and `quasi-static`: where the rays come from (μ-random lines
//! through the unit ball, or photons traced from a scene file), where the discs sit (uniform in the
//! ball, on the scene's surfaces, or read from a CSV), the disc radius d, the sphere cache's Q,
//! threshold, ordering and list mode, the disc index, the photon-map baseline, and which engines run.
//!
//! Every key is range-checked where it is read (so errors carry its line and column); checks that
//! span keys live in [`DetpConfig::from_raw`], which also translates the spec's choices into the
//! engines' own types once (point order, sphere-cache parameters, index kind) and loads the scene
//! and points files once through [`Inputs`].

use std::sync::Arc;

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use glam::DVec3;

use crate::detp::edge::EdgeMode;
use crate::detp::order::Order;
use crate::detp::quasi_static::IndexKind;
use crate::detp::sphere_cache::{ListMode, PopRule, SphereCacheParams};
use crate::experiment::inputs::{Inputs, PointsFile, SceneFile};
use crate::experiment::kind::{refuse, ConfigError};
use crate::geom::Aabb;
use crate::spec::de::{count, open_unit, opt_count, opt_positive, positive};
use crate::spec::RawExperiment;

/// The keys of `[detp]` (kinds `detp` and `quasi-static`; `raycost doc spec`, checked against
/// [`RawDetp`] by a test).
pub const KEYS: &[KeyDoc] = &[
    key("detp.source", "string", "", Value("\"lines\""), "`\"lines\"`, `\"scene\"`",
        "Where the rays come from: μ-random lines through the unit ball, or photons traced from `detp.scene`."),
    key("detp.scene", "string (path)", "", Absent("none; required with `source = \"scene\"`"),
        "a `.toml` scene (`raycost doc scene`) or a BART `.aff`/`.nff` file",
        "The scene file, relative to the spec's folder."),
    key("detp.photons", "integer", "photons", Required, "≥ 1",
        "n_R: lines drawn, or photons emitted from the scene's lights (their paths' segments are the rays)."),
    key("detp.points", "integer", "points", Absent("required with `point_source = \"ball\"`"), "≥ 1",
        "n_P: sample points uniform in the unit ball (a file name here is refused with a hint to `points_file`)."),
    key("detp.point_source", "string", "", Absent("`\"ball\"` for lines, `\"surface\"` for a scene"),
        "`\"ball\"`, `\"surface\"`, `\"file\"`",
        "Where the sample points come from: uniform in the unit ball with uniform normals, on the scene's surfaces, or a CSV."),
    key("detp.points_file", "string (path)", "", Absent("none; required with `point_source = \"file\"`"),
        "a CSV with header `x,y,z,nx,ny,nz`",
        "The sample points, relative to the spec's folder (normals need not be unit length)."),
    key("detp.point_spacing", "number", "length", Absent("2·d (the paper's optimum)"), "> 0",
        "Spacing of surface points."),
    key("detp.disc_radius", "number or string", "length", Required, "> 0, or `\"spacing\"`",
        "d: the discs' radius, or the points' mean spacing ((4π/3/n_P)^⅓ in the ball, `point_spacing` on surfaces), the paper's d for Theorem 1."),
    key("detp.q", "number", "", Value("0.6666666666666666"), "(0, 1)",
        "Q: ratio of consecutive sphere radii of the sphere cache (Proposition 1: 2/3 is optimal)."),
    key("detp.threshold", "integer", "rays", Value("100"), "≥ 1",
        "A sphere holding fewer rays is not subdivided."),
    key("detp.order", "string", "", Value("\"hilbert\""), "`\"none\"`, `\"morton\"`, `\"hilbert\"`",
        "Order in which the sphere cache visits the points."),
    key("detp.order_bits", "integer", "bits", Value("10"), "1 … 21",
        "Bits per axis of the ordering keys."),
    key("detp.list_mode", "string", "", Value("\"inherited\""), "`\"inherited\"`, `\"exact\"`",
        "The paper's cache: a new sphere's list is the parent's rays meeting it (`inherited`); or raycost's variant, exactly the rays meeting it, from the deepest enclosing ancestor (`exact`)."),
    key("detp.pop_rule", "string", "", Value("\"chain\""), "`\"chain\"`, `\"paper\"`",
        "Which levels a new point keeps: the chain of levels that all contain its disc, or the paper's rule (pop the deepest while it does not; exact with exact lists, cut back to the chain with inherited lists, repairs counted)."),
    key("detp.chunk_points", "integer", "points", Value("16384"), "≥ 1",
        "Points per independent sphere-cache run (chunks run in parallel; a spec value, never the thread count, so counts do not depend on threads)."),
    key("detp.engines", "array of strings", "", Value("[\"sphere-cache\"]"),
        "`\"sphere-cache\"`, `\"disc-index\"`, `\"brute-force\"`, `\"photon-map\"`, `\"reference\"`",
        "Kind `detp`: the engines run on every point (columns per engine)."),
    key("detp.index", "string", "", Value("\"octree\""), "`\"octree\"`, `\"grid\"`",
        "The disc index's structure."),
    key("detp.index_cell_width", "number", "length", Absent("2·d"), "> 0",
        "Cell width of the grid disc index."),
    key("detp.octree_leaf", "integer", "discs", Value("8"), "≥ 1",
        "Most discs in an octree leaf before it splits (it also stops at side ≤ d)."),
    key("detp.brute_force_points", "integer", "points", Value("256"), "≥ 0",
        "Points whose sums are checked against brute force, bit for bit (0: none); failures fail the run (exit 1)."),
    key("detp.photon_map_k", "integer", "photons", Value("64"), "≥ 1",
        "k nearest photons of the photon map."),
    key("detp.photon_map_filter", "string", "", Value("\"cone\""), "`\"cone\"`, `\"disc\"`",
        "The photon map's density estimation filter."),
    key("detp.replicas", "integer", "", Value("1"), "≥ 1",
        "Independent realisations (new rays and points each): with one, standard errors are Poisson estimates; with several, the spread across replicas."),
    key("detp.reference_samples", "integer", "paths", Value("1024"), "≥ 2",
        "Paths per point of engine `reference` (path tracing with next-event estimation: the ground truth, with its SE)."),
    key("detp.edge", "string", "", Value("\"paper\""), "`\"paper\"`, `\"clamp-radius\"`, `\"first-hit\"`, `\"clamp-first-hit\"`",
        "Discs near edges: the paper's method, or a remedy (a disc shrunk to the nearest other surface; crossings cut just past the first impact; both). Scenes only; every engine stays exact."),
    key("detp.edge_min_radius", "number", "× d", Absent("0.25 with a clamping remedy"), "(0, 1]",
        "Smallest disc radius a clamping remedy allows, as a fraction of d."),
    key("detp.edge_gap", "number", "× d", Absent("0.05 with a cutting remedy"), "> 0",
        "How far past a segment's first impact a cutting remedy still counts crossings, as a fraction of d."),
    key("detp.write_points", "bool", "", Value("false"), "`true`, `false`",
        "Also write the per-sample-point irradiance table `NAME.points.csv`."),
    key("detp.engine", "string", "", Absent("`\"hybrid\"`"),
        "`\"hybrid\"`, `\"sphere-cache\"`, `\"disc-index\"`, `\"predicted\"`",
        "Kind `quasi-static`: how dynamic points are recomputed (hybrid: Theorem 2 picks per object; predicted: the §4.1 predictor picks)."),
    key("detp.memory_budget_gib", "number", "GiB", Value("8.0"), "> 0",
        "Memory the ray store and engines may take; a point needing more is refused before it allocates."),
];

/// A spec file of kind `detp`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DetpSpec {
    /// `[experiment]`.
    pub experiment: RawExperiment,
    /// `[detp]`.
    pub detp: RawDetp,
    /// `[sweep]` (expanded by the spec layer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<toml::Table>,
}

/// `[detp]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawDetp {
    /// `"lines"` (default) or `"scene"`.
    #[serde(default)]
    pub source: RaySource,
    /// Scene file (TOML), relative to the spec's folder; `source = "scene"` only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// n_R: lines, or photons emitted.
    #[serde(deserialize_with = "count")]
    pub photons: u64,
    /// n_P for points uniform in the unit ball.
    #[serde(
        default,
        deserialize_with = "point_count",
        skip_serializing_if = "Option::is_none"
    )]
    pub points: Option<u64>,
    /// `"ball"` (uniform in the unit ball, uniform normals), `"grid"` (eq. 4's layout: a cubic
    /// lattice of k = round(∛points) per side filling the cube inscribed in the unit ball, spacing
    /// 2/(√3·k), uniform normals), `"surface"` (on the scene's surfaces) or `"file"` (a CSV of x, y,
    /// z, nx, ny, nz). Default: ball for lines, surface for a scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_source: Option<PointSourceKind>,
    /// The CSV of `point_source = "file"`, relative to the spec's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points_file: Option<String>,
    /// Spacing of surface points (default 2·d, the paper's optimum: d ≈ half the spacing).
    #[serde(
        default,
        deserialize_with = "opt_positive",
        skip_serializing_if = "Option::is_none"
    )]
    pub point_spacing: Option<f64>,
    /// d: a disc radius, or `"spacing"`: the points' mean spacing (uniform in the ball:
    /// (4π/3 / n_P)^(1/3); on surfaces: `point_spacing`), the paper's d for Theorem 1.
    pub disc_radius: DiscRadius,
    /// Q ∈ (0, 1): ratio of consecutive sphere radii.
    #[serde(default = "two_thirds", deserialize_with = "open_unit")]
    pub q: f64,
    /// A sphere holding fewer rays is not subdivided.
    #[serde(default = "hundred", deserialize_with = "count")]
    pub threshold: u64,
    /// Point ordering: `"none"`, `"morton"` (Lebesgue) or `"hilbert"`.
    #[serde(default)]
    pub order: OrderChoice,
    /// Bits per axis of the ordering keys (1–21).
    #[serde(default = "ten", deserialize_with = "bits")]
    pub order_bits: u64,
    /// `"inherited"` (default): a new list is the parent's rays meeting the new sphere (the paper's
    /// rule, §3); `"exact"`: it comes from the deepest enclosing ancestor, so every list holds
    /// exactly the rays meeting its sphere (raycost's variant for the rays-per-level law).
    #[serde(default)]
    pub list_mode: ListModeChoice,
    /// `"chain"` (default): a point keeps the levels that all contain its disc; `"paper"`: the
    /// paper's rule, popping the deepest level while it does not contain the disc (with inherited
    /// lists cut back to the chain where that would lose rays; see `docs/detp-costs.md`).
    #[serde(default)]
    pub pop_rule: PopRuleChoice,
    /// Points per independent sphere-cache run (chunks run in parallel; a spec value, never the
    /// thread count, so counters do not depend on threads).
    #[serde(default = "default_chunk", deserialize_with = "count")]
    pub chunk_points: u64,
    /// Engines to run on every point: `sphere-cache`, `disc-index`, `brute-force`, `photon-map`,
    /// `reference`.
    #[serde(default = "default_engines")]
    pub engines: Vec<EngineChoice>,
    /// Disc index kind: `"octree"` (default) or `"grid"`.
    #[serde(default)]
    pub index: IndexChoice,
    /// Cell width of the grid disc index (default 2·d).
    #[serde(
        default,
        deserialize_with = "opt_positive",
        skip_serializing_if = "Option::is_none"
    )]
    pub index_cell_width: Option<f64>,
    /// Most discs in an octree leaf before it splits (it also stops at side ≤ d).
    #[serde(default = "eight", deserialize_with = "count")]
    pub octree_leaf: u64,
    /// Points whose sums are checked against brute force, bit for bit (0: none).
    #[serde(default = "default_bf_points")]
    pub brute_force_points: u64,
    /// k of the photon map.
    #[serde(default = "default_k", deserialize_with = "count")]
    pub photon_map_k: u64,
    /// Photon-map filter: `"disc"` or `"cone"`.
    #[serde(default)]
    pub photon_map_filter: FilterChoice,
    /// Paths per sample point of engine `reference` (the path-traced ground truth).
    #[serde(default = "default_reference_samples", deserialize_with = "count")]
    pub reference_samples: u64,
    /// Independent realisations (new rays and points each); standard errors are across them.
    #[serde(default = "one_u", deserialize_with = "count")]
    pub replicas: u64,
    /// Write the per-sample-point irradiance table `NAME.points.csv`.
    #[serde(default)]
    pub write_points: bool,
    /// Kind `quasi-static`: `"hybrid"` (Theorem 2 picks per object), `"sphere-cache"` or
    /// `"disc-index"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub engine: Option<DynamicEngine>,
    /// Memory the ray store and engines may take, GiB.
    #[serde(default = "default_budget", deserialize_with = "positive")]
    pub memory_budget_gib: f64,
    /// Where a disc reaches past an edge: `"paper"` (the paper's method, default),
    /// `"clamp-radius"` (per-disc radius limited by the nearest other surface) or `"first-hit"`
    /// (crossings counted up to `edge_gap`·d beyond the first impact) or `"clamp-first-hit"` (both).
    /// See docs/hard-cases.md.
    #[serde(default)]
    pub edge: EdgeChoice,
    /// `"clamp-radius"`, `"clamp-first-hit"`: the smallest disc radius, as a fraction of d (in
    /// (0, 1]; default 0.25).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge_min_radius: Option<f64>,
    /// `"first-hit"`, `"clamp-first-hit"`: how far beyond the first impact a crossing still counts,
    /// as a fraction of d (≥ 0; default 0.05).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge_gap: Option<f64>,
}

/// Default `detp.edge_min_radius`.
pub const EDGE_MIN_RADIUS: f64 = 0.25;
/// Default `detp.edge_gap`.
pub const EDGE_GAP: f64 = 0.05;

use crate::choice;
use crate::spec::keys::{key, IfAbsent::*, KeyDoc};

choice!(
    /// Where the rays come from.
    RaySource { Lines => "lines", Scene => "scene" } default Lines
);
choice!(
    /// Where the sample points come from.
    PointSourceKind { Ball => "ball", Grid => "grid", Surface => "surface", File => "file" } default Ball
);
choice!(
    /// Point ordering.
    OrderChoice { None => "none", Morton => "morton", Hilbert => "hilbert" } default Hilbert
);
choice!(
    /// Sphere-cache list mode.
    ListModeChoice { Exact => "exact", Inherited => "inherited" } default Inherited
);
choice!(
    /// Sphere-cache pop rule.
    PopRuleChoice { Chain => "chain", Paper => "paper" } default Chain
);
choice!(
    /// An irradiance engine.
    EngineChoice {
        SphereCache => "sphere-cache",
        DiscIndex => "disc-index",
        BruteForce => "brute-force",
        PhotonMap => "photon-map",
        Reference => "reference",
    } default SphereCache
);
choice!(
    /// Disc index kind.
    IndexChoice { Octree => "octree", Grid => "grid" } default Octree
);
choice!(
    /// Photon-map filter.
    FilterChoice { Cone => "cone", Disc => "disc" } default Cone
);

choice!(
    /// `detp.edge`: the paper's method or a remedy at edges.
    EdgeChoice {
        Paper => "paper",
        ClampRadius => "clamp-radius",
        FirstHit => "first-hit",
        ClampFirstHit => "clamp-first-hit",
    } default Paper
);

choice!(
    /// Kind `quasi-static`: how dynamic points are recomputed (and static points updated).
    DynamicEngine {
        Hybrid => "hybrid",
        SphereCache => "sphere-cache",
        DiscIndex => "disc-index",
        Predicted => "predicted",
    } default Hybrid
);

impl EngineChoice {
    /// Column stem: `sphere_cache`, `disc_index`, `brute_force`, `photon_map`, `reference`.
    pub fn column(self) -> &'static str {
        match self {
            EngineChoice::SphereCache => "sphere_cache",
            EngineChoice::DiscIndex => "disc_index",
            EngineChoice::BruteForce => "brute_force",
            EngineChoice::PhotonMap => "photon_map",
            EngineChoice::Reference => "reference",
        }
    }

    /// A baseline beside the DETP engines (its own estimates, not DETP's integer sums)?
    pub fn is_baseline(self) -> bool {
        matches!(self, EngineChoice::PhotonMap | EngineChoice::Reference)
    }
}

/// `detp.disc_radius`: a number > 0 or `"spacing"`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DiscRadius {
    /// This radius.
    Value(f64),
    /// The mean spacing of the points.
    Spacing,
}

impl<'de> Deserialize<'de> for DiscRadius {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match toml::Value::deserialize(d)? {
            toml::Value::String(s) if s == "spacing" => Ok(DiscRadius::Spacing),
            toml::Value::Float(x) => crate::spec::de::check_positive(x)
                .map(DiscRadius::Value)
                .map_err(D::Error::custom),
            toml::Value::Integer(i) => crate::spec::de::check_positive(i as f64)
                .map(DiscRadius::Value)
                .map_err(D::Error::custom),
            other => Err(D::Error::custom(format!(
                "got {other}, expected a radius > 0 or \"spacing\""
            ))),
        }
    }
}

impl Serialize for DiscRadius {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            DiscRadius::Value(x) => s.serialize_f64(*x),
            DiscRadius::Spacing => s.serialize_str("spacing"),
        }
    }
}

fn two_thirds() -> f64 {
    2.0 / 3.0
}
fn hundred() -> u64 {
    100
}
fn ten() -> u64 {
    10
}
fn eight() -> u64 {
    8
}
fn one_u() -> u64 {
    1
}
fn default_chunk() -> u64 {
    16_384
}
fn default_bf_points() -> u64 {
    256
}
fn default_k() -> u64 {
    64
}
fn default_reference_samples() -> u64 {
    1024
}
fn default_budget() -> f64 {
    8.0
}
fn default_engines() -> Vec<EngineChoice> {
    vec![EngineChoice::SphereCache]
}

/// `detp.points`: a count; a file name gets a hint to the keys that read one.
fn point_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    match toml::Value::deserialize(d)? {
        toml::Value::String(s) => Err(D::Error::custom(format!(
            "got \"{s}\", a count of points uniform in the ball; to read points from a CSV write point_source = \"file\" and points_file = \"{s}\""
        ))),
        v => opt_count(v).map_err(D::Error::custom),
    }
}

/// Points per side of eq. 4's lattice for a target count: round(∛n), at least 1.
pub fn lattice_side(n: u64) -> u64 {
    ((n as f64).cbrt().round() as u64).max(1)
}

/// Spacing of eq. 4's lattice with `k` points per side: its cube (side k·spacing) is inscribed in
/// the unit ball, r_0 = √3·d·k/2 = 1.
pub fn lattice_spacing(k: u64) -> f64 {
    2.0 / (3f64.sqrt() * k as f64)
}

fn bits<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    let b = count(d)?;
    if b <= 21 {
        Ok(b)
    } else {
        Err(D::Error::custom(format!(
            "got {b}, expected 1–21 bits per axis (3 × 21 = 63 bits fit a key)"
        )))
    }
}

/// `detp.edge` and its parameter, checked: a remedy needs a scene, and each parameter belongs to
/// its own mode.
fn edge_mode(d: &RawDetp, rays: &Rays) -> Result<EdgeMode, ConfigError> {
    if d.edge != EdgeChoice::Paper && matches!(rays, Rays::Lines) {
        return refuse(
            "detp.edge",
            format!(
                "\"{}\" needs surfaces: lines through the unit ball have no edges (use detp.source = \"scene\")",
                d.edge.as_str()
            ),
        );
    }
    let clamps = matches!(d.edge, EdgeChoice::ClampRadius | EdgeChoice::ClampFirstHit);
    let cuts = matches!(d.edge, EdgeChoice::FirstHit | EdgeChoice::ClampFirstHit);
    if d.edge_min_radius.is_some() && !clamps {
        return refuse(
            "detp.edge_min_radius",
            "belongs to detp.edge = \"clamp-radius\" or \"clamp-first-hit\"",
        );
    }
    if d.edge_gap.is_some() && !cuts {
        return refuse(
            "detp.edge_gap",
            "belongs to detp.edge = \"first-hit\" or \"clamp-first-hit\"",
        );
    }
    let min = d.edge_min_radius.unwrap_or(EDGE_MIN_RADIUS);
    if !(min > 0.0 && min <= 1.0) {
        return refuse(
            "detp.edge_min_radius",
            format!("got {min}, expected a fraction of d in (0, 1]"),
        );
    }
    let gap = d.edge_gap.unwrap_or(EDGE_GAP);
    if !(gap.is_finite() && gap >= 0.0) {
        return refuse(
            "detp.edge_gap",
            format!("got {gap}, expected a fraction of d ≥ 0"),
        );
    }
    Ok(match d.edge {
        EdgeChoice::Paper => EdgeMode::Paper,
        EdgeChoice::ClampRadius => EdgeMode::ClampRadius { min },
        EdgeChoice::FirstHit => EdgeMode::FirstHit { gap },
        EdgeChoice::ClampFirstHit => EdgeMode::ClampFirstHit { min, gap },
    })
}

/// The rays of a point.
#[derive(Clone, Debug)]
pub enum Rays {
    /// μ-random lines through the unit ball.
    Lines,
    /// Photons traced from this scene (loaded once per run).
    Scene(Arc<SceneFile>),
}

/// The sample points of a point.
#[derive(Clone, Debug)]
pub enum Points {
    /// n points uniform in the unit ball with uniform normals.
    Ball(u64),
    /// k³ points on eq. 4's lattice (k per side, spacing 2/(√3·k)) with uniform normals.
    Grid(u64),
    /// On the scene's surfaces at this spacing.
    Surface(f64),
    /// Read from a CSV (once per run).
    File(Arc<PointsFile>),
}

/// Everything a DETP point needs, validated, in the engines' own types.
#[derive(Clone, Debug)]
pub struct DetpConfig {
    /// Master seed.
    pub seed: u64,
    /// Ray source.
    pub rays: Rays,
    /// n_R.
    pub photons: u64,
    /// Point source.
    pub points: Points,
    /// d.
    pub disc_radius: f64,
    /// Point order of the sphere cache.
    pub order: Order,
    /// Key bits per axis of the order.
    pub order_bits: u32,
    /// The sphere cache's Q, threshold, list mode and chunking (its `law_ball` is set per replica).
    pub cache: SphereCacheParams,
    /// The disc index.
    pub index: IndexKind,
    /// Engines, in spec order.
    pub engines: Vec<EngineChoice>,
    /// Points checked against brute force.
    pub brute_force_points: u64,
    /// Photon-map k.
    pub photon_map_k: u64,
    /// Photon-map filter.
    pub photon_map_filter: FilterChoice,
    /// Paths per sample point of the reference.
    pub reference_samples: u64,
    /// Realisations.
    pub replicas: u64,
    /// Write NAME.points.csv.
    pub write_points: bool,
    /// `detp.memory_budget_gib`.
    pub memory_budget_gib: f64,
    /// Whether the spec gave `detp.point_spacing` (else surface points are 2d apart).
    pub spacing_given: bool,
    /// `detp.edge` with its parameter.
    pub edge: EdgeMode,
}

impl DetpConfig {
    /// Q.
    pub fn q(&self) -> f64 {
        self.cache.q
    }

    /// The scene, for a scene source.
    pub fn scene(&self) -> Option<&SceneFile> {
        match &self.rays {
            Rays::Lines => None,
            Rays::Scene(s) => Some(s),
        }
    }

    /// Cross-key checks of `[detp]`; files are loaded (once per run) through `inputs`, so a missing
    /// or bad file is refused before anything is written.
    /// Counted warnings known before running: the scene's own (degenerate triangles, non-planar
    /// quads), points outside the unit ball for lines (no exact value there, and the lines are not
    /// μ-random), and for a points file with a scene, points farther than d from every surface along
    /// their normal and normals facing into the surface the point lies on.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(s) = self.scene() {
            w.extend(s.scene.warnings.iter().cloned());
        }
        let Points::File(f) = &self.points else {
            return w;
        };
        match self.scene() {
            None => {
                let out = f
                    .centers
                    .iter()
                    .filter(|c| c.length() + self.disc_radius > 1.0)
                    .count();
                if out > 0 {
                    w.push(format!(
                        "{out} of {} points of {} reach outside the unit ball (|c| + d > 1): the lines are μ-random inside it only, and those points have no exact irradiance",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
            }
            Some(s) => {
                let d = self.disc_radius;
                let (mut off, mut inward) = (0usize, 0usize);
                let sc = &s.scene;
                for (&c, &n) in f.centers.iter().zip(&f.normals) {
                    // The surface a point lies on: met within 2d by a ray from d before the point,
                    // from either side. Its light-receiving side is its winding normal (triangles)
                    // or the sphere's normal, the convention of surface points.
                    let on = [n, -n].into_iter().find_map(|dir| {
                        let (hit, _) = sc.first_two_hits(c + dir * d, -dir, 0.0, None);
                        hit.filter(|h| h.t <= 2.0 * d).map(|h| match h.prim {
                            crate::lt::Prim::Triangle(t) => sc.triangles[t as usize].normal(),
                            crate::lt::Prim::Ball(b) => {
                                let p = c + dir * d - dir * h.t;
                                sc.balls[b as usize].normal_at(p)
                            }
                        })
                    });
                    match on {
                        None => off += 1,
                        Some(g) if g.dot(n) < 0.0 => inward += 1,
                        Some(_) => {}
                    }
                }
                if off > 0 {
                    w.push(format!(
                        "{off} of {} points of {} are farther than d = {d} from every surface (along their normal): they gather light in mid-air",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
                if inward > 0 {
                    w.push(format!(
                        "{inward} of {} points of {} have a normal facing into the surface they lie on (against its light-receiving side): DETP counts crossings from the normal's side only",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
            }
        }
        w
    }

    /// How many sample points the point has (surface points: the sampler's own count, one per
    /// spacing² of area and at least one per triangle).
    pub fn point_count(&self) -> u64 {
        match &self.points {
            Points::Ball(n) => *n,
            Points::Grid(k) => k.pow(3),
            Points::File(f) => f.centers.len() as u64,
            Points::Surface(s) => self.scene().map_or(0, |sc| {
                let tris: f64 = sc
                    .scene
                    .triangles
                    .iter()
                    .map(|t| (t.area().sqrt() / s).ceil().max(1.0).powi(2))
                    .sum();
                let balls: f64 = sc.scene.balls.iter().map(|b| b.area() / (s * s)).sum();
                (tris + balls).min(u64::MAX as f64) as u64
            }),
        }
    }

    /// A box holding every sample point: the unit ball, the scene, or the file's points.
    pub fn points_bounds(&self) -> Aabb {
        match &self.points {
            Points::Ball(_) | Points::Grid(_) => Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            Points::Surface(_) => self
                .scene()
                .map_or(Aabb::new(DVec3::ZERO, DVec3::ZERO), |s| s.scene.bounds()),
            Points::File(f) => f.centers.iter().fold(
                Aabb::new(DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |b, &c| Aabb::new(b.lo.min(c), b.hi.max(c)),
            ),
        }
    }

    /// Cells of the disc grid (`detp.index = "grid"`) over the discs' bounds, `None` for an octree.
    pub fn grid_cells(&self) -> Option<f64> {
        let IndexKind::Grid(w) = self.index else {
            return None;
        };
        let b = self.points_bounds();
        let ext = (b.hi - b.lo).max(DVec3::ZERO) + DVec3::splat(2.0 * self.disc_radius);
        let dims = (ext / w).ceil().max(DVec3::ONE) + DVec3::ONE;
        Some(dims.x * dims.y * dims.z)
    }

    /// Validates `[detp]` (checks that span keys) and translates it into the engines' types, loading
    /// the scene and points files once through `inputs`.
    pub fn from_raw(seed: u64, d: &RawDetp, inputs: &mut Inputs) -> Result<Self, ConfigError> {
        let rays = match (d.source, &d.scene) {
            (RaySource::Lines, None) => Rays::Lines,
            (RaySource::Lines, Some(_)) => {
                return refuse(
                    "detp.scene",
                    "a scene file needs detp.source = \"scene\" (lines need none)",
                )
            }
            (RaySource::Scene, Some(p)) => {
                let s = inputs.scene("detp.scene", p)?;
                // Irradiance and its Poisson error multiply powers: beyond 1e100 W in total they
                // overflow f64 and a result would be written as inf.
                let total = s.scene.total_power();
                if !(total.is_finite() && total <= 1e100) {
                    return refuse(
                        "detp.scene",
                        format!(
                            "the scene emits {total:e} W in total: above 1e100 W the irradiance and its standard error overflow; rescale its powers"
                        ),
                    );
                }
                Rays::Scene(s)
            }
            (RaySource::Scene, None) => {
                return refuse(
                    "detp.scene",
                    "missing: detp.source = \"scene\" needs a scene file",
                )
            }
        };
        let kind = d.point_source.unwrap_or(match rays {
            Rays::Lines => PointSourceKind::Ball,
            Rays::Scene(_) => PointSourceKind::Surface,
        });
        if matches!(kind, PointSourceKind::Ball | PointSourceKind::Grid)
            && matches!(rays, Rays::Scene(_))
        {
            return refuse(
                "detp.point_source",
                format!(
                    "\"{}\" points in the unit ball go with lines; a scene takes \"surface\" or \"file\"",
                    kind.as_str()
                ),
            );
        }
        let points =
            match kind {
                PointSourceKind::Ball => match d.points {
                    Some(n) => Points::Ball(n),
                    None => {
                        return refuse(
                            "detp.points",
                            "missing: points uniform in the ball need a count",
                        )
                    }
                },
                PointSourceKind::Grid => match d.points {
                    Some(n) => Points::Grid(lattice_side(n)),
                    None => return refuse(
                        "detp.points",
                        "missing: points on a lattice need a count (k = round(∛points) per side)",
                    ),
                },
                PointSourceKind::Surface => {
                    if matches!(rays, Rays::Lines) {
                        return refuse(
                            "detp.point_source",
                            "\"surface\" needs a scene (detp.source = \"scene\")",
                        );
                    }
                    Points::Surface(match (d.point_spacing, d.disc_radius) {
                        (Some(s), _) => s,
                        (None, DiscRadius::Value(r)) => 2.0 * r,
                        (None, DiscRadius::Spacing) => return refuse(
                            "detp.point_spacing",
                            "missing: with disc_radius = \"spacing\" surface points need a spacing",
                        ),
                    })
                }
                PointSourceKind::File => match d.points_file.as_deref() {
                    Some(p) => Points::File(inputs.points("detp.points_file", p)?),
                    None => {
                        return refuse(
                            "detp.points_file",
                            "missing: point_source = \"file\" needs a CSV",
                        )
                    }
                },
            };
        if d.points.is_some() && !matches!(kind, PointSourceKind::Ball | PointSourceKind::Grid) {
            return refuse(
                "detp.points",
                format!(
                    "a count belongs to point_source = \"ball\" or \"grid\", not \"{}\"",
                    kind.as_str()
                ),
            );
        }
        if d.points_file.is_some() && kind != PointSourceKind::File {
            return refuse("detp.points_file", "needs detp.point_source = \"file\"");
        }
        if d.engines.is_empty() {
            return refuse("detp.engines", "empty: name at least one engine");
        }
        if d.engines.iter().all(|x| x.is_baseline()) {
            return refuse(
                "detp.engines",
                "name a DETP engine (sphere-cache, disc-index or brute-force): the photon map and the reference are baselines beside them",
            );
        }
        for (i, a) in d.engines.iter().enumerate() {
            if d.engines[..i].contains(a) {
                return refuse(
                    "detp.engines",
                    format!("\"{}\" is listed twice", a.as_str()),
                );
            }
        }
        if d.engines.contains(&EngineChoice::PhotonMap) && matches!(rays, Rays::Lines) {
            return refuse(
                "detp.engines",
                "the photon map needs photon impacts on surfaces: use detp.source = \"scene\"",
            );
        }
        if d.engines.contains(&EngineChoice::Reference) && matches!(rays, Rays::Lines) {
            return refuse(
                "detp.engines",
                "the reference path-traces a scene's lights and surfaces: it needs detp.source = \"scene\" (lines through the unit ball have an exact irradiance already)",
            );
        }
        if d.engines.contains(&EngineChoice::Reference) && d.reference_samples < 2 {
            return refuse(
                "detp.reference_samples",
                "got 1, at least 2 (the reference's standard error comes from its samples' variance)",
            );
        }
        if d.photons > 1 << 31 {
            return refuse("detp.photons", format!("got {}, at most 2³¹", d.photons));
        }
        if let Points::Ball(n) | Points::Grid(n) = points {
            let n = if let Points::Grid(k) = points {
                k.pow(3)
            } else {
                n
            };
            if n > 1 << 28 {
                return refuse("detp.points", format!("got {n}, at most 2²⁸"));
            }
        }
        let disc_radius = match (d.disc_radius, &points) {
            (DiscRadius::Value(r), _) => r,
            (DiscRadius::Spacing, Points::Ball(n)) => {
                crate::theory::detp::ball_spacing(1.0, *n as f64)
            }
            (DiscRadius::Spacing, Points::Grid(k)) => lattice_spacing(*k),
            (DiscRadius::Spacing, Points::Surface(s)) => *s,
            (DiscRadius::Spacing, Points::File(_)) => {
                return refuse(
                    "detp.disc_radius",
                    "\"spacing\" is unknown for points from a file: give a radius",
                )
            }
        };
        // A disc must be small against the space the rays cover: d ≤ 1 for lines through the unit
        // ball (each line is a segment reaching 1 beyond the ball), d ≤ the scene's diagonal for
        // photons. Larger discs lose precision in the crossing test (d² at 1e200 overflows).
        let reach = match &rays {
            Rays::Lines => (
                1.0,
                "the unit ball's radius (lines are segments reaching 1 beyond it)".to_string(),
            ),
            Rays::Scene(s) => {
                let b = s.scene.bounds();
                let diag = (b.hi - b.lo).length();
                (diag, format!("the scene's diagonal {diag:.4}"))
            }
        };
        if !(disc_radius * disc_radius).is_finite() || disc_radius > reach.0 {
            return refuse(
                if matches!(d.disc_radius, DiscRadius::Spacing) { "detp.point_spacing" } else { "detp.disc_radius" },
                format!("d = {disc_radius:e} is larger than {}: a tangent disc must be small against the scene", reach.1),
            );
        }
        // Enough of f64 left for d and the scene at the scene's coordinates (issue 26).
        if let Rays::Scene(s) = &rays {
            s.scene
                .precision()
                .check(disc_radius)
                .or_else(|m| refuse("detp.scene", m))?;
        }
        let edge = edge_mode(d, &rays)?;
        let cfg = Self {
            seed,
            rays,
            photons: d.photons,
            points,
            disc_radius,
            order: match d.order {
                OrderChoice::None => Order::None,
                OrderChoice::Morton => Order::Morton,
                OrderChoice::Hilbert => Order::Hilbert,
            },
            order_bits: d.order_bits as u32,
            cache: SphereCacheParams {
                q: d.q,
                threshold: d.threshold as usize,
                list_mode: match d.list_mode {
                    ListModeChoice::Exact => ListMode::Exact,
                    ListModeChoice::Inherited => ListMode::Inherited,
                },
                pop_rule: match d.pop_rule {
                    PopRuleChoice::Chain => PopRule::Chain,
                    PopRuleChoice::Paper => PopRule::Paper,
                },
                chunk_points: d.chunk_points as usize,
                law_ball: None,
            },
            index: match d.index {
                IndexChoice::Grid => {
                    IndexKind::Grid(d.index_cell_width.unwrap_or(2.0 * disc_radius))
                }
                IndexChoice::Octree => IndexKind::Octree(d.octree_leaf as usize),
            },
            engines: d.engines.clone(),
            brute_force_points: d.brute_force_points,
            photon_map_k: d.photon_map_k,
            photon_map_filter: d.photon_map_filter,
            reference_samples: d.reference_samples,
            replicas: d.replicas,
            write_points: d.write_points,
            memory_budget_gib: d.memory_budget_gib,
            spacing_given: d.point_spacing.is_some(),
            edge,
        };
        if let Some(cells) = cfg.grid_cells() {
            if cells >= (1u64 << 31) as f64 {
                return refuse(
                    if d.index_cell_width.is_some() { "detp.index_cell_width" } else { "detp.disc_radius" },
                    format!(
                        "a disc grid of cell width {} over the points' bounds would have {cells:.3e} cells (at most 2³¹): widen the cells or use detp.index = \"octree\"",
                        match cfg.index { IndexKind::Grid(w) => w, IndexKind::Octree(_) => f64::NAN },
                    ),
                );
            }
        }
        Ok(cfg)
    }
}
