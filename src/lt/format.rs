//! The TOML scene format: what a user writes. Every table denies unknown keys and every number is
//! checked where it is read, so an error names the file, line, column and key (as specs do).
//!
//! ```toml
//! [[surface]]              # one per surface: kind = "triangle" | "quad" | "sphere" | "obj"
//! kind = "quad"
//! vertices = [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]]   # wound so the normal faces the light
//! albedo = 0.7             # diffuse reflectance in [0, 1)
//! # emission = 1.0         # radiance L_e > 0: an area light of power π·L_e·area
//! # sphere: center = [x, y, z], radius = r, inside = true | false;  obj: path = "mesh.obj"
//!
//! [[light]]                # kind = "point" | "spot"
//! kind = "point"
//! position = [0, 1, 0]
//! power = 100.0
//! # spot: direction = [0, -1, 0], cone_deg = 30 (uniform inside the cone)
//!
//! [camera]                 # eye, look_at, up, fov_deg, width, height
//! [analytic]               # kind = "point-over-plane" | "closed-sphere": the exact irradiance
//! ```

use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use crate::toml_text::de::{number, opt_positive, positive};
use crate::toml_text::keys::{key, IfAbsent::*, KeyDoc};

/// Every key of a TOML scene file (`raycost doc scene`; a test checks them against the structs
/// below, defaults included). Serialize exists only for that test: it shows the defaults serde
/// fills in.
pub const KEYS: &[KeyDoc] = &[
    key("surface[].kind", "string", "", Required, "`\"triangle\"`, `\"quad\"`, `\"sphere\"`, `\"obj\"`",
        "What the surface is: three or four `vertices`, a sphere (`center`, `radius`, `inside`), or a Wavefront OBJ mesh (`path`)."),
    key("surface[].name", "string", "", Absent("`surface N` (its index)"), "any text",
        "A label for messages and warnings."),
    key("surface[].vertices", "array of [x, y, z]", "length", Absent("none; 3 for a triangle, 4 for a quad"), "finite",
        "Corners, listed around the edge (a quad is split into two triangles; a bow-tie or non-planar quad is refused or warned). The winding (right-hand rule) gives the normal, which matters only for an emitting surface."),
    key("surface[].center", "[x, y, z]", "length", Absent("none; required for a sphere"), "finite",
        "Sphere centre."),
    key("surface[].radius", "number", "length", Absent("none; required for a sphere"), "> 0",
        "Sphere radius."),
    key("surface[].inside", "bool", "", Value("false"), "`true`, `false`",
        "A sphere seen from inside (a closed room): its normal points inwards, photons start and bounce inside it."),
    key("surface[].path", "string (path)", "", Absent("none; required for an obj"), "an `.obj` file",
        "The OBJ mesh, relative to the scene file (triangulated; its materials are ignored: this surface's albedo applies)."),
    key("surface[].albedo", "number", "", Required, "[0, 1)",
        "Diffuse reflectance, the same on both sides (reflection is two-sided); 1 is refused (photon paths without end)."),
    key("surface[].emission", "number", "power/(area·sr)", Absent("0: not a light"), "> 0",
        "Emitted radiance L_e, one-sided (on the normal's side): an area light of power π·L_e·area. An area light is given by its radiance, not its power. A dynamic surface cannot emit."),
    key("surface[].dynamic", "string", "", Absent("static"), "the `name` of a `[[dynamic]]`",
        "The dynamic object this surface belongs to: it moves with that object's motion."),
    key("light[].kind", "string", "", Required, "`\"point\"`, `\"spot\"`",
        "An isotropic point light, or a point light emitting uniformly inside a cone."),
    key("light[].position", "[x, y, z]", "length", Required, "finite", "Where the light is."),
    key("light[].power", "number", "power", Required, "> 0",
        "Emitted power Φ (radiant flux; a spot's whole power goes into its cone). Irradiance comes out in power/length² of the same units."),
    key("light[].direction", "[x, y, z]", "", Absent("none; required for a spot"), "non-zero",
        "A spot's axis."),
    key("light[].cone_deg", "number", "degrees", Absent("none; required for a spot"), "(0, 180]",
        "A spot's half-angle."),
    key("camera.eye", "[x, y, z]", "length", Required, "finite",
        "The pinhole (`[camera]` itself is optional; `raycost render` needs it)."),
    key("camera.look_at", "[x, y, z]", "length", Required, "finite", "The point looked at."),
    key("camera.up", "[x, y, z]", "", Required, "not along the view direction", "Up vector."),
    key("camera.fov_deg", "number", "degrees", Required, "> 0", "Vertical field of view."),
    key("camera.width", "integer", "pixels", Required, "≥ 1", "Image width."),
    key("camera.height", "integer", "pixels", Required, "≥ 1", "Image height."),
    key("analytic.kind", "string", "", Required, "`\"point-over-plane\"`, `\"closed-sphere\"`",
        "A closed form of the irradiance, written as `irradiance_exact` and used for verdicts: point-over-plane is the direct light of the first point light, E = Φ·max(0, n·(p − x))/(4π|p − x|³), in a scene where nothing else is lit; closed-sphere is the inside of the one emitting sphere, E = π·L_e/(1 − α). (`[analytic]` itself is optional.)"),
    key("dynamic[].name", "string", "", Required, "any text; surfaces refer to it",
        "A dynamic object: the surfaces with `dynamic = NAME` move together."),
    key("dynamic[].path", "string", "", Required, "`\"circle\"`, `\"line\"`",
        "The path its bounding-sphere centre travels over the frames (τ = 0 … 1): a circle, or a polyline at constant speed."),
    key("dynamic[].center", "[x, y, z]", "length", Absent("none; required for a circle"), "finite", "Circle centre."),
    key("dynamic[].radius", "number", "length", Absent("none; required for a circle"), "> 0", "Circle radius."),
    key("dynamic[].axis", "[x, y, z]", "", Absent("`[0, 1, 0]`"), "non-zero", "Circle axis (normal of its plane)."),
    key("dynamic[].turns", "number", "turns", Value("1.0"), "> 0", "Turns around the circle over the frames."),
    key("dynamic[].points", "array of [x, y, z]", "length", Absent("none; ≥ 2 required for a line"), "finite",
        "The polyline's points."),
    key("dynamic[].spin_deg", "number", "degrees", Value("0.0"), "finite",
        "Spin over the frames about `spin_axis` through the object's centre."),
    key("dynamic[].spin_axis", "[x, y, z]", "", Absent("`[0, 1, 0]`"), "non-zero", "Spin axis."),
];

/// A whole scene file.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    /// Surfaces.
    #[serde(default)]
    pub surface: Vec<RawSurface>,
    /// Point and spot lights.
    #[serde(default)]
    pub light: Vec<RawLight>,
    /// The camera.
    pub camera: Option<RawCamera>,
    /// A closed form for the irradiance.
    pub analytic: Option<RawAnalytic>,
    /// Dynamic objects: the surfaces naming one in `dynamic` move with its motion.
    #[serde(default)]
    pub dynamic: Vec<RawDynamic>,
}

/// Motion paths of `[[dynamic]]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum PathKind {
    /// Around a circle (`center`, `radius`, `axis`, `turns`).
    Circle,
    /// Along a polyline (`points`) at constant speed.
    Line,
}

/// `[[dynamic]]`: a dynamic object and its motion over the frames (τ = 0 … 1).
///
/// ```toml
/// [[dynamic]]
/// name = "ball"                 # surfaces with dynamic = "ball" move together
/// path = "circle"               # or "line" with points = [[x, y, z], ...]
/// center = [278, 200, 280]      # the object's bounding-sphere centre travels this path
/// radius = 120
/// axis = [0, 1, 0]
/// turns = 1.0
/// spin_deg = 0.0                # spin about spin_axis through the object's centre
/// spin_axis = [0, 1, 0]
/// ```
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawDynamic {
    /// The name surfaces refer to.
    pub name: String,
    /// The path kind.
    pub path: PathKind,
    /// Circle centre.
    #[serde(default, deserialize_with = "opt_point")]
    pub center: Option<[f64; 3]>,
    /// Circle radius.
    #[serde(default, deserialize_with = "opt_positive")]
    pub radius: Option<f64>,
    /// Circle axis (normal of its plane).
    #[serde(default, deserialize_with = "opt_point")]
    pub axis: Option<[f64; 3]>,
    /// Turns around the circle over the frames.
    #[serde(default = "one", deserialize_with = "positive")]
    pub turns: f64,
    /// Polyline points (≥ 2).
    #[serde(
        default,
        deserialize_with = "points",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub points: Vec<[f64; 3]>,
    /// Spin over the frames, degrees.
    #[serde(default, deserialize_with = "finite_number")]
    pub spin_deg: f64,
    /// Spin axis.
    #[serde(default, deserialize_with = "opt_point")]
    pub spin_axis: Option<[f64; 3]>,
}

fn one() -> f64 {
    1.0
}

fn finite_number<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = toml::Value::deserialize(d)?;
    finite(&v).ok_or_else(|| D::Error::custom("expected a finite number"))
}

/// Surface kinds.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceKind {
    /// Three vertices.
    Triangle,
    /// Four vertices, split into two triangles.
    Quad,
    /// Center and radius.
    Sphere,
    /// A Wavefront OBJ mesh.
    Obj,
}

/// `[[surface]]`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawSurface {
    /// Kind.
    pub kind: SurfaceKind,
    /// A label for messages.
    pub name: Option<String>,
    /// Triangle or quad vertices.
    #[serde(
        default,
        deserialize_with = "points",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub vertices: Vec<[f64; 3]>,
    /// Sphere centre.
    #[serde(default, deserialize_with = "opt_point")]
    pub center: Option<[f64; 3]>,
    /// Sphere radius.
    #[serde(default, deserialize_with = "opt_positive")]
    pub radius: Option<f64>,
    /// Sphere seen from inside.
    #[serde(default)]
    pub inside: bool,
    /// OBJ path, relative to the scene file.
    pub path: Option<String>,
    /// Diffuse albedo in [0, 1).
    #[serde(deserialize_with = "albedo")]
    pub albedo: f64,
    /// Emitted radiance L_e (> 0 makes it an area light).
    #[serde(default, deserialize_with = "opt_positive")]
    pub emission: Option<f64>,
    /// The `[[dynamic]]` object this surface belongs to (it moves with it).
    pub dynamic: Option<String>,
}

/// Light kinds.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    /// Isotropic point light.
    Point,
    /// Point light emitting uniformly inside a cone.
    Spot,
}

/// `[[light]]`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawLight {
    /// Kind.
    pub kind: LightKind,
    /// Position.
    #[serde(deserialize_with = "point")]
    pub position: [f64; 3],
    /// Emitted power (> 0).
    #[serde(deserialize_with = "positive")]
    pub power: f64,
    /// Spot axis.
    #[serde(default, deserialize_with = "opt_point")]
    pub direction: Option<[f64; 3]>,
    /// Spot half-angle, degrees in (0, 180].
    #[serde(default, deserialize_with = "opt_positive")]
    pub cone_deg: Option<f64>,
}

/// `[camera]`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawCamera {
    /// Eye.
    #[serde(deserialize_with = "point")]
    pub eye: [f64; 3],
    /// Point looked at.
    #[serde(deserialize_with = "point")]
    pub look_at: [f64; 3],
    /// Up vector.
    #[serde(deserialize_with = "point")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    #[serde(deserialize_with = "positive")]
    pub fov_deg: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

/// `[analytic]`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawAnalytic {
    /// `point-over-plane` (direct light of the first point light, nothing else lit) or
    /// `closed-sphere` (the inside of an emitting sphere: E = πL_e/(1 − α)) or `direct-light` (all
    /// albedos 0, point and spot lights: their direct light with a shadow test).
    pub kind: AnalyticKind,
}

/// Closed forms a scene can declare.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum AnalyticKind {
    /// E(x) = Φ·max(0, n·(p − x)) / (4π|p − x|³) from the first point light.
    PointOverPlane,
    /// E = π·L_e / (1 − α) on the inside of the one emitting sphere.
    ClosedSphere,
    /// Direct light alone (every albedo 0, point and spot lights only):
    /// E(x) = Σ_lights V(x)·I·max(0, n·(p − x)) / |p − x|³, with I = Φ/4π (point) or Φ/(2π(1 − cos θ))
    /// inside a spot's cone, and V the shadow test (1 if nothing lies between x and the light).
    DirectLight,
}

fn finite(x: &toml::Value) -> Option<f64> {
    let v = x.as_float().or_else(|| x.as_integer().map(|i| i as f64))?;
    v.is_finite().then_some(v)
}

fn point<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    let v: Vec<toml::Value> = Vec::deserialize(d)?;
    let xs: Vec<f64> = v.iter().filter_map(finite).collect();
    if v.len() != 3 || xs.len() != 3 {
        return Err(D::Error::custom("expected three finite numbers [x, y, z]"));
    }
    Ok([xs[0], xs[1], xs[2]])
}

fn opt_point<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    point(d).map(Some)
}

fn points<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f64; 3]>, D::Error> {
    let v: Vec<Vec<toml::Value>> = Vec::deserialize(d)?;
    v.iter()
        .map(|p| {
            let xs: Vec<f64> = p.iter().filter_map(finite).collect();
            if p.len() == 3 && xs.len() == 3 {
                Ok([xs[0], xs[1], xs[2]])
            } else {
                Err(D::Error::custom(
                    "expected vertices of three finite numbers [x, y, z]",
                ))
            }
        })
        .collect()
}

fn albedo<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let x = number(d)?;
    if x.is_finite() && (0.0..1.0).contains(&x) {
        Ok(x)
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected an albedo in [0, 1) (1 would never absorb: photon paths without end)"
        )))
    }
}
