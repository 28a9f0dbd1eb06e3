//! A reader for AFF, the animated scene format of BART ("BART: A Benchmark for Animated Ray
//! Tracing", Lext, Assarsson & Möller, IEEE CG&A 21(2), 2001), and for plain NFF, its subset.
//!
//! What is read, per directive (free format: numbers may wrap over lines; `%` and `#` start
//! comments anywhere a token may start; CRLF and non-UTF-8 comment bytes are fine):
//!
//! | directive | meaning | kept as |
//! |---|---|---|
//! | `b R G B` | background | ignored |
//! | `v` + `from`/`at`/`up`/`angle`/`hither`/`resolution` | viewpoint | [`Camera`] (`angle` = vertical fov) |
//! | `am R G B` | ambient light | ignored |
//! | `l X Y Z [R G B]` | point light | [`Light::Point`], power = mean(R,G,B) (1 without colour) |
//! | `f R G B Kd Ks Shine T ior` | NFF material | [`Surface`], albedo = mean(RGB)·Kd |
//! | `fm amb(3) diff(3) spec(3) Shine T ior` | AFF material | [`Surface`], albedo = mean(diffuse RGB) |
//! | `p N` + N points, `pp N` + N (point normal) | polygon | fan of triangles |
//! | `s X Y Z R` | sphere | tessellated: 24 × 12 triangles (so it can move like any geometry) |
//! | `c` base r0 apex r1 | open cone/cylinder | tessellated: 24 quads, counted warning |
//! | `m` + `vertices`/`normals`/`texturecoords N TEX`/`triangles` | mesh | triangles (`v0 v1 v2 [n0 n1 n2] [t0 t1 t2]` per triangle) |
//! | `tt TEX` + 3 (point u v), `ttp TEX` + 3 (point normal u v) | textured triangle | triangle, texture ignored (counted warning) |
//! | `tpa N` + N (time, 3 × (point normal)) | animated triangle | [`AnimatedPatch`], linear in time as BART's renderer does |
//! | `xs` scale(3) axis(3) angle° translation(3) `{ … }` | static transform `T·R·S` | applied to the geometry |
//! | `x NAME { … }` | keyframed transform | [`AffMover`] / [`MoverPart`] chains |
//! | `k NAME { transl/rot/scale/visibility … }` | keyframes | [`spline::KbTransform`] (visibility ignored, warned) |
//! | `a START END FRAMES` | animation range | `time` |
//! | `i DETAIL FILE` | include | relative to the including file's folder, else the top file's folder |
//!
//! Albedos are clamped into [0, 0.95]; emission is 0 (AFF lights are points). Materials are
//! global state as in BART's parser (an `fm` inside a block stays in force after its `}`); every
//! `fm`/`f` occurrence is a surface of its own, named `material N (file:line)`. Degenerate
//! triangles (zero area) are dropped with a counted warning. `k camera` (BART's animated camera)
//! is kept as [`AffScene::camera_animation`]. Anything else — an unknown directive, a wrong count
//! of numbers, a non-numeric token, an index out of range, a missing include, an unterminated `{` —
//! is a [`InputError`] naming the file at fault, the line and column, and the directive.

//!
//! The reader is [`lexer`] (tokens with line and column, and the typed reads of one directive's
//! arguments) and [`parse`] (one function per directive); the scene builder is [`build`] (blocks,
//! materials, movers, tessellation, and the finished [`AffScene`]).

mod build;
mod lexer;
mod parse;

use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::DVec3;

use self::build::Loader;
use super::shapes::Triangle;
use super::spline::{self, KbTrack, KbTransform, Node};
use super::{Camera, InputError, Light, Surface};

/// Where BART scenes live and what they are, for the "file not found" message.
pub const BART_HINT: &str = "BART scenes come with raycost in experiments/scenes/bart/ (BART: A \
Benchmark for Animated Ray Tracing, Lext, Assarsson & Möller 2001), e.g. \
experiments/scenes/bart/kitchen/kitchen.aff";

/// A scene read from an AFF/NFF file.
#[derive(Clone, Debug, Default)]
pub struct AffScene {
    /// Static geometry in world coordinates; `surface` indexes `surfaces`.
    pub triangles: Vec<Triangle>,
    /// One per material directive (`fm`, `f`), plus a default one if geometry precedes them all.
    pub surfaces: Vec<Surface>,
    /// Point lights.
    pub lights: Vec<Light>,
    /// The `v` viewpoint.
    pub camera: Option<Camera>,
    /// Keyframed objects: one per outermost `x NAME` block that holds geometry.
    pub movers: Vec<AffMover>,
    /// BART's animated triangles (`tpa`): the museum's art piece.
    pub patches: Vec<AnimatedPatch>,
    /// `a START END FRAMES`.
    pub time: Option<(f64, f64, u32)>,
    /// `k camera`: BART's camera path (translation = eye; rotation: looks along −z, y up).
    pub camera_animation: Option<KbTransform>,
    /// Counted warnings (textures ignored, cones tessellated, degenerate triangles, …).
    pub warnings: Vec<String>,
    /// The files it included (`i`), sorted: their content is part of the scene.
    pub includes: Vec<PathBuf>,
}

/// The geometry under one outermost `x NAME` block.
#[derive(Clone, Debug)]
pub struct AffMover {
    /// The name of the outermost animated transform.
    pub name: String,
    /// Its geometry, grouped by innermost animated node.
    pub parts: Vec<MoverPart>,
}

/// Triangles that move together.
#[derive(Clone, Debug)]
pub struct MoverPart {
    /// In the coordinates of the innermost animated node (static transforms inside it applied).
    pub triangles: Vec<Triangle>,
    /// Outermost first: merged static transforms and the animated ones enclosing the triangles;
    /// world = `spline::compose(&chain, t).transform_point3(v)`.
    pub chain: Vec<Node>,
}

/// A BART animated triangle (`tpa`): vertex positions at key times, linear in between, clamped.
#[derive(Clone, Debug)]
pub struct AnimatedPatch {
    /// Surface index.
    pub surface: u32,
    /// Key times (non-decreasing).
    pub times: Vec<f64>,
    /// Vertices at each key time, in the coordinates of `chain`'s innermost node (world if empty).
    pub vertices: Vec<[DVec3; 3]>,
    /// Enclosing transforms, outermost first.
    pub chain: Vec<Node>,
}

impl AnimatedPatch {
    /// The triangle at `time` in world coordinates.
    pub fn at(&self, time: f64) -> Triangle {
        let n = self.times.len();
        let v = if n == 0 {
            [DVec3::ZERO; 3]
        } else if time.is_nan() || time <= self.times[0] {
            self.vertices[0]
        } else if time >= self.times[n - 1] {
            self.vertices[n - 1]
        } else {
            let i = self.times.partition_point(|&t| t <= time).clamp(1, n - 1);
            let (t0, t1) = (self.times[i - 1], self.times[i]);
            let u = if t1 > t0 {
                (time - t0) / (t1 - t0)
            } else {
                1.0
            };
            let (a, b) = (self.vertices[i - 1], self.vertices[i]);
            [a[0].lerp(b[0], u), a[1].lerp(b[1], u), a[2].lerp(b[2], u)]
        };
        let m = spline::compose(&self.chain, time);
        Triangle {
            v: v.map(|p| m.transform_point3(p)),
            surface: self.surface,
        }
    }
}

impl MoverPart {
    /// Its triangles in world coordinates at `time`.
    pub fn triangles_at(&self, time: f64) -> impl Iterator<Item = Triangle> + '_ {
        let m = spline::compose(&self.chain, time);
        self.triangles.iter().map(move |t| Triangle {
            v: t.v.map(|p| m.transform_point3(p)),
            surface: t.surface,
        })
    }
}

impl AffMover {
    /// All its triangles in world coordinates at `time`.
    pub fn triangles_at(&self, time: f64) -> Vec<Triangle> {
        self.parts
            .iter()
            .flat_map(|p| p.triangles_at(time))
            .collect()
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.parts.iter().map(|p| p.triangles.len()).sum()
    }

    /// Has it no triangles?
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl AffScene {
    /// Triangles that move (movers and animated patches).
    pub fn dynamic_len(&self) -> usize {
        self.movers.iter().map(AffMover::len).sum::<usize>() + self.patches.len()
    }

    /// Every triangle in world coordinates at `time`: static, then movers, then patches.
    pub fn triangles_at(&self, time: f64) -> Vec<Triangle> {
        let mut out = self.triangles.clone();
        for m in &self.movers {
            for p in &m.parts {
                out.extend(p.triangles_at(time));
            }
        }
        out.extend(self.patches.iter().map(|p| p.at(time)));
        out
    }
}

impl AffScene {
    /// The scene's parts for [`super::Scene::assemble`]: static triangles, surfaces, point lights,
    /// the camera, and one dynamic object per mover, keyframed over the animation range `a START
    /// END` (or the keys' range). BART's animated triangles (`tpa`, the museum's art piece) deform
    /// rather than move rigidly: they are frozen at the start time, with a counted warning.
    pub fn into_parts(self) -> super::SceneParts {
        use super::motion::{Motion, Mover, MoverPart as Part};
        let (start, end) = self.time.map_or_else(
            || {
                self.movers
                    .iter()
                    .flat_map(|m| &m.parts)
                    .flat_map(|p| &p.chain)
                    .filter_map(|n| match n {
                        Node::Animated { kb, .. } => Some(kb),
                        Node::Fixed(_) => None,
                    })
                    .flat_map(|kb| {
                        [
                            kb.translate.as_ref().map(KbTrack::active_range),
                            kb.rotate.as_ref().map(KbTrack::active_range),
                            kb.scale.as_ref().map(KbTrack::active_range),
                        ]
                    })
                    .flatten()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (c, d)| {
                        (a.min(c), b.max(d))
                    })
            },
            |(a, b, _)| (a, b),
        );
        let (start, end) = if start.is_finite() {
            (start, end)
        } else {
            (0.0, 0.0)
        };
        let (mut triangles, duplicates) = super::shapes::without_duplicates(self.triangles);
        let mut warnings = self.warnings;
        if duplicates > 0 {
            warnings.push(format!(
                "{duplicates} duplicate triangle(s) skipped (the same three vertices, wound the same \
                 way and of the same material, as another)"
            ));
        }
        if !self.patches.is_empty() {
            warnings.push(format!(
                "{} animated triangle(s) (tpa) deform rather than move rigidly: frozen at t = {start}",
                self.patches.len()
            ));
            triangles.extend(self.patches.iter().map(|p| p.at(start)));
        }
        let movers = self
            .movers
            .into_iter()
            .map(|m| {
                let parts = m
                    .parts
                    .into_iter()
                    .map(|p| Part {
                        triangles: p.triangles,
                        balls: Vec::new(),
                        motion: Motion::Keyframed {
                            chain: p.chain,
                            start,
                            end,
                        },
                    })
                    .collect();
                Mover::keyframed(m.name, parts)
            })
            .collect();
        super::SceneParts {
            triangles,
            balls: Vec::new(),
            surfaces: self.surfaces,
            lights: self.lights,
            camera: self.camera,
            analytic: None,
            warnings,
            movers,
            sources: self.includes.into_iter().map(|p| (p, "aff")).collect(),
        }
    }
}

/// Reads an AFF or NFF scene (with its includes).
pub fn load_aff(path: &Path) -> Result<AffScene, InputError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| InputError {
        file: name.clone(),
        at: None,
        key: None,
        message: format!("cannot read the AFF scene file ({e}); {BART_HINT}"),
    })?;
    let root = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut ld = Loader::new(root);
    ld.file(path, Rc::from(bytes), 0)?;
    let mut includes: Vec<PathBuf> = ld.cache.keys().cloned().collect();
    includes.sort();
    let mut scene = ld.finish();
    scene.includes = includes;
    Ok(scene)
}

/// Parses AFF text given in memory (`name` labels errors; includes are relative to `dir`).
pub fn parse_aff(text: &str, name: &Path) -> Result<AffScene, InputError> {
    let root = name.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut ld = Loader::new(root);
    ld.file(name, Rc::from(text.as_bytes()), 0)?;
    Ok(ld.finish())
}

#[cfg(test)]
mod tests {
    use super::build::ROUND;
    use super::*;

    /// The vendored BART scenes (experiments/scenes/bart/README.md).
    const BART: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/experiments/scenes/bart");

    fn bart(rel: &str) -> Option<AffScene> {
        let p = Path::new(BART).join(rel);
        assert!(p.is_file(), "{} is vendored with raycost", p.display());
        let t0 = std::time::Instant::now();
        let s = load_aff(&p).unwrap_or_else(|e| panic!("{e}"));
        eprintln!(
            "{rel}: {} static, {} dynamic ({} movers, {} parts, {} patches), {} lights, {} surfaces, time {:?}, camera {}, {:.3} s; warnings {:?}",
            s.triangles.len(),
            s.dynamic_len(),
            s.movers.len(),
            s.movers.iter().map(|m| m.parts.len()).sum::<usize>(),
            s.patches.len(),
            s.lights.len(),
            s.surfaces.len(),
            s.time,
            s.camera.is_some(),
            t0.elapsed().as_secs_f64(),
            s.warnings
        );
        Some(s)
    }

    fn bounds(ts: &[Triangle]) -> (DVec3, DVec3) {
        ts.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), t| {
                let (a, b) = t.bounds();
                (lo.min(a), hi.max(b))
            },
        )
    }

    #[test]
    fn kitchen() {
        let Some(s) = bart("kitchen/kitchen.aff") else {
            return;
        };
        // Counted independently (mesh `triangles N` + polygons + `tt`, includes with their
        // multiplicity: 110,561), less 41 zero-area triangles.
        assert_eq!(s.triangles.len(), 103_338);
        assert_eq!(s.dynamic_len(), 7_182);
        assert!(s.patches.is_empty());
        assert_eq!(s.lights.len(), 6);
        assert!(s.lights.iter().all(|l| matches!(l, Light::Point { .. })));
        assert!((s.lights[0].power() - 0.3).abs() < 1e-12);
        let c = s.camera.as_ref().expect("camera");
        assert_eq!((c.fov_deg, c.width, c.height), (40.0, 800, 600));
        assert!(s.camera_animation.is_some());
        assert_eq!(s.time, Some((0.0, 20.0, 800)));
        assert_eq!(s.movers.len(), 1);
        let car = &s.movers[0];
        assert_eq!(car.name, "toycar");
        assert_eq!(car.len(), 7_182);
        // Nested rotating wheels share the mover, with longer chains.
        assert!(car.parts.iter().any(|p| p.chain.len() > 1));
        let (a0, a1) = bounds(&car.triangles_at(0.0));
        let (b0, b1) = bounds(&car.triangles_at(20.0));
        let moved = ((a0 + a1) / 2.0 - (b0 + b1) / 2.0).length();
        // Rigid motion mid-way (wheels spin, body turns): the car keeps its size.
        let (c0, c1) = bounds(&car.triangles_at(10.0));
        let (d0, d1) = ((a1 - a0).length(), (c1 - c0).length());
        assert!(
            (d1 / d0 - 1.0).abs() < 0.25,
            "car diagonal {d0} at t=0, {d1} at t=10"
        );
        assert!(moved > 0.5, "the toy car moved only {moved}");
        // At t = 0 it stands at its first translation key (4.45, 0, 2.75), on the floor.
        let centre = (a0 + a1) / 2.0;
        assert!(
            (centre.x - 4.45).abs() < 0.2 && (centre.z - 2.75).abs() < 0.2,
            "{centre}"
        );
        for sf in &s.surfaces {
            assert!((0.0..=0.95).contains(&sf.albedo) && sf.emission == 0.0);
        }
        let n = s.surfaces.len() as u32;
        assert!(s.triangles.iter().all(|t| t.surface < n && !t.degenerate()));
    }

    #[test]
    fn robot() {
        let Some(s) = bart("robot/Robot.aff") else {
            return;
        };
        assert_eq!(s.triangles.len(), 9_170);
        assert_eq!(s.dynamic_len(), 62_410);
        assert_eq!(s.movers.len(), 10);
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.time, Some((0.0, 50.0, 800)));
        assert!(s.camera.is_some());
        for m in &s.movers {
            let (a0, a1) = bounds(&m.triangles_at(0.0));
            let (b0, b1) = bounds(&m.triangles_at(50.0));
            assert!(
                (a0 - b0).length() + (a1 - b1).length() > 1e-3,
                "{} does not move",
                m.name
            );
            assert!(a0.is_finite() && b1.is_finite());
        }
    }

    #[test]
    fn museum() {
        let Some(s) = bart("museum/museum5.aff") else {
            return;
        };
        assert_eq!(s.triangles.len(), 10_668);
        assert_eq!(s.patches.len(), 1_024);
        assert!(s.movers.is_empty());
        assert_eq!(s.lights.len(), 2);
        assert_eq!(s.time, Some((-1.0, 5.0, 300)));
        let p = &s.patches[0];
        assert_eq!(p.times, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(p.at(1.0).v[0], DVec3::new(-0.121070, 3.370914, 0.157006));
        let half = p.at(0.5).v[0];
        assert!((half - (p.vertices[0][0] + p.vertices[1][0]) / 2.0).length() < 1e-12);
        assert_eq!(p.at(-1.0).v, p.vertices[0]);
        assert_eq!(s.triangles_at(2.0).len(), 10_668 + 1_024);
    }

    fn parse(text: &str) -> Result<AffScene, InputError> {
        parse_aff(text, Path::new("/nonexistent/inline.aff"))
    }

    fn err(text: &str) -> InputError {
        match parse(text) {
            Ok(_) => panic!("expected an error for {text:?}"),
            Err(e) => {
                eprintln!("{e}");
                e
            }
        }
    }

    #[test]
    fn tiny_nff() {
        let s = parse(
            "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 64 48\n\
             b 0.1 0.1 0.1\nl 0 4 0\nl 1 4 0 0.5 0.25 0.75\n\
             f 0.8 0.4 0.6 0.5 0.5 10 0 1\n\
             p 4\n-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n\
             s 0 0 -2 0.5\n\
             c 0 0 0 1 0 1 0 1\n",
        )
        .unwrap();
        let c = s.camera.unwrap();
        assert_eq!(
            (c.eye, c.fov_deg, c.width, c.height),
            (DVec3::new(0.0, 0.0, 5.0), 45.0, 64, 48)
        );
        assert_eq!(s.lights.len(), 2);
        assert_eq!(s.lights[0].power(), 1.0);
        assert!((s.lights[1].power() - 0.5).abs() < 1e-12);
        assert_eq!(s.surfaces.len(), 1);
        assert!((s.surfaces[0].albedo - 0.3).abs() < 1e-12);
        let sphere = 2 * ROUND * (ROUND / 2 - 1);
        assert_eq!(s.triangles.len(), 2 + sphere + 2 * ROUND);
        // Quad normal +z; sphere and cone normals point outward.
        assert!(s.triangles[0].normal().z > 0.99);
        for t in &s.triangles[2..2 + sphere] {
            assert!(t.normal().dot(t.centroid() - DVec3::new(0.0, 0.0, -2.0)) > 0.0);
        }
        for t in &s.triangles[2 + sphere..] {
            let c = t.centroid();
            assert!(t.normal().dot(DVec3::new(c.x, 0.0, c.z)) > 0.0);
        }
        assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    }

    #[test]
    fn transforms_and_movers() {
        let s = parse(
            "fm 0 0 0 0.5 0.5 0.5 0 0 0 1 0 1\n\
             xs 2 2 2  0 1 0 0  1 0 0\n{\n\
               x a\n{\n\
                 xs 1 1 1  0 0 1 90  0 0 0 { p 3  1 0 0  0 1 0  0 0 1 }\n\
                 x b { p 3  1 0 0  0 1 0  0 0 1 }\n\
               }\n\
               p 3  1 0 0  0 1 0  0 0 1\n\
             }\n\
             k a { transl 1  0  0 5 0  0 0 0 }\n\
             k b { rot 1  0  0 0 1 180  0 0 0 }\n",
        )
        .unwrap();
        // The static triangle: scaled by 2, moved by +x.
        assert_eq!(s.triangles.len(), 1);
        assert_eq!(s.triangles[0].v[0], DVec3::new(3.0, 0.0, 0.0));
        assert_eq!(s.movers.len(), 1);
        let m = &s.movers[0];
        assert_eq!((m.name.as_str(), m.parts.len()), ("a", 2));
        // Part of `a`: rotation baked in, chain = [Fixed(xs), a].
        let pa = &m.parts[0];
        assert_eq!(pa.chain.len(), 2);
        assert!((pa.triangles[0].v[0] - DVec3::Y).length() < 1e-12);
        let w = spline::compose(&pa.chain, 0.0).transform_point3(pa.triangles[0].v[0]);
        // (1,0,0) → rotated (0,1,0) → a: +5y → (0,6,0) → xs: ×2, +x → (1,12,0).
        assert!((w - DVec3::new(1.0, 12.0, 0.0)).length() < 1e-12, "{w}");
        // Nested `b`: chain [Fixed, a, b].
        let pb = &m.parts[1];
        assert_eq!(pb.chain.len(), 3);
        let w = spline::compose(&pb.chain, 0.0).transform_point3(pb.triangles[0].v[0]);
        assert!((w - DVec3::new(-1.0, 10.0, 0.0)).length() < 1e-12, "{w}");
    }

    #[test]
    fn errors_name_the_line() {
        let e = err("fm 0 0 0 0.5 0.5 0.5 0 0 0 1 0 1\n\nzz 1 2 3\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((3, 1)), Some("zz")));
        assert!(e.message.contains("unknown directive"));
        assert_eq!(e.file, "/nonexistent/inline.aff");

        let e = err("l 1 2 3\nl 1 2 x3\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((2, 7)), Some("l")));
        assert!(e.message.contains("not a number"), "{}", e.message);

        // Too few numbers: the next directive is met where a number was expected.
        let e = err("b 0 0 0\nfm 0.1 0.2 0.3\np 3 0 0 0 1 0 0 0 1 0\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((3, 1)), Some("fm")));
        // Too many.
        let e = err("b 0 0 0 1\n");
        assert_eq!(e.at, Some((1, 9)));

        let e = err("m\nvertices 3\n0 0 0\n1 0 0\n0 1 0\ntriangles 2\n0 1 2\n0 2 3\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((8, 5)), Some("m")));
        assert!(e.message.contains("out of range"), "{}", e.message);
        let e =
            err("m\nvertices 3\n0 0 0\n1 0 0\n0 1 0\nnormals 1 0 0 1\ntriangles 1\n0 1 2 0 0 1\n");
        assert_eq!(e.at, Some((8, 11)));

        let e = err("\n\ni 0 not_there.aff\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((3, 5)), Some("i")));
        assert!(e.message.contains("not_there.aff"));

        let e = err("xs 1 1 1 0 1 0 0 0 0 0\n{\np 3 0 0 0 1 0 0 0 1 0\n");
        assert_eq!((e.at, e.key.as_deref()), (Some((2, 1)), Some("xs")));
        assert!(e.message.contains("unterminated"));
        let e = err("x car {\n}\nk car {\ntransl 2\n0 0 0 0 0 0 0\n");
        assert_eq!((e.at.map(|l| l.0), e.key.as_deref()), (Some(6), Some("k")));
        assert!(e.message.contains("started at line 3"), "{}", e.message);
        let e = err("x car {\n}\nk car {\ntransl 1\n0 0 0 0 0 0 0\n");
        assert_eq!(e.at, Some((3, 7)));
        assert!(e.message.contains("unterminated"), "{}", e.message);
        let e = err("p 3 0 0 0 1 0 0 0 1 0\n}\n");
        assert_eq!(e.at, Some((2, 1)));
        let e = err("x car p 3 0 0 0 1 0 0 0 1 0\n");
        assert!(e.message.contains("expected `{`"));
        let e = err("k car { spin 1 0 0 0 0 }");
        assert!(e.message.contains("unknown keyframe track"));
        let e = err("v\nfrom 0 0 0\nat 0 0 1\nangle 30\n");
        assert!(e.message.contains("up"), "{}", e.message);
        let e = err("p 2 0 0 0 1 1 1\n");
        assert!(e.message.contains("at least 3"));
    }

    #[test]
    fn errors_in_includes_name_the_included_file() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(dir.path().join("top.aff"), "i 0 sub/mid.aff\n").unwrap();
        // `mid` includes `leaf.aff`, found in its own folder; `shared.aff` only at the root.
        std::fs::write(sub.join("mid.aff"), "i 0 leaf.aff\ni 0 shared.aff\n").unwrap();
        std::fs::write(sub.join("leaf.aff"), "p 3 0 0 0 1 0 0 0 1 0\n").unwrap();
        std::fs::write(
            dir.path().join("shared.aff"),
            "% ok\np 3 0 0 0 1 0 0 0 1 0\n",
        )
        .unwrap();
        let s = load_aff(&dir.path().join("top.aff")).unwrap();
        assert_eq!(s.triangles.len(), 2);
        std::fs::write(sub.join("leaf.aff"), "p 3 0 0 0 1 0 0 0 1 0\n\n  bogus\n").unwrap();
        let e = load_aff(&dir.path().join("top.aff")).unwrap_err();
        assert!(e.file.ends_with("leaf.aff"), "{e}");
        assert_eq!(e.at, Some((3, 3)));
        // A cycle is an error, not a stack overflow.
        std::fs::write(sub.join("leaf.aff"), "i 0 mid.aff\n").unwrap();
        let e = load_aff(&dir.path().join("top.aff")).unwrap_err();
        assert!(e.message.contains("cycle"), "{e}");
    }

    /// A hostile scene: each file includes the next twice, 40 deep (2⁴¹ inclusions of a few bytes each), and
    /// one large file included from many places: both refused in milliseconds with the bound named.
    #[test]
    fn include_fan_out_and_expanded_size_are_bounded() {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..40 {
            std::fs::write(
                dir.path().join(format!("f{i}.aff")),
                format!("i 0 f{n}.aff\ni 0 f{n}.aff\n", n = i + 1),
            )
            .unwrap();
        }
        std::fs::write(dir.path().join("f40.aff"), "p 3 0 0 0 1 0 0 0 1 0\n").unwrap();
        let t = std::time::Instant::now();
        let e = load_aff(&dir.path().join("f0.aff")).unwrap_err();
        assert!(
            e.message.contains("fan-out") && e.message.contains("100000"),
            "{e}"
        );
        assert!(t.elapsed().as_secs() < 10, "{:?}", t.elapsed());
        // A 2 MiB file included 100 times from one file: under the inclusion bound, over the size one.
        let big = "% padding\n".repeat(200_000);
        std::fs::write(dir.path().join("big.aff"), big).unwrap();
        std::fs::write(dir.path().join("top.aff"), "i 0 big.aff\n".repeat(100)).unwrap();
        let e = load_aff(&dir.path().join("top.aff")).unwrap_err();
        assert!(
            e.message.contains("MiB") && e.message.contains("fan-out"),
            "{e}"
        );
        // A FIFO is refused by what it is, not called missing.
        #[cfg(unix)]
        {
            let fifo = dir.path().join("pipe.aff");
            if std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .is_ok_and(|s| s.success())
            {
                std::fs::write(dir.path().join("p.aff"), "i 0 pipe.aff\n").unwrap();
                let e = load_aff(&dir.path().join("p.aff")).unwrap_err();
                assert!(e.message.contains("FIFO"), "{e}");
            }
        }
    }

    #[test]
    fn missing_file_points_to_bart() {
        let e = load_aff(Path::new("/nonexistent/kitchen.aff")).unwrap_err();
        assert!(e.message.contains("experiments/scenes/bart/") && e.message.contains("Lext"));
    }

    #[test]
    fn never_panics_on_truncated_or_garbled_input() {
        let text = "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 hither 1 resolution 64 48\n\
                    fm 0.1 0.1 0.1 0.5 0.5 0.5 0 0 0 1 0 1\n\
                    x car { xs 1 1 1 0 1 0 30 0 0 0 { m vertices 3 0 0 0 1 0 0 0 1 0 \
                    normals 3 0 0 1 0 0 1 0 0 1 texturecoords 3 t.ppm 0 0 1 0 0 1 \
                    triangles 1 0 1 2 0 1 2 0 1 2 } }\n\
                    tpa 2 0 0 0 0 0 0 1 1 0 0 0 0 1 0 1 0 0 0 1 1 1 0 0 0 0 1 1 0 0 0 0 1 0 1 0 0 0 1\n\
                    tt t.ppm 0 0 0 0 0 1 0 0 1 0 0 1 0 0 1\n\
                    c 0 0 0 1 0 1 0 0.5\ns 0 0 0 1\n\
                    k car { transl 4 0 0 0 0 0 0 0 1 1 0 0 0 0 0 2 2 0 0 0 0 0 3 3 0 0 0 0 0 \
                    rot 1 0 0 1 0 90 0 0 0 scale 1 0 1 1 1 0 0 0 }\na 0 3 10\n";
        let full = parse(text).unwrap();
        assert_eq!((full.movers.len(), full.patches.len()), (1, 1));
        for cut in 0..text.len() {
            let _ = parse(&text[..cut]);
        }
        let tokens: Vec<&str> = text.split_whitespace().collect();
        for i in 0..tokens.len() {
            for junk in ["}", "{", "-1", "1e400", "nan", "x", "99999999"] {
                let mut t = tokens.clone();
                t[i] = junk;
                let _ = parse(&t.join(" "));
            }
        }
    }
}
