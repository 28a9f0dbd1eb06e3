//! Light-transport scenes: what DETP's photons are traced through. Triangles (quads are two, OBJ
//! meshes many), spheres seen from outside or inside, one grey diffuse albedo per surface, point,
//! spot and area lights with their power, a pinhole camera, and — for validation scenes — the
//! closed form of the irradiance. Only what DETP reads is modelled: no textures, no specular
//! materials.
//!
//! Ray casting answers the nearest hit *and* the second intersection along the same line (a
//! [`bvh::Bvh`] over triangles; spheres, which scenes have few of, are tested directly).

pub mod aff;
pub mod bvh;
pub mod format;
pub mod motion;
pub mod precision;
pub mod reference;
pub mod shapes;
pub mod spline;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use glam::DVec3;

use self::bvh::{Bvh, TwoNearest};
use self::format::{AnalyticKind, LightKind, PathKind, RawScene, SurfaceKind};
use self::motion::{Motion, Mover, MoverPart};
use self::shapes::{Ball, Triangle};
use crate::geom::Aabb;
use crate::toml_text::{find_key, line_col};

pub use crate::error::InputError;

/// Reflections per light path at most, for the photon tracer and the reference alike (albedos below
/// 1 make longer paths vanishingly rare; the photon tracer counts the cut ones).
pub const MAX_BOUNCES: u16 = 64;

/// Material and emission of one surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Label.
    pub name: String,
    /// Diffuse albedo in [0, 1).
    pub albedo: f64,
    /// Emitted radiance (0: not a light).
    pub emission: f64,
}

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light.
    Point {
        /// Position.
        position: DVec3,
        /// Power.
        power: f64,
    },
    /// Point light emitting uniformly into a cone.
    Spot {
        /// Position.
        position: DVec3,
        /// Unit axis.
        axis: DVec3,
        /// cos of the half-angle.
        cos_cone: f64,
        /// Power.
        power: f64,
    },
    /// The emitting primitives of one surface (Lambertian, power π·L_e·area).
    Area {
        /// Surface index.
        surface: u32,
        /// Triangles of the surface (empty for a sphere).
        triangles: Vec<u32>,
        /// The sphere, if the surface is one.
        ball: Option<u32>,
        /// Power.
        power: f64,
    },
}

impl Light {
    /// Its power.
    pub fn power(&self) -> f64 {
        match self {
            Light::Point { power, .. } | Light::Spot { power, .. } | Light::Area { power, .. } => {
                *power
            }
        }
    }
}

/// A pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye.
    pub eye: DVec3,
    /// Point looked at.
    pub look_at: DVec3,
    /// Up.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub fov_deg: f64,
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
}

/// The primitive a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prim {
    /// A triangle (index).
    Triangle(u32),
    /// A sphere (index).
    Ball(u32),
}

/// The nearest hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    /// What was hit.
    pub prim: Prim,
    /// Surface index.
    pub surface: u32,
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Triangles.
    pub triangles: Vec<Triangle>,
    /// Spheres.
    pub balls: Vec<Ball>,
    /// Surfaces.
    pub surfaces: Vec<Surface>,
    /// Lights (point, spot, area).
    pub lights: Vec<Light>,
    /// Camera, if the file has one.
    pub camera: Option<Camera>,
    /// Closed form, if declared.
    pub analytic: Option<AnalyticKind>,
    /// Things skipped with a warning (degenerate triangles).
    pub warnings: Vec<String>,
    /// Dynamic objects. Their geometry at the current pose follows the static geometry in
    /// `triangles` and `balls` (see [`Scene::set_tau`]).
    pub movers: Vec<Mover>,
    /// Static triangles: `triangles[..n_static_tris]`.
    pub n_static_tris: usize,
    /// Static spheres: `balls[..n_static_balls]`.
    pub n_static_balls: usize,
    /// Files read besides the scene file itself (OBJ meshes, AFF includes), with their role.
    sources: Vec<(PathBuf, &'static str)>,
    /// The movers' pose (normalised time), NaN before the first [`Scene::set_tau`].
    tau: f64,
    bvh: Bvh,
    /// Over the posed dynamic triangles (ids relative to `n_static_tris`), rebuilt at each pose.
    dyn_bvh: Bvh,
    bounds: Aabb,
}

/// What a scene is made of, before its hierarchy and bounds are built (from a TOML scene file or an
/// AFF file).
#[derive(Debug, Default)]
pub struct SceneParts {
    /// Static triangles.
    pub triangles: Vec<Triangle>,
    /// Static spheres.
    pub balls: Vec<Ball>,
    /// Surfaces.
    pub surfaces: Vec<Surface>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Camera.
    pub camera: Option<Camera>,
    /// Closed form.
    pub analytic: Option<AnalyticKind>,
    /// Warnings so far.
    pub warnings: Vec<String>,
    /// Dynamic objects.
    pub movers: Vec<Mover>,
    /// Files read besides the scene file itself (OBJ meshes, AFF includes), with their role.
    pub sources: Vec<(PathBuf, &'static str)>,
}

impl Scene {
    /// Reads a scene file: TOML (OBJ paths are relative to it), or AFF/NFF (`.aff`, `.nff`: BART
    /// scenes, includes relative to it).
    pub fn load(path: &Path) -> Result<Scene, InputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if matches!(ext.as_deref(), Some("aff" | "nff")) {
            let parts = aff::load_aff(path)?.into_parts();
            if parts.lights.is_empty() {
                return Err(InputError {
                    file: path.display().to_string(),
                    at: None,
                    key: Some("l".into()),
                    message: "the scene has no light: add a point light `l X Y Z`".into(),
                });
            }
            return Ok(Self::assemble(parts));
        }
        let text = std::fs::read_to_string(path).map_err(|e| InputError {
            file: path.display().to_string(),
            at: None,
            key: None,
            message: format!("cannot read the scene file: {e}"),
        })?;
        Self::parse(&text, path)
    }

    /// A TOML scene from its text; `path` names it in errors and anchors relative OBJ paths.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, InputError> {
        let name = path.display().to_string();
        let de = toml::Deserializer::new(text);
        let raw: RawScene = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            InputError {
                file: name.clone(),
                at: inner.span().map(|s| line_col(text, s.start)),
                key: (!key.is_empty() && key != ".").then_some(key),
                message: inner.message().trim().to_string(),
            }
        })?;
        Self::from_raw(raw, path, text)
    }

    fn from_raw(raw: RawScene, path: &Path, text: &str) -> Result<Scene, InputError> {
        let name = path.display().to_string();
        let err = |key: String, message: String| InputError {
            file: name.clone(),
            at: find_key(text, &key).filter(|_| !key.is_empty()),
            key: Some(key),
            message,
        };
        let dir = path.parent().unwrap_or(Path::new(""));
        let (mut triangles, mut balls, mut surfaces) = (Vec::new(), Vec::new(), Vec::new());
        let mut warnings = Vec::new();
        let mut lights = Vec::new();
        let mut sources = Vec::new();
        // Geometry of each [[dynamic]] object, gathered from the surfaces naming it.
        let mut moving: Vec<(Vec<Triangle>, Vec<Ball>)> =
            vec![Default::default(); raw.dynamic.len()];
        for (si, s) in raw.surface.iter().enumerate() {
            let key = |k: &str| format!("surface[{si}].{k}");
            let id = si as u32;
            let first = triangles.len();
            let label = s.name.clone().unwrap_or_else(|| format!("surface {si}"));
            let v: Vec<DVec3> = s.vertices.iter().map(|&p| DVec3::from_array(p)).collect();
            let need = |n: usize| {
                if v.len() == n {
                    Ok(())
                } else {
                    Err(err(
                        key("vertices"),
                        format!("a {:?} needs {n} vertices, got {}", s.kind, v.len())
                            .to_lowercase(),
                    ))
                }
            };
            match s.kind {
                SurfaceKind::Triangle => {
                    need(3)?;
                    triangles.push(Triangle {
                        v: [v[0], v[1], v[2]],
                        surface: id,
                    });
                }
                SurfaceKind::Quad => {
                    need(4)?;
                    // A quad is split along v0–v2: it must be planar and its vertices in order
                    // around it, or the two halves are not the quad the user meant.
                    let n1 = (v[1] - v[0]).cross(v[2] - v[0]);
                    let n2 = (v[2] - v[0]).cross(v[3] - v[0]);
                    let size = (v[2] - v[0]).length().max((v[3] - v[1]).length());
                    if n1.length() > 0.0 && n2.length() > 0.0 {
                        // Measured data is not exactly planar (the Cornell box's walls are off by
                        // 0.4 % of their size, as published): up to 1 % of the quad's size is
                        // accepted as measurement error, beyond it the quad is refused.
                        let off = (v[3] - v[0]).dot(n1.normalize()).abs();
                        if off > 0.01 * size {
                            return Err(err(
                                key("vertices"),
                                format!("the quad is not planar: its 4th vertex is {off:.3e} off the plane of the first three, over 1 % of its size {size:.3e} (split it into two triangles)"),
                            ));
                        }
                        if n1.dot(n2) < 0.0 {
                            return Err(err(
                                key("vertices"),
                                "the quad's vertices are not in order around it (a bow-tie): list them along its edge".into(),
                            ));
                        }
                    }
                    triangles.push(Triangle {
                        v: [v[0], v[1], v[2]],
                        surface: id,
                    });
                    triangles.push(Triangle {
                        v: [v[0], v[2], v[3]],
                        surface: id,
                    });
                }
                SurfaceKind::Sphere => {
                    let (Some(c), Some(r)) = (s.center, s.radius) else {
                        return Err(err(
                            key("radius"),
                            "a sphere needs center and radius".into(),
                        ));
                    };
                    balls.push(Ball {
                        center: DVec3::from_array(c),
                        radius: r,
                        inside: s.inside,
                        surface: id,
                    });
                }
                SurfaceKind::Obj => {
                    let Some(p) = &s.path else {
                        return Err(err(key("path"), "an obj surface needs a path".into()));
                    };
                    let file: PathBuf = dir.join(p);
                    if let Err(why) = crate::error::regular_input(&file) {
                        return Err(err(key("path"), format!("{}: {why}", file.display())));
                    }
                    sources.push((file.clone(), "obj"));
                    let (models, _) = tobj::load_obj(
                        &file,
                        &tobj::LoadOptions {
                            triangulate: true,
                            single_index: true,
                            ..Default::default()
                        },
                    )
                    .map_err(|e| InputError {
                        file: file.display().to_string(),
                        at: None,
                        key: None,
                        message: format!(
                            "cannot read this OBJ (named by {name}, {}): {e}",
                            key("path")
                        ),
                    })?;
                    if models.iter().all(|m| m.mesh.indices.len() < 3) {
                        return Err(InputError {
                            file: file.display().to_string(),
                            at: None,
                            key: None,
                            message: format!(
                                "the OBJ (named by {name}, {}) has no faces",
                                key("path")
                            ),
                        });
                    }
                    for m in models {
                        let p = &m.mesh.positions;
                        let vert = |i: u32| {
                            let i = i as usize * 3;
                            DVec3::new(f64::from(p[i]), f64::from(p[i + 1]), f64::from(p[i + 2]))
                        };
                        for f in m.mesh.indices.chunks_exact(3) {
                            triangles.push(Triangle {
                                v: [vert(f[0]), vert(f[1]), vert(f[2])],
                                surface: id,
                            });
                        }
                    }
                }
            }
            // Degenerate triangles are skipped and counted, never traced.
            let before = triangles.len();
            let kept: Vec<Triangle> = triangles
                .drain(first..)
                .filter(|t| !t.degenerate())
                .collect();
            if kept.len() < before - first {
                warnings.push(format!(
                    "{name}: {label}: skipped {} degenerate triangle(s) (zero area or not finite)",
                    before - first - kept.len()
                ));
            }
            let (kept, duplicates) = shapes::without_duplicates(kept);
            if duplicates > 0 {
                warnings.push(format!(
                    "{name}: {label}: skipped {duplicates} duplicate triangle(s) (the same three \
                     vertices, wound the same way, as another triangle of this surface)"
                ));
            }
            triangles.extend(kept);
            if let Some(dname) = &s.dynamic {
                let Some(k) = raw.dynamic.iter().position(|d| &d.name == dname) else {
                    return Err(err(
                        key("dynamic"),
                        format!("no [[dynamic]] object is named \"{dname}\""),
                    ));
                };
                if s.emission.is_some() {
                    return Err(err(
                        key("emission"),
                        "a dynamic surface cannot emit (lights are static)".into(),
                    ));
                }
                moving[k].0.extend(triangles.drain(first..));
                if s.kind == SurfaceKind::Sphere {
                    moving[k].1.extend(balls.pop());
                }
            }
            if let Some(le) = s.emission {
                let tris: Vec<u32> = (first as u32..triangles.len() as u32).collect();
                let ball = (s.kind == SurfaceKind::Sphere).then(|| balls.len() as u32 - 1);
                let area: f64 = tris
                    .iter()
                    .map(|&t| triangles[t as usize].area())
                    .sum::<f64>()
                    + ball.map_or(0.0, |b| balls[b as usize].area());
                if area <= 0.0 {
                    return Err(err(
                        key("emission"),
                        "an emitting surface has no area".into(),
                    ));
                }
                lights.push(Light::Area {
                    surface: id,
                    triangles: tris,
                    ball,
                    power: PI * le * area,
                });
            }
            surfaces.push(Surface {
                name: label,
                albedo: s.albedo,
                emission: s.emission.unwrap_or(0.0),
            });
        }
        for (li, l) in raw.light.iter().enumerate() {
            let position = DVec3::from_array(l.position);
            lights.push(match l.kind {
                LightKind::Point => Light::Point {
                    position,
                    power: l.power,
                },
                LightKind::Spot => {
                    let (Some(dir), Some(cone)) = (l.direction, l.cone_deg) else {
                        return Err(err(
                            format!("light[{li}].direction"),
                            "a spot light needs direction and cone_deg".into(),
                        ));
                    };
                    let axis = DVec3::from_array(dir);
                    if axis.length() == 0.0 || cone > 180.0 {
                        return Err(err(
                            format!("light[{li}].cone_deg"),
                            "a spot needs a non-zero direction and cone_deg in (0, 180]".into(),
                        ));
                    }
                    Light::Spot {
                        position,
                        axis: axis.normalize(),
                        cos_cone: cone.to_radians().cos(),
                        power: l.power,
                    }
                }
            });
        }
        if lights.is_empty() {
            return Err(err(
                "light".into(),
                "the scene has no light: add a [[light]] or a surface with emission > 0".into(),
            ));
        }
        if triangles.is_empty() && balls.is_empty() {
            return Err(err("surface".into(), "the scene has no surface".into()));
        }
        let analytic = raw.analytic.map(|a| a.kind);
        match analytic {
            Some(AnalyticKind::PointOverPlane)
                if !lights.iter().any(|l| matches!(l, Light::Point { .. })) =>
            {
                return Err(err(
                    "analytic.kind".into(),
                    "point-over-plane needs a point light".into(),
                ));
            }
            Some(AnalyticKind::ClosedSphere)
                if !balls
                    .iter()
                    .any(|b| b.inside && surfaces[b.surface as usize].emission > 0.0) =>
            {
                return Err(err(
                    "analytic.kind".into(),
                    "closed-sphere needs an emitting sphere seen from inside".into(),
                ));
            }
            Some(AnalyticKind::DirectLight)
                if surfaces.iter().any(|s| s.albedo != 0.0)
                    || lights.iter().any(|l| matches!(l, Light::Area { .. })) =>
            {
                return Err(err(
                    "analytic.kind".into(),
                    "direct-light needs every albedo 0 and point or spot lights only (no emitting surface): then the irradiance is the lights' direct light".into(),
                ));
            }
            _ => {}
        }
        let camera = raw.camera.map(|c| Camera {
            eye: DVec3::from_array(c.eye),
            look_at: DVec3::from_array(c.look_at),
            up: DVec3::from_array(c.up),
            fov_deg: c.fov_deg,
            width: c.width,
            height: c.height,
        });
        let mut movers = Vec::new();
        for (k, d) in raw.dynamic.iter().enumerate() {
            if let Some(first) = raw.dynamic[..k].iter().position(|e| e.name == d.name) {
                return Err(err(
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
        for (k, (d, (tris, bls))) in raw.dynamic.iter().zip(moving).enumerate() {
            let key = |f: &str| format!("dynamic[{k}].{f}");
            if tris.is_empty() && bls.is_empty() {
                return Err(err(
                    key("name"),
                    format!("no surface names dynamic = \"{}\"", d.name),
                ));
            }
            let unit = |v: Option<[f64; 3]>, f: &str| -> Result<DVec3, InputError> {
                let a = DVec3::from_array(v.unwrap_or([0.0, 1.0, 0.0]));
                if a.length() > 0.0 {
                    Ok(a.normalize())
                } else {
                    Err(err(key(f), "an axis must be non-zero".into()))
                }
            };
            let spin_axis = unit(d.spin_axis, "spin_axis")?;
            let motion = match d.path {
                PathKind::Circle => {
                    let (Some(c), Some(r)) = (d.center, d.radius) else {
                        return Err(err(
                            key("path"),
                            "a circle path needs center and radius".into(),
                        ));
                    };
                    Motion::Circle {
                        center: DVec3::from_array(c),
                        radius: r,
                        axis: unit(d.axis, "axis")?,
                        turns: d.turns,
                        spin_deg: d.spin_deg,
                        spin_axis,
                    }
                }
                PathKind::Line => {
                    if d.points.len() < 2 {
                        return Err(err(
                            key("points"),
                            "a line path needs at least two points".into(),
                        ));
                    }
                    Motion::Path {
                        points: d.points.iter().map(|&p| DVec3::from_array(p)).collect(),
                        spin_deg: d.spin_deg,
                        spin_axis,
                    }
                }
            };
            movers.push(Mover::new(
                d.name.clone(),
                vec![MoverPart {
                    triangles: tris,
                    balls: bls,
                    motion,
                }],
            ));
        }
        Ok(Self::assemble(SceneParts {
            triangles,
            balls,
            surfaces,
            lights,
            camera,
            analytic,
            warnings,
            movers,
            sources,
        }))
    }

    /// Files read besides the scene file itself (OBJ meshes, AFF includes), with their role
    /// (`obj`, `aff`): their content is part of the scene a result depends on.
    pub fn sources(&self) -> Vec<(PathBuf, &'static str)> {
        self.sources.clone()
    }

    /// Builds the hierarchy and bounds over `parts` (static geometry and lights; the movers stay
    /// unposed until [`Scene::set_tau`]).
    pub fn assemble(parts: SceneParts) -> Scene {
        let SceneParts {
            triangles,
            balls,
            surfaces,
            lights,
            camera,
            analytic,
            warnings,
            movers,
            sources,
        } = parts;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in &triangles {
            let (a, b) = t.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        for b in &balls {
            lo = lo.min(b.center - DVec3::splat(b.radius));
            hi = hi.max(b.center + DVec3::splat(b.radius));
        }
        for l in &lights {
            if let Light::Point { position, .. } | Light::Spot { position, .. } = l {
                lo = lo.min(*position);
                hi = hi.max(*position);
            }
        }
        let bvh = Bvh::build(&triangles);
        Scene {
            n_static_tris: triangles.len(),
            n_static_balls: balls.len(),
            triangles,
            balls,
            surfaces,
            lights,
            camera,
            analytic,
            warnings,
            movers,
            sources,
            tau: f64::NAN,
            bvh,
            dyn_bvh: Bvh::default(),
            bounds: Aabb::new(lo, hi),
        }
    }

    /// Poses every mover at normalised time τ: their world geometry replaces the previous pose's
    /// after the static geometry, and the dynamic hierarchy is rebuilt. A pure function of τ.
    pub fn set_tau(&mut self, tau: f64) {
        if self.tau == tau || self.movers.is_empty() {
            self.tau = tau;
            return;
        }
        self.triangles.truncate(self.n_static_tris);
        self.balls.truncate(self.n_static_balls);
        for m in &self.movers {
            let p = m.posed(tau);
            self.triangles.extend(p.triangles);
            self.balls.extend(p.balls);
        }
        self.dyn_bvh = Bvh::build(&self.triangles[self.n_static_tris..]);
        self.tau = tau;
    }

    /// The current pose (NaN before the first [`Scene::set_tau`]).
    pub fn tau(&self) -> f64 {
        self.tau
    }

    /// Static geometry only: (triangles, spheres).
    pub fn static_geometry(&self) -> (&[Triangle], &[Ball]) {
        (
            &self.triangles[..self.n_static_tris],
            &self.balls[..self.n_static_balls],
        )
    }

    /// The box around all geometry and lights.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Total emitted power.
    pub fn total_power(&self) -> f64 {
        self.lights.iter().map(Light::power).sum()
    }

    /// Largest coordinate magnitude (sets self-intersection epsilons).
    pub fn magnitude(&self) -> f64 {
        self.bounds.magnitude().max(1e-300)
    }

    /// The scene's coordinate magnitude and size, and the tolerances they allow
    /// ([`precision::Precision`]).
    pub fn precision(&self) -> precision::Precision {
        precision::Precision::of(&self.bounds)
    }

    /// The nearest hit with t > t_min (skipping triangle `skip`, the one a photon leaves) and the
    /// next intersection beyond it along the same line (+∞ if none).
    pub fn first_two_hits(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: Option<Prim>,
    ) -> (Option<Hit>, f64) {
        let skip_tri = match skip {
            Some(Prim::Triangle(i)) => i,
            _ => u32::MAX,
        };
        let mut best = TwoNearest::default();
        let n = self.n_static_tris;
        self.bvh
            .two_nearest(&self.triangles[..n], o, d, t_min, skip_tri, &mut best);
        if !self.dyn_bvh.is_empty() {
            // Dynamic triangles after the static ones, in a fixed order: a photon's path depends only
            // on the geometry, never on which frames came before.
            let mut dynamic = TwoNearest::default();
            let skip_dyn = skip_tri.wrapping_sub(n as u32);
            self.dyn_bvh
                .two_nearest(&self.triangles[n..], o, d, t_min, skip_dyn, &mut dynamic);
            for (t, id) in [dynamic.first, dynamic.second] {
                if t.is_finite() {
                    best.offer(t, id + n as u32);
                }
            }
        }
        // Spheres: ids above the triangles' (offset), both roots.
        let offset = self.triangles.len() as u32;
        for (i, b) in self.balls.iter().enumerate() {
            if let Some((t0, t1)) = b.roots(o, d) {
                for t in [t0, t1] {
                    if t > t_min {
                        best.offer(t, offset + i as u32);
                    }
                }
            }
        }
        let (t, id) = best.first;
        if !t.is_finite() {
            return (None, f64::INFINITY);
        }
        let prim = if id < offset {
            Prim::Triangle(id)
        } else {
            Prim::Ball(id - offset)
        };
        let surface = match prim {
            Prim::Triangle(i) => self.triangles[i as usize].surface,
            Prim::Ball(i) => self.balls[i as usize].surface,
        };
        (Some(Hit { t, prim, surface }), best.second.0)
    }

    /// The nearest hit with t > t_min, skipping triangle `skip`: the first hit of
    /// [`Scene::first_two_hits`] for the same ray, found without the second (cheaper: a path tracer
    /// needs only this).
    pub fn first_hit(&self, o: DVec3, d: DVec3, t_min: f64, skip: Option<Prim>) -> Option<Hit> {
        let skip_tri = match skip {
            Some(Prim::Triangle(i)) => i,
            _ => u32::MAX,
        };
        let n = self.n_static_tris;
        let (mut t, mut id) = self
            .bvh
            .nearest(&self.triangles[..n], o, d, t_min, skip_tri);
        if !self.dyn_bvh.is_empty() {
            let (td, idd) = self.dyn_bvh.nearest(
                &self.triangles[n..],
                o,
                d,
                t_min,
                skip_tri.wrapping_sub(n as u32),
            );
            if td < t {
                (t, id) = (td, idd + n as u32);
            }
        }
        let mut prim = Prim::Triangle(id);
        for (i, b) in self.balls.iter().enumerate() {
            if let Some((t0, t1)) = b.roots(o, d) {
                for r in [t0, t1] {
                    if r > t_min && r < t {
                        t = r;
                        prim = Prim::Ball(i as u32);
                    }
                }
            }
        }
        if !t.is_finite() {
            return None;
        }
        let surface = match prim {
            Prim::Triangle(i) => self.triangles[i as usize].surface,
            Prim::Ball(i) => self.balls[i as usize].surface,
        };
        Some(Hit { t, prim, surface })
    }

    /// Calls `f` with every triangle (static or dynamic, by its index in `triangles`) that may
    /// come within `r` of `p` (a superset: the caller measures each).
    pub fn triangles_near(&self, p: DVec3, r: f64, f: &mut dyn FnMut(u32)) {
        let n = self.n_static_tris as u32;
        self.bvh.near(p, r, f);
        self.dyn_bvh.near(p, r, &mut |i| f(i + n));
    }

    /// The normal that receives light at a point of a primitive.
    pub fn normal(&self, prim: Prim, p: DVec3) -> DVec3 {
        match prim {
            Prim::Triangle(i) => self.triangles[i as usize].normal(),
            Prim::Ball(i) => self.balls[i as usize].normal_at(p),
        }
    }

    /// The exact irradiance at point `p` with normal `n`, for scenes that declare a closed form.
    pub fn exact_irradiance(&self, p: DVec3, n: DVec3) -> Option<f64> {
        match self.analytic? {
            AnalyticKind::PointOverPlane => {
                let (pos, power) = self.lights.iter().find_map(|l| match l {
                    Light::Point { position, power } => Some((*position, *power)),
                    _ => None,
                })?;
                let v = pos - p;
                let r = v.length();
                Some(power * n.normalize().dot(v).max(0.0) / (4.0 * PI * r * r * r))
            }
            AnalyticKind::ClosedSphere => {
                let b = self
                    .balls
                    .iter()
                    .find(|b| b.inside && self.surfaces[b.surface as usize].emission > 0.0)?;
                let s = &self.surfaces[b.surface as usize];
                Some(PI * s.emission / (1.0 - s.albedo))
            }
            AnalyticKind::DirectLight => Some(self.direct_light(p, n)),
        }
    }

    /// The direct irradiance at `p` (normal `n`) from the point and spot lights, with a shadow test:
    /// a light counts if the first surface its ray toward `p` meets lies no nearer than `p` (less a
    /// relative 10⁻⁹ of the scene's size, so that the surface `p` lies on does not shadow it).
    pub fn direct_light(&self, p: DVec3, n: DVec3) -> f64 {
        let n = n.normalize();
        let tol = self.precision().offset();
        let mut e = 0.0;
        for l in &self.lights {
            let (pos, intensity) = match l {
                Light::Point { position, power } => (*position, power / (4.0 * PI)),
                Light::Spot {
                    position,
                    axis,
                    cos_cone,
                    power,
                } => {
                    let dir = (p - *position).normalize();
                    if dir.dot(*axis) < *cos_cone {
                        continue;
                    }
                    (*position, power / (2.0 * PI * (1.0 - cos_cone)))
                }
                Light::Area { .. } => continue,
            };
            let v = pos - p;
            let r = v.length();
            let cos = n.dot(v) / r;
            if cos.is_nan() || cos <= 0.0 {
                continue;
            }
            let (hit, _) = self.first_two_hits(pos, -v / r, 0.0, None);
            if hit.is_some_and(|h| h.t < r - tol) {
                continue;
            }
            e += intensity * cos / (r * r);
        }
        e
    }
}

/// "1st", "2nd", … for the k-th (0-based) table.
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
