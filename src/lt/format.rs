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

crate::spec_table! {
    /// A whole scene file.
    pub struct RawScene {
        /// Surfaces.
        surface: Vec<RawSurface> = {tables};
        /// Point and spot lights.
        light: Vec<RawLight> = {tables};
        /// The camera.
        camera: Option<RawCamera> = {optional_table};
        /// A closed form for the irradiance.
        analytic: Option<RawAnalytic> = {optional_table};
        /// Dynamic objects: the surfaces naming one in `dynamic` move with its motion.
        dynamic: Vec<RawDynamic> = {tables};
    }
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

crate::spec_table! {
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
    pub struct RawDynamic {
        /// A dynamic object: the surfaces with `dynamic = NAME` move together.
        name: String = {required}, "string", "", "any text; surfaces refer to it";
        /// The path its bounding-sphere centre travels over the frames (τ = 0 … 1): a circle, or
        /// a polyline at constant speed.
        path: PathKind = {required}, "string", "", "`\"circle\"`, `\"line\"`";
        /// Circle centre.
        center: Option<[f64; 3]> = {absent "none; required for a circle"} read opt_point,
            "[x, y, z]", "length", "finite";
        /// Circle radius.
        radius: Option<f64> = {absent "none; required for a circle"} read opt_positive,
            "number", "length", "> 0";
        /// Circle axis (normal of its plane).
        axis: Option<[f64; 3]> = {absent "`[0, 1, 0]`"} read opt_point, "[x, y, z]", "",
            "non-zero";
        /// Turns around the circle over the frames.
        turns: f64 = {default 1.0} read positive, "number", "turns", "> 0";
        /// The polyline's points.
        points: Vec<[f64; 3]> = {empty "none; ≥ 2 required for a line"} read points,
            "array of [x, y, z]", "length", "finite";
        /// Spin over the frames about `spin_axis` through the object's centre.
        spin_deg: f64 = {default 0.0} read finite_number, "number", "degrees", "finite";
        /// Spin axis.
        spin_axis: Option<[f64; 3]> = {absent "`[0, 1, 0]`"} read opt_point, "[x, y, z]", "",
            "non-zero";
    }
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

crate::spec_table! {
    /// `[[surface]]`.
    pub struct RawSurface {
        /// What the surface is: three or four `vertices`, a sphere (`center`, `radius`,
        /// `inside`), or a Wavefront OBJ mesh (`path`).
        kind: SurfaceKind = {required}, "string", "",
            "`\"triangle\"`, `\"quad\"`, `\"sphere\"`, `\"obj\"`";
        /// A label for messages and warnings.
        name: Option<String> = {absent "`surface N` (its index)"}, "string", "", "any text";
        /// Corners, listed around the edge (a quad is split into two triangles; a bow-tie or
        /// non-planar quad is refused or warned). The winding (right-hand rule) gives the normal,
        /// which matters only for an emitting surface.
        vertices: Vec<[f64; 3]> = {empty "none; 3 for a triangle, 4 for a quad"} read points,
            "array of [x, y, z]", "length", "finite";
        /// Sphere centre.
        center: Option<[f64; 3]> = {absent "none; required for a sphere"} read opt_point,
            "[x, y, z]", "length", "finite";
        /// Sphere radius.
        radius: Option<f64> = {absent "none; required for a sphere"} read opt_positive,
            "number", "length", "> 0";
        /// A sphere seen from inside (a closed room): its normal points inwards, photons start
        /// and bounce inside it.
        inside: bool = {default false}, "bool", "", "`true`, `false`";
        /// The OBJ mesh, relative to the scene file (triangulated; its materials are ignored:
        /// this surface's albedo applies).
        path: Option<String> = {absent "none; required for an obj"}, "string (path)", "",
            "an `.obj` file";
        /// Diffuse reflectance, the same on both sides (reflection is two-sided); 1 is refused
        /// (photon paths without end).
        albedo: f64 = {required} read albedo, "number", "", "[0, 1)";
        /// Emitted radiance L_e, one-sided (on the normal's side): an area light of power
        /// π·L_e·area. An area light is given by its radiance, not its power. A dynamic surface
        /// cannot emit.
        emission: Option<f64> = {absent "0: not a light"} read opt_positive,
            "number", "power/(area·sr)", "> 0";
        /// The dynamic object this surface belongs to: it moves with that object's motion.
        dynamic: Option<String> = {absent "static"}, "string", "",
            "the `name` of a `[[dynamic]]`";
    }
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

crate::spec_table! {
    /// `[[light]]`.
    pub struct RawLight {
        /// An isotropic point light, or a point light emitting uniformly inside a cone.
        kind: LightKind = {required}, "string", "", "`\"point\"`, `\"spot\"`";
        /// Where the light is.
        position: [f64; 3] = {required} read point, "[x, y, z]", "length", "finite";
        /// Emitted power Φ (radiant flux; a spot's whole power goes into its cone). Irradiance
        /// comes out in power/length² of the same units.
        power: f64 = {required} read positive, "number", "power", "> 0";
        /// A spot's axis.
        direction: Option<[f64; 3]> = {absent "none; required for a spot"} read opt_point,
            "[x, y, z]", "", "non-zero";
        /// A spot's half-angle.
        cone_deg: Option<f64> = {absent "none; required for a spot"} read opt_positive,
            "number", "degrees", "(0, 180]";
    }
}

crate::spec_table! {
    /// `[camera]`.
    pub struct RawCamera {
        /// The pinhole (`[camera]` itself is optional; `raycost render` needs it).
        eye: [f64; 3] = {required} read point, "[x, y, z]", "length", "finite";
        /// The point looked at.
        look_at: [f64; 3] = {required} read point, "[x, y, z]", "length", "finite";
        /// Up vector.
        up: [f64; 3] = {required} read point, "[x, y, z]", "", "not along the view direction";
        /// Vertical field of view.
        fov_deg: f64 = {required} read positive, "number", "degrees", "> 0";
        /// Image width.
        width: u32 = {required}, "integer", "pixels", "≥ 1";
        /// Image height.
        height: u32 = {required}, "integer", "pixels", "≥ 1";
    }
}

crate::spec_table! {
    /// `[analytic]`.
    pub struct RawAnalytic {
        /// A closed form of the irradiance, written as `irradiance_exact` and used for verdicts:
        /// point-over-plane is the direct light of the first point light,
        /// E = Φ·max(0, n·(p − x))/(4π|p − x|³), in a scene where nothing else is lit;
        /// closed-sphere is the inside of the one emitting sphere, E = π·L_e/(1 − α).
        /// (`[analytic]` itself is optional.)
        kind: AnalyticKind = {required}, "string", "",
            "`\"point-over-plane\"`, `\"closed-sphere\"`";
    }
}

impl crate::toml_text::keys::Omit for PathKind {}
impl crate::toml_text::keys::Omit for SurfaceKind {}
impl crate::toml_text::keys::Omit for LightKind {}
impl crate::toml_text::keys::Omit for AnalyticKind {}

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
