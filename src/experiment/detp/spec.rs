//! The `[detp]` table of kinds `detp` and `quasi-static`: where the rays come from (μ-random lines
//! through the unit ball, or photons traced from a scene file), where the discs sit (uniform in the
//! ball, on the scene's surfaces, or read from a CSV), the disc radius d, the sphere cache's Q,
//! threshold, ordering and list mode, the disc index, the photon-map baseline, and which engines run.
//!
//! Every key is declared once and range-checked where it is read (so errors carry its line and
//! column); checks that span keys live in `config.rs` ([`super::DetpConfig`]), which also
//! translates the spec's choices into the engines' own types once.

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use super::estimators;
pub use super::estimators::EngineChoice;
use crate::toml_text::de::{count, open_unit, opt_count, opt_positive, positive};

crate::spec_file! {
    /// A spec file of kind `detp`.
    pub struct DetpSpec {
        /// `[detp]`.
        detp: RawDetp = {table};
    }
}

crate::spec_table! {
    /// `[detp]` (kinds `detp` and `quasi-static`).
    pub struct RawDetp {
        /// Where the rays come from: μ-random lines through the unit ball, or photons traced from
        /// `detp.scene`. In kind `quasi-static`, lines meet one absorbing sphere of radius
        /// `dynamic.ratio` circling inside the ball (r_0 = 1), with static points uniform in it.
        source: RaySource = {default RaySource::Lines}, "string", "", "`\"lines\"`, `\"scene\"`";
        /// The scene file, relative to the spec's folder.
        scene: Option<String> = {absent "none; required with `source = \"scene\"`"},
            "string (path)", "",
            "a `.toml` scene (`raycost doc scene`) or a BART `.aff`/`.nff` file";
        /// n_R: lines drawn, or photons emitted from the scene's lights (their paths' segments
        /// are the rays).
        photons: u64 = {required} read count, "integer", "photons", "≥ 1";
        /// n_P: sample points uniform in the unit ball; or, with `point_source = "surface"`, the
        /// first n_P of the surface lattice's points in an order keyed by the seed alone (the same
        /// n_P gives the same points at every sweep point, a smaller one a subset; refused when the
        /// lattice holds fewer). A file name here is refused with a hint to `points_file`.
        points: Option<u64> = {absent "required with `point_source = \"ball\"`; with `\"surface\"`: the whole lattice"}
            read point_count, "integer", "points", "≥ 1";
        /// Where the sample points come from: uniform in the unit ball with uniform normals, on
        /// the scene's surfaces, or a CSV.
        point_source: Option<PointSourceKind> =
            {absent "`\"ball\"` for lines, `\"surface\"` for a scene"},
            "string", "", "`\"ball\"`, `\"surface\"`, `\"file\"`";
        /// The sample points, relative to the spec's folder (normals need not be unit length).
        points_file: Option<String> = {absent "none; required with `point_source = \"file\"`"},
            "string (path)", "", "a CSV with header `x,y,z,nx,ny,nz`";
        /// The unit of `point_spacing`, `disc_radius` and `index_cell_width`: the scene's own,
        /// or r_s, the radius of the sphere around the scene's bounds (so one sweep over scenes of
        /// different sizes keeps the same points per r_s²; lines: r_s = 1 either way).
        length_unit: LengthUnit = {default LengthUnit::Scene}, "string", "",
            "`\"scene\"`, `\"root\"`";
        /// Spacing of surface points.
        point_spacing: Option<f64> = {absent "2·d (the paper's optimum); with `points = n`, √(area/n)/1.2 (about 1.44·n lattice points over the scene's whole area)"} read opt_positive,
            "number", "length", "> 0";
        /// d: the discs' radius, or the points' mean spacing ((4π/3/n_P)^⅓ in the ball,
        /// `point_spacing` on surfaces), the paper's d for Theorem 1.
        disc_radius: DiscRadius = {required}, "number or string", "length",
            "> 0, or `\"spacing\"`";
        /// Q: ratio of consecutive sphere radii of the sphere cache (Proposition 1: 2/3 is
        /// optimal).
        q: f64 = {default 2.0 / 3.0} read open_unit, "number", "", "(0, 1)";
        /// A sphere holding fewer rays is not subdivided.
        threshold: u64 = {default 100} read count, "integer", "rays", "≥ 1";
        /// Order in which the sphere cache visits the points.
        order: OrderChoice = {default OrderChoice::Hilbert}, "string", "",
            "`\"none\"`, `\"morton\"`, `\"hilbert\"`";
        /// Bits per axis of the ordering keys.
        order_bits: u64 = {default 10} read bits, "integer", "bits", "1 … 21";
        /// The paper's cache: a new sphere's list is the parent's rays meeting it (`inherited`);
        /// or raycost's variant, exactly the rays meeting it, from the deepest enclosing ancestor
        /// (`exact`).
        list_mode: ListModeChoice = {default ListModeChoice::Inherited}, "string", "",
            "`\"inherited\"`, `\"exact\"`";
        /// Which levels a new point keeps: the chain of levels that all contain its disc, or the
        /// paper's rule (pop the deepest while it does not; exact with exact lists, cut back to
        /// the chain with inherited lists, repairs counted).
        pop_rule: PopRuleChoice = {default PopRuleChoice::Chain}, "string", "",
            "`\"chain\"`, `\"paper\"`";
        /// Points per independent sphere-cache run (chunks run in parallel; a spec value, never
        /// the thread count, so counts do not depend on threads).
        chunk_points: u64 = {default 16_384} read count, "integer", "points", "≥ 1";
        /// Kind `detp`: the engines run on every point (columns per engine). Kind
        /// `quasi-static` picks its engine with `detp.engine`; here it takes `"sphere-cache"` and
        /// `"path-tracing"` (path tracing in the posed scene at frame 0 and the checked frames).
        engines: Vec<EngineChoice> = {default estimators::default_engines()},
            "array of strings", "", estimators::spellings();
        /// The disc index's structure.
        index: IndexChoice = {default IndexChoice::Octree}, "string", "",
            "`\"octree\"`, `\"grid\"`";
        /// Cell width of the grid disc index.
        index_cell_width: Option<f64> = {absent "2·d"} read opt_positive, "number", "length",
            "> 0";
        /// Most discs in an octree leaf before it splits (it also stops at side ≤ d).
        octree_leaf: u64 = {default 8} read count, "integer", "discs", "≥ 1";
        /// Points whose sums are checked against brute force, bit for bit (0: none); failures
        /// fail the run (exit 1).
        brute_force_points: u64 = {default 256}, "integer", "points", "≥ 0";
        /// k nearest photons of the photon map.
        photon_map_k: u64 = {default 64} read count, "integer", "photons", "≥ 1";
        /// The photon map's density estimation filter.
        photon_map_filter: FilterChoice = {default FilterChoice::Cone}, "string", "",
            "`\"cone\"`, `\"disc\"`";
        /// Paths per point of engine `reference` (path tracing with next-event estimation: the
        /// ground truth, with its SE).
        reference_samples: u64 = {default 1024} read count, "integer", "paths", "≥ 2";
        /// k₀ of engine `photon-map-growing`'s k(N) = k₀·(N/N₀)^β: this is `photon_map_k`; β here.
        /// 2/3 minimises the error where irradiance is smooth, ½ where edges dominate, 0 is a
        /// fixed k.
        photon_map_k_growth: f64 = {default 2.0 / 3.0} read growth_exponent, "number", "",
            "[0, 1)";
        /// N₀ of engine `photon-map-growing`: the photons per replica at which its k equals
        /// `photon_map_k`.
        photon_map_k_photons: u64 = {default 50_000} read count, "integer", "photons", "≥ 1";
        /// K: paths per point of engine `path-tracing` (the competitor, on its own streams); its
        /// checkpoints are 1, 2, 4, … and K.
        path_samples: u64 = {default 1024} read count, "integer", "paths", "≥ 1";
        /// Engine `path-tracing` runs on this many of the points (the first of a keyed
        /// permutation, the same for every sweep point with these points): its cost and errors
        /// are per point, so a subset measures them.
        path_points: Option<u64> = {absent "all points"} read opt_count, "integer", "points",
            "≥ 1";
        /// Direct light: in DETP's photons (the paper), or by next-event estimation at each point
        /// with DETP and the photon maps estimating the indirect light from the segments after the
        /// first bounce (`"nee"`, scenes only).
        direct: DirectChoice = {default DirectChoice::Photons}, "string", "",
            "`\"photons\"`, `\"nee\"`";
        /// S: samples per area light of `direct = "nee"` (point and spot lights are exact).
        direct_samples: u64 = {default 16} read count, "integer", "samples", "≥ 2";
        /// The points table's `edge_distance` looks this far for another surface.
        edge_distance_reach: f64 = {default 2.0} read positive, "number", "× d", "> 0";
        /// Independent realisations (new rays and points each): with one, standard errors are
        /// Poisson estimates; with several, the spread across replicas.
        replicas: u64 = {default 1} read count, "integer", "", "≥ 1";
        /// Also write the per-sample-point irradiance table `NAME.points.csv`.
        write_points: bool = {default false}, "bool", "", "`true`, `false`";
        /// Kind `quasi-static`: how dynamic points are recomputed (hybrid: Theorem 2 picks per
        /// object; predicted: the §4.1 predictor picks).
        engine: Option<DynamicEngine> = {absent "`\"hybrid\"`"}, "string", "",
            "`\"hybrid\"`, `\"sphere-cache\"`, `\"disc-index\"`, `\"predicted\"`";
        /// Memory the ray store and engines may take; a point needing more is refused before it
        /// allocates.
        memory_budget_gib: f64 = {default 8.0} read positive, "number", "GiB", "> 0";
        /// Photon batches B: a point whose segments would not fit `memory_budget_gib` traces its
        /// photons in B batches one after another in this process (each batch's segments freed
        /// before the next), adding the batches' integer sums, so its table is a single pass's bit
        /// for bit. `"auto"` takes the fewest that fit (1 when everything fits); a number forces
        /// it (it must fit too). Engines whose counts do not add (sphere cache, photon maps)
        /// cannot be batched.
        photon_batches: PhotonBatches = {default PhotonBatches::Auto}, "integer or string",
            "batches", "≥ 1, or `\"auto\"`";
        /// Discs near edges: the paper's method, or a remedy (a disc shrunk to the nearest other
        /// surface; crossings cut just past the first impact; both). Scenes only; every engine
        /// stays exact.
        edge: EdgeChoice = {default EdgeChoice::Paper}, "string", "",
            "`\"paper\"`, `\"clamp-radius\"`, `\"first-hit\"`, `\"clamp-first-hit\"`";
        /// Smallest disc radius a clamping remedy allows, as a fraction of d.
        edge_min_radius: Option<f64> = {absent "0.25 with a clamping remedy"}, "number", "× d",
            "(0, 1]";
        /// How far past a segment's first impact a cutting remedy still counts crossings, as a
        /// fraction of d.
        edge_gap: Option<f64> = {absent "0.05 with a cutting remedy"}, "number", "× d", "> 0";
        /// κ of a clamping remedy: each disc's radius is κ·s (s: its distance to the nearest
        /// other surface), clamped to [`edge_min_radius`·d, d]. Below 1 a disc keeps a margin
        /// from the edge; above 1 it reaches past it for less noise.
        edge_radius_factor: Option<f64> = {absent "1 with a clamping remedy"}, "number", "",
            "> 0";
        /// N_ref of the radius schedule d(N) = d_ref·(N/N_ref)^(−β), d_ref = `disc_radius`, N =
        /// `photons`: the disc radius shrinks as photons are added, so the disc's bias (∝ d²) and
        /// its variance (∝ 1/(N·d²)) both vanish (`docs/theory.md`, "A disc radius per point and
        /// per photon count"). Surface points keep the spacing of d_ref. An edge remedy then
        /// clamps per point under d(N).
        radius_schedule_photons: Option<u64> = {absent "none: d is fixed"} read opt_count,
            "integer", "photons", "≥ 1";
        /// β of the radius schedule (with `radius_schedule_photons`): 1/6 minimises the mean
        /// square error of a disc estimate of a smooth field (its RMSE then falls as N^(−1/3)); 0
        /// keeps d.
        radius_schedule_exponent: Option<f64> = {absent "1/6 with a schedule"}, "number", "",
            "≥ 0";
        /// k_ref of the k-nearest-crossings radius: each disc keeps its k nearest crossings
        /// within its radius (d, d(N) with a schedule, an edge remedy's clamp) and its radius
        /// becomes the k-th one's distance; its estimate is the k − 1 nearer crossings' power over
        /// π r_i² (`docs/theory.md`, "A disc radius from the local density"). With fewer than k
        /// within the disc, the whole disc counts as in the paper. Kind `detp` only, not with photon
        /// shards or batches.
        radius_crossings: Option<u64> = {absent "none: each disc keeps its radius"}
            read crossings, "integer", "crossings", "≥ 2";
        /// N_ref of the k-nearest-crossings radius: k = max(2, round(k_ref·(N/N_ref)^(2/3))) at
        /// N = `photons`, so the radius shrinks as N^(−1/6) and both bias and variance vanish (the
        /// photon map's k growth with its optimal exponent for a smooth field).
        radius_crossings_photons: Option<u64> = {absent "none: k = k_ref at every photon count"}
            read opt_count, "integer", "photons", "≥ 1";
    }
}

/// Default `detp.edge_min_radius`.
pub const EDGE_MIN_RADIUS: f64 = 0.25;
/// Default `detp.edge_gap`.
pub const EDGE_GAP: f64 = 0.05;
/// Default `detp.edge_radius_factor` (κ): the disc reaches exactly to the nearest other surface.
pub const EDGE_RADIUS_FACTOR: f64 = 1.0;
/// Default `detp.radius_schedule_exponent` (β): the mean-square-optimal 1/6.
pub const RADIUS_SCHEDULE_EXPONENT: f64 = 1.0 / 6.0;

use crate::choice;

choice!(
    /// Where the rays come from.
    RaySource { Lines => "lines", Scene => "scene" } default Lines
);
choice!(
    /// The unit of `[detp]`'s lengths.
    LengthUnit { Scene => "scene", Root => "root" } default Scene
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
    /// `detp.direct`: direct light in DETP's photons, or by next-event estimation.
    DirectChoice { Photons => "photons", Nee => "nee" } default Photons
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
            toml::Value::Float(x) => crate::toml_text::de::check_positive(x)
                .map(DiscRadius::Value)
                .map_err(D::Error::custom),
            toml::Value::Integer(i) => crate::toml_text::de::check_positive(i as f64)
                .map(DiscRadius::Value)
                .map_err(D::Error::custom),
            other => Err(D::Error::custom(format!(
                "got {other}, expected a radius > 0 or \"spacing\""
            ))),
        }
    }
}

impl crate::toml_text::keys::Omit for DiscRadius {}

impl Serialize for DiscRadius {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            DiscRadius::Value(x) => s.serialize_f64(*x),
            DiscRadius::Spacing => s.serialize_str("spacing"),
        }
    }
}

/// `detp.photon_batches`: `"auto"` or a whole number ≥ 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhotonBatches {
    /// As few as fit the memory budget.
    Auto,
    /// Exactly this many.
    Count(u64),
}

impl PhotonBatches {
    /// The count forced (None: `"auto"`).
    pub fn forced(self) -> Option<u64> {
        match self {
            PhotonBatches::Auto => None,
            PhotonBatches::Count(b) => Some(b),
        }
    }
}

impl<'de> Deserialize<'de> for PhotonBatches {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match toml::Value::deserialize(d)? {
            toml::Value::String(s) if s == "auto" => Ok(PhotonBatches::Auto),
            toml::Value::Integer(i) if i >= 1 => Ok(PhotonBatches::Count(i as u64)),
            other => Err(D::Error::custom(format!(
                "got {other}, expected a whole number of batches ≥ 1 or \"auto\""
            ))),
        }
    }
}

/// `"auto"` is left out of the normalised spec: how a point is traced never changes what it
/// measures, so a spec that does not force batches keeps the hash (and resumes) it had before the
/// key existed.
impl crate::toml_text::keys::Omit for PhotonBatches {
    fn omit(&self) -> bool {
        *self == PhotonBatches::Auto
    }
}

impl Serialize for PhotonBatches {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            PhotonBatches::Auto => s.serialize_str("auto"),
            PhotonBatches::Count(b) => s.serialize_u64(*b),
        }
    }
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

/// `detp.photon_map_k_growth`: β in [0, 1).
fn growth_exponent<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let b = crate::toml_text::de::number(d)?;
    if (0.0..1.0).contains(&b) {
        Ok(b)
    } else {
        Err(D::Error::custom(format!(
            "got {b}, expected an exponent in [0, 1) (1 or more: k grows as fast as the photons, and the photon map's variance no longer falls)"
        )))
    }
}

/// `detp.radius_crossings`: k ≥ 2 (the k-th crossing only sets the radius).
fn crossings<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    match opt_count(toml::Value::deserialize(d)?).map_err(D::Error::custom)? {
        Some(k) if (k as usize) < crate::detp::nearest::MIN_K => Err(D::Error::custom(format!(
            "got {k}, expected k ≥ {} (the k-th crossing only sets the radius; the k − 1 nearer ones are counted)",
            crate::detp::nearest::MIN_K
        ))),
        k => Ok(k),
    }
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
