//! The TOML scene format: what a user writes, and its validation into a scene's parts. Every table
//! denies unknown keys and every number is checked where it is read, so an error names the file,
//! line, column and key (as specs do); the rules within a table are checked by that table's own
//! code ([`RawSurface`] by its kind, [`RawLight`], `[analytic]`, [`RawDynamic`]), and those across
//! tables by [`RawScene::into_parts`].
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

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{de::Error as _, Deserialize, Deserializer, Serialize};

use super::motion::{Motion, Mover, MoverPart};
use super::shapes::{self, Ball, Triangle};
use super::{Camera, InputError, Light, SceneParts, Surface};
use crate::toml_text::find_key;

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

/// Where a scene file's problems are reported: the file, its text (for the key's line) and its
/// folder (OBJ paths are relative to it).
struct Cx<'a> {
    name: String,
    text: &'a str,
    dir: &'a Path,
}

impl Cx<'_> {
    /// A problem with `key`, at its line.
    fn err(&self, key: String, message: impl Into<String>) -> InputError {
        InputError {
            file: self.name.clone(),
            at: find_key(self.text, &key).filter(|_| !key.is_empty()),
            key: Some(key),
            message: message.into(),
        }
    }
}

impl RawScene {
    /// The scene's parts, validated table by table ([`RawSurface`] by its kind, [`RawLight`],
    /// `[analytic]`, [`RawDynamic`]), then the rules that span tables: a light, some geometry, a
    /// closed form whose conditions hold, and dynamic objects that surfaces name. `path` names the
    /// file in errors and anchors relative OBJ paths; `text` gives each key's line.
    pub fn into_parts(self, path: &Path, text: &str) -> Result<SceneParts, InputError> {
        let cx = Cx {
            name: path.display().to_string(),
            text,
            dir: path.parent().unwrap_or(Path::new("")),
        };
        let mut parts = SceneParts::default();
        // Geometry of each [[dynamic]] object, gathered from the surfaces naming it.
        let mut moving: Vec<(Vec<Triangle>, Vec<Ball>)> =
            vec![Default::default(); self.dynamic.len()];
        for (si, s) in self.surface.iter().enumerate() {
            s.add_to(si, &self.dynamic, &cx, &mut parts, &mut moving)?;
        }
        for (li, l) in self.light.iter().enumerate() {
            parts.lights.push(l.light(li, &cx)?);
        }
        if parts.lights.is_empty() {
            return Err(cx.err(
                "light".into(),
                "the scene has no light: add a [[light]] or a surface with emission > 0",
            ));
        }
        if parts.triangles.is_empty() && parts.balls.is_empty() {
            return Err(cx.err("surface".into(), "the scene has no surface"));
        }
        parts.analytic = self.analytic.map(|a| a.kind);
        check_analytic(&parts, &cx)?;
        parts.camera = self.camera.map(|c| Camera {
            eye: DVec3::from_array(c.eye),
            look_at: DVec3::from_array(c.look_at),
            up: DVec3::from_array(c.up),
            fov_deg: c.fov_deg,
            width: c.width,
            height: c.height,
        });
        parts.movers = movers(&self.dynamic, moving, &cx)?;
        Ok(parts)
    }
}

impl RawSurface {
    /// Adds surface `si` to `parts`: its geometry by its kind (degenerate and duplicate triangles
    /// skipped and counted), its material, its light if it emits, or to its dynamic object's geometry.
    fn add_to(
        &self,
        si: usize,
        dynamic: &[RawDynamic],
        cx: &Cx,
        parts: &mut SceneParts,
        moving: &mut [(Vec<Triangle>, Vec<Ball>)],
    ) -> Result<(), InputError> {
        let key = |k: &str| format!("surface[{si}].{k}");
        let id = si as u32;
        let first = parts.triangles.len();
        let label = self.name.clone().unwrap_or_else(|| format!("surface {si}"));
        self.geometry(si, cx, parts)?;
        // Degenerate triangles are skipped and counted, never traced.
        let before = parts.triangles.len();
        let kept: Vec<Triangle> = parts
            .triangles
            .drain(first..)
            .filter(|t| !t.degenerate())
            .collect();
        if kept.len() < before - first {
            parts.warnings.push(format!(
                "{}: {label}: skipped {} degenerate triangle(s) (zero area or not finite)",
                cx.name,
                before - first - kept.len()
            ));
        }
        let (kept, duplicates) = shapes::without_duplicates(kept);
        if duplicates > 0 {
            parts.warnings.push(format!(
                "{}: {label}: skipped {duplicates} duplicate triangle(s) (the same three \
                 vertices, wound the same way, as another triangle of this surface)",
                cx.name
            ));
        }
        parts.triangles.extend(kept);
        if let Some(dname) = &self.dynamic {
            let Some(k) = dynamic.iter().position(|d| &d.name == dname) else {
                return Err(cx.err(
                    key("dynamic"),
                    format!("no [[dynamic]] object is named \"{dname}\""),
                ));
            };
            if self.emission.is_some() {
                return Err(cx.err(
                    key("emission"),
                    "a dynamic surface cannot emit (lights are static)",
                ));
            }
            moving[k].0.extend(parts.triangles.drain(first..));
            if self.kind == SurfaceKind::Sphere {
                moving[k].1.extend(parts.balls.pop());
            }
        }
        if let Some(le) = self.emission {
            let tris: Vec<u32> = (first as u32..parts.triangles.len() as u32).collect();
            let ball = (self.kind == SurfaceKind::Sphere).then(|| parts.balls.len() as u32 - 1);
            let area: f64 = tris
                .iter()
                .map(|&t| parts.triangles[t as usize].area())
                .sum::<f64>()
                + ball.map_or(0.0, |b| parts.balls[b as usize].area());
            if area <= 0.0 {
                return Err(cx.err(key("emission"), "an emitting surface has no area"));
            }
            parts.lights.push(Light::Area {
                surface: id,
                triangles: tris,
                ball,
                power: PI * le * area,
            });
        }
        parts.surfaces.push(Surface {
            name: label,
            albedo: self.albedo,
            emission: self.emission.unwrap_or(0.0),
        });
        Ok(())
    }

    /// Adds its geometry to `parts`, by its kind.
    fn geometry(&self, si: usize, cx: &Cx, parts: &mut SceneParts) -> Result<(), InputError> {
        let key = |k: &str| format!("surface[{si}].{k}");
        let id = si as u32;
        match self.kind {
            SurfaceKind::Triangle => {
                let v = self.vertices(3, si, cx)?;
                parts.triangles.push(Triangle {
                    v: [v[0], v[1], v[2]],
                    surface: id,
                });
            }
            SurfaceKind::Quad => {
                let v = self.vertices(4, si, cx)?;
                parts.triangles.extend(quad(&v, id, si, cx)?);
            }
            SurfaceKind::Sphere => {
                let (Some(c), Some(r)) = (self.center, self.radius) else {
                    return Err(cx.err(key("radius"), "a sphere needs center and radius"));
                };
                parts.balls.push(Ball {
                    center: DVec3::from_array(c),
                    radius: r,
                    inside: self.inside,
                    surface: id,
                });
            }
            SurfaceKind::Obj => {
                let Some(p) = &self.path else {
                    return Err(cx.err(key("path"), "an obj surface needs a path"));
                };
                let file: PathBuf = cx.dir.join(p);
                // A FIFO or device is refused by what it is; a missing file by the OBJ reader.
                if let Err(why) = file
                    .metadata()
                    .map_or(Ok(()), |_| crate::error::regular_input(&file))
                {
                    return Err(cx.err(key("path"), format!("{}: {why}", file.display())));
                }
                parts.sources.push((file.clone(), "obj"));
                parts.triangles.extend(obj(&file, id, &key("path"), cx)?);
            }
        }
        Ok(())
    }

    /// Its `n` vertices (a triangle has 3, a quad 4).
    fn vertices(&self, n: usize, si: usize, cx: &Cx) -> Result<Vec<DVec3>, InputError> {
        let v: Vec<DVec3> = self
            .vertices
            .iter()
            .map(|&p| DVec3::from_array(p))
            .collect();
        if v.len() == n {
            Ok(v)
        } else {
            Err(cx.err(
                format!("surface[{si}].vertices"),
                format!("a {:?} needs {n} vertices, got {}", self.kind, v.len()).to_lowercase(),
            ))
        }
    }
}

/// A quad's two triangles, split along v0–v2: it must be planar and its vertices in order around
/// it, or the two halves are not the quad the user meant.
fn quad(v: &[DVec3], id: u32, si: usize, cx: &Cx) -> Result<[Triangle; 2], InputError> {
    let n1 = (v[1] - v[0]).cross(v[2] - v[0]);
    let n2 = (v[2] - v[0]).cross(v[3] - v[0]);
    let size = (v[2] - v[0]).length().max((v[3] - v[1]).length());
    let key = || format!("surface[{si}].vertices");
    if n1.length() > 0.0 && n2.length() > 0.0 {
        // Measured data is not exactly planar (the Cornell box's walls are off by 0.4 % of their
        // size, as published): up to 1 % of the quad's size is accepted as measurement error,
        // beyond it the quad is refused.
        let off = (v[3] - v[0]).dot(n1.normalize()).abs();
        if off > 0.01 * size {
            return Err(cx.err(
                key(),
                format!("the quad is not planar: its 4th vertex is {off:.3e} off the plane of the first three, over 1 % of its size {size:.3e} (split it into two triangles)"),
            ));
        }
        if n1.dot(n2) < 0.0 {
            return Err(cx.err(
                key(),
                "the quad's vertices are not in order around it (a bow-tie): list them along its edge",
            ));
        }
    }
    Ok([
        Triangle {
            v: [v[0], v[1], v[2]],
            surface: id,
        },
        Triangle {
            v: [v[0], v[2], v[3]],
            surface: id,
        },
    ])
}

/// The triangles of a Wavefront OBJ mesh (named by spec key `key`), triangulated.
fn obj(file: &Path, id: u32, key: &str, cx: &Cx) -> Result<Vec<Triangle>, InputError> {
    let bad = |message: String| InputError {
        file: file.display().to_string(),
        at: None,
        key: None,
        message,
    };
    let (models, _) = tobj::load_obj(
        file,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .map_err(|e| {
        bad(format!(
            "cannot read this OBJ (named by {}, {key}): {e}",
            cx.name
        ))
    })?;
    if models.iter().all(|m| m.mesh.indices.len() < 3) {
        return Err(bad(format!(
            "the OBJ (named by {}, {key}) has no faces",
            cx.name
        )));
    }
    let mut out = Vec::new();
    for m in models {
        let p = &m.mesh.positions;
        let vert = |i: u32| {
            let i = i as usize * 3;
            DVec3::new(f64::from(p[i]), f64::from(p[i + 1]), f64::from(p[i + 2]))
        };
        for f in m.mesh.indices.chunks_exact(3) {
            out.push(Triangle {
                v: [vert(f[0]), vert(f[1]), vert(f[2])],
                surface: id,
            });
        }
    }
    Ok(out)
}

impl RawLight {
    /// Light `li`: a point light, or a spot with a non-zero axis and a cone of at most 180°.
    fn light(&self, li: usize, cx: &Cx) -> Result<Light, InputError> {
        let position = DVec3::from_array(self.position);
        Ok(match self.kind {
            LightKind::Point => Light::Point {
                position,
                power: self.power,
            },
            LightKind::Spot => {
                let (Some(dir), Some(cone)) = (self.direction, self.cone_deg) else {
                    return Err(cx.err(
                        format!("light[{li}].direction"),
                        "a spot light needs direction and cone_deg",
                    ));
                };
                let axis = DVec3::from_array(dir);
                if axis.length() == 0.0 || cone > 180.0 {
                    return Err(cx.err(
                        format!("light[{li}].cone_deg"),
                        "a spot needs a non-zero direction and cone_deg in (0, 180]",
                    ));
                }
                Light::Spot {
                    position,
                    axis: axis.normalize(),
                    cos_cone: cone.to_radians().cos(),
                    power: self.power,
                }
            }
        })
    }
}

/// `[analytic]`: the closed form's conditions hold in the scene.
fn check_analytic(parts: &SceneParts, cx: &Cx) -> Result<(), InputError> {
    let refuse = |m: &str| Err(cx.err("analytic.kind".into(), m));
    match parts.analytic {
        Some(AnalyticKind::PointOverPlane)
            if !parts.lights.iter().any(|l| matches!(l, Light::Point { .. })) =>
        {
            refuse("point-over-plane needs a point light")
        }
        Some(AnalyticKind::ClosedSphere)
            if !parts
                .balls
                .iter()
                .any(|b| b.inside && parts.surfaces[b.surface as usize].emission > 0.0) =>
        {
            refuse("closed-sphere needs an emitting sphere seen from inside")
        }
        Some(AnalyticKind::DirectLight)
            if parts.surfaces.iter().any(|s| s.albedo != 0.0)
                || parts.lights.iter().any(|l| matches!(l, Light::Area { .. })) =>
        {
            refuse("direct-light needs every albedo 0 and point or spot lights only (no emitting surface): then the irradiance is the lights' direct light")
        }
        _ => Ok(()),
    }
}

/// The dynamic objects: each named once, with geometry (`moving`: what the surfaces naming it
/// gave) and a motion.
fn movers(
    dynamic: &[RawDynamic],
    moving: Vec<(Vec<Triangle>, Vec<Ball>)>,
    cx: &Cx,
) -> Result<Vec<Mover>, InputError> {
    for (k, d) in dynamic.iter().enumerate() {
        if let Some(first) = dynamic[..k].iter().position(|e| e.name == d.name) {
            return Err(cx.err(
                format!("dynamic[{k}].name"),
                format!(
                    "\"{}\" names two [[dynamic]] tables (the {} and the {}); each object needs its own name",
                    d.name,
                    ordinal(first),
                    ordinal(k)
                ),
            ));
        }
    }
    let mut out = Vec::new();
    for (k, (d, (tris, bls))) in dynamic.iter().zip(moving).enumerate() {
        if tris.is_empty() && bls.is_empty() {
            return Err(cx.err(
                format!("dynamic[{k}].name"),
                format!("no surface names dynamic = \"{}\"", d.name),
            ));
        }
        out.push(Mover::new(
            d.name.clone(),
            vec![MoverPart {
                triangles: tris,
                balls: bls,
                motion: d.motion(k, cx)?,
            }],
        ));
    }
    Ok(out)
}

impl RawDynamic {
    /// The motion of `[[dynamic]]` number `k`: a circle (centre, radius, axis, turns) or a
    /// polyline of at least two points, with its spin.
    fn motion(&self, k: usize, cx: &Cx) -> Result<Motion, InputError> {
        let key = |f: &str| format!("dynamic[{k}].{f}");
        let unit = |v: Option<[f64; 3]>, f: &str| -> Result<DVec3, InputError> {
            let a = DVec3::from_array(v.unwrap_or([0.0, 1.0, 0.0]));
            if a.length() > 0.0 {
                Ok(a.normalize())
            } else {
                Err(cx.err(key(f), "an axis must be non-zero"))
            }
        };
        let spin_axis = unit(self.spin_axis, "spin_axis")?;
        match self.path {
            PathKind::Circle => {
                let (Some(c), Some(r)) = (self.center, self.radius) else {
                    return Err(cx.err(key("path"), "a circle path needs center and radius"));
                };
                Ok(Motion::Circle {
                    center: DVec3::from_array(c),
                    radius: r,
                    axis: unit(self.axis, "axis")?,
                    turns: self.turns,
                    spin_deg: self.spin_deg,
                    spin_axis,
                })
            }
            PathKind::Line if self.points.len() < 2 => {
                Err(cx.err(key("points"), "a line path needs at least two points"))
            }
            PathKind::Line => Ok(Motion::Path {
                points: self.points.iter().map(|&p| DVec3::from_array(p)).collect(),
                spin_deg: self.spin_deg,
                spin_axis,
            }),
        }
    }
}

/// "1st", "2nd", … for messages.
fn ordinal(k: usize) -> String {
    let n = k + 1;
    let suffix = match (n % 10, n % 100) {
        (1, 11) | (2, 12) | (3, 13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}
