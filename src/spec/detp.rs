//! The `[detp]` table of kind `detp`: where the rays come from (μ-random lines through the unit ball,
//! or photons traced from a scene file), where the discs sit (uniform in the ball, on the scene's
//! surfaces, or read from a CSV), the disc radius d, the sphere cache's Q, threshold, ordering and list
//! mode, the disc index, the photon-map baseline, and which engines run.
//!
//! As for the grid tables, every key is range-checked where it is read (so errors carry its line and
//! column); checks that span keys live in [`DetpConfig::from_raw`] and name the key they blame.

use std::path::{Path, PathBuf};

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use super::raw::{count, opt_count, opt_positive, positive};

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
        deserialize_with = "opt_count",
        skip_serializing_if = "Option::is_none"
    )]
    pub points: Option<u64>,
    /// `"ball"` (uniform in the unit ball, uniform normals), `"surface"` (on the scene's surfaces)
    /// or `"file"` (a CSV of x, y, z, nx, ny, nz). Default: ball for lines, surface for a scene.
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
    /// `"exact"`: every list holds exactly the rays meeting its sphere; `"inherited"`: the parent's
    /// rays meeting it (the paper's literal rule).
    #[serde(default)]
    pub list_mode: ListModeChoice,
    /// Points per independent sphere-cache run (chunks run in parallel; a spec value, never the
    /// thread count, so counters do not depend on threads).
    #[serde(default = "default_chunk", deserialize_with = "count")]
    pub chunk_points: u64,
    /// Engines to run on every point: `sphere-cache`, `disc-index`, `brute-force`, `photon-map`.
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
}

macro_rules! choice {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $v:ident => $s:literal),+ $(,)? } default $d:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $name { $($(#[$vm])* #[allow(missing_docs)] $v),+ }
        impl $name {
            /// The spelling in specs and CSV columns.
            pub fn as_str(self) -> &'static str { match self { $($name::$v => $s),+ } }
            const ALL: &'static [(&'static str, $name)] = &[$(($s, $name::$v)),+];
        }
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = String::deserialize(d)?;
                $name::ALL.iter().find(|(k, _)| *k == s).map(|(_, v)| *v).ok_or_else(|| {
                    let allowed: Vec<String> = $name::ALL.iter().map(|(k, _)| format!("\"{k}\"")).collect();
                    D::Error::custom(format!("got \"{s}\", expected one of {}", allowed.join(", ")))
                })
            }
        }
        impl Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> { s.serialize_str(self.as_str()) }
        }
        impl Default for $name { fn default() -> Self { $name::$d } }
    };
}

choice!(
    /// Where the rays come from.
    RaySource { Lines => "lines", Scene => "scene" } default Lines
);
choice!(
    /// Where the sample points come from.
    PointSourceKind { Ball => "ball", Surface => "surface", File => "file" } default Ball
);
choice!(
    /// Point ordering.
    OrderChoice { None => "none", Morton => "morton", Hilbert => "hilbert" } default Hilbert
);
choice!(
    /// Sphere-cache list mode.
    ListModeChoice { Exact => "exact", Inherited => "inherited" } default Exact
);
choice!(
    /// An irradiance engine.
    EngineChoice {
        SphereCache => "sphere-cache",
        DiscIndex => "disc-index",
        BruteForce => "brute-force",
        PhotonMap => "photon-map",
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
    /// Kind `quasi-static`: how dynamic points are recomputed (and static points updated).
    DynamicEngine {
        Hybrid => "hybrid",
        SphereCache => "sphere-cache",
        DiscIndex => "disc-index",
        Predicted => "predicted",
    } default Hybrid
);

impl EngineChoice {
    /// Column stem: `sphere_cache`, `disc_index`, `brute_force`, `photon_map`.
    pub fn column(self) -> &'static str {
        match self {
            EngineChoice::SphereCache => "sphere_cache",
            EngineChoice::DiscIndex => "disc_index",
            EngineChoice::BruteForce => "brute_force",
            EngineChoice::PhotonMap => "photon_map",
        }
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
            toml::Value::Float(x) => super::raw::check_positive(x)
                .map(DiscRadius::Value)
                .map_err(D::Error::custom),
            toml::Value::Integer(i) => super::raw::check_positive(i as f64)
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
fn default_budget() -> f64 {
    8.0
}
fn default_engines() -> Vec<EngineChoice> {
    vec![EngineChoice::SphereCache]
}

fn open_unit<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let x = super::raw::number(d)?;
    if x.is_finite() && x > 0.0 && x < 1.0 {
        Ok(x)
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected a ratio in (0, 1)"
        )))
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

/// The rays of a point.
#[derive(Clone, Debug, PartialEq)]
pub enum Rays {
    /// μ-random lines through the unit ball.
    Lines,
    /// Photons traced from this scene file.
    Scene(PathBuf),
}

/// The sample points of a point.
#[derive(Clone, Debug, PartialEq)]
pub enum Points {
    /// n points uniform in the unit ball with uniform normals.
    Ball(u64),
    /// On the scene's surfaces at this spacing.
    Surface(f64),
    /// Read from this CSV.
    File(PathBuf),
}

/// Everything a DETP point needs, validated.
#[derive(Clone, Debug, PartialEq)]
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
    /// Q.
    pub q: f64,
    /// Subdivision threshold.
    pub threshold: u64,
    /// Ordering.
    pub order: OrderChoice,
    /// Key bits per axis.
    pub order_bits: u32,
    /// List mode.
    pub list_mode: ListModeChoice,
    /// Points per sphere-cache chunk.
    pub chunk_points: u64,
    /// Engines, in spec order.
    pub engines: Vec<EngineChoice>,
    /// Disc index kind.
    pub index: IndexChoice,
    /// Grid index cell width.
    pub index_cell_width: f64,
    /// Octree leaf size.
    pub octree_leaf: u64,
    /// Points checked against brute force.
    pub brute_force_points: u64,
    /// Photon-map k.
    pub photon_map_k: u64,
    /// Photon-map filter.
    pub photon_map_filter: FilterChoice,
    /// Realisations.
    pub replicas: u64,
    /// Write NAME.points.csv.
    pub write_points: bool,
}

/// Bytes a lines point needs per ray: the 56-byte segment plus the sphere cache's f32 SoA lists,
/// which over all levels hold about 1/(1 − Q²) of the rays at 32 bytes each plus a 4-byte index.
fn bytes_per_ray(q: f64) -> f64 {
    56.0 + 36.0 / (1.0 - q * q)
}

impl DetpConfig {
    /// Cross-key checks of `[detp]`; paths are resolved against `base_dir` (the spec's folder) and
    /// must exist now, so a missing file is refused before anything is written.
    pub fn from_raw(
        seed: u64,
        d: &RawDetp,
        base_dir: &Path,
    ) -> Result<Self, super::config::ConfigError> {
        let e = |k: &str, m: String| (k.to_string(), m);
        let resolve = |key: &str, p: &str| -> Result<PathBuf, super::config::ConfigError> {
            let path = base_dir.join(p);
            if path.is_file() {
                Ok(path)
            } else {
                let aff = matches!(
                    path.extension().and_then(|x| x.to_str()),
                    Some("aff" | "nff")
                );
                let hint = if aff {
                    format!("; {}", crate::lt::aff::BART_HINT)
                } else {
                    String::new()
                };
                Err(e(key, format!("{}: no such file{hint}", path.display())))
            }
        };
        let rays = match (d.source, &d.scene) {
            (RaySource::Lines, None) => Rays::Lines,
            (RaySource::Lines, Some(_)) => {
                return Err(e(
                    "detp.scene",
                    "a scene file needs detp.source = \"scene\" (lines need none)".into(),
                ))
            }
            (RaySource::Scene, Some(p)) => {
                let path = resolve("detp.scene", p)?;
                // Read it now: a bad scene is bad input, refused before anything is written.
                crate::lt::Scene::load(&path).map_err(|err| e("detp.scene", err.to_string()))?;
                Rays::Scene(path)
            }
            (RaySource::Scene, None) => {
                return Err(e(
                    "detp.scene",
                    "missing: detp.source = \"scene\" needs a scene file".into(),
                ))
            }
        };
        let kind = d.point_source.unwrap_or(match rays {
            Rays::Lines => PointSourceKind::Ball,
            Rays::Scene(_) => PointSourceKind::Surface,
        });
        if kind == PointSourceKind::Ball && matches!(rays, Rays::Scene(_)) {
            return Err(e(
                "detp.point_source",
                "points uniform in the unit ball go with lines; a scene takes \"surface\" or \"file\"".into(),
            ));
        }
        let points =
            match kind {
                PointSourceKind::Ball => Points::Ball(d.points.ok_or_else(|| {
                    e(
                        "detp.points",
                        "missing: points uniform in the ball need a count".into(),
                    )
                })?),
                PointSourceKind::Surface => {
                    if matches!(rays, Rays::Lines) {
                        return Err(e(
                            "detp.point_source",
                            "\"surface\" needs a scene (detp.source = \"scene\")".into(),
                        ));
                    }
                    Points::Surface(match (d.point_spacing, d.disc_radius) {
                        (Some(s), _) => s,
                        (None, DiscRadius::Value(r)) => 2.0 * r,
                        (None, DiscRadius::Spacing) => return Err(e(
                            "detp.point_spacing",
                            "missing: with disc_radius = \"spacing\" surface points need a spacing"
                                .into(),
                        )),
                    })
                }
                PointSourceKind::File => {
                    let path = resolve(
                        "detp.points_file",
                        d.points_file.as_deref().ok_or_else(|| {
                            e(
                                "detp.points_file",
                                "missing: point_source = \"file\" needs a CSV".into(),
                            )
                        })?,
                    )?;
                    // Read it now: a bad row (a zero normal, not a number) is bad input,
                    // refused before anything is written.
                    crate::detp::surface_points::read_points_csv(&path)
                        .map_err(|m| e("detp.points_file", m))?;
                    Points::File(path)
                }
            };
        if d.points.is_some() && kind != PointSourceKind::Ball {
            return Err(e(
                "detp.points",
                format!(
                    "a count belongs to point_source = \"ball\", not \"{}\"",
                    kind.as_str()
                ),
            ));
        }
        if d.points_file.is_some() && kind != PointSourceKind::File {
            return Err(e(
                "detp.points_file",
                "needs detp.point_source = \"file\"".into(),
            ));
        }
        if d.engines.is_empty() {
            return Err(e("detp.engines", "empty: name at least one engine".into()));
        }
        if d.engines.iter().all(|&x| x == EngineChoice::PhotonMap) {
            return Err(e(
                "detp.engines",
                "name a DETP engine (sphere-cache, disc-index or brute-force): the photon map is a baseline beside them".into(),
            ));
        }
        for (i, a) in d.engines.iter().enumerate() {
            if d.engines[..i].contains(a) {
                return Err(e(
                    "detp.engines",
                    format!("\"{}\" is listed twice", a.as_str()),
                ));
            }
        }
        if d.engines.contains(&EngineChoice::PhotonMap) && matches!(rays, Rays::Lines) {
            return Err(e(
                "detp.engines",
                "the photon map needs photon impacts on surfaces: use detp.source = \"scene\""
                    .into(),
            ));
        }
        if d.photons > 1 << 31 {
            return Err(e("detp.photons", format!("got {}, at most 2³¹", d.photons)));
        }
        if let Points::Ball(n) = points {
            if n > 1 << 28 {
                return Err(e("detp.points", format!("got {n}, at most 2²⁸")));
            }
        }
        let need = d.photons as f64 * bytes_per_ray(d.q)
            + match points {
                Points::Ball(n) => n as f64 * 64.0,
                _ => 0.0,
            };
        let budget = d.memory_budget_gib * (1u64 << 30) as f64;
        if need > budget {
            return Err(e(
                "detp.photons",
                format!(
                    "{} rays would need about {:.2} GiB, over detp.memory_budget_gib = {} GiB",
                    d.photons,
                    need / (1u64 << 30) as f64,
                    d.memory_budget_gib
                ),
            ));
        }
        let disc_radius = match (d.disc_radius, &points) {
            (DiscRadius::Value(r), _) => r,
            (DiscRadius::Spacing, Points::Ball(n)) => {
                crate::theory::detp::ball_spacing(1.0, *n as f64)
            }
            (DiscRadius::Spacing, Points::Surface(s)) => *s,
            (DiscRadius::Spacing, Points::File(_)) => {
                return Err(e(
                    "detp.disc_radius",
                    "\"spacing\" is unknown for points from a file: give a radius".into(),
                ))
            }
        };
        Ok(Self {
            seed,
            rays,
            photons: d.photons,
            points,
            disc_radius,
            q: d.q,
            threshold: d.threshold,
            order: d.order,
            order_bits: d.order_bits as u32,
            list_mode: d.list_mode,
            chunk_points: d.chunk_points,
            engines: d.engines.clone(),
            index: d.index,
            index_cell_width: d.index_cell_width.unwrap_or(2.0 * disc_radius),
            octree_leaf: d.octree_leaf,
            brute_force_points: d.brute_force_points,
            photon_map_k: d.photon_map_k,
            photon_map_filter: d.photon_map_filter,
            replicas: d.replicas,
            write_points: d.write_points,
        })
    }
}
