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
pub mod cast;
pub mod direct;
pub mod format;
pub mod motion;
pub mod pathtrace;
pub mod precision;
pub mod reference;
pub mod shapes;
pub mod spline;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use glam::DVec3;

use self::bvh::Bvh;
use self::format::{AnalyticKind, RawScene};
use self::motion::Mover;
use self::shapes::{Ball, Triangle};
use crate::geom::Aabb;
use crate::toml_text::de::from_text;

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

impl Scene {
    /// Traverses its hierarchies with `path` from now on (tests and `raycost bench` force each
    /// instruction set; answers do not depend on it).
    pub fn set_bvh_path(&mut self, path: bvh::Path) {
        self.bvh = std::mem::take(&mut self.bvh).with_path(path);
        self.dyn_bvh = std::mem::take(&mut self.dyn_bvh).with_path(path);
    }

    /// The instruction-set path its hierarchies are traversed with.
    pub fn bvh_path(&self) -> bvh::Path {
        self.bvh.path()
    }
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
        // The spec's own reader: located by line, column and dotted key.
        let raw: RawScene = from_text(text).map_err(|e| InputError {
            file: path.display().to_string(),
            at: e.at,
            key: e.key,
            message: e.message,
        })?;
        Ok(Self::assemble(raw.into_parts(path, text)?))
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
        let path = self.bvh.path();
        self.dyn_bvh = Bvh::build(&self.triangles[self.n_static_tris..]).with_path(path);
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
        let n = self.n_static_tris;
        let mut best = self.bvh.two_nearest(o, d, t_min, skip_tri);
        if !self.dyn_bvh.is_empty() {
            // Dynamic triangles after the static ones, in a fixed order: a photon's path depends only
            // on the geometry, never on which frames came before.
            let skip_dyn = skip_tri.wrapping_sub(n as u32);
            let dynamic = self.dyn_bvh.two_nearest(o, d, t_min, skip_dyn);
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
        self.first_hit_before(o, d, t_min, f64::INFINITY, skip)
    }

    /// [`Scene::first_hit`] among the crossings with t < `limit` (None if the nearest is at or
    /// beyond it): boxes beyond `limit` are never opened.
    pub fn first_hit_before(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        limit: f64,
        skip: Option<Prim>,
    ) -> Option<Hit> {
        let skip_tri = match skip {
            Some(Prim::Triangle(i)) => i,
            _ => u32::MAX,
        };
        let n = self.n_static_tris;
        let (mut t, mut id) = self.bvh.nearest_before(o, d, t_min, limit, skip_tri);
        if !self.dyn_bvh.is_empty() {
            let (td, idd) =
                self.dyn_bvh
                    .nearest_before(o, d, t_min, limit, skip_tri.wrapping_sub(n as u32));
            if td < t {
                (t, id) = (td, idd + n as u32);
            }
        }
        let mut prim = Prim::Triangle(id);
        for (i, b) in self.balls.iter().enumerate() {
            if let Some((t0, t1)) = b.roots(o, d) {
                for r in [t0, t1] {
                    if r > t_min && r < t && r < limit {
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

    /// Is there any crossing with t_min < t < `limit` (skipping triangle `skip`)? Exactly
    /// `first_hit_before(o, d, t_min, limit, skip).is_some()`, stopping at the first crossing found
    /// (a shadow ray).
    pub fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64, skip: Option<Prim>) -> bool {
        let skip_tri = match skip {
            Some(Prim::Triangle(i)) => i,
            _ => u32::MAX,
        };
        let n = self.n_static_tris as u32;
        self.balls.iter().any(|b| {
            b.roots(o, d)
                .is_some_and(|(t0, t1)| [t0, t1].iter().any(|&r| r > t_min && r < limit))
        }) || self.bvh.any_before(o, d, t_min, limit, skip_tri)
            || (!self.dyn_bvh.is_empty()
                && self
                    .dyn_bvh
                    .any_before(o, d, t_min, limit, skip_tri.wrapping_sub(n)))
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
