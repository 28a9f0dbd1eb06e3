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

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DAffine3, DMat3, DVec3};

use super::shapes::Triangle;
use super::spline::{self, axis_angle_deg, KbKey, KbTrack, KbTransform, Node};
use super::{Camera, InputError, Light, Surface};

/// Where BART scenes live and what they are, for the "file not found" message.
pub const BART_HINT: &str = "BART scenes come from ../shared/scenes/bart/ (BART: A Benchmark for \
Animated Ray Tracing, Lext, Assarsson & Möller 2001), e.g. ../shared/scenes/bart/kitchen/kitchen.aff";

/// Segments around a tessellated sphere or cone.
const ROUND: usize = 24;
/// Includes nested deeper than this are taken for a cycle.
const MAX_INCLUDE_DEPTH: usize = 64;

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
        let mut triangles = self.triangles;
        let mut warnings = self.warnings;
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

// ---------------------------------------------------------------------------------------------
// Lexer

#[derive(Clone, Copy)]
struct Tok<'a> {
    text: &'a [u8],
    line: usize,
    col: usize,
}

impl Tok<'_> {
    fn show(&self) -> String {
        String::from_utf8_lossy(self.text).into_owned()
    }
    fn is(&self, s: &str) -> bool {
        self.text == s.as_bytes()
    }
    fn number(&self) -> Option<f64> {
        let c = *self.text.first()?;
        if !(c.is_ascii_digit() || c == b'-' || c == b'+' || c == b'.') {
            return None;
        }
        std::str::from_utf8(self.text)
            .ok()?
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
    }
}

#[derive(Clone, Copy)]
struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Lexer<'a> {
    fn new(src: &'a [u8]) -> Self {
        Lexer {
            src,
            pos: 0,
            line: 1,
            line_start: 0,
        }
    }

    fn skip(&mut self) {
        let s = self.src;
        while self.pos < s.len() {
            match s[self.pos] {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'%' | b'#' => {
                    while self.pos < s.len() && s[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    fn here(&self) -> (usize, usize) {
        (self.line, self.pos - self.line_start + 1)
    }

    fn next(&mut self) -> Option<Tok<'a>> {
        self.skip();
        let s = self.src;
        if self.pos >= s.len() {
            return None;
        }
        let (line, col) = self.here();
        let start = self.pos;
        if s[start] == b'{' || s[start] == b'}' {
            self.pos += 1;
        } else {
            while self.pos < s.len()
                && !matches!(
                    s[self.pos],
                    b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c | b'{' | b'}'
                )
            {
                self.pos += 1;
            }
        }
        Some(Tok {
            text: &s[start..self.pos],
            line,
            col,
        })
    }

    fn peek(&self) -> Option<Tok<'a>> {
        let mut c = *self;
        c.next()
    }
}

// ---------------------------------------------------------------------------------------------
// Loader

#[derive(Clone, Debug)]
enum Link {
    Fixed(DAffine3),
    Anim(String),
}

struct PartBuild {
    mover: usize,
    chain: Vec<Link>,
    tris: Vec<Triangle>,
}

struct PatchBuild {
    surface: u32,
    times: Vec<f64>,
    vertices: Vec<[DVec3; 3]>,
    part: Option<usize>,
}

#[derive(Clone, Copy)]
struct Frame {
    /// From this block's coordinates to the innermost animated node's (or world).
    local: DAffine3,
    /// The mover part geometry here belongs to (None: static).
    part: Option<usize>,
    /// Where its `{` is, for "unterminated" errors.
    open: (usize, usize),
    /// Directive that opened it.
    key: &'static str,
}

#[derive(Default)]
struct Counts {
    degenerate: usize,
    textured: usize,
    cones: usize,
    spheres: usize,
    visibility: usize,
    lights_in_movers: usize,
    duplicate_keys: Vec<String>,
    unsorted: Vec<String>,
}

struct Loader {
    root: PathBuf,
    out: AffScene,
    stack: Vec<Frame>,
    parts: Vec<PartBuild>,
    mover_names: Vec<String>,
    patches: Vec<PatchBuild>,
    anims: HashMap<String, KbTransform>,
    material: Option<u32>,
    counts: Counts,
    cache: HashMap<PathBuf, Rc<[u8]>>,
}

/// Parsing context of one file: its name (for errors) and lexer.
struct Ctx<'a> {
    name: String,
    lx: Lexer<'a>,
    key: &'static str,
    /// Where the directive being read starts.
    at: (usize, usize),
}

impl<'a> Ctx<'a> {
    fn err_at(&self, at: (usize, usize), message: String) -> InputError {
        InputError {
            file: self.name.clone(),
            at: Some(at),
            key: Some(self.key.to_string()),
            message,
        }
    }

    fn eof(&self, what: &str) -> InputError {
        self.err_at(
            self.lx.here(),
            format!(
                "the file ends inside `{}` (started at line {}): expected {what}",
                self.key, self.at.0
            ),
        )
    }

    fn tok(&mut self, what: &str) -> Result<Tok<'a>, InputError> {
        self.lx.next().ok_or_else(|| self.eof(what))
    }

    fn num(&mut self, what: &str) -> Result<f64, InputError> {
        let t = self.tok(what)?;
        t.number().ok_or_else(|| {
            self.err_at(
                (t.line, t.col),
                format!("`{}` is not a number: expected {what}", t.show()),
            )
        })
    }

    fn vec3(&mut self, what: &str) -> Result<DVec3, InputError> {
        Ok(DVec3::new(
            self.num(what)?,
            self.num(what)?,
            self.num(what)?,
        ))
    }

    /// A count or an index: a non-negative integer below `limit`.
    fn int(&mut self, what: &str, limit: usize) -> Result<usize, InputError> {
        let t = self.tok(what)?;
        let bad = |ctx: &Self, m: String| ctx.err_at((t.line, t.col), m);
        let Some(x) = t.number() else {
            return Err(bad(
                self,
                format!("`{}` is not a number: expected {what}", t.show()),
            ));
        };
        if x < 0.0 || x.fract() != 0.0 {
            return Err(bad(
                self,
                format!(
                    "`{}` is not a non-negative integer: expected {what}",
                    t.show()
                ),
            ));
        }
        if x >= limit as f64 {
            return Err(bad(
                self,
                format!(
                    "{what} {} is out of range (must be below {limit})",
                    t.show()
                ),
            ));
        }
        Ok(x as usize)
    }

    fn word(&mut self, word: &str) -> Result<(), InputError> {
        let t = self.tok(&format!("`{word}`"))?;
        if t.is(word) {
            Ok(())
        } else {
            Err(self.err_at(
                (t.line, t.col),
                format!("expected `{word}`, found `{}`", t.show()),
            ))
        }
    }
}

/// Counts above this are refused (a corrupt count would otherwise allocate wildly).
const MAX_COUNT: usize = 1 << 26;

fn trs(scale: DVec3, axis: DVec3, angle_deg: f64, trans: DVec3) -> DAffine3 {
    DAffine3 {
        matrix3: DMat3::from_quat(axis_angle_deg(axis, angle_deg)) * DMat3::from_diagonal(scale),
        translation: trans,
    }
}

fn mean(c: DVec3) -> f64 {
    (c.x + c.y + c.z) / 3.0
}

impl Loader {
    fn new(root: PathBuf) -> Self {
        Loader {
            root,
            out: AffScene::default(),
            stack: vec![Frame {
                local: DAffine3::IDENTITY,
                part: None,
                open: (0, 0),
                key: "",
            }],
            parts: Vec::new(),
            mover_names: Vec::new(),
            patches: Vec::new(),
            anims: HashMap::new(),
            material: None,
            counts: Counts::default(),
            cache: HashMap::new(),
        }
    }

    fn top(&self) -> Frame {
        self.stack[self.stack.len() - 1]
    }

    fn surface(&mut self) -> u32 {
        if let Some(m) = self.material {
            return m;
        }
        let id = self.out.surfaces.len() as u32;
        self.out.surfaces.push(Surface {
            name: "default material (geometry before any fm/f)".into(),
            albedo: 0.5,
            emission: 0.0,
        });
        self.material = Some(id);
        id
    }

    fn add_material(&mut self, albedo: f64, name: &str, at: (usize, usize)) {
        let id = self.out.surfaces.len() as u32;
        let albedo = if albedo.is_finite() {
            albedo.clamp(0.0, 0.95)
        } else {
            0.0
        };
        self.out.surfaces.push(Surface {
            name: format!("material {id} ({name}:{})", at.0),
            albedo,
            emission: 0.0,
        });
        self.material = Some(id);
    }

    /// A triangle in the current block's coordinates.
    fn emit(&mut self, v: [DVec3; 3]) {
        let f = self.top();
        let surface = self.surface();
        let t = Triangle {
            v: v.map(|p| f.local.transform_point3(p)),
            surface,
        };
        if t.degenerate() {
            self.counts.degenerate += 1;
            return;
        }
        match f.part {
            None => self.out.triangles.push(t),
            Some(p) => self.parts[p].tris.push(t),
        }
    }

    /// A triangle whose winding is fixed so that its normal points away from `inside`
    /// (towards it if `flip`).
    fn emit_oriented(&mut self, mut v: [DVec3; 3], inside: DVec3, flip: bool) {
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let c = (v[0] + v[1] + v[2]) / 3.0;
        if (n.dot(c - inside) < 0.0) != flip {
            v.swap(1, 2);
        }
        self.emit(v);
    }

    fn file(&mut self, path: &Path, bytes: Rc<[u8]>, depth: usize) -> Result<(), InputError> {
        let mut cx = Ctx {
            name: path.display().to_string(),
            lx: Lexer::new(&bytes),
            key: "",
            at: (1, 1),
        };
        let base = self.stack.len();
        let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        while let Some(t) = cx.lx.next() {
            cx.at = (t.line, t.col);
            self.directive(&mut cx, t, &dir, depth, base)?;
        }
        if self.stack.len() > base {
            let f = self.top();
            cx.key = f.key;
            return Err(cx.err_at(
                f.open,
                format!(
                    "unterminated block: this `{{` (of `{}`) has no matching `}}` before the end of the file",
                    f.key
                ),
            ));
        }
        Ok(())
    }

    fn open_block(
        &mut self,
        cx: &mut Ctx,
        frame: impl FnOnce(&mut Self) -> Frame,
    ) -> Result<(), InputError> {
        let t = cx.tok("`{`")?;
        if !t.is("{") {
            return Err(cx.err_at(
                (t.line, t.col),
                format!(
                    "expected `{{` to open the `{}` block, found `{}`",
                    cx.key,
                    t.show()
                ),
            ));
        }
        let mut f = frame(self);
        f.open = (t.line, t.col);
        f.key = cx.key;
        self.stack.push(f);
        Ok(())
    }

    #[allow(clippy::too_many_lines)]
    fn directive(
        &mut self,
        cx: &mut Ctx,
        t: Tok,
        dir: &Path,
        depth: usize,
        base: usize,
    ) -> Result<(), InputError> {
        const KEYS: [&str; 20] = [
            "b", "v", "am", "l", "f", "fm", "p", "pp", "s", "c", "m", "tt", "ttp", "tpa", "x",
            "xs", "k", "a", "i", "}",
        ];
        let Some(key) = KEYS.iter().copied().find(|k| t.is(k)) else {
            cx.key = "";
            let what = if t.number().is_some() {
                format!(
                    "unexpected number `{}` where a directive was expected (too many numbers for the previous directive?)",
                    t.show()
                )
            } else if t.is("{") {
                "a `{` must follow `xs …` or `x NAME`".to_string()
            } else {
                format!(
                    "unknown directive `{}`: expected one of b v am l f fm p pp s c m tt ttp tpa x xs k a i, `}}`, or a % / # comment",
                    t.show()
                )
            };
            let mut e = cx.err_at((t.line, t.col), what);
            e.key = Some(t.show());
            return Err(e);
        };
        cx.key = key;
        match key {
            "b" | "am" => {
                cx.vec3("an RGB colour (3 numbers)")?;
            }
            "v" => self.viewpoint(cx)?,
            "l" => {
                let p = cx.vec3("the light position X Y Z")?;
                let power = if cx.lx.peek().and_then(|t| t.number()).is_some() {
                    mean(cx.vec3("the light colour R G B")?)
                } else {
                    1.0
                };
                let f = self.top();
                if f.part.is_some() {
                    self.counts.lights_in_movers += 1;
                }
                self.out.lights.push(Light::Point {
                    position: f.local.transform_point3(p),
                    power,
                });
            }
            "f" => {
                let rgb = cx.vec3("f R G B Kd Ks Shine T ior")?;
                let kd = cx.num("f R G B Kd Ks Shine T ior")?;
                for _ in 0..4 {
                    cx.num("f R G B Kd Ks Shine T ior")?;
                }
                self.add_material(mean(rgb) * kd, &cx.name.clone(), cx.at);
            }
            "fm" => {
                let what = "fm: ambient RGB, diffuse RGB, specular RGB, Shine T ior (12 numbers)";
                cx.vec3(what)?;
                let diffuse = cx.vec3(what)?;
                for _ in 0..6 {
                    cx.num(what)?;
                }
                self.add_material(mean(diffuse), &cx.name.clone(), cx.at);
            }
            "p" | "pp" => {
                let n = cx.int("the number of polygon vertices", MAX_COUNT)?;
                if n < 3 {
                    return Err(cx.err_at(
                        cx.at,
                        format!("a polygon needs at least 3 vertices, got {n}"),
                    ));
                }
                let mut pts = Vec::with_capacity(n.min(1 << 16));
                for _ in 0..n {
                    pts.push(cx.vec3("a polygon vertex X Y Z")?);
                    if key == "pp" {
                        cx.vec3("a vertex normal NX NY NZ")?;
                    }
                }
                for i in 1..n - 1 {
                    self.emit([pts[0], pts[i], pts[i + 1]]);
                }
            }
            "s" => {
                let c = cx.vec3("the sphere centre X Y Z")?;
                let r = cx.num("the sphere radius")?;
                self.counts.spheres += 1;
                self.sphere(c, r);
            }
            "c" => {
                let what = "c: base X Y Z radius, apex X Y Z radius (8 numbers)";
                let b = cx.vec3(what)?;
                let r0 = cx.num(what)?;
                let a = cx.vec3(what)?;
                let r1 = cx.num(what)?;
                self.counts.cones += 1;
                self.cone(b, r0, a, r1);
            }
            "m" => self.mesh(cx)?,
            "tt" | "ttp" => {
                cx.tok("a texture name")?;
                let mut v = [DVec3::ZERO; 3];
                for p in &mut v {
                    *p = cx.vec3("a vertex X Y Z")?;
                    if key == "ttp" {
                        cx.vec3("a vertex normal")?;
                    }
                    cx.num("texture coordinates U V")?;
                    cx.num("texture coordinates U V")?;
                }
                self.counts.textured += 1;
                self.emit(v);
            }
            "tpa" => {
                let n = cx.int("the number of key times", MAX_COUNT)?;
                if n == 0 {
                    return Err(
                        cx.err_at(cx.at, "an animated triangle needs at least one key".into())
                    );
                }
                let mut times = Vec::with_capacity(n.min(1 << 16));
                let mut vertices = Vec::with_capacity(n.min(1 << 16));
                let local = self.top().local;
                for _ in 0..n {
                    let tm = cx.num("a key time")?;
                    if times.last().is_some_and(|&l| tm < l) {
                        return Err(cx.err_at(
                            cx.at,
                            format!(
                                "key time {tm} is before the previous one: times must not decrease"
                            ),
                        ));
                    }
                    times.push(tm);
                    let mut v = [DVec3::ZERO; 3];
                    for p in &mut v {
                        *p = local.transform_point3(cx.vec3("a vertex X Y Z")?);
                        cx.vec3("a vertex normal NX NY NZ")?;
                    }
                    vertices.push(v);
                }
                let surface = self.surface();
                self.patches.push(PatchBuild {
                    surface,
                    times,
                    vertices,
                    part: self.top().part,
                });
            }
            "xs" => {
                let what = "xs: scale SX SY SZ, rotation axis X Y Z and angle in degrees, translation TX TY TZ (10 numbers)";
                let s = cx.vec3(what)?;
                let axis = cx.vec3(what)?;
                let deg = cx.num(what)?;
                let tr = cx.vec3(what)?;
                let m = trs(s, axis, deg, tr);
                self.open_block(cx, |ld| {
                    let f = ld.top();
                    Frame {
                        local: f.local * m,
                        ..f
                    }
                })?;
            }
            "x" => {
                let name = cx.tok("the name of the animated transform")?.show();
                self.open_block(cx, |ld| {
                    let f = ld.top();
                    let (mover, mut chain) = match f.part {
                        Some(p) => (ld.parts[p].mover, ld.parts[p].chain.clone()),
                        None => {
                            ld.mover_names.push(name.clone());
                            (ld.mover_names.len() - 1, Vec::new())
                        }
                    };
                    if f.local != DAffine3::IDENTITY {
                        chain.push(Link::Fixed(f.local));
                    }
                    chain.push(Link::Anim(name));
                    ld.parts.push(PartBuild {
                        mover,
                        chain,
                        tris: Vec::new(),
                    });
                    Frame {
                        local: DAffine3::IDENTITY,
                        part: Some(ld.parts.len() - 1),
                        open: (0, 0),
                        key: "",
                    }
                })?;
            }
            "}" => {
                if self.stack.len() <= base {
                    return Err(cx.err_at(cx.at, "`}` without a matching `{` in this file".into()));
                }
                self.stack.pop();
            }
            "k" => self.keyframes(cx)?,
            "a" => {
                let s = cx.num("a START END FRAMES")?;
                let e = cx.num("a START END FRAMES")?;
                let n = cx.int("the number of frames", u32::MAX as usize)?;
                self.out.time = Some((s, e, n as u32));
            }
            "i" => {
                cx.num("the detail level of the include")?;
                let f = cx.tok("the file to include")?;
                let fname = f.show();
                let candidates = [dir.join(&fname), self.root.join(&fname)];
                let Some(p) = candidates.iter().find(|p| p.is_file()) else {
                    return Err(cx.err_at(
                        (f.line, f.col),
                        format!(
                            "include file `{fname}` not found (looked for {} and {})",
                            candidates[0].display(),
                            candidates[1].display()
                        ),
                    ));
                };
                if depth + 1 > MAX_INCLUDE_DEPTH {
                    return Err(cx.err_at(
                        (f.line, f.col),
                        format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (an include cycle?)"),
                    ));
                }
                let p = p.clone();
                let bytes = match self.cache.get(&p) {
                    Some(b) => b.clone(),
                    None => {
                        let b: Rc<[u8]> = Rc::from(std::fs::read(&p).map_err(|e| {
                            cx.err_at(
                                (f.line, f.col),
                                format!("cannot read include `{}`: {e}", p.display()),
                            )
                        })?);
                        self.cache.insert(p.clone(), b.clone());
                        b
                    }
                };
                self.file(&p, bytes, depth + 1)?;
            }
            _ => unreachable!("every key of KEYS is handled"),
        }
        Ok(())
    }

    fn viewpoint(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let (mut from, mut at, mut up, mut angle, mut res) = (None, None, None, None, None);
        const WORDS: [&str; 6] = ["from", "at", "up", "angle", "hither", "resolution"];
        while let Some(t) = cx.lx.peek() {
            let Some(w) = WORDS.iter().copied().find(|w| t.is(w)) else {
                break;
            };
            cx.lx.next();
            match w {
                "from" => from = Some(cx.vec3("v: from X Y Z")?),
                "at" => at = Some(cx.vec3("v: at X Y Z")?),
                "up" => up = Some(cx.vec3("v: up X Y Z")?),
                "angle" => angle = Some(cx.num("v: angle (degrees)")?),
                "hither" => {
                    cx.num("v: hither distance")?;
                }
                _ => {
                    let w = cx.int("v: resolution width", u32::MAX as usize)?;
                    let h = cx.int("v: resolution height", u32::MAX as usize)?;
                    res = Some((w as u32, h as u32));
                }
            }
        }
        let missing: Vec<&str> = [
            ("from", from.is_none()),
            ("at", at.is_none()),
            ("up", up.is_none()),
            ("angle", angle.is_none()),
            ("resolution", res.is_none()),
        ]
        .iter()
        .filter(|x| x.1)
        .map(|x| x.0)
        .collect();
        let (Some(eye), Some(look_at), Some(up), Some(fov_deg), Some((width, height))) =
            (from, at, up, angle, res)
        else {
            return Err(cx.err_at(
                cx.at,
                format!(
                    "the viewpoint lacks {}: expected `v` followed by from, at, up, angle, hither, resolution",
                    missing.join(", ")
                ),
            ));
        };
        let m = self.top().local;
        self.out.camera = Some(Camera {
            eye: m.transform_point3(eye),
            look_at: m.transform_point3(look_at),
            up: m.transform_vector3(up),
            fov_deg,
            width,
            height,
        });
        Ok(())
    }

    fn mesh(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        cx.word("vertices")?;
        let nv = cx.int("the number of vertices", MAX_COUNT)?;
        let mut verts = Vec::with_capacity(nv.min(1 << 16));
        for _ in 0..nv {
            verts.push(cx.vec3("a mesh vertex X Y Z")?);
        }
        let mut next = cx.tok("`normals`, `texturecoords` or `triangles`")?;
        let mut nn = 0;
        let has_normals = next.is("normals");
        if has_normals {
            nn = cx.int("the number of normals", MAX_COUNT)?;
            for _ in 0..nn {
                cx.vec3("a mesh normal X Y Z")?;
            }
            next = cx.tok("`texturecoords` or `triangles`")?;
        }
        let mut nt = 0;
        let has_tex = next.is("texturecoords");
        if has_tex {
            nt = cx.int("the number of texture coordinates", MAX_COUNT)?;
            if cx.lx.peek().is_some_and(|t| t.number().is_none()) {
                cx.lx.next(); // texture file name
            }
            for _ in 0..nt * 2 {
                cx.num("texture coordinates U V")?;
            }
            self.counts.textured += 1;
            next = cx.tok("`triangles`")?;
        }
        if !next.is("triangles") {
            return Err(cx.err_at(
                (next.line, next.col),
                format!(
                    "expected `triangles` in the mesh, found `{}` (after `vertices`, optional `normals`, optional `texturecoords`)",
                    next.show()
                ),
            ));
        }
        let ntri = cx.int("the number of triangles", MAX_COUNT)?;
        for _ in 0..ntri {
            let a = cx.int("a vertex index", nv)?;
            let b = cx.int("a vertex index", nv)?;
            let c = cx.int("a vertex index", nv)?;
            if has_normals {
                for _ in 0..3 {
                    cx.int("a normal index", nn)?;
                }
            }
            if has_tex {
                for _ in 0..3 {
                    cx.int("a texture-coordinate index", nt)?;
                }
            }
            self.emit([verts[a], verts[b], verts[c]]);
        }
        Ok(())
    }

    fn keyframes(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let name = cx.tok("the name of the animation")?.show();
        let t = cx.tok("`{`")?;
        if !t.is("{") {
            return Err(cx.err_at(
                (t.line, t.col),
                format!("expected `{{` after `k {name}`, found `{}`", t.show()),
            ));
        }
        let open = (t.line, t.col);
        let mut kb = KbTransform::default();
        loop {
            let Some(t) = cx.lx.next() else {
                return Err(cx.err_at(
                    open,
                    format!("unterminated block: the `{{` of `k {name}` has no matching `}}`"),
                ));
            };
            if t.is("}") {
                break;
            }
            let kind = if t.is("transl") {
                0
            } else if t.is("rot") {
                1
            } else if t.is("scale") {
                2
            } else if t.is("visibility") {
                3
            } else {
                return Err(cx.err_at(
                    (t.line, t.col),
                    format!(
                        "unknown keyframe track `{}` in `k {name}`: expected transl, rot, scale, visibility or `}}`",
                        t.show()
                    ),
                ));
            };
            let at = (t.line, t.col);
            let n = cx.int("the number of keys", MAX_COUNT)?;
            if kind == 3 {
                for _ in 0..n {
                    cx.num("a visibility key: time")?;
                    cx.num("a visibility key: 0 or 1")?;
                }
                self.counts.visibility += 1;
                continue;
            }
            let what = match kind {
                0 => "a translation key: time X Y Z tension continuity bias",
                1 => "a rotation key: time AX AY AZ angle° tension continuity bias",
                _ => "a scale key: time SX SY SZ tension continuity bias",
            };
            let mut vk = Vec::new();
            let mut qk = Vec::new();
            for _ in 0..n {
                let time = cx.num(what)?;
                let v = cx.vec3(what)?;
                let angle = if kind == 1 { cx.num(what)? } else { 0.0 };
                let (tension, continuity, bias) = (cx.num(what)?, cx.num(what)?, cx.num(what)?);
                if kind == 1 {
                    qk.push(KbKey {
                        time,
                        value: axis_angle_deg(v, angle),
                        tension,
                        continuity,
                        bias,
                    });
                } else {
                    vk.push(KbKey {
                        time,
                        value: v,
                        tension,
                        continuity,
                        bias,
                    });
                }
            }
            let bad = |m: String| cx.err_at(at, format!("in `k {name}`: {m}"));
            let ok = match kind {
                0 | 2 => vk.windows(2).all(|w| w[0].time <= w[1].time),
                _ => qk.windows(2).all(|w| w[0].time <= w[1].time),
            };
            if !ok {
                self.counts
                    .unsorted
                    .push(format!("{name} ({}:{})", cx.name, at.0));
            }
            match kind {
                0 => kb.translate = Some(KbTrack::new(vk).map_err(bad)?),
                1 => kb.rotate = Some(KbTrack::new(qk).map_err(bad)?),
                _ => kb.scale = Some(KbTrack::new(vk).map_err(bad)?),
            }
        }
        if name == "camera" {
            self.out.camera_animation = Some(kb);
        } else if self.anims.insert(name.clone(), kb).is_some() {
            self.counts.duplicate_keys.push(name);
        }
        Ok(())
    }

    fn sphere(&mut self, c: DVec3, r: f64) {
        let inside = r < 0.0;
        let r = r.abs();
        let (nu, nv) = (ROUND, ROUND / 2);
        let p = |i: usize, j: usize| {
            let th = std::f64::consts::TAU * i as f64 / nu as f64;
            let ph = std::f64::consts::PI * j as f64 / nv as f64;
            c + r * DVec3::new(ph.sin() * th.cos(), ph.cos(), ph.sin() * th.sin())
        };
        for i in 0..nu {
            for j in 0..nv {
                let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                if j > 0 {
                    self.emit_oriented([a, b, cc], c, inside);
                }
                if j + 1 < nv {
                    self.emit_oriented([a, cc, d], c, inside);
                }
            }
        }
    }

    fn cone(&mut self, b: DVec3, r0: f64, a: DVec3, r1: f64) {
        // NFF: both radii negative = only the inside is visible.
        let inside = r0 < 0.0;
        let (r0, r1) = (r0.abs(), r1.abs());
        let d = (a - b).normalize_or_zero();
        if d == DVec3::ZERO {
            self.counts.degenerate += 1;
            return;
        }
        let (u, w) = d.any_orthonormal_pair();
        let ring = |c: DVec3, r: f64, i: usize| {
            let th = std::f64::consts::TAU * i as f64 / ROUND as f64;
            c + r * (th.cos() * u + th.sin() * w)
        };
        for i in 0..ROUND {
            let (b0, b1, a0, a1) = (
                ring(b, r0, i),
                ring(b, r0, i + 1),
                ring(a, r1, i),
                ring(a, r1, i + 1),
            );
            // The radial direction of this slice, on the axis line, decides the outside.
            let mid = (b0 + b1 + a0 + a1) / 4.0;
            let axis_pt = b + d * (mid - b).dot(d);
            if r0 > 0.0 {
                self.emit_oriented([b0, b1, a1], axis_pt, inside);
            }
            if r1 > 0.0 {
                self.emit_oriented([b0, a1, a0], axis_pt, inside);
            }
        }
    }

    fn finish(mut self) -> AffScene {
        let mut missing = Vec::new();
        let anims = std::mem::take(&mut self.anims);
        let node = |l: &Link, missing: &mut Vec<String>| match l {
            Link::Fixed(m) => Node::Fixed(*m),
            Link::Anim(n) => Node::Animated {
                name: n.clone(),
                kb: anims.get(n).cloned().unwrap_or_else(|| {
                    if !missing.contains(n) {
                        missing.push(n.clone());
                    }
                    KbTransform::default()
                }),
            },
        };
        let mut movers: Vec<AffMover> = self
            .mover_names
            .iter()
            .map(|n| AffMover {
                name: n.clone(),
                parts: Vec::new(),
            })
            .collect();
        let mut chains: Vec<Option<Vec<Node>>> = vec![None; self.parts.len()];
        for (i, p) in self.parts.iter().enumerate() {
            let used = !p.tris.is_empty() || self.patches.iter().any(|q| q.part == Some(i));
            if used {
                chains[i] = Some(p.chain.iter().map(|l| node(l, &mut missing)).collect());
            }
        }
        for (i, p) in self.parts.into_iter().enumerate() {
            if !p.tris.is_empty() {
                movers[p.mover].parts.push(MoverPart {
                    triangles: p.tris,
                    chain: chains[i].clone().unwrap_or_default(),
                });
            }
        }
        movers.retain(|m| !m.parts.is_empty());
        self.out.movers = movers;
        self.out.patches = self
            .patches
            .into_iter()
            .map(|p| AnimatedPatch {
                surface: p.surface,
                times: p.times,
                vertices: p.vertices,
                chain: p.part.and_then(|i| chains[i].clone()).unwrap_or_default(),
            })
            .collect();
        let c = &self.counts;
        let w = &mut self.out.warnings;
        if c.degenerate > 0 {
            w.push(format!(
                "{} degenerate triangle(s) skipped (zero area)",
                c.degenerate
            ));
        }
        if c.textured > 0 {
            w.push(format!(
                "{} textured mesh(es)/triangle(s): geometry kept, texture coordinates and images ignored",
                c.textured
            ));
        }
        if c.cones > 0 {
            w.push(format!(
                "{} cone(s)/cylinder(s) tessellated into {ROUND} quads each (open, no caps)",
                c.cones
            ));
        }
        if c.spheres > 0 {
            w.push(format!(
                "{} sphere(s) tessellated into {} triangles each",
                c.spheres,
                2 * ROUND * (ROUND / 2 - 1)
            ));
        }
        if c.visibility > 0 {
            w.push(format!(
                "{} visibility track(s) ignored (objects always visible)",
                c.visibility
            ));
        }
        if c.lights_in_movers > 0 {
            w.push(format!(
                "{} light(s) inside animated transforms placed with their static transforms only",
                c.lights_in_movers
            ));
        }
        if !missing.is_empty() {
            w.push(format!(
                "{} animated transform(s) without `k` keyframes (held at identity): {}",
                missing.len(),
                missing.join(", ")
            ));
        }
        if !c.unsorted.is_empty() {
            w.push(format!(
                "{} keyframe track(s) with decreasing key times, evaluated as BART's reference code does (first segment ending after t): {}",
                c.unsorted.len(),
                c.unsorted.join(", ")
            ));
        }
        if !c.duplicate_keys.is_empty() {
            w.push(format!(
                "keyframes given more than once (the last kept): {}",
                c.duplicate_keys.join(", ")
            ));
        }
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BART: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/scenes/bart");

    fn bart(rel: &str) -> Option<AffScene> {
        let p = Path::new(BART).join(rel);
        if !p.is_file() {
            eprintln!("note: {} absent, BART scene test skipped", p.display());
            return None;
        }
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

    #[test]
    fn missing_file_points_to_bart() {
        let e = load_aff(Path::new("/nonexistent/kitchen.aff")).unwrap_err();
        assert!(e.message.contains("../shared/scenes/bart/") && e.message.contains("Lext"));
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
